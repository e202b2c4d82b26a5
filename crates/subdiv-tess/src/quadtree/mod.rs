//! Error-driven quadtree tessellation of Catmull-Clark and Loop surfaces (paper 002 §2, §5).
//!
//! Each input face is a quadtree root (an N-gon: one root per `Bfr` quad sub-face). A node is a
//! dyadic square of its root's domain and holds the surface over it as one of three *pieces*:
//! a face of a refinement level that has no patch yet ([`PatchLevels`] `Children`: flat when
//! the hull of its ring is small, where the rules between the levels are convex combinations,
//! as semi-sharp features' are; else split), the control points of the extraordinary corner's sub-patch (flat when their hull is
//! small, [`flatness::extraordinary_is_flat`]), or a bicubic Bézier patch
//! ([`flatness::regular_is_flat`]). Children come from the sub-patch matrices (exact
//! subdivision) and de Casteljau. Nodes split at their midpoints until flat.
//!
//! Every leaf corner is a parameter point with one **global vertex id** (a mesh vertex, a
//! dyadic point of a mesh edge counted from its lower-numbered vertex, a point of an N-gon's
//! spoke or its centre, or a point inside a face), so neighbouring faces and sub-faces share
//! their vertices. A leaf's polygon lists its corners and, by **polyline replacement**, every
//! vertex a finer neighbour put on its edges: an edge's midpoint is a vertex iff the node of the
//! same size across the edge was split (its children all have it as a corner), so a bisection
//! that stops at the first missing midpoint finds them all. Polygons therefore share their edges
//! exactly: no T-junctions, no cracks. Triangles are fans around the leaf's centre point, the
//! triangulation [`flatness`] bounds.
//!
//! Under a triangle split (Loop) the tree is one of triangles: a root is a triangle face, a node
//! a sub-triangle with four children in the engine's order (the middle one turned half a turn),
//! its polynomial pieces quartic Bézier triangles ([`Quartic`]); its fan's apex is the centroid,
//! an integer point because triangle roots count in thirds ([`Root::full`]).

mod build;
mod channels;
mod pieces;
mod predict;
mod vertices;

use std::sync::Arc;
use std::sync::atomic::AtomicUsize;

use glam::DVec3;
use hashbrown::HashMap;
use subdiv_mesh::{FaceId, HalfEdgeId, Mesh};
use subdiv_schemes::{ChildDomain, PatchMatrices, Scheme, Split};
use subdiv_stencil::{Dyadic, FaceDomain, Layout, PatchFrame, PatchLevels, Resolved, StencilEvaluator};

use self::build::Budget;
use self::channels::{ChannelEntries, Channels};
use self::pieces::*;
pub(crate) use self::pieces::{check_bicubic, regular_grid};
use self::vertices::{Ring, bfr};
use crate::Parallelism;
use crate::bezier::Bicubic;
use crate::flatness::Tolerance;
use crate::quartic::{self, Quartic};
use crate::{SurfaceParameter, TessCounts, TessError, TessMesh, TessSink, TessTriangle, TessVertex};

/// What the quadtree (and the error bounds of `--tolerance`, which are its) refuses on a dual
/// split's boundary face: its pieces stretch across it, where the tree splits a node in
/// quarters and bounds each quarter by one patch.
pub(crate) const DUAL_BOUNDARY: &str =
    "error bounds over a dual split's boundary face (its pieces stretch across it; `--rate` takes it)";

/// Bits of the fixed denominator of root coordinates: a node of depth `d` has corners at
/// multiples of `2^(FULL_BITS − d)`.
const FULL_BITS: u32 = 40;
/// `2^FULL_BITS`: the root's side.
const FULL: i64 = 1 << FULL_BITS;
/// The largest [`QuadtreeOptions::max_depth`] accepted (sub-face coordinates halve once more).
pub const DEPTH_LIMIT: u32 = 30;

/// Options of [`QuadtreeTessellator::tessellate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadtreeOptions {
    /// The flatness every output triangle meets. Default: `Relative(1e-3)`.
    pub tolerance: Tolerance,
    /// A screen-space error bound instead of the tolerance: each piece flat to its own `ε`,
    /// at most so many pixels on the screen ([`ScreenError`](crate::rates::ScreenError)).
    /// Default: `None` (the tolerance).
    pub screen: Option<crate::rates::ScreenError>,
    /// The deepest level a node may reach, counted from the input face (an N-gon's sub-faces
    /// are level 1); at most [`DEPTH_LIMIT`]. Default: 24 (leaves next to extraordinary vertices
    /// go deep: the parametric distance there shrinks only like λ^d).
    pub max_depth: u32,
    /// The most polygons the output may have. Default: 20 million.
    pub max_polygons: usize,
    /// Whether the roots' leaves and the vertices are found on rayon's threads (the output is
    /// the same either way). Default: [`Parallelism::Rayon`].
    pub parallelism: Parallelism,
}

impl QuadtreeOptions {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        tolerance: Tolerance::Relative(1e-3),
        screen: None,
        max_depth: 24,
        max_polygons: 20_000_000,
        parallelism: Parallelism::DEFAULT,
    };

    /// These options with [`tolerance`](Self::tolerance).
    #[must_use]
    pub const fn with_tolerance(self, tolerance: Tolerance) -> Self {
        Self { tolerance, ..self }
    }

    /// These options with [`screen`](Self::screen).
    #[must_use]
    pub const fn with_screen(self, screen: Option<crate::rates::ScreenError>) -> Self {
        Self { screen, ..self }
    }

    /// These options with [`max_depth`](Self::max_depth).
    #[must_use]
    pub const fn with_max_depth(self, max_depth: u32) -> Self {
        Self { max_depth, ..self }
    }

    /// These options with [`max_polygons`](Self::max_polygons).
    #[must_use]
    pub const fn with_max_polygons(self, max_polygons: usize) -> Self {
        Self { max_polygons, ..self }
    }

    /// These options with [`parallelism`](Self::parallelism).
    #[must_use]
    pub const fn with_parallelism(self, parallelism: Parallelism) -> Self {
        Self { parallelism, ..self }
    }
}

impl Default for QuadtreeOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A quadtree root: an input face, or one quad sub-face of an N-gon.
#[derive(Clone, Copy, Debug)]
struct Root {
    face: FaceId,
    /// `(sub-face, size, columns)` of an N-gon.
    sub: Option<(usize, usize, usize)>,
    /// Whether the root is a triangle (`u, v ≥ 0, u + v ≤ 1`) of a triangle split (Loop), whose
    /// nodes are triangles split in four.
    triangle: bool,
}

impl Root {
    /// The depth of the root counted from its input face.
    fn depth(self) -> u32 {
        u32::from(self.sub.is_some())
    }

    /// The root's side in root coordinates: [`FULL`], or `3 · FULL` for a triangle, so that its
    /// nodes' centroids are integers too.
    fn full(self) -> i64 {
        if self.triangle { 3 * FULL } else { FULL }
    }

    /// The children of a node, in the engine's order (`subdiv_schemes::ChildDomain`).
    fn child_domains(self) -> &'static [ChildDomain] {
        ChildDomain::of_face(if self.triangle { 3 } else { 4 })
    }
}

/// A leaf: the square `[x, x + h] × [y, y + h]` of its root (`h = full >> depth`, coordinates
/// over [`Root::full`]); in a triangle root the triangle `(x, y) + σ h (s, t)`, `s, t ≥ 0,
/// s + t ≤ 1`, with `σ = −1` when `flipped` (a middle child, turned half a turn).
#[derive(Clone, Copy, Debug)]
struct Leaf {
    depth: u32,
    x: i64,
    y: i64,
    /// Whether its piece is the extraordinary corner's.
    extraordinary: bool,
    /// Whether the node is a triangle turned half a turn.
    flipped: bool,
}

impl Leaf {
    /// The root's node at the top.
    const ROOT: Self = Self { depth: 0, x: 0, y: 0, extraordinary: false, flipped: false };

    /// The node's corners, counter-clockwise (the first `n`, `n` 3 or 4), and its centre (the
    /// apex of its fan).
    fn corners(&self, root: Root) -> ([(i64, i64); 4], usize, (i64, i64)) {
        let h = root.full() >> self.depth;
        let (x, y) = (self.x, self.y);
        if root.triangle {
            let g = if self.flipped { -h } else { h };
            ([(x, y), (x + g, y), (x, y + g), (x, y)], 3, (x + g / 3, y + g / 3))
        } else {
            ([(x, y), (x + h, y), (x + h, y + h), (x, y + h)], 4, (x + h / 2, y + h / 2))
        }
    }

    /// The child `domain` of the node.
    fn child(&self, root: Root, domain: ChildDomain) -> Self {
        let h = root.full() >> (self.depth + 1);
        let g = if self.flipped { -h } else { h };
        Self {
            depth: self.depth + 1,
            x: self.x + i64::from(domain.offset[0]) * g,
            y: self.y + i64::from(domain.offset[1]) * g,
            extraordinary: false,
            flipped: self.flipped != domain.flipped,
        }
    }
}

/// The extraordinary pieces of one root that its leaves were split from, by node `(depth, x,
/// y)`: the vertices' evaluation descends through them instead of applying the dense sub-patch
/// matrices again per vertex (at a valence-360 pole that was 86 % of the time).
type Corners = HashMap<(u32, i64, i64), Piece>;

/// A parameter point of the input mesh, canonical: equal points have equal keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum VertexKey {
    /// A vertex of the mesh.
    Vertex(u32),
    /// A point of a mesh edge at `t / FULL` from its lower-numbered vertex.
    Edge { edge: u32, t: i64 },
    /// A point of an N-gon's spoke `s` (from the midpoint of its side `s` to its centre).
    Spoke { face: u32, spoke: u32, t: i64 },
    /// An N-gon's centre.
    Centre(u32),
    /// A point inside a face or sub-face.
    Inner { face: u32, sub: u32, x: i64, y: i64 },
}

/// The quadtree tessellator of one mesh: the mesh's patches, prepared once and reused by every
/// [`tessellate`](Self::tessellate) call.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::{QuadtreeTessellator, QuadtreeOptions, Tolerance};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let tess = QuadtreeTessellator::new(Builtin::CatmullClark.scheme(), &cube)?;
/// let out = tess.tessellate(&QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-2)))?;
/// // Closed and watertight: V − E + F of the triangles is the cube's Euler characteristic.
/// let edges = out.triangles.len() * 3 / 2;
/// assert_eq!(out.positions.len() as i64 - edges as i64 + out.triangles.len() as i64, 2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct QuadtreeTessellator {
    levels: PatchLevels,
    /// Whether every refinement stencil between the levels is a convex combination (the
    /// built-in schemes' rules, semi-sharp blends included), so that a level's face without a
    /// patch yet lies in the hull of its ring ([`Self::face_ring`]).
    convex_levels: bool,
    shapes: HashMap<ShapeKey, ShapeKind>,
    roots: Vec<Root>,
    /// Per input face, its corners' half-edges.
    corners: Vec<Vec<HalfEdgeId>>,
    diagonal: f64,
    /// The face-varying channels carried ([`with_channels`](Self::with_channels)); none by
    /// default.
    channels: Channels,
    /// The exact evaluator of a non-polynomial scheme's surface (where some shape is
    /// [`ShapeKind::Linear`]), which evaluates the vertices of its pieces.
    limit: Option<subdiv_stencil::LimitEvaluator>,
    /// [`tessellate_into`](Self::tessellate_into)'s buffers, kept between calls.
    scratch: Scratch,
}

/// The buffers of one tessellation that do not depend on its output type.
#[derive(Debug, Default)]
struct Scratch {
    /// The global id of every parameter point.
    ids: HashMap<VertexKey, u32>,
    /// Per vertex, the root and root point that made it.
    creators: Vec<(usize, i64, i64)>,
    /// Per leaf, in root and leaf order, its centre's vertex.
    centres: Vec<u32>,
}

impl std::fmt::Debug for QuadtreeTessellator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("QuadtreeTessellator")
            .field("roots", &self.roots.len())
            .field("shapes", &self.shapes.len())
            .finish()
    }
}

/// What [`QuadtreeTessellator::face_curvature`] bounds: a face's second derivatives away from its
/// extraordinary corners, and the size of the surface next to them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceCurvature {
    /// An upper bound of `‖S_uu‖ + ‖S_uv‖ + ‖S_vv‖` over the face less the squares of side
    /// `2^−corner_depth` at its extraordinary corners, in units where the face's sides are 1
    /// long (an N-gon's sub-faces are ½ wide, as they meet their neighbours). It bounds
    /// `‖D²S[d, d]‖` for every unit direction `d`. Under a triangle split, the bound of
    /// `‖D²S[d, d]‖` for unit `d` of the *equilateral* chart (each face an equilateral triangle of
    /// side 1, so that two faces across an edge form one flat chart): `2 λ_max` of the matrix
    /// `[[A, B], [B, C]]` of the bounds of `‖S_uu‖, ‖S_uv‖, ‖S_vv‖` (the map from that chart to
    /// `(u, v)` has norm `√2`).
    pub second: f64,
    /// The largest diameter of the control-point hull of the pieces at the face's
    /// extraordinary corners at that depth (0 without such corners): the surface within
    /// `2^−corner_depth` of such a corner lies in the hull (convex sub-patch matrices).
    pub corner_hull: f64,
}

/// Statistics of one tessellation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QuadtreeStats {
    /// The deepest leaf, counted from its input face.
    pub max_depth: u32,
    /// The deepest leaf away from extraordinary corners, counted from its input face: the
    /// depth the polynomial pieces need.
    pub max_regular_depth: u32,
    /// Leaves at an extraordinary corner.
    pub extraordinary_leaves: usize,
}

impl QuadtreeTessellator {
    /// Prepares `mesh` under `scheme`, whose patches the bounds hold for (checked on its
    /// matrices: every patch away from an extraordinary corner is a bicubic, a quartic triangle,
    /// or convex combinations that reproduce linear functions, every sub-patch matrix at one a
    /// convex combination): Catmull-Clark, with its creases, corners and semi-sharp features,
    /// bilinear, and Loop likewise, `sw-quad`, and the dual splits (Doo-Sabin, mid-edge: their
    /// patches around face corners); closed and open meshes and holes (a
    /// border's pieces are bicubics, or convex sub-patches at an extraordinary border vertex, as
    /// inside; a face without a surface has no root, so its neighbours end at it as at a
    /// boundary).
    ///
    /// # Errors
    /// [`TessError::Scheme`] for √3 (ternary patches) or a scheme whose patches are not
    /// as above (Butterfly's, Kobbelt's: not convex); as [`PatchLevels::descending`].
    pub fn new(scheme: &Scheme, mesh: &Mesh) -> Result<Self, TessError> {
        if scheme.split() == Split::Sqrt3 {
            return Err(TessError::Scheme {
                scheme: scheme.name().to_string(),
                reason: "the quadtree splits a node in four, and √3's patches split in nine (a ternary split); \
                         its surface tessellates with the dual method's rates"
                    .into(),
            });
        }
        // Semi-sharp features spent by refinement: every piece bicubic or extraordinary.
        let levels = PatchLevels::descending(scheme, mesh, &subdiv_schemes::RefineOptions::DEFAULT)?;
        let mut roots = Vec::new();
        // A face without a surface (a hole, or a boundary face without boundary interpolation)
        // has no root: its neighbours end at their edges, as at a boundary.
        for face in mesh.face_ids() {
            if !levels.has_surface(face)? {
                continue;
            }
            match levels.domain(face)? {
                FaceDomain::SubFaces { size, columns } => {
                    roots.extend((0..size).map(|s| Root { face, sub: Some((s, size, columns)), triangle: false }));
                }
                domain => roots.push(Root { face, sub: None, triangle: domain == FaceDomain::Triangle }),
            }
        }
        let corners = mesh.face_ids().map(|f| mesh.face_half_edges(f).collect()).collect();
        let diagonal = mesh.bounding_box().map_or(0.0, |(lo, hi)| lo.distance(hi));
        // Every row non-negative, summing to 1 (checked, not assumed: a scheme file's rules may
        // not be).
        let convex_levels = levels.stencils().iter().all(|stencils| {
            (0..stencils.child_count()).all(|c| is_convex_combination(stencils.row(c).map(|(_, w)| w)))
        });
        let mut tess = Self {
            levels,
            convex_levels,
            shapes: HashMap::new(),
            roots,
            corners,
            diagonal,
            channels: Channels::default(),
            limit: None,
            scratch: Scratch::default(),
        };
        tess.classify_shapes(scheme)?;
        if tess.shapes.values().any(|k| matches!(k, ShapeKind::Linear { .. })) {
            tess.limit =
                Some(subdiv_stencil::LimitEvaluator::new(scheme, mesh, &subdiv_schemes::RefineOptions::DEFAULT)?);
        }
        Ok(tess)
    }

    /// The tessellator carrying `mesh`'s face-varying channels (texture coordinates; `mesh` is
    /// the mesh it was made for) in face-varying mode `mode` (`None`: the mesh's tag, else
    /// `all`): every output vertex gets
    /// their exact values at its parameter, and a vertex on a seam is split into one entry per
    /// side (the sinks' extra entries, as an infinitely sharp crease splits normals in the dual
    /// tessellator), so the values never blend across a seam.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::{QuadtreeOptions, QuadtreeTessellator, Tolerance};
    ///
    /// let cube = Mesh::build(shapes::face_charts(shapes::cube()))?; // one uv chart per face
    /// let cc = Builtin::CatmullClark.scheme();
    /// let tess = QuadtreeTessellator::new(cc, &cube)?.with_channels(cc, &cube, None)?;
    /// let out = tess.tessellate(&QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-2)))?;
    /// assert_eq!(out.channels.names, ["uv"]);
    /// // Every vertex on a cube edge is split: one entry per side of the seam.
    /// assert!(!out.normal_vertices.is_empty());
    /// assert_eq!(out.channels.values.len(), 2 * (out.positions.len() + out.normal_vertices.len()));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// [`TessError::Scheme`] for a scheme without face-varying rules (a mesh with channels);
    /// [`TessError::Surface`] if a channel's surface has no patches; [`TessError::Internal`]
    /// for a mesh of another topology than the tessellator's.
    pub fn with_channels(
        mut self,
        scheme: &Scheme,
        mesh: &Mesh,
        mode: Option<subdiv_mesh::FaceVaryingInterpolation>,
    ) -> Result<Self, TessError> {
        let own = self.levels.mesh(0);
        if (mesh.face_count(), mesh.edge_count(), mesh.vertex_count())
            != (own.face_count(), own.edge_count(), own.vertex_count())
        {
            return Err(TessError::Internal("channels of another mesh than the tessellator's".into()));
        }
        self.channels = Channels::new(scheme, mesh, mode)?;
        Ok(self)
    }

    /// The names of the channels carried ([`with_channels`](Self::with_channels)), in the
    /// mesh's order, and their numbers of components.
    pub fn channels(&self) -> (&[String], &[usize]) {
        (&self.channels.names, &self.channels.dimensions)
    }

    /// Whether the mesh's faces are a triangle split's triangles (Loop), whose
    /// [`FaceCurvature`] is in equilateral units.
    pub fn triangle_split(&self) -> bool {
        self.roots.iter().any(|r| r.triangle)
    }

    /// The diagonal of the control mesh's bounding box (what relative tolerances scale).
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Finds every patch shape the roots reach and checks the properties the bounds rest on
    /// (refusing a dual split's boundary face, [`DUAL_BOUNDARY`]).
    fn classify_shapes(&mut self, scheme: &Scheme) -> Result<(), TessError> {
        let mut stack: Vec<(usize, FaceId)> = Vec::new();
        for root in &self.roots {
            match root.sub {
                Some((s, ..)) => {
                    if let Some(Resolved::Children { children, .. }) = self.levels.resolve(0, root.face) {
                        stack.push((1, FaceId::new((children.start + s) as u32)));
                    }
                }
                None => stack.push((0, root.face)),
            }
        }
        let bad = |reason: String| TessError::Scheme { scheme: scheme.name().to_string(), reason };
        while let Some((level, face)) = stack.pop() {
            match self.levels.resolve(level, face) {
                Some(Resolved::Children { layout: Layout::DualBoundaryQuad { .. }, .. }) => {
                    return Err(TessError::Unsupported { feature: DUAL_BOUNDARY, element: format!("{face}") });
                }
                Some(Resolved::Children { children, .. }) => {
                    stack.extend(children.map(|c| (level + 1, FaceId::new(c as u32))));
                }
                Some(Resolved::Patch { patch, .. }) => {
                    let key = (Arc::as_ptr(&patch.matrices) as usize, patch.shape);
                    if !self.shapes.contains_key(&key) {
                        classify(&patch.matrices, &mut self.shapes).map_err(bad)?;
                    }
                }
                Some(Resolved::Hole) => {
                    return Err(TessError::Unsupported { feature: "holes", element: format!("{face}") });
                }
                None => return Err(TessError::Internal(format!("level {level} {face} was not prepared"))),
            }
        }
        Ok(())
    }

    /// Whether `face` has a surface (not a hole, nor a boundary face that boundary
    /// interpolation `none` leaves out), so that it is tessellated.
    pub fn has_surface(&self, face: FaceId) -> bool {
        let first = self.roots.partition_point(|r| r.face < face);
        self.roots.get(first).is_some_and(|r| r.face == face)
    }

    /// The vertices of `face` at which its surface is an extraordinary piece (a sub-patch with
    /// an extraordinary corner there, not a polynomial), in corner order; none for a hole.
    ///
    /// # Errors
    /// [`TessError::Internal`] for a face whose pieces are missing.
    pub fn extraordinary_corners(&self, face: FaceId) -> Result<Vec<subdiv_mesh::VertexId>, TessError> {
        let first = self.roots.partition_point(|r| r.face < face);
        let roots = &self.roots[first..self.roots.partition_point(|r| r.face <= face)];
        let mesh = self.levels.mesh(0);
        let mut out = Vec::new();
        for &root in roots {
            // A root's corner (0, 0) is its face's corner (an N-gon's sub-face `s`: corner `s`);
            // a quad's other corners too.
            let (f, n, _) = Leaf::ROOT.corners(root);
            let corners: Vec<(usize, (i64, i64))> = match root.sub {
                Some((s, ..)) => vec![(s, (0, 0))],
                None => f[..n].iter().copied().enumerate().collect(),
            };
            for (k, corner) in corners {
                if self.corner_is_extraordinary(root, corner)? {
                    out.push(mesh.origin(self.corners[face.index()][k]));
                }
            }
        }
        Ok(out)
    }

    /// Whether the pieces of `root` at its corner `(x, y)` end in an extraordinary piece whose
    /// extraordinary point is that corner.
    fn corner_is_extraordinary(&self, root: Root, (x, y): (i64, i64)) -> Result<bool, TessError> {
        let mut piece = self.root_piece(root)?;
        let full = root.full();
        // The child at that corner: a quad's quarter, a triangle's corner child.
        let domain = ChildDomain::binary([u8::from(x == full), u8::from(y == full)], false);
        // A piece of depth d keeps its corner at the root's: children at the same corner.
        for _ in 0..=DEPTH_LIMIT + 40 {
            match &piece {
                Piece::Regular(_) | Piece::Quartic(_) | Piece::Linear { .. } => return Ok(false),
                Piece::Extraordinary { frame, .. } => {
                    let c = frame.to_face(Dyadic::new(0, 0, 1));
                    if (c.u * full, c.v * full) == (x, y) {
                        return Ok(true);
                    }
                }
                Piece::Face { .. } => {}
            }
            piece = self.child(root, &piece, domain)?;
        }
        Err(TessError::Internal(format!("{}: no piece at a corner after {} levels", root.face, DEPTH_LIMIT + 40)))
    }

    /// Bounds of `face`'s surface from its polynomial pieces, for choosing dual-grid rates to a
    /// tolerance ([`crate::rates::ErrorRates`]): see [`FaceCurvature`].
    ///
    /// # Errors
    /// [`TessError::Internal`] for a face the mesh does not have or whose pieces are missing.
    pub fn face_curvature(&self, face: FaceId, corner_depth: u32) -> Result<FaceCurvature, TessError> {
        let first = self.roots.partition_point(|r| r.face < face);
        let roots = &self.roots[first..self.roots.partition_point(|r| r.face <= face)];
        if roots.is_empty() {
            return Err(TessError::Internal(format!("{face} is not a face of the mesh")));
        }
        let mut out = FaceCurvature { second: 0.0, corner_hull: 0.0 };
        for &root in roots {
            self.curvature_walk(root, self.root_piece(root)?, root.depth(), corner_depth, &mut out)?;
        }
        Ok(out)
    }

    /// [`face_curvature`](Self::face_curvature) over `piece`, a node `depth` levels below its
    /// input face.
    fn curvature_walk(
        &self,
        root: Root,
        piece: Piece,
        depth: u32,
        corner_depth: u32,
        out: &mut FaceCurvature,
    ) -> Result<(), TessError> {
        match &piece {
            Piece::Regular(b) => {
                // Derivatives in the input face's units: a node of depth d is 2^−d wide.
                let scale = 4f64.powi(depth as i32);
                out.second = out.second.max(scale * b.second_derivative_bounds().iter().sum::<f64>());
                return Ok(());
            }
            Piece::Extraordinary { points, .. } if depth >= corner_depth => {
                out.corner_hull = out.corner_hull.max(crate::flatness::hull_diameter(points));
                return Ok(());
            }
            Piece::Linear { .. } => {
                return Err(TessError::Unsupported {
                    feature: "dual-grid rates to a tolerance for a non-polynomial scheme (no second-derivative \
                              bound; --method quadtree takes it)",
                    element: format!("{}", root.face),
                });
            }
            Piece::Quartic(q) => {
                let scale = 4f64.powi(depth as i32);
                let [a, b, c] = q.second_derivative_bounds();
                let largest = 0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt();
                out.second = out.second.max(scale * 2.0 * largest);
                return Ok(());
            }
            _ => {}
        }
        for &domain in root.child_domains() {
            self.curvature_walk(root, self.child(root, &piece, domain)?, depth + 1, corner_depth, out)?;
        }
        Ok(())
    }

    /// The polygons of the uniform tessellation at `depth` (counted from the input faces): what
    /// a uniform quadtree that is as deep as the adaptive one's deepest leaf outputs.
    pub fn uniform_polygon_count(&self, depth: u32) -> u64 {
        self.roots.iter().map(|r| 4u64.saturating_pow(depth.saturating_sub(r.depth()))).sum()
    }

    /// The triangles of the uniform tessellation at `depth`: each polygon fanned like a leaf
    /// without hanging vertices, four triangles a square, three a triangle.
    pub fn uniform_triangle_count(&self, depth: u32) -> u64 {
        let fan = |r: &Root| if r.triangle { 3 } else { 4 };
        self.roots.iter().map(|r| fan(r) * 4u64.saturating_pow(depth.saturating_sub(r.depth()))).sum()
    }

    /// Tessellates the surface so that every output triangle is within the tolerance of it
    /// (parametric distance, see [`flatness`]).
    ///
    /// # Errors
    /// [`TessError::Tolerance`], [`TessError::DepthLimit`], [`TessError::TooManyPolygons`].
    pub fn tessellate(&self, options: &QuadtreeOptions) -> Result<TessMesh, TessError> {
        self.tessellate_with_stats(options).map(|(mesh, _)| mesh)
    }

    /// [`tessellate`](Self::tessellate), with statistics.
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate).
    pub fn tessellate_with_stats(&self, options: &QuadtreeOptions) -> Result<(TessMesh, QuadtreeStats), TessError> {
        let mut out = TessMesh::default();
        let stats = self.write(options, &mut Scratch::default(), &mut out)?;
        out.channels.names.clone_from(&self.channels.names);
        out.channels.dimensions.clone_from(&self.channels.dimensions);
        Ok((out, stats))
    }

    /// [`tessellate`](Self::tessellate) into `sink` (see [`TessSink`]): the caller's buffers and
    /// vertex type; polygons (the leaves with their hanging vertices) to sinks that
    /// [want them](TessSink::wants_polygons). The tessellator keeps its intermediate buffers
    /// (the vertex keys' table, the vertices' parameter points and the leaves' centres) for
    /// the next call; [`tessellate`](Self::tessellate) takes `&self` (so that
    /// [`ErrorRates`](crate::rates::ErrorRates), which borrows the tessellator, and threads
    /// can share it) and makes them anew each time.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::{FlatMesh, QuadtreeOptions, QuadtreeTessellator, TessMesh, Tolerance};
    ///
    /// let mesh = Mesh::build(shapes::cube())?;
    /// let mut tess = QuadtreeTessellator::new(Builtin::CatmullClark.scheme(), &mesh)?;
    /// let options = QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-2));
    /// let mut flat = FlatMesh::default();
    /// let stats = tess.tessellate_into(&options, &mut flat)?;
    /// assert!(stats.extraordinary_leaves > 0);
    /// let mut mesh = TessMesh::default();
    /// tess.tessellate_into(&options, &mut mesh)?; // the same buffers again, as `tessellate`'s
    /// assert_eq!(mesh, tess.tessellate(&options)?);
    /// assert_eq!(flat.indices.len(), 3 * mesh.triangles.len());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate); `sink` is then not called.
    pub fn tessellate_into<S: TessSink + ?Sized>(
        &mut self,
        options: &QuadtreeOptions,
        sink: &mut S,
    ) -> Result<QuadtreeStats, TessError> {
        let mut scratch = std::mem::take(&mut self.scratch);
        let done = self.write(options, &mut scratch, sink);
        self.scratch = scratch;
        done
    }

    /// The tessellation into `sink`, with `scratch`'s buffers; `sink` is called only after
    /// everything that may fail.
    fn write<S: TessSink + ?Sized>(
        &self,
        options: &QuadtreeOptions,
        scratch: &mut Scratch,
        sink: &mut S,
    ) -> Result<QuadtreeStats, TessError> {
        let epsilon = options.tolerance.absolute(self.diagonal)?;
        let screen = options.screen.as_ref().map(crate::rates::ScreenError::bound).transpose()?;
        let bound = build::error_bound(screen.as_ref(), epsilon);
        let max_depth = options.max_depth.min(DEPTH_LIMIT);
        let count = AtomicUsize::new(0);
        let parallel = options.parallelism.forks();
        // The budget predicted before the work: a lower bound on the leaves, counted until it
        // passes the limit (see `predict.rs`).
        let needed = self.polygons_at_least(options)?;
        if needed > options.max_polygons {
            return Err(TessError::TooManyPolygons { needed, limit: options.max_polygons, bound });
        }
        let grown: Vec<(Vec<Leaf>, Corners)> = crate::par::try_map(parallel, &self.roots, |&root| {
            let (mut leaves, mut corners) = (Vec::new(), Corners::new());
            let piece = self.root_piece(root)?;
            let max_depth = max_depth.saturating_sub(root.depth());
            let budget = Budget { epsilon, screen, max_depth, count: &count, options };
            self.build(root, piece, Leaf::ROOT, &budget, &mut leaves, &mut corners)?;
            Ok::<_, TessError>((leaves, corners))
        })?;
        let (forest, corner_pieces): (Vec<Vec<Leaf>>, Vec<Corners>) = grown.into_iter().unzip();
        let mut stats = QuadtreeStats::default();
        for (root, leaves) in self.roots.iter().zip(&forest) {
            for leaf in leaves {
                stats.max_depth = stats.max_depth.max(leaf.depth + root.depth());
                if leaf.extraordinary {
                    stats.extraordinary_leaves += 1;
                } else {
                    stats.max_regular_depth = stats.max_regular_depth.max(leaf.depth + root.depth());
                }
            }
        }

        // Global ids, in root and leaf order (deterministic whatever the thread count).
        let Scratch { ids, creators, centres } = scratch;
        ids.clear();
        creators.clear();
        centres.clear();
        for (r, (root, leaves)) in self.roots.iter().zip(&forest).enumerate() {
            for leaf in leaves {
                let (corners, n, centre) = leaf.corners(*root);
                for &(x, y) in &corners[..n] {
                    let key = self.key(*root, x, y);
                    ids.entry(key).or_insert_with(|| {
                        creators.push((r, x, y));
                        (creators.len() - 1) as u32
                    });
                }
                creators.push((r, centre.0, centre.1));
                centres.push((creators.len() - 1) as u32);
            }
        }
        if u32::try_from(creators.len()).is_err() {
            let limit = options.max_polygons;
            return Err(TessError::TooManyPolygons { needed: limit + 1, limit, bound });
        }

        // Every vertex evaluated once, exactly.
        let evaluated: Vec<TessVertex<'_>> = crate::par::try_map(parallel, creators, |&(r, x, y)| {
            let root = self.roots[r];
            let (position, mut normal) = self.eval(root, x, y, Some(&corner_pieces[r]))?;
            if normal == DVec3::ZERO {
                normal = self.fallback_normal(root, x, y)?;
            }
            let (u, v) = bfr(root, x, y);
            Ok::<_, TessError>(TessVertex {
                position,
                normal,
                parameter: SurfaceParameter { face: root.face, u, v },
                channels: &[],
                texcoords: None,
            })
        })?;

        // Polygons with their hanging vertices, and their fans.
        let roots: Vec<(Root, &Vec<Leaf>)> = self.roots.iter().copied().zip(&forest).collect();
        let ids = &*ids;
        let rings: Vec<Vec<Ring>> = crate::par::map(parallel, roots, |(root, leaves)| {
            leaves.iter().map(|leaf| self.ring(root, leaf, ids)).collect()
        });
        let corners: usize = rings.iter().flatten().map(|(ring, _)| ring.len()).sum();
        if u32::try_from(corners).is_err() {
            let limit = options.max_polygons;
            return Err(TessError::TooManyPolygons { needed: limit + 1, limit, bound });
        }

        // Channels: each vertex's values, and the seams' further sides (see `channels.rs`).
        let stride = self.channels.stride();
        let ChannelEntries { own, splits, split_values, ring_entries } =
            self.channel_entries(parallel, &evaluated, &rings, creators)?;
        let uv = self.channels.texcoords();
        let texcoords = |values: &[f64]| uv.map(|s| [values[s], values[s + 1]]);

        let polygons = sink.wants_polygons();
        sink.begin(&TessCounts {
            vertices: evaluated.len(),
            // One normal per vertex; the extra entries are the seams' further sides.
            extra_normals: splits.len(),
            triangles: corners,
            polygons: if polygons { centres.len() } else { 0 },
            polygon_vertices: if polygons { corners } else { 0 },
            channels: stride,
            texcoords: uv.is_some(),
        });
        for (k, vertex) in evaluated.iter().enumerate() {
            let channels = own.get(k * stride..(k + 1) * stride).unwrap_or_default();
            sink.vertex(k as u32, &TessVertex { channels, texcoords: texcoords(channels), ..*vertex });
        }
        for (j, &(id, parameter)) in splits.iter().enumerate() {
            let channels = &split_values[j * stride..(j + 1) * stride];
            let split = TessVertex { parameter, channels, texcoords: texcoords(channels), ..evaluated[id as usize] };
            sink.normal(evaluated.len() as u32 + j as u32, id, &split);
        }
        let (mut triangle, mut leaf_centres) = (0, centres.iter());
        for (r, (root, (root_rings, leaves))) in self.roots.iter().zip(rings.iter().zip(&forest)).enumerate() {
            for (i, ((ring, params), (&centre, leaf))) in
                root_rings.iter().zip(leaf_centres.by_ref().zip(leaves)).enumerate()
            {
                let (_, _, centre_point) = leaf.corners(*root);
                let c = bfr(*root, centre_point.0, centre_point.1);
                let entries = ring_entries.get(r).map_or(ring, |e| &e[i]);
                for k in 0..ring.len() {
                    let l = (k + 1) % ring.len();
                    let (a, b) = (bfr(*root, params[k].0, params[k].1), bfr(*root, params[l].0, params[l].1));
                    sink.triangle(
                        triangle,
                        &TessTriangle {
                            vertices: [centre, ring[k], ring[l]],
                            normals: [centre, entries[k], entries[l]],
                            face: root.face,
                            parameters: [[c.0, c.1], [a.0, a.1], [b.0, b.1]],
                        },
                    );
                    triangle += 1;
                }
            }
        }
        if polygons {
            let mut polygon = 0;
            for (root, root_rings) in self.roots.iter().zip(&rings) {
                for (ring, _) in root_rings {
                    sink.polygon(polygon, ring, root.face);
                    polygon += 1;
                }
            }
        }
        sink.end();
        Ok(stats)
    }
}
