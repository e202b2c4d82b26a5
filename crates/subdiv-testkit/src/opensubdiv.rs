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
use subdiv_schemes::{Builtin, RefineOptions, refine_uniform};

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
        let scheme = if name.starts_with("loop_")
            || (!name.starts_with("catmark_") && !name.starts_with("bilinear_") && soup.faces().all(|f| f.len() == 3))
        {
            Builtin::Loop
        } else if name.starts_with("bilinear_") {
            Builtin::Bilinear
        } else {
            Builtin::CatmullClark
        };
        let Ok(mesh) = Mesh::build_with(soup, &BuildOptions::default()) else {
            skipped.push(format!("{name}: not a valid mesh here (SOURCES.md marks it irregular)"));
            continue;
        };
        for &level in levels {
            let osd_name = match scheme {
                Builtin::Loop => "loop",
                Builtin::Bilinear => "bilinear",
                _ => "catmark",
            };
            let out = std::env::temp_dir().join(format!("osd_refine_{}_{level}.obj", std::process::id()));
            let status = Command::new(osd_refine)
                .arg(path)
                .args(["--levels", &level.to_string(), "--scheme", osd_name, "-o"])
                .arg(&out)
                .stderr(std::process::Stdio::null())
                .status()
                .map_err(|e| format!("cannot run {}: {e}", osd_refine.display()))?;
            if !status.success() {
                skipped.push(format!("{name} level {level}: OpenSubdiv rejects it ({status})"));
                break;
            }
            let theirs = subdiv_io::load(&out).map_err(|e| e.to_string())?;
            let _ = std::fs::remove_file(&out);
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
