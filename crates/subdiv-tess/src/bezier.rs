//! Bicubic Bézier patches: the polynomial pieces of a Catmull-Clark surface away from its
//! extraordinary vertices, in the form whose control net bounds the surface (convex hull) and
//! splits exactly (de Casteljau at ½).

use glam::DVec3;

/// A bicubic Bézier patch on `[0, 1]²`: `net[j][i]` is the control point of `x`-degree `i` and
/// `y`-degree `j` (rows run along `x`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bicubic {
    /// The 4 × 4 control net, `net[j][i]`.
    pub net: [[DVec3; 4]; 4],
}

/// The uniform cubic B-spline segment's control points in Bézier form: row `k` gives Bézier
/// point `k` from the B-spline points `P₀..P₃`.
const BSPLINE_TO_BEZIER: [[f64; 4]; 4] = [
    [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0, 0.0],
    [0.0, 4.0 / 6.0, 2.0 / 6.0, 0.0],
    [0.0, 2.0 / 6.0, 4.0 / 6.0, 0.0],
    [0.0, 1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0],
];

/// The cubic Bernstein polynomials at `t`.
pub(crate) fn bernstein3(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

/// The quadratic Bernstein polynomials at `t`.
fn bernstein2(t: f64) -> [f64; 3] {
    let s = 1.0 - t;
    [s * s, 2.0 * t * s, t * t]
}

/// One half of a cubic by de Casteljau at ½: `upper` picks `[½, 1]`.
fn half(p: [DVec3; 4], upper: bool) -> [DVec3; 4] {
    let a = [(p[0] + p[1]) * 0.5, (p[1] + p[2]) * 0.5, (p[2] + p[3]) * 0.5];
    let b = [(a[0] + a[1]) * 0.5, (a[1] + a[2]) * 0.5];
    let m = (b[0] + b[1]) * 0.5;
    if upper { [m, b[1], a[2], p[3]] } else { [p[0], a[0], b[0], m] }
}

impl Bicubic {
    /// The Bézier form of the uniform bicubic B-spline patch with control points
    /// `grid[j][i]` at integer parameters `(i − 1, j − 1)` (the patch is the unit square
    /// between the four middle points).
    pub fn from_bspline(grid: &[[DVec3; 4]; 4]) -> Self {
        let mut rows = [[DVec3::ZERO; 4]; 4];
        for j in 0..4 {
            for (k, weights) in BSPLINE_TO_BEZIER.iter().enumerate() {
                rows[j][k] = (0..4).map(|i| weights[i] * grid[j][i]).sum();
            }
        }
        let mut net = [[DVec3::ZERO; 4]; 4];
        for i in 0..4 {
            for (k, weights) in BSPLINE_TO_BEZIER.iter().enumerate() {
                net[k][i] = (0..4).map(|j| weights[j] * rows[j][i]).sum();
            }
        }
        Self { net }
    }

    /// The point at `(x, y)`.
    pub fn eval(&self, x: f64, y: f64) -> DVec3 {
        let (bx, by) = (bernstein3(x), bernstein3(y));
        (0..4).flat_map(|j| (0..4).map(move |i| (i, j))).map(|(i, j)| bx[i] * by[j] * self.net[j][i]).sum()
    }

    /// The point and the derivatives `∂/∂x`, `∂/∂y` at `(x, y)`.
    pub fn eval_with_derivatives(&self, x: f64, y: f64) -> (DVec3, DVec3, DVec3) {
        let (bx, by) = (bernstein3(x), bernstein3(y));
        let (dx2, dy2) = (bernstein2(x), bernstein2(y));
        let n = &self.net;
        let mut dx = DVec3::ZERO;
        let mut dy = DVec3::ZERO;
        for j in 0..4 {
            for i in 0..3 {
                dx += 3.0 * dx2[i] * by[j] * (n[j][i + 1] - n[j][i]);
            }
        }
        for j in 0..3 {
            for i in 0..4 {
                dy += 3.0 * bx[i] * dy2[j] * (n[j + 1][i] - n[j][i]);
            }
        }
        (self.eval(x, y), dx, dy)
    }

    /// The quarter `[qx/2, (qx+1)/2] × [qy/2, (qy+1)/2]`, reparameterized to `[0, 1]²`.
    pub fn quarter(&self, qx: usize, qy: usize) -> Self {
        let mut net = self.net;
        for row in &mut net {
            *row = half(*row, qx == 1);
        }
        for i in 0..4 {
            let column = half([net[0][i], net[1][i], net[2][i], net[3][i]], qy == 1);
            for (row, &p) in net.iter_mut().zip(&column) {
                row[i] = p;
            }
        }
        Self { net }
    }

    /// The four corner points `S(0,0), S(1,0), S(1,1), S(0,1)`.
    pub fn corners(&self) -> [DVec3; 4] {
        [self.net[0][0], self.net[0][3], self.net[3][3], self.net[3][0]]
    }

    /// Upper bounds of `‖∂²S/∂x²‖`, `‖∂²S/∂x∂y‖` and `‖∂²S/∂y²‖` over the patch: the largest
    /// norms of their Bernstein coefficients (each second derivative is a tensor Bernstein
    /// polynomial — degrees (1, 3), (2, 2), (3, 1) — whose coefficients are scaled second
    /// differences of the net, and it lies in their convex hull).
    pub fn second_derivative_bounds(&self) -> [f64; 3] {
        let n = &self.net;
        let mut out = [0.0f64; 3];
        for j in 0..4 {
            for i in 0..4 {
                if i < 2 {
                    out[0] = out[0].max((6.0 * (n[j][i + 2] - 2.0 * n[j][i + 1] + n[j][i])).length());
                }
                if i < 3 && j < 3 {
                    out[1] = out[1].max((9.0 * (n[j + 1][i + 1] - n[j + 1][i] - n[j][i + 1] + n[j][i])).length());
                }
                if j < 2 {
                    out[2] = out[2].max((6.0 * (n[j + 2][i] - 2.0 * n[j + 1][i] + n[j][i])).length());
                }
            }
        }
        out
    }

    /// The largest absolute coordinate of the net: the scale of its floating-point rounding.
    pub fn magnitude(&self) -> f64 {
        self.net.iter().flatten().map(|p| p.abs().max_element()).fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bounds are never below second differences sampled on a fine grid.
    #[test]
    fn second_derivative_bounds_hold() {
        let b = sample();
        let bounds = b.second_derivative_bounds();
        let h = 1e-4;
        for j in 1..20 {
            for i in 1..20 {
                let (x, y) = (f64::from(i) / 20.0, f64::from(j) / 20.0);
                let xx = (b.eval(x + h, y) - 2.0 * b.eval(x, y) + b.eval(x - h, y)) / (h * h);
                let xy = (b.eval(x + h, y + h) - b.eval(x + h, y - h) - b.eval(x - h, y + h) + b.eval(x - h, y - h))
                    / (4.0 * h * h);
                let yy = (b.eval(x, y + h) - 2.0 * b.eval(x, y) + b.eval(x, y - h)) / (h * h);
                for (k, d) in [xx, xy, yy].iter().enumerate() {
                    assert!(
                        d.length() <= bounds[k] * (1.0 + 1e-5) + 1e-6,
                        "{k} at ({x}, {y}): {} > {}",
                        d.length(),
                        bounds[k]
                    );
                }
            }
        }
    }

    fn sample() -> Bicubic {
        let mut net = [[DVec3::ZERO; 4]; 4];
        for (j, row) in net.iter_mut().enumerate() {
            for (i, p) in row.iter_mut().enumerate() {
                let (x, y) = (i as f64, j as f64);
                *p = DVec3::new(x + 0.1 * y * y, y - 0.2 * x * y, (x * 1.3).sin() + (y * 0.7).cos());
            }
        }
        Bicubic { net }
    }

    #[test]
    fn quarters_reproduce_the_patch() {
        let b = sample();
        for (qx, qy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let q = b.quarter(qx, qy);
            for (x, y) in [(0.0, 0.0), (0.3, 0.7), (1.0, 0.25), (0.5, 1.0)] {
                let parent = b.eval((qx as f64 + x) / 2.0, (qy as f64 + y) / 2.0);
                assert!((q.eval(x, y) - parent).length() < 1e-14);
            }
        }
    }

    #[test]
    fn derivatives_match_differences() {
        let b = sample();
        let (x, y, h) = (0.37, 0.61, 1e-6);
        let (_, dx, dy) = b.eval_with_derivatives(x, y);
        let fx = (b.eval(x + h, y) - b.eval(x - h, y)) / (2.0 * h);
        let fy = (b.eval(x, y + h) - b.eval(x, y - h)) / (2.0 * h);
        assert!((dx - fx).length() < 1e-8 && (dy - fy).length() < 1e-8);
    }

    #[test]
    fn bspline_of_a_linear_function_is_linear() {
        // B-splines reproduce linear functions of the knot grid: the patch is (u, v, 0).
        let mut grid = [[DVec3::ZERO; 4]; 4];
        for (j, row) in grid.iter_mut().enumerate() {
            for (i, p) in row.iter_mut().enumerate() {
                *p = DVec3::new(i as f64 - 1.0, j as f64 - 1.0, 0.0);
            }
        }
        let b = Bicubic::from_bspline(&grid);
        assert!((b.eval(0.25, 0.5) - DVec3::new(0.25, 0.5, 0.0)).length() < 1e-15);
        assert!((b.corners()[2] - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-15);
    }
}
