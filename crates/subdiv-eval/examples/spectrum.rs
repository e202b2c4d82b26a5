//! Prints the spectrum of the keeping child's matrix and how semisimple its parts are, for
//! Catmull-Clark and Loop at a few valences: `cargo run -p subdiv-eval --example spectrum
//! [VALENCE…]`.

#![allow(clippy::print_stdout)]

use subdiv_eval::EigenBasis;
use subdiv_schemes::Builtin;

fn main() -> Result<(), subdiv_eval::EvalError> {
    let valences: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let valences = if valences.is_empty() { vec![3, 5, 8, 16, 64] } else { valences };
    for scheme in [Builtin::CatmullClark, Builtin::Loop] {
        for &k in &valences {
            let basis = EigenBasis::interior(scheme.scheme(), k)?;
            let Some(s) = basis.spectrum() else { continue };
            let distinct: Vec<String> = s
                .eigenvalues
                .iter()
                .fold(Vec::<((f64, f64), usize)>::new(), |mut acc, &(re, im)| {
                    match acc.last_mut() {
                        Some((v, n)) if (v.0 - re).abs() < 1e-9 && (v.1 - im).abs() < 1e-9 => *n += 1,
                        _ => acc.push(((re, im), 1)),
                    }
                    acc
                })
                .into_iter()
                .take(8)
                .map(
                    |((re, im), n)| {
                        if im.abs() > 1e-12 { format!("{re:.5}{im:+.5}i×{n}") } else { format!("{re:.5}×{n}") }
                    },
                )
                .collect();
            println!(
                "{scheme:?} k={k}: size {} kept {} subdominant {:.6} | {} … | |Ax−λx| {:.1e} |YX−I| {:.1e} rebuild {:.1e} \
                 cond(all eigenvectors) {:.1e}",
                s.eigenvalues.len(),
                s.kept,
                s.subdominant,
                distinct.join(", "),
                s.right_residual,
                s.biorthogonality,
                s.reconstruction,
                s.eigenvector_condition
            );
        }
    }
    Ok(())
}
