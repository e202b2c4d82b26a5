//! Every OBJ of the shared corpus (`$SUBDIV_SHARED/testdata/meshes`, described row by row in its
//! SOURCES.md) builds a mesh whose counts equal the table's row, or — exactly for the files the
//! table marks non-manifold, degenerate or misoriented — fails with the matching named errors.

use std::collections::BTreeMap;

use subdiv_testkit::{meshes_dir, obj_files};

use subdiv::mesh::{Mesh, MeshError, RegularValence, validate};

/// One row of SOURCES.md's statistics tables.
#[derive(Debug)]
struct Row {
    vertices: usize,
    faces: usize,
    face_sizes: BTreeMap<usize, usize>,
    boundary_edges: usize,
    boundary_loops: usize,
    manifold: bool,
    non_manifold_edges: usize,
    non_manifold_vertices: usize,
    valence: (usize, usize),
    extraordinary: (usize, usize),
    components: usize,
    genus: Option<u32>,
    degenerate_faces: usize,
    misoriented_edges: usize,
}

fn number_before(text: &str, word: &str) -> usize {
    text.find(word).and_then(|at| text[..at].split_whitespace().last()).and_then(|n| n.parse().ok()).unwrap_or(0)
}

fn parse_rows(sources: &str) -> BTreeMap<String, Row> {
    let mut rows = BTreeMap::new();
    for line in sources.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | file | V | F | faces | closed / boundary | manifold | valence | extraordinary | components / genus | tags | notes |
        if cells.len() != 13 || !cells[1].contains(".obj") || cells[2].parse::<usize>().is_err() {
            continue;
        }
        let name = cells[1].split_whitespace().next().unwrap().to_string();
        let face_sizes = cells[4]
            .split('[')
            .nth(1)
            .unwrap()
            .trim_end_matches(']')
            .split(", ")
            .map(|pair| {
                let (size, count) = pair.split_once(':').unwrap();
                (size.parse().unwrap(), count.parse().unwrap())
            })
            .collect();
        let boundary = cells[5];
        let (boundary_edges, boundary_loops) = if boundary == "closed" {
            (0, 0)
        } else {
            (number_before(boundary, "bnd edges"), number_before(boundary, "loops"))
        };
        let manifold = cells[6] == "yes";
        let (lo, hi) = cells[7].split_once('–').unwrap();
        let (int, bnd) = cells[8].split_once('+').unwrap();
        let (components, genus) = cells[9].split_once(" / ").unwrap();
        rows.insert(
            name,
            Row {
                vertices: cells[2].parse().unwrap(),
                faces: cells[3].parse().unwrap(),
                face_sizes,
                boundary_edges,
                boundary_loops,
                manifold,
                non_manifold_edges: number_before(cells[6], "nm edges"),
                non_manifold_vertices: number_before(cells[6], "nm verts"),
                valence: (lo.parse().unwrap(), hi.parse().unwrap()),
                extraordinary: (int.parse().unwrap(), bnd.parse().unwrap()),
                components: components.parse().unwrap(),
                genus: genus.parse().ok(),
                degenerate_faces: number_before(cells[11], "degenerate faces"),
                misoriented_edges: number_before(cells[11], "misoriented edges"),
            },
        );
    }
    rows
}

#[test]
fn every_shared_mesh_matches_its_sources_row() {
    let Some(meshes) = meshes_dir() else { return };
    let rows = parse_rows(&std::fs::read_to_string(meshes.join("SOURCES.md")).unwrap());
    let files = obj_files(&meshes);
    assert_eq!(files.len(), 134, "the corpus has 134 OBJ files");
    assert_eq!(rows.len(), files.len(), "SOURCES.md has a row per file");

    let mut failures = Vec::new();
    for path in &files {
        let name = path.file_name().unwrap().to_str().unwrap();
        let row = &rows[name];
        let soup = match subdiv::io::load(path) {
            Ok(soup) => soup,
            Err(error) => {
                failures.push(format!("{name}: does not read: {error}"));
                continue;
            }
        };
        assert_eq!((soup.vertex_count(), soup.face_count()), (row.vertices, row.faces), "{name}");
        let expect_invalid = !row.manifold || row.degenerate_faces > 0 || row.misoriented_edges > 0;
        if expect_invalid {
            let problems = validate(&soup);
            let has = |rule: &str| problems.iter().any(|p: &MeshError| p.rule() == rule);
            let mut expected = Vec::new();
            if row.non_manifold_edges > 0 {
                expected.push("non-manifold-edge");
            }
            if row.non_manifold_vertices > 0 && row.non_manifold_edges == 0 {
                expected.push("non-manifold-vertex");
            }
            if row.degenerate_faces > 0 {
                expected.push("repeated-vertex");
            }
            if row.misoriented_edges > 0 {
                expected.push("inconsistent-orientation");
            }
            for rule in expected {
                if !has(rule) {
                    failures.push(format!("{name}: expected a {rule} error, got {problems:?}"));
                }
            }
            // Non-manifold cages (OpenSubdiv's `*_nonman_*` shapes) are refused by our rule, and
            // each refusal says why OpenSubdiv's result is not a surface there.
            let non_manifold = ["non-manifold-edge", "non-manifold-vertex", "repeated-vertex"];
            for p in problems.iter().filter(|p| non_manifold.contains(&p.rule())) {
                let text = p.to_string();
                if !(text.contains("OpenSubdiv") && text.contains("a surface there")) || text.contains('\n') {
                    failures.push(format!("{name}: the refusal does not say why in one line: {text}"));
                }
            }
            if Mesh::build(soup).is_ok() {
                failures.push(format!("{name}: built, but SOURCES.md marks it invalid"));
            }
            continue;
        }
        let mesh = match Mesh::build(soup) {
            Ok(mesh) => mesh,
            Err(error) => {
                failures.push(format!("{name}: {error}"));
                continue;
            }
        };
        let regular = RegularValence::for_faces_of(&mesh);
        let valences = mesh.valence_histogram();
        let interior = mesh.extraordinary_vertices(regular).filter(|&v| !mesh.is_boundary_vertex(v)).count();
        let boundary = mesh.extraordinary_vertices(regular).count() - interior;
        let got = (
            mesh.face_size_histogram(),
            mesh.boundary_edge_count(),
            mesh.boundary_loops().len(),
            (*valences.keys().next().unwrap(), *valences.keys().last().unwrap()),
            (interior, boundary),
            mesh.components().count(),
        );
        let want = (
            row.face_sizes.clone(),
            row.boundary_edges,
            row.boundary_loops,
            row.valence,
            row.extraordinary,
            row.components,
        );
        if got != want {
            failures.push(format!("{name}: got {got:?}, SOURCES.md says {want:?}"));
        }
        if let Some(genus) = row.genus
            && mesh.genus() != Some(genus)
        {
            failures.push(format!("{name}: genus {:?}, SOURCES.md says {genus}", mesh.genus()));
        }
    }
    assert!(failures.is_empty(), "{} of {} files differ:\n{}", failures.len(), files.len(), failures.join("\n"));
}
