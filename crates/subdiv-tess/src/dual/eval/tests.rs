//! Tests of the evaluator's routes against each other.

use super::*;
use subdiv_mesh::shapes;
use subdiv_schemes::Builtin;

/// The separable blocks give what the exact stencil tables give (position and normal,
/// through the patch frame), on a torus whose faces start their patches at every corner.
#[test]
fn separable_blocks_equal_the_table_route() {
    let mesh = Mesh::build(shapes::quad_torus(6, 5)).unwrap();
    let ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
    let cage = mesh.positions();
    let mut worst: f64 = 0.0;
    for n in [1u32, 2, 5, 8] {
        let basis = RateBasis::new(n);
        let count = (n * n) as usize;
        let (mut ps, mut ns) = (vec![DVec3::ZERO; count], vec![DVec3::ZERO; count]);
        for f in mesh.face_ids() {
            let Some(cv) = ev.cv(f.index() as u32) else { panic!("{f} of a torus is regular") };
            let Some(Resolved::Patch { patch, frame, .. }) = ev.levels.resolve(0, f) else { panic!("{f}") };
            let table =
                StencilTable::compute_rates(&patch.matrices, BoundaryInterpolation::EdgeOnly, n..=n).unwrap().remove(0);
            let points: Vec<DVec3> = patch.vertices.iter().map(|v| cage[v.index()]).collect();
            grid_block(&cv, cage, &basis, &mut WideSink(&mut ps, &mut ns), &mut Pending::new());
            let index: HashMap<Dyadic, usize> =
                (0..table.len(Grid::Dual)).map(|k| (table.point(Grid::Dual, k), k)).collect();
            let (ju, jv) = frame.chain([[1.0, 0.0], [0.0, 1.0]]);
            for j in 0..n {
                for i in 0..n {
                    let at = frame.to_patch(Dyadic::new(2 * i64::from(i) + 1, 2 * i64::from(j) + 1, 2 * i64::from(n)));
                    let [x, ds, dt] = table.apply(Grid::Dual, index[&at], &points);
                    let k = (j * n + i) as usize;
                    let want_n = normal(ju[0] * ds + ju[1] * dt, jv[0] * ds + jv[1] * dt);
                    worst = worst.max((x - ps[k]).length()).max((want_n - ns[k]).length());
                    // The pointwise polynomial, for the points outside blocks, agrees too.
                    let (u, v) = (f64::from(2 * i + 1) / f64::from(2 * n), f64::from(2 * j + 1) / f64::from(2 * n));
                    let (p, du, dv) = bicubic(&cv, cage, u, v);
                    worst = worst.max((p - x).length()).max((normal(du, dv) - want_n).length());
                }
            }
        }
    }
    // The torus is about 3 across.
    assert!(worst < 1e-12, "block route off the table route by {worst:e}");
}

/// Loop on a regular triangle torus: every face is a patch on level 0, so every centroid
/// reads the shared dual-grid table, and the other points (interior primal points, vertex
/// limit points) have their own exact stencils.
#[test]
fn level_zero_patches_read_dual_tables() {
    let mesh = Mesh::build(shapes::triangle_torus(6, 4)).unwrap();
    let mut ev = Evaluator::new(Builtin::Loop.scheme(), &mesh).unwrap();
    let domains = ev.domains().to_vec();
    let mut topo = Topology::default();
    let faces = mesh.face_count();
    super::super::topology::Builder::new(&mesh, true, false).build(&domains, &vec![4; faces], None, &mut topo);
    ev.prepare(&topo, &vec![4; faces], true).unwrap();
    let tabled = ev.records.iter().filter(|r| r.table != NO_TABLE).count();
    assert_eq!(tabled, faces * 16);
    assert_eq!(ev.records.len(), topo.point_count() as usize);
    // One table: one patch type, one rate.
    assert_eq!(ev.tables.tables.len(), 1);
}

/// Refined regular patches evaluated separably ([`PatchGrid`]) give what their points'
/// own stencil records give, and many general-route points of the cube, the default
/// model and a prism take that route at these rates.
#[test]
fn patch_grids_equal_the_records() {
    for (soup, rate) in [(shapes::cube(), 12u32), (shapes::default_model(), 8), (shapes::ngon_prism(5), 9)] {
        let mesh = Mesh::build(soup).unwrap();
        let mut ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
        // Every face on its own records (typed faces read templates instead).
        ev.typed_faces = false;
        let moved: Vec<DVec3> =
            mesh.positions().iter().enumerate().map(|(i, p)| *p * 1.3 + DVec3::splat((i as f64).sin())).collect();
        ev.set_cage(&moved);
        let domains = ev.domains().to_vec();
        let mut topo = Topology::default();
        let rates = vec![rate; mesh.face_count()];
        super::super::topology::Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut topo);
        ev.plan_blocks(&topo);
        ev.prepare_records(&topo, &rates, true).unwrap();
        let routes = ev.routes.clone();
        ev.patch_grids(&topo);
        let gridded = ev.routes.iter().filter(|k| k.get() == Route::PatchGrid).count();
        assert!(4 * gridded > ev.records.len(), "{gridded} of {} in patch grids", ev.records.len());
        let (mut ps, mut ns) = (Vec::new(), Vec::new());
        ev.evaluate(&topo, true, &mut ps, &mut ns);
        let mut worst: f64 = 0.0;
        for (v, &route) in ev.routes.iter().enumerate() {
            if let (Route::PatchGrid, Route::Record(r)) = (route.get(), routes[v].get()) {
                let (p, du, dv) = ev.general(&ev.records[r as usize]);
                worst = worst.max((p - ps[v]).length()).max((normal(du, dv) - ns[v]).length());
            }
        }
        assert!(worst < 1e-12, "patch grids off the records by {worst:e}");
    }
}

/// Faces that read their type's template ([`Evaluator::plan_copies`]) evaluate to the same
/// bits as with templates of their own, at even and odd, equal and mixed rates, on meshes
/// with extraordinary vertices (on the cube faces share templates), N-gons and borders,
/// with templates made in the same call or kept from earlier calls at other rates; the
/// plans agree too, and both agree with every face on its own records (the templates are
/// those records composed down to the cage).
#[test]
fn copied_faces_equal_their_own_descent() {
    let meshes = [
        shapes::cube(),
        shapes::pole(5),
        shapes::pole(6),
        shapes::ngon_prism(5),
        shapes::default_model(),
        shapes::quad_grid(3, 2),
    ];
    for (m, soup) in meshes.into_iter().enumerate() {
        let first = m == 0;
        let mesh = Mesh::build(soup).unwrap();
        let nf = mesh.face_count();
        let moved: Vec<DVec3> =
            mesh.positions().iter().enumerate().map(|(i, p)| *p * 0.7 + DVec3::splat((i as f64).cos())).collect();
        let uniform = |n: u32| vec![n; nf];
        let new = |copy: bool| {
            let mut ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
            ev.copy_faces = copy;
            ev.typed_faces = true;
            ev.set_cage(&moved);
            ev
        };
        // Kept across the rate sets below, with its templates.
        let mut kept = new(true);
        for rates in [
            uniform(1),
            uniform(2),
            uniform(5),
            uniform(8),
            (0..nf as u32).map(|f| 2 + f % 3).collect(),
            uniform(12),
            uniform(5),
            (0..nf as u32).map(|f| 3 + f % 4).collect(),
        ] {
            let domains = kept.domains().to_vec();
            let mut topo = Topology::default();
            super::super::topology::Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut topo);
            let run = |ev: &mut Evaluator| {
                ev.prepare(&topo, &rates, true).unwrap();
                let (mut ps, mut ns) = (Vec::new(), Vec::new());
                ev.evaluate(&topo, true, &mut ps, &mut ns);
                let bits = |v: &[DVec3]| v.iter().flat_map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>();
                let (mut plan, mut normals) = (Vec::new(), Vec::new());
                ev.plan(&topo).evaluate(&ev.positions[0], &mut plan, &mut normals);
                (bits(&ps), bits(&ns), plan)
            };
            let own = run(&mut new(false));
            for (k, copied) in [run(&mut new(true)), run(&mut kept), run(&mut kept)].into_iter().enumerate() {
                assert!(own.0 == copied.0 && own.1 == copied.1, "rates {rates:?}, run {k}");
                let worst = worst_plan(&own.2, &copied.2);
                assert!(worst < 1e-12, "plans off by {worst:e}");
            }
            // The templates (records composed to the cage) agree with the records.
            let mut records = new(true);
            records.typed_faces = false;
            let records = run(&mut records);
            let unbits = |v: &[u64]| v.iter().map(|&b| f64::from_bits(b)).collect::<Vec<_>>();
            for (a, b) in [(&own.0, &records.0), (&own.1, &records.1)] {
                let worst = unbits(a).iter().zip(unbits(b)).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                assert!(worst < 1e-12, "rates {rates:?}: templates off the records by {worst:e}");
            }
            assert!(worst_plan(&own.2, &records.2) < 1e-12);
            if first && rates == uniform(8) {
                let uses = &kept.block_templates;
                assert!(
                    uses.iter().any(|t| matches!(t, TemplateUse::Copied(_))),
                    "some of the cube's faces copy others"
                );
                assert!(uses.iter().all(|t| t.template().is_some()), "the cube's faces are typed");
            }
        }
        assert!(!first || !kept.templates.is_empty(), "the cube's faces have templates");
    }
}

/// The largest distance between two lists of points.
fn worst_plan(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (*x - *y).length()).fold(0.0, f64::max)
}

/// The cage refined by the patch levels' stencils (what `update_cage` uses) lands on the
/// patch levels' meshes, vertex for vertex: the stencil records index those vertices.
#[test]
fn refined_cage_matches_the_patch_levels() {
    for soup in [shapes::cube(), shapes::ngon_prism(5), shapes::default_model()] {
        let mesh = Mesh::build(soup).unwrap();
        let ev = Evaluator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
        assert!(ev.levels.level_count() > 1);
        for level in 0..ev.levels.level_count() {
            let want = ev.levels.mesh(level).positions();
            assert_eq!(ev.positions[level].len(), want.len());
            let worst = ev.positions[level].iter().zip(want).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
            assert!(worst < 1e-12, "level {level}: {worst:e}");
        }
    }
}

/// The typed faces' support, found level by level, is the set of cage points their cage rows
/// name (found path by path), on faces resolved on levels 1 and 2 (typed faces are on the
/// general route, which level-0 patches of these meshes are not): a torus, an open grid, a
/// pole of valence 7 with its open rim, a creased cube.
#[test]
fn cage_support_is_what_the_cage_rows_name() {
    let bits = |rows: &[(u32, f64)]| rows.iter().map(|&(x, w)| (x, w.to_bits())).collect::<Vec<_>>();
    let mut creased = Mesh::build(shapes::cube()).unwrap();
    let edge = creased.edges().next().unwrap();
    creased.set_edge_sharpness(edge, 2.5);
    let meshes = [
        Mesh::build(shapes::quad_torus(4, 3)).unwrap(),
        Mesh::build(shapes::quad_grid(3, 2)).unwrap(),
        Mesh::build(shapes::pole(7)).unwrap(),
        creased,
    ];
    let (mut signature, mut patches, mut support) = (Vec::new(), Vec::new(), Vec::new());
    let (mut rows, mut starts) = (Vec::new(), Vec::new());
    let mut levels_seen = [0usize; MAX_TYPED_LEVEL + 1];
    let (mut shared_rows, mut shared_starts) = (Vec::new(), Vec::new());
    for mesh in &meshes {
        let ev = Evaluator::new(Builtin::CatmullClark.scheme(), mesh).unwrap();
        // One memo for the mesh's faces gives the bits of a fresh one per face.
        let mut memo = CageRowMemo::default();
        for f in mesh.face_ids() {
            signature.clear();
            patches.clear();
            if !ev.face_type(0, f, &mut signature, &mut patches) {
                continue;
            }
            ev.cage_rows(&patches, &mut rows, &mut starts, &mut CageRowMemo::default());
            ev.cage_rows(&patches, &mut shared_rows, &mut shared_starts, &mut memo);
            assert_eq!((&shared_starts, bits(&shared_rows)), (&starts, bits(&rows)), "{f}");
            let mut named: Vec<u32> = rows.iter().map(|&(x, _)| x).collect();
            named.sort_unstable();
            named.dedup();
            assert_eq!(ev.cage_support(&patches, &mut support), named.len(), "{f}");
            assert_eq!(support[0], named, "{f}");
            levels_seen[patches.iter().map(|p| p.patch.0 as usize).max().unwrap()] += 1;
        }
    }
    assert!(levels_seen[1] > 0 && levels_seen[2] > 0, "faces resolved on levels 1 and 2: {levels_seen:?}");
}

/// A streamed tessellation routes each typed face as one call would, past the template budget
/// too: the budget is the call's, decided over all its blocks before the chunks (a chunk's own
/// budget would let a chunk of rate-3 faces take templates that the whole call has no room
/// for, and their points would differ in the last bits).
#[test]
fn chunks_share_the_calls_template_budget() {
    use crate::{DualOptions, DualTessellator, FlatMesh};
    let mesh = Mesh::build(shapes::cube()).unwrap();
    let options = DualOptions::DEFAULT.with_chunk(1);
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &options).unwrap();
    let ty = tess.evaluator.face_types.get(0).expect("the cube's faces are typed");
    // Room for the first face's template at rate 5, none for the others' at rate 3.
    tess.evaluator.template_budget = template_size(5, ty.cage.1 - ty.cage.0);
    let rates = [5, 3, 3, 3, 3, 3];
    let (mut whole, mut streamed) = (FlatMesh::default(), FlatMesh::default());
    tess.tessellate_flat(&rates, &mut whole).unwrap();
    tess.tessellate_stream(&rates, &mut streamed).unwrap();
    assert!(whole == streamed, "the chunks routed a face otherwise than the call");
}
