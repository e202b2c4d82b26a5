//! The crate's one error type.

use subdiv_schemes::SchemeError;
use subdiv_stencil::StencilError;

/// Why an eigenbasis could not be built or a point could not be evaluated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EvalError {
    /// From the exact stencil route (face out of range, point outside its face, a hole, …).
    #[error(transparent)]
    Stencil(#[from] StencilError),
    /// From the sub-patch matrices (unsupported split, valence, boundary rule).
    #[error(transparent)]
    Scheme(#[from] SchemeError),
    /// The valence is outside the range the eigenbases are built for.
    #[error("valence {valence} is not supported by eigenbasis evaluation (3 to {max})")]
    Valence {
        /// The valence asked for.
        valence: usize,
        /// The largest supported valence.
        max: usize,
    },
    /// The shape's limit surface is not a polynomial of the degree its face size implies
    /// (bicubic for quads, total degree 4 for triangles), or the shape is not one the
    /// eigenbasis handles (boundary patches, a shape that neither keeps itself nor is regular).
    #[error("{scheme}: shape {shape} of {patch}: {detail}")]
    NotEigenPatch {
        /// The scheme's name.
        scheme: String,
        /// The shape, an index into the patch matrices' shapes.
        shape: usize,
        /// The patch type, in words.
        patch: String,
        /// What is missing.
        detail: String,
    },
    /// The eigen decomposition failed, or its dominant part is not semisimple.
    #[error("{scheme} at valence {valence}: {detail}")]
    Eigen {
        /// The scheme's name.
        scheme: String,
        /// The extraordinary vertex's valence.
        valence: usize,
        /// What went wrong.
        detail: String,
    },
    /// An eigenbasis table file that cannot be read: another kind of file, version or
    /// scheme, or corrupt bytes.
    #[error("eigenbasis table: {0}")]
    Table(String),
    /// [`Method::Eigen`](crate::Method::Eigen) was asked for a face it cannot evaluate.
    #[error("face {face} cannot be evaluated by eigenbasis: {reason}")]
    FaceNotSupported {
        /// The face of the input mesh.
        face: usize,
        /// Why (the first patch under it that the eigenbasis does not handle).
        reason: String,
    },
    /// Second derivatives were asked of a face evaluated by exact stencils, which give first
    /// derivatives only.
    #[error("face {face} has no second derivatives here: it is evaluated by exact stencils ({reason})")]
    NoSecondDerivatives {
        /// The face of the input mesh.
        face: usize,
        /// Why the face is not evaluated by eigenbasis.
        reason: String,
    },
    /// A control-point slice of the wrong length.
    #[error("the patch has {expected} control points, {given} were given")]
    ControlPoints {
        /// The patch size.
        expected: usize,
        /// The slice's length.
        given: usize,
    },
}
