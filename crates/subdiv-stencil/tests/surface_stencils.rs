//! Surface stencils by periodic addresses: exact on regular patches, consistent across levels
//! everywhere (extraordinary and boundary patches included), affine.

use std::sync::Arc;

use subdiv_mesh::{BoundaryInterpolation, DVec3, FaceId, HalfEdgeId, Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::{
    Builtin, FoundPatch, MeshPatches, PatchMatrices, RefineOptions, refine, refine_uniform, sub_patch_starts,
};
use subdiv_stencil::{Dyadic, FaceDomain, SurfaceStencil, surface_stencil};

/// The patches of a mesh under `builtin`, and a face's: its start, control-point positions,
/// matrices and shape, in the first rotation that has a shape.
fn patches(builtin: Builtin, mesh: &Mesh) -> MeshPatches {
    MeshPatches::new(builtin.scheme(), mesh, &RefineOptions::DEFAULT).unwrap()
}

fn positions(mesh: &Mesh, found: &FoundPatch) -> Vec<DVec3> {
    found.vertices.iter().map(|&v| mesh.position(v)).collect()
}

fn find(patches: &MeshPatches, mesh: &Mesh, face: FaceId) -> (HalfEdgeId, Vec<DVec3>, Arc<PatchMatrices>, usize) {
    let found = patches.find(mesh, face).unwrap_or_else(|| panic!("face {face} has no shape"));
    (found.start, positions(mesh, &found), found.matrices, found.shape)
}

fn apply(weights: &[f64], points: &[DVec3]) -> DVec3 {
    weights.iter().zip(points).map(|(&w, &p)| w * p).sum()
}

fn assert_close(a: DVec3, b: DVec3, tolerance: f64, what: &str) {
    assert!((a - b).abs().max_element() <= tolerance, "{what}: {a} vs {b}");
}

fn check_sums(s: &SurfaceStencil, what: &str) {
    let sum = |w: &[f64]| w.iter().sum::<f64>();
    assert!((sum(&s.position) - 1.0).abs() < 1e-13, "{what}: position sums to {}", sum(&s.position));
    assert!(
        sum(&s.du).abs() < 1e-11 && sum(&s.dv).abs() < 1e-11,
        "{what}: tangents sum to {} {}",
        sum(&s.du),
        sum(&s.dv)
    );
}

/// On a regular grid lifted to z = x² + y², bicubic B-splines give x² + y² + 2/3 exactly, with
/// derivatives (1, 0, 2x) and (0, 1, 2y): the Catmull-Clark stencils are exact there.
#[test]
fn regular_catmull_clark_stencils_are_bicubic_b_splines() {
    let mut soup = shapes::quad_grid(6, 6);
    for p in soup.positions_mut() {
        p.z = p.x * p.x + p.y * p.y;
    }
    let mesh = Mesh::build(soup).unwrap();
    let patches = patches(Builtin::CatmullClark, &mesh);
    let face = FaceId::new(3 * 6 + 2); // (2, 3): its patch is clear of the boundary.
    let (start, points, m, shape) = find(&patches, &mesh, face);
    assert_eq!(start, mesh.face_half_edges(face).next().unwrap());
    let corner = mesh.position(mesh.origin(start));
    for n in [1, 2, 3, 5, 7, 12] {
        for i in 0..=n {
            for j in 0..=n {
                let s = surface_stencil(&m, shape, Dyadic::new(i, j, n)).unwrap();
                check_sums(&s, "regular");
                assert!(s.exact_derivatives);
                let (x, y) = (corner.x + i as f64 / n as f64, corner.y + j as f64 / n as f64);
                let what = format!("({i}, {j})/{n}");
                assert_close(apply(&s.position, &points), DVec3::new(x, y, x * x + y * y + 2.0 / 3.0), 1e-12, &what);
                assert_close(apply(&s.du, &points), DVec3::new(1.0, 0.0, 2.0 * x), 1e-11, &what);
                assert_close(apply(&s.dv, &points), DVec3::new(0.0, 1.0, 2.0 * y), 1e-11, &what);
            }
        }
    }
}

/// Rational points of the domain of a face with `size` sides: the corners, edge and face
/// midpoints, and a scattering with denominators 3 to 32.
fn points(size: usize) -> Vec<Dyadic> {
    let mut out = Vec::new();
    for n in [1, 2, 3, 5, 7, 10, 32] {
        let mut k = 0;
        for i in 0..=n {
            for j in 0..=n {
                if size == 4 || i + j <= n {
                    k += 1;
                    if n <= 2 || k % (n as usize + 1) == 1 {
                        out.push(Dyadic::new(i, j, n));
                    }
                }
            }
        }
    }
    out
}

/// The limit point at `(u, v)` of a face equals the limit point of the same place in the child
/// face that holds it after one refinement, and the derivatives agree with the factor 2: the
/// stencils of every face of `soup` (after `levels` refinements), extraordinary and boundary
/// ones included, describe one surface.
fn assert_consistent_across_levels(builtin: Builtin, soup: PolygonSoup, levels: usize, face_step: usize) {
    let scheme = builtin.scheme();
    let base = Mesh::build(soup).unwrap();
    let mesh = refine_uniform(&base, scheme, levels, &RefineOptions::DEFAULT).unwrap();
    let refined = refine(&mesh, scheme, &RefineOptions::DEFAULT).unwrap();
    let (lo, hi) = mesh.bounding_box().unwrap();
    let tolerance = 1e-11 * (hi - lo).max_element();
    let coarse = patches(builtin, &mesh);
    let fine = patches(builtin, &refined);
    for face in mesh.face_ids().step_by(face_step) {
        let (start, points, m, shape) = find(&coarse, &mesh, face);
        // Each child's patch, matrices and shape.
        let children: Vec<_> = sub_patch_starts(scheme, &mesh, start, &refined)
            .unwrap()
            .into_iter()
            .map(|h| {
                let found =
                    fine.at(&refined, h).unwrap_or_else(|| panic!("{builtin}: a child of face {face} has no shape"));
                let points = positions(&refined, &found);
                (found.matrices, found.shape, points)
            })
            .collect();
        for point in self::points(m.face_size) {
            let s = surface_stencil(&m, shape, point).unwrap();
            let what = format!("{builtin} face {face} at {point:?}");
            check_sums(&s, &what);
            // The child holding the point, and the point in its frame.
            let domain = if m.face_size == 3 { FaceDomain::Triangle } else { FaceDomain::Quad };
            let (c, child_point, factor) = domain.child_of(point);
            let (cm, cs, child_points) = &children[c];
            let t = surface_stencil(cm, *cs, child_point).unwrap();
            assert_close(apply(&s.position, &points), apply(&t.position, child_points), tolerance, &what);
            if s.exact_derivatives && t.exact_derivatives {
                assert_close(apply(&s.du, &points), factor * apply(&t.du, child_points), 1e3 * tolerance, &what);
                assert_close(apply(&s.dv, &points), factor * apply(&t.dv, child_points), 1e3 * tolerance, &what);
            }
        }
    }
}

/// A regular Loop patch at `(212, 44) / 645` (the centroid of a sub-triangle at rate 215): the
/// period of that parameter is 28 steps, and faer's SVD of the shifted period matrix does not
/// converge; the transpose's does. The stencil is then the one the child patch gives, as
/// everywhere.
#[test]
fn loop_stencils_at_a_long_period_are_found() {
    let mesh = Mesh::build(shapes::triangle_torus(8, 8)).unwrap();
    let refined = refine(&mesh, Builtin::Loop.scheme(), &RefineOptions::DEFAULT).unwrap();
    let coarse = patches(Builtin::Loop, &mesh);
    let fine = patches(Builtin::Loop, &refined);
    let face = FaceId::new(0);
    let (start, points, m, shape) = find(&coarse, &mesh, face);
    let point = Dyadic::new(212, 44, 645);
    let s = surface_stencil(&m, shape, point).unwrap();
    check_sums(&s, "rate 215's centroid");
    let (c, child_point, _) = FaceDomain::Triangle.child_of(point);
    let child = sub_patch_starts(Builtin::Loop.scheme(), &mesh, start, &refined).unwrap()[c];
    let found = fine.at(&refined, child).unwrap();
    let t = surface_stencil(&found.matrices, found.shape, child_point).unwrap();
    let (lo, hi) = mesh.bounding_box().unwrap();
    let tolerance = 1e-11 * (hi - lo).max_element();
    assert_close(apply(&s.position, &points), apply(&t.position, &positions(&refined, &found)), tolerance, "position");
}

#[test]
fn catmull_clark_stencils_are_consistent_across_levels() {
    assert_consistent_across_levels(Builtin::CatmullClark, shapes::cube(), 2, 1);
    assert_consistent_across_levels(Builtin::CatmullClark, shapes::pole(5), 2, 3);
    let mut grid = shapes::quad_grid(3, 3);
    grid.tags.boundary_interpolation = Some(BoundaryInterpolation::EdgeAndCorner);
    assert_consistent_across_levels(Builtin::CatmullClark, grid, 1, 1);
}

#[test]
fn loop_stencils_are_consistent_across_levels() {
    assert_consistent_across_levels(Builtin::Loop, shapes::icosahedron(), 2, 2);
    assert_consistent_across_levels(Builtin::Loop, shapes::tetrahedron(), 2, 1);
}

#[test]
fn other_schemes_stencils_are_consistent_across_levels() {
    assert_consistent_across_levels(Builtin::SwQuad, shapes::cube(), 2, 3);
    assert_consistent_across_levels(Builtin::Butterfly, shapes::octahedron(), 3, 17);
}

/// Interpolating schemes keep their vertices: the stencil at a face's corner is that corner.
#[test]
fn interpolating_stencils_at_corners_are_the_vertices() {
    for (builtin, soup, levels) in
        [(Builtin::Butterfly, shapes::icosahedron(), 3), (Builtin::Kobbelt, shapes::cube(), 3)]
    {
        let mesh =
            refine_uniform(&Mesh::build(soup).unwrap(), builtin.scheme(), levels, &RefineOptions::DEFAULT).unwrap();
        let patches = patches(builtin, &mesh);
        for face in mesh.face_ids().step_by(7) {
            let (start, points, m, shape) = find(&patches, &mesh, face);
            let s = surface_stencil(&m, shape, Dyadic::new(0, 0, 1)).unwrap();
            assert_close(
                apply(&s.position, &points),
                mesh.position(mesh.origin(start)),
                1e-13,
                &format!("{builtin} {face}"),
            );
        }
    }
}

/// At an extraordinary vertex the tangents are directions whose cross product is the normal:
/// it is the limit of the normals at points approaching the vertex.
#[test]
fn normals_at_extraordinary_vertices_are_the_limit_of_nearby_normals() {
    for k in [3, 5, 6, 8, 9] {
        let cc = Builtin::CatmullClark.scheme();
        let mesh = refine_uniform(&Mesh::build(shapes::pole(k)).unwrap(), cc, 1, &RefineOptions::DEFAULT).unwrap();
        let face = mesh.vertex_faces(subdiv_mesh::VertexId::new(0)).next().unwrap();
        let start = mesh.face_half_edges(face).find(|&h| mesh.origin(h).index() == 0).unwrap();
        let found = patches(Builtin::CatmullClark, &mesh).at(&mesh, start).unwrap();
        let points = positions(&mesh, &found);
        let (m, shape) = (found.matrices, found.shape);
        let normal = |p: Dyadic| {
            let s = surface_stencil(&m, shape, p).unwrap();
            apply(&s.du, &points).cross(apply(&s.dv, &points)).normalize()
        };
        let at_vertex = normal(Dyadic::new(0, 0, 1));
        let s = surface_stencil(&m, shape, Dyadic::new(0, 0, 1)).unwrap();
        assert!(!s.exact_derivatives);
        let near = normal(Dyadic::new(1, 1, 1 << 20));
        assert!(at_vertex.dot(near) > 1.0 - 1e-6, "k = {k}: {at_vertex} vs {near}");
        assert!(at_vertex.z > 0.9, "k = {k}: the dome's normal points up: {at_vertex}");
    }
}

/// The vertex of `meshes[k]` (each mesh the refinement of the one before) at the dyadic point
/// `point` (denominator 2^k) of the face whose patch starts at `start` in `meshes[0]`: the
/// corner it becomes after descending k times through the children that hold it.
fn vertex_at(builtin: Builtin, meshes: &[Mesh], start: HalfEdgeId, face_size: usize, point: Dyadic) -> VertexId {
    let domain = if face_size == 3 { FaceDomain::Triangle } else { FaceDomain::Quad };
    let (mut h, mut p) = (start, point);
    for level in 0..meshes.len() - 1 {
        let starts = sub_patch_starts(builtin.scheme(), &meshes[level], h, &meshes[level + 1]).unwrap();
        let (c, at, _) = domain.child_of(p);
        (h, p) = (starts[c], at);
    }
    let (a, b, q) = (p.u, p.v, p.denominator);
    let mesh = meshes.last().unwrap();
    let corner = match (a, b, face_size) {
        (0, 0, _) => h,
        (_, 0, _) => mesh.next(h),
        (_, _, 4) if a == q => mesh.next(mesh.next(h)),
        _ => mesh.prev(h),
    };
    assert!((a == 0 || a == q) && (b == 0 || b == q), "{point:?} is not dyadic at this depth");
    mesh.origin(corner)
}

/// The limit position of an interior vertex by the classic closed-form masks: Catmull-Clark
/// `(n²·v + 4·Σ e + Σ f) / (n (n + 5))` on quads, Loop `(1 − nχ)·v + χ·Σ e` with
/// `χ = 1 / (n + 3 / (8β))`.
fn limit_by_mask(builtin: Builtin, mesh: &Mesh, v: VertexId) -> DVec3 {
    let n = mesh.valence(v) as f64;
    let ring: DVec3 = mesh.one_ring(v).iter().map(|&w| mesh.position(w)).sum();
    match builtin {
        Builtin::CatmullClark => {
            let diagonals: DVec3 = mesh
                .vertex_faces(v)
                .map(|f| {
                    let corners = mesh.face_vertices(f);
                    let i = corners.iter().position(|&c| c == v).unwrap();
                    mesh.position(corners[(i + 2) % 4])
                })
                .sum();
            (n * n * mesh.position(v) + 4.0 * ring + diagonals) / (n * (n + 5.0))
        }
        Builtin::Loop => {
            let cos = (std::f64::consts::TAU / n).cos();
            let beta = (5.0 / 8.0 - (3.0 / 8.0 + cos / 4.0).powi(2)) / n;
            let chi = 1.0 / (n + 3.0 / (8.0 * beta));
            (1.0 - n * chi) * mesh.position(v) + chi * ring
        }
        _ => unreachable!("closed-form masks for Catmull-Clark and Loop only"),
    }
}

/// At a dyadic point (a/2^k, b/2^k) the stencil is k refinements exactly: the refined vertex
/// itself for interpolating schemes, and the refined vertex's limit mask for approximating ones.
#[test]
fn stencils_at_dyadic_points_are_refinement() {
    let cases = [
        (Builtin::CatmullClark, shapes::cube(), 2),
        (Builtin::CatmullClark, shapes::pole(5), 1),
        (Builtin::Loop, shapes::icosahedron(), 2),
        (Builtin::Butterfly, shapes::icosahedron(), 3),
        (Builtin::Kobbelt, shapes::cube(), 3),
    ];
    let depth = 3;
    for (builtin, soup, base_levels) in cases {
        let scheme = builtin.scheme();
        let base = refine_uniform(&Mesh::build(soup).unwrap(), scheme, base_levels, &RefineOptions::DEFAULT).unwrap();
        let mut meshes = vec![base];
        for _ in 0..depth {
            meshes.push(refine(meshes.last().unwrap(), scheme, &RefineOptions::DEFAULT).unwrap());
        }
        let patches = patches(builtin, &meshes[0]);
        let mut checked = 0;
        for face in meshes[0].face_ids().step_by(5) {
            let found = patches.find(&meshes[0], face).unwrap_or_else(|| panic!("{builtin}: face {face}"));
            let points = positions(&meshes[0], &found);
            let face_size = found.matrices.face_size;
            let q = 1 << depth;
            for (a, b) in [(1, 0), (3, 1), (5, 2), (1, 1), (2, 5), (7, 1), (0, 3)] {
                if face_size == 3 && a + b > q {
                    continue;
                }
                let point = Dyadic::new(a, b, q);
                let s = surface_stencil(&found.matrices, found.shape, point).unwrap();
                let vertex = vertex_at(builtin, &meshes, found.start, face_size, point);
                let fine = meshes.last().unwrap();
                if fine.is_boundary_vertex(vertex) && !matches!(builtin, Builtin::Butterfly | Builtin::Kobbelt) {
                    continue; // the closed-form masks are the interior ones
                }
                let expected = match builtin {
                    Builtin::Butterfly | Builtin::Kobbelt => fine.position(vertex),
                    _ => limit_by_mask(builtin, fine, vertex),
                };
                let what = format!("{builtin} face {face} at {point:?}");
                assert_close(apply(&s.position, &points), expected, 1e-13, &what);
                checked += 1;
            }
        }
        assert!(checked > 20, "{builtin}: {checked} points");
    }
}

/// √3 through its ternary split: at an extraordinary vertex of valence `k` the limit is
/// Kobbelt's closed form — the vertex rule `p' = (1 − kβ) p + kβ q̄` and the ring's mean moving
/// to `(p + 2 q̄) / 3` (its new neighbours are the centroids of its faces) keep
/// `(p + 3kβ q̄) / (1 + 3kβ)` — and the normal there is the limit of the normals nearby, on a
/// jittered bipyramid refined four √3 steps (so each face's patch holds one irregular vertex).
#[test]
fn sqrt3_limit_at_extraordinary_vertices_is_the_closed_form() {
    let sqrt3 = Builtin::Sqrt3.scheme();
    for k in [3, 4, 5, 7, 8] {
        let mut soup = PolygonSoup::new();
        for i in 0..k {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            soup.push_vertex(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        soup.push_vertex(DVec3::new(0.1, -0.05, 1.0));
        soup.push_vertex(-DVec3::Z);
        let ring = |i: usize| VertexId::new((i % k) as u32);
        let (top, bottom) = (VertexId::new(k as u32), VertexId::new(k as u32 + 1));
        for i in 0..k {
            soup.push_face([top, ring(i), ring(i + 1)]);
            soup.push_face([bottom, ring(i + 1), ring(i)]);
        }
        let coarse = Mesh::build(soup).unwrap();
        let mesh = refine_uniform(&coarse, sqrt3, 4, &RefineOptions::DEFAULT).unwrap();
        let apex = VertexId::new(k as u32);
        let face = mesh.vertex_faces(apex).next().unwrap();
        let start = mesh.face_half_edges(face).find(|&h| mesh.origin(h) == apex).unwrap();
        let found = patches(Builtin::Sqrt3, &mesh).at(&mesh, start).unwrap_or_else(|| panic!("k = {k}: no patch"));
        let points = positions(&mesh, &found);
        let (m, shape) = (found.matrices, found.shape);
        let s = surface_stencil(&m, shape, Dyadic::new(0, 0, 1)).unwrap();
        check_sums(&s, &format!("k = {k}"));
        let beta = (4.0 - 2.0 * (std::f64::consts::TAU / k as f64).cos()) / (9.0 * k as f64);
        let ring_mean = mesh.one_ring(apex).iter().map(|&v| mesh.position(v)).sum::<DVec3>() / k as f64;
        let a = 3.0 * k as f64 * beta;
        let closed = (mesh.position(apex) + a * ring_mean) / (1.0 + a);
        assert_close(apply(&s.position, &points), closed, 1e-13, &format!("k = {k}: limit at the vertex"));
        let normal = |p: Dyadic| {
            let s = surface_stencil(&m, shape, p).unwrap();
            apply(&s.du, &points).cross(apply(&s.dv, &points)).normalize()
        };
        let near = normal(Dyadic::new(1, 1, 3i64.pow(16)));
        assert!(normal(Dyadic::new(0, 0, 1)).dot(near) > 1.0 - 1e-6, "k = {k}");
        // Every stencil of a grid sums to 1, its tangents to 0 (base-3 addresses of eighths).
        for j in 0..=8 {
            for i in 0..=8 - j {
                check_sums(&surface_stencil(&m, shape, Dyadic::new(i, j, 8)).unwrap(), &format!("k = {k}"));
            }
        }
    }
}
