//! [`Scheme`]: a subdivision scheme as data — its topological split and its masks, as weight
//! formulas in the valence. The built-in schemes are themselves data: TOML files under
//! `schemes/` in this crate, parsed by the same code as a user's file.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::{Expr, SchemeError};

/// A subdivision scheme: a name and its rules.
///
/// Built-ins come from [`Builtin::scheme`] or [`Scheme::builtin`]; a user's scheme from
/// [`Scheme::from_toml_str`] or [`Scheme::from_ron_str`] (or any serde format), and it goes
/// through refinement and analysis exactly as a built-in does.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{refine, RefineOptions, Scheme};
///
/// // Catmull-Clark with a stiffer vertex rule, written as data.
/// let scheme = Scheme::from_toml_str(r#"
///     name = "stiff-quad"
///     [rules.quad]
///     face = { corner = "1/n" }
///     edge = { endpoint = "1/4", face = "1/4" }
///     vertex = { spoke = "1/(2*k^2)", face = "1/(2*k^2)" }   # the centre takes the rest
/// "#)?;
/// let cube = Mesh::build(shapes::cube())?;
/// let refined = refine(&cube, &scheme, &RefineOptions::DEFAULT)?;
/// assert_eq!(refined.face_count(), 24);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scheme {
    /// The name (the CLI's `--scheme` for built-ins).
    pub name: String,
    /// The split and the masks.
    pub rules: Rules,
}

/// The topological split of a scheme and its masks. Variables in the formulas: `k` (or `n`) is
/// the valence of the vertex or the size of the face the rule is applied at, `j` the index of
/// a neighbour counted from the rule's reference (see each field).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum Rules {
    /// Primal split of every n-gon into n quads by a point per face and per edge; every point
    /// an average (Catmull-Clark, the Schaefer-Warren quad scheme, bilinear).
    Quad {
        /// The face point.
        face: FaceMask,
        /// The edge point.
        edge: QuadEdgeMask,
        /// The new position of an old vertex.
        vertex: VertexMask,
        /// Rules along creases and boundaries; without them the scheme takes closed meshes
        /// without sharpness tags only.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        crease: Option<CreaseMask>,
    },
    /// Primal quad split, interpolating: new points by the four-point rule along the grid
    /// lines (Kobbelt's scheme); quads only, closed meshes. Next to a vertex of valence
    /// `k != 4` the line is continued by a virtual point (see the crate docs).
    FourPointQuad {
        /// The four-point tension `w`: `-w, 1/2 + w, 1/2 + w, -w` (1/16 for Kobbelt's scheme).
        weight: Expr,
        /// The rule at boundaries; absent, the scheme takes closed meshes only.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        boundary: Option<FourPointBoundary>,
    },
    /// Primal split of every triangle into four (Loop, modified Butterfly).
    Triangle {
        /// The edge point.
        edge: TriangleEdgeMask,
        /// The new position of an old vertex.
        vertex: VertexMask,
        /// Rules along creases and boundaries (see [`Rules::Quad`]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        crease: Option<CreaseMask>,
        /// The rule at boundaries of an interpolating scheme without crease rules (the modified
        /// Butterfly's); the four-point tension is `-wing`. At most one of `crease` and
        /// `boundary`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        boundary: Option<FourPointBoundary>,
    },
    /// Dual split: a new point per face corner; new faces per face, per edge and per vertex
    /// (Doo-Sabin).
    Dual {
        /// Weight of the corner's own vertex, on top of `corner` at `j = 0`.
        own: Expr,
        /// Weight of the face's vertex `j` corners after the new point's corner, in an n-gon.
        corner: Expr,
        /// The rule at boundaries; absent, the scheme takes closed meshes only.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        boundary: Option<DualBoundary>,
    },
    /// Mid-edge split: a new point at the middle of every edge; new faces per face and per
    /// vertex (Peters and Reif's simplest scheme). Closed meshes.
    Midedge,
    /// Kobbelt's √3 split of triangles: a point per face, joined to its corners, old edges
    /// flipped.
    Sqrt3 {
        /// The new position of an old vertex (the face points are centroids).
        vertex: VertexMask,
        /// The rule at boundaries; absent, the scheme takes closed meshes only.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        boundary: Option<Sqrt3Boundary>,
    },
}

/// A dual scheme's rule at boundaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DualBoundary {
    /// Chaikin's corner cutting along the boundary (Doo and Sabin 1978 §4, Nasri 1987): a
    /// corner on one boundary edge takes ¾ of its vertex and ¼ of the edge's far end, so the
    /// boundary polygon is refined by Chaikin's rule alone and the surface's boundary is its
    /// quadratic B-spline; a corner on two boundary edges (a boundary vertex of one face)
    /// stays at its vertex, where the curve keeps a corner. Boundary edges have no edge
    /// face, and a boundary vertex has a vertex face where it has three faces or more.
    /// Infinitely sharp creases and corners are refused (they would leave faces of zero
    /// width between the sides).
    Chaikin,
}

/// The √3 split's rule at boundaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Sqrt3Boundary {
    /// Kobbelt's (2000, §5): the steps alternate between keeping the boundary (its vertices
    /// stay, its triangles split as the others, boundary edges unflipped) and refining it by
    /// the ternary cubic B-spline rule (each boundary edge split in three, `(16, 10, 1)/27`
    /// and `(1, 10, 16)/27` of its ends and their outer neighbours; boundary vertices
    /// `(4, 19, 4)/27` along the boundary; a boundary triangle fanned from its far corner), so
    /// that two steps refine the boundary polygon once by three and its limit is the cubic
    /// B-spline of the polygon. A refinement starts with a keeping step. Creases, corners and
    /// holes are refused.
    TernaryCubic,
}

/// An interpolating scheme's rule at boundaries (Kobbelt's four-point quad scheme, the
/// modified Butterfly).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FourPointBoundary {
    /// A boundary edge's point by the four-point rule along the boundary (the scheme's
    /// tension), so that the boundary is the four-point curve of the boundary polygon, which
    /// ends at a corner (a boundary vertex of one face: rounding it would fold the tangent plane
    /// there); a point a rule needs beyond the boundary or a corner is extrapolated linearly
    /// (`2p − q` from the last two points of its line), the four-point curve's end rule.
    ///
    /// Interior edges of a triangle scheme: the extraordinary rule from each interior end of
    /// valence other than 6 (averaged over both), otherwise the regular ten-point rule, a wing
    /// across a boundary side reflected through that side's middle (`a + b − c` for the side
    /// `ab` of triangle `abc`), as OpenMesh's modified Butterfly does; boundary vertices count
    /// as regular.
    ///
    /// Infinitely sharp creases take the rule on each side, as Catmull-Clark and Loop do: a
    /// crease is the four-point curve of its edges, ending at tagged corners, where other than
    /// two creases (boundary edges included) meet, and where one face lies between two on a
    /// side (as at a boundary vertex of one face), and the interior rules treat it as a
    /// boundary. Semi-sharp creases and corners are refused (the rule has no fractional form).
    FourPoint,
}

/// The face point of a primal quad split.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaceMask {
    /// Weight of each corner of an n-gon (`k = n`, `j` the corner); `"1/n"` is the centroid.
    pub corner: Expr,
}

/// The edge point of a primal quad split: `endpoint · (a + b) + face · (F0 + F1)` over the two
/// endpoints and the two adjacent face points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadEdgeMask {
    /// Weight of each endpoint.
    pub endpoint: Expr,
    /// Weight of each adjacent face point.
    pub face: Expr,
    /// The face-point weight of an adjacent triangle under OpenSubdiv's smooth-triangle rule
    /// (`smoothtriangles`, [`TriangleSubdivision::Smooth`](subdiv_mesh::TriangleSubdivision)):
    /// the two sides' face weights are averaged and the endpoints take the rest. Absent, the
    /// scheme has no such rule and ignores the option.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub triangle_face: Option<Expr>,
}

/// The new position of an old vertex of valence `k`: `centre · v + spoke · Σ neighbours +
/// face · Σ adjacent face points` (quad splits; triangle splits have no face term).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VertexMask {
    /// Weight of the vertex itself; absent, it takes what the others leave: `1 - k·spoke -
    /// k·face`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<Expr>,
    /// Weight of each neighbour along an edge.
    pub spoke: Expr,
    /// Weight of each adjacent face point (quad splits only).
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub face: Expr,
}

/// The edge point of a triangle split. Between two vertices of valence 6: `endpoint · (a + b)
/// + opposite · (c + d) + wing · (the four vertices across the edges of the two triangles)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TriangleEdgeMask {
    /// Weight of each endpoint.
    pub endpoint: Expr,
    /// Weight of each vertex opposite the edge.
    pub opposite: Expr,
    /// Weight of each of the four wing vertices.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub wing: Expr,
    /// The rule next to an extraordinary vertex; absent, the rule above applies everywhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extraordinary: Option<ExtraordinaryEdgeMask>,
}

/// The edge point next to an extraordinary vertex `v` of valence `k` (the modified Butterfly
/// rule): `centre · v + Σ_j spoke(k, j) · q_j` over `v`'s neighbours, `q_0` the edge's other
/// end, counter-clockwise. With two extraordinary ends, the two points are averaged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtraordinaryEdgeMask {
    /// Weight of the extraordinary vertex.
    pub centre: Expr,
    /// Weight of neighbour `j`.
    pub spoke: Expr,
    /// Per-valence spoke weights that replace `spoke` (keys are valences).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub by_valence: BTreeMap<String, Vec<Expr>>,
}

/// The masks along a crease or boundary (the curve scheme the surface follows there). An edge
/// point on a crease is the midpoint; a corner stays.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CreaseMask {
    /// Weight of the vertex itself.
    pub own: Expr,
    /// Weight of each of its two neighbours along the crease.
    pub neighbour: Expr,
}

fn zero() -> Expr {
    Expr::constant(0.0)
}

fn is_zero(e: &Expr) -> bool {
    e.source() == "0"
}

/// The topological split of a scheme, without its masks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Split {
    /// Every n-gon into n quads.
    Quad,
    /// Every triangle into four.
    Triangle,
    /// A point per face corner (Doo-Sabin).
    Dual,
    /// A point per edge (mid-edge).
    Midedge,
    /// A point per triangle, old edges flipped (√3).
    Sqrt3,
}

impl Split {
    /// The mesh's primal split this is, if it is one (the dual, mid-edge and √3 splits are not).
    pub fn primal(self) -> Option<subdiv_mesh::PrimalSplit> {
        match self {
            Self::Quad => Some(subdiv_mesh::PrimalSplit::Quads),
            Self::Triangle => Some(subdiv_mesh::PrimalSplit::Triangles),
            Self::Dual | Self::Midedge | Self::Sqrt3 => None,
        }
    }
}

/// The built-in schemes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Builtin {
    /// `catmull-clark`: OpenSubdiv's Catmull-Clark, any polygons.
    CatmullClark,
    /// `loop`: OpenSubdiv's Loop, triangles.
    Loop,
    /// `doo-sabin`: Doo-Sabin, the dual biquadratic scheme.
    DooSabin,
    /// `midedge`: Peters and Reif's simplest scheme.
    Midedge,
    /// `sqrt3`: Kobbelt's √3 scheme.
    Sqrt3,
    /// `butterfly`: Zorin, Schröder and Sweldens' modified Butterfly scheme.
    Butterfly,
    /// `kobbelt`: Kobbelt's interpolatory quad scheme.
    Kobbelt,
    /// `sw-quad`: Schaefer and Warren's C1 non-polynomial quad scheme (paper 000 §5.4).
    SwQuad,
    /// `bilinear`: bilinear, any polygons.
    Bilinear,
}

impl Builtin {
    /// Every built-in, in CLI order.
    pub const ALL: [Self; 9] = [
        Self::CatmullClark,
        Self::Loop,
        Self::DooSabin,
        Self::Midedge,
        Self::Sqrt3,
        Self::Butterfly,
        Self::Kobbelt,
        Self::SwQuad,
        Self::Bilinear,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Self::CatmullClark => "catmull-clark",
            Self::Loop => "loop",
            Self::DooSabin => "doo-sabin",
            Self::Midedge => "midedge",
            Self::Sqrt3 => "sqrt3",
            Self::Butterfly => "butterfly",
            Self::Kobbelt => "kobbelt",
            Self::SwQuad => "sw-quad",
            Self::Bilinear => "bilinear",
        }
    }

    /// The built-in of a CLI name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    fn source(self) -> &'static str {
        match self {
            Self::CatmullClark => include_str!("../schemes/catmull-clark.toml"),
            Self::Loop => include_str!("../schemes/loop.toml"),
            Self::DooSabin => include_str!("../schemes/doo-sabin.toml"),
            Self::Midedge => include_str!("../schemes/midedge.toml"),
            Self::Sqrt3 => include_str!("../schemes/sqrt3.toml"),
            Self::Butterfly => include_str!("../schemes/butterfly.toml"),
            Self::Kobbelt => include_str!("../schemes/kobbelt.toml"),
            Self::SwQuad => include_str!("../schemes/sw-quad.toml"),
            Self::Bilinear => include_str!("../schemes/bilinear.toml"),
        }
    }

    /// The scheme, parsed once from the crate's TOML file.
    pub fn scheme(self) -> &'static Scheme {
        static PARSED: OnceLock<Vec<Scheme>> = OnceLock::new();
        let all = PARSED.get_or_init(|| {
            Self::ALL
                .iter()
                .map(|b| {
                    // The files are part of this crate and tested; a failure here is a bug in
                    // the crate, not in anyone's input.
                    Scheme::from_toml_str(b.source())
                        .unwrap_or_else(|e| panic!("built-in scheme `{}` is invalid: {e}", b.name()))
                })
                .collect()
        });
        &all[self as usize]
    }

    /// The scheme's TOML text, a starting point for a user's own scheme file.
    pub fn toml(self) -> &'static str {
        self.source()
    }
}

impl std::fmt::Display for Builtin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The valences over which a scheme file's vertex and edge rules are checked, and the face
/// sizes over which its face rules are.
fn checked_valences() -> std::ops::RangeInclusive<usize> {
    3..=64
}

fn checked_face_sizes() -> std::ops::RangeInclusive<usize> {
    3..=32
}

impl Scheme {
    /// The built-in of a CLI name.
    pub fn builtin(name: &str) -> Option<&'static Scheme> {
        Builtin::from_name(name).map(Builtin::scheme)
    }

    /// Parses and validates a scheme written in TOML.
    ///
    /// ```
    /// use subdiv_schemes::Scheme;
    ///
    /// let e = Scheme::from_toml_str("name = \"x\"\nsplit = 3\n").unwrap_err();
    /// // One line, with the place: `line 2, column 1: unknown field `split`, …`.
    /// assert!(e.to_string().contains("line 2, column 1: unknown field `split`"), "{e}");
    /// assert!(!e.to_string().contains('\n'));
    /// ```
    ///
    /// # Errors
    /// [`SchemeError::Parse`] for malformed TOML or a bad formula, [`SchemeError::InvalidScheme`]
    /// when a mask's weights do not sum to 1.
    pub fn from_toml_str(text: &str) -> Result<Self, SchemeError> {
        let scheme: Self =
            toml::from_str(text).map_err(|e| SchemeError::Parse { format: "TOML", message: toml_message(text, &e) })?;
        scheme.validate()?;
        Ok(scheme)
    }

    /// Parses and validates a scheme written in RON.
    ///
    /// # Errors
    /// As [`Scheme::from_toml_str`].
    pub fn from_ron_str(text: &str) -> Result<Self, SchemeError> {
        let scheme: Self =
            ron::from_str(text).map_err(|e| SchemeError::Parse { format: "RON", message: e.to_string() })?;
        scheme.validate()?;
        Ok(scheme)
    }

    /// The scheme's identity: FNV-1a of its TOML text ([`to_toml_string`](Self::to_toml_string)),
    /// so two schemes with the same rules have the same identity whatever their source. Tables
    /// derived from a scheme carry it, and are read only for a scheme that has it.
    ///
    /// ```
    /// use subdiv_schemes::{Builtin, Scheme};
    ///
    /// let cc = Builtin::CatmullClark.scheme();
    /// let again = Scheme::from_toml_str(&cc.to_toml_string())?;
    /// assert_eq!(again.identity(), cc.identity());
    /// assert_ne!(Builtin::Loop.scheme().identity(), cc.identity());
    /// # Ok::<(), subdiv_schemes::SchemeError>(())
    /// ```
    pub fn identity(&self) -> u64 {
        crate::binary::fnv1a(self.to_toml_string().as_bytes())
    }

    /// The scheme as TOML.
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot write this scheme as TOML: {e}\n"))
    }

    /// The scheme as RON.
    pub fn to_ron_string(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())
            .unwrap_or_else(|e| format!("// cannot write this scheme as RON: {e}\n"))
    }

    /// The name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The topological split.
    pub fn split(&self) -> Split {
        match self.rules {
            Rules::Quad { .. } | Rules::FourPointQuad { .. } => Split::Quad,
            Rules::Triangle { .. } => Split::Triangle,
            Rules::Dual { .. } => Split::Dual,
            Rules::Midedge => Split::Midedge,
            Rules::Sqrt3 { .. } => Split::Sqrt3,
        }
    }

    /// The only face size the scheme takes, if it is restricted (triangle schemes: 3; the
    /// four-point quad scheme: 4).
    pub fn face_size(&self) -> Option<usize> {
        match self.rules {
            Rules::Triangle { .. } | Rules::Sqrt3 { .. } => Some(3),
            Rules::FourPointQuad { .. } => Some(4),
            _ => None,
        }
    }

    /// The valence of a regular interior vertex: 6 for triangle schemes, else 4.
    pub fn regular_valence(&self) -> usize {
        match self.rules {
            Rules::Triangle { .. } | Rules::Sqrt3 { .. } => 6,
            _ => 4,
        }
    }

    /// Whether old vertices keep their positions, so the limit surface passes through them.
    pub fn is_interpolating(&self) -> bool {
        match &self.rules {
            Rules::FourPointQuad { .. } => true,
            Rules::Quad { vertex, .. } | Rules::Triangle { vertex, .. } => {
                checked_valences().all(|k| vertex_weights(vertex, k).0 == 1.0)
            }
            _ => false,
        }
    }

    /// Whether the scheme has rules for boundaries, creases and corners (and so takes open
    /// meshes, sharpness tags and holes).
    pub fn has_crease_rules(&self) -> bool {
        matches!(self.rules, Rules::Quad { crease: Some(_), .. } | Rules::Triangle { crease: Some(_), .. })
    }

    /// Whether the scheme takes boundaries: by its crease rules, or an interpolating scheme's
    /// [`FourPointBoundary`] rule.
    pub fn has_boundary_rules(&self) -> bool {
        self.has_crease_rules()
            || matches!(
                self.rules,
                Rules::FourPointQuad { boundary: Some(_), .. }
                    | Rules::Triangle { boundary: Some(_), .. }
                    | Rules::Dual { boundary: Some(_), .. }
                    | Rules::Midedge
                    | Rules::Sqrt3 { boundary: Some(_), .. }
            )
    }

    /// Whether the scheme takes infinitely sharp creases and corners by its boundary rule
    /// (the rule on each side), without crease rules of its own: the interpolating schemes'
    /// [`FourPointBoundary`]. The dual splits' boundary rules do not (a crease would leave
    /// faces of zero width between its sides).
    pub(crate) fn creases_by_boundary_rule(&self) -> bool {
        matches!(self.rules, Rules::FourPointQuad { boundary: Some(_), .. } | Rules::Triangle { boundary: Some(_), .. })
    }

    /// The scheme as a dual split, where it is one or where its cycle of steps
    /// ([`steps_per_cycle`](Self::steps_per_cycle)) is: a dual scheme itself, and mid-edge, whose
    /// two steps make a point per face corner, the middle of the corner's two edge points (½ of
    /// the corner's vertex and ¼ of each neighbour along the face), with the dual split's faces.
    /// Its limit surface is the scheme's, and its patches are the dual split's
    /// ([`dual_patch`](crate::dual_patch)). `None` for the others (√3's two steps split each
    /// triangle in nine).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::{refine_uniform, Builtin, RefineOptions};
    ///
    /// let cube = Mesh::build(shapes::cube())?;
    /// let midedge = Builtin::Midedge.scheme();
    /// let twice = refine_uniform(&cube, midedge, 2, &RefineOptions::DEFAULT)?;
    /// let once = refine_uniform(&cube, &midedge.dual_form().unwrap(), 1, &RefineOptions::DEFAULT)?;
    /// let mut a: Vec<_> = twice.positions().iter().map(|p| p.to_array().map(|x| (x * 1e12).round() as i64)).collect();
    /// let mut b: Vec<_> = once.positions().iter().map(|p| p.to_array().map(|x| (x * 1e12).round() as i64)).collect();
    /// a.sort_unstable();
    /// b.sort_unstable();
    /// assert_eq!(a, b);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn dual_form(&self) -> Option<Scheme> {
        match self.rules {
            Rules::Dual { .. } => Some(self.clone()),
            Rules::Midedge => {
                // ¼ at j = 1 and at j = k − 1: δ(x) = (1 − |x| + |1 − |x||) / 2 on integers.
                let corner = "(2 - abs(j-1) + abs(1-abs(j-1)) - abs(j-k+1) + abs(1-abs(j-k+1)))/8";
                Some(Scheme {
                    name: format!("{} (two steps)", self.name),
                    rules: Rules::Dual {
                        own: "1/2".parse().expect("a constant"),
                        corner: corner.parse().expect("a valid formula"),
                        boundary: Some(DualBoundary::Chaikin),
                    },
                })
            }
            _ => None,
        }
    }

    /// How many refinement steps bring the grid back onto itself: 2 for √3 and mid-edge, whose
    /// single steps rotate the grid; 1 otherwise. Analysis takes this many steps at once.
    pub fn steps_per_cycle(&self) -> usize {
        match self.rules {
            Rules::Midedge | Rules::Sqrt3 { .. } => 2,
            _ => 1,
        }
    }

    /// Checks that every mask is affine: its weights sum to 1 at every valence 3..=64 and
    /// face size 3..=32, and are finite.
    ///
    /// # Errors
    /// [`SchemeError::InvalidScheme`] naming the first rule and valence that fail.
    pub fn validate(&self) -> Result<(), SchemeError> {
        if !is_one_line_name(&self.name) {
            return Err(SchemeError::InvalidScheme {
                scheme: format!("{:?}", self.name),
                rule: "name".into(),
                detail: format!(
                    "a name is one line of at most {MAX_NAME_LENGTH} characters without control characters"
                ),
            });
        }
        let invalid = |rule: &str, size: usize, detail: String| SchemeError::InvalidScheme {
            scheme: self.name.clone(),
            rule: rule.to_string(),
            detail: format!("at k = {size}: {detail}"),
        };
        let check = |rule: &str, size: usize, weights: &[f64]| -> Result<(), SchemeError> {
            if let Some(w) = weights.iter().find(|w| !w.is_finite()) {
                return Err(invalid(rule, size, format!("weight {w} is not finite")));
            }
            let sum: f64 = weights.iter().sum();
            if (sum - 1.0).abs() > 1e-12 {
                return Err(invalid(rule, size, format!("weights sum to {sum}, not 1")));
            }
            Ok(())
        };
        if self.name.trim().is_empty() {
            return Err(SchemeError::InvalidScheme {
                scheme: self.name.clone(),
                rule: "name".into(),
                detail: "a scheme needs a name".into(),
            });
        }
        let vertex_check = |vertex: &VertexMask, faces: bool| -> Result<(), SchemeError> {
            for k in checked_valences() {
                let (centre, spoke, face) = vertex_weights(vertex, k);
                if !faces && face != 0.0 {
                    return Err(invalid("vertex.face", k, "a triangle split has no face points".into()));
                }
                check("vertex", k, &[centre, k as f64 * spoke, k as f64 * face])?;
            }
            Ok(())
        };
        let crease_check = |crease: &Option<CreaseMask>| -> Result<(), SchemeError> {
            if let Some(c) = crease {
                check("crease", 2, &[c.own.eval(2, 0), 2.0 * c.neighbour.eval(2, 0)])?;
            }
            Ok(())
        };
        match &self.rules {
            Rules::Quad { face, edge, vertex, crease } => {
                for n in checked_face_sizes() {
                    let weights: Vec<f64> = (0..n).map(|j| face.corner.eval(n, j)).collect();
                    check("face", n, &weights)?;
                }
                check("edge", 4, &[2.0 * edge.endpoint.eval(4, 0), 2.0 * edge.face.eval(4, 0)])?;
                if let Some(w) = &edge.triangle_face {
                    // The endpoints take what the face points leave, so only finiteness can fail.
                    let w = w.eval(3, 0);
                    check("edge.triangle_face", 3, &[2.0 * w, 1.0 - 2.0 * w])?;
                }
                vertex_check(vertex, true)?;
                crease_check(crease)?;
            }
            Rules::FourPointQuad { weight, .. } => {
                let w = weight.eval(4, 0);
                check("weight", 4, &[-2.0 * w, 2.0 * (0.5 + w)])?;
            }
            Rules::Triangle { edge, vertex, crease, boundary } => {
                if crease.is_some() && boundary.is_some() {
                    return Err(SchemeError::InvalidScheme {
                        scheme: self.name.clone(),
                        rule: "boundary".into(),
                        detail: "a scheme with crease rules takes boundaries by them; give `crease` or \
                                 `boundary`, not both"
                            .into(),
                    });
                }
                let regular =
                    [2.0 * edge.endpoint.eval(6, 0), 2.0 * edge.opposite.eval(6, 0), 4.0 * edge.wing.eval(6, 0)];
                check("edge", 6, &regular)?;
                if let Some(extra) = &edge.extraordinary {
                    for key in extra.by_valence.keys() {
                        match key.parse::<usize>() {
                            Ok(k) if k >= 3 && extra.by_valence[key].len() == k => {}
                            _ => {
                                return Err(SchemeError::InvalidScheme {
                                    scheme: self.name.clone(),
                                    rule: "edge.extraordinary.by_valence".into(),
                                    detail: format!("entry `{key}` must be a valence ≥ 3 with that many weights"),
                                });
                            }
                        }
                    }
                    for k in checked_valences() {
                        let mut weights = vec![extra.centre.eval(k, 0)];
                        weights.extend(extraordinary_spokes(extra, k));
                        check("edge.extraordinary", k, &weights)?;
                    }
                }
                vertex_check(vertex, false)?;
                crease_check(crease)?;
            }
            Rules::Dual { own, corner, .. } => {
                for n in checked_face_sizes() {
                    let mut weights = vec![own.eval(n, 0)];
                    weights.extend((0..n).map(|j| corner.eval(n, j)));
                    check("corner", n, &weights)?;
                }
            }
            Rules::Midedge => {}
            Rules::Sqrt3 { vertex, .. } => vertex_check(vertex, false)?,
        }
        Ok(())
    }
}

impl std::fmt::Display for Scheme {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name)
    }
}

/// `(centre, spoke, face)` of a vertex mask at valence `k`.
pub(crate) fn vertex_weights(mask: &VertexMask, k: usize) -> (f64, f64, f64) {
    let spoke = mask.spoke.eval(k, 0);
    let face = mask.face.eval(k, 0);
    let centre = match &mask.centre {
        Some(c) => c.eval(k, 0),
        None => 1.0 - k as f64 * (spoke + face),
    };
    (centre, spoke, face)
}

/// The spoke weights of an extraordinary edge mask at valence `k`, from the edge's far end.
pub(crate) fn extraordinary_spokes(mask: &ExtraordinaryEdgeMask, k: usize) -> Vec<f64> {
    match mask.by_valence.get(&k.to_string()) {
        Some(table) => table.iter().map(|w| w.eval(k, 0)).collect(),
        None => (0..k).map(|j| mask.spoke.eval(k, j)).collect(),
    }
}

/// The longest scheme name (curve or surface), in characters.
pub const MAX_NAME_LENGTH: usize = 64;

/// Whether `name` can be quoted in a one-line message: no control character, at most
/// [`MAX_NAME_LENGTH`] characters.
pub(crate) fn is_one_line_name(name: &str) -> bool {
    name.chars().count() <= MAX_NAME_LENGTH && !name.chars().any(char::is_control)
}

/// A TOML error in one line: `line L, column C: reason` (the toml crate's own message spans
/// several, with a drawing of the line), the reason's lines joined.
pub(crate) fn toml_message(text: &str, error: &toml::de::Error) -> String {
    let reason = error.message().split_whitespace().collect::<Vec<_>>().join(" ");
    match error.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            format!("line {line}, column {column}: {reason}")
        }
        None => reason,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_parses_validates_and_round_trips() {
        for b in Builtin::ALL {
            let scheme = b.scheme();
            assert_eq!(scheme.name, b.name());
            assert_eq!(Scheme::builtin(b.name()), Some(scheme));
            let toml = scheme.to_toml_string();
            assert_eq!(&Scheme::from_toml_str(&toml).unwrap(), scheme, "{toml}");
            let ron = scheme.to_ron_string();
            assert_eq!(&Scheme::from_ron_str(&ron).unwrap(), scheme, "{ron}");
        }
    }

    #[test]
    fn interpolating_builtins() {
        let interpolating: Vec<_> = Builtin::ALL.into_iter().filter(|b| b.scheme().is_interpolating()).collect();
        assert_eq!(interpolating, [Builtin::Butterfly, Builtin::Kobbelt, Builtin::Bilinear]);
    }

    #[test]
    fn bad_schemes_are_typed_errors() {
        let e = Scheme::from_toml_str("name = \"x\"\n[rules.hexagon]\n").unwrap_err();
        assert!(matches!(e, SchemeError::Parse { format: "TOML", .. }), "{e}");
        let e = Scheme::from_toml_str(
            "name = \"x\"\n[rules.quad]\nface = { corner = \"1/n\" }\n\
             edge = { endpoint = \"1/4\", face = \"1/3\" }\nvertex = { spoke = \"1/k^2\", face = \"1/k^2\" }\n",
        )
        .unwrap_err();
        match e {
            SchemeError::InvalidScheme { rule, detail, .. } => {
                assert_eq!(rule, "edge");
                assert!(detail.contains("sum to"), "{detail}");
            }
            other => panic!("{other}"),
        }
        let e = Scheme::from_toml_str("name = \"x\"\n[rules.sqrt3]\nvertex = { spoke = \"1/q\" }\n").unwrap_err();
        assert!(e.to_string().contains("unknown name `q`"), "{e}");
        // A formula nesting 10,000 parentheses (20 KB of TOML) overflowed the parser's stack;
        // now it is a one-line error with the place, as every TOML error is.
        let deep = format!("{}1{}", "(".repeat(10_000), ")".repeat(10_000));
        let e = Scheme::from_toml_str(&format!("name = \"x\"\n[rules.sqrt3]\nvertex = {{ spoke = \"{deep}\" }}\n"))
            .unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, SchemeError::Parse { format: "TOML", .. }), "{e}");
        assert!(text.starts_with("cannot read the scheme (TOML): line 3, column 20:"), "{text}");
        assert!(text.len() < 300 && !text.contains('\n'), "{text}");
        let e = Scheme::from_toml_str("name = \"x\"\nrules = [\n").unwrap_err();
        assert!(!e.to_string().contains('\n') && e.to_string().contains("line 2"), "{e}");
        let e = Scheme::from_ron_str("(name: \"x\", rules: Midedge, extra: 1)").unwrap_err();
        assert!(matches!(e, SchemeError::Parse { format: "RON", .. }), "{e}");
    }
}
