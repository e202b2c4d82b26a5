//! Scheme analysis around an interior extraordinary vertex: the local subdivision matrix,
//! derived by running the refinement engine on a canonical mesh, and its spectrum.
//!
//! The matrix is never typed in. For valence `k` we build a small mesh whose vertex 0 has
//! valence `k` (Catmull-Clark and bilinear: `k` quads around it; Loop: `k` triangles), refine it
//! once with [`Refiner`], and read the stencils of the refined one-ring of vertex 0 over the
//! parent one-ring. The one-ring is ordered centre first, then per sector its edge neighbour
//! (and, for quads, its face-diagonal neighbour), counter-clockwise.

use subdiv_mesh::{DVec3, Mesh, PolygonSoup, VertexId, shapes};

use crate::{RefineOptions, Refiner, Scheme, SchemeError};

/// The square subdivision matrix of the one-ring of an interior vertex of valence `k`: row `r`
/// holds the weights of refined one-ring vertex `r` over the parent one-ring.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalMatrix {
    size: usize,
    /// Row-major.
    entries: Vec<f64>,
}

impl LocalMatrix {
    /// The one-ring matrix of `scheme` at an interior vertex of valence `valence` (at least 3).
    ///
    /// ```
    /// use subdiv_schemes::{LocalMatrix, Scheme};
    ///
    /// let m = LocalMatrix::one_ring(Scheme::CatmullClark, 5)?;
    /// assert_eq!(m.size(), 11);
    /// // The centre's row is the smooth vertex rule: (k - 2) / k on itself, plus 1 / (4k) from
    /// // the k face points around it.
    /// assert!((m.get(0, 0) - (3.0 / 5.0 + 1.0 / 20.0)).abs() < 1e-15);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// [`SchemeError::ValenceNotSupported`] below valence 3.
    pub fn one_ring(scheme: Scheme, valence: usize) -> Result<Self, SchemeError> {
        if valence < 3 {
            return Err(SchemeError::ValenceNotSupported { scheme, valence });
        }
        let k = valence;
        let quads = scheme.splits_into_quads();
        let mesh = if quads { Mesh::build(shapes::pole(k)) } else { Mesh::build(triangle_fan(k)) }
            .map_err(|e| SchemeError::Internal(e.to_string()))?;
        let refiner = Refiner::new(&mesh, scheme, 1, &RefineOptions::DEFAULT)?;
        let child = refiner.mesh();
        let stencils = &refiner.levels()[0];
        // The one-ring in fan order: after the centre, each outgoing spoke's far end and, for
        // quads, the vertex across the face that follows it.
        let centre = VertexId::new(0);
        let ring = |m: &Mesh, v: VertexId| -> Vec<VertexId> {
            let mut ring = vec![v];
            for h in m.outgoing(v) {
                ring.push(m.dest(h));
                if quads {
                    ring.push(m.dest(m.next(h)));
                }
            }
            ring
        };
        let parent_ring = ring(&mesh, centre);
        let child_ring = ring(child, centre);
        let size = parent_ring.len();
        let mut column = vec![usize::MAX; mesh.vertex_count()];
        for (c, v) in parent_ring.iter().enumerate() {
            column[v.index()] = c;
        }
        let mut entries = vec![0.0; size * size];
        for (r, v) in child_ring.iter().enumerate() {
            for (parent, weight) in stencils.row(v.index()) {
                match column.get(parent) {
                    Some(&c) if c != usize::MAX => entries[r * size + c] += weight,
                    // The one-ring is closed under refinement for every scheme here; a weight
                    // outside it means the canonical mesh or the engine is wrong.
                    _ => {
                        return Err(SchemeError::Internal(format!(
                            "{scheme} at valence {k}: refined vertex {v} has weight on vertex {parent}, outside the one-ring"
                        )));
                    }
                }
            }
        }
        Ok(Self { size, entries })
    }

    /// Rows (and columns).
    pub fn size(&self) -> usize {
        self.size
    }

    /// The weight of parent one-ring vertex `column` in refined one-ring vertex `row`.
    pub fn get(&self, row: usize, column: usize) -> f64 {
        self.entries[row * self.size + column]
    }

    /// The eigenvalues, largest modulus first (ties: larger real part first), as `(re, im)`.
    ///
    /// # Errors
    /// [`SchemeError::Eigen`] when the eigen solver does not converge.
    pub fn eigenvalues(&self) -> Result<Vec<(f64, f64)>, SchemeError> {
        let matrix = faer::Mat::<f64>::from_fn(self.size, self.size, |i, j| self.get(i, j));
        let values = matrix.eigenvalues().map_err(|e| SchemeError::Eigen(format!("{e:?}")))?;
        let mut values: Vec<(f64, f64)> = values.iter().map(|z| (z.re, z.im)).collect();
        values.sort_by(|a, b| {
            let (ma, mb) = (a.0.hypot(a.1), b.0.hypot(b.1));
            mb.total_cmp(&ma).then(b.0.total_cmp(&a.0))
        });
        Ok(values)
    }
}

/// `k` triangles around vertex 0, the ring vertices on the unit circle.
fn triangle_fan(k: usize) -> PolygonSoup {
    let mut soup = PolygonSoup::new();
    soup.push_vertex(DVec3::Z * 0.25);
    for i in 0..k {
        let angle = std::f64::consts::TAU * i as f64 / k as f64;
        soup.push_vertex(DVec3::new(angle.cos(), angle.sin(), 0.0));
    }
    for i in 0..k as u32 {
        soup.push_face([0, 1 + i, 1 + (i + 1) % k as u32].map(VertexId::new));
    }
    soup
}

/// The spectral part of Reif's C1 conditions at one valence.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// Eigenvalues of the one-ring matrix, largest modulus first, as `(re, im)`.
    pub eigenvalues: Vec<(f64, f64)>,
    /// λ0 = 1 and it is simple.
    pub unit_dominant_simple: bool,
    /// λ1 = λ2, real and positive (the subdominant pair).
    pub subdominant_real_double: bool,
    /// |λ3| < λ1.
    pub subdominant_strict: bool,
}

impl Spectrum {
    /// The spectrum of `scheme`'s one-ring matrix at valence `valence`.
    ///
    /// # Errors
    /// As [`LocalMatrix::one_ring`] and [`LocalMatrix::eigenvalues`].
    pub fn of(scheme: Scheme, valence: usize) -> Result<Self, SchemeError> {
        let eigenvalues = LocalMatrix::one_ring(scheme, valence)?.eigenvalues()?;
        const TOLERANCE: f64 = 1e-10;
        let modulus = |i: usize| eigenvalues.get(i).map_or(0.0, |z: &(f64, f64)| z.0.hypot(z.1));
        let unit_dominant_simple =
            eigenvalues.first().is_some_and(|z| (z.0 - 1.0).abs() < TOLERANCE && z.1.abs() < TOLERANCE)
                && modulus(1) < 1.0 - TOLERANCE;
        let subdominant_real_double = eigenvalues.len() > 2
            && eigenvalues[1].1.abs() < TOLERANCE
            && eigenvalues[2].1.abs() < TOLERANCE
            && (eigenvalues[1].0 - eigenvalues[2].0).abs() < TOLERANCE
            && eigenvalues[1].0 > 0.0;
        let subdominant_strict = modulus(3) < modulus(1) - TOLERANCE;
        Ok(Self { eigenvalues, unit_dominant_simple, subdominant_real_double, subdominant_strict })
    }

    /// The subdominant eigenvalue λ1 (the modulus of the second eigenvalue).
    pub fn subdominant(&self) -> f64 {
        self.eigenvalues.get(1).map_or(0.0, |z| z.0.hypot(z.1))
    }
}
