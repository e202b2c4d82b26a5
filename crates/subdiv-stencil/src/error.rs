//! [`StencilError`].

use subdiv_schemes::SchemeError;

/// Why a stencil cannot be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StencilError {
    /// The scheme or its patch matrices cannot serve this request.
    #[error(transparent)]
    Scheme(#[from] SchemeError),
    /// A parameter outside the patch's domain, or not a finite rational.
    #[error("parameter ({u}, {v}) is outside the domain {domain}")]
    OutsideDomain {
        /// The first parameter.
        u: String,
        /// The second parameter.
        v: String,
        /// The domain, e.g. `[0, 1]²`.
        domain: &'static str,
    },
    /// A parameter text that is not `U,V` of two fractions in 64-bit integers.
    #[error("parameter {text:?}: {reason}")]
    ParameterSyntax {
        /// The text given.
        text: String,
        /// What is wrong.
        reason: &'static str,
    },
    /// A rational parameter whose address (prefix and period of its binary expansion) is
    /// longer than the walk limit, [`MAX_ADDRESS_STEPS`](crate::MAX_ADDRESS_STEPS) by default.
    #[error(
        "parameter ({u}, {v}): its sub-patch address is longer than {limit} levels (the binary expansion's period \
         grows with the denominator's odd part); use a denominator with a shorter period, such as a power of two, \
         or raise the limit (StencilEvaluator::with_max_address_steps)"
    )]
    AddressTooLong {
        /// The first parameter.
        u: String,
        /// The second parameter.
        v: String,
        /// The limit on the walk's levels.
        limit: usize,
    },
    /// Exact stencils need rational sub-patch matrices; this scheme's are not (at this patch).
    #[error("{scheme}: no exact stencils: {detail}")]
    NotRational {
        /// The scheme's name.
        scheme: String,
        /// Which entry failed.
        detail: String,
    },
    /// A shape index beyond the patch matrices' shapes.
    #[error("{scheme}: shape {shape} does not exist (the patch matrices hold {shapes} shapes)")]
    Shape {
        /// The scheme's name.
        scheme: String,
        /// The shape asked for.
        shape: usize,
        /// How many shapes there are.
        shapes: usize,
    },
    /// Bytes given as a stencil table file that do not start with [`TABLE_MAGIC`](crate::TABLE_MAGIC).
    #[error("not a subdiv stencil table file (it does not start with the bytes `SUBDIVST`)")]
    TableForeign,
    /// A stencil table file of another format version.
    #[error(
        "stencil table format version {found}, but this build reads version {expected}: regenerate the tables \
         (`cargo xtask tables`)"
    )]
    TableVersion {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        expected: u32,
    },
    /// A stencil table file that no longer matches the scheme or the matrices this build derives.
    #[error("stale stencil tables: {detail}")]
    TableStale {
        /// What differs.
        detail: String,
    },
    /// A stencil table file that is truncated or damaged.
    #[error("corrupt stencil table file at byte {offset}: {detail}")]
    TableCorrupt {
        /// Where reading failed.
        offset: usize,
        /// What was wrong.
        detail: String,
    },
    /// A grid rate of zero, or one too large to address.
    #[error("rate {rate} is not supported: {reason}")]
    Rate {
        /// The rate asked for.
        rate: u64,
        /// Why not.
        reason: &'static str,
    },
    /// The eigenvector a stencil needs is not unique or does not exist (eigenvalue 1 not
    /// simple, or the tangent eigenspace of the wrong dimension).
    #[error("{scheme}: {detail}")]
    Eigen {
        /// The scheme's name.
        scheme: String,
        /// What went wrong, with the address.
        detail: String,
    },
    // ---- limit evaluation of a mesh (mesh_eval.rs) ---------------------------------------
    /// A face index the mesh does not have.
    #[error("face {face} does not exist: the mesh has {faces} faces (0 to {faces} - 1)")]
    FaceOutOfRange {
        /// The face asked for.
        face: usize,
        /// The mesh's face count.
        faces: usize,
    },
    /// A parameter outside the face's domain (or not a finite number).
    #[error("face {face}: parameter ({u}, {v}) is outside its domain {domain}")]
    OutsideFace {
        /// The face.
        face: usize,
        /// The first parameter, as given.
        u: String,
        /// The second parameter, as given.
        v: String,
        /// The domain in words.
        domain: String,
    },
    /// The face has no limit surface: a hole (tagged, or made by the boundary rule `none`).
    #[error("face {face} has no limit surface: it is a hole (a `t hole` tag, or boundary interpolation none)")]
    NoSurface {
        /// The face.
        face: usize,
    },
    /// A face whose patch has no known shape after several refinements: a bug, please report.
    #[error("internal error, please report: face {face} finds no patch shape within {levels} levels of refinement")]
    NoPatch {
        /// The face of the mesh.
        face: usize,
        /// Levels tried.
        levels: usize,
    },
    /// A dual split (Doo-Sabin, mid-edge) on an open mesh, at a boundary configuration whose
    /// limit surface has no patches (refinement takes the mesh).
    #[error("{scheme}: the limit surface {place} has no patches: {reason}; `subdiv refine` takes the mesh")]
    DualBoundary {
        /// The scheme's name.
        scheme: String,
        /// Where, e.g. `at vertex 12, a boundary vertex of 3 faces`.
        place: String,
        /// Why.
        reason: &'static str,
    },
    /// A broken internal invariant: a bug, please report.
    #[error("internal error, please report: {0}")]
    Internal(String),
    // ---- curve stencils (curve.rs, rational.rs) -------------------------------------------
    /// A curve scheme's mask weight is not a rational with a small denominator, so the exact
    /// curve stencils cannot use it.
    #[error(
        "curve stencils (ExactMask::from_scheme, `{scheme}`): mask entry {index} = {value} is not within 1e-15 of a \
         rational with denominator at most {max_denominator}"
    )]
    CurveMaskNotRational {
        /// The scheme's name.
        scheme: String,
        /// The entry's index in the mask.
        index: usize,
        /// Its value.
        value: f64,
        /// The largest denominator tried.
        max_denominator: u64,
    },
    /// A rule of an exact curve mask does not sum to exactly 1 (the scheme would not reproduce
    /// constants).
    #[error(
        "curve stencils (ExactMask, `{scheme}`): the rule of the children {arity}j+{residue} sums to {sum}, not exactly 1"
    )]
    CurveMaskRuleSum {
        /// The scheme's name.
        scheme: String,
        /// The arity.
        arity: u32,
        /// The residue of the rule's children modulo the arity.
        residue: u32,
        /// The exact sum, as `p/q`.
        sum: String,
    },
    /// An exact curve mask of an unsupported shape (arity, all weights zero).
    #[error("curve stencils (ExactMask, `{scheme}`): {reason}")]
    CurveMaskShape {
        /// The scheme's name.
        scheme: String,
        /// What is wrong.
        reason: String,
    },
    /// The scaling-relation system of a curve scheme (with its normalisations) has no unique
    /// exact solution: the scheme does not converge (positions) or is not C¹ (derivatives).
    #[error("curve stencils (scaling relations of `{scheme}` on the grid (1/{rate})Z, {quantity}): {detail}")]
    CurveScalingSystem {
        /// The scheme's name.
        scheme: String,
        /// The grid rate.
        rate: u32,
        /// `positions` or `derivatives`.
        quantity: &'static str,
        /// What went wrong: inconsistency, or the rank.
        detail: String,
    },
    /// The left eigenvectors of a curve scheme's upsampled subdivision matrix do not give one
    /// normalised vector (floating-point route).
    #[error("curve stencils (upsampled subdivision matrix of `{scheme}` at rate {rate}, {quantity}): {detail}")]
    CurveUpsampledEigen {
        /// The scheme's name.
        scheme: String,
        /// The grid rate.
        rate: u32,
        /// `positions` or `derivatives`.
        quantity: &'static str,
        /// What went wrong.
        detail: String,
    },
    // ---- surface route 1 (surface_basis.rs) -----------------------------------------------
    /// The regular rules of a surface scheme do not give an exact scaling relation: a weight
    /// that is not a small fraction, a refined point off the dilated lattice, a rule that does
    /// not sum to exactly 1.
    #[error("surface scaling relation of `{scheme}`: {reason}")]
    SurfaceMask {
        /// The scheme's name.
        scheme: String,
        /// What is wrong.
        reason: String,
    },
    /// The scaling-relation system of a surface scheme on a regular grid (with its
    /// normalisations) has no unique exact solution.
    #[error("surface scaling relations of `{scheme}` on the grid (1/{rate})Z², {quantity}: {detail}")]
    SurfaceScalingSystem {
        /// The scheme's name.
        scheme: String,
        /// The grid rate.
        rate: u32,
        /// `positions`, `derivatives ∂/∂u` or `derivatives ∂/∂v`.
        quantity: &'static str,
        /// What went wrong: inconsistency, or the rank.
        detail: String,
    },
}

impl From<subdiv_schemes::binary::Corrupt> for StencilError {
    fn from(e: subdiv_schemes::binary::Corrupt) -> Self {
        Self::TableCorrupt { offset: e.offset, detail: e.detail }
    }
}
