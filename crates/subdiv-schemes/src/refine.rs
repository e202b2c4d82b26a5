//! Uniform refinement: the topology split and OpenSubdiv's vertex rules (smooth, dart, crease,
//! corner, and the fractional blend where a semi-sharp feature fades out).

use glam::DVec3;
use smallvec::SmallVec;
use subdiv_mesh::{
    BoundaryInterpolation, CreaseMethod, EdgeId, FaceId, HalfEdgeId, Mesh, PolygonSoup, Tags, TriangleSubdivision,
    VertexId,
};

use crate::crease::{self, INFINITE, Rule};
use crate::stencil::{Row, Stencils};
use crate::{Scheme, SchemeError};

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
    /// Catmull-Clark's rule at edges next to triangles; default: the mesh's `smoothtriangles`
    /// tag, else [`TriangleSubdivision::Catmark`] (Loop ignores it).
    pub triangle_subdivision: Option<TriangleSubdivision>,
}

impl RefineOptions {
    /// The defaults: everything from the mesh's tags.
    pub const DEFAULT: Self = Self { boundary: None, crease_method: None, triangle_subdivision: None };

    fn boundary_for(&self, mesh: &Mesh) -> BoundaryInterpolation {
        self.boundary.or(mesh.tags().boundary_interpolation).unwrap_or(BoundaryInterpolation::EdgeOnly)
    }

    fn rules_for(&self, mesh: &Mesh) -> Rules {
        Rules {
            crease_method: self.crease_method.or(mesh.tags().crease_method).unwrap_or(CreaseMethod::Uniform),
            smooth_triangles: self.triangle_subdivision.or(mesh.tags().triangle_subdivision)
                == Some(TriangleSubdivision::Smooth),
        }
    }
}

/// The options that change masks, resolved once for all levels.
#[derive(Clone, Copy)]
struct Rules {
    crease_method: CreaseMethod,
    smooth_triangles: bool,
}

/// Refines `mesh` `levels` times (0 returns a copy with the boundary rule applied).
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{refine_uniform, RefineOptions, Scheme};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let refined = refine_uniform(&cube, Scheme::CatmullClark, 2, &RefineOptions::DEFAULT)?;
/// assert_eq!(refined.face_count(), 6 * 16);
/// // Catmull-Clark shrinks the cube towards its limit surface, inside the cage.
/// assert!(refined.positions().iter().all(|p| p.abs().max_element() < 1.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`SchemeError::FaceNotSupported`] when the scheme cannot take a face of the mesh.
pub fn refine_uniform(
    mesh: &Mesh,
    scheme: Scheme,
    levels: usize,
    options: &RefineOptions,
) -> Result<Mesh, SchemeError> {
    Refiner::new(mesh, scheme, levels, options).map(Refiner::into_mesh)
}

/// Uniform refinement split as OpenSubdiv's `Far` splits it: the topology of every level and
/// its stencils are computed once by [`Refiner::new`]; [`Refiner::interpolate`] then refines new
/// positions of the same cage (an animated one, say) by applying the stencils alone.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{RefineOptions, Refiner, Scheme};
///
/// let cage = Mesh::build(shapes::quad_torus(8, 6))?;
/// let refiner = Refiner::new(&cage, Scheme::CatmullClark, 3, &RefineOptions::DEFAULT)?;
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
}

impl Refiner {
    /// Refines `mesh` `levels` times, keeping each level's stencils.
    ///
    /// # Errors
    /// [`SchemeError::FaceNotSupported`] when the scheme cannot take a face of the mesh.
    pub fn new(mesh: &Mesh, scheme: Scheme, levels: usize, options: &RefineOptions) -> Result<Self, SchemeError> {
        let rules = options.rules_for(mesh);
        let mut current = prepared(mesh, options);
        let mut stencils = Vec::with_capacity(levels);
        for _ in 0..levels {
            let (child, level) = refine_prepared(&current, scheme, rules)?;
            current = child;
            stencils.push(level);
        }
        Ok(Self { levels: stencils, mesh: current })
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

/// Refines `mesh` once; see [`refine_uniform`].
///
/// # Errors
/// As [`refine_uniform`].
pub fn refine(mesh: &Mesh, scheme: Scheme, options: &RefineOptions) -> Result<Mesh, SchemeError> {
    refine_uniform(mesh, scheme, 1, options)
}

/// Applies the boundary rule as OpenSubdiv does to its base level: boundary edges become
/// infinitely sharp; with edge-and-corner, so do boundary vertices with one face; with none,
/// the faces around a boundary vertex that is not explicitly sharp become holes.
/// Idempotent, so it may run at every level.
fn prepared(mesh: &Mesh, options: &RefineOptions) -> Mesh {
    let boundary = options.boundary_for(mesh);
    let mut out = mesh.clone();
    if boundary == BoundaryInterpolation::None {
        for v in mesh.vertices().filter(|&v| mesh.is_boundary_vertex(v)) {
            let sharp_edges =
                vertex_edges(mesh, v).iter().filter(|&&(e, _)| mesh.edge_sharpness(e) >= f64::from(INFINITE)).count();
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

/// The edges at `v` in fan order, each with its far end; for a boundary vertex the trailing
/// boundary edge comes last.
fn vertex_edges(mesh: &Mesh, v: VertexId) -> SmallVec<[(EdgeId, VertexId); 8]> {
    let mut edges: SmallVec<[(EdgeId, VertexId); 8]> = SmallVec::new();
    let mut last = None;
    for h in mesh.outgoing(v) {
        edges.push((mesh.edge(h), mesh.dest(h)));
        last = Some(h);
    }
    if let Some(h) = last
        && mesh.is_boundary_vertex(v)
    {
        let incoming = mesh.prev(h);
        edges.push((mesh.edge(incoming), mesh.origin(incoming)));
    }
    edges
}

fn sharpness(s: f64) -> f32 {
    // Sharpness is single precision in OpenSubdiv; rounding here keeps fractional weights equal.
    s as f32
}

/// Child vertex numbering: vertex points (parent order), then face points (quad schemes), then
/// edge points — the order of OpenSubdiv's `Far` levels as the peer harness writes them.
struct Numbering {
    face_base: u32,
    edge_base: u32,
}

impl Numbering {
    fn face(&self, f: FaceId) -> VertexId {
        VertexId::new(self.face_base + f.raw())
    }

    fn edge(&self, e: EdgeId) -> VertexId {
        VertexId::new(self.edge_base + e.raw())
    }
}

fn refine_prepared(mesh: &Mesh, scheme: Scheme, rules: Rules) -> Result<(Mesh, Stencils), SchemeError> {
    let method = rules.crease_method;
    let quads = scheme.splits_into_quads();
    if !quads && let Some(face) = mesh.face_ids().find(|&f| mesh.face_size(f) != 3) {
        return Err(SchemeError::FaceNotSupported { scheme, face, size: mesh.face_size(face), expected: 3 });
    }
    let nv = mesh.vertex_count() as u32;
    let face_points = if quads { mesh.face_count() as u32 } else { 0 };
    let numbering = Numbering { face_base: nv, edge_base: nv + face_points };
    let child_count = (numbering.edge_base as usize) + mesh.edge_count();

    // Geometry: one stencil row per child vertex, in child order.
    let mut stencils = Stencils::with_capacity(child_count, 8 * child_count, mesh.vertex_count());
    for v in mesh.vertices() {
        stencils.push(&vertex_row(mesh, scheme, method, v));
    }
    if quads {
        for f in mesh.face_ids() {
            stencils.push(&face_point(mesh, f));
        }
    }
    for e in mesh.edges() {
        stencils.push(&edge_row(mesh, scheme, rules, e));
    }
    let mut positions = Vec::with_capacity(child_count);
    stencils.apply(mesh.positions(), &mut positions);

    // Topology.
    let mut soup = PolygonSoup::with_capacity(child_count, 4 * mesh.face_count(), 4 * mesh.half_edge_count());
    for p in positions {
        soup.push_vertex(p);
    }
    let mut holes = Vec::new();
    for f in mesh.face_ids() {
        let halves: SmallVec<[HalfEdgeId; 8]> = mesh.face_half_edges(f).collect();
        let n = halves.len();
        let first_child = soup.face_count();
        for j in 0..n {
            let corner = mesh.origin(halves[j]);
            let after = numbering.edge(mesh.edge(halves[j]));
            let before = numbering.edge(mesh.edge(halves[(j + n - 1) % n]));
            if quads {
                let mut child = [corner, after, numbering.face(f), before];
                // OpenSubdiv rotates a quad's children so that the corner sits at position j.
                if n == 4 {
                    child.rotate_right(j);
                }
                soup.push_face(child);
            } else {
                let mut child = [corner, after, before];
                child.rotate_right(j);
                soup.push_face(child);
            }
        }
        if !quads {
            let e = |j: usize| numbering.edge(mesh.edge(halves[j]));
            soup.push_face([e(1), e(2), e(0)]);
        }
        if mesh.is_hole(f) {
            holes.extend((first_child..soup.face_count()).map(|c| FaceId::new(c as u32)));
        }
    }
    soup.tags = Tags {
        boundary_interpolation: mesh.tags().boundary_interpolation,
        crease_method: mesh.tags().crease_method,
        triangle_subdivision: mesh.tags().triangle_subdivision,
        face_varying_interpolation: mesh.tags().face_varying_interpolation,
        ..Tags::default()
    };
    let mut child =
        Mesh::build(soup).map_err(|e| SchemeError::Internal(format!("the refined mesh is invalid: {e}")))?;

    // Sharpness and holes of the child level.
    for f in holes {
        child.set_hole(f, true);
    }
    for v in mesh.vertices() {
        child.set_vertex_sharpness(v, f64::from(crease::decrement(sharpness(mesh.vertex_sharpness(v)))));
        let edges = vertex_edges(mesh, v);
        let around: SmallVec<[f32; 8]> = edges.iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
        for (&(e, _), &s) in edges.iter().zip(&around) {
            if crease::is_sharp(s) {
                let half = child
                    .find_edge(v, numbering.edge(e))
                    .ok_or_else(|| SchemeError::Internal(format!("the child of edge {e} at {v} is missing")))?;
                child.set_edge_sharpness(half, f64::from(crease::child_edge_sharpness(method, s, &around)));
            }
        }
    }
    Ok((child, stencils))
}

/// The stencil of the point of edge `e`.
fn edge_row(mesh: &Mesh, scheme: Scheme, rules: Rules, e: EdgeId) -> Row {
    let h = mesh.edge_half_edge(e);
    let (a, b) = (mesh.origin(h).raw(), mesh.dest(h).raw());
    let mut midpoint = Row::default();
    midpoint.add(a, 0.5);
    midpoint.add(b, 0.5);
    let s = sharpness(mesh.edge_sharpness(e));
    let twin = mesh.twin(h);
    let smooth = match (scheme, twin) {
        (Scheme::Bilinear, _) | (_, None) => midpoint.clone(),
        (Scheme::CatmullClark, Some(t)) => {
            let (g0, g1) = (mesh.face(h), mesh.face(t));
            let (tri0, tri1) = (mesh.face_size(g0) == 3, mesh.face_size(g1) == 3);
            let (vertex_weight, face_weight) = if rules.smooth_triangles && (tri0 || tri1) {
                // OpenSubdiv's (and Hbr's) "smooth triangle" weights, in their order of operations.
                const TRIANGLE_FACE_WEIGHT: f64 = 0.470;
                let w0 = if tri0 { TRIANGLE_FACE_WEIGHT } else { 0.25 };
                let w1 = if tri1 { TRIANGLE_FACE_WEIGHT } else { 0.25 };
                let face_weight = 0.5 * (w0 + w1);
                (0.5 * (1.0 - 2.0 * face_weight), face_weight)
            } else {
                (0.25, 0.25)
            };
            let mut row = Row::default();
            row.add(a, vertex_weight);
            row.add(b, vertex_weight);
            row.add_row(&face_point(mesh, g0), face_weight);
            row.add_row(&face_point(mesh, g1), face_weight);
            row
        }
        (Scheme::Loop, Some(t)) => {
            let mut row = Row::default();
            row.add(a, 0.375);
            row.add(b, 0.375);
            row.add(mesh.origin(mesh.prev(h)).raw(), 0.125);
            row.add(mesh.origin(mesh.prev(t)).raw(), 0.125);
            row
        }
    };
    if !crease::is_sharp(s) || scheme == Scheme::Bilinear {
        return smooth;
    }
    // The child vertex is a crease if both halves stay sharp; otherwise blend by sharpness.
    let half = |v: VertexId| {
        let around: SmallVec<[f32; 8]> =
            vertex_edges(mesh, v).iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
        crease::child_edge_sharpness(rules.crease_method, s, &around)
    };
    if crease::is_sharp(half(mesh.origin(h))) && crease::is_sharp(half(mesh.dest(h))) {
        return midpoint;
    }
    midpoint.blend(&smooth, f64::from(s))
}

/// The stencil of the centroid of face `f`.
fn face_point(mesh: &Mesh, f: FaceId) -> Row {
    let face = mesh.face_vertices(f);
    let mut row = Row::default();
    for v in face {
        row.add(v.raw(), 1.0 / face.len() as f64);
    }
    row
}

/// The stencil of the child of vertex `v`: OpenSubdiv's smooth, crease or corner mask, or a
/// blend of the parent's and the child's where a semi-sharp feature fades out.
fn vertex_row(mesh: &Mesh, scheme: Scheme, method: CreaseMethod, v: VertexId) -> Row {
    if scheme == Scheme::Bilinear || mesh.is_isolated(v) {
        return Row::single(v.raw());
    }
    let edges = vertex_edges(mesh, v);
    let parent_edges: SmallVec<[f32; 8]> = edges.iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
    let parent_vertex = sharpness(mesh.vertex_sharpness(v));
    let smooth = || -> Row {
        let n = edges.len() as f64;
        let mut row = Row::default();
        match scheme {
            Scheme::CatmullClark => {
                row.add(v.raw(), (n - 2.0) / n);
                for &(_, w) in &edges {
                    row.add(w.raw(), 1.0 / (n * n));
                }
                for f in mesh.vertex_faces(v) {
                    row.add_row(&face_point(mesh, f), 1.0 / (n * n));
                }
            }
            _ => {
                let beta = if edges.len() == 6 {
                    0.0625
                } else {
                    let c = 0.375 + 0.25 * (std::f64::consts::TAU / n).cos();
                    (0.625 - c * c) / n
                };
                row.add(v.raw(), 1.0 - n * beta);
                for &(_, w) in &edges {
                    row.add(w.raw(), beta);
                }
            }
        }
        row
    };
    let crease_along = |sharp: &[f32]| -> Row {
        let mut row = Row::default();
        row.add(v.raw(), 0.75);
        for (&(_, w), _) in edges.iter().zip(sharp).filter(|&(_, &s)| crease::is_sharp(s)).take(2) {
            row.add(w.raw(), 0.125);
        }
        row
    };
    let mask = |rule: Rule, sharp: &[f32]| match rule {
        Rule::Smooth | Rule::Dart => smooth(),
        Rule::Crease => crease_along(sharp),
        Rule::Corner => Row::single(v.raw()),
    };
    let parent_rule = crease::vertex_rule(parent_vertex, &parent_edges);
    if matches!(parent_rule, Rule::Smooth | Rule::Dart) {
        return smooth();
    }
    let child_vertex = crease::decrement(parent_vertex);
    let child_edges: SmallVec<[f32; 8]> =
        parent_edges.iter().map(|&s| crease::child_edge_sharpness(method, s, &parent_edges)).collect();
    let child_rule = crease::vertex_rule(child_vertex, &child_edges);
    if child_rule == parent_rule {
        return mask(parent_rule, &parent_edges);
    }
    let w = f64::from(crease::fractional_weight(parent_vertex, child_vertex, &parent_edges, &child_edges));
    mask(parent_rule, &parent_edges).blend(&mask(child_rule, &child_edges), w)
}
