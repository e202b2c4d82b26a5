//! Surface stencils by periodic addresses (paper 003 §4–5 joined with paper 000): the stencil of
//! a rational point of a patch from the sub-patch matrices alone.

use std::borrow::Borrow;
use std::collections::HashMap;

use faer::Mat;
use subdiv_schemes::{PatchMatrices, SubPatch, dual_signature_has_boundary};

use crate::address::{MAX_ADDRESS_STEPS, Walk, Walked, check_domain, step, too_long, walk};
use crate::linalg::{eigenspace, normalised_left_eigenvectors};
use crate::ring::{ring_position, ring_tangents};
use crate::tangents::{face_probes, irregular_tangents};
use crate::{Dyadic, StencilError};

/// Weights over a patch's control points (in [`subdiv_mesh::Patch`] order) giving a point of
/// the limit surface and its two tangents.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceStencil {
    /// Position weights; they sum to 1.
    pub position: Vec<f64>,
    /// ∂/∂u weights; they sum to 0.
    pub du: Vec<f64>,
    /// ∂/∂v weights; they sum to 0.
    pub dv: Vec<f64>,
    /// Whether `du` and `dv` are the parameter derivatives. `false` at an extraordinary vertex
    /// itself, where the parameterization has no derivative: there they are tangent
    /// *directions*, along the face's first and last sides, whose cross product is the normal.
    pub exact_derivatives: bool,
}

impl SurfaceStencil {
    /// A position stencil with zero derivatives, marked inexact ([`StencilEvaluator`]'s
    /// positions-only stencils).
    fn position_only(position: Vec<f64>) -> Self {
        let zero = vec![0.0; position.len()];
        Self { position, du: zero.clone(), dv: zero, exact_derivatives: false }
    }
}

/// How close two eigenvalues, or an imaginary part or a determinant and zero, must be to count
/// as equal.
pub(crate) const TOLERANCE: f64 = 1e-9;

/// The stencil of `point` in the patch of shape `shape` of `matrices`.
///
/// The point's [`Address`](crate::Address) splits into a prefix σ and a period τ; the prefix is
/// lengthened by whole periods until the period maps a shape to itself. Then the position
/// stencil is the left eigenvector of the period's square matrix `M_τ` for eigenvalue 1
/// (normalised to sum 1), carried back through the prefix's matrices. The derivative stencils
/// are the left eigenvectors for `±s^−|τ|` (`s` the split's scale, 2 or 3:
/// [`PatchMatrices::scale`]), normalised on the linear functions `u` and `v` of the periodic
/// shape ([`PatchShape::parameters`](subdiv_schemes::PatchShape::parameters)),
/// times `±s^|σ|`. At a point that is its own extraordinary vertex (the period keeps an
/// irregular shape) the tangents come from the leading eigenvectors that the face sees instead
/// (see [`SurfaceStencil::exact_derivatives`]). Every eigenproblem is solved on the control
/// points that influence the face
/// ([`PatchShape::influence`](subdiv_schemes::PatchShape::influence)); the others get weight 0.
///
/// For many points of one patch, a [`StencilEvaluator`] shares the work between them.
///
/// ```
/// use subdiv_mesh::BoundaryInterpolation;
/// use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
/// use subdiv_stencil::{surface_stencil, Dyadic};
///
/// let cc = Builtin::CatmullClark.scheme();
/// let m = PatchMatrices::of(cc, PatchType::interior(5), BoundaryInterpolation::EdgeOnly)?;
/// // The extraordinary vertex itself: (k²·v + 4·Σ e + Σ f) / (k (k + 5)).
/// let s = surface_stencil(&m, 0, Dyadic::new(0, 0, 1))?;
/// assert!((s.position[0] - 25.0 / 50.0).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`StencilError::OutsideDomain`] for a point outside the face, [`StencilError::Shape`] for a
/// shape the matrices do not hold, [`StencilError::Eigen`] when an eigenvector the stencil
/// needs is not unique.
pub fn surface_stencil(matrices: &PatchMatrices, shape: usize, point: Dyadic) -> Result<SurfaceStencil, StencilError> {
    StencilEvaluator::new(matrices).stencil(shape, point).cloned()
}

/// Surface stencils of many points over one set of sub-patch matrices, sharing the work.
///
/// A point's address visits a sequence of (shape, point) states, each the point in a
/// sub-patch's own domain; the stencil of a state is the next state's times the sub-patch
/// matrix. The evaluator remembers the stencil of every state it has passed through, so a
/// point whose walk meets a known state costs one vector–matrix product per new state, and a
/// cycle of states costs one eigenvector, at its least state, carried round the rest. The
/// points of a grid `(i/n, j/n)` fall into few cycles, so a whole grid costs a few
/// eigenvectors. Every state's stencil is computed the same way whichever point reaches it
/// first, so results do not depend on the order points are asked in, to the last bit.
///
/// ```
/// use subdiv_mesh::BoundaryInterpolation;
/// use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
/// use subdiv_stencil::{Dyadic, StencilEvaluator};
///
/// let loop_ = Builtin::Loop.scheme();
/// let m = PatchMatrices::of(loop_, PatchType::interior(7), BoundaryInterpolation::EdgeOnly)?;
/// let mut evaluator = StencilEvaluator::new(m.clone()); // or `&*m`
/// // Any order gives the same bits.
/// let far = StencilEvaluator::new(&*m).stencil(0, Dyadic::new(2, 1, 5))?.clone();
/// for j in 0..=5 {
///     for i in 0..=5 - j {
///         let s = evaluator.stencil(0, Dyadic::new(i, j, 5))?;
///         assert!((s.position.iter().sum::<f64>() - 1.0).abs() < 1e-12);
///     }
/// }
/// assert_eq!(evaluator.stencil(0, Dyadic::new(2, 1, 5))?, &far);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct StencilEvaluator<M: Borrow<PatchMatrices>> {
    matrices: M,
    memo: HashMap<State, usize>,
    stencils: Vec<SurfaceStencil>,
    stats: EvaluatorStats,
    max_address_steps: usize,
    /// Whether only the position stencils are wanted (their derivatives left zero): the
    /// characteristic map's probes, whose own fixed points may be irregular too.
    positions_only: bool,
    /// Whether an extraordinary vertex's own cycle is solved on its ring's frequency blocks
    /// ([`RingSpectrum`](subdiv_schemes::RingSpectrum)) where they hold its terms; `false` solves every cycle densely (the
    /// tests' reference).
    ring_blocks: bool,
}

/// What a [`StencilEvaluator`] has solved so far: the sizes of the systems behind its stencils.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EvaluatorStats {
    /// (shape, point) states whose stencils it holds.
    pub states: usize,
    /// Eigenproblems solved, one per cycle of states.
    pub eigen_solves: usize,
    /// The largest eigenproblem: the control points of a cycle's shape (the unknowns of one
    /// left eigenvector).
    pub largest_system: usize,
}

/// A shape and a point of its domain in lowest terms, so that one point reached over two
/// denominators is one state. Ordered, so that a cycle of states has a least one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) struct State {
    pub(crate) shape: usize,
    pub(crate) point: Dyadic,
}

impl State {
    fn new(shape: usize, point: Dyadic) -> Self {
        Self { shape, point: point.reduced() }
    }
}

/// The address walk of `point` in the patch of shape `shape`: each state with the child taken
/// from it, until a state `known` accepts or a state repeats. The point must be in the domain
/// and the shape among the matrices'.
///
/// # Errors
/// [`StencilError::AddressTooLong`] past `limit` steps.
pub(crate) fn address_walk(
    matrices: &PatchMatrices,
    shape: usize,
    point: Dyadic,
    known: impl Fn(&State) -> bool,
    limit: usize,
) -> Result<Walk<State>, StencilError> {
    let next = |state: State| {
        let Dyadic { u, v, denominator: q } = state.point;
        let (child, u, v) = step(matrices.face_size, matrices.scale(), u, v, q);
        let shape = matrices.shapes[state.shape].children[usize::from(child)].shape;
        (child, State::new(shape, Dyadic::new(u, v, q)))
    };
    walk(State::new(shape, point), next, known, limit).map_err(|limit| too_long(point, limit))
}

/// [`StencilError::OutsideDomain`] or [`StencilError::Shape`] unless `point` and `shape` can be
/// walked.
pub(crate) fn check_request(matrices: &PatchMatrices, shape: usize, point: Dyadic) -> Result<(), StencilError> {
    check_domain(matrices.face_size, point)?;
    if shape >= matrices.shapes.len() {
        return Err(StencilError::Shape { scheme: matrices.scheme.clone(), shape, shapes: matrices.shapes.len() });
    }
    Ok(())
}

impl<M: Borrow<PatchMatrices>> StencilEvaluator<M> {
    /// An evaluator over `matrices` (borrowed, or shared through an `Arc`), remembering nothing
    /// yet.
    pub fn new(matrices: M) -> Self {
        Self {
            matrices,
            memo: HashMap::new(),
            stencils: Vec::new(),
            stats: EvaluatorStats::default(),
            max_address_steps: MAX_ADDRESS_STEPS,
            positions_only: false,
            ring_blocks: true,
        }
    }

    /// The same evaluator solving every cycle on its dense matrix: the reference that the
    /// ring's frequency blocks are tested against.
    #[cfg(test)]
    pub(crate) fn dense(mut self) -> Self {
        self.ring_blocks = false;
        self
    }

    /// The same evaluator computing positions only: the derivative stencils are left zero and
    /// marked inexact. A face's probes for the tangents at an irregular fixed point take it, so
    /// that a probe whose own fixed point is irregular (a corner on the boundary of a ternary
    /// patch) does not ask for tangents in turn.
    pub(crate) fn positions_only(mut self) -> Self {
        self.positions_only = true;
        self
    }

    /// The same evaluator, refusing points whose address walk passes `steps` levels
    /// ([`MAX_ADDRESS_STEPS`] by default) with [`StencilError::AddressTooLong`]. Each level of
    /// a point's period costs one matrix product in its eigenproblem.
    ///
    /// ```
    /// use subdiv_mesh::BoundaryInterpolation;
    /// use subdiv_schemes::{Builtin, PatchMatrices, PatchType};
    /// use subdiv_stencil::{Dyadic, StencilError, StencilEvaluator};
    ///
    /// let cc = Builtin::CatmullClark.scheme();
    /// let m = PatchMatrices::of(cc, PatchType::interior(4), BoundaryInterpolation::EdgeOnly)?;
    /// // 1/11 has a binary period of 10 levels.
    /// let mut short = StencilEvaluator::new(&*m).with_max_address_steps(8);
    /// assert!(matches!(short.stencil(0, Dyadic::new(1, 0, 11)), Err(StencilError::AddressTooLong { .. })));
    /// assert!(short.stencil(0, Dyadic::new(1, 0, 4)).is_ok());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    #[must_use]
    pub fn with_max_address_steps(mut self, steps: usize) -> Self {
        self.max_address_steps = steps;
        self
    }

    /// What it has solved so far.
    pub fn stats(&self) -> EvaluatorStats {
        EvaluatorStats { states: self.stencils.len(), ..self.stats }
    }

    /// The matrices it evaluates over.
    pub fn matrices(&self) -> &PatchMatrices {
        self.matrices.borrow()
    }

    /// The stencil of `point` in the patch of shape `shape`; see [`surface_stencil`].
    ///
    /// # Errors
    /// As [`surface_stencil`].
    pub fn stencil(&mut self, shape: usize, point: Dyadic) -> Result<&SurfaceStencil, StencilError> {
        check_request(self.matrices(), shape, point)?;
        let (walk, end) =
            address_walk(self.matrices(), shape, point, |s| self.memo.contains_key(s), self.max_address_steps)?;
        // The order in which the walk's states get their stencils, each from its successor's:
        // a cycle is solved at its least state (not where this walk entered it), so that a
        // state's stencil does not depend on which points were asked before.
        let order: Vec<usize> = match end {
            Walked::Known(_) => (0..walk.len()).rev().collect(),
            Walked::Cycle(first) => {
                let least = (first..walk.len()).min_by_key(|&i| walk[i].0).expect("a cycle has a state");
                let stencil = self.periodic(&[&walk[least..], &walk[first..least]].concat(), point)?;
                self.stats.eigen_solves += 1;
                self.stats.largest_system = self.stats.largest_system.max(stencil.position.len());
                self.remember(walk[least].0, stencil);
                (first..least).rev().chain((least + 1..walk.len()).rev()).chain((0..first).rev()).collect()
            }
        };
        let successor = |i: usize| match end {
            _ if i + 1 < walk.len() => walk[i + 1].0,
            Walked::Known(state) => state,
            Walked::Cycle(first) => walk[first].0,
        };
        for i in order {
            let (state, child) = walk[i];
            let stencil = self.back(&self.stencils[self.memo[&successor(i)]], state.shape, child);
            self.remember(state, stencil);
        }
        let first = walk.first().map_or_else(|| State::new(shape, point), |w| w.0);
        Ok(&self.stencils[self.memo[&first]])
    }

    fn remember(&mut self, state: State, stencil: SurfaceStencil) {
        self.stencils.push(stencil);
        self.memo.insert(state, self.stencils.len() - 1);
    }

    /// The stencil over `shape`'s control points from the stencil over its child `child`'s:
    /// `w ← w · A`; derivatives also times ±2, since `u' = ±(2u − o)`. Tangent directions (at
    /// an irregular fixed point, not derivatives) are carried the same way: a direction along
    /// which the surface is parameterized regularly (along a dual boundary, below a fixed point
    /// that an f64 parameter reaches after fifty levels) keeps its weights' size so, where
    /// unscaled they would halve at every level, and the rounding that feeds the position
    /// direction is taken out at each one, where it would double.
    fn back(&self, stencil: &SurfaceStencil, shape: usize, child: u8) -> SurfaceStencil {
        let parent = &self.matrices().shapes[shape];
        let sub = &parent.children[usize::from(child)];
        let derivative = |w: &[f64]| {
            if stencil.exact_derivatives { derivative_back(w, sub, &parent.influence) } else { direction_back(w, sub) }
        };
        SurfaceStencil {
            position: times(&stencil.position, sub, 1.0),
            du: derivative(&stencil.du),
            dv: derivative(&stencil.dv),
            exact_derivatives: stencil.exact_derivatives,
        }
    }

    /// The stencil at the first state of a cycle of states, from the eigenvectors of the
    /// cycle's composite matrix `M_τ`. They are solved on the control points that influence the
    /// face ([`PatchShape::influence`](subdiv_schemes::PatchShape::influence)): the others
    /// only add eigenvalues of their own (a bilinear face's points beyond its corners repeat ½,
    /// which made its eigenvectors not unique), and get weight 0.
    fn periodic(&self, cycle: &[(State, u8)], point: Dyadic) -> Result<SurfaceStencil, StencilError> {
        if let Some(stencil) = self.ring_periodic(cycle, point)? {
            return Ok(stencil);
        }
        let matrices = self.matrices();
        let periodic = &matrices.shapes[cycle[0].0.shape];
        let size = periodic.size;
        // M_τ, applied first to last.
        let mut m_tau = Mat::<f64>::identity(size, size);
        let mut steps = Vec::with_capacity(cycle.len());
        for &(state, c) in cycle {
            let parent = &matrices.shapes[state.shape];
            let child = &parent.children[usize::from(c)];
            let mut a = Mat::<f64>::zeros(child.rows(), child.columns());
            (0..child.rows()).for_each(|i| child.row(i).for_each(|(j, w)| a[(i, j)] = w));
            m_tau = &a * &m_tau;
            steps.push((child, parent.influence.as_slice()));
        }
        // Rows of influencing points read influencing points only, at every step, so this is
        // the cycle's matrix on them.
        let influence: Vec<usize> = periodic.influence.iter().map(|&k| k as usize).collect();
        let m = Mat::<f64>::from_fn(influence.len(), influence.len(), |i, j| m_tau[(influence[i], influence[j])]);
        let widen = |w: Vec<f64>| {
            let mut out = vec![0.0; size];
            influence.iter().zip(w).for_each(|(&k, x)| out[k] = x);
            out
        };
        let ones = vec![1.0; influence.len()];
        let fail = |detail: String| {
            eigen_error(matrices, format!("{detail} at {point:?} of a {:?} patch", matrices.patch_type))
        };
        let position = normalised_left_eigenvectors(&m, 1.0, std::slice::from_ref(&ones), &[vec![1.0]])
            .map_err(|detail| fail(format!("eigenvalue 1: {detail}")))?
            .vectors
            .remove(0);
        if self.positions_only {
            return Ok(SurfaceStencil::position_only(widen(position)));
        }
        let derivatives = match &periodic.parameters {
            Some([u, v]) => {
                periodic_derivatives(&steps, u, v).map_err(|detail| fail(format!("derivatives: {detail}")))?
            }
            None => None,
        };
        let stencil = match derivatives {
            Some((du, dv)) => SurfaceStencil { position: widen(position), du, dv, exact_derivatives: true },
            None => {
                let (probes, [su, sv]) = face_probes(matrices, cycle[0].0.shape, &influence, cycle[0].0.point)?;
                let (mut du, mut dv) = irregular_tangents(&m, &probes).map_err(fail)?;
                if dual_signature_has_boundary(&periodic.signature) {
                    // Along a dual boundary the side's own direction, free of the
                    // cross-boundary term (see `boundary_tangent`).
                    let [along_u, along_v] = boundary_tangent(&m, &position, &probes).map_err(fail)?;
                    du = along_u.unwrap_or(du);
                    dv = along_v.unwrap_or(dv);
                }
                let signed = |w: Vec<f64>, s: f64| widen(w.into_iter().map(|x| s * x).collect());
                SurfaceStencil {
                    position: widen(position),
                    du: signed(du, su),
                    dv: signed(dv, sv),
                    exact_derivatives: false,
                }
            }
        };
        Ok(stencil)
    }
}

impl<M: Borrow<PatchMatrices>> StencilEvaluator<M> {
    /// The stencil at an extraordinary vertex whose cycle is its own child's (one step that
    /// keeps the shape and corner 0), from the ring's frequency blocks
    /// ([`PatchMatrices::ring_spectrum`]): the position and the tangent directions that
    /// [`periodic`](Self::periodic) finds on the dense matrix, in `O(N)`. `None` where the blocks
    /// do not hold the answer (no ring; 1 not simple; a leading eigenvalue that is defective or
    /// the rest's), for the dense route.
    fn ring_periodic(&self, cycle: &[(State, u8)], point: Dyadic) -> Result<Option<SurfaceStencil>, StencilError> {
        let matrices = self.matrices();
        let &[(state, child)] = cycle else { return Ok(None) };
        let periodic = &matrices.shapes[state.shape];
        let sub = &periodic.children[usize::from(child)];
        if !self.ring_blocks || sub.domain.offset != [0, 0] || sub.domain.flipped {
            return Ok(None);
        }
        let Some(ring) = matrices.ring_spectrum(state.shape) else { return Ok(None) };
        let Some(position) = ring_position(&ring) else { return Ok(None) };
        let influence: Vec<usize> = periodic.influence.iter().map(|&k| k as usize).collect();
        let widen = |w: Vec<f64>| {
            let mut out = vec![0.0; periodic.size];
            influence.iter().zip(w).for_each(|(&k, x)| out[k] = x);
            out
        };
        if self.positions_only {
            return Ok(Some(SurfaceStencil::position_only(widen(position))));
        }
        let fail = |detail: String| {
            eigen_error(matrices, format!("{detail} at {point:?} of a {:?} patch", matrices.patch_type))
        };
        // The derivative pair first, as on the dense route (its iteration reads the sparse rows).
        if let Some([u, v]) = &periodic.parameters {
            let steps = [(sub, periodic.influence.as_slice())];
            if let Some((du, dv)) =
                periodic_derivatives(&steps, u, v).map_err(|detail| fail(format!("derivatives: {detail}")))?
            {
                return Ok(Some(SurfaceStencil { position: widen(position), du, dv, exact_derivatives: true }));
            }
        }
        let (probes, [su, sv]) = face_probes(matrices, state.shape, &influence, state.point)?;
        let Some((du, dv)) = ring_tangents(&ring, &probes).map_err(fail)? else { return Ok(None) };
        let signed = |w: Vec<f64>, s: f64| widen(w.into_iter().map(|x| s * x).collect());
        Ok(Some(SurfaceStencil {
            position: widen(position),
            du: signed(du, su),
            dv: signed(dv, sv),
            exact_derivatives: false,
        }))
    }
}

/// `(∂/∂u, ∂/∂v)` stencils.
pub(crate) type Derivatives = (Vec<f64>, Vec<f64>);

/// At a fixed point on the boundary side of a dual boundary shape, the tangent of the boundary
/// curve toward each of the first two `probes` that lies on that curve (`None` for the
/// other): the points that the position stencils of the fixed point (`position`) and of the
/// probe read are the curve's, which the cycle's matrix `m` maps onto themselves (the curve's
/// matrix); its left eigenvector for its largest eigenvalue below 1, pointed toward the probe.
///
/// The directions that the characteristic map gives mix in a little of the cross-boundary
/// term (rounding, 1e-11), and carried up the levels of a deep point's address (an f64
/// parameter's fifty) that term grows by 3/2 a level against the boundary's own (Doo-Sabin's
/// ¾ across against ½ along) until it swamps it; this one lives on the boundary's points only,
/// and so do its images on every level above.
fn boundary_tangent(m: &Mat<f64>, position: &[f64], probes: &[Vec<f64>]) -> Result<[Option<Vec<f64>>; 2], String> {
    let n = m.nrows();
    let support = |w: &[f64]| {
        let size = w.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        (0..n).map(|j| w[j].abs() > 1e-12 * size).collect::<Vec<bool>>()
    };
    let at = support(position);
    let toward = |probe: &Vec<f64>| -> Result<Option<Vec<f64>>, String> {
        let member: Vec<bool> = at.iter().zip(support(probe)).map(|(&a, b)| a || b).collect();
        let on: Vec<usize> = (0..n).filter(|&j| member[j]).collect();
        // The curve's points map onto themselves; a probe inside the face reads others.
        let closed = on.iter().all(|&i| (0..n).all(|j| member[j] || m[(i, j)].abs() <= 1e-12));
        if on.len() < 2 || on.len() == n || !closed {
            return Ok(None);
        }
        let curve = Mat::<f64>::from_fn(on.len(), on.len(), |i, j| m[(on[i], on[j])]);
        let values = curve.eigenvalues().map_err(|e| format!("boundary curve eigenvalues: {e:?}"))?;
        let lambda = values
            .iter()
            .filter(|z| z.im.abs() < TOLERANCE && (z.re - 1.0).abs() > TOLERANCE)
            .map(|z| z.re)
            .fold(f64::NEG_INFINITY, f64::max);
        if !lambda.is_finite() {
            return Err("the boundary curve's matrix has no real eigenvalue below 1".into());
        }
        let (Some(left), Some(right)) =
            (eigenspace(&curve, lambda, true)?.pop(), eigenspace(&curve, lambda, false)?.pop())
        else {
            return Err("the boundary curve's tangent eigenvector is missing".into());
        };
        // The probe's coordinate on the term (the left vector dual to the right one): positive
        // where the curve runs toward it.
        let dual: f64 = left.iter().zip(&right).map(|(l, r)| l * r).sum();
        let view: f64 = on.iter().zip(&right).map(|(&i, r)| probe[i] * r).sum();
        let sign = if view * dual < 0.0 { -1.0 } else { 1.0 };
        let mut out = vec![0.0; n];
        on.iter().zip(&left).for_each(|(&i, l)| out[i] = sign * l);
        Ok(Some(out))
    };
    let first = probes.first().map(&toward).transpose()?.flatten();
    let second = probes.get(1).map(&toward).transpose()?.flatten();
    Ok([first, second])
}

/// `scale · w · A`: a stencil over a sub-patch's control points carried to its parent's.
fn times(w: &[f64], sub: &SubPatch, scale: f64) -> Vec<f64> {
    let mut out = vec![0.0; sub.columns()];
    for (r, &x) in w.iter().enumerate() {
        let x = x * scale;
        // The dense product's terms but its zeros (`x · 0` adds nothing but a zero's sign).
        for (c, a) in sub.row(r) {
            out[c] += x * a;
        }
    }
    out
}

/// A derivative stencil carried to the parent: `±2 w·A` (`u' = ±(2u − o)`), kept on the
/// parent's `influence` and put back on the vectors there that sum to zero. Rounding must not
/// feed the position direction, which every step doubles: across a cycle of `k` steps it would
/// grow `2^k`-fold; nor the points that do not influence the face, whose own eigenvalues the
/// iteration would pick up.
fn derivative_back(w: &[f64], sub: &SubPatch, influence: &[u32]) -> Vec<f64> {
    let full = scaled_back(w, sub);
    let mut out = vec![0.0; full.len()];
    influence.iter().for_each(|&k| out[k as usize] = full[k as usize]);
    let mean = out.iter().sum::<f64>() / influence.len() as f64;
    influence.iter().for_each(|&k| out[k as usize] -= mean);
    out
}

/// `±s w·A`: a derivative stencil carried to the parent by the step's scale `s` (`u' = ±(s u − o)`).
fn scaled_back(w: &[f64], sub: &SubPatch) -> Vec<f64> {
    let scale = f64::from(sub.domain.scale);
    times(w, sub, if sub.domain.flipped { -scale } else { scale })
}

/// A tangent direction carried to the parent as a derivative is ([`derivative_back`]), but
/// put back on the vectors that sum to zero over its own points only: a direction along a
/// dual boundary reads the boundary's points alone, and a share of the rounding spread over
/// the face's other points would grow there, by the cross-boundary term's 3/2 a level.
fn direction_back(w: &[f64], sub: &SubPatch) -> Vec<f64> {
    let mut out = scaled_back(w, sub);
    let points = out.iter().filter(|x| **x != 0.0).count().max(1);
    let mean = out.iter().sum::<f64>() / points as f64;
    out.iter_mut().filter(|x| **x != 0.0).for_each(|x| *x -= mean);
    out
}

/// The derivative stencils over a periodic shape: the left eigenvectors of `M_τ` for
/// `±2^−|τ|`, normalised on the linear functions `u` and `v` of the shape, found without
/// forming `M_τ`'s tiny eigenvalue (an SVD of `M_τ ∓ 2^−|τ|` loses `|τ|` bits). On the vectors
/// that sum to zero (which `w ↦ w·M_τ` keeps, as `M_τ` maps constants to constants) the map
/// `w ↦ ±2^|τ| w·M_τ`, applied one sub-patch matrix at a time as `w ← ±2 w·A`, has the
/// derivative pair as its eigenvalue 1; where the surface has parameter derivatives that pair
/// dominates, so a few rounds converge and each step is well conditioned.
///
/// `steps` are the cycle's sub-patches, each with its parent's
/// [`influence`](subdiv_schemes::PatchShape::influence); the iteration stays on those points.
///
/// `None` where the pair does not dominate: at an extraordinary vertex whose subdominant
/// eigenvalue exceeds the pair's (Catmull-Clark at valence 8, where ½ is also an eigenvalue, so
/// the matrices reproduce linear functions, but the 0.61 of the characteristic map wins) the
/// iteration grows, and the parameterization has no derivative there.
pub(crate) fn periodic_derivatives(
    steps: &[(&SubPatch, &[u32])],
    u: &[f64],
    v: &[f64],
) -> Result<Option<Derivatives>, String> {
    let size = u.len();
    let influence = steps[0].1;
    // w·M_τ with M_τ = A_last ⋯ A_first: the last step first.
    let round = |w: &[f64]| -> Vec<f64> {
        steps.iter().rev().fold(w.to_vec(), |w, &(child, influence)| derivative_back(&w, child, influence))
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let rounds = 64 / steps.len() + 2;
    // Two starting vectors with components on both derivatives: the linear functions,
    // centred (the stencils reproduce them, so they are far from orthogonal to the pair).
    let centre = |p: &[f64]| {
        let mean = influence.iter().map(|&k| p[k as usize]).sum::<f64>() / influence.len() as f64;
        let mut out = vec![0.0; size];
        influence.iter().for_each(|&k| out[k as usize] = p[k as usize] - mean);
        out
    };
    let mut basis = [centre(u), centre(v)];
    for w in &mut basis {
        // The growth of the last round: the dominant eigenvalue's modulus, 1 for the pair.
        let mut growth = 0.0;
        for _ in 0..rounds {
            let next = round(w);
            growth = next.iter().map(|x| x.abs()).fold(0.0, f64::max);
            if growth == 0.0 {
                return Err("the iteration vanished".into());
            }
            *w = next.iter().map(|x| x / growth).collect();
        }
        if growth > 1.0 + 1e-6 {
            return Ok(None);
        }
    }
    // du = α w₁ + β w₂ with du·u = 1, du·v = 0; dv likewise.
    let g = [[dot(&basis[0], u), dot(&basis[1], u)], [dot(&basis[0], v), dot(&basis[1], v)]];
    let det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
    if det.abs() < TOLERANCE {
        return Err("the derivative eigenvectors do not span the linear functions".into());
    }
    let combine = |t: [f64; 2]| -> Vec<f64> {
        let alpha = (g[1][1] * t[0] - g[0][1] * t[1]) / det;
        let beta = (g[0][0] * t[1] - g[1][0] * t[0]) / det;
        (0..size).map(|i| alpha * basis[0][i] + beta * basis[1][i]).collect()
    };
    let (du, dv) = (combine([1.0, 0.0]), combine([0.0, 1.0]));
    for w in [&du, &dv] {
        let residual = round(w).iter().zip(w).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        if residual > 1e-9 * w.iter().map(|x| x.abs()).fold(1.0, f64::max) {
            return Err(format!("the derivative iteration did not converge (residual {residual:e})"));
        }
    }
    Ok(Some((du, dv)))
}

fn eigen_error(matrices: &PatchMatrices, detail: String) -> StencilError {
    StencilError::Eigen { scheme: matrices.scheme.clone(), detail }
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::BoundaryInterpolation;
    use subdiv_schemes::{Builtin, PatchType, Split};

    use super::*;

    /// The largest difference of two stencils' weights, relative to the largest weight.
    fn apart(a: &[f64], b: &[f64]) -> f64 {
        let size = a.iter().chain(b).fold(0.0f64, |m, x| m.max(x.abs()));
        a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max) / size
    }

    /// At the extraordinary vertex of every smooth interior type of the binary splits
    /// (Catmull-Clark and Loop at valences 2 to 64, the others to 12), the ring's frequency
    /// blocks give the dense eigenproblems' stencil: the position, and the tangent directions
    /// (whose scale is the dense route's too: the same dual vectors, made of other bases).
    #[test]
    fn the_ring_blocks_give_the_dense_stencils() {
        let vertex = Dyadic::new(0, 0, 1);
        for builtin in Builtin::ALL {
            let scheme = builtin.scheme();
            if !matches!(scheme.split(), Split::Quad | Split::Triangle) {
                continue;
            }
            let top = if matches!(builtin, Builtin::CatmullClark | Builtin::Loop) { 64 } else { 12 };
            let mut solved = 0;
            for valence in (2..=top).filter(|&v| v != scheme.regular_valence()) {
                let Ok(m) = PatchMatrices::of(scheme, PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)
                else {
                    continue;
                };
                let what = format!("{builtin} at valence {valence}");
                let ring = StencilEvaluator::new(&*m);
                let by_blocks = ring.ring_periodic(&[(State::new(0, vertex), 0)], vertex).unwrap();
                let Some(by_blocks) = by_blocks else {
                    // The smooth schemes' blocks answer at every valence but 2.
                    let smooth = matches!(builtin, Builtin::CatmullClark | Builtin::Loop);
                    assert!(!smooth || valence == 2, "{what}: the blocks gave no answer");
                    continue;
                };
                solved += 1;
                let dense = StencilEvaluator::new(&*m).dense().stencil(0, vertex).unwrap().clone();
                assert_eq!(by_blocks.exact_derivatives, dense.exact_derivatives, "{what}");
                assert!(apart(&by_blocks.position, &dense.position) < 1e-12, "{what}: position");
                assert!(apart(&by_blocks.du, &dense.du) < 1e-9, "{what}: du {:e}", apart(&by_blocks.du, &dense.du));
                assert!(apart(&by_blocks.dv, &dense.dv) < 1e-9, "{what}: dv {:e}", apart(&by_blocks.dv, &dense.dv));
                // The evaluator takes the blocks' answer.
                assert_eq!(StencilEvaluator::new(&*m).stencil(0, vertex).unwrap(), &by_blocks, "{what}");
            }
            // Bilinear's influence is the face's corners: a ring at valence 2 only.
            assert!(solved > 0, "{builtin}: the blocks solved no valence");
        }
    }
}
