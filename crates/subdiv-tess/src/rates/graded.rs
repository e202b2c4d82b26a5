//! Dual grids graded toward extraordinary corners: a quad face's cells shrink toward a corner
//! as the second-derivative bound grows there, so that the face's cell count follows the
//! bound away from the corner (`ε^(−1/2)`) instead of its worst spot.
//!
//! Near an extraordinary point of subdominant eigenvalue `λ` the bound over the face less the
//! corner square of side `2^−d` grows like `(4λ)^d`; a uniform grid of `n` cells per side has
//! its finest cells next to the point and needs `n² ≥ M(log₂ n) / ε`, so `n` grows like
//! `ε^(−1/log₂(1/λ))`. Graded, each dyadic interval `[2^−(d+1), 2^−d]` of an axis holds as many
//! cells as its own bound asks, and those counts fall like `√λ` per interval toward the
//! point; the innermost interval is a uniform grid of a power-of-two number of cells, which
//! then looks to the rings around the point like a uniform face of rate `2^d k`.

use crate::TessError;

/// The denominator of a [`GradedGrid`]'s cell boundaries: `2^30` (cells down to `2^−30` of a
/// face side; a centre is then a dyadic parameter with denominator `2^31`).
pub const GRID_DENOMINATOR: u32 = 1 << 30;

/// Half an axis, in units of `1 / GRID_DENOMINATOR`.
const HALF: u32 = GRID_DENOMINATOR / 2;

/// The deepest dyadic interval a graded axis splits off (its cells are then at least `2^−28`
/// of a face side wide); an axis that needs more is refused as too fine for `f64` anyway.
const MAX_GRADED_DEPTH: u32 = 26;

/// A quad face's dual grid with cells of varying widths: per axis (`u`, then `v`, in the
/// face's own parameters) the `n + 1` cell boundaries, numerators over [`GRID_DENOMINATOR`],
/// increasing from 0 to it. The dual points are the cells' centres, `n × n` of them; both axes
/// have the same number of cells. [`ErrorRates::rates`](crate::rates::ErrorRates::rates)
/// grades the quads next to extraordinary points so.
///
/// ```
/// use subdiv_tess::rates::{GRID_DENOMINATOR, GradedGrid};
///
/// // Three cells per axis: a quarter, a quarter and a half.
/// let d = GRID_DENOMINATOR;
/// let grid = GradedGrid { axes: [vec![0, d / 4, d / 2, d], vec![0, d / 4, d / 2, d]] };
/// assert_eq!(grid.rate(), 3);
/// assert_eq!(grid.reach(), 4); // the corner cells are as fine as a uniform rate 4's
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GradedGrid {
    /// The cell boundaries of the `u` and the `v` axis.
    pub axes: [Vec<u32>; 2],
}

impl GradedGrid {
    /// The number of cells per axis.
    pub fn rate(&self) -> u32 {
        self.axes[0].len().saturating_sub(1) as u32
    }

    /// How finely the grid samples next to its corners, as a uniform rate would: the least
    /// `n` whose cells `1/n` are no wider than the narrowest cell at an end of an axis (its
    /// dual point then lies at least `½ / n` from the side, as a uniform rate `n`'s).
    pub fn reach(&self) -> u32 {
        let narrowest = self
            .axes
            .iter()
            .flat_map(|a| [a[1] - a[0], a[a.len() - 1] - a[a.len() - 2]])
            .min()
            .unwrap_or(GRID_DENOMINATOR)
            .max(1);
        GRID_DENOMINATOR.div_ceil(narrowest)
    }

    /// Cell `i`'s centre on `axis`, as a numerator over `2 ·` [`GRID_DENOMINATOR`].
    #[inline]
    pub(crate) fn centre(&self, axis: usize, i: u32) -> u64 {
        let a = &self.axes[axis];
        u64::from(a[i as usize]) + u64::from(a[i as usize + 1])
    }

    /// Why the grid is not one of `rate` cells per axis with increasing boundaries from 0 to
    /// [`GRID_DENOMINATOR`], if it is not.
    pub(crate) fn fault(&self, rate: u32) -> Option<String> {
        for (name, axis) in ["u", "v"].into_iter().zip(&self.axes) {
            if axis.len() != rate as usize + 1 {
                return Some(format!("its {name} axis has {} cells, not the face's rate {rate}", axis.len() - 1));
            }
            if axis.first() != Some(&0) || axis.last() != Some(&GRID_DENOMINATOR) {
                return Some(format!("its {name} axis does not run from 0 to GRID_DENOMINATOR"));
            }
            if axis.windows(2).any(|w| w[0] >= w[1]) {
                return Some(format!("its {name} axis' boundaries do not increase"));
            }
        }
        None
    }
}

/// `count` cells over `length` units, their widths within one unit of each other.
fn split(length: u32, count: u32) -> impl Iterator<Item = u32> {
    let at = move |i: u32| (u64::from(i) * u64::from(length) / u64::from(count)) as u32;
    (0..count).map(move |i| at(i + 1) - at(i))
}

/// Why no graded grid serves a face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Refusal {
    /// It needs this many cells per side, more than allowed.
    Cells(u32),
    /// It needs cells finer than `2^−depth` of a side, which the grid does not resolve.
    Finer(u32),
}

/// What a face's grading reads: the allowed cell width beyond the corner squares of side
/// `2^−e`, in units of `1 / GRID_DENOMINATOR` (0 where the bound cannot be met at that size).
pub(super) type Widths<'a> = dyn FnMut(u32) -> Result<u32, TessError> + 'a;

/// The cells of half an axis graded toward its end, as widths from that end outward (summing
/// to [`HALF`]), and the number of innermost cells (the uniform run at the end).
///
/// `far` is the cell count of the axis' other half were it uniform; `ring` gives, for the
/// innermost cells' reach, the depth of the first ring around the corner's point (in the
/// grid's units; it reads the finest reach around the point too), or `None` where that reach is
/// below what the point's rings ask for. Interval `I_d = [2^−(d+1), 2^−d]` takes cells of width at
/// most `W(d + 2)` (a quad with a centre in `I_d` lies beyond the corner square of side
/// `2^−(d+1)` and is at most as wide as the cells of `I_(d−1)`), and at least half as many as
/// `I_(d−1)`, so that the widths never grow toward the corner; the innermost `[0, 2^−d]` is
/// `k` cells (a power of two, so their widths are exact) once cells of width `2^−d / k`
/// meet the bound beyond the first ring that a reach of `2^d k` puts around the point. `None`
/// when that needs intervals deeper than [`MAX_GRADED_DEPTH`].
fn graded_half(
    widths: &mut Widths<'_>,
    far: u32,
    ring: &dyn Fn(u32) -> Option<u32>,
) -> Result<Option<(Vec<u32>, u32)>, TessError> {
    let mut intervals: Vec<(u32, u32)> = Vec::new(); // (length, cells), outermost first
    let mut previous = far;
    for d in 1..=MAX_GRADED_DEPTH {
        // The innermost run `[0, 2^−d]`, if it serves.
        let length = HALF >> (d - 1);
        let k = previous.div_ceil(2).max(1).next_power_of_two();
        if k <= length {
            let width = length / k;
            if let Some(depth) = ring(GRID_DENOMINATOR / width)
                && width <= widths(depth)?
            {
                let mut cells = vec![width; k as usize];
                for &(length, count) in intervals.iter().rev() {
                    cells.extend(split(length, count));
                }
                return Ok(Some((cells, k)));
            }
        }
        let length = HALF >> d;
        let width = widths(d + 2)?;
        if width == 0 {
            break;
        }
        let count = length.div_ceil(width).max(previous.div_ceil(2)).max(1);
        intervals.push((length, count));
        previous = count;
    }
    Ok(None)
}

/// A quad cell's graded grid (a quad's, or every sub-face's of an N-gon): `graded[a]` says
/// which ends of axis `a` (`u`, `v`) lie at an extraordinary point; `ring` as for
/// [`graded_half`]; `max_cells` the most cells per axis.
///
/// # Errors
/// The errors of `widths`; inside, why no grid serves, for the caller to name the face.
pub(super) fn graded_grid(
    widths: &mut Widths<'_>,
    graded: [[bool; 2]; 2],
    ring: &dyn Fn(u32) -> Option<u32>,
    max_cells: u32,
) -> Result<Result<GradedGrid, Refusal>, TessError> {
    // The uniform half: cells no wider than `W(2)` (its quads next to the middle lie beyond
    // the corner squares of side ¼).
    let uniform = widths(2)?;
    if uniform == 0 {
        return Ok(Err(Refusal::Finer(30)));
    }
    let far = HALF.div_ceil(uniform);
    // Every half axis toward an extraordinary end is graded alike: the bound beyond the corner
    // squares of side `2^−e` is the face's (and its neighbours'), whichever corner.
    let toward_end = if graded.as_flattened().contains(&true) {
        match graded_half(widths, far, ring)? {
            Some(half) => half,
            None => return Ok(Err(Refusal::Finer(MAX_GRADED_DEPTH + 2))),
        }
    } else {
        (Vec::new(), 0)
    };
    let uniform_half: Vec<u32> = split(HALF, far).collect();
    let half = |end: bool| if end { toward_end.clone() } else { (uniform_half.clone(), 0) };
    let mut axes: [(Vec<u32>, [u32; 2]); 2] = Default::default();
    for (axis, [low_end, high_end]) in axes.iter_mut().zip(graded) {
        let ((low, low_run), (high, high_run)) = (half(low_end), half(high_end));
        // Widths along the axis: the low half from 0, the high half mirrored.
        let widths: Vec<u32> = low.into_iter().chain(high.into_iter().rev()).collect();
        *axis = (widths, [low_run, high_run]);
    }
    // Equal counts: the axis with fewer cells splits its widest ones (not the innermost runs,
    // which keep their reach); narrower cells only lower the bound.
    let n = axes[0].0.len().max(axes[1].0.len());
    for (widths, [low, high]) in &mut axes {
        while widths.len() < n {
            let inner = *low as usize..widths.len() - *high as usize;
            let Some(k) = inner.clone().max_by_key(|&k| (widths[k], std::cmp::Reverse(k))) else { break };
            if widths[k] < 2 {
                break;
            }
            let half = widths[k] / 2;
            widths[k] -= half;
            widths.insert(k + 1, half);
        }
    }
    if axes.iter().any(|(w, _)| w.len() != n) {
        return Ok(Err(Refusal::Finer(30)));
    }
    if n > max_cells as usize {
        return Ok(Err(Refusal::Cells(n as u32)));
    }
    let boundaries = |widths: &[u32]| {
        std::iter::once(0)
            .chain(widths.iter().scan(0, |at, w| {
                *at += w;
                Some(*at)
            }))
            .collect::<Vec<u32>>()
    };
    Ok(Ok(GradedGrid { axes: [boundaries(&axes[0].0), boundaries(&axes[1].0)] }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Allowed widths of a bound growing like `(4λ)^e` with `λ = 0.6`.
    fn growing(base: f64) -> impl FnMut(u32) -> Result<u32, TessError> {
        move |e| Ok(((base / 2.4f64.powi(e as i32).sqrt()) * f64::from(GRID_DENOMINATOR)) as u32)
    }

    #[test]
    fn halves_shrink_toward_the_corner_and_end_in_a_power_of_two_run() {
        let mut w = growing(0.02);
        let far = HALF.div_ceil(w(2).unwrap());
        let ring = |reach: u32| Some(crate::rates::first_ring_depth(false, reach));
        let (cells, run) = graded_half(&mut w, far, &ring).unwrap().unwrap();
        assert_eq!(cells.iter().sum::<u32>(), HALF);
        assert!(run.is_power_of_two() && cells[..run as usize].iter().all(|&c| c == cells[0]));
        assert!(cells.windows(2).all(|p| p[0] <= p[1] + 1), "{cells:?}");
        // Far fewer cells than a uniform half at the innermost width.
        assert!((cells.len() as u32) < HALF / cells[0] / 4, "{} cells, innermost {}", cells.len(), cells[0]);
    }

    #[test]
    fn grids_are_square_and_monotone() {
        let mut w = growing(0.01);
        let ring =
            |floor: u32| move |reach: u32| (reach >= floor).then(|| crate::rates::first_ring_depth(false, reach));
        let grid = graded_grid(&mut w, [[true, false], [false, false]], &ring(1), 1000).unwrap().unwrap();
        assert_eq!(grid.fault(grid.rate()), None);
        assert_eq!(grid.axes[0].len(), grid.axes[1].len());
        // A finer floor makes the innermost run finer.
        let finer = graded_grid(&mut w, [[true, false], [false, false]], &ring(4 * grid.reach()), 1000);
        assert!(finer.unwrap().unwrap().reach() >= 4 * grid.reach());
        let refused = graded_grid(&mut w, [[true, true], [true, true]], &ring(1), 8).unwrap();
        assert!(refused.is_err());
    }
}
