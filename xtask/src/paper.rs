//! `cargo xtask paper`: every number of paper 000 (Schaefer and Warren) that we reproduce,
//! printed beside the paper's, with a verdict; exit status 1 if one differs.

use num_bigint::BigInt;
use num_integer::Integer;
use subdiv::mesh::BoundaryInterpolation;
use subdiv::schemes::{Builtin, CurveScheme, PatchMatrices, PatchType};
use subdiv::stencil::curve::{NonUniformCubicGrid, basis_grid};
use subdiv::stencil::surface_basis::{SurfaceBasisGrid, SurfaceMask};
use subdiv::stencil::{Dyadic, Grid, Rational, StencilEvaluator, surface_stencil};

/// `values / denominator` as exact fractions.
fn fractions(values: &[i64], denominator: i64) -> Vec<Rational> {
    values.iter().map(|&v| Rational::new(v, denominator).expect("nonzero denominator")).collect()
}

fn show(values: &[Rational]) -> String {
    values.iter().map(Rational::to_string).collect::<Vec<_>>().join(", ")
}

/// `1/L · {integers}` when every weight is a fraction with a denominator up to 10⁶ (checked to
/// 1e-13), else decimals.
fn normalised(weights: &[f64]) -> String {
    let exact: Option<Vec<Rational>> = weights
        .iter()
        .map(|&w| Rational::approximate(w, 1_000_000).filter(|r| (r.to_f64() - w).abs() < 1e-13))
        .collect();
    let Some(fractions) = exact else {
        return weights.iter().map(|w| format!("{w:.10}")).collect::<Vec<_>>().join(" ");
    };
    let lcm = fractions.iter().fold(BigInt::from(1), |l, r| l.lcm(r.denom()));
    let integers: Vec<String> = fractions.iter().map(|r| (r.numer() * (&lcm / r.denom())).to_string()).collect();
    format!("1/{lcm} · {{{}}}", integers.join(", "))
}

pub(crate) fn run() -> Result<(), String> {
    let mut differ = 0;
    let mut compare = |what: &str, ours: &[Rational], paper: &[Rational]| {
        let equal = ours == paper;
        differ += usize::from(!equal);
        println!(
            "{what}\n  ours:  {}\n  paper: {}\n  {}\n",
            show(ours),
            show(paper),
            if equal { "equal" } else { "DIFFERENT" }
        );
    };
    let four_point = CurveScheme::builtin("four-point").ok_or("four-point is built in")?;
    let grid = basis_grid(&four_point, 3).map_err(|e| e.to_string())?;
    compare(
        "§4 four-point φ at x = −3, −8/3, …, 3 (n = 3)",
        &grid.phi,
        &fractions(&[0, -1, 16, 0, -256, -410, 0, 2000, 4240, 5589, 4240, 2000, 0, -410, -256, 0, 16, -1, 0], 5589),
    );
    compare(
        "§4 four-point φ′ at x = −3, −8/3, …, 3 (n = 3), normalised Σ(i − x)φ′(x − i) = 1",
        &grid.dphi,
        &fractions(&[0, -1, 8, -45, -64, -1, 360, 656, 584, 0, -584, -656, -360, 1, 64, 45, -8, 1, 0], 540),
    );
    let tangent: Vec<Rational> = grid.stencil_at(1).tangent.into_iter().map(|(_, w)| w).collect();
    compare(
        "§4 four-point tangent mask at x = 1/3 over p₋₂ … p₃",
        &tangent,
        &fractions(&[-8, 1, -584, 656, -64, -1], 540),
    );

    println!("§2 non-uniform cubic B-spline: the local matrix, derived by knot insertion");
    for row in NonUniformCubicGrid::local_matrix() {
        println!("  {}", show(&row));
    }
    println!("  (the paper prints the matrix of the mirrored knot sequence: rows and columns reversed)\n");

    let sw_curve = CurveScheme::builtin("sw-curve").ok_or("sw-curve is built in")?;
    let spectrum = sw_curve.eigenvalues().map_err(|e| e.to_string())?;
    let head: Vec<String> = spectrum.iter().take(5).map(|(re, _)| format!("{re:.12}")).collect();
    println!("§5.4 sw-curve spectrum\n  ours:  {}\n  paper: 1, 1/2, 1/6, 1/6, 1/6\n", head.join(", "));
    let expected = [1.0, 0.5, 1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0];
    if spectrum.iter().zip(expected).any(|((re, im), e)| (re - e).abs() > 1e-12 || im.abs() > 1e-12) {
        differ += 1;
    }

    system_sizes()?;

    let sw_quad = Builtin::SwQuad.scheme();
    let m = PatchMatrices::of(sw_quad, PatchType::interior(5), BoundaryInterpolation::EdgeOnly)
        .map_err(|e| e.to_string())?;
    println!("§5.4 sw-quad, valence 5, n = 3 (Fig. 6; its numbers are not in our copy, and the rules at the");
    println!("extraordinary vertex are ours): position weights over the 18 control points of the patch,");
    println!("in Mesh::patch order (the face's corners first, from the extraordinary vertex)");
    for (u, v) in [(1, 0), (1, 1)] {
        let s = surface_stencil(&m, 0, Dyadic::new(u, v, 3)).map_err(|e| e.to_string())?;
        println!("  ({u}/3, {v}/3): {}", normalised(&s.position));
    }
    println!();
    // Route 1: √3 taken two steps at a time is ternary on the triangular lattice; the midpoint of
    // the edge (0, 0)–(1, 0) is (1/2, 0), residue (1, 0) on the grid (1/2)Z².
    let sqrt3 = SurfaceMask::from_scheme(Builtin::Sqrt3.scheme()).map_err(|e| e.to_string())?;
    let grid = SurfaceBasisGrid::at_residues(&sqrt3, 2, &[[1, 0]]).map_err(|e| e.to_string())?;
    let s = grid.stencil_at([1, 0]).ok_or("the midpoint's residue is computed")?;
    let common = s.position.iter().fold(BigInt::from(1), |l, w| l.lcm(w.denom()));
    println!("§5.1 √3 edge-midpoint stencil (Fig. 4; its weights are not in our copy, only the normalisation)");
    println!("  control points at lattice (i, j) (the edge from (0, 0) to (1, 0); (0, 1) and (1, −1) its");
    println!("  triangles' third corners), weights over the common denominator:");
    for (c, w) in s.control.iter().zip(&s.position) {
        println!("    ({:>2}, {:>2}): {w:>8} = {:>4}/{common}", c[0], c[1], w.numer() * (&common / w.denom()));
    }
    let equal = common == BigInt::from(2256);
    differ += usize::from(!equal);
    println!(
        "  ours:  common denominator {common}\n  paper: implicit normalization of 2256\n  {}\n",
        if equal { "equal" } else { "DIFFERENT" }
    );
    if differ > 0 { Err(format!("{differ} reproduced numbers differ from the paper")) } else { Ok(()) }
}

/// §5.3: the paper's system for a valence-6 vertex at n = 3 has 781 unknowns naively and 51
/// after its reductions. Ours are eigenproblems over one patch's control points, one per
/// cycle of the grid points' addresses.
fn system_sizes() -> Result<(), String> {
    println!("§5.3 system sizes, sw-quad valence 6, n = 3 (paper: 781 unknowns naive, 51 reduced)");
    let sw_quad = Builtin::SwQuad.scheme();
    let m = PatchMatrices::of(sw_quad, PatchType::interior(6), BoundaryInterpolation::EdgeOnly)
        .map_err(|e| e.to_string())?;
    let mut evaluator = StencilEvaluator::new(&*m);
    for grid in Grid::ALL {
        for p in grid.points(4, 3) {
            evaluator.stencil(0, p).map_err(|e| e.to_string())?;
        }
    }
    let stats = evaluator.stats();
    println!(
        "  ours: the 25 primal and dual points of the face, {} address states, {} eigenproblems of at most {} \
         unknowns each\n",
        stats.states, stats.eigen_solves, stats.largest_system
    );
    Ok(())
}
