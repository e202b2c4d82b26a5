//! Procedural shapes: the platonic solids, tori, grids, poles and prisms that tests, benches and
//! examples build on, and the built-in [`default_model`].
//!
//! Every shape is a valid, consistently oriented soup (faces counter-clockwise seen from
//! outside, or from +z for the flat ones), so [`Mesh::build`] always accepts it.
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh};
//!
//! let torus = Mesh::build(shapes::quad_torus(8, 6))?;
//! assert_eq!(torus.genus(), Some(1));
//! # Ok::<(), subdiv_mesh::MeshError>(())
//! ```

use std::f64::consts::TAU;

use glam::DVec3;

use crate::{Channel, FaceId, Mesh, PolygonSoup, VertexId};

/// The golden ratio, which places the icosahedron's vertices.
const PHI: f64 = 1.618_033_988_749_895;

/// Orients every face of a convex shape centred at the origin outward.
fn convex(positions: Vec<DVec3>, faces: &[&[u32]]) -> PolygonSoup {
    let mut soup = PolygonSoup::from_indices(positions, faces);
    for f in 0..soup.face_count() {
        let face = FaceId::new(f as u32);
        let corners: Vec<DVec3> = soup.face(face).iter().map(|v| soup.positions()[v.index()]).collect();
        let centroid = corners.iter().sum::<DVec3>() / corners.len() as f64;
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        if normal.dot(centroid) < 0.0 {
            soup.flip_face(face);
        }
    }
    soup
}

/// The cube `[-1, 1]³`: 8 vertices of valence 3, 6 quads.
pub fn cube() -> PolygonSoup {
    let positions = (0..8).map(|i| DVec3::new(f(i & 1), f(i >> 1 & 1), f(i >> 2 & 1))).collect();
    fn f(bit: u32) -> f64 {
        if bit == 1 { 1.0 } else { -1.0 }
    }
    convex(positions, &[&[0, 2, 3, 1], &[4, 5, 7, 6], &[0, 1, 5, 4], &[2, 6, 7, 3], &[0, 4, 6, 2], &[1, 3, 7, 5]])
}

/// The regular tetrahedron inscribed in the cube `[-1, 1]³`: 4 vertices, 4 triangles.
pub fn tetrahedron() -> PolygonSoup {
    let positions = vec![
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, -1.0, -1.0),
        DVec3::new(-1.0, 1.0, -1.0),
        DVec3::new(-1.0, -1.0, 1.0),
    ];
    convex(positions, &[&[0, 1, 2], &[0, 3, 1], &[0, 2, 3], &[1, 3, 2]])
}

/// The regular octahedron with vertices `±x, ±y, ±z`: 6 vertices of valence 4, 8 triangles.
pub fn octahedron() -> PolygonSoup {
    let positions = vec![DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z];
    convex(positions, &[&[0, 2, 4], &[2, 1, 4], &[1, 3, 4], &[3, 0, 4], &[2, 0, 5], &[1, 2, 5], &[3, 1, 5], &[0, 3, 5]])
}

/// The regular icosahedron on the unit sphere: 12 vertices of valence 5, 20 triangles.
pub fn icosahedron() -> PolygonSoup {
    let raw = [
        (-1.0, PHI, 0.0),
        (1.0, PHI, 0.0),
        (-1.0, -PHI, 0.0),
        (1.0, -PHI, 0.0),
        (0.0, -1.0, PHI),
        (0.0, 1.0, PHI),
        (0.0, -1.0, -PHI),
        (0.0, 1.0, -PHI),
        (PHI, 0.0, -1.0),
        (PHI, 0.0, 1.0),
        (-PHI, 0.0, -1.0),
        (-PHI, 0.0, 1.0),
    ];
    let positions = raw.iter().map(|&(x, y, z)| DVec3::new(x, y, z).normalize()).collect();
    convex(
        positions,
        &[
            &[0, 11, 5],
            &[0, 5, 1],
            &[0, 1, 7],
            &[0, 7, 10],
            &[0, 10, 11],
            &[1, 5, 9],
            &[5, 11, 4],
            &[11, 10, 2],
            &[10, 7, 6],
            &[7, 1, 8],
            &[3, 9, 4],
            &[3, 4, 2],
            &[3, 2, 6],
            &[3, 6, 8],
            &[3, 8, 9],
            &[4, 9, 5],
            &[2, 4, 11],
            &[6, 2, 10],
            &[8, 6, 7],
            &[9, 8, 1],
        ],
    )
}

/// The regular dodecahedron on the unit sphere: 20 vertices of valence 3, 12 pentagons (the dual
/// of the icosahedron).
pub fn dodecahedron() -> PolygonSoup {
    let ico = built(icosahedron());
    // One dodecahedron vertex per icosahedron face, one pentagon per icosahedron vertex; the
    // faces around a vertex, counter-clockwise, are the pentagon's corners counter-clockwise.
    let positions: Vec<DVec3> =
        ico.faces().map(|face| face.iter().map(|v| ico.position(*v)).sum::<DVec3>().normalize()).collect();
    let mut soup = PolygonSoup::new();
    for p in positions {
        soup.push_vertex(p);
    }
    for v in ico.vertices() {
        soup.push_face(ico.vertex_faces(v).map(|f| VertexId::new(f.raw())));
    }
    soup
}

/// A torus of `m × n` quads (`m` around the axis, `n` around the tube; both at least 3), radii
/// 1 and 0.4, axis z. Every vertex has valence 4.
pub fn quad_torus(m: usize, n: usize) -> PolygonSoup {
    torus(m, n, false)
}

/// A torus of `2 m n` triangles: [`quad_torus`] with each quad split along a diagonal, so every
/// vertex has valence 6.
pub fn triangle_torus(m: usize, n: usize) -> PolygonSoup {
    torus(m, n, true)
}

fn torus(m: usize, n: usize, triangles: bool) -> PolygonSoup {
    let (m, n) = (m.max(3), n.max(3));
    let (major, minor) = (1.0, 0.4);
    let mut soup = PolygonSoup::with_capacity(m * n, m * n * 2, m * n * 6);
    for i in 0..m {
        let theta = TAU * i as f64 / m as f64;
        for j in 0..n {
            let phi = TAU * j as f64 / n as f64;
            let r = major + minor * phi.cos();
            soup.push_vertex(DVec3::new(r * theta.cos(), r * theta.sin(), minor * phi.sin()));
        }
    }
    let id = |i: usize, j: usize| VertexId::new(((i % m) * n + j % n) as u32);
    for i in 0..m {
        for j in 0..n {
            // +θ then +φ: the normal ∂θ × ∂φ points away from the tube's centre.
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if triangles {
                soup.push_face([a, b, c]);
                soup.push_face([a, c, d]);
            } else {
                soup.push_face([a, b, c, d]);
            }
        }
    }
    soup
}

/// An open grid of `m × n` unit-spaced quads in the plane z = 0, from the origin along +x
/// (`m` faces) and +y (`n` faces), facing +z. Vertex `(i, j)` has id `j (m + 1) + i`.
pub fn quad_grid(m: usize, n: usize) -> PolygonSoup {
    let (m, n) = (m.max(1), n.max(1));
    let mut soup = PolygonSoup::with_capacity((m + 1) * (n + 1), m * n, 4 * m * n);
    for j in 0..=n {
        for i in 0..=m {
            soup.push_vertex(DVec3::new(i as f64, j as f64, 0.0));
        }
    }
    let id = |i: usize, j: usize| VertexId::new((j * (m + 1) + i) as u32);
    for j in 0..n {
        for i in 0..m {
            soup.push_face([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    soup
}

/// An open disk of quads around one vertex of valence `k` (at least 3): `k` sectors of 2 × 2
/// quads, so that vertex 0, at the origin, is the only extraordinary vertex and its two-ring is
/// complete. The disk is gently domed (z = 0.25 at the centre) so that it is not planar.
pub fn pole(k: usize) -> PolygonSoup {
    let k = k.max(3);
    let direction = |s: usize| {
        let angle = TAU * (s % k) as f64 / k as f64;
        DVec3::new(angle.cos(), angle.sin(), 0.0)
    };
    let mut soup = PolygonSoup::with_capacity(6 * k + 1, 4 * k, 16 * k);
    soup.push_vertex(DVec3::new(0.0, 0.0, 0.25));
    // Per sector s: the spoke vertices (a, 0) for a = 1, 2 (shared with sector s − 1 as its
    // (0, b)) and the inner vertices (a, b) for a, b ∈ {1, 2}.
    let place = |s: usize, a: usize, b: usize| {
        let p = (direction(s) * a as f64 + direction(s + 1) * b as f64) / 2.0;
        p + DVec3::Z * 0.25 * (1.0 - p.length_squared() / 4.0)
    };
    for s in 0..k {
        soup.push_vertex(place(s, 1, 0));
        soup.push_vertex(place(s, 2, 0));
        for (a, b) in [(1, 1), (2, 1), (1, 2), (2, 2)] {
            soup.push_vertex(place(s, a, b));
        }
    }
    let id = |s: usize, a: usize, b: usize| -> VertexId {
        let raw = match (a, b) {
            (0, 0) => 0,
            (_, 0) => 1 + 6 * (s % k) + (a - 1),
            (0, _) => 1 + 6 * ((s + 1) % k) + (b - 1),
            _ => 1 + 6 * (s % k) + 2 + (b - 1) * 2 + (a - 1),
        };
        VertexId::new(raw as u32)
    };
    for s in 0..k {
        for b in 0..2 {
            for a in 0..2 {
                // (a, b) → (a + 1, b) → (a + 1, b + 1) → (a, b + 1): counter-clockwise seen from +z
                // since sector directions turn counter-clockwise.
                soup.push_face([id(s, a, b), id(s, a + 1, b), id(s, a + 1, b + 1), id(s, a, b + 1)]);
            }
        }
    }
    soup
}

/// A prism over a regular `n`-gon (`n` at least 3): two `n`-gon caps at z = ±1 and `n` quads.
pub fn ngon_prism(n: usize) -> PolygonSoup {
    let n = n.max(3);
    let mut positions = Vec::with_capacity(2 * n);
    for z in [-1.0, 1.0] {
        for i in 0..n {
            let angle = TAU * i as f64 / n as f64;
            positions.push(DVec3::new(angle.cos(), angle.sin(), z));
        }
    }
    let bottom: Vec<u32> = (0..n as u32).collect();
    let top: Vec<u32> = (n as u32..2 * n as u32).collect();
    let sides: Vec<[u32; 4]> = (0..n as u32)
        .map(|i| {
            let j = (i + 1) % n as u32;
            [i, j, j + n as u32, i + n as u32]
        })
        .collect();
    let mut faces: Vec<&[u32]> = vec![&bottom, &top];
    faces.extend(sides.iter().map(|s| s.as_slice()));
    convex(positions, &faces)
}

/// The built-in model, "star": a ball with twelve rounded spikes and twenty dimples, made of 60
/// quads with 20 vertices of valence 3 (the dimples), 30 of valence 4 and 12 of valence 5 (the
/// spikes). It is the dodecahedron split once into quads, each pentagon's centre pulled out.
/// Subdivided, it shows what extraordinary vertices do: the spikes' tips and the dimples are the
/// places where a scheme is not a plain tensor-product spline.
pub fn default_model() -> PolygonSoup {
    let dodeca = built(dodecahedron());
    let mut soup = PolygonSoup::with_capacity(62, 60, 240);
    // Old vertices (valence 3), then edge points (valence 4), then face points (valence 5).
    for v in dodeca.vertices() {
        soup.push_vertex(dodeca.position(v) * 0.82);
    }
    let edge_base = soup.vertex_count() as u32;
    for e in dodeca.edges() {
        let [a, b] = dodeca.edge_vertices(e);
        soup.push_vertex((dodeca.position(a) + dodeca.position(b)).normalize() * 1.0);
    }
    let face_base = soup.vertex_count() as u32;
    for face in dodeca.faces() {
        soup.push_vertex(face.iter().map(|v| dodeca.position(*v)).sum::<DVec3>().normalize() * 1.75);
    }
    for f in dodeca.face_ids() {
        let centre = VertexId::new(face_base + f.raw());
        let halves: Vec<_> = dodeca.face_half_edges(f).collect();
        for (i, &h) in halves.iter().enumerate() {
            let before = halves[(i + halves.len() - 1) % halves.len()];
            let edge_point = |h| VertexId::new(edge_base + dodeca.edge(h).raw());
            soup.push_face([dodeca.origin(h), edge_point(h), centre, edge_point(before)]);
        }
    }
    soup
}

/// `soup` with every vertex moved by a fixed pseudo-random offset of up to `amount / 2` per
/// coordinate (xorshift from a fixed seed: the same mesh on every run), so that tests meet no
/// symmetry that would hide a mistake.
///
/// ```
/// use subdiv_mesh::shapes;
///
/// let a = shapes::jittered(shapes::cube(), 0.1);
/// assert_eq!(a.positions(), shapes::jittered(shapes::cube(), 0.1).positions());
/// assert!(a.positions().iter().zip(shapes::cube().positions()).all(|(p, q)| (*p - *q).abs().max_element() <= 0.05));
/// ```
pub fn jittered(mut soup: PolygonSoup, amount: f64) -> PolygonSoup {
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for p in soup.positions_mut() {
        *p += DVec3::new(next(), next(), next()) * amount;
    }
    soup
}

/// `positions` twisted about the vertical (y) axis through their bounding box's centre, by an
/// angle growing linearly from 0 at the box's bottom to `top` radians at its top (heights and
/// distances to the axis are kept): the built-in deformation that animates a cage in
/// `subdiv render --frames`, the GPU tests and benches.
///
/// ```
/// use subdiv_mesh::{shapes, DVec3};
///
/// let cage = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 0.0), DVec3::new(-1.0, 1.0, 0.0)];
/// let moved = shapes::twist(&cage, std::f64::consts::FRAC_PI_2);
/// assert_eq!(moved[0], cage[0]); // the bottom stays
/// assert!(moved[1].distance(DVec3::new(0.0, 1.0, -1.0)) < 1e-12); // the top turns by 90°
/// ```
pub fn twist(positions: &[DVec3], top: f64) -> Vec<DVec3> {
    let (lo, hi) = positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let centre = 0.5 * (lo + hi);
    let height = hi.y - lo.y;
    positions
        .iter()
        .map(|&p| {
            let t = if height > 0.0 { (p.y - lo.y) / height } else { 0.0 };
            let (sin, cos) = (top * t).sin_cos();
            let (x, z) = (p.x - centre.x, p.z - centre.z);
            DVec3::new(centre.x + cos * x + sin * z, p.y, centre.z - sin * x + cos * z)
        })
        .collect()
}

/// `soup` with a texture channel `"uv"` in which every face is its own chart: a corner's
/// value is its vertex's `(x + 2y + f, z − x)` on face `f`, so every edge is a seam (for tests
/// of face-varying channels at their hardest).
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
///
/// let cube = Mesh::build(shapes::face_charts(shapes::cube()))?;
/// let uv = &cube.channels()[0];
/// assert_eq!((uv.name(), uv.dimension()), ("uv", 2));
/// assert!(cube.edges().all(|e| cube.is_seam(uv, e)));
/// # Ok::<(), subdiv_mesh::MeshError>(())
/// ```
pub fn face_charts(mut soup: PolygonSoup) -> PolygonSoup {
    let mut values = Vec::new();
    for (f, face) in soup.faces().enumerate() {
        for v in face {
            let p = soup.positions()[v.index()];
            values.extend([p.x + 2.0 * p.y + f as f64, p.z - p.x]);
        }
    }
    let indices = (0..values.len() as u32 / 2).collect();
    soup.channels.push(crate::Channel::new("uv", 2, values, indices));
    soup
}

/// Builds a soup that is valid by construction.
fn built(soup: PolygonSoup) -> Mesh {
    match Mesh::build(soup) {
        Ok(mesh) => mesh,
        // The shapes above are valid by construction; reaching this is a bug in this module.
        Err(error) => unreachable!("procedural shape is invalid, please report: {error}"),
    }
}

/// `soup` with every face of more than three corners fanned into triangles from its first
/// corner: the triangle schemes' version of a quad shape (an open grid of triangles from
/// [`quad_grid`], say). Positions, crease and corner tags stay (they name vertices); a hole
/// becomes its triangles; channels keep each corner's value.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
///
/// let grid = Mesh::build(shapes::triangulated(shapes::quad_grid(3, 2)))?;
/// assert_eq!(grid.face_count(), 12);
/// assert!(grid.face_ids().all(|f| grid.face_size(f) == 3));
/// assert_eq!(grid.boundary_loops().len(), 1);
/// # Ok::<(), subdiv_mesh::MeshError>(())
/// ```
pub fn triangulated(soup: PolygonSoup) -> PolygonSoup {
    let mut out = PolygonSoup::with_capacity(soup.positions().len(), 2 * soup.face_count(), 6 * soup.face_count());
    for &p in soup.positions() {
        out.push_vertex(p);
    }
    // Per face of `soup`, its first corner's index in the corner lists and its triangles' first.
    let mut corner = 0;
    let mut corners: Vec<(usize, usize)> = Vec::new();
    let mut first_triangle = Vec::with_capacity(soup.face_count() + 1);
    for face in soup.faces() {
        first_triangle.push(out.face_count());
        for k in 1..face.len().saturating_sub(1) {
            out.push_face([face[0], face[k], face[k + 1]]);
            corners.push((corner, k));
        }
        corner += face.len();
    }
    first_triangle.push(out.face_count());
    out.tags = soup.tags.clone();
    out.tags.holes = soup
        .tags
        .holes
        .iter()
        .filter(|h| h.index() + 1 < first_triangle.len())
        .flat_map(|h| (first_triangle[h.index()]..first_triangle[h.index() + 1]).map(|t| FaceId::new(t as u32)))
        .collect();
    out.channels = soup
        .channels
        .iter()
        .map(|c| {
            let at = |i: usize| c.indices().get(i).copied().unwrap_or(0);
            let indices =
                corners.iter().flat_map(|&(first, k)| [at(first), at(first + k), at(first + k + 1)]).collect();
            Channel::new(c.name(), c.dimension(), c.values().to_vec(), indices)
        })
        .collect();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RegularValence;

    #[test]
    fn twist_keeps_heights_and_axis_distances() {
        let cage: Vec<DVec3> =
            (0..27).map(|i| DVec3::new(f64::from(i % 3), f64::from(i / 3 % 3), f64::from(i / 9) + 0.5)).collect();
        assert_eq!(twist(&cage, 0.0), cage);
        let moved = twist(&cage, 72f64.to_radians());
        let axis = DVec3::new(1.0, 0.0, 1.5);
        for (p, q) in cage.iter().zip(&moved) {
            assert_eq!(p.y, q.y);
            let (a, b) = ((*p - axis).with_y(0.0).length(), (*q - axis).with_y(0.0).length());
            assert!((a - b).abs() < 1e-12, "{p} -> {q}");
        }
        // The bottom stays, the top turns by the whole angle.
        let top = cage.iter().position(|p| p.y == 2.0 && p.x == 2.0 && p.z == 1.5).unwrap();
        let angle = (moved[top] - axis).with_y(0.0).angle_between((cage[top] - axis).with_y(0.0));
        assert!((angle - 72f64.to_radians()).abs() < 1e-12);
        let bottom = cage.iter().position(|p| p.y == 0.0).unwrap();
        assert_eq!(moved[bottom], cage[bottom]);
    }

    fn counts(soup: PolygonSoup) -> (usize, usize, usize, i64, usize) {
        let mesh = Mesh::build(soup).unwrap();
        (
            mesh.vertex_count(),
            mesh.edge_count(),
            mesh.face_count(),
            mesh.euler_characteristic(),
            mesh.boundary_loops().len(),
        )
    }

    #[test]
    fn closed_shapes_have_the_expected_counts() {
        assert_eq!(counts(cube()), (8, 12, 6, 2, 0));
        assert_eq!(counts(tetrahedron()), (4, 6, 4, 2, 0));
        assert_eq!(counts(octahedron()), (6, 12, 8, 2, 0));
        assert_eq!(counts(icosahedron()), (12, 30, 20, 2, 0));
        assert_eq!(counts(dodecahedron()), (20, 30, 12, 2, 0));
        assert_eq!(counts(quad_torus(5, 4)), (20, 40, 20, 0, 0));
        assert_eq!(counts(triangle_torus(5, 4)), (20, 60, 40, 0, 0));
        assert_eq!(counts(ngon_prism(7)), (14, 21, 9, 2, 0));
        assert_eq!(counts(default_model()), (62, 120, 60, 2, 0));
    }

    #[test]
    fn open_shapes_have_one_boundary_loop() {
        assert_eq!(counts(quad_grid(3, 2)), (12, 17, 6, 1, 1));
        for k in 3..=9 {
            let mesh = Mesh::build(pole(k)).unwrap();
            assert_eq!(mesh.valence(VertexId::new(0)), k);
            assert_eq!(mesh.boundary_loops().len(), 1);
            assert_eq!(mesh.genus(), Some(0));
            // Only the pole is extraordinary (boundary corners of valence 2 are regular).
            let extraordinary: Vec<_> = mesh.extraordinary_vertices(RegularValence::QUADS).collect();
            let expected = if k == 4 { vec![] } else { vec![VertexId::new(0)] };
            assert_eq!(extraordinary, expected, "k = {k}");
        }
    }

    #[test]
    fn faces_face_outward() {
        for soup in [cube(), tetrahedron(), octahedron(), icosahedron(), dodecahedron(), ngon_prism(5), default_model()]
        {
            for face in soup.faces() {
                let p: Vec<DVec3> = face.iter().map(|v| soup.positions()[v.index()]).collect();
                let centroid = p.iter().sum::<DVec3>() / p.len() as f64;
                let normal = (p[1] - p[0]).cross(p[2] - p[0]);
                assert!(normal.dot(centroid) > 0.0, "{face:?} faces inward");
            }
        }
        for soup in [quad_grid(2, 2), pole(5)] {
            for face in soup.faces() {
                let p: Vec<DVec3> = face.iter().map(|v| soup.positions()[v.index()]).collect();
                assert!((p[1] - p[0]).cross(p[2] - p[0]).z > 0.0);
            }
        }
    }

    #[test]
    fn default_model_has_valence_3_4_and_5() {
        let mesh = Mesh::build(default_model()).unwrap();
        let histogram = mesh.valence_histogram();
        assert_eq!(histogram.into_iter().collect::<Vec<_>>(), [(3, 20), (4, 30), (5, 12)]);
    }
}
