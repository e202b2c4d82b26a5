//! The `subdiv` binary end to end: reports, JSON, and exit status 2 with one line on stderr for
//! every kind of bad input (never a panic's 101). The schemes' commands are in `schemes.rs`.

mod common;

use std::process::{Command, Output};

use common::{json, subdiv};
use subdiv_testkit::shared_mesh;

/// Runs `subdiv info FILE` on `bytes` written to a file named `name`, and checks that it fails
/// the way bad input must: status 2, one line on stderr naming the file and `expect`.
fn rejects(name: &str, bytes: &[u8], expect: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    let output = subdiv(&["info", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{name}: stderr {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{name}: one line on stderr, got {stderr:?}");
    assert!(stderr.contains(name), "{name}: the line names the file: {stderr}");
    assert!(stderr.contains(expect), "{name}: expected {expect:?} in {stderr:?}");
}

#[test]
fn built_in_model_report() {
    let output = subdiv(&["info"]);
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.contains("vertices        62"), "{text}");
    assert!(text.contains("problems        none"), "{text}");

    let report = json(&["info", "--json"]);
    for (key, value) in [
        ("vertices", 62),
        ("faces", 60),
        ("edges", 120),
        ("boundary_edges", 0),
        ("boundary_loops", 0),
        ("components", 1),
        ("genus", 0),
        ("valence_min", 3),
        ("valence_max", 5),
        ("extraordinary_vertices", 32),
    ] {
        assert_eq!(report[key], value, "{key}");
    }
}

#[test]
fn shared_meshes_report_their_counts() {
    let Some(spot) = shared_mesh("keenan/spot_control_mesh.obj") else { return };
    let report = json(&["info", "--json", spot.to_str().unwrap()]);
    assert_eq!(report["vertices"], 188);
    assert_eq!(report["faces"], 180);
    assert_eq!(report["extraordinary_vertices"], 80);
    assert_eq!(report["genus"], 0);

    let Some(creases) = shared_mesh("opensubdiv/catmark_cube_creases1.obj") else { return };
    let report = json(&["info", "--json", creases.to_str().unwrap()]);
    assert_eq!(report["tags"]["creases"], 12);

    // A non-manifold shared mesh: the report lists the problems, stderr has one line.
    let Some(fan) = shared_mesh("opensubdiv/catmark_fan.obj") else { return };
    let output = subdiv(&["info", "--json", fan.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(2));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["valid"], false);
    assert!(report["problems"].as_array().unwrap().iter().all(|p| p["rule"] == "non-manifold-edge"));
    assert_eq!(String::from_utf8_lossy(&output.stderr).lines().count(), 1);
    // Taken apart into sheets, it is a mesh: three sheets' worth of vertices on the spine.
    let report = json(&["info", "--json", "--split-sheets", fan.to_str().unwrap()]);
    assert_eq!(report["faces"], 13);
    assert!(report["vertices"].as_u64().unwrap() > 22, "{report}");
    // Refused by the other commands too, naming the option that takes it apart into sheets as
    // OpenSubdiv does; with it, tessellated to a tolerance by both methods.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fan.glb");
    let (fan, out) = (fan.to_str().unwrap(), out.to_str().unwrap());
    let refused = subdiv(&["tessellate", fan, "-o", out]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--split-sheets"));
    for method in ["dual", "quadtree"] {
        let args = ["tessellate", fan, "--split-sheets", "--method", method, "--tolerance", "1e-3", "--relative"];
        let output = subdiv(&[&args[..], &["-o", out]].concat());
        assert!(output.status.success(), "{method}: {}", String::from_utf8_lossy(&output.stderr));
    }
}

#[test]
fn hostile_inputs_exit_2_with_one_line() {
    rejects("empty.obj", b"", "no geometry");
    rejects("garbage.obj", b"v 1 2 three\n", ":1:");
    rejects("nan.obj", b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", ":3:");
    rejects("inf.obj", b"v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", ":3:");
    rejects("zero.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4:");
    rejects("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ":4:");
    rejects("huge.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", ":4:");
    rejects("two.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n", ":3:");
    rejects("bytes.obj", b"v 0 0 0\nv 1 0 0\n\xff\xfe 1 1\nf 1 2 3\n", ":3:");
    rejects("truncated.glb", b"glTF\x02\x00\x00\x00\x00\x01\x00\x00", "truncated.glb");
    // Topology: a bow-tie (two triangles sharing only vertex 1) and three faces on one edge.
    rejects("bowtie.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3\nf 2 4 5\n", "non-manifold");
    rejects(
        "nonmanifold.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
        "non-manifold edge",
    );
    rejects(
        "flipped.obj",
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 1 2 4\n",
        "inconsistent orientation",
    );
}

#[test]
fn a_missing_file_is_bad_input() {
    let output = subdiv(&["info", "/nonexistent/cage.obj"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("/nonexistent/cage.obj"));
}

#[test]
fn orient_repairs_a_flipped_face() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flip.obj");
    // A quad strip of three faces with the middle one flipped.
    std::fs::write(
        &path,
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 3 1 0\nf 1 2 6 5\nf 2 6 7 3\nf 3 4 8 7\n",
    )
    .unwrap();
    let path = path.to_str().unwrap();
    let output = subdiv(&["info", path]);
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("inconsistent orientation"));
    let report = json(&["info", "--json", "--orient", path]);
    assert_eq!(report["faces"], 3);
    assert_eq!(report["boundary_loops"], 1);
}

#[test]
fn refine_writes_an_obj_that_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("star2.obj");
    let output = subdiv(&["refine", "--levels", "2", "-o", out.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report = json(&["info", "--json", out.to_str().unwrap()]);
    assert_eq!(report["faces"], 60 * 16);
    assert_eq!(report["genus"], 0);
    // Loop cannot take quads: a clear error, status 2.
    let output = subdiv(&["refine", "--scheme", "loop"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("loop takes only 3-sided faces"));
}

/// `subdiv refine` writes the refined sharpness, holes and texture coordinates: refining its
/// level-1 output once more gives the level-2 refinement of the original, positions and
/// texture coordinates, on every creased shared mesh.
#[test]
fn refining_the_refined_output_continues_the_same_surface() {
    let Some(meshes) = subdiv_testkit::meshes_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let (mut compared, mut with_uv) = (0, 0);
    for file in subdiv_testkit::obj_files(&meshes) {
        let text = std::fs::read_to_string(&file).unwrap();
        if !text.lines().any(|l| l.starts_with("t crease") || l.starts_with("t corner")) {
            continue;
        }
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        let scheme = ["loop", "bilinear"].into_iter().find(|s| name.starts_with(s)).unwrap_or("catmull-clark");
        let refine = |input: &str, levels: &str, out: &str| {
            subdiv(&["refine", input, "--scheme", scheme, "--levels", levels, "-o", out]).status.success()
        };
        assert!(refine(file.to_str().unwrap(), "1", &path("once.obj")), "{name}: level 1");
        assert!(refine(&path("once.obj"), "1", &path("twice.obj")), "{name}: refining the output");
        assert!(refine(file.to_str().unwrap(), "2", &path("direct.obj")), "{name}: level 2");
        let twice = subdiv::io::load_obj(path("twice.obj")).unwrap();
        let direct = subdiv::io::load_obj(path("direct.obj")).unwrap();
        assert_eq!(twice.raw_faces(), direct.raw_faces(), "{name}: the faces");
        let size = direct.positions().iter().fold(0.0f64, |m, p| m.max(p.abs().max_element())).max(1e-300);
        for (a, b) in twice.positions().iter().zip(direct.positions()) {
            assert!(a.distance(*b) <= 1e-12 * size, "{name}: {a} against {b}");
        }
        assert_eq!(twice.tags.creases, direct.tags.creases, "{name}: the creases");
        assert_eq!(twice.tags.holes, direct.tags.holes, "{name}: the holes");
        assert_eq!(twice.channels.len(), direct.channels.len(), "{name}: the channels");
        for (a, b) in twice.channels.iter().zip(&direct.channels) {
            let corners =
                |c: &subdiv::mesh::Channel| c.indices().iter().map(|&i| c.value(i).to_vec()).collect::<Vec<_>>();
            for (x, y) in corners(a).iter().zip(corners(b)) {
                assert!(x.iter().zip(&y).all(|(p, q)| (p - q).abs() <= 1e-12), "{name}: uv {x:?} against {y:?}");
            }
            with_uv += 1;
        }
        compared += 1;
    }
    // 51 files have crease or corner tags, 45 of them texture coordinates.
    assert_eq!((compared, with_uv), (51, 45));
}

#[test]
fn eval_writes_osd_limit_csv_and_rejects_bad_samples() {
    // The built-in model: 60 quads, (N + 1)² rows each, in osd_limit's columns.
    let output = subdiv(&["eval", "--grid", "2"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let text = String::from_utf8(output.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("face,u,v,px,py,pz,dux,duy,duz,dvx,dvy,dvz"));
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 60 * 9);
    assert!(rows.iter().all(|r| r.len() == 12));
    // Row order: face outer, then v, then u.
    assert_eq!(&rows[1][..3], [0.0, 0.5, 0.0]);
    assert_eq!(&rows[9][..3], [1.0, 0.0, 0.0]);

    // Samples: commas or spaces, comments; the same point as the grid's, to the bit.
    let dir = tempfile::tempdir().unwrap();
    let samples = dir.path().join("samples.txt");
    std::fs::write(&samples, "# face u v\n1, 0 0\n\n1 0.5 0.0  # trailing comment\n").unwrap();
    let out = dir.path().join("points.csv");
    let output = subdiv(&["eval", "--samples", samples.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let written = std::fs::read_to_string(&out).unwrap();
    let grid_rows: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(written.lines().skip(1).collect::<Vec<_>>(), [grid_rows[9], grid_rows[10]]);

    // Bad lines: status 2, one line naming the file, the line and the rule; no output file.
    for (content, expect) in [
        ("0 0 0\n0 0.5\n", "samples.txt:2: expected `face u v`"),
        ("0 0 0\n# ok\n0 x 0\n", "samples.txt:3: expected `face u v`"),
        ("60 0 0\n", "samples.txt:1: face 60 does not exist: the mesh has 60 faces"),
        ("0 1.5 0\n", "samples.txt:1: face 0: parameter (1.5, 0.0) is outside its domain [0, 1]²"),
        ("0 nan 0\n", "samples.txt:1: face 0: parameter (NaN, 0.0) is outside its domain"),
    ] {
        std::fs::write(&samples, content).unwrap();
        let rejected = dir.path().join("rejected.csv");
        let output = subdiv(&["eval", "--samples", samples.to_str().unwrap(), "-o", rejected.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{content:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{content:?}: {stderr}");
        assert!(stderr.contains(expect), "{content:?}: expected {expect:?} in {stderr:?}");
        assert!(!rejected.exists() && output.stdout.is_empty(), "{content:?}: nothing written");
    }
    // A scheme without boundary rules on an open mesh, a face whose limit under the dual
    // split's boundary rule has no area, and a mesh a scheme cannot take: typed errors.
    let open = dir.path().join("open.obj");
    subdiv::io::write_obj(&open, &subdiv::mesh::shapes::quad_grid(1, 1)).unwrap();
    let output = subdiv(&["eval", "--scheme", "kobbelt", "--grid", "1", open.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    let closed_only = dir.path().join("closed-only.toml");
    let text = "name = \"x\"\n[rules.dual]\nown = \"1/4\"\ncorner = \"(3 + 2*cos(2*pi*j/n))/(4*n)\"\n";
    std::fs::write(&closed_only, text).unwrap();
    let output =
        subdiv(&["eval", "--scheme-file", closed_only.to_str().unwrap(), "--grid", "1", open.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("has no rules for boundaries"), "{stderr}");
    let output = subdiv(&["eval", "--scheme", "doo-sabin", "--grid", "1", open.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("whose boundary sides leave no interior corner"), "{stderr}");
    let output = subdiv(&["eval", "--scheme", "loop", "--grid", "1"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("loop takes only 3-sided faces"));
}

#[test]
fn tessellate_writes_a_watertight_glb_and_obj() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("star.glb");
    let out = subdiv(&["tessellate", "--tolerance", "0.05", "--relative", "-o", glb.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary = String::from_utf8_lossy(&out.stderr);
    assert!(summary.contains("triangles") && summary.contains("60 faces"), "{summary}");
    let back = subdiv::io::load_mesh(&glb, &Default::default()).unwrap();
    assert!(back.face_count() > 0 && back.boundary_edge_count() == 0);

    let cube = dir.path().join("in.obj");
    subdiv::io::write_obj(&cube, &subdiv::mesh::shapes::cube()).unwrap();
    for method in ["quadtree", "dual"] {
        let obj = dir.path().join(format!("cube-{method}.obj"));
        let policy: &[&str] = if method == "quadtree" { &["--tolerance", "0.01"] } else { &["--rate", "5"] };
        let mut args = vec!["tessellate", cube.to_str().unwrap(), "--method", method, "--polygons", "-o"];
        args.push(obj.to_str().unwrap());
        args.extend_from_slice(policy);
        let out = subdiv(&args);
        assert!(out.status.success(), "{method}: {}", String::from_utf8_lossy(&out.stderr));
        // Polygons share edges exactly: the OBJ builds into a closed manifold mesh of the cube's genus.
        let mesh = subdiv::io::load_mesh(&obj, &Default::default()).unwrap();
        assert_eq!(mesh.boundary_edge_count(), 0, "{method}");
        assert_eq!(mesh.genus(), Some(0), "{method}");
        assert!(mesh.face_size_histogram().contains_key(&4), "{method}: quads");
    }
}

/// With no arguments: the built-in model at the default rate, to `tessellation.glb`; the
/// parameters CSV has one row per output vertex; Loop and screen-space rates work.
#[test]
fn tessellate_defaults_params_and_policies() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_subdiv")).arg("tessellate").current_dir(dir.path()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let glb = dir.path().join("tessellation.glb");
    let back = subdiv::io::load_mesh(&glb, &Default::default()).unwrap();
    assert_eq!(back.boundary_edge_count(), 0);

    let ico = dir.path().join("ico.obj");
    subdiv::io::write_obj(&ico, &subdiv::mesh::shapes::icosahedron()).unwrap();
    let (obj, csv) = (dir.path().join("ico-out.obj"), dir.path().join("ico.csv"));
    let out = subdiv(&[
        "tessellate",
        ico.to_str().unwrap(),
        "--scheme",
        "loop",
        "--pixels",
        "20",
        "--camera",
        "0,-6,1,0,0,0,0,0,1,50",
        "--viewport",
        "640,480",
        "-o",
        obj.to_str().unwrap(),
        "--params",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let vertices = std::fs::read_to_string(&obj).unwrap().lines().filter(|l| l.starts_with("v ")).count();
    let rows: Vec<String> = std::fs::read_to_string(&csv).unwrap().lines().map(str::to_string).collect();
    assert_eq!(rows[0], "vertex,face,u,v");
    assert_eq!(rows.len(), vertices + 1);
    assert!(rows[1].starts_with("0,"), "{}", rows[1]);
}

/// `--tolerance` takes the quadtree unless told otherwise: an open mesh with holes and texture
/// coordinates goes through, where the dual method's rates, which have no rings at an
/// extraordinary vertex on a texture seam, refuse it by name.
#[test]
fn tolerance_takes_the_quadtree_by_default() {
    let Some(mesh) = shared_mesh("opensubdiv/catmark_hole_test1.obj") else { return };
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("holes.glb");
    let args = ["tessellate", mesh.to_str().unwrap(), "--tolerance", "1e-2", "--relative", "-o", glb.to_str().unwrap()];
    let out = subdiv(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("(Quadtree, ε ="),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(subdiv::io::load_mesh(&glb, &Default::default()).unwrap().face_count() > 0);
    // The dual method too: its extraordinary vertices on texture seams take open
    // rings that share their points on the seams.
    let out = subdiv(&[&args[..], &["--method", "dual"]].concat());
    let summary = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && summary.contains("(Dual, ε ="), "{summary}");
}

/// `--pixel-error P`: the quadtree to a screen-space error bound; a farther camera needs fewer
/// triangles; the dual method and a camera without a screen policy are refused.
#[test]
fn pixel_error_bounds_the_quadtree_on_the_screen() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("screen.glb");
    let triangles = |camera: &str| {
        let out = subdiv(&["tessellate", "--pixel-error", "0.5", "--camera", camera, "-o", glb.to_str().unwrap()]);
        let summary = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success() && summary.contains("0.5 pixels of error on the screen"), "{summary}");
        let counted = summary.split(" triangles in").next().and_then(|s| s.rsplit(' ').next());
        counted.and_then(|n| n.parse::<usize>().ok()).unwrap_or_else(|| panic!("{summary}"))
    };
    assert!(triangles("0,-4,1,0,0,0,0,0,1") > triangles("0,-12,3,0,0,0,0,0,1"));
    let camera = ["--camera", "0,-4,1,0,0,0,0,0,1", "-o", glb.to_str().unwrap()];
    let out = subdiv(&[&["tessellate", "--pixel-error", "0.5", "--method", "dual"][..], &camera].concat());
    fails_with_one_line(&out, &["--pixel-error", "--pixels"]);
    let out = subdiv(&[&["tessellate"][..], &camera].concat());
    fails_with_one_line(&out, &["--camera goes with"]);
    let out = subdiv(&["tessellate", "--pixel-error", "0.5", "-o", glb.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn tessellate_rejects_bad_tolerances_and_schemes() {
    for t in ["0", "-1", "NaN", "inf"] {
        let out = subdiv(&["tessellate", "--tolerance", t]);
        assert_eq!(out.status.code(), Some(2), "{t}: {}", String::from_utf8_lossy(&out.stderr));
    }
    let out = subdiv(&["tessellate", "--tolerance", "0.1", "--scheme", "loop"]);
    assert_eq!(out.status.code(), Some(2));
    let out = subdiv(&["tessellate", "--tolerance", "0.1", "-o", "x.png"]);
    assert_eq!(out.status.code(), Some(2));
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("x.glb");
    let o = o.to_str().unwrap();
    for bad in [
        &["--rate", "0"][..],
        &["--rate", "100000"],
        &["--method", "quadtree", "--rate", "4"],
        &["--pixels", "4", "--camera", "0,0,1,0,0,1,0,1,0"],
        &["--pixels", "4", "--camera", "1,2,3"],
        &["--pixels", "-1", "--camera", "0,-5,0,0,0,0,0,0,1"],
        &["--pixels", "4", "--camera", "0,-5,0,0,0,0,0,0,1", "--viewport", "0,10"],
    ] {
        let out = subdiv(&[&["tessellate", "-o", o], bad].concat());
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(!dir.path().join("x.glb").exists(), "{bad:?} wrote a file");
    }
}

/// `subdiv render`: bad arguments fail with the rule before anything is written (no device
/// needed); with a device, a two-frame animation writes two numbered PNGs of the asked size,
/// the first (undeformed) equal to a plain render, the second different.
#[test]
fn render_writes_numbered_frames_and_rejects_bad_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("spin.png");
    let out_arg = out.to_str().unwrap();
    for (args, expect) in [
        (&["--size", "0,48"][..], "--size 0,48: sides must be integers from 1 to 16384"),
        (&["--size", "16385,48"][..], "sides must be integers from 1 to 16384"),
        (&["--size", "64"][..], "--size 64: expected 2 numbers"),
        (&["--frames", "0"][..], "--frames 0: the number of frames must be at least 1"),
        (&["--rate", "0"][..], "--rate 0: rates are integers from 1 to 1024"),
        (&["--rate", "1025"][..], "rates are integers from 1 to 1024"),
        (&["--pixels", "-1"][..], "--pixels -1: pixels per edge must be a positive finite number"),
    ] {
        let mut all = vec!["render", "-o", out_arg];
        all.extend_from_slice(args);
        let output = subdiv(&all);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expect), "{args:?}: expected {expect:?} in {stderr:?}");
    }
    let jpg = dir.path().join("x.jpg");
    let output = subdiv(&["render", "-o", jpg.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("the output must end in .png"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written on bad input");

    // The rest draws: skipped (saying so) without an adapter, unless SUBDIV_REQUIRE_GPU=1.
    if subdiv_testkit::gpu().is_none() {
        return;
    }
    let size = ["--size", "64,48"];
    let output = subdiv(&["render", "-o", out_arg, "--frames", "2", "--wireframe", "--cage", size[0], size[1]]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("60 faces") && stderr.contains("2 frames") && stderr.contains("64×48"), "{stderr}");
    let frame = |k: u32| image::open(dir.path().join(format!("spin_{k:04}.png"))).unwrap().to_rgb8();
    let (first, second) = (frame(0), frame(1));
    assert_eq!(first.dimensions(), (64, 48));
    assert_eq!(second.dimensions(), (64, 48));
    assert_ne!(first, second, "frame 1 is twisted");
    let plain = dir.path().join("plain.png");
    let output = subdiv(&["render", "-o", plain.to_str().unwrap(), "--wireframe", "--cage", size[0], size[1]]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(image::open(&plain).unwrap().to_rgb8(), first, "frame 0 is the undeformed model");
    // Only the three PNGs: no temporary files left behind.
    let mut names: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(names, ["plain.png", "spin_0000.png", "spin_0001.png"]);
}

/// `render --texture`: a checker or an image through spot's texture coordinates, each a
/// different picture from the plain surface; a bad checker, a missing image or a mesh without
/// texture coordinates are errors naming what is wrong, with nothing written.
#[test]
fn render_draws_textures_through_the_texture_coordinates() {
    let Some(spot) = shared_mesh("keenan/spot_control_mesh.obj") else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.png");
    let (spot, out_arg) = (spot.to_str().unwrap(), out.to_str().unwrap());
    for (args, expect) in [
        (&["render", spot, "--texture", "checker:0"][..], "checker:0: squares per unit are 1 to 4096"),
        (&["render", spot, "--texture", "checker:x"][..], "checker:x: N must be an integer"),
        (&["render", spot, "--texture", "/nonexistent/t.png"][..], "/nonexistent/t.png: --texture"),
        (&["render", "--texture", "checker"][..], "--texture: the mesh has no texture coordinates"),
    ] {
        let output = subdiv(&[args, &["-o", out_arg][..]].concat());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success() && stderr.contains(expect), "{args:?}: expected {expect:?} in {stderr:?}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written on bad input");
    if subdiv_testkit::gpu().is_none() {
        return;
    }
    let size = ["--size", "96,72", "--rate", "3"];
    let render = |name: &str, texture: &[&str]| {
        let path = dir.path().join(name);
        let output = subdiv(&[&["render", spot, "-o", path.to_str().unwrap()][..], &size, texture].concat());
        assert!(output.status.success(), "{texture:?}: {}", String::from_utf8_lossy(&output.stderr));
        image::open(&path).unwrap().to_rgb8()
    };
    let plain = render("plain.png", &[]);
    let checker = render("checker.png", &["--texture", "checker:8"]);
    let image = render("image.png", &["--texture", dir.path().join("checker.png").to_str().unwrap()]);
    assert_ne!(plain, checker);
    assert_ne!(checker, image);
    assert_ne!(plain, image);
}

/// A unit cube as OBJ, its coordinates multiplied by `scale`.
fn cube_obj(scale: f64) -> String {
    let mut text = String::new();
    for i in 0..8 {
        let [x, y, z] = [i & 1, (i >> 1) & 1, (i >> 2) & 1].map(|c| f64::from(c) * scale);
        text += &format!("v {x:e} {y:e} {z:e}\n");
    }
    text + "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n"
}

/// Status 2 and one line on stderr containing every one of `expect`.
fn fails_with_one_line(output: &Output, expect: &[&str]) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "stderr {stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line on stderr, got {stderr:?}");
    for word in expect {
        assert!(stderr.contains(word), "expected {word:?} in {stderr:?}");
    }
}

#[test]
fn an_obj_may_start_with_a_byte_order_mark() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bom.obj");
    std::fs::write(&path, format!("\u{feff}{}", cube_obj(1.0))).unwrap();
    let output = subdiv(&["info", path.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

#[test]
fn an_output_equal_to_an_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cube.obj");
    std::fs::write(&input, cube_obj(1.0)).unwrap();
    let linked = dir.path().join("linked.obj");
    std::fs::hard_link(&input, &linked).unwrap();
    let input_name = input.to_str().unwrap();
    for output in [input_name.to_owned(), format!("{}/./cube.obj", dir.path().display()), linked.display().to_string()]
    {
        let run = subdiv(&["refine", input_name, "-o", &output]);
        fails_with_one_line(&run, &["cube.obj", "is this input file"]);
    }
    assert_eq!(std::fs::read_to_string(&input).unwrap(), cube_obj(1.0));
}

#[test]
fn a_closed_pipe_ends_quietly_with_exit_0() {
    use std::io::Read;
    let mut child = Command::new(env!("CARGO_BIN_EXE_subdiv"))
        .args(["refine", "--levels", "4"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut head = [0u8; 10];
    child.stdout.take().unwrap().read_exact(&mut head).unwrap();
    // The pipe's read end is dropped here, as `head -c 10` exits.
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("pipe"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn sigterm_during_a_write_removes_the_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big.obj");
    let child = Command::new(env!("CARGO_BIN_EXE_subdiv"))
        .args(["refine", "--levels", "7", "-o", out.to_str().unwrap()])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let temporary = || {
        std::fs::read_dir(dir.path())
            .unwrap()
            .filter_map(Result::ok)
            .any(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
    };
    // Wait for the write to begin (refining comes first), then interrupt it.
    let start = std::time::Instant::now();
    while !temporary() && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(temporary(), "the write began");
    Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(143));
    assert!(!temporary(), "the temporary file is removed");
    assert!(!out.exists(), "no output was written");
}

#[test]
fn gltf_buffers_outside_the_folder_need_allow_outside_uris() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("model");
    std::fs::create_dir(&folder).unwrap();
    let bytes: Vec<u8> =
        [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(dir.path().join("outside.bin"), bytes).unwrap();
    let gltf = serde_json::json!({
        "asset": { "version": "2.0" },
        "buffers": [{ "uri": "../outside.bin", "byteLength": 36 }],
        "bufferViews": [{ "buffer": 0, "byteLength": 36 }],
        "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3" }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
    });
    let path = folder.join("a.gltf");
    std::fs::write(&path, gltf.to_string()).unwrap();
    let path = path.to_str().unwrap();
    fails_with_one_line(
        &subdiv(&["info", path]),
        &["a.gltf", "buffers[0].uri '../outside.bin'", "--allow-outside-uris"],
    );
    let allowed = subdiv(&["info", "--allow-outside-uris", path]);
    assert!(allowed.status.success(), "{}", String::from_utf8_lossy(&allowed.stderr));
}

#[test]
fn a_glb_of_a_mesh_too_small_for_f32_is_refused_naming_input_and_output() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tiny.obj");
    std::fs::write(&input, cube_obj(1e-50)).unwrap();
    let output = dir.path().join("tiny.glb");
    let run = subdiv(&["tessellate", input.to_str().unwrap(), "-o", output.to_str().unwrap()]);
    fails_with_one_line(&run, &["tiny.obj", "tiny.glb", "scale the mesh up"]);
    assert!(!output.exists());
}

/// `subdiv tessellate --params` lists every GLB vertex (the seams' split copies included) with
/// its texture coordinates; `subdiv eval --samples` at those parameters gives the same `s,t`
/// to 1e-12, and the GLB's `TEXCOORD_0` holds them (f32), on spot and `catmark_fvar_bound1`,
/// with both methods.
#[test]
fn tessellated_texture_coordinates_are_evals_at_their_params() {
    let methods: [&[&str]; 2] = [&["--rate", "3"], &["--method", "quadtree", "--tolerance", "3e-2", "--relative"]];
    for (file, method) in ["keenan/spot_control_mesh.obj", "opensubdiv/catmark_fvar_bound1.obj"]
        .into_iter()
        .flat_map(|f| methods.iter().map(move |m| (f, *m)))
    {
        let Some(mesh) = shared_mesh(file) else { return };
        let dir = tempfile::tempdir().unwrap();
        let (glb, csv, samples) = (dir.path().join("s.glb"), dir.path().join("p.csv"), dir.path().join("s.txt"));
        let mut args = vec!["tessellate", mesh.to_str().unwrap()];
        args.extend_from_slice(method);
        args.extend(["--params", csv.to_str().unwrap(), "-o", glb.to_str().unwrap()]);
        let out = subdiv(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("vertex,face,u,v,s,t"), "{file}");
        let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
        let points: String = rows.iter().map(|r| format!("{} {:?} {:?}\n", r[1], r[2], r[3])).collect();
        std::fs::write(&samples, points).unwrap();
        let out = subdiv(&["eval", mesh.to_str().unwrap(), "--samples", samples.to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let evaluated = String::from_utf8(out.stdout).unwrap();
        let mut evaluated = evaluated.lines();
        let header: Vec<&str> = evaluated.next().unwrap().split(',').collect();
        let (s, t) = (header.iter().position(|&c| c == "s").unwrap(), header.iter().position(|&c| c == "t").unwrap());
        let evaluated: Vec<Vec<f64>> = evaluated.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
        assert_eq!(evaluated.len(), rows.len(), "{file}");
        for (row, e) in rows.iter().zip(&evaluated) {
            assert!((row[4] - e[s]).abs() <= 1e-12 && (row[5] - e[t]).abs() <= 1e-12, "{file}: {row:?} against {e:?}");
        }
        // The GLB's vertices are the rows, in order, with their coordinates.
        let back = subdiv::io::load(&glb).unwrap();
        let uv = back.channels.iter().find(|c| c.name() == "uv").expect("TEXCOORD_0 read back");
        assert_eq!(uv.value_count(), rows.len(), "{file}");
        for (k, row) in rows.iter().enumerate() {
            let v = uv.value(k as u32);
            assert!((v[0] - row[4]).abs() < 1e-6 && (v[1] - row[5]).abs() < 1e-6, "{file}: vertex {k}");
        }
        assert_eq!(back.positions().len(), rows.len(), "{file}");
    }
}

/// An OBJ tessellation as the numbers of its vertices and points (`vn` lines) and its faces,
/// each a list of corners as text (position, normal, texture coordinates), turned to start at
/// its least corner, sorted: equal for the same mesh whatever the order of its lines.
fn obj_mesh(path: &std::path::Path) -> (usize, usize, Vec<Vec<[String; 3]>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let (mut v, mut vn, mut vt, mut faces) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let rest = |w: std::str::SplitWhitespace<'_>| w.collect::<Vec<_>>().join(" ");
        match words.next() {
            Some("v") => v.push(rest(words)),
            Some("vn") => vn.push(rest(words)),
            Some("vt") => vt.push(rest(words)),
            Some("f") => {
                let mut corners: Vec<[String; 3]> = words
                    .map(|c| {
                        let i: Vec<&str> = c.split('/').collect();
                        let at = |list: &Vec<String>, k: &str| {
                            k.parse::<usize>().map_or(String::new(), |k| list[k - 1].clone())
                        };
                        [at(&v, i[0]), at(&vn, i[2]), at(&vt, i[1])]
                    })
                    .collect();
                let least = (0..corners.len()).min_by_key(|&k| corners[k].clone()).unwrap();
                corners.rotate_left(least);
                faces.push(corners);
            }
            _ => {}
        }
    }
    faces.sort();
    (v.len(), vn.len(), faces)
}

#[test]
fn face_range_parts_merge_to_the_one_job_tessellation() {
    let Some(spot) = shared_mesh("keenan/spot_control_mesh.obj") else { return };
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let spot = spot.to_str().unwrap();
    let whole = subdiv(&["tessellate", spot, "--rate", "8", "-o", &path("whole.obj")]);
    assert!(whole.status.success(), "{}", String::from_utf8_lossy(&whole.stderr));
    // Spot has 180 faces; the last range runs past them, as a batch of fixed ranges would.
    let ranges = ["0..45", "45..90", "90..135", "135..200"];
    let mut parts = Vec::new();
    for (k, range) in ranges.iter().enumerate() {
        let part = path(&format!("part{k}.obj"));
        let out = subdiv(&["tessellate", spot, "--rate", "8", "--faces", range, "-o", &part]);
        assert!(out.status.success(), "{range}: {}", String::from_utf8_lossy(&out.stderr));
        parts.push(part);
    }
    let merged = path("merged.obj");
    let args: Vec<&str> =
        ["merge"].into_iter().chain(parts.iter().map(String::as_str)).chain(["-o", &merged]).collect();
    let out = subdiv(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (whole, merged) = (obj_mesh(std::path::Path::new(&path("whole.obj"))), obj_mesh(std::path::Path::new(&merged)));
    assert_eq!((whole.0, whole.1, whole.2.len()), (merged.0, merged.1, merged.2.len()));
    assert!(whole.2 == merged.2, "the merged faces differ from the one job's");
    // Into a GLB too; bad ranges and outputs are refused by name.
    let out = subdiv(&[&args[..args.len() - 1], &[&path("merged.glb")]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for (range, output, expect) in [
        ("180..190", "p.obj", "starts at a face of the mesh"),
        ("9..3", "p.obj", "expected A..B"),
        ("0..10", "p.glb", "write .obj"),
    ] {
        let out = subdiv(&["tessellate", spot, "--faces", range, "-o", &path(output)]);
        assert_eq!(out.status.code(), Some(2), "{range}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(expect),
            "{range}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}
