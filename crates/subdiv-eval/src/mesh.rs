//! Eigenbasis evaluation of a whole mesh in OpenSubdiv's `Bfr` parameterization.

use std::collections::HashMap;
use std::fmt::Write as _;

use std::sync::Arc;
use subdiv_mesh::{DVec3, FaceId, Mesh};

use subdiv_schemes::{PatchMatrices, PatchType, RefineOptions, Scheme, Split};

/// Why √3's faces take the exact stencils.
const TERNARY: &str = "√3's patches split in nine (ternary), and eigenbases are made for the binary splits; \
                       its faces evaluate through exact stencils (--method stencil, or auto)";
use subdiv_stencil::{Dyadic, FaceDomain, Layout, LimitEvaluator, LimitPoint, PatchLevels, Resolved, StencilError};

use crate::surface::{PatchPoint, PatchPoint2};
use crate::{EigenBasis, EvalError, PatchSurface};

/// How an [`EigenEvaluator`] evaluates faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// Eigenbasis only; a face it cannot evaluate (one under a boundary patch, or a scheme
    /// whose regular patch is not a polynomial) gives [`EvalError::FaceNotSupported`].
    Eigen,
    /// The exact stencil route ([`LimitEvaluator`]) for every face.
    Stencil,
    /// Eigenbasis where every patch under the face is an interior patch of a scheme with a
    /// polynomial regular patch (Catmull-Clark, Loop, bilinear), exact stencils otherwise —
    /// also under a derived configuration's shape whose semi-sharp features are not yet spent
    /// (its exact stencils are shared per shape, where [`Method::Eigen`] builds the chain's
    /// sub-patch surfaces per face). The default.
    #[default]
    Auto,
}

/// A [`LimitPoint`] with second derivatives in the face's `Bfr` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitPoint2 {
    /// Position and first derivatives.
    pub first: LimitPoint,
    /// ∂²/∂u²; zero where `first.exact_derivatives` is false (at an extraordinary vertex).
    pub duu: DVec3,
    /// ∂²/∂u∂v; likewise.
    pub duv: DVec3,
    /// ∂²/∂v²; likewise.
    pub dvv: DVec3,
}

/// How one input face is evaluated.
#[derive(Debug)]
enum Route {
    /// A face that is its own patch (most faces): no descent, one lookup.
    Patch {
        surface: u32,
        frame: Frame,
    },
    /// A face resolved through its children (N-gons, faces with two extraordinary vertices).
    Eigen {
        node: u32,
        domain: FaceDomain,
    },
    /// By exact stencils; the reason the eigenbasis does not take it, if it was asked.
    Stencil {
        reason: Option<String>,
    },
    Hole,
}

/// One face of one level of the patch levels, for eigenbasis evaluation.
#[derive(Debug)]
enum Node {
    /// A patch: the face's `(u, v)` is `origin + s·e1 + t·e2`; `to_patch` is `[e1 e2]⁻¹`,
    /// `derivatives` the rows of `(∂/∂u, ∂/∂v)` over `(∂/∂s, ∂/∂t)`.
    Patch { surface: u32, frame: Frame },
    /// Refined: the children are consecutive nodes from `first`.
    Children { first: u32, triangle: bool },
    /// A patch without an eigenbasis of its own (a derived configuration's shape before its
    /// semi-sharp features are spent), evaluated through its sub-patches: the face's `(u, v)`
    /// goes into the patch's frame, then to the sub-patch that holds it, consecutive nodes from
    /// `first` in the patch's own parameters (their frames are the identity).
    SubPatches { frame: Frame, first: u32, triangle: bool },
}

/// The limit surface of a mesh by eigenbasis evaluation (paper 002 §3; Stam '98, '99), at any
/// face's f64 parameter in OpenSubdiv's `Bfr` parameterization: quads `(0, 0)` at corner 0,
/// `u` toward corner 1, `v` toward corner 3; triangles of Loop `(0, 0)`, `(1, 0)`, `(0, 1)` at
/// corners 0, 1, 2; N-gons of quad schemes as `Bfr`'s tiled quad sub-faces.
///
/// Faces are resolved to patches by [`PatchLevels`] (as the stencil route does): an N-gon or a
/// face whose patch holds two extraordinary vertices descends into its children. Each patch
/// keeps a [`PatchSurface`]; a point costs the descent (none for most faces), the ring lookup
/// from its exponent bits and one Horner evaluation. Faces under boundary patches are
/// evaluated by exact stencils ([`Method`]); so are all faces with [`Method::Stencil`].
#[derive(Debug)]
pub struct EigenEvaluator {
    stencil: LimitEvaluator,
    method: Method,
    routes: Vec<Route>,
    nodes: Vec<Node>,
    surfaces: Vec<PatchSurface>,
}

impl EigenEvaluator {
    /// Prepares `mesh` under `scheme` (boundary rule and options as refinement takes them):
    /// the faces' patches, and for the faces the eigenbasis takes, their surfaces.
    ///
    /// # Errors
    /// As [`LimitEvaluator::new`] (wrapped); the eigenbasis itself fails per face, at
    /// evaluation (with [`Method::Eigen`]) or not at all (with [`Method::Auto`]).
    pub fn new(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions, method: Method) -> Result<Self, EvalError> {
        let stencil = LimitEvaluator::new(scheme, mesh, options)?;
        // Auto leaves derived chains to the stencils, whose exact stencils are shared per shape
        // where the chain's sub-patch surfaces are built per face (twice the car's setup).
        let mut tree = Tree { descend_chains: method == Method::Eigen, ..Tree::default() };
        let mut routes = Vec::new();
        for f in 0..stencil.face_count() {
            let face = FaceId::new(f as u32);
            let route = if !stencil.has_surface(face)? {
                Route::Hole
            } else if method == Method::Stencil {
                Route::Stencil { reason: None }
            } else if scheme.split() == Split::Sqrt3 {
                // The eigenbases are built for binary splits (their powers of ½).
                Route::Stencil { reason: Some(TERNARY.to_string()) }
            } else {
                let (nodes, surfaces) = (tree.nodes.len(), tree.surfaces.len());
                let node = tree.push_placeholder();
                match tree.build(scheme, stencil.patches(), 0, face, node) {
                    Ok(()) => match (&tree.nodes[node as usize], stencil.domain(face)?) {
                        (&Node::Patch { surface, frame }, FaceDomain::Quad | FaceDomain::Triangle) => {
                            tree.nodes.truncate(nodes);
                            Route::Patch { surface, frame }
                        }
                        (_, domain) => Route::Eigen { node, domain },
                    },
                    Err(reason) => {
                        tree.nodes.truncate(nodes);
                        tree.surfaces.truncate(surfaces);
                        Route::Stencil { reason: Some(reason) }
                    }
                }
            };
            routes.push(route);
        }
        Ok(Self { stencil, method, routes, nodes: tree.nodes, surfaces: tree.surfaces })
    }

    /// The method faces were prepared with.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The number of faces of the mesh.
    pub fn face_count(&self) -> usize {
        self.routes.len()
    }

    /// The exact stencil evaluator underneath (boundary faces, and [`Method::Stencil`]).
    pub fn stencil(&self) -> &LimitEvaluator {
        &self.stencil
    }

    /// Whether `face` is evaluated by eigenbasis; `Err` with the reason when it is evaluated
    /// by stencils instead (`None` for a hole).
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] (wrapped).
    pub fn uses_eigenbasis(&self, face: FaceId) -> Result<Result<(), Option<String>>, EvalError> {
        Ok(match self.route(face)? {
            Route::Patch { .. } | Route::Eigen { .. } => Ok(()),
            Route::Stencil { reason } => Err(Some(reason.clone().unwrap_or_else(|| "method stencil".to_string()))),
            Route::Hole => Err(None),
        })
    }

    fn route(&self, face: FaceId) -> Result<&Route, EvalError> {
        self.routes
            .get(face.index())
            .ok_or_else(|| StencilError::FaceOutOfRange { face: face.index(), faces: self.routes.len() }.into())
    }

    /// The limit point of `face` at `(u, v)` with first derivatives.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::OutsideFace`] (also for a non-finite
    /// parameter), [`StencilError::NoSurface`] for a hole (all wrapped);
    /// [`EvalError::FaceNotSupported`] for a face the eigenbasis does not take under
    /// [`Method::Eigen`]; as [`LimitEvaluator::eval`] for faces evaluated by stencils.
    #[inline]
    pub fn eval(&self, face: FaceId, u: f64, v: f64) -> Result<LimitPoint, EvalError> {
        match self.route(face)? {
            Route::Patch { surface, frame } => {
                let surface = &self.surfaces[*surface as usize];
                let domain = if surface.triangle() { FaceDomain::Triangle } else { FaceDomain::Quad };
                self.check(face, domain, u, v)?;
                let (s, t) = frame.patch_point(u, v);
                Ok(limit_point(surface.eval_unchecked(s, t), 1.0, frame.derivatives))
            }
            Route::Eigen { node, domain } => {
                self.check(face, *domain, u, v)?;
                let (surface, s, t, f, r) = self.descend(*node, *domain, u, v);
                let p = surface.eval_unchecked(s, t);
                Ok(limit_point(p, f, r))
            }
            Route::Stencil { reason } => self.by_stencil(face, reason, u, v),
            Route::Hole => Err(StencilError::NoSurface { face: face.index() }.into()),
        }
    }

    /// The limit point of `face` at `(u, v)` with first and second derivatives.
    ///
    /// # Errors
    /// As [`eval`](Self::eval); [`EvalError::NoSecondDerivatives`] for a face evaluated by
    /// stencils.
    pub fn eval_second(&self, face: FaceId, u: f64, v: f64) -> Result<LimitPoint2, EvalError> {
        let (surface, s, t, f, r) = match self.route(face)? {
            Route::Patch { surface, frame } => {
                let surface = &self.surfaces[*surface as usize];
                let domain = if surface.triangle() { FaceDomain::Triangle } else { FaceDomain::Quad };
                self.check(face, domain, u, v)?;
                let (s, t) = frame.patch_point(u, v);
                (surface, s, t, 1.0, frame.derivatives)
            }
            Route::Eigen { node, domain } => {
                self.check(face, *domain, u, v)?;
                self.descend(*node, *domain, u, v)
            }
            Route::Stencil { reason } => {
                // Input errors first, as eval would report them.
                self.by_stencil(face, reason, u, v)?;
                return Err(EvalError::NoSecondDerivatives {
                    face: face.index(),
                    reason: reason.clone().unwrap_or_else(|| "method stencil".to_string()),
                });
            }
            Route::Hole => return Err(StencilError::NoSurface { face: face.index() }.into()),
        };
        let PatchPoint2 { first, dss, dst, dtt } = surface.eval_second_unchecked(s, t);
        let g = f * f;
        let [a, b] = r;
        Ok(LimitPoint2 {
            first: limit_point(first, f, r),
            duu: g * (a[0] * a[0] * dss + 2.0 * a[0] * a[1] * dst + a[1] * a[1] * dtt),
            duv: g * (a[0] * b[0] * dss + (a[0] * b[1] + a[1] * b[0]) * dst + a[1] * b[1] * dtt),
            dvv: g * (b[0] * b[0] * dss + 2.0 * b[0] * b[1] * dst + b[1] * b[1] * dtt),
        })
    }

    fn by_stencil(&self, face: FaceId, reason: &Option<String>, u: f64, v: f64) -> Result<LimitPoint, EvalError> {
        if self.method == Method::Eigen {
            let domain = self.stencil.domain(face)?;
            self.check(face, domain, u, v)?;
            let reason = reason.clone().unwrap_or_default();
            return Err(EvalError::FaceNotSupported { face: face.index(), reason });
        }
        Ok(self.stencil.eval(face, u, v)?)
    }

    fn check(&self, face: FaceId, domain: FaceDomain, u: f64, v: f64) -> Result<(), EvalError> {
        if domain.contains_f64(u, v) {
            return Ok(());
        }
        Err(StencilError::OutsideFace {
            face: face.index(),
            u: format!("{u:?}"),
            v: format!("{v:?}"),
            domain: domain.describe(),
        }
        .into())
    }

    /// The patch surface holding the point, the point in its parameters, the scale of the
    /// descent's derivatives and the frame's derivative rows.
    #[inline(always)]
    fn descend(&self, node: u32, domain: FaceDomain, u: f64, v: f64) -> (&PatchSurface, f64, f64, f64, [[f64; 2]; 2]) {
        let (mut node, mut u, mut v, mut f, mut domain) = (node, u, v, 1.0, domain);
        // The frame of the patch whose sub-patches the point went into, if it did.
        let mut rows = None;
        loop {
            match &self.nodes[node as usize] {
                Node::Patch { surface, frame } => {
                    let (s, t) = frame.patch_point(u, v);
                    return (&self.surfaces[*surface as usize], s, t, f, rows.unwrap_or(frame.derivatives));
                }
                Node::SubPatches { frame, first, triangle } => {
                    (u, v) = frame.patch_point(u, v);
                    // Sub-patches' own frames are the identity: the first frame is the patch's.
                    rows.get_or_insert(frame.derivatives);
                    domain = if *triangle { FaceDomain::Triangle } else { FaceDomain::Quad };
                    let (child, cu, cv, factor) = domain.child_of_f64(u, v);
                    node = first + child as u32;
                    (u, v, f) = (cu, cv, f * factor);
                }
                Node::Children { first, triangle } => {
                    let (child, cu, cv, factor) = domain.child_of_f64(u, v);
                    node = first + child as u32;
                    (u, v, f) = (cu, cv, f * factor);
                    domain = if *triangle { FaceDomain::Triangle } else { FaceDomain::Quad };
                }
            }
        }
    }
}

/// A patch's frame in its face: the face's `(u, v)` is `origin + s·e1 + t·e2`; `to_patch` is
/// `[e1 e2]⁻¹`, `derivatives` the rows of `(∂/∂u, ∂/∂v)` over `(∂/∂s, ∂/∂t)`.
#[derive(Clone, Copy, Debug)]
struct Frame {
    origin: [f64; 2],
    to_patch: [[f64; 2]; 2],
    derivatives: [[f64; 2]; 2],
}

impl Frame {
    /// The patch's parameters are the face's.
    const IDENTITY: Self =
        Self { origin: [0.0, 0.0], to_patch: [[1.0, 0.0], [0.0, 1.0]], derivatives: [[1.0, 0.0], [0.0, 1.0]] };

    #[inline(always)]
    fn patch_point(self, u: f64, v: f64) -> (f64, f64) {
        let (x, y, m) = (u - self.origin[0], v - self.origin[1], &self.to_patch);
        (m[0][0] * x + m[0][1] * y, m[1][0] * x + m[1][1] * y)
    }
}

/// The nodes and surfaces of the faces being prepared.
#[derive(Default)]
struct Tree {
    nodes: Vec<Node>,
    surfaces: Vec<PatchSurface>,
    /// Per derived configuration's shape (by the matrices' address), its interior type's
    /// shape if it has one: asked once, not per face.
    interior: HashMap<(usize, usize), Option<InteriorShape>>,
    /// Whether a derived configuration's shape before its semi-sharp features are spent is
    /// evaluated through its sub-patches ([`Method::Eigen`]) or refused (to the stencils).
    descend_chains: bool,
}

/// An interior type's matrices and one of their shapes.
type InteriorShape = (Arc<PatchMatrices>, usize);

impl Tree {
    fn push_placeholder(&mut self) -> u32 {
        self.nodes.push(Node::Children { first: 0, triangle: false });
        (self.nodes.len() - 1) as u32
    }

    /// Fills node `slot` for `face` of `level`, and its children's, recursively.
    fn build(
        &mut self,
        scheme: &Scheme,
        levels: &PatchLevels,
        level: usize,
        face: FaceId,
        slot: u32,
    ) -> Result<(), String> {
        match levels.resolve(level, face) {
            None => Err(format!("level {level} face {face} was not prepared (internal)")),
            Some(Resolved::Hole) => Err("part of it is a hole".to_string()),
            Some(Resolved::Children { layout: Layout::DualBoundaryQuad { .. }, .. }) => {
                // Its pieces stretch one axis only: the stencils take it.
                Err("a dual split's boundary face, whose pieces stretch across it".to_string())
            }
            Some(Resolved::Children { children, layout: Layout::Domain(domain) }) => {
                let first = self.nodes.len() as u32;
                let triangle = domain == FaceDomain::Triangle;
                for _ in children.clone() {
                    self.push_placeholder();
                }
                self.nodes[slot as usize] = Node::Children { first, triangle };
                for (k, child) in children.enumerate() {
                    self.build(scheme, levels, level + 1, FaceId::new(child as u32), first + k as u32)?;
                }
                Ok(())
            }
            Some(Resolved::Patch { mesh, patch, frame }) => {
                let points: Vec<DVec3> = patch.vertices.iter().map(|&v| mesh.position(v)).collect();
                let at = |u: i64, v: i64| {
                    let p = frame.to_face(Dyadic::new(u, v, 1));
                    [p.u as f64, p.v as f64]
                };
                let (o, x, y) = (at(0, 0), at(1, 0), at(0, 1));
                let (e1, e2) = ([x[0] - o[0], x[1] - o[1]], [y[0] - o[0], y[1] - o[1]]);
                let det = e1[0] * e2[1] - e2[0] * e1[1];
                let to_patch = [[e2[1] / det, -e2[0] / det], [-e1[1] / det, e1[0] / det]];
                let frame = Frame { origin: o, to_patch, derivatives: frame.derivative_map() };
                self.build_shape(scheme, &patch.matrices, patch.shape, &points, frame, slot)
            }
        }
    }

    /// Fills node `slot` with the surface of `shape` of `matrices` over `points` in `frame`:
    /// its eigenbasis, or, for a derived configuration's shape before its semi-sharp features
    /// are spent (no eigenbasis, no child that keeps it), its sub-patches, recursively.
    fn build_shape(
        &mut self,
        scheme: &Scheme,
        matrices: &Arc<PatchMatrices>,
        shape: usize,
        points: &[DVec3],
        frame: Frame,
        slot: u32,
    ) -> Result<(), String> {
        let derived = matches!(matrices.patch_type, PatchType::Derived { .. });
        // A derived configuration's stationary shape takes its interior type's eigenbasis
        // (committed, or fitted once for every configuration that has the shape).
        let interior = derived.then(|| {
            let this = &matrices.shapes[shape];
            let key = (Arc::as_ptr(matrices) as usize, shape);
            let found = self.interior.entry(key);
            found.or_insert_with(|| PatchMatrices::interior_shape(scheme, &this.signature, this.size)).clone()
        });
        let basis = match interior.flatten() {
            Some((canonical, index)) => EigenBasis::of(&canonical, index),
            None => EigenBasis::of(matrices, shape),
        };
        match basis {
            Ok(basis) => {
                let surface = basis.surface(points).map_err(|e| e.to_string())?;
                self.nodes[slot as usize] = Node::Patch { surface: self.surfaces.len() as u32, frame };
                self.surfaces.push(surface);
                Ok(())
            }
            Err(_) if derived && !self.descend_chains => {
                Err("a derived configuration before its semi-sharp features are spent".to_string())
            }
            Err(_) if derived && matrices.keeping(shape).is_none() && !matrices.shapes[shape].children.is_empty() => {
                let children = &matrices.shapes[shape].children;
                let first = self.nodes.len() as u32;
                for _ in children {
                    self.push_placeholder();
                }
                let triangle = matrices.face_size == 3;
                self.nodes[slot as usize] = Node::SubPatches { frame, first, triangle };
                for (k, child) in children.iter().enumerate() {
                    let points = child.apply(points);
                    self.build_shape(scheme, matrices, child.shape, &points, Frame::IDENTITY, first + k as u32)?;
                }
                Ok(())
            }
            Err(e) => Err(e.to_string()),
        }
    }
}

/// The patch's point in the face's parameters: `(∂/∂u, ∂/∂v) = f · r · (∂/∂s, ∂/∂t)`.
#[inline(always)]
fn limit_point(p: PatchPoint, f: f64, r: [[f64; 2]; 2]) -> LimitPoint {
    LimitPoint {
        position: p.position,
        du: f * (r[0][0] * p.ds + r[0][1] * p.dt),
        dv: f * (r[1][0] * p.ds + r[1][1] * p.dt),
        exact_derivatives: p.exact_derivatives,
    }
}

/// Describes, for reports, how many faces each route takes.
impl std::fmt::Display for EigenEvaluator {
    fn fmt(&self, out: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let eigen = self.routes.iter().filter(|r| matches!(r, Route::Patch { .. } | Route::Eigen { .. })).count();
        let stencil = self.routes.iter().filter(|r| matches!(r, Route::Stencil { .. })).count();
        let mut s = String::new();
        let _ = write!(s, "{eigen} faces by eigenbasis, {stencil} by exact stencils ({} patches)", self.surfaces.len());
        out.write_str(&s)
    }
}
