//! Exact limit stencils of uniform curve schemes at rational parameters (Schaefer and Warren,
//! paper 000, §2–4), and the basis functions of their non-uniform cubic B-spline example.
//!
//! A uniform scheme of arity `a` with mask `s` has a basis function `φ` with the scaling
//! relation `φ(x) = Σ_i s_i φ(a·x − i)`; the limit curve of control points `p_i` (point `p_i`
//! at parameter `i`) is `Σ_i p_i φ(x − i)`. So the limit point at `x` has the *position
//! stencil* `φ(x − i)` and the *tangent stencil* `φ′(x − i)`.
//!
//! **Route 1** ([`BasisGrid::new`], paper §2 and §4): on the grid `(1/n)ℤ` the scaling relation
//! maps grid points to grid points, `φ(k/n) = Σ_i s_i φ((a·k − i·n)/n)`. Its instances at every
//! `k/n` of the support (the closed interval `[e_min, e_max]/(a − 1)`, `e` the exponents of the
//! mask) form a homogeneous system; the partition of unity `Σ_j φ(r/n − j) = 1` for **every**
//! residue `r = 0..n` (not one: the upsampled matrix below has eigenvalue 1 with multiplicity
//! above one for many `n`, and other eigenvalues of modulus 1) makes it determined. It is solved
//! exactly in [`Rational`]s, and a solution that is not unique is an error. Derivatives satisfy
//! `φ′(x) = a Σ_i s_i φ′(a·x − i)` with the normalisations `Σ_j φ′(x − j) = 0` and
//! `Σ_j (j − x) φ′(x − j) = 1` (the tangent of the line `p_j = j` is 1) for every residue.
//!
//! **Route 2** ([`EigenGrid::new`], paper §3): the same values are the left eigenvectors of
//! the subdivision matrix of the upsampled mask `ŝ(z) = s(z^n)` for eigenvalue 1 (positions)
//! and `1/a` (derivatives), combined to satisfy the same normalisations. It is computed in
//! floating point (an SVD null space) as an independent check.
//!
//! The mask of a [`CurveScheme`] is stored in `f64`; [`ExactMask::from_scheme`] recovers each
//! weight as the nearest rational with denominator at most [`ExactMask::MAX_DENOMINATOR`] and
//! checks that it reproduces the float and that every rule sums to exactly 1.
//!
//! **Local schemes** ([`LocalCurveGrid`], paper §2): a stationary scheme that is uniform away
//! from the origin and has rows of its own near it (`subdiv_schemes::LocalCurveScheme`, a file
//! like any curve scheme). The control points whose columns differ from the mask's, or whose
//! children do, have refinable functions of their own in the global parameter; with the
//! uniform one they are solved together by the route-1 system, with partition of unity at
//! every grid point around the origin. **The non-uniform cubic B-spline**
//! ([`NonUniformCubicGrid`]): knots `t_i = i` for `i ≥ 0` and `t_i = 2i` for `i < 0` (intervals
//! of 2 left of the origin, 1 right of it), refined by inserting every midpoint; the refined
//! knots are `t_i / 2`, so the scheme is stationary. Control point `p_i` (blossom `f(t_{i−1},
//! t_i, t_{i+1})`) sits at the uniform parameter `x = i` at level 0, and `i / 2^j` at level `j`.
//! Our reading of the paper: the subdivision matrix is derived here by exact knot insertion; the
//! printed 5×5 matrix of the paper is that of the mirrored knots (`t_i = 2i` for `i > 0`), see
//! [`NonUniformCubicGrid::local_matrix`]. Its rows that differ from the cubic B-spline's are
//! those of the new points `−2..=2`, and the built-in file `nonuniform-cubic-bspline` holds
//! them; the special points are `p_{−1}, p_0, p_1`. The basis function of `p_i` is the B-spline
//! `N_i(t)` on the knots `t_{i−2}..t_{i+2}` composed with `t(x) = x` for `x ≥ 0` and `2x` for
//! `x < 0`; so the functions are not smooth at 0 in `x`. (The paper attributes the kink to "x =
//! 2t for t > 0", which fits neither its knots nor its matrix: with its knots the factor 2 is on
//! the negative side, `t = 2x`; with the mirrored knots of its matrix it is `t = 2x` for `x >
//! 0`.) Its listed scaling relations use a centring of their own and are not used here; each
//! relation is read from a column of the matrix, the special functions in the global
//! parameter `x`.

use faer::Mat;
use subdiv_schemes::{CurveScheme, LocalCurveScheme, LocalRow};

use crate::StencilError;
use crate::linalg::normalised_left_eigenvectors;
use crate::rational::{Rational, SolveError, SparseRow, exact_weight, solve_sparse};

/// The largest grid rate [`BasisGrid::new`] and [`EigenGrid::new`] accept: the systems have
/// about `rate × support width` unknowns.
pub const MAX_CURVE_RATE: u32 = 1024;

/// The mask of a uniform curve scheme in exact rationals: `φ(x) = Σ_k weights[k] ·
/// φ(arity·x − (first + k))`, with no zero at either end.
///
/// ```
/// use subdiv_schemes::{CurveScheme, LocalCurveScheme, LocalRow};
/// use subdiv_stencil::Rational;
/// use subdiv_stencil::curve::ExactMask;
///
/// let four = ExactMask::from_scheme(&CurveScheme::builtin("four-point").unwrap())?;
/// assert_eq!((four.arity(), four.first()), (2, -3));
/// assert_eq!(four.weights()[0], Rational::new(-1, 16).unwrap());
/// assert_eq!(four.support(), (Rational::from_integer(-3), Rational::from_integer(3)));
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactMask {
    name: String,
    arity: u32,
    first: i64,
    weights: Vec<Rational>,
}

impl ExactMask {
    /// The largest denominator [`from_scheme`](Self::from_scheme) accepts for a weight.
    pub const MAX_DENOMINATOR: u64 = 1_000_000;

    /// The largest `|i|` of a weight `s_i` [`new`](Self::new) accepts (grid numerators stay
    /// far from overflow).
    pub const MAX_INDEX: u64 = 1 << 16;

    /// A mask from exact weights (`weights[k]` is `s_{first + k}`), checked: arity 2 to
    /// [`CurveScheme::MAX_ARITY`], some weight nonzero, and each rule (the weights `s_i` with
    /// `i ≡ r` modulo the arity) summing to exactly 1. Zeros at the ends are trimmed.
    ///
    /// ```
    /// use subdiv_stencil::{Rational, StencilError};
    /// use subdiv_stencil::curve::ExactMask;
    ///
    /// let half = Rational::new(1, 2).unwrap();
    /// let linear = ExactMask::new("linear", 2, -1, vec![half.clone(), Rational::one(), half.clone()])?;
    /// assert_eq!(linear.support(), (Rational::from_integer(-1), Rational::from_integer(1)));
    /// let bad = ExactMask::new("bad", 2, -1, vec![half.clone(), Rational::one(), Rational::zero()]);
    /// assert!(matches!(bad, Err(StencilError::CurveMaskRuleSum { residue: 1, .. })));
    /// # Ok::<(), StencilError>(())
    /// ```
    ///
    /// # Errors
    /// [`StencilError::CurveMaskShape`] or [`StencilError::CurveMaskRuleSum`].
    pub fn new(name: impl Into<String>, arity: u32, first: i64, weights: Vec<Rational>) -> Result<Self, StencilError> {
        let name = name.into();
        if !(2..=CurveScheme::MAX_ARITY).contains(&arity) {
            return Err(StencilError::CurveMaskShape {
                scheme: name,
                reason: format!("arity {arity} is not 2 to {}", CurveScheme::MAX_ARITY),
            });
        }
        let Some(start) = weights.iter().position(|w| !w.is_zero()) else {
            return Err(StencilError::CurveMaskShape { scheme: name, reason: "every weight is zero".into() });
        };
        let end = weights.iter().rposition(|w| !w.is_zero()).map_or(start, |e| e + 1);
        let Some(first) = i64::try_from(start).ok().and_then(|s| first.checked_add(s)) else {
            return Err(StencilError::CurveMaskShape { scheme: name, reason: "the mask's indices overflow".into() });
        };
        let weights = weights[start..end].to_vec();
        let last = first.checked_add(weights.len() as i64 - 1);
        if first.unsigned_abs() > Self::MAX_INDEX || last.is_none_or(|l| l.unsigned_abs() > Self::MAX_INDEX) {
            return Err(StencilError::CurveMaskShape {
                scheme: name,
                reason: format!("the mask's indices reach beyond ±{}", Self::MAX_INDEX),
            });
        }
        let a = i64::from(arity);
        for residue in 0..arity {
            let sum: Rational = (weights.iter().enumerate())
                .filter(|(k, _)| (first + *k as i64 - i64::from(residue)).rem_euclid(a) == 0)
                .map(|(_, w)| w)
                .sum();
            if sum != Rational::one() {
                return Err(StencilError::CurveMaskRuleSum { scheme: name, arity, residue, sum: sum.to_string() });
            }
        }
        Ok(Self { name, arity, first, weights })
    }

    /// The exact mask of `scheme`: each `f64` weight `w` becomes the nearest rational `r` with
    /// denominator at most [`MAX_DENOMINATOR`](Self::MAX_DENOMINATOR), accepted when
    /// `|r − w| < 1e-15 · max(1, |w|)`; then the checks of [`new`](Self::new).
    ///
    /// ```
    /// use subdiv_schemes::{CurveScheme, LocalCurveScheme, LocalRow};
    /// use subdiv_stencil::StencilError;
    /// use subdiv_stencil::curve::ExactMask;
    ///
    /// let x = 1.0 / std::f64::consts::PI;
    /// let odd = CurveScheme::new("irrational", 2, 1, vec![0.5 + x, 1.0, 0.5 - x]).unwrap();
    /// assert!(matches!(ExactMask::from_scheme(&odd), Err(StencilError::CurveMaskNotRational { index: 0, .. })));
    /// ```
    ///
    /// # Errors
    /// [`StencilError::CurveMaskNotRational`], and those of [`new`](Self::new).
    pub fn from_scheme(scheme: &CurveScheme) -> Result<Self, StencilError> {
        let mut weights = Vec::with_capacity(scheme.mask().len());
        for (index, &value) in scheme.mask().iter().enumerate() {
            let Some(exact) = exact_weight(value, Self::MAX_DENOMINATOR) else {
                return Err(StencilError::CurveMaskNotRational {
                    scheme: scheme.name().to_owned(),
                    index,
                    value,
                    max_denominator: Self::MAX_DENOMINATOR,
                });
            };
            weights.push(exact);
        }
        let first = -i64::try_from(scheme.offset()).unwrap_or(i64::MAX);
        Self::new(scheme.name(), scheme.arity(), first, weights)
    }

    /// The scheme's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Children per span.
    pub fn arity(&self) -> u32 {
        self.arity
    }

    /// The index `i` of the weight `s_i` in `weights()[0]`.
    pub fn first(&self) -> i64 {
        self.first
    }

    /// The weights `s_first, s_first+1, …`.
    pub fn weights(&self) -> &[Rational] {
        &self.weights
    }

    /// The support `[e_min, e_max] / (arity − 1)` of the basis function.
    pub fn support(&self) -> (Rational, Rational) {
        let last = self.first + self.weights.len() as i64 - 1;
        let d = i64::from(self.arity) - 1;
        // Both denominators are positive and nonzero.
        let frac = |e: i64| Rational::new(e, d).unwrap_or_else(Rational::zero);
        (frac(self.first), frac(last))
    }

    /// The scaling relation as one refinable family: `(family, shift, weight)` terms.
    fn relation(&self) -> Vec<Term> {
        (self.weights.iter().enumerate())
            .filter(|(_, w)| !w.is_zero())
            .map(|(k, w)| Term { family: 0, shift: self.first + k as i64, weight: w.clone() })
            .collect()
    }
}

/// One term `weight · F_family(arity·y − shift)` of a refinement relation.
#[derive(Clone, Debug)]
struct Term {
    family: usize,
    shift: i64,
    weight: Rational,
}

/// Refinable functions `F_t(y) = Σ weight · F_u(arity·y − shift)` sampled on `(1/rate)ℤ`:
/// unknowns `F_t(k / rate)` for `k` in each family's window.
struct Refinable<'a> {
    arity: i64,
    rate: i64,
    relations: &'a [Vec<Term>],
    /// Per family: the numerators `lo..=hi` of the grid points in its support.
    windows: Vec<(i64, i64)>,
    /// Per family: the index of its first unknown.
    offsets: Vec<usize>,
    unknowns: usize,
}

impl<'a> Refinable<'a> {
    fn new(arity: i64, rate: i64, relations: &'a [Vec<Term>]) -> Self {
        // The supports: the largest fixed point of S_t = ∪ (S_u + shift) / arity, reached from
        // an interval that holds it, [−R, R] with R·(arity − 1) ≥ max |shift|.
        let reach = relations.iter().flatten().map(|t| t.shift.unsigned_abs()).max().unwrap_or(0) as f64 + 1.0;
        let mut bounds = vec![(-reach, reach); relations.len()];
        for _ in 0..400 {
            bounds = (relations.iter())
                .map(|terms| {
                    terms.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
                        let (l, h) = bounds[t.family];
                        let s = t.shift as f64;
                        (lo.min((l + s) / arity as f64), hi.max((h + s) / arity as f64))
                    })
                })
                .collect();
        }
        let n = rate as f64;
        let windows: Vec<(i64, i64)> =
            bounds.iter().map(|&(lo, hi)| ((lo * n - 1e-9).ceil() as i64, (hi * n + 1e-9).floor() as i64)).collect();
        let mut offsets = Vec::with_capacity(windows.len());
        let mut unknowns = 0;
        for &(lo, hi) in &windows {
            offsets.push(unknowns);
            unknowns += usize::try_from(hi - lo + 1).unwrap_or(0);
        }
        Self { arity, rate, relations, windows, offsets, unknowns }
    }

    /// The unknown of `F_family(k / rate)`, `None` outside the support (where it is 0).
    fn index(&self, family: usize, k: i64) -> Option<usize> {
        let (lo, hi) = self.windows[family];
        (lo..=hi).contains(&k).then(|| self.offsets[family] + (k - lo) as usize)
    }

    /// The scaling equations `F_t(k/n) − factor · Σ w F_u((a·k − shift·n)/n) = 0`.
    fn scaling_rows(&self, factor: &Rational) -> Vec<(SparseRow, Rational)> {
        let mut rows = Vec::with_capacity(self.unknowns);
        for (family, terms) in self.relations.iter().enumerate() {
            let (lo, hi) = self.windows[family];
            for k in lo..=hi {
                let mut row: SparseRow = Vec::with_capacity(terms.len() + 1);
                if let Some(i) = self.index(family, k) {
                    row.push((i, Rational::one()));
                }
                for term in terms {
                    if let Some(j) = self.index(term.family, self.arity * k - term.shift * self.rate) {
                        row.push((j, -(factor * &term.weight)));
                    }
                }
                rows.push((row, Rational::zero()));
            }
        }
        rows
    }

    /// Solves `rows` and splits the solution per family.
    fn solve(&self, rows: Vec<(SparseRow, Rational)>) -> Result<Vec<Vec<Rational>>, SolveError> {
        let x = solve_sparse(self.unknowns, rows)?;
        Ok((0..self.windows.len())
            .map(|f| {
                let (lo, hi) = self.windows[f];
                x[self.offsets[f]..self.offsets[f] + (hi - lo + 1) as usize].to_vec()
            })
            .collect())
    }
}

fn check_rate(rate: u32) -> Result<i64, StencilError> {
    if rate == 0 {
        return Err(StencilError::Rate { rate: 0, reason: "the grid (1/rate)Z needs a rate of at least 1" });
    }
    if rate > MAX_CURVE_RATE {
        return Err(StencilError::Rate {
            rate: u64::from(rate),
            reason: "above MAX_CURVE_RATE: the exact systems grow with the rate",
        });
    }
    Ok(i64::from(rate))
}

/// The basis function `φ` of a uniform curve scheme and its derivative `φ′`, exactly, on the
/// grid `(1/rate)ℤ` over the support (route 1: scaling relations and partition of unity).
///
/// `phi[k]` is `φ((first + k) / rate)` and `dphi[k]` is `φ′((first + k) / rate)`; both vanish
/// outside.
///
/// ```
/// use subdiv_schemes::{CurveScheme, LocalCurveScheme, LocalRow};
/// use subdiv_stencil::Rational;
/// use subdiv_stencil::curve::basis_grid;
///
/// let grid = basis_grid(&CurveScheme::builtin("cubic-bspline").unwrap(), 2)?;
/// assert_eq!((grid.first, grid.phi.len()), (-4, 9));
/// // φ(0) = 2/3, φ(1/2) = 23/48, φ′(−1) = 1/2.
/// assert_eq!(grid.value(0), Rational::new(2, 3).unwrap());
/// assert_eq!(grid.value(1), Rational::new(23, 48).unwrap());
/// assert_eq!(grid.derivative(-2), Rational::new(1, 2).unwrap());
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BasisGrid {
    /// The grid rate `n`: samples at `k / n`.
    pub rate: u32,
    /// The numerator of the first sample.
    pub first: i64,
    /// `φ((first + k) / rate)`.
    pub phi: Vec<Rational>,
    /// `φ′((first + k) / rate)`.
    pub dphi: Vec<Rational>,
}

/// The position and tangent stencils of one point `x` of a uniform curve scheme's limit curve:
/// `p(x) = Σ w · p_i` over `position`, `p′(x) = Σ w · p_i` over `tangent`, as `(i, w)` pairs in
/// increasing `i` with the zero weights dropped.
///
/// ```
/// use subdiv_schemes::{CurveScheme, LocalCurveScheme, LocalRow};
/// use subdiv_stencil::Rational;
/// use subdiv_stencil::curve::basis_grid;
///
/// let grid = basis_grid(&CurveScheme::builtin("cubic-bspline").unwrap(), 1)?;
/// let s = grid.stencil_at(0);
/// let sixth = Rational::new(1, 6).unwrap();
/// assert_eq!(s.position, vec![(-1, sixth.clone()), (0, Rational::new(2, 3).unwrap()), (1, sixth)]);
/// let half = Rational::new(1, 2).unwrap();
/// assert_eq!(s.tangent, vec![(-1, -half.clone()), (1, half)]);
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CurveStencil {
    /// Weights of the limit point; they sum to 1.
    pub position: Vec<(i64, Rational)>,
    /// Weights of the derivative `d/dx`; they sum to 0.
    pub tangent: Vec<(i64, Rational)>,
}

impl CurveStencil {
    /// [`position`](Self::position) in `f64`.
    pub fn position_f64(&self) -> Vec<(i64, f64)> {
        self.position.iter().map(|(i, w)| (*i, w.to_f64())).collect()
    }

    /// [`tangent`](Self::tangent) in `f64`.
    pub fn tangent_f64(&self) -> Vec<(i64, f64)> {
        self.tangent.iter().map(|(i, w)| (*i, w.to_f64())).collect()
    }
}

/// [`BasisGrid::new`] for the exact mask of `scheme` ([`ExactMask::from_scheme`]).
///
/// # Errors
/// Those of [`ExactMask::from_scheme`] and [`BasisGrid::new`].
pub fn basis_grid(scheme: &CurveScheme, rate: u32) -> Result<BasisGrid, StencilError> {
    BasisGrid::new(&ExactMask::from_scheme(scheme)?, rate)
}

impl BasisGrid {
    /// Solves the scaling relations of `mask` on `(1/rate)ℤ` exactly (see the [module
    /// docs](self)): one unknown per grid point of the closed support (for the four-point
    /// scheme at rate 3: 19), one scaling equation per unknown, plus `rate` partition-of-unity
    /// equations for `φ`, and `2·rate` normalisations for `φ′`.
    ///
    /// # Errors
    /// [`StencilError::Rate`] for a rate of 0 or above [`MAX_CURVE_RATE`];
    /// [`StencilError::CurveScalingSystem`] when either system is inconsistent or has more than
    /// one solution (the scheme does not converge, or is not C¹).
    pub fn new(mask: &ExactMask, rate: u32) -> Result<Self, StencilError> {
        let n = check_rate(rate)?;
        let relations = [mask.relation()];
        let system = Refinable::new(i64::from(mask.arity), n, &relations);
        let fail = |quantity: &'static str| {
            move |e: SolveError| StencilError::CurveScalingSystem {
                scheme: mask.name.clone(),
                rate,
                quantity,
                detail: e.to_string(),
            }
        };
        let (lo, hi) = system.windows[0];
        let residue_rows = |coefficient: &dyn Fn(i64) -> Rational, rhs: &Rational| -> Vec<(SparseRow, Rational)> {
            (0..n)
                .map(|r| {
                    let row = (lo..=hi)
                        .filter(|k| (k - r).rem_euclid(n) == 0)
                        .filter_map(|k| system.index(0, k).map(|i| (i, coefficient(k))))
                        .collect();
                    (row, rhs.clone())
                })
                .collect()
        };
        let mut rows = system.scaling_rows(&Rational::one());
        rows.extend(residue_rows(&|_| Rational::one(), &Rational::one()));
        let phi = system.solve(rows).map_err(fail("positions"))?.swap_remove(0);

        let mut rows = system.scaling_rows(&Rational::from_integer(i64::from(mask.arity)));
        rows.extend(residue_rows(&|_| Rational::one(), &Rational::zero()));
        // Σ_j (j − x) φ′(x − j) = 1 with x − j = k/n: the coefficient of φ′(k/n) is −k/n.
        rows.extend(residue_rows(&|k| Rational::new(-k, n).unwrap_or_else(Rational::zero), &Rational::one()));
        let dphi = system.solve(rows).map_err(fail("derivatives"))?.swap_remove(0);
        Ok(Self { rate, first: lo, phi, dphi })
    }

    fn sample(values: &[Rational], first: i64, numerator: i64) -> Rational {
        let k = i128::from(numerator) - i128::from(first);
        usize::try_from(k).ok().and_then(|k| values.get(k)).cloned().unwrap_or_else(Rational::zero)
    }

    /// `φ(numerator / rate)` (0 outside the support).
    pub fn value(&self, numerator: i64) -> Rational {
        Self::sample(&self.phi, self.first, numerator)
    }

    /// `φ′(numerator / rate)` (0 outside the support).
    pub fn derivative(&self, numerator: i64) -> Rational {
        Self::sample(&self.dphi, self.first, numerator)
    }

    /// [`phi`](Self::phi) in `f64`.
    pub fn phi_f64(&self) -> Vec<f64> {
        self.phi.iter().map(Rational::to_f64).collect()
    }

    /// [`dphi`](Self::dphi) in `f64`.
    pub fn dphi_f64(&self) -> Vec<f64> {
        self.dphi.iter().map(Rational::to_f64).collect()
    }

    /// The stencils of the limit point at `x = numerator / rate`: control point `p_i` weighs
    /// `φ(x − i)` in the position and `φ′(x − i)` in the tangent.
    pub fn stencil_at(&self, numerator: i64) -> CurveStencil {
        let n = i128::from(self.rate);
        let len = self.phi.len() as i128;
        // (numerator − i·n − first) ∈ [0, len) ⇔ i ∈ ((numerator − first − len)/n, (numerator − first)/n].
        let top = i128::from(numerator) - i128::from(self.first);
        let (i_lo, i_hi) = ((top - len + 1).div_euclid(n) - 1, top.div_euclid(n) + 1);
        let mut position = Vec::new();
        let mut tangent = Vec::new();
        for i in i_lo..=i_hi {
            let Ok(index) = usize::try_from(top - i * n) else { continue };
            let Ok(i) = i64::try_from(i) else { continue };
            if let Some(w) = self.phi.get(index).filter(|w| !w.is_zero()) {
                position.push((i, w.clone()));
            }
            if let Some(w) = self.dphi.get(index).filter(|w| !w.is_zero()) {
                tangent.push((i, w.clone()));
            }
        }
        CurveStencil { position, tangent }
    }
}

/// Route 2 (paper §3): `φ` and `φ′` on `(1/rate)ℤ` in floating point, from the left
/// eigenvectors of the upsampled subdivision matrix, an independent check of [`BasisGrid`].
///
/// The upsampled mask `ŝ(z) = s(z^rate)` has the subdivision matrix `Ŝ[i][j] = ŝ_{i − a·j}`
/// (child `i`, parent `j`); on the window `m ∈ [−hi, −lo]` (`[lo, hi]` the support's grid
/// numerators) its left eigenvectors `ℓ` for eigenvalue 1 are the vectors `ℓ_m = φ(−m/rate)`
/// satisfying the scaling relation, and those for `1/a` the same for `φ′`. The eigenspaces
/// are found as null spaces (SVD) and the combination satisfying the normalisations of
/// [`BasisGrid::new`] is taken by least squares.
///
/// ```
/// use subdiv_schemes::{CurveScheme, LocalCurveScheme, LocalRow};
/// use subdiv_stencil::curve::{EigenGrid, ExactMask, basis_grid};
///
/// let four = CurveScheme::builtin("four-point").unwrap();
/// let eigen = EigenGrid::new(&ExactMask::from_scheme(&four)?, 3)?;
/// let exact = basis_grid(&four, 3)?;
/// assert_eq!(eigen.first, exact.first);
/// assert!((eigen.phi[9] - 1.0).abs() < 1e-12); // φ(0)
/// assert!((eigen.dphi[10] - exact.dphi[10].to_f64()).abs() < 1e-12); // φ′(1/3)
/// // Eigenvalue 1 of the upsampled matrix is double at rate 3: one eigenvector per cycle of
/// // the residues under k ↦ 2k mod 3, {0} and {1, 2}.
/// assert_eq!(eigen.multiplicity, 2);
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct EigenGrid {
    /// The grid rate `n`.
    pub rate: u32,
    /// The numerator of the first sample.
    pub first: i64,
    /// `φ((first + k) / rate)`.
    pub phi: Vec<f64>,
    /// `φ′((first + k) / rate)`.
    pub dphi: Vec<f64>,
    /// The dimension of the left eigenspace of eigenvalue 1.
    pub multiplicity: usize,
    /// The dimension of the left eigenspace of eigenvalue `1/arity`.
    pub derivative_multiplicity: usize,
}

impl EigenGrid {
    /// The upsampled matrix's eigenvectors for `mask` at `rate`.
    ///
    /// # Errors
    /// [`StencilError::Rate`] as for [`BasisGrid::new`]; [`StencilError::CurveUpsampledEigen`]
    /// when the SVD fails or the normalisations do not single out one vector.
    pub fn new(mask: &ExactMask, rate: u32) -> Result<Self, StencilError> {
        let n = check_rate(rate)?;
        let a = i64::from(mask.arity);
        let relations = [mask.relation()];
        let (lo, hi) = Refinable::new(a, n, &relations).windows[0];
        let size = (hi - lo + 1) as usize;
        let weights: Vec<f64> = mask.weights.iter().map(Rational::to_f64).collect();
        // ŝ_e = s_{e/n} when n divides e.
        let upsampled = |e: i64| -> f64 {
            if e.rem_euclid(n) != 0 {
                return 0.0;
            }
            usize::try_from(e / n - mask.first).ok().and_then(|k| weights.get(k)).copied().unwrap_or(0.0)
        };
        // Window index w ↔ m = −hi + w ↔ φ((lo + (size − 1 − w)) / n); build Ŝ on it.
        let m_of = |w: usize| -hi + w as i64;
        let s_hat = Mat::<f64>::from_fn(size, size, |i, j| upsampled(m_of(i) - a * m_of(j)));
        let fail = |quantity: &'static str, detail: String| StencilError::CurveUpsampledEigen {
            scheme: mask.name.clone(),
            rate,
            quantity,
            detail,
        };
        // The grid value at numerator k is ℓ at window index (hi − k).
        let residue_rows = |coefficient: &dyn Fn(i64) -> f64, rhs: f64| -> Vec<(Vec<f64>, f64)> {
            (0..n)
                .map(|r| {
                    let mut row = vec![0.0; size];
                    for k in (lo..=hi).filter(|k| (k - r).rem_euclid(n) == 0) {
                        row[(hi - k) as usize] = coefficient(k);
                    }
                    (row, rhs)
                })
                .collect()
        };
        let solve = |eigenvalue: f64, rows: Vec<(Vec<f64>, f64)>, quantity: &'static str| {
            let (rows, values): (Vec<Vec<f64>>, Vec<f64>) = rows.into_iter().unzip();
            let found = normalised_left_eigenvectors(&s_hat, eigenvalue, &rows, &[values])
                .map_err(|detail| fail(quantity, detail))?;
            let ell = found.vectors.into_iter().next().expect("one list of values, one vector");
            // Back to grid order: value at numerator lo + k is ℓ at window index size − 1 − k.
            Ok::<_, StencilError>((ell.into_iter().rev().collect::<Vec<f64>>(), found.multiplicity))
        };
        let (phi, multiplicity) = solve(1.0, residue_rows(&|_| 1.0, 1.0), "positions")?;
        let mut rows = residue_rows(&|_| 1.0, 0.0);
        rows.extend(residue_rows(&|k| -(k as f64) / n as f64, 1.0));
        let (dphi, derivative_multiplicity) = solve(1.0 / a as f64, rows, "derivatives")?;
        Ok(Self { rate, first: lo, phi, dphi, multiplicity, derivative_multiplicity })
    }
}

/// The limit functions of a [`LocalCurveScheme`] (uniform away from the origin, rows of its
/// own near it) on the grid `(1/rate)ℤ`, exactly: the uniform scheme's basis `F_0`, whose
/// shifts `F_0(x − i)` are the control points' far from the origin, and one refinable function
/// per *special* control point, in the global parameter `x` (a stationary scheme refines the
/// same rows at every level, so the basis of special point `i` at level `j` is `F_i(arity^j
/// x)`). Special points: those whose column of the subdivision matrix differs from the mask's,
/// and those whose children include a special point (their limit functions reach the
/// origin's), closed and made contiguous. All families are solved together: the scaling
/// relation of each (one column of the matrix), and partition of unity at every grid point
/// around the origin.
///
/// ```
/// use subdiv_schemes::LocalCurveScheme;
/// use subdiv_stencil::Rational;
/// use subdiv_stencil::curve::LocalCurveGrid;
///
/// let scheme = LocalCurveScheme::builtin("nonuniform-cubic-bspline").unwrap();
/// let grid = LocalCurveGrid::new(&scheme, 2)?;
/// assert_eq!(grid.special, (-1, 1));
/// // At x = 0 only p_{−1}, p_0, p_1 weigh: the non-uniform limit mask.
/// let r = |p, q| Rational::new(p, q).unwrap();
/// assert_eq!([grid.basis(-1, 0), grid.basis(0, 0), grid.basis(1, 0)], [r(1, 15), r(3, 5), r(1, 3)]);
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LocalCurveGrid {
    /// The grid rate `n`.
    pub rate: u32,
    /// The special control points `lo..=hi`.
    pub special: (i64, i64),
    /// `families[0]` the uniform function (centred at 0), `families[1 + i − lo]` special point
    /// `i`'s (in the global parameter): `(first, values)` with `values[k]` at `(first + k) /
    /// rate`.
    pub families: Vec<(i64, Vec<Rational>)>,
}

impl LocalCurveGrid {
    /// Solves `scheme`'s families at `rate`.
    ///
    /// # Errors
    /// [`StencilError::Rate`] for a rate of 0 or above [`MAX_CURVE_RATE`];
    /// [`StencilError::CurveMaskNotRational`] for a weight that is no small fraction;
    /// [`StencilError::CurveScalingSystem`] if the system has no unique solution.
    pub fn new(scheme: &LocalCurveScheme, rate: u32) -> Result<Self, StencilError> {
        let n = check_rate(rate)?;
        let uniform = scheme.uniform();
        let a = i64::from(uniform.arity());
        let name = scheme.name().to_string();
        let len = uniform.mask().len() as i64;
        // The children a parent can have: the mask's reach and every special row.
        let children_of = |parent: i64| {
            let rows = scheme.rows().iter().map(|r| r.point);
            let lo = rows.clone().chain([a * parent - uniform.offset() as i64]).min().unwrap_or(0);
            let hi = rows.chain([a * parent - uniform.offset() as i64 + len]).max().unwrap_or(0);
            (lo..=hi).filter(move |&k| scheme.weight(k, parent) != 0.0)
        };
        let reach = 64 + len;
        let mut special: Vec<bool> = (-reach..=reach)
            .map(|i| scheme.rows().iter().any(|r| scheme.weight(r.point, i) != uniform.weight(r.point, i)))
            .collect();
        let is = |special: &[bool], i: i64| (-reach..=reach).contains(&i) && special[(i + reach) as usize];
        loop {
            let grown: Vec<bool> =
                (-reach..=reach).map(|i| is(&special, i) || children_of(i).any(|k| is(&special, k))).collect();
            if grown == special {
                break;
            }
            special = grown;
        }
        let (lo, hi) = match (special.iter().position(|&s| s), special.iter().rposition(|&s| s)) {
            (Some(lo), Some(hi)) => (lo as i64 - reach, hi as i64 - reach),
            _ => (1, 0),
        };
        let family_of = |i: i64| if (lo..=hi).contains(&i) { ((1 + i - lo) as usize, 0) } else { (0, i) };
        let exact = |child: i64, parent: i64| {
            let value = scheme.weight(child, parent);
            exact_weight(value, ExactMask::MAX_DENOMINATOR).ok_or_else(|| StencilError::CurveMaskNotRational {
                scheme: name.clone(),
                index: usize::try_from(child - a * parent + uniform.offset() as i64).unwrap_or(0),
                value,
                max_denominator: ExactMask::MAX_DENOMINATOR,
            })
        };
        // One relation per family, read from one column: the uniform one far from the origin.
        let far = hi.max(0) + reach;
        let relations: Vec<Vec<Term>> = std::iter::once(far)
            .chain(lo..=hi)
            .map(|column| {
                let (_, centre) = family_of(column);
                children_of(column)
                    .map(|k| {
                        let (family, c) = family_of(k);
                        // F_t(y) with y = x − centre: F_u(a·x − c) = F_u(a·y − (c − a·centre)).
                        Ok(Term { family, shift: c - a * centre, weight: exact(k, column)? })
                    })
                    .collect::<Result<Vec<_>, StencilError>>()
            })
            .collect::<Result<_, _>>()?;
        let system = Refinable::new(a, n, &relations);
        let mut rows = system.scaling_rows(&Rational::one());
        // Partition of unity at every grid point around the origin: Σ_i F(x − centre_i) = 1.
        let around = lo.abs().max(hi.abs()) + len;
        for k in -around * n..=around * n {
            let row: SparseRow = (-2 * around..=2 * around)
                .filter_map(|i| {
                    let (family, centre) = family_of(i);
                    system.index(family, k - centre * n).map(|u| (u, Rational::one()))
                })
                .collect();
            rows.push((row, Rational::one()));
        }
        let families = system.solve(rows).map_err(|e| StencilError::CurveScalingSystem {
            scheme: name.clone(),
            rate,
            quantity: "positions",
            detail: e.to_string(),
        })?;
        let families = families.into_iter().zip(&system.windows).map(|(values, &(first, _))| (first, values)).collect();
        Ok(Self { rate, special: (lo, hi), families })
    }

    /// The basis function of control point `p_i` at `x = numerator / rate`.
    pub fn basis(&self, i: i64, numerator: i64) -> Rational {
        let (lo, hi) = self.special;
        let (family, centre) = if (lo..=hi).contains(&i) { ((1 + i - lo) as usize, 0) } else { (0, i) };
        let (first, values) = &self.families[family];
        let k = i128::from(numerator) - i128::from(centre) * i128::from(self.rate) - i128::from(*first);
        usize::try_from(k).ok().and_then(|k| values.get(k)).cloned().unwrap_or_else(Rational::zero)
    }
}

/// The non-uniform cubic B-spline of paper §2 (see the [module docs](self) for the knots and
/// the parameterisation): its rows derived by knot insertion, and its basis functions on the
/// grid `(1/rate)ℤ` by [`LocalCurveGrid`] — the same rows as the built-in scheme file
/// `nonuniform-cubic-bspline` (a test holds them equal).
///
/// ```
/// use subdiv_stencil::Rational;
/// use subdiv_stencil::curve::NonUniformCubicGrid;
///
/// let grid = NonUniformCubicGrid::new(2)?;
/// // At x = 0 (t = 0) only the B-splines of p_{−1}, p_0, p_1 are nonzero: the non-uniform
/// // limit mask c²/((b+c)(a+b+c)), …, b²/((b+c)(b+c+e)) with intervals a = b = 2, c = e = 1.
/// let r = |p, q| Rational::new(p, q).unwrap();
/// assert_eq!([grid.basis(-1, 0), grid.basis(0, 0), grid.basis(1, 0)], [r(1, 15), r(3, 5), r(1, 3)]);
/// assert!(grid.basis(-2, 0).is_zero() && grid.basis(2, 0).is_zero());
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NonUniformCubicGrid {
    grid: LocalCurveGrid,
}

impl NonUniformCubicGrid {
    /// The knot `t_i`: `i` for `i ≥ 0`, `2i` for `i < 0`.
    pub fn knot(i: i64) -> Rational {
        Rational::from_integer(if i >= 0 { i } else { 2 * i })
    }

    /// Row `k` of the subdivision matrix (the new point `q_k`, blossom
    /// `f(u_{k−1}, u_k, u_{k+1})` on the refined knots `u_k = t_k / 2`) as weights of the old
    /// points `p_{j−1}..=p_{j+2}`, `j = ⌊k/2⌋`, by the blossom form of de Boor's algorithm on
    /// the old span `[t_j, t_{j+1}]`, which holds `[u_k, u_{k+1}]`.
    fn row(k: i64) -> [(i64, Rational); 4] {
        let half = |r: Rational| &r / &Rational::from_integer(2);
        let u = |i: i64| half(Self::knot(i));
        let j = k.div_euclid(2);
        let knots: [Rational; 6] = std::array::from_fn(|q| Self::knot(j - 2 + q as i64));
        // d[i] holds the weights of the four points in the blossom of the current level.
        let mut d: [[Rational; 4]; 4] =
            std::array::from_fn(|i| std::array::from_fn(|c| Rational::from_integer(i64::from(i == c))));
        let args = [u(k - 1), u(k), u(k + 1)];
        for r in 1..=3 {
            for i in (r..=3).rev() {
                let (left, right) = (&knots[i - 1], &knots[i + 3 - r]);
                let alpha = &(&args[r - 1] - left) / &(right - left);
                let beta = &Rational::one() - &alpha;
                let next: [Rational; 4] = std::array::from_fn(|c| &(&beta * &d[i - 1][c]) + &(&alpha * &d[i][c]));
                d[i] = next;
            }
        }
        std::array::from_fn(|c| (j - 1 + c as i64, d[3][c].clone()))
    }

    /// The weight of the old point `p_column` in the new point `q_row`.
    fn entry(row: i64, column: i64) -> Rational {
        Self::row(row).into_iter().find(|(c, _)| *c == column).map_or_else(Rational::zero, |(_, w)| w)
    }

    /// The subdivision matrix on the two-ring of the origin, rows and columns `−2..=2`,
    /// derived by knot insertion.
    ///
    /// ```
    /// use subdiv_stencil::Rational;
    /// use subdiv_stencil::curve::NonUniformCubicGrid;
    ///
    /// let m = NonUniformCubicGrid::local_matrix();
    /// let r = |p, q| Rational::new(p, q).unwrap();
    /// // The paper's matrix read backwards (rows and columns reversed): its knots are mirrored.
    /// assert_eq!(m[0], [r(1, 8), r(29, 40), r(3, 20), r(0, 1), r(0, 1)]);
    /// assert_eq!(m[2], [r(0, 1), r(1, 15), r(29, 40), r(5, 24), r(0, 1)]);
    /// ```
    pub fn local_matrix() -> [[Rational; 5]; 5] {
        std::array::from_fn(|r| std::array::from_fn(|c| Self::entry(r as i64 - 2, c as i64 - 2)))
    }

    /// The scheme as data: the uniform cubic B-spline's mask, and the rows of knot insertion
    /// that differ from it (the new points `−2..=2`).
    pub fn scheme() -> LocalCurveScheme {
        let cubic = CurveScheme::builtin("cubic-bspline").expect("a built-in");
        let name = subdiv_schemes::NonUniformCubicBSpline::NAME;
        let uniform = CurveScheme::new(name, cubic.arity(), cubic.offset(), cubic.mask().to_vec()).expect("the cubic");
        let rows = (-4..=4)
            .filter_map(|k| {
                let row = Self::row(k);
                let differs = row.iter().any(|(c, w)| w.to_f64() != uniform.weight(k, *c));
                differs.then(|| LocalRow {
                    point: k,
                    first: row[0].0,
                    weights: row.iter().map(|(_, w)| w.to_f64()).collect(),
                })
            })
            .collect();
        LocalCurveScheme::new(uniform, rows).expect("knot insertion's rows sum to 1")
    }

    /// Solves the scheme's families at `rate` ([`LocalCurveGrid::new`]).
    ///
    /// # Errors
    /// As [`LocalCurveGrid::new`].
    pub fn new(rate: u32) -> Result<Self, StencilError> {
        Ok(Self { grid: LocalCurveGrid::new(&Self::scheme(), rate)? })
    }

    /// The solved families.
    pub fn grid(&self) -> &LocalCurveGrid {
        &self.grid
    }

    /// The basis function of control point `p_i` at `x = numerator / rate`.
    pub fn basis(&self, i: i64, numerator: i64) -> Rational {
        self.grid.basis(i, numerator)
    }
}
