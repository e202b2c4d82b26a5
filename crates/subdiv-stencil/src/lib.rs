//! Exact limit stencils of subdivision schemes at rational parameters.
//!
//! A stencil is the list of weights that, applied to a patch's control points, gives a point of
//! the limit surface (or curve) and its tangents. Following Schaefer and Warren (paper 000) and
//! Morlet et al. (paper 003), this crate computes them without refining meshes:
//!
//! - **Curves** ([`curve`]): the scaling relation φ(x) = Σ s_i φ(2x − i) on the grid (1/n)ℤ
//!   with partition of unity, solved exactly in rationals, and cross-checked against the
//!   dominant left eigenvectors of the upsampled subdivision matrix.
//! - **Surfaces** ([`SurfaceStencil`]): a rational parameter has an eventually periodic binary
//!   expansion, a prefix σ and a period τ of sub-patch choices; its stencil is the dominant left
//!   eigenvector of the period's composite sub-patch matrix, carried back through the prefix.
//!   The sub-patch matrices come from [`subdiv_schemes::PatchMatrices`], derived by the
//!   refinement engine, so this works for every primal scheme at regular, extraordinary and
//!   boundary patches. A [`StencilEvaluator`] shares the work between the points of one patch.
//!   [`surface_basis`] holds route 1 on surfaces: the basis function of a scheme's regular rules
//!   from their scaling relation on (1/n)ℤ², exactly.
//! - **Tables** ([`StencilTable`], [`StencilTables`], [`StencilCache`]): the stencils of the
//!   primal and dual grids a tessellator samples, per patch type and rate, in a versioned binary
//!   format, or computed on demand.

mod address;
mod domain;
mod dual_levels;
mod error;
mod exact;
mod linalg;
mod linear;
mod mesh_eval;
mod parallel;
mod patch_levels;
mod ring;
mod surface;
pub mod surface_basis;
mod table;
mod tangents;
// ---- curve stencils (curve.rs, rational.rs) ----------------------------------------------
pub mod curve;
mod rational;
pub use rational::Rational;
// ---- end of curve stencils ----------------------------------------------------------------

pub use address::{Address, Dyadic, MAX_ADDRESS_STEPS, parse_fraction};
pub use domain::{
    FaceDomain, GridParameter, Layout, MAX_DENOMINATOR_BITS, PatchFrame, TERNARY_DIGITS, dyadic_from_f64,
};
pub use error::StencilError;
pub use exact::{ExactSurfaceStencil, exact_surface_positions, exact_surface_stencil};
pub use linear::LinearEvaluator;
pub use mesh_eval::{LimitEvaluator, LimitPoint};
pub use patch_levels::{PatchLevels, Resolved};
pub use surface::{EvaluatorStats, StencilEvaluator, SurfaceStencil, surface_stencil};
pub use table::{
    DEFAULT_TABLES, Grid, MAX_TABLE_RATE, StencilCache, StencilTable, StencilTables, TABLE_MAGIC, TABLE_VERSION,
    TableSpec,
};
