//! The derived sub-patch matrices: their spectra, and agreement with the engine on real meshes.

use subdiv_mesh::{BoundaryInterpolation, DVec3, Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::{
    Builtin, FoundPatch, MeshPatches, PatchMatrices, PatchType, RefineOptions, SchemeError, refine, refine_uniform,
    sub_patch_starts,
};

const EDGE_ONLY: BoundaryInterpolation = BoundaryInterpolation::EdgeOnly;

fn modulus(z: &(f64, f64)) -> f64 {
    z.0.hypot(z.1)
}

#[test]
fn extraordinary_patch_sizes_follow_stam() {
    let cc = Builtin::CatmullClark.scheme();
    let lp = Builtin::Loop.scheme();
    for k in [3, 5, 8, 17] {
        let m = PatchMatrices::of(cc, PatchType::interior(k), EDGE_ONLY).unwrap();
        assert_eq!((m.radius, m.shapes[0].size), (1, 2 * k + 8));
        let m = PatchMatrices::of(lp, PatchType::interior(k), EDGE_ONLY).unwrap();
        assert_eq!((m.radius, m.shapes[0].size), (1, k + 6));
    }
}

/// The regular Catmull-Clark sub-patch matrices are bicubic B-spline knot insertion: each is
/// a tensor product of cubic B-spline half-interval matrices, with eigenvalues 2^-(i+j).
#[test]
fn regular_catmull_clark_sub_patches_are_bicubic_knot_insertion() {
    let cc = Builtin::CatmullClark.scheme();
    let m = PatchMatrices::of(cc, PatchType::regular(cc), EDGE_ONLY).unwrap();
    assert_eq!(m.shapes.len(), 1, "the regular patch is the only shape");
    let mut expected: Vec<f64> = (0..4).flat_map(|i| (0..4).map(move |j| 0.5_f64.powi(i + j))).collect::<Vec<_>>();
    expected.sort_by(|a, b| b.total_cmp(a));
    for child in &m.shapes[0].children {
        assert_eq!((child.shape, child.rows(), child.columns()), (0, 16, 16));
        let values: Vec<f64> = child.eigenvalues().unwrap().iter().map(modulus).collect();
        for (got, want) in values.iter().zip(&expected) {
            assert!((got - want).abs() < 1e-12, "{values:?}");
        }
    }
}

#[test]
fn every_sub_patch_row_is_affine() {
    let cases = [
        (Builtin::CatmullClark, PatchType::interior(5)),
        (Builtin::CatmullClark, PatchType::boundary(1, 0)),
        (Builtin::CatmullClark, PatchType::boundary(4, 2)),
        (Builtin::Loop, PatchType::interior(7)),
        (Builtin::Loop, PatchType::boundary(2, 1)),
        (Builtin::Butterfly, PatchType::interior(4)),
        (Builtin::Kobbelt, PatchType::interior(3)),
        (Builtin::SwQuad, PatchType::interior(6)),
        (Builtin::Bilinear, PatchType::boundary(3, 0)),
    ];
    for (builtin, patch_type) in cases {
        for boundary in [EDGE_ONLY, BoundaryInterpolation::EdgeAndCorner] {
            let m = PatchMatrices::of(builtin.scheme(), patch_type, boundary).unwrap();
            for shape in &m.shapes {
                assert!(!shape.children.is_empty());
                for child in &shape.children {
                    assert_eq!((child.rows(), child.columns()), (m.shapes[child.shape].size, shape.size));
                    for r in 0..child.rows() {
                        let sum: f64 = child.row(r).map(|e| e.1).sum();
                        assert!((sum - 1.0).abs() < 1e-13, "{builtin} {patch_type:?}: row {r} sums to {sum}");
                    }
                }
            }
        }
    }
}

#[test]
fn unsupported_splits_and_valences_are_typed_errors() {
    // The dual splits' patches: interior, around faces of 3 or more sides; √3's ternary ones
    // at valence 3 or more, and at boundary vertices (Kobbelt's boundary rule).
    for builtin in [Builtin::DooSabin, Builtin::Midedge, Builtin::Sqrt3] {
        let err = PatchMatrices::compute(builtin.scheme(), PatchType::interior(2), EDGE_ONLY).unwrap_err();
        assert!(matches!(err, SchemeError::ValenceNotSupported { .. }), "{err}");
    }
    for builtin in [Builtin::DooSabin, Builtin::Midedge] {
        let err = PatchMatrices::compute(builtin.scheme(), PatchType::boundary(2, 0), EDGE_ONLY).unwrap_err();
        assert!(matches!(err, SchemeError::ValenceNotSupported { .. }), "{err}");
    }
    let m = PatchMatrices::compute(Builtin::Sqrt3.scheme(), PatchType::boundary(3, 1), EDGE_ONLY).unwrap();
    assert_eq!((m.face_size, m.radius), (3, 2));
    let cc = Builtin::CatmullClark.scheme();
    // Valence 2 exists for quads (two faces sharing two sides), not for triangles.
    let err = PatchMatrices::compute(cc, PatchType::interior(1), EDGE_ONLY).unwrap_err();
    assert!(matches!(err, SchemeError::ValenceNotSupported { valence: 1, .. }));
    let err = PatchMatrices::compute(Builtin::Loop.scheme(), PatchType::interior(2), EDGE_ONLY).unwrap_err();
    assert!(matches!(err, SchemeError::ValenceNotSupported { valence: 2, .. }));
    for (faces, index) in [(0, 0), (2, 2)] {
        let err = PatchMatrices::compute(cc, PatchType::boundary(faces, index), EDGE_ONLY).unwrap_err();
        assert!(matches!(err, SchemeError::ValenceNotSupported { .. }));
    }
    // Butterfly has a boundary rule; without it, no boundary patches.
    let butterfly = Builtin::Butterfly.scheme();
    assert!(PatchMatrices::compute(butterfly, PatchType::boundary(3, 0), EDGE_ONLY).is_ok());
    let mut closed = butterfly.clone();
    if let subdiv_schemes::Rules::Triangle { boundary, .. } = &mut closed.rules {
        *boundary = None;
    }
    let err = PatchMatrices::compute(&closed, PatchType::boundary(3, 0), EDGE_ONLY).unwrap_err();
    assert!(matches!(err, SchemeError::FeatureNotSupported { feature: "boundaries", .. }), "{err}");
    // Kobbelt's virtual points reach past three rings around a valence-5 vertex, not past four.
    let m = PatchMatrices::compute(Builtin::Kobbelt.scheme(), PatchType::interior(5), EDGE_ONLY).unwrap();
    assert_eq!((m.radius, m.shapes[0].size), (4, 120));
}

/// An open `n × n` grid of quads, each split into two triangles along alternating diagonals.
fn triangle_grid(n: usize) -> PolygonSoup {
    let quads = shapes::quad_grid(n, n);
    let mut soup = PolygonSoup::new();
    for &p in quads.positions() {
        soup.push_vertex(p);
    }
    for (f, face) in quads.faces().enumerate() {
        let [a, b, c, d] = [face[0], face[1], face[2], face[3]];
        if (f + f / n).is_multiple_of(2) {
            soup.push_face([a, b, c]);
            soup.push_face([a, c, d]);
        } else {
            soup.push_face([a, b, d]);
            soup.push_face([b, c, d]);
        }
    }
    soup
}

/// Every face of `mesh` (after `levels` refinements, which isolate the extraordinary
/// vertices) finds its shape, in some rotation, among the matrices of the patch types of its
/// corners, and the matrices take its patch to its sub-patches as the engine refines them.
fn assert_matrices_match_the_engine(builtin: Builtin, soup: PolygonSoup, levels: usize) {
    let scheme = builtin.scheme();
    let base = Mesh::build(soup).unwrap();
    let mesh = refine_uniform(&base, scheme, levels, &RefineOptions::DEFAULT).unwrap();
    let refined = refine(&mesh, scheme, &RefineOptions::DEFAULT).unwrap();
    let (lo, hi) = mesh.bounding_box().unwrap();
    let tolerance = 1e-12 * (hi - lo).max_element();
    let patches = MeshPatches::new(scheme, &mesh, &RefineOptions::DEFAULT).unwrap();
    let positions = |m: &Mesh, vs: &[VertexId]| -> Vec<DVec3> { vs.iter().map(|&v| m.position(v)).collect() };
    for face in mesh.face_ids() {
        let Some(FoundPatch { start, vertices, matrices: table, shape }) = patches.find(&mesh, face) else {
            panic!("{builtin}: face {face} has no shape in the tables");
        };
        let radius = table.radius;
        let starts = sub_patch_starts(scheme, &mesh, start, &refined).unwrap();
        let parent = positions(&mesh, &vertices);
        for (child, &child_start) in table.shapes[shape].children.iter().zip(&starts) {
            let child_patch = refined.patch(child_start, radius);
            assert_eq!(child_patch.signature, table.shapes[child.shape].signature, "{builtin}: face {face}");
            let expected = positions(&refined, &child_patch.vertices);
            for (got, want) in child.apply(&parent).iter().zip(&expected) {
                assert!((*got - *want).abs().max_element() < tolerance, "{builtin}: face {face}: {got} vs {want}");
            }
        }
    }
}

#[test]
fn catmull_clark_matrices_match_the_engine() {
    assert_matrices_match_the_engine(Builtin::CatmullClark, shapes::cube(), 2);
    assert_matrices_match_the_engine(Builtin::CatmullClark, shapes::pole(5), 1);
    assert_matrices_match_the_engine(Builtin::CatmullClark, shapes::quad_grid(3, 2), 1);
    let mut corners = shapes::quad_grid(3, 3);
    corners.tags.boundary_interpolation = Some(BoundaryInterpolation::EdgeAndCorner);
    assert_matrices_match_the_engine(Builtin::CatmullClark, corners, 1);
}

#[test]
fn loop_matrices_match_the_engine() {
    assert_matrices_match_the_engine(Builtin::Loop, shapes::icosahedron(), 2);
    assert_matrices_match_the_engine(Builtin::Loop, shapes::octahedron(), 2);
    assert_matrices_match_the_engine(Builtin::Loop, shapes::tetrahedron(), 2);
    assert_matrices_match_the_engine(Builtin::Loop, triangle_grid(3), 2);
}

#[test]
fn other_primal_schemes_match_the_engine() {
    assert_matrices_match_the_engine(Builtin::Butterfly, shapes::icosahedron(), 3);
    assert_matrices_match_the_engine(Builtin::Kobbelt, shapes::cube(), 3);
    assert_matrices_match_the_engine(Builtin::SwQuad, shapes::cube(), 2);
    assert_matrices_match_the_engine(Builtin::SwQuad, shapes::quad_grid(3, 3), 1);
    assert_matrices_match_the_engine(Builtin::Bilinear, shapes::pole(6), 1);
}
