//! Quartic triangular Bézier patches: the polynomial pieces of a Loop surface away from its
//! extraordinary vertices (the regular patch is a quartic box spline), in the form whose
//! control net bounds the surface (convex hull) and whose sub-triangles are quartics again.

use std::sync::OnceLock;

use glam::DVec3;

/// The number of control points of a quartic triangle.
pub const POINTS: usize = 15;

/// A quartic Bézier triangle on `u, v ≥ 0, u + v ≤ 1`: control point `(i, j)` (weight
/// `4!/(i! j! k!) uⁱ vʲ wᵏ`, `w = 1 − u − v`, `k = 4 − i − j`) at [`Quartic::index`]`(i, j)`,
/// its domain point `(i/4, j/4)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quartic {
    /// The 15 control points, row `j` after row `j − 1`, `i` ascending in a row.
    pub net: [DVec3; POINTS],
}

/// `n!` for `n ≤ 4`.
const FACTORIAL: [f64; 5] = [1.0, 1.0, 2.0, 6.0, 24.0];

/// The indices `(i, j)`, `i + j ≤ n`, of a triangle's Bézier net of degree `n`, in [`Quartic`]'s
/// order for that degree (row `j` after row `j − 1`, `i` ascending in a row).
pub(crate) fn domain_points(n: usize) -> impl Iterator<Item = (usize, usize)> + Clone {
    (0..=n).flat_map(move |j| (0..=n - j).map(move |i| (i, j)))
}

/// A quartic's array over its domain points: `f(i, j)` at [`Quartic::index`]`(i, j)`.
pub(crate) fn per_point(mut f: impl FnMut(usize, usize) -> DVec3) -> [DVec3; POINTS] {
    let mut out = [DVec3::ZERO; POINTS];
    for (o, (i, j)) in out.iter_mut().zip(domain_points(4)) {
        *o = f(i, j);
    }
    out
}

/// The Bernstein polynomials of degree `n ≤ 4` on the triangle at `(u, v)`, in
/// [`domain_points`]' order.
fn bernstein(n: usize, u: f64, v: f64) -> impl Iterator<Item = f64> {
    let w = 1.0 - u - v;
    domain_points(n).map(move |(i, j)| {
        let k = n - i - j;
        FACTORIAL[n] / (FACTORIAL[i] * FACTORIAL[j] * FACTORIAL[k])
            * u.powi(i as i32)
            * v.powi(j as i32)
            * w.powi(k as i32)
    })
}

/// The index of `(i, j)` in a net of degree `n`.
const fn index_of(n: usize, i: usize, j: usize) -> usize {
    (n + 1) * j - j * (j.saturating_sub(1)) / 2 + i
}

/// The inverse of the collocation matrix `(B_b(i/4, j/4))` over the domain points, computed once:
/// `inverse[b][a]` takes the value at domain point `a` to control point `b`.
pub(crate) fn collocation_inverse() -> &'static [[f64; POINTS]; POINTS] {
    static INVERSE: OnceLock<[[f64; POINTS]; POINTS]> = OnceLock::new();
    INVERSE.get_or_init(|| {
        let mut a = [[0.0; POINTS]; POINTS];
        for (row, (i, j)) in a.iter_mut().zip(domain_points(4)) {
            for (entry, b) in row.iter_mut().zip(bernstein(4, i as f64 / 4.0, j as f64 / 4.0)) {
                *entry = b;
            }
        }
        crate::flatness::gauss_jordan(a)
    })
}

impl Quartic {
    /// The index of control point `(i, j)`.
    pub const fn index(i: usize, j: usize) -> usize {
        index_of(4, i, j)
    }

    /// The quartic taking `values[index(i, j)]` at `(i/4, j/4)` (collocation: a quartic is
    /// determined by its values there).
    pub fn from_values(values: &[DVec3; POINTS]) -> Self {
        let inverse = collocation_inverse();
        Self { net: std::array::from_fn(|b| inverse[b].iter().zip(values).map(|(&w, &p)| w * p).sum()) }
    }

    /// The point at `(u, v)`.
    pub fn eval(&self, u: f64, v: f64) -> DVec3 {
        bernstein(4, u, v).zip(&self.net).map(|(b, &p)| b * p).sum()
    }

    /// The point and its derivatives along `u` and `v` at `(u, v)`.
    pub fn eval_with_derivatives(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let n = &self.net;
        let (mut du, mut dv) = (DVec3::ZERO, DVec3::ZERO);
        for ((i, j), b) in domain_points(3).zip(bernstein(3, u, v)) {
            let base = n[Self::index(i, j)];
            du += b * 4.0 * (n[Self::index(i + 1, j)] - base);
            dv += b * 4.0 * (n[Self::index(i, j + 1)] - base);
        }
        (self.eval(u, v), du, dv)
    }

    /// The sub-triangle whose parameters `(s, t)` are the parent's
    /// `((σ s + offset₀)/2, (σ t + offset₁)/2)`, `σ = −1` for the flipped middle one (the
    /// convention of `subdiv_schemes::ChildDomain`), as a quartic in its own parameters.
    pub fn child(&self, offset: [u8; 2], flipped: bool) -> Self {
        let sign = if flipped { -1.0 } else { 1.0 };
        Self::from_values(&per_point(|i, j| {
            let (s, t) = (i as f64 / 4.0, j as f64 / 4.0);
            self.eval((sign * s + f64::from(offset[0])) / 2.0, (sign * t + f64::from(offset[1])) / 2.0)
        }))
    }

    /// The control points along side `side` (0: `(0,0) → (1,0)`, 1: `(1,0) → (0,1)`, 2:
    /// `(0,1) → (0,0)`), in order: the side's quartic curve in Bézier form.
    pub fn side(&self, side: usize) -> [DVec3; 5] {
        std::array::from_fn(|m| {
            self.net[match side {
                0 => Self::index(m, 0),
                1 => Self::index(4 - m, m),
                _ => Self::index(0, 4 - m),
            }]
        })
    }

    /// Upper bounds of `‖S_uu‖`, `‖S_uv‖` and `‖S_vv‖` over the triangle: the largest norms of
    /// their Bernstein coefficients (each is a quadratic on the triangle whose coefficients are
    /// `12 ×` second differences of the net, and it lies in their convex hull).
    pub fn second_derivative_bounds(&self) -> [f64; 3] {
        let b = |i: usize, j: usize| self.net[Self::index(i, j)];
        let mut out = [0.0f64; 3];
        for j in 0..=2 {
            for i in 0..=2 - j {
                let uu = b(i + 2, j) - 2.0 * b(i + 1, j) + b(i, j);
                let uv = b(i + 1, j + 1) - b(i + 1, j) - b(i, j + 1) + b(i, j);
                let vv = b(i, j + 2) - 2.0 * b(i, j + 1) + b(i, j);
                for (o, d) in out.iter_mut().zip([uu, uv, vv]) {
                    *o = o.max(12.0 * d.length());
                }
            }
        }
        out
    }

    /// The largest absolute coordinate of the net: the scale of its floating-point rounding.
    pub fn magnitude(&self) -> f64 {
        self.net.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Quartic {
        Quartic {
            net: per_point(|i, j| {
                let (x, y) = (i as f64, j as f64);
                DVec3::new(x + 0.1 * y * y, y - 0.2 * x * y, (x * 1.3).sin() + (y * 0.7).cos())
            }),
        }
    }

    #[test]
    fn indices_follow_the_rows() {
        assert_eq!(
            (Quartic::index(0, 0), Quartic::index(4, 0), Quartic::index(0, 1), Quartic::index(0, 4)),
            (0, 4, 5, 14)
        );
        assert!(domain_points(4).enumerate().all(|(a, (i, j))| Quartic::index(i, j) == a));
    }

    #[test]
    fn values_round_trip_and_corners_interpolate() {
        let q = sample();
        let back = Quartic::from_values(&per_point(|i, j| q.eval(i as f64 / 4.0, j as f64 / 4.0)));
        for (a, b) in back.net.iter().zip(&q.net) {
            assert!((*a - *b).length() < 1e-12, "{a} {b}");
        }
        assert_eq!(q.eval(0.0, 0.0), q.net[Quartic::index(0, 0)]);
        assert!((q.eval(1.0, 0.0) - q.net[Quartic::index(4, 0)]).length() < 1e-14);
        assert!((q.eval(0.0, 1.0) - q.net[Quartic::index(0, 4)]).length() < 1e-14);
    }

    #[test]
    fn children_reproduce_the_patch() {
        let q = sample();
        let children = [([0, 0], false), ([1, 0], false), ([0, 1], false), ([1, 1], true)];
        for (offset, flipped) in children {
            let c = q.child(offset, flipped);
            let sign = if flipped { -1.0 } else { 1.0 };
            for (s, t) in [(0.0, 0.0), (0.3, 0.5), (1.0, 0.0), (0.2, 0.8)] {
                let parent = q.eval((sign * s + f64::from(offset[0])) / 2.0, (sign * t + f64::from(offset[1])) / 2.0);
                assert!((c.eval(s, t) - parent).length() < 1e-12);
            }
        }
    }

    #[test]
    fn derivatives_match_differences() {
        let q = sample();
        let (u, v, h) = (0.27, 0.41, 1e-6);
        let (_, du, dv) = q.eval_with_derivatives(u, v);
        let fu = (q.eval(u + h, v) - q.eval(u - h, v)) / (2.0 * h);
        let fv = (q.eval(u, v + h) - q.eval(u, v - h)) / (2.0 * h);
        assert!((du - fu).length() < 1e-7 && (dv - fv).length() < 1e-7, "{du} {fu} {dv} {fv}");
    }

    /// The bounds are never below second differences sampled on a fine grid, and reached at
    /// some sample for a quadratic (constant second derivatives).
    #[test]
    fn second_derivative_bounds_hold() {
        let q = sample();
        let bounds = q.second_derivative_bounds();
        let h = 1e-4;
        for j in 1..20 {
            for i in 1..20 - j {
                let (u, v) = (f64::from(i) / 20.0, f64::from(j) / 20.0);
                let uu = (q.eval(u + h, v) - 2.0 * q.eval(u, v) + q.eval(u - h, v)) / (h * h);
                let uv = (q.eval(u + h, v + h) - q.eval(u + h, v - h) - q.eval(u - h, v + h) + q.eval(u - h, v - h))
                    / (4.0 * h * h);
                let vv = (q.eval(u, v + h) - 2.0 * q.eval(u, v) + q.eval(u, v - h)) / (h * h);
                for (k, d) in [uu, uv, vv].iter().enumerate() {
                    assert!(d.length() <= bounds[k] * (1.0 + 1e-5) + 1e-6, "{k} at ({u}, {v})");
                }
            }
        }
        let quadratic = Quartic::from_values(&per_point(|i, j| {
            let (u, v) = (i as f64 / 4.0, j as f64 / 4.0);
            DVec3::new(u * u, 3.0 * u * v, -v * v)
        }));
        let [uu, uv, vv] = quadratic.second_derivative_bounds();
        assert!((uu - 2.0).abs() < 1e-9 && (uv - 3.0).abs() < 1e-9 && (vv - 2.0).abs() < 1e-9);
    }

    #[test]
    fn sides_are_the_boundary_curves() {
        let q = sample();
        let curve = |p: &[DVec3; 5], t: f64| -> DVec3 {
            let b = [1.0, 4.0, 6.0, 4.0, 1.0];
            (0..5).map(|m| b[m] * t.powi(m as i32) * (1.0 - t).powi(4 - m as i32) * p[m]).sum()
        };
        let t = 0.3;
        assert!((curve(&q.side(0), t) - q.eval(t, 0.0)).length() < 1e-13);
        assert!((curve(&q.side(1), t) - q.eval(1.0 - t, t)).length() < 1e-13);
        assert!((curve(&q.side(2), t) - q.eval(0.0, 1.0 - t)).length() < 1e-13);
    }
}
