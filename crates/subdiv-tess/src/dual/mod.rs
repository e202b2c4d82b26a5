//! Dual-grid stitching (paper 000, Schaefer and Warren, §5.5): uniform tessellation at a
//! per-face integer rate, watertight across faces of different rates without welding.
//!
//! Each face at rate `n` owns the points of its **dual grid** (quads: the cell centres
//! `((i+½)/n, (j+½)/n)` of its `Bfr` domain; triangles: the centroids of its `n²`
//! sub-triangles). No point lies on an edge, so no point is shared and none is evaluated
//! twice. The gaps between faces are closed by **strips** along each edge, which merge the two
//! faces' rows of points nearest the edge in parameter order (equal rates give quads, different
//! rates triangles), and by a polygon around each **vertex** through each incident face's point
//! nearest it. N-gons (N ≠ 4) under a quad split are tessellated through their `Bfr` quad
//! sub-faces at rate `⌈n/2⌉` each (a sub-face is a quarter of the face, so the spacing matches a
//! quad neighbour's), with strips along the spokes and a polygon at the centre.
//!
//! - **Quad splits** (Catmull-Clark, Kobbelt, bilinear, …): the dual quad grid inside each
//!   face; a vertex of valence 3 closes with a triangle, valence 4 with a quad, valence ≥ 5
//!   with a fan around the vertex's limit point (a better shape than a fan from one corner;
//!   its normal is the limit normal of the stencils).
//! - **Triangle splits** (Loop, butterfly): the dual hexagons around each interior primal point
//!   `(i/n, j/n)` are fanned around that point (evaluated too), and every vertex's ring is
//!   fanned around the vertex's limit point, as the hexagons are.
//! - **Borders** (mesh boundaries, and the edges of tagged holes, which produce nothing): points
//!   on the edge at the parameters of the row beside it, and the limit point of each border
//!   vertex; the strips and vertex fans close against them, so the output's boundary runs
//!   through the limit points of the input's boundary vertices, in order.
//!
//! **Rings** ([`DualTessellator::tessellate_with_rings`]): the polygon at an
//! extraordinary point (an interior vertex of valence ≠ 4 or an infinitely sharp corner, or an
//! N-gon's centre) stands for a
//! piece of surface as coarse as its faces' rates, which the tolerance policy's hull bound may
//! not accept. With a ring depth `d > 0` for the point
//! ([`ErrorRates::rates`](crate::rates::ErrorRates::rates) computes them), the polygon is
//! replaced by rings of exact points at `r_j = 2^−(d1 + j − 1)` face units from the point,
//! `j = 1..=K`, `K = max(1, d − d1 + 1)`: `d1` is the depth of the first power of two strictly
//! inside the nearest dual points (which are `½ / reach` away, `reach` the rate of a quad
//! neighbour, `2⌈n/2⌉` for an N-gon's sub-faces). Each ring has a point on every edge (an
//! N-gon's spoke) at `r_j`, made once for the two faces beside it, and one per face at
//! `(r_j, r_j)` in that face's corner frame (an N-gon's sub-face coordinates are twice the face
//! units). Triangles, each in one face's region or across one edge, as the bound assumes: from
//! each face's corner dual point to ring 1 two in the face and one across each edge to the next
//! face's; between rings `j` and `j + 1` two quads per face in its L-shaped region
//! `[0, r_j]² \ [0, r_{j+1})²`; inside the last ring a fan around the point's limit point. The
//! ring points are ordinary output vertices (evaluated by exact stencils, re-evaluated by
//! [`DualTessellator::update_cage`]); below about `2^−50` face units they are no longer apart
//! in f64 positions, which the tolerances that need rings never reach. At a border vertex (quad
//! split) whose polygon only borders with nothing across cut (a boundary, a hole), each run of
//! faces between two borders takes **open rings**: the same points, the last edge's made in the
//! run's last face, the same bands without the wrap, and one triangle from the border point on
//! the first edge; the limit point is shared by the runs (an extra normal for each after the
//! first). The border then runs through the ring points on its edges too.
//! Triangle splits take rings too (around interior vertices of valence ≠ 6), in the
//! triangles' corner frames: the first ring below the corner centroids' `1 / (3n)`, per face a
//! point on its edge at `r_j` and one at `(r_j/2, r_j/2)`, the bands between rings trapezoids;
//! no tolerance policy computes their depths yet.
//!
//! Every output vertex is evaluated once, exactly, with a unit normal from the exact tangents:
//! regular bicubic faces separably, row by row, with per-rate basis tables; the cell points of
//! other level-0 patches through their patch type's dual-grid
//! [`StencilTable`](subdiv_stencil::StencilTable); every other point through its own exact
//! stencil at the patch that holds it (after descending through the refined levels an N-gon or
//! a face with two extraordinary corners needs), or, where a quad face's cell points fill a grid
//! of a regular patch on a refined level, separably too. Quad faces with the same resolution tree
//! and the same neighbourhood structure (a face **type**) share a template: their cell points as
//! combinations of the face's own cage points, made once per type and rate from the first face's
//! exact stencils and kept across calls. [`DualTessellator::update_cage`] re-evaluates
//! positions and normals for a moved cage without any topology or stencil work.

mod channels;
pub(crate) mod eval;
mod flat;
mod topology;

pub use self::flat::FlatMesh;

use glam::DVec3;
use subdiv_mesh::{FaceId, FaceVaryingInterpolation, Mesh};
use subdiv_schemes::{Scheme, Split};
use subdiv_stencil::FaceDomain;

use self::channels::Channels;
use self::eval::Evaluator;
use self::topology::{Builder, BuilderBuffers, PackedDomain, Site, Topology};
use crate::par::{self, Parallelism};
pub use crate::plan::{
    EvaluationPlan, PlanBicubic, PlanBlock, PlanEntry, PlanError, PlanGeneral, PlanItem, PlanParts, PlanRecord,
};
use crate::rates::RingDepths;
use crate::{SurfaceParameter, TessChannels, TessError, TessMesh, TessSink};

/// The largest rate [`DualTessellator::tessellate`] takes: a face of `1024²` points, past
/// which a request is one nobody means (the vertex budgets of the callers, predicted from the
/// rates before any work, are the guard that matters; this one only keeps the counts far from
/// overflow).
pub const MAX_DUAL_RATE: u32 = 1024;

/// The largest ring depth [`DualTessellator::tessellate_with_rings`] takes: rings come down to
/// `2^−60` face units, whose parameters (and an N-gon's sub-face coordinates, twice as fine)
/// are exact in the `i64` dyadics of the stencils.
pub const MAX_DUAL_RING_DEPTH: u32 = 60;

/// Options of [`DualTessellator`].
///
/// ```
/// use subdiv_tess::{DualOptions, Parallelism};
///
/// let options = DualOptions::DEFAULT.with_quads(false).with_parallelism(Parallelism::Serial);
/// assert_eq!(DualOptions::default(), DualOptions::DEFAULT);
/// assert!(!options.quads);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DualOptions {
    /// Also list the output's quads (face grids, equal-rate strips, valence-4 vertices) as
    /// [`TessMesh`] polygons. Triangles are always output. Default: `true`.
    pub quads: bool,
    /// Carry the mesh's face-varying channels (texture coordinates): every output point gets
    /// every channel's exact value, and the channels' seams are cut (see [`TessMesh`]). Fixed
    /// when the tessellator is made. Default: `true`.
    pub channels: bool,
    /// The channels' face-varying interpolation: `None` takes the mesh's tag, else
    /// [`FaceVaryingInterpolation::All`] (OpenSubdiv's default). Fixed when the tessellator is
    /// made. Default: `None`.
    pub face_varying: Option<FaceVaryingInterpolation>,
    /// Whether the evaluation and the index writing may use rayon's threads (the output is the
    /// same, bit for bit, either way). Default: [`Parallelism::Rayon`].
    pub parallelism: Parallelism,
    /// How much [`DualTessellator::tessellate_stream`] builds, evaluates and hands on at a
    /// time: a chunk closes once it holds this many vertices and triangles together (the
    /// output is the same, bit for bit, at any size). Default: [`DEFAULT_STREAM_CHUNK`].
    pub chunk: u32,
}

/// [`DualOptions::chunk`]'s default: 2^16 vertices and triangles, a megabyte or two of flat
/// output and topology per chunk, which still has tens of thousands of vertices for the
/// threads to share (the evaluation shares from 1024). Measured on a 1000 × 1000 grid at rate 2
/// (docs/perf-log.md, 2026-12-06): 2^20 → 2^18 → 2^16 took the peak from 513 to 448 to 431 MB
/// at the same time.
pub const DEFAULT_STREAM_CHUNK: u32 = 1 << 16;

impl DualOptions {
    /// The defaults: quads listed, [`Parallelism::Rayon`], chunks of [`DEFAULT_STREAM_CHUNK`].
    pub const DEFAULT: Self = Self {
        quads: true,
        channels: true,
        face_varying: None,
        parallelism: Parallelism::DEFAULT,
        chunk: DEFAULT_STREAM_CHUNK,
    };

    /// These options with [`quads`](Self::quads) set.
    #[must_use]
    pub const fn with_quads(self, quads: bool) -> Self {
        Self { quads, ..self }
    }

    /// These options with [`channels`](Self::channels) set.
    #[must_use]
    pub const fn with_channels(self, channels: bool) -> Self {
        Self { channels, ..self }
    }

    /// These options with [`face_varying`](Self::face_varying) set.
    #[must_use]
    pub const fn with_face_varying(self, face_varying: FaceVaryingInterpolation) -> Self {
        Self { face_varying: Some(face_varying), ..self }
    }

    /// These options with [`parallelism`](Self::parallelism) set.
    #[must_use]
    pub const fn with_parallelism(self, parallelism: Parallelism) -> Self {
        Self { parallelism, ..self }
    }

    /// These options with [`chunk`](Self::chunk) set (at least 1).
    #[must_use]
    pub const fn with_chunk(self, chunk: u32) -> Self {
        Self { chunk: if chunk == 0 { 1 } else { chunk }, ..self }
    }
}

impl Default for DualOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Dual-grid stitching tessellator of one control mesh under one scheme, reusable across rates
/// and cages (it keeps its allocations between calls).
///
/// Output conventions ([`TessMesh`]): a vertex's [`parameters`](TessMesh::parameters) name the
/// face that evaluated it (a border point: the face beside the border; a vertex's limit point:
/// one of its faces, at its corner). A triangle of a cell belongs to the cell's face; a strip's
/// triangle to the face on the left of the edge's lower-numbered half-edge (the face of the
/// border side, on a border); a vertex polygon's to the first face of its ring; a ring's triangle
/// (rings around extraordinary points) to the face whose region holds it (across an edge: the
/// face before the edge, counter-clockwise). Since strip, vertex-polygon and ring triangles span
/// several faces, [`triangle_parameters`](TessMesh::triangle_parameters)
/// lists each corner's own parameters (those of [`parameters`](TessMesh::parameters)), which
/// may be in different faces.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::{DualOptions, DualTessellator, FlatMesh};
///
/// let mesh = Mesh::build(shapes::ngon_prism(5))?;
/// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())?;
/// let rates: Vec<u32> = (0..tess.face_count() as u32).map(|f| 2 + f % 3).collect();
/// let out = tess.tessellate(&rates)?;
/// assert_eq!(out.normals.len(), out.positions.len());
/// let triangles = out.triangles.len();
///
/// // Animation: the same topology on a moved cage.
/// let moved: Vec<_> = mesh.positions().iter().map(|p| *p * 2.0).collect();
/// let out = tess.update_cage(&moved)?;
/// assert_eq!(out.triangles.len(), triangles);
///
/// let mut flat = FlatMesh::default();
/// tess.write_flat(&mut flat);
/// assert_eq!(flat.indices.len(), 3 * triangles);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct DualTessellator {
    options: DualOptions,
    scheme: String,
    vertex_count: usize,
    evaluator: Evaluator,
    /// The carried face-varying channels, and their values at the last topology's points.
    channels: Channels,
    channel_values: TessChannels,
    builder: TopologyBuilder,
    topology: Topology,
    rates: Vec<u32>,
    output: TessMesh,
    /// Whether `output` has the topology's connectivity and surface parameters (not after
    /// [`tessellate_flat`](Self::tessellate_flat), which leaves it empty).
    output_current: bool,
    /// The triangles' indices, for [`update_cage_flat`](Self::update_cage_flat) when `output`
    /// has none (made by its first call after [`tessellate_flat`](Self::tessellate_flat)).
    flat_indices: Vec<u32>,
}

impl DualTessellator {
    /// Prepares `mesh` under `scheme`: its patches, the levels of refinement its N-gons and
    /// double extraordinary faces need, and the bicubic faces' control points.
    ///
    /// With [`DualOptions::channels`], also prepares the surface of each of the mesh's
    /// face-varying channels.
    ///
    /// # Errors
    /// [`TessError::Surface`] as [`PatchLevels::new`](subdiv_stencil::PatchLevels::new): schemes
    /// without sub-patch matrices (√3, Doo-Sabin, mid-edge), faces the scheme does not take;
    /// [`TessError::Scheme`] for a mesh with channels under a scheme without face-varying rules
    /// (carry none: [`DualOptions::with_channels`]).
    pub fn new(scheme: &Scheme, mesh: &Mesh, options: &DualOptions) -> Result<Self, TessError> {
        let evaluator = Evaluator::new(scheme, mesh)?;
        let triangle = evaluator.levels().split() == Split::Triangle;
        let (channels, seams) =
            if options.channels { Channels::new(scheme, mesh, options.face_varying)? } else { Default::default() };
        Ok(Self {
            options: *options,
            scheme: scheme.name().to_string(),
            vertex_count: mesh.vertex_count(),
            evaluator,
            channels,
            channel_values: TessChannels::default(),
            builder: TopologyBuilder { triangle, quads: options.quads, seams, buffers: BuilderBuffers::default() },
            topology: Topology::default(),
            rates: Vec::new(),
            output: TessMesh::default(),
            output_current: false,
            flat_indices: Vec::new(),
        })
    }

    /// Seeds the dual-grid stencil tables with precomputed ones, e.g. the committed defaults
    /// (`subdiv-stencil`'s `DEFAULT_TABLES`, read with
    /// [`StencilTables::from_bytes`](subdiv_stencil::StencilTables::from_bytes)), so that the
    /// level-0 extraordinary patches at those rates need no table work; other tables are still
    /// computed on demand. Only interior patch types are taken (a boundary patch's table depends
    /// on the boundary rule). Returns how many tables were taken.
    ///
    /// # Errors
    /// [`TessError::Scheme`] if the tables are another scheme's.
    pub fn seed_tables(&mut self, tables: &subdiv_stencil::StencilTables) -> Result<usize, TessError> {
        if tables.scheme() != self.scheme {
            return Err(TessError::Scheme {
                scheme: self.scheme.clone(),
                reason: format!("the stencil tables are for `{}`", tables.scheme()),
            });
        }
        Ok(self.evaluator.seed_tables(tables))
    }

    /// Takes new options: [`parallelism`](DualOptions::parallelism) from the next call on,
    /// [`quads`](DualOptions::quads) from the next tessellation (the animation paths keep the
    /// last one's polygons); the channels stay as made. Nothing prepared is lost.
    pub fn set_options(&mut self, options: &DualOptions) {
        self.options =
            DualOptions { channels: self.options.channels, face_varying: self.options.face_varying, ..*options };
        self.builder.quads = options.quads;
    }

    /// The options (as made, or as last [set](Self::set_options)).
    pub fn options(&self) -> &DualOptions {
        &self.options
    }

    /// The number of input faces (the length [`tessellate`](Self::tessellate)'s rates must have).
    pub fn face_count(&self) -> usize {
        self.evaluator.levels().mesh(0).face_count()
    }

    /// Tessellates with `rates[f]` steps per side of input face `f` (holes: ignored, but still
    /// checked), on the latest cage (the mesh's, or the last [`update_cage`](Self::update_cage)'s).
    /// An N-gon (N ≠ 4) under a quad split takes `⌈n/2⌉` steps per side of each of its `Bfr`
    /// sub-faces. Rebuilds the topology and the stencil records; the tables and stencils solved
    /// by earlier calls are kept, and so are the templates of each face type at each rate (the
    /// cell points of faces with the same resolution tree and neighbourhood, over their cage
    /// points).
    ///
    /// # Errors
    /// [`TessError::RateCount`] unless there is one rate per face; [`TessError::Rate`] for a
    /// rate outside `1..=`[`MAX_DUAL_RATE`]; [`TessError::Surface`] if a stencil fails.
    pub fn tessellate(&mut self, rates: &[u32]) -> Result<&TessMesh, TessError> {
        self.rebuild(rates, None)?;
        self.fill_output();
        Ok(&self.output)
    }

    /// As [`tessellate`](Self::tessellate), with rings of exact points around extraordinary
    /// points down to the depths of `rings` (see the module docs; [`ErrorRates::rates`]
    /// computes them with the rates, for Catmull-Clark): `rings.vertices[v]` around interior mesh
    /// vertices of valence ≠ 4 (≠ 6 under a triangle split) or tagged infinitely sharp corners,
    /// whose polygon no sharp edge, seam or border cuts, and (quad split) in the runs of faces
    /// around a border vertex when its only cuts are borders with nothing across (open rings),
    /// `rings.centres[f]` around the
    /// centres of N-gons (N ≠ 4, quad splits); depth 0, and the entries of other vertices and
    /// faces, change nothing.
    ///
    /// [`ErrorRates::rates`]: crate::rates::ErrorRates::rates
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate); [`TessError::RingCount`] unless there is one depth
    /// per input vertex and one per input face; [`TessError::RingDepth`] for a depth above
    /// [`MAX_DUAL_RING_DEPTH`].
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::rates::ErrorRates;
    /// use subdiv_tess::{DualOptions, DualTessellator, QuadtreeTessellator, Tolerance};
    ///
    /// let mesh = Mesh::build(shapes::cube())?;
    /// let cc = Builtin::CatmullClark.scheme();
    /// // Rates and ring depths to 1% of the bounding box (the bounds come from the quadtree's pieces).
    /// let rates = ErrorRates::new(Tolerance::Relative(1e-2)).rates(&QuadtreeTessellator::new(cc, &mesh)?, &mesh)?;
    /// assert!(rates.rings.vertices.iter().all(|&d| d > 0)); // the cube's valence-3 corners
    /// let mut tess = DualTessellator::new(cc, &mesh, &DualOptions::default())?;
    /// let plain = tess.tessellate(&rates.faces)?.positions.len();
    /// let ringed = tess.tessellate_with_rings(&rates.faces, &rates.rings)?.positions.len();
    /// assert!(ringed > plain);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn tessellate_with_rings(&mut self, rates: &[u32], rings: &RingDepths) -> Result<&TessMesh, TessError> {
        self.check_rings(rates, rings)?;
        self.rebuild(rates, Some(rings))?;
        self.fill_output();
        Ok(&self.output)
    }

    /// [`tessellate`](Self::tessellate) into `sink` (see [`TessSink`]): the caller's buffers
    /// and vertex type. Polygons (the quads, where [`DualOptions::quads`] lists them) go to
    /// sinks that [want them](TessSink::wants_polygons). Afterwards [`mesh`](Self::mesh) is
    /// the same output and the animation paths work as after
    /// [`tessellate`](Self::tessellate) (the sink is written from it).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::{DualOptions, DualTessellator, FlatMesh};
    ///
    /// let mesh = Mesh::build(shapes::cube())?;
    /// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::DEFAULT)?;
    /// let mut flat = FlatMesh::default();
    /// tess.tessellate_into(&[1, 2, 3, 4, 5, 6], &mut flat)?;
    /// let mut written = FlatMesh::default();
    /// tess.write_flat(&mut written);
    /// assert_eq!(flat, written);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate); `sink` is then not called.
    pub fn tessellate_into<S: TessSink + ?Sized>(&mut self, rates: &[u32], sink: &mut S) -> Result<(), TessError> {
        self.tessellate(rates)?.write_to(sink);
        Ok(())
    }

    /// [`tessellate_with_rings`](Self::tessellate_with_rings) into `sink`, as
    /// [`tessellate_into`](Self::tessellate_into).
    ///
    /// # Errors
    /// As [`tessellate_with_rings`](Self::tessellate_with_rings); `sink` is then not called.
    pub fn tessellate_with_rings_into<S: TessSink + ?Sized>(
        &mut self,
        rates: &[u32],
        rings: &RingDepths,
        sink: &mut S,
    ) -> Result<(), TessError> {
        self.tessellate_with_rings(rates, rings)?.write_to(sink);
        Ok(())
    }

    /// Checks that `rings` has one depth per vertex and per face, none too deep, and graded
    /// grids (if any) per face, each on a quad of the quad split with `rates`' cells per axis.
    fn check_rings(&self, rates: &[u32], rings: &RingDepths) -> Result<(), TessError> {
        let (vertices, faces) = (self.vertex_count, self.face_count());
        if !rings.graded.is_empty() && rings.graded.len() != faces {
            return Err(TessError::RingCount { what: "graded grids", expected: faces, got: rings.graded.len() });
        }
        for (face, grid) in rings.graded.iter().enumerate().filter_map(|(f, g)| Some(f).zip(g.as_ref())) {
            let rate = rates.get(face).copied().unwrap_or(0);
            let reason = match self.evaluator.domains()[face].get() {
                Some(FaceDomain::Quad) => grid.fault(rate),
                // Every sub-face's grid, the same on both axes (the spokes are ladders).
                Some(FaceDomain::SubFaces { .. }) if grid.axes[0] != grid.axes[1] => {
                    Some("has different axes on an N-gon".to_string())
                }
                Some(FaceDomain::SubFaces { .. }) => grid.fault(rate.div_ceil(2)),
                _ => Some("is not on a quad or an N-gon of a quad split".to_string()),
            };
            if let Some(reason) = reason {
                return Err(TessError::Grading { face, reason });
            }
        }
        if rings.vertices.len() != vertices {
            return Err(TessError::RingCount { what: "vertices", expected: vertices, got: rings.vertices.len() });
        }
        if rings.centres.len() != faces {
            return Err(TessError::RingCount { what: "centres", expected: faces, got: rings.centres.len() });
        }
        let too_deep =
            |depths: &[u32], kind: &str| {
                depths.iter().enumerate().find(|(_, d)| **d > MAX_DUAL_RING_DEPTH).map(|(k, &depth)| {
                    TessError::RingDepth { element: format!("{kind} {k}"), depth, max: MAX_DUAL_RING_DEPTH }
                })
            };
        match too_deep(&rings.vertices, "vertex").or_else(|| too_deep(&rings.centres, "face")) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Checks `rates`, rebuilds the topology (with `rings`, if any) and prepares the evaluation.
    fn rebuild(&mut self, rates: &[u32], rings: Option<&RingDepths>) -> Result<(), TessError> {
        self.check_rates(rates)?;
        self.builder.build(self.evaluator.levels().mesh(0), self.evaluator.domains(), rates, rings, &mut self.topology);
        let parallel = self.options.parallelism.forks();
        let prepared = self
            .evaluator
            .prepare(&self.topology, rates, parallel)
            .and_then(|()| self.channels.evaluate(&self.topology, rates, parallel, &mut self.channel_values));
        self.settle(rates, prepared)
    }

    /// After the preparation of the topology just built for `rates`: on success the rates are
    /// kept; on failure the tessellator goes back to no topology and no rates, as before the
    /// first tessellation (the animation paths then evaluate nothing, instead of a topology
    /// the evaluation was not prepared for).
    fn settle(&mut self, rates: &[u32], prepared: Result<(), TessError>) -> Result<(), TessError> {
        self.rates.clear();
        match prepared {
            Ok(()) => {
                self.rates.extend_from_slice(rates);
                Ok(())
            }
            Err(e) => {
                self.topology = Topology::default();
                Err(e)
            }
        }
    }

    /// Checks `rates` (one per face, each in `1..=`[`MAX_DUAL_RATE`]) for the topology about
    /// to be built at them, which the output and the kept indices then no longer match.
    fn check_rates(&mut self, rates: &[u32]) -> Result<(), TessError> {
        if rates.len() != self.face_count() {
            return Err(TessError::RateCount { expected: self.face_count(), got: rates.len() });
        }
        if let Some((face, &rate)) = rates.iter().enumerate().find(|(_, r)| !(1..=MAX_DUAL_RATE).contains(*r)) {
            return Err(TessError::Rate { face, rate, rule: "rates are integers from 1 to MAX_DUAL_RATE = 1024" });
        }
        self.output_current = false;
        self.flat_indices.clear();
        Ok(())
    }

    /// The animation path: the same topology and rates on a new cage (one finite position per
    /// input vertex). Only positions and normals are recomputed (after
    /// [`tessellate_flat`](Self::tessellate_flat), which leaves [`mesh`](Self::mesh) empty, the
    /// whole [`TessMesh`] is made once, as [`tessellate`](Self::tessellate) would).
    ///
    /// # Errors
    /// [`TessError::CageLength`], [`TessError::CagePosition`] for a non-finite position.
    pub fn update_cage(&mut self, positions: &[DVec3]) -> Result<&TessMesh, TessError> {
        self.check_cage(positions)?;
        self.evaluator.set_cage(positions);
        if self.output_current {
            let out = &mut self.output;
            self.evaluator.evaluate(
                &self.topology,
                self.options.parallelism.forks(),
                &mut out.positions,
                &mut out.normals,
            );
        } else {
            self.fill_output();
        }
        Ok(&self.output)
    }

    fn check_cage(&self, positions: &[DVec3]) -> Result<(), TessError> {
        check_cage(self.vertex_count, positions)
    }

    /// The last tessellation's evaluation as plain arrays (for a GPU, or any evaluator
    /// elsewhere): every output vertex as a linear function of the cage, with the refined
    /// levels it goes through. See [`EvaluationPlan`]; empty before the first tessellation.
    pub fn evaluation_plan(&self) -> EvaluationPlan {
        self.evaluator.plan(&self.topology)
    }

    /// The last tessellation's evaluation of face-varying channel `channel` (by name, one of
    /// the carried ones) as an [`EvaluationPlan`] over the channel's own control values, with
    /// those values: the channel's value at every flat vertex as a linear function of them,
    /// for a GPU to evaluate as it evaluates the positions (each point's "position" is the
    /// channel's value, padded to three components with zeros). `None` for a channel not carried.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Channel, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::{DualOptions, DualTessellator};
    ///
    /// let mut soup = shapes::cube();
    /// let square = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
    /// soup.channels.push(Channel::new("uv", 2, square.repeat(6), (0..24).map(|i| i % 4).collect()));
    /// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &Mesh::build(soup)?, &DualOptions::DEFAULT)?;
    /// let points = tess.tessellate(&[3; 6])?.normals.len();
    /// let (plan, values) = tess.channel_plan("uv").expect("a carried channel");
    /// assert_eq!((plan.vertex_count(), values.len()), (points, 24));
    /// assert!(tess.channel_plan("colour").is_none());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn channel_plan(&self, channel: &str) -> Option<(EvaluationPlan, &[DVec3])> {
        let k = self.channels.names().iter().position(|n| n == channel)?;
        Some(self.channels.plan(k, &self.topology))
    }

    /// The last output, keeping nothing else (a one-shot tessellation without a copy).
    pub fn into_mesh(self) -> TessMesh {
        self.output
    }

    /// The last output (empty before the first [`tessellate`](Self::tessellate)).
    pub fn mesh(&self) -> &TessMesh {
        &self.output
    }

    /// The rates of the last [`tessellate`](Self::tessellate) (or of its variants; empty
    /// before the first and after one that failed past the checks of its rates).
    pub fn rates(&self) -> &[u32] {
        &self.rates
    }

    /// The output as flat f32 buffers (the vertices, then one split copy per extra normal;
    /// the triangles' [normals](TessMesh::triangle_normals) as indices: see [`FlatMesh`]),
    /// reusing `out`'s allocations.
    pub fn write_flat(&self, out: &mut FlatMesh) {
        self.output.write_to(out);
    }

    /// Evaluates, writes the triangles and their faces, and moves the topology's polygons into
    /// the output (their old buffers go back to the topology, to be refilled next time: no
    /// copies).
    fn fill_output(&mut self) {
        let (t, parallel) = (&mut self.topology, self.options.parallelism.forks());
        let out = &mut self.output;
        self.evaluator.evaluate(t, parallel, &mut out.positions, &mut out.normals);
        out.normal_vertices.clone_from(&t.extra);
        let triangles = t.triangle_count() as usize;
        out.triangles.resize(triangles, [0; 3]);
        t.write_triangles(out.triangles.as_flattened_mut(), parallel);
        out.triangle_normals.clear();
        out.triangle_normals.extend_from_slice(&out.triangles);
        t.set_normal_corners(out.triangle_normals.as_flattened_mut());
        out.triangle_faces.resize(triangles, FaceId::new(0));
        t.write_triangle_faces(&mut out.triangle_faces, parallel);
        out.parameters.clear();
        out.parameters.reserve(t.vertex_count as usize);
        let parameter = |s: &Site| {
            let (u, v) = s.point.to_f64();
            SurfaceParameter { face: FaceId::new(s.face), u, v }
        };
        t.for_each_site(|s| out.parameters.push(parameter(&s)));
        out.normal_parameters.clear();
        out.normal_parameters.extend(t.sites[t.sites.len() - t.extra.len()..].iter().map(parameter));
        out.channels.clone_from(&self.channel_values);
        std::mem::swap(&mut out.polygon_offsets, &mut t.polygon_offsets);
        std::mem::swap(&mut out.polygon_vertices, &mut t.polygon_vertices);
        std::mem::swap(&mut out.polygon_faces, &mut t.polygon_faces);
        out.triangle_parameters.clear();
        let params = &out.parameters;
        let corners = |tri: &[u32; 3]| tri.map(|k| [params[k as usize].u, params[k as usize].v]);
        par::extend_map(parallel, &mut out.triangle_parameters, &out.triangles, corners);
        self.output_current = true;
    }
}

/// The rules a new cage meets ([`DualTessellator::update_cage`], and evaluators of an
/// [`EvaluationPlan`] elsewhere): one finite position per vertex of a control mesh with
/// `expected` vertices.
///
/// # Errors
/// [`TessError::CageLength`], [`TessError::CagePosition`] naming the first non-finite position.
pub fn check_cage(expected: usize, positions: &[DVec3]) -> Result<(), TessError> {
    if positions.len() != expected {
        return Err(TessError::CageLength { expected, got: positions.len() });
    }
    if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(TessError::CagePosition { vertex, value: format!("{p}") });
    }
    Ok(())
}

/// The number of output vertices the construction makes for `mesh` under a scheme of `split` at
/// `rates`: cells, triangle interiors, N-gon centres, border points and vertex points (see the
/// module docs). For budgets and checks.
pub fn predicted_vertex_count(mesh: &Mesh, split: Split, rates: &[u32]) -> usize {
    topology::predicted_vertices(mesh, split, rates, None)
}

/// [`predicted_vertex_count`] with `rings` (one depth per vertex and per face, as
/// [`DualTessellator::tessellate_with_rings`] takes them): each ring adds two points per face
/// around its point, and a ringed point of valence (or size) 3 under a quad split its limit
/// point.
///
/// # Panics
/// If `rings` does not have one depth per vertex and one per face.
pub fn predicted_vertex_count_with_rings(mesh: &Mesh, split: Split, rates: &[u32], rings: &RingDepths) -> usize {
    assert!(rings.vertices.len() == mesh.vertex_count() && rings.centres.len() == mesh.face_count(), "ring depths");
    topology::predicted_vertices(mesh, split, rates, Some(rings))
}

/// A vertex of [`FlatMesh::vertices`]: `px py pz nx ny nz` in f32.
#[inline]
pub(crate) fn flat_vertex(p: DVec3, n: DVec3) -> [f32; 6] {
    [p.x as f32, p.y as f32, p.z as f32, n.x as f32, n.y as f32, n.z as f32]
}

/// The topology's builder, kept across calls: the split, whether quads are listed, and the
/// builder's buffers (the mesh is the evaluator's level 0, not a copy: a copy of a large input
/// was a tenth of the peak memory).
#[derive(Debug)]
struct TopologyBuilder {
    triangle: bool,
    quads: bool,
    /// Per edge, whether it is a seam of a carried channel (cut as a border; empty: none).
    seams: Vec<bool>,
    buffers: BuilderBuffers,
}

impl TopologyBuilder {
    /// The topology of `mesh` (level 0) at `rates` (checked) with `rings` into `out` (its
    /// allocations reused).
    fn build(
        &mut self,
        mesh: &Mesh,
        domains: &[PackedDomain],
        rates: &[u32],
        rings: Option<&RingDepths>,
        out: &mut Topology,
    ) {
        let buffers = std::mem::take(&mut self.buffers);
        let mut builder = Builder::with_buffers(mesh, &self.seams, self.triangle, self.quads, buffers);
        builder.build(domains, rates, rings, out);
        self.buffers = builder.into_buffers();
    }
}
