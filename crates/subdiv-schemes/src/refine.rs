//! Uniform refinement: the topology split and OpenSubdiv's vertex rules (smooth, dart, crease,
//! corner, and the fractional blend where a semi-sharp feature fades out).

use glam::DVec3;
use smallvec::SmallVec;
use subdiv_mesh::{
    BoundaryInterpolation, CreaseMethod, EdgeId, FaceId, HalfEdgeId, Mesh, PolygonSoup, Tags, TriangleSubdivision,
    VertexId,
};

use crate::crease::{self, INFINITE, Rule};
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
    let mut current = prepared(mesh, options);
    for _ in 0..levels {
        current = refine_prepared(&current, scheme, options.rules_for(mesh))?;
    }
    Ok(current)
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

fn centroid(mesh: &Mesh, positions: &[DVec3], f: FaceId) -> DVec3 {
    let face = mesh.face_vertices(f);
    face.iter().map(|v| positions[v.index()]).sum::<DVec3>() / face.len() as f64
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

fn refine_prepared(mesh: &Mesh, scheme: Scheme, rules: Rules) -> Result<Mesh, SchemeError> {
    let method = rules.crease_method;
    let quads = scheme.splits_into_quads();
    if !quads && let Some(face) = mesh.face_ids().find(|&f| mesh.face_size(f) != 3) {
        return Err(SchemeError::FaceNotSupported { scheme, face, size: mesh.face_size(face), expected: 3 });
    }
    let nv = mesh.vertex_count() as u32;
    let face_points = if quads { mesh.face_count() as u32 } else { 0 };
    let numbering = Numbering { face_base: nv, edge_base: nv + face_points };
    let child_count = (numbering.edge_base as usize) + mesh.edge_count();

    // Geometry, in OpenSubdiv's order: face points, then edge points, then vertex points.
    let parent = mesh.positions();
    let mut positions = vec![DVec3::ZERO; child_count];
    if quads {
        for f in mesh.face_ids() {
            positions[numbering.face(f).index()] = centroid(mesh, parent, f);
        }
    }
    for e in mesh.edges() {
        positions[numbering.edge(e).index()] = edge_point(mesh, scheme, rules, e, &positions, &numbering);
    }
    for v in mesh.vertices() {
        positions[v.index()] = vertex_point(mesh, scheme, method, v, &positions, &numbering);
    }

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
    let mut child = Mesh::build(soup).map_err(SchemeError::Internal)?;

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
                let half = child.find_edge(v, numbering.edge(e)).ok_or_else(|| {
                    SchemeError::Internal(subdiv_mesh::MeshError::CreaseNotAnEdge {
                        index: 0,
                        a: v,
                        b: numbering.edge(e),
                    })
                })?;
                child.set_edge_sharpness(half, f64::from(crease::child_edge_sharpness(method, s, &around)));
            }
        }
    }
    Ok(child)
}

/// The two faces of edge `e` (one on a boundary) and the half-edge of the first.
fn edge_point(
    mesh: &Mesh,
    scheme: Scheme,
    rules: Rules,
    e: EdgeId,
    positions: &[DVec3],
    numbering: &Numbering,
) -> DVec3 {
    let h = mesh.edge_half_edge(e);
    let (a, b) = (mesh.origin(h), mesh.dest(h));
    let p = mesh.positions();
    let midpoint = (p[a.index()] + p[b.index()]) * 0.5;
    let s = sharpness(mesh.edge_sharpness(e));
    let twin = mesh.twin(h);
    let smooth = match (scheme, twin) {
        (Scheme::Bilinear, _) | (_, None) => midpoint,
        (Scheme::CatmullClark, Some(t)) => {
            let (g0, g1) = (mesh.face(h), mesh.face(t));
            let (f0, f1) = (positions[numbering.face(g0).index()], positions[numbering.face(g1).index()]);
            let (tri0, tri1) = (mesh.face_size(g0) == 3, mesh.face_size(g1) == 3);
            if rules.smooth_triangles && (tri0 || tri1) {
                // OpenSubdiv's (and Hbr's) "smooth triangle" weights, in their order of operations.
                const TRIANGLE_FACE_WEIGHT: f64 = 0.470;
                let w0 = if tri0 { TRIANGLE_FACE_WEIGHT } else { 0.25 };
                let w1 = if tri1 { TRIANGLE_FACE_WEIGHT } else { 0.25 };
                let face_weight = 0.5 * (w0 + w1);
                let vertex_weight = 0.5 * (1.0 - 2.0 * face_weight);
                (p[a.index()] + p[b.index()]) * vertex_weight + (f0 + f1) * face_weight
            } else {
                (p[a.index()] + p[b.index()] + f0 + f1) * 0.25
            }
        }
        (Scheme::Loop, Some(t)) => {
            let (o0, o1) = (mesh.origin(mesh.prev(h)), mesh.origin(mesh.prev(t)));
            (p[a.index()] + p[b.index()]) * 0.375 + (p[o0.index()] + p[o1.index()]) * 0.125
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
    if crease::is_sharp(half(a)) && crease::is_sharp(half(b)) {
        return midpoint;
    }
    let w = f64::from(s);
    midpoint * w + smooth * (1.0 - w)
}

fn vertex_point(
    mesh: &Mesh,
    scheme: Scheme,
    method: CreaseMethod,
    v: VertexId,
    positions: &[DVec3],
    numbering: &Numbering,
) -> DVec3 {
    let p = mesh.positions();
    let here = p[v.index()];
    if scheme == Scheme::Bilinear || mesh.is_isolated(v) {
        return here;
    }
    let edges = vertex_edges(mesh, v);
    let parent_edges: SmallVec<[f32; 8]> = edges.iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
    let parent_vertex = sharpness(mesh.vertex_sharpness(v));
    let smooth = || -> DVec3 {
        let n = edges.len() as f64;
        match scheme {
            Scheme::CatmullClark => {
                let ends: DVec3 = edges.iter().map(|&(_, w)| p[w.index()]).sum();
                let faces: DVec3 = mesh.vertex_faces(v).map(|f| positions[numbering.face(f).index()]).sum();
                here * ((n - 2.0) / n) + (ends + faces) / (n * n)
            }
            _ => {
                let beta = if edges.len() == 6 {
                    0.0625
                } else {
                    let c = 0.375 + 0.25 * (std::f64::consts::TAU / n).cos();
                    (0.625 - c * c) / n
                };
                let ends: DVec3 = edges.iter().map(|&(_, w)| p[w.index()]).sum();
                here * (1.0 - n * beta) + ends * beta
            }
        }
    };
    let crease_along = |sharp: &[f32]| -> DVec3 {
        let mut ends = edges.iter().zip(sharp).filter(|&(_, &s)| crease::is_sharp(s)).map(|(&(_, w), _)| p[w.index()]);
        let (a, b) = (ends.next().unwrap_or(here), ends.next().unwrap_or(here));
        here * 0.75 + (a + b) * 0.125
    };
    let mask = |rule: Rule, sharp: &[f32]| match rule {
        Rule::Smooth | Rule::Dart => smooth(),
        Rule::Crease => crease_along(sharp),
        Rule::Corner => here,
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
    mask(parent_rule, &parent_edges) * w + mask(child_rule, &child_edges) * (1.0 - w)
}
