//! A tessellation's evaluation as plain arrays: the linear map from a cage to every output
//! vertex's position and tangents, for evaluators elsewhere (a GPU's compute shader, paper 003
//! §7.2's buffers) and as a portable reference.
//!
//! The arrays mirror the paper's: the **points** (the cage, rewritten every frame, then the
//! refined levels that some patches live on, each level a sparse combination of the one
//! before), the **patches** (point indices, flattened: [`EvaluationPlan::points`]) and, per
//! output vertex, which patch and which **combination** of its points (weights of the position
//! and both derivatives) give it. The output vertices are the flat ones
//! ([`FlatMesh`](crate::FlatMesh)'s): the tessellation's vertices, then one per extra normal of
//! a crease vertex (see [`TessMesh`](crate::TessMesh)), evaluated at the same point in a face of
//! its own sector, so its position is its vertex's up to rounding and its normal that
//! sector's. Three kinds of vertices ([`PlanEntry`]):
//! - [`PlanEntry::Block`]: a cell point `((i+½)/n, (j+½)/n)` of a regular bicubic face, found
//!   from the vertex's offset in its face's block: the uniform bicubic B-spline there (no
//!   weights stored).
//! - [`PlanEntry::Bicubic`]: any other point of a bicubic patch (on the cage or on a refined
//!   level), at a stored `(s, t)` with the chain-rule rows that turn the patch's derivatives
//!   into the face's.
//! - [`PlanEntry::General`]: an exact stencil over its patch's points (extraordinary patches,
//!   boundaries, vertex limit points); points at the same place of the same patch shape share
//!   their weights.
//!
//! A plan from [`DualTessellator::evaluation_plan`](crate::DualTessellator::evaluation_plan)
//! meets every rule of [`EvaluationPlan::validate`]; one put together elsewhere
//! ([`EvaluationPlan::from_parts`]) is checked against them, so that its evaluators index only
//! what exists.

use std::borrow::Cow;
use std::ops::Range;

use glam::DVec3;
use hashbrown::HashMap;

mod error;
mod validate;

pub use self::error::{PlanError, PlanItem};
use self::validate::check_index;

// How `EvaluationPlan::vertices` encodes an entry: `kind << PLAN_KIND_SHIFT | index`.
pub(crate) const PLAN_BLOCK: u32 = 0;
pub(crate) const PLAN_BICUBIC: u32 = 1;
pub(crate) const PLAN_GENERAL: u32 = 2;
const PLAN_KIND_SHIFT: u32 = 30;
/// The most records of one kind an entry can name.
const MAX_RECORDS: usize = 1 << PLAN_KIND_SHIFT;

/// The cell points of a regular bicubic face at rate `n`: output vertex `base + j · n + i` is
/// the patch at `((i+½)/n, (j+½)/n)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlanBlock {
    /// The first vertex.
    pub base: u32,
    /// The face's rate `n`.
    pub rate: u32,
    /// The first of the patch's 16 point indices in [`EvaluationPlan::points`] (`k = j · 4 + i`
    /// is the control point at `(i − 1, j − 1)` in the face's frame).
    pub points: u32,
}

/// A point of a bicubic patch at `(s, t)` in the patch's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanBicubic {
    /// The first of the patch's 16 point indices in [`EvaluationPlan::points`], as in
    /// [`PlanBlock::points`].
    pub points: u32,
    /// The parameter in the patch's frame.
    pub s: f64,
    /// The parameter in the patch's frame.
    pub t: f64,
    /// `∂/∂u = ju[0] · ∂/∂s + ju[1] · ∂/∂t` for the input face's `u`.
    pub ju: [f64; 2],
    /// `∂/∂v = jv[0] · ∂/∂s + jv[1] · ∂/∂t`.
    pub jv: [f64; 2],
}

/// A point given by an exact stencil over its patch's points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanGeneral {
    /// The first of the patch's `len` point indices in [`EvaluationPlan::points`].
    pub points: u32,
    /// The number of points.
    pub len: u32,
    /// The first of three rows of `len` weights in [`EvaluationPlan::weights`]: position,
    /// `∂/∂s`, `∂/∂t`.
    pub weights: u32,
    /// As [`PlanBicubic::ju`].
    pub ju: [f64; 2],
    /// As [`PlanBicubic::jv`].
    pub jv: [f64; 2],
}

/// How one output vertex is evaluated: its record ([`EvaluationPlan::entries`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlanEntry<'a> {
    /// A cell point of a regular bicubic face; the vertex's offset from
    /// [`PlanBlock::base`] gives its cell.
    Block(&'a PlanBlock),
    /// A point of a bicubic patch at a stored parameter.
    Bicubic(&'a PlanBicubic),
    /// A point on an exact stencil.
    General(&'a PlanGeneral),
}

/// Which record gives an output vertex, by its number in [`PlanParts::blocks`],
/// [`PlanParts::bicubic`] or [`PlanParts::general`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PlanRecord {
    /// A number in [`PlanParts::blocks`].
    Block(u32),
    /// A number in [`PlanParts::bicubic`].
    Bicubic(u32),
    /// A number in [`PlanParts::general`].
    General(u32),
}

/// An [`EvaluationPlan`]'s arrays, taken apart ([`EvaluationPlan::into_parts`]) to be stored
/// or sent elsewhere, and put together again by [`EvaluationPlan::from_parts`], which checks
/// them. Each field is what the accessor of the same name returns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlanParts {
    /// [`EvaluationPlan::cage_len`].
    pub cage_len: u32,
    /// [`EvaluationPlan::levels`].
    pub levels: Vec<Range<u32>>,
    /// [`EvaluationPlan::refine_rows`].
    pub refine_rows: Vec<u32>,
    /// [`EvaluationPlan::refine_ids`].
    pub refine_ids: Vec<u32>,
    /// [`EvaluationPlan::refine_weights`].
    pub refine_weights: Vec<f64>,
    /// Per output vertex, its record ([`EvaluationPlan::entries`]).
    pub vertices: Vec<PlanRecord>,
    /// [`EvaluationPlan::blocks`].
    pub blocks: Vec<PlanBlock>,
    /// [`EvaluationPlan::bicubic`].
    pub bicubic: Vec<PlanBicubic>,
    /// [`EvaluationPlan::general`].
    pub general: Vec<PlanGeneral>,
    /// [`EvaluationPlan::points`].
    pub points: Vec<u32>,
    /// [`EvaluationPlan::weights`].
    pub weights: Vec<f64>,
}

/// Every output vertex of a tessellation as a linear function of the cage; made by
/// [`DualTessellator::evaluation_plan`](crate::DualTessellator::evaluation_plan), or from
/// checked [`PlanParts`] ([`from_parts`](Self::from_parts)).
///
/// Points are numbered in one array: the cage's vertices first (`0..cage_len`), then each
/// refined level's points ([`levels`](Self::levels), in order).
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::dual::PlanEntry;
/// use subdiv_tess::{DualOptions, DualTessellator};
///
/// let mesh = Mesh::build(shapes::ngon_prism(5))?;
/// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())?;
/// let out = tess.tessellate(&vec![4; mesh.face_count()])?.clone();
/// let plan = tess.evaluation_plan();
/// assert_eq!(plan.vertex_count(), out.positions.len());
/// let stencils = plan.entries().filter(|e| matches!(e, PlanEntry::General(_))).count();
/// assert!(stencils > 0); // the prism's caps are pentagons: their points need exact stencils
/// let (mut positions, mut normals) = (Vec::new(), Vec::new());
/// plan.evaluate(mesh.positions(), &mut positions, &mut normals);
/// for (a, b) in positions.iter().zip(&out.positions) {
///     assert!(a.distance(*b) < 1e-12);
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvaluationPlan {
    /// The cage's vertex count: points `0..cage_len`.
    pub(crate) cage_len: u32,
    /// The refined levels' point ranges, in order.
    pub(crate) levels: Vec<Range<u32>>,
    /// Refined point `cage_len + k` is `Σ refine_weights[e] · point[refine_ids[e]]` over
    /// `e ∈ refine_rows[k]..refine_rows[k + 1]` (empty when there are no refined levels).
    pub(crate) refine_rows: Vec<u32>,
    /// See `refine_rows`.
    pub(crate) refine_ids: Vec<u32>,
    /// See `refine_rows`.
    pub(crate) refine_weights: Vec<f64>,
    /// Per output vertex, `kind << PLAN_KIND_SHIFT | index` (`PLAN_BLOCK`, `PLAN_BICUBIC`,
    /// `PLAN_GENERAL`); private, so that the encoding can change.
    pub(crate) vertices: Vec<u32>,
    /// Bicubic faces' cell grids.
    pub(crate) blocks: Vec<PlanBlock>,
    /// Other points of bicubic patches.
    pub(crate) bicubic: Vec<PlanBicubic>,
    /// Points on exact stencils.
    pub(crate) general: Vec<PlanGeneral>,
    /// Patches' point indices.
    pub(crate) points: Vec<u32>,
    /// Exact stencils' weights.
    pub(crate) weights: Vec<f64>,
}

impl EvaluationPlan {
    /// The cage's vertex count: points `0..cage_len` are the cage's.
    pub fn cage_len(&self) -> usize {
        self.cage_len as usize
    }

    /// The number of points: the cage's and every refined level's.
    pub fn point_count(&self) -> usize {
        self.cage_len as usize + self.refine_rows.len().saturating_sub(1)
    }

    /// The number of output vertices (one [entry](Self::entries) each).
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// The refined levels' point ranges, in order, from `cage_len` to
    /// [`point_count`](Self::point_count); each level's points combine the points of the level
    /// before (the cage, for the first).
    pub fn levels(&self) -> &[Range<u32>] {
        &self.levels
    }

    /// Per refined point, where its row starts: refined point `cage_len + k` is
    /// `Σ refine_weights[e] · point[refine_ids[e]]` over `e ∈ refine_rows[k]..refine_rows[k + 1]`
    /// (empty when there are no refined levels, else one more than the refined points).
    pub fn refine_rows(&self) -> &[u32] {
        &self.refine_rows
    }

    /// The refinement rows' point numbers: see [`refine_rows`](Self::refine_rows).
    pub fn refine_ids(&self) -> &[u32] {
        &self.refine_ids
    }

    /// The refinement rows' weights: see [`refine_rows`](Self::refine_rows).
    pub fn refine_weights(&self) -> &[f64] {
        &self.refine_weights
    }

    /// Bicubic faces' cell grids.
    pub fn blocks(&self) -> &[PlanBlock] {
        &self.blocks
    }

    /// Other points of bicubic patches.
    pub fn bicubic(&self) -> &[PlanBicubic] {
        &self.bicubic
    }

    /// Points on exact stencils.
    pub fn general(&self) -> &[PlanGeneral] {
        &self.general
    }

    /// The patches' point indices (into the points `0..point_count`), flattened: each record
    /// names where its patch's run starts.
    pub fn points(&self) -> &[u32] {
        &self.points
    }

    /// The exact stencils' weights: per [`PlanGeneral`], three rows of its `len` (position,
    /// `∂/∂s`, `∂/∂t`).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Every output vertex's entry, in vertex order.
    pub fn entries(&self) -> impl ExactSizeIterator<Item = PlanEntry<'_>> + '_ {
        self.vertices.iter().map(|&e| self.decode(e))
    }

    /// Output vertex `vertex`'s entry; `None` past the last vertex.
    pub fn entry(&self, vertex: usize) -> Option<PlanEntry<'_>> {
        self.vertices.get(vertex).map(|&e| self.decode(e))
    }

    /// A plan over `cage_len` points and no refined levels, to which [`push_general`] adds
    /// exact-stencil vertices.
    ///
    /// [`push_general`]: Self::push_general
    pub(crate) fn over_points(cage_len: u32) -> Self {
        Self { cage_len, ..Self::default() }
    }

    /// Adds a vertex that is `Σ weights[0][k] · point[points[k]]`, with the face's derivatives
    /// from `weights[1]` and `weights[2]`.
    pub(crate) fn push_general(&mut self, points: &[u32], weights: [&[f64]; 3]) {
        let (first, len) = (self.points.len() as u32, points.len() as u32);
        self.points.extend_from_slice(points);
        let at = self.weights.len() as u32;
        weights.iter().for_each(|row| self.weights.extend_from_slice(row));
        self.general.push(PlanGeneral { points: first, len, weights: at, ju: [1.0, 0.0], jv: [0.0, 1.0] });
        self.vertices.push(pack(PLAN_GENERAL, self.general.len() - 1));
    }

    /// An entry of `vertices` as its record (a valid plan's: see [`validate`](Self::validate)).
    fn decode(&self, entry: u32) -> PlanEntry<'_> {
        let (kind, index) = unpack(entry);
        let index = index as usize;
        match kind {
            PLAN_BLOCK => PlanEntry::Block(&self.blocks[index]),
            PLAN_BICUBIC => PlanEntry::Bicubic(&self.bicubic[index]),
            _ => PlanEntry::General(&self.general[index]),
        }
    }

    /// Puts a plan together from its parts and checks it ([`validate`](Self::validate)): the
    /// way in for a plan stored or made elsewhere.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::dual::{EvaluationPlan, PlanError, PlanItem};
    /// use subdiv_tess::{DualOptions, DualTessellator};
    ///
    /// let mesh = Mesh::build(shapes::cube())?;
    /// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())?;
    /// tess.tessellate(&vec![3; mesh.face_count()])?;
    /// let plan = tess.evaluation_plan();
    /// assert_eq!(EvaluationPlan::from_parts(plan.clone().into_parts())?, plan);
    ///
    /// let mut parts = plan.into_parts();
    /// parts.weights[7] = f64::NAN;
    /// let error = EvaluationPlan::from_parts(parts).unwrap_err();
    /// assert!(matches!(error, PlanError::NonFinite { at: PlanItem::Weight(7), .. }));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// The first rule the parts break, as [`validate`](Self::validate) names them.
    pub fn from_parts(parts: PlanParts) -> Result<Self, PlanError> {
        let plan = Self::encode(parts)?;
        plan.validate()?;
        Ok(plan)
    }

    /// The parts, without checks: for tests of an evaluator's own checks (that it calls
    /// [`validate`](Self::validate) before indexing). The plan may break any rule, and then
    /// [`evaluate`](Self::evaluate), [`over_cage`](Self::over_cage) and
    /// [`entries`](Self::entries) may panic. Entries that name no record, or more records than
    /// a plan can number, are still refused.
    ///
    /// # Errors
    /// As [`from_parts`](Self::from_parts), for the entries only.
    #[doc(hidden)]
    pub fn from_parts_unchecked(parts: PlanParts) -> Result<Self, PlanError> {
        Self::encode(parts)
    }

    /// The plan's arrays, for storing it or building another ([`from_parts`](Self::from_parts)).
    pub fn into_parts(self) -> PlanParts {
        let vertices = self
            .vertices
            .iter()
            .map(|&e| {
                let (kind, index) = unpack(e);
                match kind {
                    PLAN_BLOCK => PlanRecord::Block(index),
                    PLAN_BICUBIC => PlanRecord::Bicubic(index),
                    _ => PlanRecord::General(index),
                }
            })
            .collect();
        PlanParts {
            cage_len: self.cage_len,
            levels: self.levels,
            refine_rows: self.refine_rows,
            refine_ids: self.refine_ids,
            refine_weights: self.refine_weights,
            vertices,
            blocks: self.blocks,
            bicubic: self.bicubic,
            general: self.general,
            points: self.points,
            weights: self.weights,
        }
    }

    /// The parts with their entries encoded; entries must name records that exist.
    fn encode(parts: PlanParts) -> Result<Self, PlanError> {
        let counts = [parts.blocks.len(), parts.bicubic.len(), parts.general.len()];
        if counts.iter().any(|&n| n > MAX_RECORDS) {
            return Err(PlanError::Structure { at: PlanItem::Plan, rule: "more than 2^30 records of one kind" });
        }
        if u32::try_from(parts.vertices.len()).is_err() {
            return Err(PlanError::Structure { at: PlanItem::Plan, rule: "more than 2^32 - 1 output vertices" });
        }
        let mut vertices = Vec::with_capacity(parts.vertices.len());
        for (v, record) in parts.vertices.iter().enumerate() {
            let (kind, index) = match *record {
                PlanRecord::Block(k) => (PLAN_BLOCK, k),
                PlanRecord::Bicubic(k) => (PLAN_BICUBIC, k),
                PlanRecord::General(k) => (PLAN_GENERAL, k),
            };
            check_index(PlanItem::Vertex(v), RECORD_NAMES[kind as usize], index, counts[kind as usize])?;
            vertices.push(pack(kind, index as usize));
        }
        Ok(Self {
            cage_len: parts.cage_len,
            levels: parts.levels,
            refine_rows: parts.refine_rows,
            refine_ids: parts.refine_ids,
            refine_weights: parts.refine_weights,
            vertices,
            blocks: parts.blocks,
            bicubic: parts.bicubic,
            general: parts.general,
            points: parts.points,
            weights: parts.weights,
        })
    }

    /// Evaluates every output vertex on `cage` (one position per cage vertex): positions and
    /// unit normals (zero where the tangents are parallel), in f64: the tessellator's own
    /// values, to rounding.
    ///
    /// # Panics
    /// If `cage` is not [`cage_len`](Self::cage_len) long.
    pub fn evaluate(&self, cage: &[DVec3], positions: &mut Vec<DVec3>, normals: &mut Vec<DVec3>) {
        assert_eq!(cage.len(), self.cage_len as usize, "one position per cage vertex");
        let mut points = Vec::with_capacity(self.point_count());
        points.extend_from_slice(cage);
        for row in self.refine_rows.windows(2) {
            let e = row[0] as usize..row[1] as usize;
            let p = self.refine_ids[e.clone()]
                .iter()
                .zip(&self.refine_weights[e])
                .fold(DVec3::ZERO, |acc, (&i, &w)| acc + w * points[i as usize]);
            points.push(p);
        }
        positions.clear();
        normals.clear();
        for (v, entry) in self.entries().enumerate() {
            let (p, du, dv) = match entry {
                PlanEntry::Block(b) => {
                    let local = v as u32 - b.base;
                    let n = f64::from(b.rate);
                    let (s, t) = ((f64::from(local % b.rate) + 0.5) / n, (f64::from(local / b.rate) + 0.5) / n);
                    self.bicubic_at(&points, b.points, s, t, [1.0, 0.0], [0.0, 1.0])
                }
                PlanEntry::Bicubic(b) => self.bicubic_at(&points, b.points, b.s, b.t, b.ju, b.jv),
                PlanEntry::General(g) => {
                    let (len, w) = (g.len as usize, g.weights as usize);
                    let ids = &self.points[g.points as usize..g.points as usize + len];
                    let row = |r: usize| {
                        ids.iter()
                            .zip(&self.weights[w + r * len..w + (r + 1) * len])
                            .fold(DVec3::ZERO, |acc, (&i, &x)| acc + x * points[i as usize])
                    };
                    let (p, s, t) = (row(0), row(1), row(2));
                    (p, g.ju[0] * s + g.ju[1] * t, g.jv[0] * s + g.jv[1] * t)
                }
            };
            positions.push(p);
            normals.push(crate::unit_normal(du.cross(dv)));
        }
    }

    /// The same evaluation with every combination over the cage's own points: no refined
    /// levels, so one pass evaluates everything, and each stencil's weights (composed through
    /// the levels in f64) apply to the cage's exact positions. This is what evaluators in f32
    /// (GPUs) want: refined points stored in f32 carry an error of the model's size times
    /// 2^-24, which tangents on small patches magnify; combinations over the cage do not.
    /// Bicubic points on refined levels become exact-stencil points; the cage's bicubic
    /// faces and points stay as they are. Borrowed when there are no refined levels.
    pub fn over_cage(&self) -> Cow<'_, EvaluationPlan> {
        if self.levels.is_empty() {
            return Cow::Borrowed(self);
        }
        let cage = self.cage_len as usize;
        let mut scratch = Composer::new(cage);
        // Each refined point's row over the cage, level after level.
        let mut rows: Vec<Vec<(u32, f64)>> = Vec::with_capacity(self.point_count() - cage);
        for r in self.refine_rows.windows(2) {
            for e in r[0] as usize..r[1] as usize {
                let (id, w) = (self.refine_ids[e] as usize, self.refine_weights[e]);
                if id < cage {
                    scratch.add(0, id as u32, w);
                } else {
                    for &(c, x) in &rows[id - cage] {
                        scratch.add(0, c, w * x);
                    }
                }
            }
            let (ids, weights) = scratch.take(1);
            rows.push(ids.into_iter().zip(weights).collect());
        }
        let mut out = EvaluationPlan { cage_len: self.cage_len, ..EvaluationPlan::default() };
        let mut patches: HashMap<(u32, u32), u32> = HashMap::new();
        let mut patch = |out: &mut EvaluationPlan, at: u32, len: u32| {
            *patches.entry((at, len)).or_insert_with(|| {
                out.points.extend_from_slice(&self.points[at as usize..(at + len) as usize]);
                out.points.len() as u32 - len
            })
        };
        // Composed stencils, each once: per source (patch, weights or parameter).
        // Key: the source patch and length, and its weights' offset or its `(s, t)` bits;
        // value: the new patch, its length and weights.
        type Source = (u32, u32, u64, u64);
        let mut composed: HashMap<Source, (u32, u32, u32)> = HashMap::new();
        // By base: a block's cells are its vertices, so blocks have distinct bases.
        let mut blocks: HashMap<u32, u32> = HashMap::new();
        for e in self.entries() {
            let new = match e {
                PlanEntry::Block(&b) => {
                    let k = *blocks.entry(b.base).or_insert_with(|| {
                        let points = patch(&mut out, b.points, 16);
                        out.blocks.push(PlanBlock { points, ..b });
                        out.blocks.len() as u32 - 1
                    });
                    pack(PLAN_BLOCK, k as usize)
                }
                PlanEntry::Bicubic(&b) => {
                    let cv = &self.points[b.points as usize..b.points as usize + 16];
                    if cv.iter().all(|&c| (c as usize) < cage) {
                        let points = patch(&mut out, b.points, 16);
                        out.bicubic.push(PlanBicubic { points, ..b });
                        pack(PLAN_BICUBIC, out.bicubic.len() - 1)
                    } else {
                        let key = (b.points, 16, b.s.to_bits(), b.t.to_bits());
                        let (points, len, weights) = *composed.entry(key).or_insert_with(|| {
                            let (bs, ds, bt, dt) = (
                                crate::dual::eval::basis(b.s),
                                crate::dual::eval::derivative(b.s),
                                crate::dual::eval::basis(b.t),
                                crate::dual::eval::derivative(b.t),
                            );
                            for (k, &c) in cv.iter().enumerate() {
                                let (i, j) = (k % 4, k / 4);
                                let w = [bs[i] * bt[j], ds[i] * bt[j], bs[i] * dt[j]];
                                scratch.add_point(&rows, c, w);
                            }
                            scratch.push_to(&mut out)
                        });
                        out.general.push(PlanGeneral { points, len, weights, ju: b.ju, jv: b.jv });
                        pack(PLAN_GENERAL, out.general.len() - 1)
                    }
                }
                PlanEntry::General(&g) => {
                    let ids = &self.points[g.points as usize..(g.points + g.len) as usize];
                    let key = (g.points, g.len, u64::from(g.weights), u64::MAX);
                    let (points, len, weights) = if ids.iter().all(|&c| (c as usize) < cage) {
                        let points = patch(&mut out, g.points, g.len);
                        *composed.entry(key).or_insert_with(|| {
                            let w = &self.weights[g.weights as usize..(g.weights + 3 * g.len) as usize];
                            out.weights.extend_from_slice(w);
                            (points, g.len, out.weights.len() as u32 - 3 * g.len)
                        })
                    } else {
                        *composed.entry(key).or_insert_with(|| {
                            let (len, w) = (g.len as usize, g.weights as usize);
                            for (i, &c) in ids.iter().enumerate() {
                                let row = |r: usize| self.weights[w + r * len + i];
                                scratch.add_point(&rows, c, [row(0), row(1), row(2)]);
                            }
                            scratch.push_to(&mut out)
                        })
                    };
                    out.general.push(PlanGeneral { points, len, weights, ju: g.ju, jv: g.jv });
                    pack(PLAN_GENERAL, out.general.len() - 1)
                }
            };
            out.vertices.push(new);
        }
        Cow::Owned(out)
    }

    /// A bicubic patch at `(s, t)`: position and the face's two derivatives.
    fn bicubic_at(
        &self,
        points: &[DVec3],
        at: u32,
        s: f64,
        t: f64,
        ju: [f64; 2],
        jv: [f64; 2],
    ) -> (DVec3, DVec3, DVec3) {
        let cv = &self.points[at as usize..at as usize + 16];
        let (p, a, b) = crate::dual::eval::bicubic_at(|k| points[cv[k] as usize], s, t);
        (p, ju[0] * a + ju[1] * b, jv[0] * a + jv[1] * b)
    }
}

/// An entry of `EvaluationPlan::vertices`: a record's kind and its number in that kind's
/// list (the one encoding; [`unpack`] reads it).
pub(crate) fn pack(kind: u32, index: usize) -> u32 {
    kind << PLAN_KIND_SHIFT | index as u32
}

/// An entry of `EvaluationPlan::vertices` as its kind and record number ([`pack`]'s inverse).
pub(super) fn unpack(entry: u32) -> (u32, u32) {
    (entry >> PLAN_KIND_SHIFT, entry & ((1 << PLAN_KIND_SHIFT) - 1))
}

/// What each kind of entry names, for errors.
const RECORD_NAMES: [&str; 3] = ["block", "bicubic point", "stencil point"];

/// Sparse sums over the cage's points, three rows at once (position, `∂/∂s`, `∂/∂t`), with a
/// dense scratch row and the list of touched points.
struct Composer {
    dense: [Vec<f64>; 3],
    seen: Vec<bool>,
    touched: Vec<u32>,
}

impl Composer {
    fn new(cage: usize) -> Self {
        Self {
            dense: [vec![0.0; cage], vec![0.0; cage], vec![0.0; cage]],
            seen: vec![false; cage],
            touched: Vec::new(),
        }
    }

    fn add(&mut self, row: usize, point: u32, w: f64) {
        let p = point as usize;
        if !self.seen[p] {
            self.seen[p] = true;
            self.touched.push(point);
        }
        self.dense[row][p] += w;
    }

    /// Adds point `c` (a cage point, or a refined one through its row) with weights `w`.
    fn add_point(&mut self, rows: &[Vec<(u32, f64)>], c: u32, w: [f64; 3]) {
        let cage = self.seen.len();
        if (c as usize) < cage {
            for (r, &x) in w.iter().enumerate() {
                self.add(r, c, x);
            }
        } else {
            for &(p, x) in &rows[c as usize - cage] {
                for (r, &y) in w.iter().enumerate() {
                    self.add(r, p, x * y);
                }
            }
        }
    }

    /// The touched points (sorted) and the first `count` rows' values there, cleared.
    fn take(&mut self, count: usize) -> (Vec<u32>, Vec<f64>) {
        self.touched.sort_unstable();
        let mut weights = Vec::with_capacity(count * self.touched.len());
        for r in 0..count {
            weights.extend(self.touched.iter().map(|&p| self.dense[r][p as usize]));
        }
        for &p in &self.touched {
            self.seen[p as usize] = false;
            for row in &mut self.dense {
                row[p as usize] = 0.0;
            }
        }
        (std::mem::take(&mut self.touched), weights)
    }

    /// The three rows as a new patch and combination of `out`: `(points, len, weights)`.
    fn push_to(&mut self, out: &mut EvaluationPlan) -> (u32, u32, u32) {
        let (ids, weights) = self.take(3);
        let (points, len) = (out.points.len() as u32, ids.len() as u32);
        out.points.extend_from_slice(&ids);
        out.weights.extend_from_slice(&weights);
        (points, len, out.weights.len() as u32 - 3 * len)
    }
}
