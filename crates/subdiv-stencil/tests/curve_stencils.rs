//! Exact curve stencils (paper 000 §2–4): the paper's four-point numbers, closed forms of the
//! B-splines, the two routes against each other, refinement, the non-uniform cubic B-spline
//! against Cox–de Boor, and the typed errors.

use glam::DVec3;
use proptest::prelude::*;
use subdiv_schemes::{CurveScheme, NonUniformCubicBSpline};
use subdiv_stencil::curve::{BasisGrid, EigenGrid, ExactMask, MAX_CURVE_RATE, NonUniformCubicGrid, basis_grid};
use subdiv_stencil::{Rational, StencilError};

fn r(p: i64, q: i64) -> Rational {
    Rational::new(p, q).unwrap()
}

fn int(p: i64) -> Rational {
    Rational::from_integer(p)
}

fn scheme(name: &str) -> CurveScheme {
    CurveScheme::builtin(name).unwrap()
}

#[test]
fn four_point_at_rate_3_matches_the_paper() {
    let grid = basis_grid(&scheme("four-point"), 3).unwrap();
    assert_eq!((grid.rate, grid.first, grid.phi.len()), (3, -9, 19));
    let phi = [0, -1, 16, 0, -256, -410, 0, 2000, 4240, 5589, 4240, 2000, 0, -410, -256, 0, 16, -1, 0];
    let expected: Vec<Rational> = phi.iter().map(|&p| r(p, 5589)).collect();
    assert_eq!(grid.phi, expected);
    let dphi = [0, -1, 8, -45, -64, -1, 360, 656, 584, 0, -584, -656, -360, 1, 64, 45, -8, 1, 0];
    let expected: Vec<Rational> = dphi.iter().map(|&p| r(p, 540)).collect();
    assert_eq!(grid.dphi, expected);
    // The tangent mask at x = 1/3 over p_{-2..=3}.
    let stencil = grid.stencil_at(1);
    let tangent: Vec<(i64, Rational)> =
        (-2..=3).zip([-8, 1, -584, 656, -64, -1]).map(|(i, w)| (i, r(w, 540))).collect();
    assert_eq!(stencil.tangent, tangent);
    let position: Vec<(i64, Rational)> =
        (-2..=3).zip([16, -410, 4240, 2000, -256, -1]).map(|(i, w)| (i, r(w, 5589))).collect();
    assert_eq!(stencil.position, position);
}

/// The centred uniform cubic B-spline and its derivative.
fn cubic(x: &Rational) -> (Rational, Rational) {
    let a = x.abs();
    let sign = if *x < Rational::zero() { int(-1) } else { int(1) };
    if a <= int(1) {
        let value = &(&r(2, 3) - &(&a * &a)) + &(&(&a * &a) * &a) * r(1, 2);
        let slope = &(&int(-2) * x) + &(&(&r(3, 2) * x) * &a);
        (value, slope)
    } else if a <= int(2) {
        let u = &int(2) - &a;
        (&(&(&u * &u) * &u) * &r(1, 6), &(-&sign * &(&u * &u)) * &r(1, 2))
    } else {
        (Rational::zero(), Rational::zero())
    }
}

/// The uniform quadratic B-spline on the knots −2, −1, 0, 1 (Chaikin's basis function) and its
/// derivative.
fn quadratic(x: &Rational) -> (Rational, Rational) {
    let y = x + &int(2);
    if y < int(0) || y > int(3) {
        (Rational::zero(), Rational::zero())
    } else if y <= int(1) {
        (&(&y * &y) * &r(1, 2), y)
    } else if y <= int(2) {
        let value = &(&(&int(-2) * &(&y * &y)) + &(&int(6) * &y)) - &int(3);
        (&value * &r(1, 2), &int(3) - &(&int(2) * &y))
    } else {
        let u = &int(3) - &y;
        (&(&u * &u) * &r(1, 2), -u)
    }
}

#[test]
fn b_splines_equal_their_closed_forms_exactly() {
    for (name, closed) in [("cubic-bspline", cubic as fn(&Rational) -> (Rational, Rational)), ("chaikin", quadratic)] {
        for n in 1..=12u32 {
            let grid = basis_grid(&scheme(name), n).unwrap();
            for k in grid.first - 2..grid.first + grid.phi.len() as i64 + 2 {
                let (value, slope) = closed(&r(k, i64::from(n)));
                assert_eq!(grid.value(k), value, "{name} φ({k}/{n})");
                assert_eq!(grid.derivative(k), slope, "{name} φ′({k}/{n})");
            }
        }
    }
}

#[test]
fn stencils_are_normalised_and_the_two_routes_agree() {
    for name in CurveScheme::BUILTIN_NAMES {
        let mask = ExactMask::from_scheme(&scheme(name)).unwrap();
        for n in 1..=32u32 {
            let grid = BasisGrid::new(&mask, n).unwrap();
            for j in -1..=i64::from(n) {
                let s = grid.stencil_at(j);
                let sum: Rational = s.position.iter().map(|(_, w)| w).sum();
                assert_eq!(sum, Rational::one(), "{name} n={n} x={j}/{n}");
                let sum: Rational = s.tangent.iter().map(|(_, w)| w).sum();
                assert!(sum.is_zero(), "{name} n={n} x={j}/{n}");
                // The tangent of the line p_i = i is 1.
                let slope: Rational = s.tangent.iter().map(|(i, w)| &int(*i) * w).sum();
                assert_eq!(slope, Rational::one(), "{name} n={n} x={j}/{n}");
                let sum: f64 = s.position_f64().iter().map(|(_, w)| w).sum();
                assert!((sum - 1.0).abs() < 1e-13, "{name} n={n}");
                let sum: f64 = s.tangent_f64().iter().map(|(_, w)| w).sum();
                assert!(sum.abs() < 1e-13, "{name} n={n}");
            }
            let eigen = EigenGrid::new(&mask, n).unwrap();
            assert_eq!((eigen.first, eigen.phi.len(), eigen.dphi.len()), (grid.first, grid.phi.len(), grid.dphi.len()));
            for (exact, float) in grid.phi_f64().iter().zip(&eigen.phi).chain(grid.dphi_f64().iter().zip(&eigen.dphi)) {
                assert!((exact - float).abs() < 1e-12, "{name} n={n}: {exact} vs {float}");
            }
        }
    }
}

#[test]
fn eigenvalue_one_is_not_simple_for_most_rates() {
    // One eigenvector per cycle of k ↦ 2k on the residues mod n: 1 for n = 2^e, 7 for n = 31.
    let mask = ExactMask::from_scheme(&scheme("four-point")).unwrap();
    for (n, cycles) in [(1, 1), (2, 1), (3, 2), (5, 2), (7, 3), (8, 1), (9, 3), (31, 7)] {
        assert_eq!(EigenGrid::new(&mask, n).unwrap().multiplicity, cycles, "n = {n}");
    }
}

/// `levels` steps of closed refinement of the impulse at index 0 of a polygon of `len` points.
fn refined_impulse(scheme: &CurveScheme, len: usize, levels: u32) -> Vec<f64> {
    let mut points = vec![DVec3::ZERO; len];
    points[0] = DVec3::X;
    scheme.refine_levels(&points, levels as usize, subdiv_schemes::PolygonKind::Closed).iter().map(|p| p.x).collect()
}

#[test]
fn dyadic_stencils_equal_refinement() {
    let len = 32usize;
    for name in ["four-point", "six-point", "cubic-bspline"] {
        let s = scheme(name);
        for levels in 1..=4u32 {
            let rate = 1u32 << levels;
            let grid = basis_grid(&s, rate).unwrap();
            let fine = refined_impulse(&s, len, levels);
            let at = |m: i64| fine[m.rem_euclid(fine.len() as i64) as usize];
            // Weight of the impulse at p_0 in the refined point at m / 2^levels; for an
            // approximating scheme, after the limit mask (1, 4, 1)/6 of the cubic B-spline.
            let weight = |m: i64| {
                if s.is_interpolating() { at(m) } else { (at(m - 1) + 4.0 * at(m) + at(m + 1)) / 6.0 }
            };
            for j in 0..=i64::from(rate) {
                let stencil = grid.stencil_at(j);
                let mut expected: Vec<(i64, f64)> =
                    (-8..=8).map(|i| (i, weight(j - i * i64::from(rate)))).filter(|(_, w)| w.abs() > 1e-15).collect();
                expected.sort_by_key(|e| e.0);
                let got = stencil.position_f64();
                assert_eq!(got.len(), expected.len(), "{name} x = {j}/{rate}");
                for ((i, w), (ie, we)) in got.iter().zip(&expected) {
                    assert_eq!(i, ie);
                    assert!((w - we).abs() < 1e-13, "{name} x = {j}/{rate}: p_{i} {w} vs {we}");
                }
            }
        }
    }
}

#[test]
fn sw_curve_has_non_polynomial_stencils_that_sum_to_one() {
    let grid = basis_grid(&scheme("sw-curve"), 12).unwrap();
    for j in 0..12 {
        let sum: Rational = grid.stencil_at(j).position.iter().map(|(_, w)| w).sum();
        assert_eq!(sum, Rational::one());
    }
    // Not a cubic on the span [0, 1]: the fourth differences of φ there do not all vanish.
    let values: Vec<Rational> = (0..=12).map(|k| grid.value(k)).collect();
    let mut differences = values;
    for _ in 0..4 {
        differences = differences.windows(2).map(|w| &w[1] - &w[0]).collect();
    }
    assert!(differences.iter().any(|d| !d.is_zero()));
    // The B-spline is a cubic there: the same differences vanish.
    let cubic = basis_grid(&scheme("cubic-bspline"), 12).unwrap();
    let mut differences: Vec<Rational> = (0..=12).map(|k| cubic.value(k)).collect();
    for _ in 0..4 {
        differences = differences.windows(2).map(|w| &w[1] - &w[0]).collect();
    }
    assert!(differences.iter().all(Rational::is_zero));
}

/// The cubic B-spline on the five knots `knots` at `t`, by Cox–de Boor (half-open spans).
fn cox_de_boor(knots: &[Rational; 5], t: &Rational) -> Rational {
    let mut basis: Vec<Rational> =
        (0..4).map(|j| if knots[j] <= *t && *t < knots[j + 1] { int(1) } else { int(0) }).collect();
    for p in 1..=3 {
        basis = (0..4 - p)
            .map(|j| {
                let left = &(&(t - &knots[j]) / &(&knots[j + p] - &knots[j])) * &basis[j];
                let right = &(&(&knots[j + p + 1] - t) / &(&knots[j + p + 1] - &knots[j + 1])) * &basis[j + 1];
                &left + &right
            })
            .collect();
    }
    basis.swap_remove(0)
}

#[test]
fn non_uniform_cubic_bspline_matches_cox_de_boor() {
    // x ↦ t: the uniform parameter of the refined points to the B-spline's knot parameter.
    let t_of = |x: &Rational| if *x < Rational::zero() { &int(2) * x } else { x.clone() };
    for n in 1..=8u32 {
        let grid = NonUniformCubicGrid::new(n).unwrap();
        for i in -6..=6i64 {
            let knots: [Rational; 5] = std::array::from_fn(|q| NonUniformCubicGrid::knot(i - 2 + q as i64));
            for k in -8 * i64::from(n)..=8 * i64::from(n) {
                let x = r(k, i64::from(n));
                assert_eq!(grid.basis(i, k), cox_de_boor(&knots, &t_of(&x)), "N_{i} at x = {x}, n = {n}");
            }
        }
    }
}

#[test]
fn non_uniform_grid_agrees_with_de_boor_evaluation() {
    // An open curve on the knots t_{-8..=8}: the point of p_i = e_i is N_i.
    let knots: Vec<f64> = (-9..=9).map(|i| NonUniformCubicGrid::knot(i).to_f64()).collect();
    let intervals: Vec<f64> = knots.windows(2).map(|w| w[1] - w[0]).collect();
    let grid = NonUniformCubicGrid::new(5).unwrap();
    for i in -3..=3i64 {
        let mut points = vec![DVec3::ZERO; 17];
        points[(i + 8) as usize] = DVec3::X;
        let curve = NonUniformCubicBSpline::open(points, intervals.clone()).unwrap();
        // Knots start at τ_0 = 0 for p_{-8}: shift the parameter by t_{-8} = -16.
        let shift = knots[1];
        for k in -15..=15 {
            let x = k as f64 / 5.0;
            let t = if x < 0.0 { 2.0 * x } else { x };
            let value = curve.evaluate(t - shift).unwrap().x;
            assert!((grid.basis(i, k).to_f64() - value).abs() < 1e-13, "N_{i}({t})");
        }
    }
}

#[test]
fn typed_errors() {
    let four = scheme("four-point");
    assert!(matches!(basis_grid(&four, 0), Err(StencilError::Rate { rate: 0, .. })));
    assert!(matches!(basis_grid(&four, MAX_CURVE_RATE + 1), Err(StencilError::Rate { .. })));
    let mask = ExactMask::from_scheme(&four).unwrap();
    assert!(matches!(EigenGrid::new(&mask, 0), Err(StencilError::Rate { .. })));
    assert!(matches!(NonUniformCubicGrid::new(0), Err(StencilError::Rate { .. })));
    // A weight that is no small fraction.
    let x = std::f64::consts::SQRT_2 / 10.0;
    let odd = CurveScheme::new("sqrt2", 2, 2, vec![0.25 + x, 0.75, 0.75 - x, 0.25]).unwrap();
    let error = basis_grid(&odd, 3).unwrap_err();
    assert!(matches!(error, StencilError::CurveMaskNotRational { index: 0, .. }), "{error}");
    assert!(error.to_string().contains("sqrt2"));
    // Rules that do not sum to 1 exactly (the f64 check of CurveScheme allows 1e-12).
    let weights = vec![r(1, 2), int(1), r(1, 2) + r(1, 1 << 50)];
    assert!(matches!(ExactMask::new("off", 2, -1, weights), Err(StencilError::CurveMaskRuleSum { residue: 1, .. })));
    assert!(matches!(ExactMask::new("zero", 2, 0, vec![int(0)]), Err(StencilError::CurveMaskShape { .. })));
    assert!(matches!(ExactMask::new("unary", 1, 0, vec![int(1)]), Err(StencilError::CurveMaskShape { .. })));
    let far = ExactMask::new("far", 2, i64::MAX, vec![int(1), int(1)]);
    assert!(matches!(far, Err(StencilError::CurveMaskShape { .. })));
    // The box function (mask 1, 1): φ(0) and φ(1) are not pinned down at the integers.
    let haar = ExactMask::new("box", 2, 0, vec![int(1), int(1)]).unwrap();
    let error = BasisGrid::new(&haar, 1).unwrap_err();
    assert!(matches!(&error, StencilError::CurveScalingSystem { quantity: "positions", .. }), "{error}");
    // The hat function is C0 only: its derivative system has no unique solution.
    let hat = ExactMask::new("hat", 2, -1, vec![r(1, 2), int(1), r(1, 2)]).unwrap();
    let error = BasisGrid::new(&hat, 3).unwrap_err();
    assert!(matches!(&error, StencilError::CurveScalingSystem { quantity: "derivatives", .. }), "{error}");
}

#[test]
fn ternary_schemes_work_too() {
    // The ternary cubic B-spline, mask (1 + z + z²)⁴ / 27: the centred cubic B-spline again.
    let weights: Vec<Rational> = [1, 4, 10, 16, 19, 16, 10, 4, 1].iter().map(|&w| r(w, 27)).collect();
    let mask = ExactMask::new("ternary-cubic", 3, -4, weights).unwrap();
    assert_eq!(mask.support(), (int(-2), int(2)));
    for n in 1..=7u32 {
        let grid = BasisGrid::new(&mask, n).unwrap();
        for k in -2 * i64::from(n)..=2 * i64::from(n) {
            let (value, slope) = cubic(&r(k, i64::from(n)));
            assert_eq!(grid.value(k), value);
            assert_eq!(grid.derivative(k), slope);
        }
        let eigen = EigenGrid::new(&mask, n).unwrap();
        for (exact, float) in grid.phi_f64().iter().zip(&eigen.phi) {
            assert!((exact - float).abs() < 1e-12);
        }
    }
}

proptest! {
    #[test]
    fn rational_round_trips_f64(x in proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO) {
        let exact = Rational::from_f64(x).unwrap();
        prop_assert_eq!(exact.to_f64(), x);
    }

    #[test]
    fn rational_field_laws(a in -1000i64..1000, b in 1i64..1000, c in -1000i64..1000, d in 1i64..1000) {
        let (x, y) = (r(a, b), r(c, d));
        prop_assert_eq!(&(&x + &y) - &y, x.clone());
        prop_assert_eq!(&(&x * &y) + &x, &x * &(&y + &int(1)));
        if !y.is_zero() {
            prop_assert_eq!(&(&x / &y) * &y, x.clone());
        }
        prop_assert_eq!(x < y, (a as f64 / b as f64) < (c as f64 / d as f64) && x != y);
        prop_assert_eq!(Rational::approximate(x.to_f64(), 1000), Some(x));
    }

    #[test]
    fn stencils_sum_to_one_anywhere(which in 0usize..5, n in 1u32..=24, j in -100i64..100) {
        let grid = basis_grid(&scheme(CurveScheme::BUILTIN_NAMES[which]), n).unwrap();
        let s = grid.stencil_at(j);
        prop_assert_eq!(s.position.iter().map(|(_, w)| w).sum::<Rational>(), Rational::one());
        prop_assert!(s.tangent.iter().map(|(_, w)| w).sum::<Rational>().is_zero());
    }
}

/// The built-in file `nonuniform-cubic-bspline` is paper §2's scheme: its matrix near the
/// origin is knot insertion's, and its basis values (exact fractions) are those of the grid
/// from knot insertion's rows, which the tests above hold to the B-splines.
#[test]
fn the_non_uniform_file_is_the_papers_scheme() {
    use subdiv_schemes::LocalCurveScheme;
    use subdiv_stencil::curve::LocalCurveGrid;
    let file = LocalCurveScheme::builtin("nonuniform-cubic-bspline").unwrap();
    let derived = NonUniformCubicGrid::scheme();
    assert_eq!(file.rows(), derived.rows());
    let m = NonUniformCubicGrid::local_matrix();
    for (r, row) in m.iter().enumerate() {
        for (c, entry) in row.iter().enumerate() {
            let w = file.weight(r as i64 - 2, c as i64 - 2);
            // The file's fractions read as the nearest doubles; the grids below (solved in
            // fractions recovered from them) are equal exactly.
            assert_eq!(w, entry.to_f64(), "row {r} column {c}");
        }
    }
    for n in 1..=6u32 {
        let grid = LocalCurveGrid::new(&file, n).unwrap();
        let knots = NonUniformCubicGrid::new(n).unwrap();
        assert_eq!(&grid, knots.grid(), "n = {n}");
    }
}
