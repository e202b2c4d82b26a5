//! `cargo xtask bench schemes [--quads M] [--triangles M] [--grid N] [--rate R]`: every built-in
//! surface scheme on one mesh, one thread, in one process: exact evaluation (`EvalMethod::Stencil`,
//! a new evaluator per round, so its preparation is counted: what `subdiv eval --method stencil`
//! meets) in points per second, and the dual tessellation at a uniform rate (a new `Surface` per
//! round) in triangles per second. Quad schemes take `--quads`
//! (default: the built-in model, closed, all quads — Kobbelt takes nothing else — with
//! valences 3 and 5), triangle schemes `--triangles` (default: spot triangulated, valences 3 to
//! 8). Medians of [`ROUNDS`]. A scheme that refuses the mesh is reported with its reason.

use std::path::PathBuf;
use std::time::Instant;

use subdiv::schemes::{Builtin, Split};
use subdiv::{EvalMethod, EvalOptions, Parallelism, Rates, Surface, TessOptions};

use crate::bench_args::median;

/// Rounds per scheme.
const ROUNDS: usize = 5;

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    let usage = "usage: cargo xtask bench schemes [--quads M] [--triangles M] [--grid N] [--rate R]";
    let meshes = crate::shared_dir().join("testdata/meshes");
    let (mut quads, mut triangles) = (None, meshes.join("keenan/spot_triangulated.obj"));
    let (mut grid, mut rate) = (8u32, 16u32);
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        let mut value = || rest.next().ok_or_else(|| format!("{a} needs a value; {usage}"));
        match a.as_str() {
            "--quads" => quads = Some(PathBuf::from(value()?)),
            "--triangles" => triangles = PathBuf::from(value()?),
            "--grid" => grid = value()?.parse().map_err(|e| format!("--grid: {e}"))?,
            "--rate" => rate = value()?.parse().map_err(|e| format!("--rate: {e}"))?,
            other => return Err(format!("unknown option {other:?}; {usage}")),
        }
    }
    let work = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let quads = match quads {
        Some(path) => path,
        None => {
            let path = work.path().join("built-in.obj");
            subdiv::io::write_obj(&path, &subdiv::mesh::shapes::default_model()).map_err(|e| e.to_string())?;
            path
        }
    };
    // One thread, whatever the options inside say.
    rayon::ThreadPoolBuilder::new().num_threads(1).build_global().map_err(|e| e.to_string())?;
    for builtin in Builtin::ALL {
        let scheme = builtin.scheme();
        let path = if matches!(scheme.split(), Split::Triangle | Split::Sqrt3) { &triangles } else { &quads };
        let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        let soup = subdiv::io::load(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let line = format!("bench=schemes scheme={} mesh={name} threads=1 rounds={ROUNDS}", scheme.name);
        let mut eval = (Vec::new(), 0usize);
        let mut tess = (Vec::new(), 0usize);
        let outcome = (|| -> Result<(), subdiv::Error> {
            for _ in 0..ROUNDS {
                let surface = Surface::build(soup.clone(), scheme)?;
                let start = Instant::now();
                let options = EvalOptions::DEFAULT.with_method(EvalMethod::Stencil);
                let points = surface.evaluator(&options)?.grid(grid)?.points.len();
                eval.0.push(start.elapsed().as_secs_f64());
                eval.1 = points;

                let mut surface = Surface::build(soup.clone(), scheme)?;
                let start = Instant::now();
                let options =
                    TessOptions::DEFAULT.with_rates(Rates::Uniform(rate)).with_parallelism(Parallelism::Serial);
                let triangles = surface.tessellate(&options)?.mesh.triangles.len();
                tess.0.push(start.elapsed().as_secs_f64());
                tess.1 = triangles;
            }
            Ok(())
        })();
        match outcome {
            Ok(()) => {
                let (e, t) = (median(&eval.0), median(&tess.0));
                println!(
                    "{line} grid={grid} points={} eval_s={e:.4} points_per_s={:.0} rate={rate} triangles={} tess_s={t:.4} \
                     triangles_per_s={:.0}",
                    eval.1,
                    eval.1 as f64 / e,
                    tess.1,
                    tess.1 as f64 / t
                );
            }
            Err(e) => println!("{line} refused=\"{}\"", e.to_string().replace('"', "'")),
        }
    }
    Ok(())
}
