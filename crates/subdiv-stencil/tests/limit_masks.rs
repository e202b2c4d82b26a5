//! Approximating schemes: the limit surface at the dyadic points of level `L` is the level-`L`
//! refined mesh with each vertex moved to its limit position by the scheme's limit mask (the
//! dominant left eigenvector of its local subdivision matrix, in closed form: Catmull-Clark's
//! `(k² v + 4 Σ e + Σ f) / (k (k + 5))`, Loop's `(1 − k χ) v + χ Σ n` with
//! `χ = 1 / (3 / (8 β) + k)`, and the cubic B-spline's `(p + 4 v + n) / 6` along a boundary),
//! `L = 1..3`, extraordinary vertices and boundaries included. An independent check of the exact
//! evaluator: refinement and closed forms on one side, sub-patch matrices' eigenvectors and the
//! descent on the other.

use std::collections::HashMap;

use glam::DVec3;
use subdiv_mesh::{Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::{Builtin, RefineOptions, Scheme, refine_uniform};
use subdiv_stencil::LimitEvaluator;

/// Every vertex moved by a fixed pseudo-random offset, so that no symmetry helps.
fn jittered(mut soup: PolygonSoup, amount: f64) -> PolygonSoup {
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

/// The limit position of `v` under Catmull-Clark (quads) or Loop (triangles).
fn limit_position(mesh: &Mesh, v: VertexId, loop_: bool) -> DVec3 {
    let p = mesh.position(v);
    if mesh.is_boundary_vertex(v) {
        // The boundary is the cubic B-spline of the boundary polygon (edge-only rule).
        let ring = mesh.one_ring(v);
        let (first, last) = (ring[0], ring[ring.len() - 1]);
        return (mesh.position(first) + 4.0 * p + mesh.position(last)) / 6.0;
    }
    let k = mesh.valence(v) as f64;
    if loop_ {
        let c = 3.0 / 8.0 + (std::f64::consts::TAU / k).cos() / 4.0;
        let beta = (5.0 / 8.0 - c * c) / k;
        let chi = 1.0 / (3.0 / (8.0 * beta) + k);
        let sum: DVec3 = mesh.one_ring(v).iter().map(|&n| mesh.position(n)).sum();
        return (1.0 - k * chi) * p + chi * sum;
    }
    let (mut edges, mut faces) = (DVec3::ZERO, DVec3::ZERO);
    for h in mesh.outgoing(v) {
        edges += mesh.position(mesh.dest(h));
        faces += mesh.position(mesh.origin(mesh.next(mesh.next(h))));
    }
    (k * k * p + 4.0 * edges + faces) / (k * (k + 5.0))
}

/// Looks points up by position: the distance to the nearest within one cell.
struct Points {
    cells: HashMap<[i64; 3], Vec<DVec3>>,
    size: f64,
}

impl Points {
    fn new(points: &[DVec3], size: f64) -> Self {
        let mut cells: HashMap<[i64; 3], Vec<DVec3>> = HashMap::new();
        for &p in points {
            cells.entry(Self::cell(p, size)).or_default().push(p);
        }
        Self { cells, size }
    }

    fn cell(p: DVec3, size: f64) -> [i64; 3] {
        (p / size).floor().to_array().map(|x| x as i64)
    }

    fn distance(&self, p: DVec3) -> f64 {
        let [x, y, z] = Self::cell(p, self.size);
        let mut best = f64::INFINITY;
        for d in 0..27 {
            let key = [x + d % 3 - 1, y + d / 3 % 3 - 1, z + d / 9 - 1];
            for q in self.cells.get(&key).into_iter().flatten() {
                best = best.min((*q - p).length());
            }
        }
        best
    }
}

/// Every grid point `(i, j) / 2^L` of every face is a level-`L` vertex's limit position, and
/// every such position a grid point's limit.
fn limit_masks_give_the_grid(scheme: &Scheme, name: &str, soup: PolygonSoup, levels: usize) {
    let loop_ = scheme.regular_valence() == 6;
    let mesh = Mesh::build(soup).unwrap();
    let eval = LimitEvaluator::new(scheme, &mesh, &RefineOptions::DEFAULT).unwrap();
    for level in 1..=levels {
        let refined = refine_uniform(&mesh, scheme, level, &RefineOptions::DEFAULT).unwrap();
        let masked: Vec<DVec3> = refined.vertices().map(|v| limit_position(&refined, v, loop_)).collect();
        let masked_points = Points::new(&masked, 1e-6);
        let mut grid = Vec::new();
        for f in mesh.face_ids() {
            for (g, point) in eval.grid(f, 1 << level).unwrap() {
                let gap = masked_points.distance(point.position);
                assert!(
                    gap < 1e-12,
                    "{scheme} {name} level {level} face {f} at {g:?}: {gap:e} from every masked vertex"
                );
                grid.push(point.position);
            }
        }
        let grid = Points::new(&grid, 1e-6);
        for (v, &p) in masked.iter().enumerate() {
            let gap = grid.distance(p);
            assert!(gap < 1e-12, "{scheme} {name} level {level}: vertex {v}'s limit is {gap:e} from every grid point");
        }
    }
}

#[test]
fn catmull_clark_is_refinement_then_its_limit_mask() {
    let cc = Builtin::CatmullClark.scheme();
    limit_masks_give_the_grid(cc, "cube", jittered(shapes::cube(), 0.1), 3);
    limit_masks_give_the_grid(cc, "default model", jittered(shapes::default_model(), 0.05), 2);
    limit_masks_give_the_grid(cc, "open grid", jittered(shapes::quad_grid(3, 2), 0.1), 3);
}

#[test]
fn loop_is_refinement_then_its_limit_mask() {
    let lp = Builtin::Loop.scheme();
    limit_masks_give_the_grid(lp, "tetrahedron", jittered(shapes::tetrahedron(), 0.1), 3);
    limit_masks_give_the_grid(lp, "octahedron", jittered(shapes::octahedron(), 0.1), 3);
    limit_masks_give_the_grid(lp, "icosahedron", jittered(shapes::icosahedron(), 0.1), 3);
}
