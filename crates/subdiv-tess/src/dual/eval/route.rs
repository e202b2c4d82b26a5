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
    /// A bicubic B-spline patch: cage vertex `cv[j * 4 + i]` is the control point at
    /// `(i − 1, j − 1)` in the face's own frame.
    Bicubic { cv: [u32; 16] },
    /// Through exact stencils of the patch (on any level) holding each point.
    General,
    /// No surface.
    Hole,
}
