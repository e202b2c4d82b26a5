//! Curve schemes: the built-ins as data (serde round trips, typed errors), affine invariance,
//! interpolation, open refinement as a slice of closed refinement, the cubic B-spline as knot
//! insertion, the non-uniform cubic B-spline against Boehm's knot insertion and Cox–de Boor
//! evaluation (Schaefer–Warren §2), and the derived local matrices and their spectra.

use glam::{DMat3, DVec3};
use proptest::prelude::*;
use subdiv_schemes::{CurveError, CurveScheme, LocalCurveScheme, NonUniformCubicBSpline, PolygonKind};

fn builtins() -> Vec<CurveScheme> {
    CurveScheme::BUILTIN_NAMES.iter().map(|name| CurveScheme::builtin(name).unwrap()).collect()
}

fn point() -> impl Strategy<Value = DVec3> {
    (-100.0..100.0f64, -100.0..100.0f64, -100.0..100.0f64).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn polygon(sizes: std::ops::Range<usize>) -> impl Strategy<Value = Vec<DVec3>> {
    prop::collection::vec(point(), sizes)
}

fn affine() -> impl Strategy<Value = (DMat3, DVec3)> {
    (prop::array::uniform9(-2.0..2.0f64), point()).prop_map(|(m, t)| (DMat3::from_cols_array(&m), t))
}

/// A polygon with knot intervals for a closed (`n`) or open (`n + 1`) non-uniform curve.
fn knotted(kind: PolygonKind, sizes: std::ops::Range<usize>) -> impl Strategy<Value = NonUniformCubicBSpline> {
    polygon(sizes)
        .prop_flat_map(move |points| {
            let count = points.len() + usize::from(kind == PolygonKind::Open);
            (Just(points), prop::collection::vec(0.2..3.0f64, count))
        })
        .prop_map(move |(points, intervals)| NonUniformCubicBSpline::new(kind, points, intervals).unwrap())
}

fn max_norm(points: &[DVec3]) -> f64 {
    points.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max)
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| (*p - *q).abs().max_element()).fold(0.0, f64::max)
}

/// `A·p + t`, with the scale of the error this can carry.
fn map(points: &[DVec3], (a, t): (DMat3, DVec3)) -> Vec<DVec3> {
    points.iter().map(|&p| a * p + t).collect()
}

fn affine_scale(points: &[DVec3], (a, t): (DMat3, DVec3)) -> f64 {
    1.0 + max_norm(points) * (1.0 + 3.0 * a.to_cols_array().iter().fold(0.0f64, |m, x| m.max(x.abs())))
        + t.abs().max_element()
}

#[test]
fn every_builtin_is_valid_and_named() {
    for name in CurveScheme::BUILTIN_NAMES {
        let scheme = CurveScheme::builtin(name).unwrap();
        assert_eq!(scheme.name(), name);
        assert_eq!(scheme.to_string(), name);
        assert_eq!(scheme.arity(), 2);
        // Re-validated from its parts.
        let again = CurveScheme::new(name, scheme.arity(), scheme.offset(), scheme.mask().to_vec()).unwrap();
        assert_eq!(again, scheme);
    }
    assert!(CurveScheme::builtin("loop").is_none());
    assert!(CurveScheme::builtin(NonUniformCubicBSpline::NAME).is_none());
}

#[test]
fn every_builtin_round_trips_through_toml_and_ron() {
    for scheme in builtins() {
        let toml = scheme.to_toml_string().unwrap();
        assert_eq!(CurveScheme::from_toml_str(&toml).unwrap(), scheme, "{toml}");
        let ron = scheme.to_ron_string().unwrap();
        assert_eq!(CurveScheme::from_ron_str(&ron).unwrap(), scheme, "{ron}");
        // Plain serde deserialization validates too.
        assert_eq!(toml::from_str::<CurveScheme>(&toml).unwrap(), scheme);
        assert_eq!(ron::from_str::<CurveScheme>(&ron).unwrap(), scheme);
        // Bit for bit, weights such as 1/6 included.
        let back = CurveScheme::from_toml_str(&toml).unwrap();
        assert!(back.mask().iter().zip(scheme.mask()).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}

#[test]
fn malformed_files_and_bad_masks_give_typed_errors() {
    let toml = |text: &str| CurveScheme::from_toml_str(text);
    // Syntax, a missing field, an unknown field, a weight that is no number, a negative offset.
    assert!(matches!(toml("name = \"x\" offset = 1"), Err(CurveError::Toml(_))));
    assert!(matches!(toml("name = \"x\"\nmask = [1]"), Err(CurveError::Toml(_))));
    assert!(matches!(toml("name = \"x\"\noffset = 0\nmask = [1, 1]\ncolour = 3"), Err(CurveError::Toml(_))));
    let bad_weight = toml("name = \"x\"\noffset = 1\nmask = [\"1/2\", 1, \"1/x\"]").unwrap_err();
    assert!(matches!(bad_weight, CurveError::Toml(_)));
    assert!(bad_weight.to_string().contains("`1/x`"), "{bad_weight}");
    assert!(matches!(toml("name = \"x\"\noffset = -1\nmask = [1, 1]"), Err(CurveError::Toml(_))));
    assert!(matches!(CurveScheme::from_ron_str("(name: \"x\", offset: 1"), Err(CurveError::Ron(_))));
    assert!(matches!(CurveScheme::from_ron_str("(name: \"x\", offset: 1, mask: [true])"), Err(CurveError::Ron(_))));

    // The rules: the odd rule of this mask sums to 3/4.
    match toml("name = \"lopsided\"\noffset = 1\nmask = [\"1/2\", 1, \"1/4\"]") {
        Err(CurveError::RuleSum { scheme, arity: 2, residue: 1, sum }) => {
            assert_eq!((scheme.as_str(), sum), ("lopsided", 0.75));
        }
        other => panic!("{other:?}"),
    }
    // The even rule (children 2i) of this one sums to 2.
    assert!(matches!(
        CurveScheme::new("heavy", 2, 1, vec![0.5, 2.0, 0.5]),
        Err(CurveError::RuleSum { residue: 0, sum: 2.0, .. })
    ));
    assert!(matches!(CurveScheme::new("unary", 1, 0, vec![1.0]), Err(CurveError::Arity { arity: 1, .. })));
    assert!(matches!(CurveScheme::new("wide", 17, 0, vec![1.0; 17]), Err(CurveError::Arity { arity: 17, .. })));
    assert!(matches!(
        CurveScheme::new("far", 2, 3, vec![0.5, 1.0, 0.5]),
        Err(CurveError::Offset { offset: 3, len: 3, .. })
    ));
    assert!(matches!(CurveScheme::new("empty", 2, 0, vec![]), Err(CurveError::Offset { len: 0, .. })));
    assert!(matches!(
        toml("name = \"x\"\noffset = 1\nmask = [0.5, nan, 0.5]"),
        Err(CurveError::NonFiniteWeight { index: 1, .. })
    ));
    // Through plain serde, the same rule comes back in the message.
    let message =
        toml::from_str::<CurveScheme>("name = \"x\"\noffset = 1\nmask = [0.5, 1, 0.25]").unwrap_err().to_string();
    assert!(message.contains("sums to 0.75"), "{message}");
}

#[test]
fn nonuniform_curves_check_their_knot_intervals() {
    let points = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    assert!(matches!(
        NonUniformCubicBSpline::closed(points.clone(), vec![1.0; 5]),
        Err(CurveError::KnotCount { kind: PolygonKind::Closed, points: 4, intervals: 5, expected: 4 })
    ));
    assert!(matches!(
        NonUniformCubicBSpline::open(points.clone(), vec![1.0; 4]),
        Err(CurveError::KnotCount { kind: PolygonKind::Open, expected: 5, .. })
    ));
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            NonUniformCubicBSpline::closed(points.clone(), vec![1.0, 1.0, bad, 1.0]),
            Err(CurveError::KnotInterval { index: 2, .. })
        ));
    }
    // Short open curves refine to nothing, and stay consistent.
    let two = NonUniformCubicBSpline::open(points[..2].to_vec(), vec![1.0; 3]).unwrap();
    let one = two.refine();
    assert_eq!((one.points().len(), one.intervals().len()), (1, 2));
    let none = one.refine();
    assert_eq!((none.points().len(), none.intervals().len()), (0, 1));
    assert_eq!(none.refine().points().len(), 0);
    assert!(none.domain().is_none() && none.evaluate(0.0).is_none() && none.limit_points().is_empty());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn refinement_is_affine_invariant(points in polygon(1..24), f in affine()) {
        let scale = affine_scale(&points, f);
        for scheme in builtins() {
            for kind in [PolygonKind::Closed, PolygonKind::Open] {
                let refined_then_mapped = map(&scheme.refine_levels(&points, 2, kind), f);
                let mapped_then_refined = scheme.refine_levels(&map(&points, f), 2, kind);
                let error = max_distance(&refined_then_mapped, &mapped_then_refined);
                prop_assert!(error <= 1e-12 * scale, "{scheme} {kind}: {error} at scale {scale}");
            }
        }
    }

    #[test]
    fn nonuniform_refinement_is_affine_invariant(
        curve in prop_oneof![knotted(PolygonKind::Closed, 1..16), knotted(PolygonKind::Open, 2..16)],
        f in affine(),
    ) {
        let scale = affine_scale(curve.points(), f);
        let mapped = NonUniformCubicBSpline::new(curve.kind(), map(curve.points(), f), curve.intervals().to_vec()).unwrap();
        let error = max_distance(&map(curve.refine_levels(2).points(), f), mapped.refine_levels(2).points());
        prop_assert!(error <= 1e-12 * scale, "{error} at scale {scale}");
    }

    #[test]
    fn interpolating_schemes_keep_the_old_points(points in polygon(1..24)) {
        for scheme in builtins() {
            let interpolating = matches!(scheme.name(), "four-point" | "six-point");
            prop_assert_eq!(scheme.is_interpolating(), interpolating, "{}", scheme);
            if !interpolating {
                continue;
            }
            let closed = scheme.refine_closed(&points);
            for (j, p) in points.iter().enumerate() {
                prop_assert_eq!(closed[2 * j], *p);
            }
            let children = scheme.open_children(points.len());
            for (child, q) in children.zip(scheme.refine_open(&points)) {
                if child % 2 == 0 {
                    prop_assert_eq!(q, points[(child / 2) as usize]);
                }
            }
        }
    }

    /// Open refinement keeps exactly the children of closed refinement that do not wrap around.
    #[test]
    fn open_refinement_is_a_slice_of_closed_refinement(points in polygon(1..24)) {
        for scheme in builtins() {
            let closed = scheme.refine_closed(&points);
            let open = scheme.refine_open(&points);
            let children = scheme.open_children(points.len());
            prop_assert_eq!(open.len(), children.clone().count());
            // Cubic B-spline: 2n - 3 children; four-point: 2n - 5; Chaikin: 2n - 2.
            let expected = match scheme.name() {
                "cubic-bspline" | "sw-curve" => 2 * points.len() as i64 - 3,
                "chaikin" => 2 * points.len() as i64 - 2,
                "four-point" => 2 * points.len() as i64 - 5,
                _ => 2 * points.len() as i64 - 9,
            };
            prop_assert_eq!(open.len() as i64, expected.max(0));
            for (child, q) in children.zip(&open) {
                prop_assert_eq!(closed[child.rem_euclid(closed.len() as i64) as usize], *q);
            }
        }
    }

    /// `cubic-bspline` is midpoint knot insertion on the uniform cubic B-spline: the non-uniform
    /// curve with equal knot intervals gives the same bits, closed and open.
    #[test]
    fn cubic_bspline_is_uniform_knot_insertion(points in polygon(1..20), interval in 0.1..10.0f64) {
        let cubic = CurveScheme::builtin("cubic-bspline").unwrap();
        let n = points.len();
        let closed = NonUniformCubicBSpline::closed(points.clone(), vec![1.0; n]).unwrap();
        let open = NonUniformCubicBSpline::open(points.clone(), vec![1.0; n + 1]).unwrap();
        for levels in 0..4 {
            let (closed_knots, open_knots) = (closed.refine_levels(levels), open.refine_levels(levels));
            prop_assert_eq!(closed_knots.points(), &cubic.refine_levels(&points, levels, PolygonKind::Closed)[..]);
            prop_assert_eq!(open_knots.points(), &cubic.refine_levels(&points, levels, PolygonKind::Open)[..]);
        }
        // Any equal intervals: the same to rounding.
        let scaled = NonUniformCubicBSpline::closed(points.clone(), vec![interval; n]).unwrap();
        let error = max_distance(scaled.refine_levels(3).points(), &cubic.refine_levels(&points, 3, PolygonKind::Closed));
        prop_assert!(error <= 1e-13 * (1.0 + max_norm(&points)), "{}", error);
        // And Boehm's algorithm on the uniform knots agrees.
        if n >= 2 {
            let uniform = NonUniformCubicBSpline::open(points.clone(), vec![1.0; n + 1]).unwrap();
            let boehm = boehm_midpoints(&uniform, [1.0, 1.0, 1.0, 1.0], [DVec3::ZERO; 4]);
            let error = max_distance(&cubic.refine_open(&points), &boehm);
            prop_assert!(error <= 1e-12 * (1.0 + max_norm(&points)), "{}", error);
        }
    }

    /// Non-uniform refinement is Boehm's knot insertion at every midpoint.
    #[test]
    fn nonuniform_refinement_is_boehm_knot_insertion(
        curve in knotted(PolygonKind::Open, 2..16),
        pad_intervals in prop::array::uniform4(0.2..3.0f64),
        pad_points in prop::array::uniform4(point()),
    ) {
        let refined = curve.refine();
        let boehm = boehm_midpoints(&curve, pad_intervals, pad_points);
        let error = max_distance(refined.points(), &boehm);
        prop_assert!(error <= 1e-12 * (1.0 + max_norm(curve.points())), "{}", error);
        // Knots: the old ones with the midpoints between them.
        let knots = curve.knots();
        let expected: Vec<f64> = (0..knots.len() - 1)
            .flat_map(|j| [(knots[j] + knots[j + 1]) / 2.0, knots[j + 1]])
            .take(refined.points().len())
            .collect();
        let error = refined.knots().iter().zip(&expected).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        prop_assert!(error < 1e-12, "{:?} vs {:?}", refined.knots(), expected);
    }

    /// The limit points (the non-uniform (1/6, 2/3, 1/6) mask) and de Boor evaluation are the
    /// spline that Cox–de Boor evaluates, at every level of refinement.
    #[test]
    fn nonuniform_limit_points_lie_on_the_cox_de_boor_spline(
        curve in prop_oneof![knotted(PolygonKind::Closed, 1..12), knotted(PolygonKind::Open, 4..12)],
        samples in prop::collection::vec(0.0..1.0f64, 8),
    ) {
        let scale = 1.0 + max_norm(curve.points());
        let (knots, points) = cox_de_boor_form(&curve);
        let mut fine = curve.clone();
        for _ in 0..4 {
            let at_knots: Vec<f64> = match fine.kind() {
                PolygonKind::Closed => fine.knots(),
                PolygonKind::Open => fine.knots()[1..fine.points().len() - 1].to_vec(),
            };
            let expected: Vec<DVec3> = at_knots.iter().map(|&t| cox_de_boor(&knots, &points, t)).collect();
            let error = max_distance(&fine.limit_points(), &expected);
            prop_assert!(error <= 1e-12 * scale, "limit points: {}", error);
            fine = fine.refine();
        }
        let (lo, hi) = curve.domain().unwrap();
        for s in samples {
            let t = lo + s * (hi - lo);
            let expected = cox_de_boor(&knots, &points, t);
            for c in [&curve, &fine] {
                let error = (c.evaluate(t).unwrap() - expected).abs().max_element();
                prop_assert!(error <= 1e-12 * scale, "evaluate({}): {}", t, error);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// The refined control polygons converge to the spline, quadratically in the knot spacing,
    /// when point `j` is compared with the spline at its Greville abscissa
    /// `(τ_{j-1} + τ_j + τ_{j+1}) / 3`. (At its knot `τ_j` the distance shrinks only linearly:
    /// where the intervals on the two sides of an original knot differ, the abscissa and the
    /// knot are a third of their difference apart at every level.)
    #[test]
    fn nonuniform_control_polygons_converge_to_the_spline(
        curve in prop_oneof![knotted(PolygonKind::Closed, 4..8), knotted(PolygonKind::Open, 5..8)],
    ) {
        let scale = 1.0 + max_norm(curve.points());
        let (knots, points) = cox_de_boor_form(&curve);
        let (lo, hi) = curve.domain().unwrap();
        let error_at = |level: usize| {
            let fine = curve.refine_levels(level);
            let n = fine.points().len() as i64;
            let tau = tau(&fine, -1..=n);
            let greville = tau.windows(3).map(|w| (w[0] + w[1] + w[2]) / 3.0);
            // On an open curve the ends lie outside the domain: compare inside it.
            fine.points().iter().zip(greville)
                .filter(|(_, t)| (lo..=hi).contains(t) || fine.kind() == PolygonKind::Closed)
                .map(|(p, t)| (*p - cox_de_boor(&knots, &points, lo + (t - lo).rem_euclid(hi - lo))).abs().max_element())
                .fold(0.0, f64::max)
        };
        let (coarse, fine) = (error_at(6), error_at(8));
        prop_assert!(fine <= 1e-4 * scale, "level 8: {} at scale {}", fine, scale);
        prop_assert!(fine <= coarse / 12.0 + 1e-12 * scale, "levels 6 and 8: {} then {}", coarse, fine);
    }
}

/// Paper 000 §2's matrix (rows: the new points −2..=2; columns: the old points −2..=2).
const PAPER_MATRIX: [[f64; 5]; 5] = [
    [1.0 / 8.0, 25.0 / 32.0, 3.0 / 32.0, 0.0, 0.0],
    [0.0, 5.0 / 8.0, 3.0 / 8.0, 0.0, 0.0],
    [0.0, 5.0 / 24.0, 29.0 / 40.0, 1.0 / 15.0, 0.0],
    [0.0, 0.0, 3.0 / 5.0, 2.0 / 5.0, 0.0],
    [0.0, 0.0, 3.0 / 20.0, 29.0 / 40.0, 1.0 / 8.0],
];

/// The matrix of Schaefer–Warren §2: the non-uniform cubic B-spline refined around a knot with
/// intervals 1 on one side and 2 on the other, restricted to the two-ring of the origin. The
/// paper states the knots as `t_i = i` for `i > 0` and `t_i = 2i` for `i < 0`; its matrix is the
/// one for the mirrored knots (`t_i = 2i` for `i > 0`), which is what we compare with.
#[test]
fn the_nonuniform_matrix_of_the_paper() {
    let paper = PAPER_MATRIX;
    // Points -6..=6; point 0 at knot 0; unit intervals to its left, 2 to its right.
    let (n, centre) = (13usize, 6usize);
    let intervals: Vec<f64> = (0..=n).map(|k| if k <= centre { 1.0 } else { 2.0 }).collect();
    for column in 0..5 {
        let mut points = vec![DVec3::ZERO; n];
        points[centre - 2 + column] = DVec3::X;
        let refined = NonUniformCubicBSpline::open(points, intervals.clone()).unwrap().refine();
        // Open refinement keeps children 1..=2n-3; child i is refined point i - 1.
        for (row, expected) in paper.iter().enumerate() {
            let child = 2 * centre - 2 + row;
            let weight = refined.points()[child - 1].x;
            assert!((weight - expected[column]).abs() < 1e-15, "row {row} column {column}: {weight}");
        }
    }
}

/// The same scheme as a vector-valued one (paper 000 §3): the matrix-mask file gives the paper's
/// 5×5 matrix weight for weight, and is the rows file mirrored; the transcription's garbled
/// entry (4, 3), `z/2 + 29/40 + 1/(8z²)`, is refused by the check that each entry keeps its
/// components.
#[test]
fn the_paper_s_matrix_mask_is_the_nonuniform_scheme() {
    let paper = PAPER_MATRIX;
    let matrix = LocalCurveScheme::builtin("nonuniform-cubic-bspline-matrix").unwrap();
    for (i, row) in paper.iter().enumerate() {
        for (j, &w) in row.iter().enumerate() {
            assert_eq!(matrix.weight(i as i64 - 2, j as i64 - 2), w, "row {i} column {j}");
        }
    }
    let rows = LocalCurveScheme::builtin("nonuniform-cubic-bspline").unwrap();
    for i in -12..=12 {
        for j in -8..=8 {
            assert_eq!(matrix.weight(i, j), rows.weight(-i, -j), "new point {i}, old point {j}");
        }
    }
    let text = LocalCurveScheme::builtin_toml("nonuniform-cubic-bspline-matrix").unwrap();
    let garbled = text.replace(
        "row = 4\ncolumn = 3\nlowest = 0\nweights = [\"29/40\", \"1/2\", \"1/8\"]",
        "row = 4\ncolumn = 3\nlowest = -2\nweights = [\"1/8\", \"0\", \"29/40\", \"1/2\"]",
    );
    assert_ne!(garbled, text);
    let error = LocalCurveScheme::from_toml_str(&garbled).unwrap_err().to_string();
    assert!(error.contains("entry (4, 3) sends old point 1 to new point 0"), "{error}");
    // Both forms at once, or neither: refused.
    let both = format!("offset = 2\n{text}");
    let error = LocalCurveScheme::from_toml_str(&both).unwrap_err().to_string();
    assert!(error.contains("no mask, offset or [[rows]] beside it"), "{error}");
}

/// Eigenvalues as sorted by the library, compared with the expected real values.
fn assert_spectrum_begins(scheme: &CurveScheme, expected: &[f64]) {
    let values = scheme.eigenvalues().unwrap();
    assert!(values.len() >= expected.len(), "{scheme}: {values:?}");
    for (value, e) in values.iter().zip(expected) {
        assert!((value.0 - e).abs() < 1e-12 && value.1.abs() < 1e-12, "{scheme}: {values:?}, expected {expected:?}");
    }
}

#[test]
fn local_matrices_are_derived_and_their_spectra_are_the_known_ones() {
    let scheme = |name| CurveScheme::builtin(name).unwrap();
    // The window: the 2r + 1 points around the vertex for support [-r, r] (Chaikin, whose
    // support is [-2, 1], takes -1..=2).
    for (name, first, size) in [
        ("cubic-bspline", -2, 5),
        ("chaikin", -1, 4),
        ("four-point", -3, 7),
        ("six-point", -5, 11),
        ("sw-curve", -2, 5),
    ] {
        let m = scheme(name).local_matrix();
        assert_eq!((m.first(), m.size()), (first, size), "{name}");
        // Invariant neighbourhood: every row's weights lie in the window and sum to 1.
        for r in 0..m.size() {
            let sum: f64 = (0..m.size()).map(|c| m.get(r, c)).sum();
            assert!((sum - 1.0).abs() < 1e-14, "{name} row {r}: {sum}");
        }
        // The eigenvalues sum to the trace.
        let trace: f64 = (0..m.size()).map(|i| m.get(i, i)).sum();
        let sum: f64 = m.eigenvalues().unwrap().iter().map(|z| z.0).sum();
        assert!((sum - trace).abs() < 1e-12, "{name}: {sum} vs {trace}");
    }

    // sw-curve (paper §5.4): the rows are its two rules, and the spectrum is 1, 1/2, 1/6, 1/6,
    // 1/6 (1/6 is defective: a Jordan block of size 2 beside a simple 1/6).
    let sw = scheme("sw-curve").local_matrix();
    let (a, b, c) = (1.0 / 6.0, 2.0 / 3.0, 0.5);
    let rows =
        [[a, b, a, 0.0, 0.0], [0.0, c, c, 0.0, 0.0], [0.0, a, b, a, 0.0], [0.0, 0.0, c, c, 0.0], [0.0, 0.0, a, b, a]];
    for (r, row) in rows.iter().enumerate() {
        for (col, w) in row.iter().enumerate() {
            assert_eq!(sw.get(r, col), *w, "sw-curve ({r}, {col})");
        }
    }
    assert_spectrum_begins(&scheme("sw-curve"), &[1.0, 0.5, 1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0]);

    // Cubic B-spline: 1, 1/2, 1/4 (the three B-spline eigenvalues of the one-ring), then the
    // two-ring's 1/8 twice (1/8 = 2^-3 for the cubic, and the end weight of the mask).
    assert_spectrum_begins(&scheme("cubic-bspline"), &[1.0, 0.5, 0.25, 0.125, 0.125]);
    // Chaikin (the quadratic B-spline): 1, 1/2, 1/4, and the end weight 1/4.
    assert_spectrum_begins(&scheme("chaikin"), &[1.0, 0.5, 0.25, 0.25]);
    // Four-point (Dyn–Gregory–Levin, w = 1/16): 1, 1/2, 1/4, 1/4, 1/8, -1/16, -1/16; the
    // double 1/4 is why the scheme is C1 and not C2.
    assert_spectrum_begins(&scheme("four-point"), &[1.0, 0.5, 0.25, 0.25, 0.125, -0.0625, -0.0625]);

    // Six-point (Dubuc–Deslauriers): it reproduces quintics, so 2^-k for k = 0..=5 are
    // eigenvalues; it is C2 and not C3, so 1, 1/2, 1/4 lead and the fourth has modulus in
    // (1/8, 1/4).
    let six = scheme("six-point").eigenvalues().unwrap();
    assert_spectrum_begins(&scheme("six-point"), &[1.0, 0.5, 0.25]);
    for k in 0..=5 {
        let power = 0.5f64.powi(k);
        assert!(six.iter().any(|z| (z.0 - power).abs() < 1e-12 && z.1.abs() < 1e-12), "2^-{k} in {six:?}");
    }
    let fourth = six[3].0.hypot(six[3].1);
    assert!(fourth > 0.125 + 1e-9 && fourth < 0.25 - 1e-9, "{six:?}");
}

/// A ternary scheme works the same way: the ternary cubic B-spline, symbol (1 + z + z²)⁴ / 27.
#[test]
fn a_ternary_scheme_from_a_file() {
    let scheme = CurveScheme::from_toml_str(
        r#"
        name = "ternary-cubic-bspline"
        arity = 3
        offset = 4
        mask = ["1/27", "4/27", "10/27", "16/27", "19/27", "16/27", "10/27", "4/27", "1/27"]
        "#,
    )
    .unwrap();
    let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    assert_eq!(scheme.refine_closed(&square).len(), 12);
    // Collinear, equally spaced points stay so: linear precision.
    let line: Vec<DVec3> = (0..8).map(|i| DVec3::X * f64::from(i)).collect();
    let children = scheme.open_children(line.len());
    for (child, p) in children.zip(scheme.refine_open(&line)) {
        assert!((p - DVec3::X * (child as f64 / 3.0)).length() < 1e-13, "{child}: {p}");
    }
    let m = scheme.local_matrix();
    assert_eq!((m.first(), m.size()), (-2, 5));
    assert_spectrum_begins(&scheme, &[1.0, 1.0 / 3.0, 1.0 / 9.0, 1.0 / 27.0]);
}

/// The knots `τ_j` of a curve, for `j` in `range` (closed curves wrap, adding periods).
fn tau(curve: &NonUniformCubicBSpline, range: std::ops::RangeInclusive<i64>) -> Vec<f64> {
    let d = curve.intervals();
    let n = curve.points().len() as i64;
    let tau0 = curve.knots()[0];
    // d[k] ends at τ_k: on an open curve k = 0..=n; on a closed one, k modulo n.
    let before = |k: i64| match curve.kind() {
        PolygonKind::Closed => d[k.rem_euclid(n) as usize],
        PolygonKind::Open => d[k as usize],
    };
    range
        .map(
            |j| {
                if j >= 0 {
                    tau0 + (1..=j).map(before).sum::<f64>()
                } else {
                    tau0 - (j + 1..=0).map(before).sum::<f64>()
                }
            },
        )
        .collect()
}

/// The curve as a plain B-spline for Cox–de Boor: a knot vector `t` with `points.len() + 4`
/// knots, point `i` having the basis function on `[t_i, t_{i+4}]`. Open curves: points
/// `0..n` on the knots `τ_{-1}..τ_n` plus one arbitrary knot at each end. Closed curves:
/// unrolled to points `-2..=n+1`.
fn cox_de_boor_form(curve: &NonUniformCubicBSpline) -> (Vec<f64>, Vec<DVec3>) {
    let n = curve.points().len() as i64;
    match curve.kind() {
        PolygonKind::Open => {
            let inner = tau(curve, -1..=n);
            let mut knots = vec![inner[0] - 1.0];
            knots.extend(&inner);
            knots.push(inner[inner.len() - 1] + 1.0);
            (knots, curve.points().to_vec())
        }
        PolygonKind::Closed => {
            let points = (-2..=n + 1).map(|j| curve.points()[j.rem_euclid(n) as usize]).collect();
            (tau(curve, -4..=n + 3), points)
        }
    }
}

/// `Σ P_i N_{i,3}(t)` by the Cox–de Boor recursion, `t` in `[t_3, t_{len - 4}]`.
fn cox_de_boor(knots: &[f64], points: &[DVec3], t: f64) -> DVec3 {
    let n = points.len();
    assert_eq!(knots.len(), n + 4);
    assert!(t >= knots[3] - 1e-9 && t <= knots[n] + 1e-9, "{t} outside [{}, {}]", knots[3], knots[n]);
    // The span [t_s, t_{s+1}) holding t; the domain's last span is closed on the right.
    let span = (3..n).rev().find(|&s| knots[s] <= t).unwrap_or(3);
    fn basis(knots: &[f64], span: usize, i: usize, degree: usize, t: f64) -> f64 {
        if degree == 0 {
            return if i == span { 1.0 } else { 0.0 };
        }
        let ratio = |num: f64, den: f64| if den == 0.0 { 0.0 } else { num / den };
        ratio(t - knots[i], knots[i + degree] - knots[i]) * basis(knots, span, i, degree - 1, t)
            + ratio(knots[i + degree + 1] - t, knots[i + degree + 1] - knots[i + 1])
                * basis(knots, span, i + 1, degree - 1, t)
    }
    (0..n).map(|i| points[i] * basis(knots, span, i, 3, t)).sum()
}

/// Inserts knot `u` into the cubic B-spline `(knots, points)` by Boehm's algorithm.
fn insert_knot(knots: &mut Vec<f64>, points: &mut Vec<DVec3>, u: f64) {
    let k = (0..knots.len() - 1).rev().find(|&k| knots[k] <= u).unwrap();
    assert!(k >= 3 && k < points.len(), "{u} outside the domain");
    let old = points.clone();
    points.insert(k, DVec3::ZERO);
    for i in k - 2..=k {
        let alpha = (u - knots[i]) / (knots[i + 3] - knots[i]);
        points[i] = old[i - 1] * (1.0 - alpha) + old[i] * alpha;
    }
    knots.insert(k + 1, u);
}

/// The open curve refined by Boehm's algorithm, inserting the midpoint of every knot interval
/// that the refined polygon spans: the curve is padded with two points and two intervals at
/// each end (so that those intervals lie inside the domain), the midpoints of all domain
/// intervals are inserted, and the points that the padding does not reach are returned.
fn boehm_midpoints(curve: &NonUniformCubicBSpline, pad_intervals: [f64; 4], pad_points: [DVec3; 4]) -> Vec<DVec3> {
    let n = curve.points().len();
    let [i0, i1, i2, i3] = pad_intervals;
    let mut intervals = vec![i0, i1];
    intervals.extend(curve.intervals());
    intervals.extend([i2, i3]);
    let mut points = pad_points[..2].to_vec();
    points.extend(curve.points());
    points.extend(&pad_points[2..]);
    let padded = NonUniformCubicBSpline::open(points, intervals).unwrap();
    let (mut knots, mut points) = cox_de_boor_form(&padded);
    let domain: Vec<f64> = knots[3..=padded.points().len()].to_vec();
    for pair in domain.windows(2) {
        insert_knot(&mut knots, &mut points, (pair[0] + pair[1]) / 2.0);
    }
    // The refined point with knots (τ_0, m_0, τ_1) — the first one kept — is number 4: the
    // padded knots start τ_{-3}-1, τ_{-3}, τ_{-2}, τ_{-1} and then alternate midpoints and knots.
    points[4..4 + (2 * n - 3)].to_vec()
}
