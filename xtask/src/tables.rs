//! `cargo xtask tables [--check]`: the committed default stencil tables.
//!
//! They are [`subdiv::stencil::DEFAULT_TABLES`]: Catmull-Clark and Loop, interior valences 3 to
//! 8, rates 1 to 24 (paper 000 §6 ships the same range), in
//! `crates/subdiv-stencil/tables/<scheme>.stencils`. Without `--check` the files are written
//! (atomically); with it they are regenerated in memory and compared with the committed ones.

use std::path::PathBuf;
use std::time::Instant;

use subdiv::stencil::{DEFAULT_TABLES, Grid, StencilTables};

/// Weights may differ by this much between machines whose floating point rounds the eigen
/// solver's last bits differently (another SIMD path in faer); anything more is stale.
const PLATFORM_TOLERANCE: f64 = 1e-13;

pub(crate) fn run(check: bool) -> Result<(), String> {
    let dir = crate::root().join("crates/subdiv-stencil/tables");
    let mut stale = Vec::new();
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
        if check {
            if let Some(problem) = compare(&path, &bytes, &tables, scheme) {
                stale.push(format!("{}: {problem}", path.display()));
            }
        } else {
            write_atomically(&path, &bytes)?;
        }
    }
    if stale.is_empty() {
        Ok(())
    } else {
        Err(format!("stale stencil tables (run `cargo xtask tables`):\n{}", stale.join("\n")))
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

fn write_atomically(path: &PathBuf, bytes: &[u8]) -> Result<(), String> {
    subdiv::io::write_atomic(path, |w| w.write_all(bytes)).map_err(|e| e.to_string())?;
    println!("tables wrote={}", path.display());
    Ok(())
}
