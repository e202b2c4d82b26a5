//! Sub-patch matrices, derived by running the engine on a canonical mesh.
//!
//! A *patch* is a face of the control mesh with the control vertices its limit surface depends
//! on: every vertex within `radius` rings of faces of it, gathered in a topological order by
//! [`Mesh::patch`]. One refinement splits the face into sub-faces (four for quad and triangle
//! splits), each the face of a sub-patch of the refined mesh; the rows of the sub-patch's
//! vertices over the parent patch's are that sub-patch's matrix. The radius is the smallest for
//! which every such row stays inside the parent patch, so the limit surface over a face is a
//! function of its patch alone, and the matrices compose: a point given by its address (which
//! sub-patch at every level) has the stencil `… · A_2 · A_1` over the patch.
//!
//! Patches of equal [shape](subdiv_mesh::Patch::signature) have equal matrices. Starting from a
//! [`PatchType`], the sub-patches' shapes are collected level by level until no new shape
//! appears; each [`PatchShape`] lists its children. Around an extraordinary vertex the child at
//! corner 0 keeps the vertex and the shape, so its matrix is square (the matrix whose
//! eigenvectors give the limit at the vertex); the other children lead, within two levels, to
//! the regular shape.
//!
//! Child `j` of a quad face sits at corner `j` of the parent's domain `[0, 1]²` and has the same
//! axes; children 0..3 of a triangle sit at the corners of the domain `u, v ≥ 0, u + v ≤ 1` and
//! child 3 is the middle one, turned by half a turn (see [`ChildDomain`]).

use std::collections::HashMap;

use std::sync::{Arc, Mutex, OnceLock};

use subdiv_mesh::{BoundaryInterpolation, FaceId, HalfEdgeId, Mesh, Patch};

use crate::{RefineOptions, Refiner, Scheme, SchemeError, Split};

mod derivation;
mod dual;
mod ring;
mod sub_patch;
mod ternary;

use derivation::{Derivation, canonical_start};
pub use dual::{
    derive_dual_configuration, dual_child_starts, dual_corner_start, dual_patch, dual_quad_corners,
    dual_signature_has_boundary,
};
pub use ring::{Frequency, RingSpectrum};
pub use sub_patch::{ChildDomain, SubPatch};
pub use ternary::{ternary_child_starts, ternary_refine};

/// The largest patch radius tried, in rings of faces: the smallest radius whose patches are
/// closed under refinement is 1 for Catmull-Clark, Loop, sw-quad and bilinear, 2 for Butterfly
/// and for Kobbelt at valences 3 and 4, and 4 for Kobbelt at other valences (its virtual points,
/// extrapolated from the extraordinary vertex's ring, reach further than its regular support:
/// 120 control points at valence 5, 1,300 at 64).
pub const MAX_PATCH_RADIUS: usize = 4;

/// The largest valence whose interior type [`PatchMatrices::interior_shape`] looks in (the
/// committed tables' largest: beyond it a look-up would derive a type to save a fit).
const MAX_INTERIOR_LOOKUP: usize = 16;

/// Refinement levels after which the shapes must have closed up.
const MAX_LEVELS: usize = 5;

/// The number of the next [`PatchType::Derived`] in this process.
static NEXT_DERIVED: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);

/// A new [`PatchType::Derived`] number.
pub(crate) fn next_derived_id() -> u32 {
    NEXT_DERIVED.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// A stencil weight at most this large counts as zero: the engine's rows sum weights, and a
/// weight that is zero in exact arithmetic (a crease rule's, say) stays within this of it.
const ZERO_WEIGHT: f64 = 1e-14;

/// Which canonical patch to start from: a face whose corner 0 is the only irregular place.
///
/// Corner 0's fan, and its stationary sharp features ([`SharpFeatures`]: infinitely sharp
/// edges and corners). Semi-sharp features are not stationary: a face at one is refined
/// until its sharpness is spent, or has a configuration of its own derived from its mesh
/// ([`PatchType::Derived`]; see `subdiv-stencil`'s `PatchLevels`).
///
/// **How many there are.** An interior vertex of valence `k` has `2^k` sets of sharp spokes,
/// each with or without a corner, and the set is counted from the patch's face (spoke 0 is
/// the face's first side), so up to valence `K` there are `Σ_{k=2..K} 2^(k+1)` interior types
/// (a smooth vertex: one per valence). A boundary vertex with `f` faces has `2^(f−1)` sets of
/// sharp interior spokes, with or without a corner, for each of its `f` faces: up to `F`
/// faces, `Σ_{f=1..F} f · 2^f`. They are derived on demand, only for the configurations a
/// mesh has, and cached per process.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PatchType {
    /// Corner 0 is an interior vertex of this valence; the scheme's regular valence (4, or 6
    /// for triangles) without sharp features gives the regular patch.
    Interior {
        /// The valence of corner 0 (2 or more for quad splits, 3 or more for triangles).
        valence: usize,
        /// Its sharp features; spokes count counter-clockwise from the face's first side.
        sharp: SharpFeatures,
    },
    /// Corner 0 is a boundary vertex with this many faces around it, and the face is the
    /// `index`-th of them counted counter-clockwise from the boundary: index 0 has its first
    /// side (corner 0 to corner 1) on the boundary, index `faces − 1` its last side. 2 faces
    /// (3 for triangles) is the regular boundary, 1 a corner.
    Boundary {
        /// Faces around corner 0 (1 or more).
        faces: usize,
        /// The face's place in the fan, `0..faces`.
        index: usize,
        /// Its sharp features; spokes count counter-clockwise from the boundary edge on face
        /// 0's first side (spokes 0 and `faces` are the boundary, sharp by the boundary rule,
        /// and not in the set).
        sharp: SharpFeatures,
    },
    /// A configuration with semi-sharp features at the face's corners, derived from a mesh's
    /// own neighbourhood of the face ([`MeshPatches`](crate::MeshPatches) does it for such
    /// faces, once per configuration and preparation): its shapes run down the levels on which
    /// the sharpness is spent to stationary ones. Numbered in the order of derivation in this
    /// process; never in the committed tables.
    Derived {
        /// The derivation's number in this process.
        id: u32,
    },
}

/// The stationary sharp features at a [`PatchType`]'s vertex: which of its spokes (the edges
/// from the vertex) are infinitely sharp, and whether the vertex is an infinitely sharp
/// corner. Sharpness ≥ 10 ([`Tags::INFINITELY_SHARP`](subdiv_mesh::Tags::INFINITELY_SHARP))
/// is infinite, as in OpenSubdiv.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SharpFeatures {
    /// Bit `s` is set when spoke `s` is infinitely sharp (so spokes 0 to 63 can be).
    pub edges: u64,
    /// Whether the vertex is an infinitely sharp corner.
    pub corner: bool,
}

impl SharpFeatures {
    /// No sharp feature.
    pub const SMOOTH: Self = Self { edges: 0, corner: false };

    /// Whether there is no sharp feature.
    pub fn is_smooth(self) -> bool {
        self == Self::SMOOTH
    }

    /// Whether spoke `s` is infinitely sharp.
    pub fn edge(self, s: usize) -> bool {
        s < 64 && self.edges >> s & 1 == 1
    }
}

impl PatchType {
    /// The smooth interior patch type of this valence.
    pub fn interior(valence: usize) -> Self {
        Self::Interior { valence, sharp: SharpFeatures::SMOOTH }
    }

    /// The smooth boundary patch type: the `index`-th of `faces` faces.
    pub fn boundary(faces: usize, index: usize) -> Self {
        Self::Boundary { faces, index, sharp: SharpFeatures::SMOOTH }
    }

    /// The regular interior patch of `scheme`.
    pub fn regular(scheme: &Scheme) -> Self {
        Self::interior(scheme.regular_valence())
    }

    /// The stationary sharp features at corner 0 (none for a derived configuration, which
    /// has its features in its shapes).
    pub fn sharp(self) -> SharpFeatures {
        match self {
            Self::Interior { sharp, .. } | Self::Boundary { sharp, .. } => sharp,
            Self::Derived { .. } => SharpFeatures::SMOOTH,
        }
    }
}

/// A patch shape: its control-point count, its signature and its children.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchShape {
    /// Control points.
    pub size: usize,
    /// The shape's [`Patch::signature`](subdiv_mesh::Patch::signature).
    pub signature: Vec<u32>,
    /// The sub-patches, in the engine's child order.
    pub children: Vec<SubPatch>,
    /// The control points the limit surface over the face can depend on, ascending (the face's
    /// corners first): the least sets, over all shapes, that hold each face's corners and every
    /// point a child matrix reads into a point of its child's set. The surface over a face is
    /// the limit of its descendants' corners, so a point outside the set has no influence on
    /// it: a bilinear face's points beyond its own corners, or the points across an infinitely
    /// sharp edge. Every stencil is zero outside it. (A point inside may still have none; the
    /// set only errs on the safe side.)
    pub influence: Vec<u32>,
    /// The parameters `[u, v]` of the control points in the face's frame, where the matrices
    /// reproduce linear functions of the parameters from this shape on (a regular grid gives
    /// integer coordinates such as `(−1, 2)`); `None` where an irregular vertex of the face's
    /// own domain breaks that (the extraordinary vertex's shape of Catmull-Clark and Loop).
    /// Only the points of [`influence`](Self::influence) are determined; the others are given
    /// 0.
    pub parameters: Option<[Vec<f64>; 2]>,
    /// The shape's symmetry under the reflection that swaps `u` and `v` (corner 0 stays,
    /// corners 1 and the last trade places), if it has it: the limit surface at `(v, u)` puts
    /// the weight of control point `k` at `(u, v)` on control point `mirror[k]` (and swaps the
    /// two derivatives). Found by walking the patch as its mirror image
    /// ([`Mesh::mirrored_patch`]).
    pub mirror: Option<Vec<u32>>,
}

/// The sub-patch matrices of every shape reachable from one [`PatchType`].
#[derive(Clone, Debug, PartialEq)]
pub struct PatchMatrices {
    /// The scheme's name.
    pub scheme: String,
    /// The patch type the shapes start from; [`shapes`](Self::shapes)`[0]` is its shape.
    pub patch_type: PatchType,
    /// The patch radius in rings of faces (Catmull-Clark and Loop: 1).
    pub radius: usize,
    /// The faces' size: 4 (quad splits) or 3 (triangle splits).
    pub face_size: usize,
    /// The shapes; the first is the patch type's.
    pub shapes: Vec<PatchShape>,
    pub(crate) by_signature: HashMap<Vec<u32>, usize>,
    /// The scheme's [`Scheme::identity`].
    identity: u64,
    /// Shape 0's rotation about corner 0, where the canonical patch has one (a smooth interior
    /// type): per control point, the place of the same vertex in the next face's patch.
    rotation: Option<Vec<Option<u32>>>,
}

type CacheKey = (String, PatchType, BoundaryInterpolation);

impl PatchMatrices {
    /// The matrices of `scheme` from `patch_type`, computed once per process and shared.
    /// `boundary` is the boundary rule of boundary patches (interior ones ignore it).
    ///
    /// ```
    /// use subdiv_mesh::BoundaryInterpolation;
    /// use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
    ///
    /// let cc = Builtin::CatmullClark.scheme();
    /// let m = PatchMatrices::of(cc, PatchType::interior(5), BoundaryInterpolation::EdgeOnly)?;
    /// // 2k + 8 control points, and the child at the extraordinary corner keeps the shape.
    /// assert_eq!(m.shapes[0].size, 18);
    /// assert_eq!(m.shapes[0].children[0].shape, 0);
    /// // The regular shape is among the others: 16 control points.
    /// assert!(m.shapes.iter().any(|s| s.size == 16));
    /// # Ok::<(), subdiv_schemes::SchemeError>(())
    /// ```
    ///
    /// # Errors
    /// As [`compute`](Self::compute).
    pub fn of(
        scheme: &Scheme,
        patch_type: PatchType,
        boundary: BoundaryInterpolation,
    ) -> Result<Arc<Self>, SchemeError> {
        static CACHE: OnceLock<Mutex<HashMap<CacheKey, Arc<PatchMatrices>>>> = OnceLock::new();
        let boundary =
            if matches!(patch_type, PatchType::Interior { .. }) { BoundaryInterpolation::EdgeOnly } else { boundary };
        let key = (format!("{scheme:?}"), patch_type, boundary);
        let cache = CACHE.get_or_init(Mutex::default);
        if let Some(found) = cache.lock().unwrap_or_else(std::sync::PoisonError::into_inner).get(&key) {
            return Ok(found.clone());
        }
        // Read or computed outside the lock; a race does it twice and keeps one, both equal.
        let computed = match crate::patch_table::committed(scheme, patch_type, boundary) {
            Some(read) => Arc::new(read),
            None => Arc::new(Self::compute(scheme, patch_type, boundary)?),
        };
        let mut cache = cache.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        Ok(cache.entry(key).or_insert(computed).clone())
    }

    /// Computes the matrices without the cache.
    ///
    /// # Errors
    /// [`SchemeError::FeatureNotSupported`] for boundary
    /// patches of schemes without boundary rules; [`SchemeError::ValenceNotSupported`] below valence 3, with no faces, or when no
    /// patch radius up to [`MAX_PATCH_RADIUS`] is closed under refinement (a user's scheme whose
    /// rules reach further).
    pub fn compute(
        scheme: &Scheme,
        patch_type: PatchType,
        boundary: BoundaryInterpolation,
    ) -> Result<Self, SchemeError> {
        let triangles = match scheme.split() {
            Split::Quad => false,
            Split::Triangle => true,
            Split::Dual | Split::Midedge => {
                let dual = scheme.dual_form().expect("dual and mid-edge schemes have a dual form");
                return Self::compute_dual(&dual, patch_type);
            }
            Split::Sqrt3 => return Self::compute_ternary(scheme, patch_type),
        };
        let (valence, invalid) = match patch_type {
            PatchType::Derived { .. } => {
                return Err(SchemeError::Internal(
                    "a derived patch type is made from a mesh's neighbourhood (MeshPatches), not from a canonical patch"
                        .to_string(),
                ));
            }
            PatchType::Interior { valence, .. } if triangles && valence < 3 => {
                (valence, Some("an interior patch of triangles needs valence 3 or more"))
            }
            PatchType::Interior { valence, .. } if valence < 2 => {
                (valence, Some("an interior patch needs valence 2 or more"))
            }
            PatchType::Interior { valence, sharp } => (
                valence,
                (valence < 64 && sharp.edges >> valence != 0).then_some("a sharp spoke beyond the vertex's valence"),
            ),
            PatchType::Boundary { faces, index, sharp } => (
                faces + 1,
                if faces == 0 || index >= faces {
                    Some("a boundary patch needs one face or more, and an index below the face count")
                } else if sharp.edge(0) || (faces < 64 && sharp.edges >> faces != 0) {
                    Some("sharp spokes of a boundary patch are its interior spokes, 1 to faces − 1")
                } else {
                    None
                },
            ),
        };
        if let Some(reason) = invalid {
            return Err(SchemeError::ValenceNotSupported { scheme: scheme.name.clone(), valence, reason });
        }
        for radius in 1..=MAX_PATCH_RADIUS {
            let (mesh, start) = canonical_mesh(scheme, patch_type, radius, boundary)?;
            let derivation = Derivation::new(scheme, mesh, radius, MAX_LEVELS, RefineOptions::DEFAULT);
            if let Some(found) = derivation.run(start, patch_type)? {
                return Ok(found);
            }
        }
        Err(SchemeError::ValenceNotSupported {
            scheme: scheme.name.clone(),
            valence,
            reason: "the limit surface over a face near this vertex depends on vertices beyond every patch \
                     radius up to 4 (the scheme's rules there reach further than its regular support)",
        })
    }

    /// The dual split's matrices (of mid-edge: its two steps' dual form, [`Scheme::dual_form`]):
    /// smooth interior types only (the split takes no sharpness, and its boundary pieces have no
    /// patches yet), valence 3 or more (an `n`-gon at corner 0; see [`dual_patch`]).
    fn compute_dual(scheme: &Scheme, patch_type: PatchType) -> Result<Self, SchemeError> {
        match patch_type {
            PatchType::Interior { valence, sharp } if valence >= 3 && sharp.is_smooth() => {
                dual::derive(scheme, valence)
            }
            PatchType::Interior { valence, .. } => Err(SchemeError::ValenceNotSupported {
                scheme: scheme.name.clone(),
                valence,
                reason: "a dual patch has a face of 3 or more sides at corner 0, and no sharp features",
            }),
            PatchType::Boundary { faces, .. } => Err(SchemeError::ValenceNotSupported {
                scheme: scheme.name.clone(),
                valence: faces + 1,
                reason: "the dual split's boundary pieces are partial dual quads, which have no patches yet",
            }),
            PatchType::Derived { .. } => {
                Err(SchemeError::Internal("the dual split has no derived configurations".to_string()))
            }
        }
    }

    /// The ternary split's matrices (√3's two steps): smooth types only (the split takes no
    /// sharpness), interior of valence 3 or more, or at a boundary vertex (where the scheme has
    /// its boundary rule).
    fn compute_ternary(scheme: &Scheme, patch_type: PatchType) -> Result<Self, SchemeError> {
        match patch_type {
            PatchType::Interior { valence, sharp } if valence >= 3 && sharp.is_smooth() => {
                ternary::derive(scheme, patch_type)
            }
            PatchType::Interior { valence, .. } => Err(SchemeError::ValenceNotSupported {
                scheme: scheme.name.clone(),
                valence,
                reason: "a √3 patch needs valence 3 or more, and no sharp features",
            }),
            PatchType::Boundary { faces, index, sharp } if faces >= 1 && index < faces && sharp.is_smooth() => {
                if !scheme.has_boundary_rules() {
                    return Err(SchemeError::FeatureNotSupported {
                        scheme: scheme.name.clone(),
                        feature: "boundaries",
                        element: format!("a boundary vertex of {faces} faces"),
                    });
                }
                ternary::derive(scheme, patch_type)
            }
            PatchType::Boundary { faces, .. } => Err(SchemeError::ValenceNotSupported {
                scheme: scheme.name.clone(),
                valence: faces + 1,
                reason: "a √3 boundary patch needs a face of the fan, and no sharp features",
            }),
            PatchType::Derived { .. } => {
                Err(SchemeError::Internal("the √3 split has no derived configurations".to_string()))
            }
        }
    }

    /// The matrices of the configuration of `start`'s face in `mesh` (a level of a real mesh,
    /// its boundary rule applied), with patches of `radius` rings, derived from the face's
    /// neighbourhood as the canonical patches are from theirs, over as many more levels as
    /// its semi-sharp features take to be spent; shape 0 is the face's (from `start`).
    /// `None` if the shapes do not close up within the neighbourhood.
    ///
    /// # Errors
    /// As refinement, for the neighbourhood.
    pub(crate) fn derive(
        scheme: &Scheme,
        mesh: &Mesh,
        start: HalfEdgeId,
        radius: usize,
        options: &RefineOptions,
        patch_type: PatchType,
    ) -> Result<Option<Self>, SchemeError> {
        let face = mesh.face(start);
        // As the canonical meshes: the patch and three rings more, so the rim's rules reach
        // none of the sub-patches.
        let region = mesh.region(&[face], radius + 3).map_err(|e| SchemeError::Internal(e.to_string()))?;
        let inside = region.face_of(face).ok_or_else(|| SchemeError::Internal("a face outside its region".into()))?;
        let start = region.mesh.face_half_edges(inside).nth(mesh.corner(start)).expect("the face keeps its corners");
        let spent = region.mesh.edges().map(|e| region.mesh.edge_sharpness(e));
        let spent = spent.chain(region.mesh.vertices().map(|v| region.mesh.vertex_sharpness(v)));
        let levels = spent.filter(|&s| s < subdiv_mesh::Tags::INFINITELY_SHARP).fold(0.0, f64::max).ceil() as usize;
        Derivation::new(scheme, region.mesh, radius, MAX_LEVELS + levels, *options).run(start, patch_type)
    }

    /// The interior type's shape with this signature (of a patch of `size` control points),
    /// if one of the interior types of the valences it lists has it (an extraordinary valence
    /// first, then the regular one): a shape without sharp features or boundary vertices, as
    /// its matrices and index. Equal signatures have equal matrices, so a derived
    /// configuration's stationary shapes take what was solved (or committed) for the types:
    /// parameters, eigenbases.
    pub fn interior_shape(scheme: &Scheme, signature: &[u32], size: usize) -> Option<(Arc<Self>, usize)> {
        if Patch::signature_has_sharp_features(signature) {
            return None;
        }
        let mut valences = Vec::with_capacity(size);
        for (valence, boundary) in Patch::signature_vertices(signature, size) {
            if boundary {
                return None;
            }
            valences.push(valence as usize);
        }
        let regular = scheme.regular_valence();
        valences.sort_unstable();
        valences.dedup();
        valences.sort_by_key(|&v| v == regular);
        valences.into_iter().filter(|&v| v <= MAX_INTERIOR_LOOKUP).find_map(|v| {
            let m = PatchMatrices::of(scheme, PatchType::interior(v), BoundaryInterpolation::EdgeOnly).ok()?;
            let shape = m.find(signature)?;
            Some((m, shape))
        })
    }

    /// Matrices of `scheme` from `shapes` (read from a table).
    pub(crate) fn from_shapes(
        scheme: &Scheme,
        patch_type: PatchType,
        radius: usize,
        face_size: usize,
        shapes: Vec<PatchShape>,
    ) -> Self {
        let by_signature = shapes.iter().enumerate().map(|(i, s)| (s.signature.clone(), i)).collect();
        Self {
            scheme: scheme.name.clone(),
            patch_type,
            radius,
            face_size,
            shapes,
            by_signature,
            identity: scheme.identity(),
            rotation: canonical_rotation(scheme, patch_type, radius),
        }
    }

    /// The Fourier structure of the matrix of `shape`'s child that keeps its shape and corner 0
    /// (the extraordinary vertex's matrix of a smooth interior type's shape 0), on the control
    /// points that influence the face ([`PatchShape::influence`]): its spectrum from one small
    /// block per frequency ([`RingSpectrum`]). `None` for other shapes and types, and where the
    /// matrix does not commute with the patch's rotation.
    ///
    /// ```
    /// use subdiv_mesh::BoundaryInterpolation;
    /// use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
    ///
    /// let cc = Builtin::CatmullClark.scheme();
    /// let m = PatchMatrices::of(cc, PatchType::interior(7), BoundaryInterpolation::EdgeOnly)?;
    /// let ring = m.ring_spectrum(0).expect("a smooth vertex's ring");
    /// // 1 is an eigenvalue (of frequency 0: the limit position's).
    /// assert!(ring.eigenvalues().any(|(_, z)| (z.re - 1.0).abs() < 1e-12 && z.im.abs() < 1e-12));
    /// # Ok::<(), subdiv_schemes::SchemeError>(())
    /// ```
    pub fn ring_spectrum(&self, shape: usize) -> Option<RingSpectrum> {
        let rotation = self.rotation.as_ref().filter(|_| shape == 0)?;
        let PatchType::Interior { valence, .. } = self.patch_type else { return None };
        let parent = self.shapes.get(shape)?;
        let child =
            parent.children.iter().find(|c| c.shape == shape && c.domain.offset == [0, 0] && !c.domain.flipped)?;
        let mut position = vec![None; parent.size];
        parent.influence.iter().enumerate().for_each(|(i, &k)| position[k as usize] = Some(i));
        let rows: Vec<Vec<(usize, f64)>> = parent
            .influence
            .iter()
            .map(|&k| {
                child.row(k as usize).filter(|e| e.1 != 0.0).filter_map(|(c, w)| Some((position[c]?, w))).collect()
            })
            .collect();
        let turned: Vec<Option<usize>> = parent
            .influence
            .iter()
            .map(|&k| rotation.get(k as usize).copied().flatten().and_then(|r| position[r as usize]))
            .collect();
        RingSpectrum::new(&rows, &turned, valence)
    }

    /// How many children fit along a side of a face: 2 for the binary splits, 3 for √3's
    /// ternary one ([`ChildDomain::scale`]).
    pub fn scale(&self) -> u8 {
        self.shapes.first().and_then(|s| s.children.first()).map_or(2, |c| c.domain.scale)
    }

    /// The [`Scheme::identity`] of the scheme the matrices are of: with the patch type, what
    /// tables derived from them (eigenbases) are keyed by.
    pub fn scheme_identity(&self) -> u64 {
        self.identity
    }

    /// The shape with this signature, if it is among the shapes: how a face of a real mesh
    /// finds its matrices (gather its patch with [`Mesh::patch`] at [`radius`](Self::radius)).
    pub fn find(&self, signature: &[u32]) -> Option<usize> {
        self.by_signature.get(signature).copied()
    }

    /// The child of `shape` that keeps its shape (the one at an extraordinary corner), with
    /// its index, if there is one.
    pub fn keeping(&self, shape: usize) -> Option<(usize, &SubPatch)> {
        self.shapes[shape].children.iter().enumerate().find(|(_, c)| c.shape == shape)
    }
}

/// The canonical mesh of `patch_type` for patches of `radius` rings (a pillow around an
/// interior vertex, an open fan around a boundary one, of `radius + 3` rings), with the boundary
/// rule applied as refinement (and `PatchLevels`) sees a mesh (the corners edge-and-corner
/// makes are in the signatures), and the start of its face at the centre. Binary splits only.
fn canonical_mesh(
    scheme: &Scheme,
    patch_type: PatchType,
    radius: usize,
    boundary: BoundaryInterpolation,
) -> Result<(Mesh, HalfEdgeId), SchemeError> {
    let triangles = scheme.split() == Split::Triangle;
    let rings = radius + 3;
    let mut soup = match patch_type {
        PatchType::Interior { valence, sharp } => crate::canonical::pillow(valence, rings, triangles, sharp),
        PatchType::Boundary { faces, sharp, .. } => crate::canonical::open_fan(faces, rings, triangles, sharp),
        PatchType::Derived { .. } => {
            return Err(SchemeError::Internal("a derived patch type has no canonical mesh".to_string()));
        }
    };
    soup.tags.boundary_interpolation = Some(boundary);
    let mesh = Mesh::build(soup).map_err(|e| SchemeError::Internal(e.to_string()))?;
    let mesh = Refiner::new(&mesh, scheme, 0, &RefineOptions::DEFAULT)?.into_mesh();
    let start = canonical_start(&mesh, patch_type);
    Ok((mesh, start))
}

/// Whether `patch_type`'s canonical patch may have a rotation: a smooth interior type of a
/// binary split.
pub(crate) fn has_rotation(scheme: &Scheme, patch_type: PatchType) -> bool {
    matches!(patch_type, PatchType::Interior { sharp, .. } if sharp.is_smooth())
        && matches!(scheme.split(), Split::Quad | Split::Triangle)
}

/// The rotation of a smooth interior type's canonical patch about its vertex (see
/// [`PatchMatrices::ring_spectrum`]); `None` for other types and splits.
fn canonical_rotation(scheme: &Scheme, patch_type: PatchType, radius: usize) -> Option<Vec<Option<u32>>> {
    if !has_rotation(scheme, patch_type) {
        return None;
    }
    let (mesh, start) = canonical_mesh(scheme, patch_type, radius, BoundaryInterpolation::EdgeOnly).ok()?;
    ring::patch_rotation(&mesh, start, radius)
}

fn split_not_supported(scheme: &Scheme, split: Split) -> SchemeError {
    SchemeError::SplitNotSupported {
        scheme: scheme.name.clone(),
        what: "one step's sub-patches",
        split: match split {
            Split::Sqrt3 => "√3",
            _ => "this",
        },
        reason: "one step's triangles straddle the old ones; two steps split each triangle in nine \
                 (`ternary_child_starts`)",
    }
}

/// The indices of the faces that refining `parent` under a primal `split` makes from `face`, in
/// the engine's (and OpenSubdiv's `Far`) numbering: children are numbered face by face, one per
/// corner for quad splits (N-gons included) and four per triangle for triangle splits (the
/// three corner children, then the middle one). `None` for other splits.
///
/// ```
/// use subdiv_mesh::{shapes, FaceId, Mesh};
/// use subdiv_schemes::{child_faces, Split};
///
/// let prism = Mesh::build(shapes::ngon_prism(5))?;
/// // The two pentagonal caps come first: 5 + 5 children before face 2's 4.
/// assert_eq!(child_faces(Split::Quad, &prism, FaceId::new(2)), Some(10..14));
/// assert_eq!(child_faces(Split::Triangle, &prism, FaceId::new(2)), Some(8..12));
/// assert_eq!(child_faces(Split::Dual, &prism, FaceId::new(2)), None);
/// # Ok::<(), subdiv_mesh::MeshError>(())
/// ```
pub fn child_faces(split: Split, parent: &Mesh, face: FaceId) -> Option<std::ops::Range<usize>> {
    let children = split.primal()?.face_children(parent, face);
    Some(children.start as usize..children.end as usize)
}

/// Where the sub-patches of the patch starting at `start` start in `child`, the mesh the engine
/// refined `parent` into with `scheme`, in the order of [`PatchShape::children`]: the same
/// corner of each child face as `start` is of its face, so that the children's axes follow the
/// parent's whichever corner the patch starts at.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{sub_patch_starts, refine, Builtin, RefineOptions};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let cc = Builtin::CatmullClark.scheme();
/// let refined = refine(&cube, cc, &RefineOptions::DEFAULT)?;
/// let start = cube.face_half_edges(cube.face_ids().next().unwrap()).next().unwrap();
/// let children = sub_patch_starts(cc, &cube, start, &refined)?;
/// // The first child starts where the parent does.
/// assert_eq!(refined.origin(children[0]), cube.origin(start));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`SchemeError::FaceNotSupported`] for faces other than quads (quad splits) or triangles
/// (triangle splits), [`SchemeError::SplitNotSupported`] for other splits.
pub fn sub_patch_starts(
    scheme: &Scheme,
    parent: &Mesh,
    start: HalfEdgeId,
    child: &Mesh,
) -> Result<Vec<HalfEdgeId>, SchemeError> {
    let face = parent.face(start);
    let size = parent.face_size(face);
    let expected = match scheme.split() {
        Split::Quad => 4,
        Split::Triangle => 3,
        split => return Err(split_not_supported(scheme, split)),
    };
    if size != expected {
        return Err(SchemeError::FaceNotSupported { scheme: scheme.name.clone(), face, size, expected });
    }
    // Child `j` has corner `j` of the parent at its own corner `j` (the middle triangle starts
    // at the midpoint of side 1), so the rotation of `start` carries over.
    let first_corner = parent.face_half_edges(face).next().expect("faces have corners");
    let rotation = start.index() - first_corner.index();
    let children = child_faces(scheme.split(), parent, face).expect("a primal split");
    Ok((0..children.len())
        .map(|j| {
            let corner = if j < size { (j + rotation) % size } else { j };
            let child_face = FaceId::new((children.start + corner) as u32);
            child.face_half_edges(child_face).nth(rotation).expect("children have as many corners as the parent")
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::derivation::{influence_sets, parameter_coordinates};
    use super::*;
    use crate::Builtin;

    fn matrices(builtin: Builtin, patch_type: PatchType) -> Arc<PatchMatrices> {
        PatchMatrices::of(builtin.scheme(), patch_type, BoundaryInterpolation::EdgeOnly).unwrap()
    }

    #[test]
    fn smooth_shapes_are_influenced_by_every_control_point() {
        for (builtin, patch_type) in [
            (Builtin::CatmullClark, PatchType::interior(5)),
            (Builtin::CatmullClark, PatchType::boundary(4, 1)),
            (Builtin::Loop, PatchType::interior(7)),
            (Builtin::Loop, PatchType::boundary(4, 0)),
        ] {
            for shape in &matrices(builtin, patch_type).shapes {
                assert_eq!(shape.influence, (0..shape.size as u32).collect::<Vec<_>>(), "{builtin:?} {patch_type:?}");
            }
        }
    }

    #[test]
    fn a_bilinear_face_is_influenced_by_its_corners_alone_and_reproduces_their_parameters() {
        for patch_type in
            [PatchType::interior(3), PatchType::regular(Builtin::Bilinear.scheme()), PatchType::boundary(4, 2)]
        {
            for shape in &matrices(Builtin::Bilinear, patch_type).shapes {
                assert_eq!(shape.influence, [0, 1, 2, 3], "{patch_type:?}");
                let [u, v] = shape.parameters.as_ref().expect("bilinear reproduces linear functions everywhere");
                let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
                for k in 0..shape.size {
                    let want = corners.get(k).copied().unwrap_or((0.0, 0.0));
                    assert!((u[k] - want.0).abs() < 1e-12 && (v[k] - want.1).abs() < 1e-12, "{patch_type:?} {k}");
                }
            }
        }
    }

    /// The regular Catmull-Clark shape with one more control point that reaches no face, as a
    /// point across an infinitely sharp edge would: each child's copy of it is the mean of the
    /// parent's copy and the child's corner, so that its parameter is anything at all.
    #[test]
    fn points_without_influence_leave_the_parameters_unique_and_zero() {
        let regular = matrices(Builtin::CatmullClark, PatchType::regular(Builtin::CatmullClark.scheme()));
        let mut shapes = regular.shapes.clone();
        for shape in &mut shapes {
            shape.size += 1;
            for (c, child) in shape.children.iter_mut().enumerate() {
                let (rows, columns) = (child.rows() + 1, child.columns() + 1);
                let mut entries = vec![0.0; rows * columns];
                for r in 0..child.rows() {
                    entries[r * columns..r * columns + child.columns()].copy_from_slice(&child.dense_row(r));
                }
                entries[child.rows() * columns + child.columns()] = 0.5;
                entries[child.rows() * columns + c] = 0.5;
                *child = SubPatch::from_entries(child.shape, child.domain, rows, entries);
            }
        }
        let influence = influence_sets(&shapes, 4);
        // Every shape reaching the point reads it from no row of a face's set.
        let size = shapes[0].size as u32;
        for (shape, set) in shapes.iter_mut().zip(&influence) {
            assert_eq!(*set, (0..size - 1).collect::<Vec<_>>());
            shape.influence = set.clone();
        }
        let [u, v] = parameter_coordinates(&shapes, 0).expect("unique on the influencing points");
        let [ru, rv] = regular.shapes[0].parameters.clone().unwrap();
        assert_eq!((u[16], v[16]), (0.0, 0.0));
        for k in 0..16 {
            assert!((u[k] - ru[k]).abs() < 1e-12 && (v[k] - rv[k]).abs() < 1e-12, "{k}");
        }
        // Asked to determine the free point too, the system is singular.
        for shape in &mut shapes {
            shape.influence = (0..size).collect();
        }
        assert!(parameter_coordinates(&shapes, 0).is_none());
    }
}
