//! `cargo xtask rates`: rational against dyadic rates (paper 000 §6) — the triangles of the
//! cheapest dual-grid tessellation whose per-face rates provably meet `ε`
//! ([`ErrorRates`]), against the cheapest one whose rates are powers of two, on closed
//! Catmull-Clark meshes of the shared corpus.
//!
//! The bound is monotone in each face's rate, so the cheapest power-of-two rate of a face is the
//! next power of two at or above its cheapest rate; the table also gives the uniform versions
//! (every face at the largest of those rates).

use std::path::PathBuf;

use subdiv::io::load_mesh;
use subdiv::schemes::Builtin;
use subdiv::tess::rates::ErrorRates;
use subdiv::tess::{DualOptions, DualTessellator, Tessellator, Tolerance};

/// Relative tolerances (× the bounding-box diagonal).
const TOLERANCES: [f64; 3] = [3e-2, 1e-2, 3e-3];

pub(crate) fn run() -> Result<(), String> {
    if cfg!(debug_assertions) {
        return crate::cargo(&["run", "--release", "--quiet", "-p", "xtask", "--", "rates"]);
    }
    let cc = Builtin::CatmullClark.scheme();
    println!(
        "| model | faces | ε / bbox | rates (rational) | triangles (rational) | triangles (dyadic) | dyadic / rational | uniform rational n: triangles | uniform dyadic n: triangles | dyadic / rational (uniform) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    // The models of `cargo xtask adaptive`: closed Catmull-Clark cages without tags.
    for model in crate::adaptive::MODELS {
        let path: PathBuf =
            subdiv_testkit::shared_mesh(model).ok_or("the shared corpus is missing (set SUBDIV_SHARED)")?;
        let mesh = load_mesh(&path, &Default::default()).map_err(|e| format!("{model}: {e}"))?;
        let bounds = Tessellator::new(cc, &mesh).map_err(|e| format!("{model}: {e}"))?;
        let mut dual = DualTessellator::new(cc, &mesh, &DualOptions { quads: false, ..DualOptions::default() })
            .map_err(|e| format!("{model}: {e}"))?;
        let mut triangles = |rates: &[u32]| -> Result<usize, String> {
            Ok(dual.tessellate(rates).map_err(|e| format!("{model}: {e}"))?.triangles.len())
        };
        for r in TOLERANCES {
            let rational = match ErrorRates::new(Tolerance::Relative(r)).face_rates(&bounds, &mesh) {
                Ok(rates) => rates,
                Err(e) => {
                    println!("| {model} | {} | {r:e} | {e} | | | | | | |", mesh.face_count());
                    continue;
                }
            };
            let dyadic: Vec<u32> = rational.iter().map(|n| n.next_power_of_two()).collect();
            let (a, b) = (triangles(&rational)?, triangles(&dyadic)?);
            let top = *rational.iter().max().unwrap_or(&1);
            let (ua, ub) =
                (triangles(&vec![top; rational.len()])?, triangles(&vec![top.next_power_of_two(); rational.len()])?);
            let low = *rational.iter().min().unwrap_or(&1);
            println!(
                "| {model} | {} | {r:e} | {low}..={top} | {a} | {b} | {:.2} | {top}: {ua} | {}: {ub} | {:.2} |",
                mesh.face_count(),
                b as f64 / a as f64,
                top.next_power_of_two(),
                ub as f64 / ua as f64,
            );
        }
    }
    println!(
        "\nRational: each face at the least rate whose bound (subdiv_tess::rates::ErrorRates) is within ε; dyadic: \
         each at the next power of two. Uniform: every face at the largest rational rate, or its next power of two."
    );
    Ok(())
}
