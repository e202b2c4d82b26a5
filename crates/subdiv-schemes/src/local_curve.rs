//! Curve schemes that are uniform away from one point and have rules of their own near it
//! ([`LocalCurveScheme`]), as data: the stationary non-uniform schemes of Schaefer and Warren
//! §2, whose subdivision matrix is a mask far from the origin and a few rows of its own near it.

use serde::{Deserialize, Deserializer};

use crate::curve::{CurveError, CurveScheme, Weight};

/// The built-in local curve schemes: the name and the file.
const BUILTINS: [(&str, &str); 2] = [
    ("nonuniform-cubic-bspline", include_str!("../schemes/curves/nonuniform-cubic-bspline.toml")),
    ("nonuniform-cubic-bspline-matrix", include_str!("../schemes/curves/nonuniform-cubic-bspline-matrix.toml")),
];

/// A stationary curve scheme with a special point at the origin: new point `k` (at `x = k /
/// arity`) is the uniform [`CurveScheme`]'s rule unless [`rows`](Self::rows) gives one of its
/// own (weights of the old points `first, first + 1, …`). Stationary means the same rows at
/// every level (the knots of a non-uniform spline scaled with the grid, say), so the limit
/// functions of the points near the origin are refinable functions of their own, which
/// `subdiv-stencil`'s `LocalCurveGrid` solves exactly. A file is the uniform scheme's fields
/// (`name`, `arity`, `offset`, `mask`) and `[[rows]]` tables with `point`, `first` and
/// `weights` (numbers or fractions as strings).
///
/// ```
/// use subdiv_schemes::LocalCurveScheme;
///
/// let scheme = LocalCurveScheme::builtin("nonuniform-cubic-bspline").unwrap();
/// // The new point at the origin: 1/15, 29/40, 5/24 of the old points −1, 0, 1.
/// assert_eq!(scheme.weight(0, 0), 29.0 / 40.0);
/// // Far from it, the cubic B-spline's rules: 1/8, 3/4, 1/8.
/// assert_eq!(scheme.weight(8, 4), 0.75);
/// # Ok::<(), subdiv_schemes::CurveError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct LocalCurveScheme {
    uniform: CurveScheme,
    rows: Vec<LocalRow>,
}

/// One new point's own rule in a [`LocalCurveScheme`].
#[derive(Clone, Debug, PartialEq)]
pub struct LocalRow {
    /// The new point's index (at `x = point / arity`).
    pub point: i64,
    /// The first old point the weights are of.
    pub first: i64,
    /// The weights of the old points `first, first + 1, …`.
    pub weights: Vec<f64>,
}

/// One entry `s_gh(z)` of a matrix mask ([`LocalCurveScheme::from_matrix_mask`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MatrixEntry {
    /// `g`: the component of the new points.
    pub row: usize,
    /// `h`: the component of the old points.
    pub column: usize,
    /// The exponent of the first weight.
    pub lowest: i64,
    /// The weights of `z^lowest, z^(lowest + 1), …`.
    pub weights: Vec<f64>,
}

/// A component's range `(from, to)` (inclusive, `None`: unbounded): `"..=-2"`, `"-1"`,
/// `"2.."`, `"3..=5"`.
fn parse_range(text: &str) -> Option<(Option<i64>, Option<i64>)> {
    let text = text.trim();
    match text.split_once("..") {
        None => text.parse().ok().map(|i| (Some(i), Some(i))),
        Some((lo, hi)) => {
            let lo = if lo.is_empty() { None } else { Some(lo.trim().parse().ok()?) };
            let hi = match hi.strip_prefix('=') {
                Some(hi) => Some(hi.trim().parse().ok()?),
                None if hi.is_empty() => None,
                None => return None,
            };
            Some((lo, hi))
        }
    }
}

/// The largest `|index|` of a special row's point or weight.
const MAX_LOCAL_INDEX: i64 = 64;

/// The serialized form, before validation: the uniform rule with its special rows, or the
/// vector-valued form (components and a matrix mask).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLocalCurveScheme {
    name: String,
    #[serde(default = "crate::curve::binary")]
    arity: u32,
    offset: Option<usize>,
    mask: Option<Vec<Weight>>,
    #[serde(default)]
    rows: Vec<RawRow>,
    components: Option<Vec<String>>,
    #[serde(default)]
    matrix: Vec<RawEntry>,
}

/// One entry `s_gh(z)` of a matrix mask: the weights of component `column`'s old points in
/// component `row`'s new points, by exponent from `lowest` up.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEntry {
    row: usize,
    column: usize,
    lowest: i64,
    weights: Vec<Weight>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRow {
    point: i64,
    first: i64,
    weights: Vec<Weight>,
}

impl<'de> Deserialize<'de> for LocalCurveScheme {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let raw = RawLocalCurveScheme::deserialize(deserializer)?;
        if let Some(components) = raw.components {
            if raw.mask.is_some() || raw.offset.is_some() || !raw.rows.is_empty() {
                return Err(serde::de::Error::custom(
                    "a matrix mask (components and [[matrix]]) gives the uniform rule and the rows itself: \
                     no mask, offset or [[rows]] beside it",
                ));
            }
            let entries = raw
                .matrix
                .into_iter()
                .map(|e| MatrixEntry {
                    row: e.row,
                    column: e.column,
                    lowest: e.lowest,
                    weights: e.weights.into_iter().map(|w| w.0).collect(),
                })
                .collect();
            return Self::from_matrix_mask(raw.name, raw.arity, &components, entries).map_err(serde::de::Error::custom);
        }
        let (Some(offset), Some(mask)) = (raw.offset, raw.mask) else {
            return Err(serde::de::Error::custom(
                "a local scheme has `offset` and `mask` (or `components` and [[matrix]])",
            ));
        };
        let uniform = CurveScheme::new(raw.name, raw.arity, offset, mask.into_iter().map(|w| w.0).collect())
            .map_err(serde::de::Error::custom)?;
        let rows = raw
            .rows
            .into_iter()
            .map(|r| LocalRow { point: r.point, first: r.first, weights: r.weights.into_iter().map(|w| w.0).collect() })
            .collect();
        Self::new(uniform, rows).map_err(serde::de::Error::custom)
    }
}

impl LocalCurveScheme {
    /// The names of the built-in local schemes.
    pub const BUILTIN_NAMES: [&'static str; BUILTINS.len()] = [BUILTINS[0].0, BUILTINS[1].0];

    /// The built-in scheme called `name`.
    pub fn builtin(name: &str) -> Option<Self> {
        let (_, toml) = BUILTINS.iter().find(|(n, _)| *n == name)?;
        Some(Self::from_toml_str(toml).expect("the built-in local curve schemes are valid"))
    }

    /// The file of the built-in scheme called `name`, as shipped.
    pub fn builtin_toml(name: &str) -> Option<&'static str> {
        BUILTINS.iter().find(|(n, _)| *n == name).map(|(_, toml)| *toml)
    }

    /// A scheme from the uniform rule and the special rows (zeros at a row's ends trimmed),
    /// checked: each row's weights are finite and sum to 1 (to 1e-12), points and weights lie
    /// within ±64 of the origin, and no point has two rows.
    ///
    /// # Errors
    /// [`CurveError::LocalRow`].
    pub fn new(uniform: CurveScheme, mut rows: Vec<LocalRow>) -> Result<Self, CurveError> {
        rows.sort_by_key(|r| r.point);
        // Zeros at the ends say nothing: trimmed, so that equal rules are equal rows.
        for row in &mut rows {
            let start = row.weights.iter().position(|&w| w != 0.0).unwrap_or(row.weights.len());
            let end = row.weights.iter().rposition(|&w| w != 0.0).map_or(start, |e| e + 1);
            row.weights = row.weights[start..end].to_vec();
            row.first = row.first.saturating_add(start as i64);
        }
        let bad = |row: &LocalRow, reason: &str| CurveError::LocalRow {
            scheme: uniform.name().to_string(),
            point: row.point,
            reason: reason.to_string(),
        };
        for (k, row) in rows.iter().enumerate() {
            let last = row.first.saturating_add(row.weights.len() as i64);
            if row.point.abs() > MAX_LOCAL_INDEX || row.first.abs() > MAX_LOCAL_INDEX || last > MAX_LOCAL_INDEX {
                return Err(bad(row, "points and weights lie within ±64 of the origin"));
            }
            if row.weights.is_empty() || row.weights.iter().any(|w| !w.is_finite()) {
                return Err(bad(row, "a row has finite weights, at least one"));
            }
            let sum: f64 = row.weights.iter().sum();
            let scale: f64 = row.weights.iter().map(|w| w.abs()).sum();
            if (sum - 1.0).abs() > 1e-12 * scale.max(1.0) {
                return Err(bad(row, &format!("the weights sum to {sum}, not 1")));
            }
            if k > 0 && rows[k - 1].point == row.point {
                return Err(bad(row, "the point has two rows"));
            }
        }
        Ok(Self { uniform, rows })
    }

    /// The scheme of a vector-valued (matrix) mask over position classes, paper 000 §3: the
    /// old points are split into `components`, consecutive ranges of indices covering all of
    /// them (`"..=-2"`, `"-1"`, `"2.."`, `"3..=5"`), and new point `i` of component `g` is
    /// `Σ_h Σ_e s_gh[e] · p_j` over the old points `j` of component `h` with `i = arity·j + e`
    /// (`p_{k+1}[z] = s[z] p_k[z^arity]`). The two unbounded components must share their
    /// diagonal entry, the uniform mask; every other new point whose rule differs from it
    /// becomes a row of its own. Each entry must send its component's points into its row's
    /// component (which catches a mistyped exponent).
    ///
    /// ```
    /// use subdiv_schemes::{LocalCurveScheme, MatrixEntry};
    ///
    /// // The paper's mask: new point 0 is 5/24, 29/40, 1/15 of the old points −1, 0, 1.
    /// let paper = LocalCurveScheme::builtin("nonuniform-cubic-bspline-matrix").unwrap();
    /// assert_eq!(paper.weight(0, -1), 5.0 / 24.0);
    /// // The cubic B-spline's mask on the old points up to −1 reaches the new point 0, which is
    /// // not among the new points up to −1: refused.
    /// let b = |row, column| MatrixEntry { row, column, lowest: -2, weights: vec![0.125, 0.5, 0.75, 0.5, 0.125] };
    /// let components = ["..=-1", "0.."].map(String::from);
    /// let refused = LocalCurveScheme::from_matrix_mask("halves".into(), 2, &components, vec![b(0, 0), b(1, 1)]);
    /// assert!(refused.unwrap_err().to_string().contains("sends old point -1 to new point 0"));
    /// ```
    ///
    /// # Errors
    /// [`CurveError::MatrixMask`] naming the entry or component and the rule; as
    /// [`CurveScheme::new`] and [`new`](Self::new).
    pub fn from_matrix_mask(
        name: String,
        arity: u32,
        components: &[String],
        entries: Vec<MatrixEntry>,
    ) -> Result<Self, CurveError> {
        let bad = |reason: String| CurveError::MatrixMask { scheme: name.clone(), reason };
        let ranges = components
            .iter()
            .map(|c| {
                parse_range(c)
                    .ok_or_else(|| bad(format!("component {c:?} is not a range such as \"..=-2\", \"0\" or \"2..\"")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let n = ranges.len();
        let consecutive = n >= 2
            && ranges[0].0.is_none()
            && ranges[n - 1].1.is_none()
            && ranges.windows(2).all(|w| matches!((w[0].1, w[1].0), (Some(hi), Some(lo)) if lo == hi + 1))
            && ranges[1..n - 1].iter().all(|(lo, hi)| matches!((lo, hi), (Some(lo), Some(hi)) if lo <= hi));
        if !consecutive {
            return Err(bad("the components are consecutive ranges of indices, from all below to all above".into()));
        }
        let component =
            |i: i64| ranges.iter().position(|&(lo, hi)| lo.is_none_or(|lo| lo <= i) && hi.is_none_or(|hi| i <= hi));
        let mut matrix: Vec<Vec<Option<MatrixEntry>>> = vec![vec![None; n]; n];
        for e in entries {
            if e.row >= n || e.column >= n {
                return Err(bad(format!("entry ({}, {}) names a component beyond the {n} there are", e.row, e.column)));
            }
            if e.weights.iter().any(|w| !w.is_finite()) || e.lowest.abs() > MAX_LOCAL_INDEX {
                return Err(bad(format!("entry ({}, {}) has finite weights, exponents within ±64", e.row, e.column)));
            }
            let (g, h) = (e.row, e.column);
            if matrix[g][h].replace(e).is_some() {
                return Err(bad(format!("entry ({g}, {h}) is given twice")));
            }
        }
        let (first, last) = (matrix[0][0].clone(), matrix[n - 1][n - 1].clone());
        let uniform = match (first, last) {
            (Some(a), Some(b)) if a.lowest == b.lowest && a.weights == b.weights => a,
            _ => return Err(bad("the two unbounded components share their diagonal entry: the uniform mask".into())),
        };
        let offset = usize::try_from(-uniform.lowest)
            .map_err(|_| bad("the uniform mask's lowest exponent is 0 or below".into()))?;
        let uniform = CurveScheme::new(name.clone(), arity, offset, uniform.weights)?;
        let a = i64::from(arity);
        // Where the components are not the uniform ones: the bounded components, and the
        // exponents' reach around them.
        let bounded = ranges.iter().flat_map(|&(lo, hi)| [lo, hi]).flatten().map(i64::abs).max().unwrap_or(0);
        let reach =
            matrix.iter().flatten().flatten().map(|e| e.lowest.abs() + e.weights.len() as i64).max().unwrap_or(0);
        let window = a * (bounded + reach) + reach;
        // Each entry sends its column's points into its row's component.
        for e in matrix.iter().flatten().flatten() {
            let (lo, hi) = ranges[e.column];
            let (lo, hi) = (lo.unwrap_or(-window), hi.unwrap_or(window));
            for j in lo..=hi {
                for (k, &w) in e.weights.iter().enumerate() {
                    let i = a * j + e.lowest + k as i64;
                    if w != 0.0 && component(i) != Some(e.row) {
                        return Err(bad(format!(
                            "entry ({}, {}) sends old point {j} to new point {i}, which is not in component {}",
                            e.row, e.column, e.row
                        )));
                    }
                }
            }
        }
        let mut rows = Vec::new();
        for i in -window..=window {
            let g = component(i).expect("the components cover every index");
            let mut weights = std::collections::BTreeMap::new();
            for (h, entry) in matrix[g].iter().enumerate() {
                let Some(e) = entry else { continue };
                for (k, &w) in e.weights.iter().enumerate() {
                    let offset = i - e.lowest - k as i64;
                    if offset.rem_euclid(a) == 0 && component(offset / a) == Some(h) {
                        *weights.entry(offset / a).or_insert(0.0) += w;
                    }
                }
            }
            let (Some((&lo, _)), Some((&hi, _))) = (weights.first_key_value(), weights.last_key_value()) else {
                return Err(bad(format!("new point {i} has no rule")));
            };
            let span = (lo.min(i / a - reach)..=hi.max(i / a + reach)).collect::<Vec<_>>();
            if span.iter().any(|&j| weights.get(&j).copied().unwrap_or(0.0) != uniform.weight(i, j)) {
                let weights = (lo..=hi).map(|j| weights.get(&j).copied().unwrap_or(0.0)).collect();
                rows.push(LocalRow { point: i, first: lo, weights });
            }
        }
        if rows.iter().any(|r| r.point.abs() == window) {
            return Err(bad("the special rows do not end within the components' reach".into()));
        }
        Self::new(uniform, rows)
    }

    /// Reads a scheme from TOML.
    ///
    /// # Errors
    /// [`CurveError::Toml`] with the reader's message (line and column), including the checks of
    /// [`new`](Self::new) and [`CurveScheme::new`].
    pub fn from_toml_str(text: &str) -> Result<Self, CurveError> {
        toml::from_str(text).map_err(|e| CurveError::Toml(crate::scheme::toml_message(text, &e)))
    }

    /// The name.
    pub fn name(&self) -> &str {
        self.uniform.name()
    }

    /// The rule away from the origin.
    pub fn uniform(&self) -> &CurveScheme {
        &self.uniform
    }

    /// The new points' own rules, by point.
    pub fn rows(&self) -> &[LocalRow] {
        &self.rows
    }

    /// The weight of old point `parent` in new point `child`.
    pub fn weight(&self, child: i64, parent: i64) -> f64 {
        match self.rows.binary_search_by_key(&child, |r| r.point) {
            Ok(r) => {
                let row = &self.rows[r];
                usize::try_from(parent - row.first).ok().and_then(|i| row.weights.get(i)).copied().unwrap_or(0.0)
            }
            Err(_) => self.uniform.weight(child, parent),
        }
    }
}
