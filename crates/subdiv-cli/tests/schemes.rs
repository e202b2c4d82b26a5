//! The `subdiv` binary's scheme commands end to end: `analyze`, `stencil`, `plot-basis`,
//! `scheme`, scheme files (curve, local curve and surface), and every built-in scheme through
//! `eval`, `tessellate` and `render` where it goes.

mod common;

use common::{json, subdiv};

#[test]
fn analyze_reports_the_subdominant_eigenvalue() {
    let report = json(&["analyze", "--scheme", "loop", "--valence", "6", "--json"]);
    let subdominant = report["subdominant"].as_f64().unwrap();
    assert!((subdominant - 0.5).abs() < 1e-12, "regular Loop has λ1 = 1/2, got {subdominant}");
    assert_eq!(report["subdominant_real_pair"], true);
    assert_eq!(subdiv(&["analyze", "--valence", "2"]).status.code(), Some(2));
    // A boundary vertex of Loop with three faces (the regular boundary) under its boundary rule.
    let report = json(&["analyze", "--scheme", "loop", "--boundary-faces", "3", "--json"]);
    assert_eq!((report["valence"].as_u64(), report["c1"].as_bool()), (Some(4), Some(true)));
    assert_eq!(report["characteristic_map"]["outlines"], 1);
    // Doo-Sabin's regular boundary vertex under Chaikin's rule; a scheme without boundary
    // rules: a typed refusal, not a verdict.
    let report = json(&["analyze", "--scheme", "doo-sabin", "--boundary-faces", "2", "--json"]);
    assert_eq!(report["c1"].as_bool(), Some(true));
    assert!((report["subdominant"].as_f64().unwrap() - 0.75).abs() < 1e-9, "{report}");
    let out = subdiv(&["analyze", "--scheme", "butterfly", "--boundary-faces", "2"]);
    assert!(out.status.success());
    let closed_only = tempfile::tempdir().unwrap();
    let file = closed_only.path().join("x.toml");
    std::fs::write(&file, "name = \"x\"\n[rules.sqrt3]\nvertex = { spoke = \"1/(3*k)\" }\n").unwrap();
    let out = subdiv(&["analyze", "--scheme-file", file.to_str().unwrap(), "--boundary-faces", "2"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("boundaries"));
}

#[test]
fn stencil_prints_the_papers_four_point_numbers() {
    // Paper 000: the four-point scheme at n = 3 has denominator 5589, its derivative 540.
    let report = json(&["stencil", "--scheme", "four-point", "--n", "3", "--exact", "--json"]);
    let phi: Vec<&str> = report["phi"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    assert_eq!(phi.len(), 19);
    assert_eq!(&phi[..6], ["0", "-1/5589", "16/5589", "0", "-256/5589", "-410/5589"]);
    assert_eq!(report["x"][0], "-3");
    assert_eq!(report["dphi"][6], "2/3"); // 360/540
    // A Catmull-Clark extraordinary vertex of valence 5: 2k + 8 weights summing to 1.
    let report = json(&["stencil", "--valence", "5", "--at", "0,0", "--json"]);
    let weights = report["stencils"][0]["position"].as_array().unwrap();
    assert_eq!(weights.len(), 18);
    assert!((weights.iter().map(|w| w.as_f64().unwrap()).sum::<f64>() - 1.0).abs() < 1e-12);
    // √3 through its ternary split: at a vertex of valence 5, Kobbelt's limit weight
    // 1 / (1 + 3kβ) on the vertex, β = (4 − 2 cos(2π/5)) / 45, over its 24 control points.
    let report = json(&["stencil", "--scheme", "sqrt3", "--valence", "5", "--at", "0,0", "--json"]);
    let weights = report["stencils"][0]["position"].as_array().unwrap();
    assert_eq!(weights.len(), 24);
    let beta = (4.0 - 2.0 * (std::f64::consts::TAU / 5.0).cos()) / 45.0;
    assert!((weights[0].as_f64().unwrap() - 1.0 / (1.0 + 15.0 * beta)).abs() < 1e-12, "{weights:?}");
    // Off the grid: status 2.
    assert_eq!(subdiv(&["stencil", "--scheme", "four-point", "--n", "3", "--at", "1/2"]).status.code(), Some(2));
    // Exact surface stencils: sw-quad at valence 5 (paper 000 Fig. 6), and a refusal for Loop at
    // valence 5, whose weights involve cos(2π/5).
    let report = json(&["stencil", "--scheme", "sw-quad", "--valence", "5", "--at", "1/3,0", "--exact", "--json"]);
    assert_eq!(report["stencils"][0]["position"][0], "47/145");
    let refused = subdiv(&["stencil", "--scheme", "loop", "--valence", "5", "--at", "1/3,0", "--exact"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("no exact stencils"));
}

/// `stencil --scheme-file`: a built-in's own file gives the built-in's stencils, bit for bit, in
/// decimals and fractions; a variant of it (other weights) gives its own, still affine.
#[test]
fn stencil_takes_a_scheme_file() {
    let dir = tempfile::tempdir().unwrap();
    let printed = subdiv(&["scheme", "catmull-clark"]);
    assert!(printed.status.success(), "{}", String::from_utf8_lossy(&printed.stderr));
    let file = dir.path().join("cc.toml");
    std::fs::write(&file, &printed.stdout).unwrap();
    let file = file.to_str().unwrap();
    for exact in [&[][..], &["--exact"]] {
        let at = ["--valence", "5", "--at", "1/3,1/5", "--json"];
        let builtin = subdiv(&[&["stencil", "--scheme", "catmull-clark"][..], &at, exact].concat());
        let from_file = subdiv(&[&["stencil", "--scheme-file", file][..], &at, exact].concat());
        assert!(from_file.status.success(), "{}", String::from_utf8_lossy(&from_file.stderr));
        assert_eq!(from_file.stdout, builtin.stdout, "{exact:?}");
    }
    // Another vertex rule, still affine: (k - 3)/k + k · 2/k² + k · 1/k² = 1.
    let variant = String::from_utf8(printed.stdout.clone())
        .unwrap()
        .replace("centre = \"(k - 2)/k\", spoke = \"1/k^2\"", "centre = \"(k - 3)/k\", spoke = \"2/k^2\"")
        .replace("name = \"catmull-clark\"", "name = \"cc-variant\"");
    let variant_file = dir.path().join("variant.toml");
    std::fs::write(&variant_file, variant).unwrap();
    let at = ["stencil", "--valence", "5", "--at", "1/3,1/5", "--json", "--scheme-file"];
    let output = subdiv(&[&at[..], &[variant_file.to_str().unwrap()]].concat());
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["scheme"], "cc-variant");
    let position: Vec<f64> =
        report["stencils"][0]["position"].as_array().unwrap().iter().map(|w| w.as_f64().unwrap()).collect();
    assert!((position.iter().sum::<f64>() - 1.0).abs() < 1e-9, "{position:?}");
    let builtin = subdiv(&["stencil", "--scheme", "catmull-clark", "--valence", "5", "--at", "1/3,1/5", "--json"]);
    let builtin: serde_json::Value = serde_json::from_slice(&builtin.stdout).unwrap();
    assert_ne!(report["stencils"], builtin["stencils"]);
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "name = \"x\"\n").unwrap();
    let refused = subdiv(&["stencil", "--scheme-file", bad.to_str().unwrap()]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("bad.toml"));
}

/// A cage with texture coordinates under a scheme without face-varying rules of its own (the
/// interpolating ones): linear texture coordinates (the default mode) are evaluated and carried,
/// a smooth mode is left out with a notice by `eval` and `tessellate` alike, never refused.
#[test]
fn schemes_without_face_varying_rules_take_linear_texture_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    // An octahedron (butterfly's triangles) and a cube (Kobbelt's, Doo-Sabin's and mid-edge's
    // quads), texture coordinates at every corner.
    let mut octahedron =
        String::from("v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\nvt 0 0\nvt 1 0\nvt 0 1\n");
    for [a, b, c] in [[1, 3, 5], [3, 2, 5], [2, 4, 5], [4, 1, 5], [3, 1, 6], [2, 3, 6], [4, 2, 6], [1, 4, 6]] {
        octahedron.push_str(&format!("f {a}/1 {b}/2 {c}/3\n"));
    }
    let mut cube = String::new();
    for i in 0..8 {
        cube.push_str(&format!("v {} {} {}\n", i & 1, (i >> 1) & 1, (i >> 2) & 1));
    }
    cube.push_str("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    for [a, b, c, d] in [[1, 3, 4, 2], [5, 6, 8, 7], [1, 2, 6, 5], [3, 7, 8, 4], [1, 5, 7, 3], [2, 4, 8, 6]] {
        cube.push_str(&format!("f {a}/1 {b}/2 {c}/3 {d}/4\n"));
    }
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_string()
    };
    let (octahedron, cube) = (write("octahedron.obj", &octahedron), write("cube.obj", &cube));
    for (scheme, cage) in [("butterfly", &octahedron), ("kobbelt", &cube), ("doo-sabin", &cube), ("midedge", &cube)] {
        // Linear (the default mode): each face's corners (0, 0), (1, 0), (0, 1) [and (1, 1)]
        // interpolated at its (u, v), so s = u and t = v at every point.
        let output = subdiv(&["eval", cage, "--scheme", scheme, "--grid", "2"]);
        assert!(output.status.success(), "{scheme}: {}", String::from_utf8_lossy(&output.stderr));
        let text = String::from_utf8(output.stdout).unwrap();
        let mut lines = text.lines();
        assert!(lines.next().unwrap().ends_with(",s,t,dsu,dtu,dsv,dtv"), "{scheme}");
        for line in lines {
            let x: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
            assert!((x[12] - x[1]).abs() < 1e-12 && (x[13] - x[2]).abs() < 1e-12, "{scheme}: {line}");
        }
        let out = dir.path().join("out.glb");
        let output = subdiv(&["tessellate", cage, "--scheme", scheme, "--rate", "4", "-o", out.to_str().unwrap()]);
        assert!(output.status.success(), "{scheme}: {}", String::from_utf8_lossy(&output.stderr));
        assert!(!String::from_utf8_lossy(&output.stderr).contains("left out"), "{scheme}");
        assert!(String::from_utf8_lossy(&std::fs::read(&out).unwrap()).contains("TEXCOORD_0"), "{scheme}");
        // A smooth mode, which the scheme has no rules for: left out, and said.
        let smooth = ["--scheme", scheme, "--fvar-interpolation", "none"];
        let output = subdiv(&[&["eval", cage, "--grid", "2"][..], &smooth].concat());
        assert!(output.status.success(), "{scheme}: {}", String::from_utf8_lossy(&output.stderr));
        let text = String::from_utf8(output.stdout).unwrap();
        assert_eq!(text.lines().next(), Some("face,u,v,px,py,pz,dux,duy,duz,dvx,dvy,dvz"), "{scheme}");
        assert!(String::from_utf8_lossy(&output.stderr).contains("texture coordinates left out"), "{scheme}");
        let output = subdiv(&[&["tessellate", cage, "--rate", "4", "-o", out.to_str().unwrap()][..], &smooth].concat());
        assert!(output.status.success(), "{scheme}: {}", String::from_utf8_lossy(&output.stderr));
        assert!(String::from_utf8_lossy(&output.stderr).contains("texture coordinates left out"), "{scheme}");
    }
    // Loop has the rules: the coordinates are evaluated.
    let output = subdiv(&["eval", &octahedron, "--scheme", "loop", "--grid", "2"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8(output.stdout).unwrap().lines().next().unwrap().ends_with(",s,t,dsu,dtu,dsv,dtv"));
}

#[test]
fn plot_basis_writes_the_four_point_basis_function() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.png");
    let p = path.to_str().unwrap();
    let output =
        subdiv(&["plot-basis", "--scheme", "four-point", "--n", "21", "-o", p, "--width", "320", "--height", "200"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let image = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (320, 200));
    assert!(!dir.path().join("phi.png.tmp").exists());
    // φ peaks at x = 0, the middle of the support [−3, 3]: dark pixels near the top there.
    let dark = |x: u32, y: u32| image.get_pixel(x, y).0.iter().map(|&c| u32::from(c)).sum::<u32>() < 300;
    let (left, right, top) = (320 / 12, 320 - 320 / 24, 200 / 16);
    let middle = (left + right) / 2;
    let peak = (middle - 3..=middle + 3).any(|x| (top..top + 30).any(|y| dark(x, y)));
    assert!(peak, "no dark pixel where φ(0) = 1 is drawn");
    // Not blank elsewhere either: the curve crosses the columns between.
    let columns = (left + 4..right - 4).filter(|&x| (0..200).any(|y| dark(x, y))).count();
    assert!(columns > (right - left - 8) as usize * 9 / 10, "{columns} columns with ink");

    let output = subdiv(&["plot-basis", "--scheme", "four-point", "--n", "31", "--derivative", "-o", p]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let image = image::open(&path).unwrap();
    assert_eq!((image.width(), image.height()), (800, 500));

    // No scheme of that name.
    let output = subdiv(&["plot-basis", "--scheme", "no-such-scheme", "-o", p]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no-such-scheme"), "{stderr}");
}

/// Curve schemes as data: `plot-basis --scheme-file` and `stencil --scheme-file` take a curve
/// scheme's TOML file; the four-point scheme's own file gives the built-in's plot and stencils
/// bit for bit, another weight its own; a surface scheme's file is no curve to plot.
#[test]
fn curve_scheme_files_plot_and_give_stencils() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_string()
    };
    let four =
        "name = \"four-point\"\narity = 2\noffset = 3\nmask = [\"-1/16\", 0, \"9/16\", 1, \"9/16\", 0, \"-1/16\"]\n";
    let four = write("four.toml", four);
    let wider = "name = \"four-point-32\"\narity = 2\noffset = 3\nmask = [\"-1/32\", 0, \"17/32\", 1, \"17/32\", 0, \"-1/32\"]\n";
    let wider = write("wider.toml", wider);
    let png = |args: &[&str], name: &str| {
        let path = dir.path().join(name);
        let output = subdiv(&[&["plot-basis", "--n", "21", "-o", path.to_str().unwrap()][..], args].concat());
        assert!(output.status.success(), "{args:?}: {}", String::from_utf8_lossy(&output.stderr));
        std::fs::read(&path).unwrap()
    };
    let builtin = png(&["--scheme", "four-point"], "builtin.png");
    assert_eq!(png(&["--scheme-file", &four], "file.png"), builtin);
    // `subdiv scheme` prints a curve scheme's file too, in TOML or RON: the same plot.
    for (format, name) in [(&[][..], "printed.toml"), (&["--ron"][..], "printed.ron")] {
        let printed = subdiv(&[&["scheme", "four-point"][..], format].concat());
        assert!(printed.status.success(), "{}", String::from_utf8_lossy(&printed.stderr));
        let file = write(name, &String::from_utf8(printed.stdout).unwrap());
        assert_eq!(png(&["--scheme-file", &file], "printed.png"), builtin, "{name}");
    }
    assert_ne!(png(&["--scheme-file", &wider], "wider.png"), builtin);
    let stencil = |args: &[&str]| {
        let output = subdiv(&[&["stencil", "--n", "3", "--exact", "--json"][..], args].concat());
        assert!(output.status.success(), "{args:?}: {}", String::from_utf8_lossy(&output.stderr));
        output.stdout
    };
    assert_eq!(stencil(&["--scheme-file", &four]), stencil(&["--scheme", "four-point"]));
    assert_ne!(stencil(&["--scheme-file", &wider]), stencil(&["--scheme", "four-point"]));
    // A surface scheme's file: its regular basis function as a heat map.
    let printed = subdiv(&["scheme", "loop"]);
    let surface = write("loop.toml", &String::from_utf8(printed.stdout).unwrap());
    let out = dir.path().join("x.png");
    let drawn = subdiv(&["plot-basis", "--scheme-file", &surface, "--n", "4", "-o", out.to_str().unwrap()]);
    assert!(drawn.status.success(), "{}", String::from_utf8_lossy(&drawn.stderr));
    assert_eq!(image::open(&out).unwrap().width(), 800);
}

/// A curve scheme with rows of its own near the origin as data: paper 000 §2's non-uniform cubic
/// B-spline is a built-in file that `stencil` evaluates exactly, `scheme` prints and a user's
/// copy reads back; `plot-basis` says why it does not draw it.
#[test]
fn local_curve_schemes_are_files_that_stencil_evaluates() {
    let report = json(&["stencil", "--scheme", "nonuniform-cubic-bspline", "--at", "0", "--exact", "--json"]);
    let weights: Vec<(i64, String)> = report["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| (w["point"].as_i64().unwrap(), w["weight"].as_str().unwrap().to_string()))
        .collect();
    assert_eq!(weights, [(-1, "1/15".to_string()), (0, "3/5".to_string()), (1, "1/3".to_string())]);
    // The same scheme as the paper's vector-valued one (its matrix mask, the mirrored knots).
    let matrix = ["stencil", "--scheme", "nonuniform-cubic-bspline-matrix", "--at", "0", "--exact", "--json"];
    let mirrored: Vec<(i64, String)> = json(&matrix)["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| (-w["point"].as_i64().unwrap(), w["weight"].as_str().unwrap().to_string()))
        .rev()
        .collect();
    assert_eq!(mirrored, weights);
    let text = String::from_utf8(subdiv(&["scheme", "nonuniform-cubic-bspline-matrix"]).stdout).unwrap();
    assert!(text.contains("[[matrix]]") && text.contains("components"), "{text}");
    let text = String::from_utf8(subdiv(&["scheme", "nonuniform-cubic-bspline"]).stdout).unwrap();
    assert!(text.contains("[[rows]]") && text.contains("29/40"), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("mine.toml");
    std::fs::write(&file, text.replace("nonuniform-cubic-bspline", "mine")).unwrap();
    let table = json(&["stencil", "--scheme-file", file.to_str().unwrap(), "--n", "2", "--exact", "--json"]);
    assert_eq!(table["special"], serde_json::json!([-1, 1]));
    let x = table["x"].as_array().unwrap();
    let at_zero = x.iter().position(|v| v == "0").unwrap();
    assert_eq!(table["basis"]["0"][at_zero], "3/5");
    let out = subdiv(&["plot-basis", "--scheme-file", file.to_str().unwrap(), "-o", "x.png"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("rules of its own near the origin"));
    // A row that does not sum to 1: one line naming the row.
    std::fs::write(&file, text.replace("\"3/8\", \"5/8\"", "\"3/8\", \"4/8\"")).unwrap();
    let out = subdiv(&["stencil", "--scheme-file", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("the row of new point 1"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A user's surface scheme that is none of the built-ins — Catmull-Clark with other weights at
/// extraordinary vertices (the same at valence 4) — goes through every command that takes a
/// scheme, and its surface differs from Catmull-Clark's only near extraordinary vertices.
#[test]
fn a_users_surface_scheme_goes_through_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let original = r#"vertex = { centre = "(k - 2)/k", spoke = "1/k^2", face = "1/k^2" }"#;
    let text = String::from_utf8(subdiv(&["scheme", "catmull-clark"]).stdout).unwrap();
    assert!(text.contains(original), "{text}");
    let text = text
        .replace("name = \"catmull-clark\"", "name = \"my-quad\"")
        .replace(original, r#"vertex = { centre = "1 - 7/(4*k)", spoke = "3/(2*k^2)", face = "1/(4*k^2)" }"#);
    let file = dir.path().join("my-quad.toml");
    std::fs::write(&file, &text).unwrap();
    let cube = dir.path().join("cube.obj");
    subdiv::io::write_obj(&cube, &subdiv::mesh::shapes::cube()).unwrap();
    let (file, cube) = (file.to_str().unwrap(), cube.to_str().unwrap());
    let output = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    for args in [
        vec!["refine", cube, "--levels", "2", "-o", &output("fine.obj")],
        vec!["analyze", "--valence", "5"],
        vec!["stencil", "--valence", "5", "--at", "1/3,1/4"],
        vec!["eval", cube, "--grid", "4", "-o", &output("limit.csv")],
        vec!["tessellate", cube, "--rate", "8", "-o", &output("t.glb")],
        vec!["plot-basis", "--n", "8", "-o", &output("basis.png")],
    ] {
        let mut all = args.clone();
        all.extend(["--scheme-file", file]);
        let out = subdiv(&all);
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    }
    for name in ["fine.obj", "limit.csv", "t.glb", "basis.png"] {
        assert!(dir.path().join(name).exists(), "{name}");
    }
    // At a corner of the cube (valence 3), where the rules differ, the surface is not
    // Catmull-Clark's.
    let at = |scheme: &[&str], point: &str| -> Vec<f64> {
        let samples = dir.path().join("s.txt");
        std::fs::write(&samples, format!("0 {point}\n")).unwrap();
        let mut args = vec!["eval", cube, "--samples", samples.to_str().unwrap()];
        args.extend_from_slice(scheme);
        let out = subdiv(&args);
        let text = String::from_utf8(out.stdout).unwrap();
        text.lines().nth(1).unwrap().split(',').skip(3).take(3).map(|x| x.parse().unwrap()).collect()
    };
    let gap = |point: &str| {
        let (a, b) = (at(&["--scheme-file", file], point), at(&[], point));
        a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
    };
    assert!(gap("0 0") > 1e-3, "the corner moves: {}", gap("0 0"));
    if subdiv_testkit::gpu().is_some() {
        let png = output("r.png");
        let out = subdiv(&["render", cube, "--scheme-file", file, "--size", "64,48", "-o", &png]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
}

/// A √3 variant with another smoothing weight (β = (5 − 3 cos(2π/k)) / (12k), 1/24 where
/// Kobbelt has 1/18 at valence 6) goes through every command too: its patches are ternary like
/// √3's, derived from the file.
#[test]
fn a_users_sqrt3_variant_goes_through_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let original = r#"spoke = "(4 - 2*cos(2*pi/k))/(9*k)""#;
    let text = String::from_utf8(subdiv(&["scheme", "sqrt3"]).stdout).unwrap();
    assert!(text.contains(original), "{text}");
    let text = text
        .replace("name = \"sqrt3\"", "name = \"my-sqrt3\"")
        .replace(original, r#"spoke = "(5 - 3*cos(2*pi/k))/(12*k)""#);
    let file = dir.path().join("my-sqrt3.toml");
    std::fs::write(&file, &text).unwrap();
    let cage = dir.path().join("icosahedron.obj");
    subdiv::io::write_obj(&cage, &subdiv::mesh::shapes::icosahedron()).unwrap();
    let (file, cage) = (file.to_str().unwrap(), cage.to_str().unwrap());
    let output = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let [fine, limit, glb, basis, png] = ["fine.obj", "limit.csv", "t.glb", "basis.png", "r.png"].map(output);
    let mut commands = vec![
        vec!["refine", cage, "--levels", "2", "-o", &fine],
        vec!["analyze", "--valence", "5"],
        vec!["stencil", "--valence", "5", "--at", "1/3,1/4"],
        vec!["eval", cage, "--grid", "4", "-o", &limit],
        vec!["tessellate", cage, "--rate", "8", "-o", &glb],
        vec!["plot-basis", "--n", "9", "-o", &basis],
    ];
    if subdiv_testkit::gpu().is_some() {
        commands.push(vec!["render", cage, "--size", "64,48", "-o", &png]);
    }
    for args in commands {
        let mut all = args.clone();
        all.extend(["--scheme-file", file]);
        let out = subdiv(&all);
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    }
    for name in ["fine.obj", "limit.csv", "t.glb", "basis.png"] {
        assert!(dir.path().join(name).exists(), "{name}");
    }
    // Its surface is not √3's.
    let limit = |scheme: &[&str]| {
        let mut args = vec!["eval", cage, "--grid", "1"];
        args.extend_from_slice(scheme);
        String::from_utf8(subdiv(&args).stdout).unwrap()
    };
    assert_ne!(limit(&["--scheme-file", file]), limit(&["--scheme", "sqrt3"]));
}

/// The interpolating schemes on open grids (their four-point boundary rule, corners of one face
/// included): Kobbelt on quads, the Butterfly on triangles; `eval --grid 4`, `tessellate --rate
/// 8` keeping the one boundary loop, every vertex on the surface, and `render` where there is a
/// device.
#[test]
fn interpolating_schemes_take_open_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let quads = subdiv::mesh::shapes::quad_grid(4, 3);
    let mut triangles = subdiv::mesh::PolygonSoup::new();
    for &p in quads.positions() {
        triangles.push_vertex(p);
    }
    for face in quads.faces() {
        triangles.push_face([face[0], face[1], face[2]]);
        triangles.push_face([face[0], face[2], face[3]]);
    }
    for (scheme, mut soup) in [("kobbelt", quads), ("butterfly", triangles)] {
        let faces = soup.faces().len();
        for (k, p) in soup.positions_mut().iter_mut().enumerate() {
            p.z = 0.1 * ((k * 7) % 5) as f64;
        }
        let grid = dir.path().join(format!("{scheme}.obj"));
        subdiv::io::write_obj(&grid, &soup).unwrap();
        let out = subdiv(&["eval", &path(&grid), "--scheme", scheme, "--grid", "4"]);
        assert!(out.status.success(), "{scheme}: {}", String::from_utf8_lossy(&out.stderr));
        let per_face = if scheme == "kobbelt" { 25 } else { 15 };
        assert_eq!(String::from_utf8(out.stdout).unwrap().lines().count(), 1 + faces * per_face, "{scheme}");
        let tess = tessellated_on_the_surface(dir.path(), &grid, scheme, &["--polygons"]);
        assert_eq!(tess.boundary_loops().len(), 1, "{scheme}");
        if subdiv_testkit::gpu().is_some() {
            let png = dir.path().join(format!("{scheme}.png"));
            let out = subdiv(&["render", &path(&grid), "--scheme", scheme, "--size", "64,48", "-o", &path(&png)]);
            assert!(out.status.success() && png.exists(), "{scheme}: {}", String::from_utf8_lossy(&out.stderr));
        }
    }
}

/// √3 on a closed cage of triangles with vertices of valences 4 to 6 and 5-valent apexes:
/// `eval --grid 4`, `tessellate --rate 8` closed (no boundary loop) with every vertex on the
/// surface (its parameters evaluated again, to 1e-12), `render` where there is a device, and
/// `--method eigen` refused with the reason.
#[test]
fn sqrt3_evaluates_and_tessellates_closed_and_open_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let prism = capped_prism(5);
    // The prism's quads split in two; open: without the top cap (its centre is the last vertex),
    // a boundary of vertices of four faces.
    let (mut closed, mut open) = (subdiv::mesh::PolygonSoup::new(), subdiv::mesh::PolygonSoup::new());
    let top = subdiv::mesh::VertexId::new(prism.positions().len() as u32 - 1);
    for (k, &p) in prism.positions().iter().enumerate() {
        closed.push_vertex(p);
        if k + 1 < prism.positions().len() {
            open.push_vertex(p);
        }
    }
    for face in prism.faces() {
        let mut triangles = vec![[face[0], face[1], face[2]]];
        if face.len() == 4 {
            triangles.push([face[0], face[2], face[3]]);
        }
        for t in triangles {
            closed.push_face(t);
            if !t.contains(&top) {
                open.push_face(t);
            }
        }
    }
    for (name, soup, boundaries) in [("closed", closed, 0), ("open", open, 1)] {
        let faces = soup.faces().len();
        let cage = dir.path().join(format!("{name}.obj"));
        subdiv::io::write_obj(&cage, &soup).unwrap();
        let out = subdiv(&["eval", &path(&cage), "--scheme", "sqrt3", "--grid", "4"]);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(String::from_utf8(out.stdout).unwrap().lines().count(), 1 + faces * 15, "{name}");
        let tess = tessellated_on_the_surface(dir.path(), &cage, "sqrt3", &[]);
        assert_eq!(tess.boundary_loops().len(), boundaries, "{name}: watertight, the cage's boundaries only");
        let refused = subdiv(&["eval", &path(&cage), "--scheme", "sqrt3", "--grid", "2", "--method", "eigen"]);
        assert_eq!(refused.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&refused.stderr).contains("evaluate through exact stencils"));
        if subdiv_testkit::gpu().is_some() {
            let png = dir.path().join("sqrt3.png");
            let out = subdiv(&["render", &path(&cage), "--scheme", "sqrt3", "--size", "64,48", "-o", &path(&png)]);
            assert!(out.status.success() && png.exists(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        }
    }
}

/// Doo-Sabin and mid-edge on open meshes (the Chaikin boundary rule): prisms of 3 to 8 sides
/// without their top cap (a boundary of vertices of two faces, the bottom cap a face of 3 to 8
/// sides, valence 3 around it) and a jittered grid (corners of one face): `eval --grid 4` gives
/// every grid point, `tessellate --rate 8` (and 3, whose boundary points have periodic
/// addresses) is watertight but for the cage's boundary loop, and its vertices are the
/// evaluations at their parameters; `render` draws; `--tolerance` (whose error bounds take no
/// stretched pieces) and a boundary vertex of three faces are refused by name.
#[test]
fn dual_schemes_evaluate_tessellate_and_render_open_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let mut meshes = Vec::new();
    for n in 3..=8 {
        let prism = subdiv::mesh::shapes::ngon_prism(n);
        let mut open = subdiv::mesh::PolygonSoup::new();
        for &p in prism.positions() {
            open.push_vertex(p);
        }
        // The top cap is the face of n sides over the upper ring (z > 0).
        for face in prism.faces() {
            if !(face.len() == n && face.iter().all(|v| prism.positions()[v.index()].z > 0.0)) {
                open.push_face(face.iter().copied());
            }
        }
        meshes.push((format!("open prism {n}"), open, 1));
    }
    let grid = subdiv::mesh::shapes::jittered(subdiv::mesh::shapes::quad_grid(4, 3), 0.2);
    meshes.push(("grid".to_string(), grid, 1));
    for (name, soup, boundaries) in meshes {
        let cage = dir.path().join("open.obj");
        subdiv::io::write_obj(&cage, &soup).unwrap();
        let faces: usize = soup.faces().map(|f| if f.len() == 4 { 25 } else { 25 * f.len() }).sum();
        for scheme in ["doo-sabin", "midedge"] {
            let what = format!("{scheme} {name}");
            let out = subdiv(&["eval", &path(&cage), "--scheme", scheme, "--grid", "4"]);
            assert!(out.status.success(), "{what}: {}", String::from_utf8_lossy(&out.stderr));
            assert_eq!(String::from_utf8(out.stdout).unwrap().lines().count(), 1 + faces, "{what}");
            for rate in [&[][..], &["--rate", "3"][..]] {
                let tess = tessellated_on_the_surface(dir.path(), &cage, scheme, rate);
                assert_eq!(tess.boundary_loops().len(), boundaries, "{what} {rate:?}: the cage's boundary only");
            }
            // No error bounds over the stretched pieces: `--tolerance` says so.
            let out = subdiv(&[
                "tessellate",
                &path(&cage),
                "--scheme",
                scheme,
                "--tolerance",
                "1e-3",
                "-o",
                &path(&dir.path().join("tol.obj")),
            ]);
            assert_eq!(out.status.code(), Some(2), "{what}");
            assert!(String::from_utf8_lossy(&out.stderr).contains("`--rate` takes it"), "{what}");
            if subdiv_testkit::gpu().is_some() {
                let png = dir.path().join("open.png");
                let out = subdiv(&["render", &path(&cage), "--scheme", scheme, "--size", "64,48", "-o", &path(&png)]);
                assert!(out.status.success() && png.exists(), "{what}: {}", String::from_utf8_lossy(&out.stderr));
            }
        }
    }
    // A boundary vertex of three faces: the corner of an L of three quads.
    let l_shape = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 0 2 0\nv 1 2 0\n\
                   f 1 2 5 4\nf 2 3 6 5\nf 4 5 8 7\n";
    let cage = dir.path().join("l.obj");
    std::fs::write(&cage, l_shape).unwrap();
    let out = subdiv(&["eval", &path(&cage), "--scheme", "doo-sabin", "--grid", "2"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("at vertex 4, a boundary vertex of 3 faces") && stderr.contains("subdiv refine"),
        "{stderr}"
    );
}

/// `cage` tessellated under `scheme` (with `extra` arguments; `--rate 8` unless they give
/// one) into OBJ with its `--params`: every output vertex is the limit point `eval --samples`
/// gives at its parameters, to 1e-12. Returns the tessellation.
fn tessellated_on_the_surface(
    dir: &std::path::Path,
    cage: &std::path::Path,
    scheme: &str,
    extra: &[&str],
) -> subdiv::mesh::Mesh {
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (obj, csv, samples) = (dir.join("t.obj"), dir.join("p.csv"), dir.join("s.txt"));
    let args = ["tessellate", &path(cage), "--scheme", scheme, "--params", &path(&csv), "-o", &path(&obj)];
    let rate: &[&str] = if extra.contains(&"--rate") { &[] } else { &["--rate", "8"] };
    let out = subdiv(&[&args[..], rate, extra].concat());
    assert!(out.status.success(), "{scheme}: {}", String::from_utf8_lossy(&out.stderr));
    let tess = subdiv::io::load_mesh(&obj, &Default::default()).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let points: String = text
        .lines()
        .skip(1)
        .map(|l| {
            let r: Vec<&str> = l.split(',').collect();
            format!("{} {} {}\n", r[1], r[2], r[3])
        })
        .collect();
    std::fs::write(&samples, points).unwrap();
    let out = subdiv(&["eval", &path(cage), "--scheme", scheme, "--samples", &path(&samples)]);
    assert!(out.status.success(), "{scheme}: {}", String::from_utf8_lossy(&out.stderr));
    // The vertices, then (on creases and seams) their split copies, each at its own parameters.
    let evaluated = String::from_utf8(out.stdout).unwrap();
    assert!(evaluated.lines().count() > tess.vertex_count(), "{scheme}: a parameter per vertex");
    for (k, (line, p)) in evaluated.lines().skip(1).zip(tess.positions()).enumerate() {
        let e: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let gap = (*p - subdiv::mesh::DVec3::new(e[3], e[4], e[5])).length();
        assert!(gap < 1e-12, "{scheme} {}: vertex {k} is {gap:e} off the surface", cage.display());
    }
    tess
}

/// An `n`-gon prism whose caps are fans of triangles around two vertices of valence `n`; the
/// ring's vertices have valence 4.
fn capped_prism(n: usize) -> subdiv::mesh::PolygonSoup {
    use subdiv::mesh::{DVec3, VertexId};
    let mut soup = subdiv::mesh::PolygonSoup::new();
    for z in [-1.0, 1.0] {
        for i in 0..n {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            soup.push_vertex(DVec3::new(a.cos(), a.sin(), z));
        }
    }
    soup.push_vertex(DVec3::new(0.1, 0.0, -1.6));
    soup.push_vertex(DVec3::new(0.0, 0.2, 1.4));
    let (b, t) = (|i: usize| VertexId::new((i % n) as u32), |i: usize| VertexId::new((n + i % n) as u32));
    let (cb, ct) = (VertexId::new(2 * n as u32), VertexId::new(2 * n as u32 + 1));
    for i in 0..n {
        soup.push_face([b(i), b(i + 1), t(i + 1), t(i)]);
        soup.push_face([cb, b(i + 1), b(i)]);
        soup.push_face([ct, t(i), t(i + 1)]);
    }
    soup
}

/// Doo-Sabin and mid-edge (patches around the faces' corners, `subdiv_schemes::dual_patch`) on
/// closed meshes with faces of 3 to 8 sides and vertices of valence 3 to 8: `eval --grid 4`
/// gives every grid point, `tessellate --rate 8` is watertight and its vertices are the
/// evaluations at their parameters (to 1e-12), and `render` draws where there is a device.
#[test]
fn dual_schemes_evaluate_tessellate_and_render() {
    let dir = tempfile::tempdir().unwrap();
    let mut meshes = Vec::new();
    for n in 3..=8 {
        for (kind, soup) in [("prism", subdiv::mesh::shapes::ngon_prism(n)), ("capped", capped_prism(n))] {
            let path = dir.path().join(format!("{kind}{n}.obj"));
            subdiv::io::write_obj(&path, &soup).unwrap();
            meshes.push(path);
        }
    }
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    for scheme in ["doo-sabin", "midedge"] {
        for mesh in &meshes {
            let what = format!("{scheme} {}", mesh.display());
            let cage = subdiv::io::load_mesh(mesh, &Default::default()).unwrap();
            let out = subdiv(&["eval", &path(mesh), "--scheme", scheme, "--grid", "4"]);
            assert!(out.status.success(), "{what}: {}", String::from_utf8_lossy(&out.stderr));
            let rows = String::from_utf8(out.stdout).unwrap().lines().count() - 1;
            let per_face: usize =
                cage.face_ids().map(|f| if cage.face_size(f) == 4 { 25 } else { 25 * cage.face_size(f) }).sum();
            assert_eq!(rows, per_face, "{what}");

            let tess = tessellated_on_the_surface(dir.path(), mesh, scheme, &["--polygons"]);
            assert_eq!(tess.boundary_edge_count(), 0, "{what}: watertight");
            assert_eq!(tess.genus(), Some(0), "{what}");
        }
    }
    if subdiv_testkit::gpu().is_none() {
        return;
    }
    let png = dir.path().join("ds.png");
    let out = subdiv(&["render", &path(&meshes[5]), "--scheme", "doo-sabin", "--size", "64,48", "-o", &path(&png)]);
    assert!(out.status.success() && png.exists(), "{}", String::from_utf8_lossy(&out.stderr));
}
