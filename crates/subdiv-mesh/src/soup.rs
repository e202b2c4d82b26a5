//! [`PolygonSoup`]: positions, faces as vertex lists and the authored [`Tags`] — the input of
//! [`Mesh::build`](crate::Mesh::build) and the output of every reader.

use glam::DVec3;

use crate::{Channel, FaceId, VertexId};

/// Polygon soup: positions plus faces given as lists of vertex indices, with the tags authored
/// on them (creases, corners, holes, boundary rules).
///
/// Nothing is checked when a soup is filled; [`Mesh::build`](crate::Mesh::build) and
/// [`validate`](crate::validate) check every rule and name the face or vertex that breaks it.
///
/// ```
/// use subdiv_mesh::PolygonSoup;
/// use glam::DVec3;
///
/// let soup = PolygonSoup::from_indices(
///     vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
///     [[0u32, 1, 2, 3]],
/// );
/// assert_eq!(soup.face_count(), 1);
/// assert_eq!(soup.face(subdiv_mesh::FaceId::new(0)).len(), 4);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PolygonSoup {
    positions: Vec<DVec3>,
    /// `face_offsets[f]..face_offsets[f + 1]` is the range of face `f` in `face_vertices`.
    face_offsets: Vec<u32>,
    face_vertices: Vec<VertexId>,
    /// Creases, corners, holes and boundary rules authored on the soup.
    pub tags: Tags,
    /// Face-varying channels (texture coordinates, …), each with one value index per face
    /// corner; checked by [`Mesh::build`](crate::Mesh::build).
    pub channels: Vec<Channel>,
}

impl Default for PolygonSoup {
    fn default() -> Self {
        Self::new()
    }
}

impl PolygonSoup {
    /// An empty soup.
    pub fn new() -> Self {
        Self {
            positions: Vec::new(),
            face_offsets: vec![0],
            face_vertices: Vec::new(),
            tags: Tags::default(),
            channels: Vec::new(),
        }
    }

    /// An empty soup with room for `vertices` positions, `faces` faces and `corners` face corners.
    pub fn with_capacity(vertices: usize, faces: usize, corners: usize) -> Self {
        let mut face_offsets = Vec::with_capacity(faces + 1);
        face_offsets.push(0);
        Self {
            positions: Vec::with_capacity(vertices),
            face_offsets,
            face_vertices: Vec::with_capacity(corners),
            tags: Tags::default(),
            channels: Vec::new(),
        }
    }

    /// A soup from positions and faces given as 0-based `u32` vertex indices.
    pub fn from_indices<F: AsRef<[u32]>>(positions: Vec<DVec3>, faces: impl IntoIterator<Item = F>) -> Self {
        let mut soup = Self { positions, ..Self::new() };
        for face in faces {
            soup.push_face(face.as_ref().iter().copied().map(VertexId::new));
        }
        soup
    }

    /// Appends a vertex and returns its id.
    pub fn push_vertex(&mut self, position: DVec3) -> VertexId {
        let id = VertexId::new(self.positions.len() as u32);
        self.positions.push(position);
        id
    }

    /// Appends a face (its vertices in order, counter-clockwise seen from outside) and returns
    /// its id. Any size is accepted here; validation reports faces with fewer than 3 vertices.
    pub fn push_face(&mut self, vertices: impl IntoIterator<Item = VertexId>) -> FaceId {
        let id = FaceId::new((self.face_offsets.len() - 1) as u32);
        self.face_vertices.extend(vertices);
        self.face_offsets.push(self.face_vertices.len() as u32);
        id
    }

    /// Number of vertices (positions).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.face_offsets.len() - 1
    }

    /// Number of face corners (the sum of all face sizes).
    pub fn corner_count(&self) -> usize {
        self.face_vertices.len()
    }

    /// The vertex positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// The vertex positions, to move them.
    pub fn positions_mut(&mut self) -> &mut [DVec3] {
        &mut self.positions
    }

    /// The vertices of face `face`, in order.
    ///
    /// # Panics
    /// When `face` is not a face of this soup.
    pub fn face(&self, face: FaceId) -> &[VertexId] {
        let f = face.index();
        &self.face_vertices[self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize]
    }

    /// The faces in order, each as its vertex list.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = &[VertexId]> + '_ {
        self.face_offsets.windows(2).map(|w| &self.face_vertices[w[0] as usize..w[1] as usize])
    }

    /// Reverses the vertex order of `face`, keeping its first vertex first (so a flipped quad
    /// `(v0, v1, v2, v3)` becomes `(v0, v3, v2, v1)`); the channels' corners follow.
    pub fn flip_face(&mut self, face: FaceId) {
        let f = face.index();
        let range = self.face_offsets[f] as usize + 1..self.face_offsets[f + 1] as usize;
        for channel in &mut self.channels {
            channel.reverse_corners(range.clone());
        }
        self.face_vertices[range].reverse();
    }

    /// Every face's corners, in face order, to renumber their vertices.
    pub(crate) fn corners_mut(&mut self) -> &mut [VertexId] {
        &mut self.face_vertices
    }

    /// The flattened face data: `(offsets, vertices)` with `offsets.len() == face_count() + 1`.
    pub fn raw_faces(&self) -> (&[u32], &[VertexId]) {
        (&self.face_offsets, &self.face_vertices)
    }

    /// Splits the soup into its parts: `(positions, offsets, vertices, tags, channels)`.
    pub fn into_parts(self) -> (Vec<DVec3>, Vec<u32>, Vec<VertexId>, Tags, Vec<Channel>) {
        (self.positions, self.face_offsets, self.face_vertices, self.tags, self.channels)
    }
}

/// Tags authored on a mesh, as OpenSubdiv's shape files carry them (`t crease`, `t corner`,
/// `t hole`, `t interpolateboundary`, …). They are data here; the schemes give them meaning.
///
/// Sharpness follows OpenSubdiv: `0` is smooth, values `>= 10` ([`Tags::INFINITELY_SHARP`]) are
/// infinitely sharp, values in between are semi-sharp.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tags {
    /// Sharp edges, each given by its two end vertices (either order).
    pub creases: Vec<CreaseTag>,
    /// Sharp vertices.
    pub corners: Vec<CornerTag>,
    /// Faces that are holes: they stay in the topology but produce no surface.
    pub holes: Vec<FaceId>,
    /// `t interpolateboundary`; `None` when the file does not say.
    pub boundary_interpolation: Option<BoundaryInterpolation>,
    /// `t facevaryinginterpolateboundary`; `None` when the file does not say.
    pub face_varying_interpolation: Option<FaceVaryingInterpolation>,
    /// `t creasemethod`; `None` when the file does not say.
    pub crease_method: Option<CreaseMethod>,
    /// `t smoothtriangles`; `None` when the file does not say.
    pub triangle_subdivision: Option<TriangleSubdivision>,
    /// Tags that are read but not interpreted (for example OpenSubdiv 2's hierarchical edits,
    /// `vertexedit`, `edgeedit`, `faceedit`, which OpenSubdiv 3 does not implement either).
    pub unsupported: Vec<String>,
}

impl Tags {
    /// Sharpness at or above which an edge or vertex is infinitely sharp (OpenSubdiv's
    /// `Sdc::Crease::SHARPNESS_INFINITE`).
    pub const INFINITELY_SHARP: f64 = 10.0;

    /// Whether no tag of any kind is set.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// The class of an edge's or vertex's sharpness: what decides whether its subdivision rules
/// are stationary (the same at every level).
///
/// ```
/// use subdiv_mesh::{Sharpness, Tags};
///
/// assert_eq!(Sharpness::of(0.0), Sharpness::Smooth);
/// assert_eq!(Sharpness::of(2.5), Sharpness::SemiSharp);
/// assert_eq!(Sharpness::of(Tags::INFINITELY_SHARP), Sharpness::Infinite);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sharpness {
    /// Sharpness 0 (or below).
    Smooth,
    /// Infinitely sharp: at least [`Tags::INFINITELY_SHARP`]. Stationary, like smooth.
    Infinite,
    /// Strictly between: sharp for the first levels, then smooth. Not stationary.
    SemiSharp,
}

impl Sharpness {
    /// The class of the sharpness value `s`.
    pub fn of(s: f64) -> Self {
        if s >= Tags::INFINITELY_SHARP {
            Self::Infinite
        } else if s > 0.0 {
            Self::SemiSharp
        } else {
            Self::Smooth
        }
    }
}

/// A sharp edge between two vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CreaseTag {
    /// The edge's end vertices, in either order.
    pub vertices: [VertexId; 2],
    /// Sharpness, `>= 0`.
    pub sharpness: f64,
}

/// A sharp vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CornerTag {
    /// The vertex.
    pub vertex: VertexId,
    /// Sharpness, `>= 0`.
    pub sharpness: f64,
}

/// How a scheme treats boundary edges and vertices (OpenSubdiv's `VtxBoundaryInterpolation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BoundaryInterpolation {
    /// No boundary interpolation: boundary faces produce no surface (`t interpolateboundary 1/0/0 0`).
    None,
    /// Boundary edges are sharp, and so are boundary vertices with one face (`… 1`).
    EdgeAndCorner,
    /// Boundary edges are sharp; corners stay smooth (`… 2`, OpenSubdiv's default).
    EdgeOnly,
}

impl BoundaryInterpolation {
    /// From OpenSubdiv's shape-file code: 0 none, 1 edge-and-corner, 2 edge-only.
    pub fn from_code(code: i64) -> Option<Self> {
        match code {
            0 => Some(Self::None),
            1 => Some(Self::EdgeAndCorner),
            2 => Some(Self::EdgeOnly),
            _ => None,
        }
    }

    /// OpenSubdiv's shape-file code ([`from_code`](Self::from_code)'s inverse), which the
    /// table files use too.
    pub fn code(self) -> u8 {
        match self {
            Self::None => 0,
            Self::EdgeAndCorner => 1,
            Self::EdgeOnly => 2,
        }
    }
}

/// Where face-varying channels (texture coordinates) are linear rather than smooth: OpenSubdiv's
/// `Sdc::Options::FVarLinearInterpolation`, from none (smooth everywhere, seams and channel
/// boundaries refined like creases) to all (linear everywhere, the default of OpenSubdiv and of
/// this library). Only channels are affected, never the positions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaceVaryingInterpolation {
    /// Smooth everywhere; seams and channel boundaries follow the crease rule, their corners
    /// included (`t facevaryinginterpolateboundary 1/0/0 0`).
    None,
    /// As [`None`](Self::None), but a channel corner (a value used by one face only) is sharp
    /// (`… 1`).
    CornersOnly,
    /// As [`CornersOnly`](Self::CornersOnly), and every value of a vertex with more than two
    /// values is sharp; with two, both are when one is disjoint (`… 2`).
    CornersPlus1,
    /// As [`CornersPlus1`](Self::CornersPlus1), and with two values both are sharp when one is
    /// a corner; darts of the channel (a seam that ends inside) are sharp (`… 3`).
    CornersPlus2,
    /// Linear along seams and channel boundaries, smooth inside (`… 4`).
    Boundaries,
    /// Linear everywhere: each refined value interpolates its parent face's values (`… 5`).
    All,
}

impl FaceVaryingInterpolation {
    /// All six, in the order of their codes.
    pub const ALL_MODES: [Self; 6] =
        [Self::None, Self::CornersOnly, Self::CornersPlus1, Self::CornersPlus2, Self::Boundaries, Self::All];

    /// From OpenSubdiv's shape-file code 0..=5.
    pub fn from_code(code: i64) -> Option<Self> {
        usize::try_from(code).ok().and_then(|i| Self::ALL_MODES.get(i).copied())
    }

    /// OpenSubdiv's shape-file code 0..=5.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The name the CLI and the peer harness use: `none`, `corners-only`, `corners-plus1`,
    /// `corners-plus2`, `boundaries`, `all`.
    pub fn name(self) -> &'static str {
        ["none", "corners-only", "corners-plus1", "corners-plus2", "boundaries", "all"][self as usize]
    }
}

/// How semi-sharp creases lose their sharpness from one level to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CreaseMethod {
    /// Sharpness decreases by one per level (`t creasemethod 0/0/1 normal`).
    Uniform,
    /// Chaikin's rule: sharpness is averaged along the crease (`… chaikin`).
    Chaikin,
}

/// How Catmull-Clark treats triangles (OpenSubdiv's `TriangleSubdivision`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TriangleSubdivision {
    /// The ordinary Catmull-Clark rule (`t smoothtriangles 0/0/1 catmark`).
    Catmark,
    /// A modified rule that keeps triangles rounder (`… smooth`).
    Smooth,
}
