//! The crate's one error type.

use subdiv_stencil::StencilError;

/// The error bound a tessellation was asked for, as its refusals state it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ErrorBound {
    /// An absolute distance `ε` in the mesh's units.
    Absolute(f64),
    /// Pixels on the screen ([`ScreenError`](crate::rates::ScreenError)).
    Pixels(f64),
}

impl std::fmt::Display for ErrorBound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Absolute(epsilon) => write!(f, "ε = {epsilon:e}"),
            Self::Pixels(pixels) => write!(f, "{pixels} pixels of error on the screen"),
        }
    }
}

/// Why a tessellation failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TessError {
    /// The tolerance is not a positive finite number, or a relative one of a mesh whose
    /// bounding box has no diagonal to be relative to.
    #[error("tolerance {value} {reason}")]
    Tolerance {
        /// The value as given.
        value: String,
        /// Why it cannot be used.
        reason: String,
    },
    /// The scheme is not one the quadtree's bounds hold for.
    #[error("scheme {scheme}: {reason}")]
    Scheme {
        /// The scheme's name.
        scheme: String,
        /// The rule broken.
        reason: String,
    },
    /// The mesh (or the request) has a feature the tessellator does not handle.
    #[error("{element}: {feature} not supported by this tessellator")]
    Unsupported {
        /// The feature.
        feature: &'static str,
        /// Where it is (an edge, a vertex, a face).
        element: String,
    },
    /// Preparing the surface (patches, stencils) failed.
    #[error(transparent)]
    Surface(#[from] StencilError),
    /// A face needed more levels than allowed ([`QuadtreeOptions::max_depth`](crate::QuadtreeOptions)).
    #[error(
        "face {face}: not flat to ε = {epsilon:e} at depth {depth} (the limit); raise the tolerance (or the screen error)"
    )]
    DepthLimit {
        /// The input face.
        face: usize,
        /// The depth reached.
        depth: u32,
        /// The absolute tolerance.
        epsilon: f64,
    },
    /// The output would exceed [`QuadtreeOptions::max_polygons`](crate::QuadtreeOptions).
    #[error(
        "at least {needed} polygons (about twice as many vertices) needed for {bound}, more than the limit \
         {limit}; raise the tolerance or the limit (QuadtreeOptions::max_polygons; TessOptions::max_vertices, \
         `subdiv tessellate --max-vertices`, allow a quarter as many polygons as vertices)"
    )]
    TooManyPolygons {
        /// A lower bound on the polygons needed: predicted before the work (usually), or the
        /// limit plus one when the work found it.
        needed: usize,
        /// The limit.
        limit: usize,
        /// The error bound asked for.
        bound: ErrorBound,
    },
    /// A screen-space rate policy with a degenerate camera or viewport.
    #[error("screen-space rates: {reason}")]
    Camera {
        /// The rule broken.
        reason: String,
    },
    /// A face needs a finer rate than allowed to meet a tolerance.
    #[error(
        "face {face}: the tolerance needs {needed}, beyond the largest rate allowed ({max_rate}); raise the tolerance or the largest rate, or take the quadtree (it adapts within faces)"
    )]
    RateLimit {
        /// The input face.
        face: usize,
        /// What it needs, in words: `rate N`, or why no allowed rate serves.
        needed: String,
        /// The largest rate allowed.
        max_rate: u32,
    },
    /// A face's tessellation rate is outside `1..=`[`MAX_DUAL_RATE`](crate::dual::MAX_DUAL_RATE).
    #[error("face {face}: rate {rate} is not allowed ({rule})")]
    Rate {
        /// The input face.
        face: usize,
        /// The rate as given.
        rate: u32,
        /// The rule broken.
        rule: &'static str,
    },
    /// The rates slice does not have one rate per input face.
    #[error("{got} rates given for {expected} faces (one rate per face)")]
    RateCount {
        /// The number of faces.
        expected: usize,
        /// The number of rates given.
        got: usize,
    },
    /// The ring depths do not have one depth per input vertex (`what`: `"vertices"`) or per
    /// input face (`"centres"`) ([`RingDepths`](crate::rates::RingDepths)).
    #[error("{got} ring depths given for {expected} {what} (one depth per element)")]
    RingCount {
        /// Which list: `"vertices"`, `"centres"` or `"graded grids"`.
        what: &'static str,
        /// The number of vertices or faces.
        expected: usize,
        /// The number of depths given.
        got: usize,
    },
    /// A ring depth beyond [`MAX_DUAL_RING_DEPTH`](crate::dual::MAX_DUAL_RING_DEPTH).
    #[error("{element}: ring depth {depth} is above the largest allowed ({max})")]
    RingDepth {
        /// The vertex or face.
        element: String,
        /// The depth as given.
        depth: u32,
        /// The largest depth allowed.
        max: u32,
    },
    /// A graded grid ([`GradedGrid`](crate::rates::GradedGrid)) that does not fit its face: not a
    /// quad under a quad split, or not one of the face's rate cells per axis with increasing
    /// boundaries.
    #[error("face {face}: its graded grid {reason}")]
    Grading {
        /// The input face.
        face: usize,
        /// The rule broken, in words.
        reason: String,
    },
    /// The cage positions do not have one position per input vertex.
    #[error("{got} cage positions given for {expected} vertices (one position per vertex)")]
    CageLength {
        /// The number of vertices.
        expected: usize,
        /// The number of positions given.
        got: usize,
    },
    /// A cage position is not finite.
    #[error("vertex {vertex}: position {value} is not finite (cage positions must be finite)")]
    CagePosition {
        /// The input vertex.
        vertex: usize,
        /// The position as given.
        value: String,
    },
    /// An [`EvaluationPlan`](crate::EvaluationPlan) that breaks a rule of
    /// [`validate`](crate::EvaluationPlan::validate).
    #[error(transparent)]
    Plan(#[from] crate::dual::PlanError),
    /// An internal invariant failed: please report.
    #[error("internal error (please report): {0}")]
    Internal(String),
}
