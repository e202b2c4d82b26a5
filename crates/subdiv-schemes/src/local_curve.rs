//! Curve schemes that are uniform away from one point and have rules of their own near it
//! ([`LocalCurveScheme`]), as data: the stationary non-uniform schemes of Schaefer and Warren
//! §2, whose subdivision matrix is a mask far from the origin and a few rows of its own near it.

use serde::{Deserialize, Deserializer};

use crate::curve::{CurveError, CurveScheme, Weight};

/// The built-in local curve schemes: the name and the file.
const BUILTINS: [(&str, &str); 1] =
    [("nonuniform-cubic-bspline", include_str!("../schemes/curves/nonuniform-cubic-bspline.toml"))];

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

/// The largest `|index|` of a special row's point or weight.
const MAX_LOCAL_INDEX: i64 = 64;

/// The serialized form, before validation.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLocalCurveScheme {
    name: String,
    #[serde(default = "crate::curve::binary")]
    arity: u32,
    offset: usize,
    mask: Vec<Weight>,
    rows: Vec<RawRow>,
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
        let uniform = CurveScheme::new(raw.name, raw.arity, raw.offset, raw.mask.into_iter().map(|w| w.0).collect())
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
    pub const BUILTIN_NAMES: [&'static str; BUILTINS.len()] = [BUILTINS[0].0];

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
