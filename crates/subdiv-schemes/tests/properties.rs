//! Properties every refinement must have, for every built-in scheme (and the perturbed ones of
//! `subdiv_schemes::strategies`), on the meshes of `subdiv_mesh::strategies`: affine invariance,
//! interpolation where the scheme interpolates, and on regular grids the refinement the scheme
//! generalises (Catmull-Clark: bicubic B-spline knot insertion; sw-quad: the tensor product of
//! its curve rules; Kobbelt: the tensor-product four-point rule; Loop: the quartic box spline).

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::TestRunner;
use subdiv_mesh::strategies::MeshParams;
use subdiv_mesh::{CornerTag, DVec3, Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::strategies::{builtin_schemes, meshes_for, perturbed_schemes, with_meshes};
use subdiv_schemes::{Builtin, RefineOptions, Rules, Scheme, refine_uniform};

/// A small deterministic generator, so that a failing seed reproduces.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn vector(&mut self) -> DVec3 {
        DVec3::new(self.unit(), self.unit(), self.unit())
    }
}

/// The meshes of these tests (within what each scheme takes, `mesh_params`): jittered, and
/// where the scheme has crease rules, open ones among them and about a fifth of the edges and a
/// tenth of the vertices tagged, semi-sharp or infinitely sharp.
const PARAMS: MeshParams =
    MeshParams { jitter: 0.1, crease_probability: 0.2, corner_probability: 0.1, ..MeshParams::DEFAULT };

fn built(soup: PolygonSoup) -> Mesh {
    Mesh::build(soup).unwrap()
}

/// The interpolating built-ins, and Kobbelt's scheme at other tensions.
fn interpolating() -> impl Strategy<Value = Scheme> {
    let builtins = prop::sample::select(vec![Builtin::Bilinear, Builtin::Butterfly, Builtin::Kobbelt]);
    prop_oneof![
        builtins.prop_map(|b| b.scheme().clone()),
        perturbed_schemes().prop_filter("Kobbelt's", |s| matches!(s.rules, Rules::FourPointQuad { .. })),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn refinement_commutes_with_affine_maps(
        (scheme, soup) in with_meshes(prop_oneof![builtin_schemes(), perturbed_schemes()], PARAMS),
        levels in 1usize..3,
        seed: u64,
    ) {
        let scheme = &scheme;
        let mut rng = Lcg(seed);
        let mesh = built(soup);
        let (x, y, z, t) = (rng.vector(), rng.vector(), rng.vector(), rng.vector());
        let map = |p: DVec3| x * p.x + y * p.y + z * p.z + t + p * 1.5;
        let mut mapped = mesh.clone();
        for p in mapped.positions_mut() {
            *p = map(*p);
        }
        let options = RefineOptions::DEFAULT;
        let refined = refine_uniform(&mesh, scheme, levels, &options).unwrap();
        let refined_mapped = refine_uniform(&mapped, scheme, levels, &options).unwrap();
        let scale = refined_mapped.positions().iter().map(|p| p.abs().max_element()).fold(1.0, f64::max);
        for (p, q) in refined.positions().iter().zip(refined_mapped.positions()) {
            prop_assert!((map(*p) - *q).abs().max_element() <= 1e-12 * scale, "{scheme}: {} vs {q}", map(*p));
        }
    }

    #[test]
    fn interpolating_schemes_keep_every_old_vertex((scheme, soup) in with_meshes(interpolating(), PARAMS)) {
        let scheme = &scheme;
        prop_assert!(scheme.is_interpolating());
        let mesh = built(soup);
        let refined = refine_uniform(&mesh, scheme, 2, &RefineOptions::DEFAULT).unwrap();
        prop_assert_eq!(&refined.positions()[..mesh.vertex_count()], mesh.positions());
    }
}

#[test]
fn infinitely_sharp_corners_and_creases_stay_put() {
    // Catmull-Clark and Loop are approximating, but an infinitely sharp corner interpolates.
    for scheme in [Builtin::CatmullClark, Builtin::Loop, Builtin::SwQuad].map(Builtin::scheme) {
        let mut soup = if scheme.face_size() == Some(3) { shapes::icosahedron() } else { shapes::cube() };
        soup.tags.corners.push(CornerTag { vertex: VertexId::new(3), sharpness: 10.0 });
        let mesh = Mesh::build(soup).unwrap();
        let refined = refine_uniform(&mesh, scheme, 3, &RefineOptions::DEFAULT).unwrap();
        assert_eq!(refined.position(VertexId::new(3)), mesh.position(VertexId::new(3)), "{scheme}");
        assert_ne!(refined.position(VertexId::new(2)), mesh.position(VertexId::new(2)), "{scheme}");
    }
}

/// On a torus of regular quads, one step of a tensor-product scheme applies the tensor products
/// of its curve masks: `old` at old vertices, `new` at new ones (offsets from the vertex).
fn assert_tensor_product(scheme: &Scheme, old: &[(isize, f64)], new: &[(isize, f64)]) {
    let (m, n) = (7usize, 6usize);
    let mut soup = shapes::quad_torus(m, n);
    let mut rng = Lcg(7);
    for p in soup.positions_mut() {
        *p += rng.vector() * 0.2;
    }
    let mesh = Mesh::build(soup).unwrap();
    let refined = refine_uniform(&mesh, scheme, 1, &RefineOptions::DEFAULT).unwrap();
    // Control point (i, j) of the torus is vertex i n + j, indices taken cyclically.
    let id = |i: isize, j: isize| {
        VertexId::new((i.rem_euclid(m as isize) as usize * n + j.rem_euclid(n as isize) as usize) as u32)
    };
    let point = |i: isize, j: isize| mesh.position(id(i, j));
    let tensor = |i: isize, j: isize, mi: &[(isize, f64)], mj: &[(isize, f64)]| -> DVec3 {
        mi.iter().flat_map(|&(a, wa)| mj.iter().map(move |&(b, wb)| point(i + a, j + b) * (wa * wb))).sum()
    };
    let (nv, nf) = (mesh.vertex_count(), mesh.face_count());
    let edge_point = |a: VertexId, b: VertexId| VertexId::new((nv + nf + mesh.find_edge(a, b).unwrap().index()) as u32);
    for i in 0..m as isize {
        for j in 0..n as isize {
            let close = |p: DVec3, q: DVec3| assert!(p.distance(q) < 1e-14, "{scheme}: {p} vs {q} at ({i}, {j})");
            close(refined.position(id(i, j)), tensor(i, j, old, old));
            close(refined.position(edge_point(id(i, j), id(i + 1, j))), tensor(i, j, new, old));
            close(refined.position(edge_point(id(i, j), id(i, j + 1))), tensor(i, j, old, new));
            let face = VertexId::new((nv + i as usize * n + j as usize) as u32);
            close(refined.position(face), tensor(i, j, new, new));
        }
    }
}

/// Catmull-Clark: bicubic B-spline knot insertion, the cubic B-spline's masks [1, 6, 1]/8 and
/// [1, 1]/2.
#[test]
fn regular_catmull_clark_is_bicubic_knot_insertion() {
    assert_tensor_product(Builtin::CatmullClark.scheme(), &[(-1, 0.125), (0, 0.75), (1, 0.125)], &[(0, 0.5), (1, 0.5)]);
}

/// sw-quad: the tensor product of paper 000's curve rules (1/6, 2/3, 1/6) and (1/2, 1/2).
#[test]
fn regular_sw_quad_is_the_tensor_product_of_its_curve_rules() {
    let old = [(-1, 1.0 / 6.0), (0, 2.0 / 3.0), (1, 1.0 / 6.0)];
    assert_tensor_product(Builtin::SwQuad.scheme(), &old, &[(0, 0.5), (1, 0.5)]);
}

/// Kobbelt: the tensor-product four-point rule.
#[test]
fn regular_kobbelt_is_the_tensor_product_four_point_rule() {
    let new = [(-1, -1.0 / 16.0), (0, 9.0 / 16.0), (1, 9.0 / 16.0), (2, -1.0 / 16.0)];
    assert_tensor_product(Builtin::Kobbelt.scheme(), &[(0, 1.0)], &new);
}

/// On a torus of regular triangles (every vertex of valence 6), one Loop step is the refinement
/// of the quartic box spline on the three-direction lattice: 10/16 of the vertex plus 1/16 of
/// each lattice neighbour, and 3/8, 3/8, 1/8, 1/8 at the edges.
#[test]
fn regular_loop_is_the_quartic_box_spline() {
    let (m, n) = (7usize, 6usize);
    let mut soup = shapes::triangle_torus(m, n);
    let mut rng = Lcg(11);
    for p in soup.positions_mut() {
        *p += rng.vector() * 0.2;
    }
    let mesh = Mesh::build(soup).unwrap();
    let refined = refine_uniform(&mesh, Builtin::Loop.scheme(), 1, &RefineOptions::DEFAULT).unwrap();
    let id = |i: isize, j: isize| {
        VertexId::new((i.rem_euclid(m as isize) as usize * n + j.rem_euclid(n as isize) as usize) as u32)
    };
    let point = |i: isize, j: isize| mesh.position(id(i, j));
    // The torus splits each quad (i, j)-(i+1, j+1) along that diagonal: the three lattice
    // directions are (1, 0), (0, 1) and (1, 1).
    let directions = [(1, 0), (0, 1), (1, 1)];
    let nv = mesh.vertex_count();
    for i in 0..m as isize {
        for j in 0..n as isize {
            let ring: DVec3 = directions.iter().map(|&(a, b)| point(i + a, j + b) + point(i - a, j - b)).sum();
            let expected = point(i, j) * 0.625 + ring * 0.0625;
            assert!(refined.position(id(i, j)).distance(expected) < 1e-14);
            for (k, &(a, b)) in directions.iter().enumerate() {
                // The two lattice points that see the edge (i, j)-(i+a, j+b) from its sides.
                let (c, d) = match k {
                    0 => (point(i + 1, j + 1), point(i, j - 1)),
                    1 => (point(i + 1, j + 1), point(i - 1, j)),
                    _ => (point(i + 1, j), point(i, j + 1)),
                };
                let expected = (point(i, j) + point(i + a, j + b)) * 0.375 + (c + d) * 0.125;
                let e = mesh.find_edge(id(i, j), id(i + a, j + b)).unwrap();
                let got = refined.position(VertexId::new((nv + e.index()) as u32));
                assert!(got.distance(expected) < 1e-14, "edge {k} at ({i}, {j})");
            }
        }
    }
}

#[test]
fn stencil_rows_sum_to_one_and_reproduce_the_refined_positions() {
    // Four meshes per scheme, drawn from the strategies with a fixed seed.
    let mut runner = TestRunner::deterministic();
    for scheme in Builtin::ALL.map(Builtin::scheme) {
        let soups = meshes_for(scheme, PARAMS);
        for _ in 0..4 {
            let mesh = built(soups.new_tree(&mut runner).unwrap().current());
            let refiner = subdiv_schemes::Refiner::new(&mesh, scheme, 2, &RefineOptions::DEFAULT).unwrap();
            for level in refiner.levels() {
                for child in 0..level.child_count() {
                    let sum: f64 = level.row(child).map(|(_, w)| w).sum();
                    assert!((sum - 1.0).abs() < 1e-12, "{scheme}: row {child} sums to {sum}");
                }
            }
            let (mut out, mut scratch) = (Vec::new(), Vec::new());
            refiner.interpolate(mesh.positions(), &mut out, &mut scratch);
            assert_eq!(out, refiner.mesh().positions());
        }
    }
}

/// A scheme that cannot take a mesh says why, naming the element.
#[test]
fn unsupported_input_is_a_typed_error() {
    use subdiv_schemes::SchemeError;
    let grid = Mesh::build(shapes::quad_grid(2, 2)).unwrap();
    // Kobbelt and Doo-Sabin have boundary rules; mid-edge takes boundaries two steps at a time;
    // a dual scheme file without `boundary` takes none.
    assert!(refine_uniform(&grid, Builtin::Kobbelt.scheme(), 1, &RefineOptions::DEFAULT).is_ok());
    assert!(refine_uniform(&grid, Builtin::DooSabin.scheme(), 1, &RefineOptions::DEFAULT).is_ok());
    let closed_dual = subdiv_schemes::Scheme::from_toml_str(
        "name = \"x\"\n[rules.dual]\nown = \"1/4\"\ncorner = \"(3 + 2*cos(2*pi*j/n))/(4*n)\"\n",
    )
    .unwrap();
    for (scheme, feature) in [
        (&closed_dual, "boundaries"),
        (
            Builtin::Midedge.scheme(),
            "boundaries in an odd number of steps (it refines open meshes two steps at a time)",
        ),
    ] {
        match refine_uniform(&grid, scheme, 1, &RefineOptions::DEFAULT) {
            Err(SchemeError::FeatureNotSupported { feature: f, element, .. }) if f == feature => {
                assert!(element.starts_with("edge "), "{element}");
            }
            other => panic!("{scheme}: {other:?}"),
        }
    }
    let cube = Mesh::build(shapes::cube()).unwrap();
    for builtin in [Builtin::Loop, Builtin::Butterfly, Builtin::Sqrt3] {
        let e = refine_uniform(&cube, builtin.scheme(), 1, &RefineOptions::DEFAULT).unwrap_err();
        assert!(matches!(e, SchemeError::FaceNotSupported { size: 4, expected: 3, .. }), "{builtin}: {e}");
    }
    let prism = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let e = refine_uniform(&prism, Builtin::Kobbelt.scheme(), 1, &RefineOptions::DEFAULT).unwrap_err();
    assert!(matches!(e, SchemeError::FaceNotSupported { size: 5, expected: 4, .. }), "{e}");
    // The four-point boundary rule takes infinitely sharp creases and corners, not semi-sharp
    // ones; the dual splits take neither.
    let tagged = |crease: f64, corner: f64| {
        let mut soup = shapes::cube();
        soup.tags
            .creases
            .push(subdiv_mesh::CreaseTag { vertices: [VertexId::new(0), VertexId::new(1)], sharpness: crease });
        soup.tags.corners.push(CornerTag { vertex: VertexId::new(6), sharpness: corner });
        Mesh::build(soup).unwrap()
    };
    let kobbelt = Builtin::Kobbelt.scheme();
    assert!(refine_uniform(&tagged(10.0, 10.0), kobbelt, 1, &RefineOptions::DEFAULT).is_ok());
    let e = refine_uniform(&tagged(2.5, 0.0), kobbelt, 1, &RefineOptions::DEFAULT).unwrap_err();
    assert!(matches!(e, SchemeError::FeatureNotSupported { feature: "semi-sharp creases", .. }), "{e}");
    let e = refine_uniform(&tagged(10.0, 1.5), kobbelt, 1, &RefineOptions::DEFAULT).unwrap_err();
    assert!(matches!(e, SchemeError::FeatureNotSupported { feature: "semi-sharp corners", .. }), "{e}");
    let e = refine_uniform(&tagged(10.0, 0.0), Builtin::DooSabin.scheme(), 1, &RefineOptions::DEFAULT).unwrap_err();
    assert!(matches!(e, SchemeError::FeatureNotSupported { feature: "creases", .. }), "{e}");
}

/// Face and vertex counts of one step of each split on the cube (V 8, E 12, F 6) and the
/// icosahedron (V 12, E 30, F 20).
#[test]
fn splits_have_the_expected_counts() {
    let cube = Mesh::build(shapes::cube()).unwrap();
    let icosahedron = Mesh::build(shapes::icosahedron()).unwrap();
    let counts = |mesh: &Mesh, b: Builtin| {
        let r = refine_uniform(mesh, b.scheme(), 1, &RefineOptions::DEFAULT).unwrap();
        assert_eq!(r.euler_characteristic(), 2, "{b}");
        (r.vertex_count(), r.face_count())
    };
    assert_eq!(counts(&cube, Builtin::CatmullClark), (26, 24));
    assert_eq!(counts(&cube, Builtin::DooSabin), (24, 26));
    assert_eq!(counts(&cube, Builtin::Midedge), (12, 14));
    assert_eq!(counts(&icosahedron, Builtin::Loop), (42, 80));
    assert_eq!(counts(&icosahedron, Builtin::Sqrt3), (32, 60));
    assert_eq!(counts(&icosahedron, Builtin::Butterfly), (42, 80));
}
