//! Stencil tables: every grid point equals the direct stencil (mirrored points included), the
//! binary format round-trips and rejects what it must, the cache is shared between threads, and
//! the committed default tables load and agree with the direct stencils.

use std::sync::Arc;

use subdiv_mesh::BoundaryInterpolation;
use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
use subdiv_stencil::{
    DEFAULT_TABLES, Dyadic, Grid, StencilCache, StencilError, StencilTable, StencilTables, SurfaceStencil,
    TABLE_VERSION, surface_stencil,
};

const EDGE_ONLY: BoundaryInterpolation = BoundaryInterpolation::EdgeOnly;

fn assert_close(a: &SurfaceStencil, b: &SurfaceStencil, what: &str) {
    assert_eq!(a.exact_derivatives, b.exact_derivatives, "{what}");
    for (x, y) in [(&a.position, &b.position), (&a.du, &b.du), (&a.dv, &b.dv)] {
        let worst = x.iter().zip(y).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-12, "{what}: differs by {worst:e}");
    }
}

#[test]
fn every_grid_point_equals_the_direct_stencil() {
    let cases = [
        (Builtin::CatmullClark, PatchType::interior(5), true),
        (Builtin::CatmullClark, PatchType::interior(4), true),
        (Builtin::CatmullClark, PatchType::boundary(3, 0), false),
        (Builtin::Loop, PatchType::interior(7), true),
        (Builtin::Loop, PatchType::interior(3), true),
        (Builtin::Loop, PatchType::boundary(2, 1), false),
    ];
    for (builtin, patch_type, symmetric) in cases {
        let scheme = builtin.scheme();
        let matrices = PatchMatrices::of(scheme, patch_type, EDGE_ONLY).unwrap();
        assert_eq!(matrices.shapes[0].mirror.is_some(), symmetric, "{builtin} {patch_type:?}");
        let points: Vec<_> = (0..matrices.shapes[0].size)
            .map(|k| subdiv_mesh::DVec3::new(k as f64, (k * k) as f64 / 7.0, (k % 3) as f64))
            .collect();
        for table in StencilTable::compute_rates(&matrices, EDGE_ONLY, 1..=6).unwrap() {
            let mut stored = 0;
            for grid in Grid::ALL {
                stored += table.len(grid);
                for i in 0..table.len(grid) {
                    let point = table.point(grid, i);
                    let direct = surface_stencil(&matrices, 0, point).unwrap();
                    let what = format!("{builtin} {patch_type:?} rate {} {grid:?} {point:?}", table.rate());
                    if symmetric && point.u < point.v {
                        // Read through the mirror: the mirror image's stencil, permuted.
                        assert_close(&table.stencil(grid, i), &direct, &what);
                    } else {
                        // The evaluator's results do not depend on the order of the points.
                        assert_eq!(table.stencil(grid, i), direct, "{what}");
                    }
                    // `apply` is the stencil applied, mirrored points included.
                    let [p, du, dv] = table.apply(grid, i, &points);
                    let dot = |w: &[f64]| w.iter().zip(&points).map(|(w, x)| *x * *w).sum::<subdiv_mesh::DVec3>();
                    for (got, want) in [(p, dot(&direct.position)), (du, dot(&direct.du)), (dv, dot(&direct.dv))] {
                        assert!((got - want).length() < 1e-10, "{what}: apply {got} vs {want}");
                    }
                }
            }
            // The symmetric ones keep a little over half the points.
            assert_eq!(table.stored_points() < stored, symmetric);
        }
    }
}

#[test]
fn grids_hold_the_points_a_tessellator_needs() {
    for n in 1..=9_u32 {
        let n64 = i64::from(n);
        assert_eq!(Grid::Primal.points(4, n).len() as u32, (n + 1) * (n + 1));
        assert_eq!(Grid::Dual.points(4, n).len() as u32, n * n);
        assert_eq!(Grid::Primal.points(3, n).len() as u32, (n + 1) * (n + 2) / 2);
        assert_eq!(Grid::Dual.points(3, n).len() as u32, n * n);
        // Triangle dual points are the centroids of the sub-triangles: inside the face, none on
        // a side, none twice.
        let dual = Grid::Dual.points(3, n);
        assert!(dual.iter().all(|p| p.denominator == 3 * n64 && p.u > 0 && p.v > 0 && p.u + p.v < 3 * n64));
        let mut seen = dual.clone();
        seen.sort_by_key(|p| (p.u, p.v));
        seen.dedup();
        assert_eq!(seen.len(), dual.len());
    }
    assert_eq!(Grid::Primal.points(4, 2)[5], Dyadic::new(2, 1, 2));
}

fn small_tables() -> StencilTables {
    let types = [PatchType::interior(5), PatchType::boundary(2, 0)];
    StencilTables::compute(Builtin::CatmullClark.scheme(), &types, EDGE_ONLY, 1..=3).unwrap()
}

#[test]
fn the_format_round_trips_and_is_deterministic() {
    let tables = small_tables();
    let bytes = tables.to_bytes();
    assert_eq!(&bytes[..8], b"SUBDIVST");
    assert_eq!(small_tables().to_bytes(), bytes, "the same tables, byte for byte");
    let read = StencilTables::from_bytes(&bytes, Builtin::CatmullClark.scheme()).unwrap();
    assert_eq!(read, tables);
    assert!(read.get(PatchType::interior(5), EDGE_ONLY, 2).is_some());
    assert!(read.get(PatchType::interior(5), EDGE_ONLY, 4).is_none());
}

#[test]
fn the_loader_rejects_foreign_stale_and_corrupt_files() {
    let cc = Builtin::CatmullClark.scheme();
    let bytes = small_tables().to_bytes();

    let foreign = b"# an OBJ file\nv 0 0 0\n".to_vec();
    assert_eq!(StencilTables::from_bytes(&foreign, cc), Err(StencilError::TableForeign));

    let mut other_version = bytes.clone();
    other_version[8..12].copy_from_slice(&(TABLE_VERSION + 1).to_le_bytes());
    let error = StencilTables::from_bytes(&other_version, cc).unwrap_err();
    assert_eq!(error, StencilError::TableVersion { found: TABLE_VERSION + 1, expected: TABLE_VERSION });
    assert!(error.to_string().contains("cargo xtask tables"), "{error}");

    // Another scheme's tables, or a scheme whose rules changed under the same name.
    let error = StencilTables::from_bytes(&bytes, Builtin::Loop.scheme()).unwrap_err();
    assert!(error.to_string().contains("for scheme `catmull-clark`, not `loop`"), "{error}");
    let mut edited = cc.clone();
    edited.name = "catmull-clark".into();
    let sw = Builtin::SwQuad.scheme();
    edited.rules = sw.rules.clone();
    let error = StencilTables::from_bytes(&bytes, &edited).unwrap_err();
    assert!(matches!(error, StencilError::TableStale { .. }) && error.to_string().contains("regenerate"), "{error}");

    // A flipped bit in the weights, and a truncated file.
    let mut damaged = bytes.clone();
    let middle = bytes.len() / 2;
    damaged[middle] ^= 0x10;
    let error = StencilTables::from_bytes(&damaged, cc).unwrap_err();
    assert!(error.to_string().contains("checksum"), "{error}");
    let error = StencilTables::from_bytes(&bytes[..middle], cc).unwrap_err();
    assert!(matches!(error, StencilError::TableCorrupt { .. }), "{error}");
    assert!(StencilTables::from_bytes(&bytes[..10], cc).is_err());
}

#[test]
fn the_cache_computes_once_and_is_shared_between_threads() {
    let cache = StencilCache::new(Builtin::Loop.scheme(), EDGE_ONLY);
    let t = PatchType::interior(5);
    let tables: Vec<Arc<StencilTable>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..4).map(|_| scope.spawn(|| cache.table(t, 7).unwrap())).collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert!(tables.iter().all(|x| Arc::ptr_eq(x, &cache.table(t, 7).unwrap())));
    assert!(matches!(cache.table(t, 0), Err(StencilError::Rate { rate: 0, .. })));
    // Seeded tables are used as they are; another scheme's are refused.
    let seeded = StencilCache::new(Builtin::CatmullClark.scheme(), EDGE_ONLY).with_tables(small_tables()).unwrap();
    assert_eq!(seeded.table(PatchType::interior(5), 3).unwrap().rate(), 3);
    assert!(StencilCache::new(Builtin::Loop.scheme(), EDGE_ONLY).with_tables(small_tables()).is_err());
}

/// The committed tables load, hold what `DEFAULT_TABLES` says, and agree with the direct
/// stencils (`cargo xtask tables --check` compares all of them with a regeneration).
#[test]
fn the_committed_default_tables_load_and_agree() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tables");
    for spec in DEFAULT_TABLES {
        let scheme = spec.scheme.scheme();
        let bytes = std::fs::read(dir.join(spec.file)).unwrap();
        let tables = StencilTables::from_bytes(&bytes, scheme).unwrap();
        assert_eq!(tables.tables().len(), spec.valences.clone().count() * spec.rates.clone().count());
        for patch_type in spec.patch_types() {
            let matrices = PatchMatrices::of(scheme, patch_type, EDGE_ONLY).unwrap();
            for rate in [1, 7, 24] {
                let table = tables.get(patch_type, EDGE_ONLY, rate).unwrap();
                for grid in Grid::ALL {
                    // A few points of each grid, mirrored ones among them.
                    for i in (0..table.len(grid)).step_by(table.len(grid) / 5 + 1) {
                        let direct = surface_stencil(&matrices, 0, table.point(grid, i)).unwrap();
                        assert_close(&table.stencil(grid, i), &direct, &format!("{} {patch_type:?} {rate}", spec.file));
                    }
                }
            }
        }
    }
}
