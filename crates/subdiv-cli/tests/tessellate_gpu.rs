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
