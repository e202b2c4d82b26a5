//! [`SchemeError`].

use subdiv_mesh::FaceId;

/// Why a scheme cannot be loaded, or cannot refine or analyse a mesh.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SchemeError {
    /// The scheme takes only faces of one size (Loop: triangles).
    #[error("{scheme} takes only {expected}-sided faces, but {face} has {size} sides")]
    FaceNotSupported {
        /// The scheme's name.
        scheme: String,
        /// The first face it cannot take.
        face: FaceId,
        /// That face's size.
        size: usize,
        /// The size the scheme takes.
        expected: usize,
    },
    /// The scheme has no rules for boundaries, creases, corners or holes (a dual split: interior
    /// vertices of two faces), and the mesh has one.
    #[error("{scheme} has no rules for {feature}, but the mesh has them ({element})")]
    FeatureNotSupported {
        /// The scheme's name.
        scheme: String,
        /// `boundaries`, `creases`, `corners`, `holes`, or (the dual splits) interior vertices of
        /// two faces.
        feature: &'static str,
        /// The first element that has it, e.g. `edge 3-7`.
        element: String,
    },
    /// The scheme's split has no such construction (sub-patch matrices of a dual split).
    #[error("{scheme}: {what} are not available for the {split} split: {reason}")]
    SplitNotSupported {
        /// The scheme's name.
        scheme: String,
        /// What was asked for, e.g. `sub-patch matrices`.
        what: &'static str,
        /// The split, e.g. `dual`.
        split: &'static str,
        /// Why not.
        reason: &'static str,
    },
    /// The analysis cannot take this valence.
    #[error("{scheme}: valence {valence} is not supported; {reason}")]
    ValenceNotSupported {
        /// The scheme's name.
        scheme: String,
        /// The valence asked for.
        valence: usize,
        /// What the analysis needs.
        reason: &'static str,
    },
    /// A scheme file does not parse (syntax, unknown field, bad formula).
    #[error("cannot read the scheme ({format}): {message}")]
    Parse {
        /// `TOML` or `RON`.
        format: &'static str,
        /// The parser's message, with the place.
        message: String,
    },
    /// A scheme's masks break a rule (weights that do not sum to 1, a table of the wrong size).
    #[error("scheme `{scheme}`, rule `{rule}`: {detail}")]
    InvalidScheme {
        /// The scheme's name.
        scheme: String,
        /// The rule, as its path in the scheme file (`vertex`, `edge.extraordinary`, ...).
        rule: String,
        /// What is wrong, with the valence.
        detail: String,
    },
    /// A vertex whose valence is past its limit ([`ValenceLimit`](crate::ValenceLimit):
    /// [`RefineOptions::max_patch_valence`](crate::RefineOptions) for a smooth one,
    /// `max_dense_patch_valence` for the others), refused before its sub-patch matrices are
    /// derived.
    #[error(
        "{vertex} has valence {valence} (an N-gon of as many sides has such a centre once refined), more than \
         the limit of {limit} for {kind}"
    )]
    ValenceTooLarge {
        /// The vertex.
        vertex: subdiv_mesh::VertexId,
        /// Its valence.
        valence: usize,
        /// The limit in force.
        limit: usize,
        /// Which limit.
        kind: crate::ValenceLimit,
    },
    /// The eigen solver did not converge.
    #[error("the eigen solver did not converge: {0}")]
    Eigen(String),
    /// A table file (committed sub-patch matrices) that cannot be read: another kind of file,
    /// version or scheme, or corrupt bytes.
    #[error("patch table: {0}")]
    Table(String),
    /// The refined mesh broke a topology rule: a bug, please report it.
    #[error("internal error, please report: {0}")]
    Internal(String),
}
