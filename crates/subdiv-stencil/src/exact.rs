//! Exact surface stencils for schemes whose sub-patch matrices are rational: the matrices read
//! back as fractions (checked: every row sums to exactly 1), the cycle's eigenvectors solved in
//! exact rational arithmetic, and carried back through the prefix exactly.

use std::collections::HashMap;

use subdiv_schemes::{PatchMatrices, SubPatch};

use crate::address::{MAX_ADDRESS_STEPS, Walked};
use crate::rational::{SparseRow, fraction_within, solve_sparse};
use crate::surface::{State, address_walk, check_request, periodic_derivatives};
use crate::{Dyadic, Rational, StencilError};

/// Matrix entries are read back as fractions with denominators up to this.
const MAX_DENOMINATOR: u64 = 1 << 24;

/// Position and tangent weights as exact fractions (see [`exact_surface_stencil`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactSurfaceStencil {
    /// Position weights; they sum to exactly 1.
    pub position: Vec<Rational>,
    /// `[∂/∂u, ∂/∂v]` weights, each summing to exactly 0; `None` at an extraordinary vertex
    /// itself, where the parameterization has no derivative (and the tangent directions are
    /// not rational in general).
    pub derivatives: Option<[Vec<Rational>; 2]>,
}

/// The stencil of `point` in the patch of shape `shape`, in exact fractions: the same
/// eigenvector problems as [`surface_stencil`](crate::surface_stencil), solved exactly.
///
/// ```
/// use subdiv_mesh::BoundaryInterpolation;
/// use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
/// use subdiv_stencil::{exact_surface_stencil, Dyadic, Rational};
///
/// let cc = Builtin::CatmullClark.scheme();
/// let m = PatchMatrices::of(cc, PatchType::interior(5), BoundaryInterpolation::EdgeOnly)?;
/// let s = exact_surface_stencil(&m, 0, Dyadic::new(0, 0, 1))?;
/// // The extraordinary vertex: k/(k + 5) on itself.
/// assert_eq!(s.position[0], Rational::new(1, 2).unwrap());
/// assert_eq!(s.position.iter().sum::<Rational>(), Rational::one());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`StencilError::NotRational`] when a sub-patch matrix entry is not a fraction (Loop's
/// weights at most valences involve cos 2π/k); otherwise as
/// [`surface_stencil`](crate::surface_stencil).
pub fn exact_surface_stencil(
    matrices: &PatchMatrices,
    shape: usize,
    point: Dyadic,
) -> Result<ExactSurfaceStencil, StencilError> {
    exact_stencil(matrices, shape, point, true, &mut Memo::default())
}

/// The position weights of [`exact_surface_stencil`] at each of `points`, without the two
/// eigenvector problems of the derivatives: what fitting a polynomial patch to its stencils
/// needs. The points share the work: each sub-patch matrix is read back as fractions once, and
/// points whose walks enter a cycle at the same state share its eigenvector.
///
/// ```
/// use subdiv_mesh::BoundaryInterpolation;
/// use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
/// use subdiv_stencil::{exact_surface_positions, exact_surface_stencil, Dyadic};
///
/// let cc = Builtin::CatmullClark.scheme();
/// let m = PatchMatrices::of(cc, PatchType::interior(4), BoundaryInterpolation::EdgeOnly)?;
/// let points = [Dyadic::new(1, 2, 3), Dyadic::new(2, 1, 3)];
/// let positions = exact_surface_positions(&m, 0, &points)?;
/// assert_eq!(positions[1], exact_surface_stencil(&m, 0, points[1])?.position);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`exact_surface_stencil`], for the first point that fails.
pub fn exact_surface_positions(
    matrices: &PatchMatrices,
    shape: usize,
    points: &[Dyadic],
) -> Result<Vec<Vec<Rational>>, StencilError> {
    let mut memo = Memo::default();
    points.iter().map(|&p| Ok(exact_stencil(matrices, shape, p, false, &mut memo)?.position)).collect()
}

/// Work that the points of one patch share: sub-patch matrices in fractions by (shape, child),
/// and the position eigenvector of each cycle by the state the walk entered it at.
#[derive(Default)]
struct Memo {
    matrices: HashMap<(usize, u8), Vec<Vec<Rational>>>,
    cycles: HashMap<State, Vec<Rational>>,
}

/// [`exact_surface_stencil`], the derivatives only when `with_derivatives` asks for them.
fn exact_stencil(
    matrices: &PatchMatrices,
    shape: usize,
    point: Dyadic,
    with_derivatives: bool,
    memo: &mut Memo,
) -> Result<ExactSurfaceStencil, StencilError> {
    check_request(matrices, shape, point)?;
    let (walk, end) = address_walk(matrices, shape, point, |_| false, MAX_ADDRESS_STEPS)?;
    let Walked::Cycle(first) = end else { unreachable!("a walk that knows no state ends in a cycle") };
    let sub = |(s, c): (State, u8)| &matrices.shapes[s.shape].children[usize::from(c)];
    for &(s, c) in &walk {
        if let std::collections::hash_map::Entry::Vacant(slot) = memo.matrices.entry((s.shape, c)) {
            slot.insert(exact_matrix(matrices, sub((s, c)))?);
        }
    }
    let exact: Vec<&Vec<Vec<Rational>>> = walk.iter().map(|&(s, c)| &memo.matrices[&(s.shape, c)]).collect();

    // M_τ over the cycle, applied first to last, on the points that influence the face (as the
    // floating-point route solves it: the others have eigenvalues of their own, and weight 0);
    // not formed when the cycle's position is known and no derivative is asked for.
    let periodic = &matrices.shapes[walk[first].0.shape];
    let size = periodic.size;
    let flips: usize = walk[first..].iter().map(|&w| usize::from(sub(w).domain.flipped)).sum();
    let influence: Vec<usize> = periodic.influence.iter().map(|&k| k as usize).collect();
    let known = memo.cycles.get(&walk[first].0).cloned();
    let m: Vec<Vec<Rational>> = if known.is_none() || with_derivatives {
        let mut m = exact[first].clone();
        for step in &exact[first + 1..] {
            m = multiply(step, &m);
        }
        influence.iter().map(|&i| influence.iter().map(|&j| m[i][j].clone()).collect()).collect()
    } else {
        Vec::new()
    };
    let on_influence = |w: &[Rational]| -> Vec<Rational> { influence.iter().map(|&k| w[k].clone()).collect() };
    let widen = |w: Vec<Rational>| -> Vec<Rational> {
        let mut out = vec![Rational::zero(); size];
        influence.iter().zip(w).for_each(|(&k, x)| out[k] = x);
        out
    };
    let fail = |what: &str, detail: String| StencilError::Eigen {
        scheme: matrices.scheme.clone(),
        detail: format!("exact {what} at {point:?}: {detail}"),
    };
    let ones = vec![Rational::one(); influence.len()];
    let mut position = match known {
        Some(known) => known,
        None => {
            let solved = widen(
                left_eigenvector(&m, &Rational::one(), &[(&ones, Rational::one())])
                    .map_err(|e| fail("positions", e))?,
            );
            memo.cycles.insert(walk[first].0, solved.clone());
            solved
        }
    };
    let period = walk.len() - first;
    let scale = num_bigint::BigInt::from(matrices.scale());
    let lambda = Rational::new(if flips % 2 == 1 { -1 } else { 1 }, num_traits::Pow::pow(&scale, period))
        .expect("a nonzero denominator");
    // Whether the surface has parameter derivatives at the cycle's point: the same test as the
    // floating-point route's (the derivative pair must dominate the cycle's spectrum).
    let steps: Vec<(&SubPatch, &[u32])> =
        walk[first..].iter().map(|&w| (sub(w), matrices.shapes[w.0.shape].influence.as_slice())).collect();
    let differentiable = |u: &[f64], v: &[f64]| -> Result<bool, StencilError> {
        Ok(periodic_derivatives(&steps, u, v).map_err(|e| fail("derivatives", e))?.is_some())
    };
    let mut derivatives = match &periodic.parameters {
        Some([u, v]) if with_derivatives && differentiable(u, v)? => {
            // The parameters come from a least-squares solve: looser.
            let u = on_influence(&exact_vector(matrices, u, 1e-11)?);
            let v = on_influence(&exact_vector(matrices, v, 1e-11)?);
            let (zero, one) = (Rational::zero(), Rational::one());
            let du = left_eigenvector(&m, &lambda, &[(&ones, zero.clone()), (&u, one.clone()), (&v, zero.clone())])
                .map_err(|e| fail("∂/∂u", e))?;
            let dv = left_eigenvector(&m, &lambda, &[(&ones, zero.clone()), (&u, zero), (&v, one)])
                .map_err(|e| fail("∂/∂v", e))?;
            Some([widen(du), widen(dv)])
        }
        _ => None,
    };
    // Back through the prefix, last step first: w ← w · A (derivatives ×±2, or ±3).
    let two = Rational::from_integer(i64::from(matrices.scale()));
    for k in (0..first).rev() {
        position = times(&position, exact[k]);
        let scale = if sub(walk[k]).domain.flipped { -&two } else { two.clone() };
        if let Some([du, dv]) = &mut derivatives {
            *du = times(du, exact[k]).iter().map(|x| x * &scale).collect();
            *dv = times(dv, exact[k]).iter().map(|x| x * &scale).collect();
        }
    }
    Ok(ExactSurfaceStencil { position, derivatives })
}

/// The sub-patch matrix in fractions, or [`StencilError::NotRational`].
fn exact_matrix(matrices: &PatchMatrices, child: &SubPatch) -> Result<Vec<Vec<Rational>>, StencilError> {
    (0..child.rows())
        .map(|r| {
            // The engine's arithmetic leaves the entries within an ulp or two of their fractions.
            let row = exact_vector(matrices, &child.dense_row(r), 1e-15)?;
            if row.iter().sum::<Rational>() != Rational::one() {
                return Err(StencilError::NotRational {
                    scheme: matrices.scheme.clone(),
                    detail: format!("a sub-patch row read back as fractions sums to {}", row.iter().sum::<Rational>()),
                });
            }
            Ok(row)
        })
        .collect()
}

/// `values` as fractions with denominators up to [`MAX_DENOMINATOR`], each within `tolerance`
/// (relative, at least absolute) of its value.
fn exact_vector(matrices: &PatchMatrices, values: &[f64], tolerance: f64) -> Result<Vec<Rational>, StencilError> {
    values
        .iter()
        .map(|&x| {
            fraction_within(x, MAX_DENOMINATOR, tolerance).ok_or_else(|| StencilError::NotRational {
                scheme: matrices.scheme.clone(),
                detail: format!("{x:e} (in its sub-patch matrices) is not a fraction with denominator ≤ 2^24"),
            })
        })
        .collect()
}

/// `a · b` for square-or-rectangular matrices in fractions.
fn multiply(a: &[Vec<Rational>], b: &[Vec<Rational>]) -> Vec<Vec<Rational>> {
    a.iter().map(|row| times(row, b)).collect()
}

/// The row vector `w` times the matrix `a`.
fn times(w: &[Rational], a: &[Vec<Rational>]) -> Vec<Rational> {
    let columns = a.first().map_or(0, Vec::len);
    let mut out = vec![Rational::zero(); columns];
    for (x, row) in w.iter().zip(a) {
        if x.is_zero() {
            continue;
        }
        for (o, y) in out.iter_mut().zip(row) {
            if !y.is_zero() {
                *o = &*o + &(x * y);
            }
        }
    }
    out
}

/// The left eigenvector `w` of `m` for `lambda` with `w · row = value` for each normalisation,
/// solved exactly: `w (M − λI) = 0` with the normalisations appended.
fn left_eigenvector(
    m: &[Vec<Rational>],
    lambda: &Rational,
    normalisations: &[(&Vec<Rational>, Rational)],
) -> Result<Vec<Rational>, String> {
    let n = m.len();
    let mut equations: Vec<(SparseRow, Rational)> = (0..n)
        .map(|j| {
            let row: SparseRow = (0..n)
                .map(|i| (i, if i == j { &m[i][j] - lambda } else { m[i][j].clone() }))
                .filter(|(_, x)| !x.is_zero())
                .collect();
            (row, Rational::zero())
        })
        .collect();
    for (row, value) in normalisations {
        equations.push((row.iter().cloned().enumerate().filter(|(_, x)| !x.is_zero()).collect(), value.clone()));
    }
    solve_sparse(n, equations).map_err(|e| e.to_string())
}
