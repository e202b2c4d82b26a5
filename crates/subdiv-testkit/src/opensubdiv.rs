//! Our uniform refinement against OpenSubdiv's, on the shared corpus.
//!
//! Runs the peer harness's `osd_refine` (built from `../shared/peers/osd/src/osd_refine.cpp`
//! outside the repository; `.ci/run` does it) and `subdiv_schemes::refine_uniform` on every OBJ
//! of the corpus that OpenSubdiv accepts, at the given levels, and compares the refined vertices as
//! point sets (edge points are numbered differently) to 1e-12 × the bounding-box diagonal, and
//! the faces that are not holes by count.

use std::path::Path;
use std::process::Command;

use subdiv_mesh::{BuildOptions, DVec3, Mesh};

/// What [`compare_refinement`] found.
#[derive(Debug, Default)]
pub struct RefinementReport {
    /// Mesh-levels equal to OpenSubdiv's.
    pub equal: usize,
    /// Mesh-levels that differ, each with why.
    pub differ: Vec<String>,
    /// Meshes not compared, each with why (invalid here, or rejected by OpenSubdiv).
    pub skipped: Vec<String>,
}
use subdiv_mesh::{Channel, FaceVaryingInterpolation, PolygonSoup};
use subdiv_schemes::{Builtin, RefineOptions, refine_uniform};

/// The scheme the comparisons refine a corpus file with, from its name's prefix (`loop_`,
/// `bilinear_`, else Catmull-Clark, and Loop for all-triangle meshes without a prefix), and
/// `osd_refine`'s name for it.
pub fn scheme_of(name: &str, soup: &PolygonSoup) -> (Builtin, &'static str) {
    if name.starts_with("loop_")
        || (!name.starts_with("catmark_") && !name.starts_with("bilinear_") && soup.faces().all(|f| f.len() == 3))
    {
        (Builtin::Loop, "loop")
    } else if name.starts_with("bilinear_") {
        (Builtin::Bilinear, "bilinear")
    } else {
        (Builtin::CatmullClark, "catmark")
    }
}

/// Runs `osd_refine` on `path` with `args`, returning its output read back, or `None` when
/// OpenSubdiv rejects the input.
fn run_osd_refine(osd_refine: &Path, path: &Path, args: &[String]) -> Result<Option<PolygonSoup>, String> {
    // A name of its own per call: the tests of one process run on several threads.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let out = std::env::temp_dir().join(format!("osd_refine_{}_{call}.obj", std::process::id()));
    let status = Command::new(osd_refine)
        .arg(path)
        .args(args)
        .arg("-o")
        .arg(&out)
        .stderr(std::process::Stdio::null())
        .status()
        .map_err(|e| format!("cannot run {}: {e}", osd_refine.display()))?;
    if !status.success() {
        return Ok(None);
    }
    let theirs = subdiv_io::load(&out).map_err(|e| e.to_string());
    let _ = std::fs::remove_file(&out);
    theirs.map(Some)
}

/// Compares the refined texture coordinates of `refine_uniform` with `osd_refine --fvar` on
/// every OBJ below `meshes` whose name `select` accepts and that has texture coordinates, at
/// `levels`, in each of `modes` (`None`: the file's tag, else the default, on both sides). Faces
/// that are not holes are compared in order, corner by corner: the corner's position to 1e-12 ×
/// bbox and its texture coordinate to 1e-12 × the largest coordinate (at least 1).
///
/// # Errors
/// When `osd_refine` cannot be run or a file cannot be read.
pub fn compare_face_varying(
    osd_refine: &Path,
    meshes: &Path,
    select: impl Fn(&str) -> bool,
    levels: &[usize],
    modes: &[Option<FaceVaryingInterpolation>],
) -> Result<RefinementReport, String> {
    let mut report = RefinementReport::default();
    for path in crate::obj_files(meshes) {
        let name = path.file_name().unwrap_or_default().to_string_lossy().to_string();
        if !select(&name) {
            continue;
        }
        let soup = subdiv_io::load(&path).map_err(|e| e.to_string())?;
        if soup.channels.is_empty() {
            continue;
        }
        let (scheme, osd_name) = scheme_of(&name, &soup);
        let Ok(mesh) = Mesh::build_with(soup, &BuildOptions::default()) else {
            report.skipped.push(format!("{name}: not a valid mesh here"));
            continue;
        };
        for &mode in modes {
            let mode_name = mode.map_or("tag or default", FaceVaryingInterpolation::name);
            for &level in levels {
                let mut args: Vec<String> =
                    ["--fvar", "--levels", &level.to_string(), "--scheme", osd_name].map(String::from).to_vec();
                if let Some(mode) = mode {
                    args.extend(["--fvar-interpolation".to_owned(), mode.name().to_owned()]);
                }
                let Some(theirs) = run_osd_refine(osd_refine, &path, &args)? else {
                    report.skipped.push(format!("{name} level {level}: OpenSubdiv rejects it"));
                    break;
                };
                let options = RefineOptions { face_varying: mode, ..RefineOptions::DEFAULT };
                let place = format!("{name} ({scheme}, {mode_name}) level {level}");
                match refine_uniform(&mesh, scheme.scheme(), level, &options) {
                    Ok(ours) => match compare_corners(&ours, &theirs) {
                        Ok(()) => report.equal += 1,
                        Err(why) => report.differ.push(format!("{place}: {why}")),
                    },
                    Err(e) => report.differ.push(format!("{place}: we refuse it: {e}")),
                }
            }
        }
    }
    Ok(report)
}

/// `ours`' faces that are not holes against `theirs`' faces, in order, corner by corner.
fn compare_corners(ours: &Mesh, theirs: &PolygonSoup) -> Result<(), String> {
    let (Some(our_uv), Some(their_uv)) = (ours.channel(Channel::UV), theirs.channels.first()) else {
        return Err("a side has no texture coordinates".into());
    };
    let faces: Vec<_> = ours.face_ids().filter(|&f| !ours.is_hole(f)).collect();
    if faces.len() != theirs.face_count() {
        return Err(format!("{} faces, OpenSubdiv has {}", faces.len(), theirs.face_count()));
    }
    let (lo, hi) =
        theirs.positions().iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let position_tolerance = 1e-12 * (hi - lo).length().max(1e-300);
    let uv_tolerance = 1e-12 * their_uv.values().iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let (offsets, corners) = theirs.raw_faces();
    let mut worst = 0.0f64;
    for (k, &f) in faces.iter().enumerate() {
        let their_face = offsets[k] as usize..offsets[k + 1] as usize;
        if their_face.len() != ours.face_size(f) {
            return Err(format!("face {k} has {} corners, OpenSubdiv's {}", ours.face_size(f), their_face.len()));
        }
        for (h, c) in ours.face_half_edges(f).zip(their_face) {
            let d = ours.position(ours.origin(h)).distance(theirs.positions()[corners[c].index()]);
            if d > position_tolerance {
                return Err(format!("face {k}: a corner is {d:.3e} from OpenSubdiv's (positions)"));
            }
            let (a, b) = (our_uv.value(our_uv.corner_value(h)), their_uv.value(their_uv.indices()[c]));
            let e = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            worst = worst.max(e);
            if e > uv_tolerance {
                return Err(format!("face {k} corner {h}: uv {a:?}, OpenSubdiv's {b:?} ({e:.3e} apart)"));
            }
        }
    }
    Ok(())
}

/// Compares `refine_uniform` with `osd_refine` on every OBJ below `meshes` at `levels`; the
/// scheme comes from the file name's prefix (`loop_`, `bilinear_`, else Catmull-Clark, and Loop
/// for all-triangle meshes without a prefix).
///
/// # Errors
/// When `osd_refine` cannot be run or a file cannot be read.
pub fn compare_refinement(osd_refine: &Path, meshes: &Path, levels: &[usize]) -> Result<RefinementReport, String> {
    let files = crate::obj_files(meshes);
    let mut report = RefinementReport::default();
    let RefinementReport { equal: same, differ, skipped } = &mut report;
    for path in &files {
        let name = path.file_name().unwrap_or_default().to_string_lossy().to_string();
        let soup = subdiv_io::load(path).map_err(|e| e.to_string())?;
        let (scheme, osd_name) = scheme_of(&name, &soup);
        let Ok(mesh) = Mesh::build_with(soup, &BuildOptions::default()) else {
            skipped.push(format!("{name}: not a valid mesh here (SOURCES.md marks it irregular)"));
            continue;
        };
        for &level in levels {
            let args = ["--levels", &level.to_string(), "--scheme", osd_name].map(String::from);
            let Some(theirs) = run_osd_refine(osd_refine, path, &args)? else {
                skipped.push(format!("{name} level {level}: OpenSubdiv rejects it"));
                break;
            };
            let ours = match refine_uniform(&mesh, scheme.scheme(), level, &RefineOptions::DEFAULT) {
                Ok(mesh) => mesh,
                Err(e) => {
                    differ.push(format!("{name} level {level}: we refuse it: {e}"));
                    break;
                }
            };
            let our_faces = ours.face_ids().filter(|&f| !ours.is_hole(f)).count();
            if our_faces != theirs.face_count() {
                differ.push(format!("{name} level {level}: {our_faces} faces, OpenSubdiv has {}", theirs.face_count()));
                continue;
            }
            match compare(ours.positions(), theirs.positions()) {
                Ok(()) => *same += 1,
                Err(why) => differ.push(format!("{name} ({scheme}) level {level}: {why}")),
            }
        }
    }
    Ok(report)
}

/// Matches every point of `ours` to a distinct point of `theirs` within 1e-12 × bbox diagonal.
fn compare(ours: &[DVec3], theirs: &[DVec3]) -> Result<(), String> {
    if ours.len() != theirs.len() {
        return Err(format!("{} vertices, OpenSubdiv has {}", ours.len(), theirs.len()));
    }
    let (lo, hi) = theirs.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let tolerance = 1e-12 * (hi - lo).length().max(1e-300);
    let mut sorted: Vec<(DVec3, bool)> = theirs.iter().map(|&p| (p, false)).collect();
    sorted.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
    let mut worst = 0.0f64;
    for (i, p) in ours.iter().enumerate() {
        let start = sorted.partition_point(|q| q.0.x < p.x - tolerance);
        let mut best: Option<(usize, f64)> = None;
        for (j, q) in sorted.iter().enumerate().skip(start) {
            if q.0.x > p.x + tolerance {
                break;
            }
            let d = q.0.distance(*p);
            if !q.1 && d <= tolerance && best.is_none_or(|(_, bd)| d < bd) {
                best = Some((j, d));
            }
        }
        match best {
            Some((j, d)) => {
                sorted[j].1 = true;
                worst = worst.max(d);
            }
            None => {
                let nearest = theirs.iter().map(|q| q.distance(*p)).fold(f64::INFINITY, f64::min);
                return Err(format!(
                    "our vertex {i} at {p} is {:.3e} × bbox from OpenSubdiv's nearest",
                    nearest / (hi - lo).length()
                ));
            }
        }
    }
    Ok(())
}
