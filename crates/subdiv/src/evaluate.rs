//! Limit evaluation through the facade: [`EvalOptions`], [`Evaluator`] and its grids.

use subdiv_eval::{EigenEvaluator, EvalError, Method as EvalMethod};
use subdiv_mesh::{BoundaryInterpolation, FaceId, Mesh};
use subdiv_schemes::{RefineOptions, Scheme};
use subdiv_stencil::{FaceDomain, LimitPoint, LinearEvaluator};

use crate::Error;

/// The largest grid [`Evaluator::grid`] takes: `(n + 1)²` points per quad.
pub const MAX_GRID: u32 = 4096;

/// The most points [`Evaluator::grid`] evaluates unless raised with
/// [`EvalOptions::with_max_points`]: 10⁷, about 1 GB of [`GridPoint`]s (96 bytes each) and
/// 2 GB of `subdiv eval` CSV.
pub const DEFAULT_MAX_POINTS: u64 = 10_000_000;

/// Options of [`Surface::evaluator`](crate::Surface::evaluator).
///
/// ```
/// use subdiv::{EvalMethod, EvalOptions};
/// use subdiv::mesh::BoundaryInterpolation;
///
/// let options = EvalOptions::DEFAULT.with_method(EvalMethod::Stencil).with_boundary(BoundaryInterpolation::EdgeAndCorner);
/// assert_eq!(EvalOptions::default(), EvalOptions::DEFAULT);
/// assert_eq!(options.refine.boundary, Some(BoundaryInterpolation::EdgeAndCorner));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EvalOptions {
    /// How faces are evaluated: eigenbasis (Stam, Lai-Cheng; any real parameter), exact
    /// stencils, or eigenbasis on interior patches and stencils on boundary ones. Default:
    /// [`EvalMethod::Auto`].
    pub method: EvalMethod,
    /// The boundary rule and the other options refinement takes. Default:
    /// [`RefineOptions::DEFAULT`] (everything from the mesh's tags).
    pub refine: RefineOptions,
    /// The most points one [`Evaluator::grid`] evaluates; a larger grid is refused with
    /// [`Error::Budget`] before anything is allocated. Default: [`DEFAULT_MAX_POINTS`].
    pub max_points: u64,
}

impl EvalOptions {
    /// The defaults: [`EvalMethod::Auto`], the mesh's tags.
    pub const DEFAULT: Self =
        Self { method: EvalMethod::Auto, refine: RefineOptions::DEFAULT, max_points: DEFAULT_MAX_POINTS };

    /// These options with [`method`](Self::method).
    #[must_use]
    pub const fn with_method(self, method: EvalMethod) -> Self {
        Self { method, ..self }
    }

    /// These options with [`max_points`](Self::max_points).
    #[must_use]
    pub const fn with_max_points(self, max_points: u64) -> Self {
        Self { max_points, ..self }
    }

    /// These options with the boundary rule `boundary` (instead of the mesh's
    /// `interpolateboundary` tag).
    #[must_use]
    pub const fn with_boundary(self, boundary: BoundaryInterpolation) -> Self {
        Self { refine: RefineOptions { boundary: Some(boundary), ..self.refine }, ..self }
    }
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// One point of an [`Evaluator::grid`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPoint {
    /// The face.
    pub face: FaceId,
    /// `u` as OpenSubdiv's `osd_limit` prints it (N-gons: the tiled sub-face coordinates).
    pub u: f64,
    /// `v`, likewise.
    pub v: f64,
    /// The limit point.
    pub point: LimitPoint,
}

/// The points of an [`Evaluator::grid`] and the faces it skipped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvalGrid {
    /// The points, face by face, in `osd_limit`'s order.
    pub points: Vec<GridPoint>,
    /// The faces without a limit surface (holes), which have no points.
    pub holes: usize,
}

/// The limit surface of a mesh at any face's `Bfr` parameters, prepared once
/// ([`Surface::evaluator`](crate::Surface::evaluator)): positions and first derivatives.
#[derive(Debug)]
pub struct Evaluator {
    inner: Inner,
    max_points: u64,
}

/// How an [`Evaluator`] evaluates.
#[derive(Debug)]
enum Inner {
    /// A surface's patches, by eigenbasis or exact stencils.
    Patches(EigenEvaluator),
    /// A linear channel's faces, their corners combined directly (any method: exact up to
    /// rounding), with the method asked for.
    Linear(LinearEvaluator, EvalMethod),
}

impl Evaluator {
    /// Prepares `mesh` under `scheme`.
    pub(crate) fn new(scheme: &Scheme, mesh: &Mesh, options: &EvalOptions) -> Result<Self, Error> {
        let inner = Inner::Patches(EigenEvaluator::new(scheme, mesh, &options.refine, options.method)?);
        Ok(Self { inner, max_points: options.max_points })
    }

    /// Evaluates a linear channel's surface directly.
    pub(crate) fn linear(linear: LinearEvaluator, options: &EvalOptions) -> Self {
        Self { inner: Inner::Linear(linear, options.method), max_points: options.max_points }
    }

    /// The method faces were prepared with.
    pub fn method(&self) -> EvalMethod {
        match &self.inner {
            Inner::Patches(eigen) => eigen.method(),
            Inner::Linear(_, method) => *method,
        }
    }

    /// The evaluator underneath (second derivatives, which face takes which route, the exact
    /// stencil evaluator); `None` for a linear channel's surface
    /// ([`Surface::channel_evaluator`](crate::Surface::channel_evaluator) in face-varying mode
    /// `all`), whose faces are their corners' bilinear or linear interpolation.
    pub fn eigen(&self) -> Option<&EigenEvaluator> {
        match &self.inner {
            Inner::Patches(eigen) => Some(eigen),
            Inner::Linear(..) => None,
        }
    }

    fn face_count(&self) -> usize {
        match &self.inner {
            Inner::Patches(eigen) => eigen.face_count(),
            Inner::Linear(linear, _) => linear.face_count(),
        }
    }

    fn has_surface(&self, face: FaceId) -> Result<bool, Error> {
        Ok(match &self.inner {
            Inner::Patches(eigen) => eigen.stencil().has_surface(face)?,
            Inner::Linear(linear, _) => linear.has_surface(face)?,
        })
    }

    fn domain(&self, face: FaceId) -> Result<FaceDomain, Error> {
        Ok(match &self.inner {
            Inner::Patches(eigen) => eigen.stencil().domain(face)?,
            Inner::Linear(linear, _) => linear.domain(face)?,
        })
    }

    /// The limit point of `face` at `(u, v)` with its first derivatives (at an extraordinary
    /// vertex itself, tangent directions: [`LimitPoint::exact_derivatives`] is then `false`).
    ///
    /// # Errors
    /// [`Error::Eval`] for a face out of range, a parameter outside the face, a hole
    /// ([`Error::is_hole`]), or a face [`EvalMethod::Eigen`] does not take.
    #[inline]
    pub fn evaluate(&self, face: FaceId, u: f64, v: f64) -> Result<LimitPoint, Error> {
        Ok(match &self.inner {
            Inner::Patches(eigen) => eigen.eval(face, u, v)?,
            // Wrapped as the patches' errors are: `Error::Eval` for every evaluation.
            Inner::Linear(linear, _) => linear.eval(face, u, v).map_err(EvalError::Stencil)?,
        })
    }

    /// Every face at the grid `(i/n, j/n)` of `osd_limit --grid n`: quads `(n + 1)²` points,
    /// `j` outer; triangles of triangle schemes `i + j ≤ n`; other faces of quad schemes the
    /// grid of every `Bfr` sub-face. With [`EvalMethod::Stencil`] the exact rational grid
    /// points are evaluated, otherwise the f64 parameters listed. Holes are counted, not
    /// evaluated.
    ///
    /// # Errors
    /// [`Error::Grid`] unless `1 ≤ n ≤` [`MAX_GRID`]; [`Error::Budget`] for more points than
    /// [`EvalOptions::max_points`]; as [`evaluate`](Self::evaluate).
    ///
    /// ```
    /// use subdiv::mesh::shapes;
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{Error, EvalOptions, Surface};
    ///
    /// let surface = Surface::build(shapes::cube(), Builtin::CatmullClark.scheme())?;
    /// let evaluator = surface.evaluator(&EvalOptions::DEFAULT.with_max_points(1000))?;
    /// assert_eq!(evaluator.grid(8)?.points.len(), 6 * 81);
    /// assert!(matches!(evaluator.grid(16), Err(Error::Budget { requested: 1734, limit: 1000, .. })));
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    pub fn grid(&self, n: u32) -> Result<EvalGrid, Error> {
        if !(1..=MAX_GRID).contains(&n) {
            return Err(Error::Grid { n, max: MAX_GRID });
        }
        let mut points = 0u64;
        for face in (0..self.face_count() as u32).map(FaceId::new) {
            if self.has_surface(face)? {
                points = points.saturating_add(self.domain(face)?.grid_len(n));
            }
        }
        Error::check_budget(
            points,
            self.max_points,
            "the grid would evaluate",
            "points",
            "use a smaller grid, or raise the limit (EvalOptions::with_max_points, `subdiv eval --max-points`)",
        )?;
        let mut grid = EvalGrid { points: Vec::with_capacity(points as usize), holes: 0 };
        for face in (0..self.face_count() as u32).map(FaceId::new) {
            if let (Inner::Patches(eigen), EvalMethod::Stencil) = (&self.inner, self.method()) {
                let points = eigen.stencil().grid(face, n)?;
                grid.holes += usize::from(points.is_empty());
                grid.points.extend(points.into_iter().map(|(g, point)| GridPoint { face, u: g.u, v: g.v, point }));
                continue;
            }
            if !self.has_surface(face)? {
                grid.holes += 1;
                continue;
            }
            for g in self.domain(face)?.grid(n) {
                grid.points.push(GridPoint { face, u: g.u, v: g.v, point: self.evaluate(face, g.u, g.v)? });
            }
        }
        Ok(grid)
    }
}
