//! Eigenbasis evaluation of subdivision surfaces: Catmull-Clark (Stam '98, in Lai and Cheng's
//! general form, paper 002 §3) and Loop (Stam '99) at **any real** `(u, v)` of any face, with
//! first and second derivatives, in O(1) per point after a per-valence precomputation.
//!
//! Inputs are a [`Mesh`](subdiv_mesh::Mesh) and a [`Scheme`](subdiv_schemes::Scheme); the rules
//! come from the scheme's data: every matrix is a sub-patch matrix of
//! [`PatchMatrices`](subdiv_schemes::PatchMatrices), derived by the refinement engine, so no
//! Catmull-Clark or Loop weight is typed in here, and a user scheme with the same patch
//! structure works unchanged.
//!
//! - **Regular patches** are polynomials (bicubic for quads, total degree 4 for triangles):
//!   the power-basis matrix is fitted to the scheme's exact rational stencils at a unisolvent
//!   set of points and checked at others ([`EigenBasis`]).
//! - **Extraordinary patches** of valence `k` (3 to [`MAX_VALENCE`]): the point at ring `m`,
//!   sub-patch `b` has the control points `M_b A^{m−1} C`. The first [`DIRECT_LEVELS`] rings
//!   iterate `A` (exact subdivision: a defective part, such as the Jordan block of eigenvalue 0
//!   of Catmull-Clark at valence 3, is dead after that many steps); deeper rings use the
//!   eigenvalues of modulus above [`KEPT_MODULUS`] with their left and right eigenvectors,
//!   complex pairs in complex arithmetic. At construction the kept part is checked to be
//!   semisimple (`|Ax − λx|`, `|YX − I|`, and `A^32` rebuilt from it), else
//!   [`EvalError::Eigen`]. Coefficients are kept *less the limit position*, so derivatives,
//!   scaled by `2^m`, keep their relative precision next to the vertex.
//! - **Meshes** ([`EigenEvaluator`]): OpenSubdiv `Bfr` parameterization over the faces'
//!   patches ([`PatchLevels`](subdiv_stencil::PatchLevels)); faces whose patches are not
//!   interior ones (boundaries) go through the exact stencil route
//!   ([`LimitEvaluator`](subdiv_stencil::LimitEvaluator)) — see [`Method`].
//!
//! Accuracy (tests): positions agree with the exact stencil route to `1e−12` of the bounding box
//! at rational points and next to extraordinary vertices down to `2^−40`; derivatives to `1e−11`
//! (relative) down to `2^−24`. Deeper, the stencil route's own derivative weights cancel and lose
//! digits, so there only directions are compared (to `1e−6`); the eigenbasis gives the same
//! digits whether it iterates `A` or expands in eigenvectors.
//!
//! ```
//! use subdiv_eval::{EigenEvaluator, Method};
//! use subdiv_mesh::{shapes, FaceId, Mesh};
//! use subdiv_schemes::{Builtin, RefineOptions};
//!
//! let mesh = Mesh::build(shapes::pole(5))?;
//! let eval = EigenEvaluator::new(Builtin::CatmullClark.scheme(), &mesh, &RefineOptions::DEFAULT, Method::Auto)?;
//! // Face 0 touches the valence-5 vertex at its corner 0.
//! let p = eval.eval(FaceId::new(0), 1e-9, 0.3)?;
//! assert!(p.exact_derivatives);
//! let q = eval.eval_second(FaceId::new(0), 0.25, 0.5)?;
//! assert!(q.first.du.cross(q.first.dv).z > 0.0);
//! // At the vertex itself: the normal, from the subdominant eigenvectors.
//! let v = eval.eval(FaceId::new(0), 0.0, 0.0)?;
//! assert!(!v.exact_derivatives && v.du.cross(v.dv).normalize().z > 0.99);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod basis;
mod basis_table;
mod error;
mod mesh;
mod poly;
mod surface;

pub use basis::{DIRECT_LEVELS, EigenBasis, EigenBasisSpectrum, KEPT_MODULUS, MAX_VALENCE};
pub use basis_table::{EIGEN_TABLE_MAGIC, EIGEN_TABLE_VERSION, EigenTables, eigen_table_file};
pub use error::EvalError;
pub use mesh::{EigenEvaluator, LimitPoint2, Method};
pub use poly::PolyKind;
pub use surface::{PatchPoint, PatchPoint2, PatchSurface, STORED_LEVELS};
