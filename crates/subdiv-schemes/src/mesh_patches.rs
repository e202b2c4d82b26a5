//! A mesh's patches: the patch types its vertices have ([`PatchMatrices`] for each, derived on
//! demand) and the lookup from a face to its shape.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use subdiv_mesh::{BoundaryInterpolation, CreaseMethod, FaceId, HalfEdgeId, Mesh, Patch, Sharpness, VertexId};

use crate::patch::{MAX_PATCH_RADIUS, PatchMatrices, PatchType, SharpFeatures, has_rotation};
use crate::{RefineOptions, Scheme, SchemeError, ValenceLimit};

/// The sub-patch matrices a mesh's faces need — one [`PatchMatrices`] per patch type at its
/// vertices (interior valences, and every place in every boundary fan) — and the lookup from a
/// face to its shape.
#[derive(Clone, Debug)]
pub struct MeshPatches {
    tables: Vec<Arc<PatchMatrices>>,
    /// Per patch radius, every table's shapes by signature.
    lookup: Vec<(usize, ShapeLookup)>,
    /// What deriving the configurations at semi-sharp features takes.
    derive: Derive,
    /// Where faces at semi-sharp features find derived configurations (`None`: they descend).
    derived: Option<DerivedConfigurations>,
}

/// Shapes by signature: (table, shape).
/// One radius's shapes by signature (table and shape), and what their faces have: the corners,
/// each `(valence, boundary)` from corner 0 (a signature's first vertices), and whether a point
/// of the patch is on a boundary. A rotation whose face has corners no shape has, or (radius 1)
/// a boundary point where no shape with its corners has one, is passed over without walking its
/// patch: at a vertex of valence N each walk visits 2N + 8 points, all but one rotation of a face
/// there match nothing, and a face whose patch reaches a boundary at its far side matches nothing
/// until a finer level.
#[derive(Clone, Debug, Default)]
struct ShapeLookup {
    shapes: hashbrown::HashMap<Vec<u32>, (usize, usize)>,
    /// Per corners, whether shapes with them have patches without a boundary point, and with.
    corners: hashbrown::HashMap<Vec<(u32, bool)>, [bool; 2]>,
}

/// Whether a point of the radius-1 patch of `face` (the vertices of the faces at its corners) is
/// on a boundary.
fn reaches_a_boundary(mesh: &Mesh, face: FaceId) -> bool {
    mesh.face_vertices(face).iter().any(|&corner| {
        mesh.is_boundary_vertex(corner)
            || mesh.vertex_faces(corner).any(|f| mesh.face_vertices(f).iter().any(|&v| mesh.is_boundary_vertex(v)))
    })
}

/// The corners of `start`'s face from `start`'s origin, as a signature lists them.
fn face_corners(mesh: &Mesh, start: HalfEdgeId) -> Vec<(u32, bool)> {
    let size = mesh.face_size(mesh.face(start));
    std::iter::successors(Some(start), |&h| Some(mesh.next(h)))
        .take(size)
        .map(|h| {
            let v = mesh.origin(h);
            (mesh.valence(v) as u32, mesh.is_boundary_vertex(v))
        })
        .collect()
}

/// The scheme and rules a configuration at semi-sharp features is derived under.
#[derive(Clone, Debug)]
struct Derive {
    scheme: Scheme,
    options: RefineOptions,
    key: RulesKey,
}

/// What, besides its signature, makes a configuration's matrices: the scheme (its identity)
/// and the rules refinement applies there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct RulesKey {
    scheme: u64,
    boundary: BoundaryInterpolation,
    crease_method: CreaseMethod,
    smooth_triangles: bool,
}

/// The configurations at semi-sharp features derived so far ([`PatchType::Derived`]), shared
/// by the [`MeshPatches`] of one preparation (`PatchLevels` keeps one for all its levels), by
/// rules and signature: the matrices of one and its shape there (every shape of a derivation is
/// listed, so a face whose configuration is another's after a few levels finds it), or `None`
/// where the derivation did not close up (such faces descend instead). One per preparation,
/// not per process: a mesh's bits do not depend on what the process prepared before, and the
/// memory goes with the preparation. Cloning shares it.
#[derive(Clone, Debug, Default)]
pub struct DerivedConfigurations {
    shapes: Arc<Mutex<DerivedShapes>>,
}

type DerivedShapes = HashMap<(RulesKey, Vec<u32>), Option<(Arc<PatchMatrices>, usize)>>;

impl DerivedConfigurations {
    /// How many configurations were derived (shape 0 of each).
    pub fn len(&self) -> usize {
        let shapes = self.shapes.lock().unwrap_or_else(PoisonError::into_inner);
        shapes.values().filter(|found| matches!(found, Some((_, 0)))).count()
    }

    /// Whether none was.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A patch's control points: sixteen (a bicubic patch's) held inline, more (an extraordinary
/// vertex's ring) on the heap. A mesh's patches are mostly of sixteen points or fewer, and a
/// heap allocation per face was 80 bytes of a million-face grid's patches, each read through a
/// pointer.
pub type PatchVertices = smallvec::SmallVec<[VertexId; 16]>;

/// A face's patch, found by [`MeshPatches::find`]: the rotation it starts at, its control
/// points and its matrices.
#[derive(Clone, Debug)]
pub struct FoundPatch {
    /// The half-edge the patch starts at (corner 0 of its domain).
    pub start: HalfEdgeId,
    /// The control points, in [`Mesh::patch`] order.
    pub vertices: PatchVertices,
    /// The matrices holding the shape.
    pub matrices: Arc<PatchMatrices>,
    /// The shape, an index into the matrices' shapes.
    pub shape: usize,
}

impl MeshPatches {
    /// The matrices for `mesh`'s faces under `scheme`, with the boundary rule refinement would
    /// use (`options`, else the mesh's tags).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::{refine_uniform, Builtin, MeshPatches, RefineOptions};
    ///
    /// let cc = Builtin::CatmullClark.scheme();
    /// let cube = Mesh::build(shapes::cube())?;
    /// // After one refinement a patch can still hold two of the cube's corners; after two,
    /// // every face has a shape.
    /// let once = refine_uniform(&cube, cc, 1, &RefineOptions::DEFAULT)?;
    /// let patches = MeshPatches::new(cc, &once, &RefineOptions::DEFAULT)?;
    /// assert!(patches.find(&once, once.face_ids().next().unwrap()).is_none());
    /// let twice = refine_uniform(&cube, cc, 2, &RefineOptions::DEFAULT)?;
    /// let patches = MeshPatches::new(cc, &twice, &RefineOptions::DEFAULT)?;
    /// assert!(twice.face_ids().all(|f| patches.find(&twice, f).is_some()));
    /// // Face 0 has a corner of the cube (valence 3): 2k + 8 control points.
    /// assert_eq!(patches.find(&twice, twice.face_ids().next().unwrap()).unwrap().vertices.len(), 14);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`PatchMatrices::of`], for the first vertex whose patch type fails.
    pub fn new(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions) -> Result<Self, SchemeError> {
        Self::for_vertices(scheme, mesh, options, mesh.vertices())
    }

    /// The matrices for the faces `faces` of `mesh` only: the patch types at the vertices
    /// their patches may hold (within 3 rings, the largest patch radius). Refining a part of a
    /// mesh leaves a rim whose vertices no face asked for needs.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn near(
        scheme: &Scheme,
        mesh: &Mesh,
        options: &RefineOptions,
        faces: impl IntoIterator<Item = FaceId>,
    ) -> Result<Self, SchemeError> {
        let mut corners: Vec<VertexId> =
            faces.into_iter().flat_map(|f| mesh.face_vertices(f).iter().copied()).collect();
        corners.sort_unstable();
        corners.dedup();
        Self::for_vertices(scheme, mesh, options, mesh.vertices_within(&corners, MAX_PATCH_RADIUS))
    }

    fn for_vertices(
        scheme: &Scheme,
        mesh: &Mesh,
        options: &RefineOptions,
        vertices: impl IntoIterator<Item = VertexId>,
    ) -> Result<Self, SchemeError> {
        let boundary = options.boundary_for(mesh);
        let mut types = Vec::new();
        for v in vertices.into_iter().filter(|&v| !mesh.is_isolated(v)) {
            let valence = mesh.valence(v);
            let before = types.len();
            vertex_types(scheme, mesh, v, &mut types)?;
            // Semi-sharp vertices have no types here: their configurations are derived, densely.
            let smooth = types.len() > before && types[before..].iter().all(|&t| has_rotation(scheme, t));
            let kind = if smooth { ValenceLimit::Smooth } else { ValenceLimit::Dense };
            let limit = kind.of(options);
            if valence > limit {
                return Err(SchemeError::ValenceTooLarge { vertex: v, valence, limit, kind });
            }
        }
        let mut seen = std::collections::HashSet::new();
        types.retain(|t| seen.insert(*t));
        let tables: Vec<Arc<PatchMatrices>> =
            types.into_iter().map(|t| PatchMatrices::of(scheme, t, boundary)).collect::<Result<_, _>>()?;
        // One lookup over every table, per radius; the first table with a shape keeps it
        // (equal signatures have equal matrices).
        let mut lookup: Vec<(usize, ShapeLookup)> = Vec::new();
        for (t, table) in tables.iter().enumerate() {
            let at = match lookup.iter().position(|(r, _)| *r == table.radius) {
                Some(at) => at,
                None => {
                    lookup.push((table.radius, ShapeLookup::default()));
                    lookup.len() - 1
                }
            };
            for (signature, &shape) in &table.by_signature {
                let found = &mut lookup[at].1;
                found.shapes.entry(signature.clone()).or_insert((t, shape));
                let corners = signature.first().map_or(0, |&size| size as usize);
                let vertices = || Patch::signature_vertices(signature, table.shapes[shape].size);
                let flags = found.corners.entry(vertices().take(corners).collect()).or_default();
                flags[usize::from(vertices().any(|(_, boundary)| boundary))] = true;
            }
        }
        let rules = options.rules_for(mesh);
        let key = RulesKey {
            scheme: scheme.identity(),
            boundary,
            crease_method: rules.crease_method,
            smooth_triangles: rules.smooth_triangles,
        };
        Ok(Self { tables, lookup, derive: Derive { scheme: scheme.clone(), options: *options, key }, derived: None })
    }

    /// Sets where faces at semi-sharp features find (and enter) derived configurations
    /// (default `None`: they descend). Deriving pays where configurations repeat:
    /// `PatchLevels` asks from its level 2 on.
    pub fn with_derived(mut self, derived: Option<DerivedConfigurations>) -> Self {
        self.derived = derived;
        self
    }

    /// The largest patch radius of the types found, `None` when there are none.
    pub fn max_radius(&self) -> Option<usize> {
        self.lookup.iter().map(|(r, _)| *r).max()
    }

    /// The patch of `face` in the first rotation whose shape is known, or `None` (a face whose
    /// patch holds two irregular vertices, which a further refinement separates). A face with
    /// a semi-sharp feature at a corner (or on an edge at one) has its own configuration's
    /// matrices ([`PatchType::Derived`], derived once per configuration in a
    /// [`DerivedConfigurations`]) if
    /// [`with_derived`](Self::with_derived) asks for them, else `None` (refinement spends the
    /// sharpness).
    pub fn find(&self, mesh: &Mesh, face: FaceId) -> Option<FoundPatch> {
        // No table holds a semi-sharp feature: such a face's configuration has matrices of its
        // own, derived once per preparation.
        if mesh.near_semi_sharp(face) {
            return self.derived.as_ref().and_then(|derived| self.derived(derived, mesh, face));
        }
        // One buffer for every rotation and radius tried: most walks are looked up and dropped.
        let (mut patch, mut boundary) = (Patch::default(), None);
        mesh.face_half_edges(face).find_map(|start| self.at_with(mesh, start, &mut patch, &mut boundary))
    }

    /// The patch of `face`, which has semi-sharp features at its corners, from the derived
    /// configurations: a rotation whose configuration was derived before, else one derived
    /// now from the face's neighbourhood (rotation 0). `None` for schemes with patches of
    /// another radius than 1 (the features' reach is shown for radius 1) and where the
    /// derivation fails: the face then descends until the sharpness is spent.
    fn derived(&self, derived: &DerivedConfigurations, mesh: &Mesh, face: FaceId) -> Option<FoundPatch> {
        if self.max_radius() != Some(1) {
            return None;
        }
        let known = |signature: &Vec<u32>| {
            let shapes = derived.shapes.lock().unwrap_or_else(PoisonError::into_inner);
            shapes.get(&(self.derive.key, signature.clone())).cloned()
        };
        let mut patch = Patch::default();
        for start in mesh.face_half_edges(face) {
            mesh.patch_into(start, 1, &mut patch);
            if let Some(found) = known(&patch.signature) {
                let (matrices, shape) = found?;
                return Some(FoundPatch { start, vertices: PatchVertices::from_vec(patch.vertices), matrices, shape });
            }
        }
        // From the corner most likely irregular: a shape's irregular fixed point (an
        // extraordinary, boundary or sharp vertex) must be its corner 0, where the limit's
        // tangents are read, as the canonical patches have it.
        let regular = self.derive.scheme.regular_valence();
        let irregular = |h: HalfEdgeId| {
            let v = mesh.origin(h);
            mesh.valence(v) != regular
                || mesh.is_boundary_vertex(v)
                || mesh.vertex_sharpness(v) > 0.0
                || mesh.outgoing(v).any(|o| Sharpness::of(mesh.edge_sharpness(mesh.edge(o))) == Sharpness::Infinite)
        };
        let start = mesh.face_half_edges(face).find(|&h| irregular(h)).or(mesh.face_half_edges(face).next())?;
        mesh.patch_into(start, 1, &mut patch);
        let id = crate::patch::next_derived_id();
        let Derive { scheme, options, key } = &self.derive;
        let fixed_points_at_corner_0 =
            |m: &PatchMatrices| (0..m.shapes.len()).all(|s| m.keeping(s).is_none_or(|(child, _)| child == 0));
        let made = PatchMatrices::derive(scheme, mesh, start, 1, options, PatchType::Derived { id })
            .ok()
            .flatten()
            .filter(|m| m.find(&patch.signature) == Some(0) && fixed_points_at_corner_0(m))
            .map(Arc::new);
        let mut shapes = derived.shapes.lock().unwrap_or_else(PoisonError::into_inner);
        match made {
            Some(matrices) => {
                for (s, shape) in matrices.shapes.iter().enumerate() {
                    shapes.entry((*key, shape.signature.clone())).or_insert_with(|| Some((matrices.clone(), s)));
                }
                Some(FoundPatch { start, vertices: PatchVertices::from_vec(patch.vertices), matrices, shape: 0 })
            }
            None => {
                shapes.insert((*key, patch.signature), None);
                None
            }
        }
    }

    /// The patch starting at `start`, if its shape is known.
    pub fn at(&self, mesh: &Mesh, start: HalfEdgeId) -> Option<FoundPatch> {
        self.at_with(mesh, start, &mut Patch::default(), &mut None)
    }

    /// [`at`](Self::at), walking into `patch` (a buffer); `boundary` is [`reaches_a_boundary`]
    /// of the face once known (the same for every rotation).
    fn at_with(
        &self,
        mesh: &Mesh,
        start: HalfEdgeId,
        patch: &mut Patch,
        boundary: &mut Option<bool>,
    ) -> Option<FoundPatch> {
        let corners = face_corners(mesh, start);
        self.lookup.iter().find_map(|(radius, lookup)| {
            let &flags = lookup.corners.get(&corners)?;
            if *radius == 1 && flags != [true, true] {
                let reaches = *boundary.get_or_insert_with(|| reaches_a_boundary(mesh, mesh.face(start)));
                if !flags[usize::from(reaches)] {
                    return None;
                }
            }
            mesh.patch_into(start, *radius, patch);
            let &(table, shape) = lookup.shapes.get(&patch.signature)?;
            Some(FoundPatch {
                start,
                vertices: PatchVertices::from_slice(&patch.vertices),
                matrices: self.tables[table].clone(),
                shape,
            })
        })
    }
}

/// Appends the patch types of `v`'s faces to `types`: one per face for a boundary vertex or
/// an interior one with sharp spokes (each counted from its face), one for a smooth interior
/// vertex; none where a feature at `v` is semi-sharp (not stationary: its faces are refined
/// until it is spent).
fn vertex_types(scheme: &Scheme, mesh: &Mesh, v: VertexId, types: &mut Vec<PatchType>) -> Result<(), SchemeError> {
    let class = Sharpness::of;
    let corner = class(mesh.vertex_sharpness(v));
    if corner == Sharpness::SemiSharp {
        return Ok(());
    }
    // The spokes counter-clockwise: spoke s is the first side of the fan's face s, and the
    // last side of face s − 1. A boundary fan starts at its boundary half-edge.
    let boundary = mesh.is_boundary_vertex(v);
    let first = if boundary {
        mesh.outgoing(v).find(|&h| mesh.twin(h).is_none()).expect("a boundary vertex has a boundary half-edge")
    } else {
        mesh.outgoing(v).next().expect("a vertex with faces has an outgoing half-edge")
    };
    let mut spokes = Vec::new();
    let mut h = Some(first);
    while let Some(at) = h {
        spokes.push(class(mesh.edge_sharpness(mesh.edge(at))));
        let incoming = mesh.prev(at);
        h = mesh.twin(incoming).filter(|&t| t != first);
        if h.is_none() && boundary {
            spokes.push(class(mesh.edge_sharpness(mesh.edge(incoming))));
        }
    }
    if spokes.contains(&Sharpness::SemiSharp) {
        return Ok(());
    }
    let faces = if boundary { spokes.len() - 1 } else { spokes.len() };
    let sharp_spoke = |s: usize| spokes[s] == Sharpness::Infinite && !(boundary && (s == 0 || s == faces));
    if (0..spokes.len()).any(|s| s >= 64 && sharp_spoke(s)) {
        return Err(SchemeError::ValenceNotSupported {
            scheme: scheme.name.clone(),
            valence: spokes.len(),
            reason: "infinitely sharp edges are supported at vertices of up to 64 edges",
        });
    }
    let mask = |rotation: usize| -> u64 {
        (0..faces.min(64)).filter(|&s| sharp_spoke((s + rotation) % spokes.len())).fold(0, |m, s| m | 1 << s)
    };
    let corner = corner == Sharpness::Infinite;
    if boundary {
        let sharp = SharpFeatures { edges: mask(0), corner };
        types.extend((0..faces).map(|index| PatchType::Boundary { faces, index, sharp }));
    } else if mask(0) == 0 {
        types.push(PatchType::Interior { valence: faces, sharp: SharpFeatures { edges: 0, corner } });
    } else {
        types.extend(
            (0..faces).map(|j| PatchType::Interior { valence: faces, sharp: SharpFeatures { edges: mask(j), corner } }),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::{Mesh, shapes};

    use super::*;
    use crate::Builtin;

    #[test]
    fn valences_past_the_limit_are_refused_before_any_matrix() {
        // pole(k): a vertex of valence k.
        let mesh = Mesh::build(shapes::pole(7)).unwrap();
        let cc = Builtin::CatmullClark.scheme();
        let options = RefineOptions { max_patch_valence: 6, ..RefineOptions::DEFAULT };
        let Err(error) = MeshPatches::new(cc, &mesh, &options) else { panic!("valence 7 is past 6") };
        assert!(
            matches!(error, SchemeError::ValenceTooLarge { valence: 7, limit: 6, kind: ValenceLimit::Smooth, .. }),
            "{error}"
        );
        assert!(error.to_string().contains("max_patch_valence"), "{error}");
        let options = RefineOptions { max_patch_valence: 7, ..options };
        assert!(MeshPatches::new(cc, &mesh, &options).is_ok());
        // With a sharp spoke the vertex's matrices are dense, under the other limit.
        let mut sharp = mesh.clone();
        let spoke = sharp.edge(sharp.outgoing(VertexId::new(0)).next().unwrap());
        sharp.set_edge_sharpness(spoke, subdiv_mesh::Tags::INFINITELY_SHARP);
        let options = RefineOptions { max_dense_patch_valence: 6, ..options };
        let Err(error) = MeshPatches::new(cc, &sharp, &options) else { panic!("valence 7 is past 6") };
        assert!(matches!(error, SchemeError::ValenceTooLarge { kind: ValenceLimit::Dense, .. }), "{error}");
        assert!(error.to_string().contains("max_dense_patch_valence"), "{error}");
    }
}
