//! The quadtree's budget predicted before the work: a lower bound on its leaves.
//!
//! The tree splits every node that is not flat. A regular (bicubic) node is flat only if each
//! side's chord bound, `h² max‖S''‖ / 8` along the side, is within `ε`
//! ([`flatness::regular_is_flat`] requires it), so a tree split exactly where that necessary
//! condition fails is refined by the real one: its leaves are a lower bound on the real
//! leaves, and when they pass the limit the real tessellation would too. Such a node costs
//! the second derivatives at five points, against a Bézier split, four flatness tests and later
//! the vertices' evaluation for a real one. Pieces that are not regular (faces without a patch,
//! extraordinary corners) are split as the real build splits them: their chains are linear in
//! the depth. A quartic (Loop) node is flat only if each side's chord bound is within `ε`
//! ([`flatness::quartic_is_flat`]), and that bound is at least the side's distance from its chord
//! at the side's middle: the same tree over triangles, split where a middle strays further.
//! A non-polynomial (linear) piece is flat only if its surface lies within `ε/2` of an affine
//! map ([`flatness::linear_is_flat`] bounds that distance by twice its control points'), so a
//! side's middle lies within `ε` of its chord's: the tree splits where a middle strays further,
//! from the shape's position stencils at the node's corners and sides' middles (square pieces;
//! triangles count one leaf each, a weak bound). The count stops once it passes the limit, so a refusal costs about a tree of the
//! limit's size in cheap nodes, not the tessellation.
//!
//! A screen-space bound gives each node its own `ε` from the hull of its control points: the
//! nearest depth and the widest angle off the axis ([`ScreenBound::epsilon`]). A node's corners
//! (and a triangle's sides' middles) lie in its hull, so their depth is no nearer and their angle no wider: the `ε` they
//! give is at least the build's, a node the build finds flat is flat here too, and the count
//! stays a lower bound. (A node whose points are all behind the near plane counts one leaf.)

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;

use subdiv_stencil::Dyadic;

use super::{Budget, Piece, QuadtreeOptions, QuadtreeTessellator, Root, ShapeKind};
use crate::TessError;
use crate::bezier::{Bicubic, bernstein3};
use crate::quartic::Quartic;
use crate::rates::ScreenBound;

impl QuadtreeTessellator {
    /// A lower bound on the polygons (leaves) that [`tessellate`](Self::tessellate) with
    /// `options` outputs, found before the work and in a small part of its time (see the module
    /// docs), counted until it passes [`QuadtreeOptions::max_polygons`]: the tessellation
    /// refuses the options at once when it does (screen-space bounds included: see the module
    /// docs).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::{QuadtreeOptions, QuadtreeTessellator, Tolerance};
    ///
    /// let cube = Mesh::build(shapes::cube())?;
    /// let tess = QuadtreeTessellator::new(Builtin::CatmullClark.scheme(), &cube)?;
    /// let options = QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-4));
    /// let at_least = tess.polygons_at_least(&options)?;
    /// let mesh = tess.tessellate(&options)?;
    /// assert!(at_least <= mesh.polygon_count() && 10 * at_least >= 9 * mesh.polygon_count());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// [`TessError::Tolerance`] for a tolerance that is not positive and finite, the screen
    /// bound's errors, and errors of the pieces' derivation.
    pub fn polygons_at_least(&self, options: &QuadtreeOptions) -> Result<usize, TessError> {
        let epsilon = options.tolerance.absolute(self.diagonal)?;
        let screen = options.screen.as_ref().map(crate::rates::ScreenError::bound).transpose()?;
        let max_depth = options.max_depth.min(super::DEPTH_LIMIT);
        let count = AtomicUsize::new(0);
        crate::par::try_map(options.parallelism.forks(), &self.roots, |&root| {
            let max_depth = max_depth.saturating_sub(root.depth());
            let budget = Budget { epsilon, screen, max_depth, count: &count, options };
            self.count_leaves(root, self.root_piece(root)?, 0, &budget)
        })?;
        Ok(count.load(Ordering::Relaxed))
    }

    /// Adds to `budget.count` a lower bound on the leaves of `piece`, a node at `depth`.
    fn count_leaves(&self, root: Root, piece: Piece, depth: u32, budget: &Budget<'_>) -> Result<(), TessError> {
        let limit = budget.options.max_polygons;
        if budget.count.load(Ordering::Relaxed) > limit {
            return Ok(());
        }
        match &piece {
            Piece::Regular(b) => {
                let levels = budget.max_depth.saturating_sub(depth);
                let epsilon = Epsilon { fixed: budget.epsilon, screen: budget.screen.as_ref() };
                SecondDerivatives::of(b).count_leaves(b, epsilon, levels, budget.count, limit);
                return Ok(());
            }
            Piece::Quartic(q) => {
                let levels = budget.max_depth.saturating_sub(depth);
                let epsilon = Epsilon { fixed: budget.epsilon, screen: budget.screen.as_ref() };
                quartic_leaves(q, epsilon, levels, budget.count, limit);
                return Ok(());
            }
            Piece::Linear { matrices, shape, points, frame } => {
                let key = (std::sync::Arc::as_ptr(matrices) as usize, *shape);
                let Some(ShapeKind::Linear { sides: Some(sides) }) = self.shapes.get(&key) else {
                    budget.count.fetch_add(1, Ordering::Relaxed);
                    return Ok(());
                };
                // The surface at the node's point (i/2, j/2), through the frame.
                let at = |i: i64, j: i64| -> DVec3 {
                    let p = frame.to_patch(Dyadic::new(i, j, 2));
                    let w = &sides[p.v as usize][p.u as usize];
                    w.iter().zip(points).map(|(&w, &p)| w * p).sum()
                };
                let corners = [at(0, 0), at(2, 0), at(2, 2), at(0, 2)];
                let middles = [at(1, 0), at(2, 1), at(1, 2), at(0, 1)];
                let epsilon = Epsilon { fixed: budget.epsilon, screen: budget.screen.as_ref() }.of(&corners);
                let bent = epsilon.is_some_and(|e| {
                    (0..4).any(|k| (middles[k] - (corners[k] + corners[(k + 1) % 4]) / 2.0).length() > e)
                });
                if !bent || depth >= budget.max_depth {
                    budget.count.fetch_add(1, Ordering::Relaxed);
                    return Ok(());
                }
            }
            Piece::Face { .. } | Piece::Extraordinary { .. } => {}
        }
        let flat = matches!(piece, Piece::Face { .. } | Piece::Extraordinary { .. }) && self.flatness(&piece, budget).0;
        if flat || depth >= budget.max_depth {
            budget.count.fetch_add(1, Ordering::Relaxed);
            return Ok(());
        }
        for &domain in root.child_domains() {
            self.count_leaves(root, self.child(root, &piece, domain)?, depth + 1, budget)?;
        }
        Ok(())
    }
}

/// The `ε` a node of the prediction is measured against: the tolerance's, or a screen bound's
/// from points of the node's surface (at least the build's, from its hull; `None`: all behind
/// the near plane, a leaf).
#[derive(Clone, Copy)]
struct Epsilon<'a> {
    fixed: f64,
    screen: Option<&'a ScreenBound>,
}

impl Epsilon<'_> {
    fn of(self, points: &[DVec3]) -> Option<f64> {
        match self.screen {
            None => Some(self.fixed),
            Some(screen) => screen.epsilon(points),
        }
    }
}

/// A bicubic's second derivatives along its two directions in Bézier form: `∂²/∂x²` of degree
/// (1, 3), `xx[j][i]`, and `∂²/∂y²` of degree (3, 1), `yy[j][i]`.
struct SecondDerivatives {
    xx: [[DVec3; 2]; 4],
    yy: [[DVec3; 4]; 2],
}

impl SecondDerivatives {
    fn of(patch: &Bicubic) -> Self {
        let n = &patch.net;
        Self {
            xx: std::array::from_fn(|j| std::array::from_fn(|i| 6.0 * (n[j][i] - 2.0 * n[j][i + 1] + n[j][i + 2]))),
            yy: std::array::from_fn(|j| std::array::from_fn(|i| 6.0 * (n[j][i] - 2.0 * n[j + 1][i] + n[j + 2][i]))),
        }
    }

    /// `max(‖∂²S/∂x²‖, ‖∂²S/∂y²‖)` at `(x, y)`.
    fn largest(&self, x: f64, y: f64) -> f64 {
        let (bx, by) = (bernstein3(x), bernstein3(y));
        let (lx, ly) = ([1.0 - x, x], [1.0 - y, y]);
        let mut xx = DVec3::ZERO;
        let mut yy = DVec3::ZERO;
        for j in 0..4 {
            for i in 0..2 {
                xx += lx[i] * by[j] * self.xx[j][i];
                yy += bx[j] * ly[i] * self.yy[i][j];
            }
        }
        xx.length().max(yy.length())
    }

    /// Adds to `count` the leaves of the tree over the unit square split wherever a node of
    /// side `h` has `h² · max over its corners / 8 > ε` (a side's chord bound past `ε`: then it
    /// is not flat), at most `levels` deep, stopping once `count` passes `limit`. `patch` is the
    /// bicubic, whose points give a screen bound's `ε` per node.
    fn count_leaves(&self, patch: &Bicubic, epsilon: Epsilon<'_>, levels: u32, count: &AtomicUsize, limit: usize) {
        // A node: depth, corner 0, and per corner the largest second derivative and (for a
        // screen bound) the point; a split node's sides' middles and centre are its children's
        // corners, so each is evaluated once.
        let screen = epsilon.screen.is_some();
        let at = |x: f64, y: f64| (self.largest(x, y), if screen { patch.eval(x, y) } else { DVec3::ZERO });
        let corners = [at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)];
        let mut stack = vec![(0u32, 0.0, 0.0, corners)];
        let mut leaves = Leaves { count, limit, local: 0 };
        while let Some((depth, x, y, c)) = stack.pop() {
            let h = 0.5f64.powi(depth as i32);
            let largest = c.iter().map(|c| c.0).fold(0.0, f64::max);
            let e = if screen { epsilon.of(&c.map(|c| c.1)) } else { Some(epsilon.fixed) };
            if depth >= levels || e.is_none_or(|e| h * h * largest / 8.0 <= e) {
                if !leaves.add() {
                    return;
                }
                continue;
            }
            let (m, x1, y1) = (h / 2.0, x + h, y + h);
            let (xm, ym) = (x + m, y + m);
            let [c0, c1, c2, c3] = c;
            let (bottom, right, top, left) = (at(xm, y), at(x1, ym), at(xm, y1), at(x, ym));
            let centre = at(xm, ym);
            stack.push((depth + 1, x, y, [c0, bottom, centre, left]));
            stack.push((depth + 1, xm, y, [bottom, c1, right, centre]));
            stack.push((depth + 1, xm, ym, [centre, right, c2, top]));
            stack.push((depth + 1, x, ym, [left, centre, top, c3]));
        }
    }
}

/// [`SecondDerivatives::count_leaves`] for a quartic triangle, split as the quadtree splits
/// triangles (four children, the middle one turned half a turn), wherever a side's middle lies
/// further than `epsilon` from its chord's middle: the quartic chord bound is at least the side's
/// largest distance from its chord (it bounds that distance by Bézier coefficients).
fn quartic_leaves(q: &Quartic, epsilon: Epsilon<'_>, levels: u32, count: &AtomicUsize, limit: usize) {
    let q = PowerForm::of(q);
    // A node: depth, corner 0, turned or not, and its corners' points; its sides' middles are its
    // children's corners (in `ChildDomain::of_face(3)`'s order), so each is evaluated once.
    let top = [q.eval(0.0, 0.0), q.eval(1.0, 0.0), q.eval(0.0, 1.0)];
    let mut stack = vec![(0u32, 0.0f64, 0.0f64, false, top)];
    let mut leaves = Leaves { count, limit, local: 0 };
    while let Some((depth, x, y, flipped, [c0, c1, c2])) = stack.pop() {
        let h = 0.5f64.powi(depth as i32);
        let g = if flipped { -h } else { h };
        let half = g / 2.0;
        let (m01, m12, m20) = (q.eval(x + half, y), q.eval(x + half, y + half), q.eval(x, y + half));
        let bent = epsilon.of(&[c0, c1, c2, m01, m12, m20]).is_some_and(|e| {
            [(c0, c1, m01), (c1, c2, m12), (c2, c0, m20)].iter().any(|&(a, b, m)| (m - (a + b) / 2.0).length() > e)
        });
        if depth >= levels || !bent {
            if !leaves.add() {
                return;
            }
            continue;
        }
        stack.push((depth + 1, x, y, flipped, [c0, m01, m20]));
        stack.push((depth + 1, x + half, y, flipped, [m01, c1, m12]));
        stack.push((depth + 1, x, y + half, flipped, [m20, m12, c2]));
        stack.push((depth + 1, x + half, y + half, !flipped, [m12, m20, m01]));
    }
}

/// A tree's leaves, added to the shared count in batches (so that other roots see the total
/// grow without contending on every leaf), the rest when dropped.
struct Leaves<'a> {
    count: &'a AtomicUsize,
    limit: usize,
    local: usize,
}

impl Leaves<'_> {
    /// Counts one leaf; `false` once the total has passed the limit (stop counting).
    fn add(&mut self) -> bool {
        self.local += 1;
        if self.local < 4096 {
            return true;
        }
        let total = self.count.fetch_add(self.local, Ordering::Relaxed) + self.local;
        self.local = 0;
        total <= self.limit
    }
}

impl Drop for Leaves<'_> {
    fn drop(&mut self) {
        self.count.fetch_add(self.local, Ordering::Relaxed);
    }
}

/// A quartic triangle in the power basis, `Σ m[a][b] uᵃ vᵇ` (`a + b ≤ 4`): the predictor's
/// evaluations, several times cheaper than the Bernstein form's.
struct PowerForm {
    m: [[DVec3; 5]; 5],
}

impl PowerForm {
    /// The expansion of each Bernstein term `4!/(i! j! k!) uⁱ vʲ (1 − u − v)ᵏ`.
    fn of(q: &Quartic) -> Self {
        const FACTORIAL: [f64; 5] = [1.0, 1.0, 2.0, 6.0, 24.0];
        let mut m = [[DVec3::ZERO; 5]; 5];
        for j in 0..=4 {
            for i in 0..=4 - j {
                let k = 4 - i - j;
                let c = FACTORIAL[4] / (FACTORIAL[i] * FACTORIAL[j] * FACTORIAL[k]);
                for p in 0..=k {
                    for r in 0..=k - p {
                        let sign = if (p + r) % 2 == 0 { 1.0 } else { -1.0 };
                        let multinomial = FACTORIAL[k] / (FACTORIAL[p] * FACTORIAL[r] * FACTORIAL[k - p - r]);
                        m[i + p][j + r] += sign * c * multinomial * q.net[Quartic::index(i, j)];
                    }
                }
            }
        }
        Self { m }
    }

    fn eval(&self, u: f64, v: f64) -> DVec3 {
        let (mut out, mut vb) = (DVec3::ZERO, 1.0);
        for b in 0..=4 {
            let mut ua = vb;
            for a in 0..=4 - b {
                out += ua * self.m[a][b];
                ua *= u;
            }
            vb *= v;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bicubic that is `S(x, y) = (x, y, a x² + b y²)`: second derivatives `2a` and `2b`
    /// everywhere, so the tree is uniform at the depth where `h² · 2 max(a, b) / 8 ≤ ε`.
    fn paraboloid(a: f64, b: f64) -> Bicubic {
        // The Bézier points of t ↦ t² on [0, 1] are 0, 0, 1/3, 1; of t ↦ t, k/3.
        let square = [0.0, 0.0, 1.0 / 3.0, 1.0];
        Bicubic {
            net: std::array::from_fn(|j| {
                std::array::from_fn(|i| DVec3::new(i as f64 / 3.0, j as f64 / 3.0, a * square[i] + b * square[j]))
            }),
        }
    }

    #[test]
    fn the_power_form_is_the_quartic() {
        let q = Quartic { net: std::array::from_fn(|k| DVec3::new(k as f64, (k * k % 7) as f64, (k as f64).sin())) };
        let p = PowerForm::of(&q);
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.2, 0.3), (0.6, 0.1)] {
            assert!((p.eval(u, v) - q.eval(u, v)).length() < 1e-12, "({u}, {v})");
        }
    }

    #[test]
    fn a_uniform_second_derivative_gives_a_uniform_tree() {
        let patch = paraboloid(3.0, 1.0);
        let d = SecondDerivatives::of(&patch);
        assert!((d.largest(0.3, 0.7) - 6.0).abs() < 1e-12);
        // h² · 6 / 8 ≤ ε: h = 1/8 just above ε = 0.75 / 64, 64 leaves; h = 1/16 just below it.
        for (epsilon, leaves) in [(0.75 / 64.0 * 1.01, 64), (0.75 / 64.0 * 0.99, 256), (1.0, 1)] {
            let count = AtomicUsize::new(0);
            d.count_leaves(&patch, Epsilon { fixed: epsilon, screen: None }, 24, &count, usize::MAX);
            assert_eq!(count.load(Ordering::Relaxed), leaves, "ε = {epsilon}");
        }
        // The depth limit caps it; the count stops soon after passing the limit.
        let count = AtomicUsize::new(0);
        d.count_leaves(&patch, Epsilon { fixed: 1e-12, screen: None }, 3, &count, usize::MAX);
        assert_eq!(count.load(Ordering::Relaxed), 64);
        let count = AtomicUsize::new(0);
        d.count_leaves(&patch, Epsilon { fixed: 1e-12, screen: None }, 24, &count, 10_000);
        assert!((10_000..10_000 + 4096 + 4).contains(&count.load(Ordering::Relaxed)));
    }
}
