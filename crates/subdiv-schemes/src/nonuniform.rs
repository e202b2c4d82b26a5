//! The non-uniform cubic B-spline of Schaefer and Warren §2, refined by midpoint knot insertion
//! ([`NonUniformCubicBSpline`], whose knot intervals travel with the control points).

use glam::DVec3;

#[cfg(doc)]
use crate::CurveScheme;
use crate::curve::{CurveError, PolygonKind};

/// A cubic B-spline with arbitrary knot intervals (Schaefer–Warren §2), refined by inserting a
/// knot at the midpoint of every interval (Boehm's knot insertion). The knot intervals are
/// part of the curve: they travel with the control points and halve at each level.
///
/// Convention: control point `p_j` belongs to the knot `τ_j` (its blossom is
/// `f(τ_{j-1}, τ_j, τ_{j+1})`, so its basis function spans `[τ_{j-2}, τ_{j+2}]`), and
/// `intervals[k] = τ_k − τ_{k−1}`, the interval that ends at the knot of point `k`. A closed
/// (periodic) curve of `n` points takes `n` intervals (`intervals[0]` lies between the last
/// point's knot and the first's); an open curve takes `n + 1` (the last one follows the last
/// point's knot). `τ_0` is 0 when the curve is built and knots keep their values through
/// refinement, so a parameter means the same point of the curve at every level.
///
/// Refinement makes, for each `j`, the vertex point `f(m_{j-1}, τ_j, m_j)` (child `2j`) and
/// the edge point `f(τ_j, m_j, τ_{j+1})` (child `2j+1`), `m_j` being the midpoint of
/// `[τ_j, τ_{j+1}]`. On an open curve only the children whose knots are all known are kept,
/// as [`CurveScheme::refine_open`] does: the edge points `0..n-1` and the vertex points
/// `1..n-2`. With equal intervals this is `cubic-bspline` exactly (the same bits).
///
/// ```
/// use glam::DVec3;
/// use subdiv_schemes::NonUniformCubicBSpline;
///
/// let points = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
/// // Uneven knot intervals: 2 around the first point, 1 around the third.
/// let curve = NonUniformCubicBSpline::closed(points.to_vec(), vec![2.0, 2.0, 1.0, 1.0])?;
/// let fine = curve.refine_levels(2);
/// assert_eq!(fine.points().len(), 16);
/// assert_eq!(fine.intervals()[0], 0.5);
/// // The refined curve is the same spline: it has the same points at the same parameters.
/// let t = 0.7;
/// assert!((fine.evaluate(t).unwrap() - curve.evaluate(t).unwrap()).length() < 1e-12);
/// # Ok::<(), subdiv_schemes::CurveError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct NonUniformCubicBSpline {
    kind: PolygonKind,
    points: Vec<DVec3>,
    intervals: Vec<f64>,
    /// `τ_0`.
    start: f64,
}

impl NonUniformCubicBSpline {
    /// The scheme's name, beside [`CurveScheme::BUILTIN_NAMES`].
    pub const NAME: &'static str = "nonuniform-cubic-bspline";

    /// A closed (periodic) curve: `n` points and `n` positive intervals, `intervals[k]` ending
    /// at the knot of point `k` (`intervals[0]` after the last point's knot).
    ///
    /// # Errors
    /// [`CurveError::KnotCount`] or [`CurveError::KnotInterval`].
    pub fn closed(points: Vec<DVec3>, intervals: Vec<f64>) -> Result<Self, CurveError> {
        Self::new(PolygonKind::Closed, points, intervals)
    }

    /// An open curve: `n` points and `n + 1` positive intervals, `intervals[k]` ending at the
    /// knot of point `k` (`intervals[0]` before the first point's knot, `intervals[n]` after the
    /// last's). The curve spans `[τ_1, τ_{n-2}]`.
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_schemes::{CurveError, NonUniformCubicBSpline};
    ///
    /// let points: Vec<DVec3> = (0..5).map(|i| DVec3::new(i as f64, (i * i) as f64, 0.0)).collect();
    /// let curve = NonUniformCubicBSpline::open(points.clone(), vec![1.0, 1.0, 3.0, 1.0, 2.0, 1.0])?;
    /// assert_eq!(curve.domain(), Some((1.0, 5.0)));
    /// let fine = curve.refine();
    /// assert_eq!((fine.points().len(), fine.intervals().len()), (7, 8));
    /// assert!(matches!(
    ///     NonUniformCubicBSpline::open(points, vec![1.0; 5]),
    ///     Err(CurveError::KnotCount { expected: 6, .. })
    /// ));
    /// # Ok::<(), CurveError>(())
    /// ```
    ///
    /// # Errors
    /// [`CurveError::KnotCount`] or [`CurveError::KnotInterval`].
    pub fn open(points: Vec<DVec3>, intervals: Vec<f64>) -> Result<Self, CurveError> {
        Self::new(PolygonKind::Open, points, intervals)
    }

    /// A curve of either kind (see [`closed`](Self::closed) and [`open`](Self::open)).
    ///
    /// # Errors
    /// [`CurveError::KnotCount`] or [`CurveError::KnotInterval`].
    pub fn new(kind: PolygonKind, points: Vec<DVec3>, intervals: Vec<f64>) -> Result<Self, CurveError> {
        let expected = match kind {
            PolygonKind::Closed => points.len(),
            PolygonKind::Open => points.len() + 1,
        };
        if intervals.len() != expected {
            return Err(CurveError::KnotCount { kind, points: points.len(), intervals: intervals.len(), expected });
        }
        if let Some((index, &value)) = intervals.iter().enumerate().find(|(_, d)| !(d.is_finite() && **d > 0.0)) {
            return Err(CurveError::KnotInterval { index, value });
        }
        Ok(Self { kind, points, intervals, start: 0.0 })
    }

    /// Closed or open.
    pub fn kind(&self) -> PolygonKind {
        self.kind
    }

    /// The control points.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The knot intervals (see the [type docs](Self) for the convention).
    pub fn intervals(&self) -> &[f64] {
        &self.intervals
    }

    /// The knot `τ_j` of each control point.
    pub fn knots(&self) -> Vec<f64> {
        let table = self.knot_table();
        (0..self.points.len() as i64).map(|j| self.knot(&table, j)).collect()
    }

    /// The parameter interval of the curve: one period `[τ_0, τ_0 + Σ intervals]` when
    /// closed, `[τ_1, τ_{n-2}]` when open (`None` for an open curve of fewer than 4 points).
    pub fn domain(&self) -> Option<(f64, f64)> {
        self.domain_in(&self.knot_table())
    }

    fn domain_in(&self, table: &[f64]) -> Option<(f64, f64)> {
        let n = self.points.len() as i64;
        match self.kind {
            PolygonKind::Closed if n > 0 => Some((self.knot(table, 0), self.knot(table, n))),
            PolygonKind::Open if n >= 4 => Some((self.knot(table, 1), self.knot(table, n - 2))),
            _ => None,
        }
    }

    /// The knots in order: `τ_0..=τ_n` when closed, `τ_{-1}..=τ_n` when open.
    fn knot_table(&self) -> Vec<f64> {
        let mut table = Vec::with_capacity(self.intervals.len() + 1);
        if self.kind == PolygonKind::Open {
            table.push(self.start - self.intervals[0]);
        }
        table.push(self.start);
        // Closed: intervals[0] comes last, from τ_{n-1} to τ_n.
        let skip = usize::from(!self.intervals.is_empty());
        let rest: Vec<f64> = match self.kind {
            PolygonKind::Closed => self.intervals.iter().skip(skip).chain(self.intervals.first()).copied().collect(),
            PolygonKind::Open => self.intervals[1..].to_vec(),
        };
        let mut knot = self.start;
        for d in rest {
            knot += d;
            table.push(knot);
        }
        table
    }

    /// `τ_j` from the [`knot_table`](Self::knot_table): from `τ_{-1}` to `τ_n` on an open
    /// curve, any `j` on a closed one.
    fn knot(&self, table: &[f64], j: i64) -> f64 {
        match self.kind {
            PolygonKind::Closed => {
                let n = self.points.len() as i64;
                let period = table[n as usize] - table[0];
                table[j.rem_euclid(n) as usize] + period * j.div_euclid(n) as f64
            }
            PolygonKind::Open => table[(j + 1) as usize],
        }
    }

    /// `d_j = τ_{j+1} − τ_j`: for `j` from -1 to `n - 1` on an open curve, any `j` on a closed
    /// one.
    fn after(&self, j: i64) -> f64 {
        match self.kind {
            PolygonKind::Closed => self.intervals[(j + 1).rem_euclid(self.points.len() as i64) as usize],
            PolygonKind::Open => self.intervals[(j + 1) as usize],
        }
    }

    fn point(&self, j: i64) -> DVec3 {
        self.points[j.rem_euclid(self.points.len() as i64) as usize]
    }

    /// The vertex point `f(m_{j-1}, τ_j, m_j)`.
    fn vertex_point(&self, j: i64) -> DVec3 {
        let (a, b, c, e) = (self.after(j - 2), self.after(j - 1), self.after(j), self.after(j + 1));
        // (1 - β)(1 - γ) and β·α from the blossom: with equal intervals exactly 1/8 each.
        let before = c * (b + 2.0 * c) / (4.0 * (b + c) * (a + b + c));
        let after = b * (2.0 * b + c) / (4.0 * (b + c) * (b + c + e));
        let centre = 1.0 - before - after;
        self.point(j - 1) * before + self.point(j) * centre + self.point(j + 1) * after
    }

    /// The edge point `f(τ_j, m_j, τ_{j+1})`.
    fn edge_point(&self, j: i64) -> DVec3 {
        let (b, c, e) = (self.after(j - 1), self.after(j), self.after(j + 1));
        let sum = b + c + e;
        self.point(j) * ((0.5 * c + e) / sum) + self.point(j + 1) * ((b + 0.5 * c) / sum)
    }

    /// One step of midpoint knot insertion: `2n` points on a closed curve, `2n - 3` on an open
    /// one (none below 2 points), every interval halved.
    pub fn refine(&self) -> Self {
        let n = self.points.len() as i64;
        match self.kind {
            PolygonKind::Closed => {
                let points = (0..n).flat_map(|j| [self.vertex_point(j), self.edge_point(j)]).collect();
                let intervals = (0..n).flat_map(|j| [self.after(j - 1) / 2.0, self.after(j) / 2.0]).collect();
                Self { kind: self.kind, points, intervals, start: self.start }
            }
            PolygonKind::Open if n < 2 => {
                // Degenerate: no span, so no point; keep one interval for the count rule.
                Self { kind: self.kind, points: Vec::new(), intervals: vec![self.after(-1) / 2.0], start: self.start }
            }
            PolygonKind::Open => {
                let mut points = Vec::with_capacity(2 * n as usize - 3);
                for j in 0..n - 1 {
                    if j > 0 {
                        points.push(self.vertex_point(j));
                    }
                    points.push(self.edge_point(j));
                }
                let intervals = (0..n - 1).flat_map(|j| [self.after(j) / 2.0; 2]).collect();
                Self { kind: self.kind, points, intervals, start: self.start + self.after(0) / 2.0 }
            }
        }
    }

    /// `levels` steps of [`refine`](Self::refine).
    pub fn refine_levels(&self, levels: usize) -> Self {
        let mut curve = self.clone();
        for _ in 0..levels {
            curve = curve.refine();
        }
        curve
    }

    /// The points of the curve at the knots `τ_j` of the control points: the non-uniform
    /// generalisation of the limit mask (1/6, 2/3, 1/6). All `n` points on a closed curve,
    /// the points `1..=n-2` (those inside the [`domain`](Self::domain)) on an open one.
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_schemes::NonUniformCubicBSpline;
    ///
    /// let points = vec![DVec3::ZERO, DVec3::X * 6.0, DVec3::Y * 6.0];
    /// let curve = NonUniformCubicBSpline::closed(points, vec![1.0; 3])?;
    /// assert!((curve.limit_points()[0] - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-15);
    /// # Ok::<(), subdiv_schemes::CurveError>(())
    /// ```
    pub fn limit_points(&self) -> Vec<DVec3> {
        let n = self.points.len() as i64;
        let range = match self.kind {
            PolygonKind::Closed => 0..n,
            PolygonKind::Open => 1..(n - 1).max(1),
        };
        range
            .map(|j| {
                let (a, b, c, e) = (self.after(j - 2), self.after(j - 1), self.after(j), self.after(j + 1));
                // f(τ_j, τ_j, τ_j) from the blossoms of p_{j-1}, p_j, p_{j+1}.
                let before = c * c / ((b + c) * (a + b + c));
                let after = b * b / ((b + c) * (b + c + e));
                self.point(j - 1) * before + self.point(j) * (1.0 - before - after) + self.point(j + 1) * after
            })
            .collect()
    }

    /// The point of the curve at parameter `t`, by de Boor's algorithm; a closed curve wraps
    /// `t` into its period; an open curve gives `None` outside its [`domain`](Self::domain).
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_schemes::NonUniformCubicBSpline;
    ///
    /// // Collinear, equally spaced points on uneven knots: a line, but not at unit speed.
    /// let points: Vec<DVec3> = (0..6).map(|i| DVec3::X * i as f64).collect();
    /// let curve = NonUniformCubicBSpline::open(points, vec![1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 1.0])?;
    /// let (lo, hi) = curve.domain().unwrap();
    /// assert_eq!((lo, hi), (1.0, 5.0));
    /// assert!(curve.evaluate(hi + 0.1).is_none());
    /// assert!(curve.evaluate(lo).unwrap().y.abs() < 1e-15);
    /// # Ok::<(), subdiv_schemes::CurveError>(())
    /// ```
    pub fn evaluate(&self, t: f64) -> Option<DVec3> {
        let table = self.knot_table();
        let (lo, hi) = self.domain_in(&table)?;
        let n = self.points.len() as i64;
        let (t, spans) = match self.kind {
            PolygonKind::Closed => (lo + (t - lo).rem_euclid(hi - lo), 0..n),
            PolygonKind::Open if (lo..=hi).contains(&t) => (t, 1..n - 2),
            PolygonKind::Open => return None,
        };
        // The span [τ_j, τ_{j+1}] holding t: the last one starting at or before it.
        let (start, len) = (spans.start, spans.end - spans.start);
        let before = partition_point(len, |q| self.knot(&table, start + q) <= t);
        let j = start + before.max(1) - 1;
        let knots: [f64; 6] = std::array::from_fn(|q| self.knot(&table, j - 2 + q as i64));
        let mut d: [DVec3; 4] = std::array::from_fn(|q| self.point(j - 1 + q as i64));
        // d[i] is the blossom f(k_i, k_{i+1}, k_{i+2}); level r replaces one argument by t.
        for r in 1..=3 {
            for i in (r..=3).rev() {
                let (left, right) = (knots[i - 1], knots[i + 3 - r]);
                let alpha = (t - left) / (right - left);
                d[i] = d[i - 1] * (1.0 - alpha) + d[i] * alpha;
            }
        }
        Some(d[3])
    }
}

/// The number of `q` in `0..len` for which `pred` holds, `pred` being true then false.
fn partition_point(len: i64, pred: impl Fn(i64) -> bool) -> i64 {
    let (mut lo, mut hi) = (0, len);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}
