//! [`Rational`]: exact fractions of big integers, and an exact sparse Gaussian elimination for
//! the scaling-relation systems of the curve stencils.

use std::cmp::Ordering;
use std::collections::BTreeSet;
use std::fmt;
use std::iter::Sum;
use std::ops::{Add, Div, Mul, Neg, Sub};

use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{One, Signed, ToPrimitive, Zero};

/// An exact rational number `numerator / denominator` of big integers, always normalised: the
/// denominator is positive and shares no factor with the numerator (zero is `0/1`), so equal
/// numbers have equal representations and `==` is exact equality.
///
/// ```
/// use subdiv_stencil::Rational;
///
/// let third = Rational::new(1, 3).unwrap();
/// let sum = &third + &Rational::new(1, 6).unwrap();
/// assert_eq!(sum, Rational::new(2, 4).unwrap());
/// assert_eq!(sum.to_string(), "1/2");
/// assert_eq!((&sum * &Rational::from_integer(4)).to_string(), "2");
/// assert!(third < sum);
/// assert_eq!(Rational::approximate(0.1, 1000), Rational::new(1, 10));
/// assert!(Rational::new(1, 0).is_none());
/// ```
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Rational {
    num: BigInt,
    den: BigInt,
}

impl Rational {
    /// `numerator / denominator`, normalised; `None` when the denominator is zero.
    pub fn new(numerator: impl Into<BigInt>, denominator: impl Into<BigInt>) -> Option<Self> {
        let den = denominator.into();
        if den.is_zero() {
            return None;
        }
        Some(Self::normalised(numerator.into(), den))
    }

    /// Normalises `num / den`; `den` must be nonzero.
    fn normalised(mut num: BigInt, mut den: BigInt) -> Self {
        if den.is_negative() {
            num = -num;
            den = -den;
        }
        let g = num.gcd(&den);
        if !g.is_one() && !g.is_zero() {
            num /= &g;
            den /= &g;
        }
        Self { num, den }
    }

    /// The integer `value`.
    pub fn from_integer(value: i64) -> Self {
        Self { num: BigInt::from(value), den: BigInt::one() }
    }

    /// Zero.
    pub fn zero() -> Self {
        Self::from_integer(0)
    }

    /// One.
    pub fn one() -> Self {
        Self::from_integer(1)
    }

    /// The numerator (its sign is the number's).
    pub fn numer(&self) -> &BigInt {
        &self.num
    }

    /// The denominator, always positive.
    pub fn denom(&self) -> &BigInt {
        &self.den
    }

    /// Whether the number is zero.
    pub fn is_zero(&self) -> bool {
        self.num.is_zero()
    }

    /// The absolute value.
    pub fn abs(&self) -> Self {
        Self { num: self.num.abs(), den: self.den.clone() }
    }

    /// `1 / self`; `None` for zero.
    pub fn recip(&self) -> Option<Self> {
        Self::new(self.den.clone(), self.num.clone())
    }

    /// `self / other`; `None` when `other` is zero.
    pub fn checked_div(&self, other: &Self) -> Option<Self> {
        Some(self * &other.recip()?)
    }

    /// The exact value of a finite `f64` (every finite double is a dyadic rational
    /// `m · 2^e`); `None` for NaN and infinities.
    ///
    /// ```
    /// use subdiv_stencil::Rational;
    ///
    /// assert_eq!(Rational::from_f64(-0.375), Rational::new(-3, 8));
    /// // 0.1 is not 1/10 in binary: its exact value has denominator 2^55.
    /// assert_eq!(Rational::from_f64(0.1).unwrap().denom().bits(), 56);
    /// assert_eq!(Rational::from_f64(f64::NAN), None);
    /// ```
    pub fn from_f64(x: f64) -> Option<Self> {
        if !x.is_finite() {
            return None;
        }
        if x == 0.0 {
            return Some(Self::zero());
        }
        let bits = x.to_bits();
        let negative = bits >> 63 == 1;
        let exponent = ((bits >> 52) & 0x7ff) as i64;
        let fraction = bits & ((1u64 << 52) - 1);
        // x = mantissa · 2^power.
        let (mantissa, power) =
            if exponent == 0 { (fraction, -1074) } else { (fraction | (1u64 << 52), exponent - 1075) };
        let mut num = BigInt::from(mantissa);
        if negative {
            num = -num;
        }
        Some(if power >= 0 {
            Self::normalised(num << power as usize, BigInt::one())
        } else {
            Self::normalised(num, BigInt::one() << (-power) as usize)
        })
    }

    /// The rational with denominator at most `max_denominator` closest to `x` (continued
    /// fractions: the best of the last convergent and the last semiconvergent; ties go to the
    /// convergent); `None` when `x` is not finite or `max_denominator` is 0.
    ///
    /// ```
    /// use subdiv_stencil::Rational;
    ///
    /// assert_eq!(Rational::approximate(1.0 / 6.0, 1_000_000), Rational::new(1, 6));
    /// assert_eq!(Rational::approximate(std::f64::consts::PI, 1000), Rational::new(355, 113));
    /// assert_eq!(Rational::approximate(-2.5, 1), Rational::new(-3, 1));
    /// ```
    pub fn approximate(x: f64, max_denominator: u64) -> Option<Self> {
        if max_denominator == 0 {
            return None;
        }
        let exact = Self::from_f64(x)?;
        let max = BigInt::from(max_denominator);
        if exact.den <= max {
            return Some(exact);
        }
        let (mut p0, mut q0, mut p1, mut q1) = (BigInt::zero(), BigInt::one(), BigInt::one(), BigInt::zero());
        let (mut n, mut d) = (exact.num.clone(), exact.den.clone());
        loop {
            let a = n.div_floor(&d);
            let q2 = &q0 + &a * &q1;
            if q2 > max {
                break;
            }
            let p2 = &p0 + &a * &p1;
            (p0, q0, p1, q1) = (p1, q1, p2, q2);
            let r = &n - &a * &d;
            (n, d) = (d, r);
            if n.is_zero() || d.is_zero() {
                break;
            }
        }
        let k = (&max - &q0).div_floor(&q1);
        let semi = Self::normalised(&p0 + &k * &p1, &q0 + &k * &q1);
        let conv = Self::normalised(p1, q1);
        let (ds, dc) = ((&semi - &exact).abs(), (&conv - &exact).abs());
        Some(if ds < dc { semi } else { conv })
    }

    /// The nearest `f64` (to within one unit in the last place).
    pub fn to_f64(&self) -> f64 {
        const EXACT: u64 = 53;
        if self.num.bits() <= EXACT && self.den.bits() <= EXACT {
            // Both exact in f64: one correctly rounded division.
            return self.num.to_f64().unwrap_or(f64::NAN) / self.den.to_f64().unwrap_or(f64::NAN);
        }
        // Scale so that the integer quotient has about 64 significant bits.
        let shift = self.num.bits() as i64 - self.den.bits() as i64 - 64;
        let quotient = if shift >= 0 {
            &self.num / (&self.den << shift as usize)
        } else {
            (&self.num << (-shift) as usize) / &self.den
        };
        let q = quotient.to_f64().unwrap_or(f64::NAN);
        // 2^shift in two steps so that neither overflows for the exponents an f64 can hold.
        let half = shift / 2;
        q * 2f64.powi(half.clamp(-2000, 2000) as i32) * 2f64.powi((shift - half).clamp(-2000, 2000) as i32)
    }
}

impl From<i64> for Rational {
    fn from(value: i64) -> Self {
        Self::from_integer(value)
    }
}

impl fmt::Display for Rational {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.den.is_one() { write!(f, "{}", self.num) } else { write!(f, "{}/{}", self.num, self.den) }
    }
}

impl Ord for Rational {
    fn cmp(&self, other: &Self) -> Ordering {
        // Denominators are positive, so cross-multiplying keeps the order.
        (&self.num * &other.den).cmp(&(&other.num * &self.den))
    }
}

impl PartialOrd for Rational {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Add<&Rational> for &Rational {
    type Output = Rational;
    fn add(self, rhs: &Rational) -> Rational {
        if self.den == rhs.den {
            return Rational::normalised(&self.num + &rhs.num, self.den.clone());
        }
        Rational::normalised(&self.num * &rhs.den + &rhs.num * &self.den, &self.den * &rhs.den)
    }
}

impl Sub<&Rational> for &Rational {
    type Output = Rational;
    fn sub(self, rhs: &Rational) -> Rational {
        if self.den == rhs.den {
            return Rational::normalised(&self.num - &rhs.num, self.den.clone());
        }
        Rational::normalised(&self.num * &rhs.den - &rhs.num * &self.den, &self.den * &rhs.den)
    }
}

impl Mul<&Rational> for &Rational {
    type Output = Rational;
    fn mul(self, rhs: &Rational) -> Rational {
        if self.num.is_zero() || rhs.num.is_zero() {
            return Rational::zero();
        }
        Rational::normalised(&self.num * &rhs.num, &self.den * &rhs.den)
    }
}

/// # Panics
/// When `rhs` is zero, as integer division does; use [`Rational::checked_div`] to avoid it.
impl Div<&Rational> for &Rational {
    type Output = Rational;
    fn div(self, rhs: &Rational) -> Rational {
        assert!(!rhs.is_zero(), "division of a Rational by zero");
        Rational::normalised(&self.num * &rhs.den, &self.den * &rhs.num)
    }
}

/// The owned and mixed forms of a binary operator, forwarding to the `&a op &b` form.
macro_rules! forward_binop {
    ($($trait:ident $method:ident),*) => {$(
        impl $trait<Rational> for Rational {
            type Output = Rational;
            fn $method(self, rhs: Rational) -> Rational {
                (&self).$method(&rhs)
            }
        }
        impl $trait<&Rational> for Rational {
            type Output = Rational;
            fn $method(self, rhs: &Rational) -> Rational {
                (&self).$method(rhs)
            }
        }
        impl $trait<Rational> for &Rational {
            type Output = Rational;
            fn $method(self, rhs: Rational) -> Rational {
                self.$method(&rhs)
            }
        }
    )*};
}

forward_binop!(Add add, Sub sub, Mul mul, Div div);

impl Neg for Rational {
    type Output = Rational;
    fn neg(self) -> Rational {
        Rational { num: -self.num, den: self.den }
    }
}

impl Neg for &Rational {
    type Output = Rational;
    fn neg(self) -> Rational {
        Rational { num: -&self.num, den: self.den.clone() }
    }
}

impl Sum for Rational {
    fn sum<I: Iterator<Item = Rational>>(iter: I) -> Self {
        iter.fold(Rational::zero(), |acc, x| acc + x)
    }
}

impl<'a> Sum<&'a Rational> for Rational {
    fn sum<I: Iterator<Item = &'a Rational>>(iter: I) -> Self {
        iter.fold(Rational::zero(), |acc, x| acc + x)
    }
}

/// The weight of a scheme's `f64` rule recovered as an exact fraction: the nearest rational
/// with denominator at most `max_denominator`, accepted only when it is within
/// `1e-15 · max(1, |value|)` of the float (the rule was a small fraction, rounded once).
pub(crate) fn exact_weight(value: f64, max_denominator: u64) -> Option<Rational> {
    fraction_within(value, max_denominator, 1e-15)
}

/// The nearest rational to `value` with denominator at most `max_denominator`, if it is within
/// `tolerance · max(1, |value|)` of it.
pub(crate) fn fraction_within(value: f64, max_denominator: u64, tolerance: f64) -> Option<Rational> {
    Rational::approximate(value, max_denominator)
        .filter(|r| (r.to_f64() - value).abs() < tolerance * f64::max(1.0, value.abs()))
}

/// A sparse row: `(column, coefficient)` in increasing column order, no zero coefficients.
pub(crate) type SparseRow = Vec<(usize, Rational)>;

/// Why an exact linear system has no unique solution.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum SolveError {
    /// The equations contradict each other.
    Inconsistent,
    /// The equations leave some unknowns free: their rank is below the number of unknowns.
    NotUnique {
        /// The rank of the coefficient matrix.
        rank: usize,
        /// The number of unknowns.
        unknowns: usize,
    },
}

impl fmt::Display for SolveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Inconsistent => f.write_str("the equations are inconsistent"),
            Self::NotUnique { rank, unknowns } => {
                write!(f, "the equations have rank {rank} in {unknowns} unknowns: the solution is not unique")
            }
        }
    }
}

/// `row - factor · pivot`, both sparse and sorted; exact cancellations are dropped.
fn subtract_multiple(row: &[(usize, Rational)], factor: &Rational, pivot: &[(usize, Rational)]) -> SparseRow {
    let mut out = Vec::with_capacity(row.len() + pivot.len());
    let (mut i, mut j) = (0, 0);
    while i < row.len() || j < pivot.len() {
        let next_row = row.get(i).map_or(usize::MAX, |e| e.0);
        let next_pivot = pivot.get(j).map_or(usize::MAX, |e| e.0);
        match next_row.cmp(&next_pivot) {
            Ordering::Less => {
                out.push(row[i].clone());
                i += 1;
            }
            Ordering::Greater => {
                out.push((next_pivot, -(factor * &pivot[j].1)));
                j += 1;
            }
            Ordering::Equal => {
                let value = &row[i].1 - &(factor * &pivot[j].1);
                if !value.is_zero() {
                    out.push((next_row, value));
                }
                i += 1;
                j += 1;
            }
        }
    }
    out
}

/// Solves `A x = b` exactly, `A` given by sparse rows over `unknowns` columns. The system may
/// be over-determined; it must be consistent and of full column rank.
///
/// Gaussian elimination with a minimum-degree pivot order (the column met by the fewest
/// remaining rows, then that column's shortest row), which keeps the scaling-relation systems
/// nearly as sparse as they start: each scaling equation links one residue class of grid
/// points to another.
pub(crate) fn solve_sparse(
    unknowns: usize,
    equations: Vec<(SparseRow, Rational)>,
) -> Result<Vec<Rational>, SolveError> {
    let mut rows: Vec<SparseRow> = Vec::with_capacity(equations.len());
    let mut rhs: Vec<Rational> = Vec::with_capacity(equations.len());
    let mut active: Vec<bool> = Vec::with_capacity(equations.len());
    let mut members: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); unknowns];
    for (index, (mut row, b)) in equations.into_iter().enumerate() {
        row.retain(|(column, value)| *column < unknowns && !value.is_zero());
        row.sort_by_key(|e| e.0);
        // Merge repeated columns.
        let mut merged: SparseRow = Vec::with_capacity(row.len());
        for (column, value) in row {
            match merged.last_mut() {
                Some(last) if last.0 == column => last.1 = &last.1 + &value,
                _ => merged.push((column, value)),
            }
        }
        merged.retain(|e| !e.1.is_zero());
        for (column, _) in &merged {
            members[*column].insert(index);
        }
        rows.push(merged);
        rhs.push(b);
        active.push(true);
    }
    let mut done = vec![false; unknowns];
    let mut pivots: Vec<(usize, usize)> = Vec::with_capacity(unknowns);
    let mut free = 0usize;
    for _ in 0..unknowns {
        // The column met by the fewest active rows; a column met by none is free.
        let Some(column) = (0..unknowns).filter(|&c| !done[c]).min_by_key(|&c| members[c].len()) else {
            break;
        };
        done[column] = true;
        if members[column].is_empty() {
            free += 1;
            continue;
        }
        let Some(pivot) = members[column].iter().copied().min_by_key(|&r| rows[r].len()) else {
            continue;
        };
        // Normalise the pivot row and take it out of the active set.
        let Some(scale) = rows[pivot].iter().find(|e| e.0 == column).and_then(|e| e.1.recip()) else {
            continue;
        };
        for entry in &mut rows[pivot] {
            entry.1 = &entry.1 * &scale;
        }
        rhs[pivot] = &rhs[pivot] * &scale;
        active[pivot] = false;
        for (c, _) in &rows[pivot] {
            members[*c].remove(&pivot);
        }
        let pivot_row = rows[pivot].clone();
        let pivot_rhs = rhs[pivot].clone();
        let others: Vec<usize> = members[column].iter().copied().collect();
        for other in others {
            let Some(factor) = rows[other].iter().find(|e| e.0 == column).map(|e| e.1.clone()) else {
                continue;
            };
            let updated = subtract_multiple(&rows[other], &factor, &pivot_row);
            for (c, _) in &pivot_row {
                let had = rows[other].binary_search_by_key(c, |e| e.0).is_ok();
                let has = updated.binary_search_by_key(c, |e| e.0).is_ok();
                if had && !has {
                    members[*c].remove(&other);
                } else if has && !had {
                    members[*c].insert(other);
                }
            }
            rows[other] = updated;
            rhs[other] = &rhs[other] - &(&factor * &pivot_rhs);
        }
        pivots.push((column, pivot));
    }
    // Every active row has lost all its entries; a nonzero right-hand side is a contradiction.
    if (0..rows.len()).any(|r| active[r] && rows[r].is_empty() && !rhs[r].is_zero()) {
        return Err(SolveError::Inconsistent);
    }
    if free > 0 {
        return Err(SolveError::NotUnique { rank: pivots.len(), unknowns });
    }
    let mut x = vec![Rational::zero(); unknowns];
    for &(column, row) in pivots.iter().rev() {
        let mut value = rhs[row].clone();
        for (c, a) in &rows[row] {
            if *c != column {
                value = &value - &(a * &x[*c]);
            }
        }
        x[column] = value;
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(p: i64, q: i64) -> Rational {
        Rational::new(p, q).unwrap()
    }

    #[test]
    fn arithmetic_is_exact_and_normalised() {
        assert_eq!(r(2, -4), r(-1, 2));
        assert_eq!(r(2, -4).denom(), &BigInt::from(2));
        assert_eq!(&r(1, 3) - &r(1, 3), Rational::zero());
        assert_eq!(Rational::zero().denom(), &BigInt::one());
        assert_eq!(r(3, 4) / r(3, 8), r(2, 1));
        assert_eq!(-r(1, 2), r(-1, 2));
        assert_eq!(r(-7, 3).to_string(), "-7/3");
        assert_eq!(r(1, 3).checked_div(&Rational::zero()), None);
        assert!(r(-1, 2) < r(-1, 3));
    }

    #[test]
    fn f64_round_trips() {
        for x in [0.0, 1.0, -0.1, 1e300, 5e-324, 1.0 / 3.0, -123.456] {
            let exact = Rational::from_f64(x).unwrap();
            assert_eq!(exact.to_f64(), x, "{x}");
        }
        assert_eq!(r(1, 3).to_f64(), 1.0 / 3.0);
        let big = Rational::new(BigInt::from(10).pow(400) + 1, BigInt::from(10).pow(399)).unwrap();
        assert!((big.to_f64() - 10.0).abs() < 1e-14);
    }

    #[test]
    fn approximation_finds_small_denominators() {
        assert_eq!(Rational::approximate(0.5625, 16), Some(r(9, 16)));
        assert_eq!(Rational::approximate(-25.0 / 256.0, 1_000_000), Some(r(-25, 256)));
        assert_eq!(Rational::approximate(2.0 / 3.0, 2), Some(r(1, 2)));
        assert_eq!(Rational::approximate(0.7, 2), Some(r(1, 2)));
        assert_eq!(Rational::approximate(0.8, 2), Some(r(1, 1)));
        assert_eq!(Rational::approximate(0.3, 0), None);
        assert_eq!(Rational::approximate(f64::INFINITY, 10), None);
    }

    #[test]
    fn solver_handles_overdetermined_consistent_systems() {
        // x + y = 3, x - y = 1, 2x = 4.
        let rows = vec![
            (vec![(0, r(1, 1)), (1, r(1, 1))], r(3, 1)),
            (vec![(0, r(1, 1)), (1, r(-1, 1))], r(1, 1)),
            (vec![(0, r(2, 1))], r(4, 1)),
        ];
        assert_eq!(solve_sparse(2, rows), Ok(vec![r(2, 1), r(1, 1)]));
    }

    #[test]
    fn solver_reports_inconsistency_and_rank_deficiency() {
        let inconsistent =
            vec![(vec![(0, r(1, 1)), (1, r(1, 1))], r(3, 1)), (vec![(0, r(2, 1)), (1, r(2, 1))], r(5, 1))];
        assert_eq!(solve_sparse(2, inconsistent), Err(SolveError::Inconsistent));
        let deficient = vec![(vec![(0, r(1, 1)), (1, r(1, 1))], r(3, 1))];
        assert_eq!(solve_sparse(2, deficient), Err(SolveError::NotUnique { rank: 1, unknowns: 2 }));
    }
}
