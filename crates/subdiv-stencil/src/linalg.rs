//! The floating-point linear algebra both stencil routes share: eigenspaces by SVD, and the one
//! vector of an eigenspace that meets given normalisations.

use faer::Mat;

/// Singular values below this count as zero.
pub(crate) const NULL_TOLERANCE: f64 = 1e-9;

/// The residual the normalisations may leave.
const RESIDUAL_TOLERANCE: f64 = 1e-8;

/// Vectors spanning a space, each as long as the matrix is wide.
pub(crate) type Basis = Vec<Vec<f64>>;

/// Orthonormal bases of the null space of the square matrix `a` (`a x = 0`) and of its left
/// null space (`w a = 0`), from one SVD: the right and the left singular vectors whose singular
/// values are below [`NULL_TOLERANCE`] (as many of each). Half the work of two
/// [`null_space`] calls, which an eigenvalue's terms need both of (an SVD of a matrix of the
/// ring at valence 500 was 15 % of a tessellation).
pub(crate) fn null_spaces(a: &Mat<f64>) -> Result<(Basis, Basis), String> {
    let null = singular_null_vectors(a)?;
    Ok((null.right, null.left))
}

/// A basis of the eigenspace of `m` for the real eigenvalue `lambda`: right eigenvectors
/// (`M x = λ x`), or left ones (`w M = λ w`) if `left`; the right singular vectors of the
/// shifted matrix whose singular values are below [`NULL_TOLERANCE`].
pub(crate) fn eigenspace(m: &Mat<f64>, lambda: f64, left: bool) -> Result<Vec<Vec<f64>>, String> {
    let n = m.nrows();
    null_space(&Mat::<f64>::from_fn(n, n, |i, j| m[(i, j)] - if i == j { lambda } else { 0.0 }), left)
}

/// An orthonormal basis of the null space of the square matrix `a` (`a x = 0`), or of its left
/// null space (`w a = 0`) if `left`: the right singular vectors (of `a`, or of its transpose)
/// whose singular values are below [`NULL_TOLERANCE`].
pub(crate) fn null_space(a: &Mat<f64>, left: bool) -> Result<Vec<Vec<f64>>, String> {
    let a = if left { a.transpose().to_owned() } else { a.clone() };
    Ok(singular_null_vectors(&a)?.right)
}

/// The right and left singular vectors of the square matrix `a` whose singular values are below
/// [`NULL_TOLERANCE`].
struct NullVectors {
    right: Basis,
    left: Basis,
}

/// [`NullVectors`] of `a` from its SVD. The iteration does not converge on a few matrices (a
/// Loop period of 28 steps at a parameter of denominator 645); that of the transpose takes
/// another path, and its singular vectors are these with their sides swapped.
fn singular_null_vectors(a: &Mat<f64>) -> Result<NullVectors, String> {
    let n = a.nrows();
    let columns = |sigma: faer::ColRef<'_, f64>, vectors: faer::MatRef<'_, f64>| -> Basis {
        (0..n).filter(|&c| sigma[c] < NULL_TOLERANCE).map(|c| (0..n).map(|r| vectors[(r, c)]).collect()).collect()
    };
    match a.svd() {
        Ok(svd) => {
            let sigma = svd.S().column_vector();
            Ok(NullVectors { right: columns(sigma, svd.V()), left: columns(sigma, svd.U()) })
        }
        Err(first) => {
            let svd = a.transpose().to_owned().svd().map_err(|e| format!("SVD failed: {first:?}, then {e:?}"))?;
            let sigma = svd.S().column_vector();
            Ok(NullVectors { right: columns(sigma, svd.U()), left: columns(sigma, svd.V()) })
        }
    }
}

/// Left eigenvectors `w` of `m` for `lambda` normalised by linear conditions: solution `k` has
/// `w · rows[r] = values[k][r]` for every `r`.
pub(crate) struct Normalised {
    /// One vector per list of values.
    pub(crate) vectors: Vec<Vec<f64>>,
    /// The eigenspace's dimension.
    pub(crate) multiplicity: usize,
}

/// See [`Normalised`]. Errors name what failed: `lambda` is no eigenvalue, the normalisations
/// do not single out one vector of the eigenspace, or they cannot all be met.
pub(crate) fn normalised_left_eigenvectors(
    m: &Mat<f64>,
    lambda: f64,
    rows: &[Vec<f64>],
    values: &[Vec<f64>],
) -> Result<Normalised, String> {
    let basis = eigenspace(m, lambda, true)?;
    let d = basis.len();
    if d == 0 {
        return Err(format!("{lambda} is not an eigenvalue"));
    }
    if d > rows.len() {
        // Fewer normalisations than dimensions (the bilinear scheme's eigenvalue 1 is not simple).
        return Err(format!("the normalisations do not single out one vector of the {d}-dimensional eigenspace"));
    }
    // The normalisations on the basis, B c = b, solved by the pseudo-inverse of B.
    let b = Mat::<f64>::from_fn(rows.len(), d, |r, c| rows[r].iter().zip(&basis[c]).map(|(x, y)| x * y).sum());
    let svd = b.thin_svd().map_err(|e| format!("SVD failed: {e:?}"))?;
    let s = svd.S().column_vector();
    let largest = (0..d).map(|i| s[i]).fold(0.0, f64::max);
    if (0..d).any(|i| s[i] <= NULL_TOLERANCE * largest.max(1.0)) {
        return Err(format!("the normalisations do not single out one vector of the {d}-dimensional eigenspace"));
    }
    let (u, v) = (svd.U(), svd.V());
    let mut vectors = Vec::with_capacity(values.len());
    for want in values {
        let c: Vec<f64> = (0..d)
            .map(|i| (0..d).map(|t| v[(i, t)] * (0..rows.len()).map(|r| u[(r, t)] * want[r]).sum::<f64>() / s[t]).sum())
            .collect();
        let w: Vec<f64> = (0..m.nrows()).map(|i| (0..d).map(|k| basis[k][i] * c[k]).sum()).collect();
        let residual = rows
            .iter()
            .zip(want)
            .map(|(row, b)| (row.iter().zip(&w).map(|(x, y)| x * y).sum::<f64>() - b).abs())
            .fold(0.0, f64::max);
        if residual > RESIDUAL_TOLERANCE {
            return Err(format!("the normalisations are not met (residual {residual:e})"));
        }
        vectors.push(w);
    }
    Ok(Normalised { vectors, multiplicity: d })
}
