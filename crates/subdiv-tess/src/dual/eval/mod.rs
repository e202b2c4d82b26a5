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
use subdiv_schemes::{PatchMatrices, PatchType, RefineOptions, Scheme, Split, Stencils};
use subdiv_stencil::{Dyadic, FaceDomain, Grid, Layout, PatchLevels, Resolved, StencilEvaluator, StencilTable};

use super::topology::{Block, PackedDomain, Topology};
use crate::TessError;
use crate::plan::{EvaluationPlan, PLAN_BICUBIC, PLAN_BLOCK, PLAN_GENERAL, PlanBicubic, PlanBlock, PlanGeneral};
use crate::quadtree::{check_bicubic, regular_grid};

mod kernels;
mod patch_grid;
mod pieces;
mod records;
mod route;
mod templates;
#[cfg(test)]
mod tests;
mod to_plan;

use self::kernels::*;
pub(crate) use self::kernels::{basis, bicubic_at, derivative};
use self::patch_grid::*;
use self::pieces::*;
use self::records::*;
use self::route::*;
use self::templates::*;

/// Evaluates the output vertices of a [`Topology`] on one mesh's limit surface.
#[derive(Debug)]
pub(crate) struct Evaluator {
    /// Shared with a streamed tessellation's topology builder, which reads level 0 while the
    /// evaluator prepares its chunks.
    levels: Arc<PatchLevels>,
    faces: Vec<FacePlan>,
    /// The orders of [`FacePlan::Bicubic`] faces' control points: per (shape, frame), the
    /// patch's points at `(i − 1, j − 1)` in the face's frame, `j * 4 + i`.
    bicubic_orders: Vec<[u32; 16]>,
    /// Per input face, its domain (`None`: a hole), packed.
    domains: Arc<[PackedDomain]>,
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
    routes: Vec<PackedRoute>,
    records: Vec<Record>,
    /// Per record, its patch and parameter (for [`Self::patch_grids`]).
    places: Vec<Place>,
    /// The separable grids of bicubic patches on refined levels.
    patch_grids: Vec<PatchGrid>,
    /// Per block of the topology, its range of `patch_grids`.
    block_grids: Vec<(u32, u32)>,
    /// Per input face, its type if it has one ([`Self::find_face_types`]), fixed by the mesh;
    /// the types' patches, and each typed face's cage points in its type's order.
    face_types: FaceTypes,
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
    /// Per input face, whether its cell points may read a dual-grid table (on the general
    /// route, resolved on level 0 by a patch that [`reads_table`]), fixed by the mesh.
    table_faces: Vec<bool>,
    /// Per input face, whether its block reads its type's template in this call (its cell
    /// points then need no table).
    copied: Vec<bool>,
    /// [`plan_copies`](Self::plan_copies)'s maps, kept for their allocations.
    fits: HashMap<(u32, u32), bool>,
    made: hashbrown::HashSet<TemplateKey>,
    /// The fits of a streamed call, decided over all its blocks before its chunks
    /// ([`fix_fits`](Self::fix_fits)): each chunk then routes its faces as the whole call would.
    fixed_fits: Option<HashMap<(u32, u32), bool>>,
    /// The template weights a call may use ([`MAX_TEMPLATE_WEIGHTS`]; smaller in tests).
    template_budget: usize,
    /// The blocks of the last [`prepare`](Self::prepare)'s topology: face and rate.
    planned: Vec<(u32, u32)>,
}

impl Evaluator {
    pub(crate) fn new(scheme: &Scheme, mesh: &Mesh) -> Result<Self, TessError> {
        let levels = Arc::new(PatchLevels::new(scheme, mesh, &RefineOptions::DEFAULT)?);
        let count = levels.level_count();
        let (faces, bicubic_orders) = face_plans(mesh, &levels)?;
        let domains = mesh
            .face_ids()
            .map(|f| match faces[f.index()] {
                FacePlan::Hole => Ok(PackedDomain::pack(None)),
                _ => Ok(PackedDomain::pack(Some(levels.domain(f)?))),
            })
            .collect::<Result<Vec<_>, TessError>>()?
            .into();
        let mut evaluator = Self {
            levels,
            faces,
            bicubic_orders,
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
            face_types: FaceTypes::default(),
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
            copied: vec![false; mesh.face_count()],
            fits: HashMap::new(),
            made: hashbrown::HashSet::new(),
            fixed_fits: None,
            template_budget: MAX_TEMPLATE_WEIGHTS,
            planned: Vec::new(),
        };
        evaluator.table_faces = mesh
            .face_ids()
            .map(|f| {
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
    pub(crate) fn domains(&self) -> &[PackedDomain] {
        &self.domains
    }

    /// The patch levels and the faces' domains, shared (for a reader beside a mutable borrow).
    pub(crate) fn shared(&self) -> (Arc<PatchLevels>, Arc<[PackedDomain]>) {
        (Arc::clone(&self.levels), Arc::clone(&self.domains))
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
        for (l, stencils) in self.levels.stencils().iter().enumerate().take(levels - 1).skip(self.refined - 1) {
            let (parent, child) = self.positions.split_at_mut(l + 1);
            stencils.apply(&parent[l], &mut child[0]);
        }
        self.refined = self.refined.max(levels);
    }

    /// Plans the blocks (the whole quad faces' dual grids) of `topo`: the basis tables of the
    /// bicubic faces' rates, and which typed faces read their type's template
    /// ([`plan_copies`](Self::plan_copies)).
    fn plan_blocks(&mut self, topo: &Topology) {
        // The last call's marks off (a chunk of a streamed tessellation resets its own faces,
        // not the mesh's).
        for &(f, _) in &self.planned {
            self.copied[f as usize] = false;
        }
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
            topo.explicit_sites().filter(|&(v, _)| self.routes[v as usize].get() == Route::BicubicPoint).map(
                |(v, site)| {
                    let (u, w) = site.point.to_f64();
                    (v, site.face, [u, w])
                },
            ),
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
}

impl Evaluator {
    /// Face `face`'s bicubic control points in its own frame (cage vertex `cv[j * 4 + i]` at
    /// `(i − 1, j − 1)`), if it is a [`FacePlan::Bicubic`] face.
    #[inline]
    pub(super) fn cv(&self, face: u32) -> Option<[u32; 16]> {
        let FacePlan::Bicubic { order } = self.faces[face as usize] else { return None };
        let Some(Resolved::Patch { patch, .. }) = self.levels.resolve(0, FaceId::new(face)) else { return None };
        let order = &self.bicubic_orders[order as usize];
        Some(std::array::from_fn(|k| patch.vertices[order[k] as usize].index() as u32))
    }
}

/// How each input face is evaluated: holes, bicubic faces (a level-0 patch whose matrices are
/// a bicubic B-spline's, with its control points in the face's frame) and the others; and the
/// bicubic faces' orders of control points.
fn face_plans(mesh: &Mesh, levels: &PatchLevels) -> Result<(Vec<FacePlan>, Vec<[u32; 16]>), TessError> {
    let mut shapes: HashMap<(usize, usize), Option<[usize; 16]>> = HashMap::new();
    let mut orders: HashMap<[u32; 16], u32> = HashMap::new();
    let mut faces = Vec::with_capacity(mesh.face_count());
    for f in mesh.face_ids() {
        let plan = match levels.resolve(0, f) {
            Some(Resolved::Hole) => FacePlan::Hole,
            Some(Resolved::Patch { patch, frame, .. }) if levels.split() == Split::Quad => {
                let key = (Arc::as_ptr(&patch.matrices) as usize, patch.shape);
                let grid = *shapes.entry(key).or_insert_with(|| bicubic_grid(&patch.matrices, patch.shape));
                match grid {
                    Some(grid) => {
                        let order: [u32; 16] = std::array::from_fn(|k| {
                            let (i, j) = ((k % 4) as i64, (k / 4) as i64);
                            let p = frame.to_patch(Dyadic::new(i - 1, j - 1, 1));
                            grid[(p.v + 1) as usize * 4 + (p.u + 1) as usize] as u32
                        });
                        let next = orders.len() as u32;
                        FacePlan::Bicubic { order: *orders.entry(order).or_insert(next) }
                    }
                    None => FacePlan::General,
                }
            }
            Some(_) => FacePlan::General,
            None => return Err(TessError::Internal(format!("{f} was not prepared"))),
        };
        faces.push(plan);
    }
    let mut list = vec![[0; 16]; orders.len()];
    for (order, k) in orders {
        list[k as usize] = order;
    }
    Ok((faces, list))
}
