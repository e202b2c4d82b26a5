//! **subdiv**: exact, fast subdivision surfaces in Rust.
//!
//! Input: a control mesh (a cage of polygons: OBJ with OpenSubdiv's tags, glTF/GLB, or a
//! [`PolygonSoup`] built in code) and a subdivision scheme (the built-ins of
//! [`schemes::Builtin`] — Catmull-Clark, Loop, Doo-Sabin, √3, Butterfly, … — or one's own,
//! as data). Output: the refined mesh, the exact limit surface at any face parameter with its
//! derivatives, and watertight tessellations of it whose every vertex is an exact limit point,
//! written to GLB or OBJ or into one's own buffers ([`TessSink`]).
//!
//! [`Surface`] is the high-level API: one mesh under one scheme, with
//! [`refine`](Surface::refine), [`evaluate`](Surface::evaluate) (eigenbasis on interior
//! patches, exact stencils elsewhere; positions and first derivatives in OpenSubdiv's `Bfr`
//! parameterization) and [`tessellate`](Surface::tessellate) ([`TessOptions`]: a [`Rates`]
//! policy, a [`Method`], limits and [`Parallelism`]).
//!
//! **Tolerance model.** [`Rates::Tolerance`] is a proof, not a sampled estimate: with
//! [`Method::Dual`] every limit point is within `ε` of the output (the rates and the rings
//! around extraordinary points come from Bernstein bounds of the second derivatives,
//! [`tess::rates::ErrorRates`]); with [`Method::Quadtree`] every output triangle is within `ε`
//! of the surface parametrically ([`tess::flatness`]). `ε` is absolute, or relative to the
//! control mesh's bounding-box diagonal ([`Tolerance`]). Uniform, per-face and screen-space
//! rates make no distance promise.
//!
//! ```
//! use subdiv::mesh::shapes;
//! use subdiv::schemes::Builtin;
//! use subdiv::{FaceId, Rates, Surface, TessOptions, Tolerance};
//!
//! let mut surface = Surface::build(shapes::default_model(), Builtin::CatmullClark.scheme())?;
//! let point = surface.evaluate(FaceId::new(7), 0.25, 0.5)?;
//! let normal = point.du.cross(point.dv).normalize();
//! assert!((normal.length() - 1.0).abs() < 1e-12);
//! let options = TessOptions::DEFAULT.with_rates(Rates::Tolerance(Tolerance::Relative(1e-2)));
//! let tessellation = surface.tessellate(&options)?;
//! assert!(tessellation.info.epsilon.is_some());
//! tessellation.write_obj(std::env::temp_dir().join("subdiv-crate-doc.obj"), false)?;
//! # Ok::<(), subdiv::Error>(())
//! ```
//!
//! The workspace's crates are re-exported under one name for everything below the facade:
//! half-edge topology ([`mesh`]), mesh files ([`io`]), refinement with OpenSubdiv's rules
//! ([`schemes`]), exact limit stencils at rational parameters ([`stencil`]), eigenbasis
//! evaluation of Catmull-Clark and Loop at any real parameter ([`eval`]) and tessellation
//! ([`tess`]). The GPU backend is **not** re-exported: `subdiv-gpu` is a separate crate
//! (wgpu stays out of programs that do not draw); it takes [`tess::DualTessellator`]'s
//! evaluation plan and [`FlatMesh`]'s layout.
//!
//! ```
//! use subdiv::mesh::{shapes, Mesh, RegularValence};
//!
//! let mesh = Mesh::build(shapes::default_model())?;
//! let regular = RegularValence::for_faces_of(&mesh);
//! assert!(mesh.extraordinary_vertices(regular).count() > 0);
//! # Ok::<(), subdiv::mesh::MeshError>(())
//! ```

mod error;
mod evaluate;
mod surface;
mod tessellate;

pub use subdiv_eval as eval;
pub use subdiv_io as io;
pub use subdiv_mesh as mesh;
pub use subdiv_schemes as schemes;
pub use subdiv_stencil as stencil;
pub use subdiv_tess as tess;

pub use crate::error::Error;
pub use crate::evaluate::{DEFAULT_MAX_POINTS, EvalGrid, EvalOptions, Evaluator, GridPoint, MAX_GRID};
pub use crate::surface::{DEFAULT_MAX_REFINED_FACES, Surface, without_holes};
pub use crate::tessellate::{
    DEFAULT_MAX_TESS_VERTICES, FaceRates, Method, Rates, TessInfo, TessOptions, Tessellation, check_vertex_budget,
    write_flat_glb,
};
pub use subdiv_eval::Method as EvalMethod;
pub use subdiv_mesh::{DVec3, FaceId, Mesh, MeshError, PolygonSoup};
pub use subdiv_schemes::{Builtin, Scheme};
pub use subdiv_stencil::LimitPoint;
pub use subdiv_tess::rates::Camera;
pub use subdiv_tess::{
    BuffersBuilder, FlatMesh, Parallelism, TessMesh, TessSink, TessTriangle, TessVertex, Tolerance, VertexBuffers,
};

/// The README's code blocks, run as doc tests (the library section's example must compile and
/// run as shown there).
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
