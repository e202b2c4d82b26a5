//! Subdivision schemes as data, and one refinement engine for all of them.
//!
//! A [`Scheme`] is a value: its topological split ([`Split`]) and its masks as weight formulas
//! in the valence ([`Rules`], [`Expr`]). The built-ins ([`Builtin`]) are TOML files under
//! `schemes/` parsed by the same code as a user's file: Catmull-Clark, Loop, Doo-Sabin,
//! mid-edge, √3, modified Butterfly, Kobbelt's interpolatory quad scheme, Schaefer and
//! Warren's C1 non-polynomial quad scheme, and bilinear. Catmull-Clark, Loop and bilinear
//! follow OpenSubdiv's `Sdc` exactly — boundaries (edge-only, edge-and-corner, none),
//! infinitely sharp and semi-sharp creases and corners (uniform and Chaikin creasing), holes,
//! and N-gons for Catmull-Clark; any scheme with crease rules gets the same treatment.
//!
//! For primal schemes, child vertices are numbered as OpenSubdiv's `Far` levels: the children
//! of the parent's vertices first (vertex `v` stays vertex `v` at every level), then one point
//! per face (quad schemes), then one per edge. Child faces follow their parent's, in corner
//! order.
//!
//! Curve schemes ([`CurveScheme`], [`NonUniformCubicBSpline`]) are data too: cubic B-spline,
//! Chaikin, the four-point and six-point interpolating schemes, Schaefer and Warren's
//! non-polynomial curve scheme, and the non-uniform cubic B-spline refined by knot insertion.
//!
//! Analysis ([`Analysis`], [`LocalMatrix`], [`LocalSpectrum`]) derives each scheme's local
//! subdivision matrix by running the engine on a canonical mesh and applies Reif's C1 test,
//! characteristic map included, at interior and boundary vertices; [`c1_table`] lists the
//! verdicts at valences 3 to 16 and boundary vertices of 1 to 15 faces.
//! [`PatchMatrices`] derives the sub-patch matrices of the primal schemes the same way: for a
//! regular patch, one at an extraordinary vertex of any valence, or one at a boundary vertex,
//! the matrix that maps a face's control points to each of its sub-faces', every shape that
//! appears below it included.
//!
//! # The sw-quad rules at extraordinary vertices
//!
//! Paper 000 (§5.4) gives the regular rules of its C1 quad scheme, the tensor product of the
//! curve rules (1/6, 2/3, 1/6) and (1/2, 1/2), but its Figure 5, the rules at a vertex of
//! valence `k`, is missing from our copy. Written with face points (centroids), the regular
//! masks are: edge point = 1/6 of each endpoint + 1/3 of each adjacent face point; vertex
//! point = 1/3 of the vertex + 1/18 of each neighbour + 1/9 of each adjacent face point. We
//! keep the face and edge rules at every valence and spread the vertex rule's shares evenly:
//! the vertex keeps 1/3, its `k` neighbours share 2/9 and its `k` face points 4/9
//! (`schemes/sw-quad.toml`). Why this is C1, by the discrete Fourier transform of the one-ring
//! (centre `c`, edge neighbours `e_i`, face neighbours `f_i`):
//!
//! - At frequency ω ≠ 0 the centre drops out and the refined ring is
//!   `e' = (1/3 + cos θ/6)·e + (1 + e^{−iθ})/12·f`, `f' = (1 + e^{iθ})/4·e + f/4` with
//!   θ = 2πω/k. Its eigenvalues are the roots of x² − (7/12 + cos θ/6)·x + 1/24: they depend
//!   on the edge and face rules only, are real, and the larger one grows with cos θ, so ω = 1
//!   and ω = k − 1 give the subdominant pair λ1 = λ2, strictly above every other frequency.
//! - At frequency 0, over the centre and the means ē, f̄ of the rings, the face points expanded:
//!   `c' = 4/9·c + 4/9·ē + 1/9·f̄`, `ē' = 1/3·c + 1/2·ē + 1/6·f̄`, `f̄' = 1/4·c + 1/2·ē + 1/4·f̄`.
//!   With the even spread no entry depends on `k`, so the eigenvalues are the regular ones,
//!   1, 1/6 and 1/36, below λ1 (which is 0.394 at k = 3 and rises towards 0.689).
//! - The characteristic map, from the ω = 1 eigenvectors, is then checked regular and
//!   injective numerically by [`Analysis`], at every valence 3..=16 (the test
//!   `sw_quad_is_c1_at_valences_3_to_16` asserts it, and λ1 against the formula above).
//!
//! # Kobbelt's rule next to an extraordinary vertex
//!
//! Kobbelt's interpolatory quad scheme applies the four-point rule along grid lines; an edge
//! point next to a vertex `p` of valence `k ≠ 4` needs a point beyond `p` that the grid lacks.
//! We use the virtual point `4/k · Σ q − q_{i−1} − q_i − q_{i+1}` over `p`'s neighbours `q`
//! (`q_i` the edge's far end), which is the opposite neighbour when `k = 4`, and take face
//! points as the four-point rule through the new edge points in both grid directions,
//! averaged. We could not consult Kobbelt's paper for its exact extraordinary rule; this
//! reconstruction reproduces the regular scheme exactly (tested) and passes the C1 test at
//! valences 3 to 16, but it may differ from the original next to extraordinary vertices.
//!
//! With the `proptest` feature, [`strategies`] generates schemes and meshes they take, for
//! property tests.
//!
//! **Architecture invariant:** this crate does no I/O; scheme files arrive as text.
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh};
//! use subdiv_schemes::{refine, Builtin, RefineOptions};
//!
//! let icosahedron = Mesh::build(shapes::icosahedron())?;
//! let refined = refine(&icosahedron, Builtin::Loop.scheme(), &RefineOptions::DEFAULT)?;
//! assert_eq!((refined.vertex_count(), refined.face_count()), (42, 80));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
mod analysis;
pub mod binary;
mod canonical;
mod channel;
mod crease;
mod curve;
mod dual;
mod eigen;
mod error;
mod expr;
mod limit_mask;
mod local_curve;
mod mesh_patches;
mod nonuniform;
mod patch;
mod patch_table;
mod primal;
mod refine;
mod scheme;
mod stencil;
mod stencil_table;
#[cfg(feature = "proptest")]
pub mod strategies;

pub use analysis::{Analysis, Centre, CharacteristicMap, LocalMatrix, LocalSpectrum};
pub use channel::ChannelSurface;
pub use curve::{CurveError, CurveMatrix, CurveScheme, PolygonKind};
pub use error::SchemeError;
pub use expr::{Expr, ExprError, MAX_FORMULA_DEPTH, MAX_FORMULA_LENGTH};
pub use limit_mask::LimitMask;
pub use local_curve::{LocalCurveScheme, LocalRow, MatrixEntry};
pub use mesh_patches::{DerivedConfigurations, FoundPatch, MeshPatches, PatchVertices};
pub use nonuniform::NonUniformCubicBSpline;
pub use patch::{
    ChildDomain, Frequency, MAX_PATCH_RADIUS, PatchMatrices, PatchShape, PatchType, RingSpectrum, SharpFeatures,
    SubPatch, child_faces, derive_dual_configuration, dual_child_starts, dual_corner_start, dual_patch,
    dual_quad_corners, dual_signature_has_boundary, sub_patch_starts, ternary_child_starts, ternary_refine,
};
pub use patch_table::{DEFAULT_PATCH_TABLES, PATCH_TABLE_MAGIC, PATCH_TABLE_VERSION, PatchTableSpec, PatchTables};
pub use refine::{
    LocalRefinement, MAX_DENSE_PATCH_VALENCE, MAX_PATCH_VALENCE, RefineOptions, Refiner, ValenceLimit, refine,
    refine_uniform, refine_uniform_with_progress,
};
pub use scheme::{
    Builtin, CreaseMask, DualBoundary, ExtraordinaryEdgeMask, FaceMask, FourPointBoundary, MAX_NAME_LENGTH,
    QuadEdgeMask, Rules, Scheme, Split, Sqrt3Boundary, TriangleEdgeMask, VertexMask,
};
pub use stencil::Stencils;
pub use stencil_table::StencilTable;

pub mod c1_table {
    //! The C1 verdicts of every built-in surface scheme at interior valences 3 to 16 and at
    //! boundary vertices of 1 to 15 faces, from `subdiv analyze --table 16`.
    #![doc = include_str!("../C1_TABLE.md")]
}
