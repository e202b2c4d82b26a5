//! Curve subdivision schemes as data: stationary schemes given by their mask
//! ([`CurveScheme`]: cubic B-spline, Chaikin, the four- and six-point schemes, the
//! non-polynomial curve scheme of Schaefer and Warren §5.4, or any scheme a TOML or RON file
//! defines), and their local subdivision matrices and spectra ([`CurveMatrix`]). The
//! non-uniform cubic B-spline is `nonuniform.rs`'s; its errors are [`CurveError`]'s too.

use std::fmt;
use std::ops::Range;

use glam::DVec3;
use serde::{Deserialize, Deserializer, Serialize};

/// Why a curve scheme or a non-uniform curve cannot be built, read or analysed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CurveError {
    /// A scheme name with a control character (a line break, say), or longer than
    /// [`MAX_NAME_LENGTH`](crate::MAX_NAME_LENGTH): names are quoted in one-line messages.
    #[error("curve scheme name {name}: a name is one line of at most 64 characters without control characters")]
    Name {
        /// The name, quoted with its escapes.
        name: String,
    },
    /// The arity (children per span) is below 2 or above [`CurveScheme::MAX_ARITY`].
    #[error("curve scheme `{scheme}`: arity {arity} is not supported (2 to {max})", max = CurveScheme::MAX_ARITY)]
    Arity {
        /// The scheme's name.
        scheme: String,
        /// The arity asked for.
        arity: u32,
    },
    /// A mask entry is NaN or infinite.
    #[error("curve scheme `{scheme}`: mask entry {index} is not finite ({value})")]
    NonFiniteWeight {
        /// The scheme's name.
        scheme: String,
        /// The entry's index in the mask.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The offset does not index an entry of the mask.
    #[error("curve scheme `{scheme}`: offset {offset} is outside the mask (length {len})")]
    Offset {
        /// The scheme's name.
        scheme: String,
        /// The offset asked for.
        offset: usize,
        /// The mask's length.
        len: usize,
    },
    /// The weights of one rule (the children `arity·i + residue`) do not sum to 1, so the
    /// scheme would not be affine invariant.
    #[error("curve scheme `{scheme}`: the rule of the children {arity}i+{residue} sums to {sum}, not 1")]
    RuleSum {
        /// The scheme's name.
        scheme: String,
        /// The scheme's arity.
        arity: u32,
        /// Which children the rule makes: those with index `residue` modulo the arity (for
        /// arity 2: 0 is the even rule, 1 the odd rule).
        residue: u32,
        /// The sum of its weights.
        sum: f64,
    },
    /// A non-uniform curve's knot intervals do not match its control points: a closed curve of
    /// `n` points takes `n` intervals, an open one `n + 1`.
    #[error("a {kind} curve of {points} control points takes {expected} knot intervals, not {intervals}")]
    KnotCount {
        /// Closed or open.
        kind: PolygonKind,
        /// Control points given.
        points: usize,
        /// Knot intervals given.
        intervals: usize,
        /// Knot intervals expected.
        expected: usize,
    },
    /// A knot interval is not a positive finite number.
    #[error("knot interval {index} is {value}; knot intervals must be positive and finite")]
    KnotInterval {
        /// The interval's index.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A local curve scheme's own rule for one new point is not usable.
    #[error("curve scheme `{scheme}`: the row of new point {point}: {reason}")]
    LocalRow {
        /// The scheme's name.
        scheme: String,
        /// The new point whose row it is.
        point: i64,
        /// What is wrong.
        reason: String,
    },
    /// A vector-valued (matrix) mask does not define a local scheme.
    #[error("curve scheme `{scheme}`: matrix mask: {reason}")]
    MatrixMask {
        /// The scheme's name.
        scheme: String,
        /// What is wrong.
        reason: String,
    },
    /// A TOML scheme file does not parse (syntax, missing or unknown field, bad weight): where
    /// and why, in one line.
    #[error("cannot read the curve scheme (TOML): {0}")]
    Toml(String),
    /// A RON scheme file does not parse (syntax, missing or unknown field, bad weight).
    #[error("cannot read the curve scheme (RON): {0}")]
    Ron(#[from] ron::error::SpannedError),
    /// The scheme cannot be written as TOML.
    #[error("cannot write the curve scheme as TOML: {0}")]
    TomlWrite(#[from] toml::ser::Error),
    /// The scheme cannot be written as RON.
    #[error("cannot write the curve scheme as RON: {0}")]
    RonWrite(#[from] ron::Error),
    /// The eigen solver did not converge.
    #[error("the eigen solver did not converge: {0}")]
    Eigen(String),
}

/// Whether a control polygon closes on itself (periodic) or has two ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PolygonKind {
    /// Periodic: the last point is followed by the first.
    Closed,
    /// Two ends: only the part of the curve that the points determine is refined.
    Open,
}

impl fmt::Display for PolygonKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Closed => "closed",
            Self::Open => "open",
        })
    }
}

/// The built-in schemes, as the TOML a user would write (files under `schemes/curves/`).
const BUILTINS: [(&str, &str); 5] = [
    ("cubic-bspline", include_str!("../schemes/curves/cubic-bspline.toml")),
    ("chaikin", include_str!("../schemes/curves/chaikin.toml")),
    ("four-point", include_str!("../schemes/curves/four-point.toml")),
    ("six-point", include_str!("../schemes/curves/six-point.toml")),
    ("sw-curve", include_str!("../schemes/curves/sw-curve.toml")),
];

/// A stationary, uniform curve subdivision scheme given by its mask: child `p'_i` of the
/// control polygon `p` is `Σ_j mask[i - arity·j + offset] · p_j`, that is, the mask holds the
/// coefficients of the symbol `a(z) = Σ_k mask[k] · z^(k - offset)`. Control point `p_j` sits
/// at parameter `j` and child `p'_i` at parameter `i / arity`, so for a primal scheme child
/// `arity·j` is the new position of `p_j`. The children `arity·j + r` for one residue `r` are
/// made by one *rule* (for arity 2: the even and the odd rule).
///
/// The built-ins ([`BUILTIN_NAMES`](Self::BUILTIN_NAMES)):
///
/// | name | mask (`offset` marks `a_0`) | |
/// |---|---|---|
/// | `cubic-bspline` | (1, 4, **6**, 4, 1) / 8 | the uniform cubic B-spline (Lane–Riesenfeld) |
/// | `chaikin` | (1, 3, **3**, 1) / 4 | corner cutting, the uniform quadratic B-spline |
/// | `four-point` | (−1, 0, 9, **16**, 9, 0, −1) / 16 | Dyn–Gregory–Levin, w = 1/16, interpolating |
/// | `six-point` | (3, 0, −25, 0, 150, **256**, 150, 0, −25, 0, 3) / 256 | Dubuc–Deslauriers, interpolating |
/// | `sw-curve` | (1, 3, **4**, 3, 1) / 6 | Schaefer–Warren §5.4: C¹, non-polynomial |
///
/// A scheme is data: it (de)serializes with serde, and [`from_toml_str`](Self::from_toml_str)
/// and [`from_ron_str`](Self::from_ron_str) read a file. Fields: `name`, `arity` (default 2),
/// `offset` (the index of `a_0` in the mask) and `mask`, whose entries are numbers or
/// fractions written as strings (`"-1/16"`). Every way of building a scheme, deserialization
/// included, checks that each rule's weights sum to 1.
///
/// ```
/// use glam::DVec3;
/// use subdiv_schemes::CurveScheme;
///
/// // The four-point scheme with tension 1/32, as a user would write it.
/// let scheme = CurveScheme::from_toml_str(r#"
///     name = "four-point-1/32"
///     offset = 3
///     mask = ["-1/32", 0, "17/32", 1, "17/32", 0, "-1/32"]
/// "#)?;
/// assert!(scheme.is_interpolating());
/// let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
/// let refined = scheme.refine_closed(&square);
/// assert_eq!(refined.len(), 8);
/// assert_eq!(refined[2], square[1]);
/// # Ok::<(), subdiv_schemes::CurveError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename = "CurveScheme")]
pub struct CurveScheme {
    name: String,
    arity: u32,
    offset: usize,
    mask: Vec<f64>,
}

/// The serialized form, before validation.
#[derive(Deserialize)]
#[serde(rename = "CurveScheme", deny_unknown_fields)]
struct RawCurveScheme {
    name: String,
    #[serde(default = "binary")]
    arity: u32,
    offset: usize,
    mask: Vec<Weight>,
}

pub(crate) fn binary() -> u32 {
    2
}

/// A mask entry: a number, or a string holding a number or a fraction `p/q`.
pub(crate) struct Weight(pub(crate) f64);

impl<'de> Deserialize<'de> for Weight {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Weight;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number, or a fraction written as a string such as \"-1/16\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Weight, E> {
                Ok(Weight(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Weight, E> {
                Ok(Weight(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Weight, E> {
                Ok(Weight(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Weight, E> {
                parse_fraction(v)
                    .map(Weight)
                    .ok_or_else(|| E::custom(format!("weight `{v}` is not a number or a fraction p/q")))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// `"p"` or `"p/q"`, with `p` and `q` decimal numbers.
fn parse_fraction(text: &str) -> Option<f64> {
    let number = |s: &str| s.trim().parse::<f64>().ok();
    match text.split_once('/') {
        Some((p, q)) => Some(number(p)? / number(q)?),
        None => number(text),
    }
}

impl<'de> Deserialize<'de> for CurveScheme {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let raw = RawCurveScheme::deserialize(deserializer)?;
        Self::from_raw(raw).map_err(serde::de::Error::custom)
    }
}

/// One rule of a scheme: child `arity·j + residue` is `Σ weight · p_{j + shift}` over the
/// nonzero weights, in increasing `shift`.
type Rule = Vec<(i64, f64)>;

impl CurveScheme {
    /// The built-in schemes' names.
    pub const BUILTIN_NAMES: [&'static str; BUILTINS.len()] = {
        let mut names = [""; BUILTINS.len()];
        let mut i = 0;
        while i < BUILTINS.len() {
            names[i] = BUILTINS[i].0;
            i += 1;
        }
        names
    };

    /// The largest arity (children per span) a scheme may have.
    pub const MAX_ARITY: u32 = 16;

    /// The built-in scheme called `name` (one of [`BUILTIN_NAMES`](Self::BUILTIN_NAMES)).
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let chaikin = CurveScheme::builtin("chaikin").unwrap();
    /// assert_eq!(chaikin.mask(), &[0.25, 0.75, 0.75, 0.25]);
    /// assert!(CurveScheme::builtin("catmull-clark").is_none());
    /// ```
    pub fn builtin(name: &str) -> Option<Self> {
        let (_, toml) = BUILTINS.iter().find(|(n, _)| *n == name)?;
        // The built-ins are checked by the tests; they parse as a user's file does.
        Some(Self::from_toml_str(toml).expect("the built-in curve schemes are valid"))
    }

    /// The file of the built-in scheme called `name`, as shipped (comments included): a
    /// template for one's own.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let text = CurveScheme::builtin_toml("four-point").unwrap();
    /// assert_eq!(CurveScheme::from_toml_str(text)?, CurveScheme::builtin("four-point").unwrap());
    /// # Ok::<(), subdiv_schemes::CurveError>(())
    /// ```
    pub fn builtin_toml(name: &str) -> Option<&'static str> {
        BUILTINS.iter().find(|(n, _)| *n == name).map(|(_, toml)| *toml)
    }

    /// A scheme from its parts, checked: the arity is 2 to [`MAX_ARITY`](Self::MAX_ARITY),
    /// the mask's entries are finite, `offset` indexes the mask, and the weights of each rule
    /// (the entries `a[k]` with `k ≡ residue + offset` modulo the arity) sum to 1 (to 1e-12
    /// relative to the sum of their moduli).
    ///
    /// ```
    /// use subdiv_schemes::{CurveError, CurveScheme};
    ///
    /// // The linear B-spline: midpoints, old points kept.
    /// let linear = CurveScheme::new("linear", 2, 1, vec![0.5, 1.0, 0.5])?;
    /// assert!(linear.is_interpolating());
    /// // An odd rule of 1/2 + 1/4 does not reproduce constants.
    /// let bad = CurveScheme::new("bad", 2, 1, vec![0.5, 1.0, 0.25]);
    /// assert!(matches!(bad, Err(CurveError::RuleSum { residue: 1, .. })));
    /// # Ok::<(), CurveError>(())
    /// ```
    ///
    /// # Errors
    /// [`CurveError::Arity`], [`CurveError::NonFiniteWeight`], [`CurveError::Offset`] or
    /// [`CurveError::RuleSum`].
    pub fn new(name: impl Into<String>, arity: u32, offset: usize, mask: Vec<f64>) -> Result<Self, CurveError> {
        let scheme = Self { name: name.into(), arity, offset, mask };
        scheme.validate()?;
        Ok(scheme)
    }

    fn from_raw(raw: RawCurveScheme) -> Result<Self, CurveError> {
        Self::new(raw.name, raw.arity, raw.offset, raw.mask.into_iter().map(|w| w.0).collect())
    }

    fn validate(&self) -> Result<(), CurveError> {
        if !crate::scheme::is_one_line_name(&self.name) {
            return Err(CurveError::Name { name: format!("{:?}", self.name) });
        }
        let scheme = || self.name.clone();
        if !(2..=Self::MAX_ARITY).contains(&self.arity) {
            return Err(CurveError::Arity { scheme: scheme(), arity: self.arity });
        }
        if let Some((index, &value)) = self.mask.iter().enumerate().find(|(_, w)| !w.is_finite()) {
            return Err(CurveError::NonFiniteWeight { scheme: scheme(), index, value });
        }
        if self.offset >= self.mask.len() {
            return Err(CurveError::Offset { scheme: scheme(), offset: self.offset, len: self.mask.len() });
        }
        let m = self.arity as usize;
        for residue in 0..self.arity {
            let class = self.mask.iter().enumerate().filter(|(k, _)| k % m == (residue as usize + self.offset) % m);
            let (sum, size) = class.fold((0.0, 0.0), |(s, a), (_, w)| (s + w, a + w.abs()));
            if (sum - 1.0f64).abs() > 1e-12 * f64::max(1.0, size) {
                return Err(CurveError::RuleSum { scheme: scheme(), arity: self.arity, residue, sum });
            }
        }
        Ok(())
    }

    /// Reads a scheme from TOML (fields as in the [type docs](Self)).
    ///
    /// ```
    /// use subdiv_schemes::{CurveError, CurveScheme};
    ///
    /// let chaikin = CurveScheme::from_toml_str(r#"
    ///     name = "my-chaikin"
    ///     offset = 2
    ///     mask = [0.25, 0.75, 0.75, 0.25]
    /// "#)?;
    /// assert_eq!(chaikin.arity(), 2);
    /// assert!(matches!(CurveScheme::from_toml_str("name = 3"), Err(CurveError::Toml(_))));
    /// # Ok::<(), CurveError>(())
    /// ```
    ///
    /// # Errors
    /// [`CurveError::Toml`] when the text does not parse, has a missing or unknown field or a
    /// bad weight; otherwise the errors of [`new`](Self::new).
    pub fn from_toml_str(text: &str) -> Result<Self, CurveError> {
        Self::from_raw(toml::from_str(text).map_err(|e| CurveError::Toml(crate::scheme::toml_message(text, &e)))?)
    }

    /// Reads a scheme from RON (fields as in the [type docs](Self); the struct name
    /// `CurveScheme` is optional).
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let sw = CurveScheme::from_ron_str(
    ///     r#"CurveScheme(name: "sw", offset: 2, mask: ["1/6", 0.5, "2/3", 0.5, "1/6"])"#,
    /// )?;
    /// assert_eq!(sw.mask(), CurveScheme::builtin("sw-curve").unwrap().mask());
    /// # Ok::<(), subdiv_schemes::CurveError>(())
    /// ```
    ///
    /// # Errors
    /// [`CurveError::Ron`] when the text does not parse, has a missing or unknown field or a
    /// bad weight; otherwise the errors of [`new`](Self::new).
    pub fn from_ron_str(text: &str) -> Result<Self, CurveError> {
        Self::from_raw(ron::from_str(text)?)
    }

    /// The scheme as TOML, which [`from_toml_str`](Self::from_toml_str) reads back equal.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let four = CurveScheme::builtin("four-point").unwrap();
    /// assert_eq!(CurveScheme::from_toml_str(&four.to_toml_string()?)?, four);
    /// # Ok::<(), subdiv_schemes::CurveError>(())
    /// ```
    ///
    /// # Errors
    /// [`CurveError::TomlWrite`] if the serializer fails.
    pub fn to_toml_string(&self) -> Result<String, CurveError> {
        Ok(toml::to_string(self)?)
    }

    /// The scheme as (pretty) RON, which [`from_ron_str`](Self::from_ron_str) reads back
    /// equal.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let six = CurveScheme::builtin("six-point").unwrap();
    /// assert_eq!(CurveScheme::from_ron_str(&six.to_ron_string()?)?, six);
    /// # Ok::<(), subdiv_schemes::CurveError>(())
    /// ```
    ///
    /// # Errors
    /// [`CurveError::RonWrite`] if the serializer fails.
    pub fn to_ron_string(&self) -> Result<String, CurveError> {
        Ok(ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())?)
    }

    /// The name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Children per span: 2 for binary schemes.
    pub fn arity(&self) -> u32 {
        self.arity
    }

    /// The index of the mask entry `a_0`.
    pub fn offset(&self) -> usize {
        self.offset
    }

    /// The mask `a`, from `a[0]`; entry `k` is the coefficient of `z^(k - offset)`.
    pub fn mask(&self) -> &[f64] {
        &self.mask
    }

    /// Whether the scheme keeps the old points: child `arity·j` is `p_j` (its rule is the
    /// single weight 1 on `p_j`), so the limit curve interpolates the control points.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let interpolating: Vec<&str> = CurveScheme::BUILTIN_NAMES
    ///     .into_iter()
    ///     .filter(|name| CurveScheme::builtin(name).unwrap().is_interpolating())
    ///     .collect();
    /// assert_eq!(interpolating, ["four-point", "six-point"]);
    /// ```
    pub fn is_interpolating(&self) -> bool {
        let m = self.arity as usize;
        self.mask
            .iter()
            .enumerate()
            .filter(|(k, _)| k % m == self.offset % m)
            .all(|(k, &w)| if k == self.offset { w == 1.0 } else { w == 0.0 })
    }

    /// The rules, one per residue of the child index modulo the arity.
    /// The weight of old point `parent` in new point `child`: `mask[child − arity·parent +
    /// offset]`, 0 outside the mask.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let chaikin = CurveScheme::builtin("chaikin").unwrap();
    /// assert_eq!((chaikin.weight(0, 0), chaikin.weight(0, 1), chaikin.weight(0, 2)), (0.75, 0.25, 0.0));
    /// ```
    pub fn weight(&self, child: i64, parent: i64) -> f64 {
        let k = child - i64::from(self.arity) * parent + self.offset as i64;
        usize::try_from(k).ok().and_then(|k| self.mask.get(k)).copied().unwrap_or(0.0)
    }

    fn rules(&self) -> Vec<Rule> {
        let m = i64::from(self.arity);
        (0..m)
            .map(|residue| {
                // Child m·j + residue takes a[k] from p_{j'} with k = m·(j - j') + residue + offset.
                let mut rule: Rule = (self.mask.iter().enumerate())
                    .filter(|&(k, &w)| w != 0.0 && (k as i64 - residue - self.offset as i64).rem_euclid(m) == 0)
                    .map(|(k, &w)| ((residue + self.offset as i64 - k as i64) / m, w))
                    .collect();
                rule.sort_by_key(|&(shift, _)| shift);
                rule
            })
            .collect()
    }

    /// The exponents `(e_min, e_max)` of the first and last nonzero entries of the symbol:
    /// the basis function is supported on `[e_min, e_max] / (arity - 1)`.
    fn support(&self) -> (i64, i64) {
        let first = self.mask.iter().position(|&w| w != 0.0).unwrap_or(0);
        let last = self.mask.iter().rposition(|&w| w != 0.0).unwrap_or(0);
        (first as i64 - self.offset as i64, last as i64 - self.offset as i64)
    }

    /// Child `child` (any integer index). Parent indices wrap modulo `points.len()`; open
    /// refinement asks only for children whose parents lie inside.
    fn child(&self, rules: &[Rule], points: &[DVec3], child: i64) -> DVec3 {
        let m = i64::from(self.arity);
        let (j, residue) = (child.div_euclid(m), child.rem_euclid(m));
        let n = points.len() as i64;
        let mut terms =
            rules[residue as usize].iter().map(|&(shift, w)| points[(j + shift).rem_euclid(n) as usize] * w);
        // Start from the first term, not from zero, so that a single weight 1 copies the point.
        let first = terms.next().unwrap_or(DVec3::ZERO);
        terms.fold(first, |acc, term| acc + term)
    }

    /// One step on a closed (periodic) polygon: `arity × n` children, child `i` at parameter
    /// `i / arity`. Polygons shorter than the mask are fine: they stand for their periodic
    /// extension.
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let chaikin = CurveScheme::builtin("chaikin").unwrap();
    /// let refined = chaikin.refine_closed(&[DVec3::ZERO, DVec3::X * 4.0, DVec3::Y * 4.0]);
    /// assert_eq!(refined.len(), 6);
    /// assert_eq!(refined[0], DVec3::X); // 3/4 of p0 + 1/4 of p1
    /// ```
    pub fn refine_closed(&self, points: &[DVec3]) -> Vec<DVec3> {
        let rules = self.rules();
        let count = points.len() as i64 * i64::from(self.arity);
        (0..count).map(|i| self.child(&rules, points, i)).collect()
    }

    /// The children that [`refine_open`](Self::refine_open) keeps from `n` points, numbered
    /// as by [`refine_closed`](Self::refine_closed) (child `i` at parameter `i / arity`; the
    /// range may start below 0): the longest run of consecutive children whose stencils
    /// lie inside the polygon, a child's stencil reaching over the whole mask (from its first
    /// to its last nonzero entry, zeros inside the child's own rule included) so that the run
    /// is contiguous. Empty when the polygon is too short.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let cubic = CurveScheme::builtin("cubic-bspline").unwrap();
    /// assert_eq!(cubic.open_children(5), 1..8);
    /// let four = CurveScheme::builtin("four-point").unwrap();
    /// assert_eq!(four.open_children(5), 2..7);
    /// ```
    pub fn open_children(&self, n: usize) -> Range<i64> {
        let m = i64::from(self.arity);
        let (e_min, e_max) = self.support();
        // Child i reads p_j for ceil((i - e_max) / m) <= j <= floor((i - e_min) / m).
        let first = e_max - m + 1;
        let end = (m * n as i64 + e_min).max(first);
        first..end
    }

    /// One step on an open polygon: the children of [`open_children`](Self::open_children),
    /// those whose stencils lie inside the polygon. Nothing is invented at the ends, so
    /// repeated open refinement converges to exactly the part of the limit curve that the
    /// points determine (for the cubic B-spline, the `n - 3` spans between `p_1` and
    /// `p_{n-2}`; for the four-point scheme, between `p_2` and `p_{n-3}`): each level drops
    /// the children near the ends that would need points beyond them.
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let line: Vec<DVec3> = (0..6).map(|i| DVec3::X * i as f64).collect();
    /// let cubic = CurveScheme::builtin("cubic-bspline").unwrap();
    /// let refined = cubic.refine_open(&line);
    /// assert_eq!(refined.len(), 2 * 6 - 3);
    /// assert_eq!(refined[0], DVec3::X * 0.5); // the midpoint of p0 p1
    /// ```
    pub fn refine_open(&self, points: &[DVec3]) -> Vec<DVec3> {
        let rules = self.rules();
        self.open_children(points.len()).map(|i| self.child(&rules, points, i)).collect()
    }

    /// One step on a polygon of either kind.
    pub fn refine(&self, points: &[DVec3], kind: PolygonKind) -> Vec<DVec3> {
        match kind {
            PolygonKind::Closed => self.refine_closed(points),
            PolygonKind::Open => self.refine_open(points),
        }
    }

    /// `levels` steps; the point count grows by about `arity^levels`.
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_schemes::{CurveScheme, PolygonKind};
    ///
    /// let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let cubic = CurveScheme::builtin("cubic-bspline").unwrap();
    /// assert_eq!(cubic.refine_levels(&square, 3, PolygonKind::Closed).len(), 32);
    /// ```
    pub fn refine_levels(&self, points: &[DVec3], levels: usize, kind: PolygonKind) -> Vec<DVec3> {
        let mut points = points.to_vec();
        for _ in 0..levels {
            points = self.refine(&points, kind);
        }
        points
    }

    /// The local subdivision matrix at vertex 0 (the point at parameter 0), derived by
    /// refining impulses on a long closed polygon and reading the weights.
    ///
    /// Its rows and columns are the points `j_min..=j_max` with `j_min = ⌊-e_max/(m-1)⌋` and
    /// `j_max = ⌈-e_min/(m-1)⌉`, where the basis function is supported on
    /// `[e_min, e_max]/(m-1)`: the control points whose basis functions do not vanish on the
    /// two spans `(-1, 1)` around the vertex. For a symmetric binary scheme of support
    /// `[-r, r]` these are the `2r + 1` points `-r..=r` (5 for the cubic B-spline and the
    /// Schaefer–Warren curve, 7 for the four-point scheme). Refinement maps them to the
    /// children with the same indices, which depend on them alone.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let m = CurveScheme::builtin("cubic-bspline").unwrap().local_matrix();
    /// assert_eq!((m.first(), m.size()), (-2, 5));
    /// // Row of the vertex point: 1/8, 3/4, 1/8.
    /// assert_eq!([m.get(2, 1), m.get(2, 2), m.get(2, 3)], [0.125, 0.75, 0.125]);
    /// ```
    pub fn local_matrix(&self) -> CurveMatrix {
        let m = i64::from(self.arity);
        let (e_min, e_max) = self.support();
        let first = (-e_max).div_euclid(m - 1);
        let last = -(e_min.div_euclid(m - 1));
        let size = (last - first + 1) as usize;
        // Long enough that no child of the window reads a parent through the wrap-around.
        let len = 2 * (size as i64 + e_max - e_min + 1);
        let mut entries = vec![0.0; size * size];
        let mut polygon = vec![DVec3::ZERO; len as usize];
        for column in 0..size {
            let parent = (first + column as i64).rem_euclid(len) as usize;
            polygon[parent] = DVec3::X;
            let refined = self.refine_closed(&polygon);
            polygon[parent] = DVec3::ZERO;
            for row in 0..size {
                entries[row * size + column] = refined[(first + row as i64).rem_euclid(m * len) as usize].x;
            }
        }
        CurveMatrix { first, size, entries }
    }

    /// The eigenvalues of the [`local_matrix`](Self::local_matrix), largest modulus first.
    ///
    /// ```
    /// use subdiv_schemes::CurveScheme;
    ///
    /// let values = CurveScheme::builtin("cubic-bspline").unwrap().eigenvalues()?;
    /// for (value, expected) in values.iter().zip([1.0, 0.5, 0.25, 0.125, 0.125]) {
    ///     assert!((value.0 - expected).abs() < 1e-12 && value.1.abs() < 1e-12);
    /// }
    /// # Ok::<(), subdiv_schemes::CurveError>(())
    /// ```
    ///
    /// # Errors
    /// [`CurveError::Eigen`] when the eigen solver does not converge.
    pub fn eigenvalues(&self) -> Result<Vec<(f64, f64)>, CurveError> {
        self.local_matrix().eigenvalues()
    }
}

impl fmt::Display for CurveScheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name)
    }
}

/// The local subdivision matrix of a curve scheme at a vertex: row `r` holds the weights of
/// child `first + r` over the parents `first..first + size` (see
/// [`CurveScheme::local_matrix`]).
#[derive(Clone, Debug, PartialEq)]
pub struct CurveMatrix {
    first: i64,
    size: usize,
    /// Row-major.
    entries: Vec<f64>,
}

impl CurveMatrix {
    /// Rows (and columns).
    pub fn size(&self) -> usize {
        self.size
    }

    /// The index (parameter) of the point of row and column 0, relative to the vertex.
    pub fn first(&self) -> i64 {
        self.first
    }

    /// The weight of parent `first + column` in child `first + row`.
    pub fn get(&self, row: usize, column: usize) -> f64 {
        self.entries[row * self.size + column]
    }

    /// The eigenvalues as `(re, im)`, largest modulus first (ties: larger real part first).
    ///
    /// Eigenvalues closer than 1e-6 (relative to the largest modulus) are taken as one multiple
    /// eigenvalue split by rounding and each replaced by their mean. A defective eigenvalue of
    /// multiplicity `k` (a Jordan block, such as 1/6 of `sw-curve` and 1/4 of `four-point`)
    /// moves by about `ε^(1/k)` in floating point, about 1e-8 for `k = 2`, but the mean of its
    /// copies, the trace of its invariant subspace, is as accurate as the matrix. The price: two
    /// distinct eigenvalues closer than 1e-6 are reported as their mean.
    ///
    /// # Errors
    /// [`CurveError::Eigen`] when the eigen solver does not converge.
    pub fn eigenvalues(&self) -> Result<Vec<(f64, f64)>, CurveError> {
        let values = crate::eigen::eigenvalues(self.size, |i, j| self.get(i, j)).map_err(CurveError::Eigen)?;
        let mut values = merge_clusters(&values, 1e-6);
        crate::eigen::sort_by_modulus(&mut values);
        Ok(values)
    }
}

/// Replaces each cluster of `values` (single linkage: chains of values closer than
/// `tolerance` times the largest modulus, or than `tolerance` when that is below 1) by copies
/// of its mean.
fn merge_clusters(values: &[(f64, f64)], tolerance: f64) -> Vec<(f64, f64)> {
    let scale = values.iter().map(|z| z.0.hypot(z.1)).fold(1.0, f64::max);
    let mut cluster: Vec<usize> = (0..values.len()).collect();
    // Few values (the size of a curve's local matrix): a quadratic relabelling pass is fine.
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..values.len() {
            for j in 0..values.len() {
                let (a, b) = (values[i], values[j]);
                if (a.0 - b.0).hypot(a.1 - b.1) < tolerance * scale && cluster[j] > cluster[i] {
                    cluster[j] = cluster[i];
                    changed = true;
                }
            }
        }
    }
    (0..values.len())
        .map(|i| {
            let members: Vec<(f64, f64)> =
                (0..values.len()).filter(|&j| cluster[j] == cluster[i]).map(|j| values[j]).collect();
            let count = members.len() as f64;
            let sum = members.iter().fold((0.0, 0.0), |s, z| (s.0 + z.0, s.1 + z.1));
            (sum.0 / count, sum.1 / count)
        })
        .collect()
}
