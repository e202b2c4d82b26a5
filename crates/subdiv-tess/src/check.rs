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
