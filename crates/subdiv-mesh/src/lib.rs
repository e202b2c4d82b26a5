//! Half-edge topology of polygon meshes, the ground of every subdivision scheme in `subdiv`.
//!
//! Input is a [`PolygonSoup`]: positions, faces of any size ≥ 3 as vertex lists, and the
//! [`Tags`] authored on them (creases, corners, holes, boundary rules). [`Mesh::build`] checks
//! every rule a subdivision surface needs — no degenerate faces, indices in range, finite
//! coordinates, manifold edges and vertices, consistent orientation — and reports the first one
//! broken as a [`MeshError`] naming the face or vertex; [`validate`] lists them all. The result
//! answers the queries subdivision needs: valence, boundary tests, ordered one-ring fans (a
//! boundary fan starts at its boundary edge), k-rings, components, Euler characteristic, genus
//! and extraordinary vertices.
//!
//! With the `proptest` feature, [`strategies`] generates valid meshes for property tests.
//!
//! **Architecture invariant:** this crate knows no subdivision scheme and no file format. Tags
//! are stored as authored; the schemes give them meaning, the readers produce them.
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh, RegularValence};
//!
//! let mesh = Mesh::build(shapes::cube())?;
//! assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (8, 12, 6));
//! assert_eq!(mesh.genus(), Some(0));
//! // Every cube corner has valence 3, which is extraordinary for quads.
//! assert_eq!(mesh.extraordinary_vertices(RegularValence::QUADS).count(), 8);
//! # Ok::<(), subdiv_mesh::MeshError>(())
//! ```

mod build;
mod channel;
mod error;
mod ids;
mod mesh;
pub mod par;
mod patch;
mod region;
pub mod shapes;
mod sheets;
mod soup;
mod split;
#[cfg(feature = "proptest")]
pub mod strategies;

pub use build::{BuildOptions, MAX_COORDINATE, validate};
pub use channel::Channel;
pub use error::MeshError;
pub use ids::{EdgeId, FaceId, HalfEdgeId, VertexId};
pub use mesh::{BoundaryLoop, Components, Mesh, OutgoingHalfEdges, RegularValence};
pub use par::Parallelism;
pub use patch::Patch;
pub use region::Region;
pub use soup::{
    BoundaryInterpolation, CornerTag, CreaseMethod, CreaseTag, FaceVaryingInterpolation, PolygonSoup, Sharpness, Tags,
    TriangleSubdivision,
};
pub use split::{ChildOrigin, PrimalSplit};

pub use glam::DVec3;
