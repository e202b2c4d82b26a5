//! Tests of the topology: strips, implicit sites, runs written in place, triangle cells.

use super::*;
use std::collections::HashMap;
use subdiv_mesh::shapes;
use subdiv_stencil::Grid;

fn row(vertices: std::ops::Range<u32>, den: u64) -> Vec<RowPoint> {
    vertices
        .enumerate()
        .map(|(k, vertex)| RowPoint { vertex, num: 2 * k as u64 + 1, den, near: true, extra: None })
        .collect()
}

/// Rows of equal rates merge into quads; rows of rates 2 and 3 into 3 triangles, each
/// counter-clockwise with the first row on the left.
#[test]
fn strips_merge_rows_in_parameter_order() {
    let mesh = Mesh::build(shapes::quad_torus(3, 3)).unwrap();
    let mut b = Builder::new(&mesh, false, true);
    b.out.polygon_offsets.push(0);
    b.strip(&row(0..3, 6), &row(10..13, 6), 0);
    assert_eq!(b.out.polygon_faces.len(), 2);
    assert_eq!(b.out.polygon_vertices[..4], [10, 11, 1, 0]);
    assert_eq!(b.out.triangles.len(), 4);
    let mut b = Builder::new(&mesh, false, false);
    // a: 1/4, 3/4; b: 1/6, 3/6, 5/6.
    b.strip(&row(0..2, 4), &row(10..13, 6), 0);
    assert_eq!(b.out.triangles, [[10, 11, 0], [10 + 1, 1, 0], [11, 12, 1]]);
}

/// The implicit sites of blocks and the explicit ones of the other vertices read the same
/// by vertex ([`Topology::site`]), in order ([`Topology::for_each_site`]) and, for the
/// explicit ones, with their numbers ([`Topology::explicit_sites`]): a block's
/// point `(i, j)` at `((2i+1)/2n, (2j+1)/2n)` of its face, every other site where it was
/// made, on meshes with N-gons and borders at mixed rates.
#[test]
fn block_sites_are_implicit() {
    for soup in [shapes::ngon_prism(5), shapes::quad_grid(3, 2), shapes::default_model()] {
        let mesh = Mesh::build(soup).unwrap();
        let domains: Vec<_> = mesh
            .face_ids()
            .map(|f| PackedDomain::pack(FaceDomain::of(subdiv_schemes::Split::Quad, mesh.face_size(f))))
            .collect();
        let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 1 + f % 4).collect();
        let mut out = Topology::default();
        Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut out);
        assert_eq!(out.vertex_count as usize, predicted_vertices(&mesh, Split::Quad, &rates, None));
        let mut walked = Vec::new();
        out.for_each_site(|s| walked.push(s));
        assert_eq!(walked.len(), out.vertex_count as usize);
        for (v, s) in walked.iter().enumerate() {
            assert_eq!(*s, out.site(v as u32), "vertex {v}");
        }
        let explicit: Vec<(u32, Site)> = out.explicit_sites().collect();
        assert_eq!(explicit.len(), out.sites.len());
        for &(v, s) in &explicit {
            assert!(!out.blocks.iter().any(|b| (b.base..b.base + b.len()).contains(&v)), "vertex {v} in a block");
            assert_eq!(s, out.site(v), "vertex {v}");
        }
        let in_blocks: u32 = out.blocks.iter().map(Block::len).sum();
        assert_eq!(out.sites.len() as u32 + in_blocks, out.vertex_count);
        for b in &out.blocks {
            let n = i64::from(b.rate);
            for j in 0..n {
                for i in 0..n {
                    let s = out.site(b.base + (j * n + i) as u32);
                    assert_eq!((s.face, s.point), (b.face, Dyadic::new(2 * i + 1, 2 * j + 1, 2 * n)));
                }
            }
        }
    }
}

/// The runs' triangles land where the builder counted them, between the explicit ones,
/// whether written on one thread or halved between several (at rates where the halving
/// starts: more than `GRAIN` triangles): every output edge of a closed mesh then has two
/// triangles, and each run's range holds its face's triangles (a grid's, of its points).
#[test]
fn runs_are_written_in_place() {
    for soup in [shapes::default_model(), shapes::ngon_prism(5), shapes::quad_torus(6, 5)] {
        let mesh = Mesh::build(soup).unwrap();
        let domains: Vec<_> = mesh
            .face_ids()
            .map(|f| PackedDomain::pack(FaceDomain::of(subdiv_schemes::Split::Quad, mesh.face_size(f))))
            .collect();
        let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 60 + 9 * (f % 5)).collect();
        let mut out = Topology::default();
        Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut out);
        let n = out.triangle_count() as usize;
        assert!(n > 2 << 14, "{n} triangles: too few to halve");
        let (mut serial, mut parallel) = (vec![0; 3 * n], vec![u32::MAX; 3 * n]);
        out.write_triangles(&mut serial, false);
        out.write_triangles(&mut parallel, true);
        assert_eq!(serial, parallel);
        let (mut faces, mut faces_parallel) = (vec![FaceId::new(0); n], vec![FaceId::new(7); n]);
        out.write_triangle_faces(&mut faces, false);
        out.write_triangle_faces(&mut faces_parallel, true);
        assert_eq!(faces, faces_parallel);
        let in_runs: u32 = out.runs.iter().map(Run::triangles).sum();
        assert_eq!(in_runs as usize + out.triangles.len(), n);
        for r in &out.runs {
            let range = r.first as usize..(r.first + r.triangles()) as usize;
            assert!(faces[range.clone()].iter().all(|f| f.index() == r.face as usize));
            if let RunShape::Grid { base, n } = r.shape {
                let grid = base..base + n * n;
                assert!(serial[3 * range.start..3 * range.end].iter().all(|v| grid.contains(v)));
            }
        }
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in serial.chunks_exact(3) {
            for k in 0..3 {
                *edges.entry((t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))).or_default() += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 2), "an edge without two triangles");
    }
}

/// A triangle's cell points come in `Grid::Dual`'s order (the tables' order, which the
/// closed-form indices of the evaluator and the hexagons rely on).
#[test]
fn triangle_cells_follow_the_dual_grid_order() {
    let mesh = Mesh::build(shapes::icosahedron()).unwrap();
    let domains = vec![PackedDomain::pack(Some(FaceDomain::Triangle)); mesh.face_count()];
    for n in [1, 2, 3, 7] {
        let mut out = Topology::default();
        Builder::new(&mesh, true, false).build(&domains, &vec![n; mesh.face_count()], None, &mut out);
        let dual = Grid::Dual.points(3, n);
        let face0: Vec<Dyadic> = out.sites.iter().take(dual.len()).map(|s| s.point).collect();
        assert_eq!(face0, dual, "rate {n}");
        assert_eq!(
            out.vertex_count as usize,
            predicted_vertices(&mesh, Split::Triangle, &vec![n; mesh.face_count()], None)
        );
    }
}

/// Every domain packs into four bytes and back, holes too.
#[test]
fn domains_pack_and_unpack() {
    let mut domains = vec![None, Some(FaceDomain::Quad), Some(FaceDomain::Triangle), Some(FaceDomain::Ternary)];
    domains.extend([3, 5, 8, 9, 10, 1000].map(|n| FaceDomain::of(subdiv_schemes::Split::Quad, n)));
    for d in domains {
        assert_eq!(PackedDomain::pack(d).get(), d);
    }
    assert_eq!(std::mem::size_of::<PackedDomain>(), 4);
}
