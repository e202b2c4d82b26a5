//! The splits that do not keep the old vertices in place: dual (Doo-Sabin), mid-edge
//! (Peters-Reif) and √3 (Kobbelt). They take closed meshes (checked before).
//!
//! Child numbering: Doo-Sabin numbers its points by face corner (the parent's half-edge
//! index), mid-edge by parent edge, √3 keeps the old vertices first and then one point per
//! face. Child faces: Doo-Sabin and mid-edge list the faces made from parent faces, then (Doo-
//! Sabin) those from edges, then those from vertices; √3 has one triangle per half-edge.

use subdiv_mesh::{HalfEdgeId, Mesh, PolygonSoup, VertexId};

use crate::scheme::{VertexMask, vertex_weights};
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
/// face's vertices `v_j`, `j` counted from `h`'s corner.
pub(crate) fn doo_sabin(mesh: &Mesh, own: &Expr, corner: &Expr) -> Result<(Mesh, Stencils), SchemeError> {
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
    let mut stencils = Stencils::with_capacity(mesh.half_edge_count(), 4 * mesh.half_edge_count(), mesh.vertex_count());
    for f in mesh.face_ids() {
        let vertices = mesh.face_vertices(f);
        let n = vertices.len();
        let w = weights[n].as_ref().expect("every face size was weighed");
        for i in 0..n {
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
        let t = mesh.twin(h).ok_or_else(|| SchemeError::Internal("Doo-Sabin met a boundary edge".into()))?;
        soup.push_face([corner(mesh.next(h)), corner(h), corner(mesh.next(t)), corner(t)]);
    }
    for v in mesh.vertices().filter(|&v| !mesh.is_isolated(v)) {
        soup.push_face(mesh.outgoing(v).map(corner));
    }
    finish(mesh, stencils, soup)
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
pub(crate) fn sqrt3(mesh: &Mesh, vertex: &VertexMask) -> Result<(Mesh, Stencils), SchemeError> {
    let nv = mesh.vertex_count();
    let mut stencils = Stencils::with_capacity(nv + mesh.face_count(), 16 * nv, nv);
    for v in mesh.vertices() {
        let ring = mesh.one_ring(v);
        let (centre, spoke, _) = vertex_weights(vertex, ring.len());
        let mut row = Row::default();
        row.add(v.raw(), if ring.is_empty() { 1.0 } else { centre });
        for w in ring {
            row.add(w.raw(), spoke);
        }
        stencils.push(&row);
    }
    for f in mesh.face_ids() {
        let mut row = Row::default();
        for v in mesh.face_vertices(f) {
            row.add(v.raw(), 1.0 / 3.0);
        }
        stencils.push(&row);
    }
    let face_point = |h: HalfEdgeId| VertexId::new(nv as u32 + mesh.face(h).raw());
    let mut soup =
        PolygonSoup::with_capacity(nv + mesh.face_count(), mesh.half_edge_count(), 3 * mesh.half_edge_count());
    for f in mesh.face_ids() {
        for h in mesh.face_half_edges(f) {
            let t = mesh.twin(h).ok_or_else(|| SchemeError::Internal("√3 met a boundary edge".into()))?;
            soup.push_face([mesh.origin(h), face_point(t), face_point(h)]);
        }
    }
    finish(mesh, stencils, soup)
}
