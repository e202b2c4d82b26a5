//! `cargo xtask tables [--check]`: the committed tables — sub-patch matrices
//! ([`subdiv::schemes::DEFAULT_PATCH_TABLES`], in `crates/subdiv-schemes/tables`), the
//! eigenbases of their interior types (`crates/subdiv-eval/tables`) and the default stencil
//! tables.
//!
//! They are [`subdiv::stencil::DEFAULT_TABLES`]: Catmull-Clark and Loop, interior valences 3 to
//! 8, rates 1 to 24 (paper 000 §6 ships the same range), in
//! `crates/subdiv-stencil/tables/<scheme>.stencils`. Without `--check` the files are written
//! (atomically) where the committed ones are stale (beyond the last bits, see
//! [`PLATFORM_TOLERANCE`]); with it they are regenerated in memory and compared with the
//! committed ones.

use std::path::{Path, PathBuf};
use std::time::Instant;

use subdiv::eval::{EigenTables, eigen_table_file};
use subdiv::schemes::{DEFAULT_PATCH_TABLES, PatchTables, Scheme};
use subdiv::stencil::{DEFAULT_TABLES, Grid, StencilTables};

/// Weights may differ by this much between machines whose floating point rounds the eigen
/// solver's last bits differently (another SIMD path in faer); anything more is stale.
const PLATFORM_TOLERANCE: f64 = 1e-13;

pub(crate) fn run(check: bool) -> Result<(), String> {
    let mut stale = patch_tables(check)?;
    stale.extend(eigen_tables(check)?);
    let dir = crate::root().join("crates/subdiv-stencil/tables");
    for spec in DEFAULT_TABLES {
        let scheme = spec.scheme.scheme();
        let start = Instant::now();
        let tables = spec.compute().map_err(|e| format!("{}: {e}", spec.scheme))?;
        let seconds = start.elapsed().as_secs_f64();
        let bytes = tables.to_bytes();
        let path = dir.join(spec.file);
        let stored: usize = tables.tables().iter().map(|t| t.stored_points()).sum();
        println!(
            "tables scheme={} types={} rates={}..={} tables={} stored_points={} bytes={} seconds={seconds:.2}",
            spec.scheme,
            spec.valences.clone().count(),
            spec.rates.start(),
            spec.rates.end(),
            tables.tables().len(),
            stored,
            bytes.len(),
        );
        // Written only when stale: a file equal but for the last bits stays as it is.
        match compare(&path, &bytes, &tables, scheme) {
            Some(problem) if check => stale.push(format!("{}: {problem}", path.display())),
            Some(_) => write_atomically(&path, &bytes)?,
            None => {}
        }
    }
    if stale.is_empty() {
        Ok(())
    } else {
        Err(format!("stale tables (run `cargo xtask tables`):\n{}", stale.join("\n")))
    }
}

/// Why the committed file differs from the regenerated tables, if it does beyond the last bits.
fn compare(path: &PathBuf, bytes: &[u8], fresh: &StencilTables, scheme: &subdiv::schemes::Scheme) -> Option<String> {
    let committed = match std::fs::read(path) {
        Ok(committed) => committed,
        Err(e) => return Some(format!("cannot read it: {e}")),
    };
    if committed == bytes {
        println!("tables file={} identical", path.display());
        return None;
    }
    let old = match StencilTables::from_bytes(&committed, scheme) {
        Ok(old) => old,
        Err(e) => return Some(e.to_string()),
    };
    if old.tables().len() != fresh.tables().len() {
        return Some(format!("{} tables committed, {} generated", old.tables().len(), fresh.tables().len()));
    }
    let mut worst = 0.0_f64;
    for (a, b) in old.tables().iter().zip(fresh.tables()) {
        let same_layout = (a.patch_type(), a.boundary(), a.rate(), a.control_points(), a.stored_points())
            == (b.patch_type(), b.boundary(), b.rate(), b.control_points(), b.stored_points());
        if !same_layout {
            return Some(format!("the layout of {:?} at rate {} differs", b.patch_type(), b.rate()));
        }
        for grid in Grid::ALL {
            for i in 0..a.len(grid) {
                let (x, y) = (a.stencil(grid, i), b.stencil(grid, i));
                if x.exact_derivatives != y.exact_derivatives {
                    return Some(format!("{:?} at rate {}: {grid:?} point {i} differs", b.patch_type(), b.rate()));
                }
                for (p, q) in [(&x.position, &y.position), (&x.du, &y.du), (&x.dv, &y.dv)] {
                    worst = p.iter().zip(q).map(|(p, q)| (p - q).abs()).fold(worst, f64::max);
                }
            }
        }
    }
    if worst > PLATFORM_TOLERANCE {
        return Some(format!("weights differ by up to {worst:e}"));
    }
    println!(
        "tables file={} equal to {PLATFORM_TOLERANCE:e} (largest difference {worst:e}; the bytes differ in the last bits, \
         as this machine's floating point rounds differently from the one that wrote them)",
        path.display()
    );
    None
}

/// The sub-patch matrix tables: written, or checked (the stale ones' reasons returned).
fn patch_tables(check: bool) -> Result<Vec<String>, String> {
    let dir = crate::root().join("crates/subdiv-schemes/tables");
    let mut stale = Vec::new();
    for spec in DEFAULT_PATCH_TABLES {
        let start = Instant::now();
        let tables = spec.compute().map_err(|e| format!("{}: {e}", spec.scheme.name()))?;
        let bytes = tables.to_bytes();
        let path = dir.join(spec.file);
        println!(
            "patch_tables scheme={} entries={} bytes={} seconds={:.2}",
            spec.scheme.name(),
            tables.entries().len(),
            bytes.len(),
            start.elapsed().as_secs_f64()
        );
        // What the build embeds is what is committed (the file at build time); written only
        // when stale.
        let problem = match std::fs::read(&path) {
            Err(e) => Some(format!("cannot read it: {e}")),
            Ok(committed) if committed == bytes => {
                println!("patch_tables file={} identical", path.display());
                None
            }
            Ok(committed) => compare_patches(&committed, &tables, spec.scheme.scheme(), &path),
        };
        match problem {
            Some(problem) if check => stale.push(format!("{}: {problem}", path.display())),
            Some(_) => write_atomically(&path, &bytes)?,
            None => {}
        }
    }
    Ok(stale)
}

/// The eigenbasis tables (over freshly derived matrices): written, or checked.
fn eigen_tables(check: bool) -> Result<Vec<String>, String> {
    let dir = crate::root().join("crates/subdiv-eval/tables");
    let mut stale = Vec::new();
    for spec in DEFAULT_PATCH_TABLES {
        let start = Instant::now();
        let tables = EigenTables::compute(&spec).map_err(|e| format!("{}: {e}", spec.scheme.name()))?;
        let bytes = tables.to_bytes();
        let path = dir.join(eigen_table_file(&spec));
        println!(
            "eigen_tables scheme={} entries={} bytes={} seconds={:.2}",
            spec.scheme.name(),
            tables.len(),
            bytes.len(),
            start.elapsed().as_secs_f64()
        );
        let problem = match std::fs::read(&path) {
            Err(e) => Some(format!("cannot read it: {e}")),
            Ok(committed) if committed == bytes => {
                println!("eigen_tables file={} identical", path.display());
                None
            }
            Ok(committed) => match EigenTables::from_bytes(&committed, &spec).map_err(|e| e.to_string()) {
                Ok(old) => match old.max_difference(&tables) {
                    Ok(worst) if worst <= EIGEN_TOLERANCE => {
                        println!(
                            "eigen_tables file={} equal to {EIGEN_TOLERANCE:e} (largest difference {worst:e})",
                            path.display()
                        );
                        None
                    }
                    Ok(worst) => Some(format!("numbers differ by up to {worst:e}")),
                    Err(e) => Some(e),
                },
                Err(e) => Some(e),
            },
        };
        match problem {
            Some(problem) if check => stale.push(format!("{}: {problem}", path.display())),
            Some(_) => write_atomically(&path, &bytes)?,
            None => {}
        }
    }
    Ok(stale)
}

/// Eigenvectors and the spectrum's diagnostics come from faer's eigen solver, whose rounding
/// follows the machine's SIMD paths more than the stencils' sums do; a stale table differs by
/// far more (any change to a rule moves them by its own size).
const EIGEN_TOLERANCE: f64 = 1e-10;

/// Why committed patch tables differ from fresh ones beyond the last bits, if they do.
fn compare_patches(committed: &[u8], fresh: &PatchTables, scheme: &Scheme, path: &Path) -> Option<String> {
    let old = match PatchTables::from_bytes(committed, scheme) {
        Ok(old) => old,
        Err(e) => return Some(e.to_string()),
    };
    if old.entries().len() != fresh.entries().len() {
        return Some(format!("{} entries committed, {} derived", old.entries().len(), fresh.entries().len()));
    }
    let mut worst = 0.0_f64;
    let mut widen = |a: &[f64], b: &[f64]| a.iter().zip(b).for_each(|(x, y)| worst = worst.max((x - y).abs()));
    for ((rule_a, a), (rule_b, b)) in old.entries().iter().zip(fresh.entries()) {
        let what = format!("{:?} ({rule_b:?})", b.patch_type);
        let same_layout = (rule_a, a.patch_type, a.radius, a.face_size, a.shapes.len())
            == (rule_b, b.patch_type, b.radius, b.face_size, b.shapes.len());
        if !same_layout {
            return Some(format!("{what}: the layout differs"));
        }
        for (x, y) in a.shapes.iter().zip(&b.shapes) {
            let same_shape = (x.size, &x.signature, &x.influence, &x.mirror, x.children.len())
                == (y.size, &y.signature, &y.influence, &y.mirror, y.children.len())
                && x.parameters.is_some() == y.parameters.is_some();
            if !same_shape {
                return Some(format!("{what}: a shape differs"));
            }
            for (c, d) in x.children.iter().zip(&y.children) {
                if (c.shape, c.domain, c.rows(), c.columns()) != (d.shape, d.domain, d.rows(), d.columns()) {
                    return Some(format!("{what}: a child differs"));
                }
                for r in 0..c.rows() {
                    widen(&c.dense_row(r), &d.dense_row(r));
                }
            }
            if let (Some([u, v]), Some([p, q])) = (&x.parameters, &y.parameters) {
                widen(u, p);
                widen(v, q);
            }
        }
    }
    if worst > PLATFORM_TOLERANCE {
        return Some(format!("entries differ by up to {worst:e}"));
    }
    println!("patch_tables file={} equal to {PLATFORM_TOLERANCE:e} (largest difference {worst:e})", path.display());
    None
}

fn write_atomically(path: &PathBuf, bytes: &[u8]) -> Result<(), String> {
    subdiv::io::write_atomic(path, |w| w.write_all(bytes)).map_err(|e| e.to_string())?;
    println!("tables wrote={}", path.display());
    Ok(())
}
