//! Face-varying channels as surfaces of their own ([`ChannelSurface`]) on every shared mesh
//! with texture coordinates: refining the channel's surface gives the channel's face-varying
//! refinement (which equals OpenSubdiv's, `opensubdiv.rs`), corner for corner, in all six
//! modes; evaluating it equals OpenSubdiv's Bfr (`SUBDIV_OSD_LIMIT`).

#![allow(clippy::print_stderr)]

use subdiv::mesh::{Channel, FaceVaryingInterpolation, Mesh};
use subdiv::schemes::{ChannelSurface, RefineOptions, refine_uniform};

/// Each face corner's value of `mesh`'s first channel, as `(u, v)`.
fn corner_values(mesh: &Mesh) -> Vec<[f64; 2]> {
    let uv = mesh.channel(Channel::UV).expect("a uv channel");
    (0..mesh.half_edge_count())
        .map(|h| {
            let x = uv.value(uv.indices()[h]);
            [x[0], x[1]]
        })
        .collect()
}

#[test]
fn refining_a_channels_surface_is_its_face_varying_refinement() {
    let meshes = subdiv_testkit::textured_meshes();
    assert!(subdiv_testkit::meshes_dir().is_none() || meshes.len() == 103, "{} textured meshes", meshes.len());
    for (path, builtin, mesh) in &meshes {
        let name = path.file_name().unwrap().to_string_lossy();
        for mode in FaceVaryingInterpolation::ALL_MODES {
            let options = RefineOptions::DEFAULT.with_face_varying(mode);
            let surface = ChannelSurface::new(mesh, &mesh.channels()[0], builtin.scheme(), &options).unwrap();
            let levels = 2;
            let refined = refine_uniform(mesh, builtin.scheme(), levels, &options).unwrap();
            let channel = refine_uniform(surface.mesh(), surface.scheme(), levels, &RefineOptions::DEFAULT).unwrap();
            assert_eq!(refined.face_count(), channel.face_count(), "{name}");
            let expected = corner_values(&refined);
            let size = expected.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
            for f in channel.face_ids() {
                for (h, g) in channel.face_half_edges(f).zip(refined.face_half_edges(f)) {
                    let p = channel.position(channel.origin(h));
                    let e = expected[g.index()];
                    let d = (p.x - e[0]).abs().max((p.y - e[1]).abs());
                    assert!(d <= 1e-12 * size, "{name} ({}): {f} corner {p} against {e:?}", mode.name());
                }
            }
        }
    }
}

/// The vertices around which one value of `mesh`'s first channel takes two runs of faces that
/// do not touch (a fan A, B, A, B): Far's sibling detection splits the other value into two
/// (B and B', each a crease of its own), while Bfr sees B twice, apart, and makes it a corner.
/// Far's refinement — ours — and Far's own limit (`osd_refine --limit`) agree; Bfr does not.
fn split_runs(mesh: &Mesh) -> std::collections::HashSet<subdiv::mesh::VertexId> {
    let uv = &mesh.channels()[0];
    mesh.vertices()
        .filter(|&v| {
            let values: Vec<u32> = mesh.outgoing(v).map(|h| uv.corner_value(h)).collect();
            let runs: Vec<u32> =
                (0..values.len()).filter(|&i| i == 0 || values[i] != values[i - 1]).map(|i| values[i]).collect();
            let closed = !mesh.is_boundary_vertex(v);
            let runs = if closed && runs.len() > 1 && runs[0] == runs[runs.len() - 1] { &runs[1..] } else { &runs[..] };
            runs.iter().enumerate().any(|(i, r)| runs[i + 1..].contains(r))
        })
        .collect()
}

/// `osd_limit --fvar --grid 4` (Bfr's face-varying surfaces, approximation level 10): the
/// texture coordinates equal ours at every grid point, and their derivatives wherever Bfr's are
/// exact (away from face corners), in all six modes on the `*_fvar_*` shapes, spot and blub,
/// and in `none` (the smoothest) on the other textured meshes. Excepted: the points that differ on
/// faces around a vertex of [`split_runs`], where Bfr and Far differ (counted on stderr).
#[test]
fn texture_coordinates_equal_bfr_on_grids() {
    let Some(osd_limit) = subdiv_testkit::peer_program("SUBDIV_OSD_LIMIT") else { return };
    let mut differ = Vec::new();
    let mut compared = 0;
    for (path, builtin, mesh) in subdiv_testkit::textured_meshes() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let osd_scheme = match builtin {
            subdiv::Builtin::Loop => "loop",
            subdiv::Builtin::Bilinear => continue, // osd_limit takes catmark and loop
            _ => "catmark",
        };
        let surface = subdiv::Surface::new(mesh.clone(), builtin.scheme());
        let Ok(positions) = surface.evaluator(&subdiv::EvalOptions::DEFAULT) else { continue };
        let grid = positions.grid(4).unwrap();
        let split = split_runs(&mesh);
        let excepted: std::collections::HashSet<u32> =
            split.iter().flat_map(|&v| mesh.vertex_faces(v).map(|f| f.raw()).collect::<Vec<_>>()).collect();
        let mut exceptions = 0usize;
        let every_mode = name.contains("_fvar_") || name.starts_with("spot") || name.starts_with("blub");
        let modes: &[FaceVaryingInterpolation] =
            if every_mode { &FaceVaryingInterpolation::ALL_MODES } else { &[FaceVaryingInterpolation::None] };
        for &mode in modes {
            let mut options = subdiv::EvalOptions::DEFAULT;
            options.refine.face_varying = Some(mode);
            let uv = surface.channel_evaluator(Channel::UV, &options).unwrap();
            let output = std::process::Command::new(&osd_limit)
                .arg(&path)
                .args(["--scheme", osd_scheme, "--grid", "4", "--fvar", "--fvar-interpolation", mode.name()])
                .output()
                .unwrap();
            let text = String::from_utf8(output.stdout).unwrap();
            let rows: Vec<Vec<f64>> =
                text.lines().skip(1).map(|l| l.split(',').map(|s| s.parse().unwrap()).collect()).collect();
            // Faces whose construction made OpenSubdiv warn get no rows (a Bfr 3.5.0 defect at
            // interior valence-2 vertices, the harness's README).
            let warned: std::collections::HashSet<u32> = String::from_utf8_lossy(&output.stderr)
                .lines()
                .filter_map(|l| l.strip_prefix("osd_limit: warning: face ")?.split_once(" skipped")?.0.parse().ok())
                .collect();
            let points: Vec<_> = grid.points.iter().filter(|g| !warned.contains(&g.face.raw())).collect();
            if rows.len() != points.len() {
                differ.push(format!("{name} ({}): {} rows, ours {}", mode.name(), rows.len(), points.len()));
                continue;
            }
            let mut worst = (0.0f64, 0.0f64);
            for (x, g) in rows.iter().zip(points) {
                assert_eq!((x[0], x[1], x[2]), (f64::from(g.face.raw()), g.u, g.v), "{name}: rows in Bfr's order");
                let ours = uv.evaluate(g.face, g.u, g.v).unwrap();
                let dv = (ours.position.x - x[12]).abs().max((ours.position.y - x[13]).abs());
                // Face corners (Bfr takes Far's tangent masks there) and extraordinary points
                // inside a face (an N-gon's centre: no derivative) compare values only.
                let corner = [0.0, 1.0].contains(&g.u) && [0.0, 1.0].contains(&g.v);
                let dd = if corner || !ours.exact_derivatives {
                    0.0
                } else {
                    [(ours.du.x, x[14]), (ours.du.y, x[15]), (ours.dv.x, x[16]), (ours.dv.y, x[17])]
                        .iter()
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                };
                if (dv > 1e-12 || dd > 1e-9) && excepted.contains(&g.face.raw()) {
                    exceptions += 1;
                    continue;
                }
                worst = (worst.0.max(dv), worst.1.max(dd));
            }
            if worst.0 > 1e-12 || worst.1 > 1e-9 {
                differ.push(format!("{name} ({}): |Δuv| {:.1e}, |Δd| {:.1e}", mode.name(), worst.0, worst.1));
            }
            compared += 1;
        }
        if exceptions > 0 {
            eprintln!(
                "{name}: {exceptions} grid points differ from Bfr on faces around the {} vertices where a value takes \
                 two runs of faces (Far's limit is ours there)",
                split.len()
            );
        }
    }
    assert!(differ.is_empty(), "{} of {compared} differ from Bfr:\n{}", differ.len(), differ.join("\n"));
    assert!(compared >= 150, "{compared} mesh-modes compared");
}

/// A method independent of Bfr: `osd_refine --fvar --levels L --limit --exact-fvar-limit`
/// (refinement, then Far's face-varying limit masks with exact crease weights) gives the texture
/// coordinates at the dyadic points `(i/2^L, j/2^L)` of every base face, `L = max(2, ⌈largest
/// finite sharpness⌉)` so that no semi-sharp feature is left; ours equal them to 1e-12 at every
/// point, in all six modes, on the `*_fvar_*` shapes, spot and blub — darts and interior
/// valence-2 vertices (where Far's masks are not the limit) and their neighbours excepted.
#[test]
fn texture_coordinates_equal_far_limits_at_dyadic_points() {
    let Some(osd_refine) = subdiv_testkit::peer_program("SUBDIV_OSD_REFINE") else { return };
    let mut compared = 0;
    for (path, builtin, mesh) in subdiv_testkit::textured_meshes() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !(name.contains("_fvar_") || name.starts_with("spot_control") || name.starts_with("blub")) {
            continue;
        }
        let osd_scheme = match builtin {
            subdiv::Builtin::Loop => "loop",
            _ => "catmark",
        };
        let finite = mesh
            .edges()
            .map(|e| mesh.edge_sharpness(e))
            .chain(mesh.vertices().map(|v| mesh.vertex_sharpness(v)))
            .filter(|&s| s < subdiv::mesh::Tags::INFINITELY_SHARP)
            .fold(0.0, f64::max);
        let levels = (finite.ceil() as usize).max(2);
        let (refined, corners) = subdiv_testkit::refined::refined_corners(&mesh, builtin.scheme().split(), levels);
        let skip = subdiv_testkit::refined::far_limit_exceptions(&refined);
        let surface = subdiv::Surface::new(mesh.clone(), builtin.scheme());
        for mode in FaceVaryingInterpolation::ALL_MODES {
            let mut options = subdiv::EvalOptions::DEFAULT;
            options.refine.face_varying = Some(mode);
            let uv = surface.channel_evaluator(Channel::UV, &options).unwrap();
            let out = std::env::temp_dir().join(format!("osd_fvar_limit_{}.obj", std::process::id()));
            let level = levels.to_string();
            let args = ["--fvar", "--fvar-interpolation", mode.name(), "--levels", &level, "--scheme", osd_scheme];
            let status = std::process::Command::new(&osd_refine)
                .arg(&path)
                .args(args)
                .args(["--limit", "--exact-fvar-limit", "-o"])
                .arg(&out)
                .status()
                .unwrap();
            assert!(status.success(), "{name}: osd_refine {args:?}");
            let theirs = subdiv::io::load_obj(&out).unwrap();
            let _ = std::fs::remove_file(&out);
            let their_uv = &theirs.channels[0];
            let faces: Vec<_> = refined.face_ids().filter(|&f| !refined.is_hole(f)).collect();
            assert_eq!(faces.len(), theirs.face_count(), "{name}");
            let (offsets, _) = theirs.raw_faces();
            let mut worst = 0.0f64;
            for (k, &f) in faces.iter().enumerate() {
                let (base, params) = &corners[f.index()];
                for (j, v) in refined.face_vertices(f).iter().enumerate() {
                    if skip.contains(v) {
                        continue;
                    }
                    let p = params[j];
                    let d = p.denominator as f64;
                    let ours = uv.evaluate(*base, p.u as f64 / d, p.v as f64 / d).unwrap().position;
                    let far = their_uv.value(their_uv.indices()[offsets[k] as usize + j]);
                    let e = (ours.x - far[0]).abs().max((ours.y - far[1]).abs());
                    assert!(e < 1e-12, "{name} ({}): {base} at {p:?}: ours {ours}, Far's {far:?}", mode.name());
                    worst = worst.max(e);
                }
            }
            eprintln!("{name} ({}): level {levels}, worst {worst:.1e}, {} excepted", mode.name(), skip.len());
            compared += 1;
        }
    }
    assert!(compared >= 12 * 6, "{compared} mesh-modes compared");
}

/// The points' surface parameters of a tessellation: the vertices', then the extra normals'.
fn point_parameters(out: &subdiv::TessMesh) -> Vec<subdiv::tess::SurfaceParameter> {
    out.parameters.iter().chain(&out.normal_parameters).copied().collect()
}

/// Whether faces `a` and `b` use one value of `channel` somewhere they meet: at a shared vertex
/// where their corners take the same value. (A triangle of a vertex's fan may join two faces
/// across a seam that starts at the vertex: at the vertex they agree.)
fn joined(mesh: &Mesh, channel: &Channel, a: subdiv::FaceId, b: subdiv::FaceId) -> bool {
    a == b
        || mesh.face_half_edges(a).any(|h| {
            mesh.face_half_edges(b)
                .any(|g| mesh.origin(g) == mesh.origin(h) && channel.corner_value(g) == channel.corner_value(h))
        })
}

/// Tessellations of spot, blub and `catmark_fvar_bound0..4` at rates 3, 8 and screen-space:
/// watertight and welded in positions (each directed edge once, borders only where the cage
/// has them, the cage's Euler characteristic), every point's texture coordinates equal to the
/// channel's evaluator at the point's parameters to 1e-12 (the vertices and the seams' second
/// sides, each in its own face), no triangle across a seam (its corners' faces use one value
/// where they meet), and the seams split (some vertex has a second side of other values).
#[test]
fn tessellations_carry_exact_texture_coordinates_split_at_seams() {
    use subdiv::tess::rates::ScreenSpace;
    use subdiv::{Camera, DVec3, EvalOptions, Rates, Surface, TessOptions};
    if subdiv_testkit::meshes_dir().is_none() {
        return;
    }
    let wanted = ["spot_control_mesh.obj", "blub_control_mesh.obj"]
        .into_iter()
        .map(String::from)
        .chain((0..5).map(|k| format!("catmark_fvar_bound{k}.obj")))
        .collect::<Vec<_>>();
    let mut compared = 0;
    for (path, builtin, mesh) in subdiv_testkit::textured_meshes() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !wanted.contains(&name) {
            continue;
        }
        let channel = mesh.channel(Channel::UV).unwrap().clone();
        let mut surface = Surface::new(mesh.clone(), builtin.scheme());
        let uv = surface.channel_evaluator(Channel::UV, &EvalOptions::DEFAULT).unwrap();
        let (lo, hi) = mesh.bounding_box().unwrap();
        let camera =
            Camera::look_at((lo + hi) * 0.5 + (hi - lo) * DVec3::new(0.9, 0.7, 1.3), (lo + hi) * 0.5, DVec3::Y);
        let screen = Rates::Screen { camera, viewport: [640, 480], pixels_per_edge: 12.0 };
        assert!(ScreenSpace::new(camera, [640, 480], 12.0).face_rates(&mesh).is_ok());
        let mut split = 0;
        for rates in [Rates::Uniform(3), Rates::Uniform(8), screen] {
            let tessellation = surface.tessellate(&TessOptions { rates, ..TessOptions::DEFAULT }).unwrap();
            let predicted = subdiv::tess::dual::predicted_vertex_count(
                &mesh,
                subdiv::schemes::Split::Quad,
                &tessellation.info.rates,
            );
            let out = tessellation.into_mesh();
            assert_eq!(out.positions.len(), predicted, "{name}: the budget's count, seams included");
            let coords = out.channels.find(Channel::UV).expect("the texture coordinates are carried");
            // Welded and watertight in positions.
            let mut directed = std::collections::HashMap::new();
            for t in &out.triangles {
                for i in 0..3 {
                    assert!(
                        directed.insert((t[i], t[(i + 1) % 3]), ()).is_none(),
                        "{name}: an edge used twice one way"
                    );
                }
            }
            let open = mesh.edges().any(|e| mesh.is_boundary_edge(e)) || mesh.face_ids().any(|f| mesh.is_hole(f));
            let border = directed.keys().filter(|&&(a, b)| !directed.contains_key(&(b, a))).count();
            assert!(open || border == 0, "{name}: {border} border edges on a closed cage");
            let mut seen = std::collections::HashSet::new();
            assert!(out.positions.iter().all(|p| seen.insert(p.to_array().map(f64::to_bits))), "{name}: not welded");
            if !open {
                let edges = directed.len() / 2;
                let euler = out.positions.len() as i64 - edges as i64 + out.triangles.len() as i64;
                assert_eq!(euler, mesh.euler_characteristic(), "{name}");
            }
            // Every point's coordinates, at its own parameters.
            let parameters = point_parameters(&out);
            assert_eq!(out.channels.values.len(), 2 * parameters.len());
            for (k, p) in parameters.iter().enumerate() {
                let expected = uv.evaluate(p.face, p.u, p.v).unwrap().position;
                let got = &out.channels.point(k)[coords.clone()];
                let error = (got[0] - expected.x).abs().max((got[1] - expected.y).abs());
                assert!(error <= 1e-12, "{name}: point {k} at {p:?}: {got:?} against {expected}");
            }
            // No triangle across a seam; the seams split.
            for (t, corners) in out.triangle_normals.iter().enumerate() {
                let faces = corners.map(|c| parameters[c as usize].face);
                for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                    assert!(
                        joined(&mesh, &channel, faces[a], faces[b]),
                        "{name}: triangle {t} crosses a seam: {faces:?}"
                    );
                }
            }
            let positions = out.positions.len();
            split += out
                .normal_vertices
                .iter()
                .enumerate()
                .filter(|&(k, &v)| out.channels.point(positions + k) != out.channels.point(v as usize))
                .count();
        }
        assert!(split > 0 || mesh.edges().all(|e| !mesh.is_seam(&channel, e)), "{name}: no seam split");
        eprintln!("{name}: {split} seam points split");
        compared += 1;
    }
    assert_eq!(compared, 7, "spot, blub and catmark_fvar_bound0..4");
}

/// Every shared mesh with texture coordinates tessellates with them at rate 2 (its scheme's
/// face-varying surface prepared by the dual tessellator's own evaluator): one value per point,
/// every seventh point equal to the channel's evaluator to 1e-12, positions welded.
#[test]
fn every_textured_shared_mesh_tessellates_with_its_texture_coordinates() {
    use subdiv::{EvalOptions, Rates, Surface, TessOptions};
    let meshes = subdiv_testkit::textured_meshes();
    if subdiv_testkit::meshes_dir().is_none() {
        return;
    }
    let mut points = 0;
    for (path, builtin, mesh) in &meshes {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let mut surface = Surface::new(mesh.clone(), builtin.scheme());
        let out = surface
            .tessellate(&TessOptions { rates: Rates::Uniform(2), ..TessOptions::DEFAULT })
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .into_mesh();
        let uv = surface.channel_evaluator(Channel::UV, &EvalOptions::DEFAULT).unwrap();
        let coords = out.channels.find(Channel::UV).unwrap_or_else(|| panic!("{name}: no texture coordinates"));
        let parameters = point_parameters(&out);
        assert_eq!(out.channels.values.len(), out.channels.stride() * parameters.len(), "{name}");
        for (k, p) in parameters.iter().enumerate().step_by(7) {
            let expected = uv.evaluate(p.face, p.u, p.v).unwrap().position;
            let got = &out.channels.point(k)[coords.clone()];
            let error = (got[0] - expected.x).abs().max((got[1] - expected.y).abs());
            assert!(error <= 1e-12, "{name}: point {k} at {p:?}: {got:?} against {expected}");
            points += 1;
        }
    }
    eprintln!("{} meshes, {points} points compared", meshes.len());
    assert!(meshes.len() >= 100, "{} textured meshes", meshes.len());
}

/// In every face-varying mode, the tessellation's texture coordinates (the surface made
/// `with_refine_options` of that mode) are the channel's evaluator's in that mode at every point,
/// to 1e-12, on spot and `catmark_fvar_bound1` at rate 3; the modes give different values.
#[test]
fn tessellated_texture_coordinates_follow_the_face_varying_mode() {
    use subdiv::{EvalOptions, Rates, Surface, TessOptions};
    if subdiv_testkit::meshes_dir().is_none() {
        return;
    }
    let mut compared = 0;
    for (path, builtin, mesh) in subdiv_testkit::textured_meshes() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if name != "spot_control_mesh.obj" && name != "catmark_fvar_bound1.obj" {
            continue;
        }
        let mut seen: Vec<Vec<f64>> = Vec::new();
        for mode in FaceVaryingInterpolation::ALL_MODES {
            let refine = RefineOptions::DEFAULT.with_face_varying(mode);
            let mut surface = Surface::new(mesh.clone(), builtin.scheme()).with_refine_options(refine);
            let out = surface.tessellate(&TessOptions { rates: Rates::Uniform(3), ..TessOptions::DEFAULT }).unwrap();
            let out = out.into_mesh();
            let uv = surface.channel_evaluator(Channel::UV, &EvalOptions { refine, ..EvalOptions::DEFAULT }).unwrap();
            for (k, p) in point_parameters(&out).iter().enumerate() {
                let expected = uv.evaluate(p.face, p.u, p.v).unwrap().position;
                let got = out.channels.point(k);
                let error = (got[0] - expected.x).abs().max((got[1] - expected.y).abs());
                assert!(error <= 1e-12, "{name} in mode {}: point {k}: {got:?} against {expected}", mode.name());
            }
            seen.push(out.channels.values.clone());
            compared += 1;
        }
        assert!(seen.windows(2).any(|w| w[0] != w[1]), "{name}: every mode gave the same values");
    }
    assert_eq!(compared, 12);
}
