//! Periodic addresses: which sub-patch a rational parameter falls in at every level.

use std::collections::HashMap;
use std::hash::Hash;

use num_integer::Integer;
use subdiv_schemes::ChildDomain;

use crate::StencilError;

/// The sub-patch choices of a rational point, level by level: a prefix, then a period repeated
/// for ever. Every rational point has one, because its parameters keep their denominator under
/// the map to a child's domain, so the sequence of points revisits one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Address {
    /// Children taken once, from the top.
    pub prefix: Vec<u8>,
    /// Children taken for ever after the prefix (never empty).
    pub period: Vec<u8>,
}

/// A rational point of a face's domain over a common denominator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Dyadic {
    /// `u · denominator`.
    pub u: i64,
    /// `v · denominator`.
    pub v: i64,
    /// The denominator, at least 1.
    pub denominator: i64,
}

impl Dyadic {
    /// The point `(u / denominator, v / denominator)`.
    pub fn new(u: i64, v: i64, denominator: i64) -> Self {
        Self { u, v, denominator }
    }

    /// The same point in lowest terms.
    ///
    /// ```
    /// use subdiv_stencil::Dyadic;
    ///
    /// assert_eq!(Dyadic::new(2, 6, 8).reduced(), Dyadic::new(1, 3, 4));
    /// assert_eq!(Dyadic::new(0, 0, 5).reduced(), Dyadic::new(0, 0, 1));
    /// ```
    pub fn reduced(self) -> Self {
        let g = self.u.gcd(&self.v).gcd(&self.denominator).max(1);
        Self { u: self.u / g, v: self.v / g, denominator: self.denominator / g }
    }

    /// The point in f64.
    pub fn to_f64(self) -> (f64, f64) {
        (self.u as f64 / self.denominator as f64, self.v as f64 / self.denominator as f64)
    }
}

impl std::str::FromStr for Dyadic {
    type Err = StencilError;

    /// `U,V` with each a fraction `p/q` (q > 0) or an integer, over their least common
    /// denominator, computed with checked arithmetic: a denominator past 64 bits is an error,
    /// never a wrap to another point.
    ///
    /// ```
    /// use subdiv_stencil::Dyadic;
    ///
    /// assert_eq!("1/3, 1/2".parse::<Dyadic>()?, Dyadic::new(2, 3, 6));
    /// assert_eq!("1,0".parse::<Dyadic>()?, Dyadic::new(1, 0, 1));
    /// assert!("1/4294967297,1/4294967298".parse::<Dyadic>().is_err());
    /// # Ok::<(), subdiv_stencil::StencilError>(())
    /// ```
    fn from_str(text: &str) -> Result<Self, StencilError> {
        let bad = |reason: &'static str| StencilError::ParameterSyntax { text: text.to_string(), reason };
        let (u, v) = text.split_once(',').ok_or_else(|| bad("expected U,V"))?;
        let whole = |e: StencilError| match e {
            StencilError::ParameterSyntax { reason, .. } => bad(reason),
            e => e,
        };
        let ((a, b), (c, d)) = (parse_fraction(u).map_err(whole)?, parse_fraction(v).map_err(whole)?);
        let q = (b / b.gcd(&d)).checked_mul(d);
        let point = q.and_then(|q| Some(Self::new(a.checked_mul(q / b)?, c.checked_mul(q / d)?, q)));
        point.ok_or_else(|| bad("the common denominator of the two fractions does not fit in 64 bits"))
    }
}

/// One rational number `p/q` (q > 0) or an integer, in 64-bit integers, not reduced: the
/// parser of [`Dyadic`]'s `U,V` and of a curve parameter.
///
/// ```
/// use subdiv_stencil::parse_fraction;
///
/// assert_eq!(parse_fraction(" 3/8 ")?, (3, 8));
/// assert_eq!(parse_fraction("-2")?, (-2, 1));
/// assert!(parse_fraction("1/0").is_err());
/// assert!(parse_fraction("1/99999999999999999999").is_err());
/// # Ok::<(), subdiv_stencil::StencilError>(())
/// ```
///
/// # Errors
/// [`StencilError::ParameterSyntax`] naming the text and the rule.
pub fn parse_fraction(text: &str) -> Result<(i64, i64), StencilError> {
    let bad = |reason: &'static str| StencilError::ParameterSyntax { text: text.to_string(), reason };
    let number = |t: &str| t.trim().parse::<i64>().map_err(|_| bad("expected integers p and q in p/q"));
    let (p, q) = match text.split_once('/') {
        Some((p, q)) => (number(p)?, number(q)?),
        None => (number(text)?, 1),
    };
    if q <= 0 { Err(bad("a denominator must be positive")) } else { Ok((p, q)) }
}

impl Address {
    /// The address of `point` in the domain of a face of `face_size` sides: the unit square
    /// (4) or the triangle `u, v ≥ 0, u + v ≤ 1` (3). Where a point lies on the border of two
    /// children the first in the engine's order wins.
    ///
    /// ```
    /// use subdiv_stencil::{Address, Dyadic};
    ///
    /// // 1/3 = 0.010101…₂: in u, child 0 then child 1 for ever; v = 0 stays in children 0, 1.
    /// let a = Address::of(4, Dyadic::new(1, 0, 3))?;
    /// assert_eq!((a.prefix.as_slice(), a.period.as_slice()), (&[][..], &[0, 1][..]));
    /// # Ok::<(), subdiv_stencil::StencilError>(())
    /// ```
    ///
    /// # Errors
    /// [`StencilError::OutsideDomain`] for a point outside the domain or a denominator below 1.
    pub fn of(face_size: usize, point: Dyadic) -> Result<Self, StencilError> {
        check_domain(face_size, point)?;
        let q = point.denominator;
        let next = |(a, b): (i64, i64)| {
            let (child, a, b) = step(face_size, 2, a, b, q);
            (child, (a, b))
        };
        let (steps, end) =
            walk((point.u, point.v), next, |_| false, MAX_ADDRESS_STEPS).map_err(|limit| too_long(point, limit))?;
        let Walked::Cycle(first) = end else { unreachable!("a walk that knows no state ends in a cycle") };
        let mut prefix: Vec<u8> = steps.iter().map(|&(_, child)| child).collect();
        let period = prefix.split_off(first);
        Ok(Self { prefix, period })
    }
}

/// The most levels an address walk takes (its prefix and one period) before it is refused
/// with [`StencilError::AddressTooLong`]: the default of
/// [`StencilEvaluator::with_max_address_steps`](crate::StencilEvaluator::with_max_address_steps).
///
/// A point `p/q` has a period as long as the order of 2 modulo `q`'s odd part, up to `q − 1`
/// levels, and the routes multiply one sub-patch matrix per level of it: 16,380 levels
/// (`subdiv stencil --valence 4 --at 1/16381,0`) take 0.14 s in a debug build, and a walk
/// keeps every state, so `1/1000003` (10⁶ levels) would take minutes and gigabytes.
pub const MAX_ADDRESS_STEPS: usize = 1 << 14;

/// Where an address [`walk`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Walked<S> {
    /// At a state the caller knows, which follows the last step.
    Known(S),
    /// At a state the walk had passed: the steps from this index on form a cycle.
    Cycle(usize),
}

/// The states of an address [`walk`] with the child taken from each, and where it stopped.
pub(crate) type Walk<S> = (Vec<(S, u8)>, Walked<S>);

/// An address walk from `start`: each state with the child `next` takes from it, until a state
/// `known` accepts or a state repeats. Linear in the steps (states are hashed); `Err(limit)`
/// once it would take more than `limit` steps.
pub(crate) fn walk<S: Copy + Eq + Hash>(
    start: S,
    mut next: impl FnMut(S) -> (u8, S),
    known: impl Fn(&S) -> bool,
    limit: usize,
) -> Result<Walk<S>, usize> {
    let mut steps: Vec<(S, u8)> = Vec::new();
    let mut seen: HashMap<S, usize> = HashMap::new();
    let mut state = start;
    loop {
        if known(&state) {
            return Ok((steps, Walked::Known(state)));
        }
        if let Some(&first) = seen.get(&state) {
            return Ok((steps, Walked::Cycle(first)));
        }
        if steps.len() == limit {
            return Err(limit);
        }
        seen.insert(state, steps.len());
        let (child, successor) = next(state);
        steps.push((state, child));
        state = successor;
    }
}

/// [`StencilError::AddressTooLong`] for `point` and the walk limit it passed.
pub(crate) fn too_long(point: Dyadic, limit: usize) -> StencilError {
    let Dyadic { u, v, denominator: q } = point;
    StencilError::AddressTooLong { u: format!("{u}/{q}"), v: format!("{v}/{q}"), limit }
}

/// [`StencilError::OutsideDomain`] unless `point` lies in the domain of a face of `face_size`
/// sides, over a denominator small enough that the address arithmetic cannot overflow.
pub(crate) fn check_domain(face_size: usize, point: Dyadic) -> Result<(), StencilError> {
    let Dyadic { u, v, denominator: q } = point;
    let triangle = face_size == 3;
    let inside = q >= 1 && u >= 0 && v >= 0 && if triangle { u + v <= q } else { u <= q && v <= q };
    if !inside || q > i64::MAX / 4 {
        return Err(StencilError::OutsideDomain {
            u: format!("{u}/{q}"),
            v: format!("{v}/{q}"),
            domain: if triangle { "u, v ≥ 0, u + v ≤ 1" } else { "[0, 1]²" },
        });
    }
    Ok(())
}

/// One level of an address: the child of a face of `face_size` sides, split `scale` times
/// along each side (2, or 3 for the ternary split of triangles), holding the point `(a, b) / q`
/// (on a border one of the children holding it, always the same), and the point in the child's
/// domain, over the same denominator.
pub(crate) fn step(face_size: usize, scale: u8, a: i64, b: i64, q: i64) -> (u8, i64, i64) {
    if scale == 3 {
        return ternary_step(a, b, q);
    }
    let child = if face_size == 3 {
        if 2 * (a + b) <= q {
            0
        } else if 2 * a >= q {
            1
        } else if 2 * b >= q {
            2
        } else {
            3
        }
    } else {
        match (2 * a >= q, 2 * b >= q) {
            (false, false) => 0,
            (true, false) => 1,
            (true, true) => 2,
            (false, true) => 3,
        }
    };
    let ChildDomain { offset, flipped, .. } = ChildDomain::of_face(face_size)[child];
    let sign = if flipped { -1 } else { 1 };
    (child as u8, sign * (2 * a - i64::from(offset[0]) * q), sign * (2 * b - i64::from(offset[1]) * q))
}

/// [`step`] of the ternary split ([`ChildDomain::ternary`]): the lattice cell `(i, j)` of
/// `3·(a, b)/q`, upright where the point's offset in it sums to at most 1, else upside down.
fn ternary_step(a: i64, b: i64, q: i64) -> (u8, i64, i64) {
    let (mut i, j) = ((3 * a / q).min(2), (3 * b / q).min(2));
    if i + j == 3 {
        // A lattice point of the long side: corner 1 of the upright cell to its left.
        i -= 1;
    }
    let (x, y) = (3 * a - i * q, 3 * b - j * q);
    if x + y <= q {
        let child = [[0, 3, 5], [1, 4, 5], [2, 4, 5]][i as usize][j as usize];
        (child, x, y)
    } else {
        let child = 6 + i + 2 * j;
        (child as u8, q - x, q - y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_and_centres() {
        let a = Address::of(4, Dyadic::new(0, 0, 1)).unwrap();
        assert_eq!((a.prefix, a.period), (vec![], vec![0]));
        let a = Address::of(4, Dyadic::new(1, 1, 2)).unwrap();
        assert_eq!((a.prefix, a.period), (vec![2], vec![0]));
        let a = Address::of(4, Dyadic::new(1, 1, 1)).unwrap();
        assert_eq!((a.prefix, a.period), (vec![], vec![2]));
        // The centroid of a triangle is the middle child's centroid for ever.
        let a = Address::of(3, Dyadic::new(1, 1, 3)).unwrap();
        assert_eq!((a.prefix, a.period), (vec![], vec![3]));
        assert!(Address::of(3, Dyadic::new(2, 2, 3)).is_err());
        assert!(Address::of(4, Dyadic::new(0, 0, 0)).is_err());
    }

    #[test]
    fn ternary_steps_land_in_the_child_s_domain() {
        // Every point i/q, j/q of the triangle: the child's point, mapped back, is the point.
        let q = 36;
        for j in 0..=q {
            for i in 0..=q - j {
                let (child, a, b) = step(3, 3, i, j, q);
                assert!(a >= 0 && b >= 0 && a + b <= q, "({i}, {j}) -> child {child} at ({a}, {b})");
                let d = ChildDomain::ternary()[usize::from(child)];
                let (u, v) = d.to_parent(a as f64 / q as f64, b as f64 / q as f64);
                assert!((u - i as f64 / q as f64).abs() < 1e-15 && (v - j as f64 / q as f64).abs() < 1e-15);
            }
        }
        // The centroid is corner 0 of the middle upright child; 1/4 = 0.0202…₃ alternates.
        assert_eq!(step(3, 3, 1, 1, 3), (4, 0, 0));
        assert_eq!(step(3, 3, 1, 0, 4), (0, 3, 0));
        assert_eq!(step(3, 3, 3, 0, 4), (2, 1, 0));
    }

    #[test]
    fn long_periods_are_walked_in_linear_time_up_to_the_limit() {
        // 2 has order 16380 modulo the prime 16381: the longest period under the limit.
        let a = Address::of(4, Dyadic::new(1, 0, 16381)).unwrap();
        assert_eq!((a.prefix.len(), a.period.len()), (0, 16380));
        // 1/1000003 has a period of 10⁶ levels: refused at the limit, not walked for minutes.
        let e = Address::of(4, Dyadic::new(1, 0, 1_000_003)).unwrap_err();
        assert_eq!(
            e,
            StencilError::AddressTooLong { u: "1/1000003".into(), v: "0/1000003".into(), limit: MAX_ADDRESS_STEPS }
        );
        assert!(e.to_string().contains("longer than 16384 levels"), "{e}");
    }
}
