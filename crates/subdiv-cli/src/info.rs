//! `subdiv info`: topology report of a mesh.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use serde_json::{Value, json};
use subdiv::mesh::{BuildOptions, Mesh, MeshError, PolygonSoup, RegularValence, Tags, shapes, validate};

use crate::UserError;
use crate::input::{InputArgs, LoadedMesh};

/// Arguments of `subdiv info`.
#[derive(Debug, clap::Args)]
pub(crate) struct InfoArgs {
    /// Mesh file (.obj, .gltf, .glb); the built-in model when omitted.
    mesh: Option<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Repair inconsistent face orientation before building (keeps each component's majority
    /// orientation).
    #[arg(long)]
    orient: bool,
}

pub(crate) fn run(args: &InfoArgs, out: &mut impl Write) -> Result<(), UserError> {
    let loaded = match &args.mesh {
        Some(path) => LoadedMesh::read(path, &args.input)?,
        None => LoadedMesh::built_in(shapes::default_model()),
    };
    let options = BuildOptions::default().with_orient(args.orient).with_split_sheets(args.input.split_sheets);
    match Mesh::build_with(loaded.soup.clone(), &options) {
        Ok(mesh) => {
            let report = report(&loaded.name, &mesh);
            if args.json {
                writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
            } else {
                write_text(out, &report)?;
            }
            Ok(())
        }
        Err(first) => {
            // Report every problem on stdout, then fail with the first one on stderr.
            let mut problems = validate(&loaded.soup);
            if args.input.split_sheets {
                // Taken apart into sheets, a non-manifold edge or vertex is no problem.
                problems
                    .retain(|p| !matches!(p, MeshError::NonManifoldEdge { .. } | MeshError::NonManifoldVertex { .. }));
            }
            if problems.is_empty() {
                problems.push(first.clone()); // orientation repair failed (non-orientable)
            }
            let located: Vec<String> = problems.iter().map(|p| loaded.locate(p)).collect();
            let summary = soup_report(&loaded.name, &loaded.soup, &problems, &located);
            if args.json {
                writeln!(out, "{}", serde_json::to_string_pretty(&summary)?)?;
            } else {
                write_text(out, &summary)?;
            }
            let more = match problems.len() {
                1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            Err(UserError(format!("{}{more}", loaded.locate(&first))))
        }
    }
}

fn histogram_json(histogram: &BTreeMap<usize, usize>) -> Value {
    Value::Object(histogram.iter().map(|(k, v)| (k.to_string(), json!(v))).collect())
}

fn tags_json(tags: &Tags) -> Value {
    json!({
        "creases": tags.creases.len(),
        "corners": tags.corners.len(),
        "holes": tags.holes.len(),
        "boundary_interpolation": tags.boundary_interpolation.map(|b| format!("{b:?}")),
        "crease_method": tags.crease_method.map(|c| format!("{c:?}")),
        "triangle_subdivision": tags.triangle_subdivision.map(|t| format!("{t:?}")),
        "face_varying_interpolation": tags.face_varying_interpolation.map(|m| m.name()),
        "unsupported": tags.unsupported,
    })
}

/// The full report of a valid mesh, as JSON (the text form is printed from it).
fn report(name: &str, mesh: &Mesh) -> Value {
    let regular = RegularValence::for_faces_of(mesh);
    let valences = mesh.valence_histogram();
    let extraordinary: Vec<_> = mesh.extraordinary_vertices(regular).collect();
    let boundary_extraordinary = extraordinary.iter().filter(|&&v| mesh.is_boundary_vertex(v)).count();
    let isolated = mesh.vertices().filter(|&v| mesh.is_isolated(v)).count();
    json!({
        "mesh": name,
        "valid": true,
        "vertices": mesh.vertex_count(),
        "faces": mesh.face_count(),
        "face_sizes": histogram_json(&mesh.face_size_histogram()),
        "edges": mesh.edge_count(),
        "boundary_edges": mesh.boundary_edge_count(),
        "boundary_loops": mesh.boundary_loops().len(),
        "components": mesh.components().count(),
        "euler_characteristic": mesh.euler_characteristic(),
        "genus": mesh.genus(),
        "isolated_vertices": isolated,
        "valence_min": valences.keys().next(),
        "valence_max": valences.keys().last(),
        "valences": histogram_json(&valences),
        "regular_valence": { "interior": regular.interior, "boundary": regular.boundary },
        "extraordinary_vertices": extraordinary.len(),
        "extraordinary_interior": extraordinary.len() - boundary_extraordinary,
        "extraordinary_boundary": boundary_extraordinary,
        "tags": tags_json(mesh.tags()),
        "channels": mesh.channels().iter().map(|c| json!({
            "name": c.name(),
            "dimension": c.dimension(),
            "values": c.value_count(),
            "seams": mesh.edges().filter(|&e| mesh.is_seam(c, e)).count(),
        })).collect::<Vec<_>>(),
        "problems": [],
    })
}

/// What can be said of a soup that does not build: counts and every problem.
fn soup_report(name: &str, soup: &PolygonSoup, problems: &[MeshError], located: &[String]) -> Value {
    let mut sizes = BTreeMap::new();
    for face in soup.faces() {
        *sizes.entry(face.len()).or_insert(0usize) += 1;
    }
    let problems: Vec<Value> =
        problems.iter().zip(located).map(|(p, at)| json!({ "rule": p.rule(), "message": at })).collect();
    json!({
        "mesh": name,
        "valid": false,
        "vertices": soup.vertex_count(),
        "faces": soup.face_count(),
        "face_sizes": histogram_json(&sizes),
        "tags": tags_json(&soup.tags),
        "problems": problems,
    })
}

fn write_text(out: &mut impl Write, report: &Value) -> std::io::Result<()> {
    let get = |key: &str| report.get(key).cloned().unwrap_or(Value::Null);
    let histogram = |key: &str| -> String {
        match report.get(key) {
            Some(Value::Object(map)) => map.iter().map(|(k, v)| format!("{k}:{v}")).collect::<Vec<_>>().join(" "),
            _ => String::new(),
        }
    };
    writeln!(out, "mesh            {}", get("mesh").as_str().unwrap_or_default())?;
    writeln!(out, "vertices        {}", get("vertices"))?;
    writeln!(out, "faces           {}  [size:count {}]", get("faces"), histogram("face_sizes"))?;
    if get("valid") == Value::Bool(true) {
        writeln!(out, "edges           {}", get("edges"))?;
        writeln!(out, "boundary        {} edges in {} loops", get("boundary_edges"), get("boundary_loops"))?;
        let genus = match get("genus") {
            Value::Null => "- (several components)".to_string(),
            g => g.to_string(),
        };
        writeln!(
            out,
            "components      {}  (Euler characteristic {}, genus {genus})",
            get("components"),
            get("euler_characteristic")
        )?;
        if get("isolated_vertices") != json!(0) {
            writeln!(out, "isolated        {} vertices used by no face", get("isolated_vertices"))?;
        }
        writeln!(
            out,
            "valence         {}..{}  [valence:count {}]",
            get("valence_min"),
            get("valence_max"),
            histogram("valences")
        )?;
        let regular = get("regular_valence");
        writeln!(
            out,
            "extraordinary   {} ({} interior + {} boundary; regular valence {} inside, {} on the boundary)",
            get("extraordinary_vertices"),
            get("extraordinary_interior"),
            get("extraordinary_boundary"),
            regular["interior"],
            regular["boundary"],
        )?;
    }
    if let Some(Value::Array(channels)) = report.get("channels") {
        for c in channels {
            writeln!(
                out,
                "channel         {} ({} components): {} values, {} seam edges",
                c["name"].as_str().unwrap_or_default(),
                c["dimension"],
                c["values"],
                c["seams"]
            )?;
        }
    }
    writeln!(out, "tags            {}", tags_text(&get("tags")))?;
    match report.get("problems") {
        Some(Value::Array(problems)) if !problems.is_empty() => {
            writeln!(out, "problems        {}", problems.len())?;
            for p in problems {
                writeln!(out, "  {}", p["message"].as_str().unwrap_or_default())?;
            }
        }
        _ => writeln!(out, "problems        none")?,
    }
    Ok(())
}

fn tags_text(tags: &Value) -> String {
    let mut parts = Vec::new();
    for key in ["creases", "corners", "holes"] {
        if let Some(n) = tags[key].as_u64().filter(|&n| n > 0) {
            parts.push(format!("{key}×{n}"));
        }
    }
    for key in ["boundary_interpolation", "crease_method", "triangle_subdivision", "face_varying_interpolation"] {
        if !tags[key].is_null() {
            parts.push(format!("{key}={}", tags[key].to_string().trim_matches('"')));
        }
    }
    if let Some(unsupported) = tags["unsupported"].as_array().filter(|u| !u.is_empty()) {
        let names: Vec<_> = unsupported.iter().filter_map(Value::as_str).collect();
        parts.push(format!("unsupported: {}", names.join(", ")));
    }
    if parts.is_empty() { "none".to_string() } else { parts.join(", ") }
}
