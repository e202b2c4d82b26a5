//! The facade's one error type.

use subdiv_eval::EvalError;
use subdiv_io::IoError;
use subdiv_mesh::MeshError;
use subdiv_schemes::SchemeError;
use subdiv_stencil::StencilError;
use subdiv_tess::TessError;

/// Why a [`Surface`](crate::Surface) operation failed: the error of the crate that did the
/// work, or a request the facade itself refuses. Every variant's message names the rule
/// broken; none is a panic.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The control mesh breaks a topology rule.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Reading or writing a file failed (with its `file:line` where there is one).
    #[error(transparent)]
    Io(#[from] IoError),
    /// The scheme refused the mesh or the request (refinement).
    #[error(transparent)]
    Scheme(#[from] SchemeError),
    /// Exact stencils could not serve the request.
    #[error(transparent)]
    Stencil(#[from] StencilError),
    /// Limit evaluation failed (a face out of range, a parameter outside its face, a hole, …).
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// Tessellation failed (rates, tolerances, cameras, unsupported features).
    #[error(transparent)]
    Tess(#[from] TessError),
    /// [`Rates::Tolerance`](crate::Rates::Tolerance) for the dual method needs the quadtree's
    /// curvature bounds, which do not take this mesh or scheme (Catmull-Clark meshes whose
    /// border vertices are not extraordinary).
    #[error("rates to a tolerance: {0}")]
    ToleranceBounds(#[source] TessError),
    /// [`Method::Quadtree`](crate::Method::Quadtree) was asked for with rates other than
    /// [`Rates::Tolerance`](crate::Rates::Tolerance) or [`Rates::ScreenError`](crate::Rates::ScreenError).
    #[error(
        "the quadtree tessellator takes a tolerance (Rates::Tolerance) or a screen error (Rates::ScreenError), not {given} rates"
    )]
    QuadtreeRates {
        /// The rates given, in words.
        given: &'static str,
    },
    /// [`Method::Dual`](crate::Method::Dual) was asked for with
    /// [`Rates::ScreenError`](crate::Rates::ScreenError), which only the quadtree bounds.
    #[error(
        "the dual tessellator takes screen-space rates by edge length (Rates::Screen), not a screen-space error bound (the quadtree's)"
    )]
    DualScreenError,
    /// A face-varying channel asked for by a name the mesh has no channel of.
    #[error("the mesh has no channel {channel:?} (its channels: {channels:?})")]
    NoChannel {
        /// The name asked for.
        channel: String,
        /// The mesh's channels.
        channels: Vec<String>,
    },
    /// Refinement to so many levels that the faces would not fit 32-bit ids.
    #[error("refining {levels} levels would make at least {faces} faces, more than 32-bit face ids can name")]
    RefineLevels {
        /// The levels asked for.
        levels: usize,
        /// A lower bound of the faces they would make.
        faces: u64,
    },
    /// A request for more work than a documented, raisable limit allows, refused before
    /// anything is allocated: grid points ([`EvalOptions::max_points`](crate::EvalOptions::max_points)),
    /// refined faces ([`Surface::with_max_refined_faces`](crate::Surface::with_max_refined_faces)).
    #[error("{verb} {requested} {noun}, more than the limit of {limit}; {raise}")]
    Budget {
        /// What the request would do, e.g. `would evaluate`.
        verb: &'static str,
        /// What it would make, e.g. `grid points`.
        noun: &'static str,
        /// How many it would make.
        requested: u64,
        /// The limit in force.
        limit: u64,
        /// How to ask for less or raise the limit.
        raise: &'static str,
    },
    /// A part of a tessellation asked for faces the mesh does not have, or of the quadtree
    /// ([`Surface::tessellate_part`](crate::Surface::tessellate_part)).
    #[error("faces {start}..{end} of {faces}: {reason}")]
    FaceRange {
        /// The first face asked for.
        start: usize,
        /// One past the last.
        end: usize,
        /// The mesh's face count.
        faces: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// A grid size outside `1..=`[`MAX_GRID`](crate::MAX_GRID).
    #[error("grid {n}: the grid size must be from 1 to {max}")]
    Grid {
        /// The size given.
        n: u32,
        /// The largest allowed.
        max: u32,
    },
}

impl Error {
    /// `Ok` if `requested` is within `limit`, else [`Error::Budget`] with the words given: the
    /// one check every budget makes before its work.
    pub(crate) fn check_budget(
        requested: u64,
        limit: u64,
        verb: &'static str,
        noun: &'static str,
        raise: &'static str,
    ) -> Result<(), Self> {
        if requested > limit { Err(Self::Budget { verb, noun, requested, limit, raise }) } else { Ok(()) }
    }

    /// Whether the error is a point asked of a hole (a face without limit surface), which
    /// callers evaluating many points often skip rather than stop at.
    pub fn is_hole(&self) -> bool {
        matches!(
            self,
            Self::Eval(EvalError::Stencil(StencilError::NoSurface { .. }))
                | Self::Stencil(StencilError::NoSurface { .. })
        )
    }
}
