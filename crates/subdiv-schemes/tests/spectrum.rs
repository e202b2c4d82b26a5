//! The derived one-ring and sub-patch matrices have the subdominant eigenvalues known in
//! closed form.

use std::f64::consts::PI;

use subdiv_mesh::BoundaryInterpolation;
use subdiv_schemes::{
    Analysis, Builtin, Centre, LocalMatrix, LocalSpectrum, PatchMatrices, PatchType, Scheme, SchemeError,
};

/// The derived matrices of `builtin` pass the spectral conditions at k = 3..=64 and their
/// subdominant eigenvalue is `closed_form(k)` to 1e-12: the one-ring matrix, and the square
/// matrix of the sub-patch at the extraordinary corner (after a simple eigenvalue 1).
fn assert_subdominant(builtin: Builtin, closed_form: impl Fn(f64) -> f64) {
    let modulus = |z: &(f64, f64)| z.0.hypot(z.1);
    for k in 3..=64 {
        let expected = closed_form(k as f64);
        let spectrum = LocalSpectrum::of(builtin.scheme(), k).unwrap();
        assert!(
            (spectrum.subdominant() - expected).abs() < 1e-12,
            "{builtin} k = {k}: {} vs {expected}",
            spectrum.subdominant()
        );
        assert!(spectrum.passes(), "{builtin} k = {k}");

        let patch_type = PatchType::interior(k);
        let m = PatchMatrices::of(builtin.scheme(), patch_type, BoundaryInterpolation::EdgeOnly).unwrap();
        let (_, keeping) = m.keeping(0).expect("the extraordinary child keeps the shape");
        let values = keeping.eigenvalues().unwrap();
        assert!((values[0].0 - 1.0).abs() < 1e-12 && values[0].1.abs() < 1e-12, "{builtin} k = {k}: {values:?}");
        assert!(modulus(&values[1]) < 1.0 - 1e-9, "{builtin} k = {k}: 1 is not simple");
        assert!((modulus(&values[1]) - expected).abs() < 1e-12, "{builtin} k = {k}: {:?} vs {expected}", values[1]);
    }
}

#[test]
fn catmull_clark_subdominant_eigenvalue_matches_the_closed_form() {
    assert_subdominant(Builtin::CatmullClark, |k| {
        let c = (2.0 * PI / k).cos();
        (5.0 + c + (PI / k).cos() * (18.0 + 2.0 * c).sqrt()) / 16.0
    });
}

#[test]
fn loop_subdominant_eigenvalue_matches_the_closed_form() {
    assert_subdominant(Builtin::Loop, |k| 0.375 + (2.0 * PI / k).cos() / 4.0);
}

#[test]
fn local_matrix_rows_sum_to_one_and_valence_below_3_is_refused() {
    for scheme in Builtin::ALL.map(Builtin::scheme) {
        for k in [3, 4, 7] {
            let m = LocalMatrix::around(scheme, k).unwrap();
            for r in 0..m.size() {
                let sum: f64 = (0..m.size()).map(|c| m.get(r, c)).sum();
                assert!((sum - 1.0).abs() < 1e-13, "{scheme} k = {k} row {r}");
            }
        }
        assert!(matches!(LocalMatrix::around(scheme, 2), Err(SchemeError::ValenceNotSupported { valence: 2, .. })));
    }
}

/// The derived rules of the Schaefer-Warren quad scheme keep it C1 at every valence 3..=16:
/// spectrum and characteristic map (see the crate docs for the derivation).
#[test]
fn sw_quad_is_c1_at_valences_3_to_16() {
    for k in 3..=16 {
        let analysis = Analysis::of(Builtin::SwQuad.scheme(), k).unwrap();
        assert!(analysis.is_c1(), "k = {k}: {analysis:?}");
        // The subdominant eigenvalue comes from the edge and face rules alone (crate docs):
        // the larger root of x² − (7/12 + cos(2π/k)/6)·x + 1/24.
        let t = 7.0 / 12.0 + (2.0 * PI / k as f64).cos() / 6.0;
        let expected = (t + (t * t - 1.0 / 6.0).sqrt()) / 2.0;
        assert!((analysis.spectrum.subdominant() - expected).abs() < 1e-12, "k = {k}");
    }
}

/// The verdict separates smooth schemes from others: Catmull-Clark, Loop and the other
/// smooth built-ins are C1 at valences 3, 5 and 8; bilinear is not.
#[test]
fn c1_verdicts() {
    for b in
        [Builtin::CatmullClark, Builtin::Loop, Builtin::DooSabin, Builtin::Sqrt3, Builtin::Butterfly, Builtin::Kobbelt]
    {
        for k in [3, 5, 8] {
            let analysis = Analysis::of(b.scheme(), k).unwrap();
            assert!(analysis.is_c1(), "{b} k = {k}: {analysis:?}");
        }
    }
    let bilinear = Analysis::of(Builtin::Bilinear.scheme(), 5).unwrap();
    assert!(!bilinear.spectrum.subdominant_strict && !bilinear.is_c1());
}

/// Boundary vertices: an eigenvector that is odd across the boundary vanishes on it, where the
/// boundary rule and the interior rules of the mirrored mesh agree, so the largest interior
/// eigenvalue of valence `2f` is the cross-boundary one at `f` faces; the boundary curve's `1/2`
/// is there too (Catmull-Clark, Loop and sw-quad, whose boundaries are cubic B-splines). The
/// regular boundary is C1 for every scheme with boundary rules but bilinear; the dual split
/// has none, which is a typed error.
#[test]
fn boundary_vertices_have_the_mirrored_interior_eigenvalues() {
    // 1e-7: where the two coincide (Loop at 6 faces: 1/2 twice, defective) they split by ~√ε.
    let has = |values: &[(f64, f64)], x: f64| values.iter().any(|z| (z.0 - x).abs() < 1e-7 && z.1.abs() < 1e-6);
    for b in [Builtin::CatmullClark, Builtin::Loop, Builtin::SwQuad] {
        for faces in 2..=6 {
            let boundary = LocalSpectrum::at(b.scheme(), Centre::Boundary(faces)).unwrap();
            let interior = LocalSpectrum::of(b.scheme(), 2 * faces).unwrap();
            assert!(has(&boundary.eigenvalues, interior.subdominant()), "{b}, {faces} faces: {boundary:?}");
            assert!(has(&boundary.eigenvalues, 0.5), "{b}, {faces} faces: no 1/2");
        }
    }
    let regular = [
        (Builtin::CatmullClark, 2),
        (Builtin::SwQuad, 2),
        (Builtin::Kobbelt, 2),
        (Builtin::Loop, 3),
        (Builtin::Butterfly, 3),
    ];
    for (b, faces) in regular {
        let analysis = Analysis::at(b.scheme(), Centre::Boundary(faces)).unwrap();
        assert!(analysis.is_c1(), "{b}, {faces} faces: {analysis:?}");
        assert_eq!(analysis.characteristic_map.as_ref().map(|m| m.outlines), Some(1));
    }
    assert!(!Analysis::at(Builtin::Bilinear.scheme(), Centre::Boundary(2)).unwrap().is_c1());
    let closed_only =
        Scheme::from_toml_str("name = \"x\"\n[rules.dual]\nown = \"1/4\"\ncorner = \"(3 + 2*cos(2*pi*j/n))/(4*n)\"\n")
            .unwrap();
    let err = Analysis::at(&closed_only, Centre::Boundary(2)).unwrap_err();
    assert!(matches!(err, SchemeError::FeatureNotSupported { feature: "boundaries", .. }), "{err}");
}

/// The boundary rules of the splits that do not keep old vertices: Chaikin's along the
/// boundary of Doo-Sabin and mid-edge (its `1/2` at a regular boundary vertex, and `1/2` with
/// the boundary vertex's face at three faces or more), the ternary cubic B-spline's `1/3` per
/// two √3 steps; the regular boundary vertex is C1 under all three. The cross-boundary
/// eigenvalue is not the mirrored interior's (the boundary rules are not the interior rules
/// of a mirrored mesh): `3/4` at Doo-Sabin's regular boundary vertex.
#[test]
fn dual_and_sqrt3_boundary_rules_refine_the_boundary_curve() {
    let has = |values: &[(f64, f64)], x: f64| values.iter().any(|z| (z.0 - x).abs() < 1e-9 && z.1.abs() < 1e-9);
    for (b, curve) in [(Builtin::DooSabin, 0.5), (Builtin::Midedge, 0.5), (Builtin::Sqrt3, 1.0 / 3.0)] {
        for faces in 2..=4 {
            let spectrum = LocalSpectrum::at(b.scheme(), Centre::Boundary(faces)).unwrap();
            assert!(has(&spectrum.eigenvalues, curve), "{b}, {faces} faces: {spectrum:?}");
        }
        let regular = if b == Builtin::Sqrt3 { 3 } else { 2 };
        let analysis = Analysis::at(b.scheme(), Centre::Boundary(regular)).unwrap();
        assert!(analysis.is_c1(), "{b}, {regular} faces: {analysis:?}");
    }
    let doo_sabin = LocalSpectrum::at(Builtin::DooSabin.scheme(), Centre::Boundary(2)).unwrap();
    assert!((doo_sabin.subdominant() - 0.75).abs() < 1e-9, "{doo_sabin:?}");
}
