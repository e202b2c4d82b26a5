//! `cargo xtask rates`: rational against dyadic rates (paper 000 §6) — the triangles of the
//! cheapest dual-grid tessellation whose per-face rates provably meet `ε`
//! ([`ErrorRates`]), against the cheapest one whose rates are powers of two, on closed
//! Catmull-Clark meshes of the shared corpus.
//!
//! Both come from the same bound ([`ErrorRates::rates_rounded`]: the least fixed point with
//! every rate rounded up to a power of two for the dyadic column).

use std::path::PathBuf;

use subdiv::io::load_mesh;
use subdiv::mesh::DVec3;
use subdiv::schemes::Builtin;
use subdiv::tess::check::MeshDistance;
use subdiv::tess::rates::{ErrorRates, RingDepths};
use subdiv::tess::{DualOptions, DualTessellator, QuadtreeTessellator, Tolerance};

/// Relative tolerances (× the bounding-box diagonal).
const TOLERANCES: [f64; 3] = [3e-2, 1e-2, 3e-3];

pub(crate) fn run() -> Result<(), String> {
    if cfg!(debug_assertions) {
        return crate::cargo(&["run", "--release", "--quiet", "-p", "xtask", "--", "rates"]);
    }
    let cc = Builtin::CatmullClark.scheme();
    println!(
        "| model | faces | ε / bbox | rational: rates, triangles, worst/ε | dyadic by the bound: rates, triangles | dyadic / rational | rational rounded up: triangles, worst/ε | rounded / rational |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    // The models of `cargo xtask adaptive`: closed Catmull-Clark cages without tags.
    for model in crate::adaptive::MODELS {
        let path: PathBuf =
            subdiv_testkit::shared_mesh(model).ok_or("the shared corpus is missing (set SUBDIV_SHARED)")?;
        let mesh = load_mesh(&path, &Default::default()).map_err(|e| format!("{model}: {e}"))?;
        let bounds = QuadtreeTessellator::new(cc, &mesh).map_err(|e| format!("{model}: {e}"))?;
        // Positions only: the rates and their triangles, not the texture seams (which cut the
        // polygons at extraordinary vertices, refused by the rates).
        let options = DualOptions { quads: false, channels: false, ..DualOptions::default() };
        let mut dual = DualTessellator::new(cc, &mesh, &options).map_err(|e| format!("{model}: {e}"))?;
        let samples: Vec<DVec3> =
            crate::adaptive::limit_grids(&mesh, 24)?.into_iter().flatten().map(|(.., p)| p).collect();
        for r in TOLERANCES {
            let epsilon = Tolerance::Relative(r).absolute(bounds.diagonal()).map_err(|e| e.to_string())?;
            let policy = ErrorRates::new(Tolerance::Relative(r));
            let (rational, rings) = match policy.rates(&bounds, &mesh) {
                Ok(rates) => (rates.faces, rates.rings),
                Err(e) => {
                    println!("| {model} | {} | {r:e} | {e} | | | | |", mesh.face_count());
                    continue;
                }
            };
            let span = |r: &[u32]| format!("{}..={}", r.iter().min().unwrap_or(&1), r.iter().max().unwrap_or(&1));
            let mut run = |rates: &[u32], rings: &RingDepths| -> Result<(usize, f64), String> {
                let out = dual.tessellate_with_rings(rates, rings).map_err(|e| format!("{model}: {e}"))?;
                let distance = MeshDistance::new(out, epsilon);
                let worst = samples.iter().map(|&p| distance.distance(out, p)).fold(0.0, f64::max);
                Ok((out.triangles.len(), worst / epsilon))
            };
            let (a, worst_a) = run(&rational, &rings)?;
            let dyadic = match policy.rates_rounded(&bounds, &mesh, u32::next_power_of_two) {
                Ok(d) => {
                    let (b, _) = run(&d.faces, &d.rings)?;
                    format!("{}, {b} | {:.2}", span(&d.faces), b as f64 / a as f64)
                }
                Err(e) => format!("{e} | "),
            };
            let rounded: Vec<u32> = rational.iter().map(|n| n.next_power_of_two()).collect();
            let (c, worst_c) = run(&rounded, &rings)?;
            println!(
                "| {model} | {} | {r:e} | {}, {a}, {worst_a:.3} | {dyadic} | {c}, {worst_c:.3} | {:.2} |",
                mesh.face_count(),
                span(&rational),
                c as f64 / a as f64,
            );
        }
    }
    println!(
        "\nRational: each face at the least rate whose bound (subdiv_tess::rates::ErrorRates::rates, rings around \
         extraordinary points) is within ε; dyadic by the bound: the least powers of two by the same bound \
         (rates_rounded: finer rates near an extraordinary vertex push its first ring deeper, where the parametric \
         bound grows, so the powers of two cascade); rounded up: each rational rate rounded up to a power of two, \
         the same rings, not proven by the bound but measured. worst/ε: the largest distance from the exact limit \
         surface (each face's 24 × 24 grid, eigenbasis evaluator) to the output triangles, over ε."
    );
    Ok(())
}
