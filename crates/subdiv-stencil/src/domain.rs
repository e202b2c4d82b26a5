//! A face's parameter domain as OpenSubdiv's `Bfr` lays it out (quads, triangles, an N-gon's
//! quad sub-faces), the frame of its patch inside it, and f64 parameters taken exactly.

use subdiv_schemes::{ChildDomain, Split};

use crate::address::step;
use crate::{Dyadic, Grid};

/// The largest denominator exponent of an f64 parameter used exactly: `2^60` stays below the
/// bound of [`Address::of`](crate::Address::of) (`i64::MAX / 4`) after the doublings of a descent.
pub const MAX_DENOMINATOR_BITS: u32 = 60;

/// One point of a face's `--grid N` sampling, in OpenSubdiv's order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridParameter {
    /// The exact parameter.
    pub point: Dyadic,
    /// The parameter in f64, rounded as OpenSubdiv's `osd_limit` rounds it (for N-gons:
    /// `origin + (i / N) / 2`), so that output columns agree to the bit.
    pub u: f64,
    /// See [`u`](Self::u).
    pub v: f64,
}

/// The parameter domain of a face, as `Bfr` lays it out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceDomain {
    /// The unit square (quads under a quad split).
    Quad,
    /// The triangle `u, v ≥ 0, u + v ≤ 1` (triangles under a triangle split).
    Triangle,
    /// The same triangle split in nine (√3, whose two steps are one ternary split): children
    /// as [`ChildDomain::ternary`] lays them out.
    Ternary,
    /// An N-gon under a quad split (triangles included): `size` quad sub-faces, sub-face `s`
    /// the lower-left half `[0, ½]²` of the unit tile at `(s mod columns, s div columns)`, where
    /// `columns = ⌈√size⌉` (`Bfr::Parameterization::QUAD_SUBFACES`).
    SubFaces {
        /// The face's number of sides.
        size: usize,
        /// Tiles per row.
        columns: usize,
    },
}

impl FaceDomain {
    /// The domain of a face of `size` sides under `split` (the dual and mid-edge splits' faces take
    /// the quad split's domains: their patches are the faces' corners); `None` for a split without
    /// sub-patch matrices, or a triangle split's non-triangle.
    pub fn of(split: Split, size: usize) -> Option<Self> {
        match (split, size) {
            (Split::Quad | Split::Dual | Split::Midedge, 4) => Some(Self::Quad),
            (Split::Quad | Split::Dual | Split::Midedge, _) => {
                Some(Self::SubFaces { size, columns: (1..).find(|c| c * c >= size).unwrap_or(size) })
            }
            (Split::Triangle, 3) => Some(Self::Triangle),
            (Split::Sqrt3, 3) => Some(Self::Ternary),
            _ => None,
        }
    }

    /// Whether `p` lies in the domain.
    pub fn contains(self, p: Dyadic) -> bool {
        let Dyadic { u, v, denominator: q } = p;
        if q < 1 || u < 0 || v < 0 {
            return false;
        }
        match self {
            Self::Quad => u <= q && v <= q,
            Self::Triangle | Self::Ternary => u <= q - v,
            Self::SubFaces { size, columns } => {
                let (tu, tv) = (u / q, v / q);
                let tile =
                    usize::try_from(tv).ok().and_then(|tv| tv.checked_mul(columns)).zip(usize::try_from(tu).ok());
                tile.is_some_and(|(row, column)| column < columns && row + column < size)
                    && 2 * (u - tu * q) <= q
                    && 2 * (v - tv * q) <= q
            }
        }
    }

    /// [`contains`](Self::contains) for f64 parameters (false for non-finite values).
    pub fn contains_f64(self, u: f64, v: f64) -> bool {
        if !(u >= 0.0 && v >= 0.0 && u.is_finite() && v.is_finite()) {
            return false;
        }
        match self {
            Self::Quad => u <= 1.0 && v <= 1.0,
            Self::Triangle | Self::Ternary => u + v <= 1.0,
            Self::SubFaces { size, columns } => {
                let (tu, tv) = (u.floor(), v.floor());
                tu < columns as f64
                    && tv * (columns as f64) + tu < size as f64
                    && 2.0 * (u - tu) <= 1.0
                    && 2.0 * (v - tv) <= 1.0
            }
        }
    }

    /// The domain in words, for error messages.
    pub fn describe(self) -> String {
        match self {
            Self::Quad => "[0, 1]²".to_string(),
            Self::Triangle | Self::Ternary => "u, v ≥ 0, u + v ≤ 1".to_string(),
            Self::SubFaces { size, columns } => format!(
                "the {size} sub-face tiles of a {size}-gon: (s mod {columns} + a/2, s div {columns} + b/2) \
                 for sub-face s < {size} and a, b in [0, 1]"
            ),
        }
    }

    /// The child of a face with this domain that holds `p`, and `p` in the child's parameters,
    /// with the factor `f` of the step's derivatives (`∂/∂u = f · ∂/∂u_child`, likewise `v`):
    /// 2, or −2 for the middle triangle (3 and −3 under the ternary split). On a border
    /// between children the first in the
    /// engine's order that holds the point wins (either gives the same value). `p` must be
    /// [contained](Self::contains).
    pub fn child_of(self, p: Dyadic) -> (usize, Dyadic, f64) {
        let Dyadic { u, v, denominator: q } = p;
        match self {
            Self::Quad | Self::Triangle => {
                // The address's first step: the same choice on borders as the stencils make.
                let size = if self == Self::Triangle { 3 } else { 4 };
                let (child, a, b) = step(size, 2, u, v, q);
                let flipped = ChildDomain::of_face(size)[usize::from(child)].flipped;
                (usize::from(child), Dyadic::new(a, b, q), if flipped { -2.0 } else { 2.0 })
            }
            Self::Ternary => {
                let (child, a, b) = step(3, 3, u, v, q);
                let flipped = ChildDomain::ternary()[usize::from(child)].flipped;
                (usize::from(child), Dyadic::new(a, b, q), if flipped { -3.0 } else { 3.0 })
            }
            Self::SubFaces { columns, .. } => {
                let (tu, tv) = (u / q, v / q);
                let sub = tv as usize * columns + tu as usize;
                (sub, Dyadic::new(2 * (u - tu * q), 2 * (v - tv * q), q), 2.0)
            }
        }
    }

    /// [`child_of`](Self::child_of) for f64 parameters, for evaluators that do not need exact
    /// points: the child holding `(u, v)` (on a border, the first in the engine's order, as the
    /// exact address's first step chooses), the point in its parameters, and the derivative
    /// factor.
    #[inline]
    pub fn child_of_f64(self, u: f64, v: f64) -> (usize, f64, f64, f64) {
        match self {
            Self::Quad | Self::Triangle => {
                let triangle = self == Self::Triangle;
                let child = if triangle {
                    if u + v <= 0.5 {
                        0
                    } else if u >= 0.5 {
                        1
                    } else if v >= 0.5 {
                        2
                    } else {
                        3
                    }
                } else {
                    match (u <= 0.5, v <= 0.5) {
                        (true, true) => 0,
                        (false, true) => 1,
                        (false, false) => 2,
                        (true, false) => 3,
                    }
                };
                let domain = ChildDomain::of_face(if triangle { 3 } else { 4 })[child];
                let (cu, cv) = domain.to_child(u, v);
                (child, cu, cv, if domain.flipped { -2.0 } else { 2.0 })
            }
            Self::Ternary => {
                // The exact step on the point's nearest multiple of 2^-52 (exact for the
                // dyadic parameters callers give).
                let q = 1i64 << 52;
                let p = |x: f64| (x * q as f64).round() as i64;
                let (child, a, b) = step(3, 3, p(u), p(v), q);
                let domain = ChildDomain::ternary()[usize::from(child)];
                (usize::from(child), a as f64 / q as f64, b as f64 / q as f64, if domain.flipped { -3.0 } else { 3.0 })
            }
            Self::SubFaces { columns, .. } => {
                let (tu, tv) = (u.floor().max(0.0), v.floor().max(0.0));
                let sub = tv as usize * columns + tu as usize;
                (sub, 2.0 * (u - tu), 2.0 * (v - tv), 2.0)
            }
        }
    }

    /// The `Bfr` parameter of normalized sub-face coordinates `(a, b)` of sub-face `sub`
    /// (quads and triangles: the point itself).
    pub fn from_sub_face(self, sub: usize, a: Dyadic) -> Dyadic {
        match self {
            Self::Quad | Self::Triangle | Self::Ternary => a,
            Self::SubFaces { columns, .. } => {
                let q = 2 * a.denominator;
                let (tu, tv) = ((sub % columns) as i64, (sub / columns) as i64);
                Dyadic::new(tu * q + a.u, tv * q + a.v, q)
            }
        }
    }

    /// The limit of the linear split (bilinear for quad splits, linear triangles for triangle
    /// splits) over a face of this domain at `(u, v)`, as weights of the face's corners, into
    /// `out`: per corner in order, its weight in the value and in `∂/∂u`, `∂/∂v`. A quad's is
    /// the bilinear interpolation, a triangle's the linear one; an N-gon's point lies on a `Bfr`
    /// sub-face, the quad of its corner `s`, the midpoints of its sides `s` and `s − 1` and its
    /// centroid (the bilinear split's first level), bilinear there. `(u, v)` must be
    /// [contained](Self::contains_f64).
    ///
    /// ```
    /// use subdiv_stencil::FaceDomain;
    ///
    /// let mut w = Vec::new();
    /// FaceDomain::Quad.linear_weights(0.25, 0.5, &mut w);
    /// assert_eq!(w.iter().map(|w| w[0]).collect::<Vec<_>>(), [0.375, 0.125, 0.125, 0.375]);
    /// // A pentagon's centroid: a fifth of each corner.
    /// FaceDomain::SubFaces { size: 5, columns: 3 }.linear_weights(0.5, 0.5, &mut w);
    /// assert!(w.iter().all(|w| (w[0] - 0.2).abs() < 1e-15));
    /// ```
    pub fn linear_weights(self, u: f64, v: f64, out: &mut Vec<[f64; 3]>) {
        let bilinear = |u: f64, v: f64| {
            [
                [(1.0 - u) * (1.0 - v), v - 1.0, u - 1.0],
                [u * (1.0 - v), 1.0 - v, -u],
                [u * v, v, u],
                [(1.0 - u) * v, -v, 1.0 - u],
            ]
        };
        out.clear();
        match self {
            Self::Triangle | Self::Ternary => out.extend([[1.0 - u - v, -1.0, -1.0], [u, 1.0, 0.0], [v, 0.0, 1.0]]),
            Self::Quad => out.extend(bilinear(u, v)),
            Self::SubFaces { size: n, .. } => {
                let (sub, a, b, scale) = self.child_of_f64(u, v);
                let [w0, w1, w2, w3] = bilinear(a, b).map(|[p, du, dv]| [p, scale * du, scale * dv]);
                // The centroid's share, then each corner's.
                out.extend((0..n).map(|_| w2.map(|x| x / n as f64)));
                let mut add = |k: usize, w: [f64; 3], f: f64| {
                    let e = &mut out[k % n];
                    (0..3).for_each(|r| e[r] += f * w[r]);
                };
                add(sub, w0, 1.0);
                add(sub, w1, 0.5);
                add(sub + 1, w1, 0.5);
                add(sub, w3, 0.5);
                add(sub + n - 1, w3, 0.5);
            }
        }
    }

    /// How many points [`grid`](Self::grid) lists for `n`, without listing them (for budgets).
    ///
    /// ```
    /// use subdiv_stencil::FaceDomain;
    ///
    /// assert_eq!(FaceDomain::Quad.grid_len(4), 25);
    /// assert_eq!(FaceDomain::Triangle.grid_len(4), 15);
    /// assert_eq!(FaceDomain::SubFaces { size: 5, columns: 3 }.grid_len(4), 5 * 25);
    /// ```
    pub fn grid_len(self, n: u32) -> u64 {
        let side = u64::from(n) + 1;
        match self {
            Self::Quad => side * side,
            Self::Triangle | Self::Ternary => side * (side + 1) / 2,
            Self::SubFaces { size, .. } => size as u64 * side * side,
        }
    }

    /// The points of `osd_limit --grid n` on a face of this domain, in its order: quads
    /// `(i/n, j/n)`, `j` outer; triangles the same with `i + j ≤ n`; N-gons, for each sub-face,
    /// the `(n + 1)²` grid of normalized sub-face coordinates.
    pub fn grid(self, n: u32) -> Vec<GridParameter> {
        let exact = |point: Dyadic| {
            let (u, v) = point.to_f64();
            GridParameter { point, u, v }
        };
        match self {
            Self::Quad => Grid::Primal.points(4, n).into_iter().map(exact).collect(),
            Self::Triangle | Self::Ternary => Grid::Primal.points(3, n).into_iter().map(exact).collect(),
            Self::SubFaces { size, columns } => {
                let square = Grid::Primal.points(4, n);
                (0..size)
                    .flat_map(|s| square.iter().map(move |&ab| (s, ab)))
                    .map(|(s, ab)| {
                        let (a, b) = ab.to_f64();
                        GridParameter {
                            point: self.from_sub_face(s, ab),
                            u: (s % columns) as f64 + a * 0.5,
                            v: (s / columns) as f64 + b * 0.5,
                        }
                    })
                    .collect()
            }
        }
    }
}

/// How the descent splits a face into its children on the next level of
/// [`PatchLevels`](crate::PatchLevels) ([`Resolved::Children`](crate::Resolved::Children)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// As the face's domain lays its children out ([`FaceDomain::child_of`]): quarters,
    /// triangles, an N-gon's sub-faces, √3's nine.
    Domain(FaceDomain),
    /// A quad of a dual split (Doo-Sabin, mid-edge) with boundary sides, whose parameter
    /// domain is the unit square: a corner on a boundary side has no piece of surface (its
    /// point on the first level is a boundary vertex, whose dual quad is empty), so the other
    /// corners' pieces (the [`Quad`](FaceDomain::Quad) split's quarters, in their own frames)
    /// stretch across the face. `sides` has bit `k` set for boundary side `k` (from corner `k`
    /// to corner `k + 1`): one side, and the two corners across from it cover a half each,
    /// stretched twice along the side's normal; or two sides meeting at a corner, and the
    /// opposite corner's piece covers the face.
    DualBoundaryQuad {
        /// The boundary sides, bit `k` for side `k`.
        sides: u8,
    },
}

impl Layout {
    /// The child that holds `p`, `p` in the child's parameters, and the factors `[f, g]` of
    /// the step's derivatives (`∂/∂u = f · ∂/∂u_child`, `∂/∂v = g · ∂/∂v_child`): the domain's
    /// [`child_of`](FaceDomain::child_of) on both axes, or a dual boundary quad's stretch. On a
    /// border between children the first in the engine's order wins. `p` must be in the
    /// face's domain.
    ///
    /// ```
    /// use subdiv_stencil::{Dyadic, FaceDomain, Layout};
    ///
    /// assert_eq!(Layout::Domain(FaceDomain::Quad).child_of(Dyadic::new(3, 1, 4)), (1, Dyadic::new(2, 2, 4), [2.0, 2.0]));
    /// // Side 0 (v = 0) on the boundary: corner 3's quarter covers the left half, stretched along v.
    /// let boundary = Layout::DualBoundaryQuad { sides: 0b0001 };
    /// assert_eq!(boundary.child_of(Dyadic::new(1, 1, 4)), (3, Dyadic::new(2, 1, 4), [2.0, 1.0]));
    /// ```
    pub fn child_of(self, p: Dyadic) -> (usize, Dyadic, [f64; 2]) {
        match self {
            Self::Domain(domain) => {
                let (child, at, factor) = domain.child_of(p);
                (child, at, [factor, factor])
            }
            Self::DualBoundaryQuad { sides } => {
                let Dyadic { u, v, denominator: q } = p;
                let (child, [a, b], factors) = dual_boundary_child(sides, [u, v], q);
                (child, Dyadic::new(a, b, q), factors)
            }
        }
    }
}

/// [`Layout::DualBoundaryQuad`]'s step: the quarter holding the point `[u, v] / q` and the
/// point in its frame, and the derivative factors. One boundary side `k`: the corners `k + 2`
/// and `k + 3` cover the halves across it, each the quarter of its corner stretched twice
/// along the side's normal; two sides meeting at corner `k`: corner `k + 2`'s quarter covers
/// the face.
fn dual_boundary_child(sides: u8, [u, v]: [i64; 2], q: i64) -> (usize, [i64; 2], [f64; 2]) {
    match sides {
        // Side 0 (v = 0): corners 3 (u < ½) and 2, stretched along v.
        0b0001 if 2 * u >= q => (2, [2 * u - q, v], [2.0, 1.0]),
        0b0001 => (3, [2 * u, v], [2.0, 1.0]),
        // Side 1 (u = 1): corners 0 (v ≤ ½) and 3, stretched along u.
        0b0010 if 2 * v <= q => (0, [u, 2 * v], [1.0, 2.0]),
        0b0010 => (3, [u, 2 * v - q], [1.0, 2.0]),
        // Side 2 (v = 1): corners 0 (u ≤ ½) and 1.
        0b0100 if 2 * u <= q => (0, [2 * u, v], [2.0, 1.0]),
        0b0100 => (1, [2 * u - q, v], [2.0, 1.0]),
        // Side 3 (u = 0): corners 1 (v ≤ ½) and 2.
        0b1000 if 2 * v <= q => (1, [u, 2 * v], [1.0, 2.0]),
        0b1000 => (2, [u, 2 * v - q], [1.0, 2.0]),
        // Two sides at a corner: the opposite corner's quarter, unstretched.
        0b0011 => (3, [u, v], [1.0, 1.0]),
        0b0110 => (0, [u, v], [1.0, 1.0]),
        0b1100 => (1, [u, v], [1.0, 1.0]),
        _ => (2, [u, v], [1.0, 1.0]),
    }
}

/// A face's frame in the frame of its patch, which starts at corner `rotation` of the face:
/// the face's parameters are `origin + s·e1 + t·e2` in the patch's `(s, t)`, with integer
/// vectors of determinant 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PatchFrame {
    origin: [i64; 2],
    e1: [i64; 2],
    e2: [i64; 2],
}

impl PatchFrame {
    /// The frame of a patch starting at corner `rotation` of a quad (`face_size` 4) or a
    /// triangle (3): its first side runs from corner `rotation` to the next corner, its last
    /// side to the previous one.
    pub fn new(face_size: usize, rotation: usize) -> Self {
        const QUAD: [[i64; 2]; 4] = [[0, 0], [1, 0], [1, 1], [0, 1]];
        const TRIANGLE: [[i64; 2]; 3] = [[0, 0], [1, 0], [0, 1]];
        let corners: &[[i64; 2]] = if face_size == 3 { &TRIANGLE } else { &QUAD };
        let n = corners.len();
        let c = |k: usize| corners[k % n];
        let (o, next, previous) = (c(rotation), c(rotation + 1), c(rotation + n - 1));
        Self { origin: o, e1: [next[0] - o[0], next[1] - o[1]], e2: [previous[0] - o[0], previous[1] - o[1]] }
    }

    /// The determinant of `[e1 e2]` (1: the patch keeps the face's orientation).
    fn determinant(self) -> i64 {
        self.e1[0] * self.e2[1] - self.e2[0] * self.e1[1]
    }

    /// The face's point `p` in the patch's parameters.
    pub fn to_patch(self, p: Dyadic) -> Dyadic {
        let q = p.denominator;
        let (x, y) = (p.u - self.origin[0] * q, p.v - self.origin[1] * q);
        // [e1 e2]⁻¹ = adj / det, det = ±1.
        let d = self.determinant();
        Dyadic::new(d * (self.e2[1] * x - self.e2[0] * y), d * (self.e1[0] * y - self.e1[1] * x), q)
    }

    /// The patch's point in the face's parameters.
    pub fn to_face(self, p: Dyadic) -> Dyadic {
        let q = p.denominator;
        let at = |k: usize| self.origin[k] * q + p.u * self.e1[k] + p.v * self.e2[k];
        Dyadic::new(at(0), at(1), q)
    }

    /// The rows of `j · J` ([`derivative_map`](Self::derivative_map)): with `j` taking a
    /// face's derivatives to this face's (`(∂/∂u, ∂/∂v)` of the input face `= j ·` those of
    /// this face), the rows give the input face's `∂/∂u` and `∂/∂v` as combinations of the
    /// patch's `(∂/∂s, ∂/∂t)`.
    pub fn chain(self, j: [[f64; 2]; 2]) -> ([f64; 2], [f64; 2]) {
        let r = self.derivative_map();
        let m = |row: [f64; 2]| [row[0] * r[0][0] + row[1] * r[1][0], row[0] * r[0][1] + row[1] * r[1][1]];
        (m(j[0]), m(j[1]))
    }

    /// `J` with `(∂/∂u, ∂/∂v) = J · (∂/∂s, ∂/∂t)`: the inverse transpose of `[e1 e2]`.
    pub fn derivative_map(self) -> [[f64; 2]; 2] {
        let d = self.determinant() as f64;
        // ([e1 e2]⁻¹)ᵀ = (adj / det)ᵀ.
        [[d * self.e2[1] as f64, -d * self.e1[1] as f64], [-d * self.e2[0] as f64, d * self.e1[0] as f64]]
    }
}

/// The exponent of the lattice `(1/3^k) ℤ²` that [`FaceDomain::exact_point`] rounds a ternary
/// face's f64 parameters to: `3^−33 ≈ 1.8e−16`, below the spacing of f64 values near 1, and
/// `3^33 ≈ 5.6e15` leaves the address arithmetic room in 64 bits.
pub const TERNARY_DIGITS: u32 = 33;

impl FaceDomain {
    /// The f64 parameters `(u, v)` as the exact point the evaluators take: the fraction over
    /// `2^k` that they are ([`dyadic_from_f64`]), except on a [ternary](Self::Ternary) face,
    /// where a dyadic point's base-3 address has a period of up to `2^(k−2)` levels (`1/2^52`:
    /// 2^50): there the nearest point of `(1/3^33) ℤ²` in the triangle, whose address ends after
    /// [`TERNARY_DIGITS`] levels at a corner, within `1e−16` of `(u, v)`. `None` where
    /// [`dyadic_from_f64`] has none, or (ternary) outside the triangle.
    ///
    /// ```
    /// use subdiv_stencil::{Dyadic, FaceDomain};
    ///
    /// assert_eq!(FaceDomain::Triangle.exact_point(0.25, 0.5), Some(Dyadic::new(1, 2, 4)));
    /// let p = FaceDomain::Ternary.exact_point(0.3, 0.2).unwrap();
    /// assert_eq!(p.denominator, 3i64.pow(33));
    /// assert!((p.to_f64().0 - 0.3).abs() < 1e-16);
    /// assert_eq!(FaceDomain::Ternary.exact_point(1.0 / 3.0, 0.0).map(|p| p.reduced()), Some(Dyadic::new(1, 0, 3)));
    /// ```
    pub fn exact_point(self, u: f64, v: f64) -> Option<Dyadic> {
        if self != Self::Ternary {
            return dyadic_from_f64(u, v);
        }
        if !self.contains_f64(u, v) {
            return None;
        }
        let q = 3i64.pow(TERNARY_DIGITS);
        let (mut a, mut b) = ((u * q as f64).round() as i64, (v * q as f64).round() as i64);
        // Rounding may step past the long side.
        let over = (a + b - q).max(0);
        if a >= b {
            a -= over;
        } else {
            b -= over;
        }
        Some(Dyadic::new(a, b, q))
    }
}

/// The f64 parameters `(u, v)` as one exact fraction over `2^k`, `k ≤` [`MAX_DENOMINATOR_BITS`];
/// a value with more binary digits after the point (below `2^−60` in its last place) is rounded
/// to the nearest multiple of `2^−60`, which moves the point by less than `1e−18`. `None` for a
/// non-finite value or one beyond `±2^20` (outside every face's domain).
pub fn dyadic_from_f64(u: f64, v: f64) -> Option<Dyadic> {
    const LIMIT: f64 = (1u64 << 20) as f64;
    if !(u.abs() <= LIMIT && v.abs() <= LIMIT) {
        return None;
    }
    let bits = |x: f64| (0..=MAX_DENOMINATOR_BITS).find(|&k| (x * (1u64 << k) as f64).fract() == 0.0);
    let k = bits(u).zip(bits(v)).map_or(MAX_DENOMINATOR_BITS, |(a, b)| a.max(b));
    let scale = (1u64 << k) as f64;
    // Exact when the value has at most k binary digits after the point; rounded otherwise.
    Some(Dyadic::new((u * scale).round() as i64, (v * scale).round() as i64, 1i64 << k).reduced())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch_levels::children;
    use subdiv_mesh::{FaceId, Mesh, shapes};
    use subdiv_schemes::{Builtin, RefineOptions, refine};

    #[test]
    fn grid_len_counts_the_grid() {
        let domains = [FaceDomain::Quad, FaceDomain::Triangle, FaceDomain::of(Split::Quad, 7).unwrap()];
        for (domain, n) in domains.into_iter().flat_map(|d| [1, 2, 5, 16].map(|n| (d, n))) {
            assert_eq!(domain.grid_len(n), domain.grid(n).len() as u64, "{domain:?} at {n}");
        }
    }

    #[test]
    fn patch_frames_round_trip_and_keep_orientation() {
        for (size, rotations) in [(4, 4), (3, 3)] {
            for r in 0..rotations {
                let frame = PatchFrame::new(size, r);
                assert_eq!(frame.determinant(), 1, "size {size}, rotation {r}");
                // The patch's corner 0 is the face's corner r.
                let corner0 = frame.to_face(Dyadic::new(0, 0, 1));
                let corners: [[i64; 2]; 4] = [[0, 0], [1, 0], [1, 1], [0, 1]];
                let tri: [[i64; 2]; 3] = [[0, 0], [1, 0], [0, 1]];
                let expect = if size == 4 { corners[r] } else { tri[r] };
                assert_eq!([corner0.u, corner0.v], expect);
                for (u, v) in [(1, 2), (3, 0), (0, 5), (2, 2)] {
                    let p = Dyadic::new(u, v, 7);
                    if size == 3 && u + v > 7 {
                        continue;
                    }
                    assert_eq!(frame.to_face(frame.to_patch(p)), p);
                }
            }
        }
        // Rotation 1 of a quad: s runs along v, t against u.
        let frame = PatchFrame::new(4, 1);
        assert_eq!(frame.to_patch(Dyadic::new(1, 3, 4)), Dyadic::new(3, 3, 4));
        // A linear function f = a·u + b·v: ∂f/∂s = b, ∂f/∂t = −a; the map gives back (a, b).
        let (a, b) = (2.0, 5.0);
        let j = frame.derivative_map();
        let (ds, dt) = (b, -a);
        assert_eq!([j[0][0] * ds + j[0][1] * dt, j[1][0] * ds + j[1][1] * dt], [a, b]);
        // The same on a triangle at rotation 2: s = from corner 2 (0, 1) toward corner 0.
        let frame = PatchFrame::new(3, 2);
        let f = |p: Dyadic| a * p.u as f64 + b * p.v as f64;
        let origin = f(frame.to_face(Dyadic::new(0, 0, 1)));
        let (ds, dt) =
            (f(frame.to_face(Dyadic::new(1, 0, 1))) - origin, f(frame.to_face(Dyadic::new(0, 1, 1))) - origin);
        let j = frame.derivative_map();
        assert_eq!([j[0][0] * ds + j[0][1] * dt, j[1][0] * ds + j[1][1] * dt], [a, b]);
    }

    #[test]
    fn sub_face_tiles_follow_bfr() {
        // A pentagon: 3 tiles per row; sub-face 4 at tile (1, 1).
        let d = FaceDomain::of(Split::Quad, 5).unwrap();
        assert_eq!(d, FaceDomain::SubFaces { size: 5, columns: 3 });
        let p = d.from_sub_face(4, Dyadic::new(1, 3, 4));
        assert_eq!(p.to_f64(), (1.125, 1.375));
        assert!(d.contains(p));
        assert_eq!(d.child_of(p), (4, Dyadic::new(2, 6, 8), 2.0));
        // The upper half of a tile and tiles past the last sub-face are outside.
        assert!(!d.contains(Dyadic::new(3, 1, 4)));
        assert!(!d.contains(Dyadic::new(5, 4, 2)));
        assert!(!d.contains(Dyadic::new(6, 0, 2)));
        // A triangle under a quad split: 2 columns, sub-face 2 at (0, 1).
        let t = FaceDomain::of(Split::Quad, 3).unwrap();
        assert_eq!(t.child_of(Dyadic::new(1, 5, 4)), (2, Dyadic::new(2, 2, 4), 2.0));
        // The grid in osd_limit's order: sub-face outer, then j, then i.
        let g = t.grid(2);
        assert_eq!(g.len(), 27);
        assert_eq!((g[1].u, g[1].v), (0.25, 0.0));
        assert_eq!((g[9].u, g[9].v), (1.0, 0.0));
        assert_eq!((g[26].u, g[26].v), (0.5, 1.5));
    }

    #[test]
    fn children_of_quads_and_triangles_follow_child_domains() {
        let q = FaceDomain::Quad;
        assert_eq!(q.child_of(Dyadic::new(3, 1, 4)), (1, Dyadic::new(2, 2, 4), 2.0));
        assert_eq!(q.child_of(Dyadic::new(1, 3, 4)), (3, Dyadic::new(2, 2, 4), 2.0));
        let t = FaceDomain::Triangle;
        // The middle triangle's centroid stays its centroid, turned.
        assert_eq!(t.child_of(Dyadic::new(1, 1, 3)), (3, Dyadic::new(1, 1, 3), -2.0));
        assert_eq!(t.child_of(Dyadic::new(1, 5, 8)), (2, Dyadic::new(2, 2, 8), 2.0));
        assert_eq!(t.grid(3).len(), 10);
    }

    /// The engine's child faces sit where the maps say: a quad's child `j` has the parent's
    /// corner `j` at its own corner `j` (same axes), an N-gon's child `j` starts at corner `j`
    /// (Bfr's sub-face `j`), a triangle's child `j < 3` keeps corner `j` at position `j`.
    #[test]
    fn child_faces_match_the_maps() {
        let mesh = Mesh::build(shapes::ngon_prism(5)).unwrap();
        let bilinear = Builtin::Bilinear.scheme();
        let refined = refine(&mesh, bilinear, &RefineOptions::DEFAULT).unwrap();
        for f in mesh.face_ids() {
            let corners = mesh.face_vertices(f);
            let n = corners.len();
            let domain = FaceDomain::of(Split::Quad, n).unwrap();
            for (j, child) in children(&mesh, Split::Quad, f).enumerate() {
                let cv = refined.face_vertices(FaceId::new(child as u32));
                if n == 4 {
                    // Child j's corner j is the parent's corner j.
                    assert_eq!(cv[j], corners[j]);
                    // Its domain corner j is the parent's corner j in the parent's domain.
                    let c = [[0, 0], [1, 0], [1, 1], [0, 1]][j];
                    let at = Dyadic::new(c[0], c[1], 1);
                    assert_eq!(domain.child_of(at).0, j);
                } else {
                    // Sub-face j starts at corner j.
                    assert_eq!(cv[0], corners[j]);
                    let at = domain.from_sub_face(j, Dyadic::new(0, 0, 1));
                    assert_eq!(domain.child_of(at), (j, Dyadic::new(0, 0, 2), 2.0));
                }
            }
        }
        // Triangles under Loop: children 0..2 keep corner j at position j.
        let tri = Mesh::build(shapes::icosahedron()).unwrap();
        let refined = refine(&tri, Builtin::Loop.scheme(), &RefineOptions::DEFAULT).unwrap();
        for f in tri.face_ids() {
            for (j, child) in children(&tri, Split::Triangle, f).take(3).enumerate() {
                assert_eq!(refined.face_vertices(FaceId::new(child as u32))[j], tri.face_vertices(f)[j]);
            }
        }
    }

    #[test]
    fn f64_parameters_are_used_exactly_when_they_fit() {
        assert_eq!(dyadic_from_f64(0.5, 0.25), Some(Dyadic::new(2, 1, 4)));
        let p = dyadic_from_f64(0.1, 0.0).unwrap();
        assert_eq!(p.to_f64(), (0.1, 0.0));
        // Below 2^-60 in the last place: rounded to the nearest multiple of 2^-60.
        let tiny = dyadic_from_f64(3.0 * 0.5_f64.powi(61), 0.75).unwrap();
        assert_eq!(tiny, Dyadic::new(1, 3 << 57, 1 << 59));
        assert_eq!(dyadic_from_f64(1e-20, 0.75), Some(Dyadic::new(0, 3, 4)));
        assert!(dyadic_from_f64(f64::NAN, 0.0).is_none());
        assert!(dyadic_from_f64(0.0, 1e30).is_none());
    }
}
