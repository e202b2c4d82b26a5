//! **subdiv**: exact, fast subdivision surfaces in Rust.
//!
//! This facade re-exports the workspace's crates under one name: half-edge topology ([`mesh`]),
//! mesh files ([`io`]), refinement with OpenSubdiv's rules ([`schemes`]) and exact limit
//! stencils at rational parameters ([`stencil`]), eigenbasis evaluation of Catmull-Clark and
//! Loop at any real parameter ([`eval`]) and tessellation with a guaranteed distance bound
//! ([`tess`]). The GPU backend arrives as its own crate and is re-exported here.
//!
//! ```
//! use subdiv::mesh::{shapes, Mesh, RegularValence};
//!
//! let mesh = Mesh::build(shapes::default_model())?;
//! let regular = RegularValence::for_faces_of(&mesh);
//! assert!(mesh.extraordinary_vertices(regular).count() > 0);
//! # Ok::<(), subdiv::mesh::MeshError>(())
//! ```

pub use subdiv_eval as eval;
pub use subdiv_io as io;
pub use subdiv_mesh as mesh;
pub use subdiv_schemes as schemes;
pub use subdiv_stencil as stencil;
pub use subdiv_tess as tess;

pub use subdiv_mesh::{DVec3, Mesh, MeshError, PolygonSoup};
