//! The eigenbasis route against the exact stencil route, on meshes with one extraordinary
//! vertex of each valence: Catmull-Clark discs (`shapes::pole`) and Loop bipyramids.

use subdiv_eval::{EigenEvaluator, EvalError, Method};
use subdiv_mesh::{DVec3, FaceId, Mesh, PolygonSoup, shapes};
use subdiv_schemes::{Builtin, RefineOptions};

/// A closed triangle mesh: two poles of valence `k` over a ring of `k` vertices (valence 4),
/// perturbed so that nothing is symmetric.
fn bipyramid(k: usize) -> PolygonSoup {
    let mut positions: Vec<DVec3> = (0..k)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            DVec3::new(a.cos() * (1.0 + 0.1 * (i % 3) as f64), a.sin(), 0.05 * (i % 2) as f64)
        })
        .collect();
    positions.push(DVec3::new(0.1, 0.0, 1.0));
    positions.push(DVec3::new(0.0, -0.1, -0.8));
    let (top, bottom) = (k as u32, k as u32 + 1);
    let faces: Vec<Vec<u32>> = (0..k as u32)
        .flat_map(|i| {
            let j = (i + 1) % k as u32;
            [vec![top, i, j], vec![bottom, j, i]]
        })
        .collect();
    let refs: Vec<&[u32]> = faces.iter().map(Vec::as_slice).collect();
    PolygonSoup::from_indices(positions, &refs)
}

fn diagonal(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh
        .vertices()
        .map(|v| mesh.position(v))
        .fold((DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)), |(lo, hi), p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

/// Rational, dyadic and near-vertex points of a face's domain (quads or triangles).
fn points(triangle: bool) -> Vec<(f64, f64)> {
    let mut p = vec![(0.0, 0.0), (1.0 / 7.0, 3.0 / 7.0), (2.0 / 9.0, 5.0 / 9.0), (0.375, 0.125), (0.5, 0.25)];
    p.extend([(1.0 / 3.0, 1.0 / 5.0), (1.0, 2.0 / 3.0), (3.0 / 7.0, 0.0)]);
    for e in [9, 20, 40] {
        let s = 0.5f64.powi(e);
        p.push((s / 3.0, s / 5.0));
        p.push((s * 0.75, 0.0));
    }
    p.into_iter().filter(|&(u, v)| !triangle || u + v <= 1.0).collect()
}

struct Worst {
    position: f64,
    derivative: f64,
    normal: f64,
    compared: usize,
}

/// Compares both routes at every point of every face the eigenbasis takes; returns the worst
/// deviations (positions over the bounding box diagonal, derivatives over their size).
fn compare(scheme: Builtin, mesh: &Mesh, only: Option<&[(f64, f64)]>) -> Worst {
    let eval = EigenEvaluator::new(scheme.scheme(), mesh, &RefineOptions::DEFAULT, Method::Auto).unwrap();
    let scale = diagonal(mesh);
    let mut worst = Worst { position: 0.0, derivative: 0.0, normal: 0.0, compared: 0 };
    let triangle = scheme == Builtin::Loop;
    let all = points(triangle);
    for face in mesh.face_ids() {
        if eval.uses_eigenbasis(face).unwrap().is_err() {
            continue;
        }
        for &(u, v) in only.unwrap_or(&all) {
            let a = eval.eval(face, u, v).unwrap();
            let b = eval.stencil().eval(face, u, v).unwrap();
            assert_eq!(a.exact_derivatives, b.exact_derivatives, "{scheme:?} {face} ({u}, {v})");
            worst.position = worst.position.max((a.position - b.position).length() / scale);
            if a.exact_derivatives {
                for (x, y) in [(a.du, b.du), (a.dv, b.dv)] {
                    // Beyond 2^-24 the stencil route's own derivatives lose digits (its weights
                    // cancel; the loss grows with the level, about 1.45^level at Loop valence 5),
                    // while the eigenbasis keeps coefficients less the limit and gives the same
                    // digits whether it iterates A or expands in eigenvectors. There the
                    // directions are compared, to 1e-6.
                    let deep = u.max(v) < 0.5f64.powi(24);
                    let e = if deep {
                        (x.normalize() - y.normalize()).length() * 1e-5
                    } else {
                        (x - y).length() / y.length().max(scale)
                    };
                    worst.derivative = worst.derivative.max(e);
                }
            } else {
                let (n, m) = (a.du.cross(a.dv).normalize(), b.du.cross(b.dv).normalize());
                worst.normal = worst.normal.max((n - m).length());
            }
            worst.compared += 1;
        }
    }
    worst
}

fn check(scheme: Builtin, mesh: &Mesh, valence: usize, only: Option<&[(f64, f64)]>) {
    let w = compare(scheme, mesh, only);
    assert!(w.compared > 0, "{scheme:?} valence {valence}: no face by eigenbasis");
    assert!(
        w.position < 1e-12 && w.derivative < 1e-11 && w.normal < 1e-9,
        "{scheme:?} valence {valence}: position {:.1e}, derivatives {:.1e}, normal {:.1e}",
        w.position,
        w.derivative,
        w.normal
    );
}

#[test]
fn catmull_clark_agrees_with_exact_stencils_at_valences_3_to_16() {
    for k in 3..=16 {
        // Valence 4: the regular torus (the disc's inner patches touch its rim).
        let soup = if k == 4 { shapes::quad_torus(6, 4) } else { shapes::pole(k) };
        check(Builtin::CatmullClark, &Mesh::build(soup).unwrap(), k, None);
    }
}

#[test]
fn loop_agrees_with_exact_stencils_at_valences_3_to_16() {
    for k in 3..=16 {
        check(Builtin::Loop, &Mesh::build(bipyramid(k)).unwrap(), k, None);
    }
}

#[test]
fn high_valences_agree_at_a_few_points() {
    let few = [(0.3, 0.2), (1.0 / 3.0 * 0.5f64.powi(20), 0.2 * 0.5f64.powi(20)), (0.0, 0.0)];
    for k in [32, 64] {
        check(Builtin::CatmullClark, &Mesh::build(shapes::pole(k)).unwrap(), k, Some(&few));
        check(Builtin::Loop, &Mesh::build(bipyramid(k)).unwrap(), k, Some(&few));
    }
}

/// N-gons (Bfr sub-faces) and faces with two extraordinary vertices descend before the
/// eigenbasis takes over; a closed mesh has no stencil-only faces.
#[test]
fn ngons_and_refined_faces_agree() {
    let prism = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let pts = [(0.1, 0.2), (1.25, 0.375), (0.5, 0.5), (0.0, 0.0), (1.0, 0.5)];
    let eval =
        EigenEvaluator::new(Builtin::CatmullClark.scheme(), &prism, &RefineOptions::DEFAULT, Method::Eigen).unwrap();
    let scale = diagonal(&prism);
    for face in prism.face_ids() {
        for &(u, v) in &pts {
            let (a, b) = match (eval.eval(face, u, v), eval.stencil().eval(face, u, v)) {
                (Ok(a), Ok(b)) => (a, b),
                (Err(EvalError::Stencil(_)), Err(_)) => continue,
                (a, b) => panic!("{face} ({u}, {v}): {a:?} vs {b:?}"),
            };
            assert!((a.position - b.position).length() < 1e-12 * scale, "{face} ({u}, {v})");
            if a.exact_derivatives {
                assert!((a.du - b.du).length() < 1e-11 * b.du.length().max(scale), "{face} ({u}, {v})");
            }
        }
    }
}

/// Second derivatives against central differences of the first (which agree with the exact
/// stencils), on regular and extraordinary patches.
#[test]
fn second_derivatives_match_differences_of_the_first() {
    for (scheme, mesh) in [
        (Builtin::CatmullClark, Mesh::build(shapes::pole(5)).unwrap()),
        (Builtin::Loop, Mesh::build(bipyramid(7)).unwrap()),
    ] {
        let eval = EigenEvaluator::new(scheme.scheme(), &mesh, &RefineOptions::DEFAULT, Method::Auto).unwrap();
        let h = 1e-6;
        for face in mesh.face_ids().filter(|&f| eval.uses_eigenbasis(f).unwrap().is_ok()) {
            for (u, v) in [(0.3, 0.2), (0.05, 0.4), (0.01, 0.02), (0.4, 0.45)] {
                let p = eval.eval_second(face, u, v).unwrap();
                let d = |du: f64, dv: f64| eval.eval(face, u + du, v + dv).unwrap();
                let duu = (d(h, 0.0).du - d(-h, 0.0).du) / (2.0 * h);
                let duv = (d(0.0, h).du - d(0.0, -h).du) / (2.0 * h);
                let dvv = (d(0.0, h).dv - d(0.0, -h).dv) / (2.0 * h);
                for (name, got, want) in [("duu", p.duu, duu), ("duv", p.duv, duv), ("dvv", p.dvv, dvv)] {
                    assert!(
                        (got - want).length() < 1e-5 * want.length().max(1.0),
                        "{scheme:?} {face} ({u}, {v}) {name}: {got} vs {want}"
                    );
                }
                assert_eq!(p.first, eval.eval(face, u, v).unwrap());
            }
        }
    }
}

#[test]
fn user_errors_are_typed() {
    let mesh = Mesh::build(shapes::pole(5)).unwrap();
    let cc = Builtin::CatmullClark.scheme();
    let eigen = EigenEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT, Method::Eigen).unwrap();
    // The disc's rim faces sit on boundary patches.
    let rim = mesh.face_ids().find(|&f| eigen.uses_eigenbasis(f).unwrap().is_err()).unwrap();
    assert!(matches!(eigen.eval(rim, 0.5, 0.5), Err(EvalError::FaceNotSupported { .. })));
    let auto = EigenEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT, Method::Auto).unwrap();
    assert!(auto.eval(rim, 0.5, 0.5).is_ok());
    assert!(matches!(auto.eval_second(rim, 0.5, 0.5), Err(EvalError::NoSecondDerivatives { .. })));
    for (u, v) in [(1.5, 0.0), (f64::NAN, 0.0), (0.0, f64::INFINITY), (-0.1, 0.2)] {
        assert!(matches!(auto.eval(FaceId::new(0), u, v), Err(EvalError::Stencil(_))), "({u}, {v})");
    }
    assert!(auto.eval(FaceId::new(10_000), 0.0, 0.0).is_err());
    assert!(matches!(subdiv_eval::EigenBasis::interior(cc, 65), Err(EvalError::Valence { valence: 65, .. })));
    assert!(subdiv_eval::EigenBasis::interior(cc, 2).is_err());
}

/// Valences 3 to 64 of both schemes have an eigenbasis whose kept part passed the
/// semisimplicity checks (Auto would otherwise fall back to stencils silently).
#[test]
fn every_valence_has_a_semisimple_kept_spectrum() {
    for scheme in [Builtin::CatmullClark, Builtin::Loop] {
        // All of 3..=64 in release: `cargo run --release -p subdiv-eval --example spectrum $(seq 3 64)`.
        for k in (3..=12).chain([16, 23, 32, 64]) {
            let basis = subdiv_eval::EigenBasis::interior(scheme.scheme(), k).unwrap();
            let regular = if scheme == Builtin::Loop { 6 } else { 4 };
            if k == regular {
                assert!(basis.is_regular());
                continue;
            }
            let s = basis.spectrum().unwrap();
            assert_eq!(basis.valence(), Some(k));
            assert!(s.reconstruction < 1e-9 && s.biorthogonality < 1e-8, "{scheme:?} {k}: {s:?}");
            assert!(s.subdominant > 0.2 && s.subdominant < 1.0, "{scheme:?} {k}: {}", s.subdominant);
        }
    }
}
