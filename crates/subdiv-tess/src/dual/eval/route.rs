//! How each output vertex and each block is evaluated: the routes.

/// How one output vertex is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Route {
    /// A cell of a bicubic face's block: the separable grid of its rate.
    BlockCell,
    /// A point of a bicubic face outside its block: the bicubic polynomial at its parameter
    /// (listed in [`Evaluator::pointwise`]).
    BicubicPoint,
    /// A cell point of a typed face: its type's [`Template`] over the face's cage points.
    Template,
    /// A point of a [`PatchGrid`] (a bicubic patch on a refined level), evaluated separably.
    PatchGrid,
    /// Its own exact stencil: the [`Record`] of this number.
    Record(u32),
}

/// A [`Route`] in 4 bytes: the number of a record, or one of the four values above the
/// largest record number for the other routes. The evaluator keeps one per output vertex and
/// writes them all on every full call (32 MB at torus_big's rate 32); with the 8-byte enum
/// stored, torus_big's full path measured 9-15 % slower (most likely these writes, doubled;
/// not isolated: see docs/perf-log.md). The packing
/// lives here alone: everything else reads [`get`](Self::get) and writes `Route::….into()`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct PackedRoute(u32);

impl PackedRoute {
    const BLOCK_CELL: u32 = u32::MAX;
    const BICUBIC_POINT: u32 = u32::MAX - 1;
    const TEMPLATE: u32 = u32::MAX - 2;
    const PATCH_GRID: u32 = u32::MAX - 3;

    /// The route.
    #[inline(always)]
    pub(super) fn get(self) -> Route {
        match self.0 {
            Self::BLOCK_CELL => Route::BlockCell,
            Self::BICUBIC_POINT => Route::BicubicPoint,
            Self::TEMPLATE => Route::Template,
            Self::PATCH_GRID => Route::PatchGrid,
            record => Route::Record(record),
        }
    }
}

impl From<Route> for PackedRoute {
    /// # Panics
    /// For a record number among the four reserved values (a topology has fewer than
    /// `u32::MAX - 4` vertices, hence records).
    #[inline(always)]
    fn from(route: Route) -> Self {
        Self(match route {
            Route::BlockCell => Self::BLOCK_CELL,
            Route::BicubicPoint => Self::BICUBIC_POINT,
            Route::Template => Self::TEMPLATE,
            Route::PatchGrid => Self::PATCH_GRID,
            Route::Record(record) => {
                assert!(record < Self::PATCH_GRID, "record number {record} out of range");
                record
            }
        })
    }
}

/// Whether a block reads a face type's [`Template`] ([`Evaluator::plan_copies`] decides it,
/// [`Evaluator::patch_grids`] settles it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TemplateUse {
    /// The block's cells take their own records.
    Own,
    /// The first block of its (type, rate) without a template: it descends, and its records
    /// become the template.
    Make,
    /// It will read the template a [`Make`](Self::Make) block of this call makes.
    Copy,
    /// Settled: it made this template.
    Made(u32),
    /// Settled: it reads this template (made by another block, in this call or before).
    Copied(u32),
}

impl TemplateUse {
    /// The template it reads, once settled.
    pub(super) fn template(self) -> Option<u32> {
        match self {
            Self::Made(t) | Self::Copied(t) => Some(t),
            Self::Own | Self::Make | Self::Copy => None,
        }
    }

    /// Whether its cells read a template made by another block (not its own records).
    pub(super) fn copies(self) -> bool {
        matches!(self, Self::Copy | Self::Copied(_))
    }
}

/// How an input face is evaluated.
#[derive(Clone, Copy, Debug)]
pub(super) enum FacePlan {
    /// A bicubic B-spline patch: its control points in the face's own frame are its level-0
    /// patch's points in [`Evaluator::bicubic_orders`]`[order]`'s order (see
    /// [`Evaluator::cv`]; sixteen indices per face were 64 MB of a million-face grid's peak).
    ///
    /// [`Evaluator::bicubic_orders`]: super::Evaluator
    /// [`Evaluator::cv`]: super::Evaluator::cv
    Bicubic { order: u32 },
    /// Through exact stencils of the patch (on any level) holding each point.
    General,
    /// No surface.
    Hole,
}
