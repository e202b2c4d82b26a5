//! Route 1 on surfaces (paper 000 §2, §4, §5.1): the basis function of a scheme's regular rules
//! from its scaling relation on the grid `(1/n)ℤ²`, exactly.
//!
//! On a regular grid every control point `p_j` sits at a lattice point `j` and the limit surface
//! is `Σ_j p_j φ(x − j)` for one basis function `φ`. Refining once (√3: twice) puts the refined
//! points on the lattice `(1/a)ℤ²`, `a` the arity, and gives the scaling relation
//! `φ(x) = Σ_k s_k φ(a·x − k)`, where `s_k` is the weight of the control point at the origin in
//! the refined point at `k/a` ([`SurfaceMask`]). Lattices are written in the patch's own frame
//! (see DESIGN.md): quads on `ℤ²`, triangles on `ℤ²` with the grid lines along `(1, 0)`,
//! `(0, 1)` and `(1, −1)` (the triangle `(0, 0), (1, 0), (0, 1)` is a face).
//!
//! **√3.** One √3 step turns the lattice by 30° and shrinks it by √3; two steps turn it by 60°
//! and shrink it by 3, and a turn by 60° maps the triangular lattice and its grid lines onto
//! themselves. So two steps are a ternary scheme on the same lattice, `a = 3` and `A = 3·I`:
//! the rotation does not survive into the relation, because the refined points' lattice
//! coordinates are read from where the rules put them (their rows applied to the control
//! points' coordinates), not from a turned numbering. [`SurfaceMask::from_scheme`] checks that
//! every refined point lands on `(1/3)ℤ²` and that each of the nine rules sums to exactly 1.
//!
//! **The system and its reduction.** At `x = m/n` the relation reads
//! `φ(m/n) = Σ_k s_k φ((a·m − n·k)/n)`: the unknowns with numerators `m ≡ r (mod n)` depend
//! only on those with residue `a·r mod n`. The residues therefore fall into chains that end
//! in cycles of `r ↦ a·r mod n`. Round a cycle `r_0 → … → r_(L−1) → r_0` the relation is
//! `v = D^−L·Q·v` for the values `v` at `r_0`'s points, `Q` a product of integer matrices
//! formed exactly (`D` the mask's common denominator); that, with the partition of unity
//! `Σ_j φ(r_0/n − j) = 1`, is the one system solved per cycle, with one unknown per grid point
//! of `r_0` in the closed support (the convex hull of the mask's offsets over `a − 1`). Every
//! other residue, on the cycle or leading into it, follows by substitution. So where the
//! unreduced system has about `n² × area(support)` unknowns, each solved system has about
//! `area(support)` ([`SystemSizes`] counts both). Cycles that a symmetry of the mask maps onto
//! a solved one are copied (`φ(M·x) = φ(x)` for every lattice map `M` that keeps the mask). A
//! point's stencil needs only its own residue's chain ([`SurfaceBasisGrid::at_residues`]).
//! The cost is in the big numbers: `Q`'s entries have about `L·log₂(D·|mask|)` bits, and the
//! exact elimination multiplies that by the unknowns (Kobbelt's scheme at `n = 29`, `L = 28`:
//! 42 unknowns, seconds).
//!
//! **Derivatives** (§4): `∂φ/∂u` and `∂φ/∂v` satisfy the relation with the factor `a`, and are
//! normalised per residue on the linear functions: `Σ_j ψ(x − j) = 0`, and
//! `Σ_j (j_u − x_u) ψ(x − j)`, `Σ_j (j_v − x_v) ψ(x − j)` equal to `(1, 0)` for `ψ = ∂φ/∂u`
//! and `(0, 1)` for `ψ = ∂φ/∂v`. Under a symmetry `M`, `∇φ(x) = Mᵀ ∇φ(M·x)`.

use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex, OnceLock};

use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{One, Zero};
use subdiv_mesh::{BoundaryInterpolation, DVec3, Mesh, PolygonSoup, VertexId};
use subdiv_schemes::{PatchMatrices, PatchType, RefineOptions, Refiner, Scheme, SchemeError, Split};

use crate::address::check_domain;
use crate::rational::{Rational, SparseRow, exact_weight, solve_sparse};
use crate::{Dyadic, StencilError, SurfaceStencil};

/// The largest grid rate [`SurfaceBasisGrid`] accepts: a whole grid has about
/// `rate² × area(support)` points, and a residue cycle up to `rate − 1` residues.
pub const MAX_SURFACE_BASIS_RATE: u32 = 128;

/// A 2×2 integer matrix, row by row.
type Matrix = [[i64; 2]; 2];

fn apply(m: &Matrix, x: [i64; 2]) -> [i64; 2] {
    [m[0][0] * x[0] + m[0][1] * x[1], m[1][0] * x[0] + m[1][1] * x[1]]
}

/// The lattice of a scheme's regular grid, in the patch's frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Lattice {
    /// Quads: `ℤ²`, grid lines along `(1, 0)` and `(0, 1)`.
    Quad,
    /// Triangles: `ℤ²` with grid lines along `(1, 0)`, `(0, 1)` and `(1, −1)`.
    Triangle,
}

impl Lattice {
    /// The directions of the edges at a vertex.
    fn directions(self) -> &'static [[i64; 2]] {
        match self {
            Self::Quad => &[[1, 0], [0, 1], [-1, 0], [0, -1]],
            Self::Triangle => &[[1, 0], [0, 1], [-1, 1], [-1, 0], [0, -1], [1, -1]],
        }
    }

    /// The lattice maps that keep the grid lines: 8 for quads, 12 for triangles.
    fn automorphisms(self) -> Vec<Matrix> {
        let d = self.directions();
        let mut out = Vec::new();
        for &c0 in d {
            for &c1 in d {
                let m = [[c0[0], c1[0]], [c0[1], c1[1]]];
                let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
                if det.abs() == 1 && d.iter().all(|&e| d.contains(&apply(&m, e))) {
                    out.push(m);
                }
            }
        }
        out
    }

    /// A flat torus of `size × size` cells in which every vertex is regular; vertex `(i, j)` has
    /// id `j·size + i` and position `(i, j, 0)` (positions play no part in the rows).
    fn torus(self, size: usize) -> PolygonSoup {
        let mut soup = PolygonSoup::with_capacity(size * size, 2 * size * size, 6 * size * size);
        for j in 0..size {
            for i in 0..size {
                soup.push_vertex(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| VertexId::new(((j % size) * size + i % size) as u32);
        for j in 0..size {
            for i in 0..size {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                match self {
                    Self::Quad => {
                        soup.push_face([a, b, c, d]);
                    }
                    // The diagonal from (i + 1, j) to (i, j + 1): grid lines along (1, −1).
                    Self::Triangle => {
                        soup.push_face([a, b, d]);
                        soup.push_face([b, c, d]);
                    }
                }
            }
        }
        soup
    }
}

/// The cells per side of the torus the mask is read from.
const TORUS: usize = 24;

/// How far (in lattice steps, per coordinate) a refined point's parents may lie from the
/// origin: well inside half the torus, so that no row that touches the origin wraps around.
const REACH: i64 = 6;

/// The scaling relation of a scheme's regular rules, `φ(x) = Σ_k s_k φ(a·x − k)` over lattice
/// offsets `k`, in exact rationals, read from the refinement engine.
///
/// ```
/// use subdiv_schemes::Builtin;
/// use subdiv_stencil::Rational;
/// use subdiv_stencil::surface_basis::{Lattice, SurfaceMask};
///
/// let cc = SurfaceMask::from_scheme(Builtin::CatmullClark.scheme())?;
/// assert_eq!((cc.lattice(), cc.arity(), cc.weights().len()), (Lattice::Quad, 2, 25));
/// // The tensor product of the cubic B-spline's (1, 4, 6, 4, 1)/8 with itself.
/// assert_eq!(cc.weight([0, 0]), Rational::new(36, 64).unwrap());
/// assert_eq!(cc.weight([2, 1]), Rational::new(4, 64).unwrap());
/// let sqrt3 = SurfaceMask::from_scheme(subdiv_schemes::Builtin::Sqrt3.scheme())?;
/// assert_eq!((sqrt3.lattice(), sqrt3.arity(), sqrt3.steps()), (Lattice::Triangle, 3, 2));
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SurfaceMask {
    name: String,
    lattice: Lattice,
    arity: u32,
    steps: usize,
    weights: Vec<([i64; 2], Rational)>,
    /// Whether the control points sit at `ℤ² + (½, ½)` (the dual splits: Doo-Sabin, mid-edge by
    /// its two steps), so that the mask is that of `ψ(x) = φ(x − (½, ½))`, the basis function
    /// of the control point at `(½, ½)`: with `φ(y) = Σ s φ(2y − k)` over half-integer `k`,
    /// `ψ(x) = Σ s ψ(2x − (k + (½, ½)))`, integer shifts again.
    half: bool,
    /// The convex hull of the offsets, counter-clockwise.
    hull: Vec<[i64; 2]>,
    /// The lattice maps `M` with `s_{M·k} = s_k`.
    symmetries: Vec<Matrix>,
}

impl SurfaceMask {
    /// The largest denominator a rule's weight may have.
    pub const MAX_DENOMINATOR: u64 = 1_000_000;

    /// The mask of `scheme`'s regular rules: a flat torus of regular quads or triangles is
    /// refined by the engine (√3: two steps, composed exactly), each refined point's lattice
    /// position is its row applied to its parents' positions, and the weight of the parent at
    /// the origin in the refined point at `k/a` is `s_k`. Checked: every weight is a fraction
    /// with a denominator up to [`MAX_DENOMINATOR`](Self::MAX_DENOMINATOR), every refined point
    /// lies on `(1/a)ℤ²` (the dual splits: on `(1/a)(ℤ² + (½, ½))`, read as the mask of the
    /// basis shifted by `(½, ½)`, see [`control_offset`](Self::control_offset)), and each of
    /// the `a²` rules sums to exactly 1. Mid-edge is read as its two steps, one dual step
    /// ([`Scheme::dual_form`]).
    ///
    /// # Errors
    /// Engine errors; [`StencilError::SurfaceMask`] when a check fails.
    pub fn from_scheme(scheme: &Scheme) -> Result<Self, StencilError> {
        let (lattice, arity, half) = match scheme.split() {
            Split::Quad => (Lattice::Quad, 2, false),
            Split::Triangle => (Lattice::Triangle, 2, false),
            Split::Sqrt3 => (Lattice::Triangle, 3, false),
            Split::Dual | Split::Midedge => (Lattice::Quad, 2, true),
        };
        let name = scheme.name().to_owned();
        let fail = |reason: String| StencilError::SurfaceMask { scheme: name.clone(), reason };
        let dual = scheme.dual_form();
        let (refined, steps) = match &dual {
            Some(dual) => (dual, 1),
            None => (scheme, scheme.steps_per_cycle()),
        };
        let mesh = Mesh::build(lattice.torus(TORUS)).map_err(|e| SchemeError::Internal(e.to_string()))?;
        let refiner = Refiner::new(&mesh, refined, steps, &RefineOptions::DEFAULT)?;
        // Rows of the last level over the torus's vertices, composed exactly.
        let mut rows: Vec<BTreeMap<usize, Rational>> =
            (0..mesh.vertex_count()).map(|v| BTreeMap::from([(v, Rational::one())])).collect();
        for level in refiner.levels() {
            let mut next = Vec::with_capacity(level.child_count());
            for child in 0..level.child_count() {
                let mut row = BTreeMap::new();
                for (parent, w) in level.row(child) {
                    let w = exact_weight(w, Self::MAX_DENOMINATOR).ok_or_else(|| {
                        fail(format!("a regular rule's weight {w} is not a fraction with a small denominator"))
                    })?;
                    for (v, x) in &rows[parent] {
                        let entry = row.entry(*v).or_insert_with(Rational::zero);
                        *entry = &*entry + &(&w * x);
                    }
                }
                row.retain(|_, w: &mut Rational| !w.is_zero());
                next.push(row);
            }
            rows = next;
        }
        let coordinate = |v: usize| {
            let wrap = |c: usize| if c >= TORUS / 2 { c as i64 - TORUS as i64 } else { c as i64 };
            [wrap(v % TORUS), wrap(v / TORUS)]
        };
        let a = i64::from(arity);
        let mut weights = BTreeMap::new();
        for row in rows.iter().filter(|row| row.contains_key(&0)) {
            let mut position = [Rational::zero(), Rational::zero()];
            for (&v, w) in row {
                let c = coordinate(v);
                if c.iter().any(|x| x.abs() > REACH) {
                    return Err(fail(format!("a regular rule reaches beyond {REACH} rings")));
                }
                for (p, x) in position.iter_mut().zip(c) {
                    *p = &*p + &(w * &Rational::from_integer(x));
                }
            }
            // ψ's shift a·p + (a − 1)·(½, ½) where the control points sit at half-integers.
            let shift = if half { Rational::new(a - 1, 2).expect("a nonzero denominator") } else { Rational::zero() };
            let scaled = [&position[0], &position[1]].map(|p| &(p * &Rational::from_integer(a)) + &shift);
            if scaled.iter().any(|p| !p.denom().is_one()) {
                return Err(fail(format!(
                    "a refined point lies at ({}, {}), off the lattice (1/{a})Z²{}",
                    position[0],
                    position[1],
                    if half { " + (1/4, 1/4)" } else { "" }
                )));
            }
            let k = scaled.map(|p| p.to_f64() as i64);
            if weights.insert(k, row[&0].clone()).is_some() {
                return Err(fail(format!("two refined points lie at ({}, {})/{a}", k[0], k[1])));
            }
        }
        for r in 0..a * a {
            let residue = [r % a, r / a];
            let sum: Rational = (weights.iter())
                .filter(|(k, _)| (0..2).all(|c| (k[c] - residue[c]).rem_euclid(a) == 0))
                .map(|(_, w)| w)
                .sum();
            if sum != Rational::one() {
                return Err(fail(format!(
                    "the rule of the refined points at (({}, {}) + {a}Z²)/{a} sums to {sum}, not exactly 1",
                    residue[0], residue[1]
                )));
            }
        }
        let weights: Vec<([i64; 2], Rational)> = weights.into_iter().collect();
        let hull = convex_hull(weights.iter().map(|(k, _)| *k).collect());
        if hull.len() < 3 {
            return Err(fail("the mask's offsets lie on a line".into()));
        }
        let lookup: HashMap<[i64; 2], &Rational> = weights.iter().map(|(k, w)| (*k, w)).collect();
        let symmetries = (lattice.automorphisms().into_iter())
            .filter(|m| weights.iter().all(|(k, w)| lookup.get(&apply(m, *k)) == Some(&w)))
            .collect();
        Ok(Self { name, lattice, arity, steps, weights, half, hull, symmetries })
    }

    /// Where the control points sit relative to the lattice `ℤ²`: `(0, 0)`, or `(½, ½)` for the
    /// dual splits, whose [`weights`](Self::weights) are those of the basis function of the
    /// control point at `(½, ½)` (so that the shifts are integers).
    pub fn control_offset(&self) -> [Rational; 2] {
        let h = if self.half { Rational::new(1, 2).expect("a nonzero denominator") } else { Rational::zero() };
        [h.clone(), h]
    }

    /// [`from_scheme`](Self::from_scheme), computed once per scheme and process.
    ///
    /// # Errors
    /// As [`from_scheme`](Self::from_scheme).
    pub fn of(scheme: &Scheme) -> Result<Arc<Self>, StencilError> {
        static CACHE: OnceLock<Mutex<HashMap<String, Arc<SurfaceMask>>>> = OnceLock::new();
        let key = format!("{scheme:?}");
        let cache = CACHE.get_or_init(Mutex::default);
        if let Some(found) = cache.lock().unwrap_or_else(std::sync::PoisonError::into_inner).get(&key) {
            return Ok(found.clone());
        }
        let computed = Arc::new(Self::from_scheme(scheme)?);
        let mut cache = cache.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        Ok(cache.entry(key).or_insert(computed).clone())
    }

    /// The scheme's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The lattice.
    pub fn lattice(&self) -> Lattice {
        self.lattice
    }

    /// The dilation `a`: 2, or 3 for √3 taken two steps at a time.
    pub fn arity(&self) -> u32 {
        self.arity
    }

    /// Refinement steps per dilation: 1, or 2 for √3.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The nonzero weights `(k, s_k)`, by offset.
    pub fn weights(&self) -> &[([i64; 2], Rational)] {
        &self.weights
    }

    /// `s_k` (zero off the mask).
    pub fn weight(&self, k: [i64; 2]) -> Rational {
        self.weights
            .binary_search_by_key(&k, |(o, _)| *o)
            .map_or_else(|_| Rational::zero(), |i| self.weights[i].1.clone())
    }

    /// The corners of the basis function's support, the convex hull of the offsets over
    /// `a − 1`, counter-clockwise (as the hull of the offsets; divide by `a − 1`).
    pub fn hull(&self) -> &[[i64; 2]] {
        &self.hull
    }

    /// How many lattice maps keep the mask (8 for a symmetric quad scheme, 12 for a symmetric
    /// triangle scheme).
    pub fn symmetry_count(&self) -> usize {
        self.symmetries.len()
    }
}

/// The convex hull of integer points, counter-clockwise, without collinear points (Andrew's
/// monotone chain).
fn convex_hull(mut points: Vec<[i64; 2]>) -> Vec<[i64; 2]> {
    points.sort_unstable();
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: [i64; 2], a: [i64; 2], b: [i64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut hull: Vec<[i64; 2]> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[i64; 2]>> =
            if pass == 0 { Box::new(points.iter()) } else { Box::new(points.iter().rev()) };
        for &p in iter {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0 {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The sizes of the systems a [`SurfaceBasisGrid`] solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SystemSizes {
    /// Grid points of the closed support: the unknowns of the unreduced system.
    pub grid_points: usize,
    /// Residue cycles met.
    pub cycles: usize,
    /// The grid points of the residues on those cycles (the unknowns of the cycles' scaling
    /// systems, before each is reduced to its first residue).
    pub cycle_points: usize,
    /// Cycles solved as linear systems; the others were images of solved ones under the
    /// mask's symmetries.
    pub solved_cycles: usize,
    /// The unknowns of all solved systems together: the points of each solved cycle's first
    /// residue (each system is solved for `φ`, `∂φ/∂u` and `∂φ/∂v`).
    pub solved_unknowns: usize,
    /// The unknowns of the largest solved system.
    pub largest_system: usize,
    /// Grid points whose values were computed (solved or substituted).
    pub computed_points: usize,
}

/// Exact position and derivative weights of a limit point over control points at lattice
/// positions.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactStencil {
    /// The control points' lattice positions (the patch's parameters of its control points).
    pub control: Vec<[i64; 2]>,
    /// Position weights `φ(x − c)`; they sum to 1.
    pub position: Vec<Rational>,
    /// `∂/∂u` weights; they sum to 0.
    pub du: Vec<Rational>,
    /// `∂/∂v` weights; they sum to 0.
    pub dv: Vec<Rational>,
}

impl ExactStencil {
    /// The weights in `f64`, as route 3 gives them.
    pub fn to_f64(&self) -> SurfaceStencil {
        let f = |w: &[Rational]| w.iter().map(Rational::to_f64).collect();
        SurfaceStencil { position: f(&self.position), du: f(&self.du), dv: f(&self.dv), exact_derivatives: true }
    }
}

/// `φ`, `∂φ/∂u` and `∂φ/∂v` of a [`SurfaceMask`] on the grid `(1/rate)ℤ²`, exactly (route 1),
/// for every residue or for the residues asked for.
///
/// ```
/// use subdiv_schemes::Builtin;
/// use subdiv_stencil::Rational;
/// use subdiv_stencil::surface_basis::{SurfaceBasisGrid, SurfaceMask};
///
/// let loop_ = SurfaceMask::from_scheme(Builtin::Loop.scheme())?;
/// let grid = SurfaceBasisGrid::new(&loop_, 1)?;
/// // Loop's limit mask at a regular vertex: 1/2 at the vertex, 1/12 at each neighbour.
/// assert_eq!(grid.value([0, 0]), Some(Rational::new(1, 2).unwrap()));
/// assert_eq!(grid.value([1, -1]), Some(Rational::new(1, 12).unwrap()));
/// let s = grid.stencil_at([0, 0]).unwrap();
/// assert_eq!(s.control.len(), 7);
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SurfaceBasisGrid {
    rate: u32,
    /// The numerators' box: `lo[c] ..= lo[c] + extent[c] − 1`.
    lo: [i64; 2],
    extent: [usize; 2],
    phi: Vec<Rational>,
    du: Vec<Rational>,
    dv: Vec<Rational>,
    /// Per residue `r_u + rate·r_v`: whether its points are computed.
    computed: Vec<bool>,
    sizes: SystemSizes,
}

/// The closed support at one rate: numerators `m` with `m/n` in the hull over `a − 1`.
struct Support<'a> {
    hull: &'a [[i64; 2]],
    scale: i64,
    rate: i64,
}

impl Support<'_> {
    fn contains(&self, m: [i64; 2]) -> bool {
        // (a − 1)·m inside rate·hull: on the left of (or on) every counter-clockwise edge.
        let x = [i128::from(self.scale * m[0]), i128::from(self.scale * m[1])];
        let n = i128::from(self.rate);
        (0..self.hull.len()).all(|i| {
            let (p, q) = (self.hull[i], self.hull[(i + 1) % self.hull.len()]);
            let (p0, p1) = (n * i128::from(p[0]), n * i128::from(p[1]));
            let (e0, e1) = (i128::from(q[0] - p[0]), i128::from(q[1] - p[1]));
            e0 * (x[1] - p1) - e1 * (x[0] - p0) >= 0
        })
    }

    /// The box of numerators holding the support: `(lo, extent)`.
    fn bounds(&self) -> ([i64; 2], [usize; 2]) {
        let mut lo = [0; 2];
        let mut extent = [0; 2];
        for c in 0..2 {
            let min = self.hull.iter().map(|p| p[c]).min().unwrap_or(0) * self.rate;
            let max = self.hull.iter().map(|p| p[c]).max().unwrap_or(0) * self.rate;
            lo[c] = min.div_euclid(self.scale) + i64::from(min.rem_euclid(self.scale) != 0);
            let hi = max.div_euclid(self.scale);
            extent[c] = usize::try_from(hi - lo[c] + 1).unwrap_or(0);
        }
        (lo, extent)
    }
}

impl SurfaceBasisGrid {
    /// Every residue: the whole grid over the support.
    ///
    /// # Errors
    /// [`StencilError::Rate`] for a rate of 0 or above [`MAX_SURFACE_BASIS_RATE`];
    /// [`StencilError::SurfaceScalingSystem`] when a system has no unique solution.
    pub fn new(mask: &SurfaceMask, rate: u32) -> Result<Self, StencilError> {
        let n = i64::from(rate);
        let all: Vec<[i64; 2]> = (0..n * n).map(|r| [r % n, r / n]).collect();
        Self::at_residues(mask, rate, &all)
    }

    /// The values at the grid points whose numerators are congruent to one of `residues`
    /// modulo the rate, and at those they depend on; the others stay uncomputed
    /// ([`value`](Self::value) gives `None` there).
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn at_residues(mask: &SurfaceMask, rate: u32, residues: &[[i64; 2]]) -> Result<Self, StencilError> {
        if rate == 0 || rate > MAX_SURFACE_BASIS_RATE {
            return Err(StencilError::Rate {
                rate: u64::from(rate),
                reason: "surface grids take rates 1 to MAX_SURFACE_BASIS_RATE (the grid grows with its square)",
            });
        }
        let n = i64::from(rate);
        let support = Support { hull: &mask.hull, scale: i64::from(mask.arity) - 1, rate: n };
        let (lo, extent) = support.bounds();
        let cells = extent[0] * extent[1];
        let mut builder = Builder {
            mask,
            support,
            n,
            grid: Self {
                rate,
                lo,
                extent,
                phi: vec![Rational::zero(); cells],
                du: vec![Rational::zero(); cells],
                dv: vec![Rational::zero(); cells],
                computed: vec![false; (n * n) as usize],
                sizes: SystemSizes::default(),
            },
        };
        builder.grid.sizes.grid_points =
            (0..cells).filter(|&i| builder.support.contains(builder.grid.numerator(i))).count();
        for &r in residues {
            builder.ensure([r[0].rem_euclid(n), r[1].rem_euclid(n)])?;
        }
        Ok(builder.grid)
    }

    /// The grid rate `n`.
    pub fn rate(&self) -> u32 {
        self.rate
    }

    /// The sizes of the systems solved.
    pub fn sizes(&self) -> SystemSizes {
        self.sizes
    }

    fn numerator(&self, index: usize) -> [i64; 2] {
        [self.lo[0] + (index % self.extent[0]) as i64, self.lo[1] + (index / self.extent[0]) as i64]
    }

    fn index(&self, m: [i64; 2]) -> Option<usize> {
        let i = usize::try_from(m[0] - self.lo[0]).ok().filter(|&i| i < self.extent[0])?;
        let j = usize::try_from(m[1] - self.lo[1]).ok().filter(|&j| j < self.extent[1])?;
        Some(j * self.extent[0] + i)
    }

    fn residue(&self, m: [i64; 2]) -> usize {
        let n = i64::from(self.rate);
        (m[0].rem_euclid(n) + n * m[1].rem_euclid(n)) as usize
    }

    fn sample(&self, values: &[Rational], m: [i64; 2]) -> Option<Rational> {
        if !self.computed[self.residue(m)] {
            return None;
        }
        Some(self.index(m).map_or_else(Rational::zero, |i| values[i].clone()))
    }

    /// The box of numerators holding the support: the smallest `m` on each axis and the
    /// number of grid points along it.
    pub fn bounds(&self) -> ([i64; 2], [usize; 2]) {
        (self.lo, self.extent)
    }

    /// `φ(m / rate)`: zero outside the support, `None` where `m`'s residue was not computed.
    pub fn value(&self, m: [i64; 2]) -> Option<Rational> {
        self.sample(&self.phi, m)
    }

    /// `∂φ/∂u (m / rate)`, as [`value`](Self::value).
    pub fn du(&self, m: [i64; 2]) -> Option<Rational> {
        self.sample(&self.du, m)
    }

    /// `∂φ/∂v (m / rate)`, as [`value`](Self::value).
    pub fn dv(&self, m: [i64; 2]) -> Option<Rational> {
        self.sample(&self.dv, m)
    }

    /// The stencils of the limit point `x = point / rate` over control points at the lattice
    /// positions `control`: `φ(x − c)`, `∂φ/∂u(x − c)`, `∂φ/∂v(x − c)`; `None` if the point's
    /// residue was not computed.
    pub fn stencil_over(&self, point: [i64; 2], control: &[[i64; 2]]) -> Option<ExactStencil> {
        let n = i64::from(self.rate);
        let offsets: Vec<[i64; 2]> = control.iter().map(|c| [point[0] - n * c[0], point[1] - n * c[1]]).collect();
        let all = |values: &[Rational]| offsets.iter().map(|&m| self.sample(values, m)).collect::<Option<Vec<_>>>();
        Some(ExactStencil {
            control: control.to_vec(),
            position: all(&self.phi)?,
            du: all(&self.du)?,
            dv: all(&self.dv)?,
        })
    }

    /// [`stencil_over`](Self::stencil_over) every control point whose basis function (or a
    /// derivative) is nonzero at `point / rate`, in lexicographic order of position.
    pub fn stencil_at(&self, point: [i64; 2]) -> Option<ExactStencil> {
        let n = i64::from(self.rate);
        let (r, q) = (point.map(|p| p.rem_euclid(n)), point.map(|p| p.div_euclid(n)));
        let mut control = Vec::new();
        for index in 0..self.phi.len() {
            let m = self.numerator(index);
            if (0..2).all(|c| (m[c] - r[c]).rem_euclid(n) == 0)
                && !(self.phi[index].is_zero() && self.du[index].is_zero() && self.dv[index].is_zero())
            {
                // m = point − n·c.
                control.push([q[0] - (m[0] - r[0]) / n, q[1] - (m[1] - r[1]) / n]);
            }
        }
        control.sort_unstable();
        self.stencil_over(point, &control)
    }
}

/// Fills a [`SurfaceBasisGrid`] residue chain by residue chain.
struct Builder<'a> {
    mask: &'a SurfaceMask,
    support: Support<'a>,
    n: i64,
    grid: SurfaceBasisGrid,
}

impl Builder<'_> {
    fn image(&self, r: [i64; 2]) -> [i64; 2] {
        let a = i64::from(self.mask.arity);
        [(a * r[0]).rem_euclid(self.n), (a * r[1]).rem_euclid(self.n)]
    }

    fn done(&self, r: [i64; 2]) -> bool {
        self.grid.computed[self.grid.residue(r)]
    }

    /// The grid points of residue `r` in the support, as grid indices.
    fn points(&self, r: [i64; 2]) -> Vec<usize> {
        let (lo, extent, n) = (self.grid.lo, self.grid.extent, self.n);
        let first = [lo[0] + (r[0] - lo[0]).rem_euclid(n), lo[1] + (r[1] - lo[1]).rem_euclid(n)];
        let mut out = Vec::new();
        let mut y = first[1];
        while y < lo[1] + extent[1] as i64 {
            let mut x = first[0];
            while x < lo[0] + extent[0] as i64 {
                if self.support.contains([x, y]) {
                    out.extend(self.grid.index([x, y]));
                }
                x += n;
            }
            y += n;
        }
        out
    }

    /// The scaling relation's terms at grid point `index`: `(grid index, s_k)` of
    /// `φ((a·m − n·k)/n)` inside the support.
    fn terms(&self, index: usize) -> Vec<(usize, &Rational)> {
        let m = self.grid.numerator(index);
        let a = i64::from(self.mask.arity);
        (self.mask.weights.iter())
            .filter_map(|(k, s)| {
                let t = [a * m[0] - self.n * k[0], a * m[1] - self.n * k[1]];
                self.support.contains(t).then(|| self.grid.index(t).map(|i| (i, s))).flatten()
            })
            .collect()
    }

    /// Computes residue `r` and the chain it leads to.
    fn ensure(&mut self, r: [i64; 2]) -> Result<(), StencilError> {
        let mut path: Vec<[i64; 2]> = Vec::new();
        let mut at: HashMap<[i64; 2], usize> = HashMap::new();
        let mut current = r;
        while !self.done(current) {
            if let Some(&start) = at.get(&current) {
                // A cycle r_0 → r_1 → … → r_0: r_0 is solved; the rest of the cycle, like the
                // residues leading into it, follows by substitution, last first.
                self.cycle_start(&path[start..])?;
                path.remove(start);
                break;
            }
            at.insert(current, path.len());
            path.push(current);
            current = self.image(current);
        }
        let a = Rational::from_integer(i64::from(self.mask.arity));
        for &residue in path.iter().rev() {
            for index in self.points(residue) {
                let terms = self.terms(index);
                let sum = |values: &[Rational]| -> Rational { terms.iter().map(|&(i, s)| s * &values[i]).sum() };
                let (phi, du, dv) = (sum(&self.grid.phi), sum(&self.grid.du), sum(&self.grid.dv));
                self.grid.phi[index] = phi;
                self.grid.du[index] = &a * &du;
                self.grid.dv[index] = &a * &dv;
                self.grid.sizes.computed_points += 1;
            }
            self.mark(residue);
        }
        Ok(())
    }

    fn mark(&mut self, residue: [i64; 2]) {
        let slot = self.grid.residue(residue);
        self.grid.computed[slot] = true;
    }

    /// The first residue of a cycle: copied from its image under a symmetry of the mask if
    /// that is known, else solved.
    fn cycle_start(&mut self, cycle: &[[i64; 2]]) -> Result<(), StencilError> {
        self.grid.sizes.cycles += 1;
        self.grid.sizes.cycle_points += cycle.iter().map(|&r| self.points(r).len()).sum::<usize>();
        let n = self.n;
        let image = |m: &Matrix, r: [i64; 2]| apply(m, r).map(|x| x.rem_euclid(n));
        let symmetry = self.mask.symmetries.iter().find(|m| self.done(image(m, cycle[0]))).copied();
        let points = self.points(cycle[0]);
        self.grid.sizes.computed_points += points.len();
        if let Some(m) = symmetry {
            // φ(x) = φ(M·x) and ∇φ(x) = Mᵀ ∇φ(M·x); M·x stays in the support, which M keeps.
            for &index in &points {
                let x = self.grid.numerator(index);
                let Some(j) = self.grid.index(apply(&m, x)) else { continue };
                let (du, dv) = (self.grid.du[j].clone(), self.grid.dv[j].clone());
                let c = |x: i64| Rational::from_integer(x);
                self.grid.phi[index] = self.grid.phi[j].clone();
                self.grid.du[index] = &(&c(m[0][0]) * &du) + &(&c(m[1][0]) * &dv);
                self.grid.dv[index] = &(&c(m[0][1]) * &du) + &(&c(m[1][1]) * &dv);
            }
        } else {
            self.solve(cycle, &points)?;
        }
        self.mark(cycle[0]);
        Ok(())
    }

    /// Solves for the values at the first residue `r_0` of a cycle of length `L`. Going once
    /// round the cycle, the scaling relation gives `v = D^−L · Q · v` for the vector `v` of
    /// `r_0`'s points, where `Q` is the product of the integer relation matrices
    /// `N_i = D·T_i` (`D` the mask's common denominator; `T_i` takes residue `r_(i+1)`'s values
    /// to `r_i`'s), formed exactly in big integers; derivatives satisfy
    /// `v = (a/D)^L · Q · v`. So one system per cycle with `r_0`'s points as unknowns:
    /// `(Q − D^L·I) v = 0` (positions) or `(a^L·Q − D^L·I) v = 0` (derivatives), plus the
    /// normalisations at `r_0`.
    fn solve(&mut self, cycle: &[[i64; 2]], points: &[usize]) -> Result<(), StencilError> {
        let sizes = &mut self.grid.sizes;
        sizes.solved_cycles += 1;
        sizes.solved_unknowns += points.len();
        sizes.largest_system = sizes.largest_system.max(points.len());
        let denominator = (self.mask.weights.iter()).fold(BigInt::one(), |d, (_, w)| d.lcm(w.denom()));
        let integer: HashMap<[i64; 2], BigInt> =
            (self.mask.weights.iter()).map(|(k, w)| (*k, w.numer() * (&denominator / w.denom()))).collect();
        let p = points.len();
        // Q, row by row over r_0's points, columns over the current residue's points.
        let mut q: Vec<HashMap<usize, BigInt>> = points.iter().map(|&g| HashMap::from([(g, BigInt::one())])).collect();
        let a = i64::from(self.mask.arity);
        for _ in cycle {
            for row in &mut q {
                let mut next: HashMap<usize, BigInt> = HashMap::with_capacity(row.len());
                for (&g, x) in row.iter() {
                    let m = self.grid.numerator(g);
                    for (k, w) in &integer {
                        let t = [a * m[0] - self.n * k[0], a * m[1] - self.n * k[1]];
                        if let Some(i) = self.support.contains(t).then(|| self.grid.index(t)).flatten() {
                            *next.entry(i).or_default() += x * w;
                        }
                    }
                }
                next.retain(|_, x| !x.is_zero());
                *row = next;
            }
        }
        let local: HashMap<usize, usize> = points.iter().enumerate().map(|(l, &g)| (g, l)).collect();
        let length = u32::try_from(cycle.len()).unwrap_or(u32::MAX);
        let d_l = Rational::new(denominator.pow(length), 1).expect("nonzero");
        let cycle_rows = |scale: &Rational| -> Result<Vec<(SparseRow, Rational)>, StencilError> {
            let mut rows = Vec::with_capacity(p + 3);
            for (l, row) in q.iter().enumerate() {
                let mut sparse: SparseRow = vec![(l, -d_l.clone())];
                for (g, x) in row {
                    // Round the cycle, every term is back at r_0.
                    let &column = local.get(g).ok_or_else(|| self.fail("positions", "a term leaves the cycle"))?;
                    sparse.push((column, scale * &Rational::new(x.clone(), 1).expect("nonzero")));
                }
                rows.push((sparse, Rational::zero()));
            }
            Ok(rows)
        };
        let n = self.n;
        let at_r0 = |coefficient: &dyn Fn([i64; 2]) -> Rational| -> SparseRow {
            points.iter().enumerate().map(|(l, &g)| (l, coefficient(self.grid.numerator(g)))).collect()
        };
        let one = |_: [i64; 2]| Rational::one();
        // Σ_j (j_c − x_c) ψ(x − j) with x − j = m/n: the coefficient of ψ(m/n) is −m_c/n.
        let moment = |c: usize| move |m: [i64; 2]| Rational::new(-m[c], n).unwrap_or_else(Rational::zero);

        let mut rows = cycle_rows(&Rational::one())?;
        rows.push((at_r0(&one), Rational::one()));
        let phi = solve_sparse(p, rows).map_err(|e| self.fail("positions", &e.to_string()))?;

        let a_l = Rational::new(BigInt::from(a).pow(length), 1).expect("nonzero");
        let mut derivatives = Vec::with_capacity(2);
        for (quantity, target) in [("derivatives ∂/∂u", [1, 0]), ("derivatives ∂/∂v", [0, 1])] {
            let mut rows = cycle_rows(&a_l)?;
            rows.push((at_r0(&one), Rational::zero()));
            for (c, t) in target.into_iter().enumerate() {
                rows.push((at_r0(&moment(c)), Rational::from_integer(t)));
            }
            derivatives.push(solve_sparse(p, rows).map_err(|e| self.fail(quantity, &e.to_string()))?);
        }
        let dv = derivatives.pop().expect("two derivatives");
        let du = derivatives.pop().expect("two derivatives");
        for (l, &g) in points.iter().enumerate() {
            self.grid.phi[g] = phi[l].clone();
            self.grid.du[g] = du[l].clone();
            self.grid.dv[g] = dv[l].clone();
        }
        Ok(())
    }

    fn fail(&self, quantity: &'static str, detail: &str) -> StencilError {
        StencilError::SurfaceScalingSystem {
            scheme: self.mask.name.clone(),
            rate: self.grid.rate,
            quantity,
            detail: detail.to_owned(),
        }
    }
}

/// Route 1's stencil at `point` of `scheme`'s regular patch, over the same control points in
/// the same order as route 3's ([`PatchMatrices::of`] with [`PatchType::regular`], shape 0,
/// whose [`parameters`](subdiv_schemes::PatchShape::parameters) are the control points'
/// lattice positions), so that the two routes compare weight for weight. The grid is solved
/// at the point's reduced denominator, for its residue only.
///
/// ```
/// use subdiv_schemes::Builtin;
/// use subdiv_stencil::{Dyadic, Rational};
/// use subdiv_stencil::surface_basis::regular_patch_stencil;
///
/// let s = regular_patch_stencil(Builtin::CatmullClark.scheme(), Dyadic::new(1, 1, 2))?;
/// // The centre of a regular Catmull-Clark face: (1/48)(1, 23, 23, 1) ⊗ itself at the middle.
/// let centre = s.control.iter().position(|&c| c == [0, 0]).unwrap();
/// assert_eq!(s.position[centre], Rational::new(23 * 23, 48 * 48).unwrap());
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
///
/// # Errors
/// [`StencilError::OutsideDomain`] for a point outside the face, [`StencilError::Rate`] for a
/// reduced denominator above [`MAX_SURFACE_BASIS_RATE`], the errors of [`SurfaceMask::of`] and
/// [`PatchMatrices::of`], and [`StencilError::SurfaceMask`] if the patch's parameters are not lattice points.
pub fn regular_patch_stencil(scheme: &Scheme, point: Dyadic) -> Result<ExactStencil, StencilError> {
    check_domain(if scheme.regular_valence() == 6 { 3 } else { 4 }, point)?;
    let Dyadic { u, v, denominator: rate } = point.reduced();
    let point = [u, v];
    let rate = u32::try_from(rate)
        .map_err(|_| StencilError::Rate { rate: rate.unsigned_abs(), reason: "above MAX_SURFACE_BASIS_RATE" })?;
    let mask = SurfaceMask::of(scheme)?;
    let matrices = PatchMatrices::of(scheme, PatchType::regular(scheme), BoundaryInterpolation::EdgeOnly)?;
    let not_lattice = || StencilError::SurfaceMask {
        scheme: scheme.name().to_owned(),
        reason: "the regular patch's control points are not at lattice positions".into(),
    };
    let [pu, pv] = matrices.shapes[0].parameters.as_ref().ok_or_else(not_lattice)?;
    let offset = mask.control_offset().map(|h| h.to_f64());
    let control: Vec<[i64; 2]> = (pu.iter().zip(pv))
        .map(|(&x, &y)| {
            let (x, y) = (x - offset[0], y - offset[1]);
            let (rx, ry) = (x.round(), y.round());
            ((x - rx).abs() < 1e-9 && (y - ry).abs() < 1e-9).then_some([rx as i64, ry as i64])
        })
        .collect::<Option<_>>()
        .ok_or_else(not_lattice)?;
    let grid = SurfaceBasisGrid::at_residues(&mask, rate, &[point])?;
    Ok(grid.stencil_over(point, &control).expect("the point's residue is computed"))
}
