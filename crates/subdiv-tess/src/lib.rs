//! Tessellation of subdivision surfaces.
//!
//! Input: a control mesh ([`subdiv_mesh::Mesh`]) and a scheme. Output: a [`TessMesh`]
//! (positions and normals of exact limit points, each vertex's face and `Bfr` parameters,
//! triangles with their faces, and polygons), or the caller's own buffers and vertex type
//! through a [`TessSink`] ([`sink`]: [`FlatMesh`]'s f32 buffers, [`VertexBuffers`] of any
//! `bytemuck::Pod` vertex). Two tessellators, prepared once per mesh and reusable (the dual one
//! keeps all its buffers between calls; the quadtree's `tessellate_into` keeps its vertex table,
//! creators and centres, and allocates its leaves anew):
//!
//! - The [`dual`] tessellator ([`DualTessellator`], paper 000 §5.5, Schaefer and Warren's
//!   dual-grid stitching) samples each face uniformly at its own integer rate: every face owns
//!   the points of its dual grid, and strips along the edges and polygons around the vertices
//!   stitch faces of any rates together, watertight by construction, with no welding. It takes
//!   every primal scheme with sub-patch matrices (Catmull-Clark, Kobbelt, bilinear, Loop,
//!   butterfly), closed and open meshes and holes, and re-evaluates a moved cage without any
//!   topology work ([`DualTessellator::update_cage`]): the animation path.
//! - The [`quadtree`] tessellator ([`QuadtreeTessellator`], paper 002, Lai and Cheng) refines each
//!   Catmull-Clark face's parameter domain by midpoint splits until every piece is flat,
//!   with **global vertex ids** (one vertex per parameter point, shared across faces) and
//!   **polyline replacement** (a polygon lists the vertices its finer neighbours put on its
//!   edges), so the output is watertight by construction. Its tolerance model ([`flatness`]):
//!   every output triangle is within `ε` of the surface *parametrically* — each parameter
//!   point of the triangle maps to a surface point within `ε` of the triangle's linear
//!   interpolant — with a proof, not a sampled estimate.
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh};
//! use subdiv_schemes::Builtin;
//! use subdiv_tess::{QuadtreeTessellator, QuadtreeOptions, Tolerance};
//!
//! let mesh = Mesh::build(shapes::ngon_prism(5))?;
//! let tess = QuadtreeTessellator::new(Builtin::CatmullClark.scheme(), &mesh)?;
//! let coarse = tess.tessellate(&QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-2)))?;
//! let fine = tess.tessellate(&QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-3)))?;
//! assert!(fine.triangles.len() > coarse.triangles.len());
//! assert_eq!(fine.normals.len(), fine.positions.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The dual tessellator at per-face rates, and the animation path:
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh};
//! use subdiv_schemes::Builtin;
//! use subdiv_tess::{DualOptions, DualTessellator};
//!
//! let mesh = Mesh::build(shapes::cube())?;
//! let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())?;
//! let out = tess.tessellate(&[1, 2, 3, 4, 5, 6])?;
//! assert!(out.triangles.iter().all(|t| t.iter().all(|&v| (v as usize) < out.positions.len())));
//! let lifted: Vec<_> = mesh.positions().iter().map(|p| *p + glam::DVec3::Z).collect();
//! tess.update_cage(&lifted)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod bezier;
pub mod check;
pub mod dual;
mod error;
pub mod flatness;
mod mesh;
mod normal;
pub mod quartic;
use subdiv_mesh::par;
pub mod plan;
pub mod quadtree;
pub mod rates;
pub mod sink;

pub use dual::{DualOptions, DualTessellator, EvaluationPlan, FlatMesh, MAX_DUAL_RATE};
pub use error::{ErrorBound, TessError};
pub use flatness::Tolerance;
pub use mesh::{SurfaceParameter, TessChannels, TessMesh};
pub use normal::unit_normal;
pub use quadtree::{FaceCurvature, QuadtreeOptions, QuadtreeStats, QuadtreeTessellator};
pub use sink::{BuffersBuilder, FlatStream, TessCounts, TessSink, TessTriangle, TessVertex, VertexBuffers};
pub use subdiv_mesh::Parallelism;
