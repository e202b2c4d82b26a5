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
//! # The node at the extraordinary corner
//! Every sub-patch matrix of Catmull-Clark has non-negative entries with rows summing to 1
//! (checked when the tessellator is built). So the limit surface over the node at the corner of
//! depth `d` is a limit of convex combinations of its control points `C_d = A^d C`: it lies in
//! their convex hull. Every vertex of a triangle of that leaf lies on the node's surface, hence
//! `T(p)` lies in the hull too, and `‖S(p) − T(p)‖ ≤ diam(C_d)`, the largest distance between two
//! control points ([`hull_diameter`]). This is the paper's `m_ε` argument (§4.1, `‖S − S(0,0)‖ <
//! ε/2` once `m ≥ m_ε`) with the convex hull giving the constant: `diam ≤ 2 max‖c_i − S(0, 0)‖`.
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

/// How often an undecided Bernstein bound is split before the node counts as not flat.
const REFINEMENTS: usize = 6;

/// The inverse collocation matrices of degrees 6 and 3.
type Inverses = ([[f64; 7]; 7], [[f64; 4]; 4]);

/// `(B^n_k(i/n))_{ik}⁻¹` for n = 6 and n = 3, computed once.
fn collocation_inverses() -> &'static Inverses {
    static INVERSES: OnceLock<Inverses> = OnceLock::new();
    INVERSES.get_or_init(|| (invert::<7>(), invert::<4>()))
}

/// The inverse of the Bernstein collocation matrix of degree `N − 1` at `i/(N − 1)`
/// (Gauss-Jordan with partial pivoting; the matrix is totally positive and well conditioned).
fn invert<const N: usize>() -> [[f64; N]; N] {
    let n = N - 1;
    let binomial = |k: usize| (0..k).fold(1.0, |acc, m| acc * (n - m) as f64 / (m + 1) as f64);
    let mut a = [[0.0; N]; N];
    let mut inv = [[0.0; N]; N];
    for (i, (row, inv_row)) in a.iter_mut().zip(&mut inv).enumerate() {
        let t = i as f64 / n as f64;
        for (k, entry) in row.iter_mut().enumerate() {
            *entry = binomial(k) * t.powi(k as i32) * (1.0 - t).powi((n - k) as i32);
        }
        inv_row[i] = 1.0;
    }
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

/// A polynomial of bidegree (6, 3) in tensor Bernstein form, `c[i][j]` for `s`-index `i`.
#[derive(Clone, Copy)]
struct Bernstein63 {
    c: [[DVec3; 4]; 7],
}

impl Bernstein63 {
    /// The largest Bernstein coefficient of `‖c‖ + χ·s` on an `s`-range `[s0, s1]`.
    fn upper(&self, chord: f64, s0: f64, s1: f64) -> f64 {
        (0..7)
            .flat_map(|i| (0..4).map(move |j| (i, j)))
            .map(|(i, j)| self.c[i][j].length() + chord * (s0 + (s1 - s0) * i as f64 / 6.0))
            .fold(0.0, f64::max)
    }

    /// The largest known value of `‖c‖ + χ·s`: the corner coefficients are values.
    fn lower(&self, chord: f64, s0: f64, s1: f64) -> f64 {
        [(0, 0, s0), (6, 0, s1), (0, 3, s0), (6, 3, s1)]
            .iter()
            .map(|&(i, j, s)| self.c[i][j].length() + chord * s)
            .fold(0.0, f64::max)
    }

    /// The two halves along `s` (`along_s`) or `t`, by de Casteljau at ½.
    fn split(&self, along_s: bool) -> (Self, Self) {
        let mut lo = *self;
        let mut hi = *self;
        if along_s {
            for j in 0..4 {
                let (l, h) = casteljau(&self.c.map(|row| row[j]));
                for i in 0..7 {
                    lo.c[i][j] = l[i];
                    hi.c[i][j] = h[i];
                }
            }
        } else {
            for i in 0..7 {
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

/// The cone error `S(c + s(q(t) − c)) − (1 − s)S(c) − s S(q(t))` of fan triangle `edge` of the
/// unit square, in Bernstein form.
fn cone_error(patch: &Bicubic, edge: usize) -> Bernstein63 {
    let (inv6, inv3) = collocation_inverses();
    let [ax, ay] = CORNERS[edge];
    let [bx, by] = CORNERS[(edge + 1) % 4];
    let centre = patch.eval(0.5, 0.5);
    let mut values = [[DVec3::ZERO; 4]; 7];
    for (j, t) in (0..4).map(|j| (j, j as f64 / 3.0)) {
        let (qx, qy) = (ax + t * (bx - ax), ay + t * (by - ay));
        let on_edge = patch.eval(qx, qy);
        for (i, row) in values.iter_mut().enumerate() {
            let s = i as f64 / 6.0;
            let p = patch.eval(0.5 + s * (qx - 0.5), 0.5 + s * (qy - 0.5));
            row[j] = p - (1.0 - s) * centre - s * on_edge;
        }
    }
    let mut c = [[DVec3::ZERO; 4]; 7];
    for i in 0..7 {
        for j in 0..4 {
            c[i][j] = (0..7)
                .flat_map(|a| (0..4).map(move |b| (a, b)))
                .map(|(a, b)| inv6[i][a] * inv3[j][b] * values[a][b])
                .sum();
        }
    }
    Bernstein63 { c }
}

/// The chord bound of edge `edge`: `max‖C''‖ / 8` for the edge's cubic `C`.
fn chord_bound(patch: &Bicubic, edge: usize) -> f64 {
    let n = &patch.net;
    let p = match edge {
        0 => n[0],
        1 => [n[0][3], n[1][3], n[2][3], n[3][3]],
        2 => n[3],
        _ => [n[0][0], n[1][0], n[2][0], n[3][0]],
    };
    let second = |a: DVec3, b: DVec3, c: DVec3| (6.0 * (a - 2.0 * b + c)).length();
    second(p[0], p[1], p[2]).max(second(p[1], p[2], p[3])) / 8.0
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
        cone: std::array::from_fn(|e| cone_error(patch, e).upper(0.0, 0.0, 1.0)),
        chord: std::array::from_fn(|e| chord_bound(patch, e)),
    }
}

/// Whether every fan triangle of a regular node, with any hanging points on its edges, is within
/// `epsilon` of the surface (cone + chord + slack, the cone bound refined by splitting its
/// Bernstein form while undecided).
pub fn regular_is_flat(patch: &Bicubic, epsilon: f64) -> bool {
    let slack = rounding_slack(patch.magnitude());
    let budget = epsilon - slack;
    budget >= 0.0 && (0..4).all(|edge| bounded_by(cone_error(patch, edge), chord_bound(patch, edge), budget))
}

/// Whether `‖poly‖ + chord·s` stays within `budget` on the whole box `[0, 1]²`.
fn bounded_by(poly: Bernstein63, chord: f64, budget: f64) -> bool {
    let mut stack = vec![(poly, 0.0, 1.0, 0)];
    while let Some((p, s0, s1, depth)) = stack.pop() {
        if p.upper(chord, s0, s1) <= budget {
            continue;
        }
        if p.lower(chord, s0, s1) > budget || depth == REFINEMENTS {
            return false;
        }
        // s carries degree 6, t degree 3: split s twice as often.
        let along_s = depth % 3 != 2;
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

    /// The largest parametric distance of the fan triangles (with a hanging point at every
    /// edge's `t`) to the patch, sampled densely.
    fn sampled_fan_error(patch: &Bicubic, hanging: f64) -> f64 {
        let c = [0.5, 0.5];
        let mut worst: f64 = 0.0;
        for edge in 0..4 {
            let [ax, ay] = CORNERS[edge];
            let [bx, by] = CORNERS[(edge + 1) % 4];
            let h = [ax + hanging * (bx - ax), ay + hanging * (by - ay)];
            for (a, b) in [([ax, ay], h), (h, [bx, by])] {
                let (sc, sa, sb) = (patch.eval(c[0], c[1]), patch.eval(a[0], a[1]), patch.eval(b[0], b[1]));
                for i in 0..=20 {
                    for j in 0..=(20 - i) {
                        let (la, lb) = (f64::from(i) / 20.0, f64::from(j) / 20.0);
                        let lc = 1.0 - la - lb;
                        let x = lc * c[0] + la * a[0] + lb * b[0];
                        let y = lc * c[1] + la * a[1] + lb * b[1];
                        worst = worst.max((patch.eval(x, y) - (lc * sc + la * sa + lb * sb)).length());
                    }
                }
            }
        }
        worst
    }

    #[test]
    fn collocation_inverses_invert() {
        let (inv6, _) = collocation_inverses();
        // The Bernstein coefficients of the constant 1 are all 1.
        for row in inv6 {
            assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-12);
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
