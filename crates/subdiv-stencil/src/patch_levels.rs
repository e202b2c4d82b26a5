//! The refinement levels a mesh's faces need before each has a patch shape: refined locally
//! (the faces that descend and the rings their children's patches reach), with each level's
//! stencils over the level above.

use subdiv_mesh::{FaceId, Mesh};
use subdiv_schemes::{
    DerivedConfigurations, FoundPatch, LocalRefinement, MAX_PATCH_RADIUS, MeshPatches, RefineOptions, Refiner, Scheme,
    Split, Stencils, child_faces, ternary_refine,
};

use crate::{Dyadic, FaceDomain, Layout, PatchFrame, StencilError};

/// Refinement levels after which every face's patch must have a shape: semi-sharp features
/// below sharpness 10 are spent after at most 10 levels (each level takes 1), and irregular
/// vertices, N-gons and features in one patch are apart within 3 more.
const MAX_LEVELS: usize = 16;

/// The first level whose faces at semi-sharp features take derived configurations
/// ([`MeshPatches::with_derived`]) instead of descending: after two levels every face holds at
/// most one extraordinary vertex, so the faces along a crease repeat a few configurations and
/// each is derived once. Measured (first tessellation at rate 8, one thread, `subdiv
/// tessellate`): deriving from level 0 / 1 / 2 / 3 / 4, catmark_car 1.13 / 0.29 / 0.19 / 0.20 /
/// 0.26 s, catmark_rook 1.42 / 0.86 / 0.24 / 0.19 / 0.24 s, catmark_bishop 0.62 / 0.65 / 0.32 /
/// 0.30 / 0.32 s; never deriving (descending until the sharpness is spent) 0.67, 2.1 and
/// 0.33 s. From level 0 most configurations are met once (the car derives 407 for 1,249 faces).
const DERIVED_FROM_LEVEL: usize = 2;

/// How a face of one level of [`PatchLevels`] is evaluated.
#[derive(Clone, Debug)]
pub(crate) enum Resolution {
    /// Through its patch.
    Patch(FoundPatch),
    /// Through its children, these faces of the next level.
    Children(std::ops::Range<usize>),
    /// A dual split's quad with boundary sides (bit `k` for side `k`), through the children
    /// (its corners) of the pieces that stretch across it ([`Layout::DualBoundaryQuad`]).
    DualBoundary(std::ops::Range<usize>, u8),
    /// Not at all: a hole (tagged, or made by the boundary rule `none`).
    Hole,
}

/// One level of the refined mesh and how its faces of interest are evaluated.
#[derive(Debug)]
pub(crate) struct Level {
    /// The level's mesh: its vertices are the patches' control points, and (primal splits) its
    /// faces the level's faces.
    pub(crate) mesh: Mesh,
    /// Per face of the level, how it is evaluated if points can reach it (every face on level
    /// 0); dense, since looking a face up is on every evaluation's path.
    pub(crate) faces: Vec<Option<Resolution>>,
    /// Per face, the corner its patch starts at, where the faces are not `mesh`'s (the dual
    /// split's levels below the input: face corners and their children, see `dual_levels`);
    /// empty where they are, and the patch's start half-edge says it.
    rotations: Vec<u8>,
}

impl Level {
    /// A level of `mesh` with nothing resolved yet: one face per face of `mesh`, or `virtual_faces`
    /// faces that are not `mesh`'s (each with a rotation).
    pub(crate) fn new(mesh: Mesh, virtual_faces: Option<usize>) -> Self {
        let faces = vec![None; virtual_faces.unwrap_or(mesh.face_count())];
        let rotations = virtual_faces.map_or_else(Vec::new, |n| vec![0; n]);
        Self { mesh, faces, rotations }
    }

    /// Resolves virtual face `face` by `resolution`, a patch starting at corner `rotation`.
    pub(crate) fn set(&mut self, face: usize, resolution: Resolution, rotation: usize) {
        self.faces[face] = Some(resolution);
        self.rotations[face] = rotation as u8;
    }
}

/// How a face of one level of [`PatchLevels`] reaches the limit surface.
#[derive(Clone, Debug)]
pub enum Resolved<'a> {
    /// Through its patch, which starts at corner `frame` of the face.
    Patch {
        /// The level's mesh (the patch's control points are its vertices).
        mesh: &'a Mesh,
        /// The patch, its shape and its matrices.
        patch: &'a FoundPatch,
        /// The face's frame in the patch's.
        frame: PatchFrame,
    },
    /// Through its children on the next level: the face's point `p` lies in child
    /// `layout.child_of(p).0`, which is face `children.start + that` of the next level.
    Children {
        /// The children's face numbers on the next level.
        children: std::ops::Range<usize>,
        /// How its points map to its children's.
        layout: Layout,
    },
    /// Not at all: the face is a hole.
    Hole,
}

/// A mesh's faces and, for each, the patch (with its sub-patch matrices) that evaluates it,
/// on the level of refinement where it has one: a face whose patch has a shape in the scheme's
/// [`PatchMatrices`] is resolved on level 0; a face without one — an N-gon under a quad split,
/// or a face whose patch holds two irregular vertices — is refined, and its children are
/// resolved on the next level, as often as needed.
///
/// This is the part of [`LimitEvaluator`] that does not depend on how a patch is evaluated:
/// exact stencils there, eigenbases in `subdiv-eval`, quadtrees in `subdiv-tess`.
///
/// ```
/// use subdiv_mesh::{shapes, FaceId, Mesh};
/// use subdiv_schemes::{Builtin, RefineOptions};
/// use subdiv_stencil::{PatchLevels, Resolved};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let levels = PatchLevels::new(Builtin::CatmullClark.scheme(), &cube, &RefineOptions::DEFAULT)?;
/// // Every corner of the cube has valence 3: its faces are resolved by their children.
/// assert!(matches!(levels.resolve(0, FaceId::new(0)), Some(Resolved::Children { .. })));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct PatchLevels {
    split: Split,
    levels: Vec<Level>,
    /// `stencils[l]`: level `l + 1`'s vertices over level `l`'s.
    stencils: Vec<Stencils>,
}

/// The next level: a part of the current one refined (or all of it), its stencils over the
/// whole current level, and the faces each refined face becomes.
struct Next {
    mesh: Mesh,
    stencils: Stencils,
    /// Per face of `refine` (in its order), its children on the next level.
    children: Vec<std::ops::Range<usize>>,
}

impl Next {
    /// Refines the faces `refine` of `current` and `rings` rings of faces around them.
    fn of(
        scheme: &Scheme,
        current: &Mesh,
        refine: &[FaceId],
        rings: usize,
        options: &RefineOptions,
    ) -> Result<Self, StencilError> {
        let local = LocalRefinement::new(scheme, current, refine, rings, options)?;
        let children = refine
            .iter()
            .map(|&f| {
                let (mesh, face) =
                    local.split_parent(current, f).ok_or_else(|| internal(f, "the region lacks a face it refines"))?;
                Ok(children(mesh, scheme.split(), face))
            })
            .collect::<Result<_, StencilError>>()?;
        Ok(Self { mesh: local.mesh, stencils: local.stencils, children })
    }

    /// √3's next level: two steps of the whole of `current` (it has no rules for a part's
    /// border) as one ternary split, face `f`'s children at `9f..9f + 9`.
    fn ternary(
        scheme: &Scheme,
        current: &Mesh,
        refine: &[FaceId],
        options: &RefineOptions,
    ) -> Result<Self, StencilError> {
        let (mesh, stencils) = ternary_refine(scheme, current, options)?;
        let children = refine.iter().map(|f| 9 * f.index()..9 * f.index() + 9).collect();
        Ok(Self { mesh, stencils, children })
    }
}

impl PatchLevels {
    /// Prepares `mesh` under `scheme` with the boundary rule and options of refinement
    /// (`options`, else the mesh's tags): finds every face's patch, refining the mesh as often
    /// as faces without a patch shape need (an N-gon once; the cube's faces twice; a face at a
    /// semi-sharp edge of sharpness `s` until `s` is spent, ⌈s⌉ times, or at most to
    /// level 2, where the rest is a derived configuration's patch, then as its
    /// stationary features need). Each level refines only the faces that need it and
    /// as many rings of faces around them as their children's patches and rules reach, so a level costs as much as those faces, not the
    /// mesh (a semi-sharp crease of sharpness 6 on a car would otherwise be 4^6 times the
    /// car). Schemes without crease rules refine the whole mesh (a part of it has a boundary
    /// they cannot refine).
    ///
    /// # Errors
    /// [`StencilError::Scheme`] for a scheme without sub-patch matrices for a valence
    /// (`ValenceNotSupported`), a
    /// face the scheme does not take, or boundaries a scheme has no rules for;
    /// [`StencilError::NoPatch`] if a face finds no patch within 16 levels (an internal error).
    pub fn new(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions) -> Result<Self, StencilError> {
        Self::build(scheme, mesh, options, Some(DERIVED_FROM_LEVEL))
    }

    /// As [`new`](Self::new), but every face at a semi-sharp feature descends until the
    /// sharpness is spent, so that every patch has a stationary shape (a shape of the
    /// canonical types): for consumers that take only those (the quadtree's error bounds need
    /// bicubic patches and extraordinary ones).
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn descending(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions) -> Result<Self, StencilError> {
        Self::build(scheme, mesh, options, None)
    }

    /// [`new`](Self::new) with derived configurations from level `derived_from` (`None`:
    /// never).
    fn build(
        scheme: &Scheme,
        mesh: &Mesh,
        options: &RefineOptions,
        derived_from: Option<usize>,
    ) -> Result<Self, StencilError> {
        let patch_size = match scheme.split() {
            Split::Quad => 4,
            Split::Triangle | Split::Sqrt3 => 3,
            // Mid-edge's levels are those of its two steps as one (`Scheme::dual_form`).
            Split::Dual | Split::Midedge => {
                let dual = scheme.dual_form().expect("dual and mid-edge schemes have a dual form");
                let (levels, stencils) = crate::dual_levels::dual_levels(&dual, &scheme.name, mesh, options)?;
                return Ok(Self { split: scheme.split(), levels, stencils });
            }
        };
        // Level 0 with the boundary rule applied (boundary edges sharp, holes of `none`), without
        // the face-varying channels: the levels here are the positions' alone.
        let mut base = Refiner::new(mesh, scheme, 0, options)?.into_mesh();
        base.clear_channels();
        let mut levels = Vec::new();
        let mut stencils = Vec::new();
        let mut wanted: Vec<FaceId> = base.face_ids().collect();
        let derived = DerivedConfigurations::default();
        let mut current = base;
        loop {
            let patches = if wanted.len() == current.face_count() {
                MeshPatches::new(scheme, &current, options)?
            } else {
                MeshPatches::near(scheme, &current, options, wanted.iter().copied())?
            };
            let patches =
                patches.with_derived(derived_from.is_some_and(|from| levels.len() >= from).then(|| derived.clone()));
            let mut faces: Vec<Option<Resolution>> = vec![None; current.face_count()];
            let mut refine = Vec::new();
            for &f in &wanted {
                if current.is_hole(f) {
                    faces[f.index()] = Some(Resolution::Hole);
                } else if let Some(found) =
                    (current.face_size(f) == patch_size).then(|| patches.find(&current, f)).flatten()
                {
                    faces[f.index()] = Some(Resolution::Patch(found));
                } else {
                    refine.push(f);
                }
            }
            if refine.is_empty() {
                levels.push(Level { mesh: current, faces, rotations: Vec::new() });
                break;
            }
            if levels.len() + 1 == MAX_LEVELS {
                return Err(StencilError::NoPatch { face: refine[0].index(), levels: MAX_LEVELS });
            }
            // The rings of this level whose refinement makes the children's patches right. A
            // child's patch of radius 1 (Catmull-Clark's, Loop's) holds only the vertex points of
            // its parent's corners, the edge points of the edges at them and the face points of
            // the faces around them, whose rules read the faces at the corners: one ring (points
            // further out, made wrong by the region's border rules, are in no wanted patch).
            // Wider patches reach `radius` rings of the next level, inside as many of this one,
            // and those points' rules one ring more.
            let rings = match patches.max_radius() {
                Some(1) => 1,
                radius => radius.unwrap_or(MAX_PATCH_RADIUS) + 1,
            };
            let next = if scheme.split() == Split::Sqrt3 {
                Next::ternary(scheme, &current, &refine, options)?
            } else {
                Next::of(scheme, &current, &refine, rings, options)?
            };
            let mut next_wanted = Vec::new();
            for (&f, children) in refine.iter().zip(next.children) {
                next_wanted.extend(children.clone().map(|c| FaceId::new(c as u32)));
                faces[f.index()] = Some(Resolution::Children(children));
            }
            next_wanted.sort_unstable();
            levels.push(Level { mesh: current, faces, rotations: Vec::new() });
            stencils.push(next.stencils);
            current = next.mesh;
            wanted = next_wanted;
        }
        Ok(Self { split: scheme.split(), levels, stencils })
    }

    /// The scheme's split.
    pub fn split(&self) -> Split {
        self.split
    }

    /// The number of levels (1 when every face has a patch on the mesh itself).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// The mesh of `level`: level 0 is the input with the boundary rule applied (same faces,
    /// same vertices), level `l + 1` is the part of level `l` that needed it refined once
    /// (see [`new`](Self::new); its vertices are given over level `l`'s by
    /// [`stencils`](Self::stencils)).
    ///
    /// # Panics
    /// If `level >= level_count()`.
    pub fn mesh(&self, level: usize) -> &Mesh {
        &self.levels[level].mesh
    }

    /// The refinement stencils between the levels: entry `l` gives level `l + 1`'s vertices
    /// over level `l`'s (empty when every face has a patch on level 0). Applied from the cage
    /// down, they give every level's control points of a moved cage.
    pub fn stencils(&self) -> &[Stencils] {
        &self.stencils
    }

    /// The number of faces of the input mesh.
    pub fn face_count(&self) -> usize {
        self.levels[0].mesh.face_count()
    }

    /// How `face` of `level` reaches the surface; `None` for a face that no point of the input
    /// reaches on that level (or a level or face out of range).
    pub fn resolve(&self, level: usize, face: FaceId) -> Option<Resolved<'_>> {
        let l = self.levels.get(level)?;
        Some(match l.faces.get(face.index())?.as_ref()? {
            Resolution::Hole => Resolved::Hole,
            Resolution::Children(children) => Resolved::Children {
                children: children.clone(),
                layout: Layout::Domain(if level == 0 {
                    FaceDomain::of(self.split, l.mesh.face_size(face)).unwrap_or(FaceDomain::Quad)
                } else if self.split == Split::Triangle {
                    FaceDomain::Triangle
                } else if self.split == Split::Sqrt3 {
                    FaceDomain::Ternary
                } else {
                    FaceDomain::Quad
                }),
            },
            &Resolution::DualBoundary(ref children, sides) => {
                Resolved::Children { children: children.clone(), layout: Layout::DualBoundaryQuad { sides } }
            }
            Resolution::Patch(found) => {
                let frame = match l.rotations.get(face.index()) {
                    Some(&rotation) => PatchFrame::new(4, usize::from(rotation)),
                    None => {
                        let first = l.mesh.face_half_edges(face).next().expect("faces have corners");
                        PatchFrame::new(l.mesh.face_size(face), found.start.index() - first.index())
                    }
                };
                Resolved::Patch { mesh: &l.mesh, patch: found, frame }
            }
        })
    }

    /// Whether `face` has a limit surface (it is not a hole).
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn has_surface(&self, face: FaceId) -> Result<bool, StencilError> {
        Ok(!matches!(self.resolution(face)?, Resolution::Hole))
    }

    /// The domain of `face` of the input mesh.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn domain(&self, face: FaceId) -> Result<FaceDomain, StencilError> {
        self.resolution(face)?;
        let size = self.levels[0].mesh.face_size(face);
        // `new` accepted the split, and refinement accepted every face's size.
        Ok(FaceDomain::of(self.split, size).unwrap_or(FaceDomain::Quad))
    }

    fn resolution(&self, face: FaceId) -> Result<&Resolution, StencilError> {
        self.levels[0]
            .faces
            .get(face.index())
            .and_then(Option::as_ref)
            .ok_or(StencilError::FaceOutOfRange { face: face.index(), faces: self.face_count() })
    }

    /// Checks that `point` is a parameter of `face` with a surface.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::OutsideFace`] for a point outside the
    /// face's domain, [`StencilError::NoSurface`] for a hole.
    pub fn check(&self, face: FaceId, point: Dyadic) -> Result<(), StencilError> {
        let domain = self.domain(face)?;
        if !domain.contains(point) {
            let (u, v) = point.to_f64();
            return Err(StencilError::OutsideFace {
                face: face.index(),
                u: format!("{u:?}"),
                v: format!("{v:?}"),
                domain: domain.describe(),
            });
        }
        if !self.has_surface(face)? {
            return Err(StencilError::NoSurface { face: face.index() });
        }
        Ok(())
    }
}

pub(crate) fn internal(face: FaceId, detail: &str) -> StencilError {
    StencilError::Internal(format!("limit evaluation of {face}: {detail}"))
}

/// The child faces of `face` ([`child_faces`]; `split` is a primal one here).
pub(crate) fn children(mesh: &Mesh, split: Split, face: FaceId) -> std::ops::Range<usize> {
    child_faces(split, mesh, face).unwrap_or(0..0)
}
