//! Properties every refinement must have: affine invariance, interpolation where the scheme
//! interpolates, and on regular grids the spline refinement the scheme generalises
//! (Catmull-Clark: bicubic B-spline knot insertion; Loop: the quartic box spline).

use proptest::prelude::*;
use subdiv_mesh::{CornerTag, CreaseTag, DVec3, Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::{RefineOptions, Scheme, refine_uniform};

fn shape(scheme: Scheme, index: usize) -> PolygonSoup {
    match (scheme, index % 4) {
        (Scheme::Loop, 0) => shapes::icosahedron(),
        (Scheme::Loop, 1) => shapes::triangle_torus(5, 4),
        (Scheme::Loop, 2) => shapes::octahedron(),
        (Scheme::Loop, _) => shapes::tetrahedron(),
        (_, 0) => shapes::default_model(),
        (_, 1) => shapes::pole(5),
        (_, 2) => shapes::ngon_prism(6),
        (_, _) => shapes::quad_grid(3, 2),
    }
}

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

/// `soup` with jittered positions and a few semi-sharp and infinitely sharp tags.
fn tagged(mut soup: PolygonSoup, rng: &mut Lcg) -> Mesh {
    for p in soup.positions_mut() {
        *p += rng.vector() * 0.1;
    }
    let mesh = Mesh::build(soup.clone()).unwrap();
    for (k, e) in mesh.edges().enumerate().filter(|(k, _)| k % 5 == 0) {
        let [a, b] = mesh.edge_vertices(e);
        let sharpness = [0.4, 1.7, 10.0][k % 3];
        soup.tags.creases.push(CreaseTag { vertices: [a, b], sharpness });
    }
    soup.tags.corners.push(CornerTag { vertex: VertexId::new(0), sharpness: 2.5 });
    Mesh::build(soup).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn refinement_commutes_with_affine_maps(scheme_index in 0usize..3, index in 0usize..4, levels in 1usize..3, seed: u64) {
        let scheme = Scheme::ALL[scheme_index];
        let mut rng = Lcg(seed);
        let mesh = tagged(shape(scheme, index), &mut rng);
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
    fn bilinear_keeps_every_old_vertex(index in 0usize..4, seed: u64) {
        let mesh = tagged(shape(Scheme::Bilinear, index), &mut Lcg(seed));
        let refined = refine_uniform(&mesh, Scheme::Bilinear, 2, &RefineOptions::DEFAULT).unwrap();
        prop_assert_eq!(&refined.positions()[..mesh.vertex_count()], mesh.positions());
    }
}

#[test]
fn infinitely_sharp_corners_and_creases_stay_put() {
    // Catmull-Clark and Loop are approximating, but an infinitely sharp corner interpolates.
    for scheme in [Scheme::CatmullClark, Scheme::Loop] {
        let mut soup = if scheme == Scheme::Loop { shapes::icosahedron() } else { shapes::cube() };
        soup.tags.corners.push(CornerTag { vertex: VertexId::new(3), sharpness: 10.0 });
        let mesh = Mesh::build(soup).unwrap();
        let refined = refine_uniform(&mesh, scheme, 3, &RefineOptions::DEFAULT).unwrap();
        assert_eq!(refined.position(VertexId::new(3)), mesh.position(VertexId::new(3)), "{scheme}");
        assert_ne!(refined.position(VertexId::new(2)), mesh.position(VertexId::new(2)), "{scheme}");
    }
}

/// On a torus of regular quads, one Catmull-Clark step is bicubic B-spline knot insertion: the
/// tensor products of the cubic B-spline's refinement masks [1, 6, 1]/8 (at old vertices) and
/// [1, 1]/2 (at new ones).
#[test]
fn regular_catmull_clark_is_bicubic_knot_insertion() {
    let (m, n) = (7usize, 6usize);
    let mut soup = shapes::quad_torus(m, n);
    let mut rng = Lcg(7);
    for p in soup.positions_mut() {
        *p += rng.vector() * 0.2;
    }
    let mesh = Mesh::build(soup).unwrap();
    let refined = refine_uniform(&mesh, Scheme::CatmullClark, 1, &RefineOptions::DEFAULT).unwrap();
    // Control point (i, j) of the torus is vertex i n + j, indices taken cyclically.
    let id = |i: isize, j: isize| {
        VertexId::new((i.rem_euclid(m as isize) as usize * n + j.rem_euclid(n as isize) as usize) as u32)
    };
    let point = |i: isize, j: isize| mesh.position(id(i, j));
    let old = [(-1, 0.125), (0, 0.75), (1, 0.125)];
    let new = [(0, 0.5), (1, 0.5)];
    let tensor = |i: isize, j: isize, mi: &[(isize, f64)], mj: &[(isize, f64)]| -> DVec3 {
        mi.iter().flat_map(|&(a, wa)| mj.iter().map(move |&(b, wb)| point(i + a, j + b) * (wa * wb))).sum()
    };
    let (nv, nf) = (mesh.vertex_count(), mesh.face_count());
    let edge_point = |a: VertexId, b: VertexId| VertexId::new((nv + nf + mesh.find_edge(a, b).unwrap().index()) as u32);
    for i in 0..m as isize {
        for j in 0..n as isize {
            let close = |p: DVec3, q: DVec3| assert!(p.distance(q) < 1e-14, "{p} vs {q} at ({i}, {j})");
            close(refined.position(id(i, j)), tensor(i, j, &old, &old));
            close(refined.position(edge_point(id(i, j), id(i + 1, j))), tensor(i, j, &new, &old));
            close(refined.position(edge_point(id(i, j), id(i, j + 1))), tensor(i, j, &old, &new));
            let face = VertexId::new((nv + i as usize * n + j as usize) as u32);
            close(refined.position(face), tensor(i, j, &new, &new));
        }
    }
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
    let refined = refine_uniform(&mesh, Scheme::Loop, 1, &RefineOptions::DEFAULT).unwrap();
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
    let mut rng = Lcg(3);
    for scheme in Scheme::ALL {
        for index in 0..4 {
            let mesh = tagged(shape(scheme, index), &mut rng);
            let refiner = subdiv_schemes::Refiner::new(&mesh, scheme, 3, &RefineOptions::DEFAULT).unwrap();
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
