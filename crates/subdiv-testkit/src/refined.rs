//! Refined faces as parameters of the base faces they come from: what compares a refinement
//! (OpenSubdiv's `osd_refine --limit`) with an evaluation at dyadic points.

use std::collections::HashSet;

use subdiv_mesh::{FaceId, Mesh, VertexId};
use subdiv_schemes::{Builtin, ChildDomain, RefineOptions, Split, child_faces, refine};
use subdiv_stencil::{Dyadic, FaceDomain};

/// Each vertex of `mesh` refined `levels` times as a base face's parameter, with the refined
/// mesh (`None` for a vertex no face reaches).
///
/// # Panics
/// As [`refined_corners`].
pub fn refined_parameters(mesh: &Mesh, split: Split, levels: usize) -> (Mesh, Vec<Option<(FaceId, Dyadic)>>) {
    let (current, faces) = refined_corners(mesh, split, levels);
    let mut at = vec![None; current.vertex_count()];
    for (f, (base, corners)) in faces.iter().enumerate() {
        for (k, &v) in current.face_vertices(FaceId::new(f as u32)).iter().enumerate() {
            at[v.index()].get_or_insert((*base, corners[k]));
        }
    }
    (current, at)
}

/// `mesh` refined `levels` times, with each refined face's base face and the base parameters of
/// its corners (in the base face's domain, as [`FaceDomain`] lays it out).
///
/// # Panics
/// When `split` is not a primal split, or the refinement fails.
pub fn refined_corners(mesh: &Mesh, split: Split, levels: usize) -> (Mesh, Vec<(FaceId, Vec<Dyadic>)>) {
    // Per face of the current level: its base face and the base parameters of its corners.
    let mut current = mesh.clone();
    let mut faces: Vec<(FaceId, Vec<Dyadic>)> = Vec::new();
    let scheme = match split {
        Split::Triangle => Builtin::Loop.scheme(),
        _ => Builtin::CatmullClark.scheme(),
    };
    for level in 0..levels {
        let child = refine(&current, scheme, &RefineOptions::DEFAULT).unwrap();
        let mut next = vec![(FaceId::new(0), Vec::new()); child.face_count()];
        for f in current.face_ids() {
            let size = current.face_size(f);
            let Some(range) = child_faces(split, &current, f) else { unreachable!("a primal split") };
            for (j, c) in range.enumerate() {
                let corners = corner_points(child.face_size(FaceId::new(c as u32)));
                let base: Vec<Dyadic> = if level == 0 {
                    let domain = FaceDomain::of(split, size).unwrap();
                    match domain {
                        FaceDomain::SubFaces { .. } => corners.iter().map(|&p| domain.from_sub_face(j, p)).collect(),
                        _ => corners.iter().map(|&p| to_parent(ChildDomain::of_face(size)[j], p)).collect(),
                    }
                } else {
                    let (_, parent) = &faces[f.index()];
                    corners
                        .iter()
                        .map(|&p| interpolate(parent, to_parent(ChildDomain::of_face(size)[j], p), size))
                        .collect()
                };
                next[c] = (if level == 0 { f } else { faces[f.index()].0 }, base);
            }
        }
        faces = next;
        current = child;
    }
    (current, faces)
}

/// The corners of a face's own domain: the unit triangle (size 3) or the unit square.
pub fn corner_points(size: usize) -> Vec<Dyadic> {
    let d = |u, v| Dyadic::new(u, v, 1);
    if size == 3 { vec![d(0, 0), d(1, 0), d(0, 1)] } else { vec![d(0, 0), d(1, 0), d(1, 1), d(0, 1)] }
}

fn to_parent(child: ChildDomain, p: Dyadic) -> Dyadic {
    let sign = if child.flipped { -1 } else { 1 };
    let (o0, o1) = (i64::from(child.offset[0]), i64::from(child.offset[1]));
    Dyadic::new(sign * p.u + o0 * p.denominator, sign * p.v + o1 * p.denominator, 2 * p.denominator).reduced()
}

/// The base parameter of the point `p` of a face whose corners are at `corners` (an affine
/// map: bilinear interpolation is affine on these parallelogram images).
fn interpolate(corners: &[Dyadic], p: Dyadic, size: usize) -> Dyadic {
    let (a, b, c) = if size == 3 { (corners[0], corners[1], corners[2]) } else { (corners[0], corners[1], corners[3]) };
    let den = p.denominator * a.denominator * b.denominator * c.denominator;
    let at = |q: Dyadic, x: i64| x * (den / q.denominator);
    let (pu, pv, pd) = (p.u, p.v, p.denominator);
    let u = at(a, a.u) * pd + (at(b, b.u) - at(a, a.u)) * pu + (at(c, c.u) - at(a, a.u)) * pv;
    let v = at(a, a.v) * pd + (at(b, b.v) - at(a, a.v)) * pu + (at(c, c.v) - at(a, a.v)) * pv;
    Dyadic::new(u, v, den * pd).reduced()
}

/// Darts (one sharp edge, no sharp vertex, interior) and interior valence-2 vertices of `mesh`,
/// with their one-rings: where Far's limit masks are not the limit (the peer harness's README).
pub fn far_limit_exceptions(mesh: &Mesh) -> HashSet<VertexId> {
    let mut out = HashSet::new();
    for v in mesh.vertices().filter(|&v| !mesh.is_isolated(v) && !mesh.is_boundary_vertex(v)) {
        let sharp = mesh.outgoing(v).filter(|&h| mesh.edge_sharpness(mesh.edge(h)) > 0.0).count();
        if (sharp == 1 && mesh.vertex_sharpness(v) == 0.0) || mesh.valence(v) == 2 {
            out.insert(v);
            out.extend(mesh.one_ring(v));
        }
    }
    out
}
