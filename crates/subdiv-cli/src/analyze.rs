//! `subdiv analyze`: the spectrum of a scheme's one-ring matrix at a valence.

use std::io::Write;

use serde_json::json;
use subdiv::schemes::{Scheme, Spectrum};

use crate::UserError;
use crate::refine::parse_scheme;

/// Arguments of `subdiv analyze`.
#[derive(Debug, clap::Args)]
pub(crate) struct AnalyzeArgs {
    /// Subdivision scheme.
    #[arg(long, default_value = "catmull-clark", value_parser = parse_scheme)]
    scheme: Scheme,
    /// Valence of the interior extraordinary vertex.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(3..=256))]
    valence: u32,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: &AnalyzeArgs, out: &mut impl Write) -> Result<(), UserError> {
    let spectrum = Spectrum::of(args.scheme, args.valence as usize)?;
    if args.json {
        let eigenvalues: Vec<_> = spectrum.eigenvalues.iter().map(|&(re, im)| json!([re, im])).collect();
        let report = json!({
            "scheme": args.scheme.name(),
            "valence": args.valence,
            "eigenvalues": eigenvalues,
            "subdominant": spectrum.subdominant(),
            "unit_dominant_simple": spectrum.unit_dominant_simple,
            "subdominant_real_double": spectrum.subdominant_real_double,
            "subdominant_strict": spectrum.subdominant_strict,
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(());
    }
    writeln!(out, "scheme        {} at an interior vertex of valence {}", args.scheme, args.valence)?;
    writeln!(
        out,
        "one-ring      {} × {} matrix, derived by refining a canonical mesh",
        spectrum.eigenvalues.len(),
        spectrum.eigenvalues.len()
    )?;
    let head: Vec<String> = spectrum
        .eigenvalues
        .iter()
        .take(6)
        .map(|&(re, im)| if im.abs() < 1e-12 { format!("{re:.12}") } else { format!("{re:.6}{im:+.6}i") })
        .collect();
    writeln!(out, "spectrum      {}", head.join(", "))?;
    let yes = |b: bool| if b { "yes" } else { "no" };
    writeln!(out, "λ0 = 1 simple            {}", yes(spectrum.unit_dominant_simple))?;
    writeln!(out, "λ1 = λ2 real, positive   {}", yes(spectrum.subdominant_real_double))?;
    writeln!(out, "|λ3| < λ1                {}", yes(spectrum.subdominant_strict))?;
    writeln!(out, "(spectral conditions of Reif's C1 test; the characteristic-map check is not implemented yet)")?;
    Ok(())
}
