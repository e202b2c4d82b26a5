//! Tessellation through the facade: [`TessOptions`] (rate policy, method, limits) and the
//! [`Tessellation`] they give, with its files.

use std::io::Write;
use std::path::Path;

use subdiv_io::write_atomic;
use subdiv_mesh::Mesh;
use subdiv_schemes::Scheme;
use subdiv_tess::rates::{Camera, DEFAULT_MAX_RATE, RingDepths};
use subdiv_tess::{FlatMesh, MAX_DUAL_RATE, Parallelism, QuadtreeStats, TessMesh, Tolerance};

use crate::Error;

/// How finely each face is cut (the dual method), or how flat the output must be (both
/// methods; the only policy [`Method::Quadtree`] takes).
#[derive(Clone, Debug, PartialEq)]
pub enum Rates {
    /// Every face at this rate: `n × n` samples per quad, `1..=1024`.
    Uniform(u32),
    /// One rate per face, in face order.
    PerFace(Vec<u32>),
    /// The rates (dual) or leaves (quadtree) that prove every limit point within the
    /// tolerance of the output. Catmull-Clark meshes (creases included; the dual method not
    /// yet at extraordinary border vertices).
    Tolerance(Tolerance),
    /// The quadtree's leaves that prove every limit point within `pixels` pixels, on the
    /// screen of a `viewport` seen by `camera`, of the output (each piece to its own
    /// [`ScreenError`](subdiv_tess::rates::ScreenError) bound): a renderer's "at most P pixels
    /// of geometric error". [`Method::Quadtree`] only.
    ScreenError {
        /// The camera.
        camera: Camera,
        /// The image size in pixels, `[width, height]`.
        viewport: [u32; 2],
        /// The largest error on the screen, in pixels (> 0).
        pixels: f64,
    },
    /// Screen-space rates (paper 000 §6): each face cut so that its output edges are about
    /// `pixels_per_edge` pixels long in a `viewport` seen by `camera`.
    Screen {
        /// The camera.
        camera: Camera,
        /// The image size in pixels, `[width, height]`.
        viewport: [u32; 2],
        /// The wanted length of an output edge, in pixels (> 0).
        pixels_per_edge: f64,
    },
}

impl Rates {
    /// The policy's name, for messages.
    pub(crate) fn name(&self) -> &'static str {
        match self {
            Self::Uniform(_) => "uniform",
            Self::PerFace(_) => "per-face",
            Self::Tolerance(_) => "tolerance",
            Self::Screen { .. } => "screen-space",
            Self::ScreenError { .. } => "screen-error",
        }
    }
}

/// Which tessellator cuts the surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// Dual-grid stitching at per-face rates (Schaefer-Warren, paper 000 §5.5): any primal
    /// scheme with sub-patch matrices, open meshes and holes; every [`Rates`] policy but
    /// [`Rates::ScreenError`]. The default.
    #[default]
    Dual,
    /// The error-driven quadtree with global vertex ids and polyline replacement (Lai-Cheng,
    /// paper 002): Catmull-Clark, Loop and `sw-quad` meshes, open ones and holes too, texture
    /// coordinates carried;
    /// [`Rates::Tolerance`] and [`Rates::ScreenError`] only.
    Quadtree,
}

/// Options of [`Surface::tessellate`](crate::Surface::tessellate).
///
/// ```
/// use subdiv::{Method, Parallelism, Rates, TessOptions, Tolerance};
///
/// let options = TessOptions::DEFAULT
///     .with_rates(Rates::Tolerance(Tolerance::Relative(1e-3)))
///     .with_max_rate(32)
///     .with_parallelism(Parallelism::Serial);
/// assert_eq!(options.method, Method::Dual);
/// assert_eq!(TessOptions::default(), TessOptions::DEFAULT);
/// assert_eq!(TessOptions::DEFAULT.rates, Rates::Uniform(8));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct TessOptions {
    /// The rate policy. Default: [`Rates::Uniform`]`(8)` (what `subdiv tessellate` does
    /// without one).
    pub rates: Rates,
    /// The tessellator. Default: [`Method::Dual`].
    pub method: Method,
    /// The largest rate [`Rates::Tolerance`] and [`Rates::Screen`] may give a face (dual; a
    /// face that needs more to meet a tolerance is an error). Default:
    /// [`DEFAULT_MAX_RATE`] (1024, the largest the dual tessellator takes: the vertex budget
    /// below is the guard that matters).
    pub max_rate: u32,
    /// Also list the output's polygons in [`TessMesh`]'s polygon lists: the dual
    /// tessellation's quads (face grids, equal-rate strips, valence-4 vertices), or the
    /// quadtree's leaves with their hanging vertices. Triangles are always output. Default:
    /// `false`.
    pub polygons: bool,
    /// Whether the work may use rayon's threads (the output is the same, bit for bit, either
    /// way). Default: [`Parallelism::Rayon`].
    pub parallelism: Parallelism,
    /// The most output vertices a tessellation may make: the dual method's count is predicted
    /// from the rates before anything is allocated ([`Error::Budget`]); the quadtree, whose
    /// count shows only as it refines and which holds twice the memory per vertex, stops at a
    /// quarter this many polygons (a leaf brings about two vertices with the hanging ones:
    /// [`TessError::TooManyPolygons`](subdiv_tess::TessError::TooManyPolygons)). Default:
    /// [`DEFAULT_MAX_TESS_VERTICES`].
    pub max_vertices: usize,
}

/// [`TessOptions::max_vertices`]' default: 2^24 ≈ 16.8 million vertices, about 34 million
/// triangles (a 2000 × 2000 quad grid at rate 2): 0.8 GB of flat f32 output (48 bytes per
/// vertex with its two triangles), which a GLB file takes streamed
/// ([`Surface::write_glb_stream`](crate::Surface::write_glb_stream): 1.4 GB peak for that grid)
/// and a whole [`TessMesh`] in f64 holds at about 200 bytes per vertex (3–4 GB), so that a
/// request of a size nobody means (a rate of 256 on a large mesh, a tolerance of 1e-6 for the
/// quadtree) is refused instead of exhausting memory. Raise it for larger outputs.
pub const DEFAULT_MAX_TESS_VERTICES: usize = 1 << 24;

impl TessOptions {
    /// The defaults: every face at rate 8 by the dual method, triangles only, on rayon's
    /// threads.
    pub const DEFAULT: Self = Self {
        rates: Rates::Uniform(8),
        method: Method::Dual,
        max_rate: DEFAULT_MAX_RATE,
        polygons: false,
        parallelism: Parallelism::DEFAULT,
        max_vertices: DEFAULT_MAX_TESS_VERTICES,
    };

    /// These options with [`rates`](Self::rates).
    #[must_use]
    pub fn with_rates(self, rates: Rates) -> Self {
        Self { rates, ..self }
    }

    /// These options with [`method`](Self::method).
    #[must_use]
    pub fn with_method(self, method: Method) -> Self {
        Self { method, ..self }
    }

    /// These options with [`max_rate`](Self::max_rate).
    #[must_use]
    pub fn with_max_rate(self, max_rate: u32) -> Self {
        Self { max_rate, ..self }
    }

    /// These options with [`polygons`](Self::polygons).
    #[must_use]
    pub fn with_polygons(self, polygons: bool) -> Self {
        Self { polygons, ..self }
    }

    /// These options with [`parallelism`](Self::parallelism).
    #[must_use]
    pub fn with_parallelism(self, parallelism: Parallelism) -> Self {
        Self { parallelism, ..self }
    }

    /// These options with [`max_vertices`](Self::max_vertices).
    #[must_use]
    pub fn with_max_vertices(self, max_vertices: usize) -> Self {
        Self { max_vertices, ..self }
    }
}

impl Default for TessOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What a rate policy gives the dual tessellator ([`Surface::face_rates`](crate::Surface::face_rates)).
#[derive(Clone, Debug, PartialEq)]
pub struct FaceRates {
    /// The rate of each face.
    pub faces: Vec<u32>,
    /// For [`Rates::Tolerance`]: the rings of exact points around extraordinary points that
    /// the bound needs.
    pub rings: Option<RingDepths>,
    /// For [`Rates::Tolerance`]: the absolute tolerance `ε`.
    pub epsilon: Option<f64>,
}

/// How a tessellation was made: what [`Surface::tessellate_into`](crate::Surface::tessellate_into)
/// returns beside the output.
#[derive(Clone, Debug, PartialEq)]
pub struct TessInfo {
    /// The tessellator.
    pub method: Method,
    /// The rate of each face (dual; empty for the quadtree).
    pub rates: Vec<u32>,
    /// The absolute tolerance `ε`, for [`Rates::Tolerance`].
    pub epsilon: Option<f64>,
    /// The quadtree's statistics (quadtree only).
    pub quadtree: Option<QuadtreeStats>,
}

/// A tessellation of the limit surface and how it was made
/// ([`Surface::tessellate`](crate::Surface::tessellate)), with its files.
#[derive(Clone, Debug, PartialEq)]
pub struct Tessellation {
    /// The output: exact limit points with unit normals and their faces' `Bfr` parameters,
    /// triangles, and polygons if [`TessOptions::polygons`].
    pub mesh: TessMesh,
    /// How it was made.
    pub info: TessInfo,
}

impl Tessellation {
    /// The output, keeping nothing else.
    pub fn into_mesh(self) -> TessMesh {
        self.mesh
    }

    /// Writes the triangles as GLB (f32 positions and normals, `TEXCOORD_0` when the mesh has
    /// texture coordinates, `u32` indices), atomically: the flat vertices
    /// ([`FlatMesh`](subdiv_tess::FlatMesh)'s), so a vertex with two normals on an infinitely
    /// sharp crease, or two sides' coordinates on a seam, is split into one GLB vertex each.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file; [`IoError::Unwritable`](subdiv_io::IoError::Unwritable)
    /// (in [`Error::Io`]) for a coordinate f32 cannot hold without flushing it to 0
    /// ([`subdiv_io::MIN_GLB_EXTENT`]): scale such a mesh first.
    pub fn write_glb(&self, path: impl AsRef<Path>) -> Result<(), Error> {
        // Before the f32 conversion below, which would turn a 1e-50 coordinate into 0.
        subdiv_io::check_glb_positions(self.mesh.positions.iter().copied())?;
        let mut flat = FlatMesh::default();
        self.mesh.write_to(&mut flat);
        write_flat_glb(path, &flat)
    }

    /// Writes OBJ (`v`, `vn` and `f v//vn` lines; with texture coordinates `vt` and
    /// `f v/vt/vn`), atomically: one `v` per (welded) vertex, one `vn` (and `vt`) per normal (a
    /// crease or seam vertex's extra normals after the vertices', see [`TessMesh`]), each
    /// corner's own; the triangles, or with
    /// `polygons` the polygons where there are any — the quadtree's leaves alone (they cover
    /// the surface), the dual tessellation's quads and the triangles outside them.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn write_obj(&self, path: impl AsRef<Path>, polygons: bool) -> Result<(), Error> {
        write_atomic(path, |w| self.write_obj_to(w, polygons))?;
        Ok(())
    }

    /// [`write_obj`](Self::write_obj) into any writer.
    ///
    /// # Errors
    /// The writer's.
    pub fn write_obj_to(&self, w: &mut dyn Write, polygons: bool) -> std::io::Result<()> {
        let faces = match (polygons && self.mesh.polygon_count() > 0, self.info.method) {
            (false, _) => ObjFaces::Triangles,
            (true, Method::Quadtree) => ObjFaces::Polygons,
            (true, Method::Dual) => ObjFaces::PolygonsAndTriangles,
        };
        write_obj(w, &self.mesh, faces)
    }

    /// Writes `vertex,face,u,v` per flat vertex, in output order (`Bfr` parameters, shortest
    /// round-trip f64s), as CSV, atomically: the vertices, then the split copies of crease and
    /// seam vertices (the GLB's vertices, whose numbers these are), each at the point it was
    /// evaluated at. With texture coordinates, the columns `s,t` follow.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn write_params(&self, path: impl AsRef<Path>) -> Result<(), Error> {
        let mesh = &self.mesh;
        let uv = mesh.channels.texcoords();
        write_atomic(path, |w| {
            writeln!(w, "vertex,face,u,v{}", if uv.is_some() { ",s,t" } else { "" })?;
            for (k, p) in mesh.parameters.iter().chain(&mesh.normal_parameters).enumerate() {
                write!(w, "{k},{},{:?},{:?}", p.face.index(), p.u, p.v)?;
                if let Some(start) = uv {
                    let c = mesh.channels.point(k);
                    write!(w, ",{:?},{:?}", c[start], c[start + 1])?;
                }
                writeln!(w)?;
            }
            Ok(())
        })?;
        Ok(())
    }
}

/// Refuses per-face `rates` (with `rings`, if any) for the dual tessellator of `mesh` under
/// `scheme` if they would make more than `max_vertices` output vertices: the count is
/// predicted from the topology, before anything is allocated. What
/// [`Surface::face_rates`](crate::Surface::face_rates) checks against
/// [`TessOptions::max_vertices`]; for callers that drive a
/// [`DualTessellator`](subdiv_tess::DualTessellator) themselves. Rates the tessellator refuses
/// anyway (a wrong count, a rate outside `1..=1024`) are left to its own error.
///
/// ```
/// use subdiv::mesh::{shapes, Mesh};
/// use subdiv::schemes::Builtin;
/// use subdiv::Error;
///
/// let cube = Mesh::build(shapes::cube())?;
/// let cc = Builtin::CatmullClark.scheme();
/// assert!(subdiv::check_vertex_budget(&cube, cc, &[8; 6], None, 1000).is_ok());
/// assert!(matches!(subdiv::check_vertex_budget(&cube, cc, &[128; 6], None, 1000), Err(Error::Budget { .. })));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`Error::Budget`] naming the count and the limit.
pub fn check_vertex_budget(
    mesh: &Mesh,
    scheme: &Scheme,
    rates: &[u32],
    rings: Option<&RingDepths>,
    max_vertices: usize,
) -> Result<(), Error> {
    if rates.len() != mesh.face_count() || !rates.iter().all(|r| (1..=MAX_DUAL_RATE).contains(r)) {
        return Ok(());
    }
    let vertices = match rings {
        Some(rings) => subdiv_tess::dual::predicted_vertex_count_with_rings(mesh, scheme.split(), rates, rings),
        None => subdiv_tess::dual::predicted_vertex_count(mesh, scheme.split(), rates),
    };
    Error::check_budget(
        vertices as u64,
        max_vertices as u64,
        "tessellating would make",
        "vertices",
        "lower the rates or raise the limit (TessOptions::max_vertices, `--max-vertices`)",
    )
}

/// Writes a flat tessellation ([`FlatMesh`], e.g. from
/// [`Surface::tessellate_flat`](crate::Surface::tessellate_flat)) as GLB, atomically, streamed
/// from its buffers: the lean way to a file, without the f64 [`TessMesh`].
///
/// Its positions are f32 already, so a coordinate that the conversion flushed to 0 can no
/// longer be told from a 0: check the cage first with
/// [`subdiv_io::check_glb_positions`] (the limit surface lies at the cage's scale).
///
/// ```
/// use subdiv::mesh::shapes;
/// use subdiv::schemes::Builtin;
/// use subdiv::{FlatMesh, Surface, TessOptions};
///
/// let mut surface = Surface::build(shapes::cube(), Builtin::CatmullClark.scheme())?;
/// subdiv::io::check_glb_positions(surface.mesh().positions().iter().copied())?;
/// let mut flat = FlatMesh::default();
/// surface.tessellate_flat(&TessOptions::DEFAULT, &mut flat)?;
/// let dir = tempfile::tempdir().unwrap();
/// subdiv::write_flat_glb(dir.path().join("cube.glb"), &flat)?;
/// # Ok::<(), subdiv::Error>(())
/// ```
///
/// # Errors
/// [`Error::Io`] naming the file, as [`subdiv_io::write_glb`].
pub fn write_flat_glb(path: impl AsRef<Path>, flat: &FlatMesh) -> Result<(), Error> {
    let (vertices, rest) = flat.vertices.as_chunks::<6>();
    debug_assert!(rest.is_empty(), "six floats per flat vertex");
    let texcoords: Option<Vec<glam::Vec2>> =
        (!flat.texcoords.is_empty()).then(|| flat.texcoords.chunks_exact(2).map(glam::Vec2::from_slice).collect());
    subdiv_io::write_glb_interleaved(path, vertices, texcoords.as_deref(), &flat.indices)?;
    Ok(())
}

/// Which faces an OBJ output lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ObjFaces {
    Triangles,
    /// The polygons alone: they cover the surface (the quadtree's leaves; its triangles' fan
    /// centres stay unused).
    Polygons,
    /// The polygons and the triangles outside them (the dual tessellation's quads, and its
    /// strip and vertex triangles).
    PolygonsAndTriangles,
}

/// OBJ with `v` and `vn` lines, and faces as `f v//vn` (each corner's normal).
fn write_obj(w: &mut dyn Write, mesh: &TessMesh, faces: ObjFaces) -> std::io::Result<()> {
    writeln!(w, "# subdiv tessellate")?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    // Texture coordinates per point, as the normals: a seam's second side is an extra normal.
    let uv = mesh.channels.texcoords();
    if let Some(start) = uv {
        for k in 0..mesh.normals.len() {
            let p = mesh.channels.point(k);
            writeln!(w, "vt {} {}", p[start], p[start + 1])?;
        }
    }
    let face = |w: &mut dyn Write, vertices: &[u32], normals: &[u32]| -> std::io::Result<()> {
        write!(w, "f")?;
        for (&v, &n) in vertices.iter().zip(normals) {
            match uv {
                Some(_) => write!(w, " {}/{}/{}", v + 1, n + 1, n + 1)?,
                None => write!(w, " {}//{}", v + 1, n + 1)?,
            }
        }
        writeln!(w)
    };
    if faces == ObjFaces::Triangles {
        for (t, n) in mesh.triangles.iter().zip(&mesh.triangle_normals) {
            face(w, t, n)?;
        }
        return Ok(());
    }
    // A polygon's corners take the normals of the triangles it is made of (a dual quad
    // `a b c d` is the triangles `a b c` and `a c d`; the quadtree's leaves have
    // their vertices' own: it does not split normals at creases).
    let mut triangles = std::collections::HashMap::new();
    for (t, n) in mesh.triangles.iter().zip(&mesh.triangle_normals) {
        triangles.insert(sorted(*t), (*t, *n));
    }
    let mut covered = std::collections::HashSet::new();
    let mut normals = Vec::new();
    for k in 0..mesh.polygon_count() {
        let p = mesh.polygon(k);
        normals.clear();
        normals.extend_from_slice(p);
        for i in 1..p.len().saturating_sub(1) {
            let key = sorted([p[0], p[i], p[i + 1]]);
            covered.insert(key);
            if let Some((t, n)) = triangles.get(&key) {
                for c in [0, i, i + 1] {
                    if let Some(j) = t.iter().position(|&v| v == p[c]) {
                        normals[c] = n[j];
                    }
                }
            }
        }
        face(w, p, &normals)?;
    }
    if faces == ObjFaces::PolygonsAndTriangles {
        for (t, n) in mesh.triangles.iter().zip(&mesh.triangle_normals).filter(|(t, _)| !covered.contains(&sorted(**t)))
        {
            face(w, t, n)?;
        }
    }
    Ok(())
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}
