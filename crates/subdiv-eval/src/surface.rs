//! The limit surface over one patch, with its per-face precomputation: power-basis
//! coefficients of the polynomial patch, or of the first levels of sub-patches around the
//! extraordinary vertex.

use std::sync::Arc;

use subdiv_mesh::DVec3;
use subdiv_stencil::StencilError;

use crate::EvalError;
use crate::basis::{DIRECT_LEVELS, EigenBasis, Extraordinary, Kind};
use crate::poly::{Lanes, PolyKind, eval1, eval1_lanes, eval2, eval2_lanes, lanes};

/// Levels of sub-patches around the extraordinary vertex whose coefficients each face keeps
/// (a uniformly random point lands deeper with probability `4^−8`); deeper ones are computed
/// per point.
pub const STORED_LEVELS: usize = 8;

/// The largest patch the per-point scratch holds: Catmull-Clark at valence 64, `2·64 + 8`.
pub(crate) const MAX_PATCH: usize = 2 * crate::MAX_VALENCE + 8;

/// A point of one patch's limit surface with its derivatives in the patch's `(s, t)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchPoint {
    /// The position.
    pub position: DVec3,
    /// ∂/∂s.
    pub ds: DVec3,
    /// ∂/∂t.
    pub dt: DVec3,
    /// `false` at the extraordinary vertex itself, where `ds` and `dt` are tangent directions
    /// (the limits of the directions of `∂/∂s` along the first side and `∂/∂t` along the
    /// last) whose cross product is the normal.
    pub exact_derivatives: bool,
}

/// A [`PatchPoint`] with second derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchPoint2 {
    /// Position and first derivatives.
    pub first: PatchPoint,
    /// ∂²/∂s².
    pub dss: DVec3,
    /// ∂²/∂s∂t.
    pub dst: DVec3,
    /// ∂²/∂t².
    pub dtt: DVec3,
}

/// The limit surface over one patch: [`EigenBasis::surface`] of its control points.
///
/// Regular patches keep the power-basis coefficients of their polynomial. Extraordinary ones
/// keep the limit position and tangent directions at the vertex and, for the first
/// [`STORED_LEVELS`] rings of sub-patches, the coefficients of each sub-patch's polynomial
/// less the limit position (so that derivatives scaled by `2^level` keep their relative
/// precision). A point at level `m` (the ring `2^−m < max(s, t) ≤ 2^{1−m}`; `s + t` for
/// triangles) and sub-patch `b` is one Horner evaluation; deeper rings are computed per
/// point: by iterating the keeping child's matrix up to [`DIRECT_LEVELS`], then from the kept
/// eigenvalues `λ_i^m` (paper 002 §3).
///
/// ```
/// use subdiv_eval::EigenBasis;
/// use subdiv_schemes::Builtin;
/// use subdiv_mesh::DVec3;
///
/// let basis = EigenBasis::interior(Builtin::CatmullClark.scheme(), 5)?;
/// // 2k + 8 control points; lift the vertex to see a bump.
/// let mut points: Vec<DVec3> = (0..basis.size()).map(|i| DVec3::new(i as f64, (i * i % 7) as f64, 0.0)).collect();
/// points[0].z = 1.0;
/// let surface = basis.surface(&points)?;
/// let p = surface.eval(0.25, 1e-9)?;
/// assert!(p.exact_derivatives && p.position.z > 0.0);
/// # Ok::<(), subdiv_eval::EvalError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PatchSurface {
    basis: Arc<EigenBasis>,
    data: Data,
}

// The regular variant is the common one and is kept inline on purpose (one load less per
// point); extraordinary faces are few.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Data {
    /// Inline, so that a face's coefficients are one load away from its surface.
    Regular([Lanes; 16]),
    Extraordinary(Box<ExtraordinarySurface>),
}

#[derive(Clone, Debug)]
struct ExtraordinarySurface {
    /// Per quadrant code of a first-ring point (`s ≥ ½`, `t ≥ ½` as bits): its child and map,
    /// copied from the basis so that locating a point reads nothing behind another pointer.
    steps: [Step; 4],
    /// Whether the domain is a triangle (the ring key is `s + t`, not `max(s, t)`).
    triangle: bool,
    limit: DVec3,
    tangents: [DVec3; 2],
    /// Coefficients less the limit, level `j < STORED_LEVELS`, child `b`: at `(3j + b)·n`.
    levels: Box<[Lanes]>,
    /// `A^STORED_LEVELS · (C − limit)`.
    deep_start: Box<[DVec3]>,
    /// `y_i · (C − limit)` per kept eigenvalue but 1, as (re, im).
    modes: Box<[(DVec3, DVec3)]>,
}

/// One entry of [`ExtraordinarySurface::steps`]: the child's parameters are
/// `sign · (2·(s, t) − offset)` ([`ChildDomain::to_child`](subdiv_schemes::ChildDomain::to_child)).
#[derive(Clone, Copy, Debug)]
struct Step {
    child: usize,
    offset: [f64; 2],
    sign: f64,
}

/// Where a point lies among the rings of sub-patches.
struct Located {
    level: usize,
    child: usize,
    /// The point in the child's parameters.
    u: f64,
    v: f64,
    /// `±1`: the middle triangle is turned.
    sign: f64,
}

/// The biased exponent field of `x` (0 for zero and subnormals, 1023 for `[1, 2)`).
#[inline(always)]
fn biased_exponent(x: f64) -> usize {
    ((x.to_bits() >> 52) & 0x7ff) as usize
}

/// `2^e` for `0 ≤ e ≤ 1023`, from its bits.
#[inline(always)]
fn pow2(e: usize) -> f64 {
    f64::from_bits(((1023 + e.min(1023)) as u64) << 52)
}

impl PatchSurface {
    pub(crate) fn new(basis: Arc<EigenBasis>, points: &[DVec3]) -> Self {
        let data = match &basis.kind {
            Kind::Regular => {
                let mut c = [[0.0; 4]; 16];
                for (slot, x) in c.iter_mut().zip(basis.power.coefficients(points)) {
                    *slot = lanes(x);
                }
                Data::Regular(c)
            }
            Kind::Extraordinary(e) => Data::Extraordinary(Box::new(ExtraordinarySurface::new(
                e,
                points,
                basis.power.kind == PolyKind::Quartic,
            ))),
        };
        Self { basis, data }
    }

    /// The eigenbasis it was built from.
    pub fn basis(&self) -> &Arc<EigenBasis> {
        &self.basis
    }

    /// The limit point at `(s, t)` of the patch's domain (`[0, 1]²`, or the triangle
    /// `s, t ≥ 0, s + t ≤ 1`), with first derivatives.
    ///
    /// # Errors
    /// [`StencilError::OutsideDomain`] (wrapped) for a point outside the domain or not finite.
    #[inline]
    pub fn eval(&self, s: f64, t: f64) -> Result<PatchPoint, EvalError> {
        self.check(s, t)?;
        Ok(self.eval_unchecked(s, t))
    }

    /// As [`eval`](Self::eval), with second derivatives (zero at the extraordinary vertex
    /// itself, where they do not exist).
    ///
    /// # Errors
    /// As [`eval`](Self::eval).
    #[inline]
    pub fn eval_second(&self, s: f64, t: f64) -> Result<PatchPoint2, EvalError> {
        self.check(s, t)?;
        Ok(self.eval_second_unchecked(s, t))
    }

    pub(crate) fn triangle(&self) -> bool {
        self.basis.power.kind == PolyKind::Quartic
    }

    #[inline]
    fn check(&self, s: f64, t: f64) -> Result<(), EvalError> {
        let inside = if self.triangle() {
            s >= 0.0 && t >= 0.0 && s + t <= 1.0
        } else {
            (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)
        };
        if inside {
            Ok(())
        } else {
            Err(StencilError::OutsideDomain {
                u: format!("{s:?}"),
                v: format!("{t:?}"),
                domain: if self.triangle() { "u, v ≥ 0, u + v ≤ 1" } else { "[0, 1]²" },
            }
            .into())
        }
    }

    /// [`eval`](Self::eval) for a point known to be in the domain.
    #[inline]
    pub(crate) fn eval_unchecked(&self, s: f64, t: f64) -> PatchPoint {
        let kind = self.basis.power.kind;
        match &self.data {
            Data::Regular(c) => {
                let [position, ds, dt] = eval1_lanes(kind, &c[..kind.monomials()], s, t);
                PatchPoint { position, ds, dt, exact_derivatives: true }
            }
            Data::Extraordinary(x) => {
                let Some(at) = x.locate(s, t) else {
                    return PatchPoint {
                        position: x.limit,
                        ds: x.tangents[0],
                        dt: x.tangents[1],
                        exact_derivatives: false,
                    };
                };
                let n = kind.monomials();
                if at.level < STORED_LEVELS {
                    let start = (3 * at.level + at.child) * n;
                    let [p, pu, pv] = eval1_lanes(kind, &x.levels[start..start + n], at.u, at.v);
                    let f = at.sign * pow2(at.level + 1);
                    return PatchPoint { position: x.limit + p, ds: f * pu, dt: f * pv, exact_derivatives: true };
                }
                let e = self.extraordinary();
                let mut c = [DVec3::ZERO; 16];
                if at.level < DIRECT_LEVELS {
                    x.iterated(e, at.level, at.child, &mut c[..n]);
                    let [p, pu, pv] = eval1(kind, &c[..n], at.u, at.v);
                    let f = at.sign * pow2(at.level + 1);
                    PatchPoint { position: x.limit + p, ds: f * pu, dt: f * pv, exact_derivatives: true }
                } else {
                    // (gλ)^m keeps each quantity in range: g = 1 positions, 2 first derivatives.
                    x.expanded(e, at.level, at.child, 1.0, &mut c[..n]);
                    let position = x.limit + eval1(kind, &c[..n], at.u, at.v)[0];
                    x.expanded(e, at.level, at.child, 2.0, &mut c[..n]);
                    let [_, pu, pv] = eval1(kind, &c[..n], at.u, at.v);
                    let f = 2.0 * at.sign;
                    PatchPoint { position, ds: f * pu, dt: f * pv, exact_derivatives: true }
                }
            }
        }
    }

    /// [`eval_second`](Self::eval_second) for a point known to be in the domain.
    pub(crate) fn eval_second_unchecked(&self, s: f64, t: f64) -> PatchPoint2 {
        let kind = self.basis.power.kind;
        let with = |p: [DVec3; 6], limit: DVec3, f: f64, g: f64| PatchPoint2 {
            first: PatchPoint { position: limit + p[0], ds: f * p[1], dt: f * p[2], exact_derivatives: true },
            dss: g * p[3],
            dst: g * p[4],
            dtt: g * p[5],
        };
        match &self.data {
            Data::Regular(c) => with(eval2_lanes(kind, &c[..kind.monomials()], s, t), DVec3::ZERO, 1.0, 1.0),
            Data::Extraordinary(x) => {
                let Some(at) = x.locate(s, t) else {
                    return PatchPoint2 {
                        first: self.eval_unchecked(s, t),
                        dss: DVec3::ZERO,
                        dst: DVec3::ZERO,
                        dtt: DVec3::ZERO,
                    };
                };
                let n = kind.monomials();
                let f = at.sign * pow2(at.level + 1);
                if at.level < STORED_LEVELS {
                    let start = (3 * at.level + at.child) * n;
                    return with(eval2_lanes(kind, &x.levels[start..start + n], at.u, at.v), x.limit, f, f * f);
                }
                let e = self.extraordinary();
                let mut c = [DVec3::ZERO; 16];
                if at.level < DIRECT_LEVELS {
                    x.iterated(e, at.level, at.child, &mut c[..n]);
                    with(eval2(kind, &c[..n], at.u, at.v), x.limit, f, f * f)
                } else {
                    let first = self.eval_unchecked(s, t);
                    x.expanded(e, at.level, at.child, 4.0, &mut c[..n]);
                    let p = eval2(kind, &c[..n], at.u, at.v);
                    PatchPoint2 { first, dss: 4.0 * p[3], dst: 4.0 * p[4], dtt: 4.0 * p[5] }
                }
            }
        }
    }

    fn extraordinary(&self) -> &Extraordinary {
        match &self.basis.kind {
            Kind::Extraordinary(e) => e,
            Kind::Regular => unreachable!("extraordinary data comes from an extraordinary basis"),
        }
    }
}

impl ExtraordinarySurface {
    /// The ring, sub-patch and child parameters of `(s, t)`; `None` at the vertex. The ring
    /// comes from the exponent of `max(s, t)` (quads) or `s + t` (triangles): scaled by
    /// `2^level` the point lies in the first ring, `[½, 1]`.
    #[inline(always)]
    fn locate(&self, s: f64, t: f64) -> Option<Located> {
        let key = if self.triangle { s + t } else { s.max(t) };
        if key <= 0.0 {
            return None;
        }
        let e = biased_exponent(key);
        if e <= 22 {
            return Some(self.locate_deep(s, t, key));
        }
        // `key · 2^level ∈ [½, 1]`: the level from the exponent alone. The quadrant test
        // `s · 2^level ≥ ½` is `s`'s exponent reaching `key`'s (capped at ½'s for level 0),
        // in integers, so that the table read does not wait for a multiplication.
        let level = 1022usize.saturating_sub(e);
        let floor = e.min(1022);
        let code = usize::from(biased_exponent(s) >= floor) | usize::from(biased_exponent(t) >= floor) << 1;
        // Exact: a power of two (level ≤ 1000), computed beside the table read.
        let scale = pow2(level + 1);
        let (s, t) = (s * scale, t * scale);
        let step = self.steps[code];
        Some(Located {
            level,
            child: step.child,
            u: step.sign * (s - step.offset[0]),
            v: step.sign * (t - step.offset[1]),
            sign: step.sign,
        })
    }

    /// [`locate`](Self::locate) for keys below `2^−1000` (subnormal ones included), scaled in
    /// steps that each stay exact.
    #[cold]
    fn locate_deep(&self, s: f64, t: f64, key: f64) -> Located {
        let level = match biased_exponent(key) {
            // Subnormal: scale into the normal range first.
            0 => 1022 + 64 - biased_exponent(key * pow2(64)),
            e => 1022 - e,
        };
        let (mut s, mut t) = (s, t);
        let mut rest = level;
        while rest > 0 {
            let step = rest.min(1000);
            (s, t) = (s * pow2(step), t * pow2(step));
            rest -= step;
        }
        let step = self.steps[usize::from(s >= 0.5) | usize::from(t >= 0.5) << 1];
        Located {
            level,
            child: step.child,
            u: step.sign * (2.0 * s - step.offset[0]),
            v: step.sign * (2.0 * t - step.offset[1]),
            sign: step.sign,
        }
    }

    fn new(e: &Extraordinary, points: &[DVec3], triangle: bool) -> Self {
        let size = points.len();
        let limit: DVec3 = e.limit.iter().zip(points).map(|(&w, &p)| w * p).sum();
        let apply = |w: &[f64]| -> DVec3 { w.iter().zip(points).map(|(&w, &p)| w * p).sum() };
        let tangents = [apply(&e.tangents[0]), apply(&e.tangents[1])];
        let mut d: Vec<DVec3> = points.iter().map(|&p| p - limit).collect();
        let modes = (0..e.eigenvalues.len())
            .map(|i| {
                let y = &e.left[i * size..(i + 1) * size];
                let re: DVec3 = y.iter().zip(&d).map(|(z, &p)| z.re * p).sum();
                let im: DVec3 = y.iter().zip(&d).map(|(z, &p)| z.im * p).sum();
                (re, im)
            })
            .collect();
        let n = e.children.first().map_or(0, |c| c.to_power.len() / size);
        let mut levels = Vec::with_capacity(STORED_LEVELS * 3 * n);
        for _ in 0..STORED_LEVELS {
            for child in &e.children {
                levels.extend(
                    child
                        .to_power
                        .chunks_exact(size)
                        .map(|row| lanes(row.iter().zip(&d).map(|(&w, &p)| w * p).sum::<DVec3>())),
                );
            }
            d = multiply(&e.a, &d);
        }
        let steps = e.lookup.map(|child| {
            let child = usize::from(child);
            let domain = e.children[child].domain;
            Step { child, offset: domain.offset.map(f64::from), sign: if domain.flipped { -1.0 } else { 1.0 } }
        });
        Self {
            steps,
            triangle,
            limit,
            tangents,
            levels: levels.into_boxed_slice(),
            deep_start: d.into_boxed_slice(),
            modes,
        }
    }

    /// The coefficients (less the limit) at `level` in `[STORED_LEVELS, DIRECT_LEVELS)`, by
    /// iterating `A` from the stored start.
    fn iterated(&self, e: &Extraordinary, level: usize, child: usize, out: &mut [DVec3]) {
        let size = self.deep_start.len();
        let (mut a, mut b) = ([DVec3::ZERO; MAX_PATCH], [DVec3::ZERO; MAX_PATCH]);
        a[..size].copy_from_slice(&self.deep_start);
        for _ in STORED_LEVELS..level {
            for (row, o) in e.a.chunks_exact(size).zip(&mut b[..size]) {
                *o = row.iter().zip(&a[..size]).map(|(&w, &p)| w * p).sum();
            }
            std::mem::swap(&mut a, &mut b);
        }
        for (row, o) in e.children[child].to_power.chunks_exact(size).zip(out) {
            *o = row.iter().zip(&a[..size]).map(|(&w, &p)| w * p).sum();
        }
    }

    /// The coefficients (less the limit) at `level ≥ DIRECT_LEVELS` times `gain^level`, from
    /// the kept eigenvalues: `Σ_i Re((B·M_b·x_i) · (gain·λ_i)^level · y_i·(C − limit))`.
    fn expanded(&self, e: &Extraordinary, level: usize, child: usize, gain: f64, out: &mut [DVec3]) {
        let r = e.eigenvalues.len();
        let modes = &e.children[child].modes;
        out.fill(DVec3::ZERO);
        for (i, (&lambda, &(are, aim))) in e.eigenvalues.iter().zip(self.modes.iter()).enumerate() {
            let scaled = crate::basis::Complex { re: gain * lambda.re, im: gain * lambda.im };
            let z = scaled.pow(level.min(u32::MAX as usize) as u32);
            // z · a, then each row's mode times that, real part.
            let (zre, zim) = (z.re * are - z.im * aim, z.re * aim + z.im * are);
            for (row, o) in out.iter_mut().enumerate() {
                let m = modes[row * r + i];
                *o += m.re * zre - m.im * zim;
            }
        }
    }
}

/// `A · d` for a row-major square `A`.
fn multiply(a: &[f64], d: &[DVec3]) -> Vec<DVec3> {
    a.chunks_exact(d.len()).map(|row| row.iter().zip(d).map(|(&w, &p)| w * p).sum()).collect()
}
