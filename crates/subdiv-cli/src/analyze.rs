//! `subdiv analyze`: Reif's C1 test of a scheme at an extraordinary vertex or a boundary
//! vertex, or a table of it for every built-in surface scheme.

use std::io::Write;

use serde_json::json;
use subdiv::schemes::{Analysis, Builtin, Centre};

use crate::UserError;
use crate::scheme_arg::SchemeArgs;

/// Arguments of `subdiv analyze`.
#[derive(Debug, clap::Args)]
pub(crate) struct AnalyzeArgs {
    #[command(flatten)]
    scheme: SchemeArgs,
    /// Valence of the extraordinary vertex.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(3..=64))]
    valence: u32,
    /// Analyse a boundary vertex with this many faces instead (valence faces + 1), under the
    /// scheme's boundary rule (edge-only for OpenSubdiv's).
    #[arg(long, conflicts_with = "valence", value_parser = clap::value_parser!(u32).range(1..=63))]
    boundary_faces: Option<u32>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Print a Markdown table for every built-in scheme instead: interior vertices of valence 3
    /// to this one, and boundary vertices of 1 to this many faces less one.
    #[arg(long, value_name = "MAX_VALENCE", value_parser = clap::value_parser!(u32).range(3..=64))]
    table: Option<u32>,
}

fn format_eigenvalue(&(re, im): &(f64, f64)) -> String {
    if im.abs() < 1e-9 { format!("{re:.6}") } else { format!("{re:.4}{im:+.4}i") }
}

pub(crate) fn run(args: &AnalyzeArgs, out: &mut impl Write) -> Result<(), UserError> {
    if let Some(max) = args.table {
        return table(max as usize, out);
    }
    let scheme = args.scheme.resolve()?;
    let centre = match args.boundary_faces {
        Some(faces) => Centre::Boundary(faces as usize),
        None => Centre::Interior(args.valence as usize),
    };
    let analysis = Analysis::at(&scheme, centre)?;
    let spectrum = &analysis.spectrum;
    let map = analysis.characteristic_map.as_ref();
    if args.json {
        let eigenvalues: Vec<_> = spectrum.eigenvalues.iter().map(|&(re, im)| json!([re, im])).collect();
        let report = json!({
            "scheme": scheme.name(),
            "valence": analysis.valence,
            "boundary_faces": args.boundary_faces,
            "matrix_size": analysis.matrix_size,
            "radius": analysis.radius,
            "eigenvalues": eigenvalues,
            "subdominant": spectrum.subdominant(),
            "unit_dominant_simple": spectrum.unit_dominant_simple,
            "subdominant_real_pair": spectrum.subdominant_real_pair,
            "subdominant_strict": spectrum.subdominant_strict,
            "characteristic_map": map.map(|m| json!({
                "levels": m.levels,
                "faces": m.faces,
                "flipped_faces": m.flipped_faces,
                "min_area_ratio": m.min_area_ratio,
                "windings": [m.windings.0, m.windings.1],
                "outlines": m.outlines,
                "outlines_simple": m.outlines_simple,
                "regular": m.is_regular(),
                "injective": m.is_injective(),
            })),
            "c1": analysis.is_c1(),
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(());
    }
    writeln!(out, "scheme        {scheme} at {centre}")?;
    writeln!(
        out,
        "matrix        {n} × {n}, the {}-ring neighbourhood, derived by refining a canonical mesh",
        analysis.radius,
        n = analysis.matrix_size,
    )?;
    let head: Vec<String> = spectrum.eigenvalues.iter().take(6).map(format_eigenvalue).collect();
    writeln!(out, "spectrum      {}", head.join(", "))?;
    let yes = |b: bool| if b { "yes" } else { "no" };
    writeln!(out, "λ0 = 1 simple            {}", yes(spectrum.unit_dominant_simple))?;
    let pair =
        if args.boundary_faces.is_some() { "λ1 ≥ λ2 real, positive   " } else { "λ1 = λ2 real, positive   " };
    writeln!(out, "{pair}{}", yes(spectrum.subdominant_real_pair))?;
    writeln!(out, "|λ3| < λ2                {}", yes(spectrum.subdominant_strict))?;
    match map {
        Some(m) => {
            let outline = if m.outlines == 2 {
                format!("windings {} and {}", m.windings.0, m.windings.1)
            } else {
                format!("{} outline(s), simple: {}", m.outlines, yes(m.outlines_simple))
            };
            writeln!(
                out,
                "characteristic map       {} faces sampled after {} levels: {} flipped, min/max area {:.3}, {outline}",
                m.faces, m.levels, m.flipped_faces, m.min_area_ratio
            )?;
            writeln!(out, "  regular                {}", yes(m.is_regular()))?;
            writeln!(out, "  injective              {}", yes(m.is_injective()))?;
        }
        None => writeln!(out, "characteristic map       not checked: no real subdominant pair")?,
    }
    writeln!(out, "C1 (Reif)                {}", yes(analysis.is_c1()))?;
    Ok(())
}

fn table(max: usize, out: &mut impl Write) -> Result<(), UserError> {
    writeln!(out, "| scheme | vertex | matrix | λ0 … λ4 (moduli of complex ones with i) | C1 |")?;
    writeln!(out, "|---|---|---|---|---|")?;
    for builtin in Builtin::ALL {
        let scheme = builtin.scheme();
        let interior = (3..=max).map(Centre::Interior);
        let boundary = (1..max).map(Centre::Boundary);
        for centre in interior.chain(boundary) {
            let vertex = match centre {
                Centre::Interior(k) => format!("k = {k}"),
                Centre::Boundary(faces) => format!("boundary, {faces} face{}", if faces == 1 { "" } else { "s" }),
            };
            if matches!(centre, Centre::Boundary(_)) && !scheme.has_boundary_rules() {
                writeln!(out, "| {builtin} | boundary | — | — | no boundary rules |")?;
                break;
            }
            let a = Analysis::at(scheme, centre)?;
            let head: Vec<String> = a.spectrum.eigenvalues.iter().take(5).map(format_eigenvalue).collect();
            let verdict = if a.is_c1() {
                "yes"
            } else if !a.spectrum.passes() {
                "no (spectrum)"
            } else {
                "no (characteristic map)"
            };
            writeln!(out, "| {builtin} | {vertex} | {0}×{0} | {1} | {verdict} |", a.matrix_size, head.join(", "))?;
        }
    }
    Ok(())
}
