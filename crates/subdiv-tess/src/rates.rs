//! Per-face tessellation rates: from the screen (paper 000 §6, paper 003 §7.5) or to a
//! tolerance.
//!
//! The dual-grid tessellator takes any rate per face, independent of its neighbours, so a
//! policy only has to say how finely each face should be cut; it never has to agree with the
//! faces around it (a uniform rate is `vec![n; faces]`).

use subdiv_mesh::{FaceId, Mesh};

use crate::flatness::{Tolerance, rounding_slack};

mod graded;
mod screen;

pub use self::graded::{GRID_DENOMINATOR, GradedGrid};
pub(crate) use self::screen::ScreenBound;
pub use self::screen::{Camera, NEAR_PLANE, ScreenError, ScreenSpace};
use crate::{QuadtreeTessellator, TessError};

/// The largest rate the policies give unless told otherwise.
pub const DEFAULT_MAX_RATE: u32 = crate::dual::MAX_DUAL_RATE;

/// Rates to a tolerance: the smallest rate per face for which the dual-grid tessellation is
/// provably within `ε` of the surface — every limit point at distance ≤ `ε` from the output.
///
/// # The bound
/// The dual-grid output has three kinds of triangles: cells of one face's grid, triangles of a
/// strip between two faces, and the polygon around a mesh vertex. Each has its corners at
/// parameter points `p_i` that lie, in one flat chart (one face, two faces across their edge,
/// or the four faces around a regular vertex), within `h = √2 / n` of each other, `n` the
/// smallest rate among the faces involved (cells: the diagonal `√2/n`; strips: the rows are
/// `½/n_f + ½/n_g` apart and merged in parameter order; regular vertex polygons: corner points
/// at `½/n_f` from the vertex on each side). Where the surface is C² with `‖D²S[d, d]‖ ≤ M`,
/// Taylor's theorem with integral remainder at each corner gives, for the point `p` with
/// barycentric weights `λ_i`,
///
/// `‖S(p) − Σ λ_i S(p_i)‖ ≤ ½ M Σ λ_i ‖p − p_i‖²`,
///
/// and `Σ λ_i ‖p − p_i‖² = R² − ‖p − O‖²` (`O`, `R` the circumcentre and radius). Over the
/// triangle its largest value is `R² ≤ L²/3` when the triangle is acute (its largest angle is
/// at least 60°, and `L = 2R sin` of it), else `(L/2)²` (at the midpoint of the longest side
/// `L`, the point nearest `O`). So every triangle is within `M L² / 6 ≤ M / (3 n²)`, and a
/// cell's right triangles (hypotenuse `√2/n`) within `M / (4 n²)`:
/// a face with rate `n ≥ √(M/(3ε))` keeps its own triangles, and those it shares with coarser
/// neighbours' rates, within `ε` — provided `M` bounds every face that a triangle touches:
/// each face takes the largest `M` ([`QuadtreeTessellator::face_curvature`]) of the faces sharing a
/// vertex with it. Near an extraordinary point `M` is taken over the face less the corner
/// square inside the first ring around it (below), which no cell or strip triangle enters;
/// since that square shrinks as the rates around grow, and `M` grows like `(4λ)^d` there,
/// slower than `n²`, the rates are the least fixed point of this rule.
///
/// The polygon around an extraordinary point is not in a flat chart: the tessellator replaces
/// it by rings ([`DualTessellator::tessellate_with_rings`](crate::DualTessellator::tessellate_with_rings)),
/// whose depths [`rates`](Self::rates) computes and whose bound it states.
///
/// Under a triangle split (Loop) the same argument runs in the *equilateral* chart (each face
/// an equilateral triangle of side 1, so that two faces across an edge, or the six around a
/// regular vertex, are one flat chart where the box spline is C²), with `M` the bound there
/// ([`FaceCurvature::second`](crate::FaceCurvature::second)) and the triangles' longest sides
/// of that chart (`SplitGeometry`): a cell's hexagon fans `1/(√3 n)`, strip and vertex
/// triangles at most `√(19/12) / n`, so `n ≥ √(19 M / (72 ε))`; bands between rings `√7/4 · r`.
///
/// A `rounding_slack` of `1e−12 ×` the model's size is kept from `ε` for the f64 arithmetic.
/// The bounds come from the quadtree tessellator's pieces, so this policy takes what it takes:
/// Catmull-Clark and Loop meshes, open ones and holes too. At a border (a boundary, or the edge of a
/// hole) the strips close against border points at the parameters of the row beside them, and a
/// border vertex's polygon is fanned around its limit point, all within `√2 / n` in the chart of
/// one face or of the two faces at a regular border vertex. An *extraordinary* border vertex (a
/// smooth corner, a boundary vertex of three or more faces, a vertex next to a hole, which keeps
/// the interior rules) takes rings in its open runs of faces, bounded as the closed rings below
/// (each band in one face, from the first border point a triangle in the first face). The
/// tessellator also cuts the polygon around a vertex along infinitely sharp edges and the seams
/// of the channels it carries: the runs on either side of such an edge take open rings too, and
/// share their ring points on it (one vertex, an extra normal and channel values per side).
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::{QuadtreeTessellator, Tolerance};
/// use subdiv_tess::rates::ErrorRates;
///
/// let mesh = Mesh::build(shapes::quad_torus(16, 8))?;
/// let bounds = QuadtreeTessellator::new(Builtin::CatmullClark.scheme(), &mesh)?;
/// let coarse = ErrorRates::new(Tolerance::Relative(1e-2)).rates(&bounds, &mesh)?.faces;
/// let fine = ErrorRates::new(Tolerance::Relative(1e-3)).rates(&bounds, &mesh)?.faces;
/// assert!(coarse.iter().zip(&fine).all(|(c, f)| c <= f) && fine.iter().max() > coarse.iter().max());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorRates {
    /// How close the output must be.
    pub tolerance: Tolerance,
    /// The largest rate allowed: a face that needs more is an error.
    pub max_rate: u32,
    /// Whether the faces around extraordinary points take grids graded toward them
    /// ([`GradedGrid`], under a quad split): their cell counts then follow the bound away from
    /// the points instead of its worst spot. Without, every face's grid is uniform (the
    /// regular fast path's blocks), at rates that grow much faster as `ε` falls.
    pub graded: bool,
}

impl ErrorRates {
    /// Rates to `tolerance`, at most [`DEFAULT_MAX_RATE`], graded around extraordinary points.
    pub fn new(tolerance: Tolerance) -> Self {
        Self { tolerance, max_rate: DEFAULT_MAX_RATE, graded: true }
    }

    /// The same policy, graded around extraordinary points or not.
    #[must_use]
    pub fn with_graded(self, graded: bool) -> Self {
        Self { graded, ..self }
    }
}

/// Per-face rates with, around extraordinary points, the depth down to which the dual-grid
/// tessellator adds rings ([`ErrorRates::rates`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DualRates {
    /// The rate of each input face.
    pub faces: Vec<u32>,
    /// The rings around extraordinary points.
    pub rings: RingDepths,
}

/// How close to each extraordinary point the dual-grid tessellator must sample: rings of exact
/// points at parameter distances `r, r/2, r/4, …` down to `2^−depth` (face units, the corner
/// square of that side around the point), fanned at the end around its limit point; `0` for
/// none. `r` is the largest power of two inside the point's nearest dual points, so rings only
/// appear where the rates leave the point's neighbourhood too coarse. Consumed by
/// [`DualTessellator::tessellate_with_rings`](crate::DualTessellator::tessellate_with_rings).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RingDepths {
    /// Per mesh vertex (used at interior vertices of valence ≠ 4 under a quad split, and at
    /// infinitely sharp corners, where the polygon around the vertex is not cut).
    pub vertices: Vec<u32>,
    /// Per face (used at the centres of N-gons, N ≠ 4, under a quad split).
    pub centres: Vec<u32>,
    /// Per face, its dual grid graded toward its extraordinary corners, or `None` for the
    /// uniform grid of its rate (quads under a quad split only); empty: none graded.
    pub graded: Vec<Option<GradedGrid>>,
}

impl RingDepths {
    /// Face `face`'s graded grid, if it has one.
    pub(crate) fn grid(&self, face: FaceId) -> Option<&GradedGrid> {
        self.graded.get(face.index()).and_then(Option::as_ref)
    }

    /// [`graded_reach`] of `face` at `rate` with its graded grid, if any.
    pub(crate) fn reach(&self, mesh: &Mesh, triangle: bool, face: FaceId, rate: u32) -> u32 {
        graded_reach(mesh, triangle, face, rate, self.grid(face))
    }
}

/// [`reach`] of `face` at `rate`, or, where it has a graded grid, the grid's (an N-gon's
/// sub-faces are half as wide as a face, so their reach counts twice).
fn graded_reach(mesh: &Mesh, triangle: bool, face: FaceId, rate: u32, grid: Option<&GradedGrid>) -> u32 {
    match grid {
        Some(grid) if mesh.face_size(face) == 4 => grid.reach(),
        Some(grid) => 2 * grid.reach(),
        None => reach(mesh, triangle, face, rate),
    }
}

/// How finely a face at `rate` samples next to its corners: under a quad split as a rate of a
/// quad, its dual points nearest a corner `½ / reach` away in face units (an N-gon's sub-faces,
/// at `⌈n/2⌉` each and half as wide, reach `2⌈n/2⌉`); under a triangle split (`triangle`) the
/// rate, the corner centroid `1/(3 reach)` from each side.
pub(crate) fn reach(mesh: &Mesh, triangle: bool, face: FaceId, rate: u32) -> u32 {
    if triangle || mesh.face_size(face) == 4 { rate } else { 2 * rate.div_ceil(2) }
}

/// The depth `d` of the first ring around a point whose finest face reach is `finest`: under a
/// quad split `2^−d` is the largest power of two below the nearest dual points' `½ / finest`;
/// under a triangle split (`triangle`) the largest below `1 / (3 finest)`, the corner
/// centroids' distance from each side, so that the first ring's points on the edges and at
/// `(r/2, r/2)` lie inside the polygon through the centroids.
pub(crate) fn first_ring_depth(triangle: bool, finest: u32) -> u32 {
    if triangle {
        (3 * finest + 1).next_power_of_two().trailing_zeros()
    } else {
        finest.next_power_of_two().trailing_zeros() + 2 - u32::from(!finest.is_power_of_two())
    }
}

/// The constants of the bound `½ M max Σ λ_i ‖p − p_i‖²` for one split's dual-grid triangles
/// (see [`ErrorRates::rates`]; the maximum is at most `L²/3` for a longest side `L`, `L²/4` for
/// a right triangle): the rate `n` needs `cells · M / n² ≤ ε`, and the band between rings of
/// radii `r` and `r/2` needs `bands · M r² ≤ ε`.
#[derive(Clone, Copy)]
struct SplitGeometry {
    /// `½ n² max Σ λ_i ‖p − p_i‖²` over the cell, strip and vertex triangles at rate `n`.
    cells: f64,
    /// `½ r⁻² max Σ λ_i ‖p − p_i‖²` over a band's triangles.
    bands: f64,
}

/// Quads, in face units: cells' right triangles of hypotenuse `√2 / n` (`L²/4 = ½ n⁻²`); strip
/// and vertex triangles within `√2 / n` (`L²/3 = ⅔ n⁻²`, the larger); bands' triangles of
/// longest side `√5/2 · r` (`5/12 r²`).
const QUAD_SPLIT: SplitGeometry = SplitGeometry { cells: 0.5 * 2.0 / 3.0, bands: 0.5 * 5.0 / 12.0 };

/// Triangles, in equilateral units (each face an equilateral triangle of side 1, so that two
/// faces across an edge are one flat chart): a cell's hexagon fans are equilateral of side
/// `1/(√3 n)` (`R² = 1/(9 n²)`); strip triangles join rows of centroids at most `2/(√3 n)` apart
/// across the edge and `½ / n` along it, so `L² ≤ (¼ + 4/3) / n² = 19 / (12 n²)` (`L²/3`, the
/// largest); vertex fans are shorter. A band's trapezoid `r/2 ≤ s + t ≤ r` (its points
/// `(r/2, 0)`, `(r, 0)`, `(r/2, r/2)`, `(r/4, r/4)`) is cut along a diagonal of at most `√7/4 · r`
/// (`7/48 r²`).
const TRIANGLE_SPLIT: SplitGeometry = SplitGeometry { cells: 0.5 * 19.0 / 36.0, bands: 0.5 * 7.0 / 48.0 };

/// What a graded face's bound reads besides the curvature of the faces around its ring
/// points: which faces have a surface, every face's bound less its corner quarters (for the
/// faces sharing no ring point with it), the budget and the split's constants.
#[derive(Clone, Copy)]
struct Within<'a> {
    surfaced: &'a [bool],
    shallow: &'a [f64],
    budget: f64,
    geometry: SplitGeometry,
}

/// Rounds of the faces' rule after which the rates are taken as unsettled (a bug): each round
/// raises some rate or grading, and they settle within a few on every shared mesh.
const MAX_SETTLING_ROUNDS: u32 = 1000;

/// The faces whose grids are graded toward their ring points: under a quad split, every
/// N-gon (its centre has rings) and every quad with a ring point at a corner — so every face
/// around a ring point (a uniform face there would have to keep its cells out of the first
/// ring, which a graded neighbour's innermost cells put far deeper). None unless `grade`: not
/// asked for, or under a triangle split (Loop's cells are not graded yet).
fn graded_faces(mesh: &Mesh, grade: bool, surfaced: &[bool], corner_of: &[bool]) -> Vec<bool> {
    mesh.face_ids()
        .map(|f| {
            grade
                && surfaced[f.index()]
                && (mesh.face_size(f) != 4 || mesh.face_vertices(f).iter().any(|v| corner_of[v.index()]))
        })
        .collect()
}

/// The rings around an extraordinary point at the current rates.
enum Rings {
    /// Down to this depth, every band within the bound.
    Down(u32),
    /// The band ending at this depth fails the bound: the rates around must be finer.
    BandFails(u32),
}

/// Below this depth (a square of side 2^−40 around an extraordinary point) a hull bound that is
/// still above `ε` means the model is too small for the tolerance.
const MAX_RING_DEPTH: u32 = 40;

impl ErrorRates {
    /// Rates and ring depths to the tolerance, for the dual-grid tessellator's rings
    /// ([`DualTessellator::tessellate_with_rings`](crate::DualTessellator::tessellate_with_rings)),
    /// with `bounds` the quadtree tessellator of the same mesh (its pieces give the bounds): face
    /// rates from the second-derivative bound (see [`ErrorRates`]), and around each
    /// extraordinary point the least depth `d` whose corner hulls are within `ε`.
    ///
    /// # The bound, with rings
    /// Rings around an extraordinary point lie at powers of two `r_j` below its nearest dual
    /// points; between ring `j` and `j + 1` each face holds two quadrilaterals,
    /// `(r_{j+1}, 0), (r_j, 0), (r_j, r_j), (r_{j+1}, r_{j+1})` and its mirror, inside the
    /// face's L-shaped region `[0, r_j]² \ [0, r_{j+1})²`: two triangles each, of longest side
    /// `√5/2 · r_j`, in one flat chart where the surface is C². Their deviation is at most
    /// `½ M (√5/2 · r_j)² / 3` (see [`ErrorRates`]), `M` the second-derivative bound of the face
    /// less its corner square of side `r_{j+1}` — checked for every depth below the faces' own
    /// bound region. Where a band fails, the rates of the faces around the point are doubled
    /// (the first ring moves inward, where a band's `M r²` is smaller: it falls like `λ^d`) and
    /// the rates are settled again. The fan
    /// inside the last ring lies, with the surface it stands for, in the hull of the corner
    /// piece of depth `d`: within its diameter. The band from the dual points to the first ring
    /// has triangles in one face or across one edge, with corners at least `r_1` from the point
    /// and within `√2 / n` of each other: the faces' bound, which excludes only the corner
    /// squares of side `r_1` (for the finest rate around), covers them.
    ///
    /// # The bound, graded
    /// With [`graded`](Self::graded), every face around a ring point (under a quad split) takes
    /// a [`GradedGrid`] instead of one rate: per axis, cells whose widths never grow toward the
    /// axis' ends at ring points. The uniform argument holds cell by cell: a cell quad (and a
    /// strip triangle beside an edge) spans two consecutive centres per axis, so its longest
    /// side is within `√2 w` for the wider of its cells' widths `w`, and it lies beyond the
    /// corner square whose side is the nearer centre's distance from the end. Each dyadic
    /// interval `[2^−(d+1), 2^−d]` of a half axis takes cells no wider than the bound beyond the
    /// square of side `2^−(d+2)` allows (a quad with a centre in the interval reaches at most
    /// into the next interval out, whose cells obey the square of side `2^−(d+1)`); a quad is
    /// at least as far from a ring corner, in the max norm, as its centres along either axis, so
    /// both its sides obey the bound of the square it lies outside. The innermost run `[0,
    /// 2^−d]` of `k` equal cells (a power of two) is, next to the corner, a uniform grid of rate
    /// `2^d k`: the uniform argument covers it and its band to the first ring, with the bound
    /// beyond that ring (for the finest reach around the point). An N-gon's grid is every
    /// sub-face's, in sub-face units (half a face unit). The strips between a graded face and a
    /// neighbour take the larger bound of the two faces beyond the same square, which each
    /// face's grading reads (faces sharing a ring point with it at depth `e`, the others less
    /// their corner quarters: no triangle between faces sharing no ring point comes nearer one).
    ///
    /// # Errors
    /// [`TessError::Tolerance`] for a tolerance that is not a positive finite number,
    /// [`TessError::RateLimit`] when a face needs more than `max_rate` (for its cells, or for
    /// the bands of the rings around a point) or an extraordinary point's hull stays above `ε`
    /// down to depth 40, and the errors of
    /// [`QuadtreeTessellator::face_curvature`].
    pub fn rates(&self, bounds: &QuadtreeTessellator, mesh: &Mesh) -> Result<DualRates, TessError> {
        self.rates_rounded(bounds, mesh, |n| n)
    }

    /// As [`rates`](Self::rates), with every face rate taken from those `round` gives (which
    /// must not be below its argument): `u32::next_power_of_two` gives the cheapest dyadic
    /// rates that meet the tolerance by the same bound (paper 000 §6's comparison).
    ///
    /// # Errors
    /// As [`rates`](Self::rates).
    pub fn rates_rounded(
        &self,
        bounds: &QuadtreeTessellator,
        mesh: &Mesh,
        round: impl Fn(u32) -> u32,
    ) -> Result<DualRates, TessError> {
        let budget = self.budget(bounds, mesh)?;
        let triangle = bounds.triangle_split();
        let geometry = if triangle { TRIANGLE_SPLIT } else { QUAD_SPLIT };
        let max_rate = self.max_rate.max(1);
        let limit = |face: FaceId, needed: String| TessError::RateLimit { face: face.index(), needed, max_rate };
        let mut cache: std::collections::HashMap<(FaceId, u32), crate::FaceCurvature> = Default::default();
        let mut curvature = |f: FaceId, d: u32| -> Result<crate::FaceCurvature, TessError> {
            if let Some(c) = cache.get(&(f, d)) {
                return Ok(*c);
            }
            let c = bounds.face_curvature(f, d)?;
            cache.insert((f, d), c);
            Ok(c)
        };
        // Faces without a surface (holes): no rate of theirs matters, and they bound nothing.
        let faces: Vec<FaceId> = mesh.face_ids().filter(|&f| bounds.has_surface(f)).collect();
        let mut extraordinary = vec![false; mesh.face_count()];
        for &f in &faces {
            extraordinary[f.index()] = curvature(f, 1)?.corner_hull > 0.0;
        }
        // The vertices at which some face's surface is an extraordinary piece: every valence
        // other than the regular one, and sharp corners and darts of any valence.
        let mut corner_of = vec![false; mesh.vertex_count()];
        for &f in faces.iter().filter(|f| extraordinary[f.index()]) {
            for v in bounds.extraordinary_corners(f)? {
                corner_of[v.index()] = true;
            }
        }
        let mut surfaced = vec![false; mesh.face_count()];
        faces.iter().for_each(|f| surfaced[f.index()] = true);
        let graded = graded_faces(mesh, self.graded && !triangle, &surfaced, &corner_of);
        let mut shallow = vec![0.0; mesh.face_count()];
        for &f in &faces {
            shallow[f.index()] = curvature(f, 1)?.second;
        }
        let mut grids: Vec<Option<GradedGrid>> = vec![None; mesh.face_count()];
        // The least reach of a graded face's innermost cells (raised where rings' bands fail).
        let mut floors = vec![1u32; mesh.face_count()];
        let mut rates = vec![round(1); mesh.face_count()];
        let reach_of = |rates: &[u32], grids: &[Option<GradedGrid>], f: FaceId| {
            graded_reach(mesh, triangle, f, rates[f.index()], grids[f.index()].as_ref())
        };
        // The faces whose reach puts the first rings around `f`'s extraordinary points: those
        // around its ring corners, and `f` itself (an N-gon's centre).
        let ring_neighbours = |f: FaceId| {
            mesh.face_vertices(f)
                .iter()
                .filter(|v| corner_of[v.index()])
                .flat_map(|&v| mesh.vertex_faces(v))
                .chain(std::iter::once(f))
                .filter(|&g| bounds.has_surface(g))
        };
        let finest_of = |rates: &[u32], grids: &[Option<GradedGrid>], f: FaceId| -> u32 {
            ring_neighbours(f).map(|g| reach_of(rates, grids, g)).max().unwrap_or(1)
        };
        let ring_depth = |rates: &[u32],
                          grids: &[Option<GradedGrid>],
                          around: &[FaceId],
                          curvature: &mut dyn FnMut(FaceId, u32) -> Result<crate::FaceCurvature, TessError>|
         -> Result<Rings, TessError> {
            let finest = around.iter().map(|&g| reach_of(rates, grids, g)).max().unwrap_or(1);
            let first = first_ring_depth(triangle, finest);
            let mut d = first;
            loop {
                let mut within = true;
                for &g in around {
                    let c = curvature(g, d)?;
                    if d > first {
                        // The band between the rings at `2^−(d−1)` and `2^−d`.
                        let r = 0.5f64.powi(d as i32 - 1);
                        if geometry.bands * c.second * r * r > budget {
                            return Ok(Rings::BandFails(d));
                        }
                    }
                    within &= c.corner_hull <= budget;
                }
                if within {
                    return Ok(Rings::Down(d));
                }
                d += 1;
                if d > MAX_RING_DEPTH {
                    return Err(limit(
                        around[0],
                        format!("rings deeper than {MAX_RING_DEPTH} (ε is below what f64 resolves)"),
                    ));
                }
            }
        };
        // Extraordinary points with rings: every vertex at an extraordinary corner of some
        // face, and (quad split) every N-gon's centre.
        let points: Vec<(Option<subdiv_mesh::VertexId>, Vec<FaceId>)> = mesh
            .vertices()
            .filter(|v| corner_of[v.index()])
            .map(|v| (Some(v), mesh.vertex_faces(v).filter(|&f| bounds.has_surface(f)).collect()))
            .chain(faces.iter().filter(|&&f| mesh.face_size(f) != 4 && !triangle).map(|&f| (None, vec![f])))
            .collect();
        loop {
            // Fixed point: a face's bound region stops at the corner square of side 2^−d, d the
            // depth of the first ring for the finest reach around each of its ring points (no
            // triangle outside the rings comes closer); finer reaches push d deeper, where M
            // grows like (4λ)^d, slower than n², so rates and gradings (which only grow) settle.
            for round_trip in 0.. {
                if round_trip > MAX_SETTLING_ROUNDS {
                    return Err(TessError::Internal(format!(
                        "dual rates unsettled after {MAX_SETTLING_ROUNDS} rounds"
                    )));
                }
                // Each uniform extraordinary face's bound over the face less the corner squares
                // inside the first rings around it, which the faces sharing a ring point with it
                // take; every other face, and every face for a neighbour that shares no ring
                // point with it (no nearer those points), takes `shallow`.
                let mut deep = shallow.clone();
                for &f in faces.iter().filter(|f| extraordinary[f.index()] && !graded[f.index()]) {
                    let depth = first_ring_depth(triangle, finest_of(&rates, &grids, f));
                    deep[f.index()] = curvature(f, depth)?.second;
                }
                let mut changed = false;
                for &f in faces.iter().filter(|f| !graded[f.index()]) {
                    let around = mesh.face_vertices(f).iter().flat_map(|&v| mesh.vertex_faces(v));
                    let m = around.fold(0.0f64, |m, g| m.max(shallow[g.index()]));
                    let m = ring_neighbours(f).fold(m, |m, g| m.max(deep[g.index()]));
                    let needed = (geometry.cells * m / budget).sqrt().ceil().max(1.0);
                    let needed = if needed > f64::from(max_rate) { needed } else { f64::from(round(needed as u32)) };
                    if needed > f64::from(max_rate) {
                        return Err(limit(f, format!("rate {needed}")));
                    }
                    if needed as u32 > rates[f.index()] {
                        rates[f.index()] = needed as u32;
                        changed = true;
                    }
                }
                for &f in faces.iter().filter(|f| graded[f.index()]) {
                    let floor = floors[f.index()].max(finest_of(&rates, &grids, f));
                    let within = Within { surfaced: &surfaced, shallow: &shallow, budget, geometry };
                    let grid = self.graded_grid(mesh, f, &corner_of, within, &mut curvature, floor)?;
                    let grid = grid.map_err(|why| limit(f, why))?;
                    if grids[f.index()].as_ref() != Some(&grid) {
                        // An N-gon's sub-faces take `⌈n/2⌉` cells each.
                        rates[f.index()] = if mesh.face_size(f) == 4 { grid.rate() } else { 2 * grid.rate() };
                        grids[f.index()] = Some(grid);
                        changed = true;
                    }
                }
                if !changed {
                    break;
                }
            }
            // Rings: per extraordinary point, from the first power of two inside its nearest
            // dual points down to the least depth whose hull is within ε, every band checked.
            let mut vertices = vec![0u32; mesh.vertex_count()];
            let mut centres = vec![0u32; mesh.face_count()];
            let mut refine: Vec<(FaceId, u32)> = Vec::new();
            for (point, around) in &points {
                match ring_depth(&rates, &grids, around, &mut curvature)? {
                    Rings::Down(d) => match point {
                        Some(v) => vertices[v.index()] = d,
                        None => centres[around[0].index()] = d,
                    },
                    Rings::BandFails(d) => refine.extend(around.iter().map(|&g| (g, d))),
                }
            }
            if refine.is_empty() {
                let graded = if grids.iter().any(Option::is_some) { grids } else { Vec::new() };
                return Ok(DualRates { faces: rates, rings: RingDepths { vertices, centres, graded } });
            }
            refine.sort_unstable_by_key(|&(g, _)| g);
            refine.dedup_by_key(|&mut (g, _)| g);
            for (g, d) in refine {
                if graded[g.index()] {
                    // A graded face's innermost cells twice as fine.
                    floors[g.index()] = floors[g.index()].max(2 * reach_of(&rates, &grids, g));
                    continue;
                }
                let finer = round(2 * rates[g.index()]);
                if finer > max_rate {
                    let why = format!("finer rates around it (its rings' bands fail the bound at depth {d})");
                    return Err(limit(g, why));
                }
                rates[g.index()] = rates[g.index()].max(finer);
            }
        }
    }

    /// Face `f`'s grid graded toward its ring points (see [`graded`]): the allowed cell width
    /// beyond the corner squares of side `2^−e` from the largest bound there of the faces
    /// sharing a vertex with it — a face around one of `f`'s ring points (or `f`, for an N-gon's
    /// centre) at depth `e`, any other less its corner quarters (it is no nearer `f`'s points,
    /// nor `f` nearer its own) — and `floor` the least reach of its innermost cells.
    ///
    /// A quad's grid is in its own parameters, corner `c` of its vertices at `(0, 0)`, `(1, 0)`,
    /// `(1, 1)`, `(0, 1)`. An N-gon's is every sub-face's (the same grid, so that the spokes
    /// between them stay ladders of equal parameters), in sub-face units: half a face unit, the
    /// N-gon's vertex at `(0, 0)` and its centre at `(1, 1)`; its width is twice the face
    /// width, its corner squares of side `2^−e` are the face's of side `2^−(e+1)`, and its
    /// reach is half the face's.
    fn graded_grid(
        &self,
        mesh: &Mesh,
        f: FaceId,
        corner_of: &[bool],
        Within { surfaced, shallow, budget, geometry }: Within<'_>,
        curvature: &mut dyn FnMut(FaceId, u32) -> Result<crate::FaceCurvature, TessError>,
        floor: u32,
    ) -> Result<Result<GradedGrid, String>, TessError> {
        let corners = mesh.face_vertices(f);
        let ring = |c: usize| corner_of[corners[c].index()];
        let quad = corners.len() == 4;
        // The ends of u at 0 and 1, of v: a quad's corners, or a sub-face's vertex and centre.
        let ends = if quad {
            [[ring(0) || ring(3), ring(1) || ring(2)], [ring(0) || ring(1), ring(2) || ring(3)]]
        } else {
            let vertex = (0..corners.len()).any(ring);
            [[vertex, true], [vertex, true]]
        };
        let mut near: Vec<FaceId> = corners
            .iter()
            .filter(|v| corner_of[v.index()])
            .flat_map(|&v| mesh.vertex_faces(v))
            .chain(std::iter::once(f))
            .filter(|g| surfaced[g.index()])
            .collect();
        near.sort_unstable();
        near.dedup();
        let others = corners.iter().flat_map(|&v| mesh.vertex_faces(v)).fold(0.0f64, |m, g| m.max(shallow[g.index()]));
        // Grid units per face unit, and the face depth of the grid's depth 0.
        let (scale, shift) = if quad { (1.0, 0) } else { (2.0, 1) };
        let mut widths = |e: u32| -> Result<u32, TessError> {
            let mut m = others;
            for &g in &near {
                m = m.max(curvature(g, e + shift)?.second);
            }
            let width = scale * (budget / (geometry.cells * m)).sqrt() * f64::from(GRID_DENOMINATOR);
            // A flat neighbourhood (m = 0) allows any width: the cast saturates.
            Ok(width.min(f64::from(u32::MAX)) as u32)
        };
        let first_ring = |reach: u32| {
            let face_reach = reach << shift;
            (face_reach >= floor).then(|| first_ring_depth(false, face_reach) - shift)
        };
        let max_cells = if quad { self.max_rate.max(1) } else { self.max_rate.max(1) / 2 };
        let graded = graded::graded_grid(&mut widths, ends, &first_ring, max_cells)?;
        Ok(graded.map_err(|refusal| match refusal {
            graded::Refusal::Cells(n) if quad => format!("rate {n} (graded toward its extraordinary points)"),
            graded::Refusal::Cells(n) => {
                format!("rate {} ({n} cells per sub-face side, graded toward its extraordinary points)", 2 * n)
            }
            graded::Refusal::Finer(depth) => {
                format!("cells finer than 2^-{depth} of a face (ε is below what f64 resolves)")
            }
        }))
    }

    /// `ε` less the rounding slack.
    fn budget(&self, bounds: &QuadtreeTessellator, mesh: &Mesh) -> Result<f64, TessError> {
        let epsilon = self.tolerance.absolute(bounds.diagonal())?;
        let magnitude = mesh.positions().iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
        Ok(epsilon - rounding_slack(magnitude))
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use subdiv_mesh::shapes;

    use super::*;

    fn square() -> Mesh {
        Mesh::build(shapes::quad_grid(1, 1)).expect("grid")
    }

    /// A unit square 10 units in front of a 90° camera on a 1000-pixel-high image spans
    /// 1000 / 2 / 10 = 50 pixels per unit: 50 / 5 = 10 segments.
    #[test]
    fn rate_is_projected_edge_over_pixels() {
        let mesh = square();
        let corner = mesh.position(mesh.vertices().next().expect("a vertex"));
        let (lo, hi) =
            mesh.vertices().map(|v| mesh.position(v)).fold((corner, corner), |(lo, hi), p| (lo.min(p), hi.max(p)));
        let centre = 0.5 * (lo + hi);
        let side = (hi - lo).max_element();
        let camera = Camera::look_at(centre + DVec3::Z * 10.0 * side, centre, DVec3::Y).with_fovy_degrees(90.0);
        let rates = ScreenSpace::new(camera, [1000, 1000], 5.0).face_rates(&mesh).expect("valid");
        assert_eq!(rates, [10]);
        let clamped = ScreenSpace { max_rate: 4, ..ScreenSpace::new(camera, [1000, 1000], 5.0) };
        assert_eq!(clamped.face_rates(&mesh).expect("valid"), [4]);
        // Behind the eye: the coarsest rate.
        let behind = Camera::look_at(centre + DVec3::Z * side, centre + DVec3::Z * 2.0 * side, DVec3::Y);
        assert_eq!(ScreenSpace::new(behind, [1000, 1000], 5.0).face_rates(&mesh).expect("valid"), [1]);
    }

    /// On a regular torus the rate grows like `1/√ε`; a tolerance beyond reach is a typed error
    /// naming a face.
    #[test]
    fn error_rates_follow_the_bounds() {
        let cc = subdiv_schemes::Builtin::CatmullClark.scheme();
        let torus = Mesh::build(shapes::quad_torus(16, 8)).expect("torus");
        let bounds = QuadtreeTessellator::new(cc, &torus).expect("closed");
        let rate = |r: f64| ErrorRates::new(Tolerance::Relative(r)).rates(&bounds, &torus).expect("reachable").faces;
        let (coarse, fine) = (rate(1e-3), rate(1e-5));
        let ratio = f64::from(*fine.iter().max().expect("faces")) / f64::from(*coarse.iter().max().expect("faces"));
        assert!((8.0..=12.0).contains(&ratio), "rates {coarse:?} → {fine:?}");
        let cube = Mesh::build(shapes::cube()).expect("cube");
        let bounds = QuadtreeTessellator::new(cc, &cube).expect("closed");
        assert!(ErrorRates::new(Tolerance::Relative(3e-2)).rates(&bounds, &cube).is_ok());
        let err = ErrorRates { max_rate: 8, ..ErrorRates::new(Tolerance::Relative(1e-3)) }.rates(&bounds, &cube);
        assert!(matches!(err, Err(TessError::RateLimit { max_rate: 8, .. })), "{err:?}");
        let bad = ErrorRates::new(Tolerance::Absolute(-1.0)).rates(&bounds, &cube);
        assert!(matches!(bad, Err(TessError::Tolerance { .. })), "{bad:?}");
    }

    /// With rings the face rates follow the second derivatives alone; the cube's valence-3
    /// corners get ring depths, deeper for a finer tolerance.
    #[test]
    fn ring_depths_follow_the_hulls() {
        let cc = subdiv_schemes::Builtin::CatmullClark.scheme();
        let cube = Mesh::build(shapes::cube()).expect("cube");
        let bounds = QuadtreeTessellator::new(cc, &cube).expect("closed");
        let rates = |r: f64| ErrorRates::new(Tolerance::Relative(r)).rates(&bounds, &cube).expect("reachable");
        let (coarse, fine) = (rates(3e-2), rates(1e-2));
        assert!(coarse.faces.iter().zip(&fine.faces).all(|(c, f)| c < f), "{coarse:?} {fine:?}");
        assert!(coarse.rings.vertices.iter().all(|&d| d > 0) && coarse.rings.centres.iter().all(|&d| d == 0));
        assert!(coarse.rings.vertices.iter().zip(&fine.rings.vertices).all(|(c, f)| c <= f), "{coarse:?} {fine:?}");
        // A regular torus has no extraordinary points: no rings.
        let torus = Mesh::build(shapes::quad_torus(16, 8)).expect("torus");
        let bounds = QuadtreeTessellator::new(cc, &torus).expect("closed");
        let r = ErrorRates::new(Tolerance::Relative(1e-3)).rates(&bounds, &torus).expect("reachable");
        assert!(r.rings.vertices.iter().all(|&d| d == 0));
        // And the rates are ⌈√(M/(3ε))⌉ of the faces' own bound (no corner to exclude).
        let epsilon = Tolerance::Relative(1e-3).absolute(bounds.diagonal()).expect("valid");
        let magnitude = torus.positions().iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
        let budget = epsilon - rounding_slack(magnitude);
        let second: Vec<f64> = torus.face_ids().map(|f| bounds.face_curvature(f, 1).expect("face").second).collect();
        let want: Vec<u32> = torus
            .face_ids()
            .map(|f| {
                let around = torus.face_vertices(f).iter().flat_map(|&v| torus.vertex_faces(v));
                let m = around.map(|g| second[g.index()]).fold(0.0, f64::max);
                (QUAD_SPLIT.cells * m / budget).sqrt().ceil() as u32
            })
            .collect();
        assert_eq!(r.faces, want);
    }

    #[test]
    fn degenerate_cameras_are_typed_errors() {
        let mesh = square();
        let good = Camera::look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y);
        let cases = [
            ScreenSpace::new(Camera { target: good.eye, ..good }, [100, 100], 2.0),
            ScreenSpace::new(Camera { up: DVec3::Z, ..good }, [100, 100], 2.0),
            ScreenSpace::new(good.with_fovy_degrees(180.0), [100, 100], 2.0),
            ScreenSpace::new(Camera { eye: DVec3::NAN, ..good }, [100, 100], 2.0),
            ScreenSpace::new(good, [0, 100], 2.0),
            ScreenSpace::new(good, [100, 100], 0.0),
            ScreenSpace::new(good, [100, 100], f64::INFINITY),
            ScreenSpace { max_rate: 0, ..ScreenSpace::new(good, [100, 100], 2.0) },
        ];
        for case in cases {
            assert!(matches!(case.face_rates(&mesh), Err(TessError::Camera { .. })), "{case:?}");
        }
    }
}
