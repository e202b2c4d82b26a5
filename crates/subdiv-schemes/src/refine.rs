//! Uniform refinement: one engine for every [`Scheme`]. Each level is a topology split
//! (primal quad, primal triangle, dual, mid-edge or √3) and the child vertices from the scheme's
//! masks — applied to the positions directly ([`refine_uniform`]) or as one stencil row per child
//! vertex ([`Refiner`], which keeps them); primal schemes with crease rules follow OpenSubdiv's
//! `Sdc` for boundaries, creases, corners and holes.

use glam::DVec3;
use subdiv_mesh::{
    BoundaryInterpolation, CreaseMethod, FaceId, FaceVaryingInterpolation, Mesh, Parallelism, Region, Sharpness,
    TriangleSubdivision, VertexId,
};

use crate::crease::INFINITE;
use crate::primal::{ChannelLevel, ChannelRules};
use crate::scheme::{Rules, Scheme, Split};
use crate::stencil::Stencils;
use crate::stencil_table::StencilTable;
use crate::{SchemeError, dual, primal};

/// Options of [`refine`] and [`refine_uniform`]. `None` fields take the mesh's tags, and
/// OpenSubdiv's regression defaults where the mesh has none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefineOptions {
    /// Boundary rule; default: the mesh's `interpolateboundary` tag, else
    /// [`BoundaryInterpolation::EdgeOnly`].
    pub boundary: Option<BoundaryInterpolation>,
    /// How semi-sharp creases fade; default: the mesh's `creasemethod` tag, else
    /// [`CreaseMethod::Uniform`].
    pub crease_method: Option<CreaseMethod>,
    /// The rule at edges next to triangles; default: the mesh's `smoothtriangles` tag, else
    /// [`TriangleSubdivision::Catmark`]. Schemes without a smooth-triangle mask
    /// ([`QuadEdgeMask::triangle_face`](crate::QuadEdgeMask::triangle_face); of the built-ins
    /// only Catmull-Clark has one) ignore it.
    pub triangle_subdivision: Option<TriangleSubdivision>,
    /// Where face-varying channels (texture coordinates) are linear; default: the mesh's
    /// `facevaryinginterpolateboundary` tag, else [`FaceVaryingInterpolation::All`]
    /// (OpenSubdiv's default: every refined value interpolates its parent face's values).
    /// Channels are refined by the primal schemes with crease rules (Catmull-Clark, Loop,
    /// bilinear, and scheme files with crease masks); the other schemes' refined meshes have no
    /// channels.
    pub face_varying: Option<FaceVaryingInterpolation>,
    /// The largest valence of a smooth interior vertex of a quad or triangle split whose
    /// sub-patch matrices the exact pipeline derives (refinement itself takes any valence):
    /// past it [`MeshPatches`](crate::MeshPatches) refuses the mesh with
    /// [`SchemeError::ValenceTooLarge`](crate::SchemeError::ValenceTooLarge) before any matrix
    /// is made ([`ValenceLimit::Smooth`]). Default: [`MAX_PATCH_VALENCE`].
    pub max_patch_valence: usize,
    /// The same for every other vertex, whose matrices are solved densely
    /// ([`ValenceLimit::Dense`]): one with sharp features, on a boundary or semi-sharp, and
    /// the dual and ternary splits' faces and vertices. Default: [`MAX_DENSE_PATCH_VALENCE`].
    pub max_dense_patch_valence: usize,
    /// Whether a level's passes (the split, face, edge and vertex points) may run on rayon's
    /// threads; the result is the same either way, bit for bit. Default:
    /// [`Parallelism::Rayon`].
    pub parallelism: Parallelism,
}

/// [`RefineOptions::max_patch_valence`]' default: 4096. A smooth vertex's spectrum comes from
/// its ring's frequency blocks in `O(n)`, but each of its `n` faces carries a patch of about
/// `2n` points through the pipeline (walked and evaluated), so the cost grows with the square
/// of `n` (measured, `subdiv tessellate --rate 2` of an open fan of `n` quads: 1000 takes 0.3 s
/// and 36 MB, 4096 takes 4.2 s and 0.2 GB, 10 000 takes 24 s and 0.9 GB; one 10 000-gon at
/// `--rate 4` 58 s and 2.5 GB).
pub const MAX_PATCH_VALENCE: usize = 4096;

/// [`RefineOptions::max_dense_patch_valence`]' default: 1024. Dense sub-patch matrices of
/// valence `n` are of size about `2n`, and their eigen analysis takes time cubic in `n`
/// (measured, `subdiv eval --grid 2` of one smooth vertex of valence `n` before the ring's
/// blocks: 300 took 1.7 s and 0.38 GB, 1000 took 21 s and 1.3 GB), so a 5000-gon would take
/// most of an hour and 30 GB.
pub const MAX_DENSE_PATCH_VALENCE: usize = 1024;

/// Which valence limit of [`RefineOptions`] a vertex falls under.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValenceLimit {
    /// A smooth interior vertex of a quad or triangle split, whose spectrum the ring's
    /// frequency blocks give ([`PatchMatrices::ring_spectrum`](crate::PatchMatrices::ring_spectrum)):
    /// [`RefineOptions::max_patch_valence`].
    Smooth,
    /// Any other vertex, solved densely: [`RefineOptions::max_dense_patch_valence`].
    Dense,
}

impl ValenceLimit {
    /// The limit `options` set.
    pub fn of(self, options: &RefineOptions) -> usize {
        match self {
            Self::Smooth => options.max_patch_valence,
            Self::Dense => options.max_dense_patch_valence,
        }
    }
}

impl std::fmt::Display for ValenceLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Smooth => {
                "a smooth vertex's sub-patch matrices: their cost grows with the square of the valence (4000 \
                 takes about 4 s, 10 000 half a minute and 1 GB); split the face or vertex, or raise the limit \
                 (RefineOptions::max_patch_valence)"
            }
            Self::Dense => {
                "sub-patch matrices solved densely (a vertex with sharp features or on a boundary, a dual or \
                 ternary split): their cost grows with the cube of the valence (1000 takes about 20 s and 1.3 \
                 GB); split the face or vertex, or raise the limit (RefineOptions::max_dense_patch_valence)"
            }
        })
    }
}

impl RefineOptions {
    /// The defaults: everything from the mesh's tags, valences up to [`MAX_PATCH_VALENCE`].
    pub const DEFAULT: Self = Self {
        boundary: None,
        crease_method: None,
        triangle_subdivision: None,
        face_varying: None,
        max_patch_valence: MAX_PATCH_VALENCE,
        max_dense_patch_valence: MAX_DENSE_PATCH_VALENCE,
        parallelism: Parallelism::Rayon,
    };

    /// Sets [`parallelism`](Self::parallelism).
    pub fn with_parallelism(mut self, parallelism: Parallelism) -> Self {
        self.parallelism = parallelism;
        self
    }

    /// Sets [`face_varying`](Self::face_varying).
    pub fn with_face_varying(mut self, mode: FaceVaryingInterpolation) -> Self {
        self.face_varying = Some(mode);
        self
    }

    pub(crate) fn boundary_for(&self, mesh: &Mesh) -> BoundaryInterpolation {
        self.boundary.or(mesh.tags().boundary_interpolation).unwrap_or(BoundaryInterpolation::EdgeOnly)
    }

    pub(crate) fn rules_for(&self, mesh: &Mesh) -> Options {
        let crease_method = self.crease_method.or(mesh.tags().crease_method).unwrap_or(CreaseMethod::Uniform);
        Options {
            parallelism: self.parallelism,
            crease_method,
            smooth_triangles: self.triangle_subdivision.or(mesh.tags().triangle_subdivision)
                == Some(TriangleSubdivision::Smooth),
            channels: ChannelRules {
                mode: self
                    .face_varying
                    .or(mesh.tags().face_varying_interpolation)
                    .unwrap_or(FaceVaryingInterpolation::All),
                sharp_mesh_corners: self.boundary_for(mesh) == BoundaryInterpolation::EdgeAndCorner,
                crease_method,
            },
        }
    }
}

/// The options that change masks, resolved once for all levels.
#[derive(Clone, Copy)]
pub(crate) struct Options {
    pub(crate) parallelism: Parallelism,
    pub(crate) crease_method: CreaseMethod,
    pub(crate) smooth_triangles: bool,
    pub(crate) channels: ChannelRules,
}

/// Refines `mesh` `levels` times with `scheme` (0 returns a copy with the boundary rule
/// applied).
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{refine_uniform, Builtin, RefineOptions};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let refined = refine_uniform(&cube, Builtin::CatmullClark.scheme(), 2, &RefineOptions::DEFAULT)?;
/// assert_eq!(refined.face_count(), 6 * 16);
/// // Catmull-Clark shrinks the cube towards its limit surface, inside the cage.
/// assert!(refined.positions().iter().all(|p| p.abs().max_element() < 1.0));
///
/// // Doo-Sabin cuts the corners: one face per face, edge and vertex.
/// let cut = refine_uniform(&cube, Builtin::DooSabin.scheme(), 1, &RefineOptions::DEFAULT)?;
/// assert_eq!(cut.face_count(), 6 + 12 + 8);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`SchemeError::FaceNotSupported`] when the scheme cannot take a face of the mesh,
/// [`SchemeError::FeatureNotSupported`] when the mesh has boundaries, sharpness or holes and
/// the scheme has no rules for them.
pub fn refine_uniform(
    mesh: &Mesh,
    scheme: &Scheme,
    levels: usize,
    options: &RefineOptions,
) -> Result<Mesh, SchemeError> {
    refine_uniform_with_progress(mesh, scheme, levels, options, |_| {})
}

/// As [`refine_uniform`], calling `progress(level)` after each level is done (1 to `levels`),
/// for a progress bar.
///
/// # Errors
/// As [`refine_uniform`].
pub fn refine_uniform_with_progress(
    mesh: &Mesh,
    scheme: &Scheme,
    levels: usize,
    options: &RefineOptions,
    mut progress: impl FnMut(usize),
) -> Result<Mesh, SchemeError> {
    refine_levels(mesh, scheme, levels, options, false, &mut progress).map(|(mesh, _)| mesh)
}

/// The loop of [`refine_uniform_with_progress`] and [`Refiner::with_progress`]: `levels` levels,
/// with each level's stencils when `stencils` asks for them.
fn refine_levels(
    mesh: &Mesh,
    scheme: &Scheme,
    levels: usize,
    options: &RefineOptions,
    stencils: bool,
    progress: &mut dyn FnMut(usize),
) -> Result<(Mesh, Vec<Stencils>), SchemeError> {
    check_input(mesh, scheme)?;
    if let Some(pairs) = midedge_pairs(mesh, scheme, levels)? {
        return refine_levels(mesh, &pairs, levels / 2, options, stencils, &mut |pair| {
            progress(2 * pair - 1);
            progress(2 * pair);
        });
    }
    let rules = options.rules_for(mesh);
    let mut current = if scheme.has_crease_rules() { prepared(mesh, options) } else { mesh.clone() };
    let mut all = Vec::with_capacity(if stencils { levels } else { 0 });
    // The channels' face-varying topology, carried from level to level.
    let mut channels = Vec::new();
    for level in 0..levels {
        let (child, level_stencils) = refine_once(&current, scheme, level, rules, &mut channels, stencils)?;
        current = child;
        all.extend(level_stencils);
        progress(level + 1);
    }
    Ok((current, all))
}

/// Two √3 steps of `mesh` as the ternary split takes them — a step that keeps the boundary, then
/// one that splits it ([`Sqrt3Boundary`](crate::Sqrt3Boundary)) — each mesh with its rows over
/// the one before.
///
/// # Errors
/// As [`refine_uniform`].
pub(crate) fn sqrt3_steps(
    mesh: &Mesh,
    scheme: &Scheme,
    options: &RefineOptions,
) -> Result<[(Mesh, Stencils); 2], SchemeError> {
    check_input(mesh, scheme)?;
    let rules = options.rules_for(mesh);
    let mut channels = Vec::new();
    let missing = || SchemeError::Internal("a √3 step without its rows".into());
    let (mid, first) = refine_once(mesh, scheme, 0, rules, &mut channels, true)?;
    let (fine, second) = refine_once(&mid, scheme, 1, rules, &mut channels, true)?;
    Ok([(mid, first.ok_or_else(missing)?), (fine, second.ok_or_else(missing)?)])
}

/// Mid-edge refines an open mesh two steps at a time, as its two-step dual form
/// ([`Scheme::dual_form`]) with Chaikin's boundary rule: a single step has no boundary rule that
/// keeps the boundary refining (the polygon of a boundary's edge middles has as many vertices
/// as the boundary). The dual form, for an open mesh under mid-edge; `None` otherwise.
///
/// # Errors
/// [`SchemeError::FeatureNotSupported`] for an odd number of steps on an open mesh.
fn midedge_pairs(mesh: &Mesh, scheme: &Scheme, levels: usize) -> Result<Option<Scheme>, SchemeError> {
    if !matches!(scheme.rules, Rules::Midedge) {
        return Ok(None);
    }
    let Some(e) = mesh.edges().find(|&e| mesh.is_boundary_edge(e)) else {
        return Ok(None);
    };
    if levels % 2 == 1 {
        let [a, b] = mesh.edge_vertices(e);
        return Err(SchemeError::FeatureNotSupported {
            scheme: scheme.name.clone(),
            feature: "boundaries in an odd number of steps (it refines open meshes two steps at a time)",
            element: format!("edge {}-{}", a.raw(), b.raw()),
        });
    }
    Ok(scheme.dual_form())
}

/// Uniform refinement split as OpenSubdiv's `Far` splits it: the topology of every level and
/// its stencils are computed once by [`Refiner::new`]; [`Refiner::interpolate`] then refines new
/// positions of the same cage (an animated one, say) by applying the stencils alone.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{Builtin, RefineOptions, Refiner};
///
/// let cage = Mesh::build(shapes::quad_torus(8, 6))?;
/// let refiner = Refiner::new(&cage, Builtin::CatmullClark.scheme(), 3, &RefineOptions::DEFAULT)?;
/// // Move the cage and refine the moved positions without redoing the topology.
/// let moved: Vec<_> = cage.positions().iter().map(|p| *p * 2.0).collect();
/// let (mut out, mut scratch) = (Vec::new(), Vec::new());
/// refiner.interpolate(&moved, &mut out, &mut scratch);
/// assert!(out.iter().zip(refiner.mesh().positions()).all(|(a, b)| (*a - *b * 2.0).length() < 1e-12));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Refiner {
    levels: Vec<Stencils>,
    mesh: Mesh,
    parallelism: Parallelism,
}

impl Refiner {
    /// Refines `mesh` `levels` times, keeping each level's stencils.
    ///
    /// # Errors
    /// As [`refine_uniform`].
    pub fn new(mesh: &Mesh, scheme: &Scheme, levels: usize, options: &RefineOptions) -> Result<Self, SchemeError> {
        Self::with_progress(mesh, scheme, levels, options, |_| {})
    }

    /// As [`Refiner::new`], calling `progress(level)` after each level is done (1 to `levels`),
    /// for a progress bar.
    ///
    /// # Errors
    /// As [`refine_uniform`].
    pub fn with_progress(
        mesh: &Mesh,
        scheme: &Scheme,
        levels: usize,
        options: &RefineOptions,
        mut progress: impl FnMut(usize),
    ) -> Result<Self, SchemeError> {
        let (mesh, levels) = refine_levels(mesh, scheme, levels, options, true, &mut progress)?;
        Ok(Self { levels, mesh, parallelism: options.parallelism })
    }

    /// The refined mesh (topology, sharpness, holes, and the positions refined from the cage's).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The refined mesh, by value.
    pub fn into_mesh(self) -> Mesh {
        self.mesh
    }

    /// Each level's stencils, from the cage down.
    pub fn levels(&self) -> &[Stencils] {
        &self.levels
    }

    /// The last level as weighted sums of the cage's vertices: the levels' stencils composed
    /// (Far's `StencilTableFactory::Create` with `generateIntermediateLevels = false`), on
    /// rayon's threads as the refinement's [`RefineOptions::parallelism`] allowed.
    pub fn stencil_table(&self) -> StencilTable {
        let cage = self.levels.first().map_or(self.mesh.vertex_count(), Stencils::parent_count);
        StencilTable::compose(cage, &self.levels, self.parallelism.forks())
    }

    /// Refines `base` (one position per cage vertex) to the last level, into `out`; `scratch`
    /// holds the levels in between. Both are resized as needed and may be reused across calls.
    ///
    /// # Panics
    /// When `base` does not have one position per cage vertex.
    pub fn interpolate(&self, base: &[DVec3], out: &mut Vec<DVec3>, scratch: &mut Vec<DVec3>) {
        out.clear();
        out.extend_from_slice(base);
        for level in &self.levels {
            std::mem::swap(out, scratch);
            level.apply(scratch, out);
        }
    }
}

/// One level of refinement of part of a mesh: some of its faces and `rings` rings of faces
/// around them (a [`Region`]), or the whole mesh when the region would be all of it or the
/// scheme has no crease rules (a region's cut edges need boundary rules). Its stencils are over
/// the whole parent's vertices. Refining level by level only where patches are still missing
/// (`PatchLevels` on real meshes, the sub-patch derivation on canonical ones) costs what those
/// faces need, not what the mesh is.
///
/// ```
/// use subdiv_mesh::{shapes, FaceId, Mesh};
/// use subdiv_schemes::{Builtin, LocalRefinement, RefineOptions};
///
/// let grid = Mesh::build(shapes::quad_grid(9, 9))?;
/// let centre = FaceId::new(40);
/// let local = LocalRefinement::new(Builtin::CatmullClark.scheme(), &grid, &[centre], 1, &RefineOptions::DEFAULT)?;
/// // The centre face and a ring around it, 5 × 5 faces, each split in four.
/// assert_eq!(local.mesh.face_count(), 100);
/// assert_eq!(local.stencils.parent_count(), grid.vertex_count());
/// let (split_parent, face) = local.split_parent(&grid, centre).expect("a refined face");
/// assert_eq!(split_parent.face_count(), 25);
/// assert_eq!(split_parent.face_vertices(face).len(), 4);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct LocalRefinement {
    /// The refined part.
    pub mesh: Mesh,
    /// [`mesh`](Self::mesh)'s vertices over the parent's.
    pub stencils: Stencils,
    /// The part of the parent that was refined; `None`: all of it.
    pub region: Option<Region>,
}

impl LocalRefinement {
    /// Refines `faces` of `parent` and `rings` rings of faces around them with `scheme`.
    ///
    /// # Errors
    /// As [`Refiner::new`].
    pub fn new(
        scheme: &Scheme,
        parent: &Mesh,
        faces: &[FaceId],
        rings: usize,
        options: &RefineOptions,
    ) -> Result<Self, SchemeError> {
        let region = if scheme.has_crease_rules() {
            let region = parent.region(faces, rings).map_err(|e| SchemeError::Internal(e.to_string()))?;
            (region.faces.len() < parent.face_count()).then_some(region)
        } else {
            None
        };
        let (mesh, stencils) = match &region {
            None => {
                let refiner = Refiner::new(parent, scheme, 1, options)?;
                let stencils = refiner.levels()[0].clone();
                (refiner.into_mesh(), stencils)
            }
            Some(region) => {
                let refiner = Refiner::new(&region.mesh, scheme, 1, options)?;
                let parents: Vec<u32> = region.vertices.iter().map(|v| v.raw()).collect();
                let stencils = refiner.levels()[0].with_parents(&parents, parent.vertex_count());
                (refiner.into_mesh(), stencils)
            }
        };
        Ok(Self { mesh, stencils, region })
    }

    /// The mesh [`mesh`](Self::mesh) is the split of (`parent` itself, or the region) and
    /// `face`'s number there, with the same corners; `None` if `face` was not refined.
    pub fn split_parent<'a>(&'a self, parent: &'a Mesh, face: FaceId) -> Option<(&'a Mesh, FaceId)> {
        match &self.region {
            None => Some((parent, face)),
            Some(region) => Some((&region.mesh, region.face_of(face)?)),
        }
    }
}

/// Refines `mesh` once; see [`refine_uniform`].
///
/// # Errors
/// As [`refine_uniform`].
pub fn refine(mesh: &Mesh, scheme: &Scheme, options: &RefineOptions) -> Result<Mesh, SchemeError> {
    refine_uniform(mesh, scheme, 1, options)
}

/// One level of any scheme, with its stencils when `stencils` asks for them; `channels` holds
/// the face-varying topology of `mesh`'s channels (empty at the base level) and is replaced by
/// the child's. `level` counts the steps before this one (√3 refines boundaries every second
/// step).
fn refine_once(
    mesh: &Mesh,
    scheme: &Scheme,
    level: usize,
    options: Options,
    channels: &mut Vec<ChannelLevel>,
    stencils: bool,
) -> Result<(Mesh, Option<Stencils>), SchemeError> {
    let (child, level_stencils) = match &scheme.rules {
        Rules::Quad { .. } | Rules::Triangle { .. } | Rules::FourPointQuad { .. } => {
            return primal::refine(mesh, scheme, options, channels, stencils);
        }
        Rules::Dual { own, corner, boundary } => dual::doo_sabin(mesh, own, corner, *boundary)?,
        Rules::Midedge => dual::midedge(mesh)?,
        Rules::Sqrt3 { vertex, boundary } => dual::sqrt3(mesh, vertex, boundary.is_some() && level % 2 == 1)?,
    };
    Ok((child, stencils.then_some(level_stencils)))
}

/// Rejects what the scheme cannot take: faces of the wrong size and, for a scheme without
/// crease rules, boundaries, sharpness tags and holes.
fn check_input(mesh: &Mesh, scheme: &Scheme) -> Result<(), SchemeError> {
    if let Some(expected) = scheme.face_size()
        && let Some(face) = mesh.face_ids().find(|&f| mesh.face_size(f) != expected)
    {
        return Err(SchemeError::FaceNotSupported {
            scheme: scheme.name.clone(),
            face,
            size: mesh.face_size(face),
            expected,
        });
    }
    let unsupported = |feature: &'static str, element: String| SchemeError::FeatureNotSupported {
        scheme: scheme.name.clone(),
        feature,
        element,
    };
    // The dual splits make a face of each vertex's corners: an interior vertex of two faces
    // would make a face of two sides (OpenSubdiv's `catmark_val2_back2back`).
    if matches!(scheme.split(), Split::Dual | Split::Midedge)
        && let Some(v) = mesh
            .vertices()
            .find(|&v| !mesh.is_isolated(v) && !mesh.is_boundary_vertex(v) && mesh.outgoing(v).nth(2).is_none())
    {
        return Err(unsupported(
            "interior vertices of two faces (their vertex face would have two sides)",
            v.to_string(),
        ));
    }
    if scheme.has_crease_rules() {
        return Ok(());
    }
    if !scheme.has_boundary_rules()
        && let Some(e) = mesh.edges().find(|&e| mesh.is_boundary_edge(e))
    {
        let [a, b] = mesh.edge_vertices(e);
        return Err(unsupported("boundaries", format!("edge {}-{}", a.raw(), b.raw())));
    }
    // An interpolating scheme's boundary rule takes infinitely sharp creases and corners (the
    // rule on each side).
    let by_boundary = scheme.creases_by_boundary_rule();
    let takes = |s: f64| s <= 0.0 || (by_boundary && Sharpness::of(s) == Sharpness::Infinite);
    let (creases, corners) =
        if by_boundary { ("semi-sharp creases", "semi-sharp corners") } else { ("creases", "corners") };
    if let Some(e) = mesh.edges().find(|&e| !takes(mesh.edge_sharpness(e))) {
        let [a, b] = mesh.edge_vertices(e);
        return Err(unsupported(creases, format!("edge {}-{}", a.raw(), b.raw())));
    }
    // The dual splits keep a boundary vertex of one face as a corner: a tag there says so.
    let corner_already = |v: VertexId| {
        matches!(scheme.split(), Split::Dual | Split::Midedge)
            && Sharpness::of(mesh.vertex_sharpness(v)) == Sharpness::Infinite
            && mesh.is_boundary_vertex(v)
            && mesh.outgoing(v).nth(1).is_none()
    };
    if let Some(v) = mesh.vertices().find(|&v| !takes(mesh.vertex_sharpness(v)) && !corner_already(v)) {
        return Err(unsupported(corners, v.to_string()));
    }
    if let Some(f) = mesh.face_ids().find(|&f| mesh.is_hole(f)) {
        return Err(unsupported("holes", f.to_string()));
    }
    Ok(())
}

/// Applies the boundary rule as OpenSubdiv does to its base level: boundary edges become
/// infinitely sharp; with edge-and-corner, so do boundary vertices with one face; with none,
/// the faces around a boundary vertex that is not explicitly sharp become holes.
/// Idempotent, so it may run at every level.
pub(crate) fn prepared(mesh: &Mesh, options: &RefineOptions) -> Mesh {
    let boundary = options.boundary_for(mesh);
    let mut out = mesh.clone();
    if boundary == BoundaryInterpolation::None {
        for v in mesh.vertices().filter(|&v| mesh.is_boundary_vertex(v)) {
            let sharp_edges = primal::vertex_edges(mesh, v)
                .iter()
                .filter(|&&(e, _)| mesh.edge_sharpness(e) >= f64::from(INFINITE))
                .count();
            if mesh.vertex_sharpness(v) < f64::from(INFINITE) && sharp_edges < 2 {
                for f in mesh.vertex_faces(v) {
                    out.set_hole(f, true);
                }
            }
        }
    }
    for e in mesh.edges().filter(|&e| mesh.is_boundary_edge(e)) {
        out.set_edge_sharpness(e, f64::from(INFINITE));
    }
    if boundary == BoundaryInterpolation::EdgeAndCorner {
        for v in mesh.vertices().filter(|&v| mesh.is_boundary_vertex(v) && mesh.valence(v) == 2) {
            out.set_vertex_sharpness(v, f64::from(INFINITE));
        }
    }
    out
}
