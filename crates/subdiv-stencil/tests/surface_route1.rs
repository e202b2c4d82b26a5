//! Surface route 1 (scaling relations on (1/n)Z², exact) against route 3 (periodic addresses
//! over the derived sub-patch matrices), closed forms and the paper's √3 stencil.

use num_bigint::BigInt;
use num_integer::Integer;
use proptest::prelude::*;
use subdiv_mesh::BoundaryInterpolation;
use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
use subdiv_stencil::surface_basis::{SurfaceBasisGrid, SurfaceMask, regular_patch_stencil};
use subdiv_stencil::{Dyadic, Rational, StencilError, SurfaceStencil, surface_stencil};

/// The schemes both routes serve at the regular patch (the dual splits' route 1 on the lattice
/// shifted by (½, ½), their route 3 over the dual quad).
const BOTH: [Builtin; 7] = [
    Builtin::CatmullClark,
    Builtin::Loop,
    Builtin::Butterfly,
    Builtin::SwQuad,
    Builtin::Kobbelt,
    Builtin::DooSabin,
    Builtin::Midedge,
];

fn r(p: i64, q: i64) -> Rational {
    Rational::new(p, q).unwrap()
}

fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Denominators whose residues under doubling run through long cycles (period 18 to 28 of
/// 1/n in binary): route 1's exact elimination then grows big numbers, seconds per point for the
/// schemes with the widest support (Kobbelt at n = 29: about 13 s at opt-level 1), so those two
/// schemes draw the other denominators up to 32 here, and meet these once each in
/// `routes_1_and_3_agree_at_the_long_cycle_denominators`; the rest draw all of them.
const SLOW: [i64; 4] = [19, 25, 27, 29];

/// A scheme and a rational point of its face's domain with denominator up to 32.
fn scheme_and_point() -> impl Strategy<Value = (Builtin, Dyadic)> {
    (0..BOTH.len(), 1i64..=32, 0.0..=1.0f64, 0.0..=1.0f64).prop_map(|(s, n, x, y)| {
        let builtin = BOTH[s];
        let wide = matches!(builtin, Builtin::Kobbelt | Builtin::Butterfly);
        let n = if wide && SLOW.contains(&n) { n + 1 } else { n };
        let u = (x * n as f64).round() as i64;
        let v = (y * n as f64).round() as i64;
        // Triangles: fold the square onto the triangle u + v ≤ 1.
        let (u, v) = if builtin.scheme().regular_valence() == 6 && u + v > n { (n - u, n - v) } else { (u, v) };
        (builtin, Dyadic::new(u, v, n))
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20, ..ProptestConfig::default() })]

    #[test]
    fn routes_1_and_3_agree_at_the_regular_patch((builtin, point) in scheme_and_point()) {
        let scheme = builtin.scheme();
        let exact = regular_patch_stencil(scheme, point).unwrap();
        // Exactly 1 and 0.
        prop_assert_eq!(exact.position.iter().sum::<Rational>(), Rational::one());
        prop_assert!(exact.du.iter().sum::<Rational>().is_zero() && exact.dv.iter().sum::<Rational>().is_zero());
        let route1 = exact.to_f64();
        let sum = |w: &[f64]| w.iter().sum::<f64>();
        prop_assert!((sum(&route1.position) - 1.0).abs() < 1e-13);
        prop_assert!(sum(&route1.du).abs() < 1e-13 && sum(&route1.dv).abs() < 1e-13);

        let m = PatchMatrices::of(scheme, PatchType::regular(scheme), BoundaryInterpolation::EdgeOnly).unwrap();
        let route3 = surface_stencil(&m, 0, point).unwrap();
        let (what, d) = worst_component(&route1, &route3);
        prop_assert!(d < 1e-12, "{} at {:?}, {}: routes differ by {:e}", builtin.name(), point, what, d);
    }
}

/// The denominators the proptest leaves out for the widest schemes, once each: their long
/// cycles make the exact solve slow, not different.
#[test]
fn routes_1_and_3_agree_at_the_long_cycle_denominators() {
    for builtin in [Builtin::Butterfly, Builtin::Kobbelt] {
        let scheme = builtin.scheme();
        let m = PatchMatrices::of(scheme, PatchType::regular(scheme), BoundaryInterpolation::EdgeOnly).unwrap();
        for n in SLOW {
            let point = Dyadic::new(n / 3, (2 * n) / 5, n);
            let route1 = regular_patch_stencil(scheme, point).unwrap().to_f64();
            let route3 = surface_stencil(&m, 0, point).unwrap();
            let (what, d) = worst_component(&route1, &route3);
            assert!(d < 1e-12, "{} at {point:?}, {what}: routes differ by {d:e}", builtin.name());
        }
    }
}

/// The component (position, du, dv) where two stencils differ most, and by how much.
fn worst_component(a: &SurfaceStencil, b: &SurfaceStencil) -> (&'static str, f64) {
    [("position", &a.position, &b.position), ("du", &a.du, &b.du), ("dv", &a.dv, &b.dv)]
        .into_iter()
        .map(|(what, x, y)| (what, max_difference(x, y)))
        .fold(("position", 0.0), |worst, c| if c.1 > worst.1 { c } else { worst })
}

/// The uniform cubic B-spline centred at 0 and its derivative, exactly.
fn cubic_b_spline(t: &Rational) -> (Rational, Rational) {
    let r = |p: i64, q: i64| Rational::new(p, q).unwrap();
    let a = t.abs();
    let sign = if *t < Rational::zero() { r(-1, 1) } else { r(1, 1) };
    if a >= r(2, 1) {
        return (Rational::zero(), Rational::zero());
    }
    if a >= r(1, 1) {
        let s = &r(2, 1) - &a;
        // (2 − |t|)³/6, derivative −sign·(2 − |t|)²/2.
        return (&(&(&s * &s) * &s) * &r(1, 6), &(&(&s * &s) * &r(-1, 2)) * &sign);
    }
    // (4 − 6t² + 3|t|³)/6, derivative sign·(−12|t| + 9t²)/6.
    let a2 = &a * &a;
    let value = &(&(&r(4, 1) - &(&r(6, 1) * &a2)) + &(&r(3, 1) * &(&a2 * &a))) * &r(1, 6);
    let slope = &(&(&(&r(-12, 1) * &a) + &(&r(9, 1) * &a2)) * &r(1, 6)) * &sign;
    (value, slope)
}

#[test]
fn catmull_clark_route_1_is_the_bicubic_b_spline_exactly() {
    let cc = SurfaceMask::from_scheme(Builtin::CatmullClark.scheme()).unwrap();
    for n in [1, 2, 3, 4, 5, 6, 7, 9] {
        let grid = SurfaceBasisGrid::new(&cc, n).unwrap();
        let n = i64::from(n);
        for i in -2 * n - 1..=2 * n + 1 {
            for j in -2 * n - 1..=2 * n + 1 {
                let (bx, dx) = cubic_b_spline(&Rational::new(i, n).unwrap());
                let (by, dy) = cubic_b_spline(&Rational::new(j, n).unwrap());
                assert_eq!(grid.value([i, j]).unwrap(), &bx * &by, "φ({i}/{n}, {j}/{n})");
                assert_eq!(grid.du([i, j]).unwrap(), &dx * &by, "∂φ/∂u({i}/{n}, {j}/{n})");
                assert_eq!(grid.dv([i, j]).unwrap(), &bx * &dy, "∂φ/∂v({i}/{n}, {j}/{n})");
            }
        }
    }
}

/// The whole grid (cycles copied by symmetry where possible) equals the grid solved residue by
/// residue (every cycle solved), and the basis function has the mask's symmetries.
#[test]
fn whole_grids_match_per_residue_solves() {
    for builtin in [Builtin::Loop, Builtin::Butterfly, Builtin::Kobbelt, Builtin::Sqrt3] {
        let mask = SurfaceMask::from_scheme(builtin.scheme()).unwrap();
        let n = 5;
        let whole = SurfaceBasisGrid::new(&mask, n).unwrap();
        let sizes = whole.sizes();
        assert!(sizes.solved_cycles < sizes.cycles, "{}: {sizes:?}", builtin.name());
        for r in [[1, 0], [0, 1], [4, 4], [2, 3]] {
            let alone = SurfaceBasisGrid::at_residues(&mask, n, &[r]).unwrap();
            for i in -20..=20 {
                for j in -20..=20 {
                    let m = [r[0] + 5 * i, r[1] + 5 * j];
                    assert_eq!(whole.value(m), alone.value(m), "{} φ at {m:?}", builtin.name());
                    assert_eq!(whole.du(m), alone.du(m), "{} ∂φ/∂u at {m:?}", builtin.name());
                    assert_eq!(whole.dv(m), alone.dv(m), "{} ∂φ/∂v at {m:?}", builtin.name());
                }
            }
        }
        // φ(−x) = φ(x) and ∂φ/∂u(−x) = −∂φ/∂u(x).
        for i in -12..=12 {
            for j in -12..=12 {
                assert_eq!(whole.value([i, j]), whole.value([-i, -j]));
                assert_eq!(whole.du([i, j]), whole.du([-i, -j]).map(|d| -d));
            }
        }
    }
}

/// Paper 000 §5.1, Fig. 4: the exact stencil of √3 at the midpoint of an edge, "with an implicit
/// normalization of 2256" (the figure's numbers are not in our copy of the text). Ours has
/// exactly that common denominator: 1/2256 · {740, 740, 312, 312, 28 ×4, 18 ×2, 1 ×4} over the
/// 14 control points where φ is nonzero.
#[test]
fn sqrt3_edge_midpoint_has_the_papers_normalisation() {
    let mask = SurfaceMask::from_scheme(Builtin::Sqrt3.scheme()).unwrap();
    assert_eq!((mask.arity(), mask.steps(), mask.symmetry_count()), (3, 2, 12));
    // The edge from (0, 0) to (1, 0); its midpoint (1/2, 0) at rate 2.
    let grid = SurfaceBasisGrid::at_residues(&mask, 2, &[[1, 0]]).unwrap();
    let s = grid.stencil_at([1, 0]).unwrap();
    let common = s.position.iter().fold(BigInt::from(1), |l, w| l.lcm(w.denom()));
    assert_eq!(common, BigInt::from(2256));
    let mut scaled: Vec<(i64, [i64; 2])> = (s.position.iter().zip(&s.control))
        .map(|(w, c)| ((w.numer() * (&common / w.denom())).try_into().unwrap(), *c))
        .collect();
    scaled.sort_by_key(|&(w, c)| (std::cmp::Reverse(w), c));
    let weights: Vec<i64> = scaled.iter().map(|&(w, _)| w).collect();
    assert_eq!(weights, [740, 740, 312, 312, 28, 28, 28, 28, 18, 18, 1, 1, 1, 1]);
    // The two ends of the edge, the two opposite corners of its triangles.
    let at = |w: i64| scaled.iter().filter(|s| s.0 == w).map(|s| s.1).collect::<Vec<_>>();
    assert_eq!(at(740), [[0, 0], [1, 0]]);
    assert_eq!(at(312), [[0, 1], [1, -1]]);
    assert_eq!(weights.iter().sum::<i64>(), 2256);
    assert!(s.du.iter().sum::<Rational>().is_zero());
}

/// The dual splits on whole grids: route 1 on the shifted lattice against route 3 over the dual
/// quad, every point of (1/n)Z² in the patch for n up to 7.
#[test]
fn dual_routes_1_and_3_agree_on_whole_grids() {
    for builtin in [Builtin::DooSabin, Builtin::Midedge] {
        let scheme = builtin.scheme();
        let m = PatchMatrices::of(scheme, PatchType::regular(scheme), BoundaryInterpolation::EdgeOnly).unwrap();
        for n in [1, 2, 3, 5, 7] {
            for j in 0..=n {
                for i in 0..=n {
                    let point = Dyadic::new(i, j, n);
                    let route1 = regular_patch_stencil(scheme, point).unwrap().to_f64();
                    let route3 = surface_stencil(&m, 0, point).unwrap();
                    let (what, d) = worst_component(&route1, &route3);
                    assert!(d < 1e-12, "{} at {point:?}, {what}: routes differ by {d:e}", builtin.name());
                }
            }
        }
    }
}

/// Doo-Sabin's route 1 is the biquadratic B-spline: its mask (of the basis shifted by
/// (½, ½)) is the tensor product of (1, 3, 3, 1)/4 with itself.
#[test]
fn doo_sabin_route_1_is_the_biquadratic_b_spline() {
    let ds = SurfaceMask::from_scheme(Builtin::DooSabin.scheme()).unwrap();
    let chaikin = [r(1, 4), r(3, 4), r(3, 4), r(1, 4)];
    let mut expected: Vec<([i64; 2], Rational)> = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            expected.push(([i - 1, j - 1], &chaikin[i as usize] * &chaikin[j as usize]));
        }
    }
    expected.sort_by_key(|(k, _)| *k);
    assert_eq!(ds.weights(), expected.as_slice());
    assert_eq!(ds.control_offset(), [r(1, 2), r(1, 2)]);
}

#[test]
fn unsupported_splits_and_rates_are_typed_errors() {
    let cc = SurfaceMask::from_scheme(Builtin::CatmullClark.scheme()).unwrap();
    assert!(matches!(SurfaceBasisGrid::new(&cc, 0), Err(StencilError::Rate { .. })));
    assert!(matches!(
        regular_patch_stencil(Builtin::Loop.scheme(), Dyadic::new(2, 2, 3)),
        Err(StencilError::OutsideDomain { .. })
    ));
}

/// √3 on whole grids: route 1 (its two steps, arity 3) against route 3 over the ternary
/// split's regular patch (base-3 addresses), every point of the triangle at denominators with
/// and without a terminating ternary expansion; and route 3 at the middle of an edge is the
/// paper's stencil, 1/2256 · {740, 740, 312, 312, 28 ×4, 18 ×2, 1 ×4}.
#[test]
fn sqrt3_routes_1_and_3_agree_on_whole_grids() {
    let scheme = Builtin::Sqrt3.scheme();
    let m = PatchMatrices::of(scheme, PatchType::regular(scheme), BoundaryInterpolation::EdgeOnly).unwrap();
    for n in [1, 2, 3, 4, 5, 6, 9] {
        for j in 0..=n {
            for i in 0..=n - j {
                let point = Dyadic::new(i, j, n);
                let route1 = regular_patch_stencil(scheme, point).unwrap().to_f64();
                let route3 = surface_stencil(&m, 0, point).unwrap();
                let (what, d) = worst_component(&route1, &route3);
                assert!(d < 1e-12, "√3 at {point:?}, {what}: routes differ by {d:e}");
            }
        }
    }
    let middle = surface_stencil(&m, 0, Dyadic::new(1, 0, 2)).unwrap();
    let mut weights: Vec<f64> = middle.position.iter().map(|w| w * 2256.0).filter(|w| w.abs() > 1e-9).collect();
    weights.sort_by(|a, b| b.total_cmp(a));
    let expected = [740.0, 740.0, 312.0, 312.0, 28.0, 28.0, 28.0, 28.0, 18.0, 18.0, 1.0, 1.0, 1.0, 1.0];
    assert_eq!(weights.len(), expected.len(), "{weights:?}");
    for (w, e) in weights.iter().zip(expected) {
        assert!((w - e).abs() < 1e-9, "{weights:?}");
    }
}
