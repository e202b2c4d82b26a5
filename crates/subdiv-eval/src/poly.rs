//! The regular patch as a polynomial in the power basis: fitted to the scheme's exact stencils,
//! verified, and evaluated by Horner's rule.

use faer::Mat;
use faer::linalg::solvers::Solve;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock, PoisonError};
use subdiv_mesh::DVec3;

use subdiv_schemes::{ChildDomain, PatchMatrices};
use subdiv_stencil::{Dyadic, Rational, StencilError, StencilEvaluator, exact_surface_positions};

use crate::EvalError;

/// The polynomial space of a regular patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PolyKind {
    /// Degree 3 in each of `s` and `t` (16 monomials `s^a t^b`, index `4a + b`): quads.
    Bicubic,
    /// Total degree 4 (15 monomials `s^a t^b`, `a + b ≤ 4`, rows of equal `a` in turn):
    /// triangles.
    Quartic,
}

/// First index of row `a` (the monomials `s^a t^b`) of the quartic layout.
const QUARTIC_ROWS: [usize; 6] = [0, 5, 9, 12, 14, 15];

impl PolyKind {
    /// The space for faces of `face_size` sides.
    pub fn for_face(face_size: usize) -> Self {
        if face_size == 3 { Self::Quartic } else { Self::Bicubic }
    }

    /// The number of monomials.
    pub fn monomials(self) -> usize {
        match self {
            Self::Bicubic => 16,
            Self::Quartic => 15,
        }
    }

    /// The exponents `(a, b)` of monomial `index`.
    fn exponents(self, index: usize) -> (usize, usize) {
        match self {
            Self::Bicubic => (index / 4, index % 4),
            Self::Quartic => {
                let a = (0..5).rev().find(|&a| QUARTIC_ROWS[a] <= index).unwrap_or(0);
                (a, index - QUARTIC_ROWS[a])
            }
        }
    }

    /// The unisolvent fitting points: `(i/3, j/3)` for the bicubic, the triangle lattice
    /// `(i/4, j/4)`, `i + j ≤ 4`, for the quartic.
    fn fitting_points(self) -> Vec<Dyadic> {
        match self {
            Self::Bicubic => (0..4).flat_map(|j| (0..4).map(move |i| Dyadic::new(i, j, 3))).collect(),
            Self::Quartic => (0..5).flat_map(|j| (0..5 - j).map(move |i| Dyadic::new(i, j, 4))).collect(),
        }
    }

    /// Points off the fitting set where the fit is checked, inside the domain.
    fn check_points(self) -> [Dyadic; 4] {
        [Dyadic::new(1, 2, 7), Dyadic::new(2, 1, 9), Dyadic::new(3, 1, 10), Dyadic::new(1, 4, 13)]
    }

    /// Rows `(first index, count)` of monomials with equal power of `s`.
    fn row(self, a: usize) -> (usize, usize) {
        match self {
            Self::Bicubic => (4 * a, 4),
            Self::Quartic => (QUARTIC_ROWS[a], 5 - a),
        }
    }

    /// The highest power of `s`.
    fn degree_s(self) -> usize {
        match self {
            Self::Bicubic => 3,
            Self::Quartic => 4,
        }
    }
}

/// The monomial values `s^a t^b` and their first derivatives, in `kind`'s order.
fn monomials(kind: PolyKind, s: f64, t: f64) -> Vec<[f64; 3]> {
    (0..kind.monomials())
        .map(|i| {
            let (a, b) = kind.exponents(i);
            let p = |x: f64, n: usize| if n == 0 { 1.0 } else { x.powi(n as i32) };
            let d = |x: f64, n: usize| if n == 0 { 0.0 } else { n as f64 * p(x, n - 1) };
            [p(s, a) * p(t, b), d(s, a) * p(t, b), p(s, a) * d(t, b)]
        })
        .collect()
}

/// The values (`which` 0), `∂/∂s` (1) or `∂/∂t` (2) of the monomials at `(s, t)`.
pub(crate) fn monomial_row(kind: PolyKind, s: f64, t: f64, which: usize) -> Vec<f64> {
    monomials(kind, s, t).into_iter().map(|m| m[which]).collect()
}

/// The power-basis matrix of a polynomial shape: row `i` holds the weights, over the shape's
/// control points, of the coefficient of monomial `i`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PowerBasis {
    pub(crate) kind: PolyKind,
    /// Control points of the shape.
    pub(crate) size: usize,
    /// `kind.monomials() × size`, row-major.
    pub(crate) weights: Vec<f64>,
}

/// Everything a shape's fit reads: the face size, and for each shape its walks reach (in the
/// order first reached from `shape`) its size, influence set and parameters, and each child's
/// shape (by that order), domain and matrix, as bits. Two shapes with equal keys have the same
/// stencils at every point, so the same fit.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct FitKey {
    face_size: usize,
    words: Vec<u64>,
}

impl FitKey {
    fn of(matrices: &PatchMatrices, shape: usize) -> Self {
        let mut order = vec![shape];
        let mut words = Vec::new();
        let mut next = 0;
        while let Some(&s) = order.get(next) {
            next += 1;
            let this = &matrices.shapes[s];
            words.push(this.size as u64);
            words.push(this.influence.len() as u64);
            words.extend(this.influence.iter().map(|&k| u64::from(k)));
            match &this.parameters {
                Some([u, v]) => words.extend(u.iter().chain(v).map(|x| x.to_bits())),
                None => words.push(u64::MAX),
            }
            words.push(this.children.len() as u64);
            for child in &this.children {
                let local = order.iter().position(|&o| o == child.shape).unwrap_or_else(|| {
                    order.push(child.shape);
                    order.len() - 1
                });
                words.push(local as u64);
                let ChildDomain { offset, flipped, scale } = child.domain;
                words.push(
                    u64::from(offset[0])
                        | u64::from(offset[1]) << 8
                        | u64::from(flipped) << 16
                        | u64::from(scale) << 24,
                );
                words.extend((0..child.rows()).flat_map(|r| child.dense_row(r)).map(f64::to_bits));
            }
        }
        Self { face_size: matrices.face_size, words }
    }
}

/// Tolerance of the fit's check against the exact stencils, on weights of order 1.
const FIT_TOLERANCE: f64 = 1e-11;

impl PowerBasis {
    /// Fits the limit surface of `shape` of `matrices` with the polynomial space of its face
    /// size, from its position stencils at the unisolvent points (exact fractions where the
    /// matrices are rational, f64 otherwise), and checks the fit (positions and derivatives)
    /// at other points, within [`FIT_TOLERANCE`] of their f64 stencils.
    ///
    /// The check points have long periods (denominators 7, 9, 10, 13), so their exact
    /// stencils would multiply fractions of hundreds of digits: a check within a tolerance
    /// needs none of that, and f64 keeps the fit of a shape to milliseconds.
    ///
    /// Fits are kept for the process by what they depend on ([`FitKey`]), so the polynomial
    /// children of every valence's extraordinary patch (equal matrices, other signatures) and
    /// the regular patch are fitted once.
    pub(crate) fn fit(matrices: &PatchMatrices, shape: usize) -> Result<Self, EvalError> {
        static CACHE: OnceLock<Mutex<HashMap<FitKey, PowerBasis>>> = OnceLock::new();
        let key = FitKey::of(matrices, shape);
        let cache = CACHE.get_or_init(Mutex::default);
        if let Some(found) = cache.lock().unwrap_or_else(PoisonError::into_inner).get(&key) {
            return Ok(found.clone());
        }
        // Refusals are not kept here: their messages name the shape (`EigenBasis::of` keeps them).
        let fitted = Self::fit_uncached(matrices, shape)?;
        cache.lock().unwrap_or_else(PoisonError::into_inner).entry(key).or_insert_with(|| fitted.clone());
        Ok(fitted)
    }

    fn fit_uncached(matrices: &PatchMatrices, shape: usize) -> Result<Self, EvalError> {
        let kind = PolyKind::for_face(matrices.face_size);
        let size = matrices.shapes[shape].size;
        let not_polynomial = |detail: String| EvalError::NotEigenPatch {
            scheme: matrices.scheme.clone(),
            shape,
            patch: format!("{:?}", matrices.patch_type),
            detail,
        };
        let points = kind.fitting_points();
        let n = kind.monomials();
        let vandermonde = Mat::<f64>::from_fn(n, n, |r, c| {
            let (u, v) = points[r].to_f64();
            monomials(kind, u, v)[c][0]
        });
        // The f64 stencils of the check points, and of the fitting points when the exact ones
        // are refused: one evaluator, whose states the two sets share.
        let mut evaluator = StencilEvaluator::new(matrices);
        let stencils: Vec<Vec<f64>> = match exact_surface_positions(matrices, shape, &points) {
            Ok(exact) => exact.iter().map(|w| w.iter().map(Rational::to_f64).collect()).collect(),
            // Irrational regular weights (a user's scheme): the f64 stencils fit as well.
            Err(StencilError::NotRational { .. }) => points
                .iter()
                .map(|&p| Ok(evaluator.stencil(shape, p)?.position.clone()))
                .collect::<Result<_, EvalError>>()?,
            Err(e) => return Err(e.into()),
        };
        let rhs = Mat::<f64>::from_fn(n, size, |r, c| stencils[r][c]);
        let solution = vandermonde.partial_piv_lu().solve(&rhs);
        let weights: Vec<f64> =
            (0..n).flat_map(|r| (0..size).map(move |c| (r, c))).map(|(r, c)| solution[(r, c)]).collect();
        let basis = Self { kind, size, weights };
        for p in kind.check_points() {
            let s = evaluator.stencil(shape, p)?;
            let (u, v) = p.to_f64();
            let m = monomials(kind, u, v);
            for (which, want) in [&s.position, &s.du, &s.dv].into_iter().enumerate() {
                for (k, &w) in want.iter().enumerate() {
                    let got: f64 = (0..n).map(|i| m[i][which] * basis.weights[i * size + k]).sum();
                    if (got - w).abs() > FIT_TOLERANCE {
                        return Err(not_polynomial(format!(
                            "its limit surface is not a polynomial of the {kind:?} space: at ({u}, {v}) the fit's \
                             weight {k} ({}) is {got}, the stencil's {w}",
                            ["position", "d/du", "d/dv"][which]
                        )));
                    }
                }
            }
        }
        Ok(basis)
    }

    /// The power-basis coefficients of `points` (in the shape's order).
    pub(crate) fn coefficients(&self, points: &[DVec3]) -> Vec<DVec3> {
        self.weights.chunks_exact(self.size).map(|row| row.iter().zip(points).map(|(&w, &p)| w * p).sum()).collect()
    }

    /// The composed matrix `self · m` (`m`: `size × columns`, row-major), row-major.
    pub(crate) fn compose(&self, m: &[f64], columns: usize) -> Vec<f64> {
        let mut out = vec![0.0; self.kind.monomials() * columns];
        for (row, out_row) in self.weights.chunks_exact(self.size).zip(out.chunks_exact_mut(columns)) {
            for (&w, m_row) in row.iter().zip(m.chunks_exact(columns)) {
                for (o, &x) in out_row.iter_mut().zip(m_row) {
                    *o += w * x;
                }
            }
        }
        out
    }
}

/// Position and first derivatives of the polynomial with coefficients `c` at `(s, t)`.
#[inline]
pub(crate) fn eval1(kind: PolyKind, c: &[DVec3], s: f64, t: f64) -> [DVec3; 3] {
    match kind {
        PolyKind::Bicubic => eval1_rows::<4>(c, s, t, |a| (4 * a, 4)),
        PolyKind::Quartic => eval1_rows::<5>(c, s, t, |a| (QUARTIC_ROWS[a], 5 - a)),
    }
}

/// Horner's rule along `t` within each row of equal power of `s`, then along `s`.
#[inline(always)]
fn eval1_rows<const R: usize>(c: &[DVec3], s: f64, t: f64, row: impl Fn(usize) -> (usize, usize)) -> [DVec3; 3] {
    let (mut p, mut ps, mut pt) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for a in (0..R).rev() {
        let (first, count) = row(a);
        let coefficients = &c[first..first + count];
        // q(t) and q'(t) of row a.
        let mut q = coefficients[count - 1];
        let mut dq = DVec3::ZERO;
        for &x in coefficients[..count - 1].iter().rev() {
            dq = dq * t + q;
            q = q * t + x;
        }
        // ∂s of Σ q_a s^a by Horner: the derivative accumulates the value before each step.
        ps = ps * s + p;
        p = p * s + q;
        pt = pt * s + dq;
    }
    [p, ps, pt]
}

/// A point padded to four lanes, so that Horner steps compile to two 2-wide SIMD operations
/// (SSE2, the baseline) instead of three scalar ones.
pub(crate) type Lanes = [f64; 4];

/// `a · x + b`, lane by lane.
#[inline(always)]
fn lanes_step(a: Lanes, x: f64, b: Lanes) -> Lanes {
    [a[0] * x + b[0], a[1] * x + b[1], a[2] * x + b[2], a[3] * x + b[3]]
}

/// A point as [`Lanes`].
#[inline(always)]
pub(crate) fn lanes(p: DVec3) -> Lanes {
    [p.x, p.y, p.z, 0.0]
}

/// [`eval1`] on coefficients in [`Lanes`]: the hot path.
#[inline]
pub(crate) fn eval1_lanes(kind: PolyKind, c: &[Lanes], s: f64, t: f64) -> [DVec3; 3] {
    let out = match kind {
        PolyKind::Bicubic => eval1_lanes_rows::<4>(c, s, t, |a| (4 * a, 4)),
        PolyKind::Quartic => eval1_lanes_rows::<5>(c, s, t, |a| (QUARTIC_ROWS[a], 5 - a)),
    };
    out.map(|l| DVec3::new(l[0], l[1], l[2]))
}

#[inline(always)]
fn eval1_lanes_rows<const R: usize>(c: &[Lanes], s: f64, t: f64, row: impl Fn(usize) -> (usize, usize)) -> [Lanes; 3] {
    let zero = [0.0; 4];
    let (mut p, mut ps, mut pt) = (zero, zero, zero);
    for a in (0..R).rev() {
        let (first, count) = row(a);
        let coefficients = &c[first..first + count];
        let mut q = coefficients[count - 1];
        let mut dq = zero;
        for &x in coefficients[..count - 1].iter().rev() {
            dq = lanes_step(dq, t, q);
            q = lanes_step(q, t, x);
        }
        ps = lanes_step(ps, s, p);
        p = lanes_step(p, s, q);
        pt = lanes_step(pt, s, dq);
    }
    [p, ps, pt]
}

/// [`eval2`] on coefficients in [`Lanes`].
pub(crate) fn eval2_lanes(kind: PolyKind, c: &[Lanes], s: f64, t: f64) -> [DVec3; 6] {
    let zero = [0.0; 4];
    let mut out = [zero; 6];
    for a in (0..=kind.degree_s()).rev() {
        let (first, count) = kind.row(a);
        let coefficients = &c[first..first + count];
        let (mut q, mut dq, mut ddq) = (coefficients[count - 1], zero, zero);
        for &x in coefficients[..count - 1].iter().rev() {
            ddq = lanes_step(ddq, t, dq.map(|d| 2.0 * d));
            dq = lanes_step(dq, t, q);
            q = lanes_step(q, t, x);
        }
        let [p, ps, pt, pss, pst, ptt] = &mut out;
        *pss = lanes_step(*pss, s, ps.map(|d| 2.0 * d));
        *ps = lanes_step(*ps, s, *p);
        *p = lanes_step(*p, s, q);
        *pst = lanes_step(*pst, s, *pt);
        *pt = lanes_step(*pt, s, dq);
        *ptt = lanes_step(*ptt, s, ddq);
    }
    out.map(|l| DVec3::new(l[0], l[1], l[2]))
}

/// Position, first and second derivatives `[p, ps, pt, pss, pst, ptt]` at `(s, t)`.
pub(crate) fn eval2(kind: PolyKind, c: &[DVec3], s: f64, t: f64) -> [DVec3; 6] {
    let mut out = [DVec3::ZERO; 6];
    let degree = kind.degree_s();
    for a in (0..=degree).rev() {
        let (first, count) = kind.row(a);
        let coefficients = &c[first..first + count];
        let (mut q, mut dq, mut ddq) = (coefficients[count - 1], DVec3::ZERO, DVec3::ZERO);
        for &x in coefficients[..count - 1].iter().rev() {
            ddq = ddq * t + 2.0 * dq;
            dq = dq * t + q;
            q = q * t + x;
        }
        let [p, ps, pt, pss, pst, ptt] = &mut out;
        *pss = *pss * s + 2.0 * *ps;
        *ps = *ps * s + *p;
        *p = *p * s + q;
        *pst = *pst * s + *pt;
        *pt = *pt * s + dq;
        *ptt = *ptt * s + ddq;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use subdiv_mesh::BoundaryInterpolation;
    use subdiv_schemes::{Builtin, PatchType};

    /// The shared fits are sound: the polynomial children of two valences' extraordinary
    /// patches have one key, and fitting each on its own gives the same bits; the
    /// extraordinary shape has another key.
    #[test]
    fn equal_fit_keys_have_equal_fits() {
        for (builtin, valences) in [(Builtin::CatmullClark, [3, 5]), (Builtin::Loop, [4, 8])] {
            let of = |valence| {
                PatchMatrices::of(builtin.scheme(), PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)
                    .unwrap()
            };
            let (a, b) = (of(valences[0]), of(valences[1]));
            let polynomial = |m: &PatchMatrices| -> Vec<usize> {
                let children = &m.shapes[0].children;
                children.iter().map(|c| c.shape).filter(|&s| s != 0).collect()
            };
            let (pa, pb) = (polynomial(&a), polynomial(&b));
            assert_eq!(pa.len(), pb.len());
            for (&sa, &sb) in pa.iter().zip(&pb) {
                assert_ne!(a.shapes[sa].signature, b.shapes[sb].signature, "{builtin:?}: the valences differ");
                assert_eq!(FitKey::of(&a, sa), FitKey::of(&b, sb), "{builtin:?}");
                let (fa, fb) = (PowerBasis::fit_uncached(&a, sa).unwrap(), PowerBasis::fit_uncached(&b, sb).unwrap());
                assert_eq!(fa, fb, "{builtin:?}");
            }
            // The extraordinary shape itself reads other matrices.
            assert_ne!(FitKey::of(&a, 0), FitKey::of(&a, pa[0]));
        }
    }

    /// Horner's rule against the monomials, term by term, with derivatives by hand.
    #[test]
    fn horner_matches_the_monomials() {
        for kind in [PolyKind::Bicubic, PolyKind::Quartic] {
            let c: Vec<DVec3> = (0..kind.monomials())
                .map(|i| DVec3::new(i as f64 + 1.0, (i * i) as f64 * 0.1, 1.0 / (i as f64 + 2.0)))
                .collect();
            let (s, t) = (0.37, 0.21);
            let m = monomials(kind, s, t);
            let want: [DVec3; 3] = std::array::from_fn(|k| (0..kind.monomials()).map(|i| m[i][k] * c[i]).sum());
            let got = eval1(kind, &c, s, t);
            let l: Vec<Lanes> = c.iter().map(|&p| lanes(p)).collect();
            assert_eq!(eval1_lanes(kind, &l, s, t), got);
            assert_eq!(eval2_lanes(kind, &l, s, t), eval2(kind, &c, s, t));
            let second = eval2(kind, &c, s, t);
            // Second derivatives against central differences of the first.
            let h = 1e-5;
            let ds = |ds: f64, dt: f64| eval1(kind, &c, s + ds, t + dt);
            let pss = (ds(h, 0.0)[1] - ds(-h, 0.0)[1]) / (2.0 * h);
            let pst = (ds(0.0, h)[1] - ds(0.0, -h)[1]) / (2.0 * h);
            let ptt = (ds(0.0, h)[2] - ds(0.0, -h)[2]) / (2.0 * h);
            for k in 0..3 {
                assert!((got[k] - want[k]).length() < 1e-12, "{kind:?} {k}: {} vs {}", got[k], want[k]);
                assert!((second[k] - want[k]).length() < 1e-12);
            }
            for (a, b) in [(second[3], pss), (second[4], pst), (second[5], ptt)] {
                assert!((a - b).length() < 1e-6 * (1.0 + b.length()), "{kind:?}: {a} vs {b}");
            }
        }
    }
}
