//! Hostile requests: more work than the documented limits allow (refused in one line with
//! exit status 2 before anything is allocated, allowed once the limit is raised), and
//! coordinates at the ends of f64's range.

mod common;

use common::subdiv;

/// Checks that `args` fail with status 2 and one line on stderr containing each of `expect`.
fn refused(args: &[&str], expect: &[&str]) {
    let output = subdiv(args);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: one line on stderr, got {stderr:?}");
    for e in expect {
        assert!(stderr.contains(e), "{args:?}: expected {e:?} in {stderr:?}");
    }
    assert!(output.stdout.is_empty(), "{args:?}: nothing written on stdout");
}

/// An `n × n` grid of quads as OBJ, in a temporary folder.
fn grid_obj(n: usize) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for j in 0..=n {
        for i in 0..=n {
            text += &format!("v {i} {j} 0\n");
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            text += &format!("f {} {} {} {}\n", a, a + 1, a + n + 2, a + n + 1);
        }
    }
    let path = dir.path().join("grid.obj");
    std::fs::write(&path, text).unwrap();
    (dir, path.to_str().unwrap().to_string())
}

#[test]
fn eval_grids_past_the_point_budget_are_refused() {
    // A cube at the largest grid, 6 · 4097² = 100.7 million points, aborted on memory.
    let (dir, _) = grid_obj(1);
    let cube = dir.path().join("cube.obj");
    subdiv::io::write_obj(&cube, &subdiv::mesh::shapes::cube()).unwrap();
    let cube = cube.to_str().unwrap();
    refused(&["eval", cube, "--grid", "4096"], &["cube.obj", "100712454 points", "limit of 10000000", "--max-points"]);
    refused(&["eval", cube, "--grid", "8", "--max-points", "100"], &["486 points", "limit of 100"]);
    let output = subdiv(&["eval", cube, "--grid", "8", "--max-points", "486"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(String::from_utf8_lossy(&output.stdout).lines().count(), 1 + 486);
}

#[test]
fn tessellations_past_the_vertex_budget_are_refused() {
    // 900 quads at rate 256 (an allowed rate): 59 million vertices, aborted on memory (a
    // 300 × 300 grid at rate 128 used 6 GB before the abort, when the budget was new).
    let (dir, grid) = grid_obj(30);
    let out = dir.path().join("out.glb");
    let out = out.to_str().unwrap();
    refused(
        &["tessellate", &grid, "--rate", "256", "-o", out],
        &["grid.obj", "vertices", "limit of 16777216", "--max-vertices"],
    );
    refused(
        &["tessellate", &grid, "--rate", "2", "--max-vertices", "100", "-o", out],
        &["3960 vertices", "limit of 100"],
    );
    assert!(!std::path::Path::new(out).exists(), "nothing written");
    let output = subdiv(&["tessellate", &grid, "--rate", "2", "--max-vertices", "3960", "-o", out]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    // The quadtree predicts its polygons before the work (a lower bound, counted until it
    // passes the limit): a tolerance of 1e-6 on a cube once made 12.6 million vertices (7 GB)
    // before the limit, then took 17 s to reach it.
    let cube = dir.path().join("cube.obj");
    subdiv::io::write_obj(&cube, &subdiv::mesh::shapes::cube()).unwrap();
    let cube = cube.to_str().unwrap();
    refused(
        &["tessellate", cube, "--method", "quadtree", "--tolerance", "1e-6", "--max-vertices", "20000", "-o", out],
        &["cube.obj", "at least", "more than the limit 5000", "--max-vertices"],
    );
}

#[test]
fn valences_past_the_patch_limit_are_refused_at_once() {
    // A 5000-gon aborted on an 845 MB allocation (its refined centre has valence 5000, whose
    // dense sub-patch matrices took time cubic in it); a fan of 5000 triangles the same. Their
    // smooth centres now cost the square of the valence, past the smooth limit (4096); the
    // centre of an open fan of 1500 triangles, on the boundary, is solved densely, past 1024.
    let dir = tempfile::tempdir().unwrap();
    let n = 5000;
    let ring = |i: usize| {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        format!("v {} {} 0\n", a.cos(), a.sin())
    };
    let ngon = dir.path().join("ngon.obj");
    let face: Vec<String> = (1..=n).map(|i| i.to_string()).collect();
    std::fs::write(&ngon, (0..n).map(ring).collect::<String>() + &format!("f {}\n", face.join(" "))).unwrap();
    let fan = dir.path().join("fan.obj");
    let triangles: String = (0..n).map(|i| format!("f 1 {} {}\n", i + 2, (i + 1) % n + 2)).collect();
    std::fs::write(&fan, "v 0 0 1\n".to_string() + &(0..n).map(ring).collect::<String>() + &triangles).unwrap();
    let out = dir.path().join("out.glb");
    let out = out.to_str().unwrap();
    let open = dir.path().join("open.obj");
    let m: u32 = 1500;
    let points: String = (0..=m).map(|i| format!("v {} {} 0\n", f64::from(i), f64::from(i * i) / 1e4)).collect();
    let triangles: String = (0..m).map(|i| format!("f 1 {} {}\n", i + 2, i + 3)).collect();
    std::fs::write(&open, "v 0 -10 0\n".to_string() + &points + &triangles).unwrap();
    let smooth = ["valence 5000", "limit of 4096", "RefineOptions::max_patch_valence"];
    let dense = ["valence 1501", "limit of 1024", "max_dense_patch_valence"];
    for (mesh, expect) in [(&ngon, smooth), (&fan, smooth), (&open, dense)] {
        let mesh = mesh.to_str().unwrap();
        refused(&["eval", mesh, "--grid", "2"], &expect);
        refused(&["tessellate", mesh, "--rate", "2", "-o", out], &expect);
    }
    // Refinement takes any valence.
    let refined = dir.path().join("refined.obj");
    let output = subdiv(&["refine", ngon.to_str().unwrap(), "--levels", "1", "-o", refined.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

#[test]
fn refinement_past_the_face_budget_is_refused() {
    // 225 quads at 8 levels, 900 · 4⁷ = 14.7 million faces, aborted on memory.
    let (_dir, grid) = grid_obj(15);
    refused(&["refine", &grid, "--levels", "8"], &["grid.obj", "14745600 faces", "limit of 4194304", "--max-faces"]);
    refused(&["refine", &grid, "--levels", "2", "--max-faces", "1000"], &["3600 faces", "limit of 1000"]);
    let output = subdiv(&["refine", &grid, "--levels", "2", "--max-faces", "3600"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

#[test]
fn stencil_parameters_are_exact_and_their_periods_bounded() {
    // 1/1000003 has a binary period of 10⁶ levels: 548 s before, refused at the walk limit now.
    refused(&["stencil", "--at", "1/1000003,0"], &["longer than 16384 levels", "power of two"]);
    // A common denominator past 64 bits wrapped to the stencil at (0.5, 0.5).
    refused(
        &["stencil", "--at", "1/4294967297,1/4294967298"],
        &["--at: parameter \"1/4294967297,1/4294967298\"", "64 bits"],
    );
    refused(&["stencil", "--scheme", "four-point", "--at", "9223372036854775807"], &["too large"]);
    // The same denominator twice is its own common one.
    let output = subdiv(&["stencil", "--at", "1/3,2/3", "--json"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

/// The cube scaled by `scale`, as OBJ in `dir`.
fn scaled_cube(dir: &std::path::Path, scale: f64) -> String {
    let mut cube = subdiv::mesh::shapes::cube();
    cube.positions_mut().iter_mut().for_each(|p| *p *= scale);
    let path = dir.join("cube.obj");
    subdiv::io::write_obj(&path, &cube).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn coordinates_past_f64s_headroom_are_refused_naming_the_vertex() {
    // One coordinate of 1e308: an "internal error" (a single quad) or NaN and inf with exit 0.
    let dir = tempfile::tempdir().unwrap();
    let quad = dir.path().join("quad.obj");
    std::fs::write(&quad, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 1e308\nf 1 2 3 4\n").unwrap();
    let quad = quad.to_str().unwrap();
    for command in ["eval", "tessellate", "refine"] {
        let mut args = vec![command, quad];
        if command == "eval" {
            args.extend(["--grid", "2"]);
        }
        refused(&args, &["quad.obj", "vertex 3", "too large", "scale the mesh down"]);
    }
}

#[test]
fn a_tiny_model_keeps_unit_normals() {
    // A cube scaled to 1e-90: |du × dv|² underflowed to 0 and every OBJ normal was 0.
    let dir = tempfile::tempdir().unwrap();
    let cube = scaled_cube(dir.path(), 1e-90);
    let out = dir.path().join("tiny.obj");
    let output = subdiv(&["tessellate", &cube, "--rate", "2", "-o", out.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let normals: Vec<[f64; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("vn "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert!(!normals.is_empty());
    for n in normals {
        let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((length - 1.0).abs() < 1e-6, "normal {n:?}");
    }
}

#[test]
fn a_relative_tolerance_of_a_mesh_at_one_point_says_why() {
    // Every vertex at the origin: "tolerance 0.01 is not a positive finite number" before.
    let dir = tempfile::tempdir().unwrap();
    let cube = scaled_cube(dir.path(), 0.0);
    let out = dir.path().join("point.glb");
    refused(
        &["tessellate", &cube, "--tolerance", "0.01", "--relative", "-o", out.to_str().unwrap()],
        &["cube.obj", "tolerance 0.01 is relative", "diagonal is 0.0", "absolute tolerance"],
    );
    assert!(!out.exists());
}
