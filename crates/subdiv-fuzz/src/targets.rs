//! The fuzz targets: one entry point each, run on arbitrary bytes.

use std::str::FromStr;
use std::sync::OnceLock;

use arbitrary::Unstructured;
use subdiv::mesh::{BoundaryInterpolation, CreaseTag, Mesh, PolygonSoup, VertexId, shapes};
use subdiv::schemes::{Builtin, CurveScheme, PatchMatrices, PatchType, Scheme};
use subdiv::stencil::{Address, Dyadic, StencilEvaluator};
use subdiv::{Camera, FaceId, Method, Rates, Surface, TessOptions, Tolerance};

/// An entry point of the library, fuzzed on arbitrary bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Target {
    /// `subdiv_io::read_obj`, then `Mesh::build` and, for small meshes, one level of
    /// refinement and a tessellation at rate 2.
    Obj,
    /// `subdiv_io::parse_gltf` on a real folder: the input is the JSON, then optionally a
    /// zero byte and the bytes of `buffer.bin`, which is written beside it and read through
    /// the JSON's URIs; then `Mesh::build`.
    Gltf,
    /// `Scheme::from_toml_str` and `CurveScheme::from_toml_str`; a scheme that parses refines
    /// a cube (quad splits) or an octahedron (triangle splits) once, and derives its sub-patch
    /// matrices at an extraordinary vertex (valence 3 to 5, from the input's hash).
    Scheme,
    /// `Dyadic::from_str` (`U,V`), then its address and the stencil of a valence-5
    /// Catmull-Clark patch there.
    Parameter,
    /// Small random meshes (shapes, jitter, creases, holes) under every built-in scheme:
    /// build, refine, evaluate, tessellate (both methods, every rate policy, up to a small
    /// vertex budget so that the budgets' refusals are reached) and the grid.
    Pipeline,
}

impl Target {
    /// Every target, in `cargo xtask fuzz` order.
    pub const ALL: [Self; 5] = [Self::Obj, Self::Gltf, Self::Scheme, Self::Parameter, Self::Pipeline];

    /// The name on the command line and in the reproducers' folder.
    pub fn name(self) -> &'static str {
        match self {
            Self::Obj => "obj",
            Self::Gltf => "gltf",
            Self::Scheme => "scheme",
            Self::Parameter => "parameter",
            Self::Pipeline => "pipeline",
        }
    }

    /// The target named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The inputs mutation starts from: valid inputs of every kind the entry point takes.
    pub fn seeds(self) -> Vec<Vec<u8>> {
        match self {
            Self::Obj => {
                let mut creased = shapes::cube();
                creased.tags.creases.push(CreaseTag { vertices: [VertexId::new(0), VertexId::new(1)], sharpness: 2.5 });
                [shapes::cube(), creased, shapes::ngon_prism(5), shapes::quad_grid(2, 2), shapes::tetrahedron()]
                    .iter()
                    .map(|soup| {
                        let mut text = Vec::new();
                        subdiv::io::write_obj_to(&mut text, soup).expect("writing to memory");
                        text
                    })
                    .chain([
                        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 4/1\nt corner 1/1/0 0 4\n".to_vec()
                    ])
                    .collect()
            }
            Self::Gltf => {
                // The triangle again, its positions in `buffer.bin` after the zero byte.
                let json = GLTF_TRIANGLE_FILE.to_vec();
                let positions: Vec<u8> =
                    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|x| x.to_le_bytes()).collect();
                vec![GLTF_TRIANGLE.to_vec(), GLTF_QUAD_INDEXED.to_vec(), [json, vec![0], positions].concat()]
            }
            Self::Scheme => Builtin::ALL
                .iter()
                .map(|b| b.scheme().to_toml_string().into_bytes())
                .chain(CurveScheme::BUILTIN_NAMES.iter().filter_map(|name| {
                    CurveScheme::builtin(name).and_then(|c| c.to_toml_string().ok()).map(String::into_bytes)
                }))
                .collect(),
            Self::Parameter => ["0,0", "1/2,1/2", "1/3,2/7", "5/8, 0", "1,1", "1/1023,1/11", "3/4294967296,1/3"]
                .iter()
                .map(|s| s.as_bytes().to_vec())
                .collect(),
            Self::Pipeline => vec![vec![0; 16], vec![1, 2, 3, 4, 5, 6, 7, 8], (0..64).collect(), vec![255; 32]],
        }
    }

    /// Runs the entry point on `data` and returns a short label of what happened (`ok`, or
    /// the start of the error's message), which the driver uses to keep inputs that reach new
    /// outcomes.
    ///
    /// # Panics
    /// On a finding: the entry point panicked, an error message spans several lines, or a
    /// result breaks an invariant.
    pub fn run(self, data: &[u8]) -> String {
        match self {
            Self::Obj => obj(data),
            Self::Gltf => gltf(data),
            Self::Scheme => scheme(data),
            Self::Parameter => parameter(data),
            Self::Pipeline => pipeline(data),
        }
    }
}

/// `ok`, or the error's message cut to its first words, after checking that it is one line.
fn label<T, E: std::fmt::Display>(what: &str, result: &Result<T, E>) -> String {
    match result {
        Ok(_) => format!("{what}: ok"),
        Err(e) => {
            let text = e.to_string();
            assert!(!text.contains('\n'), "{what}: an error message of several lines: {text:?}");
            let words: Vec<&str> =
                text.split_whitespace().filter(|w| !w.chars().any(|c| c.is_ascii_digit())).take(4).collect();
            format!("{what}: {}", words.join(" "))
        }
    }
}

/// Builds, refines and tessellates a small mesh under Catmull-Clark; labels what failed.
fn exercise(soup: PolygonSoup) -> String {
    let built = Mesh::build(soup);
    let mut outcome = label("build", &built);
    if let Ok(mesh) = built
        && mesh.face_count() <= 64
    {
        let mut surface = Surface::new(mesh, Builtin::CatmullClark.scheme());
        let refined = surface.refine(1);
        outcome += &format!("; {}", label("refine", &refined));
        let tessellation = surface.tessellate(&TessOptions::DEFAULT.with_rates(Rates::Uniform(2)));
        outcome += &format!("; {}", label("tessellate", &tessellation));
        if let Ok(t) = tessellation {
            check_tessellation(&t.mesh);
        }
    }
    outcome
}

fn check_tessellation(mesh: &subdiv::TessMesh) {
    let n = mesh.positions.len() as u32;
    assert!(mesh.positions.iter().all(|p| p.is_finite()), "a non-finite tessellation vertex");
    assert!(mesh.triangles.iter().flatten().all(|&i| i < n), "a triangle indexes past the vertices");
}

fn obj(data: &[u8]) -> String {
    let read = subdiv::io::read_obj(data, "fuzz.obj");
    let outcome = label("read", &read);
    match read {
        Ok(soup) => format!("{outcome}; {}", exercise(soup)),
        Err(_) => outcome,
    }
}

fn gltf(data: &[u8]) -> String {
    // One folder per process, its buffer file rewritten for each input.
    static FOLDER: OnceLock<std::path::PathBuf> = OnceLock::new();
    let folder = FOLDER.get_or_init(|| {
        let folder = std::env::temp_dir().join(format!("subdiv-fuzz-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&folder).expect("a scratch folder can be made");
        folder
    });
    let (json, buffer) = match data.iter().position(|&b| b == 0) {
        Some(at) => (&data[..at], &data[at + 1..]),
        None => (data, &[][..]),
    };
    std::fs::write(folder.join("buffer.bin"), buffer).expect("the scratch buffer can be written");
    let read = subdiv::io::parse_gltf(json, "fuzz.gltf", Some(folder));
    let outcome = label("read", &read);
    match read {
        Ok(soup) => format!("{outcome}; {}", label("build", &Mesh::build(soup))),
        Err(_) => outcome,
    }
}

fn scheme(data: &[u8]) -> String {
    let Ok(text) = std::str::from_utf8(data) else { return "not utf-8".into() };
    let curve = CurveScheme::from_toml_str(text);
    let parsed = Scheme::from_toml_str(text);
    let mut outcome = format!("{}; {}", label("curve", &curve), label("scheme", &parsed));
    if let Ok(scheme) = parsed {
        let cage =
            if scheme.split() == subdiv::schemes::Split::Triangle { shapes::octahedron() } else { shapes::cube() };
        let surface = Surface::build(cage, &scheme).expect("a shape builds");
        outcome += &format!("; {}", label("refine", &surface.refine(1)));
        // The sub-patch derivation runs the engine on a canonical mesh of this valence.
        let valence = 3 + (crate::driver::hash(data) % 3) as usize;
        let matrices = PatchMatrices::compute(&scheme, PatchType::interior(valence), BoundaryInterpolation::EdgeOnly);
        outcome += &format!("; {}", label("patches", &matrices));
    }
    outcome
}

fn parameter(data: &[u8]) -> String {
    static MATRICES: OnceLock<std::sync::Arc<PatchMatrices>> = OnceLock::new();
    let Ok(text) = std::str::from_utf8(data) else { return "not utf-8".into() };
    let point = Dyadic::from_str(text);
    let mut outcome = label("parse", &point);
    if let Ok(point) = point {
        outcome += &format!("; {}", label("address", &Address::of(4, point)));
        let matrices = MATRICES.get_or_init(|| {
            PatchMatrices::of(Builtin::CatmullClark.scheme(), PatchType::interior(5), BoundaryInterpolation::EdgeOnly)
                .expect("valence-5 Catmull-Clark matrices")
        });
        let mut evaluator = StencilEvaluator::new(&**matrices);
        let stencil = evaluator.stencil(0, point);
        if let Ok(s) = &stencil {
            assert!(s.position.iter().all(|w| w.is_finite()), "a non-finite stencil weight at {text}");
        }
        outcome += &format!("; {}", label("stencil", &stencil));
    }
    outcome
}

/// A small random mesh and requests on it, from `data`.
fn pipeline(data: &[u8]) -> String {
    let mut u = Unstructured::new(data);
    let Ok(outcome) = pipeline_from(&mut u) else { return "too few bytes".into() };
    outcome
}

fn pipeline_from(u: &mut Unstructured<'_>) -> arbitrary::Result<String> {
    let mut soup = match u.int_in_range(0..=7)? {
        0 => shapes::cube(),
        1 => shapes::tetrahedron(),
        2 => shapes::octahedron(),
        3 => shapes::quad_grid(u.int_in_range(1..=4)?, u.int_in_range(1..=4)?),
        4 => shapes::ngon_prism(u.int_in_range(3..=9)?),
        5 => shapes::pole(u.int_in_range(3..=9)?),
        6 => shapes::quad_torus(u.int_in_range(3..=5)?, u.int_in_range(3..=5)?),
        _ => shapes::triangle_torus(u.int_in_range(3..=5)?, u.int_in_range(3..=5)?),
    };
    let scale = [1.0, 1e-6, 1e6, 1e-90, 1e120][u.int_in_range(0..=4)?];
    for p in soup.positions_mut() {
        let jitter: [i8; 3] = u.arbitrary()?;
        *p = (*p + subdiv::mesh::DVec3::from(jitter.map(|j| f64::from(j) / 512.0))) * scale;
    }
    let faces: Vec<Vec<VertexId>> = soup.faces().map(<[VertexId]>::to_vec).collect();
    for _ in 0..u.int_in_range(0..=4)? {
        let face = &faces[u.choose_index(faces.len())?];
        let k = u.choose_index(face.len())?;
        let sharpness = [0.5, 1.0, 2.5, 10.0][u.int_in_range(0..=3)?];
        soup.tags.creases.push(CreaseTag { vertices: [face[k], face[(k + 1) % face.len()]], sharpness });
    }
    if u.ratio(1, 8)? {
        soup.tags.holes.push(FaceId::new(u.int_in_range(0..=faces.len() as u32 - 1)?));
    }
    let builtin = Builtin::ALL[u.choose_index(Builtin::ALL.len())?];
    // Loop and the Butterfly take the quad shapes split into triangles (open ones too: their
    // boundary rules), without drawing more bytes, so that the reproducers read as they were
    // cut. Not √3: its patch derivations on open fans take seconds in the debug build, and CI's
    // short pass gives an input 10 s (8.4 s measured with it).
    if builtin.scheme().face_size() == Some(3) && builtin != Builtin::Sqrt3 {
        soup = shapes::triangulated(soup);
    }
    let built = Mesh::build(soup);
    let mut outcome = format!("{}; {}", builtin.name(), label("build", &built));
    let Ok(mesh) = built else { return Ok(outcome) };
    let mut surface = Surface::new(mesh, builtin.scheme());
    outcome += &format!("; {}", label("refine", &surface.refine(u.int_in_range(0..=2)?)));
    for _ in 0..u.int_in_range(0..=3)? {
        let face = FaceId::new(u.int_in_range(0..=surface.mesh().face_count() as u32)?);
        let (a, b): (u16, u16) = (u.arbitrary()?, u.arbitrary()?);
        let point = surface.evaluate(face, f64::from(a) / 65535.0, f64::from(b) / 65535.0);
        if let Ok(p) = &point {
            assert!(p.position.is_finite() && p.du.is_finite() && p.dv.is_finite(), "a non-finite limit point {p:?}");
        }
        outcome += &format!("; {}", label("evaluate", &point));
    }
    // Every policy, rates up to 64 and tolerances down to 1e-6 against a small budget: what
    // the budgets refuse is refused before the work, so these stay quick.
    let camera = Camera::look_at(
        subdiv::mesh::DVec3::from(u.arbitrary::<[i8; 3]>()?.map(f64::from)),
        subdiv::mesh::DVec3::ZERO,
        subdiv::mesh::DVec3::Z,
    );
    let viewport = [u.int_in_range(1..=4096)?, u.int_in_range(1..=4096)?];
    let rates = match u.int_in_range(0..=4)? {
        0 => Rates::Uniform(u.int_in_range(1..=64)?),
        1 => Rates::Tolerance(Tolerance::Relative([1e-1, 1e-2, 1e-3, 1e-6][u.int_in_range(0..=3)?])),
        2 => Rates::Screen { camera, viewport, pixels_per_edge: [0.5, 4.0, 64.0][u.int_in_range(0..=2)?] },
        3 => Rates::ScreenError { camera, viewport, pixels: [0.1, 1.0, 16.0][u.int_in_range(0..=2)?] },
        _ => {
            Rates::PerFace((0..surface.mesh().face_count()).map(|_| u.int_in_range(1..=64)).collect::<Result<_, _>>()?)
        }
    };
    let method = if u.arbitrary()? { Method::Quadtree } else { Method::Dual };
    let options = TessOptions::DEFAULT.with_rates(rates).with_method(method).with_max_vertices(PIPELINE_MAX_VERTICES);
    let tessellation = surface.tessellate(&options);
    if let Ok(t) = &tessellation {
        check_tessellation(&t.mesh);
    }
    outcome += &format!("; {}", label("tessellate", &tessellation));
    // A part of the dual tessellation: its points are the whole's, bit for bit (on small
    // tessellations: the part is a second one, and the debug pass in CI has 10 s an input).
    if let (Ok(whole), Method::Dual) = (&tessellation, method)
        && whole.mesh.positions.len() <= PART_CHECK_VERTICES
    {
        let count = surface.mesh().face_count();
        let start = u.int_in_range(0..=count - 1)?;
        let end = u.int_in_range(start + 1..=count + 2)?;
        let part = surface.tessellate_part(&options, start..end);
        if let Ok(part) = &part {
            let points: std::collections::HashSet<[u64; 3]> =
                whole.mesh.positions.iter().map(|p| p.to_array().map(f64::to_bits)).collect();
            assert!(
                part.mesh.positions.iter().all(|p| points.contains(&p.to_array().map(f64::to_bits))),
                "a point of part {start}..{end} is not a point of the whole tessellation"
            );
            assert!(part.mesh.triangles.len() <= whole.mesh.triangles.len());
        }
        outcome += &format!("; {}", label("part", &part));
        // Streamed in chunks of a drawn size: the flat tessellation's bytes (no rings: a
        // tolerance's tessellation is handed on whole).
        if whole.info.epsilon.is_none() {
            let chunk = u.int_in_range(1..=4096)?;
            let options = subdiv::tess::DualOptions::DEFAULT.with_chunk(chunk).with_channels(surface.takes_channels());
            if let Ok(mut tess) = subdiv::tess::DualTessellator::new(surface.scheme(), surface.mesh(), &options) {
                let (mut flat, mut streamed) = (subdiv::FlatMesh::default(), subdiv::FlatMesh::default());
                let made = tess.tessellate_flat(&whole.info.rates, &mut flat);
                let stream = tess.tessellate_stream(&whole.info.rates, &mut streamed);
                assert_eq!(made.is_ok(), stream.is_ok(), "the stream fails where the flat tessellation does not");
                assert!(
                    made.is_err() || flat == streamed,
                    "the stream in chunks of {chunk} is not the flat tessellation"
                );
            }
        }
    }
    outcome += &format!("; {}", label("grid", &surface.evaluate_grid(u.int_in_range(1..=4)?)));
    Ok(outcome)
}

/// The largest whole tessellation whose face-range part the pipeline target also makes.
const PART_CHECK_VERTICES: usize = 20_000;

/// The most vertices a pipeline input's tessellation may have: past it the budget refuses. A
/// quadtree whose prediction stays under it may grow to a quarter as many polygons before it
/// refuses, each node bounded from samples: 200 000 let a mid-edge cage run past the debug
/// pass's 10 s (0.49 s in release; reproducer `pipeline/1e59d5ccef79792d`).
const PIPELINE_MAX_VERTICES: usize = 50_000;

/// One triangle whose positions are in `buffer.bin` beside it (seed of [`Target::Gltf`]).
const GLTF_TRIANGLE_FILE: &[u8] = br#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"buffer.bin"}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,0],"min":[0,0,0]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#;

/// One triangle, its positions in a `data:` URI (seed of [`Target::Gltf`]).
const GLTF_TRIANGLE: &[u8] = br#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,0],"min":[0,0,0]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#;

/// A quad as two indexed triangles (seed of [`Target::Gltf`]).
const GLTF_QUAD_INDEXED: &[u8] = br#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":60,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAgD8AAAAAAAABAAIAAAACAAMA"}],"bufferViews":[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],"accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","max":[1,1,0],"min":[0,0,0]},{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#;
