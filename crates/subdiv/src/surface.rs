//! [`Surface`]: a control mesh under a scheme, and everything one does with its limit surface.

use std::path::Path;
use std::sync::OnceLock;

use subdiv_mesh::{BuildOptions, FaceId, Mesh, PolygonSoup};
use subdiv_schemes::{ChannelSurface, RefineOptions, Scheme, Split, refine_uniform_with_progress};
use subdiv_stencil::{LimitPoint, LinearEvaluator};
use subdiv_tess::{DualTessellator, QuadtreeTessellator};

use crate::Error;
use crate::evaluate::{EvalGrid, EvalOptions, Evaluator};

mod tessellation;

/// The limit surface of a control mesh under a subdivision scheme: refine it, evaluate it
/// exactly with derivatives, tessellate it watertight at per-face rates or to a proven
/// tolerance, and write the result as GLB or OBJ.
///
/// The work each operation needs is prepared on first use and kept: the evaluator's patches,
/// the dual-grid tessellator (its templates and stencils, as `DualTessellator` keeps them
/// across rates) and the quadtree's pieces (which the tolerance policy's bounds also use).
///
/// ```
/// use subdiv::mesh::shapes;
/// use subdiv::schemes::Builtin;
/// use subdiv::{FaceId, Rates, Surface, TessOptions, Tolerance};
///
/// let mut surface = Surface::build(shapes::cube(), Builtin::CatmullClark.scheme())?;
/// // The exact limit point at the centre of face 0, with its derivatives.
/// let point = surface.evaluate(FaceId::new(0), 0.5, 0.5)?;
/// assert!(point.du.cross(point.dv).length() > 0.0);
/// // Every face at rate 4, then to 1% of the bounding box's diagonal.
/// let coarse = surface.tessellate(&TessOptions::DEFAULT.with_rates(Rates::Uniform(4)))?;
/// let fine = surface.tessellate(&TessOptions::DEFAULT.with_rates(Rates::Tolerance(Tolerance::Relative(1e-2))))?;
/// assert!(fine.mesh.triangles.len() > coarse.mesh.triangles.len());
/// fine.write_glb(std::env::temp_dir().join("subdiv-surface-doc.glb"))?;
/// # Ok::<(), subdiv::Error>(())
/// ```
#[derive(Debug)]
pub struct Surface {
    mesh: Mesh,
    scheme: Scheme,
    /// The evaluator with the default options, made on the first [`Surface::evaluate`].
    evaluator: OnceLock<Evaluator>,
    /// The dual tessellator (its options set per call).
    dual: Option<DualTessellator>,
    /// The quadtree tessellator (also the tolerance policy's bounds).
    quadtree: Option<QuadtreeTessellator>,
    /// The most faces [`Surface::refine`] makes.
    max_refined_faces: u64,
    /// The options of [`Surface::refine`].
    refine_options: RefineOptions,
}

/// The most faces [`Surface::refine`] makes unless raised with
/// [`Surface::with_max_refined_faces`]: 2²², about 4 million faces, a refined mesh of about
/// 1 GB in memory (a face, its half-edges, vertices and the refiner's tables take about 250
/// bytes), and an OBJ of about 300 MB.
pub const DEFAULT_MAX_REFINED_FACES: u64 = 1 << 22;

impl Surface {
    /// The surface of `mesh` under `scheme` (prepared lazily: nothing fails here).
    pub fn new(mesh: Mesh, scheme: &Scheme) -> Self {
        Self {
            mesh,
            scheme: scheme.clone(),
            evaluator: OnceLock::new(),
            dual: None,
            quadtree: None,
            max_refined_faces: DEFAULT_MAX_REFINED_FACES,
            refine_options: RefineOptions::DEFAULT,
        }
    }

    /// The same surface, with [`refine`](Self::refine) taking `options` (the boundary rule,
    /// crease method, face-varying interpolation, …) instead of [`RefineOptions::DEFAULT`],
    /// which takes everything from the mesh's tags; the dual tessellations carry the channels
    /// in `options`' face-varying mode.
    ///
    /// ```
    /// use subdiv::mesh::{Channel, FaceVaryingInterpolation, shapes};
    /// use subdiv::schemes::{Builtin, RefineOptions};
    /// use subdiv::Surface;
    ///
    /// // A quad with texture coordinates at its corners: linear (the default) keeps the centre's
    /// // coordinate at the average, smooth ("none") follows the boundary curve.
    /// let mut soup = shapes::quad_grid(1, 1);
    /// soup.channels.push(Channel::new("uv", 2, vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0], vec![0, 1, 2, 3]));
    /// let surface = Surface::build(soup, Builtin::CatmullClark.scheme())?;
    /// let linear = surface.refine(1)?;
    /// let smooth = RefineOptions::DEFAULT.with_face_varying(FaceVaryingInterpolation::None);
    /// let smooth = surface.with_refine_options(smooth).refine(1)?;
    /// assert_eq!(linear.channels()[0].value_count(), 9);
    /// assert_ne!(linear.channels()[0].values(), smooth.channels()[0].values());
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    #[must_use]
    pub fn with_refine_options(mut self, options: RefineOptions) -> Self {
        self.refine_options = options;
        // The dual tessellator carries the channels in the face-varying mode it was made with.
        self.dual = None;
        self
    }

    /// The same surface, letting [`refine`](Self::refine) make up to `faces` faces (by the
    /// lower bound [`refined_faces_at_least`](Self::refined_faces_at_least)) instead of
    /// [`DEFAULT_MAX_REFINED_FACES`].
    ///
    /// ```
    /// use subdiv::mesh::shapes;
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{Error, Surface};
    ///
    /// // A cube's 6 faces make 24 · 4^(levels − 1) faces.
    /// let surface = Surface::build(shapes::cube(), Builtin::CatmullClark.scheme())?.with_max_refined_faces(100);
    /// assert_eq!(surface.refine(2)?.face_count(), 96);
    /// assert!(matches!(surface.refine(3), Err(Error::Budget { requested: 384, limit: 100, .. })));
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    #[must_use]
    pub fn with_max_refined_faces(mut self, faces: u64) -> Self {
        self.max_refined_faces = faces;
        self
    }

    /// The surface of a polygon soup, built into a mesh first.
    ///
    /// # Errors
    /// [`Error::Mesh`] for the first topology rule the soup breaks.
    pub fn build(soup: PolygonSoup, scheme: &Scheme) -> Result<Self, Error> {
        Ok(Self::new(Mesh::build(soup)?, scheme))
    }

    /// The surface of the mesh file at `path` (`.obj` with OpenSubdiv's tags, `.gltf`,
    /// `.glb`).
    ///
    /// # Errors
    /// [`Error::Io`]: an unreadable file, or one that is no valid mesh (with the OBJ line of the
    /// face, vertex or tag at fault).
    pub fn load(path: impl AsRef<Path>, scheme: &Scheme) -> Result<Self, Error> {
        Ok(Self::new(subdiv_io::load_mesh(path, &BuildOptions::default())?, scheme))
    }

    /// The control mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The scheme.
    pub fn scheme(&self) -> &Scheme {
        &self.scheme
    }

    /// The control mesh refined `levels` times (OpenSubdiv's rules for Catmull-Clark and Loop;
    /// the mesh's boundary, crease, corner and hole tags). Each level multiplies the face
    /// count by about 4.
    ///
    /// # Errors
    /// [`Error::Scheme`] for a mesh the scheme does not take; [`Error::Budget`] for more faces
    /// than [`with_max_refined_faces`](Self::with_max_refined_faces) allows
    /// ([`DEFAULT_MAX_REFINED_FACES`]); [`Error::RefineLevels`] for more faces than 32-bit ids
    /// hold.
    pub fn refine(&self, levels: usize) -> Result<Mesh, Error> {
        self.refine_with_progress(levels, |_| {})
    }

    /// A lower bound of the faces `levels` levels of refinement make under this surface's
    /// scheme, which [`refine`](Self::refine) checks against 32-bit ids: the primal splits'
    /// exact counts (a quad split's first level makes one quad per half-edge, every later one
    /// four per face; a triangle split four per triangle), and for the dual, mid-edge and √3
    /// splits the faces alone (each face keeps at least one child face; more holds only away
    /// from borders, so the bound does not count it).
    pub fn refined_faces_at_least(&self, levels: usize) -> u64 {
        if levels == 0 {
            return self.mesh.face_count() as u64;
        }
        let f = self.mesh.face_count() as u64;
        let (first, growth) = match self.scheme.split() {
            Split::Quad => (self.mesh.half_edge_count() as u64, 4u64),
            Split::Triangle => (4 * f, 4),
            Split::Dual | Split::Midedge | Split::Sqrt3 => (f, 1),
        };
        (1..levels).fold(first, |n, _| n.saturating_mul(growth))
    }

    /// [`refine`](Self::refine), calling `progress(level)` after each level (1 to `levels`).
    ///
    /// # Errors
    /// As [`refine`](Self::refine).
    pub fn refine_with_progress(&self, levels: usize, progress: impl FnMut(usize)) -> Result<Mesh, Error> {
        let faces = self.refined_faces_at_least(levels);
        Error::check_budget(
            faces,
            self.max_refined_faces,
            "refining would make at least",
            "faces",
            "refine fewer levels, or raise the limit (Surface::with_max_refined_faces, `subdiv refine --max-faces`)",
        )?;
        if faces > u64::from(u32::MAX) {
            return Err(Error::RefineLevels { levels, faces });
        }
        Ok(refine_uniform_with_progress(&self.mesh, &self.scheme, levels, &self.refine_options, progress)?)
    }

    /// The limit point of `face` at its `Bfr` parameters `(u, v)`, with first derivatives: by
    /// eigenbasis on interior patches of Catmull-Clark, Loop and bilinear, by exact stencils
    /// elsewhere ([`EvalOptions::DEFAULT`]; [`evaluator`](Self::evaluator) takes others).
    ///
    /// # Errors
    /// As [`Surface::evaluator`] (the first call prepares it) and [`Evaluator::evaluate`].
    pub fn evaluate(&self, face: FaceId, u: f64, v: f64) -> Result<LimitPoint, Error> {
        self.default_evaluator()?.evaluate(face, u, v)
    }

    /// Every face at the grid of `osd_limit --grid n`, as [`Evaluator::grid`], with
    /// [`EvalOptions::DEFAULT`].
    ///
    /// # Errors
    /// As [`Evaluator::grid`].
    pub fn evaluate_grid(&self, n: u32) -> Result<EvalGrid, Error> {
        self.default_evaluator()?.grid(n)
    }

    /// An evaluator of the limit surface with `options`.
    ///
    /// # Errors
    /// [`Error::Eval`]: schemes without sub-patch matrices (√3, Doo-Sabin, mid-edge), creases and
    /// corners, faces the scheme does not take.
    pub fn evaluator(&self, options: &EvalOptions) -> Result<Evaluator, Error> {
        Evaluator::new(&self.scheme, &self.mesh, options)
    }

    /// An evaluator of the face-varying channel `channel` (one of the mesh's, by name: `"uv"`
    /// for texture coordinates) as the surface its values lie on: at a face's `(u, v)` its
    /// [`LimitPoint::position`](subdiv_stencil::LimitPoint) holds the channel's value (padded
    /// to three components) and `du`, `dv` the value's derivatives. `options.refine` gives the
    /// face-varying interpolation mode; [`EvalMethod::Eigen`](crate::EvalMethod) becomes
    /// [`EvalMethod::Auto`](crate::EvalMethod) (a channel's seams are boundaries).
    ///
    /// ```
    /// use subdiv::mesh::{Channel, FaceId, shapes};
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{EvalOptions, Surface};
    ///
    /// // Texture coordinates equal to each vertex's x and y, on a grid: under the default (linear
    /// // everywhere) the coordinate at a face's centre is the average of its corners'.
    /// let mut soup = shapes::quad_grid(3, 3);
    /// let xy: Vec<f64> = soup.positions().iter().flat_map(|p| [p.x, p.y]).collect();
    /// let corners = soup.raw_faces().1.iter().map(|v| v.raw()).collect();
    /// soup.channels.push(Channel::new("uv", 2, xy, corners));
    /// let surface = Surface::build(soup, Builtin::CatmullClark.scheme())?;
    /// let uv = surface.channel_evaluator("uv", &EvalOptions::DEFAULT)?;
    /// let centre = uv.evaluate(FaceId::new(4), 0.5, 0.5)?;
    /// assert!((centre.position.x - 1.5).abs() < 1e-12 && (centre.position.y - 1.5).abs() < 1e-12);
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::NoChannel`] when the mesh has no channel of that name; [`Error::Scheme`] for a
    /// scheme without face-varying rules or a channel of more than three components; as
    /// [`evaluator`](Self::evaluator) otherwise.
    pub fn channel_evaluator(&self, channel: &str, options: &EvalOptions) -> Result<Evaluator, Error> {
        let found = self.mesh.channel(channel).ok_or_else(|| Error::NoChannel {
            channel: channel.to_owned(),
            channels: self.mesh.channels().iter().map(|c| c.name().to_owned()).collect(),
        })?;
        let surface = ChannelSurface::new(&self.mesh, found, &self.scheme, &options.refine)?;
        if let Some(linear) = LinearEvaluator::new(&surface)? {
            return Ok(Evaluator::linear(linear, options));
        }
        let method = match options.method {
            crate::EvalMethod::Eigen => crate::EvalMethod::Auto,
            method => method,
        };
        let options = EvalOptions { method, refine: RefineOptions::DEFAULT, ..*options };
        Evaluator::new(surface.scheme(), surface.mesh(), &options)
    }

    fn default_evaluator(&self) -> Result<&Evaluator, Error> {
        if let Some(evaluator) = self.evaluator.get() {
            return Ok(evaluator);
        }
        let made = self.evaluator(&EvalOptions::DEFAULT)?;
        Ok(self.evaluator.get_or_init(|| made))
    }
}

/// `mesh` as a soup with its hole faces left out (their vertices stay, so the numbering does
/// not change), as OpenSubdiv's refinement output lists it: what `subdiv refine` writes.
pub fn without_holes(mesh: &Mesh) -> PolygonSoup {
    let mut soup = PolygonSoup::with_capacity(mesh.vertex_count(), mesh.face_count(), mesh.half_edge_count());
    for &p in mesh.positions() {
        soup.push_vertex(p);
    }
    for f in mesh.face_ids().filter(|&f| !mesh.is_hole(f)) {
        soup.push_face(mesh.face_vertices(f).iter().copied());
    }
    soup
}

#[cfg(test)]
mod tests {
    use subdiv_eval::EigenEvaluator;
    use subdiv_mesh::DVec3;
    use subdiv_mesh::shapes;
    use subdiv_schemes::Builtin;
    use subdiv_tess::rates::{Camera, ErrorRates, ScreenSpace};
    use subdiv_tess::{DualOptions, FlatMesh, Parallelism, QuadtreeOptions, TessError, Tolerance};

    use super::*;
    use crate::EvalMethod;
    use crate::tessellate::{Method, Rates, TessOptions};

    fn surface(soup: PolygonSoup) -> Surface {
        Surface::build(soup, Builtin::CatmullClark.scheme()).unwrap()
    }

    /// Each policy gives what the tessellators give when driven by hand, as the CLI drove
    /// them before the facade.
    #[test]
    fn tessellations_equal_the_tessellators_own() {
        let cc = Builtin::CatmullClark.scheme();
        for soup in [shapes::cube(), shapes::ngon_prism(5), shapes::default_model(), shapes::quad_grid(3, 2)] {
            let mesh = Mesh::build(soup.clone()).unwrap();
            let mut s = surface(soup);
            let faces = mesh.face_count();
            let camera = Camera::look_at(DVec3::new(0.0, -5.0, 2.0), DVec3::ZERO, DVec3::Z);
            let closed = mesh.boundary_edge_count() == 0;
            let mut policies = vec![
                Rates::Uniform(3),
                Rates::PerFace((0..faces as u32).map(|f| 1 + f % 4).collect()),
                Rates::Screen { camera, viewport: [640, 480], pixels_per_edge: 12.0 },
            ];
            if closed {
                policies.push(Rates::Tolerance(Tolerance::Relative(3e-2)));
            }
            for polygons in [false, true] {
                let dual = DualOptions::DEFAULT.with_quads(polygons);
                let mut tess = DualTessellator::new(cc, &mesh, &dual).unwrap();
                for rates in &policies {
                    let options =
                        TessOptions::DEFAULT.with_rates(rates.clone()).with_max_rate(32).with_polygons(polygons);
                    let expected = match rates {
                        Rates::Uniform(n) => tess.tessellate(&vec![*n; faces]).unwrap().clone(),
                        Rates::PerFace(r) => tess.tessellate(r).unwrap().clone(),
                        Rates::Screen { camera, viewport, pixels_per_edge } => {
                            let policy =
                                ScreenSpace { max_rate: 32, ..ScreenSpace::new(*camera, *viewport, *pixels_per_edge) };
                            tess.tessellate(&policy.face_rates(&mesh).unwrap()).unwrap().clone()
                        }
                        Rates::Tolerance(t) => {
                            let bounds = QuadtreeTessellator::new(cc, &mesh).unwrap();
                            let r = ErrorRates { max_rate: 32, ..ErrorRates::new(*t) }.rates(&bounds, &mesh).unwrap();
                            tess.tessellate_with_rings(&r.faces, &r.rings).unwrap().clone()
                        }
                        Rates::ScreenError { .. } => unreachable!("not a policy of the dual method"),
                    };
                    let out = s.tessellate(&options).unwrap();
                    assert_eq!(out.mesh, expected, "{rates:?}");
                    assert_eq!(out.info.rates.len(), faces);
                    assert_eq!(out.info.epsilon.is_some(), matches!(rates, Rates::Tolerance(_)));
                    let mut flat = FlatMesh::default();
                    s.tessellate_into(&options, &mut flat).unwrap();
                    let mut written = FlatMesh::default();
                    tess.write_flat(&mut written);
                    assert_eq!(flat, written, "{rates:?}");
                }
            }
            {
                let quadtree = QuadtreeTessellator::new(cc, &mesh).unwrap();
                let tolerance = Tolerance::Relative(1e-2);
                let (expected, stats) =
                    quadtree.tessellate_with_stats(&QuadtreeOptions::DEFAULT.with_tolerance(tolerance)).unwrap();
                let options =
                    TessOptions::DEFAULT.with_method(Method::Quadtree).with_rates(Rates::Tolerance(tolerance));
                let with = s.tessellate(&options.clone().with_polygons(true)).unwrap();
                assert_eq!(with.mesh, expected);
                assert_eq!(with.info.quadtree, Some(stats));
                assert_eq!(with.info.epsilon, Some(tolerance.absolute(quadtree.diagonal()).unwrap()));
                let without = s.tessellate(&options.with_parallelism(Parallelism::Serial)).unwrap();
                assert_eq!(without.mesh.polygon_count(), 0);
                assert_eq!(
                    (&without.mesh.positions, &without.mesh.triangles),
                    (&expected.positions, &expected.triangles)
                );
            }
        }
    }

    /// A face-range part's points are the whole tessellation's, bit for bit, under the
    /// triangle schemes too: a triangle's primal point at a rate of 3n is a cell centroid at n,
    /// which read the rate-n dual-grid table once a part's far faces at rate 1 had made it
    /// (fuzz reproducer `pipeline/6b266055e3c25eed`; √3's parts used to keep every face's rate
    /// for it).
    #[test]
    fn parts_are_the_whole_tessellations_points_under_the_triangle_schemes() {
        for builtin in [Builtin::Loop, Builtin::Sqrt3] {
            let mut s = Surface::build(shapes::jittered(shapes::triangle_torus(6, 5), 0.1), builtin.scheme()).unwrap();
            let options = TessOptions::DEFAULT.with_rates(Rates::Uniform(3));
            let whole = s.tessellate(&options).unwrap();
            let bits = |p: &DVec3| p.to_array().map(f64::to_bits);
            let points: std::collections::HashSet<[u64; 3]> = whole.mesh.positions.iter().map(bits).collect();
            for start in (0..60).step_by(15) {
                let part = s.tessellate_part(&options, start..start + 15).unwrap();
                let off = part.mesh.positions.iter().filter(|p| !points.contains(&bits(p))).count();
                assert_eq!(off, 0, "{builtin:?} part {start}..: points off the whole's");
            }
        }
    }

    #[test]
    fn tessellations_past_the_vertex_budget_are_refused_before_the_work() {
        let mut s = surface(shapes::cube());
        // 6 faces at rate 128: the count is predicted, not made.
        let count = subdiv_tess::dual::predicted_vertex_count(s.mesh(), subdiv_schemes::Split::Quad, &[128; 6]);
        let options = TessOptions::DEFAULT.with_rates(Rates::Uniform(128)).with_max_vertices(count - 1);
        let Err(error) = s.tessellate(&options) else { panic!("over the budget") };
        let (requested, limit) = (count as u64, count as u64 - 1);
        assert!(
            matches!(error, Error::Budget { requested: r, limit: l, noun: "vertices", .. } if r == requested && l == limit),
            "{error}"
        );
        assert!(error.to_string().contains("--max-vertices"), "{error}");
        assert!(s.face_rates(&options).is_err(), "the GPU path's rates are checked too");
        let out = s.tessellate(&options.with_max_vertices(count)).map_err(|e| e.to_string()).unwrap();
        assert_eq!(out.mesh.positions.len(), count);
        // The quadtree counts its polygons as it goes (a quarter of the vertices: they weigh twice).
        let quadtree = TessOptions::DEFAULT
            .with_method(Method::Quadtree)
            .with_rates(Rates::Tolerance(Tolerance::Relative(1e-6)))
            .with_max_vertices(10_000);
        let Err(error) = s.tessellate(&quadtree) else { panic!("over the budget") };
        assert!(matches!(error, Error::Tess(TessError::TooManyPolygons { limit: 2_500, .. })), "{error}");
    }

    #[test]
    fn bad_requests_are_typed_errors() {
        let mut s = surface(shapes::quad_grid(2, 2));
        let quadtree = TessOptions::DEFAULT.with_method(Method::Quadtree);
        assert!(matches!(s.tessellate(&quadtree), Err(Error::QuadtreeRates { given: "uniform" })));
        // A screen-space error bound is the quadtree's.
        let camera = Camera::look_at(DVec3::new(0.0, -5.0, 2.0), DVec3::ZERO, DVec3::Z);
        let screen = TessOptions::DEFAULT.with_rates(Rates::ScreenError { camera, viewport: [640, 480], pixels: 1.0 });
        assert!(matches!(s.tessellate(&screen), Err(Error::DualScreenError)));
        let on_screen = s.tessellate(&screen.clone().with_method(Method::Quadtree)).unwrap();
        assert!(on_screen.info.epsilon.is_none() && !on_screen.mesh.triangles.is_empty());
        // Both methods take the grid to a tolerance (its smooth corners ringed in open runs), and
        // an extraordinary vertex on an infinitely sharp edge (the dual's runs on its two sides
        // share their ring points on it); the dual tessellator takes no rate 0.
        let tolerance = TessOptions::DEFAULT.with_rates(Rates::Tolerance(Tolerance::Relative(1e-2)));
        assert!(s.tessellate(&tolerance).is_ok());
        assert!(s.tessellate(&quadtree.clone().with_rates(tolerance.rates.clone())).is_ok());
        let mut creased = shapes::cube();
        let [a, b] = [creased.face(FaceId::new(0))[0], creased.face(FaceId::new(0))[1]];
        creased.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [a, b], sharpness: 10.0 });
        let mut creased = surface(creased);
        assert!(creased.tessellate(&tolerance).is_ok());
        assert!(creased.tessellate(&quadtree.with_rates(tolerance.rates.clone())).is_ok());
        assert!(matches!(s.tessellate(&TessOptions::DEFAULT.with_rates(Rates::Uniform(0))), Err(Error::Tess(_))));
        assert!(matches!(
            s.tessellate(&TessOptions::DEFAULT.with_rates(Rates::PerFace(vec![2; 3]))),
            Err(Error::Tess(_))
        ));
        let mut flat = FlatMesh { vertices: vec![1.0], indices: vec![], ..FlatMesh::default() };
        assert!(s.tessellate_into(&TessOptions::DEFAULT.with_rates(Rates::Uniform(1025)), &mut flat).is_err());
        assert_eq!(flat.vertices, [1.0], "a failed call leaves the sink alone");
        let bad_camera = Rates::Screen {
            camera: Camera::look_at(DVec3::ZERO, DVec3::ZERO, DVec3::Z),
            viewport: [10, 10],
            pixels_per_edge: 1.0,
        };
        assert!(matches!(s.tessellate(&TessOptions::DEFAULT.with_rates(bad_camera)), Err(Error::Tess(_))));
        // Evaluation: a face out of range, a parameter outside the face, a grid of 0.
        assert!(matches!(s.evaluate(FaceId::new(99), 0.5, 0.5), Err(Error::Eval(_))));
        assert!(s.evaluate(FaceId::new(0), 1.5, 0.5).is_err());
        assert!(s.evaluate(FaceId::new(0), f64::NAN, 0.5).is_err());
        assert!(matches!(s.evaluate_grid(0), Err(Error::Grid { n: 0, .. })));
        assert!(matches!(s.evaluate_grid(crate::MAX_GRID + 1), Err(Error::Grid { .. })));
        // A scheme that does not take the mesh (√3, quads).
        assert!(matches!(
            Surface::new(Mesh::build(shapes::cube()).unwrap(), Builtin::Sqrt3.scheme()).evaluate(
                FaceId::new(0),
                0.5,
                0.5
            ),
            Err(Error::Eval(_))
        ));
        // Files.
        assert!(matches!(Surface::load("no/such/cage.obj", Builtin::CatmullClark.scheme()), Err(Error::Io(_))));
        let mut bowtie = shapes::cube();
        bowtie.push_face([0, 1, 2].map(subdiv_mesh::VertexId::new));
        assert!(matches!(Surface::build(bowtie, Builtin::CatmullClark.scheme()), Err(Error::Mesh(_))));
        assert!(matches!(
            Surface::new(Mesh::build(shapes::cube()).unwrap(), Builtin::Loop.scheme()).refine(1),
            Err(Error::Scheme(_))
        ));
        // Levels × faces past the budget, then past 32-bit ids once the budget is raised:
        // refused before anything is allocated (8 levels of the cube: 393,216 faces).
        let s = Surface::build(shapes::cube(), Builtin::CatmullClark.scheme()).unwrap();
        assert!(matches!(
            s.refine(12),
            Err(Error::Budget { requested: 100_663_296, limit: DEFAULT_MAX_REFINED_FACES, .. })
        ));
        let s = s.with_max_refined_faces(u64::MAX);
        assert!(matches!(s.refine(40), Err(Error::RefineLevels { levels: 40, .. })));
    }

    /// The refinement bound is exact for the primal splits and never above the real count for
    /// the others (√3 and mid-edge refine far past what 4× growth would refuse).
    #[test]
    fn refined_face_bounds_are_lower_bounds() {
        for (builtin, soup) in [
            (Builtin::CatmullClark, shapes::default_model()),
            (Builtin::Loop, shapes::icosahedron()),
            (Builtin::Sqrt3, shapes::icosahedron()),
            (Builtin::Midedge, shapes::cube()),
            (Builtin::DooSabin, shapes::cube()),
        ] {
            let s = Surface::new(Mesh::build(soup).unwrap(), builtin.scheme());
            for levels in 0..3 {
                let real = s.refine(levels).unwrap().face_count() as u64;
                let bound = s.refined_faces_at_least(levels);
                assert!(bound <= real, "{builtin:?} at {levels} levels: bound {bound}, {real} faces");
                if matches!(builtin, Builtin::CatmullClark | Builtin::Loop) {
                    assert_eq!(bound, real, "{builtin:?} at {levels} levels");
                }
            }
        }
    }

    #[test]
    fn evaluation_and_refinement_are_the_crates_own() {
        let s = surface(shapes::default_model());
        let eigen = EigenEvaluator::new(s.scheme(), s.mesh(), &RefineOptions::DEFAULT, EvalMethod::Auto).unwrap();
        for face in [0, 7, 59].map(FaceId::new) {
            assert_eq!(s.evaluate(face, 0.25, 0.75).unwrap(), eigen.eval(face, 0.25, 0.75).unwrap());
        }
        let grid = s.evaluate_grid(2).unwrap();
        assert_eq!(grid.holes, 0);
        assert_eq!(grid.points.len(), 9 * s.mesh().face_count());
        assert!(grid.points.iter().all(|p| p.point == eigen.eval(p.face, p.u, p.v).unwrap()));
        let exact = s.evaluator(&EvalOptions::DEFAULT.with_method(EvalMethod::Stencil)).unwrap().grid(2).unwrap();
        assert_eq!(exact.points.len(), grid.points.len());
        let mut levels = Vec::new();
        let refined = s.refine_with_progress(2, |l| levels.push(l)).unwrap();
        assert_eq!(levels, [1, 2]);
        let expected = subdiv_schemes::refine_uniform(s.mesh(), s.scheme(), 2, &RefineOptions::DEFAULT).unwrap();
        assert_eq!(refined.positions(), expected.positions());
        assert_eq!(without_holes(&refined).face_count(), refined.face_count());
    }

    #[test]
    fn files_read_back() {
        let dir = std::env::temp_dir().join(format!("subdiv-facade-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cage = dir.join("cube.obj");
        subdiv_io::write_obj(&cage, &shapes::cube()).unwrap();
        let mut s = Surface::load(&cage, Builtin::CatmullClark.scheme()).unwrap();
        for method in [Method::Dual, Method::Quadtree] {
            let rates = Rates::Tolerance(Tolerance::Relative(2e-2));
            let out =
                s.tessellate(&TessOptions::DEFAULT.with_method(method).with_rates(rates).with_polygons(true)).unwrap();
            let (glb, obj, csv) = (dir.join("out.glb"), dir.join("out.obj"), dir.join("out.csv"));
            out.write_glb(&glb).unwrap();
            let back = subdiv_io::load_mesh(&glb, &BuildOptions::default()).unwrap();
            assert_eq!(back.face_count(), out.mesh.triangles.len());
            for polygons in [false, true] {
                out.write_obj(&obj, polygons).unwrap();
                // Watertight either way: the faces build a closed mesh of the cube's genus.
                let back = subdiv_io::load_mesh(&obj, &BuildOptions::default()).unwrap();
                assert_eq!((back.boundary_edge_count(), back.genus()), (0, Some(0)), "{method:?}");
                assert_eq!(back.face_size_histogram().contains_key(&4), polygons, "{method:?}");
            }
            out.write_params(&csv).unwrap();
            let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
            assert_eq!(rows, out.mesh.positions.len() + 1);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
    /// A cube with every edge infinitely sharp: its crease points have two normals (three at
    /// the corners). OBJ keeps one `v` per vertex and gives those corners their own `vn`; GLB
    /// splits exactly those vertices.
    #[test]
    fn split_normals_in_files() {
        let mut mesh = Mesh::build(shapes::cube()).unwrap();
        for e in mesh.edges().collect::<Vec<_>>() {
            mesh.set_edge_sharpness(e, subdiv_mesh::Tags::INFINITELY_SHARP);
        }
        let mut s = Surface::new(mesh, Builtin::CatmullClark.scheme());
        let out = s.tessellate(&TessOptions::DEFAULT.with_rates(Rates::Uniform(3)).with_polygons(true)).unwrap();
        let m = &out.mesh;
        let vertices = m.positions.len();
        // Each edge's 3 points once more, each corner twice more.
        assert_eq!(m.normal_vertices.len(), 12 * 3 + 8 * 2);
        for polygons in [false, true] {
            let mut text = Vec::new();
            out.write_obj_to(&mut text, polygons).unwrap();
            let text = String::from_utf8(text).unwrap();
            let count = |tag: &str| text.lines().filter(|l| l.starts_with(tag)).count();
            assert_eq!((count("v "), count("vn ")), (vertices, m.normals.len()), "polygons: {polygons}");
            let mut split = 0;
            for corner in text.lines().filter(|l| l.starts_with("f ")).flat_map(|l| l.split_whitespace().skip(1)) {
                let (v, n) = corner.split_once("//").unwrap();
                let (v, n): (u32, usize) = (v.parse::<u32>().unwrap() - 1, n.parse::<usize>().unwrap() - 1);
                match n.checked_sub(vertices) {
                    None => assert_eq!(n, v as usize, "{corner}: a vertex's own normal"),
                    Some(e) => {
                        assert_eq!(m.normal_vertices[e], v, "{corner}: an extra normal of its vertex");
                        split += 1;
                    }
                }
            }
            assert!(split > 0, "polygons: {polygons}: no corner takes an extra normal");
        }
        let glb = std::env::temp_dir().join(format!("subdiv-split-normals-{}.glb", std::process::id()));
        out.write_glb(&glb).unwrap();
        let back = subdiv_io::load(&glb).unwrap();
        std::fs::remove_file(&glb).unwrap();
        assert_eq!(back.vertex_count(), vertices + m.normal_vertices.len());
        assert_eq!(back.face_count(), m.triangles.len());
    }
}
