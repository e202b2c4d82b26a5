//! Stencil tables: the stencils of the grid points a tessellator samples, per (scheme, patch
//! type, rate), computed once and kept in a versioned binary file or a lazy cache.

use std::collections::HashMap;
use std::ops::RangeInclusive;
use std::sync::{Arc, Mutex, PoisonError};

use glam::DVec3;
use subdiv_mesh::BoundaryInterpolation;
use subdiv_schemes::binary::{ByteReader, fnv1a};
use subdiv_schemes::{Builtin, PatchMatrices, PatchType, Scheme, SharpFeatures};

use crate::parallel::{self, Threads};
use crate::{Dyadic, StencilError, StencilEvaluator, SurfaceStencil};

/// The grids of a face at rate `n` that a tessellator samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Grid {
    /// The primal grid, row by row (`j` outer, `i` inner, as `osd_limit --grid`): quads
    /// `(i/n, j/n)` for `0 ≤ i, j ≤ n`; triangles `(i/n, j/n)` for `i + j ≤ n`.
    Primal,
    /// The dual grid, row by row: quads the cell centres `((i+½)/n, (j+½)/n)` for
    /// `0 ≤ i, j < n`; triangles the centroids of the `n²` sub-triangles, each row left to
    /// right, upward `((i+⅓)/n, (j+⅓)/n)` and downward `((i+⅔)/n, (j+⅔)/n)` in turn.
    Dual,
}

impl Grid {
    /// Both grids, primal first (the order of a table's data).
    pub const ALL: [Grid; 2] = [Grid::Primal, Grid::Dual];

    /// The grid's points on a face of `face_size` sides (3 or 4) at `rate`, in order.
    ///
    /// ```
    /// use subdiv_stencil::{Dyadic, Grid};
    ///
    /// assert_eq!(Grid::Dual.points(4, 1), [Dyadic::new(1, 1, 2)]);
    /// // A triangle at rate 2: three upward sub-triangles and one downward one.
    /// let dual = Grid::Dual.points(3, 2);
    /// assert_eq!(dual, [Dyadic::new(1, 1, 6), Dyadic::new(2, 2, 6), Dyadic::new(4, 1, 6), Dyadic::new(1, 4, 6)]);
    /// assert_eq!(Grid::Primal.points(3, 2).len(), 6);
    /// ```
    pub fn points(self, face_size: usize, rate: u32) -> Vec<Dyadic> {
        let n = i64::from(rate);
        let mut points = Vec::new();
        match (self, face_size == 3) {
            (Grid::Primal, false) => {
                points.extend((0..=n).flat_map(|j| (0..=n).map(move |i| Dyadic::new(i, j, n))));
            }
            (Grid::Primal, true) => {
                points.extend((0..=n).flat_map(|j| (0..=n - j).map(move |i| Dyadic::new(i, j, n))));
            }
            (Grid::Dual, false) => {
                points.extend((0..n).flat_map(|j| (0..n).map(move |i| Dyadic::new(2 * i + 1, 2 * j + 1, 2 * n))));
            }
            (Grid::Dual, true) => {
                for j in 0..n {
                    for i in 0..n - j {
                        points.push(Dyadic::new(3 * i + 1, 3 * j + 1, 3 * n));
                        if i + j + 1 < n {
                            points.push(Dyadic::new(3 * i + 2, 3 * j + 2, 3 * n));
                        }
                    }
                }
            }
        }
        points
    }

    fn code(self) -> u8 {
        match self {
            Grid::Primal => 0,
            Grid::Dual => 1,
        }
    }
}

/// Where a grid point's stencil is kept: a stored point, itself or mirrored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Slot {
    stored: u32,
    mirrored: bool,
}

/// One grid's stencils: the stored points' weights (position, ∂/∂u, ∂/∂v, each over the patch's
/// control points), and per grid point the stored point that gives it.
#[derive(Clone, Debug, PartialEq)]
struct GridStencils {
    points: Vec<Dyadic>,
    slots: Vec<Slot>,
    exact: Vec<bool>,
    weights: Vec<f64>,
}

impl GridStencils {
    /// The grid's points and slots; with a mirror symmetry only points with `u ≥ v` are stored,
    /// the others read their mirror image's.
    fn layout(grid: Grid, face_size: usize, rate: u32, symmetric: bool) -> (Vec<Dyadic>, Vec<Slot>, Vec<Dyadic>) {
        let points = grid.points(face_size, rate);
        let mut stored = Vec::new();
        let mut index: HashMap<Dyadic, u32> = HashMap::new();
        for p in points.iter().filter(|p| !symmetric || p.u >= p.v) {
            index.insert(*p, stored.len() as u32);
            stored.push(*p);
        }
        let slots = points
            .iter()
            .map(|p| match index.get(p) {
                Some(&stored) => Slot { stored, mirrored: false },
                None => Slot { stored: index[&Dyadic::new(p.v, p.u, p.denominator)], mirrored: true },
            })
            .collect();
        (points, slots, stored)
    }
}

/// The position and tangent stencils of every point of the primal and dual grids of one patch
/// type at one rate, for the face of the patch type's own shape (shape 0 of its
/// [`PatchMatrices`]), over its control points in [`subdiv_mesh::Patch`] order.
///
/// A shape symmetric under swapping `u` and `v` ([`PatchShape::mirror`](subdiv_schemes::PatchShape::mirror))
/// stores only the points with `u ≥ v`; the others are read through the mirror.
///
/// ```
/// use subdiv_mesh::BoundaryInterpolation;
/// use subdiv_schemes::{Builtin, PatchType};
/// use subdiv_stencil::{Grid, StencilTable};
///
/// let cc = Builtin::CatmullClark.scheme();
/// let table = StencilTable::compute(cc, PatchType::interior(5), BoundaryInterpolation::EdgeOnly, 3)?;
/// assert_eq!((table.len(Grid::Primal), table.len(Grid::Dual)), (16, 9));
/// // Stored: the primal points with u ≥ v, 10 of 16, and 6 of the 9 dual ones.
/// assert_eq!(table.stored_points(), 16);
/// let s = table.stencil(Grid::Dual, 4); // the centre, (1/2, 1/2)
/// assert!((s.position.iter().sum::<f64>() - 1.0).abs() < 1e-12);
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct StencilTable {
    patch_type: PatchType,
    boundary: BoundaryInterpolation,
    matrices_fingerprint: u64,
    face_size: usize,
    size: usize,
    rate: u32,
    mirror: Option<Vec<u32>>,
    grids: [GridStencils; 2],
}

impl StencilTable {
    /// The table of `scheme`'s patch type at `rate`.
    ///
    /// # Errors
    /// As [`PatchMatrices::of`] (as [`StencilError::Scheme`]) and [`surface_stencil`](crate::surface_stencil);
    /// [`StencilError::Rate`] for rate 0 or above [`MAX_TABLE_RATE`].
    pub fn compute(
        scheme: &Scheme,
        patch_type: PatchType,
        boundary: BoundaryInterpolation,
        rate: u32,
    ) -> Result<Self, StencilError> {
        let matrices = PatchMatrices::of(scheme, patch_type, boundary)?;
        Self::compute_rates(&matrices, boundary, rate..=rate).map(|mut tables| tables.remove(0))
    }

    /// The tables of `matrices`' patch type at every rate of `rates`, sharing the work between
    /// them (their grids meet in many points). `boundary` is the rule the matrices were derived
    /// with, recorded in the tables.
    ///
    /// # Errors
    /// As [`compute`](Self::compute).
    pub fn compute_rates(
        matrices: &PatchMatrices,
        boundary: BoundaryInterpolation,
        rates: RangeInclusive<u32>,
    ) -> Result<Vec<Self>, StencilError> {
        let shape = &matrices.shapes[0];
        let mut evaluator = StencilEvaluator::new(matrices);
        let fingerprint = matrices_fingerprint(matrices);
        let mut tables = Vec::new();
        for rate in rates {
            check_rate(rate)?;
            let grids = Grid::ALL.map(|grid| -> Result<GridStencils, StencilError> {
                let (points, slots, stored) =
                    GridStencils::layout(grid, matrices.face_size, rate, shape.mirror.is_some());
                let mut exact = Vec::with_capacity(stored.len());
                let mut weights = Vec::with_capacity(stored.len() * 3 * shape.size);
                for p in stored {
                    let s = evaluator.stencil(0, p)?;
                    exact.push(s.exact_derivatives);
                    weights.extend_from_slice(&s.position);
                    weights.extend_from_slice(&s.du);
                    weights.extend_from_slice(&s.dv);
                }
                Ok(GridStencils { points, slots, exact, weights })
            });
            let [primal, dual] = grids;
            tables.push(Self {
                patch_type: matrices.patch_type,
                boundary,
                matrices_fingerprint: fingerprint,
                face_size: matrices.face_size,
                size: shape.size,
                rate,
                mirror: shape.mirror.clone(),
                grids: [primal?, dual?],
            });
        }
        Ok(tables)
    }

    /// The patch type.
    pub fn patch_type(&self) -> PatchType {
        self.patch_type
    }

    /// The boundary rule the patch matrices were derived with.
    pub fn boundary(&self) -> BoundaryInterpolation {
        self.boundary
    }

    /// The rate `n`.
    pub fn rate(&self) -> u32 {
        self.rate
    }

    /// The face's size: 4 or 3.
    pub fn face_size(&self) -> usize {
        self.face_size
    }

    /// The number of control points each stencil weighs.
    pub fn control_points(&self) -> usize {
        self.size
    }

    /// The number of points of `grid`.
    pub fn len(&self, grid: Grid) -> usize {
        self.grid(grid).points.len()
    }

    /// Whether `grid` has no points (never, for rates of 1 or more).
    pub fn is_empty(&self, grid: Grid) -> bool {
        self.len(grid) == 0
    }

    /// The number of points whose stencils are stored, over both grids.
    pub fn stored_points(&self) -> usize {
        self.grids.iter().map(|g| g.exact.len()).sum()
    }

    /// The parameter of point `index` of `grid`.
    pub fn point(&self, grid: Grid, index: usize) -> Dyadic {
        self.grid(grid).points[index]
    }

    /// The stencil of point `index` of `grid`.
    ///
    /// # Panics
    /// If `index` is not below [`len`](Self::len).
    pub fn stencil(&self, grid: Grid, index: usize) -> SurfaceStencil {
        let g = self.grid(grid);
        let slot = g.slots[index];
        let [position, du, dv] = self.stored(g, slot.stored);
        let exact_derivatives = g.exact[slot.stored as usize];
        match (&self.mirror, slot.mirrored) {
            (Some(mirror), true) => {
                let permute = |w: &[f64]| {
                    let mut out = vec![0.0; w.len()];
                    for (k, &x) in w.iter().enumerate() {
                        out[mirror[k] as usize] = x;
                    }
                    out
                };
                SurfaceStencil { position: permute(position), du: permute(dv), dv: permute(du), exact_derivatives }
            }
            _ => SurfaceStencil { position: position.to_vec(), du: du.to_vec(), dv: dv.to_vec(), exact_derivatives },
        }
    }

    /// Point `index` of `grid` on the surface of the patch with control points `points` (in
    /// [`subdiv_mesh::Patch`] order): position, ∂/∂u and ∂/∂v, without allocating.
    ///
    /// # Panics
    /// If `index` is not below [`len`](Self::len) or `points` is shorter than
    /// [`control_points`](Self::control_points).
    #[inline]
    pub fn apply(&self, grid: Grid, index: usize, points: &[DVec3]) -> [DVec3; 3] {
        let g = self.grid(grid);
        let slot = g.slots[index];
        let [position, du, dv] = self.stored(g, slot.stored);
        let (mut p, mut a, mut b) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        match (&self.mirror, slot.mirrored) {
            (Some(mirror), true) => {
                for k in 0..self.size {
                    let x = points[mirror[k] as usize];
                    p += x * position[k];
                    a += x * dv[k];
                    b += x * du[k];
                }
            }
            _ => {
                for (k, &x) in points[..self.size].iter().enumerate() {
                    p += x * position[k];
                    a += x * du[k];
                    b += x * dv[k];
                }
            }
        }
        [p, a, b]
    }

    fn grid(&self, grid: Grid) -> &GridStencils {
        &self.grids[usize::from(grid.code())]
    }

    fn stored<'a>(&self, g: &'a GridStencils, stored: u32) -> [&'a [f64]; 3] {
        let start = stored as usize * 3 * self.size;
        let w = &g.weights[start..start + 3 * self.size];
        [&w[..self.size], &w[self.size..2 * self.size], &w[2 * self.size..]]
    }
}

/// The largest rate a table takes: its dual grid has `(2n)²` cells' worth of denominators and
/// `n²` points, so 1024 is far beyond what tessellation asks for. (The curve grids'
/// [`MAX_CURVE_RATE`](crate::curve::MAX_CURVE_RATE) is the same number for another reason: it
/// bounds exact rational systems.)
pub const MAX_TABLE_RATE: u32 = 1024;

fn check_rate(rate: u32) -> Result<(), StencilError> {
    if rate == 0 || rate > MAX_TABLE_RATE {
        return Err(StencilError::Rate {
            rate: u64::from(rate),
            reason: "stencil tables take rates 1 to 1024 (MAX_TABLE_RATE)",
        });
    }
    Ok(())
}

/// A set of [`StencilTable`]s of one scheme, and their binary file format.
///
/// The format (little-endian): the magic bytes `SUBDIVST`, the format version (u32), the
/// scheme's name (u32 length, UTF-8) and fingerprint (u64, FNV-1a of its TOML text), the table
/// count (u32); per table its layout — patch type (u8 kind, two u32), boundary rule (u8),
/// the fingerprint of its derived sub-patch matrices (u64), face size (u8), control points
/// (u32), rate (u32), the mirror permutation (u8 flag, then u32 per control point) — then per
/// grid (primal, dual) its stored point count (u32) and per stored point a flag (u8, exact
/// derivatives) and the position, ∂/∂u and ∂/∂v weights (f64 each); last, an FNV-1a checksum
/// (u64) of everything before it. Which points are stored follows from the layout (see
/// [`Grid`] and [`StencilTable`]). [`from_bytes`](Self::from_bytes) rejects a foreign file, another version, another
/// scheme, tables whose matrices the code now derives differently, and corrupt data, each with
/// an error that says so.
#[derive(Clone, Debug, PartialEq)]
pub struct StencilTables {
    scheme: String,
    fingerprint: u64,
    tables: Vec<StencilTable>,
}

/// The first bytes of a table file.
pub const TABLE_MAGIC: [u8; 8] = *b"SUBDIVST";

/// The table format version this build reads and writes.
pub const TABLE_VERSION: u32 = 1;

impl StencilTables {
    /// The tables of `scheme` for every patch type of `patch_types` at every rate of `rates`,
    /// the patch types in parallel with the `rayon` feature (on by default), one after the
    /// other without it. The result, or the first patch type's error, is the same either way
    /// and whatever the thread count.
    ///
    /// ```
    /// use subdiv_mesh::BoundaryInterpolation;
    /// use subdiv_schemes::{Builtin, PatchType};
    /// use subdiv_stencil::StencilTables;
    ///
    /// let loop_ = Builtin::Loop.scheme();
    /// let types = [PatchType::interior(5), PatchType::interior(6)];
    /// let tables = StencilTables::compute(loop_, &types, BoundaryInterpolation::EdgeOnly, 1..=4)?;
    /// assert_eq!(tables.tables().len(), 8);
    /// let bytes = tables.to_bytes();
    /// assert_eq!(StencilTables::from_bytes(&bytes, loop_)?, tables);
    /// # Ok::<(), subdiv_stencil::StencilError>(())
    /// ```
    ///
    /// # Errors
    /// As [`StencilTable::compute`].
    pub fn compute(
        scheme: &Scheme,
        patch_types: &[PatchType],
        boundary: BoundaryInterpolation,
        rates: RangeInclusive<u32>,
    ) -> Result<Self, StencilError> {
        Self::compute_on(Threads::Any, scheme, patch_types, boundary, rates)
    }

    /// [`compute`](Self::compute) on `threads`.
    fn compute_on(
        threads: Threads,
        scheme: &Scheme,
        patch_types: &[PatchType],
        boundary: BoundaryInterpolation,
        rates: RangeInclusive<u32>,
    ) -> Result<Self, StencilError> {
        let per_type: Vec<Vec<StencilTable>> = parallel::map(patch_types, threads, |&t| {
            let matrices = PatchMatrices::of(scheme, t, boundary)?;
            StencilTable::compute_rates(&matrices, boundary, rates.clone())
        })
        .into_iter()
        .collect::<Result<_, _>>()?;
        Ok(Self {
            scheme: scheme.name.clone(),
            fingerprint: scheme.identity(),
            tables: per_type.into_iter().flatten().collect(),
        })
    }

    /// The scheme's name.
    pub fn scheme(&self) -> &str {
        &self.scheme
    }

    /// The tables, in the order they were computed (patch type, then rate).
    pub fn tables(&self) -> &[StencilTable] {
        &self.tables
    }

    /// The table of `patch_type` and `boundary` at `rate`, if present.
    pub fn get(&self, patch_type: PatchType, boundary: BoundaryInterpolation, rate: u32) -> Option<&StencilTable> {
        self.tables.iter().find(|t| t.patch_type == patch_type && t.boundary == boundary && t.rate == rate)
    }

    /// The tables in the binary format.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(&TABLE_MAGIC);
        out.extend_from_slice(&TABLE_VERSION.to_le_bytes());
        put_u32(&mut out, self.scheme.len() as u32);
        out.extend_from_slice(self.scheme.as_bytes());
        out.extend_from_slice(&self.fingerprint.to_le_bytes());
        put_u32(&mut out, self.tables.len() as u32);
        for t in &self.tables {
            // Kinds 2 and 3 are 0 and 1 with sharp features, which follow as the spoke mask
            // (u64) and the corner flag (u8), so that smooth tables keep their bytes.
            let (kind, a, b) = match t.patch_type {
                PatchType::Interior { valence, .. } => (0, valence, 0),
                PatchType::Boundary { faces, index, .. } => (1, faces, index),
                // `compute` takes its types from `PatchMatrices::of`, which derives none, and
                // `from_bytes` reads none.
                PatchType::Derived { .. } => unreachable!("a set of stencil tables holds no derived configuration"),
            };
            let sharp = t.patch_type.sharp();
            out.push(if sharp.is_smooth() { kind } else { kind + 2 });
            put_u32(&mut out, a as u32);
            put_u32(&mut out, b as u32);
            if !sharp.is_smooth() {
                out.extend_from_slice(&sharp.edges.to_le_bytes());
                out.push(u8::from(sharp.corner));
            }
            out.push(t.boundary.code());
            out.extend_from_slice(&t.matrices_fingerprint.to_le_bytes());
            out.push(t.face_size as u8);
            put_u32(&mut out, t.size as u32);
            put_u32(&mut out, t.rate);
            match &t.mirror {
                Some(mirror) => {
                    out.push(1);
                    mirror.iter().for_each(|&k| put_u32(&mut out, k));
                }
                None => out.push(0),
            }
            for g in &t.grids {
                put_u32(&mut out, g.exact.len() as u32);
                for (k, &exact) in g.exact.iter().enumerate() {
                    out.push(u8::from(exact));
                    for w in &g.weights[k * 3 * t.size..(k + 1) * 3 * t.size] {
                        out.extend_from_slice(&w.to_le_bytes());
                    }
                }
            }
        }
        let checksum = fnv1a(&out);
        out.extend_from_slice(&checksum.to_le_bytes());
        out
    }

    /// Reads tables written by [`to_bytes`](Self::to_bytes) for `scheme`, checking each
    /// table's sub-patch matrices against the ones this build derives.
    ///
    /// # Errors
    /// [`StencilError::TableForeign`] for bytes that are not a table file,
    /// [`StencilError::TableVersion`] for another format version, [`StencilError::TableStale`]
    /// for another scheme or matrices derived differently since, [`StencilError::TableCorrupt`]
    /// for truncated or damaged data.
    pub fn from_bytes(bytes: &[u8], scheme: &Scheme) -> Result<Self, StencilError> {
        if bytes.len() < 12 || bytes[..8] != TABLE_MAGIC {
            return Err(StencilError::TableForeign);
        }
        let mut r = ByteReader::new(bytes);
        r.take(8)?;
        let version = r.u32()?;
        if version != TABLE_VERSION {
            return Err(StencilError::TableVersion { found: version, expected: TABLE_VERSION });
        }
        let (body, tail) = bytes.split_at(bytes.len().saturating_sub(8).max(12));
        if u64::from_le_bytes(tail.try_into().map_err(|_| StencilError::from(r.corrupt("no checksum")))?) != fnv1a(body)
        {
            return Err(StencilError::TableCorrupt {
                offset: body.len(),
                detail: "the checksum does not match".into(),
            });
        }
        let mut r = ByteReader::new(body);
        r.take(12)?;
        let name_len = r.u32()? as usize;
        let name = std::str::from_utf8(r.take(name_len)?)
            .map_err(|_| StencilError::from(r.corrupt("the scheme name is not UTF-8")))?;
        if name != scheme.name {
            return Err(StencilError::TableStale {
                detail: format!("the tables are for scheme `{name}`, not `{}`", scheme.name),
            });
        }
        let fingerprint = r.u64()?;
        if fingerprint != scheme.identity() {
            return Err(StencilError::TableStale {
                detail: format!(
                    "the tables were written for another definition of `{name}` (fingerprint {fingerprint:016x}, \
                     now {:016x}); regenerate them",
                    scheme.identity()
                ),
            });
        }
        let count = r.u32()?;
        let mut tables = Vec::new();
        let mut matrices_prints: HashMap<(PatchType, BoundaryInterpolation), u64> = HashMap::new();
        for _ in 0..count {
            let kind = r.u8()?;
            let (a, b) = (r.u32()? as usize, r.u32()? as usize);
            let sharp = match kind {
                0 | 1 => SharpFeatures::SMOOTH,
                2 | 3 => SharpFeatures { edges: r.u64()?, corner: r.u8()? != 0 },
                _ => return Err(StencilError::from(r.corrupt(format!("unknown patch kind {kind}")))),
            };
            let patch_type = match kind {
                0 | 2 => PatchType::Interior { valence: a, sharp },
                _ => PatchType::Boundary { faces: a, index: b, sharp },
            };
            let code = r.u8()?;
            let boundary = BoundaryInterpolation::from_code(code.into())
                .ok_or_else(|| StencilError::from(r.corrupt(format!("unknown boundary rule {code}"))))?;
            let written_from = r.u64()?;
            let face_size = usize::from(r.u8()?);
            let size = r.u32()? as usize;
            let rate = r.u32()?;
            check_rate(rate).map_err(|_| StencilError::from(r.corrupt(format!("rate {rate}"))))?;
            let known = match matrices_prints.get(&(patch_type, boundary)) {
                Some(&known) => known,
                None => {
                    let matrices = PatchMatrices::of(scheme, patch_type, boundary)?;
                    let (print, shape) = (matrices_fingerprint(&matrices), &matrices.shapes[0]);
                    if (matrices.face_size, shape.size) != (face_size, size) {
                        return Err(StencilError::TableStale {
                            detail: format!(
                                "{patch_type:?}: the table has {size} control points on a {face_size}-sided face, \
                                 the matrices {} on a {}-sided one",
                                shape.size, matrices.face_size
                            ),
                        });
                    }
                    matrices_prints.insert((patch_type, boundary), print);
                    print
                }
            };
            if known != written_from {
                return Err(StencilError::TableStale {
                    detail: format!(
                        "{patch_type:?} at rate {rate}: the sub-patch matrices this build derives differ from \
                         those the table was computed from; regenerate it"
                    ),
                });
            }
            let mirror = match r.u8()? {
                0 => None,
                1 => {
                    let m = (0..size).map(|_| r.u32()).collect::<Result<Vec<_>, _>>()?;
                    if m.iter().any(|&k| k as usize >= size) {
                        return Err(StencilError::from(r.corrupt("a mirror index is out of range")));
                    }
                    Some(m)
                }
                flag => return Err(StencilError::from(r.corrupt(format!("unknown mirror flag {flag}")))),
            };
            let mut grids = Vec::new();
            for grid in Grid::ALL {
                let (points, slots, stored) = GridStencils::layout(grid, face_size, rate, mirror.is_some());
                let count = r.u32()? as usize;
                if count != stored.len() {
                    return Err(StencilError::from(r.corrupt(format!(
                        "{patch_type:?} at rate {rate}: {count} stored {grid:?} points, the layout has {}",
                        stored.len()
                    ))));
                }
                let mut exact = Vec::with_capacity(count);
                let mut weights = Vec::with_capacity(count * 3 * size);
                for _ in 0..count {
                    exact.push(r.u8()? != 0);
                    for _ in 0..3 * size {
                        weights.push(f64::from_le_bytes(r.take(8)?.try_into().expect("8 bytes")));
                    }
                }
                grids.push(GridStencils { points, slots, exact, weights });
            }
            let dual = grids.pop().expect("two grids");
            let primal = grids.pop().expect("two grids");
            tables.push(StencilTable {
                patch_type,
                boundary,
                matrices_fingerprint: written_from,
                face_size,
                size,
                rate,
                mirror,
                grids: [primal, dual],
            });
        }
        if !r.is_at_end() {
            return Err(StencilError::from(r.corrupt("bytes left over after the last table")));
        }
        Ok(Self { scheme: name.to_string(), fingerprint, tables })
    }
}

/// Stencil tables computed on demand and kept, safe to share between threads.
///
/// ```
/// use subdiv_mesh::BoundaryInterpolation;
/// use subdiv_schemes::{Builtin, PatchType};
/// use subdiv_stencil::{Grid, StencilCache};
///
/// let cache = StencilCache::new(Builtin::CatmullClark.scheme(), BoundaryInterpolation::EdgeOnly);
/// let table = cache.table(PatchType::interior(3), 5)?;
/// // The second request is the same table.
/// assert!(std::sync::Arc::ptr_eq(&table, &cache.table(PatchType::interior(3), 5)?));
/// assert_eq!(table.len(Grid::Dual), 25);
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Debug)]
pub struct StencilCache {
    scheme: Scheme,
    boundary: BoundaryInterpolation,
    tables: Mutex<HashMap<(PatchType, u32), Arc<StencilTable>>>,
}

impl StencilCache {
    /// An empty cache for `scheme` with the boundary rule `boundary`.
    pub fn new(scheme: &Scheme, boundary: BoundaryInterpolation) -> Self {
        Self { scheme: scheme.clone(), boundary, tables: Mutex::default() }
    }

    /// The cache holding `tables` already (those with this cache's boundary rule).
    ///
    /// # Errors
    /// [`StencilError::TableStale`] if `tables` are another scheme's.
    pub fn with_tables(self, tables: StencilTables) -> Result<Self, StencilError> {
        if tables.scheme != self.scheme.name || tables.fingerprint != self.scheme.identity() {
            return Err(StencilError::TableStale {
                detail: format!("the tables are for `{}`, the cache for `{}`", tables.scheme, self.scheme.name),
            });
        }
        {
            let mut held = self.tables.lock().unwrap_or_else(PoisonError::into_inner);
            for t in tables.tables.into_iter().filter(|t| t.boundary == self.boundary) {
                held.insert((t.patch_type, t.rate), Arc::new(t));
            }
        }
        Ok(self)
    }

    /// The table of `patch_type` at `rate`, computed now if it is not held yet.
    ///
    /// # Errors
    /// As [`StencilTable::compute`].
    pub fn table(&self, patch_type: PatchType, rate: u32) -> Result<Arc<StencilTable>, StencilError> {
        let key = (patch_type, rate);
        if let Some(t) = self.tables.lock().unwrap_or_else(PoisonError::into_inner).get(&key) {
            return Ok(t.clone());
        }
        // Computed outside the lock, so that other tables can be read meanwhile; a race
        // computes twice and keeps the first, both equal.
        let computed = Arc::new(StencilTable::compute(&self.scheme, patch_type, self.boundary, rate)?);
        let mut held = self.tables.lock().unwrap_or_else(PoisonError::into_inner);
        Ok(held.entry(key).or_insert(computed).clone())
    }
}

/// A set of tables the project keeps ready: a built-in scheme, its interior valences and the
/// rates, and the file (under `crates/subdiv-stencil/tables/`) that `cargo xtask tables`
/// writes them to.
#[derive(Clone, Debug)]
pub struct TableSpec {
    /// The scheme.
    pub scheme: Builtin,
    /// The interior valences of the patch types (boundary rule: edge-only).
    pub valences: RangeInclusive<usize>,
    /// The rates.
    pub rates: RangeInclusive<u32>,
    /// The file name.
    pub file: &'static str,
}

impl TableSpec {
    /// The patch types: one interior patch per valence.
    pub fn patch_types(&self) -> Vec<PatchType> {
        self.valences.clone().map(PatchType::interior).collect()
    }

    /// Computes the tables.
    ///
    /// # Errors
    /// As [`StencilTables::compute`].
    pub fn compute(&self) -> Result<StencilTables, StencilError> {
        StencilTables::compute(
            self.scheme.scheme(),
            &self.patch_types(),
            BoundaryInterpolation::EdgeOnly,
            self.rates.clone(),
        )
    }
}

/// The default tables: Catmull-Clark and Loop, valences 3 to 8, rates 1 to 24 — the range
/// paper 000 §6 precomputes.
pub const DEFAULT_TABLES: [TableSpec; 2] = [
    TableSpec { scheme: Builtin::CatmullClark, valences: 3..=8, rates: 1..=24, file: "catmull-clark.stencils" },
    TableSpec { scheme: Builtin::Loop, valences: 3..=8, rates: 1..=24, file: "loop.stencils" },
];

/// FNV-1a, 64 bits: a fingerprint that is the same on every platform and build.
/// A fingerprint of everything a table's numbers follow from: the shapes, their children and
/// the matrices' entries (exact bits: the engine's arithmetic is the same everywhere).
fn matrices_fingerprint(m: &PatchMatrices) -> u64 {
    let mut bytes = Vec::new();
    bytes.extend_from_slice(&(m.radius as u64).to_le_bytes());
    bytes.extend_from_slice(&(m.face_size as u64).to_le_bytes());
    for shape in &m.shapes {
        bytes.extend_from_slice(&(shape.size as u64).to_le_bytes());
        shape.signature.iter().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes()));
        for child in &shape.children {
            bytes.extend_from_slice(&(child.shape as u64).to_le_bytes());
            bytes.extend_from_slice(&child.domain.offset);
            bytes.push(u8::from(child.domain.flipped));
            for r in 0..child.rows() {
                child.dense_row(r).iter().for_each(|x| bytes.extend_from_slice(&x.to_bits().to_le_bytes()));
            }
        }
    }
    fnv1a(&bytes)
}

fn put_u32(out: &mut Vec<u8>, x: u32) {
    out.extend_from_slice(&x.to_le_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tables computed one patch type after the other on the calling thread are those of
    /// the default path (in parallel with the `rayon` feature), bit for bit, and so is the
    /// error when a patch type fails.
    #[test]
    fn the_serial_path_gives_the_bits_of_the_parallel_one() {
        let edge = BoundaryInterpolation::EdgeOnly;
        let types = [
            PatchType::interior(3),
            PatchType::interior(5),
            PatchType::boundary(2, 0),
            PatchType::interior(6),
            PatchType::boundary(3, 1),
        ];
        for builtin in [Builtin::CatmullClark, Builtin::Loop] {
            let scheme = builtin.scheme();
            let parallel = StencilTables::compute_on(Threads::Any, scheme, &types, edge, 1..=5).unwrap();
            let serial = StencilTables::compute_on(Threads::Calling, scheme, &types, edge, 1..=5).unwrap();
            assert_eq!(parallel.tables().len(), types.len() * 5);
            assert_eq!(serial.to_bytes(), parallel.to_bytes(), "{builtin}");
            assert_eq!(StencilTables::compute(scheme, &types, edge, 1..=5).unwrap(), parallel, "{builtin}");
        }
        let failing = [PatchType::interior(5), PatchType::interior(1), types[2]];
        let scheme = Builtin::CatmullClark.scheme();
        let parallel = StencilTables::compute_on(Threads::Any, scheme, &failing, edge, 1..=2).unwrap_err();
        let serial = StencilTables::compute_on(Threads::Calling, scheme, &failing, edge, 1..=2).unwrap_err();
        assert_eq!(serial, parallel);
    }
}
