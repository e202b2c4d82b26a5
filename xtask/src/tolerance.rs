//! `cargo xtask tolerance [--mesh M]... [--relative R]`: `subdiv tessellate --tolerance R
//! --relative` by both methods on real meshes, measured against OpenSubdiv: the worst distance
//! from `osd_limit --grid 16`'s limit points (`SUBDIV_OSD_LIMIT`) to the output, over `ε`, with
//! the output's triangles, the time, and the triangles of the uniform tessellation that the
//! same bound asks for (the dual method's largest rate on every face; the quadtree's deepest
//! leaf away from extraordinary corners, everywhere) — or the refusal, said. Meshes named
//! `loop_*` (all triangles) are read under Loop, on both sides; the others under Catmull-Clark.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use subdiv::mesh::{BuildOptions, DVec3};
use subdiv::schemes::Builtin;
use subdiv::tess::check::MeshDistance;
use subdiv::tess::dual::predicted_vertex_count;
use subdiv::tess::rates::ErrorRates;
use subdiv::tess::{QuadtreeTessellator, Tolerance};
use subdiv::{Method, Rates, Surface, TessOptions};

/// The largest uniform dual tessellation the table makes to count its triangles; past it, the
/// count is predicted (a uniform rate of hundreds on a thousand faces is gigabytes).
const COUNTED_VERTICES: usize = 1 << 22;

/// The meshes of issue 48's distance table (`../shared/testdata/meshes`).
const MESHES: [&str; 6] = [
    "keenan/spot_control_mesh.obj",
    "keenan/blub_control_mesh.obj",
    "opensubdiv/catmark_car.obj",
    "opensubdiv/catmark_bishop.obj",
    "opensubdiv/catmark_cube_creases1.obj",
    "opensubdiv/catmark_fan.obj",
];

/// `osd_limit`'s grid per face.
const GRID: u32 = 16;

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    if cfg!(debug_assertions) {
        let mut forwarded = vec!["run", "--release", "--quiet", "-p", "xtask", "--", "tolerance"];
        forwarded.extend(args.iter().map(String::as_str));
        return crate::cargo(&forwarded);
    }
    let usage = "usage: cargo xtask tolerance [--mesh M]... [--relative R]";
    let (mut meshes, mut relative) = (Vec::new(), 1e-3);
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        match (a.as_str(), rest.next()) {
            ("--mesh", Some(m)) => meshes.push(PathBuf::from(m)),
            ("--relative", Some(r)) => relative = r.parse().map_err(|_| format!("--relative {r}: not a number"))?,
            _ => return Err(format!("unknown option {a:?}; {usage}")),
        }
    }
    if meshes.is_empty() {
        let dir = subdiv_testkit::meshes_dir().ok_or("the shared corpus is missing (set SUBDIV_SHARED)")?;
        meshes = MESHES.iter().map(|m| dir.join(m)).collect();
    }
    let osd = subdiv_testkit::peer_program("SUBDIV_OSD_LIMIT").ok_or("set SUBDIV_OSD_LIMIT to osd_limit")?;
    println!(
        "| mesh | method | ε | triangles | seconds | worst distance / ε ({GRID}² osd_limit points per face) | uniform triangles, same bound | adaptive / uniform |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for path in &meshes {
        let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        let scheme = if name.starts_with("loop_") { Builtin::Loop } else { Builtin::CatmullClark };
        // Non-manifold meshes split into sheets, as OpenSubdiv (osd_limit) refines them.
        let sheets = BuildOptions::DEFAULT.with_split_sheets(true);
        let mut surface = match subdiv::io::load_mesh(path, &sheets).map(|mesh| Surface::new(mesh, scheme.scheme())) {
            Ok(surface) => surface,
            Err(e) => {
                println!("| {name} | both | | refused on reading: {} | | | | |", one_line(&e.to_string()));
                continue;
            }
        };
        let points = osd_points(&osd, path, scheme)?;
        for method in [Method::Dual, Method::Quadtree] {
            let options = TessOptions::DEFAULT
                .with_method(method)
                .with_rates(Rates::Tolerance(Tolerance::Relative(relative)))
                .with_max_vertices(usize::MAX / 4);
            let start = Instant::now();
            let out = match surface.tessellate(&options) {
                Ok(out) => out,
                Err(e) => {
                    println!("| {name} | {method:?} | | refused: {} | | | | |", one_line(&e.to_string()));
                    continue;
                }
            };
            let seconds = start.elapsed().as_secs_f64();
            let epsilon = out.info.epsilon.ok_or("a tolerance without ε")?;
            let distance = MeshDistance::new(&out.mesh, 4.0 * epsilon);
            let worst = points.iter().map(|&p| distance.distance(&out.mesh, p)).fold(0.0, f64::max);
            let triangles = out.mesh.triangles.len();
            let uniform = match (&out.info.quadtree, method) {
                // A uniform quadtree as deep as the deepest leaf away from extraordinary corners
                // (paper 002's U'; the corner leaves go deeper only because the bound is
                // parametric), fanned like the adaptive ones: four triangles a square, three a
                // triangle.
                (Some(stats), _) => QuadtreeTessellator::new(scheme.scheme(), surface.mesh())
                    .map_err(|e| format!("{name}: {e}"))?
                    .uniform_triangle_count(stats.max_regular_depth),
                // The dual tessellation at the least uniform rate that meets the same bound (the
                // largest ungraded rate) on every face: counted by the tessellator, or, past
                // `COUNTED_VERTICES`, as twice the vertices it would make (a closed mesh's
                // triangles; a few fewer on an open one).
                (None, _) => {
                    let mesh = surface.mesh();
                    let bounds = QuadtreeTessellator::new(scheme.scheme(), mesh).map_err(|e| format!("{name}: {e}"))?;
                    let ungraded = ErrorRates { max_rate: 1 << 20, ..ErrorRates::new(Tolerance::Relative(relative)) }
                        .with_graded(false)
                        .rates(&bounds, mesh)
                        .map_err(|e| format!("{name}: {e}"))?;
                    let n = ungraded.faces.iter().copied().max().unwrap_or(1);
                    let rates = vec![n; mesh.face_count()];
                    let predicted = predicted_vertex_count(mesh, scheme.scheme().split(), &rates);
                    if predicted <= COUNTED_VERTICES {
                        let uniform =
                            TessOptions::DEFAULT.with_rates(Rates::Uniform(n)).with_max_vertices(usize::MAX / 4);
                        surface.tessellate(&uniform).map_or(0, |u| u.mesh.triangles.len() as u64)
                    } else {
                        2 * predicted as u64
                    }
                }
            };
            println!(
                "| {name} | {method:?} | {epsilon:.3e} | {triangles} | {seconds:.3} | {:.3} | {uniform} | {:.3} |",
                worst / epsilon,
                triangles as f64 / uniform.max(1) as f64
            );
        }
    }
    Ok(())
}

/// `osd_limit MESH --scheme S --grid 16`'s positions.
fn osd_points(osd: &Path, mesh: &Path, scheme: Builtin) -> Result<Vec<DVec3>, String> {
    let run = Command::new(osd)
        .arg(mesh)
        .args(["--scheme", if scheme == Builtin::Loop { "loop" } else { "catmark" }, "--grid", &GRID.to_string()])
        .output()
        .map_err(|e| format!("{}: {e}", osd.display()))?;
    if !run.status.success() {
        return Err(format!("osd_limit {}: {}", mesh.display(), String::from_utf8_lossy(&run.stderr)));
    }
    let text = String::from_utf8_lossy(&run.stdout);
    text.lines()
        .skip(1)
        .map(|line| {
            let x: Vec<f64> = line.split(',').map(|s| s.parse().unwrap_or(f64::NAN)).collect();
            match x.get(3..6) {
                Some(&[a, b, c]) if [a, b, c].iter().all(|v| v.is_finite()) => Ok(DVec3::new(a, b, c)),
                _ => Err(format!("osd_limit {}: bad line {line:?}", mesh.display())),
            }
        })
        .collect()
}

/// The first line of an error message, `|` escaped for a Markdown table.
fn one_line(message: &str) -> String {
    message.lines().next().unwrap_or_default().replace('|', "\\|")
}
