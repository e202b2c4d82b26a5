//! Measuring a tessellation against the exact limit surface: the parametric distance that
//! [`flatness`](crate::flatness) bounds, sampled with [`LimitEvaluator`] (an independent route:
//! exact stencils, no Bézier pieces) on every face's `Bfr` grid.

use glam::DVec3;
use hashbrown::HashMap;
use subdiv_mesh::Mesh;
use subdiv_stencil::LimitEvaluator;

use crate::{TessError, TessMesh};

/// Exact limit points on every face's `--grid n` (`FaceDomain::grid`), kept to measure several
/// tessellations of one mesh.
#[derive(Clone, Debug)]
pub struct LimitSamples {
    /// Per face: `(u, v, position)`.
    faces: Vec<Vec<(f64, f64, DVec3)>>,
    /// The bucket size in `Bfr` units (the grid spacing of N-gon sub-faces, `1 / 2n`).
    cell: f64,
}

/// The result of [`LimitSamples::measure`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// The largest `‖S(p) − T(p)‖` over samples `p` and the triangles containing them.
    pub worst: f64,
    /// Samples checked.
    pub samples: usize,
    /// Samples that no triangle of their face contains (0 for a tessellation that covers
    /// every face's domain).
    pub uncovered: usize,
}

impl LimitSamples {
    /// Evaluates `evaluator` on every face of `mesh` at the grid `(i/n, j/n)` (per sub-face for
    /// N-gons).
    ///
    /// # Errors
    /// As [`LimitEvaluator::grid`].
    pub fn new(evaluator: &LimitEvaluator, mesh: &Mesh, n: u32) -> Result<Self, TessError> {
        let faces = mesh
            .face_ids()
            .map(|f| Ok(evaluator.grid(f, n)?.into_iter().map(|(g, p)| (g.u, g.v, p.position)).collect()))
            .collect::<Result<_, TessError>>()?;
        Ok(Self { faces, cell: 0.5 / f64::from(n) })
    }

    /// Samples computed elsewhere (another evaluator of the same parameterization): per face,
    /// `(u, v, position)` on the `--grid n` of that face.
    pub fn from_samples(faces: Vec<Vec<(f64, f64, DVec3)>>, n: u32) -> Self {
        Self { faces, cell: 0.5 / f64::from(n.max(1)) }
    }

    /// The parametric distance of `tess`'s triangles to the samples: each sample against every
    /// triangle of its face whose parameter triangle contains it.
    pub fn measure(&self, tess: &TessMesh) -> Measured {
        let mut buckets: Vec<HashMap<(i64, i64), Vec<usize>>> = vec![HashMap::new(); self.faces.len()];
        for (f, samples) in self.faces.iter().enumerate() {
            for (k, &(u, v, _)) in samples.iter().enumerate() {
                buckets[f].entry(((u / self.cell).round() as i64, (v / self.cell).round() as i64)).or_default().push(k);
            }
        }
        let mut covered: Vec<Vec<bool>> = self.faces.iter().map(|s| vec![false; s.len()]).collect();
        let mut worst: f64 = 0.0;
        for (t, tri) in tess.triangles.iter().enumerate() {
            let f = tess.triangle_faces[t].index();
            let [a, b, c] = tess.triangle_parameters[t];
            let lo = [a[0].min(b[0]).min(c[0]), a[1].min(b[1]).min(c[1])];
            let hi = [a[0].max(b[0]).max(c[0]), a[1].max(b[1]).max(c[1])];
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            if det == 0.0 {
                continue;
            }
            let positions = tri.map(|i| tess.positions[i as usize]);
            for i in (lo[0] / self.cell).floor() as i64..=(hi[0] / self.cell).ceil() as i64 {
                for j in (lo[1] / self.cell).floor() as i64..=(hi[1] / self.cell).ceil() as i64 {
                    let Some(list) = buckets[f].get(&(i, j)) else { continue };
                    for &k in list {
                        let (u, v, s) = self.faces[f][k];
                        let l1 = ((u - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (v - a[1])) / det;
                        let l2 = ((b[0] - a[0]) * (v - a[1]) - (u - a[0]) * (b[1] - a[1])) / det;
                        let l0 = 1.0 - l1 - l2;
                        if l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12 {
                            continue;
                        }
                        covered[f][k] = true;
                        let interpolant = l0 * positions[0] + l1 * positions[1] + l2 * positions[2];
                        worst = worst.max((s - interpolant).length());
                    }
                }
            }
        }
        let samples = self.faces.iter().map(Vec::len).sum();
        let uncovered = covered.iter().flatten().filter(|&&c| !c).count();
        Measured { worst, samples, uncovered }
    }
}

/// Closest point of triangle `abc` to `p` (Ericson, Real-Time Collision Detection §5.1.5).
fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// The distance from points to a tessellation's triangles, for points within `reach` of it:
/// triangles bucketed by their bounding boxes grown by `reach` on a uniform grid, so a point's
/// cell lists every triangle within `reach` of it. It measures the one-sided distance from the
/// surface to the output that tolerances promise (the parametric measure of [`LimitSamples`]
/// needs each triangle in one face, which the dual tessellator's strips and rings are not).
///
/// ```
/// use glam::DVec3;
/// use subdiv_tess::TessMesh;
/// use subdiv_tess::check::MeshDistance;
///
/// let mesh = TessMesh {
///     positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
///     triangles: vec![[0, 1, 2]],
///     ..TessMesh::default()
/// };
/// let d = MeshDistance::new(&mesh, 1.0);
/// assert_eq!(d.distance(&mesh, DVec3::new(0.25, 0.25, 0.5)), 0.5);
/// assert!(d.distance(&mesh, DVec3::new(0.0, 0.0, 9.0)) >= 1.0);
/// ```
#[derive(Clone, Debug)]
pub struct MeshDistance {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    cells: Vec<Vec<u32>>,
}

impl MeshDistance {
    /// Buckets `out`'s triangles for points within `reach` of it.
    pub fn new(out: &TessMesh, reach: f64) -> Self {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in &out.positions {
            (lo, hi) = (lo.min(*p), hi.max(*p));
        }
        (lo, hi) = (lo - DVec3::splat(2.0 * reach), hi + DVec3::splat(2.0 * reach));
        let cell = ((hi - lo).max_element() / 48.0).max(reach);
        let dims = ((hi - lo) / cell).ceil().to_array().map(|x| (x as usize).max(1));
        let mut cells = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let index = |p: DVec3| -> [usize; 3] {
            let q = ((p - lo) / cell).floor().to_array();
            std::array::from_fn(|i| (q[i].max(0.0) as usize).min(dims[i] - 1))
        };
        for (k, t) in out.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| out.positions[v as usize]);
            let (tlo, thi) = (a.min(b).min(c) - DVec3::splat(reach), a.max(b).max(c) + DVec3::splat(reach));
            let (i0, i1) = (index(tlo), index(thi));
            for x in i0[0]..=i1[0] {
                for y in i0[1]..=i1[1] {
                    for z in i0[2]..=i1[2] {
                        cells[(z * dims[1] + y) * dims[0] + x].push(k as u32);
                    }
                }
            }
        }
        Self { lo, cell, dims, cells }
    }

    /// The distance from `p` to the nearest triangle of `out` (the mesh it was built on) when
    /// one is within `reach`; otherwise a value ≥ `reach` (infinity when no triangle is near).
    pub fn distance(&self, out: &TessMesh, p: DVec3) -> f64 {
        let q = ((p - self.lo) / self.cell).floor().to_array();
        let [x, y, z]: [usize; 3] = std::array::from_fn(|i| (q[i].max(0.0) as usize).min(self.dims[i] - 1));
        self.cells[(z * self.dims[1] + y) * self.dims[0] + x]
            .iter()
            .map(|&k| {
                let [a, b, c] = out.triangles[k as usize].map(|v| out.positions[v as usize]);
                (closest_on_triangle(p, a, b, c) - p).length()
            })
            .fold(f64::INFINITY, f64::min)
    }
}
