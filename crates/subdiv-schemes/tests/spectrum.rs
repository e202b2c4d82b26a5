//! The derived one-ring matrices have the subdominant eigenvalues known in closed form.

use std::f64::consts::PI;

use subdiv_schemes::{LocalMatrix, Scheme, SchemeError, Spectrum};

#[test]
fn catmull_clark_subdominant_eigenvalue_matches_the_closed_form() {
    for k in 3..=64 {
        let c = (2.0 * PI / k as f64).cos();
        let expected = (5.0 + c + (PI / k as f64).cos() * (18.0 + 2.0 * c).sqrt()) / 16.0;
        let spectrum = Spectrum::of(Scheme::CatmullClark, k).unwrap();
        assert!((spectrum.subdominant() - expected).abs() < 1e-12, "k = {k}: {} vs {expected}", spectrum.subdominant());
        assert!(
            spectrum.unit_dominant_simple && spectrum.subdominant_real_double && spectrum.subdominant_strict,
            "k = {k}"
        );
    }
}

#[test]
fn loop_subdominant_eigenvalue_matches_the_closed_form() {
    for k in 3..=64 {
        let expected = 0.375 + (2.0 * PI / k as f64).cos() / 4.0;
        let spectrum = Spectrum::of(Scheme::Loop, k).unwrap();
        assert!((spectrum.subdominant() - expected).abs() < 1e-12, "k = {k}: {} vs {expected}", spectrum.subdominant());
        assert!(
            spectrum.unit_dominant_simple && spectrum.subdominant_real_double && spectrum.subdominant_strict,
            "k = {k}"
        );
    }
}

#[test]
fn one_ring_rows_sum_to_one_and_valence_below_3_is_refused() {
    for scheme in Scheme::ALL {
        for k in [3, 4, 7] {
            let m = LocalMatrix::one_ring(scheme, k).unwrap();
            for r in 0..m.size() {
                let sum: f64 = (0..m.size()).map(|c| m.get(r, c)).sum();
                assert!((sum - 1.0).abs() < 1e-14, "{scheme} k = {k} row {r}");
            }
        }
        assert!(matches!(LocalMatrix::one_ring(scheme, 2), Err(SchemeError::ValenceNotSupported { valence: 2, .. })));
    }
}
