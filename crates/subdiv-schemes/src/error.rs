//! [`SchemeError`].

use subdiv_mesh::FaceId;

use crate::Scheme;

/// Why a scheme cannot refine a mesh.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SchemeError {
    /// The scheme takes only faces of one size (Loop: triangles).
    #[error("{scheme} takes only {expected}-sided faces, but {face} has {size} sides")]
    FaceNotSupported {
        /// The scheme.
        scheme: Scheme,
        /// The first face it cannot take.
        face: FaceId,
        /// That face's size.
        size: usize,
        /// The size the scheme takes.
        expected: usize,
    },
    /// The analysis needs an interior vertex of valence at least 3.
    #[error("{scheme}: valence {valence} is not supported; analysis needs valence 3 or more")]
    ValenceNotSupported {
        /// The scheme.
        scheme: Scheme,
        /// The valence asked for.
        valence: usize,
    },
    /// The eigen solver did not converge.
    #[error("the eigen solver did not converge: {0}")]
    Eigen(String),
    /// The refined mesh broke a topology rule: a bug, please report it.
    #[error("internal error, please report: {0}")]
    Internal(String),
}
