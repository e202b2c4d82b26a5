//! The limit surface of a whole mesh at any face's rational (or f64) parameter, in OpenSubdiv's
//! `Bfr` parameterization, from exact surface stencils.
//!
//! A face whose patch has a shape in the scheme's [`PatchMatrices`] is evaluated directly: its
//! point is carried into the patch's frame (the patch may start at another corner of the face)
//! and weighted by [`surface_stencil`]. A face without one — an N-gon under a quad split, or a
//! face whose patch holds two irregular vertices — is refined once and the point descends into
//! the child face that holds it, as often as needed. The maps between a face's parameters, its
//! children's and its patch's are integer affine maps, so a rational point stays exact all the
//! way down.
//!
//! Children follow the refinement engine's (and OpenSubdiv's `Far`) numbering: the children of
//! face `f` are consecutive; a quad's child `j` sits at corner `j` of the domain with the
//! parent's axes ([`ChildDomain::of_face`]); a triangle's children 0..2 sit at its corners and
//! child 3 is the middle one, turned by half a turn; an N-gon's child `j` is `Bfr`'s sub-face `j`
//! (it starts at corner `j`, so its own parameters are the normalized sub-face coordinates).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use subdiv_mesh::{DVec3, FaceId, Mesh};
use subdiv_schemes::{
    ChildDomain, FoundPatch, MeshPatches, PatchMatrices, RefineOptions, Refiner, Scheme, Split, Stencils, child_faces,
};

use crate::address::step;
use crate::{Dyadic, Grid, StencilError, StencilEvaluator, SurfaceStencil};

/// Refinement levels after which every face's patch must have a shape: semi-sharp features
/// below sharpness 10 are spent after at most 10 levels (each level takes 1), and irregular
/// vertices, N-gons and features in one patch are apart within 3 more.
const MAX_LEVELS: usize = 16;

/// The largest patch radius of any scheme: a level whose patch types are not known yet
/// refines this many rings (plus one) around its faces.
const MAX_PATCH_RADIUS: usize = 3;

/// The largest denominator exponent of an f64 parameter used exactly: `2^60` stays below the
/// bound of [`Address::of`](crate::Address::of) (`i64::MAX / 4`) after the doublings of a descent.
pub const MAX_DENOMINATOR_BITS: u32 = 60;

/// A point of the limit surface with its derivatives in the face's `Bfr` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitPoint {
    /// The position.
    pub position: DVec3,
    /// ∂/∂u.
    pub du: DVec3,
    /// ∂/∂v.
    pub dv: DVec3,
    /// Whether `du` and `dv` are the parameter derivatives. `false` at an extraordinary vertex
    /// itself, where the parameterization has none: there they are tangent directions whose
    /// cross product points along the normal (see [`SurfaceStencil::exact_derivatives`]).
    pub exact_derivatives: bool,
}

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
    /// The domain of a face of `size` sides under `split`; `None` for a split without
    /// sub-patch matrices, or a triangle split's non-triangle.
    pub fn of(split: Split, size: usize) -> Option<Self> {
        match (split, size) {
            (Split::Quad, 4) => Some(Self::Quad),
            (Split::Quad, _) => Some(Self::SubFaces { size, columns: (1..).find(|c| c * c >= size).unwrap_or(size) }),
            (Split::Triangle, 3) => Some(Self::Triangle),
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
            Self::Triangle => u <= q - v,
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
            Self::Triangle => u + v <= 1.0,
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
            Self::Triangle => "u, v ≥ 0, u + v ≤ 1".to_string(),
            Self::SubFaces { size, columns } => format!(
                "the {size} sub-face tiles of a {size}-gon: (s mod {columns} + a/2, s div {columns} + b/2) \
                 for sub-face s < {size} and a, b in [0, 1]"
            ),
        }
    }

    /// The child of a face with this domain that holds `p`, and `p` in the child's parameters,
    /// with the factor `f` of the step's derivatives (`∂/∂u = f · ∂/∂u_child`, likewise `v`):
    /// 2, or −2 for the middle triangle. On a border between children the first in the
    /// engine's order that holds the point wins (either gives the same value). `p` must be
    /// [contained](Self::contains).
    pub fn child_of(self, p: Dyadic) -> (usize, Dyadic, f64) {
        let Dyadic { u, v, denominator: q } = p;
        match self {
            Self::Quad | Self::Triangle => {
                // The address's first step: the same choice on borders as the stencils make.
                let size = if self == Self::Triangle { 3 } else { 4 };
                let (child, a, b) = step(size, u, v, q);
                let flipped = ChildDomain::of_face(size)[usize::from(child)].flipped;
                (usize::from(child), Dyadic::new(a, b, q), if flipped { -2.0 } else { 2.0 })
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
            Self::Quad | Self::Triangle => a,
            Self::SubFaces { columns, .. } => {
                let q = 2 * a.denominator;
                let (tu, tv) = ((sub % columns) as i64, (sub / columns) as i64);
                Dyadic::new(tu * q + a.u, tv * q + a.v, q)
            }
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
            Self::Triangle => Grid::Primal.points(3, n).into_iter().map(exact).collect(),
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

/// How a face of one level of [`PatchLevels`] is evaluated.
#[derive(Clone, Debug)]
enum Resolution {
    /// Through its patch.
    Patch(FoundPatch),
    /// Through its children, these faces of the next level.
    Children(std::ops::Range<usize>),
    /// Not at all: a hole (tagged, or made by the boundary rule `none`).
    Hole,
}

/// One level of the refined mesh and how its faces of interest are evaluated.
#[derive(Debug)]
struct Level {
    mesh: Mesh,
    /// Per face of `mesh`, how it is evaluated if points can reach it (every face on level 0);
    /// dense, since looking a face up is on every evaluation's path.
    faces: Vec<Option<Resolution>>,
}

/// How a face of one level of [`PatchLevels`] reaches the limit surface.
#[derive(Clone, Debug)]
pub enum Resolved<'a> {
    /// Through its patch, which starts at corner `frame` of the face.
    Patch {
        /// The level's mesh (the patch's control points are its vertices).
        mesh: &'a Mesh,
        /// The patch, its shape and its matrices.
        patch: &'a FoundPatch,
        /// The face's frame in the patch's.
        frame: PatchFrame,
    },
    /// Through its children on the next level: the face's point `p` lies in child
    /// `domain.child_of(p).0`, which is face `children.start + that` of the next level.
    Children {
        /// The children's face numbers on the next level.
        children: std::ops::Range<usize>,
        /// The face's domain, which says how its points map to its children's.
        domain: FaceDomain,
    },
    /// Not at all: the face is a hole.
    Hole,
}

/// A mesh's faces and, for each, the patch (with its sub-patch matrices) that evaluates it,
/// on the level of refinement where it has one: a face whose patch has a shape in the scheme's
/// [`PatchMatrices`] is resolved on level 0; a face without one — an N-gon under a quad split,
/// or a face whose patch holds two irregular vertices — is refined, and its children are
/// resolved on the next level, as often as needed.
///
/// This is the part of [`LimitEvaluator`] that does not depend on how a patch is evaluated:
/// exact stencils there, eigenbases in `subdiv-eval`, quadtrees in `subdiv-tess`.
///
/// ```
/// use subdiv_mesh::{shapes, FaceId, Mesh};
/// use subdiv_schemes::{Builtin, RefineOptions};
/// use subdiv_stencil::{PatchLevels, Resolved};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let levels = PatchLevels::new(Builtin::CatmullClark.scheme(), &cube, &RefineOptions::DEFAULT)?;
/// // Every corner of the cube has valence 3: its faces are resolved by their children.
/// assert!(matches!(levels.resolve(0, FaceId::new(0)), Some(Resolved::Children { .. })));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct PatchLevels {
    split: Split,
    levels: Vec<Level>,
    /// `stencils[l]`: level `l + 1`'s vertices over level `l`'s.
    stencils: Vec<Stencils>,
}

/// The next level: a part of the current one refined (or all of it), its stencils over the
/// whole current level, and the faces each refined face becomes.
struct Next {
    mesh: Mesh,
    stencils: Stencils,
    /// Per face of `refine` (in its order), its children on the next level.
    children: Vec<std::ops::Range<usize>>,
}

impl Next {
    /// Refines the faces `refine` of `current` and `rings` rings of faces around them.
    fn of(
        scheme: &Scheme,
        current: &Mesh,
        refine: &[FaceId],
        rings: usize,
        options: &RefineOptions,
    ) -> Result<Self, StencilError> {
        let region = if scheme.has_crease_rules() {
            let region = current.region(refine, rings).map_err(|e| StencilError::Internal(e.to_string()))?;
            (region.faces.len() < current.face_count()).then_some(region)
        } else {
            None
        };
        let Some(region) = region else {
            let refiner = Refiner::new(current, scheme, 1, options)?;
            let stencils = refiner.levels()[0].clone();
            let children = refine.iter().map(|&f| children(current, scheme.split(), f)).collect();
            return Ok(Self { mesh: refiner.into_mesh(), stencils, children });
        };
        let refiner = Refiner::new(&region.mesh, scheme, 1, options)?;
        let parents: Vec<u32> = region.vertices.iter().map(|v| v.index() as u32).collect();
        let stencils = refiner.levels()[0].with_parents(&parents, current.vertex_count());
        let children = refine
            .iter()
            .map(|&f| {
                let local = region.face_of(f).ok_or_else(|| internal(f, "the region lacks a face it refines"))?;
                Ok(children(&region.mesh, scheme.split(), local))
            })
            .collect::<Result<_, StencilError>>()?;
        Ok(Self { mesh: refiner.into_mesh(), stencils, children })
    }
}

impl PatchLevels {
    /// Prepares `mesh` under `scheme` with the boundary rule and options of refinement
    /// (`options`, else the mesh's tags): finds every face's patch, refining the mesh as often
    /// as faces without a patch shape need (an N-gon once; the cube's faces twice; a face next
    /// to a semi-sharp edge of sharpness `s` until `s` is spent, ⌈s⌉ times, then as its
    /// stationary features need). Each level refines only the faces that need it and
    /// as many rings of faces around them as their children's patches and rules reach, so a level costs as much as those faces, not the
    /// mesh (a semi-sharp crease of sharpness 6 on a car would otherwise be 4^6 times the
    /// car). Schemes without crease rules refine the whole mesh (a part of it has a boundary
    /// they cannot refine).
    ///
    /// # Errors
    /// [`StencilError::Scheme`] for a scheme without sub-patch matrices (dual, mid-edge, √3:
    /// `SplitNotSupported`; Kobbelt next to valences other than 3, 4: `ValenceNotSupported`), a
    /// face the scheme does not take, or boundaries a scheme has no rules for;
    /// [`StencilError::NoPatch`] if a face finds no patch within 16 levels (an internal error).
    pub fn new(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions) -> Result<Self, StencilError> {
        let patch_size = match scheme.split() {
            Split::Quad => 4,
            Split::Triangle => 3,
            // MeshPatches says why not.
            _ => {
                MeshPatches::new(scheme, mesh, options)?;
                4
            }
        };
        // Level 0 with the boundary rule applied (boundary edges sharp, holes of `none`).
        let base = Refiner::new(mesh, scheme, 0, options)?.into_mesh();
        let mut levels = Vec::new();
        let mut stencils = Vec::new();
        let mut wanted: Vec<FaceId> = base.face_ids().collect();
        let mut current = base;
        loop {
            let patches = if wanted.len() == current.face_count() {
                MeshPatches::new(scheme, &current, options)?
            } else {
                MeshPatches::near(scheme, &current, options, wanted.iter().copied())?
            };
            let mut faces: Vec<Option<Resolution>> = vec![None; current.face_count()];
            let mut refine = Vec::new();
            for &f in &wanted {
                if current.is_hole(f) {
                    faces[f.index()] = Some(Resolution::Hole);
                } else if let Some(found) =
                    (current.face_size(f) == patch_size).then(|| patches.find(&current, f)).flatten()
                {
                    faces[f.index()] = Some(Resolution::Patch(found));
                } else {
                    refine.push(f);
                }
            }
            if refine.is_empty() {
                levels.push(Level { mesh: current, faces });
                break;
            }
            if levels.len() + 1 == MAX_LEVELS {
                return Err(StencilError::NoPatch { face: refine[0].index(), levels: MAX_LEVELS });
            }
            // The children's patches reach `radius` rings of the next level, inside as many rings
            // of this one, and the rules of those rings' points read one ring more. (A scheme's
            // patch types share one radius: Catmull-Clark's and Loop's are 1.)
            let rings = patches.max_radius().unwrap_or(MAX_PATCH_RADIUS) + 1;
            let next = Next::of(scheme, &current, &refine, rings, options)?;
            let mut next_wanted = Vec::new();
            for (&f, children) in refine.iter().zip(next.children) {
                next_wanted.extend(children.clone().map(|c| FaceId::new(c as u32)));
                faces[f.index()] = Some(Resolution::Children(children));
            }
            next_wanted.sort_unstable();
            levels.push(Level { mesh: current, faces });
            stencils.push(next.stencils);
            current = next.mesh;
            wanted = next_wanted;
        }
        Ok(Self { split: scheme.split(), levels, stencils })
    }

    /// The scheme's split.
    pub fn split(&self) -> Split {
        self.split
    }

    /// The number of levels (1 when every face has a patch on the mesh itself).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// The mesh of `level`: level 0 is the input with the boundary rule applied (same faces,
    /// same vertices), level `l + 1` is the part of level `l` that needed it refined once
    /// (see [`new`](Self::new); its vertices are given over level `l`'s by
    /// [`stencils`](Self::stencils)).
    ///
    /// # Panics
    /// If `level >= level_count()`.
    pub fn mesh(&self, level: usize) -> &Mesh {
        &self.levels[level].mesh
    }

    /// The refinement stencils between the levels: entry `l` gives level `l + 1`'s vertices
    /// over level `l`'s (empty when every face has a patch on level 0). Applied from the cage
    /// down, they give every level's control points of a moved cage.
    pub fn stencils(&self) -> &[Stencils] {
        &self.stencils
    }

    /// The number of faces of the input mesh.
    pub fn face_count(&self) -> usize {
        self.levels[0].mesh.face_count()
    }

    /// How `face` of `level` reaches the surface; `None` for a face that no point of the input
    /// reaches on that level (or a level or face out of range).
    pub fn resolve(&self, level: usize, face: FaceId) -> Option<Resolved<'_>> {
        let l = self.levels.get(level)?;
        Some(match l.faces.get(face.index())?.as_ref()? {
            Resolution::Hole => Resolved::Hole,
            Resolution::Children(children) => Resolved::Children {
                children: children.clone(),
                domain: if level == 0 {
                    FaceDomain::of(self.split, l.mesh.face_size(face)).unwrap_or(FaceDomain::Quad)
                } else if self.split == Split::Triangle {
                    FaceDomain::Triangle
                } else {
                    FaceDomain::Quad
                },
            },
            Resolution::Patch(found) => {
                let first = l.mesh.face_half_edges(face).next().expect("faces have corners");
                Resolved::Patch {
                    mesh: &l.mesh,
                    patch: found,
                    frame: PatchFrame::new(l.mesh.face_size(face), found.start.index() - first.index()),
                }
            }
        })
    }

    /// Whether `face` has a limit surface (it is not a hole).
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn has_surface(&self, face: FaceId) -> Result<bool, StencilError> {
        Ok(!matches!(self.resolution(face)?, Resolution::Hole))
    }

    /// The domain of `face` of the input mesh.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn domain(&self, face: FaceId) -> Result<FaceDomain, StencilError> {
        self.resolution(face)?;
        let size = self.levels[0].mesh.face_size(face);
        // `new` accepted the split, and refinement accepted every face's size.
        Ok(FaceDomain::of(self.split, size).unwrap_or(FaceDomain::Quad))
    }

    fn resolution(&self, face: FaceId) -> Result<&Resolution, StencilError> {
        self.levels[0]
            .faces
            .get(face.index())
            .and_then(Option::as_ref)
            .ok_or(StencilError::FaceOutOfRange { face: face.index(), faces: self.face_count() })
    }

    /// Checks that `point` is a parameter of `face` with a surface.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::OutsideFace`] for a point outside the
    /// face's domain, [`StencilError::NoSurface`] for a hole.
    pub fn check(&self, face: FaceId, point: Dyadic) -> Result<(), StencilError> {
        let domain = self.domain(face)?;
        if !domain.contains(point) {
            let (u, v) = point.to_f64();
            return Err(StencilError::OutsideFace {
                face: face.index(),
                u: format!("{u:?}"),
                v: format!("{v:?}"),
                domain: domain.describe(),
            });
        }
        if !self.has_surface(face)? {
            return Err(StencilError::NoSurface { face: face.index() });
        }
        Ok(())
    }
}

/// The limit surface of a mesh under a primal scheme, at any face's parameter in OpenSubdiv's
/// `Bfr` parameterization: quads `(0, 0)` at corner 0, `u` toward corner 1, `v` toward corner 3;
/// triangles of triangle schemes `(0, 0)`, `(1, 0)`, `(0, 1)` at corners 0, 1, 2; other faces
/// of quad schemes as `Bfr`'s tiled quad sub-faces ([`FaceDomain::SubFaces`]).
///
/// Positions and derivatives are exact up to f64 rounding (no approximation near extraordinary
/// vertices). Each set of sub-patch matrices has one [`StencilEvaluator`], so faces of equal
/// shape share their stencils (all regular faces of a torus sampled on a grid cost one set) and
/// points share the work of their addresses.
///
/// ```
/// use subdiv_mesh::{shapes, FaceId, Mesh};
/// use subdiv_schemes::{Builtin, RefineOptions};
/// use subdiv_stencil::{Dyadic, LimitEvaluator};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let eval = LimitEvaluator::new(Builtin::CatmullClark.scheme(), &cube, &RefineOptions::DEFAULT)?;
/// // Face centres, exact (1/2, 1/2) or as f64: by symmetry all as far from the cube's centre.
/// let a = eval.eval_exact(FaceId::new(0), Dyadic::new(1, 1, 2))?;
/// let b = eval.eval(FaceId::new(3), 0.5, 0.5)?;
/// assert!((a.position.length() - b.position.length()).abs() < 1e-14);
/// // The derivatives there are exact; their cross product is the outward normal.
/// assert!(a.exact_derivatives && a.du.cross(a.dv).dot(a.position) > 0.0);
/// // Corner 0 of every face is an extraordinary vertex (valence 3): tangent directions only.
/// assert!(!eval.eval(FaceId::new(0), 0.0, 0.0)?.exact_derivatives);
/// // A --grid 2 face has 9 points.
/// assert_eq!(eval.grid(FaceId::new(0), 2)?.len(), 9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct LimitEvaluator {
    patches: PatchLevels,
    /// One stencil evaluator per set of sub-patch matrices, by the matrices' address.
    evaluators: Mutex<HashMap<usize, StencilEvaluator<Arc<PatchMatrices>>>>,
}

impl LimitEvaluator {
    /// Prepares `mesh` under `scheme` with the boundary rule and options of refinement
    /// (`options`, else the mesh's tags): see [`PatchLevels::new`].
    ///
    /// # Errors
    /// As [`PatchLevels::new`].
    pub fn new(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions) -> Result<Self, StencilError> {
        Ok(Self { patches: PatchLevels::new(scheme, mesh, options)?, evaluators: Mutex::default() })
    }

    /// The faces' patches, level by level.
    pub fn patches(&self) -> &PatchLevels {
        &self.patches
    }

    /// The number of faces of the mesh.
    pub fn face_count(&self) -> usize {
        self.patches.face_count()
    }

    /// Whether `face` has a limit surface (it is not a hole).
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn has_surface(&self, face: FaceId) -> Result<bool, StencilError> {
        self.patches.has_surface(face)
    }

    /// The domain of `face`.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn domain(&self, face: FaceId) -> Result<FaceDomain, StencilError> {
        self.patches.domain(face)
    }

    /// Checks that `point` is a parameter of `face` with a surface, as [`eval_exact`](Self::eval_exact)
    /// would, without evaluating.
    ///
    /// # Errors
    /// As [`eval_exact`](Self::eval_exact), for input errors.
    pub fn check(&self, face: FaceId, point: Dyadic) -> Result<(), StencilError> {
        self.patches.check(face, point)
    }

    /// The limit point of `face` at f64 parameters, used exactly (see [`dyadic_from_f64`]).
    ///
    /// # Errors
    /// As [`eval_exact`](Self::eval_exact); [`StencilError::OutsideFace`] also for a non-finite
    /// parameter.
    pub fn eval(&self, face: FaceId, u: f64, v: f64) -> Result<LimitPoint, StencilError> {
        let point = dyadic_from_f64(u, v).ok_or_else(|| StencilError::OutsideFace {
            face: face.index(),
            u: format!("{u:?}"),
            v: format!("{v:?}"),
            domain: self.domain(face).map_or_else(|_| String::new(), FaceDomain::describe),
        })?;
        self.eval_exact(face, point)
    }

    /// The limit point of `face` at the rational parameter `point`.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::OutsideFace`] for a point outside the
    /// face's domain, [`StencilError::NoSurface`] for a hole, [`StencilError::Eigen`] if a
    /// stencil's eigenvector is not unique.
    pub fn eval_exact(&self, face: FaceId, point: Dyadic) -> Result<LimitPoint, StencilError> {
        self.check(face, point)?;
        let (mut f, mut p) = (face, point.reduced());
        // (∂/∂u, ∂/∂v) of the face = j · (the same of the current level's face or patch).
        let mut j = [[1.0, 0.0], [0.0, 1.0]];
        for level in 0..self.patches.level_count() {
            let resolved =
                self.patches.resolve(level, f).ok_or_else(|| internal(face, "a child face was not prepared"))?;
            match resolved {
                Resolved::Hole => return Err(StencilError::NoSurface { face: face.index() }),
                Resolved::Children { children, domain } => {
                    let (child, at, factor) = domain.child_of(p);
                    f = FaceId::new((children.start + child) as u32);
                    p = at;
                    j = [[j[0][0] * factor, j[0][1] * factor], [j[1][0] * factor, j[1][1] * factor]];
                }
                Resolved::Patch { mesh, patch: found, frame } => {
                    let apply = |w: &[f64]| -> DVec3 {
                        w.iter().zip(&found.vertices).map(|(&w, &v)| w * mesh.position(v)).sum()
                    };
                    let (position, ds, dt, exact_derivatives) =
                        self.with_stencil(&found.matrices, found.shape, frame.to_patch(p), |s| {
                            (apply(&s.position), apply(&s.du), apply(&s.dv), s.exact_derivatives)
                        })?;
                    let (ju, jv) = frame.chain(j);
                    return Ok(LimitPoint {
                        position,
                        du: ju[0] * ds + ju[1] * dt,
                        dv: jv[0] * ds + jv[1] * dt,
                        exact_derivatives,
                    });
                }
            }
        }
        Err(internal(face, "the descent ran past the last prepared level"))
    }

    /// The points of `osd_limit --grid n` on `face` ([`FaceDomain::grid`]) with their limit
    /// points; empty for a hole.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::Rate`] for `n = 0`, and as
    /// [`eval_exact`](Self::eval_exact).
    pub fn grid(&self, face: FaceId, n: u32) -> Result<Vec<(GridParameter, LimitPoint)>, StencilError> {
        if n == 0 {
            return Err(StencilError::Rate { rate: 0, reason: "a grid needs at least one step per side" });
        }
        if !self.has_surface(face)? {
            return Ok(Vec::new());
        }
        self.domain(face)?.grid(n).into_iter().map(|g| Ok((g, self.eval_exact(face, g.point)?))).collect()
    }

    /// `f` of the stencil of `shape` of `matrices` at `point`, from the evaluator of those
    /// matrices, which shares work between points (and whose results do not depend on their
    /// order). Evaluations through one `LimitEvaluator` take turns on its lock.
    fn with_stencil<R>(
        &self,
        matrices: &Arc<PatchMatrices>,
        shape: usize,
        point: Dyadic,
        f: impl FnOnce(&SurfaceStencil) -> R,
    ) -> Result<R, StencilError> {
        // The matrices are shared per process and kept alive by the evaluators, so the address
        // identifies them.
        let mut evaluators = self.evaluators.lock().unwrap_or_else(PoisonError::into_inner);
        let evaluator =
            evaluators.entry(Arc::as_ptr(matrices) as usize).or_insert_with(|| StencilEvaluator::new(matrices.clone()));
        Ok(f(evaluator.stencil(shape, point)?))
    }
}

fn internal(face: FaceId, detail: &str) -> StencilError {
    StencilError::Internal(format!("limit evaluation of {face}: {detail}"))
}

/// The child faces of `face` ([`child_faces`]; `split` is a primal one here).
fn children(mesh: &Mesh, split: Split, face: FaceId) -> std::ops::Range<usize> {
    child_faces(split, mesh, face).unwrap_or(0..0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use subdiv_mesh::shapes;
    use subdiv_schemes::{Builtin, refine};

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

    #[test]
    fn other_primal_schemes_meet_their_known_values() {
        // Bilinear: the face's bilinear interpolant, with its derivatives.
        let torus = Mesh::build(shapes::quad_torus(6, 4)).unwrap();
        let eval = LimitEvaluator::new(Builtin::Bilinear.scheme(), &torus, &RefineOptions::DEFAULT).unwrap();
        let c: Vec<DVec3> = torus.face_vertices(FaceId::new(0)).iter().map(|&v| torus.position(v)).collect();
        let (u, v) = (0.5, 0.25);
        let got = eval.eval(FaceId::new(0), u, v).unwrap();
        let want = c[0] * (1.0 - u) * (1.0 - v) + c[1] * u * (1.0 - v) + c[2] * u * v + c[3] * (1.0 - u) * v;
        let du = (c[1] - c[0]) * (1.0 - v) + (c[2] - c[3]) * v;
        let dv = (c[3] - c[0]) * (1.0 - u) + (c[2] - c[1]) * u;
        assert!(got.exact_derivatives);
        for (a, b) in [(got.position, want), (got.du, du), (got.dv, dv)] {
            assert!((a - b).length() < 1e-12, "bilinear: {a} vs {b}");
        }
        // Interpolating schemes pass through the cage's vertices: butterfly on the icosahedron,
        // Kobbelt on the cube (valence 3).
        for (scheme, soup) in [(Builtin::Butterfly, shapes::icosahedron()), (Builtin::Kobbelt, shapes::cube())] {
            let mesh = Mesh::build(soup).unwrap();
            let eval = LimitEvaluator::new(scheme.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            for f in mesh.face_ids() {
                let p = eval.eval(f, 0.0, 0.0).unwrap().position;
                assert!((p - mesh.position(mesh.face_vertices(f)[0])).length() < 1e-12, "{scheme:?} {f}");
            }
        }
    }

    #[test]
    fn infinitely_sharp_creases_are_the_crease_polygon_s_b_spline() {
        // A ring of edges of a torus (j = 0), infinitely sharp: the limit along it is the
        // uniform cubic B-spline of the ring's vertices, and the two sides' normals differ.
        let (m, n) = (8, 6);
        let mut soup = shapes::quad_torus(m, n);
        let id = |i: usize| subdiv_mesh::VertexId::new(((i % m) * n) as u32);
        for i in 0..m {
            soup.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [id(i), id(i + 1)], sharpness: 10.0 });
        }
        let mesh = Mesh::build(soup).unwrap();
        let p = |i: usize| mesh.position(id(i + m));
        let eval = LimitEvaluator::new(Builtin::CatmullClark.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
        for i in 0..m {
            // Face (i, 0) has the crease as its first side; face (i, n − 1) as its last side's
            // opposite, v = 1.
            let (above, below) = (FaceId::new((i * n) as u32), FaceId::new((i * n + n - 1) as u32));
            for u in [0.0, 0.25, 0.5, 0.75] {
                let b = [
                    (1.0f64 - u).powi(3) / 6.0,
                    (3.0 * u.powi(3) - 6.0 * u * u + 4.0) / 6.0,
                    (-3.0 * u.powi(3) + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
                    u.powi(3) / 6.0,
                ];
                let want = p(i + m - 1) * b[0] + p(i) * b[1] + p(i + 1) * b[2] + p(i + 2) * b[3];
                let (a, c) = (eval.eval(above, u, 0.0).unwrap(), eval.eval(below, u, 1.0).unwrap());
                assert!((a.position - want).length() < 1e-13, "face {above} at {u}: {:?} vs {want:?}", a.position);
                assert!((c.position - want).length() < 1e-13, "face {below} at {u}");
                let (na, nc) = (a.du.cross(a.dv).normalize(), c.du.cross(c.dv).normalize());
                assert!(na.dot(nc) < 0.999, "the crease at {u} is smooth: {na:?} {nc:?}");
                // Along the crease both sides have the curve's tangent.
                assert!(a.du.normalize().dot(c.du.normalize()) > 1.0 - 1e-12);
            }
        }
    }

    #[test]
    fn semi_sharp_features_equal_the_refined_mesh_s_surface() {
        // An edge of sharpness 2.5 and a corner of sharpness 1.5 are spent after 3 levels: the
        // surface of the cage over face f's corner square [0, 1/8]² is the surface of the
        // 3 times refined mesh over child 0 of child 0 of child 0 of f.
        let cc = Builtin::CatmullClark.scheme();
        let mut soup = shapes::cube();
        let [a, b] = [soup.face(FaceId::new(0))[0], soup.face(FaceId::new(0))[1]];
        soup.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [a, b], sharpness: 2.5 });
        soup.tags.corners.push(subdiv_mesh::CornerTag { vertex: b, sharpness: 1.5 });
        let mesh = Mesh::build(soup).unwrap();
        let refined = refine_uniform_n(&mesh, cc, 3);
        let coarse = LimitEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT).unwrap();
        let fine = LimitEvaluator::new(cc, &refined.0, &RefineOptions::DEFAULT).unwrap();
        for f in mesh.face_ids() {
            let mut child = f;
            for level in &refined.1 {
                child = FaceId::new(child_faces(Split::Quad, level, child).unwrap().start as u32);
            }
            for (u, v) in [(0.0, 0.0), (1.0 / 16.0, 0.0), (0.0, 1.0 / 32.0), (1.0 / 8.0, 1.0 / 8.0), (0.05, 0.1)] {
                let (x, y) = (coarse.eval(f, u, v).unwrap(), fine.eval(child, 8.0 * u, 8.0 * v).unwrap());
                assert!((x.position - y.position).length() < 1e-13, "{f} at ({u}, {v})");
                if x.exact_derivatives && y.exact_derivatives {
                    assert!((x.du - y.du * 8.0).length() < 1e-11, "{f} at ({u}, {v}): {:?} {:?}", x.du, y.du * 8.0);
                    assert!((x.dv - y.dv * 8.0).length() < 1e-11);
                }
            }
        }
    }

    /// `mesh` refined `levels` times, with the mesh of every level before the last.
    fn refine_uniform_n(mesh: &Mesh, scheme: &Scheme, levels: usize) -> (Mesh, Vec<Mesh>) {
        let mut all = vec![mesh.clone()];
        for _ in 0..levels {
            all.push(refine(all.last().unwrap(), scheme, &RefineOptions::DEFAULT).unwrap());
        }
        let last = all.pop().unwrap();
        (last, all)
    }

    #[test]
    fn holes_and_bad_points_are_typed_errors() {
        let cc = Builtin::CatmullClark.scheme();
        let mut soup = shapes::cube();
        soup.tags.holes.push(FaceId::new(1));
        let mesh = Mesh::build(soup).unwrap();
        let eval = LimitEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT).unwrap();
        assert!(eval.grid(FaceId::new(1), 2).unwrap().is_empty());
        assert_eq!(eval.eval(FaceId::new(1), 0.5, 0.5), Err(StencilError::NoSurface { face: 1 }));
        assert_eq!(eval.grid(FaceId::new(0), 2).unwrap().len(), 9);
        assert_eq!(eval.eval(FaceId::new(6), 0.0, 0.0), Err(StencilError::FaceOutOfRange { face: 6, faces: 6 }));
        assert!(matches!(eval.eval(FaceId::new(0), 1.0, 1.5), Err(StencilError::OutsideFace { face: 0, .. })));
        assert!(matches!(eval.eval(FaceId::new(0), f64::INFINITY, 0.0), Err(StencilError::OutsideFace { .. })));

        let doo_sabin = LimitEvaluator::new(Builtin::DooSabin.scheme(), &mesh, &RefineOptions::DEFAULT);
        assert!(matches!(doo_sabin, Err(StencilError::Scheme(subdiv_schemes::SchemeError::SplitNotSupported { .. }))));
    }

    /// `k` sectors of a `rings`-ring grid (quads, or triangles) over a half-disk around vertex 0,
    /// which is on the boundary with `k` faces; gently curved so that normals vary.
    fn open_fan(k: usize, rings: usize, triangles: bool) -> subdiv_mesh::PolygonSoup {
        let mut soup = subdiv_mesh::PolygonSoup::new();
        let direction = |s: usize| {
            let a = std::f64::consts::PI * s as f64 / k as f64;
            DVec3::new(a.cos(), a.sin(), 0.0)
        };
        let inside = |i: usize, j: usize| if triangles { i + j <= rings } else { i.max(j) <= rings };
        let centre = soup.push_vertex(DVec3::new(0.0, 0.0, 0.3));
        let mut ids = HashMap::new();
        for s in 0..=k {
            for i in 1..=rings {
                for j in 0..=if s < k { rings } else { 0 } {
                    if inside(i, j) {
                        let p = direction(s) * i as f64 + direction(s + 1) * j as f64;
                        let p = p + DVec3::new(0.0, 0.0, 0.3 - 0.05 * p.length_squared() + 0.1 * p.x);
                        ids.insert((s, i, j), soup.push_vertex(p));
                    }
                }
            }
        }
        let id = |s: usize, i: usize, j: usize| match (i, j) {
            (0, 0) => centre,
            (0, j) => ids[&(s + 1, j, 0)],
            _ => ids[&(s, i, j)],
        };
        for s in 0..k {
            for i in 0..rings {
                for j in 0..rings {
                    if !triangles {
                        soup.push_face([id(s, i, j), id(s, i + 1, j), id(s, i + 1, j + 1), id(s, i, j + 1)]);
                        continue;
                    }
                    if i + j < rings {
                        soup.push_face([id(s, i, j), id(s, i + 1, j), id(s, i, j + 1)]);
                    }
                    if i + j + 1 < rings {
                        soup.push_face([id(s, i + 1, j), id(s, i + 1, j + 1), id(s, i, j + 1)]);
                    }
                }
            }
        }
        soup
    }

    #[test]
    fn tangents_at_boundary_vertices_span_each_faces_own_plane() {
        // Catmull-Clark's ½ is defective at four faces (a Jordan block under 0.61), and at six
        // the two leading modes vanish on the boundary; Loop's eight faces make a thin wedge.
        for (scheme, k) in
            [(Builtin::CatmullClark, 4), (Builtin::CatmullClark, 6), (Builtin::Loop, 4), (Builtin::Loop, 8)]
        {
            let triangles = scheme == Builtin::Loop;
            let mesh = Mesh::build(open_fan(k, 3, triangles)).unwrap();
            let eval = LimitEvaluator::new(scheme.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            let corners: &[(f64, f64)] = if triangles {
                &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
            } else {
                &[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            };
            let centre = if triangles { (1.0 / 3.0, 1.0 / 3.0) } else { (0.5, 0.5) };
            let mut seen = 0;
            for f in mesh.face_ids() {
                let Some(c) = mesh.face_vertices(f).iter().position(|v| v.index() == 0) else { continue };
                seen += 1;
                let (u0, v0) = corners[c];
                // Towards the face's centre by h.
                let near = |h: f64| eval.eval(f, u0 + h * (centre.0 - u0), v0 + h * (centre.1 - v0)).unwrap();
                let at = eval.eval(f, u0, v0).unwrap();
                let what = format!("{scheme:?} k = {k} face {f}");
                assert!(!at.exact_derivatives, "{what}");
                let angle = at.du.angle_between(at.dv).to_degrees();
                assert!(angle > 1.0 && angle < 179.0, "{what}: du and dv {angle}° apart");
                let normal = at.du.cross(at.dv).normalize();
                for h in [0.5f64.powi(3), 0.5f64.powi(10), 0.5f64.powi(20)] {
                    let p = near(h);
                    assert!(p.exact_derivatives, "{what}");
                    let dot = normal.dot(p.du.cross(p.dv).normalize());
                    assert!(dot > 0.9, "{what}: the normal at h = {h} is {dot} off");
                }
                // Lengths like the exact derivatives next to the vertex (not 1e7 of them).
                let p = near(0.125);
                let exact = p.du.length().max(p.dv.length());
                for d in [at.du, at.dv] {
                    assert!(
                        d.length() < 20.0 * exact && d.length() > exact / 20.0,
                        "{what}: {} vs {exact}",
                        d.length()
                    );
                }
            }
            assert_eq!(seen, k, "{scheme:?}");
        }
    }

    /// Catmull-Clark at `vertex` of `soup`, per quad around it: the tangents there, and the
    /// limit points approaching it along the face's diagonal at distances `hs` (in the face's
    /// parameters, towards its centre).
    fn tangents_and_nearby_normals(
        soup: subdiv_mesh::PolygonSoup,
        vertex: usize,
        hs: &[f64],
    ) -> Vec<(String, LimitPoint, Vec<LimitPoint>)> {
        let mesh = Mesh::build(soup).unwrap();
        let eval = LimitEvaluator::new(Builtin::CatmullClark.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
        let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        mesh.face_ids()
            .filter_map(|f| {
                let c = mesh.face_vertices(f).iter().position(|v| v.index() == vertex)?;
                let (u0, v0) = corners[c];
                let at = eval.eval(f, u0, v0).unwrap();
                let near = hs
                    .iter()
                    .map(|&h| {
                        let p = eval.eval(f, u0 + h * (0.5 - u0), v0 + h * (0.5 - v0)).unwrap();
                        assert!(p.exact_derivatives, "face {f} at {h}");
                        p
                    })
                    .collect();
                Some((format!("face {f}"), at, near))
            })
            .collect()
    }

    /// `pole(k)` with the spokes `sharp` (whole spokes, both edges) infinitely sharp.
    fn creased_pole(k: usize, sharp: &[usize]) -> subdiv_mesh::PolygonSoup {
        let mut soup = shapes::pole(k);
        for &s in sharp {
            let (a, b) = (subdiv_mesh::VertexId::new(1 + 6 * s as u32), subdiv_mesh::VertexId::new(2 + 6 * s as u32));
            for vertices in [[subdiv_mesh::VertexId::new(0), a], [a, b]] {
                soup.tags
                    .creases
                    .push(subdiv_mesh::CreaseTag { vertices, sharpness: subdiv_mesh::Tags::INFINITELY_SHARP });
            }
        }
        soup
    }

    /// Tangents that are directions (not parallel) of about the exact derivatives' lengths
    /// next to the vertex, `near` (not 1e7 of them).
    fn assert_sane_tangents(what: &str, at: &LimitPoint, near: &LimitPoint) {
        assert!(!at.exact_derivatives, "{what}");
        let angle = at.du.angle_between(at.dv).to_degrees();
        assert!(angle > 1.0 && angle < 179.0, "{what}: du and dv {angle}° apart");
        let exact = near.du.length().max(near.dv.length());
        for d in [at.du, at.dv] {
            assert!(d.length() < 20.0 * exact && d.length() > exact / 20.0, "{what}: {} vs {exact}", d.length());
        }
    }

    #[test]
    fn tangents_at_infinitely_sharp_creases_and_corners_are_the_limit_of_nearby_normals() {
        let hs: Vec<f64> = [3, 10, 20, 40].iter().map(|&k| 0.5f64.powi(k)).collect();
        // A crease with four faces on one side, whose ½ is a 2 × 2 Jordan block beside the two
        // faces' own ½ (below 0.61); four and four (two blocks on the crease's ½); a corner of
        // three creases whose sector of two faces has 0.58 above the creases' ½; a dart.
        for (k, sharp) in [(6, vec![0, 4]), (8, vec![0, 4]), (6, vec![0, 1, 3]), (5, vec![0])] {
            let points = tangents_and_nearby_normals(creased_pole(k, &sharp), 0, &hs);
            assert_eq!(points.len(), k);
            for (what, at, near) in points {
                let what = format!("k = {k}, sharp spokes {sharp:?}, {what}");
                // The side of two faces of a crease has derivatives: the regular crease's.
                if !at.exact_derivatives {
                    assert_sane_tangents(&what, &at, &near[0]);
                }
                let normal = at.du.cross(at.dv).normalize();
                for (p, h) in near[1..].iter().zip(&hs[1..]) {
                    let dot = normal.dot(p.du.cross(p.dv).normalize());
                    assert!(dot > 0.999, "{what}: the normal at h = {h} is {dot} off");
                }
            }
        }
        // Corners of three creases whose sectors of two faces have the creases' ½ as a 2 × 2
        // block beside a simple ½: the block's top (the creases' mean tangent, growing as
        // n 2⁻ⁿ) and the simple one (their difference) span the plane, which the normals near
        // the vertex reach only as 1/n (at 2⁻ⁿ), the part of the block's eigenvector fading.
        for (k, sharp, lowered) in [(4, vec![1, 2, 3], 0.6), (5, vec![0, 2, 3], 0.0), (5, vec![0, 2, 3], 0.6)] {
            let mut soup = creased_pole(k, &sharp);
            soup.positions_mut()[0].z -= lowered;
            let mut seen = 0;
            for (what, at, near) in tangents_and_nearby_normals(soup, 0, &hs) {
                let what = format!("k = {k}, sharp spokes {sharp:?}, centre lowered by {lowered}, {what}");
                if at.exact_derivatives {
                    continue; // A sector of one face: a regular corner.
                }
                seen += 1;
                assert_sane_tangents(&what, &at, &near[0]);
                let normal = at.du.cross(at.dv).normalize();
                let angles: Vec<f64> =
                    near[1..].iter().map(|p| normal.angle_between(p.du.cross(p.dv)).to_degrees()).collect();
                assert!(angles[0] < 20.0, "{what}: {angles:?}");
                assert!(angles[1] < 0.7 * angles[0] && angles[2] < 0.7 * angles[1], "{what}: {angles:?}");
            }
            assert_eq!(seen, 2 * (k - 3), "k = {k}");
        }
    }

    /// Two quads glued along two edges, around a vertex of valence 2 (the last) in the middle of
    /// a 3 × 3 grid, whose middle quad they replace; domed, the vertex lowered by `lowered`.
    fn valence_two(lowered: f64) -> subdiv_mesh::PolygonSoup {
        let grid = shapes::quad_grid(3, 3);
        let mut soup = subdiv_mesh::PolygonSoup::new();
        let dome =
            |p: DVec3| p + DVec3::Z * (0.3 - 0.1 * (p - DVec3::new(1.5, 1.5, 0.0)).length_squared() + 0.05 * p.x);
        for &p in grid.positions() {
            soup.push_vertex(dome(p));
        }
        let centre = soup.push_vertex(dome(DVec3::new(1.5, 1.5, -lowered)));
        let id = |i: usize, j: usize| subdiv_mesh::VertexId::new((j * 4 + i) as u32);
        for j in 0..3 {
            for i in 0..3 {
                let corners = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                if (i, j) == (1, 1) {
                    soup.push_face([corners[0], corners[1], corners[2], centre]);
                    soup.push_face([corners[0], centre, corners[2], corners[3]]);
                } else {
                    soup.push_face(corners);
                }
            }
        }
        soup
    }

    #[test]
    fn tangents_at_a_vertex_of_valence_two_run_along_the_first_side_and_into_the_face() {
        // Each face covers half a turn of the characteristic map, so its sides are opposite:
        // dv points into the face instead, and both faces get one normal. The normals nearby
        // differ from it a little, by the direction of approach and the level's parity (−¼
        // beside the ¼ pair).
        let hs: Vec<f64> = [3, 10, 11, 20, 21].iter().map(|&k| 0.5f64.powi(k)).collect();
        for lowered in [0.0, 0.5] {
            let points = tangents_and_nearby_normals(valence_two(lowered), 16, &hs);
            assert_eq!(points.len(), 2);
            let normals: Vec<DVec3> = points.iter().map(|(_, at, _)| at.du.cross(at.dv).normalize()).collect();
            assert!(normals[0].dot(normals[1]) > 1.0 - 1e-9, "lowered by {lowered}: {normals:?}");
            for ((what, at, near), normal) in points.iter().zip(normals) {
                let what = format!("lowered by {lowered}, {what}");
                assert_sane_tangents(&what, at, &near[0]);
                assert!(normal.z > 0.9, "{what}: the dome's normal points up: {normal}");
                for (p, h) in near[1..].iter().zip(&hs[1..]) {
                    let dot = normal.dot(p.du.cross(p.dv).normalize());
                    assert!(dot > 0.99, "{what}: the normal at h = {h} is {dot} off");
                }
            }
        }
    }

    #[test]
    fn bilinear_is_each_faces_interpolant_with_exact_derivatives() {
        // Valence 3 (the cube), 5 (the pole) and a boundary vertex of four faces.
        for soup in [shapes::cube(), shapes::pole(5), open_fan(4, 2, false)] {
            let mesh = Mesh::build(soup).unwrap();
            let eval = LimitEvaluator::new(Builtin::Bilinear.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            for f in mesh.face_ids() {
                let c: Vec<DVec3> = mesh.face_vertices(f).iter().map(|&v| mesh.position(v)).collect();
                for j in 0..=4 {
                    for i in 0..=4 {
                        let (u, v) = (f64::from(i) / 4.0, f64::from(j) / 4.0);
                        let got = eval.eval(f, u, v).unwrap();
                        let want =
                            c[0] * (1.0 - u) * (1.0 - v) + c[1] * u * (1.0 - v) + c[2] * u * v + c[3] * (1.0 - u) * v;
                        let du = (c[1] - c[0]) * (1.0 - v) + (c[2] - c[3]) * v;
                        let dv = (c[3] - c[0]) * (1.0 - u) + (c[2] - c[1]) * u;
                        assert!(got.exact_derivatives, "{f} ({u}, {v})");
                        for (a, b) in [(got.position, want), (got.du, du), (got.dv, dv)] {
                            assert!((a - b).length() < 1e-12, "{f} ({u}, {v}): {a} vs {b}");
                        }
                    }
                }
            }
        }
    }
}
