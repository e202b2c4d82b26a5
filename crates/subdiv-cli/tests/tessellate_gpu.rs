//! `subdiv tessellate --gpu`: the same tessellation as the CPU path, with positions and normals
//! evaluated on the GPU (f32).

use std::process::Command;

fn vertices(obj: &str) -> Vec<[f64; 3]> {
    obj.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let mut it = l.split_whitespace().map(|x| x.parse::<f64>().unwrap());
            [it.next().unwrap(), it.next().unwrap(), it.next().unwrap()]
        })
        .collect()
}

#[test]
fn gpu_evaluation_writes_the_cpu_output() {
    // The adapter helper decides: skip without one, fail under SUBDIV_REQUIRE_GPU=1.
    let Some(_gpu) = subdiv_testkit::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let run = |gpu: bool, name: &str| {
        let path = dir.path().join(name);
        let mut args = vec!["tessellate", "--rate", "5", "-o", path.to_str().unwrap()];
        if gpu {
            args.push("--gpu");
        }
        let out = Command::new(env!("CARGO_BIN_EXE_subdiv")).args(&args).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        (std::fs::read_to_string(path).unwrap(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (gpu, said) = run(true, "gpu.obj");
    let (cpu, _) = run(false, "cpu.obj");
    assert!(said.contains("evaluated on"), "{said}");
    // The same faces, the same vertex count, positions to f32 precision.
    let faces = |s: &str| s.lines().filter(|l| l.starts_with("f ")).map(str::to_owned).collect::<Vec<_>>();
    assert_eq!(faces(&gpu), faces(&cpu));
    let (a, b) = (vertices(&gpu), vertices(&cpu));
    assert_eq!(a.len(), b.len());
    let size = b.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let worst = a.iter().zip(&b).flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs())).fold(0.0, f64::max);
    assert!(worst <= 1e-5 * size, "worst difference {worst}");
}

#[test]
fn gpu_needs_the_dual_method() {
    let out = Command::new(env!("CARGO_BIN_EXE_subdiv"))
        .args(["tessellate", "--method", "quadtree", "--tolerance", "0.1", "--gpu"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--gpu"));
}

/// The numbers after `tag` on each of its lines.
fn rows(obj: &str, tag: &str) -> Vec<Vec<f64>> {
    obj.lines()
        .filter_map(|l| l.strip_prefix(tag))
        .map(|l| l.split_whitespace().map(|x| x.parse::<f64>().unwrap()).collect())
        .collect()
}

/// A cube with infinitely sharp edges: `--gpu` writes the CPU's OBJ (the same `f v//vn`
/// corners, a crease vertex's extra normals as further `vn` lines), normals to f32 precision;
/// `subdiv render` draws it.
#[test]
fn creased_meshes_evaluate_and_render_with_split_normals() {
    let Some(_gpu) = subdiv_testkit::gpu() else { return };
    let Some(cube) = subdiv_testkit::shared_mesh("opensubdiv/catmark_cube_creases2.obj") else { return };
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_subdiv")).args(args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    };
    let obj = |gpu: bool| {
        let path = dir.path().join(if gpu { "gpu.obj" } else { "cpu.obj" });
        let mut args = vec!["tessellate", cube.to_str().unwrap(), "--rate", "4", "-o", path.to_str().unwrap()];
        if gpu {
            args.push("--gpu");
        }
        run(&args);
        std::fs::read_to_string(path).unwrap()
    };
    let (gpu, cpu) = (obj(true), obj(false));
    let faces = |s: &str| s.lines().filter(|l| l.starts_with("f ")).map(str::to_owned).collect::<Vec<_>>();
    assert_eq!(faces(&gpu), faces(&cpu));
    let (normals, cpu_normals) = (rows(&gpu, "vn "), rows(&cpu, "vn "));
    assert!(normals.len() > vertices(&cpu).len(), "the creases split normals");
    assert_eq!(normals.len(), cpu_normals.len());
    let worst = normals.iter().zip(&cpu_normals).flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()));
    let worst = worst.fold(0.0, f64::max);
    assert!(worst <= 1e-5, "worst normal difference {worst}");
    let png = dir.path().join("creases.png");
    run(&["render", cube.to_str().unwrap(), "-o", png.to_str().unwrap(), "--size", "64,48"]);
    let image = image::open(&png).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (64, 48));
}
