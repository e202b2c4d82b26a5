//! The splits that do not keep the old vertices in place: dual (Doo-Sabin), mid-edge
//! (Peters-Reif) and √3 (Kobbelt). The dual split takes boundaries by its [`DualBoundary`]
//! rule; the others closed meshes (checked before).
//!
//! Child numbering: Doo-Sabin numbers its points by face corner (the parent's half-edge
//! index), mid-edge by parent edge, √3 keeps the old vertices first and then one point per
//! face. Child faces: Doo-Sabin and mid-edge list the faces made from parent faces, then (Doo-
//! Sabin) those from edges, then those from vertices; √3 has one triangle per half-edge.

use subdiv_mesh::{HalfEdgeId, Mesh, PolygonSoup, VertexId};

use crate::scheme::{DualBoundary, VertexMask, vertex_weights};
use crate::stencil::{Row, Stencils};
use crate::{Expr, SchemeError};

/// The child mesh: `soup` holds the child faces; the positions come from the stencils.
fn finish(mesh: &Mesh, stencils: Stencils, mut soup: PolygonSoup) -> Result<(Mesh, Stencils), SchemeError> {
    let mut positions = Vec::with_capacity(stencils.child_count());
    stencils.apply(mesh.positions(), &mut positions);
    for p in positions {
        soup.push_vertex(p);
    }
    let child = Mesh::build(soup).map_err(|e| SchemeError::Internal(format!("the refined mesh is invalid: {e}")))?;
    Ok((child, stencils))
}

/// Doo-Sabin: the point of corner `h` is `own · origin(h) + Σ_j corner(n, j) · v_j` over the
/// face's vertices `v_j`, `j` counted from `h`'s corner. At boundaries (where `boundary` allows
/// them), a corner on a boundary edge takes the boundary rule instead, a boundary edge has no
/// edge face and a boundary vertex has a vertex face only where it has three faces or more
/// (with two, the edge face between them closes the boundary).
pub(crate) fn doo_sabin(
    mesh: &Mesh,
    own: &Expr,
    corner: &Expr,
    boundary: Option<DualBoundary>,
) -> Result<(Mesh, Stencils), SchemeError> {
    // The weights of each face size the mesh has (only those: an n-gon's take n evaluations).
    let mut weights: Vec<Option<Vec<f64>>> = Vec::new();
    for f in mesh.face_ids() {
        let n = mesh.face_size(f);
        if weights.len() <= n {
            weights.resize(n + 1, None);
        }
        weights[n].get_or_insert_with(|| {
            let mut w: Vec<f64> = (0..n).map(|j| corner.eval(n, j)).collect();
            w[0] += own.eval(n, 0);
            w
        });
    }
    let open = |h: HalfEdgeId| mesh.twin(h).is_none();
    let mut stencils = Stencils::with_capacity(mesh.half_edge_count(), 4 * mesh.half_edge_count(), mesh.vertex_count());
    for f in mesh.face_ids() {
        let vertices = mesh.face_vertices(f);
        let n = vertices.len();
        let w = weights[n].as_ref().expect("every face size was weighed");
        for (i, h) in mesh.face_half_edges(f).enumerate() {
            let (after, before) = (open(h), open(mesh.prev(h)));
            if after || before {
                let rule = boundary.ok_or_else(|| SchemeError::Internal("Doo-Sabin met a boundary edge".into()))?;
                let toward = match (after, before) {
                    (true, true) => None,
                    (true, false) => Some(vertices[(i + 1) % n]),
                    _ => Some(vertices[(i + n - 1) % n]),
                };
                stencils.push(&boundary_corner(rule, vertices[i], toward));
                continue;
            }
            // A face's corners are distinct vertices: no search for equal parents (an n-gon's
            // rows cost n², not n³).
            let row = Row::of_distinct((0..n).map(|j| (vertices[(i + j) % n].raw(), w[j])));
            stencils.push(&row);
        }
    }
    let corner = |h: HalfEdgeId| VertexId::new(h.raw());
    let faces = mesh.face_count() + mesh.edge_count() + mesh.vertex_count();
    let mut soup = PolygonSoup::with_capacity(mesh.half_edge_count(), faces, 3 * mesh.half_edge_count());
    for f in mesh.face_ids() {
        soup.push_face(mesh.face_half_edges(f).map(corner));
    }
    for e in mesh.edges() {
        let h = mesh.edge_half_edge(e);
        if let Some(t) = mesh.twin(h) {
            soup.push_face([corner(mesh.next(h)), corner(h), corner(mesh.next(t)), corner(t)]);
        }
    }
    // A boundary vertex's fan runs from boundary to boundary ([`Mesh::outgoing`]), so its
    // corners close into a face whose last side is on the boundary.
    for v in mesh.vertices().filter(|&v| !mesh.is_isolated(v)) {
        if !mesh.is_boundary_vertex(v) || mesh.outgoing(v).nth(2).is_some() {
            soup.push_face(mesh.outgoing(v).map(corner));
        }
    }
    finish(mesh, stencils, soup)
}

/// The point of a face corner at `vertex` on a boundary edge whose far end is `toward`, or on
/// two (`None`: the face is the vertex's only one).
fn boundary_corner(rule: DualBoundary, vertex: VertexId, toward: Option<VertexId>) -> Row {
    let mut row = Row::default();
    match (rule, toward) {
        (DualBoundary::Chaikin, Some(far)) => {
            row.add(vertex.raw(), 0.75);
            row.add(far.raw(), 0.25);
        }
        (DualBoundary::Chaikin, None) => row.add(vertex.raw(), 1.0),
    }
    row
}

/// Mid-edge: a point at the middle of every edge; a face per old face (its edge points) and
/// per old vertex (the points of its edges).
pub(crate) fn midedge(mesh: &Mesh) -> Result<(Mesh, Stencils), SchemeError> {
    let mut stencils = Stencils::with_capacity(mesh.edge_count(), 2 * mesh.edge_count(), mesh.vertex_count());
    for e in mesh.edges() {
        let [a, b] = mesh.edge_vertices(e);
        let mut row = Row::default();
        row.add(a.raw(), 0.5);
        row.add(b.raw(), 0.5);
        stencils.push(&row);
    }
    let edge = |h: HalfEdgeId| VertexId::new(mesh.edge(h).raw());
    let faces = mesh.face_count() + mesh.vertex_count();
    let mut soup = PolygonSoup::with_capacity(mesh.edge_count(), faces, 2 * mesh.half_edge_count());
    for f in mesh.face_ids() {
        soup.push_face(mesh.face_half_edges(f).map(edge));
    }
    for v in mesh.vertices().filter(|&v| !mesh.is_isolated(v)) {
        soup.push_face(mesh.outgoing(v).map(edge));
    }
    finish(mesh, stencils, soup)
}

/// √3: old vertices relaxed by the vertex mask, a centroid per triangle, and one triangle per
/// half-edge `h` (face `F`, twin in face `G`): `origin(h)`, the point of `G`, the point of `F`.
///
/// Open meshes follow Kobbelt (2000, §5): the steps alternate, and the boundary is refined
/// every second one (`split_boundary`) by the ternary cubic B-spline rule. A step that keeps it
/// keeps the boundary vertices in place and splits a boundary triangle `l r x` (boundary edge
/// `l → r`) into three as any other, its boundary edge unflipped: the triangle `l r c_F`. A step
/// that splits it puts two points `a`, `b` on each boundary edge, `(16 l + 10 r + l')/27` and
/// `(10 l + 16 r + r')/27` (`l'`, `r'` the ends' other boundary neighbours), relaxes the boundary
/// vertices by `(4, 19, 4)/27` along the boundary, and fans a boundary triangle from its far
/// corner `x` instead of giving it a centroid: `a b x` stays, and its sides `x → l`, `r → x` flip
/// with the neighbours as the interior edges do, `a` (or `b`) taking the place of the centroid
/// on the side where it lies. The step before a splitting one leaves one boundary edge per
/// triangle, which the split needs.
///
/// Numbering: the old vertices, then a point per face (a boundary triangle's `a` when it is
/// split), then the `b`s of the split boundary triangles in face order.
pub(crate) fn sqrt3(mesh: &Mesh, vertex: &VertexMask, split_boundary: bool) -> Result<(Mesh, Stencils), SchemeError> {
    let nv = mesh.vertex_count();
    let open = |h: HalfEdgeId| mesh.twin(h).is_none();
    // Per face, its boundary half-edge when the step splits it.
    let mut boundary_of: Vec<Option<HalfEdgeId>> = vec![None; mesh.face_count()];
    let mut second = Vec::new();
    if split_boundary {
        for f in mesh.face_ids() {
            let mut edges = mesh.face_half_edges(f).filter(|&h| open(h));
            if let Some(h) = edges.next() {
                if edges.next().is_some() {
                    return Err(SchemeError::Internal(format!(
                        "√3 split a boundary at {f}, which has more than one boundary edge (the step before \
                         should have split it)"
                    )));
                }
                boundary_of[f.index()] = Some(h);
                second.push(f);
            }
        }
    }
    let b_point: std::collections::HashMap<u32, u32> =
        second.iter().enumerate().map(|(i, f)| (f.raw(), (nv + mesh.face_count() + i) as u32)).collect();
    let mut stencils = Stencils::with_capacity(nv + mesh.face_count() + second.len(), 16 * nv, nv);
    // A boundary vertex's two boundary neighbours: the ends of its one-ring.
    let boundary_neighbours = |v: VertexId| {
        let ring = mesh.one_ring(v);
        (ring[0], ring[ring.len() - 1])
    };
    for v in mesh.vertices() {
        let mut row = Row::default();
        if mesh.is_boundary_vertex(v) {
            if split_boundary {
                let (p, q) = boundary_neighbours(v);
                row.add(v.raw(), 19.0 / 27.0);
                row.add(p.raw(), 4.0 / 27.0);
                row.add(q.raw(), 4.0 / 27.0);
            } else {
                row.add(v.raw(), 1.0);
            }
            stencils.push(&row);
            continue;
        }
        let ring = mesh.one_ring(v);
        let (centre, spoke, _) = vertex_weights(vertex, ring.len());
        row.add(v.raw(), if ring.is_empty() { 1.0 } else { centre });
        for w in ring {
            row.add(w.raw(), spoke);
        }
        stencils.push(&row);
    }
    // The point of a split boundary edge `l → r` next to `near`, from `far`'s side.
    let third = |near: VertexId, far: VertexId| {
        let (p, q) = boundary_neighbours(near);
        let beyond = if p == far { q } else { p };
        let mut row = Row::default();
        row.add(near.raw(), 16.0 / 27.0);
        row.add(far.raw(), 10.0 / 27.0);
        row.add(beyond.raw(), 1.0 / 27.0);
        row
    };
    for f in mesh.face_ids() {
        let row = match boundary_of[f.index()] {
            Some(h) => third(mesh.origin(h), mesh.dest(h)),
            None => {
                let mut row = Row::default();
                for v in mesh.face_vertices(f) {
                    row.add(v.raw(), 1.0 / 3.0);
                }
                row
            }
        };
        stencils.push(&row);
    }
    for &f in &second {
        let h = boundary_of[f.index()].expect("a split boundary face");
        stencils.push(&third(mesh.dest(h), mesh.origin(h)));
    }
    // The point that stands for `h`'s face on `h`'s side: the centroid, or the split boundary
    // edge's point at the end `h` shares with it.
    let point = |h: HalfEdgeId| {
        let f = mesh.face(h);
        let a = VertexId::new(nv as u32 + f.raw());
        match boundary_of[f.index()] {
            Some(b) if mesh.dest(h) == mesh.origin(b) => a,
            Some(_) => VertexId::new(b_point[&f.raw()]),
            None => a,
        }
    };
    let mut soup = PolygonSoup::with_capacity(
        nv + mesh.face_count() + second.len(),
        mesh.half_edge_count(),
        3 * mesh.half_edge_count(),
    );
    for f in mesh.face_ids() {
        for h in mesh.face_half_edges(f) {
            let centre = VertexId::new(nv as u32 + f.raw());
            let triangle = match (mesh.twin(h), boundary_of[f.index()]) {
                (Some(t), _) => [mesh.origin(h), point(t), point(h)],
                (None, Some(_)) => [centre, VertexId::new(b_point[&f.raw()]), mesh.dest(mesh.next(h))],
                (None, None) => [mesh.origin(h), mesh.dest(h), centre],
            };
            soup.push_face(triangle);
        }
    }
    finish(mesh, stencils, soup)
}
