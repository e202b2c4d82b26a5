//! [`MeshError`]: one variant per rule a polygon soup can break.

use crate::{FaceId, VertexId};

/// Why a [`PolygonSoup`](crate::PolygonSoup) does not make a [`Mesh`](crate::Mesh).
///
/// Each variant is one rule and names the face, vertex or edge that breaks it, so that readers
/// (which know file lines) can point at the place in the file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A face lists fewer than three vertices.
    #[error("{face} has {count} vertices; a face needs at least 3")]
    TooFewVertices {
        /// The face.
        face: FaceId,
        /// How many vertices it lists.
        count: usize,
    },
    /// A face lists the same vertex twice (a degenerate face: OpenSubdiv's `quadpole` shapes,
    /// quads with a collapsed edge). Kept as our rule, not refined as OpenSubdiv does: a
    /// repeated vertex makes a zero-length edge (listed one after the other) or a face that
    /// touches itself, which OpenSubdiv tags non-manifold and sharpens; the limit is then not a
    /// 2-manifold there.
    #[error(
        "{face} lists {vertex} twice; a face's vertices must be distinct: a repeated vertex makes a zero-length edge \
         or a face touching itself, which OpenSubdiv tags non-manifold and sharpens, so the limit is not a surface \
         there; list the corner once (a quad with a collapsed edge is a triangle)"
    )]
    RepeatedVertex {
        /// The face.
        face: FaceId,
        /// The repeated vertex.
        vertex: VertexId,
    },
    /// A face refers to a vertex that does not exist.
    #[error("{face} refers to vertex {index}, but the mesh has {vertex_count} vertices (0-based)")]
    IndexOutOfRange {
        /// The face.
        face: FaceId,
        /// The offending 0-based index.
        index: u32,
        /// How many vertices there are.
        vertex_count: usize,
    },
    /// A vertex position has a NaN or infinite coordinate.
    #[error("{vertex} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFiniteCoordinate {
        /// The vertex.
        vertex: VertexId,
        /// Its x coordinate.
        x: f64,
        /// Its y coordinate.
        y: f64,
        /// Its z coordinate.
        z: f64,
    },
    /// A vertex coordinate larger in magnitude than [`MAX_COORDINATE`](crate::MAX_COORDINATE),
    /// whose refinement and normals would overflow f64.
    #[error(
        "{vertex} has a coordinate too large for subdivision ({x}, {y}, {z}): magnitudes above 2^500 (3.3e150) \
         overflow f64 in refinement and normals; scale the mesh down"
    )]
    CoordinateTooLarge {
        /// The vertex.
        vertex: VertexId,
        /// Its x coordinate.
        x: f64,
        /// Its y coordinate.
        y: f64,
        /// Its z coordinate.
        z: f64,
    },
    /// Three or more faces share one edge. Kept as our rule, not refined as OpenSubdiv does:
    /// OpenSubdiv makes such an edge infinitely sharp, so that the faces' sheets all end on
    /// one crease curve — a limit that is not a 2-manifold (no point of the curve has a disc or
    /// half-disc around it, nor one normal), which no patch, chart or tessellation of ours
    /// describes.
    #[error(
        "non-manifold edge {a}-{b}: {face_count} faces share it (first {face}); an edge may have at most 2: the \
         limit would not be a surface there (OpenSubdiv makes the edge infinitely sharp, so {face_count} sheets end \
         on one crease curve, with no single normal); split the edge or the mesh into pieces, or build it with its sheets \
         split (`--split-sheets`)"
    )]
    NonManifoldEdge {
        /// One end of the edge.
        a: VertexId,
        /// The other end.
        b: VertexId,
        /// The first face (lowest id) on the edge.
        face: FaceId,
        /// How many faces share the edge.
        face_count: usize,
    },
    /// The faces around a vertex form more than one fan (for example two cones touching at
    /// their tips, a "bow-tie"). Kept as our rule, not refined as OpenSubdiv does: OpenSubdiv
    /// makes such a vertex a corner that every fan interpolates, so the limit surfaces touch
    /// at one point, which is not a 2-manifold there.
    #[error(
        "non-manifold {vertex}: its faces form {fans} separate fans; they must form one: the limit would not be a \
         surface there (OpenSubdiv makes the vertex a corner of every fan, {fans} surfaces touching at one point); \
         give each fan its own copy of the vertex, or build the mesh with its sheets split (`--split-sheets`)"
    )]
    NonManifoldVertex {
        /// The vertex.
        vertex: VertexId,
        /// How many fans (at least 2).
        fans: usize,
    },
    /// Two faces traverse their shared edge in the same direction.
    #[error(
        "inconsistent orientation: {face} and {other} both run from {a} to {b}; neighbouring faces must traverse a shared edge in opposite directions (build with `orient` to repair)"
    )]
    InconsistentOrientation {
        /// The first face.
        face: FaceId,
        /// The second face.
        other: FaceId,
        /// Where the shared edge starts in both faces.
        a: VertexId,
        /// Where it ends in both faces.
        b: VertexId,
    },
    /// Orientation repair was asked for, but a component is non-orientable (a Möbius strip).
    #[error(
        "the component of {face} is not orientable (a Möbius strip or similar); no orientation repair can make its faces consistent"
    )]
    NonOrientable {
        /// A face of the non-orientable component.
        face: FaceId,
    },
    /// A crease tag names two vertices that share no edge.
    #[error("crease tag {index} names {a} and {b}, which share no edge")]
    CreaseNotAnEdge {
        /// Position of the tag in [`Tags::creases`](crate::Tags::creases).
        index: usize,
        /// One vertex.
        a: VertexId,
        /// The other vertex.
        b: VertexId,
    },
    /// A tag refers to a vertex that does not exist.
    #[error("{tag} tag {index} refers to vertex {vertex}, but the mesh has {vertex_count} vertices (0-based)")]
    TagVertexOutOfRange {
        /// `"crease"` or `"corner"`.
        tag: &'static str,
        /// Position of the tag in its list.
        index: usize,
        /// The offending vertex index.
        vertex: u32,
        /// How many vertices there are.
        vertex_count: usize,
    },
    /// A hole tag refers to a face that does not exist.
    #[error("hole tag {index} refers to face {face}, but the mesh has {face_count} faces (0-based)")]
    HoleOutOfRange {
        /// Position of the tag in [`Tags::holes`](crate::Tags::holes).
        index: usize,
        /// The offending face index.
        face: u32,
        /// How many faces there are.
        face_count: usize,
    },
    /// A crease or corner sharpness is negative or NaN.
    #[error("{tag} tag {index} has sharpness {sharpness}; sharpness must be a number >= 0")]
    InvalidSharpness {
        /// `"crease"` or `"corner"`.
        tag: &'static str,
        /// Position of the tag in its list.
        index: usize,
        /// The offending value.
        sharpness: f64,
    },
    /// The soup has more vertices or face corners than 32-bit ids can address.
    #[error("too many {what}: {count} (at most {max})")]
    TooLarge {
        /// `"vertices"` or `"face corners"`.
        what: &'static str,
        /// How many there are.
        count: usize,
        /// The most supported.
        max: usize,
    },
    /// A face-varying channel whose shape does not fit the soup: values that are not whole
    /// `dimension`-tuples, or not one value index per face corner.
    #[error("channel {channel:?}: {rule}")]
    ChannelShape {
        /// The channel's name.
        channel: String,
        /// The rule, with the counts.
        rule: String,
    },
    /// A face corner's channel index names no value.
    #[error(
        "channel {channel:?}: corner {corner} of {face} refers to value {index}, but the channel has {value_count}"
    )]
    ChannelIndexOutOfRange {
        /// The channel's name.
        channel: String,
        /// The face.
        face: FaceId,
        /// The corner of the face (0-based, in the face's order).
        corner: usize,
        /// The offending 0-based value index.
        index: u32,
        /// How many values the channel has.
        value_count: usize,
    },
    /// A channel value with a NaN or infinite component.
    #[error("channel {channel:?}: value {value} has a non-finite component")]
    ChannelNonFinite {
        /// The channel's name.
        channel: String,
        /// The value (0-based).
        value: usize,
    },
}

impl MeshError {
    /// The face the error is about, when it is about one face (readers map it to a file line).
    pub fn face(&self) -> Option<FaceId> {
        match *self {
            Self::TooFewVertices { face, .. }
            | Self::RepeatedVertex { face, .. }
            | Self::IndexOutOfRange { face, .. }
            | Self::NonManifoldEdge { face, .. }
            | Self::InconsistentOrientation { face, .. }
            | Self::NonOrientable { face }
            | Self::ChannelIndexOutOfRange { face, .. } => Some(face),
            _ => None,
        }
    }

    /// The vertex the error is about, when it is about one vertex.
    pub fn vertex(&self) -> Option<VertexId> {
        match *self {
            Self::NonFiniteCoordinate { vertex, .. }
            | Self::CoordinateTooLarge { vertex, .. }
            | Self::NonManifoldVertex { vertex, .. } => Some(vertex),
            _ => None,
        }
    }

    /// A short stable name of the rule, e.g. `"non-manifold-edge"`, for reports and JSON.
    pub fn rule(&self) -> &'static str {
        match self {
            Self::TooFewVertices { .. } => "too-few-vertices",
            Self::RepeatedVertex { .. } => "repeated-vertex",
            Self::IndexOutOfRange { .. } => "index-out-of-range",
            Self::NonFiniteCoordinate { .. } => "non-finite-coordinate",
            Self::CoordinateTooLarge { .. } => "coordinate-too-large",
            Self::NonManifoldEdge { .. } => "non-manifold-edge",
            Self::NonManifoldVertex { .. } => "non-manifold-vertex",
            Self::InconsistentOrientation { .. } => "inconsistent-orientation",
            Self::NonOrientable { .. } => "non-orientable",
            Self::CreaseNotAnEdge { .. } => "crease-not-an-edge",
            Self::TagVertexOutOfRange { .. } => "tag-vertex-out-of-range",
            Self::HoleOutOfRange { .. } => "hole-out-of-range",
            Self::InvalidSharpness { .. } => "invalid-sharpness",
            Self::TooLarge { .. } => "too-large",
            Self::ChannelShape { .. } => "channel-shape",
            Self::ChannelIndexOutOfRange { .. } => "channel-index-out-of-range",
            Self::ChannelNonFinite { .. } => "channel-non-finite",
        }
    }
}
