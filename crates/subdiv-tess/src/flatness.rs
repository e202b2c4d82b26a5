//! Flatness with a guaranteed bound (paper 002 §4, §6), for the triangles the quadtree
//! tessellator actually outputs.
//!
//! # The guarantee
//! For every output triangle with parameter corners `c, a, b` and every parameter point `p`
//! inside it, `‖S(p) − T(p)‖ ≤ ε`, where `T` is the linear interpolant of `S(c), S(a), S(b)` over
//! the parameter triangle. This *parametric* distance is stronger than the distance from `S` to
//! the mesh, and it is what the tests measure.
//!
//! # Regular nodes: cone + chord
//! A quadtree node away from the extraordinary corner is one bicubic polynomial `S` (a Bézier
//! patch, [`Bicubic`]) on its square. Its leaf polygon (corners plus the hanging points of finer
//! neighbours on its edges) is triangulated as a fan around the centre `c`. Take a fan triangle
//! `(c, a, b)`, `a, b` consecutive on edge `e`, and `p = c + s(q − c)` with `q` on `[a, b]`,
//! `s ∈ [0, 1]`. Its barycentric weights are `1 − s` for `c` and `s·(weights of q on [a, b])`,
//! so `T(p) = (1 − s) S(c) + s L_ab(q)` with `L_ab` the chord of `S` over `[a, b]`, and
//!
//! `S(p) − T(p) = [S(p) − K(p)] + s [S(q) − L_ab(q)]`, `K(p) = (1 − s) S(c) + s S(q)`.
//!
//! *Bound 1 (cone)*: `K` does not depend on the hanging points. On the whole triangle
//! `(c, P_e, P_{e+1})` with `q = P_e + t (P_{e+1} − P_e)`, `S(p(s, t)) − K` is a polynomial of
//! bidegree (6, 3) in `(s, t)` (`p` is bilinear in `(s, t)` with no `t` in the coordinate that
//! stays constant along the edge, and `S` is bicubic). Its tensor Bernstein coefficients come
//! from its values on the 7 × 4 grid `(i/6, j/3)` times the inverse Bernstein collocation
//! matrices; the polynomial is a convex combination of its coefficients, so their largest norm
//! bounds it (upper), and the corner coefficients are values (lower). When undecided the
//! Bernstein patch is split by de Casteljau and the test repeated on the halves.
//!
//! *Bound 2 (chord)*: along the edge `S` is a cubic `C(t)`; for any sub-segment of parameter
//! length `h ≤ 1`, `C − L = −∫ G C''` with Green's function `G ≥ 0`, `∫ G ≤ h²/8`, so
//! `‖C − L‖ ≤ max‖C''‖ / 8`; `C''` is linear, so its largest norm is at an end. Any set of
//! hanging points only shortens the segments: the bound does not depend on the neighbours.
//!
//! Combined: `‖S(p) − T(p)‖ ≤ F(s, t) = ‖S − K‖(s, t) + s·χ` with `χ` the chord bound, and `F`
//! is bounded by the Bernstein coefficients of both terms (`s` has coefficients `i/6`): tighter
//! than adding the two maxima, since the cone error vanishes at the edge (`s = 1`). A node is
//! flat when `max F` + slack ≤ ε for each of its four edges. The slack
//! ([`rounding_slack`], `1e−12 ×` the largest coordinate of the net) covers the f64 rounding of
//! these few hundred operations and of the vertices' own evaluation (each relative error is a
//! few units of 2⁻⁵³ times the small norms of the collocation inverses).
//!
//! *Triangles* (Loop): a quartic node's leaf polygon is fanned around its centroid, and the same
//! two bounds hold with bidegree (4, 4) for the cone (`p` is bilinear in `(s, t)`, `S` has total
//! degree 4) and a quartic side for the chord ([`quartic_is_flat`]).
//!
//! # The node at the extraordinary corner
//! Every sub-patch matrix of Catmull-Clark and of Loop has non-negative entries with rows summing to 1
//! (checked when the tessellator is built). So the limit surface over the node at the corner of
//! depth `d` is a limit of convex combinations of its control points `C_d = A^d C`: it lies in
//! their convex hull. Every vertex of a triangle of that leaf lies on the node's surface, hence
//! `T(p)` lies in the hull too, and `‖S(p) − T(p)‖ ≤ diam(C_d)`, the largest distance between two
//! control points ([`hull_diameter`]). This is the paper's `m_ε` argument (§4.1, `‖S − S(0,0)‖ <
//! ε/2` once `m ≥ m_ε`) with the convex hull giving the constant: `diam ≤ 2 max‖c_i − S(0, 0)‖`.
//!
//! # Non-polynomial pieces
//! A scheme whose regular pieces are no polynomials (paper 000's `sw-quad`) but whose matrices
//! are convex combinations that reproduce linear functions of the control points' parameters
//! is bounded by the control points' distance from an affine fit ([`linear_is_flat`]): second
//! order like the cone and chord bounds, looser by the footprint of the control points — the
//! quadtree hands it the piece's descendants' points two levels down, whose rings hug the
//! piece (about 1.5 times its side, against 3 for its own).
//!
//! # The paper's own quantities
//! [`base_quad_distance_bound`] (Eq. 7: the distance of a patch to its bilinear base
//! quadrilateral, as a guaranteed upper bound), [`two_sided_bound`] (Eq. 8: the slab between two
//! offsets of the base quadrilateral) and [`relative_flatness`] (§6). They bound the distance to
//! the *base quadrilateral*, not to the triangles a polygon with hanging points is cut into,
//! which is why the tessellator uses the cone and chord bounds.

use std::sync::OnceLock;

use glam::DVec3;

use crate::TessError;
use crate::bezier::Bicubic;
use crate::quartic::Quartic;

/// How flat the output must be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// Every output triangle within `ε` (model units) of the surface.
    Absolute(f64),
    /// `ε = r ×` the diagonal of the control mesh's bounding box. (The paper's §6 divides by
    /// each patch's own base-quad diagonal; with a parametric distance that ratio does not
    /// shrink at extraordinary vertices — the characteristic map is not bilinear — so leaves
    /// there would never pass. Relative to the model it keeps the guarantee absolute.)
    Relative(f64),
}

impl Tolerance {
    /// The absolute `ε` for a model whose bounding-box diagonal is `diagonal`.
    ///
    /// # Errors
    /// [`TessError::Tolerance`] for a value that is not a positive finite number, or a
    /// relative one when `diagonal` is 0 or not finite (every vertex at one point).
    ///
    /// ```
    /// use subdiv_tess::Tolerance;
    ///
    /// assert_eq!(Tolerance::Relative(0.01).absolute(2.0)?, 0.02);
    /// let e = Tolerance::Relative(0.01).absolute(0.0).unwrap_err();
    /// assert!(e.to_string().contains("bounding-box diagonal is 0"), "{e}");
    /// # Ok::<(), subdiv_tess::TessError>(())
    /// ```
    pub fn absolute(self, diagonal: f64) -> Result<f64, TessError> {
        let (value, epsilon) = match self {
            Self::Absolute(e) => (e, e),
            Self::Relative(r) => (r, r * diagonal),
        };
        if !(value.is_finite() && value > 0.0) {
            return Err(TessError::Tolerance {
                value: format!("{value:?}"),
                reason: "is not a positive finite number".into(),
            });
        }
        if !(epsilon.is_finite() && epsilon > 0.0) {
            return Err(TessError::Tolerance {
                value: format!("{value:?}"),
                reason: format!(
                    "is relative, but the mesh's bounding-box diagonal is {diagonal:?}, so it gives no distance; \
                     give an absolute tolerance"
                ),
            });
        }
        Ok(epsilon)
    }
}

/// The floating-point slack added to every bound of a net whose largest coordinate is
/// `magnitude` (see the module docs).
pub fn rounding_slack(magnitude: f64) -> f64 {
    1e-12 * magnitude
}

/// The corners of the unit square in fan order.
const CORNERS: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

/// The corners of the unit triangle `u, v ≥ 0, u + v ≤ 1` in fan order.
const TRIANGLE_CORNERS: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// How often an undecided Bernstein bound is split before the node counts as not flat.
const REFINEMENTS: usize = 6;

/// The inverse collocation matrices of degrees 6, 3 and 4.
type Inverses = ([[f64; 7]; 7], [[f64; 4]; 4], [[f64; 5]; 5]);

/// `(B^n_k(i/n))_{ik}⁻¹` for n = 6, 3 and 4, computed once.
fn collocation_inverses() -> &'static Inverses {
    static INVERSES: OnceLock<Inverses> = OnceLock::new();
    INVERSES.get_or_init(|| (invert::<7>(), invert::<4>(), invert::<5>()))
}

/// The inverse of the Bernstein collocation matrix of degree `N − 1` at `i/(N − 1)` (the matrix
/// is totally positive and well conditioned).
fn invert<const N: usize>() -> [[f64; N]; N] {
    let n = N - 1;
    let binomial = |k: usize| (0..k).fold(1.0, |acc, m| acc * (n - m) as f64 / (m + 1) as f64);
    let a = std::array::from_fn(|i| {
        let t = i as f64 / n as f64;
        std::array::from_fn(|k| binomial(k) * t.powi(k as i32) * (1.0 - t).powi((n - k) as i32))
    });
    gauss_jordan(a)
}

/// The inverse of a non-singular matrix, by Gauss-Jordan elimination with partial pivoting.
pub(crate) fn gauss_jordan<const N: usize>(mut a: [[f64; N]; N]) -> [[f64; N]; N] {
    let mut inv: [[f64; N]; N] = std::array::from_fn(|i| std::array::from_fn(|k| f64::from(u8::from(i == k))));
    for col in 0..N {
        let pivot = (col..N).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs())).unwrap_or(col);
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let d = a[col][col];
        for k in 0..N {
            a[col][k] /= d;
            inv[col][k] /= d;
        }
        for row in 0..N {
            if row != col {
                let f = a[row][col];
                for k in 0..N {
                    a[row][k] -= f * a[col][k];
                    inv[row][k] -= f * inv[col][k];
                }
            }
        }
    }
    inv
}

/// A polynomial of bidegree `(M − 1, N − 1)` in tensor Bernstein form, `c[i][j]` for `s`-index
/// `i`.
#[derive(Clone, Copy)]
struct Bernstein<const M: usize, const N: usize> {
    c: [[DVec3; N]; M],
}

impl<const M: usize, const N: usize> Bernstein<M, N> {
    /// The largest Bernstein coefficient of `‖c‖ + χ·s` on an `s`-range `[s0, s1]`.
    fn upper(&self, chord: f64, s0: f64, s1: f64) -> f64 {
        (0..M)
            .flat_map(|i| (0..N).map(move |j| (i, j)))
            .map(|(i, j)| self.c[i][j].length() + chord * (s0 + (s1 - s0) * i as f64 / (M - 1) as f64))
            .fold(0.0, f64::max)
    }

    /// The largest known value of `‖c‖ + χ·s`: the corner coefficients are values.
    fn lower(&self, chord: f64, s0: f64, s1: f64) -> f64 {
        [(0, 0, s0), (M - 1, 0, s1), (0, N - 1, s0), (M - 1, N - 1, s1)]
            .iter()
            .map(|&(i, j, s)| self.c[i][j].length() + chord * s)
            .fold(0.0, f64::max)
    }

    /// The two halves along `s` (`along_s`) or `t`, by de Casteljau at ½.
    fn split(&self, along_s: bool) -> (Self, Self) {
        let mut lo = *self;
        let mut hi = *self;
        if along_s {
            for j in 0..N {
                let (l, h) = casteljau(&self.c.map(|row| row[j]));
                for i in 0..M {
                    lo.c[i][j] = l[i];
                    hi.c[i][j] = h[i];
                }
            }
        } else {
            for i in 0..M {
                let (l, h) = casteljau(&self.c[i]);
                lo.c[i] = l;
                hi.c[i] = h;
            }
        }
        (lo, hi)
    }
}

/// Both halves of a Bernstein polynomial of degree `N − 1` at ½.
fn casteljau<const N: usize>(p: &[DVec3; N]) -> ([DVec3; N], [DVec3; N]) {
    let mut work = *p;
    let mut lo = [DVec3::ZERO; N];
    let mut hi = [DVec3::ZERO; N];
    for r in 0..N {
        lo[r] = work[0];
        hi[N - 1 - r] = work[N - 1 - r];
        for k in 0..N - 1 - r {
            work[k] = (work[k] + work[k + 1]) * 0.5;
        }
    }
    (lo, hi)
}

/// The cone error `S(c + s(q(t) − c)) − (1 − s)S(c) − s S(q(t))`, `q(t) = a + t(b − a)`, of the
/// fan triangle `(c, a, b)` of a polynomial `eval` whose restriction to it has bidegree
/// `(M − 1, N − 1)` in `(s, t)`, in Bernstein form (values on the grid `(i/(M−1), j/(N−1))`
/// times the inverse collocation matrices).
fn cone_error<const M: usize, const N: usize>(
    eval: impl Fn(f64, f64) -> DVec3,
    [c, a, b]: [[f64; 2]; 3],
    (inv_s, inv_t): (&[[f64; M]; M], &[[f64; N]; N]),
) -> Bernstein<M, N> {
    let centre = eval(c[0], c[1]);
    let mut values = [[DVec3::ZERO; N]; M];
    for j in 0..N {
        let t = j as f64 / (N - 1) as f64;
        let q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
        let on_edge = eval(q[0], q[1]);
        for (i, row) in values.iter_mut().enumerate() {
            let s = i as f64 / (M - 1) as f64;
            let p = eval(c[0] + s * (q[0] - c[0]), c[1] + s * (q[1] - c[1]));
            row[j] = p - (1.0 - s) * centre - s * on_edge;
        }
    }
    let mut out = [[DVec3::ZERO; N]; M];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            *entry = (0..M)
                .flat_map(|x| (0..N).map(move |y| (x, y)))
                .map(|(x, y)| inv_s[i][x] * inv_t[j][y] * values[x][y])
                .sum();
        }
    }
    Bernstein { c: out }
}

/// The cone error of fan triangle `edge` of the unit square around its centre: bidegree (6, 3)
/// (`p` is bilinear in `(s, t)` with no `t` in the coordinate that stays constant along the
/// edge, and `S` is bicubic).
fn bicubic_cone_error(patch: &Bicubic, edge: usize) -> Bernstein<7, 4> {
    let (inv6, inv3, _) = collocation_inverses();
    let fan = [[0.5, 0.5], CORNERS[edge], CORNERS[(edge + 1) % 4]];
    cone_error(|x, y| patch.eval(x, y), fan, (inv6, inv3))
}

/// The chord bound of a side whose curve has Bézier points `p`: `max‖C''‖ / 8`, `C''` bounded
/// by its own Bézier coefficients `n(n − 1) Δ²p`.
fn side_chord_bound<const N: usize>(p: &[DVec3; N]) -> f64 {
    let n = (N - 1) as f64;
    p.windows(3).map(|w| (n * (n - 1.0) * (w[0] - 2.0 * w[1] + w[2])).length()).fold(0.0, f64::max) / 8.0
}

/// The chord bound of edge `edge`: `max‖C''‖ / 8` for the edge's cubic `C` (`C''` is linear, so
/// its largest norm is at an end).
fn chord_bound(patch: &Bicubic, edge: usize) -> f64 {
    let n = &patch.net;
    let p = match edge {
        0 => n[0],
        1 => [n[0][3], n[1][3], n[2][3], n[3][3]],
        2 => n[3],
        _ => [n[0][0], n[1][0], n[2][0], n[3][0]],
    };
    side_chord_bound(&p)
}

/// The unrefined bounds of a regular node's four fan triangles (edge order: `y = 0`, `x = 1`,
/// `y = 1`, `x = 0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FanBound {
    /// Bound 1 per edge: the largest Bernstein coefficient of the cone error.
    pub cone: [f64; 4],
    /// Bound 2 per edge: the chord bound.
    pub chord: [f64; 4],
}

impl FanBound {
    /// The bound on the parametric distance of the node's fan triangles to the surface.
    pub fn total(&self) -> f64 {
        (0..4).map(|e| self.cone[e] + self.chord[e]).fold(0.0, f64::max)
    }
}

/// The cone and chord bounds of a regular node (see the module docs), without refinement.
pub fn fan_bound(patch: &Bicubic) -> FanBound {
    FanBound {
        cone: std::array::from_fn(|e| bicubic_cone_error(patch, e).upper(0.0, 0.0, 1.0)),
        chord: std::array::from_fn(|e| chord_bound(patch, e)),
    }
}

/// Whether every fan triangle of a regular node, with any hanging points on its edges, is within
/// `epsilon` of the surface (cone + chord + slack, the cone bound refined by splitting its
/// Bernstein form while undecided).
pub fn regular_is_flat(patch: &Bicubic, epsilon: f64) -> bool {
    let slack = rounding_slack(patch.magnitude());
    let budget = epsilon - slack;
    budget >= 0.0 && (0..4).all(|edge| bounded_by(bicubic_cone_error(patch, edge), chord_bound(patch, edge), budget))
}

/// Whether a quartic triangle node's three fan triangles around its centroid `(⅓, ⅓)`, with any
/// hanging points on its sides, are within `epsilon` of the surface: the cone and chord bounds
/// of the regular nodes (see the module docs), with bidegree (4, 4) (`p` is bilinear in
/// `(s, t)` and `S` has total degree 4) and quartic sides ([`quartic_chord_bound`]).
pub fn quartic_is_flat(patch: &Quartic, epsilon: f64) -> bool {
    let (.., inv4) = collocation_inverses();
    let budget = epsilon - rounding_slack(patch.magnitude());
    budget >= 0.0
        && (0..3).all(|side| {
            let fan = [[1.0 / 3.0, 1.0 / 3.0], TRIANGLE_CORNERS[side], TRIANGLE_CORNERS[(side + 1) % 3]];
            let cone = cone_error(|u, v| patch.eval(u, v), fan, (inv4, inv4));
            bounded_by(cone, quartic_chord_bound(&patch.side(side)), budget)
        })
}

/// The chord bound of a quartic side with Bézier points `p`, for chords between dyadic hanging
/// points: over the whole side the chord error `C − L` is a quartic whose Bézier coefficients
/// are `p_k − L(k/4)`, bounded by their largest norm after three halvings (eight pieces, whose
/// coefficients bound it piecewise); with any hanging point, every chord spans
/// at most half the side, where `max‖C''‖ h² / 8 ≤ max‖C''‖ / 32`. (`max‖C''‖ / 8` alone is three
/// times the sampled error on a sine-like side.)
fn quartic_chord_bound(p: &[DVec3; 5]) -> f64 {
    let error: [DVec3; 5] = std::array::from_fn(|k| p[k] - p[0].lerp(p[4], k as f64 / 4.0));
    let mut pieces = vec![error];
    for _ in 0..3 {
        pieces = pieces.iter().flat_map(|c| <[[DVec3; 5]; 2]>::from(casteljau(c))).collect();
    }
    let whole = pieces.iter().flatten().map(|d| d.length()).fold(0.0, f64::max);
    whole.max(side_chord_bound(p) / 4.0)
}

/// Whether `‖poly‖ + chord·s` stays within `budget` on the whole box `[0, 1]²`.
fn bounded_by<const M: usize, const N: usize>(poly: Bernstein<M, N>, chord: f64, budget: f64) -> bool {
    let mut stack = vec![(poly, 0.0, 1.0, 0)];
    while let Some((p, s0, s1, depth)) = stack.pop() {
        if p.upper(chord, s0, s1) <= budget {
            continue;
        }
        if p.lower(chord, s0, s1) > budget || depth == REFINEMENTS {
            return false;
        }
        // Split the higher degree more often: s twice as often as t for (6, 3).
        let along_s = if M > N { depth % 3 != 2 } else { depth % 2 == 0 };
        let (a, b) = p.split(along_s);
        let mid = 0.5 * (s0 + s1);
        if along_s {
            stack.push((a, s0, mid, depth + 1));
            stack.push((b, mid, s1, depth + 1));
        } else {
            stack.push((a, s0, s1, depth + 1));
            stack.push((b, s0, s1, depth + 1));
        }
    }
    true
}

/// The diameter of a point set: the largest distance between two of its points, which bounds
/// the distance between any two points of its convex hull.
pub fn hull_diameter(points: &[DVec3]) -> f64 {
    let mut d: f64 = 0.0;
    for (k, a) in points.iter().enumerate() {
        for b in &points[k + 1..] {
            d = d.max(a.distance(*b));
        }
    }
    d
}

/// Whether the node at an extraordinary corner with control points `points` is flat: every
/// triangle with its vertices on the node's surface is within the hull's diameter of it.
pub fn extraordinary_is_flat(points: &[DVec3], epsilon: f64) -> bool {
    let magnitude = points.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    hull_diameter(points) + rounding_slack(magnitude) <= epsilon
}

/// Whether a piece of a non-polynomial scheme is flat: its surface is `S(u) = Σ B_i(u) c_i` over
/// its control points `points` with `B_i ≥ 0`, `Σ B_i = 1` (convex matrices) and `Σ B_i(u) ξ_i =
/// u` (linear precision over the control points' `parameters` ξ; points without influence
/// left out by the caller). For any affine `A`, `S(u) − A(u) = Σ B_i(u) (c_i − A(ξ_i))`, so `‖S − A‖ ≤ D =
/// max_i ‖c_i − A(ξ_i)‖`; a triangle with its corners on the piece interpolates values within
/// `D` of `A` too, so every output point is within `2D` of the surface at its parameter. `A` is
/// the least-squares fit; `D` shrinks like the square of the piece's size where the surface is
/// smooth (second differences of the control points), as the cone and chord bounds do.
pub fn linear_is_flat(points: &[DVec3], parameters: &[Vec<f64>; 2], epsilon: f64) -> bool {
    let basis = |k: usize| [1.0, parameters[0][k], parameters[1][k]];
    let mut normal = [[0.0; 3]; 3];
    let mut rhs = [DVec3::ZERO; 3];
    for (k, &p) in points.iter().enumerate() {
        let b = basis(k);
        for i in 0..3 {
            for j in 0..3 {
                normal[i][j] += b[i] * b[j];
            }
            rhs[i] += b[i] * p;
        }
    }
    let inverse = gauss_jordan(normal);
    let a: [DVec3; 3] = std::array::from_fn(|i| (0..3).map(|j| inverse[i][j] * rhs[j]).sum());
    if !a.iter().all(|c| c.is_finite()) {
        // Parameters on a line (not a surface piece): the hull alone.
        return extraordinary_is_flat(points, epsilon);
    }
    let d = (0..points.len()).map(|k| (points[k] - a[0] - a[1] * parameters[0][k] - a[2] * parameters[1][k]).length());
    let magnitude = points.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    2.0 * d.fold(0.0, f64::max) + rounding_slack(magnitude) <= epsilon
}

/// The bilinear base quadrilateral of the patch's corners at `(x, y)` (paper 002, Eq. 4).
pub fn base_quad(corners: &[DVec3; 4], x: f64, y: f64) -> DVec3 {
    (1.0 - y) * ((1.0 - x) * corners[0] + x * corners[1]) + y * ((1.0 - x) * corners[3] + x * corners[2])
}

/// An upper bound, never below the truth, of the paper's distance `D = max ‖S − Q‖` between a
/// patch and its bilinear base quadrilateral `Q` (Eq. 7's left side): `Q` raised to bicubic
/// degree has the net `Q(i/3, j/3)`, so `S − Q` is a convex combination of `b_ij − Q(i/3, j/3)`.
pub fn base_quad_distance_bound(patch: &Bicubic) -> f64 {
    let corners = patch.corners();
    (0..4)
        .flat_map(|j| (0..4).map(move |i| (i, j)))
        .map(|(i, j)| (patch.net[j][i] - base_quad(&corners, i as f64 / 3.0, j as f64 / 3.0)).length())
        .fold(0.0, f64::max)
}

/// The two sides of Eq. 8: how far the patch reaches above and below its base quadrilateral
/// along `N = (V₁ − V₃) × (V₂ − V₄)` (paper 002 §4.2), as guaranteed bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoSided {
    /// `max(0, max (S − Q)·N̂)`.
    pub above: f64,
    /// `max(0, max (Q − S)·N̂)`.
    pub below: f64,
}

impl TwoSided {
    /// Eq. 8: the patch lies between two offsets of the base quadrilateral `ε` apart.
    pub fn is_flat(&self, epsilon: f64) -> bool {
        self.above + self.below <= epsilon
    }
}

/// Eq. 8's two one-sided distances, from the Bernstein coefficients of `(S − Q)·N̂`; a patch
/// whose diagonals are parallel (no normal) gets the full distance bound on both sides.
pub fn two_sided_bound(patch: &Bicubic) -> TwoSided {
    let corners = patch.corners();
    let normal = (corners[0] - corners[2]).cross(corners[1] - corners[3]);
    let Some(n) = normal.try_normalize() else {
        let d = base_quad_distance_bound(patch);
        return TwoSided { above: d, below: d };
    };
    let heights = (0..4)
        .flat_map(|j| (0..4).map(move |i| (i, j)))
        .map(|(i, j)| (patch.net[j][i] - base_quad(&corners, i as f64 / 3.0, j as f64 / 3.0)).dot(n));
    let (lo, hi) = heights.fold((0.0f64, 0.0f64), |(lo, hi), h| (lo.min(h), hi.max(h)));
    TwoSided { above: hi, below: -lo }
}

/// The paper's relative flatness (§6): `distance / max(D₁, D₂)`, the diagonals of the base
/// quadrilateral with corners `corners`; infinite for a quadrilateral collapsed to a point.
pub fn relative_flatness(distance: f64, corners: &[DVec3; 4]) -> f64 {
    let diagonal = corners[0].distance(corners[2]).max(corners[1].distance(corners[3]));
    if diagonal > 0.0 { distance / diagonal } else { f64::INFINITY }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wavy(scale: f64) -> Bicubic {
        let mut net = [[DVec3::ZERO; 4]; 4];
        for (j, row) in net.iter_mut().enumerate() {
            for (i, p) in row.iter_mut().enumerate() {
                let (x, y) = (i as f64 / 3.0, j as f64 / 3.0);
                *p = DVec3::new(x, y, scale * ((3.0 * x).sin() * (2.0 * y).cos() + x * y));
            }
        }
        Bicubic { net }
    }

    /// The largest parametric distance of the fan triangles around `c` of the polygon `corners`
    /// (with a hanging point at every side's `hanging`) to the patch `eval`, sampled densely.
    fn sampled_fan_error_of(eval: impl Fn(f64, f64) -> DVec3, c: [f64; 2], corners: &[[f64; 2]], hanging: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for side in 0..corners.len() {
            let ([ax, ay], [bx, by]) = (corners[side], corners[(side + 1) % corners.len()]);
            let h = [ax + hanging * (bx - ax), ay + hanging * (by - ay)];
            for (a, b) in [([ax, ay], h), (h, [bx, by])] {
                let (sc, sa, sb) = (eval(c[0], c[1]), eval(a[0], a[1]), eval(b[0], b[1]));
                for i in 0..=20 {
                    for j in 0..=(20 - i) {
                        let (la, lb) = (f64::from(i) / 20.0, f64::from(j) / 20.0);
                        let lc = 1.0 - la - lb;
                        let (x, y) = (lc * c[0] + la * a[0] + lb * b[0], lc * c[1] + la * a[1] + lb * b[1]);
                        worst = worst.max((eval(x, y) - (lc * sc + la * sa + lb * sb)).length());
                    }
                }
            }
        }
        worst
    }

    /// The bicubic's four fan triangles around its centre.
    fn sampled_fan_error(patch: &Bicubic, hanging: f64) -> f64 {
        sampled_fan_error_of(|x, y| patch.eval(x, y), [0.5, 0.5], &CORNERS, hanging)
    }

    #[test]
    fn collocation_inverses_invert() {
        let (inv6, inv3, inv4) = collocation_inverses();
        // The Bernstein coefficients of the constant 1 are all 1.
        let rows = inv6.iter().map(|r| r.iter().sum::<f64>());
        for sum in rows.chain(inv3.iter().map(|r| r.iter().sum())).chain(inv4.iter().map(|r| r.iter().sum())) {
            assert!((sum - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn fan_bound_is_never_below_the_sampled_error() {
        for scale in [0.01, 0.1, 1.0] {
            let patch = wavy(scale);
            let bound = fan_bound(&patch).total();
            for hanging in [1.0, 0.5, 0.25, 0.8125] {
                let sampled = sampled_fan_error(&patch, hanging);
                assert!(sampled <= bound * (1.0 + 1e-12), "{sampled} > {bound}");
            }
            // The refined test is never below the sampled error, and not far above it: the
            // smallest ε it accepts, by bisection.
            let sampled = [1.0, 0.5, 0.25].map(|h| sampled_fan_error(&patch, h)).into_iter().fold(0.0, f64::max);
            assert!(regular_is_flat(&patch, bound * 1.0001));
            assert!(!regular_is_flat(&patch, sampled * 0.999));
            let (mut lo, mut hi) = (sampled, bound * 1.0001);
            for _ in 0..30 {
                let mid = 0.5 * (lo + hi);
                if regular_is_flat(&patch, mid) { hi = mid } else { lo = mid }
            }
            assert!(hi < 1.25 * sampled, "scale {scale}: refined bound {hi} loose against {sampled} (coarse {bound})");
        }
    }

    /// A wavy quartic triangle: the quartic interpolating a smooth function at the domain points.
    fn wavy_quartic(scale: f64) -> Quartic {
        Quartic::from_values(&crate::quartic::per_point(|i, j| {
            let (x, y) = (i as f64 / 4.0, j as f64 / 4.0);
            DVec3::new(x, y, scale * ((3.0 * x).sin() * (2.0 * y).cos() + x * y))
        }))
    }

    /// A quartic's three fan triangles around `(⅓, ⅓)`.
    fn sampled_quartic_fan_error(patch: &Quartic, hanging: f64) -> f64 {
        sampled_fan_error_of(|u, v| patch.eval(u, v), [1.0 / 3.0, 1.0 / 3.0], &TRIANGLE_CORNERS, hanging)
    }

    #[test]
    fn quartic_bound_is_never_below_the_sampled_error_and_not_loose() {
        for scale in [0.01, 0.1, 1.0] {
            let patch = wavy_quartic(scale);
            let sampled = [1.0, 0.5, 0.25, 0.8125].map(|h| sampled_quartic_fan_error(&patch, h));
            let worst = sampled.into_iter().fold(0.0, f64::max);
            // The smallest ε the test accepts, by bisection: never below any sampled error.
            let (mut lo, mut hi) = (0.0, 10.0);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if quartic_is_flat(&patch, mid) { hi = mid } else { lo = mid }
            }
            assert!(hi >= worst * (1.0 - 1e-9), "scale {scale}: accepted {hi} below the sampled {worst}");
            assert!(hi < 1.5 * worst, "scale {scale}: bound {hi} loose against {worst}");
        }
        // A linear triangle is flat at any tolerance.
        let flat = Quartic::from_values(&std::array::from_fn(|a| DVec3::new(a as f64, 0.5, 0.0)));
        let linear = Quartic {
            net: crate::quartic::per_point(|i, j| DVec3::new(i as f64, j as f64, 0.5 * i as f64 - j as f64)),
        };
        assert!(quartic_is_flat(&linear, 1e-9));
        assert!(!quartic_is_flat(&flat, 1e-9), "values not on a plane are not flat");
    }

    #[test]
    fn a_bilinear_patch_is_flat_at_any_tolerance() {
        let corners = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.5), DVec3::Y];
        let mut net = [[DVec3::ZERO; 4]; 4];
        for (j, row) in net.iter_mut().enumerate() {
            for (i, p) in row.iter_mut().enumerate() {
                *p = base_quad(&corners, i as f64 / 3.0, j as f64 / 3.0);
            }
        }
        let patch = Bicubic { net };
        assert!(base_quad_distance_bound(&patch) < 1e-15);
        assert!(two_sided_bound(&patch).is_flat(1e-15));
    }

    #[test]
    fn paper_bounds_contain_the_sampled_distances() {
        let patch = wavy(0.3);
        let corners = patch.corners();
        let bound = base_quad_distance_bound(&patch);
        let sides = two_sided_bound(&patch);
        let n = (corners[0] - corners[2]).cross(corners[1] - corners[3]).normalize();
        let mut worst: f64 = 0.0;
        for i in 0..=32 {
            for j in 0..=32 {
                let (x, y) = (f64::from(i) / 32.0, f64::from(j) / 32.0);
                let d = patch.eval(x, y) - base_quad(&corners, x, y);
                worst = worst.max(d.length());
                assert!(d.dot(n) <= sides.above + 1e-15 && -d.dot(n) <= sides.below + 1e-15);
            }
        }
        assert!(worst <= bound && bound < 2.0 * worst, "{worst} vs {bound}");
        assert!(sides.above > 0.0 && sides.below > 0.0);
    }

    #[test]
    fn relative_flatness_is_scale_invariant() {
        let corners = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let scaled = corners.map(|c| 7.0 * c);
        let r = relative_flatness(0.1, &corners);
        assert!((r - 0.1 / 2f64.sqrt()).abs() < 1e-15);
        assert!((relative_flatness(0.7, &scaled) - r).abs() < 1e-15);
        assert_eq!(relative_flatness(1.0, &[DVec3::ONE; 4]), f64::INFINITY);
    }

    #[test]
    fn hull_diameter_is_the_widest_pair() {
        let points = [DVec3::ZERO, DVec3::X, DVec3::new(0.0, 3.0, 4.0)];
        assert_eq!(hull_diameter(&points), DVec3::new(1.0, 3.0, 4.0).length());
        assert!(extraordinary_is_flat(&points, 5.2) && !extraordinary_is_flat(&points, 5.0));
    }

    #[test]
    fn tolerances_are_checked() {
        assert_eq!(Tolerance::Relative(0.01).absolute(10.0).ok(), Some(0.1));
        assert!(Tolerance::Absolute(0.0).absolute(1.0).is_err());
        assert!(Tolerance::Absolute(f64::NAN).absolute(1.0).is_err());
        assert!(Tolerance::Relative(-1.0).absolute(1.0).is_err());
        assert!(Tolerance::Relative(1e-300).absolute(1e-300).is_err());
    }
}
