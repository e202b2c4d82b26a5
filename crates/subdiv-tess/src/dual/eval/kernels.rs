//! The evaluation kernels: the uniform cubic B-spline basis, the bicubic patch (pointwise and in lanes over a block), the typed faces' dense products, and the batched normalisation.

use super::*;

/// The lanes of the general route's dot products: each record's ids and weight rows are padded
/// to a multiple of this (the same sums on every target, so the same bits).
pub(super) const LANES: usize = 4;

/// `len` rounded up to a multiple of [`LANES`].
#[inline]
pub(super) fn padded(len: usize) -> usize {
    len.div_ceil(LANES) * LANES
}

/// The position and both derivatives `Σ w_k · points[ids[k]]` of a record with its own weights
/// (`ids` and each of the three weight rows [`padded`]): [`LANES`] partial sums per coordinate,
/// added pairwise at the end. In f64, so exact to rounding.
#[inline(always)]
pub(super) fn dot3(points: &[DVec3], ids: &[u32], w: &[f64]) -> [DVec3; 3] {
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

/// The uniform cubic B-spline basis and its derivative at the dual points `(i+½)/n`.
#[derive(Clone, Debug)]
pub(super) struct RateBasis {
    pub(super) b: Vec<[f64; 4]>,
    pub(super) d: Vec<[f64; 4]>,
    /// The same by groups of [`LANES`] points: per group, each basis function's values at the
    /// group's points (zeros past the last point), then each derivative's.
    pub(super) lanes: Vec<[[f64; LANES]; 8]>,
}

impl RateBasis {
    pub(super) fn new(n: u32) -> Self {
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
pub(crate) fn basis(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    let (t2, t3) = (t * t, t * t * t);
    [s * s * s / 6.0, (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0, (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, t3 / 6.0]
}

/// The derivative of [`basis`].
#[inline(always)]
pub(crate) fn derivative(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [-0.5 * s * s, (3.0 * t * t - 4.0 * t) * 0.5, (-3.0 * t * t + 2.0 * t + 1.0) * 0.5, 0.5 * t * t]
}

/// The bicubic patch with control points `cv` (face frame) at `(u, v)`: position, `∂/∂u`,
/// `∂/∂v`.
#[inline(always)]
pub(super) fn bicubic(cv: &[u32; 16], cage: &[DVec3], u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    bicubic_at(|k| cage[cv[k] as usize], u, v)
}

/// The bicubic patch with control point `k = j · 4 + i` at `(i − 1, j − 1)` given by
/// `point(k)`, at `(u, v)`: position, `∂/∂u`, `∂/∂v`. The one bicubic sum: the blocks and
/// the patch grids run the same [`columns`] and [`combine`] (a row's columns shared by its
/// points), so every route gives these bits; the GPU's shader is checked against it by the
/// GPU tests (positions within 1e-7 of the bounding box).
#[inline(always)]
pub(crate) fn bicubic_at(point: impl Fn(usize) -> DVec3, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let c: [DVec3; 16] = std::array::from_fn(point);
    let (bu, du) = (basis(u), derivative(u));
    let (col, dcol) = (columns(&c, basis(v)), columns(&c, derivative(v)));
    (combine(bu, &col), combine(du, &col), combine(bu, &dcol))
}

/// The 4 column combinations `Σ_j w[j] · c[4j + i]` of a patch's control points (`c[j · 4 + i]`
/// at `(i − 1, j − 1)`) for one row's `v` weights.
#[inline(always)]
pub(super) fn columns(c: &[DVec3; 16], w: [f64; 4]) -> [DVec3; 4] {
    std::array::from_fn(|i| w[0] * c[i] + w[1] * c[4 + i] + w[2] * c[8 + i] + w[3] * c[12 + i])
}

/// `Σ_i w[i] · col[i]`: a point of a row from its [`columns`] and its `u` weights.
#[inline(always)]
pub(super) fn combine(w: [f64; 4], col: &[DVec3; 4]) -> DVec3 {
    w[0] * col[0] + w[1] * col[1] + w[2] * col[2] + w[3] * col[3]
}

/// A unit normal from two tangents (zero where they are parallel).
#[cfg(test)]
pub(super) fn normal(du: DVec3, dv: DVec3) -> DVec3 {
    crate::unit_normal(du.cross(dv))
}

/// The dual grid of a bicubic face, row by row, into `out` (point `k = j · n + i` at `k`).
/// Per row, the 4 column combinations of the control points (and of their `v` derivative),
/// then [`LANES`] points of the row at a time, coordinate by coordinate in lanes: the same
/// operations as [`bicubic_at`]'s sums, so the same bits.
#[inline(always)]
pub(super) fn grid_block<S: Sink>(
    cv: &[u32; 16],
    cage: &[DVec3],
    basis: &RateBasis,
    out: &mut S,
    pending: &mut Pending,
) {
    let c: [DVec3; 16] = std::array::from_fn(|k| cage[cv[k] as usize]);
    let n = basis.b.len();
    for j in 0..n {
        let (bv, dv) = (basis.b[j], basis.d[j]);
        let (col, dcol) = (columns(&c, bv), columns(&c, dv));
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
pub(super) const GROUPS: usize = 8;

/// Groups of [`LANES`] points waiting for their normals: per group its positions and its
/// tangents' cross products (by coordinate, in lanes), and its first vertex and point count.
/// Normalising [`GROUPS`] groups at once lets their square roots and divisions overlap, where
/// one group at a time waits for each before its points can be written.
pub(super) struct Pending {
    pub(super) p: [[[f64; LANES]; 3]; GROUPS],
    pub(super) c: [[[f64; LANES]; 3]; GROUPS],
    pub(super) at: [(usize, usize); GROUPS],
    pub(super) len: usize,
}

impl Pending {
    pub(super) fn new() -> Self {
        Self { p: [[[0.0; LANES]; 3]; GROUPS], c: [[[0.0; LANES]; 3]; GROUPS], at: [(0, 0); GROUPS], len: 0 }
    }

    /// Adds `count` points from vertex `first` from their lanes `[px, py, pz, ax, ay, az, bx, by,
    /// bz]` (position, and the tangents `a = ∂/∂u`, `b = ∂/∂v`), and writes the groups into
    /// `out` when there are [`GROUPS`] of them.
    #[inline(always)]
    pub(super) fn push<S: Sink>(&mut self, acc: &[[f64; LANES]; 9], first: usize, count: usize, out: &mut S) {
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
    pub(super) fn flush<S: Sink>(&mut self, out: &mut S) {
        // In place: the cross products become the normals.
        for [x, y, z] in self.c.iter_mut().take(self.len) {
            for ((x, y), z) in x.iter_mut().zip(y.iter_mut()).zip(z.iter_mut()) {
                let rcp = 1.0 / ((*x * *x) + (*y * *y) + (*z * *z)).sqrt();
                (*x, *y, *z) = if rcp.is_finite() && rcp > 0.0 {
                    (*x * rcp, *y * rcp, *z * rcp)
                } else {
                    // |c|² out of range (a tiny or huge model), or zero: the scaled path.
                    crate::unit_normal(DVec3::new(*x, *y, *z)).into()
                };
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

/// Point `l` of lanes by coordinate.
#[inline(always)]
pub(super) fn lane(x: &[[f64; LANES]; 3], l: usize) -> DVec3 {
    DVec3::new(x[0][l], x[1][l], x[2][l])
}

/// A typed face's cell points (`out.len()` of them) from its template and its cage points
/// `ids`: per group of [`LANES`] points, nine sums per lane (position, `∂/∂u`, `∂/∂v`, by
/// coordinate) over the cage points in order, each cage point read once per group, then into
/// `out` through [`Pending`]. The sums are fused multiply-adds (`mul_add`, exact on every
/// target: the same bits, one rounding per term, half the operations of a multiply and an
/// add); the lanes are plain arrays; the normals are glam's
/// `du.cross(dv).normalize_or_zero()`, operation for operation.
#[inline(always)]
pub(super) fn typed_block<S: Sink>(t: &Template, ids: &[u32], cage: &[DVec3], out: &mut S, scratch: &mut Scratch) {
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
