//! `subdiv stencil`: exact limit stencils of a curve scheme on the grid (1/n)ℤ, or of a surface
//! scheme's patch at a rational (u, v).

use std::io::Write;
use std::path::PathBuf;

use serde_json::{Value, json};
use subdiv::mesh::BoundaryInterpolation;
use subdiv::schemes::{Builtin, CurveScheme, LocalCurveScheme, PatchMatrices, PatchType, Scheme};
use subdiv::stencil::curve::{LocalCurveGrid, basis_grid};
use subdiv::stencil::{Dyadic, Grid, Rational, StencilEvaluator, exact_surface_stencil};

use crate::UserError;
use crate::scheme_arg::SchemeFile;

/// Arguments of `subdiv stencil`.
#[derive(Debug, clap::Args)]
pub(crate) struct StencilArgs {
    /// A built-in curve scheme (cubic-bspline, chaikin, four-point, six-point, sw-curve,
    /// nonuniform-cubic-bspline: paper 000 §2's, uniform away from the origin, and
    /// nonuniform-cubic-bspline-matrix, the same as §3's matrix mask) or surface scheme
    /// (catmull-clark, loop, butterfly, kobbelt, sw-quad, bilinear, doo-sabin, midedge, sqrt3).
    #[arg(long, default_value = "catmull-clark")]
    scheme: String,
    /// A user-defined scheme: a curve scheme's TOML file (`arity`, `offset`, `mask`), or a
    /// surface scheme's TOML or RON file (`subdiv scheme NAME` prints a built-in's as a start).
    /// Overrides `--scheme`.
    #[arg(long, value_name = "FILE")]
    scheme_file: Option<PathBuf>,
    /// The grid rate: curves are sampled on (1/n)ℤ, surfaces at (i/n, j/n) when `--at` is not
    /// given.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1024))]
    n: u32,
    /// Valence of the surface patch's corner 0 (default: the scheme's regular valence); for
    /// doo-sabin and midedge, whose patches are centred on face corners, the sides of the face
    /// at corner 0.
    #[arg(long, value_parser = clap::value_parser!(u32).range(3..=64))]
    valence: Option<u32>,
    /// One point: `X` for a curve (on the grid), `U,V` for a surface; fractions such as `1/3`.
    #[arg(long, value_name = "U,V")]
    at: Option<String>,
    /// Print exact fractions instead of decimals (surfaces: schemes whose sub-patch matrices are
    /// rational, e.g. Catmull-Clark, sw-quad, Loop at valences 3, 4 and 6).
    #[arg(long)]
    exact: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: &StencilArgs, out: &mut impl Write) -> Result<(), UserError> {
    if let Some(path) = &args.scheme_file {
        return match crate::scheme_arg::read_any_scheme_file(path)? {
            SchemeFile::Surface(scheme) => run_surface(args, &scheme, out),
            SchemeFile::Curve(curve) => run_curve(args, &curve, out),
            SchemeFile::LocalCurve(local) => run_local(args, &local, out),
        };
    }
    if let Some(curve) = CurveScheme::builtin(&args.scheme) {
        return run_curve(args, &curve, out);
    }
    if let Some(local) = LocalCurveScheme::builtin(&args.scheme) {
        return run_local(args, &local, out);
    }
    let builtin = Builtin::from_name(&args.scheme).ok_or_else(|| {
        let mut known: Vec<&str> = CurveScheme::BUILTIN_NAMES.to_vec();
        known.extend(LocalCurveScheme::BUILTIN_NAMES);
        known.extend(Builtin::ALL.iter().map(|b| b.name()));
        UserError(format!("unknown scheme {:?}; known: {}", args.scheme, known.join(", ")))
    })?;
    run_surface(args, builtin.scheme(), out)
}

fn run_curve(args: &StencilArgs, scheme: &CurveScheme, out: &mut impl Write) -> Result<(), UserError> {
    let n = args.n;
    let grid = basis_grid(scheme, n)?;
    let number = |r: &Rational| if args.exact { json!(r.to_string()) } else { json!(r.to_f64()) };
    let text = |r: &Rational| if args.exact { r.to_string() } else { format!("{:.17}", r.to_f64()) };
    if let Some(at) = &args.at {
        let (p, q) = subdiv::stencil::parse_fraction(at).map_err(|e| UserError(e.to_string()))?;
        let scaled = p.checked_mul(i64::from(n)).ok_or_else(|| UserError(format!("x = {at} is too large")))?;
        if scaled % q != 0 {
            return Err(UserError(format!("x = {at} is not on the grid (1/{n})ℤ; pass --n a multiple of {q}")));
        }
        let stencil = grid.stencil_at(scaled / q);
        let weights = |w: &[(i64, Rational)]| -> Value {
            w.iter().map(|(i, r)| json!({"point": i, "weight": number(r)})).collect()
        };
        if args.json {
            let report = json!({
                "scheme": scheme.name(), "n": n, "x": at,
                "position": weights(&stencil.position), "tangent": weights(&stencil.tangent),
            });
            writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
        } else {
            writeln!(out, "{} at x = {at}: weights of the control points p_i", scheme.name())?;
            for (label, w) in [("position", &stencil.position), ("tangent", &stencil.tangent)] {
                let list: Vec<String> = w.iter().map(|(i, r)| format!("p{i}: {}", text(r))).collect();
                writeln!(out, "{label:9} {}", list.join(", "))?;
            }
        }
        return Ok(());
    }
    let x: Vec<Rational> =
        (0..grid.phi.len()).map(|k| Rational::new(grid.first + k as i64, i64::from(n)).expect("n ≥ 1")).collect();
    if args.json {
        let report = json!({
            "scheme": scheme.name(), "n": n,
            "x": x.iter().map(number).collect::<Vec<_>>(),
            "phi": grid.phi.iter().map(number).collect::<Vec<_>>(),
            "dphi": grid.dphi.iter().map(number).collect::<Vec<_>>(),
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        writeln!(out, "{:>12} {:>24} {:>24}", "x", "phi", "dphi")?;
        for ((x, phi), dphi) in x.iter().zip(&grid.phi).zip(&grid.dphi) {
            writeln!(out, "{:>12} {:>24} {:>24}", x.to_string(), text(phi), text(dphi))?;
        }
    }
    Ok(())
}

/// A local curve scheme (rows of its own near the origin): the basis functions of the special
/// control points and their two neighbours on `(1/n)ℤ`, or with `--at X` every point's weight
/// there. Positions only: the tangents of a local scheme are not solved.
fn run_local(args: &StencilArgs, scheme: &LocalCurveScheme, out: &mut impl Write) -> Result<(), UserError> {
    let n = i64::from(args.n);
    let grid = LocalCurveGrid::new(scheme, args.n)?;
    let number = |r: &Rational| if args.exact { json!(r.to_string()) } else { json!(r.to_f64()) };
    let text = |r: &Rational| if args.exact { r.to_string() } else { format!("{:.17}", r.to_f64()) };
    let (lo, hi) = grid.special;
    let points: Vec<i64> = (lo - 1..=hi + 1).collect();
    let span = grid.families.iter().map(|(first, values)| (*first, *first + values.len() as i64 - 1));
    let reach = span.fold(0, |r, (first, last)| r.max(first.abs()).max(last.abs())) + (hi - lo + 2) * n;
    let (first, last) = (-reach, reach);
    if let Some(at) = &args.at {
        let (p, q) = subdiv::stencil::parse_fraction(at).map_err(|e| UserError(e.to_string()))?;
        let scaled = p.checked_mul(n).ok_or_else(|| UserError(format!("x = {at} is too large")))?;
        if scaled % q != 0 {
            return Err(UserError(format!("x = {at} is not on the grid (1/{n})ℤ; pass --n a multiple of {q}")));
        }
        let k = scaled / q;
        let weights: Vec<(i64, Rational)> =
            (k / n - reach..=k / n + reach).map(|i| (i, grid.basis(i, k))).filter(|(_, w)| !w.is_zero()).collect();
        if args.json {
            let list: Vec<Value> = weights.iter().map(|(i, w)| json!({"point": i, "weight": number(w)})).collect();
            let report = json!({"scheme": scheme.name(), "n": n, "x": at, "position": list});
            writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
        } else {
            writeln!(out, "{} at x = {at}: weights of the control points p_i (positions only)", scheme.name())?;
            let list: Vec<String> = weights.iter().map(|(i, w)| format!("p{i}: {}", text(w))).collect();
            writeln!(out, "position  {}", list.join(", "))?;
        }
        return Ok(());
    }
    // The rows where one of the listed basis functions is nonzero.
    let rows: Vec<i64> = (first..=last).filter(|&k| points.iter().any(|&i| !grid.basis(i, k).is_zero())).collect();
    let x = |k: i64| Rational::new(k, n).expect("n ≥ 1");
    if args.json {
        let basis: serde_json::Map<String, Value> = points
            .iter()
            .map(|&i| (i.to_string(), Value::Array(rows.iter().map(|&k| number(&grid.basis(i, k))).collect())))
            .collect();
        let report = json!({
            "scheme": scheme.name(), "n": n, "special": [lo, hi],
            "x": rows.iter().map(|&k| number(&x(k))).collect::<Vec<_>>(), "basis": basis,
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        write!(out, "{:>12}", "x")?;
        for i in &points {
            write!(out, " {:>24}", format!("phi_{i}"))?;
        }
        writeln!(out)?;
        for &k in &rows {
            write!(out, "{:>12}", x(k).to_string())?;
            for &i in &points {
                write!(out, " {:>24}", text(&grid.basis(i, k)))?;
            }
            writeln!(out)?;
        }
    }
    Ok(())
}

fn run_surface(args: &StencilArgs, scheme: &Scheme, out: &mut impl Write) -> Result<(), UserError> {
    let valence = args.valence.map_or(scheme.regular_valence(), |k| k as usize);
    let matrices = PatchMatrices::of(scheme, PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)?;
    let points: Vec<Dyadic> = match &args.at {
        Some(at) => {
            vec![at.parse::<Dyadic>().map_err(|e| UserError(format!("--at: {e}")))?]
        }
        None => Grid::Primal.points(matrices.face_size, args.n),
    };
    let mut reports = Vec::new();
    let mut evaluator = StencilEvaluator::new(&*matrices);
    for point in points {
        let (u, v) = point.to_f64();
        // Weights as JSON values and as text, in decimals or (--exact) fractions.
        let (position, du, dv, exact_derivatives): (Vec<String>, Vec<String>, Vec<String>, bool) = if args.exact {
            let s = exact_surface_stencil(&matrices, 0, point)?;
            let text = |w: &[Rational]| w.iter().map(ToString::to_string).collect::<Vec<_>>();
            match &s.derivatives {
                Some([du, dv]) => (text(&s.position), text(du), text(dv), true),
                None => (text(&s.position), Vec::new(), Vec::new(), false),
            }
        } else {
            let s = evaluator.stencil(0, point)?;
            let text = |w: &[f64]| w.iter().map(|x| format!("{x:.12}")).collect::<Vec<_>>();
            (text(&s.position), text(&s.du), text(&s.dv), s.exact_derivatives)
        };
        if args.json {
            let values = |w: &[String]| -> Vec<Value> {
                w.iter()
                    .map(|x| if args.exact { json!(x) } else { json!(x.parse::<f64>().unwrap_or(f64::NAN)) })
                    .collect()
            };
            reports.push(json!({
                "u": u, "v": v, "position": values(&position), "du": values(&du), "dv": values(&dv),
                "exact_derivatives": exact_derivatives,
            }));
        } else {
            writeln!(out, "({u}, {v}):")?;
            writeln!(out, "  position {}", position.join(" "))?;
            if du.is_empty() {
                writeln!(out, "  (at the extraordinary vertex the tangents are directions, not rational in general)")?;
            } else {
                writeln!(out, "  du       {}", du.join(" "))?;
                writeln!(out, "  dv       {}", dv.join(" "))?;
                if !exact_derivatives {
                    writeln!(out, "  (at the extraordinary vertex: du, dv are tangent directions)")?;
                }
            }
        }
    }
    if args.json {
        let report = json!({
            "scheme": scheme.name, "valence": valence, "control_points": matrices.shapes[0].size,
            "stencils": reports,
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    }
    Ok(())
}
