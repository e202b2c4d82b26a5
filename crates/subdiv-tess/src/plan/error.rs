//! What a malformed [`EvaluationPlan`](super::EvaluationPlan) breaks: the item and the rule.

use std::fmt;
use std::ops::Range;

/// What part of an [`EvaluationPlan`] a [`PlanError`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum PlanItem {
    /// The plan as a whole (how its arrays' lengths agree).
    Plan,
    /// A refined level: its number in [`EvaluationPlan::levels`].
    Level(usize),
    /// A refined point's row ([`EvaluationPlan::refine_rows`]), by its number among all
    /// points (at least [`EvaluationPlan::cage_len`]).
    RefinedPoint(usize),
    /// An output vertex's entry.
    Vertex(usize),
    /// A block: its number in [`EvaluationPlan::blocks`].
    Block(usize),
    /// A bicubic point: its number in [`EvaluationPlan::bicubic`].
    Bicubic(usize),
    /// A stencil point: its number in [`EvaluationPlan::general`].
    General(usize),
    /// A patch's point index: its place in [`EvaluationPlan::points`].
    PatchPoint(usize),
    /// A stencil weight: its place in [`EvaluationPlan::weights`].
    Weight(usize),
}

impl fmt::Display for PlanItem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Plan => write!(f, "evaluation plan"),
            Self::Level(k) => write!(f, "evaluation plan, level {k}"),
            Self::RefinedPoint(p) => write!(f, "evaluation plan, refined point {p}"),
            Self::Vertex(v) => write!(f, "evaluation plan, vertex {v}"),
            Self::Block(k) => write!(f, "evaluation plan, block {k}"),
            Self::Bicubic(k) => write!(f, "evaluation plan, bicubic point {k}"),
            Self::General(k) => write!(f, "evaluation plan, stencil point {k}"),
            Self::PatchPoint(k) => write!(f, "evaluation plan, patch point index {k}"),
            Self::Weight(k) => write!(f, "evaluation plan, weight {k}"),
        }
    }
}

/// A rule of [`EvaluationPlan::validate`] that a plan breaks, with the item that breaks it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// An index that names nothing: a record, a point, or a point outside the level a
    /// refinement row may read.
    #[error("{at}: {what} {index} is not in {}..{}", valid.start, valid.end)]
    OutOfRange {
        /// Where.
        at: PlanItem,
        /// What the index names (`"block"`, `"point"`, …).
        what: &'static str,
        /// The index.
        index: u64,
        /// The indices allowed.
        valid: Range<u64>,
    },
    /// A record's run in one of the flat arrays ends past the array's end.
    #[error("{at}: its {array} {start}..{end} run past the end ({len})")]
    PastEnd {
        /// Where.
        at: PlanItem,
        /// Which array (`"patch point indices"`, `"weights"`, `"cell vertices"`).
        array: &'static str,
        /// The run's start.
        start: u64,
        /// The run's end.
        end: u64,
        /// The array's length.
        len: u64,
    },
    /// A length or an offset that disagrees with the rest of the plan.
    #[error("{at}: {what} is {got}, expected {expected}")]
    Length {
        /// Where.
        at: PlanItem,
        /// What was counted or where something starts.
        what: &'static str,
        /// Its value.
        got: u64,
        /// What the plan's other arrays make it.
        expected: u64,
    },
    /// A weight, parameter or chain-rule entry that is NaN or infinite.
    #[error("{at}: {what} {value} is not finite")]
    NonFinite {
        /// Where.
        at: PlanItem,
        /// Which value (`"weight"`, `"s"`, `"ju"`, …).
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// A rule about the plan's shape (the text says which).
    #[error("{at}: {rule}")]
    Structure {
        /// Where.
        at: PlanItem,
        /// The rule.
        rule: &'static str,
    },
}
