//! Half-edge invariants over the generated meshes (`subdiv_mesh::strategies`: every procedural
//! shape, closed and open, N-gons, creases), under random relabelling of vertices, random face
//! order and random starting corners; orientation errors and their repair.

use std::collections::HashSet;

use proptest::prelude::*;
use subdiv_mesh::strategies::{MeshParams, meshes, relabelled};
use subdiv_mesh::{BuildOptions, FaceId, Mesh, MeshError, PolygonSoup, VertexId, shapes};

/// Valid meshes of every kind the strategies make (every procedural shape among them), each
/// with at least two faces (a lone face flipped is still consistent), with a copy whose vertices are renamed, faces reordered and corners rotated.
fn relabelled_pairs() -> impl Strategy<Value = (PolygonSoup, PolygonSoup)> {
    meshes(MeshParams::DEFAULT.with_valences(3..=16).with_min_faces(2))
        .prop_flat_map(|soup| (Just(soup.clone()), relabelled(soup)))
}

/// V − E + F counted on the soup itself (used vertices, distinct undirected edges), without the
/// half-edge structure.
fn euler_of(soup: &PolygonSoup) -> i64 {
    let vertices: HashSet<VertexId> = soup.faces().flatten().copied().collect();
    let edges: HashSet<(VertexId, VertexId)> = soup
        .faces()
        .flat_map(|f| (0..f.len()).map(move |i| (f[i].min(f[(i + 1) % f.len()]), f[i].max(f[(i + 1) % f.len()]))))
        .collect();
    vertices.len() as i64 - edges.len() as i64 + soup.face_count() as i64
}

fn check_invariants(mesh: &Mesh, euler: i64) {
    for f in mesh.face_ids() {
        // `next` cycles through the face, `prev` inverts it.
        let halves: Vec<_> = mesh.face_half_edges(f).collect();
        let mut h = halves[0];
        for (i, &expected) in halves.iter().enumerate() {
            assert_eq!(h, expected);
            assert_eq!(mesh.face(h), f);
            assert_eq!(mesh.origin(h), mesh.face_vertices(f)[i]);
            assert_eq!(mesh.prev(mesh.next(h)), h);
            h = mesh.next(h);
        }
        assert_eq!(h, halves[0]);
        for &h in &halves {
            if let Some(t) = mesh.twin(h) {
                assert_eq!(mesh.twin(t), Some(h), "twin of twin");
                assert_ne!(mesh.face(t), f);
                assert_eq!((mesh.origin(t), mesh.dest(t)), (mesh.dest(h), mesh.origin(h)), "twins run opposite");
                assert_eq!(mesh.edge(t), mesh.edge(h));
            }
        }
    }
    // Ordered, complete fans: every outgoing half-edge exactly once, consecutive ones adjacent.
    let mut seen = vec![false; mesh.half_edge_count()];
    for v in mesh.vertices() {
        let fan: Vec<_> = mesh.outgoing(v).collect();
        let boundary = mesh.is_boundary_vertex(v);
        assert_eq!(mesh.valence(v), fan.len() + usize::from(boundary));
        assert_eq!(mesh.one_ring(v).len(), mesh.valence(v));
        if boundary {
            assert!(mesh.twin(fan[0]).is_none(), "a boundary fan starts at its boundary edge");
            assert!(mesh.twin(mesh.prev(*fan.last().unwrap())).is_none(), "and ends at one");
        }
        for pair in fan.windows(2) {
            assert_eq!(mesh.twin(mesh.prev(pair[0])), Some(pair[1]), "fan order is counter-clockwise");
        }
        for h in fan {
            assert_eq!(mesh.origin(h), v);
            assert!(!std::mem::replace(&mut seen[h.index()], true));
        }
    }
    assert!(seen.iter().all(|&s| s), "every half-edge leaves some vertex's fan");
    assert_eq!(mesh.euler_characteristic(), euler);
    for e in mesh.edges() {
        let [a, b] = mesh.edge_vertices(e);
        assert_eq!(mesh.find_edge(a, b), Some(e));
        assert_eq!(mesh.find_edge(b, a), Some(e));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn half_edge_invariants_hold_under_relabelling((soup, relabelled) in relabelled_pairs()) {
        let euler = euler_of(&soup);
        let mesh = Mesh::build(relabelled).unwrap();
        check_invariants(&mesh, euler);
        let original = Mesh::build(soup).unwrap();
        prop_assert_eq!(mesh.edge_count(), original.edge_count());
        prop_assert_eq!(mesh.valence_histogram(), original.valence_histogram());
        prop_assert_eq!(mesh.genus(), original.genus());
    }

    #[test]
    fn one_flipped_face_is_reported_and_repaired((soup, relabelled) in relabelled_pairs(), which: usize) {
        let euler = euler_of(&soup);
        let mut soup = relabelled;
        let flipped = FaceId::new((which % soup.face_count()) as u32);
        soup.flip_face(flipped);
        let error = Mesh::build(soup.clone()).unwrap_err();
        prop_assert!(matches!(error, MeshError::InconsistentOrientation { face, other, .. } if face == flipped || other == flipped),
            "{error}");
        let repaired = Mesh::build_with(soup.clone(), &BuildOptions::default().with_orient(true)).unwrap();
        check_invariants(&repaired, euler);
        // Only the flipped face changed: the majority orientation wins (with two faces it is a
        // tie, which the lowest face wins).
        if soup.face_count() == 2 {
            return Ok(());
        }
        let mut expected = soup;
        expected.flip_face(flipped);
        for (f, face) in repaired.faces().enumerate() {
            prop_assert_eq!(face, expected.face(FaceId::new(f as u32)));
        }
    }
}

#[test]
fn bow_tie_is_a_non_manifold_vertex() {
    // Two triangles touching at vertex 0 only.
    let soup = PolygonSoup::from_indices(vec![Default::default(); 5], [[0u32, 1, 2], [0, 3, 4]]);
    let error = Mesh::build(soup).unwrap_err();
    assert_eq!(error, MeshError::NonManifoldVertex { vertex: VertexId::new(0), fans: 2 });
}

#[test]
fn three_faces_on_an_edge_are_a_non_manifold_edge() {
    let soup = PolygonSoup::from_indices(vec![Default::default(); 5], [[0u32, 1, 2], [1, 0, 3], [0, 1, 4]]);
    let error = Mesh::build(soup).unwrap_err();
    assert!(
        matches!(error, MeshError::NonManifoldEdge { face_count: 3, face, .. } if face == FaceId::new(0)),
        "{error}"
    );
}

#[test]
fn moebius_strip_cannot_be_oriented() {
    // A strip of 5 quads whose ends are glued with a half twist.
    let n = 5u32;
    let positions = vec![Default::default(); 2 * n as usize];
    let faces: Vec<[u32; 4]> =
        (0..n).map(|i| if i + 1 < n { [i, i + 1, n + i + 1, n + i] } else { [i, n, 0, n + i] }).collect();
    let soup = PolygonSoup::from_indices(positions, faces);
    assert!(matches!(Mesh::build(soup.clone()), Err(MeshError::InconsistentOrientation { .. })));
    let error = Mesh::build_with(soup, &BuildOptions::default().with_orient(true)).unwrap_err();
    assert!(matches!(error, MeshError::NonOrientable { .. }), "{error}");
}

#[test]
fn validate_lists_every_problem_once() {
    let mut positions = vec![Default::default(); 8];
    positions[7] = subdiv_mesh::DVec3::new(f64::NAN, 0.0, 0.0);
    let soup = PolygonSoup::from_indices(positions, [&[0u32, 1][..], &[2, 3, 3], &[4, 5, 9], &[0, 1, 2], &[0, 2, 6]]);
    let rules: Vec<_> = subdiv_mesh::validate(&soup).iter().map(|e| e.rule()).collect();
    assert_eq!(rules, ["non-finite-coordinate", "too-few-vertices", "repeated-vertex", "index-out-of-range"]);
}

#[test]
fn isolated_vertices_are_allowed_and_left_out_of_the_counts() {
    let mut soup = shapes::cube();
    let isolated = soup.push_vertex(Default::default());
    let mesh = Mesh::build(soup).unwrap();
    assert!(mesh.is_isolated(isolated));
    assert_eq!(mesh.valence(isolated), 0);
    assert_eq!(mesh.euler_characteristic(), 2);
    assert_eq!(mesh.genus(), Some(0));
    assert_eq!(mesh.outgoing(isolated).count(), 0);
}

#[test]
fn k_rings_grow_ring_by_ring() {
    let mesh = Mesh::build(shapes::quad_grid(6, 6)).unwrap();
    let centre = VertexId::new(3 * 7 + 3);
    let rings = mesh.k_ring(centre, 2);
    assert_eq!(rings.iter().map(Vec::len).collect::<Vec<_>>(), [1, 4, 8]);
}

#[test]
fn tags_resolve_to_edges_vertices_and_faces() {
    let mut soup = shapes::cube();
    soup.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [VertexId::new(0), VertexId::new(1)], sharpness: 2.5 });
    soup.tags.corners.push(subdiv_mesh::CornerTag { vertex: VertexId::new(7), sharpness: 10.0 });
    soup.tags.holes.push(FaceId::new(2));
    let mesh = Mesh::build(soup.clone()).unwrap();
    let edge = mesh.find_edge(VertexId::new(1), VertexId::new(0)).unwrap();
    assert_eq!(mesh.edge_sharpness(edge), 2.5);
    assert_eq!(mesh.edges().filter(|&e| mesh.edge_sharpness(e) > 0.0).count(), 1);
    assert_eq!(mesh.vertex_sharpness(VertexId::new(7)), 10.0);
    assert!(mesh.is_hole(FaceId::new(2)) && !mesh.is_hole(FaceId::new(0)));
    // The soup again, with the tags as resolved: one crease per edge, corners, holes.
    let again = mesh.to_soup();
    assert_eq!((again.positions(), again.raw_faces()), (soup.positions(), soup.raw_faces()));
    assert_eq!(again.tags.creases, [subdiv_mesh::CreaseTag { vertices: mesh.edge_vertices(edge), sharpness: 2.5 }]);
    assert_eq!((&again.tags.corners, &again.tags.holes), (&soup.tags.corners, &soup.tags.holes));

    let mut bad = shapes::cube();
    bad.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [VertexId::new(0), VertexId::new(7)], sharpness: 1.0 });
    assert!(matches!(Mesh::build(bad), Err(MeshError::CreaseNotAnEdge { index: 0, .. })));
    let mut bad = shapes::cube();
    bad.tags.corners.push(subdiv_mesh::CornerTag { vertex: VertexId::new(0), sharpness: f64::NAN });
    assert!(matches!(Mesh::build(bad), Err(MeshError::InvalidSharpness { tag: "corner", .. })));
    let mut bad = shapes::cube();
    bad.tags.holes.push(FaceId::new(6));
    assert!(matches!(Mesh::build(bad), Err(MeshError::HoleOutOfRange { face: 6, .. })));
}
