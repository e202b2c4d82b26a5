//! Exact surface stencils: the bicubic B-spline in fractions on the regular Catmull-Clark patch,
//! agreement with the floating-point route, and a typed refusal where the matrices are not
//! rational.

use num_integer::Integer;
use subdiv_mesh::BoundaryInterpolation;
use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
use subdiv_stencil::{Dyadic, Rational, StencilError, exact_surface_stencil, surface_stencil};

const EDGE_ONLY: BoundaryInterpolation = BoundaryInterpolation::EdgeOnly;

fn r(p: i64, q: i64) -> Rational {
    Rational::new(p, q).unwrap()
}

/// The uniform cubic B-spline's four pieces at t and their derivatives, exactly.
fn bspline(t: &Rational) -> ([Rational; 4], [Rational; 4]) {
    let one = Rational::one();
    let s = &one - t;
    let (t2, t3) = (t * t, &(t * t) * t);
    let values = [
        &(&(&s * &s) * &s) * &r(1, 6),
        &(&(&(&t3 * &r(3, 1)) - &(&t2 * &r(6, 1))) + &r(4, 1)) * &r(1, 6),
        &(&(&(&(&t3 * &r(-3, 1)) + &(&t2 * &r(3, 1))) + &(t * &r(3, 1))) + &one) * &r(1, 6),
        &t3 * &r(1, 6),
    ];
    let derivatives = [
        -(&(&s * &s) * &r(1, 2)),
        &(&(&t2 * &r(3, 1)) - &(t * &r(4, 1))) * &r(1, 2),
        &(&(&(&t2 * &r(-3, 1)) + &(t * &r(2, 1))) + &one) * &r(1, 2),
        &t2 * &r(1, 2),
    ];
    (values, derivatives)
}

#[test]
fn regular_catmull_clark_is_the_bicubic_b_spline_in_fractions() {
    let cc = Builtin::CatmullClark.scheme();
    let m = PatchMatrices::of(cc, PatchType::regular(cc), EDGE_ONLY).unwrap();
    let [pu, pv] = m.shapes[0].parameters.clone().unwrap();
    for n in [3, 5, 7] {
        for (a, b) in [(1, 0), (1, 1), (2, 1), (n - 1, 2)] {
            let s = exact_surface_stencil(&m, 0, Dyadic::new(a, b, n)).unwrap();
            let [du, dv] = s.derivatives.clone().unwrap();
            let ((bu, dbu), (bv, dbv)) = (bspline(&r(a, n)), bspline(&r(b, n)));
            for k in 0..m.shapes[0].size {
                // Control point k sits at integer (i, j) in −1..=2: B-spline piece i + 1.
                let (i, j) = (pu[k].round() as i64, pv[k].round() as i64);
                let (x, y) = ((i + 1) as usize, (j + 1) as usize);
                assert_eq!(s.position[k], &bu[x] * &bv[y], "({a}, {b})/{n}, point {k}");
                assert_eq!(du[k], &dbu[x] * &bv[y], "∂u at ({a}, {b})/{n}, point {k}");
                assert_eq!(dv[k], &bu[x] * &dbv[y], "∂v at ({a}, {b})/{n}, point {k}");
            }
        }
    }
}

#[test]
fn exact_stencils_equal_the_floating_point_ones() {
    let cases = [
        (Builtin::CatmullClark, PatchType::interior(5)),
        // Valence 8 reproduces linear functions (½ is an eigenvalue) but has no derivative at the
        // vertex: both routes must say so.
        (Builtin::CatmullClark, PatchType::interior(8)),
        (Builtin::CatmullClark, PatchType::boundary(3, 1)),
        (Builtin::SwQuad, PatchType::interior(5)),
        (Builtin::Loop, PatchType::interior(3)),
        (Builtin::Butterfly, PatchType::interior(4)),
    ];
    for (builtin, patch_type) in cases {
        let m = PatchMatrices::of(builtin.scheme(), patch_type, EDGE_ONLY).unwrap();
        let triangle = m.face_size == 3;
        for p in [(0, 0, 1), (1, 0, 3), (1, 1, 3), (2, 1, 5), (3, 2, 7), (1, 4, 12)] {
            let point = Dyadic::new(p.0, p.1, p.2);
            if triangle && point.u + point.v > point.denominator {
                continue;
            }
            let exact = exact_surface_stencil(&m, 0, point).unwrap();
            let float = surface_stencil(&m, 0, point).unwrap();
            let what = format!("{builtin} {patch_type:?} at {point:?}");
            assert_eq!(exact.position.iter().sum::<Rational>(), Rational::one(), "{what}");
            let close = |e: &[Rational], f: &[f64]| e.iter().zip(f).all(|(e, f)| (e.to_f64() - f).abs() < 1e-12);
            assert!(close(&exact.position, &float.position), "{what}");
            match exact.derivatives {
                Some([du, dv]) => {
                    assert!(float.exact_derivatives && close(&du, &float.du) && close(&dv, &float.dv), "{what}");
                    assert!(du.iter().sum::<Rational>().is_zero(), "{what}");
                }
                None => assert!(!float.exact_derivatives, "{what}"),
            }
        }
    }
}

/// Fig. 6's first stencil (sw-quad, valence 5, at (1/3, 0)) over its common denominator.
#[test]
fn sw_quad_figure_6_denominator() {
    let m = PatchMatrices::of(Builtin::SwQuad.scheme(), PatchType::interior(5), EDGE_ONLY).unwrap();
    let s = exact_surface_stencil(&m, 0, Dyadic::new(1, 0, 3)).unwrap();
    let common = s.position.iter().fold(num_bigint::BigInt::from(1), |l, w| l.lcm(w.denom()));
    assert_eq!(common, num_bigint::BigInt::from(52200));
}

#[test]
fn irrational_matrices_are_refused() {
    // Loop's weights at valence 5 involve cos(2π/5).
    let m = PatchMatrices::of(Builtin::Loop.scheme(), PatchType::interior(5), EDGE_ONLY).unwrap();
    let error = exact_surface_stencil(&m, 0, Dyadic::new(1, 1, 3)).unwrap_err();
    assert!(matches!(error, StencilError::NotRational { .. }), "{error}");
}
