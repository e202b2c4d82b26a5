//! Tessellation of subdivision surfaces.
//!
//! Input: a closed Catmull-Clark control mesh ([`subdiv_mesh::Mesh`]). Output: a [`TessMesh`]
//! (positions and normals of exact limit points, each vertex's face and `Bfr` parameters,
//! triangles with their faces, and polygons).
//!
//! The [`quadtree`] tessellator (paper 002, Lai and Cheng) refines each face's parameter domain
//! by midpoint splits until every piece is flat, with **global vertex ids** (one vertex per
//! parameter point, shared across faces) and **polyline replacement** (a polygon lists the
//! vertices its finer neighbours put on its edges), so the output is watertight by
//! construction. Its tolerance model ([`flatness`]): every output triangle is within `ε` of the
//! surface *parametrically* — each parameter point of the triangle maps to a surface point
//! within `ε` of the triangle's linear interpolant — with a proof, not a sampled estimate.
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh};
//! use subdiv_schemes::Builtin;
//! use subdiv_tess::{Tessellator, TessOptions, Tolerance};
//!
//! let mesh = Mesh::build(shapes::ngon_prism(5))?;
//! let tess = Tessellator::new(Builtin::CatmullClark.scheme(), &mesh)?;
//! let coarse = tess.tessellate(&TessOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-2)))?;
//! let fine = tess.tessellate(&TessOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-3)))?;
//! assert!(fine.triangles.len() > coarse.triangles.len());
//! assert_eq!(fine.normals.len(), fine.positions.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod bezier;
pub mod check;
pub mod dual;
mod error;
pub mod flatness;
mod mesh;
pub mod quadtree;

pub use dual::{DualOptions, DualTessellator, FlatMesh, MAX_DUAL_RATE};
pub use error::TessError;
pub use flatness::Tolerance;
pub use mesh::{SurfaceParameter, TessMesh};
pub use quadtree::{TessOptions, TessStats, Tessellator};
