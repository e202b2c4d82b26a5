//! Scheme analysis around an extraordinary vertex (or, for dual schemes, the extraordinary face
//! a vertex becomes): the local subdivision matrix, derived by running the refinement engine on
//! a canonical mesh, its spectrum, and Reif's C1 test with the characteristic map checked
//! numerically.
//!
//! The matrices are never typed in. For valence `k` the canonical mesh is a *pillow*: `k`
//! sectors of a regular grid around vertex 0 (quads, or triangles for triangle schemes), glued
//! along their rim to a mirrored copy so that the mesh is closed. Dual schemes first refine it
//! once, which turns vertex 0 into a `k`-sided face. The engine refines the mesh
//! [`Scheme::steps_per_cycle`] times and the stencils of the refined neighbourhood over the
//! parent neighbourhood are the matrix. The neighbourhood is the smallest ring of faces around
//! the centre that refinement maps into itself; its vertices are ordered by ring, then by angle
//! from the direction of the first spoke (both meshes are `k`-fold symmetric, so equal order
//! means equal place).

use faer::Mat;
use faer::linalg::solvers::Solve;
use subdiv_mesh::{DVec3, FaceId, Mesh, VertexId};

use crate::{RefineOptions, Refiner, Scheme, SchemeError, Split};

/// The largest neighbourhood radius (in rings of faces) the analysis tries before it gives up
/// on finding one that refinement maps into itself.
const MAX_RADIUS: usize = 4;

/// How many rings past the invariant neighbourhood the characteristic map's eigenvectors are
/// extended, so that a few refinements leave a dense ring whose every vertex is known.
const EXTENSION: usize = 3;

/// The square subdivision matrix of the smallest closed neighbourhood of an extraordinary
/// vertex: row `r` holds the weights of refined vertex `r` over the parent vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalMatrix {
    size: usize,
    radius: usize,
    /// Row-major.
    entries: Vec<f64>,
}

impl LocalMatrix {
    /// The matrix of `scheme` around a vertex of valence `valence` (at least 3).
    ///
    /// ```
    /// use subdiv_schemes::{Builtin, LocalMatrix};
    ///
    /// let m = LocalMatrix::around(Builtin::CatmullClark.scheme(), 5)?;
    /// assert_eq!((m.size(), m.radius()), (11, 1));
    /// // The centre's row is the smooth vertex rule: (k - 2) / k on itself, plus 1 / (4k) from
    /// // the k face points around it.
    /// assert!((m.get(0, 0) - (3.0 / 5.0 + 1.0 / 20.0)).abs() < 1e-15);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// [`SchemeError::ValenceNotSupported`] below valence 3, and errors of the engine.
    pub fn around(scheme: &Scheme, valence: usize) -> Result<Self, SchemeError> {
        Canonical::new(scheme, valence, MAX_RADIUS)?.closed()
    }

    /// Rows (and columns).
    pub fn size(&self) -> usize {
        self.size
    }

    /// The neighbourhood's radius in rings of faces (0: the extraordinary face alone).
    pub fn radius(&self) -> usize {
        self.radius
    }

    /// The weight of parent vertex `column` in refined vertex `row`.
    pub fn get(&self, row: usize, column: usize) -> f64 {
        self.entries[row * self.size + column]
    }

    /// The eigenvalues, largest modulus first (ties: larger real part first), as `(re, im)`.
    ///
    /// # Errors
    /// [`SchemeError::Eigen`] when the eigen solver does not converge.
    pub fn eigenvalues(&self) -> Result<Vec<(f64, f64)>, SchemeError> {
        crate::eigen::eigenvalues(self.size, |i, j| self.get(i, j)).map_err(SchemeError::Eigen)
    }

    /// A real basis of the eigenspace of the real eigenvalue `lambda`, `count` vectors: the
    /// right singular vectors of `self - lambda·I` with the smallest singular values.
    fn eigenspace(&self, lambda: f64, count: usize) -> Result<Vec<Vec<f64>>, SchemeError> {
        let shifted =
            Mat::<f64>::from_fn(self.size, self.size, |i, j| self.get(i, j) - if i == j { lambda } else { 0.0 });
        let svd = shifted.svd().map_err(|e| SchemeError::Eigen(format!("{e:?}")))?;
        let singular: Vec<f64> = (0..self.size).map(|i| svd.S().column_vector()[i]).collect();
        let mut order: Vec<usize> = (0..self.size).collect();
        order.sort_by(|&a, &b| singular[a].total_cmp(&singular[b]));
        Ok(order[..count].iter().map(|&c| (0..self.size).map(|r| svd.V()[(r, c)]).collect()).collect())
    }
}

/// The canonical mesh of one valence, refined as far as the analysis needs it.
struct Canonical {
    scheme: Scheme,
    valence: usize,
    /// The parent mesh (the pillow, or for dual schemes the pillow refined once).
    mesh: Mesh,
    /// `steps_per_cycle` levels of refinement of `mesh`.
    refiner: Refiner,
    centre_is_face: bool,
    /// The centres of `mesh` and of the refined mesh, found once.
    centres: [Vec<VertexId>; 2],
}

impl Canonical {
    /// The canonical mesh for neighbourhoods of radius up to `largest_radius`: the pillow has
    /// two rings more, so that no such neighbourhood reaches its rim.
    fn new(scheme: &Scheme, valence: usize, largest_radius: usize) -> Result<Self, SchemeError> {
        let rings = largest_radius + 2;
        if valence < 3 {
            return Err(SchemeError::ValenceNotSupported {
                scheme: scheme.name.clone(),
                valence,
                reason: "analysis needs valence 3 or more",
            });
        }
        let triangles = matches!(scheme.split(), Split::Triangle | Split::Sqrt3);
        let pillow = Mesh::build(crate::canonical::pillow(valence, rings, triangles, crate::SharpFeatures::SMOOTH))
            .map_err(|e| SchemeError::Internal(e.to_string()))?;
        let centre_is_face = matches!(scheme.split(), Split::Dual | Split::Midedge);
        let mesh = if centre_is_face {
            Refiner::new(&pillow, scheme, 1, &RefineOptions::DEFAULT)?.into_mesh()
        } else {
            pillow
        };
        let refiner = Refiner::new(&mesh, scheme, scheme.steps_per_cycle(), &RefineOptions::DEFAULT)?;
        let centres = [centre(&mesh, centre_is_face), centre(refiner.mesh(), centre_is_face)];
        Ok(Self { scheme: scheme.clone(), valence, mesh, refiner, centre_is_face, centres })
    }

    /// The matrix of the smallest neighbourhood that refinement maps into itself.
    fn closed(&self) -> Result<LocalMatrix, SchemeError> {
        let first = if self.centre_is_face { 0 } else { 1 };
        for radius in first..=MAX_RADIUS {
            if let Some(matrix) = self.matrix(radius)? {
                return Ok(matrix);
            }
        }
        Err(SchemeError::ValenceNotSupported {
            scheme: self.scheme.name.clone(),
            valence: self.valence,
            reason: "no neighbourhood of up to 4 rings is closed under refinement",
        })
    }

    /// The matrix of the invariant neighbourhood: one ring more than the smallest closed one,
    /// so that it holds every vertex whose basis function reaches the faces around the centre
    /// (Reif's condition is on this matrix; its extra eigenvalues may exceed the closed
    /// one's).
    fn invariant(&self) -> Result<LocalMatrix, SchemeError> {
        let radius = self.closed()?.radius + 1;
        self.matrix(radius)?.ok_or_else(|| {
            SchemeError::Internal(format!("{}: the radius-{radius} neighbourhood is not closed", self.scheme))
        })
    }

    /// The ordered neighbourhood of radius `radius` of the centre of the parent mesh (or, if
    /// `refined`, of the refined one), with each vertex's ring.
    fn neighbourhood(&self, refined: bool, radius: usize) -> Vec<(VertexId, usize)> {
        let mesh = if refined { self.refiner.mesh() } else { &self.mesh };
        let ring = mesh.face_rings(&self.centres[usize::from(refined)], radius);
        let all = mesh.vertices().filter(|v| ring.contains_key(v));
        let key = |v: VertexId| {
            let p = mesh.position(v);
            let angle = (p.y.atan2(p.x) + 1e-6).rem_euclid(std::f64::consts::TAU);
            (ring[&v], angle, p.truncate().length())
        };
        let mut keyed: Vec<_> = all.map(|v| (key(v), v)).collect();
        keyed.sort_by(|(a, _), (b, _)| {
            a.0.cmp(&b.0)
                .then(if (a.1 - b.1).abs() < 1e-9 { std::cmp::Ordering::Equal } else { a.1.total_cmp(&b.1) })
                .then(a.2.total_cmp(&b.2))
        });
        keyed.into_iter().map(|((r, _, _), v)| (v, r)).collect()
    }

    /// The matrix of the neighbourhood of radius `radius`, or `None` when refinement does not
    /// map that neighbourhood into itself.
    fn matrix(&self, radius: usize) -> Result<Option<LocalMatrix>, SchemeError> {
        let parent = self.neighbourhood(false, radius);
        let child = self.neighbourhood(true, radius);
        if parent.len() != child.len() || parent.iter().zip(&child).any(|(a, b)| a.1 != b.1) {
            return Err(SchemeError::Internal(format!(
                "{} at valence {}: the refined neighbourhood of radius {radius} differs from the parent's",
                self.scheme, self.valence
            )));
        }
        let size = parent.len();
        let mut column = vec![usize::MAX; self.mesh.vertex_count()];
        for (c, (v, _)) in parent.iter().enumerate() {
            column[v.index()] = c;
        }
        let mut entries = vec![0.0; size * size];
        for (r, (v, _)) in child.iter().enumerate() {
            for (p, w) in composed_row(&self.refiner, v.index()) {
                match column[p] {
                    usize::MAX if w.abs() > 1e-14 => return Ok(None),
                    usize::MAX => {}
                    c => entries[r * size + c] += w,
                }
            }
        }
        Ok(Some(LocalMatrix { size, radius, entries }))
    }
}

/// The weights of vertex `child` of the refiner's last level over the first level's vertices.
fn composed_row(refiner: &Refiner, child: usize) -> Vec<(usize, f64)> {
    let mut row = vec![(child, 1.0)];
    for level in refiner.levels().iter().rev() {
        let mut next: Vec<(usize, f64)> = Vec::new();
        for &(c, w) in &row {
            for (p, pw) in level.row(c) {
                match next.iter_mut().find(|(q, _)| *q == p) {
                    Some((_, acc)) => *acc += w * pw,
                    None => next.push((p, w * pw)),
                }
            }
        }
        row = next;
    }
    row
}

/// The centre of a canonical mesh: vertex 0, or the extraordinary face's vertices.
fn centre(mesh: &Mesh, is_face: bool) -> Vec<VertexId> {
    if is_face { mesh.face_vertices(centre_face(mesh)).to_vec() } else { vec![VertexId::new(0)] }
}

/// The face of `mesh` whose centroid is nearest the origin: the extraordinary face of a dual
/// scheme's canonical mesh.
fn centre_face(mesh: &Mesh) -> FaceId {
    let centroid = |f: FaceId| {
        let vs = mesh.face_vertices(f);
        vs.iter().map(|&v| mesh.position(v)).sum::<DVec3>() / vs.len() as f64
    };
    mesh.face_ids()
        .min_by(|&a, &b| centroid(a).length_squared().total_cmp(&centroid(b).length_squared()))
        .expect("the canonical mesh has faces")
}

/// The spectrum of the [`LocalMatrix`] at one valence, and the spectral part of Reif's C1
/// conditions on it.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalSpectrum {
    /// Eigenvalues of the local matrix, largest modulus first, as `(re, im)`.
    pub eigenvalues: Vec<(f64, f64)>,
    /// λ0 = 1 and it is simple.
    pub unit_dominant_simple: bool,
    /// λ1 = λ2, real and positive (the subdominant pair).
    pub subdominant_real_double: bool,
    /// |λ3| < λ1.
    pub subdominant_strict: bool,
}

const TOLERANCE: f64 = 1e-10;

impl LocalSpectrum {
    /// The spectrum of `scheme`'s local matrix at valence `valence`.
    ///
    /// # Errors
    /// As [`LocalMatrix::around`] and [`LocalMatrix::eigenvalues`].
    pub fn of(scheme: &Scheme, valence: usize) -> Result<Self, SchemeError> {
        Self::of_matrix(&Canonical::new(scheme, valence, MAX_RADIUS + 1)?.invariant()?)
    }

    fn of_matrix(matrix: &LocalMatrix) -> Result<Self, SchemeError> {
        let eigenvalues = matrix.eigenvalues()?;
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

    /// Whether every spectral condition holds.
    pub fn passes(&self) -> bool {
        self.unit_dominant_simple && self.subdominant_real_double && self.subdominant_strict
    }
}

/// The characteristic map, sampled: the subdominant eigenvectors as a planar control net,
/// refined until a ring around the centre is dense, and that ring checked face by face.
#[derive(Clone, Debug, PartialEq)]
pub struct CharacteristicMap {
    /// Refinement levels applied to the eigenvector net.
    pub levels: usize,
    /// Faces of the sampled ring.
    pub faces: usize,
    /// Faces whose orientation differs from the majority's, or whose area vanishes.
    pub flipped_faces: usize,
    /// The smallest face area over the largest, in the majority orientation.
    pub min_area_ratio: f64,
    /// How often the ring's outer and inner boundaries wind around the centre.
    pub windings: (i64, i64),
}

impl CharacteristicMap {
    /// Regular: every sampled face keeps the orientation.
    pub fn is_regular(&self) -> bool {
        self.faces > 0 && self.flipped_faces == 0
    }

    /// Injective: regular, and both boundaries of the ring wind once around the centre, so
    /// every point is covered once.
    pub fn is_injective(&self) -> bool {
        self.is_regular() && self.windings.0.abs() == 1 && self.windings.1.abs() == 1
    }
}

/// Reif's C1 test at one valence: the spectrum and the characteristic map.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    /// The scheme's name.
    pub scheme: String,
    /// The valence.
    pub valence: usize,
    /// The local matrix's size and radius.
    pub matrix_size: usize,
    /// The neighbourhood's radius in rings of faces.
    pub radius: usize,
    /// The spectral conditions.
    pub spectrum: LocalSpectrum,
    /// The characteristic map; `None` when the subdominant eigenvalue is not a real double
    /// one (there is no planar characteristic map to check).
    pub characteristic_map: Option<CharacteristicMap>,
}

impl Analysis {
    /// Analyses `scheme` at an extraordinary vertex of valence `valence`.
    ///
    /// ```
    /// use subdiv_schemes::{Analysis, Builtin};
    ///
    /// let a = Analysis::of(Builtin::CatmullClark.scheme(), 5)?;
    /// assert!(a.is_c1());
    /// assert!((a.spectrum.subdominant() - 0.55).abs() < 1e-4);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`LocalMatrix::around`].
    pub fn of(scheme: &Scheme, valence: usize) -> Result<Self, SchemeError> {
        let canonical = Canonical::new(scheme, valence, MAX_RADIUS + 1 + EXTENSION)?;
        let matrix = canonical.invariant()?;
        let spectrum = LocalSpectrum::of_matrix(&matrix)?;
        let characteristic_map = if spectrum.subdominant_real_double && spectrum.unit_dominant_simple {
            Some(characteristic_map(&canonical, &matrix, spectrum.eigenvalues[1].0)?)
        } else {
            None
        };
        Ok(Self {
            scheme: scheme.name.clone(),
            valence,
            matrix_size: matrix.size,
            radius: matrix.radius,
            spectrum,
            characteristic_map,
        })
    }

    /// The verdict: the spectral conditions hold and the characteristic map is regular and
    /// injective.
    pub fn is_c1(&self) -> bool {
        self.spectrum.passes() && self.characteristic_map.as_ref().is_some_and(CharacteristicMap::is_injective)
    }
}

/// Samples and checks the characteristic map of `lambda`'s eigenspace (see
/// [`CharacteristicMap`]).
fn characteristic_map(
    canonical: &Canonical,
    inner: &LocalMatrix,
    lambda: f64,
) -> Result<CharacteristicMap, SchemeError> {
    // The eigenvectors on the invariant neighbourhood, extended outwards: outer rows depend on
    // the inner ones, so the extension solves (λ·I − S_oo) v_o = S_oi v_i.
    let basis = inner.eigenspace(lambda, 2)?;
    let radius = inner.radius + EXTENSION;
    let outer = canonical.matrix(radius)?.ok_or_else(|| {
        SchemeError::Internal(format!("{}: the radius-{radius} neighbourhood is not closed", canonical.scheme))
    })?;
    let n = inner.size;
    let m = outer.size - n;
    let system = Mat::<f64>::from_fn(m, m, |i, j| if i == j { lambda } else { 0.0 } - outer.get(n + i, n + j));
    let lu = system.partial_piv_lu();
    let mut net = Vec::new();
    for v in &basis {
        let rhs = Mat::<f64>::from_fn(m, 1, |i, _| (0..n).map(|c| outer.get(n + i, c) * v[c]).sum());
        let solution = lu.solve(&rhs);
        let mut x = v.clone();
        x.extend((0..m).map(|i| solution[(i, 0)]));
        if x.iter().any(|x| !x.is_finite()) {
            return Err(SchemeError::Eigen(format!(
                "{}: the subdominant eigenvector does not extend past its neighbourhood",
                canonical.scheme
            )));
        }
        net.push(x);
    }
    // The planar net on the parent mesh; everything outside the neighbourhood is unknown, and
    // only refined vertices whose every ancestor is known are used.
    let order = canonical.neighbourhood(false, radius);
    let mut positions = vec![DVec3::ZERO; canonical.mesh.vertex_count()];
    let mut known = vec![false; canonical.mesh.vertex_count()];
    for (i, (v, _)) in order.iter().enumerate() {
        positions[v.index()] = DVec3::new(net[0][i], net[1][i], 0.0);
        known[v.index()] = true;
    }
    let levels = if canonical.scheme.steps_per_cycle() == 2 { 4 } else { 3 };
    let refiner = Refiner::new(&canonical.mesh, &canonical.scheme, levels, &RefineOptions::DEFAULT)?;
    let (mut out, mut scratch) = (Vec::new(), Vec::new());
    refiner.interpolate(&positions, &mut out, &mut scratch);
    for level in refiner.levels() {
        known = (0..level.child_count()).map(|c| level.row(c).all(|(p, _)| known[p])).collect();
    }
    let fine = refiner.mesh();
    // Ring distances from the centre in the refined mesh, and how far every vertex is known.
    let ring = fine.face_rings(&centre(fine, canonical.centre_is_face), usize::MAX);
    let reach = fine
        .vertices()
        .filter(|v| !known[v.index()])
        .filter_map(|v| ring.get(&v).map(|r| r.saturating_sub(1)))
        .min()
        .unwrap_or(usize::MAX);
    if reach == usize::MAX || reach < 4 {
        return Err(SchemeError::Internal(format!(
            "{} at valence {}: too few known rings ({reach}) to sample the characteristic map",
            canonical.scheme, canonical.valence
        )));
    }
    let (low, high) = (reach.div_ceil(4), reach);
    let faces: Vec<FaceId> = fine
        .face_ids()
        .filter(|&f| fine.face_vertices(f).iter().all(|v| ring.get(v).is_some_and(|r| (low..=high).contains(r))))
        .collect();
    let area = |f: FaceId| {
        let vs = fine.face_vertices(f);
        let p = |i: usize| out[vs[i].index()];
        (1..vs.len() - 1).map(|i| (p(i) - p(0)).truncate().perp_dot((p(i + 1) - p(0)).truncate())).sum::<f64>() / 2.0
    };
    let areas: Vec<f64> = faces.iter().map(|&f| area(f)).collect();
    let positive = areas.iter().filter(|&&a| a > 0.0).count();
    let sign = if 2 * positive >= areas.len() { 1.0 } else { -1.0 };
    let largest = areas.iter().map(|a| a * sign).fold(0.0_f64, f64::max);
    let flipped_faces = areas.iter().filter(|&&a| a * sign <= largest * 1e-12).count();
    let min_area_ratio = areas.iter().map(|a| a * sign).fold(f64::INFINITY, f64::min) / largest;
    // The ring's boundary: edges of exactly one of its faces, as loops; their windings.
    let in_ring: std::collections::HashSet<FaceId> = faces.iter().copied().collect();
    let mut windings = Vec::new();
    let mut used = std::collections::HashSet::new();
    for &f in &faces {
        for h in fine.face_half_edges(f) {
            let boundary = fine.twin(h).is_none_or(|t| !in_ring.contains(&fine.face(t)));
            if !boundary || used.contains(&h) {
                continue;
            }
            // Walk the loop: from the end of h, the next boundary half-edge of the ring.
            let mut angle = 0.0;
            let mut x = h;
            loop {
                used.insert(x);
                let (a, b) = (out[fine.origin(x).index()].truncate(), out[fine.dest(x).index()].truncate());
                angle += a.perp_dot(b).atan2(a.dot(b));
                // Rotate around dest(x) inside the ring until the next boundary half-edge.
                let mut y = fine.next(x);
                loop {
                    match fine.twin(y) {
                        Some(t) if in_ring.contains(&fine.face(t)) => y = fine.next(t),
                        _ => break,
                    }
                }
                x = y;
                if x == h || used.contains(&x) {
                    break;
                }
            }
            windings.push((angle / std::f64::consts::TAU).round() as i64);
        }
    }
    windings.sort_by_key(|w| std::cmp::Reverse(w.abs()));
    let windings = match windings.as_slice() {
        [a, b] => (*a, *b),
        _ => (0, 0),
    };
    Ok(CharacteristicMap { levels, faces: faces.len(), flipped_faces, min_area_ratio, windings })
}
