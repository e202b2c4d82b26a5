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
//! the centre that refinement maps into itself; the parent's vertices are ordered by ring, then
//! by angle from the direction of the first spoke, and the refined ones follow them through the
//! meshes' combinatorial match (walked in step from the first spoke, so equal order means equal
//! place).
//!
//! A boundary vertex with `f` faces ([`Centre::Boundary`]) is analysed the same way on an open
//! fan of `f` sectors under the scheme's boundary rule; there the subdominant pair may be two
//! distinct eigenvalues (the boundary curve's and the cross-boundary one), and the
//! characteristic map is checked on a half-ring whose image must be a simple polygon.

use faer::Mat;
use faer::linalg::solvers::Solve;
use subdiv_mesh::{DVec3, FaceId, Mesh, VertexId};

use crate::{RefineOptions, Refiner, Scheme, SchemeError, Split};

/// The largest neighbourhood radius (in rings of faces) the analysis tries before it gives up
/// on finding one that refinement maps into itself.
pub(crate) const MAX_RADIUS: usize = 4;

/// How many rings past the invariant neighbourhood the characteristic map's eigenvectors are
/// extended, so that a few refinements leave a dense ring whose every vertex is known.
const EXTENSION: usize = 3;

/// Steps of a dual split before its neighbourhood of a boundary vertex of three faces or more
/// repeats out to `MAX_RADIUS + 1 + EXTENSION` rings. The vertex's face (on the boundary) has
/// boundary vertices of three faces at its ends, which make a triangle each at the next step,
/// whose own ends do the same: a train of triangles along the boundary, each one ring further
/// out in its level than the one before, twice as far at the next level. Five steps put the
/// rings within the characteristic map's radius in their final pattern.
const DUAL_BOUNDARY_STEPS: usize = 5;

/// The vertex an analysis is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Centre {
    /// An interior vertex of this valence, 3 or more (for dual schemes, the face it becomes).
    Interior(usize),
    /// A boundary vertex with this many faces around it (valence `faces + 1`), under the
    /// scheme's boundary rule (edge-only where the scheme takes OpenSubdiv's rules).
    Boundary(usize),
}

impl Centre {
    /// The vertex's valence (edges at it).
    pub fn valence(self) -> usize {
        match self {
            Self::Interior(k) => k,
            Self::Boundary(faces) => faces + 1,
        }
    }
}

impl std::fmt::Display for Centre {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Interior(k) => write!(f, "an interior vertex of valence {k}"),
            Self::Boundary(1) => write!(f, "a boundary vertex of 1 face"),
            Self::Boundary(faces) => write!(f, "a boundary vertex of {faces} faces"),
        }
    }
}

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
        Self::at(scheme, Centre::Interior(valence))
    }

    /// The matrix of `scheme` around `centre`, interior or boundary.
    ///
    /// # Errors
    /// As [`around`](Self::around); boundary vertices of schemes without boundary rules are
    /// [`SchemeError::FeatureNotSupported`].
    pub fn at(scheme: &Scheme, centre: Centre) -> Result<Self, SchemeError> {
        Canonical::new(scheme, centre, MAX_RADIUS)?.closed()
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

    /// The transpose, whose right eigenvectors are this matrix's left ones.
    pub(crate) fn transposed(&self) -> Self {
        let n = self.size;
        Self { size: n, radius: self.radius, entries: (0..n * n).map(|k| self.entries[(k % n) * n + k / n]).collect() }
    }

    /// A real basis of the eigenspace of the real eigenvalue `lambda`, `count` vectors: the
    /// right singular vectors of `self - lambda·I` with the smallest singular values.
    pub(crate) fn eigenspace(&self, lambda: f64, count: usize) -> Result<Vec<Vec<f64>>, SchemeError> {
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
pub(crate) struct Canonical {
    scheme: Scheme,
    centre: Centre,
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
    pub(crate) fn new(scheme: &Scheme, at: Centre, largest_radius: usize) -> Result<Self, SchemeError> {
        // A dual split doubles the rings of faces around the centre at every step: its boundary
        // centres, refined `DUAL_BOUNDARY_STEPS` times first, need few.
        let dual_boundary = matches!(scheme.split(), Split::Dual | Split::Midedge) && matches!(at, Centre::Boundary(_));
        let rings = if dual_boundary { 3 } else { largest_radius + 2 };
        let invalid = match at {
            Centre::Interior(k) if k < 3 => Some("analysis needs valence 3 or more"),
            Centre::Boundary(0) => Some("a boundary vertex needs one face or more"),
            _ => None,
        };
        if let Some(reason) = invalid {
            return Err(SchemeError::ValenceNotSupported {
                scheme: scheme.name.clone(),
                valence: at.valence(),
                reason,
            });
        }
        let triangles = matches!(scheme.split(), Split::Triangle | Split::Sqrt3);
        let smooth = crate::SharpFeatures::SMOOTH;
        let soup = match at {
            Centre::Interior(k) => crate::canonical::pillow(k, rings, triangles, smooth),
            Centre::Boundary(faces) => {
                if !scheme.has_boundary_rules() {
                    return Err(SchemeError::FeatureNotSupported {
                        scheme: scheme.name.clone(),
                        feature: "boundaries",
                        element: at.to_string(),
                    });
                }
                let mut soup = crate::canonical::open_fan(faces, rings, triangles, smooth);
                soup.tags.boundary_interpolation = Some(subdiv_mesh::BoundaryInterpolation::EdgeOnly);
                soup
            }
        };
        let pillow = Mesh::build(soup).map_err(|e| SchemeError::Internal(e.to_string()))?;
        let centre_is_face = matches!(scheme.split(), Split::Dual | Split::Midedge);
        // Mid-edge takes open meshes two steps at a time: its boundary is its dual form's.
        let scheme = match (scheme.split(), at) {
            (Split::Midedge, Centre::Boundary(_)) => &scheme.dual_form().expect("mid-edge has a dual form"),
            _ => scheme,
        };
        let first_steps = if dual_boundary { DUAL_BOUNDARY_STEPS } else { 1 };
        let (mesh, centres) = if scheme.split() == Split::Dual {
            // The centre face on the first level is the one nearest the origin (the vertex's
            // face; at a boundary vertex of one or two faces, which has none, the face of its
            // corner or of its interior edge, whose children shrink onto its limit), and on each
            // further level its own face's child, found by the split's numbering.
            let mut mesh = Refiner::new(&pillow, scheme, 1, &RefineOptions::DEFAULT)?.into_mesh();
            let mut face = centre_face(&mesh);
            for _ in 1..first_steps {
                let next = Refiner::new(&mesh, scheme, 1, &RefineOptions::DEFAULT)?.into_mesh();
                face = own_child(&mesh, face, &next)?;
                mesh = next;
            }
            let refined = Refiner::new(&mesh, scheme, 1, &RefineOptions::DEFAULT)?.into_mesh();
            let centres =
                [mesh.face_vertices(face).to_vec(), refined.face_vertices(own_child(&mesh, face, &refined)?).to_vec()];
            (mesh, Some(centres))
        } else if centre_is_face {
            (Refiner::new(&pillow, scheme, first_steps, &RefineOptions::DEFAULT)?.into_mesh(), None)
        } else {
            (pillow, None)
        };
        let refiner = Refiner::new(&mesh, scheme, scheme.steps_per_cycle(), &RefineOptions::DEFAULT)?;
        let centres =
            centres.unwrap_or_else(|| [centre(&mesh, centre_is_face), centre(refiner.mesh(), centre_is_face)]);
        Ok(Self { scheme: scheme.clone(), centre: at, mesh, refiner, centre_is_face, centres })
    }

    /// The split the matrix is read under (mid-edge's dual form at a boundary).
    pub(crate) fn split(&self) -> Split {
        self.scheme.split()
    }

    /// The parent mesh, whose vertices the matrix's columns are.
    pub(crate) fn parent(&self) -> &Mesh {
        &self.mesh
    }

    /// The centre's vertices on the parent mesh (one, or a dual scheme's face's).
    pub(crate) fn centre(&self) -> &[VertexId] {
        &self.centres[0]
    }

    /// The matrix of the smallest neighbourhood that refinement maps into itself.
    pub(crate) fn closed(&self) -> Result<LocalMatrix, SchemeError> {
        let first = if self.centre_is_face { 0 } else { 1 };
        for radius in first..=MAX_RADIUS {
            if let Some(matrix) = self.matrix(radius)? {
                return Ok(matrix);
            }
        }
        Err(SchemeError::ValenceNotSupported {
            scheme: self.scheme.name.clone(),
            valence: self.centre.valence(),
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

    /// The ordered neighbourhood of radius `radius` of the centre of the parent mesh, with each
    /// vertex's ring: by ring, then by angle from the first spoke, then by distance.
    pub(crate) fn neighbourhood(&self, radius: usize) -> Vec<(VertexId, usize)> {
        let mesh = &self.mesh;
        let ring = mesh.face_rings(&self.centres[0], radius);
        let all = mesh.vertices().filter(|v| ring.contains_key(v));
        let key = |v: VertexId| (ring[&v], angle(mesh.position(v)), mesh.position(v).truncate().length());
        let mut keyed: Vec<_> = all.map(|v| (key(v), v)).collect();
        keyed.sort_by(|(a, _), (b, _)| {
            a.0.cmp(&b.0)
                .then(if (a.1 - b.1).abs() < 1e-9 { std::cmp::Ordering::Equal } else { a.1.total_cmp(&b.1) })
                .then(a.2.total_cmp(&b.2))
        });
        keyed.into_iter().map(|((r, _, _), v)| (v, r)).collect()
    }

    /// The refined mesh's vertices in the places of `parent` (a [`neighbourhood`](Self::neighbourhood)
    /// of radius `radius`), with their rings there: the two meshes walked in step, half-edge by
    /// half-edge, from the centre's first spoke (the one at the smallest angle), so that a place
    /// is found by the combinatorics and never by rounding positions.
    fn refined_neighbourhood(
        &self,
        parent: &[(VertexId, usize)],
        radius: usize,
    ) -> Result<Vec<(VertexId, usize)>, SchemeError> {
        let (coarse, fine) = (&self.mesh, self.refiner.mesh());
        let mismatch = || {
            SchemeError::Internal(format!(
                "{} at {}: the refined neighbourhood of radius {radius} differs from the parent's",
                self.scheme, self.centre
            ))
        };
        let rings = [coarse.face_rings(&self.centres[0], radius), fine.face_rings(&self.centres[1], radius)];
        let starts = [first_spoke(coarse, &self.centres[0]), first_spoke(fine, &self.centres[1])];
        let (Some(start_coarse), Some(start_fine)) = (starts[0], starts[1]) else {
            return Err(mismatch());
        };
        let mut place = std::collections::HashMap::new();
        let mut seen = std::collections::HashSet::new();
        let mut stack = vec![(start_coarse, start_fine)];
        while let Some((a, b)) = stack.pop() {
            if !rings[0].contains_key(&coarse.origin(a)) || !seen.insert(a) {
                continue;
            }
            match place.insert(coarse.origin(a), fine.origin(b)) {
                Some(old) if old != fine.origin(b) => return Err(mismatch()),
                _ => {}
            }
            stack.push((coarse.next(a), fine.next(b)));
            match (coarse.twin(a), fine.twin(b)) {
                (Some(x), Some(y)) => stack.push((x, y)),
                (None, None) => {}
                _ => return Err(mismatch()),
            }
        }
        parent
            .iter()
            .map(|&(v, r)| {
                let w = *place.get(&v).ok_or_else(mismatch)?;
                (rings[1].get(&w) == Some(&r)).then_some((w, r)).ok_or_else(mismatch)
            })
            .collect::<Result<Vec<_>, _>>()
            .and_then(|child| if child.len() == rings[1].len() { Ok(child) } else { Err(mismatch()) })
    }

    /// The matrix of the neighbourhood of radius `radius`, or `None` when refinement does not
    /// map that neighbourhood into itself.
    fn matrix(&self, radius: usize) -> Result<Option<LocalMatrix>, SchemeError> {
        let parent = self.neighbourhood(radius);
        let child = self.refined_neighbourhood(&parent, radius)?;
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

/// The angle of `p` from the first spoke's direction (the x axis), in `[0, 2π)`; points a hair
/// below the axis count as on it.
fn angle(p: DVec3) -> f64 {
    (p.y.atan2(p.x) + 1e-6).rem_euclid(std::f64::consts::TAU)
}

/// The half-edge the walk of [`Canonical::refined_neighbourhood`] starts from: out of the centre
/// vertex, towards the neighbour at the smallest angle; or on the centre face, from its corner
/// at the smallest angle.
pub(crate) fn first_spoke(mesh: &Mesh, centre: &[VertexId]) -> Option<subdiv_mesh::HalfEdgeId> {
    let by_angle = |v: VertexId| angle(mesh.position(v));
    match centre {
        [v] => mesh.outgoing(*v).min_by(|&a, &b| by_angle(mesh.dest(a)).total_cmp(&by_angle(mesh.dest(b)))),
        _ => {
            let face = mesh.vertex_faces(centre[0]).find(|&f| {
                let vs = mesh.face_vertices(f);
                vs.len() == centre.len() && centre.iter().all(|v| vs.contains(v))
            })?;
            mesh.face_half_edges(face).min_by(|&a, &b| by_angle(mesh.origin(a)).total_cmp(&by_angle(mesh.origin(b))))
        }
    }
}

/// The centre of a canonical mesh: vertex 0, or the extraordinary face's vertices.
fn centre(mesh: &Mesh, is_face: bool) -> Vec<VertexId> {
    if is_face { mesh.face_vertices(centre_face(mesh)).to_vec() } else { vec![VertexId::new(0)] }
}

/// The face a dual step makes of `face` of `parent` in `child`: its corners are the child's
/// vertices numbered by `face`'s half-edges.
fn own_child(parent: &Mesh, face: FaceId, child: &Mesh) -> Result<FaceId, SchemeError> {
    let corners: Vec<VertexId> = parent.face_half_edges(face).map(|h| VertexId::new(h.raw())).collect();
    child
        .vertex_faces(corners[0])
        .find(|&f| child.face_size(f) == corners.len() && child.face_vertices(f).iter().all(|v| corners.contains(v)))
        .ok_or_else(|| SchemeError::Internal(format!("the dual step made no face of {face}'s corners")))
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
    /// λ1 and λ2 real and positive, and equal at an interior vertex (the subdominant pair; at a
    /// boundary vertex the boundary curve's and the cross-boundary eigenvalue may differ).
    pub subdominant_real_pair: bool,
    /// |λ3| < λ2.
    pub subdominant_strict: bool,
}

const TOLERANCE: f64 = 1e-10;

/// Eigenvalues closer than this are one multiple eigenvalue (and imaginary parts smaller than
/// it are zero): a defective double eigenvalue splits by about √ε ≈ 1e-8 in floating point,
/// into two reals or a complex pair (Loop's boundary vertex of 6 faces: 0.5 ± 7.6e-9).
const MULTIPLE: f64 = 1e-6;

impl LocalSpectrum {
    /// The spectrum of `scheme`'s local matrix at valence `valence`.
    ///
    /// # Errors
    /// As [`LocalMatrix::around`] and [`LocalMatrix::eigenvalues`].
    pub fn of(scheme: &Scheme, valence: usize) -> Result<Self, SchemeError> {
        Self::at(scheme, Centre::Interior(valence))
    }

    /// The spectrum of `scheme`'s local matrix around `centre`.
    ///
    /// # Errors
    /// As [`LocalMatrix::at`] and [`LocalMatrix::eigenvalues`].
    pub fn at(scheme: &Scheme, centre: Centre) -> Result<Self, SchemeError> {
        Self::of_matrix(&Canonical::new(scheme, centre, MAX_RADIUS + 1)?.invariant()?, centre)
    }

    fn of_matrix(matrix: &LocalMatrix, centre: Centre) -> Result<Self, SchemeError> {
        let eigenvalues = matrix.eigenvalues()?;
        let modulus = |i: usize| eigenvalues.get(i).map_or(0.0, |z: &(f64, f64)| z.0.hypot(z.1));
        let unit_dominant_simple =
            eigenvalues.first().is_some_and(|z| (z.0 - 1.0).abs() < TOLERANCE && z.1.abs() < TOLERANCE)
                && modulus(1) < 1.0 - TOLERANCE;
        let equal =
            (eigenvalues.get(1).map_or(0.0, |z| z.0) - eigenvalues.get(2).map_or(0.0, |z| z.0)).abs() < MULTIPLE;
        let subdominant_real_pair = eigenvalues.len() > 2
            && eigenvalues[1].1.abs() < MULTIPLE
            && eigenvalues[2].1.abs() < MULTIPLE
            && (equal || matches!(centre, Centre::Boundary(_)))
            && eigenvalues[2].0 > 0.0;
        let subdominant_strict = modulus(3) < modulus(2) - MULTIPLE;
        Ok(Self { eigenvalues, unit_dominant_simple, subdominant_real_pair, subdominant_strict })
    }

    /// The subdominant eigenvalue λ1 (the modulus of the second eigenvalue).
    pub fn subdominant(&self) -> f64 {
        self.eigenvalues.get(1).map_or(0.0, |z| z.0.hypot(z.1))
    }

    /// Whether every spectral condition holds.
    pub fn passes(&self) -> bool {
        self.unit_dominant_simple && self.subdominant_real_pair && self.subdominant_strict
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
    /// How often the ring's outer and inner boundaries wind around the centre (an interior
    /// vertex's ring; a boundary vertex's half-ring has one outline, `(0, 0)`).
    pub windings: (i64, i64),
    /// The outlines of the sampled ring (2 around an interior vertex, 1 at a boundary vertex).
    pub outlines: usize,
    /// No two non-adjacent sides of the outlines' images cross.
    pub outlines_simple: bool,
}

impl CharacteristicMap {
    /// Regular: every sampled face keeps the orientation.
    pub fn is_regular(&self) -> bool {
        self.faces > 0 && self.flipped_faces == 0
    }

    /// Injective: regular, and both boundaries of the ring wind once around the centre, so
    /// every point is covered once; at a boundary vertex, the half-ring's one outline is a
    /// simple polygon (a regular map of a disc whose boundary maps to a simple curve is one to
    /// one).
    pub fn is_injective(&self) -> bool {
        self.is_regular()
            && match self.outlines {
                2 => self.windings.0.abs() == 1 && self.windings.1.abs() == 1,
                1 => self.outlines_simple,
                _ => false,
            }
    }
}

/// Reif's C1 test at one vertex, interior or boundary: the spectrum and the characteristic map.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    /// The scheme's name.
    pub scheme: String,
    /// The vertex analysed.
    pub centre: Centre,
    /// Its valence.
    pub valence: usize,
    /// The local matrix's size and radius.
    pub matrix_size: usize,
    /// The neighbourhood's radius in rings of faces.
    pub radius: usize,
    /// The spectral conditions.
    pub spectrum: LocalSpectrum,
    /// The characteristic map; `None` when the subdominant pair is not real (there is no
    /// planar characteristic map to check).
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
        Self::at(scheme, Centre::Interior(valence))
    }

    /// Analyses `scheme` at `centre`, interior or boundary (under the scheme's boundary rule).
    ///
    /// ```
    /// use subdiv_schemes::{Analysis, Builtin, Centre};
    ///
    /// // Catmull-Clark at a regular boundary vertex (two faces): the boundary curve's 1/2 and
    /// // the cross-boundary 1/2.
    /// let a = Analysis::at(Builtin::CatmullClark.scheme(), Centre::Boundary(2))?;
    /// assert!(a.is_c1());
    /// assert!((a.spectrum.subdominant() - 0.5).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`LocalMatrix::at`].
    pub fn at(scheme: &Scheme, centre: Centre) -> Result<Self, SchemeError> {
        let canonical = Canonical::new(scheme, centre, MAX_RADIUS + 1 + EXTENSION)?;
        let matrix = canonical.invariant()?;
        let spectrum = LocalSpectrum::of_matrix(&matrix, centre)?;
        let characteristic_map = if spectrum.subdominant_real_pair && spectrum.unit_dominant_simple {
            let pair = [spectrum.eigenvalues[1].0, spectrum.eigenvalues[2].0];
            Some(characteristic_map(&canonical, &matrix, pair)?)
        } else {
            None
        };
        Ok(Self {
            scheme: scheme.name.clone(),
            centre,
            valence: centre.valence(),
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

/// Samples and checks the characteristic map of the subdominant pair `[λ1, λ2]`'s eigenvectors
/// (one eigenspace of dimension 2 where they are equal; see [`CharacteristicMap`]).
fn characteristic_map(
    canonical: &Canonical,
    inner: &LocalMatrix,
    [lambda1, lambda2]: [f64; 2],
) -> Result<CharacteristicMap, SchemeError> {
    // The eigenvectors on the invariant neighbourhood, extended outwards: outer rows depend on
    // the inner ones, so the extension solves (λ·I − S_oo) v_o = S_oi v_i.
    let basis: Vec<(f64, Vec<f64>)> = if (lambda1 - lambda2).abs() < MULTIPLE {
        inner.eigenspace(lambda1, 2)?.into_iter().map(|v| (lambda1, v)).collect()
    } else {
        let mut pair = Vec::new();
        for lambda in [lambda1, lambda2] {
            pair.extend(inner.eigenspace(lambda, 1)?.into_iter().map(|v| (lambda, v)));
        }
        pair
    };
    let radius = inner.radius + EXTENSION;
    let outer = canonical.matrix(radius)?.ok_or_else(|| {
        SchemeError::Internal(format!("{}: the radius-{radius} neighbourhood is not closed", canonical.scheme))
    })?;
    let n = inner.size;
    let m = outer.size - n;
    let mut net = Vec::new();
    for (lambda, v) in &basis {
        let system = Mat::<f64>::from_fn(m, m, |i, j| if i == j { *lambda } else { 0.0 } - outer.get(n + i, n + j));
        let lu = system.partial_piv_lu();
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
    let order = canonical.neighbourhood(radius);
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
            "{} at {}: too few known rings ({reach}) to sample the characteristic map",
            canonical.scheme, canonical.centre
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
    let mut outlines: Vec<Vec<glam::DVec2>> = Vec::new();
    let mut used = std::collections::HashSet::new();
    for &f in &faces {
        for h in fine.face_half_edges(f) {
            let boundary = fine.twin(h).is_none_or(|t| !in_ring.contains(&fine.face(t)));
            if !boundary || used.contains(&h) {
                continue;
            }
            // Walk the loop: from the end of h, the next boundary half-edge of the ring.
            let mut angle = 0.0;
            let mut outline = Vec::new();
            let mut x = h;
            loop {
                used.insert(x);
                let (a, b) = (out[fine.origin(x).index()].truncate(), out[fine.dest(x).index()].truncate());
                outline.push(a);
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
            outlines.push(outline);
        }
    }
    let outlines_simple = outlines.iter().all(|o| is_simple(o));
    let outline_count = outlines.len();
    windings.sort_by_key(|w| std::cmp::Reverse(w.abs()));
    let windings = match windings.as_slice() {
        [a, b] => (*a, *b),
        _ => (0, 0),
    };
    Ok(CharacteristicMap {
        levels,
        faces: faces.len(),
        flipped_faces,
        min_area_ratio,
        windings,
        outlines: outline_count,
        outlines_simple,
    })
}

/// Whether the closed polygon `points` is simple: no side collapses to a point (shorter than
/// 1e-9 of the longest: a map that sends a stretch of the boundary to one point, as eigenvectors
/// that vanish on the boundary do, is not one to one) and no two sides that share no corner
/// cross (sides that only touch count as not crossing).
fn is_simple(points: &[glam::DVec2]) -> bool {
    let n = points.len();
    let side = |i: usize| (points[i], points[(i + 1) % n]);
    let longest = (0..n).map(|i| side(i).0.distance(side(i).1)).fold(0.0, f64::max);
    if (0..n).any(|i| side(i).0.distance(side(i).1) <= 1e-9 * longest) {
        return false;
    }
    let orient = |a: glam::DVec2, b: glam::DVec2, c: glam::DVec2| (b - a).perp_dot(c - a);
    let cross = |(a, b): (glam::DVec2, glam::DVec2), (c, d): (glam::DVec2, glam::DVec2)| {
        orient(a, b, c) * orient(a, b, d) < 0.0 && orient(c, d, a) * orient(c, d, b) < 0.0
    };
    (0..n).all(|i| (i + 2..n).filter(|&j| (j + 1) % n != i).all(|j| !cross(side(i), side(j))))
}
