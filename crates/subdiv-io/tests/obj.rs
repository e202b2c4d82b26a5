//! OBJ reading and writing: every index form, tags, hostile input (each error typed and
//! located), round trips, atomic writes.

use proptest::prelude::*;
use subdiv_io::{IoError, ObjFile, load_mesh, read_obj, write_obj, write_obj_to};
use subdiv_mesh::strategies::{MeshParams, meshes};
use subdiv_mesh::{
    BoundaryInterpolation, BuildOptions, CornerTag, CreaseMethod, CreaseTag, DVec3, FaceId, FaceVaryingInterpolation,
    MeshError, PolygonSoup, TriangleSubdivision, VertexId,
};

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

fn read(text: impl AsRef<[u8]>) -> Result<PolygonSoup, IoError> {
    read_obj(text.as_ref(), "test.obj")
}

fn faces(soup: &PolygonSoup) -> Vec<Vec<u32>> {
    soup.faces().map(|f| f.iter().map(|v| v.raw()).collect()).collect()
}

fn v(i: u32) -> VertexId {
    VertexId::new(i)
}

#[test]
fn every_index_form_reads_the_same_face() {
    for (face, with_uv) in [
        ("f 1 2 3 4", false),
        ("f 1/1 2/2 3/3 4/4", true),
        ("f 1//1 2//2 3//3 4//4", false),
        ("f 1/1/1 2/2/2 3/3/3 4/4/4", true),
        ("f -4 -3 -2 -1", false),
    ] {
        let soup = read(format!("{QUAD}vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n{face}\n")).unwrap();
        assert_eq!(faces(&soup), [[0, 1, 2, 3]], "{face}");
        // The forms with texture coordinates make the channel, the others none.
        let uv: Vec<&[u32]> = soup.channels.iter().map(|c| c.indices()).collect();
        let expected: Vec<&[u32]> = if with_uv { vec![&[0, 1, 2, 3]] } else { vec![] };
        assert_eq!(uv, expected, "{face}");
    }
}

#[test]
fn relative_indices_count_back_from_the_last_vertex_defined_so_far() {
    let soup = read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf -3 -1 -2\n").unwrap();
    assert_eq!(faces(&soup), [[0, 1, 2], [1, 3, 2]]);
}

#[test]
fn faces_may_refer_to_vertices_defined_later() {
    let soup = read("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    assert_eq!(faces(&soup), [[0, 1, 2]]);
}

#[test]
fn extra_vertex_values_comments_and_other_records_are_skipped() {
    let text = "# comment \u{e9}\nmtllib none.mtl\no thing\ng group\ns 1\nusemtl red\n\
                v 0 0 0 1\nv 1 0 0 0.5 0.5 0.5\nv 0 1 \\\n 0\nl 1 2\nvp 0.5\nf 1 2 3\r\n";
    let soup = read(text).unwrap();
    assert_eq!(soup.positions(), [DVec3::ZERO, DVec3::X, DVec3::Y]);
    assert_eq!(faces(&soup), [[0, 1, 2]]);
    // Comments and skipped records need not be UTF-8 (old files carry Latin-1 names).
    assert!(read(b"# caf\xe9\ng caf\xe9\nv 0 0 0\n").is_ok());
}

#[test]
fn crease_chains_take_one_sharpness_or_one_per_edge() {
    let soup = read(format!("{QUAD}f 1 2 3 4\nt crease 3/1/0 0 1 2 2.5\nt crease 3/2/0 2 3 0 1 10\n")).unwrap();
    let crease = |a, b, sharpness| CreaseTag { vertices: [v(a), v(b)], sharpness };
    assert_eq!(soup.tags.creases, [crease(0, 1, 2.5), crease(1, 2, 2.5), crease(2, 3, 1.0), crease(3, 0, 10.0)]);
}

#[test]
fn corner_hole_and_scheme_tags_are_read() {
    let text = format!(
        "{QUAD}v 2 0 0\nf 1 2 3 4\nf 2 5 3\nt corner 2/1/0 0 1 4\nt corner 2/2/0 2 3 0.5 1.5\nt hole 1/0/0 1\n\
         t interpolateboundary 1/0/0 1\nt facevaryinginterpolateboundary 1/0/0 3\nt creasemethod 0/0/1 chaikin\n\
         t smoothtriangles 0/0/1 smooth\n"
    );
    let tags = read(text).unwrap().tags;
    let corner = |vertex, sharpness| CornerTag { vertex: v(vertex), sharpness };
    assert_eq!(tags.corners, [corner(0, 4.0), corner(1, 4.0), corner(2, 0.5), corner(3, 1.5)]);
    assert_eq!(tags.holes, [FaceId::new(1)]);
    assert_eq!(tags.boundary_interpolation, Some(BoundaryInterpolation::EdgeAndCorner));
    assert_eq!(tags.face_varying_interpolation, Some(FaceVaryingInterpolation::CornersPlus2));
    assert_eq!(tags.crease_method, Some(CreaseMethod::Chaikin));
    assert_eq!(tags.triangle_subdivision, Some(TriangleSubdivision::Smooth));
    for (code, expected) in [(0, BoundaryInterpolation::None), (2, BoundaryInterpolation::EdgeOnly)] {
        let tags = read(format!("{QUAD}t interpolateboundary 1/0/0 {code}\n")).unwrap().tags;
        assert_eq!(tags.boundary_interpolation, Some(expected));
    }
    let tags = read(format!("{QUAD}t creasemethod 0/0/1 normal\nt smoothtriangles 0/0/1 catmark\n")).unwrap().tags;
    assert_eq!(
        (tags.crease_method, tags.triangle_subdivision),
        (Some(CreaseMethod::Uniform), Some(TriangleSubdivision::Catmark))
    );
}

#[test]
fn unknown_tags_are_recorded_by_name() {
    let text = format!("{QUAD}f 1 2 3 4\nt vertexedit 2/1/3 0 1 0.5 add P value\nt faceedit 1/0/1 0 hole\n");
    assert_eq!(read(text).unwrap().tags.unsupported, ["vertexedit", "faceedit"]);
}

/// Asserts that `text` fails with `expected(error)` at `line`.
#[track_caller]
fn fails_at(text: impl AsRef<[u8]>, line: usize, expected: impl Fn(&IoError) -> bool) -> IoError {
    let error = read(text).unwrap_err();
    assert!(expected(&error), "unexpected error: {error:?}");
    assert_eq!(error.line(), Some(line), "{error}");
    assert!(error.to_string().starts_with(&format!("test.obj:{line}: ")), "{error}");
    error
}

#[test]
fn an_empty_file_has_no_geometry() {
    for text in ["", "\n\n", "# only a comment\n", "g nothing\n"] {
        let error = read(text).unwrap_err();
        assert!(matches!(&error, IoError::NoGeometry { file } if file == "test.obj"), "{error:?}");
        assert_eq!(error.to_string(), "test.obj: no geometry; a mesh file needs vertices and faces");
    }
}

#[test]
fn garbage_lines_are_errors() {
    fails_at(format!("{QUAD}\u{1}\u{2}\u{3} junk\n"), 5, |e| matches!(e, IoError::ObjSyntax { .. }));
    fails_at("v 0 0 0\n1.0 2.0 3.0\n", 2, |e| matches!(e, IoError::ObjSyntax { .. }));
    fails_at(b"\x00\xff\xfe\x89PNG\n", 1, |e| matches!(e, IoError::NotUtf8 { .. }));
}

#[test]
fn non_numeric_and_missing_coordinates_are_errors() {
    let error = fails_at("v 0 0 0\nv 1 x 0\n", 2, |e| matches!(e, IoError::ObjSyntax { .. }));
    assert!(error.to_string().contains("\"x\" is not a number"), "{error}");
    fails_at("v 0 0\n", 1, |e| matches!(e, IoError::ObjSyntax { .. }));
    fails_at("v 0 0 0 red\n", 1, |e| matches!(e, IoError::ObjSyntax { .. }));
}

#[test]
fn nan_and_infinite_coordinates_are_errors_at_their_vertex() {
    for (text, nan) in [("nan", true), ("NaN", true), ("inf", false), ("-infinity", false), ("1e999", false)] {
        let error =
            fails_at(format!("v 0 0 0\nv 0 {text} 0\n"), 2, |e| matches!(e, IoError::NonFiniteCoordinate { .. }));
        let IoError::NonFiniteCoordinate { value, .. } = error else { unreachable!() };
        assert_eq!(value.is_nan(), nan);
    }
}

#[test]
fn index_zero_is_an_error() {
    fails_at(format!("{QUAD}f 1 2 3\nf 0 1 2\n"), 6, |e| matches!(e, IoError::IndexZero { .. }));
    fails_at(format!("{QUAD}f 1/0 2 0//3\n"), 5, |e| matches!(e, IoError::IndexZero { .. }));
}

#[test]
fn out_of_range_indices_are_errors_at_their_face() {
    let error = fails_at(format!("{QUAD}f 1 2 3\nf 1 2 5\nf 1 2 9\n"), 6, |e| {
        matches!(e, IoError::IndexOutOfRange { index: 5, vertex_count: 4, .. })
    });
    assert_eq!(
        error.to_string(),
        "test.obj:6: vertex index 5 is out of range: the file has 4 vertices (OBJ indices are 1-based)"
    );
    // A relative index may only reach the vertices defined above its face.
    fails_at("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", 3, |e| {
        matches!(e, IoError::IndexOutOfRange { index: -3, vertex_count: 2, .. })
    });
}

#[test]
fn huge_indices_are_errors_not_panics() {
    let twenty_digits = "12345678901234567890";
    fails_at(
        format!("{QUAD}f 1 2 {twenty_digits}\n"),
        5,
        |e| matches!(e, IoError::IndexOverflow { token, .. } if token == twenty_digits),
    );
    fails_at(format!("{QUAD}f 1 2 -{twenty_digits}\n"), 5, |e| matches!(e, IoError::IndexOverflow { .. }));
    // Fits i64, but no 32-bit vertex id.
    fails_at(format!("{QUAD}f 1 2 99999999999\n"), 5, |e| matches!(e, IoError::IndexOverflow { .. }));
    fails_at(format!("{QUAD}f 1 2 3\nt crease 2/1/0 0 {twenty_digits} 1\n"), 6, |e| {
        matches!(e, IoError::ObjSyntax { .. })
    });
}

#[test]
fn malformed_face_vertices_are_errors() {
    for face in ["f 1 2 x", "f 1 2 3/a", "f 1 2 3/1/1/1", "f 1 2 /3", "f 1 2 3.5"] {
        fails_at(format!("{QUAD}{face}\n"), 5, |e| matches!(e, IoError::ObjSyntax { .. }));
    }
}

#[test]
fn a_face_needs_three_vertices() {
    let error = fails_at(format!("{QUAD}f 1 2 3\nf 1 2\n"), 6, |e| matches!(e, IoError::FaceTooSmall { count: 2, .. }));
    assert_eq!(error.to_string(), "test.obj:6: face has 2 vertices; a face needs at least 3");
    fails_at(format!("{QUAD}f\n"), 5, |e| matches!(e, IoError::FaceTooSmall { count: 0, .. }));
}

#[test]
fn non_utf8_records_are_errors_at_their_line() {
    fails_at(b"v 0 0 0\nv 1 \xff 0\n", 2, |e| matches!(e, IoError::NotUtf8 { .. }));
    fails_at(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt cr\xc3ase 0/0/0\n", 5, |e| matches!(e, IoError::NotUtf8 { .. }));
}

#[test]
fn malformed_tags_are_errors_at_their_line() {
    let body = format!("{QUAD}f 1 2 3 4\n");
    for tag in [
        "t crease",
        "t crease 2/1",
        "t crease 2/1/0 0 1",
        "t crease 2/1/0 0 1 2 3",
        "t crease 1/1/0 0 1",
        "t crease 3/3/0 0 1 2 1 1 1",
        "t crease 2/1/0 0 x 1",
        "t crease 2/1/0 0 1 sharp",
        "t corner 2/3/0 0 1 1 1 1",
        "t hole 1/1/0 0 1",
        "t interpolateboundary 1/0/0 3",
        "t interpolateboundary 2/0/0 1 1",
        "t facevaryinginterpolateboundary 1/0/0 6",
        "t creasemethod 0/0/1 sideways",
        "t smoothtriangles 0/0/1 bumpy",
        "t vertexedit 99999999999999999999/0/0",
    ] {
        let error = read(format!("{body}{tag}\n")).unwrap_err();
        assert!(matches!(error, IoError::ObjSyntax { line: 6, .. }), "{tag}: {error:?}");
    }
}

#[test]
fn tag_indices_out_of_range_are_errors_at_the_tag_line() {
    let body = format!("{QUAD}f 1 2 3 4\n");
    let error = read(format!("{body}t crease 2/1/0 0 1 1\nt crease 3/1/0 1 2 4 1\n")).unwrap_err();
    assert!(matches!(error, IoError::TagOutOfRange { line: 7, tag: "crease", what: "vertex", index: 4, count: 4, .. }));
    assert_eq!(error.to_string(), "test.obj:7: t crease: vertex 4 is out of range 0..4 (tag indices are 0-based)");
    let error = read(format!("{body}t corner 1/1/0 -1 1\n")).unwrap_err();
    assert!(matches!(error, IoError::TagOutOfRange { line: 6, index: -1, .. }), "{error:?}");
    let error = read(format!("{body}t hole 2/0/0 0 1\n")).unwrap_err();
    assert!(matches!(error, IoError::TagOutOfRange { line: 6, what: "face", index: 1, count: 1, .. }), "{error:?}");
}

#[test]
fn mesh_errors_name_the_line_of_the_face_or_tag() {
    // Faces 0 and 1 both run from vertex 0 to vertex 1: inconsistent orientation.
    let text = format!("{QUAD}f 1 2 3\nf 1 2 4\n");
    let obj = ObjFile::read(text.as_bytes(), "test.obj").unwrap();
    assert_eq!(obj.lines.faces, [5, 6]);
    let error = obj.build(&BuildOptions::DEFAULT).unwrap_err();
    let IoError::Mesh { line: Some(line), source: MeshError::InconsistentOrientation { face, .. }, .. } = &error else {
        panic!("{error:?}")
    };
    assert_eq!(*line, 5 + face.index());
    assert!(error.to_string().starts_with(&format!("test.obj:{line}: inconsistent orientation")), "{error}");

    let text = format!("{QUAD}f 1 2 3 4\nt crease 2/1/0 0 2 1\n");
    let error = ObjFile::read(text.as_bytes(), "test.obj").unwrap().build(&BuildOptions::DEFAULT).unwrap_err();
    assert!(
        matches!(error, IoError::Mesh { line: Some(6), source: MeshError::CreaseNotAnEdge { .. }, .. }),
        "{error:?}"
    );
    assert!(error.to_string().starts_with("test.obj:6: crease tag 0"), "{error}");
}

#[test]
fn load_mesh_dispatches_on_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("Quad.OBJ");
    std::fs::write(&path, format!("{QUAD}f 1 2 3 4\nf 1 2 3\n")).unwrap();
    let error = load_mesh(&path, &BuildOptions::DEFAULT).unwrap_err();
    assert!(matches!(error, IoError::Mesh { line: Some(5 | 6), .. }), "{error:?}");
    assert!(error.to_string().starts_with(&path.display().to_string()), "{error}");
    std::fs::write(dir.path().join("quad.txt"), QUAD).unwrap();
    let error = subdiv_io::load(dir.path().join("quad.txt")).unwrap_err();
    assert!(matches!(error, IoError::UnknownFormat { .. }), "{error:?}");
    let error = subdiv_io::load(dir.path().join("missing.obj")).unwrap_err();
    assert!(matches!(error, IoError::Io { .. }), "{error:?}");
}

fn soup_with_every_tag() -> PolygonSoup {
    let positions = vec![
        DVec3::new(0.1, -0.0, 1e-300),
        DVec3::new(1.0 / 3.0, 2.5e20, -7.0),
        DVec3::new(std::f64::consts::PI, 1.0, 0.0),
        DVec3::new(f64::MAX, f64::MIN_POSITIVE, -1e-7),
    ];
    let mut soup = PolygonSoup::from_indices(positions, [[0u32, 1, 2, 3], [3, 2, 1, 0]]);
    let tags = &mut soup.tags;
    tags.creases = vec![
        CreaseTag { vertices: [v(0), v(1)], sharpness: 0.3 },
        CreaseTag { vertices: [v(2), v(1)], sharpness: 10.0 },
    ];
    tags.corners = vec![CornerTag { vertex: v(3), sharpness: 2.0 }];
    tags.holes = vec![FaceId::new(1), FaceId::new(0)];
    tags.boundary_interpolation = Some(BoundaryInterpolation::EdgeOnly);
    tags.face_varying_interpolation = Some(FaceVaryingInterpolation::All);
    tags.crease_method = Some(CreaseMethod::Chaikin);
    tags.triangle_subdivision = Some(TriangleSubdivision::Smooth);
    tags.unsupported = vec!["vertexedit".into(), "edgeedit".into()];
    soup
}

#[test]
fn obj_round_trip_keeps_positions_faces_and_tags_exactly() {
    let soup = soup_with_every_tag();
    let mut text = Vec::new();
    write_obj_to(&mut text, &soup).unwrap();
    assert_eq!(read(&text).unwrap(), soup, "{}", String::from_utf8_lossy(&text));

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.obj");
    write_obj(&path, &soup).unwrap();
    assert_eq!(subdiv_io::load(&path).unwrap(), soup);
    assert_eq!(std::fs::read(&path).unwrap(), text, "the same soup gives the same bytes");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file is left");
}

#[test]
fn unwritable_soups_are_refused_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.obj");
    let cases = [
        PolygonSoup::from_indices(vec![DVec3::ZERO, DVec3::X, DVec3::NAN], [[0u32, 1, 2]]),
        PolygonSoup::from_indices(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1]]),
        PolygonSoup::from_indices(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 3]]),
        {
            let mut soup = PolygonSoup::from_indices(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
            soup.tags.holes.push(FaceId::new(1));
            soup
        },
        {
            let mut soup = PolygonSoup::from_indices(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
            soup.tags.unsupported.push("crease".into());
            soup
        },
    ];
    for soup in cases {
        let error = write_obj(&path, &soup).unwrap_err();
        assert!(matches!(error, IoError::Unwritable { format: "OBJ", .. }), "{error:?}");
        let error = write_obj_to(Vec::new(), &soup).unwrap_err();
        assert_eq!(error.kind(), std::io::ErrorKind::InvalidInput);
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn a_failed_write_leaves_the_old_file_and_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let error = write_obj(dir.path().join("no/such/dir/out.obj"), &soup_with_every_tag()).unwrap_err();
    assert!(matches!(error, IoError::Io { .. }), "{error:?}");
    // The target is a directory: the rename fails after the temporary file was written.
    let target = dir.path().join("taken.obj");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), "x").unwrap();
    assert!(matches!(write_obj(&target, &soup_with_every_tag()), Err(IoError::Io { .. })));
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, ["taken.obj"]);
}

fn arbitrary_soup() -> impl Strategy<Value = PolygonSoup> {
    let coordinate = prop_oneof![any::<f64>().prop_filter("finite", |x| x.is_finite()), -10.0..10.0f64];
    (3usize..12)
        .prop_flat_map(move |n| {
            let positions = prop::collection::vec([coordinate.clone(), coordinate.clone(), coordinate.clone()], n);
            let faces = prop::collection::vec(prop::collection::vec(0..n as u32, 3..6), 0..6);
            let creases = prop::collection::vec((0..n as u32, 0..n as u32, 0.0..20.0f64), 0..4);
            let corners = prop::collection::vec((0..n as u32, 0.0..20.0f64), 0..3);
            (positions, faces, creases, corners, any::<Option<bool>>())
        })
        .prop_map(|(positions, faces, creases, corners, flag)| {
            let positions = positions.into_iter().map(DVec3::from_array).collect();
            let mut soup = PolygonSoup::from_indices(positions, faces);
            soup.tags.creases =
                creases.into_iter().map(|(a, b, sharpness)| CreaseTag { vertices: [v(a), v(b)], sharpness }).collect();
            soup.tags.corners =
                corners.into_iter().map(|(i, sharpness)| CornerTag { vertex: v(i), sharpness }).collect();
            soup.tags.holes = (0..soup.face_count() as u32).step_by(2).map(FaceId::new).collect();
            soup.tags.crease_method = flag.map(|f| if f { CreaseMethod::Chaikin } else { CreaseMethod::Uniform });
            soup
        })
}

proptest! {
    /// Arbitrary soups (invalid ones too), and valid meshes with creases and corners from
    /// `subdiv_mesh::strategies`.
    #[test]
    fn obj_round_trip_is_exact(soup in prop_oneof![arbitrary_soup(), meshes(MeshParams::DEFAULT.with_crease_probability(0.3))]) {
        let mut text = Vec::new();
        write_obj_to(&mut text, &soup).unwrap();
        prop_assert_eq!(read(&text).unwrap(), soup);
    }
}
