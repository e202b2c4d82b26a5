//! Exact limit evaluation ([`LimitEvaluator`]) equals OpenSubdiv's `Bfr` (the peer harness's
//! `osd_limit`) on the peer's meshes: closed quad meshes with extraordinary vertices (cube,
//! torus, valence56), N-gons (ngon_prism), boundaries (grid_open) and Loop (icosahedron,
//! octahedron, torus_tri), on `--grid N` for N = 4, 5, 7 (non-dyadic N included), row for row;
//! and OpenSubdiv's `catmark_fan` (three sheets on a chain of non-manifold edges), split into
//! sheets (`BuildOptions::split_sheets`).
//!
//! - Away from extraordinary vertices (EVs) — every grid point that is not an EV, and the
//!   probes below at least 2^-9 (normalized) from one — positions and derivatives agree to
//!   1e-12 × the cage's bounding-box diagonal: Bfr is exact there.
//! - At an EV, positions agree to the same bound; the parameterization has no derivative there
//!   (Bfr returns finite Gregory-patch values), so only the normals are compared. Where Bfr's
//!   two derivatives are parallel (grid_open's valence-2 corners), its normal is undefined and
//!   we check that its tangent lies in our tangent plane.
//! - Probes converging to every EV, (2^-k, 2^-k) in normalized (sub-)face coordinates for
//!   k = 1..14, show how far Bfr's Gregory patches (within 2^-10 of an EV at approximation
//!   level 10) are from the exact surface: printed, and only sanity-checked (1e-3).
//!
//! The eigenbasis route ([`EigenEvaluator`], `Method::Auto`: eigenbasis on interior patches,
//! exact stencils on boundary ones) is held to the same bounds at the same points, given the
//! printed f64 parameters.
//!
//! `osd_limit` is named by `SUBDIV_OSD_LIMIT` (`.ci/run` builds it outside the repository); when
//! the variable is unset the test says so and does not run; when it is set, the program and the
//! shared meshes must exist.

#![allow(clippy::print_stderr)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use subdiv::DVec3;
use subdiv::eval::{EigenEvaluator, Method};
use subdiv::mesh::{BoundaryInterpolation, FaceId};
use subdiv::schemes::{Builtin, RefineOptions};
use subdiv::stencil::{Dyadic, FaceDomain, LimitEvaluator, LimitPoint};

/// One CSV row of `osd_limit`: face, u, v, position, du, dv.
#[derive(Clone, Copy, Debug)]
struct Row {
    face: usize,
    u: f64,
    v: f64,
    p: DVec3,
    du: DVec3,
    dv: DVec3,
}

fn run_osd(osd_limit: &Path, mesh: &Path, scheme: &str, points: &[&str]) -> Vec<Row> {
    let output =
        Command::new(osd_limit).arg(mesh).args(["--scheme", scheme]).args(points).output().expect("osd_limit runs");
    assert!(output.status.success(), "osd_limit {}: {}", mesh.display(), String::from_utf8_lossy(&output.stderr));
    let text = String::from_utf8(output.stdout).expect("CSV is text");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("face,u,v,px,py,pz,dux,duy,duz,dvx,dvy,dvz"));
    lines
        .map(|line| {
            let x: Vec<f64> = line.split(',').map(|s| s.parse().expect("a number")).collect();
            let at = |i: usize| DVec3::new(x[i], x[i + 1], x[i + 2]);
            Row { face: x[0] as usize, u: x[1], v: x[2], p: at(3), du: at(6), dv: at(9) }
        })
        .collect()
}

/// The angle between the normals of two derivative pairs, or `None` when the second pair is
/// parallel (no normal).
fn normal_angle(ours: &LimitPoint, osd: &Row) -> Option<f64> {
    let (a, b) = (ours.du.cross(ours.dv), osd.du.cross(osd.dv));
    if b.length() < 1e-8 * osd.du.length() * osd.dv.length() {
        return None;
    }
    Some(a.angle_between(b))
}

/// Corners of a face's (or sub-face's) normalized domain, each with the inward diagonal.
fn corners(domain: FaceDomain) -> Vec<([i64; 2], [i64; 2])> {
    match domain {
        FaceDomain::Triangle => vec![([0, 0], [1, 1]), ([1, 0], [-2, 1]), ([0, 1], [1, -2])],
        _ => vec![([0, 0], [1, 1]), ([1, 0], [-1, 1]), ([1, 1], [-1, -1]), ([0, 1], [1, -1])],
    }
}

/// Max differences of one comparison.
#[derive(Default)]
struct Max {
    position: f64,
    derivative: f64,
}

fn compare_mesh(
    osd_limit: &Path,
    path: &Path,
    scheme: Builtin,
    boundary: Option<BoundaryInterpolation>,
    grids: &[u32],
    report: &mut String,
) {
    let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
    // Non-manifold meshes taken apart into sheets, as OpenSubdiv refines them (a manifold
    // mesh is built as it is).
    let sheets = subdiv::mesh::BuildOptions::DEFAULT.with_split_sheets(true);
    let mesh = subdiv::io::load_mesh(path, &sheets).unwrap();
    let options = RefineOptions { boundary, ..RefineOptions::DEFAULT };
    let eval = LimitEvaluator::new(scheme.scheme(), &mesh, &options).unwrap();
    let eigen = EigenEvaluator::new(scheme.scheme(), &mesh, &options, Method::Auto).unwrap();
    let mut eigen_away = Max::default();
    let boundary_args: Vec<&str> = match boundary {
        None => vec![],
        Some(BoundaryInterpolation::None) => vec!["--boundary", "none"],
        Some(BoundaryInterpolation::EdgeAndCorner) => vec!["--boundary", "edge-and-corner"],
        Some(BoundaryInterpolation::EdgeOnly) => vec!["--boundary", "edge-only"],
    };
    let name = format!("{stem}{}", boundary_args.get(1).map_or(String::new(), |b| format!(" --boundary {b}")));
    let (lo, hi) = mesh.bounding_box().unwrap();
    let tolerance = 1e-12 * (hi - lo).length();
    let osd_scheme = if scheme == Builtin::Loop { "loop" } else { "catmark" };

    // The grids, row for row.
    let (mut away, mut at_ev, mut ev_points, mut worst_angle) = (Max::default(), 0.0_f64, 0, 0.0_f64);
    for &n in grids {
        let n_text = n.to_string();
        let theirs = run_osd(osd_limit, path, osd_scheme, &[&["--grid", n_text.as_str()], &boundary_args[..]].concat());
        let ours: Vec<(usize, _, LimitPoint)> = mesh
            .face_ids()
            .flat_map(|f| eval.grid(f, n).unwrap().into_iter().map(move |(g, p)| (f.index(), g, p)))
            .collect();
        assert_eq!(ours.len(), theirs.len(), "{name} grid {n}: row count");
        for ((face, g, p), o) in ours.iter().zip(&theirs) {
            let place = format!("{name} grid {n}: face {face} at ({}, {})", g.u, g.v);
            assert_eq!((*face, g.u, g.v), (o.face, o.u, o.v), "{place}: rows in osd_limit's order");
            let dp = (p.position - o.p).length();
            assert!(dp <= tolerance, "{place}: position differs by {dp:e}");
            let e = eigen.eval(FaceId::new(*face as u32), g.u, g.v).unwrap();
            let de = (e.position - o.p).length();
            assert!(de <= tolerance, "{place}: eigenbasis position differs by {de:e}");
            assert_eq!(e.exact_derivatives, p.exact_derivatives, "{place}: eigenbasis");
            if e.exact_derivatives {
                let dd = (e.du - o.du).length().max((e.dv - o.dv).length());
                assert!(dd <= tolerance, "{place}: eigenbasis derivatives differ by {dd:e}");
                eigen_away.position = eigen_away.position.max(de);
                eigen_away.derivative = eigen_away.derivative.max(dd);
            } else if let Some(angle) = normal_angle(&e, o) {
                assert!(angle <= 1e-5, "{place}: eigenbasis normals differ by {angle:e} rad");
            }
            if p.exact_derivatives {
                let dd = (p.du - o.du).length().max((p.dv - o.dv).length());
                assert!(dd <= tolerance, "{place}: derivatives differ by {dd:e}");
                away.position = away.position.max(dp);
                away.derivative = away.derivative.max(dd);
            } else {
                ev_points += 1;
                at_ev = at_ev.max(dp);
                match normal_angle(p, o) {
                    Some(angle) => {
                        assert!(angle <= 1e-5, "{place}: normals differ by {angle:e} rad");
                        worst_angle = worst_angle.max(angle);
                    }
                    None => {
                        // Bfr's derivatives are parallel: its tangent lies in our tangent plane.
                        let normal = p.du.cross(p.dv).normalize();
                        let off = normal.dot(o.du.normalize()).abs();
                        assert!(off <= 1e-9, "{place}: Bfr's tangent leaves our tangent plane by {off:e}");
                    }
                }
            }
        }
    }
    writeln!(
        report,
        "{name} ({osd_scheme}, grids {grids:?}): away from EVs max |Δp| {:.1e}, |Δd| {:.1e}; at {ev_points} EV points \
         max |Δp| {at_ev:.1e}, normal angle {worst_angle:.1e} rad (tolerance {tolerance:.1e}); eigenbasis away \
         from EVs max |Δp| {:.1e}, |Δd| {:.1e} ({eigen})",
        away.position, away.derivative, eigen_away.position, eigen_away.derivative
    )
    .unwrap();

    // Probes converging to every EV corner of every (sub-)face.
    let mut probes: Vec<(usize, FaceId, Dyadic)> = Vec::new();
    for f in mesh.face_ids().filter(|&f| eval.has_surface(f).unwrap()) {
        let domain = eval.domain(f).unwrap();
        let subs = match domain {
            FaceDomain::SubFaces { size, .. } => size,
            _ => 1,
        };
        for sub in 0..subs {
            for (corner, inward) in corners(domain) {
                let at = domain.from_sub_face(sub, Dyadic::new(corner[0], corner[1], 1));
                if eval.eval_exact(f, at).unwrap().exact_derivatives {
                    continue;
                }
                for k in 1..=14 {
                    let q = 1i64 << k;
                    let local = Dyadic::new(corner[0] * q + inward[0], corner[1] * q + inward[1], q);
                    probes.push((k, f, domain.from_sub_face(sub, local)));
                }
            }
        }
    }
    if probes.is_empty() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let samples = dir.path().join("samples.txt");
    let mut text = String::from("# face u v: points converging to extraordinary vertices\n");
    for (_, f, p) in &probes {
        let (u, v) = p.to_f64();
        writeln!(text, "{}, {u:?} {v:?}", f.index()).unwrap();
    }
    std::fs::write(&samples, text).unwrap();
    let theirs =
        run_osd(osd_limit, path, osd_scheme, &[&["--samples", samples.to_str().unwrap()], &boundary_args[..]].concat());
    assert_eq!(theirs.len(), probes.len(), "{name}: one row per probe");
    let mut by_k = vec![(0.0_f64, 0.0_f64); 15];
    for ((k, f, point), o) in probes.iter().zip(&theirs) {
        let p = eval.eval_exact(*f, *point).unwrap();
        let dp = (p.position - o.p).length();
        let angle = normal_angle(&p, o).unwrap_or(0.0);
        let place = format!("{name}: face {} probe k = {k} at ({}, {})", f.index(), o.u, o.v);
        assert!(dp <= 1e-3 * (hi - lo).length(), "{place}: position differs by {dp:e}");
        if *k <= 9 {
            let dd = (p.du - o.du).length().max((p.dv - o.dv).length());
            assert!(dp <= tolerance && dd <= tolerance, "{place}: |Δp| {dp:e}, |Δd| {dd:e} (Bfr is exact here)");
            let e = eigen.eval(*f, o.u, o.v).unwrap();
            let (de, dd) = ((e.position - o.p).length(), (e.du - o.du).length().max((e.dv - o.dv).length()));
            assert!(de <= tolerance && dd <= tolerance, "{place}: eigenbasis |Δp| {de:e}, |Δd| {dd:e}");
        }
        by_k[*k].0 = by_k[*k].0.max(dp);
        by_k[*k].1 = by_k[*k].1.max(angle);
    }
    let line: Vec<String> = (1..=14).map(|k| format!("{k}: {:.1e}/{:.1e}", by_k[k].0, by_k[k].1)).collect();
    writeln!(report, "  near EVs, k: max |Δp| / normal angle: {}", line.join(", ")).unwrap();
}

#[test]
fn limit_evaluation_equals_opensubdiv_bfr() {
    let Some(osd_limit) = std::env::var_os("SUBDIV_OSD_LIMIT").map(PathBuf::from) else {
        eprintln!("SUBDIV_OSD_LIMIT is unset: comparison of limit evaluation with OpenSubdiv not run");
        return;
    };
    assert!(osd_limit.is_file(), "SUBDIV_OSD_LIMIT={} does not exist", osd_limit.display());
    let shared = subdiv_testkit::shared_dir().expect("the shared folder is needed for the comparison");
    let meshes = shared.join("peers/osd/meshes");
    let mut report = String::new();
    let (cc, lp) = (Builtin::CatmullClark, Builtin::Loop);
    for (mesh, scheme, boundary, grids) in [
        ("cube", cc, None, &[4, 5, 7][..]),
        ("torus", cc, None, &[5]),
        ("valence56", cc, None, &[4, 5, 7]),
        ("ngon_prism", cc, None, &[4, 5, 7]),
        ("grid_open", cc, None, &[4, 7]),
        ("grid_open", cc, Some(BoundaryInterpolation::EdgeAndCorner), &[5]),
        ("grid_open", cc, Some(BoundaryInterpolation::None), &[5]),
        ("icosahedron", lp, None, &[4, 5, 7]),
        ("octahedron", lp, None, &[4, 5, 7]),
        ("torus_tri", lp, None, &[5]),
        // Three sheets ending on one chain of non-manifold edges (OpenSubdiv's regression mesh).
        ("../../../testdata/meshes/opensubdiv/catmark_fan", cc, None, &[4, 5]),
    ] {
        let path = meshes.join(format!("{mesh}.obj"));
        assert!(path.is_file(), "{} is missing", path.display());
        compare_mesh(&osd_limit, &path, scheme, boundary, grids, &mut report);
    }
    eprint!("{report}");
}
