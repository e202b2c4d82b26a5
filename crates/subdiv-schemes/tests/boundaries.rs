//! The boundary rules of the splits that do not keep old vertices in place: the boundary of an
//! open mesh refined by Doo-Sabin, mid-edge (two steps at a time) or √3 is the boundary polygon
//! refined by the rule's curve scheme alone (Chaikin's, the ternary cubic B-spline), checked
//! point for point against that curve rule written out here.

use glam::DVec3;
use subdiv_mesh::{HalfEdgeId, Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::{Builtin, RefineOptions, Refiner, SchemeError, refine_uniform};

/// The boundary loop of a mesh with one boundary, in the faces' orientation, as positions,
/// with whether each vertex has one face.
fn boundary_loop(mesh: &Mesh) -> Vec<(DVec3, bool)> {
    let first = (0..mesh.half_edge_count() as u32)
        .map(HalfEdgeId::new)
        .find(|&h| mesh.twin(h).is_none())
        .expect("an open mesh");
    let mut out = Vec::new();
    let mut h = first;
    loop {
        let v = mesh.origin(h);
        out.push((mesh.position(v), mesh.outgoing(v).count() == 1));
        // The boundary half-edge leaving `h`'s end comes first in its fan.
        h = mesh.outgoing(mesh.dest(h)).next().expect("a boundary vertex has a boundary edge");
        assert!(mesh.twin(h).is_none(), "the fan of a boundary vertex starts on the boundary");
        if h == first {
            return out;
        }
        assert!(out.len() <= mesh.vertex_count(), "the boundary does not close");
    }
}

/// Whether `a` is `b` turned to start elsewhere, point for point to 1e-12.
fn same_cycle(a: &[DVec3], b: &[DVec3]) -> bool {
    a.len() == b.len()
        && (0..b.len()).any(|shift| a.iter().enumerate().all(|(i, p)| (*p - b[(i + shift) % b.len()]).length() < 1e-12))
}

/// One step of Chaikin's corner cutting on a closed polygon whose corners (`true`) stay.
fn chaikin(polygon: &[(DVec3, bool)]) -> Vec<(DVec3, bool)> {
    let n = polygon.len();
    let mut out: Vec<(DVec3, bool)> = Vec::new();
    for i in 0..n {
        let ((p, p_corner), (q, q_corner)) = (polygon[i], polygon[(i + 1) % n]);
        let near = |a: DVec3, corner: bool, b: DVec3| if corner { (a, true) } else { ((3.0 * a + b) / 4.0, false) };
        for point in [near(p, p_corner, q), near(q, q_corner, p)] {
            if out.last().is_none_or(|last| last.0 != point.0) {
                out.push(point);
            }
        }
    }
    if out.len() > 1 && out[0].0 == out[out.len() - 1].0 {
        out.pop();
    }
    out
}

/// One step of the ternary cubic B-spline on a closed polygon: per vertex its relaxed position
/// and the two thirds of its edge forward.
fn ternary_cubic(polygon: &[DVec3]) -> Vec<DVec3> {
    let n = polygon.len();
    let p = |i: isize| polygon[i.rem_euclid(n as isize) as usize];
    (0..n as isize)
        .flat_map(|i| {
            [
                (4.0 * p(i - 1) + 19.0 * p(i) + 4.0 * p(i + 1)) / 27.0,
                (p(i - 1) + 16.0 * p(i) + 10.0 * p(i + 1)) / 27.0,
                (10.0 * p(i) + 16.0 * p(i + 1) + p(i + 2)) / 27.0,
            ]
        })
        .collect()
}

fn positions(polygon: &[(DVec3, bool)]) -> Vec<DVec3> {
    polygon.iter().map(|&(p, _)| p).collect()
}

/// A jittered, domed open grid of quads, with corners of one face.
fn open_quads() -> Mesh {
    let mut soup = shapes::jittered(shapes::quad_grid(4, 3), 0.2);
    for p in soup.positions_mut() {
        p.z += 0.1 * (p.x * p.y).sin();
    }
    Mesh::build(soup).unwrap()
}

/// A hexagonal fan of triangles and a ring of triangles around it: an open triangle mesh with
/// interior vertices of valence 6 and 5, every boundary triangle on one boundary edge.
fn open_triangles() -> Mesh {
    let mut soup = PolygonSoup::default();
    soup.push_vertex(DVec3::new(0.0, 0.0, 0.3));
    for i in 0..6 {
        let a = std::f64::consts::TAU * f64::from(i) / 6.0;
        soup.push_vertex(DVec3::new(a.cos(), a.sin(), 0.1 * f64::from(i)));
    }
    for i in 0..5 {
        let a = std::f64::consts::TAU * (f64::from(i) + 0.5) / 5.0;
        soup.push_vertex(DVec3::new(2.0 * a.cos(), 2.0 * a.sin(), -0.2));
    }
    let v = |i: usize| VertexId::new(i as u32);
    for i in 0..6 {
        soup.push_face([v(0), v(1 + i), v(1 + (i + 1) % 6)]);
    }
    // The outer ring: five outer vertices against six inner ones.
    let ring = [(1, 7), (2, 7), (3, 8), (4, 9), (5, 10), (6, 11)];
    for (k, &(inner, outer)) in ring.iter().enumerate() {
        let next_inner = 1 + (inner % 6);
        soup.push_face([v(inner), v(outer), v(next_inner)]);
        let next_outer = ring[(k + 1) % 6].1;
        if next_outer != outer {
            soup.push_face([v(next_inner), v(outer), v(next_outer)]);
        }
    }
    Mesh::build(soup).unwrap()
}

#[test]
fn doo_sabin_cuts_the_boundary_polygon_by_chaikin_and_keeps_corners() {
    let mesh = open_quads();
    let mut expected = boundary_loop(&mesh);
    for level in 1..=3 {
        let refined = refine_uniform(&mesh, Builtin::DooSabin.scheme(), level, &RefineOptions::DEFAULT).unwrap();
        expected = chaikin(&expected);
        let found = boundary_loop(&refined);
        assert!(same_cycle(&positions(&found), &positions(&expected)), "level {level}");
        // The four corners stay corners of one face, at their place.
        assert_eq!(found.iter().filter(|&&(_, corner)| corner).count(), 4, "level {level}");
        assert_eq!(refined.euler_characteristic(), mesh.euler_characteristic(), "level {level}");
    }
}

#[test]
fn doo_sabin_gives_a_boundary_vertex_of_three_faces_or_more_a_vertex_face() {
    // A fan of five quads around a boundary vertex: its vertex face is a pentagon on the
    // boundary, and the interior is as on closed meshes.
    let mesh = Mesh::build(shapes::pole(5)).unwrap();
    let refined = refine_uniform(&mesh, Builtin::DooSabin.scheme(), 1, &RefineOptions::DEFAULT).unwrap();
    let interior_edges = mesh.edges().filter(|&e| !mesh.is_boundary_edge(e)).count();
    let boundary_with_vertex_face =
        mesh.vertices().filter(|&v| mesh.is_boundary_vertex(v) && mesh.outgoing(v).count() >= 3).count();
    let interior_vertices = mesh.vertices().filter(|&v| !mesh.is_boundary_vertex(v)).count();
    assert_eq!(
        refined.face_count(),
        mesh.face_count() + interior_edges + interior_vertices + boundary_with_vertex_face
    );
    let pentagon = mesh.face_ids().any(|f| mesh.face_size(f) == 5);
    assert!(!pentagon && refined.face_ids().any(|f| refined.face_size(f) == 5), "the centre's face");
}

#[test]
fn midedge_refines_open_meshes_two_steps_at_a_time_by_its_dual_form() {
    let mesh = open_quads();
    let midedge = Builtin::Midedge.scheme();
    let twice = refine_uniform(&mesh, midedge, 2, &RefineOptions::DEFAULT).unwrap();
    let dual = refine_uniform(&mesh, &midedge.dual_form().unwrap(), 1, &RefineOptions::DEFAULT).unwrap();
    assert_eq!(twice.positions(), dual.positions());
    let mut expected = boundary_loop(&mesh);
    for pairs in 1..=2 {
        let refined = refine_uniform(&mesh, midedge, 2 * pairs, &RefineOptions::DEFAULT).unwrap();
        expected = chaikin(&expected);
        assert!(same_cycle(&positions(&boundary_loop(&refined)), &positions(&expected)), "{pairs} pairs");
    }
    // The refiner's progress counts the steps asked for.
    let mut steps = Vec::new();
    Refiner::with_progress(&mesh, midedge, 4, &RefineOptions::DEFAULT, |s| steps.push(s)).unwrap();
    assert_eq!(steps, [1, 2, 3, 4]);
    let e = refine_uniform(&mesh, midedge, 3, &RefineOptions::DEFAULT).unwrap_err();
    assert!(matches!(e, SchemeError::FeatureNotSupported { .. }), "{e}");
    assert!(e.to_string().contains("two steps at a time"), "{e}");
}

#[test]
fn sqrt3_refines_the_boundary_polygon_by_the_ternary_cubic_b_spline_every_second_step() {
    let mesh = open_triangles();
    let sqrt3 = Builtin::Sqrt3.scheme();
    let polygon = positions(&boundary_loop(&mesh));
    let once = refine_uniform(&mesh, sqrt3, 1, &RefineOptions::DEFAULT).unwrap();
    // The first step keeps the boundary: its vertices stay, its edges are not split.
    assert!(same_cycle(&positions(&boundary_loop(&once)), &polygon));
    let mut expected = polygon;
    for pairs in 1..=2 {
        let refined = refine_uniform(&mesh, sqrt3, 2 * pairs, &RefineOptions::DEFAULT).unwrap();
        expected = ternary_cubic(&expected);
        assert!(same_cycle(&positions(&boundary_loop(&refined)), &expected), "{pairs} pairs");
        assert_eq!(refined.face_count(), mesh.face_count() * 9usize.pow(pairs as u32));
        assert_eq!(refined.euler_characteristic(), mesh.euler_characteristic());
    }
}

#[test]
fn sqrt3_interior_away_from_the_boundary_is_as_on_closed_meshes() {
    // The vertex at the centre of the fan is two rings from the boundary: after two steps its
    // position is the closed rule's twice (relaxed by α_6 over its neighbours, which are
    // relaxed or centroids of interior triangles only).
    let mesh = open_triangles();
    let sqrt3 = Builtin::Sqrt3.scheme();
    let refined = refine_uniform(&mesh, sqrt3, 1, &RefineOptions::DEFAULT).unwrap();
    let ring = mesh.one_ring(VertexId::new(0));
    let alpha = (4.0 - 2.0 * (std::f64::consts::TAU / 6.0).cos()) / 9.0;
    let mean = ring.iter().map(|&w| mesh.position(w)).sum::<DVec3>() / 6.0;
    let expected = (1.0 - alpha) * mesh.position(VertexId::new(0)) + alpha * mean;
    assert!((refined.position(VertexId::new(0)) - expected).length() < 1e-14);
}

#[test]
fn a_sqrt3_variant_without_boundary_rule_refuses_open_meshes() {
    let text = "name = \"closed-sqrt3\"\n[rules.sqrt3]\nvertex = { spoke = \"(4 - 2*cos(2*pi/k))/(9*k)\" }\n";
    let scheme = subdiv_schemes::Scheme::from_toml_str(text).unwrap();
    let e = refine_uniform(&open_triangles(), &scheme, 1, &RefineOptions::DEFAULT).unwrap_err();
    assert!(matches!(e, SchemeError::FeatureNotSupported { feature: "boundaries", .. }), "{e}");
}

/// The dual splits make a face of each vertex's corners: an interior vertex of two faces (two
/// quads folded back to back, OpenSubdiv's `catmark_val2_back2back`) is refused by name, not
/// turned into a two-sided face that the refined mesh's validation reports as an internal
/// error.
#[test]
fn the_dual_splits_refuse_interior_vertices_of_two_faces() {
    let mut soup = PolygonSoup::default();
    for p in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]] {
        soup.push_vertex(DVec3::from(p));
    }
    soup.push_face([0, 1, 2, 3].map(VertexId::new));
    soup.push_face([3, 2, 1, 0].map(VertexId::new));
    let pillow = Mesh::build(soup).unwrap();
    for builtin in [Builtin::DooSabin, Builtin::Midedge] {
        let e = refine_uniform(&pillow, builtin.scheme(), 1, &RefineOptions::DEFAULT).unwrap_err();
        assert!(
            matches!(&e, SchemeError::FeatureNotSupported { element, .. } if element == "vertex 0"),
            "{builtin:?}: {e}"
        );
        assert!(e.to_string().contains("two faces"), "{e}");
    }
    // Catmull-Clark takes it (a valence-2 vertex is an extraordinary vertex like any other).
    refine_uniform(&pillow, Builtin::CatmullClark.scheme(), 1, &RefineOptions::DEFAULT).unwrap();
}
