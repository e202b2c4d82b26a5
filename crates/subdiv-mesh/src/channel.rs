//! [`Channel`]: face-varying data (texture coordinates, or any other per-corner values) with its
//! own topology over a mesh's faces.

use crate::{EdgeId, FaceId, HalfEdgeId, Mesh, MeshError};

/// A face-varying channel: an array of values of [`dimension`](Self::dimension) components
/// each, and one value index per face corner, in the order of the soup's (and the mesh's) face
/// corners — the mesh's half-edges.
///
/// Faces that share a vertex may use one value there (the channel is continuous across their
/// edge) or different ones (a *seam*: the channel's own topology is cut along that edge). A
/// channel's boundary is the mesh's boundary plus its seams; refinement and evaluation treat it
/// with the channel's own rules (OpenSubdiv's face-varying interpolation modes).
///
/// ```
/// use subdiv_mesh::{Channel, DVec3, FaceId, Mesh, PolygonSoup, VertexId};
///
/// // Two quads side by side whose texture coordinates are cut along the shared edge 1-4.
/// let positions = (0..6).map(|i| DVec3::new(f64::from(i % 3), f64::from(i / 3), 0.0)).collect();
/// let mut soup = PolygonSoup::from_indices(positions, [[0u32, 1, 4, 3], [1, 2, 5, 4]]);
/// let uv = vec![0.0, 0.0, 0.5, 0.0, 0.5, 1.0, 0.0, 1.0, 0.5, 0.0, 1.0, 0.0, 1.0, 1.0, 0.5, 1.0];
/// soup.channels.push(Channel::new("uv", 2, uv, vec![0, 1, 2, 3, 4, 5, 6, 7]));
/// let mesh = Mesh::build(soup)?;
/// let uv = &mesh.channels()[0];
/// let shared = mesh.find_edge(VertexId::new(1), VertexId::new(4)).unwrap();
/// assert!(mesh.is_seam(uv, shared));
/// let second_corner = mesh.face_half_edges(FaceId::new(0)).nth(1).unwrap();
/// assert_eq!(uv.value(uv.corner_value(second_corner)), [0.5, 0.0]);
/// # Ok::<(), subdiv_mesh::MeshError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    name: String,
    dimension: usize,
    values: Vec<f64>,
    indices: Vec<u32>,
}

impl Channel {
    /// The usual name of texture coordinates (OBJ `vt`, glTF `TEXCOORD_0`).
    pub const UV: &'static str = "uv";

    /// A channel named `name` with `values` (flat, [`dimension`](Self::dimension) components per
    /// value) and one index into them per face corner. Nothing is checked here;
    /// [`Mesh::build`] checks the channel against the soup and names what breaks a rule.
    pub fn new(name: impl Into<String>, dimension: usize, values: Vec<f64>, indices: Vec<u32>) -> Self {
        Self { name: name.into(), dimension, values, indices }
    }

    /// The channel's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The number of components of each value (2 for texture coordinates).
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The number of values.
    pub fn value_count(&self) -> usize {
        self.values.len().checked_div(self.dimension).unwrap_or(0)
    }

    /// All values, flat: value `i` is `values()[i * dimension..(i + 1) * dimension]`.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Value `i`.
    ///
    /// # Panics
    /// When `i` is not below [`value_count`](Self::value_count).
    pub fn value(&self, i: u32) -> &[f64] {
        let d = self.dimension;
        &self.values[i as usize * d..(i as usize + 1) * d]
    }

    /// One value index per face corner (per half-edge of the mesh, in its order).
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// The value index of the corner where half-edge `h` starts (corner `mesh.corner(h)` of
    /// `mesh.face(h)`).
    pub fn corner_value(&self, h: HalfEdgeId) -> u32 {
        self.indices[h.index()]
    }

    /// Splits the channel into `(name, dimension, values, indices)`.
    pub fn into_parts(self) -> (String, usize, Vec<f64>, Vec<u32>) {
        (self.name, self.dimension, self.values, self.indices)
    }

    /// Reverses the corners `range` (a face's corners after its first, as
    /// [`PolygonSoup::flip_face`](crate::PolygonSoup::flip_face) reverses its vertices).
    pub(crate) fn reverse_corners(&mut self, range: std::ops::Range<usize>) {
        if let Some(corners) = self.indices.get_mut(range) {
            corners.reverse();
        }
    }

    /// The first rule the channel breaks against a soup of `corners` face corners, whose face
    /// `f` has the corners `offsets[f]..offsets[f + 1]`.
    pub(crate) fn check(&self, offsets: &[u32], corners: usize) -> Option<MeshError> {
        let channel = || self.name.clone();
        if self.dimension == 0 || !self.values.len().is_multiple_of(self.dimension) {
            let rule = format!(
                "{} components do not make values of {} components each (the dimension must be at least 1)",
                self.values.len(),
                self.dimension
            );
            return Some(MeshError::ChannelShape { channel: channel(), rule });
        }
        if self.indices.len() != corners {
            let rule = format!("{} value indices for {corners} face corners (one per corner)", self.indices.len());
            return Some(MeshError::ChannelShape { channel: channel(), rule });
        }
        if let Some(i) = self.values.iter().position(|x| !x.is_finite()) {
            return Some(MeshError::ChannelNonFinite { channel: channel(), value: i / self.dimension });
        }
        let count = self.value_count();
        let h = self.indices.iter().position(|&i| i as usize >= count)?;
        let f = offsets.partition_point(|&o| o as usize <= h) - 1;
        Some(MeshError::ChannelIndexOutOfRange {
            channel: channel(),
            face: FaceId::new(f as u32),
            corner: h - offsets[f] as usize,
            index: self.indices[h],
            value_count: count,
        })
    }
}

impl Mesh {
    /// Whether `edge` is a seam of `channel`: an interior edge whose two faces use different
    /// values of the channel at one of its ends.
    pub fn is_seam(&self, channel: &Channel, edge: EdgeId) -> bool {
        let h = self.edge_half_edge(edge);
        let Some(t) = self.twin(h) else {
            return false;
        };
        // `h` runs a → b and `t` runs b → a: the values at a are h's start and next(t)'s start.
        channel.corner_value(h) != channel.corner_value(self.next(t))
            || channel.corner_value(self.next(h)) != channel.corner_value(t)
    }

    /// Whether `edge` is on the boundary of `channel`'s topology: a boundary edge of the mesh or
    /// a [seam](Self::is_seam) of the channel.
    pub fn is_channel_boundary(&self, channel: &Channel, edge: EdgeId) -> bool {
        self.is_boundary_edge(edge) || self.is_seam(channel, edge)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DVec3, PolygonSoup, VertexId, shapes};

    fn quad_pair(indices: Vec<u32>) -> PolygonSoup {
        let positions = (0..6).map(|i| DVec3::new(f64::from(i % 3), f64::from(i / 3), 0.0)).collect();
        let mut soup = PolygonSoup::from_indices(positions, [[0u32, 1, 4, 3], [1, 2, 5, 4]]);
        soup.channels.push(Channel::new("uv", 2, (0..16).map(f64::from).collect(), indices));
        soup
    }

    #[test]
    fn shared_values_make_no_seam_and_split_values_do() {
        let shared = Mesh::build(quad_pair(vec![0, 1, 4, 3, 1, 2, 5, 4])).unwrap();
        let e = shared.find_edge(VertexId::new(1), VertexId::new(4)).unwrap();
        assert!(!shared.is_seam(&shared.channels()[0], e));
        // Split at one end only is a seam too.
        let half = Mesh::build(quad_pair(vec![0, 1, 4, 3, 6, 2, 5, 4])).unwrap();
        assert!(half.is_seam(&half.channels()[0], e));
        assert!(half.edges().filter(|&e| half.is_channel_boundary(&half.channels()[0], e)).count() == 7);
    }

    #[test]
    fn channel_errors_name_the_channel_face_and_corner() {
        let error = Mesh::build(quad_pair(vec![0, 1, 4, 3, 1, 2, 9, 4])).unwrap_err();
        assert_eq!(
            error,
            MeshError::ChannelIndexOutOfRange {
                channel: "uv".into(),
                face: FaceId::new(1),
                corner: 2,
                index: 9,
                value_count: 8
            }
        );
        assert_eq!(error.face(), Some(FaceId::new(1)));
        let error = Mesh::build(quad_pair(vec![0, 1, 4])).unwrap_err();
        assert!(matches!(error, MeshError::ChannelShape { .. }), "{error}");
        let mut soup = quad_pair(vec![0, 1, 4, 3, 1, 2, 5, 4]);
        soup.channels[0] = Channel::new("uv", 2, vec![f64::NAN; 16], vec![0; 8]);
        assert_eq!(Mesh::build(soup).unwrap_err(), MeshError::ChannelNonFinite { channel: "uv".into(), value: 0 });
    }

    #[test]
    fn orientation_repair_flips_the_channel_with_the_face() {
        let mut soup = shapes::cube();
        let corners = soup.corner_count() as u32;
        soup.channels.push(Channel::new("id", 1, (0..corners).map(f64::from).collect(), (0..corners).collect()));
        soup.flip_face(FaceId::new(2));
        let mesh = Mesh::build_with(soup, &crate::BuildOptions::DEFAULT.with_orient(true)).unwrap();
        let id = &mesh.channels()[0];
        // Every corner still carries the value that was authored at its vertex.
        let original = shapes::cube();
        for f in mesh.face_ids() {
            for h in mesh.face_half_edges(f) {
                let authored = id.value(id.corner_value(h))[0] as usize;
                assert_eq!(original.raw_faces().1[authored], mesh.origin(h));
            }
        }
    }
}
