//! glTF / GLB: write → read round trips, the structure of written files, and hostile input
//! (each error typed and located, never a panic).

use base64::Engine as _;
use glam::{Vec2, Vec3};
use serde_json::{Value, json};
use subdiv_io::{GlbMesh, GltfOptions, IoError, encode_glb, load_gltf, parse_gltf, parse_gltf_with, write_glb};
use subdiv_mesh::{BuildOptions, PolygonSoup};

/// A tetrahedron with faces counter-clockwise from outside.
const POSITIONS: [Vec3; 4] =
    [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.1, 0.2, 1.0 / 3.0)];
const INDICES: [u32; 12] = [0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3];

fn tetrahedron() -> GlbMesh<'static> {
    GlbMesh { positions: &POSITIONS, normals: None, texcoords: None, indices: &INDICES }
}

fn parse(bytes: &[u8]) -> Result<PolygonSoup, IoError> {
    parse_gltf(bytes, "test.glb", None)
}

fn triangles(soup: &PolygonSoup) -> Vec<u32> {
    soup.faces().flatten().map(|v| v.raw()).collect()
}

/// Splits a GLB into its JSON document and BIN chunk.
fn split(glb: &[u8]) -> (Value, Vec<u8>) {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_length = word(12);
    let json = serde_json::from_slice(&glb[20..20 + json_length]).unwrap();
    let bin_length = word(20 + json_length);
    (json, glb[28 + json_length..28 + json_length + bin_length].to_vec())
}

/// Joins a JSON document and BIN chunk into a GLB.
fn join(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_string().into_bytes();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(((28 + json.len() + bin.len()) as u32).to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(bin);
    glb
}

/// The tetrahedron's GLB with its JSON and BIN edited.
fn edited(edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> Vec<u8> {
    let (mut json, mut bin) = split(&encode_glb(&tetrahedron()).unwrap());
    edit(&mut json, &mut bin);
    join(&json, &bin)
}

/// Asserts that `bytes` fail as a glTF error at `location` whose rule contains `rule`.
#[track_caller]
fn fails_at(bytes: &[u8], location: &str, rule: &str) {
    fails_with(bytes, &GltfOptions::DEFAULT, location, rule);
}

/// `IoError::Gltf` or one of the typed glTF variants: each displays as `FILE: LOCATION: RULE`.
fn fails_with(bytes: &[u8], options: &GltfOptions, location: &str, rule: &str) {
    match parse_gltf_with(bytes, "test.glb", None, options) {
        Err(error) => {
            let text = error.to_string();
            let prefix = format!("test.glb: {location}: ");
            assert!(text.starts_with(&prefix) && text.contains(rule), "{text:?} is not at {location} saying {rule:?}");
        }
        other => panic!("expected a glTF error at {location}, got {other:?}"),
    }
}

#[test]
fn glb_round_trip_keeps_positions_and_triangles() {
    let soup = parse(&encode_glb(&tetrahedron()).unwrap()).unwrap();
    let positions: Vec<Vec3> = soup.positions().iter().map(|p| p.as_vec3()).collect();
    assert_eq!(positions, POSITIONS);
    assert_eq!(triangles(&soup), INDICES);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tet.GLB");
    write_glb(&path, &tetrahedron()).unwrap();
    assert_eq!(subdiv_io::load(&path).unwrap(), soup);
    let mesh = subdiv_io::load_mesh(&path, &BuildOptions::DEFAULT).unwrap();
    assert_eq!((mesh.vertex_count(), mesh.face_count(), mesh.genus()), (4, 4, Some(0)));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file is left");
}

#[test]
fn written_glb_follows_the_container_and_accessor_rules() {
    let normals = [Vec3::Z * 2.0, Vec3::X, Vec3::Y, Vec3::ONE];
    let glb = encode_glb(&GlbMesh { normals: Some(&normals), ..tetrahedron() }).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len());
    assert_eq!(glb.len() % 4, 0);
    let (json, bin) = split(&glb);
    assert_eq!(json["asset"], json!({ "version": "2.0", "generator": "subdiv" }));
    assert_eq!(json["buffers"][0]["byteLength"], bin.len());
    let primitive = &json["meshes"][0]["primitives"][0];
    assert_eq!(primitive["attributes"], json!({ "POSITION": 0, "NORMAL": 1 }));
    let position = &json["accessors"][0];
    assert_eq!(position["min"], json!([0.0, 0.0, 0.0]));
    assert_eq!(position["max"], json!([1.0, 1.0, f64::from(1.0f32 / 3.0)]));
    for (view, target) in json["bufferViews"].as_array().unwrap().iter().zip([34962, 34962, 34963]) {
        assert_eq!(view["target"], target);
        assert!(view.get("byteStride").is_none());
        assert_eq!(view["byteOffset"].as_u64().unwrap() % 4, 0);
    }
    // Normals are stored normalised.
    let first_normal: Vec<f32> = bin[48..60].chunks(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
    assert_eq!(first_normal, [0.0, 0.0, 1.0]);
    // The same mesh gives the same bytes.
    assert_eq!(glb, encode_glb(&GlbMesh { normals: Some(&normals), ..tetrahedron() }).unwrap());
    // Interleaved vertices (a tessellator's flat buffers) give them too, and the same checks.
    let interleaved: Vec<[f32; 6]> =
        POSITIONS.iter().zip(&normals).map(|(p, n)| [p.x, p.y, p.z, n.x, n.y, n.z]).collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tet.glb");
    subdiv_io::write_glb_interleaved(&path, &interleaved, None, &INDICES).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), glb);
    let uv = [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::new(0.25, 0.75)];
    subdiv_io::write_glb_interleaved(&path, &interleaved, Some(&uv), &INDICES).unwrap();
    let textured = GlbMesh { normals: Some(&normals), texcoords: Some(&uv), ..tetrahedron() };
    assert_eq!(std::fs::read(&path).unwrap(), encode_glb(&textured).unwrap());
    let mut zero = interleaved.clone();
    zero[2][3..].fill(0.0);
    let error = subdiv_io::write_glb_interleaved(&path, &zero, None, &INDICES).unwrap_err();
    assert!(error.to_string().contains("normal 2"), "{error}");
    assert_eq!(std::fs::read(&path).unwrap(), encode_glb(&textured).unwrap(), "a refused mesh leaves the file alone");
}

#[test]
fn texture_coordinates_are_written_as_texcoord_0_and_read_back_as_the_uv_channel() {
    let uv = [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::new(0.25, 0.75)];
    let glb = encode_glb(&GlbMesh { texcoords: Some(&uv), ..tetrahedron() }).unwrap();
    let (json, _) = split(&glb);
    assert_eq!(json["meshes"][0]["primitives"][0]["attributes"], json!({ "POSITION": 0, "TEXCOORD_0": 1 }));
    assert_eq!(json["accessors"][1]["type"], "VEC2");
    let soup = parse(&glb).unwrap();
    let channel = &soup.channels[0];
    assert_eq!(channel.name(), subdiv_mesh::Channel::UV);
    for (corner, &v) in channel.indices().iter().zip(soup.raw_faces().1) {
        assert_eq!(channel.value(*corner), uv[v.index()].to_array().map(f64::from));
    }
}

#[test]
fn meshes_no_glb_can_hold_are_refused_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.glb");
    let nan = [Vec3::ZERO, Vec3::X, Vec3::NAN];
    let zero_normals = [Vec3::ZERO; 4];
    for mesh in [
        GlbMesh { indices: &[], ..tetrahedron() },
        GlbMesh { indices: &[0, 1], ..tetrahedron() },
        GlbMesh { indices: &[0, 1, 4], ..tetrahedron() },
        GlbMesh { positions: &nan, indices: &[0, 1, 2], normals: None, texcoords: None },
        GlbMesh { normals: Some(&POSITIONS[..3]), ..tetrahedron() },
        GlbMesh { normals: Some(&zero_normals), ..tetrahedron() },
        GlbMesh { texcoords: Some(&[Vec2::ZERO; 3]), ..tetrahedron() },
        GlbMesh { texcoords: Some(&[Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::NAN]), ..tetrahedron() },
    ] {
        let error = write_glb(&path, &mesh).unwrap_err();
        assert!(matches!(error, IoError::Unwritable { format: "GLB", .. }), "{error:?}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn gltf_with_a_data_uri_or_an_external_buffer_reads_like_glb() {
    let (mut json, bin) = split(&encode_glb(&tetrahedron()).unwrap());
    let expected = parse(&encode_glb(&tetrahedron()).unwrap()).unwrap();

    let data = base64::engine::general_purpose::STANDARD.encode(&bin);
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{data}"));
    assert_eq!(parse_gltf(json.to_string().as_bytes(), "test.gltf", None).unwrap(), expected);

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tet data.bin"), &bin).unwrap();
    json["buffers"][0]["uri"] = json!("tet%20data.bin");
    let path = dir.path().join("tet.gltf");
    std::fs::write(&path, json.to_string()).unwrap();
    assert_eq!(load_gltf(&path).unwrap(), expected);
    assert_eq!(subdiv_io::load(&path).unwrap(), expected);

    // Without a directory, or with the file missing, the buffer cannot be read.
    let error = parse_gltf(json.to_string().as_bytes(), "tet.gltf", None).unwrap_err();
    assert!(matches!(&error, IoError::Gltf { location, .. } if location == "buffers[0]"), "{error:?}");
    std::fs::remove_file(dir.path().join("tet data.bin")).unwrap();
    assert!(matches!(load_gltf(&path), Err(IoError::Io { .. })));
}

#[test]
fn primitives_without_indices_are_consecutive_triangles() {
    let glb = edited(|json, _| {
        json["meshes"][0]["primitives"][0].as_object_mut().unwrap().remove("indices");
        json["accessors"][0]["count"] = json!(3);
    });
    assert_eq!(triangles(&parse(&glb).unwrap()), [0, 1, 2]);
    // Four vertices do not make whole triangles.
    let glb = edited(|json, _| {
        json["meshes"][0]["primitives"][0].as_object_mut().unwrap().remove("indices");
    });
    fails_at(&glb, "meshes[0].primitives[0]", "multiple of 3");
}

#[test]
fn every_truncation_of_a_glb_is_an_error() {
    let glb = encode_glb(&tetrahedron()).unwrap();
    for length in 0..glb.len() {
        let error = parse(&glb[..length]).unwrap_err();
        assert!(matches!(error, IoError::Gltf { .. }), "{length}: {error:?}");
    }
    fails_at(&glb[..8], "GLB header", "truncated");
    fails_at(&glb[..40], "GLB header", "truncated");
    // A consistent header whose BIN chunk is cut short.
    let mut cut = glb[..glb.len() - 8].to_vec();
    let length = cut.len() as u32;
    cut[8..12].copy_from_slice(&length.to_le_bytes());
    fails_at(&cut, "GLB chunk 1", "truncated");
}

#[test]
fn bad_glb_magic_and_version_are_errors() {
    let mut glb = encode_glb(&tetrahedron()).unwrap();
    glb[..4].copy_from_slice(b"glTf");
    fails_at(&glb, "GLB header", "bad magic \"glTf\"");
    fails_at(b"PK\x03\x04 not a glb", "GLB header", "bad magic");
    let mut glb = encode_glb(&tetrahedron()).unwrap();
    glb[4] = 1;
    fails_at(&glb, "GLB header", "version 1");
}

#[test]
fn corrupt_bytes_never_panic() {
    let glb = encode_glb(&tetrahedron()).unwrap();
    for at in 0..glb.len() {
        for value in [0x00, 0x7f, 0xff] {
            let mut corrupt = glb.clone();
            corrupt[at] = value;
            let _ = parse(&corrupt);
        }
    }
}

#[test]
fn unsupported_primitive_modes_are_errors() {
    let glb = edited(|json, _| json["meshes"][0]["primitives"][0]["mode"] = json!(1));
    fails_at(&glb, "meshes[0].primitives[0].mode", "mode 1 (Lines) is not supported");
    let glb = edited(|json, _| json["meshes"][0]["primitives"][0]["mode"] = json!(99));
    fails_at(&glb, "meshes[0].primitives[0].mode", "is not a glTF primitive mode");
}

#[test]
fn missing_or_wrongly_typed_positions_are_errors() {
    let glb = edited(|json, _| json["meshes"][0]["primitives"][0]["attributes"] = json!({ "NORMAL": 0 }));
    fails_at(&glb, "meshes[0].primitives[0].attributes", "has no POSITION");
    let glb = edited(|json, _| json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99));
    fails_at(&glb, "meshes[0].primitives[0].attributes.POSITION", "refers to accessors[99]");
    let glb = edited(|json, _| json["accessors"][0]["componentType"] = json!(5123));
    fails_at(&glb, "accessors[0]", "POSITION must be VEC3 of FLOAT");
}

#[test]
fn non_finite_positions_are_errors() {
    let glb = edited(|_, bin| bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes()));
    fails_at(&glb, "accessors[0]", "element 1 = [NaN, 0, 0] is not finite");
    let glb = edited(|_, bin| bin[8..12].copy_from_slice(&f32::INFINITY.to_le_bytes()));
    fails_at(&glb, "accessors[0]", "element 0");
}

#[test]
fn indices_out_of_range_are_errors() {
    // The index buffer starts after the 4 positions (48 bytes); its second entry becomes 7.
    let glb = edited(|_, bin| bin[52..56].copy_from_slice(&7u32.to_le_bytes()));
    fails_at(&glb, "meshes[0].primitives[0].indices", "element 1 is 7, but POSITION has 4 vertices");
    let glb = edited(|json, _| json["accessors"][1]["type"] = json!("VEC2"));
    fails_at(&glb, "accessors[1]", "indices must be SCALAR");
}

#[test]
fn accessors_and_views_outside_their_buffer_are_errors() {
    let glb = edited(|json, _| json["accessors"][0]["count"] = json!(5));
    fails_at(&glb, "accessors[0]", "overrun bufferViews[0]");
    let glb = edited(|json, _| json["accessors"][0]["count"] = json!(u64::MAX));
    let unlimited = GltfOptions::DEFAULT.with_max_vertices(u64::MAX).with_max_indices(u64::MAX);
    fails_with(&glb, &unlimited, "accessors[0]", "overrun");
    let glb = edited(|json, _| json["accessors"][0]["byteOffset"] = json!(u64::MAX - 3));
    fails_at(&glb, "accessors[0]", "overrun");
    let glb = edited(|json, _| json["bufferViews"][1]["byteLength"] = json!(4000));
    fails_at(&glb, "bufferViews[1]", "outside buffers[0]");
    let glb = edited(|json, _| json["bufferViews"][0]["byteStride"] = json!(8));
    fails_at(&glb, "bufferViews[0]", "byteStride 8");
    let glb = edited(|json, _| json["accessors"][0]["bufferView"] = json!(9));
    fails_at(&glb, "accessors[0].bufferView", "refers to bufferViews[9]");
    let glb = edited(|json, bin| json["buffers"][0]["byteLength"] = json!(bin.len() + 4));
    fails_at(&glb, "buffers[0]", "declares byteLength");
    let glb = edited(|json, _| {
        json["accessors"][0]["sparse"] =
            json!({ "count": 1, "indices": { "bufferView": 1, "componentType": 5125 }, "values": { "bufferView": 0 } });
    });
    fails_at(&glb, "accessors[0]", "sparse");
}

#[test]
fn documents_without_geometry_or_with_required_extensions_are_errors() {
    let glb = edited(|json, _| json["meshes"] = json!([]));
    assert!(matches!(parse(&glb), Err(IoError::NoGeometry { file }) if file == "test.glb"));
    let glb = edited(|json, _| json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]));
    fails_at(&glb, "extensionsRequired", "KHR_draco_mesh_compression");
    fails_at(&join(&json!({ "meshes": [] }), &[]), "GLB chunk 0 (JSON)", "asset");
    let error = parse_gltf(b"{ not json", "test.gltf", None).unwrap_err();
    assert!(matches!(&error, IoError::Gltf { location, .. } if location == "JSON"), "{error:?}");
    assert!(error.to_string().starts_with("test.gltf: JSON: "), "{error}");
}
