//! The numerical half of dual-grid stitching: every output vertex's limit position and unit
//! normal, and the per-vertex data that lets a new cage be evaluated without topology work.
//!
//! Two routes:
//! - **Regular bicubic faces** (a quad face resolved on level 0 by a patch whose sub-patch
//!   matrices are those of a bicubic B-spline, checked once per shape as the quadtree does):
//!   the 16 control points are read from the cage in the face's own frame, and the face's dual
//!   grid is evaluated separably with per-rate basis tables (`B_a((i+½)/n)` and derivatives):
//!   per row `j`, 4 column combinations of the control points (and of their `v` derivative),
//!   then per point 4-term sums for the position, `∂/∂u` and `∂/∂v`. Other points of such a
//!   face (border points, corners) use the same polynomial at their parameter.
//! - **Every other face** (extraordinary, boundary or non-bicubic patches on level 0, and faces
//!   resolved through their children: N-gons, quads with two extraordinary corners): each
//!   point descends (exactly, in rationals) to the patch that holds it, with the chain-rule
//!   factors of the descent and the patch frame. A point of a level-0 patch's own dual grid
//!   (the face's cell points, read in the patch's frame) refers to the patch type's
//!   [`StencilTable`] at that rate, shared by every face of the type and kept across calls
//!   (computed on demand from the patch's matrices, unless seeded with precomputed tables such
//!   as the committed defaults:
//!   [`DualTessellator::seed_tables`](super::DualTessellator::seed_tables)). Any other point
//!   (border points, vertex limit points, points under refined faces) stores its own exact
//!   surface stencil (position and both derivatives over
//!   the patch's control points) from a [`StencilEvaluator`], also kept across calls; points at
//!   the same place of the same patch shape share one copy. A new cage is refined to the levels
//!   these patches live on by the refinement engine's stencils (a sparse product per level over
//!   the whole mesh: `O(4^L)` times the cage for `L` levels, `L ≤ 2` for N-gons and double
//!   extraordinary quads), and each point is then a dot product (4 fixed f64 lanes, weights
//!   padded with zeros): no topology work, no allocation per vertex. The records are prepared
//!   in parallel by chunks of vertices; the exact stencils' weights are kept across calls.
//!   **Face types**: quad faces with the same resolution tree up to vertex labels (the same
//!   children, patch shapes and frames) and the same cage rows of their patches' control points
//!   (up to the order of the cage points, which the type fixes) have the same cell points as
//!   combinations of their own cage points. Per (type, rate) the first face that descends makes
//!   a [`Template`] from its records and patch grids, composed down to the cage, kept across
//!   calls; every face of the type evaluates its cell points from it, 4 points at a time in
//!   lanes over its cage points (no refinement, no per-point records). **Patch grids** (faces
//!   without a template): the cell points of
//!   a quad face that fall in one regular (bicubic) patch on a refined level form a grid
//!   `s × t` in its frame;
//!   they are then evaluated separably, as the level-0 blocks are (the shape's stencils checked
//!   once to be the tensor products over its grid), instead of one 16-point stencil each.
//!
//! One pass writes every vertex (f64 arrays or interleaved f32), over disjoint pieces of the
//! vertex range (blocks, faces with patch grids, runs of other vertices) shared among threads;
//! each vertex is computed alone, so the bits do not depend on the thread count, nor on the
//! vector width the pieces are compiled for at run time (`pulp`: no product and sum is fused but
//! the typed faces' explicit `mul_add`, exact on every target). Normals are
//! normalised by batches (cross products first; on the blocks and typed faces 8 groups of 4
//! points in lanes), which lets the square roots and divisions overlap.

use std::sync::Arc;

use glam::DVec3;
use hashbrown::HashMap;
use subdiv_mesh::{BoundaryInterpolation, FaceId, Mesh};
use subdiv_schemes::{PatchMatrices, PatchType, RefineOptions, Refiner, Scheme, Split};
use subdiv_stencil::{Dyadic, FaceDomain, Grid, PatchLevels, Resolved, StencilEvaluator, StencilTable};

use super::plan::{
    EvaluationPlan, PLAN_BICUBIC, PLAN_BLOCK, PLAN_GENERAL, PLAN_KIND_SHIFT, PlanBicubic, PlanBlock, PlanGeneral,
};
use super::topology::Topology;
use crate::TessError;
use crate::quadtree::{check_bicubic, regular_grid};

/// How one output vertex is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    /// A cell of a bicubic face's block: the separable grid of its rate.
    BlockCell,
    /// A point of a bicubic face outside its block: the bicubic polynomial at its parameter
    /// (listed in [`Evaluator::pointwise`]).
    BicubicPoint,
    /// A cell point of a typed face: its type's [`Template`] over the face's cage points.
    Template,
    /// A point of a [`PatchGrid`] (a bicubic patch on a refined level), evaluated separably.
    PatchGrid,
    /// Its own exact stencil: the [`Record`] of this number.
    Record(u32),
}

/// Whether a block reads a face type's [`Template`] ([`Evaluator::plan_copies`] decides it,
/// [`Evaluator::patch_grids`] settles it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TemplateUse {
    /// The block's cells take their own records.
    Own,
    /// The first block of its (type, rate) without a template: it descends, and its records
    /// become the template.
    Make,
    /// It will read the template a [`Make`](Self::Make) block of this call makes.
    Copy,
    /// Settled: it made this template.
    Made(u32),
    /// Settled: it reads this template (made by another block, in this call or before).
    Copied(u32),
}

impl TemplateUse {
    /// The template it reads, once settled.
    fn template(self) -> Option<u32> {
        match self {
            Self::Made(t) | Self::Copied(t) => Some(t),
            Self::Own | Self::Make | Self::Copy => None,
        }
    }

    /// Whether its cells read a template made by another block (not its own records).
    fn copies(self) -> bool {
        matches!(self, Self::Copy | Self::Copied(_))
    }
}

/// How an input face is evaluated.
#[derive(Clone, Copy, Debug)]
enum FacePlan {
    /// A bicubic B-spline patch: cage vertex `cv[j * 4 + i]` is the control point at
    /// `(i − 1, j − 1)` in the face's own frame.
    Bicubic { cv: [u32; 16] },
    /// Through exact stencils of the patch (on any level) holding each point.
    General,
    /// No surface.
    Hole,
}

/// A vertex on the general route: its patch's control points, its stencil, and the rows that
/// turn the patch's `(∂/∂s, ∂/∂t)` into the input face's `(∂/∂u, ∂/∂v)`.
#[derive(Clone, Copy, Debug)]
struct Record {
    level: u32,
    ids: u32,
    len: u32,
    /// The first of the record's weights in `weights` (three rows of [`padded`]`(len)`: position,
    /// `∂/∂s`, `∂/∂t`, zeros after `len`), or, when `table` is not
    /// [`NO_TABLE`], the point's index in that table's dual grid.
    weights: u32,
    table: u32,
    ju: [f64; 2],
    jv: [f64; 2],
}

/// Stencil evaluators per matrices (keyed by the matrices' address), and the bicubic grids of
/// patch shapes (per matrices and shape; `None`: not bicubic).
#[derive(Debug, Default)]
struct Evaluators {
    stencils: HashMap<usize, StencilEvaluator<Arc<PatchMatrices>>>,
    grids: HashMap<(usize, usize), Option<[u8; 16]>>,
}

/// Vertices per chunk of [`Evaluator::prepare`].
const CHUNK: usize = 4096;

/// The fewest vertices [`Evaluator::evaluate_into`] shares among threads: waking a sleeping
/// thread costs about what a thousand vertices take (tens of microseconds in a virtual
/// machine), and past that the pieces stay small, so that the calling thread can do them all
/// when the others wake late.
const PARALLEL_VERTICES: usize = 1024;

/// One chunk's stencil records, with offsets into its own `ids` and `weights`.
#[derive(Debug, Default)]
struct Chunk {
    /// `(vertex, record)` pairs.
    assigned: Vec<(u32, u32)>,
    records: Vec<Record>,
    /// Per record: where it is, for gathering the points of one bicubic patch into a grid.
    places: Vec<Place>,
    ids: Vec<u32>,
    /// Weights of stencils not in the evaluator's `stencil_index` (records name them by their
    /// number `k` here, with `table` [`FRESH`]), and per such stencil its key and first weight
    /// here.
    weights: Vec<f64>,
    fresh: Vec<((usize, usize, Dyadic), u32)>,
}

/// The `table` of a chunk record whose `weights` is the number of one of the chunk's fresh
/// stencils.
const FRESH: u32 = u32::MAX - 1;

/// A record's patch and parameter there, for [`Evaluator::patch_grids`].
#[derive(Clone, Copy, Debug)]
struct Place {
    /// The patch's level and face on that level.
    patch: (u32, u32),
    /// The point in the patch's frame.
    at: Dyadic,
    /// The patch's 4 × 4 grid (indices into its control points, `grid[j * 4 + i]` at
    /// `(i − 1, j − 1)` in the patch's frame) if its sub-patch matrices are bicubic.
    grid: Option<[u8; 16]>,
}

/// A face's patch, in the order of [`Evaluator::face_type`]: the patch (level, face on that
/// level), and the number of its first control point among the face's patches' points (all
/// the face's patches' points in order) and its control point count.
#[derive(Clone, Copy, Debug)]
struct FacePatch {
    patch: (u32, u32),
    first: u32,
    len: u32,
}

/// A quad face's type ([`Evaluator::find_face_types`]): its number, its range of
/// [`Evaluator::face_patches`], and its range of [`Evaluator::face_cage`] (the cage points its
/// patches depend on, in the type's canonical order).
#[derive(Clone, Copy, Debug)]
struct FaceType {
    id: u32,
    patches: (u32, u32),
    cage: (u32, u32),
}

/// The cell points of one face type at one rate as combinations of the face's cage points:
/// made by the first face of the type that descends (its records and patch grids, composed
/// down the refinement levels to the cage, with the chain-rule rows folded in), kept across
/// calls, and read by every face of the type with its own cage points.
#[derive(Clone, Debug, Default)]
struct Template {
    /// Per group of [`LANES`] cell points (in the block's order, the last group padded with
    /// zeros), per row (position, `∂/∂u`, `∂/∂v`), per cage point `x` (in the type's order,
    /// `len` of them), the group's weights: `weights[((g · 3 + row) · len + x) · LANES + lane]`.
    weights: Vec<f64>,
}

/// The most template weights (8 bytes each) one call uses, and [`Evaluator`] keeps into the
/// next: past it, faces take their own records (decided from the call's rates alone, so a
/// face's route, hence its bits, does not depend on earlier calls), and kept templates are
/// dropped at the start of a call.
const MAX_TEMPLATE_WEIGHTS: usize = 1 << 24;

/// The most cage points a typed face may depend on (more: its own records).
const MAX_TYPED_POINTS: usize = 64;

/// A template's key: the face type (or, with `Evaluator::copy_faces` off, the face, marked by
/// the flag) and the rate.
type TemplateKey = (bool, u32, u32);

/// The points of one bicubic patch on a refined level that form a grid `s × t` in its frame
/// (the dual grid of a quad face over a regular descendant): evaluated separably, as the
/// level-0 blocks are, instead of one stencil per point.
#[derive(Clone, Debug)]
struct PatchGrid {
    level: u32,
    /// The patch (level, face on it), and its 4 × 4 grid (as [`Place::grid`]).
    patch: (u32, u32),
    grid: [u8; 16],
    /// Control points, `cv[j * 4 + i]` at `(i − 1, j − 1)` in the patch's frame.
    cv: [u32; 16],
    /// The rows turning `(∂/∂s, ∂/∂t)` into the face's `(∂/∂u, ∂/∂v)`.
    ju: [f64; 2],
    jv: [f64; 2],
    /// The first of the basis and its derivative at each `s`, then at each `t`, in
    /// `grid_basis`.
    basis: u32,
    /// The numbers of `s` and of `t`.
    s: u32,
    t: u32,
    /// The first vertex in `grid_vertices`: the output vertex at `(s[a], t[b])` is
    /// `grid_vertices[vertices + b · s + a]`.
    vertices: u32,
}

/// A record with its own weights.
const NO_TABLE: u32 = u32::MAX;
/// The lanes of the general route's dot products: each record's ids and weight rows are padded
/// to a multiple of this (the same sums on every target, so the same bits).
const LANES: usize = 4;

/// `len` rounded up to a multiple of [`LANES`].
#[inline]
fn padded(len: usize) -> usize {
    len.div_ceil(LANES) * LANES
}

/// The position and both derivatives `Σ w_k · points[ids[k]]` of a record with its own weights
/// (`ids` and each of the three weight rows [`padded`]): [`LANES`] partial sums per coordinate,
/// added pairwise at the end. In f64, so exact to rounding.
#[inline(always)]
fn dot3(points: &[DVec3], ids: &[u32], w: &[f64]) -> [DVec3; 3] {
    let len = ids.len();
    let (wp, rest) = w.split_at(len);
    let (ws, wt) = rest.split_at(len);
    let mut acc = [[0.0f64; LANES]; 9];
    for (((id, a), b), c) in
        ids.chunks_exact(LANES).zip(wp.chunks_exact(LANES)).zip(ws.chunks_exact(LANES)).zip(wt.chunks_exact(LANES))
    {
        let x: [DVec3; LANES] = std::array::from_fn(|l| points[id[l] as usize]);
        for l in 0..LANES {
            acc[0][l] += a[l] * x[l].x;
            acc[1][l] += a[l] * x[l].y;
            acc[2][l] += a[l] * x[l].z;
            acc[3][l] += b[l] * x[l].x;
            acc[4][l] += b[l] * x[l].y;
            acc[5][l] += b[l] * x[l].z;
            acc[6][l] += c[l] * x[l].x;
            acc[7][l] += c[l] * x[l].y;
            acc[8][l] += c[l] * x[l].z;
        }
    }
    let sum = |a: [f64; LANES]| (a[0] + a[1]) + (a[2] + a[3]);
    let v = acc.map(sum);
    [DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]), DVec3::new(v[6], v[7], v[8])]
}
/// The most control points a table record gathers on the stack (Catmull-Clark valence 12).
const MAX_GATHER: usize = 32;

/// The uniform cubic B-spline basis and its derivative at the dual points `(i+½)/n`.
#[derive(Clone, Debug)]
struct RateBasis {
    b: Vec<[f64; 4]>,
    d: Vec<[f64; 4]>,
    /// The same by groups of [`LANES`] points: per group, each basis function's values at the
    /// group's points (zeros past the last point), then each derivative's.
    lanes: Vec<[[f64; LANES]; 8]>,
}

impl RateBasis {
    fn new(n: u32) -> Self {
        let t = |i: u32| f64::from(2 * i + 1) / f64::from(2 * n);
        let (b, d): (Vec<_>, Vec<_>) = (0..n).map(|i| (basis(t(i)), derivative(t(i)))).unzip();
        let lanes = (0..b.len().div_ceil(LANES))
            .map(|g| {
                std::array::from_fn(|f| {
                    std::array::from_fn(|l| {
                        let i = g * LANES + l;
                        match (f < 4, i < b.len()) {
                            (true, true) => b[i][f],
                            (false, true) => d[i][f - 4],
                            _ => 0.0,
                        }
                    })
                })
            })
            .collect();
        Self { b, d, lanes }
    }
}

/// The uniform cubic B-spline basis at `t ∈ [0, 1]`.
#[inline(always)]
pub(super) fn basis(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    let (t2, t3) = (t * t, t * t * t);
    [s * s * s / 6.0, (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0, (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, t3 / 6.0]
}

/// The derivative of [`basis`].
#[inline(always)]
pub(super) fn derivative(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [-0.5 * s * s, (3.0 * t * t - 4.0 * t) * 0.5, (-3.0 * t * t + 2.0 * t + 1.0) * 0.5, 0.5 * t * t]
}

/// The bicubic patch with control points `cv` (face frame) at `(u, v)`: position, `∂/∂u`,
/// `∂/∂v`.
#[inline(always)]
fn bicubic(cv: &[u32; 16], cage: &[DVec3], u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    bicubic_at(|k| cage[cv[k] as usize], u, v)
}

/// The bicubic patch with control point `k = j · 4 + i` at `(i − 1, j − 1)` given by
/// `point(k)`, at `(u, v)`: position, `∂/∂u`, `∂/∂v`.
#[inline(always)]
pub(super) fn bicubic_at(point: impl Fn(usize) -> DVec3, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let (bu, du, bv, dv) = (basis(u), derivative(u), basis(v), derivative(v));
    let (mut p, mut a, mut b) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for j in 0..4 {
        let (mut c, mut e) = (DVec3::ZERO, DVec3::ZERO);
        for i in 0..4 {
            let x = point(j * 4 + i);
            c += bu[i] * x;
            e += du[i] * x;
        }
        p += bv[j] * c;
        a += bv[j] * e;
        b += dv[j] * c;
    }
    (p, a, b)
}

/// A unit normal from two tangents (zero where they are parallel).
#[cfg(test)]
fn normal(du: DVec3, dv: DVec3) -> DVec3 {
    du.cross(dv).normalize_or_zero()
}

/// Evaluates the output vertices of a [`Topology`] on one mesh's limit surface.
#[derive(Debug)]
pub(crate) struct Evaluator {
    levels: PatchLevels,
    refiner: Option<Refiner>,
    faces: Vec<FacePlan>,
    /// Per input face, its domain (`None`: a hole).
    domains: Vec<Option<FaceDomain>>,
    /// The [`Route::BicubicPoint`] vertices in vertex order, with their face and parameter (made once per
    /// tessellation: no site lookups per frame).
    pointwise: Vec<(u32, u32, [f64; 2])>,
    /// Per refinement level, the current cage refined to it (level 0: the cage); the first
    /// `refined` levels hold the current cage's points, and the last [`prepare`](Self::prepare)
    /// reads the first `needed` (typed faces read the cage only).
    positions: Vec<Vec<DVec3>>,
    refined: usize,
    needed: usize,
    bases: Vec<Option<Arc<RateBasis>>>,
    /// Per output vertex of the last [`prepare`](Self::prepare), how it is evaluated.
    routes: Vec<Route>,
    records: Vec<Record>,
    /// Per record, its patch and parameter (for [`Self::patch_grids`]).
    places: Vec<Place>,
    /// The separable grids of bicubic patches on refined levels.
    patch_grids: Vec<PatchGrid>,
    /// Per block of the topology, its range of `patch_grids`.
    block_grids: Vec<(u32, u32)>,
    /// Per input face, its type if it has one ([`Self::find_face_types`]), fixed by the mesh;
    /// the types' patches, and each typed face's cage points in its type's order.
    face_types: Vec<Option<FaceType>>,
    face_patches: Vec<FacePatch>,
    face_cage: Vec<u32>,
    /// The templates of (face type, rate), kept across calls (as `OpenSubdiv`'s `Bfr` keeps
    /// its topology cache), by key, and how many weights they hold.
    templates: Vec<Template>,
    template_index: HashMap<TemplateKey, u32>,
    template_weights: usize,
    /// Per block of the last [`prepare`](Self::prepare): whether it reads a template.
    block_templates: Vec<TemplateUse>,
    /// Whether typed faces read templates (off: every face on its own records, for tests).
    typed_faces: bool,
    /// Whether faces of one type share a template (off: each typed face makes its own, for
    /// tests).
    copy_faces: bool,
    /// The patch grids' bases and vertices.
    grid_basis: Vec<[[f64; 4]; 2]>,
    /// The parameters of `grid_basis`'s entries.
    grid_params: Vec<f64>,
    grid_vertices: Vec<u32>,
    ids: Vec<u32>,
    /// The exact stencils' weights, kept across calls (only growing): `stencil_index` gives
    /// each (matrices, shape, point in the patch's frame)'s first weight.
    weights: Vec<f64>,
    stencil_index: HashMap<(usize, usize, Dyadic), u32>,
    tables: DualTables,
    /// Sets of exact stencil evaluators per matrices, one per chunk at work, kept across calls
    /// (they remember what they solved, so a second tessellation at the same rates solves
    /// little).
    pool: Vec<Evaluators>,
    /// Chunk buffers of the last [`prepare`](Self::prepare), to be reused.
    spare: Vec<Chunk>,
    /// [`record_spans`](Self::record_spans)'s buffer.
    spans: Vec<std::ops::Range<usize>>,
    /// The faces whose cell points may read a dual-grid table (on the general route, resolved
    /// on level 0 by a patch that [`reads_table`]), fixed by the mesh.
    table_faces: Vec<FaceId>,
    /// Per input face, whether its block reads its type's template in this call (its cell
    /// points then need no table).
    copied: Vec<bool>,
    /// [`plan_copies`](Self::plan_copies)'s maps, kept for their allocations.
    fits: HashMap<(u32, u32), bool>,
    made: hashbrown::HashSet<TemplateKey>,
    /// The blocks of the last [`prepare`](Self::prepare)'s topology: face and rate.
    planned: Vec<(u32, u32)>,
}

impl Evaluator {
    pub(crate) fn new(scheme: &Scheme, mesh: &Mesh) -> Result<Self, TessError> {
        let levels = PatchLevels::new(scheme, mesh, &RefineOptions::DEFAULT)?;
        let count = levels.level_count();
        let refiner = if count > 1 {
            let refiner = Refiner::new(levels.mesh(0), scheme, count - 1, &RefineOptions::DEFAULT)
                .map_err(subdiv_stencil::StencilError::from)?;
            for (l, s) in refiner.levels().iter().enumerate() {
                if s.child_count() != levels.mesh(l + 1).vertex_count() {
                    return Err(TessError::Internal(format!(
                        "refinement level {} does not match the patch levels",
                        l + 1
                    )));
                }
            }
            Some(refiner)
        } else {
            None
        };
        let mut shapes: HashMap<(usize, usize), Option<[usize; 16]>> = HashMap::new();
        let mut faces = Vec::with_capacity(mesh.face_count());
        for f in mesh.face_ids() {
            let plan = match levels.resolve(0, f) {
                Some(Resolved::Hole) => FacePlan::Hole,
                Some(Resolved::Patch { patch, frame, .. }) if levels.split() == Split::Quad => {
                    let key = (Arc::as_ptr(&patch.matrices) as usize, patch.shape);
                    let grid = *shapes.entry(key).or_insert_with(|| bicubic_grid(&patch.matrices, patch.shape));
                    match grid {
                        Some(grid) => FacePlan::Bicubic {
                            cv: std::array::from_fn(|k| {
                                let (i, j) = ((k % 4) as i64, (k / 4) as i64);
                                let p = frame.to_patch(Dyadic::new(i - 1, j - 1, 1));
                                patch.vertices[grid[(p.v + 1) as usize * 4 + (p.u + 1) as usize]].index() as u32
                            }),
                        },
                        None => FacePlan::General,
                    }
                }
                Some(_) => FacePlan::General,
                None => return Err(TessError::Internal(format!("{f} was not prepared"))),
            };
            faces.push(plan);
        }
        let domains = mesh
            .face_ids()
            .map(|f| match faces[f.index()] {
                FacePlan::Hole => Ok(None),
                _ => Ok(Some(levels.domain(f)?)),
            })
            .collect::<Result<_, TessError>>()?;
        let mut evaluator = Self {
            levels,
            refiner,
            faces,
            domains,
            pointwise: Vec::new(),
            positions: vec![Vec::new(); count],
            refined: 0,
            needed: count,
            bases: Vec::new(),
            routes: Vec::new(),
            records: Vec::new(),
            places: Vec::new(),
            patch_grids: Vec::new(),
            block_grids: Vec::new(),
            face_types: Vec::new(),
            face_patches: Vec::new(),
            face_cage: Vec::new(),
            templates: Vec::new(),
            template_index: HashMap::new(),
            template_weights: 0,
            block_templates: Vec::new(),
            typed_faces: true,
            copy_faces: true,
            grid_basis: Vec::new(),
            grid_params: Vec::new(),
            grid_vertices: Vec::new(),
            ids: Vec::new(),
            weights: Vec::new(),
            stencil_index: HashMap::new(),
            tables: DualTables::default(),
            pool: Vec::new(),
            spare: Vec::new(),
            spans: Vec::new(),
            table_faces: Vec::new(),
            copied: Vec::new(),
            fits: HashMap::new(),
            made: hashbrown::HashSet::new(),
            planned: Vec::new(),
        };
        evaluator.table_faces = mesh
            .face_ids()
            .filter(|&f| {
                matches!(evaluator.faces[f.index()], FacePlan::General)
                    && matches!(evaluator.levels.resolve(0, f), Some(Resolved::Patch { patch, .. }) if reads_table(patch))
            })
            .collect();
        evaluator.set_cage(mesh.positions());
        evaluator.find_face_types();
        Ok(evaluator)
    }

    /// Seeds the dual-grid tables with precomputed interior-patch tables (those of the level-0
    /// patches' types; the scheme was checked by the caller). Returns how many were taken.
    pub(crate) fn seed_tables(&mut self, tables: &subdiv_stencil::StencilTables) -> usize {
        // A template made before may hold exact stencils where a face would now read a table.
        self.drop_templates();
        let mut seen = hashbrown::HashSet::new();
        let mut taken = 0;
        for f in self.levels.mesh(0).face_ids() {
            let (FacePlan::General, Some(Resolved::Patch { patch, .. })) =
                (self.faces[f.index()], self.levels.resolve(0, f))
            else {
                continue;
            };
            let m = &patch.matrices;
            let ptr = Arc::as_ptr(m) as usize;
            // Boundary patch types depend on the boundary rule: only interior ones are taken.
            if patch.shape != 0 || !matches!(m.patch_type, PatchType::Interior { .. }) || !seen.insert(ptr) {
                continue;
            }
            for t in tables.tables().iter().filter(|t| {
                t.patch_type() == m.patch_type && t.face_size() == m.face_size && t.control_points() == m.shapes[0].size
            }) {
                if let hashbrown::hash_map::Entry::Vacant(slot) = self.tables.index.entry((ptr, t.rate())) {
                    self.tables.tables.push(Arc::new(t.clone()));
                    slot.insert((self.tables.tables.len() - 1) as u32);
                    taken += 1;
                }
            }
        }
        taken
    }

    /// The patch levels (level 0: the input with the boundary rule applied).
    pub(crate) fn levels(&self) -> &PatchLevels {
        &self.levels
    }

    /// The faces' domains, `None` for holes.
    pub(crate) fn domains(&self) -> &[Option<FaceDomain>] {
        &self.domains
    }

    /// Takes a new cage (checked by the caller) and refines it to every level.
    pub(crate) fn set_cage(&mut self, cage: &[DVec3]) {
        self.positions[0].clear();
        self.positions[0].extend_from_slice(cage);
        self.refined = 1;
        self.refine(self.needed);
    }

    /// Refines the current cage to the first `levels` levels (those not refined yet).
    fn refine(&mut self, levels: usize) {
        if let Some(refiner) = &self.refiner {
            for (l, stencils) in refiner.levels().iter().enumerate().take(levels - 1).skip(self.refined - 1) {
                let (parent, child) = self.positions.split_at_mut(l + 1);
                stencils.apply(&parent[l], &mut child[0]);
            }
        }
        self.refined = self.refined.max(levels);
    }

    /// Plans the blocks (the whole quad faces' dual grids) of `topo`: the basis tables of the
    /// bicubic faces' rates, and which typed faces read their type's template
    /// ([`plan_copies`](Self::plan_copies)).
    fn plan_blocks(&mut self, topo: &Topology) {
        self.planned.clear();
        self.planned.extend(topo.blocks.iter().map(|b| (b.face, b.rate)));
        for &(f, rate) in &self.planned {
            if let FacePlan::Bicubic { .. } = self.faces[f as usize] {
                let r = rate as usize;
                if self.bases.len() <= r {
                    self.bases.resize(r + 1, None);
                }
                if self.bases[r].is_none() {
                    self.bases[r] = Some(Arc::new(RateBasis::new(rate)));
                }
            }
        }
        self.plan_copies();
    }

    /// Prepares the evaluation of `topo`'s vertices (built at `rates`): its blocks' plan, a
    /// stencil record for every vertex on the general route but the typed faces' cells, and the
    /// typed faces' templates.
    pub(crate) fn prepare(&mut self, topo: &Topology, rates: &[u32], parallel: bool) -> Result<(), TessError> {
        self.plan_blocks(topo);
        self.prepare_records(topo, rates, parallel)?;
        self.patch_grids(topo);
        // Only vertices outside the blocks can be pointwise: their sites are the explicit ones.
        self.pointwise.clear();
        self.pointwise.extend(
            topo.explicit_sites().filter(|&(v, _)| self.routes[v as usize] == Route::BicubicPoint).map(|(v, site)| {
                let (u, w) = site.point.to_f64();
                (v, site.face, [u, w])
            }),
        );
        // The levels the records and patch grids read (the templates read the cage): the next
        // cages are refined to those only.
        let used = |level: u32| level as usize + 1;
        self.needed = self
            .records
            .iter()
            .map(|r| used(r.level))
            .chain(self.patch_grids.iter().map(|g| used(g.level)))
            .fold(1, usize::max);
        self.refine(self.needed);
        Ok(())
    }

    /// [`prepare`](Self::prepare) but the patch grids: every general-route vertex on its record,
    /// but the typed faces' cell points that read a template ([`Route::Template`]).
    fn prepare_records(&mut self, topo: &Topology, rates: &[u32], parallel: bool) -> Result<(), TessError> {
        let n = topo.vertex_count as usize;
        self.routes.clear();
        self.routes.resize(n, Route::BicubicPoint);
        self.records.clear();
        self.ids.clear();
        for (b, block) in topo.blocks.iter().enumerate() {
            let cells = block.base as usize..(block.base + block.len()) as usize;
            if let FacePlan::Bicubic { .. } = self.faces[block.face as usize] {
                self.routes[cells].fill(Route::BlockCell);
            } else if self.block_templates[b].copies() {
                self.routes[cells].fill(Route::Template);
            }
        }
        // The dual-grid tables the level-0 patches' cell points read (but those of faces that
        // copy a template), first: the chunks below only read them.
        for &f in &self.table_faces {
            if self.copied[f.index()] {
                continue;
            }
            if let Some(Resolved::Patch { patch, .. }) = self.levels.resolve(0, f) {
                ensure_table(&mut self.tables, patch, rates[f.index()])?;
            }
        }
        // Stencil records by chunks of vertices, in parallel; each chunk borrows a set of
        // stencil evaluators from the pool (their results do not depend on what they solved
        // before, so neither does the output on the thread count).
        let spans = self.record_spans(topo);
        // Runs of consecutive spans of at most `CHUNK` vertices in all (no span is longer).
        let mut chunks: Vec<&[std::ops::Range<usize>]> = Vec::new();
        let (mut first, mut len) = (0, 0);
        for (k, span) in spans.iter().enumerate() {
            if len + span.len() > CHUNK {
                chunks.push(&spans[first..k]);
                (first, len) = (k, 0);
            }
            len += span.len();
        }
        if first < spans.len() {
            chunks.push(&spans[first..]);
        }
        let pool = std::sync::Mutex::new(std::mem::take(&mut self.pool));
        // The chunks' buffers are kept across calls too (no fresh pages per call).
        let spare = std::sync::Mutex::new(std::mem::take(&mut self.spare));
        let this = &*self;
        let work = |spans: &[std::ops::Range<usize>]| -> Result<Chunk, TessError> {
            let mut evaluators =
                pool.lock().unwrap_or_else(std::sync::PoisonError::into_inner).pop().unwrap_or_default();
            let out = spare.lock().unwrap_or_else(std::sync::PoisonError::into_inner).pop().unwrap_or_default();
            let chunk = this.chunk(topo, spans, &mut evaluators, out);
            pool.lock().unwrap_or_else(std::sync::PoisonError::into_inner).push(evaluators);
            chunk
        };
        let results: Vec<Result<Chunk, TessError>> = crate::par::map(parallel, chunks, work);
        self.spans = spans;
        self.pool = pool.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
        self.spare = spare.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
        self.places.clear();
        let mut fresh = Vec::new();
        for chunk in results {
            let chunk = chunk?;
            self.places.extend_from_slice(&chunk.places);
            let (records, ids) = (self.records.len() as u32, self.ids.len() as u32);
            for &(vertex, record) in &chunk.assigned {
                self.routes[vertex as usize] = Route::Record(records + record);
            }
            // The chunk's fresh stencils join the kept ones (a key an earlier chunk added
            // takes that copy: the same weights).
            fresh.clear();
            for (k, &(key, at)) in chunk.fresh.iter().enumerate() {
                let end = chunk.fresh.get(k + 1).map_or(chunk.weights.len(), |&(_, next)| next as usize);
                let weights = &mut self.weights;
                fresh.push(*self.stencil_index.entry(key).or_insert_with(|| {
                    weights.extend_from_slice(&chunk.weights[at as usize..end]);
                    (weights.len() - (end - at as usize)) as u32
                }));
            }
            self.records.extend(chunk.records.iter().map(|r| Record {
                ids: r.ids + ids,
                weights: if r.table == FRESH { fresh[r.weights as usize] } else { r.weights },
                table: if r.table == FRESH { NO_TABLE } else { r.table },
                ..*r
            }));
            self.ids.extend_from_slice(&chunk.ids);
            self.spare.push(chunk);
        }
        Ok(())
    }

    /// Finds every quad face's type ([`Self::face_type`]; faces on the general route under a
    /// quad split), with its patches and the cage points they depend on.
    ///
    /// A type is the resolution tree up to vertex labels, and the cage rows of the patches'
    /// control points ([`Self::cage_rows`]) up to the order of the cage points: each cage point
    /// is named by its column (the points it enters, with their weights' bits), and the cage
    /// points are put in the order of their columns. Two faces of one type then have equal
    /// cage rows point for point, column for column, and their cell points are the same
    /// combinations of their own cage points.
    fn find_face_types(&mut self) {
        let mesh = self.levels.mesh(0);
        self.face_types = vec![None; mesh.face_count()];
        if self.levels.split() != Split::Quad {
            return;
        }
        let mut types: HashMap<Vec<u64>, u32> = HashMap::new();
        let (mut signature, mut patches) = (Vec::new(), Vec::new());
        let (mut rows, mut starts, mut columns, mut order) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for f in mesh.face_ids() {
            if !matches!(self.faces[f.index()], FacePlan::General) {
                continue;
            }
            signature.clear();
            patches.clear();
            if !self.face_type(0, f, &mut signature, &mut patches) {
                continue;
            }
            self.cage_rows(&patches, &mut rows, &mut starts);
            // Each cage point's column: (point, weight bits), by point.
            columns.clear();
            for (point, w) in starts.windows(2).enumerate() {
                columns.extend(rows[w[0] as usize..w[1] as usize].iter().map(|&(x, r)| (x, point as u32, r.to_bits())));
            }
            columns.sort_unstable();
            order.clear();
            let mut at = 0;
            while at < columns.len() {
                let end = at + columns[at..].iter().take_while(|c| c.0 == columns[at].0).count();
                order.push((at, end));
                at = end;
            }
            if order.len() > MAX_TYPED_POINTS {
                continue;
            }
            let column = |&(a, b): &(usize, usize)| columns[a..b].iter().map(|c| (c.1, c.2));
            order.sort_unstable_by(|a, b| column(a).cmp(column(b)).then(columns[a.0].0.cmp(&columns[b.0].0)));
            signature.extend([5, order.len() as u64]);
            for range in &order {
                signature.push((range.1 - range.0) as u64);
                signature.extend(column(range).flat_map(|(point, bits)| [u64::from(point), bits]));
            }
            let next = types.len() as u32;
            let id = *types.entry_ref(&signature).or_insert(next);
            let first = self.face_patches.len() as u32;
            self.face_patches.extend_from_slice(&patches);
            let cage = self.face_cage.len() as u32;
            self.face_cage.extend(order.iter().map(|&(a, _)| columns[a].0));
            self.face_types[f.index()] = Some(FaceType {
                id,
                patches: (first, self.face_patches.len() as u32),
                cage: (cage, self.face_cage.len() as u32),
            });
        }
    }

    /// The control points of `patches` (in order, each patch's in its order) as combinations
    /// of the cage: point `k`'s entries `(cage vertex, weight)` are
    /// `rows[starts[k]..starts[k + 1]]`, by vertex. Each entry sums the products of the
    /// refinement weights along the paths down to the cage (multiplied level by level) in the
    /// order of the products' bits, so that it does not depend on how the mesh numbers its
    /// vertices.
    fn cage_rows(&self, patches: &[FacePatch], rows: &mut Vec<(u32, f64)>, starts: &mut Vec<u32>) {
        fn expand(refiner: Option<&Refiner>, level: usize, id: usize, w: f64, terms: &mut Vec<(u32, f64)>) {
            match refiner {
                Some(r) if level > 0 => {
                    for (parent, x) in r.levels()[level - 1].row(id) {
                        expand(refiner, level - 1, parent, w * x, terms);
                    }
                }
                _ => terms.push((id as u32, w)),
            }
        }
        rows.clear();
        starts.clear();
        starts.push(0);
        let mut terms = Vec::new();
        for &FacePatch { patch: (level, face), .. } in patches {
            let Some(Resolved::Patch { patch, .. }) = self.levels.resolve(level as usize, FaceId::new(face)) else {
                unreachable!("face_type lists patches")
            };
            for v in &patch.vertices {
                terms.clear();
                expand(self.refiner.as_ref(), level as usize, v.index(), 1.0, &mut terms);
                terms.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.to_bits().cmp(&b.1.to_bits())));
                let start = rows.len();
                for &(x, w) in &terms {
                    match rows[start..].last_mut() {
                        Some(last) if last.0 == x => last.1 += w,
                        _ => rows.push((x, w)),
                    }
                }
                starts.push(rows.len() as u32);
            }
        }
    }

    /// Decides, per planned block, whether it reads its type's template
    /// ([`TemplateUse::Copy`], or [`Copied`](TemplateUse::Copied) if kept: its cell points
    /// [`Route::Template`], out of the chunks), makes it ([`Make`](TemplateUse::Make): the first block of a key
    /// without a template) or takes its own records (0).
    ///
    /// The (type, rate) pairs past the [`MAX_TEMPLATE_WEIGHTS`] budget, counted in block order
    /// over the call's pairs, take their own records: the decision depends on this call's
    /// rates only (not on the templates kept), so a face's bits do too.
    fn plan_copies(&mut self) {
        let blocks = self.planned.len();
        self.copied.clear();
        self.copied.resize(self.faces.len(), false);
        self.block_templates.clear();
        self.block_templates.resize(blocks, TemplateUse::Own);
        if !self.typed_faces {
            return;
        }
        if self.template_weights > MAX_TEMPLATE_WEIGHTS {
            self.drop_templates();
        }
        // Per (type, rate) of the call, in block order: whether it fits the budget.
        let (mut fits, mut made) = (std::mem::take(&mut self.fits), std::mem::take(&mut self.made));
        fits.clear();
        made.clear();
        let mut budget = MAX_TEMPLATE_WEIGHTS;
        for &(face, rate) in &self.planned {
            let Some(ty) = self.face_types[face as usize] else { continue };
            fits.entry((ty.id, rate)).or_insert_with(|| {
                let size = template_size(rate, ty.cage.1 - ty.cage.0);
                let fit = size <= budget;
                if fit {
                    budget -= size;
                }
                fit
            });
        }
        for (b, &(face, rate)) in self.planned.iter().enumerate() {
            let Some(ty) = self.face_types[face as usize] else { continue };
            if !fits[&(ty.id, rate)] {
                continue;
            }
            let key = self.template_key(face, rate, ty);
            if let Some(&t) = self.template_index.get(&key) {
                self.block_templates[b] = TemplateUse::Copied(t);
            } else if made.insert(key) {
                self.block_templates[b] = TemplateUse::Make;
                continue;
            } else {
                self.block_templates[b] = TemplateUse::Copy;
            }
            self.copied[face as usize] = true;
        }
        (self.fits, self.made) = (fits, made);
    }

    /// The key of the template of `face` (of type `ty`) at `rate`.
    fn template_key(&self, face: u32, rate: u32, ty: FaceType) -> TemplateKey {
        if self.copy_faces { (false, ty.id, rate) } else { (true, face, rate) }
    }

    /// Forgets the templates.
    fn drop_templates(&mut self) {
        self.templates.clear();
        self.template_index.clear();
        self.template_weights = 0;
    }

    /// Appends the resolution tree of `face` on `level` to `signature` (depth first: each
    /// node's kind; a patch's matrices, shape, size and frame), its patches to `patches`.
    /// Two quad faces with equal signatures reach every cell point through the same children
    /// to patches of the same shapes at the same points with the same derivative maps.
    /// `false` if the tree holds a face that is not a quad under a quad split, or no patch.
    fn face_type(&self, level: usize, face: FaceId, signature: &mut Vec<u64>, patches: &mut Vec<FacePatch>) -> bool {
        match self.levels.resolve(level, face) {
            Some(Resolved::Children { children, domain }) => {
                if domain != FaceDomain::Quad {
                    return false;
                }
                signature.extend([1, children.len() as u64]);
                children.into_iter().all(|c| self.face_type(level + 1, FaceId::new(c as u32), signature, patches))
            }
            Some(Resolved::Patch { patch, frame, .. }) => {
                // The frame as the images of three points (it is affine).
                let code = [(0, 0), (1, 0), (0, 1)].iter().fold(0u64, |code, &(u, v)| {
                    let p = frame.to_patch(Dyadic::new(u, v, 1));
                    code << 8 | ((p.u + 4) as u64) << 4 | (p.v + 4) as u64
                });
                signature.extend([
                    2,
                    Arc::as_ptr(&patch.matrices) as usize as u64,
                    patch.shape as u64,
                    patch.vertices.len() as u64,
                    code,
                ]);
                let first = patches.last().map_or(0, |p: &FacePatch| p.first + p.len);
                let len = patch.vertices.len() as u32;
                patches.push(FacePatch { patch: (level as u32, face.index() as u32), first, len });
                true
            }
            // Cell points without a patch cannot be composed.
            Some(Resolved::Hole) | None => false,
        }
    }

    /// The template of `block`'s face type at its rate, from its records and patch grids
    /// (`first..last` of `patch_grids`), just made by its own descent: each cell point's three
    /// rows over its patch's points (the position's and, through the chain-rule rows, those of
    /// `∂/∂u` and `∂/∂v`) composed with the cage rows of those points ([`Self::cage_rows`]),
    /// each sum in the order of the patch's points, so a face of the same type makes the same
    /// bits.
    fn make_template(&self, block: &super::topology::Block, (first, last): (u32, u32)) -> Template {
        let ty = self.face_types[block.face as usize].expect("a typed face");
        let patches = &self.face_patches[ty.patches.0 as usize..ty.patches.1 as usize];
        let cage = &self.face_cage[ty.cage.0 as usize..ty.cage.1 as usize];
        let len = cage.len();
        let (mut rows, mut starts) = (Vec::new(), Vec::new());
        self.cage_rows(patches, &mut rows, &mut starts);
        for entry in &mut rows {
            entry.0 = cage.iter().position(|&c| c == entry.0).expect("a cage point of the face") as u32;
        }
        let index = |patch: (u32, u32)| patches.iter().find(|p| p.patch == patch).expect("the face's own patch");
        let mut weights = vec![0.0; template_size(block.rate, len as u32)];
        // Adds cell `k`'s rows over patch `p`'s points.
        let mut add = |k: usize, p: &FacePatch, [wp, ws, wt]: [&[f64]; 3], ju: [f64; 2], jv: [f64; 2]| {
            let (g, lane) = (k / LANES, k % LANES);
            for j in 0..p.len as usize {
                let (du, dv) = (ju[0] * ws[j] + ju[1] * wt[j], jv[0] * ws[j] + jv[1] * wt[j]);
                let point = p.first as usize + j;
                for &(x, r) in &rows[starts[point] as usize..starts[point + 1] as usize] {
                    let at = (g * 3 * len + x as usize) * LANES + lane;
                    weights[at] += wp[j] * r;
                    weights[at + len * LANES] += du * r;
                    weights[at + 2 * len * LANES] += dv * r;
                }
            }
        };
        let base = block.base as usize;
        let mut w = [Vec::new(), Vec::new(), Vec::new()];
        for g in &self.patch_grids[first as usize..last as usize] {
            let p = index(g.patch);
            let (ns, nt) = (g.s as usize, g.t as usize);
            let (ss, ts) = self.grid_basis[g.basis as usize..g.basis as usize + ns + nt].split_at(ns);
            for (b, [bt, dt]) in ts.iter().enumerate() {
                for (a, [bs, ds]) in ss.iter().enumerate() {
                    // The tensor-product weights over the patch's points, as the grid evaluates.
                    for row in &mut w {
                        row.clear();
                        row.resize(p.len as usize, 0.0);
                    }
                    for (k, &c) in g.grid.iter().enumerate() {
                        let (i, j, c) = (k % 4, k / 4, usize::from(c));
                        (w[0][c], w[1][c], w[2][c]) = (bs[i] * bt[j], ds[i] * bt[j], bs[i] * dt[j]);
                    }
                    let v = self.grid_vertices[g.vertices as usize + b * ns + a] as usize;
                    add(v - base, p, [&w[0], &w[1], &w[2]], g.ju, g.jv);
                }
            }
        }
        for (k, &route) in self.routes[base..base + block.len() as usize].iter().enumerate() {
            // The other cells are in patch grids.
            let Route::Record(record) = route else { continue };
            let (r, place) = (&self.records[record as usize], &self.places[record as usize]);
            let p = index(place.patch);
            if r.table == NO_TABLE {
                let pad = padded(r.len as usize);
                let w = &self.weights[r.weights as usize..r.weights as usize + 3 * pad];
                add(k, p, [&w[..pad], &w[pad..2 * pad], &w[2 * pad..]], r.ju, r.jv);
            } else {
                let s = self.tables.tables[r.table as usize].stencil(Grid::Dual, r.weights as usize);
                add(k, p, [&s.position, &s.du, &s.dv], r.ju, r.jv);
            }
        }
        Template { weights }
    }

    /// Gathers, per quad face on the general route, the points of each bicubic patch on a
    /// refined level that form a full grid `s × t` in the patch's frame into a [`PatchGrid`]
    /// (the patch shapes' stencils checked once against the tensor products), and marks them
    /// [`Route::PatchGrid`]; the first face of a key without a template makes it from its records
    /// and grids ([`Self::make_template`]), then reads it as the others of its type do.
    fn patch_grids(&mut self, topo: &Topology) {
        self.patch_grids.clear();
        self.block_grids.clear();
        self.grid_basis.clear();
        self.grid_params.clear();
        self.grid_vertices.clear();
        let (mut s, mut t) = (Vec::new(), Vec::new());
        // Per face: the distinct patches (few), each vertex's group, then the groups' vertices
        // by a counting sort (in vertex order within each).
        let (mut keys, mut group, mut starts, mut sorted) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (b, block) in topo.blocks.iter().enumerate() {
            let first = self.patch_grids.len() as u32;
            let template = self.block_templates.get(b).copied().unwrap_or(TemplateUse::Own);
            if !template.copies() && matches!(self.faces[block.face as usize], FacePlan::General) {
                keys.clear();
                group.clear();
                let base = block.base as usize;
                let mut last = usize::MAX;
                for v in base..base + (block.rate * block.rate) as usize {
                    let Route::Record(record) = self.routes[v] else { continue };
                    if self.places[record as usize].grid.is_none() {
                        continue;
                    }
                    let key = self.places[record as usize].patch;
                    if last == usize::MAX || keys[last] != key {
                        last = keys.iter().position(|&k| k == key).unwrap_or_else(|| {
                            keys.push(key);
                            keys.len() - 1
                        });
                    }
                    group.push((last as u32, v as u32));
                }
                starts.clear();
                starts.resize(keys.len() + 1, 0u32);
                for &(g, _) in &group {
                    starts[g as usize + 1] += 1;
                }
                for g in 0..keys.len() {
                    starts[g + 1] += starts[g];
                }
                sorted.clear();
                sorted.resize(group.len(), 0u32);
                let mut next = starts.clone();
                for &(g, v) in &group {
                    sorted[next[g as usize] as usize] = v;
                    next[g as usize] += 1;
                }
                for g in 0..keys.len() {
                    let vertices = &sorted[starts[g] as usize..starts[g + 1] as usize];
                    if let Some(grid) = self.patch_grid(vertices, &mut s, &mut t) {
                        for &v in vertices {
                            self.routes[v as usize] = Route::PatchGrid;
                        }
                        self.patch_grids.push(grid);
                    }
                }
            }
            if template == TemplateUse::Make {
                let template = self.make_template(block, (first, self.patch_grids.len() as u32));
                let ty = self.face_types[block.face as usize].expect("a typed face");
                self.template_index.insert(self.template_key(block.face, block.rate, ty), self.templates.len() as u32);
                self.template_weights += template.weights.len();
                self.templates.push(template);
                // Its records and grids served the template: it reads the template too.
                if let Some(g) = self.patch_grids.get(first as usize) {
                    self.grid_vertices.truncate(g.vertices as usize);
                    self.grid_basis.truncate(g.basis as usize);
                    self.grid_params.truncate(g.basis as usize);
                    self.patch_grids.truncate(first as usize);
                }
                self.routes[block.base as usize..(block.base + block.len()) as usize].fill(Route::Template);
            }
            if template != TemplateUse::Own {
                let ty = self.face_types[block.face as usize].expect("a typed face");
                let t = self.template_index[&self.template_key(block.face, block.rate, ty)];
                self.block_templates[b] =
                    if template == TemplateUse::Make { TemplateUse::Made(t) } else { TemplateUse::Copied(t) };
            }
            self.block_grids.push((first, self.patch_grids.len() as u32));
        }
    }

    /// The [`PatchGrid`] of `vertices` (records of one bicubic patch, whose shape's stencils were
    /// checked to be the tensor products over its grid) if they form a full grid with one
    /// derivative map;
    /// its bases and vertices are appended to `grid_basis` and `grid_vertices` (`s` and `t`:
    /// scratch).
    fn patch_grid(&mut self, vertices: &[u32], s: &mut Vec<f64>, t: &mut Vec<f64>) -> Option<PatchGrid> {
        let (records, places, routes) = (&self.records, &self.places, &self.routes);
        let index = |v: u32| match routes[v as usize] {
            Route::Record(r) => r as usize,
            _ => unreachable!("patch grids gather records"),
        };
        let record = |v: u32| &records[index(v)];
        let place = |v: u32| &places[index(v)];
        let r0 = *record(vertices[0]);
        let grid = place(vertices[0]).grid?;
        s.clear();
        t.clear();
        for &v in vertices {
            let (a, b) = place(v).at.to_f64();
            // Few distinct values (at most the face's rate): a scan, then a sort of those.
            if !s.contains(&a) {
                s.push(a);
            }
            if !t.contains(&b) {
                t.push(b);
            }
        }
        s.sort_unstable_by(f64::total_cmp);
        t.sort_unstable_by(f64::total_cmp);
        if s.len() * t.len() != vertices.len() || s.len() < 2 || t.len() < 2 {
            return None;
        }
        let pad = padded(r0.len as usize);
        let ids0 = &self.ids[r0.ids as usize..r0.ids as usize + pad];
        let first = self.grid_vertices.len();
        self.grid_vertices.resize(first + vertices.len(), u32::MAX);
        let slots = &mut self.grid_vertices[first..];
        let fail = |this: &mut Self| {
            this.grid_vertices.truncate(first);
            None
        };
        for &v in vertices {
            let r = record(v);
            let same_patch = r.ids == r0.ids || self.ids[r.ids as usize..r.ids as usize + pad] == *ids0;
            if r.level != r0.level || r.len != r0.len || !same_patch || r.ju != r0.ju || r.jv != r0.jv {
                return fail(self);
            }
            let (u, w) = place(v).at.to_f64();
            let (Ok(a), Ok(b)) = (s.binary_search_by(|x| x.total_cmp(&u)), t.binary_search_by(|x| x.total_cmp(&w)))
            else {
                return fail(self);
            };
            let slot = &mut slots[b * s.len() + a];
            if *slot != u32::MAX {
                return fail(self);
            }
            *slot = v;
        }
        let at = self.grid_basis.len() as u32;
        self.grid_basis.extend(s.iter().chain(t.iter()).map(|&x| [basis(x), derivative(x)]));
        self.grid_params.extend(s.iter().chain(t.iter()));
        Some(PatchGrid {
            level: r0.level,
            patch: place(vertices[0]).patch,
            grid,
            cv: std::array::from_fn(|k| ids0[usize::from(grid[k])]),
            ju: r0.ju,
            jv: r0.jv,
            basis: at,
            s: s.len() as u32,
            t: t.len() as u32,
            vertices: first as u32,
        })
    }

    /// The vertices that may take records, as ranges of at most [`CHUNK`] vertices, in order:
    /// all but the blocks whose points are evaluated without (bicubic faces' grids and typed
    /// faces' cells), which a scan vertex by vertex would only skip (most of a tessellation's
    /// vertices, often all). In a buffer kept across calls.
    fn record_spans(&mut self, topo: &Topology) -> Vec<std::ops::Range<usize>> {
        let mut spans = std::mem::take(&mut self.spans);
        spans.clear();
        let mut push = |start: usize, end: usize| {
            spans.extend((start..end).step_by(CHUNK).map(|s| s..(s + CHUNK).min(end)));
        };
        let mut at = 0;
        for block in &topo.blocks {
            let (base, end) = (block.base as usize, (block.base + block.len()) as usize);
            // A block's points are all of one kind (`prepare_records` marks them together).
            if base < end && matches!(self.routes[base], Route::BlockCell | Route::Template) {
                push(at, base);
                at = end;
            }
        }
        push(at, topo.vertex_count as usize);
        spans
    }

    /// The stencil records of the general-route vertices of `spans`, with chunk-local offsets.
    fn chunk(
        &self,
        topo: &Topology,
        spans: &[std::ops::Range<usize>],
        evaluators: &mut Evaluators,
        mut out: Chunk,
    ) -> Result<Chunk, TessError> {
        out.assigned.clear();
        out.records.clear();
        out.places.clear();
        out.ids.clear();
        out.weights.clear();
        out.fresh.clear();
        let mut patches: HashMap<(usize, u32), (u32, u32)> = HashMap::new();
        let mut last: Vec<Option<(FaceId, Option<Resolved<'_>>)>> = vec![None; self.levels.level_count()];
        let mut shared: HashMap<(usize, usize, Dyadic), u32> = HashMap::new();
        for i in spans.iter().flat_map(Clone::clone) {
            // `record_spans` left out the blocks of those kinds, and only blocks have them.
            debug_assert!(
                !matches!(self.routes[i], Route::BlockCell | Route::Template),
                "vertex {i} outside the record spans"
            );
            let site = topo.site(i as u32);
            if !matches!(self.faces[site.face as usize], FacePlan::General) {
                continue;
            }
            let face = FaceId::new(site.face);
            // Reduced once, as `LimitEvaluator::eval_exact` does: the descent's maps keep it exact.
            let (mut f, mut p) = (face, site.point.reduced());
            let mut j = [[1.0, 0.0], [0.0, 1.0]];
            let mut done = false;
            for (level, kept) in last.iter_mut().enumerate() {
                // Neighbouring points share their faces: the last resolution per level is kept.
                let resolved = match kept {
                    Some((g, r)) if *g == f => r.clone(),
                    _ => {
                        let r = self.levels.resolve(level, f);
                        *kept = Some((f, r.clone()));
                        r
                    }
                };
                match resolved {
                    Some(Resolved::Children { children, domain }) => {
                        let (child, at, factor) = domain.child_of(p);
                        f = FaceId::new((children.start + child) as u32);
                        p = at;
                        j = j.map(|row| row.map(|x| x * factor));
                    }
                    Some(Resolved::Patch { patch, frame, .. }) => {
                        let (ids, len) = *patches.entry((level, f.index() as u32)).or_insert_with(|| {
                            let start = out.ids.len() as u32;
                            out.ids.extend(patch.vertices.iter().map(|v| v.index() as u32));
                            // Padded to a multiple of `LANES` with the first id (its weights are 0).
                            let first = out.ids[start as usize];
                            out.ids.resize(start as usize + padded(patch.vertices.len()), first);
                            (start, patch.vertices.len() as u32)
                        });
                        let (ju, jv) = frame.chain(j);
                        out.assigned.push((i as u32, out.records.len() as u32));
                        // A point of a level-0 patch's own dual grid reads the shared table.
                        let table = if level == 0 && reads_table(patch) {
                            dual_table(&self.tables, patch, frame.to_patch(site.point))
                        } else {
                            None
                        };
                        if let Some((table, index)) = table {
                            out.records.push(Record { level: 0, ids, len, weights: index, table, ju, jv });
                            out.places.push(Place { patch: (0, f.index() as u32), at: site.point, grid: None });
                            done = true;
                            break;
                        }
                        // Points at the same place of the same patch shape (the same sub-face
                        // point on every face of the cube) share one copy of their weights.
                        let matrices = Arc::as_ptr(&patch.matrices) as usize;
                        let at = frame.to_patch(p);
                        let key = (matrices, patch.shape, at);
                        let (weights, table) = match (self.stencil_index.get(&key), shared.get(&key)) {
                            (Some(&w), _) => (w, NO_TABLE),
                            (None, Some(&k)) => (k, FRESH),
                            (None, None) => {
                                let evaluator = evaluators
                                    .stencils
                                    .entry(matrices)
                                    .or_insert_with(|| StencilEvaluator::new(patch.matrices.clone()));
                                let stencil = evaluator.stencil(patch.shape, at)?;
                                let k = out.fresh.len() as u32;
                                out.fresh.push((key, out.weights.len() as u32));
                                let pad = padded(stencil.position.len());
                                for row in [&stencil.position, &stencil.du, &stencil.dv] {
                                    out.weights.extend_from_slice(row);
                                    out.weights.resize(out.weights.len() + pad - row.len(), 0.0);
                                }
                                shared.insert(key, k);
                                (k, FRESH)
                            }
                        };
                        out.records.push(Record { level: level as u32, ids, len, weights, table, ju, jv });
                        let grid = if level > 0 && len == 16 {
                            match evaluators.grids.get(&(matrices, patch.shape)) {
                                Some(&grid) => grid,
                                None => {
                                    let grid = bicubic_grid(&patch.matrices, patch.shape)
                                        .map(|g| g.map(|k| k as u8))
                                        .filter(|g| {
                                            let evaluator = evaluators
                                                .stencils
                                                .entry(matrices)
                                                .or_insert_with(|| StencilEvaluator::new(patch.matrices.clone()));
                                            tensor_weights_match(evaluator, patch.shape, g)
                                        });
                                    evaluators.grids.insert((matrices, patch.shape), grid);
                                    grid
                                }
                            }
                        } else {
                            None
                        };
                        out.places.push(Place { patch: (level as u32, f.index() as u32), at, grid });
                        done = true;
                        break;
                    }
                    _ => break,
                }
            }
            if !done {
                return Err(TessError::Internal(format!("{face}: no patch holds point {:?}", site.point)));
            }
        }
        Ok(out)
    }

    /// [`evaluate`](Self::evaluate) straight into interleaved f32 (`6 ·` vertices long):
    /// positions and normals, without the f64 arrays.
    pub(crate) fn evaluate_flat(&self, topo: &Topology, parallel: bool, out: &mut [f32]) {
        self.evaluate_into(topo, parallel, FlatSink(out));
    }

    /// Evaluates every vertex of `topo` (prepared) on the current cage.
    pub(crate) fn evaluate(
        &self,
        topo: &Topology,
        parallel: bool,
        positions: &mut Vec<DVec3>,
        normals: &mut Vec<DVec3>,
    ) {
        let n = topo.vertex_count as usize;
        positions.resize(n, DVec3::ZERO);
        normals.resize(n, DVec3::ZERO);
        self.evaluate_into(topo, parallel, WideSink(positions, normals));
    }

    /// Every vertex into `out`, in one pass over
    /// disjoint pieces of the vertex range: the bicubic blocks, the typed faces, the faces with
    /// patch grids, and the runs between them (general-route and pointwise bicubic vertices)
    /// cut to at most [`RUN`] vertices. Each vertex is computed alone, so the output does not
    /// depend on how the pieces are shared among threads.
    fn evaluate_into<S: Sink>(&self, topo: &Topology, parallel: bool, out: S) {
        let mut pieces: Vec<Piece<'_, S>> = Vec::with_capacity(2 * topo.blocks.len() + 1);
        let mut rest = out;
        let mut at = 0;
        let push_run = |rest: &mut S, at: &mut usize, end: usize, pieces: &mut Vec<Piece<'_, S>>| {
            while *at < end {
                let len = (end - *at).min(RUN);
                let (piece, tail) = std::mem::replace(rest, S::empty()).split(len);
                *rest = tail;
                pieces.push(Piece::Run { start: *at, out: piece, grids: &[] });
                *at += len;
            }
        };
        for (b, (block, &(first, last))) in topo.blocks.iter().zip(&self.block_grids).enumerate() {
            let whole = self.block_templates[b].template().is_some()
                || matches!(self.faces[block.face as usize], FacePlan::Bicubic { .. })
                || first < last;
            if !whole {
                continue;
            }
            push_run(&mut rest, &mut at, block.base as usize, &mut pieces);
            let len = block.len() as usize;
            let (piece, tail) = std::mem::replace(&mut rest, S::empty()).split(len);
            let start = at;
            (rest, at) = (tail, at + len);
            // A general face with patch grids: one piece (its grids write anywhere in it).
            let grids = &self.patch_grids[first as usize..last as usize];
            pieces.push(self.block_piece(b, block.face, block.rate, piece).unwrap_or_else(|out| Piece::Run {
                start,
                out,
                grids,
            }));
        }
        push_run(&mut rest, &mut at, topo.vertex_count as usize, &mut pieces);
        self.run_pieces(pieces, parallel && topo.vertex_count as usize >= PARALLEL_VERTICES);
    }

    /// Block `b` (of `face` at `rate`) as one piece if it is one (a typed face reading its
    /// template, or a bicubic face), else its output back.
    fn block_piece<'a, S: Sink>(&'a self, b: usize, face: u32, rate: u32, out: S) -> Result<Piece<'a, S>, S> {
        if let Some(template) = self.block_templates[b].template() {
            let ty = self.face_types[face as usize].expect("a typed face");
            let cage = &self.face_cage[ty.cage.0 as usize..ty.cage.1 as usize];
            return Ok(Piece::Typed { template: &self.templates[template as usize], cage, out });
        }
        match &self.faces[face as usize] {
            FacePlan::Bicubic { cv } => Ok(Piece::Block { cv, rate, out }),
            _ => Err(out),
        }
    }

    /// Evaluates `pieces`, on rayon's threads if `parallel`.
    fn run_pieces<S: Sink>(&self, pieces: Vec<Piece<'_, S>>, parallel: bool) {
        if pieces.is_empty() {
            return;
        }
        // The CPU's features, looked up once per call.
        let arch = pulp::Arch::new();
        crate::par::for_each_init(parallel, pieces, Scratch::new, |scratch, piece| {
            self.run_piece(arch, piece, scratch)
        });
    }

    /// One piece, with the widest vector instructions the CPU has (AVX2 on x86-64), chosen at
    /// run time: the same operations in the same order (Rust never fuses a product and a sum
    /// on its own; the typed faces' `mul_add` is one rounding on every target), so the same
    /// bits as the baseline build. The piece's work is inlined into the dispatched function,
    /// which compiles it for the CPU's features.
    #[inline(always)]
    fn run_piece<S: Sink>(&self, arch: pulp::Arch, piece: Piece<'_, S>, scratch: &mut Scratch) {
        arch.dispatch(
            #[inline(always)]
            || self.evaluate_piece(piece, scratch),
        );
    }

    /// One piece of [`evaluate_into`](Self::evaluate_into)'s work.
    #[inline(always)]
    fn evaluate_piece<S: Sink>(&self, piece: Piece<'_, S>, scratch: &mut Scratch) {
        let cage = &self.positions[0];
        match piece {
            Piece::Block { cv, rate, mut out } => {
                let basis = self.bases[rate as usize].as_deref().expect("prepared");
                grid_block(cv, cage, basis, &mut out, &mut scratch.pending);
            }
            Piece::Typed { template, cage: ids, mut out } => {
                typed_block(template, ids, cage, &mut out, scratch);
            }
            Piece::Run { start, mut out, grids } => {
                // By batches: first the positions and the tangents' cross products, then the
                // normalisations (their square roots and divisions overlap).
                let mut xs = [DVec3::ZERO; BATCH];
                let mut cs = [DVec3::ZERO; BATCH];
                for grid in grids {
                    let points = &self.positions[grid.level as usize];
                    self.patch_grid_eval(grid, points, (&mut xs, &mut cs), |v, p, n| out.put(v as usize - start, p, n));
                }
                let mut ks = [0usize; BATCH];
                // The piece's first pointwise vertex; the others follow in order.
                let mut next = self.pointwise.partition_point(|&(v, ..)| (v as usize) < start);
                let routes = &self.routes[start..start + out.len()];
                for (b, batch) in routes.chunks(BATCH).enumerate() {
                    let mut m = 0;
                    for (k, &route) in batch.iter().enumerate() {
                        let (x, du, dv) = match route {
                            // Written by their grids above.
                            Route::PatchGrid => continue,
                            Route::BicubicPoint => {
                                let (vertex, face, [u, v]) = self.pointwise[next];
                                debug_assert_eq!(vertex as usize, start + b * BATCH + k);
                                next += 1;
                                let FacePlan::Bicubic { cv } = &self.faces[face as usize] else {
                                    unreachable!("bicubic face")
                                };
                                bicubic(cv, cage, u, v)
                            }
                            Route::Record(r) => self.general(&self.records[r as usize]),
                            Route::BlockCell | Route::Template => unreachable!("blocks are pieces of their own"),
                        };
                        (xs[m], cs[m], ks[m]) = (x, du.cross(dv), b * BATCH + k);
                        m += 1;
                    }
                    for ((x, c), &k) in xs.iter().zip(&cs).zip(&ks).take(m) {
                        out.put(k, *x, c.normalize_or_zero());
                    }
                }
            }
        }
    }

    /// A [`PatchGrid`] on its level's points, row by row: `put(vertex, position, normal)`.
    #[inline(always)]
    fn patch_grid_eval(
        &self,
        g: &PatchGrid,
        points: &[DVec3],
        (xs, cs): (&mut [DVec3; BATCH], &mut [DVec3; BATCH]),
        mut put: impl FnMut(u32, DVec3, DVec3),
    ) {
        let c: [DVec3; 16] = std::array::from_fn(|k| points[g.cv[k] as usize]);
        let (ns, nt) = (g.s as usize, g.t as usize);
        let (ss, ts) = self.grid_basis[g.basis as usize..g.basis as usize + ns + nt].split_at(ns);
        let vertices = &self.grid_vertices[g.vertices as usize..g.vertices as usize + ns * nt];
        let mut ks = [0u32; BATCH];
        let mut m = 0;
        for ([bt, dt], row) in ts.iter().zip(vertices.chunks_exact(ns)) {
            let col: [DVec3; 4] =
                std::array::from_fn(|i| bt[0] * c[i] + bt[1] * c[4 + i] + bt[2] * c[8 + i] + bt[3] * c[12 + i]);
            let dcol: [DVec3; 4] =
                std::array::from_fn(|i| dt[0] * c[i] + dt[1] * c[4 + i] + dt[2] * c[8 + i] + dt[3] * c[12 + i]);
            // By batches (across rows): positions and cross products, then the normalisations.
            for ([bs, ds], &v) in ss.iter().zip(row) {
                let p = bs[0] * col[0] + bs[1] * col[1] + bs[2] * col[2] + bs[3] * col[3];
                let s = ds[0] * col[0] + ds[1] * col[1] + ds[2] * col[2] + ds[3] * col[3];
                let t = bs[0] * dcol[0] + bs[1] * dcol[1] + bs[2] * dcol[2] + bs[3] * dcol[3];
                let (du, dv) = (g.ju[0] * s + g.ju[1] * t, g.jv[0] * s + g.jv[1] * t);
                (xs[m], cs[m], ks[m]) = (p, du.cross(dv), v);
                m += 1;
                if m == BATCH {
                    for ((x, c), &k) in xs.iter().zip(cs.iter()).zip(ks.iter()) {
                        put(k, *x, c.normalize_or_zero());
                    }
                    m = 0;
                }
            }
        }
        for ((x, c), &k) in xs.iter().zip(cs.iter()).zip(ks.iter()).take(m) {
            put(k, *x, c.normalize_or_zero());
        }
    }

    /// A general-route vertex on the current cage.
    #[inline(always)]
    fn general(&self, r: &Record) -> (DVec3, DVec3, DVec3) {
        let points = &self.positions[r.level as usize];
        let len = r.len as usize;
        let ids = &self.ids[r.ids as usize..r.ids as usize + len];
        if r.table != NO_TABLE {
            let mut gathered = [DVec3::ZERO; MAX_GATHER];
            for (g, &id) in gathered.iter_mut().zip(ids) {
                *g = points[id as usize];
            }
            let [p, s, t] =
                self.tables.tables[r.table as usize].apply(Grid::Dual, r.weights as usize, &gathered[..len]);
            return (p, r.ju[0] * s + r.ju[1] * t, r.jv[0] * s + r.jv[1] * t);
        }
        let pad = padded(len);
        let ids = &self.ids[r.ids as usize..r.ids as usize + pad];
        let w = &self.weights[r.weights as usize..r.weights as usize + 3 * pad];
        let [p, s, t] = dot3(points, ids, w);
        (p, r.ju[0] * s + r.ju[1] * t, r.jv[0] * s + r.jv[1] * t)
    }
}

impl Evaluator {
    /// The evaluation of `topo`'s vertices (prepared) as plain arrays: see [`EvaluationPlan`].
    pub(crate) fn plan(&self, topo: &Topology) -> EvaluationPlan {
        let mut plan = EvaluationPlan { cage_len: self.positions[0].len() as u32, ..EvaluationPlan::default() };
        // Each level's first point in the one array of points.
        let mut starts = Vec::with_capacity(self.positions.len());
        let mut total = 0u32;
        for level in &self.positions {
            starts.push(total);
            total += level.len() as u32;
        }
        if let Some(refiner) = &self.refiner {
            plan.refine_rows.push(0);
            for (l, stencils) in refiner.levels().iter().enumerate() {
                for child in 0..stencils.child_count() {
                    for (parent, w) in stencils.row(child) {
                        plan.refine_ids.push(starts[l] + parent as u32);
                        plan.refine_weights.push(w);
                    }
                    plan.refine_rows.push(plan.refine_ids.len() as u32);
                }
                plan.levels.push(starts[l + 1]..starts[l + 1] + stencils.child_count() as u32);
            }
        }
        const UNSET: u32 = u32::MAX;
        let entry = |kind: u32, index: usize| kind << PLAN_KIND_SHIFT | index as u32;
        plan.vertices = vec![UNSET; topo.vertex_count as usize];
        let mut face_patches: HashMap<u32, u32> = HashMap::new();
        for block in &topo.blocks {
            if let FacePlan::Bicubic { cv } = &self.faces[block.face as usize] {
                let at = plan.points.len() as u32;
                plan.points.extend_from_slice(cv);
                face_patches.insert(block.face, at);
                let base = block.base as usize;
                let end = base + (block.rate * block.rate) as usize;
                plan.vertices[base..end].fill(entry(PLAN_BLOCK, plan.blocks.len()));
                plan.blocks.push(PlanBlock { base: block.base, rate: block.rate, points: at });
            }
        }
        for g in &self.patch_grids {
            let at = plan.points.len() as u32;
            plan.points.extend(g.cv.iter().map(|&c| starts[g.level as usize] + c));
            let (ns, nt) = (g.s as usize, g.t as usize);
            let params = &self.grid_params[g.basis as usize..g.basis as usize + ns + nt];
            for b in 0..nt {
                for a in 0..ns {
                    let v = self.grid_vertices[g.vertices as usize + b * ns + a];
                    plan.vertices[v as usize] = entry(PLAN_BICUBIC, plan.bicubic.len());
                    plan.bicubic.push(PlanBicubic { points: at, s: params[a], t: params[ns + b], ju: g.ju, jv: g.jv });
                }
            }
        }
        for &(v, face, [s, t]) in &self.pointwise {
            let FacePlan::Bicubic { cv } = &self.faces[face as usize] else { unreachable!("bicubic face") };
            let at = *face_patches.entry(face).or_insert_with(|| {
                plan.points.extend_from_slice(cv);
                plan.points.len() as u32 - 16
            });
            plan.vertices[v as usize] = entry(PLAN_BICUBIC, plan.bicubic.len());
            plan.bicubic.push(PlanBicubic { points: at, s, t, ju: [1.0, 0.0], jv: [0.0, 1.0] });
        }
        // The typed faces' cell points: their templates' rows (`∂/∂u` and `∂/∂v` already) over
        // their cage points, each template's cell once.
        let mut cells: HashMap<(u32, u32), u32> = HashMap::new();
        for (block, &t) in topo.blocks.iter().zip(&self.block_templates) {
            let Some(t) = t.template() else { continue };
            let template = &self.templates[t as usize];
            let ty = self.face_types[block.face as usize].expect("a typed face");
            let points = plan.points.len() as u32;
            plan.points.extend_from_slice(&self.face_cage[ty.cage.0 as usize..ty.cage.1 as usize]);
            let len = (ty.cage.1 - ty.cage.0) as usize;
            for k in 0..block.len() {
                let weights = *cells.entry((t, k)).or_insert_with(|| {
                    let at = plan.weights.len() as u32;
                    let (g, lane) = (k as usize / LANES, k as usize % LANES);
                    for row in 0..3 {
                        plan.weights
                            .extend((0..len).map(|x| template.weights[((g * 3 + row) * len + x) * LANES + lane]));
                    }
                    at
                });
                plan.vertices[(block.base + k) as usize] = entry(PLAN_GENERAL, plan.general.len());
                plan.general.push(PlanGeneral { points, len: len as u32, weights, ju: [1.0, 0.0], jv: [0.0, 1.0] });
            }
        }
        // The general records' patches and weights, each once.
        let mut patches: HashMap<(u32, u32), u32> = HashMap::new();
        let mut weights: HashMap<(u32, u32), u32> = HashMap::new();
        for v in 0..topo.vertex_count as usize {
            if plan.vertices[v] != UNSET {
                continue;
            }
            let Route::Record(record) = self.routes[v] else { unreachable!("vertex {v} has no plan") };
            let r = &self.records[record as usize];
            let len = r.len as usize;
            let points = *patches.entry((r.level, r.ids)).or_insert_with(|| {
                let ids = &self.ids[r.ids as usize..r.ids as usize + len];
                plan.points.extend(ids.iter().map(|&i| starts[r.level as usize] + i));
                plan.points.len() as u32 - r.len
            });
            let w = *weights.entry((r.table, r.weights)).or_insert_with(|| {
                let at = plan.weights.len() as u32;
                if r.table == NO_TABLE {
                    let pad = padded(len);
                    for row in 0..3 {
                        let start = r.weights as usize + row * pad;
                        plan.weights.extend_from_slice(&self.weights[start..start + len]);
                    }
                } else {
                    let stencil = self.tables.tables[r.table as usize].stencil(Grid::Dual, r.weights as usize);
                    for row in [&stencil.position, &stencil.du, &stencil.dv] {
                        plan.weights.extend_from_slice(row);
                    }
                }
                at
            });
            plan.vertices[v] = entry(PLAN_GENERAL, plan.general.len());
            plan.general.push(PlanGeneral { points, len: r.len, weights: w, ju: r.ju, jv: r.jv });
        }
        plan
    }
}

/// Dual-grid stencil tables of level-0 patches, per (matrices, rate), kept across calls.
#[derive(Debug, Default)]
struct DualTables {
    tables: Vec<Arc<StencilTable>>,
    index: HashMap<(usize, u32), u32>,
}

/// Whether the points of level-0 `patch`'s own dual grid read a dual-grid table (shape 0, at
/// most [`MAX_GATHER`] control points), rather than stencils of their own.
fn reads_table(patch: &subdiv_schemes::FoundPatch) -> bool {
    patch.shape == 0 && patch.vertices.len() <= MAX_GATHER
}

/// Computes the dual-grid table of `patch`'s shape at `rate` unless it is held.
fn ensure_table(tables: &mut DualTables, patch: &subdiv_schemes::FoundPatch, rate: u32) -> Result<(), TessError> {
    let key = (Arc::as_ptr(&patch.matrices) as usize, rate);
    if !tables.index.contains_key(&key) {
        let computed =
            StencilTable::compute_rates(&patch.matrices, BoundaryInterpolation::EdgeOnly, rate..=rate)?.remove(0);
        tables.tables.push(Arc::new(computed));
        tables.index.insert(key, (tables.tables.len() - 1) as u32);
    }
    Ok(())
}

/// The table and index of `point` (in the patch's frame, as the face's grid gave it: not
/// reduced) if it is a point of a held dual-grid table of the patch's shape.
fn dual_table(tables: &DualTables, patch: &subdiv_schemes::FoundPatch, point: Dyadic) -> Option<(u32, u32)> {
    let Dyadic { u: a, v: b, denominator: q } = point;
    let triangle = patch.matrices.face_size == 3;
    let (rate, index) = if triangle {
        // Centroids ((3i+1)/3n, (3j+1)/3n) up, ((3i+2)/3n, (3j+2)/3n) down.
        let r = a.rem_euclid(3);
        if q % 3 != 0 || r == 0 || b.rem_euclid(3) != r {
            return None;
        }
        let (n, i, j) = (q / 3, (a - r) / 3, (b - r) / 3);
        (n, 2 * n * j - j * j + 2 * i + i64::from(r == 2))
    } else {
        if q % 2 != 0 || a % 2 == 0 || b % 2 == 0 {
            return None;
        }
        let n = q / 2;
        (n, (b - 1) / 2 * n + (a - 1) / 2)
    };
    let rate = u32::try_from(rate).ok()?;
    let table = *tables.index.get(&(Arc::as_ptr(&patch.matrices) as usize, rate))?;
    let t = &tables.tables[table as usize];
    // The closed-form index, checked against the table's own order.
    let index = usize::try_from(index).ok().filter(|&k| k < t.len(Grid::Dual) && t.point(Grid::Dual, k) == point)?;
    Some((table, index as u32))
}

/// The dual grid of a bicubic face, row by row, into `out` (point `k = j · n + i` at `k`).
/// Per row, the 4 column combinations of the control points (and of their `v` derivative),
/// then [`LANES`] points of the row at a time, coordinate by coordinate in lanes: the same
/// operations as [`bicubic_at`]'s sums, so the same bits.
#[inline(always)]
fn grid_block<S: Sink>(cv: &[u32; 16], cage: &[DVec3], basis: &RateBasis, out: &mut S, pending: &mut Pending) {
    let c: [DVec3; 16] = std::array::from_fn(|k| cage[cv[k] as usize]);
    let n = basis.b.len();
    for j in 0..n {
        let (bv, dv) = (basis.b[j], basis.d[j]);
        let col: [DVec3; 4] =
            std::array::from_fn(|i| bv[0] * c[i] + bv[1] * c[4 + i] + bv[2] * c[8 + i] + bv[3] * c[12 + i]);
        let dcol: [DVec3; 4] =
            std::array::from_fn(|i| dv[0] * c[i] + dv[1] * c[4 + i] + dv[2] * c[8 + i] + dv[3] * c[12 + i]);
        // By coordinate: [x, y, z][column].
        let split = |v: &[DVec3; 4]| [v.map(|p| p.x), v.map(|p| p.y), v.map(|p| p.z)];
        let (col, dcol) = (split(&col), split(&dcol));
        for (g, lanes) in basis.lanes.iter().enumerate() {
            let (bu, du) = lanes.split_at(4);
            // Plain loops: `array::from_fn` is not always inlined here.
            let sum = |w: &[[f64; LANES]], x: &[f64; 4]| {
                let mut out = [0.0; LANES];
                for (l, o) in out.iter_mut().enumerate() {
                    *o = w[0][l] * x[0] + w[1][l] * x[1] + w[2][l] * x[2] + w[3][l] * x[3];
                }
                out
            };
            let acc = [
                sum(bu, &col[0]),
                sum(bu, &col[1]),
                sum(bu, &col[2]),
                sum(du, &col[0]),
                sum(du, &col[1]),
                sum(du, &col[2]),
                sum(bu, &dcol[0]),
                sum(bu, &dcol[1]),
                sum(bu, &dcol[2]),
            ];
            let first = g * LANES;
            pending.push(&acc, j * n + first, LANES.min(n - first), out);
        }
    }
    pending.flush(out);
}

/// Groups of [`LANES`] points whose normals [`Pending`] normalises together (8 measured
/// fastest of 4, 8 and 16 on the typed faces).
const GROUPS: usize = 8;

/// Groups of [`LANES`] points waiting for their normals: per group its positions and its
/// tangents' cross products (by coordinate, in lanes), and its first vertex and point count.
/// Normalising [`GROUPS`] groups at once lets their square roots and divisions overlap, where
/// one group at a time waits for each before its points can be written.
struct Pending {
    p: [[[f64; LANES]; 3]; GROUPS],
    c: [[[f64; LANES]; 3]; GROUPS],
    at: [(usize, usize); GROUPS],
    len: usize,
}

impl Pending {
    fn new() -> Self {
        Self { p: [[[0.0; LANES]; 3]; GROUPS], c: [[[0.0; LANES]; 3]; GROUPS], at: [(0, 0); GROUPS], len: 0 }
    }

    /// Adds `count` points from vertex `first` from their lanes `[px, py, pz, ax, ay, az, bx, by,
    /// bz]` (position, and the tangents `a = ∂/∂u`, `b = ∂/∂v`), and writes the groups into
    /// `out` when there are [`GROUPS`] of them.
    #[inline(always)]
    fn push<S: Sink>(&mut self, acc: &[[f64; LANES]; 9], first: usize, count: usize, out: &mut S) {
        let [px, py, pz, ax, ay, az, bx, by, bz] = acc;
        let (m, c) = (self.len, &mut self.c[self.len]);
        // Plain loops: `array::from_fn` is not always inlined here.
        for l in 0..LANES {
            c[0][l] = ay[l] * bz[l] - by[l] * az[l];
            c[1][l] = az[l] * bx[l] - bz[l] * ax[l];
            c[2][l] = ax[l] * by[l] - bx[l] * ay[l];
        }
        self.p[m] = [*px, *py, *pz];
        self.at[m] = (first, count);
        self.len += 1;
        if self.len == GROUPS {
            self.flush(out);
        }
    }

    /// Writes the waiting groups into `out`, each normal being glam's
    /// `a.cross(b).normalize_or_zero()`, operation for operation (so the same bits), in lanes.
    #[inline(always)]
    fn flush<S: Sink>(&mut self, out: &mut S) {
        // In place: the cross products become the normals.
        for [x, y, z] in self.c.iter_mut().take(self.len) {
            for ((x, y), z) in x.iter_mut().zip(y.iter_mut()).zip(z.iter_mut()) {
                let rcp = 1.0 / ((*x * *x) + (*y * *y) + (*z * *z)).sqrt();
                let unit = rcp.is_finite() && rcp > 0.0;
                (*x, *y, *z) = if unit { (*x * rcp, *y * rcp, *z * rcp) } else { (0.0, 0.0, 0.0) };
            }
        }
        for ((p, n), &(first, count)) in self.p.iter().zip(&self.c).zip(&self.at).take(self.len) {
            for l in 0..count {
                out.put(first + l, lane(p, l), lane(n, l));
            }
        }
        self.len = 0;
    }
}

/// What the blocks and typed faces of one thread reuse from piece to piece (made anew for
/// each, their zeroing showed in profiles as a `memset` of 4 % of the full path's time).
pub(crate) struct Scratch {
    pending: Pending,
    /// A typed face's cage points by coordinate.
    gathered: [[f64; MAX_TYPED_POINTS]; 3],
}

impl Scratch {
    pub(crate) fn new() -> Self {
        Self { pending: Pending::new(), gathered: [[0.0; MAX_TYPED_POINTS]; 3] }
    }
}

/// Point `l` of lanes by coordinate.
#[inline(always)]
fn lane(x: &[[f64; LANES]; 3], l: usize) -> DVec3 {
    DVec3::new(x[0][l], x[1][l], x[2][l])
}

/// The weights of a [`Template`] at `rate` over `len` cage points.
fn template_size(rate: u32, len: u32) -> usize {
    (rate as usize * rate as usize).div_ceil(LANES) * len as usize * 3 * LANES
}

/// A typed face's cell points (`out.len()` of them) from its template and its cage points
/// `ids`: per group of [`LANES`] points, nine sums per lane (position, `∂/∂u`, `∂/∂v`, by
/// coordinate) over the cage points in order, each cage point read once per group, then into
/// `out` through [`Pending`]. The sums are fused multiply-adds (`mul_add`, exact on every
/// target: the same bits, one rounding per term, half the operations of a multiply and an
/// add); the lanes are plain arrays; the normals are glam's
/// `du.cross(dv).normalize_or_zero()`, operation for operation.
#[inline(always)]
fn typed_block<S: Sink>(t: &Template, ids: &[u32], cage: &[DVec3], out: &mut S, scratch: &mut Scratch) {
    let (len, cells) = (ids.len(), out.len());
    // The cage points by coordinate: each coordinate is one load to broadcast.
    let Scratch { gathered, pending } = scratch;
    for (k, &id) in ids.iter().enumerate() {
        let p = cage[id as usize];
        (gathered[0][k], gathered[1][k], gathered[2][k]) = (p.x, p.y, p.z);
    }
    let [gx, gy, gz] = &*gathered;
    for (g, w) in t.weights.chunks_exact(3 * LANES * len).enumerate() {
        let (wp, w) = w.split_at(LANES * len);
        let (wu, wv) = w.split_at(LANES * len);
        let (wp, wu, wv) = (wp.as_chunks::<LANES>().0, wu.as_chunks::<LANES>().0, wv.as_chunks::<LANES>().0);
        // The position and `∂/∂u` rows together, then the `∂/∂v` row: six accumulators, three
        // broadcasts and the weights fit the 16 vector registers of AVX2 (all nine do not, and
        // then the compiler splits the lanes).
        let zero = [0.0f64; LANES];
        let (mut px, mut py, mut pz, mut ux, mut uy, mut uz, mut vx, mut vy, mut vz) =
            (zero, zero, zero, zero, zero, zero, zero, zero, zero);
        for k in 0..len {
            let (x, y, z) = (gx[k], gy[k], gz[k]);
            let (p, u) = (&wp[k], &wu[k]);
            for l in 0..LANES {
                px[l] = p[l].mul_add(x, px[l]);
                py[l] = p[l].mul_add(y, py[l]);
                pz[l] = p[l].mul_add(z, pz[l]);
                ux[l] = u[l].mul_add(x, ux[l]);
                uy[l] = u[l].mul_add(y, uy[l]);
                uz[l] = u[l].mul_add(z, uz[l]);
            }
        }
        for k in 0..len {
            let (x, y, z, v) = (gx[k], gy[k], gz[k], &wv[k]);
            for l in 0..LANES {
                vx[l] = v[l].mul_add(x, vx[l]);
                vy[l] = v[l].mul_add(y, vy[l]);
                vz[l] = v[l].mul_add(z, vz[l]);
            }
        }
        let acc = [px, py, pz, ux, uy, uz, vx, vy, vz];
        let first = g * LANES;
        pending.push(&acc, first, LANES.min(cells - first), out);
    }
    pending.flush(out);
}

/// Vertices per piece of a run of vertices outside the blocks in [`Evaluator::evaluate_into`].
const RUN: usize = 1024;

/// Vertices per batch of a run's normalisations.
const BATCH: usize = 64;

/// A piece of [`Evaluator::evaluate_into`]'s work.
enum Piece<'a, S> {
    /// A bicubic face's dual grid.
    Block { cv: &'a [u32; 16], rate: u32, out: S },
    /// A typed face's cell points: its template over its cage points.
    Typed { template: &'a Template, cage: &'a [u32], out: S },
    /// Vertices `start..start + out.len()`: the patch grids' (all in the range), then each
    /// other one on its own.
    Run { start: usize, out: S, grids: &'a [PatchGrid] },
}

/// Where [`Evaluator::evaluate_into`] writes a range of vertices.
trait Sink: Send + Sized {
    /// An empty range.
    fn empty() -> Self;
    /// The number of vertices.
    fn len(&self) -> usize;
    /// The first `k` vertices and the rest.
    fn split(self, k: usize) -> (Self, Self);
    /// Writes vertex `k`'s position and unit normal.
    fn put(&mut self, k: usize, p: DVec3, n: DVec3);
}

/// Interleaved f32: per vertex `px py pz nx ny nz`.
struct FlatSink<'a>(&'a mut [f32]);

impl Sink for FlatSink<'_> {
    fn empty() -> Self {
        Self(&mut [])
    }
    fn len(&self) -> usize {
        self.0.len() / 6
    }
    fn split(self, k: usize) -> (Self, Self) {
        let (a, b) = self.0.split_at_mut(6 * k);
        (Self(a), Self(b))
    }
    #[inline]
    fn put(&mut self, k: usize, p: DVec3, n: DVec3) {
        self.0[6 * k..6 * k + 6].copy_from_slice(&super::flat_vertex(p, n));
    }
}

/// f64 positions and normals.
struct WideSink<'a>(&'a mut [DVec3], &'a mut [DVec3]);

impl Sink for WideSink<'_> {
    fn empty() -> Self {
        Self(&mut [], &mut [])
    }
    fn len(&self) -> usize {
        self.0.len()
    }
    fn split(self, k: usize) -> (Self, Self) {
        let (a, b) = self.0.split_at_mut(k);
        let (c, d) = self.1.split_at_mut(k);
        (Self(a, c), Self(b, d))
    }
    #[inline]
    fn put(&mut self, k: usize, p: DVec3, n: DVec3) {
        self.0[k] = p;
        self.1[k] = n;
    }
}

/// Whether the exact stencil of the shape at a point without symmetry is the tensor product
/// of the cubic B-spline basis over `grid` (position and both derivatives, to 1e-12): then so
/// is every point's, the patch being bicubic, and the grid's orientation is the stencils'.
fn tensor_weights_match(evaluator: &mut StencilEvaluator<Arc<PatchMatrices>>, shape: usize, grid: &[u8; 16]) -> bool {
    let at = Dyadic::new(3, 5, 16);
    let Ok(stencil) = evaluator.stencil(shape, at) else { return false };
    let (s, t) = at.to_f64();
    let (bs, ds, bt, dt) = (basis(s), derivative(s), basis(t), derivative(t));
    (0..16).all(|k| {
        let (i, j) = (k % 4, k / 4);
        let g = usize::from(grid[k]);
        let want = [bs[i] * bt[j], ds[i] * bt[j], bs[i] * dt[j]];
        let got = [stencil.position[g], stencil.du[g], stencil.dv[g]];
        want.iter().zip(got).all(|(w, g)| (w - g).abs() <= 1e-12)
    })
}

/// The 4 × 4 grid of a shape if its sub-patch matrices are those of a bicubic B-spline.
fn bicubic_grid(matrices: &PatchMatrices, shape: usize) -> Option<[usize; 16]> {
    let s = &matrices.shapes[shape];
    let grid = regular_grid(s.size, s.parameters.as_ref())?;
    check_bicubic(matrices, shape, &grid).ok().map(|()| grid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use subdiv_mesh::shapes;
    use subdiv_schemes::Builtin;

    /// The separable blocks give what the exact stencil tables give (position and normal,
    /// through the patch frame), on a torus whose faces start their patches at every corner.
    #[test]
    fn separable_blocks_equal_the_table_route() {
        let mesh = Mesh::build(shapes::quad_torus(6, 5)).unwrap();
        let ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
        let cage = mesh.positions();
        let mut worst: f64 = 0.0;
        for n in [1u32, 2, 5, 8] {
            let basis = RateBasis::new(n);
            let count = (n * n) as usize;
            let (mut ps, mut ns) = (vec![DVec3::ZERO; count], vec![DVec3::ZERO; count]);
            for f in mesh.face_ids() {
                let FacePlan::Bicubic { cv } = ev.faces[f.index()] else { panic!("{f} of a torus is regular") };
                let Some(Resolved::Patch { patch, frame, .. }) = ev.levels.resolve(0, f) else { panic!("{f}") };
                let table = StencilTable::compute_rates(&patch.matrices, BoundaryInterpolation::EdgeOnly, n..=n)
                    .unwrap()
                    .remove(0);
                let points: Vec<DVec3> = patch.vertices.iter().map(|v| cage[v.index()]).collect();
                grid_block(&cv, cage, &basis, &mut WideSink(&mut ps, &mut ns), &mut Pending::new());
                let index: HashMap<Dyadic, usize> =
                    (0..table.len(Grid::Dual)).map(|k| (table.point(Grid::Dual, k), k)).collect();
                let (ju, jv) = frame.chain([[1.0, 0.0], [0.0, 1.0]]);
                for j in 0..n {
                    for i in 0..n {
                        let at =
                            frame.to_patch(Dyadic::new(2 * i64::from(i) + 1, 2 * i64::from(j) + 1, 2 * i64::from(n)));
                        let [x, ds, dt] = table.apply(Grid::Dual, index[&at], &points);
                        let k = (j * n + i) as usize;
                        let want_n = normal(ju[0] * ds + ju[1] * dt, jv[0] * ds + jv[1] * dt);
                        worst = worst.max((x - ps[k]).length()).max((want_n - ns[k]).length());
                        // The pointwise polynomial, for the points outside blocks, agrees too.
                        let (u, v) = (f64::from(2 * i + 1) / f64::from(2 * n), f64::from(2 * j + 1) / f64::from(2 * n));
                        let (p, du, dv) = bicubic(&cv, cage, u, v);
                        worst = worst.max((p - x).length()).max((normal(du, dv) - want_n).length());
                    }
                }
            }
        }
        // The torus is about 3 across.
        assert!(worst < 1e-12, "block route off the table route by {worst:e}");
    }

    /// Loop on a regular triangle torus: every face is a patch on level 0, so every centroid
    /// reads the shared dual-grid table, and the other points (interior primal points, vertex
    /// limit points) have their own exact stencils.
    #[test]
    fn level_zero_patches_read_dual_tables() {
        let mesh = Mesh::build(shapes::triangle_torus(6, 4)).unwrap();
        let mut ev = Evaluator::new(Builtin::Loop.scheme(), &mesh).unwrap();
        let domains = ev.domains().to_vec();
        let mut topo = Topology::default();
        let faces = mesh.face_count();
        super::super::topology::Builder::new(&mesh, true, false).build(&domains, &vec![4; faces], None, &mut topo);
        ev.prepare(&topo, &vec![4; faces], true).unwrap();
        let tabled = ev.records.iter().filter(|r| r.table != NO_TABLE).count();
        assert_eq!(tabled, faces * 16);
        assert_eq!(ev.records.len(), topo.vertex_count as usize);
        // One table: one patch type, one rate.
        assert_eq!(ev.tables.tables.len(), 1);
    }

    /// Refined regular patches evaluated separably ([`PatchGrid`]) give what their points'
    /// own stencil records give, and many general-route points of the cube, the default
    /// model and a prism take that route at these rates.
    #[test]
    fn patch_grids_equal_the_records() {
        for (soup, rate) in [(shapes::cube(), 12u32), (shapes::default_model(), 8), (shapes::ngon_prism(5), 9)] {
            let mesh = Mesh::build(soup).unwrap();
            let mut ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
            // Every face on its own records (typed faces read templates instead).
            ev.typed_faces = false;
            let moved: Vec<DVec3> =
                mesh.positions().iter().enumerate().map(|(i, p)| *p * 1.3 + DVec3::splat((i as f64).sin())).collect();
            ev.set_cage(&moved);
            let domains = ev.domains().to_vec();
            let mut topo = Topology::default();
            let rates = vec![rate; mesh.face_count()];
            super::super::topology::Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut topo);
            ev.plan_blocks(&topo);
            ev.prepare_records(&topo, &rates, true).unwrap();
            let routes = ev.routes.clone();
            ev.patch_grids(&topo);
            let gridded = ev.routes.iter().filter(|&&k| k == Route::PatchGrid).count();
            assert!(4 * gridded > ev.records.len(), "{gridded} of {} in patch grids", ev.records.len());
            let (mut ps, mut ns) = (Vec::new(), Vec::new());
            ev.evaluate(&topo, true, &mut ps, &mut ns);
            let mut worst: f64 = 0.0;
            for (v, &route) in ev.routes.iter().enumerate() {
                if let (Route::PatchGrid, Route::Record(r)) = (route, routes[v]) {
                    let (p, du, dv) = ev.general(&ev.records[r as usize]);
                    worst = worst.max((p - ps[v]).length()).max((normal(du, dv) - ns[v]).length());
                }
            }
            assert!(worst < 1e-12, "patch grids off the records by {worst:e}");
        }
    }

    /// Faces that read their type's template ([`Evaluator::plan_copies`]) evaluate to the same
    /// bits as with templates of their own, at even and odd, equal and mixed rates, on meshes
    /// with extraordinary vertices (on the cube faces share templates), N-gons and borders,
    /// with templates made in the same call or kept from earlier calls at other rates; the
    /// plans agree too, and both agree with every face on its own records (the templates are
    /// those records composed down to the cage).
    #[test]
    fn copied_faces_equal_their_own_descent() {
        let meshes = [
            shapes::cube(),
            shapes::pole(5),
            shapes::pole(6),
            shapes::ngon_prism(5),
            shapes::default_model(),
            shapes::quad_grid(3, 2),
        ];
        for (m, soup) in meshes.into_iter().enumerate() {
            let first = m == 0;
            let mesh = Mesh::build(soup).unwrap();
            let nf = mesh.face_count();
            let moved: Vec<DVec3> =
                mesh.positions().iter().enumerate().map(|(i, p)| *p * 0.7 + DVec3::splat((i as f64).cos())).collect();
            let uniform = |n: u32| vec![n; nf];
            let new = |copy: bool| {
                let mut ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
                ev.copy_faces = copy;
                ev.typed_faces = true;
                ev.set_cage(&moved);
                ev
            };
            // Kept across the rate sets below, with its templates.
            let mut kept = new(true);
            for rates in [
                uniform(1),
                uniform(2),
                uniform(5),
                uniform(8),
                (0..nf as u32).map(|f| 2 + f % 3).collect(),
                uniform(12),
                uniform(5),
                (0..nf as u32).map(|f| 3 + f % 4).collect(),
            ] {
                let domains = kept.domains().to_vec();
                let mut topo = Topology::default();
                super::super::topology::Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut topo);
                let run = |ev: &mut Evaluator| {
                    ev.prepare(&topo, &rates, true).unwrap();
                    let (mut ps, mut ns) = (Vec::new(), Vec::new());
                    ev.evaluate(&topo, true, &mut ps, &mut ns);
                    let bits = |v: &[DVec3]| v.iter().flat_map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>();
                    let (mut plan, mut normals) = (Vec::new(), Vec::new());
                    ev.plan(&topo).evaluate(&ev.positions[0], &mut plan, &mut normals);
                    (bits(&ps), bits(&ns), plan)
                };
                let own = run(&mut new(false));
                for (k, copied) in [run(&mut new(true)), run(&mut kept), run(&mut kept)].into_iter().enumerate() {
                    assert!(own.0 == copied.0 && own.1 == copied.1, "rates {rates:?}, run {k}");
                    let worst = worst_plan(&own.2, &copied.2);
                    assert!(worst < 1e-12, "plans off by {worst:e}");
                }
                // The templates (records composed to the cage) agree with the records.
                let mut records = new(true);
                records.typed_faces = false;
                let records = run(&mut records);
                let unbits = |v: &[u64]| v.iter().map(|&b| f64::from_bits(b)).collect::<Vec<_>>();
                for (a, b) in [(&own.0, &records.0), (&own.1, &records.1)] {
                    let worst = unbits(a).iter().zip(unbits(b)).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                    assert!(worst < 1e-12, "rates {rates:?}: templates off the records by {worst:e}");
                }
                assert!(worst_plan(&own.2, &records.2) < 1e-12);
                if first && rates == uniform(8) {
                    let uses = &kept.block_templates;
                    assert!(
                        uses.iter().any(|t| matches!(t, TemplateUse::Copied(_))),
                        "some of the cube's faces copy others"
                    );
                    assert!(uses.iter().all(|t| t.template().is_some()), "the cube's faces are typed");
                }
            }
            assert!(!first || !kept.templates.is_empty(), "the cube's faces have templates");
        }
    }

    /// The largest distance between two lists of points.
    fn worst_plan(a: &[DVec3], b: &[DVec3]) -> f64 {
        assert_eq!(a.len(), b.len());
        a.iter().zip(b).map(|(x, y)| (*x - *y).length()).fold(0.0, f64::max)
    }

    /// The cage refined by the evaluator's own `Refiner` (what `update_cage` uses) lands on the
    /// patch levels' meshes, vertex for vertex: the stencil records index those vertices.
    #[test]
    fn refined_cage_matches_the_patch_levels() {
        for soup in [shapes::cube(), shapes::ngon_prism(5), shapes::default_model()] {
            let mesh = Mesh::build(soup).unwrap();
            let ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
            assert!(ev.levels.level_count() > 1);
            for level in 0..ev.levels.level_count() {
                let want = ev.levels.mesh(level).positions();
                assert_eq!(ev.positions[level].len(), want.len());
                let worst = ev.positions[level].iter().zip(want).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
                assert!(worst < 1e-12, "level {level}: {worst:e}");
            }
        }
    }
}
