//! Stencils: each refined vertex as a weighted sum of the parent level's vertices.
//!
//! Storage is built for [`Stencils::apply`]. The rows of one level share a handful of distinct
//! weight patterns (a uniform split of a regular mesh has one per kind of child vertex), so each
//! pattern's weights are stored once, in a palette, and the rows are kept as runs of consecutive
//! rows with the same pattern. Applying a run streams only its parent indices (4 bytes an entry
//! instead of 12) with the weights in registers, through a loop specialised to the pattern.
//!
//! Most patterns have a few groups of equal weights (Catmull-Clark's smooth vertex rule: the
//! vertex, its `k` edge neighbours, its `k` diagonal neighbours). Such a pattern is stored with
//! its entries sorted into groups, and its kernel adds each group's parents before multiplying
//! by the group's weight: one multiplication per group instead of one per entry. That changes
//! the rounding of the sum, by a few units in the last place of the parents' magnitude. Patterns
//! of another shape keep their order and their sums are formed as in a plain CSR loop.

use std::collections::HashMap;

use glam::DVec3;
use smallvec::SmallVec;

/// One refined vertex's weights over parent vertices, with repeated parents merged.
#[derive(Clone, Debug, Default)]
pub(crate) struct Row(SmallVec<[(u32, f64); 16]>);

impl Row {
    pub(crate) fn single(vertex: u32) -> Self {
        let mut row = Self::default();
        row.add(vertex, 1.0);
        row
    }

    /// A row of entries whose parents are distinct (a face's corners, say): no search for
    /// equal parents, which made the rows of an n-gon's points cost n³.
    pub(crate) fn of_distinct(entries: impl IntoIterator<Item = (u32, f64)>) -> Self {
        let row = Self(entries.into_iter().collect());
        debug_assert!(row.0.iter().enumerate().all(|(i, (v, _))| row.0[..i].iter().all(|(u, _)| u != v)));
        row
    }

    pub(crate) fn add(&mut self, vertex: u32, weight: f64) {
        match self.0.iter_mut().find(|(v, _)| *v == vertex) {
            Some((_, w)) => *w += weight,
            None => self.0.push((vertex, weight)),
        }
    }

    pub(crate) fn add_row(&mut self, other: &Row, scale: f64) {
        for &(v, w) in &other.0 {
            self.add(v, w * scale);
        }
    }

    /// The entries `(parent, weight)`, each parent once.
    pub(crate) fn entries(&self) -> &[(u32, f64)] {
        &self.0
    }

    /// `self · a + other · (1 − a)`.
    pub(crate) fn blend(self, other: &Row, a: f64) -> Row {
        let mut out = Row::default();
        out.add_row(&self, a);
        out.add_row(other, 1.0 - a);
        out
    }
}

/// Consecutive rows with the same weight pattern.
#[derive(Clone, Copy, Debug)]
struct Run {
    /// The pattern, in [`Stencils::patterns`].
    pattern: u32,
    /// The run's first entry in [`Stencils::indices`].
    entries_start: u32,
    /// The row after the run's last.
    rows_end: u32,
}

/// Applies rows of one pattern: `(parent, the run's indices, the pattern's weights, child)`.
type Kernel = fn(&[DVec3], &[u32], &[f64], &mut Vec<DVec3>);

/// A distinct weight pattern: its weights in [`Stencils::weights`] and how to apply it.
#[derive(Clone, Debug)]
struct Pattern {
    start: u32,
    len: u32,
    kernel: Kernel,
    /// Stored entry `k` is entry `order[k]` of the row as pushed (empty: the same order).
    order: SmallVec<[u8; 16]>,
}

impl Pattern {
    /// Whether `row`'s weights, as pushed, are this pattern's (bit for bit).
    fn matches(&self, weights: &[f64], row: &Row) -> bool {
        let stored = &weights[self.start as usize..][..self.len as usize];
        let entries = &row.0;
        entries.len() == stored.len()
            && if self.order.is_empty() {
                stored.iter().zip(entries).all(|(a, (_, b))| a.to_bits() == b.to_bits())
            } else {
                stored.iter().zip(&self.order).all(|(a, &k)| a.to_bits() == entries[usize::from(k)].1.to_bits())
            }
    }
}

/// The refinement matrix of one level, row by row: child vertex `c` is
/// `Σ weight · parent[index]` over the `(index, weight)` pairs of [`Stencils::row`]`(c)`.
///
/// Weights of every row sum to 1 (to rounding): refinement is affine invariant.
#[derive(Clone)]
pub struct Stencils {
    /// Parent indices, row after row, each row in its pattern's stored order.
    indices: Vec<u32>,
    /// The palette: every distinct weight pattern once, one after another.
    weights: Vec<f64>,
    patterns: Vec<Pattern>,
    /// The rows, as runs sharing a pattern, in row order.
    runs: Vec<Run>,
    /// Palette lookup while rows are pushed: a pattern's weights as pushed (bits) to its number.
    lookup: HashMap<Box<[u64]>, u32>,
    parent_count: usize,
}

impl Stencils {
    pub(crate) fn with_capacity(_rows: usize, entries: usize, parent_count: usize) -> Self {
        Self {
            indices: Vec::with_capacity(entries),
            weights: Vec::new(),
            patterns: Vec::new(),
            runs: Vec::new(),
            lookup: HashMap::new(),
            parent_count,
        }
    }

    /// Appends `row` as the next child vertex.
    ///
    /// # Panics
    /// When the row names a vertex outside the parent level, or the level outgrows 32-bit offsets.
    pub(crate) fn push(&mut self, row: &Row) {
        let entries = &row.0;
        assert!(entries.iter().all(|&(v, _)| (v as usize) < self.parent_count), "stencil names no parent vertex");
        let last = self.runs.last().copied();
        // Most rows repeat the previous row's pattern: compare with it before hashing.
        let pattern = match last {
            Some(run) if self.patterns[run.pattern as usize].matches(&self.weights, row) => run.pattern,
            _ => self.pattern_of(row),
        };
        let order = &self.patterns[pattern as usize].order;
        let entries_start = offset(self.indices.len());
        if order.is_empty() {
            self.indices.extend(entries.iter().map(|&(v, _)| v));
        } else {
            self.indices.extend(order.iter().map(|&k| entries[usize::from(k)].0));
        }
        let rows_end = last.map_or(0, |run| run.rows_end) + 1;
        match self.runs.last_mut() {
            Some(run) if run.pattern == pattern => run.rows_end = rows_end,
            _ => self.runs.push(Run { pattern, entries_start, rows_end }),
        }
    }

    /// The number of `row`'s weight pattern, added to the palette if new.
    fn pattern_of(&mut self, row: &Row) -> u32 {
        let bits: SmallVec<[u64; 16]> = row.0.iter().map(|&(_, w)| w.to_bits()).collect();
        if let Some(&pattern) = self.lookup.get(&bits[..]) {
            return pattern;
        }
        let weights: SmallVec<[f64; 16]> = row.0.iter().map(|&(_, w)| w).collect();
        let (kernel, order) = plan(&weights);
        let start = offset(self.weights.len());
        if order.is_empty() {
            self.weights.extend_from_slice(&weights);
        } else {
            self.weights.extend(order.iter().map(|&k| weights[usize::from(k)]));
        }
        let pattern = offset(self.patterns.len());
        self.patterns.push(Pattern { start, len: offset(weights.len()), kernel, order });
        self.lookup.insert(bits.as_slice().into(), pattern);
        pattern
    }

    /// The same rows over another numbering of the parent level: parent `p` becomes
    /// `parents[p]`, of `parent_count` vertices (how a part of a mesh, refined on its own,
    /// gives stencils over the whole mesh).
    ///
    /// # Panics
    /// When `parents` does not name every parent vertex, or names one at or past
    /// `parent_count`.
    pub fn with_parents(&self, parents: &[u32], parent_count: usize) -> Self {
        assert_eq!(parents.len(), self.parent_count, "one new number per parent vertex");
        assert!(parents.iter().all(|&p| (p as usize) < parent_count), "parents within the new count");
        let mut out = self.clone();
        out.indices.iter_mut().for_each(|i| *i = parents[*i as usize]);
        out.parent_count = parent_count;
        out
    }

    /// Two levels as one: `next`'s rows (over this level's children) over this level's
    /// parents.
    ///
    /// # Panics
    /// When `next` is not over this level's children.
    pub(crate) fn then(&self, next: &Stencils) -> Stencils {
        assert_eq!(next.parent_count, self.child_count(), "the next level is over this level's children");
        let mut out = Stencils::with_capacity(next.child_count(), 0, self.parent_count);
        for child in 0..next.child_count() {
            let mut row = Row::default();
            for (w, a) in next.row(child) {
                for (x, b) in self.row(w) {
                    row.add(x as u32, a * b);
                }
            }
            out.push(&row);
        }
        out
    }

    /// Number of rows: the refined level's vertices.
    pub fn child_count(&self) -> usize {
        self.runs.last().map_or(0, |run| run.rows_end as usize)
    }

    /// Number of columns: the parent level's vertices.
    pub fn parent_count(&self) -> usize {
        self.parent_count
    }

    /// The weights of child vertex `child` as `(parent vertex index, weight)` pairs, one per
    /// parent vertex, in no particular order.
    ///
    /// # Panics
    /// When `child >= self.child_count()`.
    pub fn row(&self, child: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (indices, weights) = self.row_in_run(self.run_of(child), child);
        indices.iter().map(|&i| i as usize).zip(weights.iter().copied())
    }

    /// The rows of `children`, in order, each as its parent indices and their weights (in the
    /// pattern's stored order).
    pub(crate) fn rows_in(&self, children: std::ops::Range<usize>) -> impl Iterator<Item = (&[u32], &[f64])> + '_ {
        let mut r = self.run_of(children.start);
        children.map(move |child| {
            while self.runs[r].rows_end as usize <= child {
                r += 1;
            }
            self.row_in_run(r, child)
        })
    }

    /// The run that holds row `child`.
    fn run_of(&self, child: usize) -> usize {
        self.runs.partition_point(|run| run.rows_end as usize <= child)
    }

    /// Row `child`, which run `r` holds: its parent indices and their weights.
    fn row_in_run(&self, r: usize, child: usize) -> (&[u32], &[f64]) {
        let run = self.runs[r];
        let first_row = if r == 0 { 0 } else { self.runs[r - 1].rows_end as usize };
        let pattern = &self.patterns[run.pattern as usize];
        let len = pattern.len as usize;
        let start = run.entries_start as usize + (child - first_row) * len;
        (&self.indices[start..start + len], &self.weights[pattern.start as usize..][..len])
    }

    /// Applies the stencils to `parent` (one value per parent vertex), writing one value per
    /// child vertex into `child` (resized).
    ///
    /// # Panics
    /// When `parent.len() != self.parent_count()`.
    pub fn apply(&self, parent: &[DVec3], child: &mut Vec<DVec3>) {
        assert_eq!(parent.len(), self.parent_count, "one value per parent vertex");
        child.clear();
        child.reserve(self.child_count());
        let mut first_row = 0;
        for run in &self.runs {
            let pattern = &self.patterns[run.pattern as usize];
            let len = pattern.len as usize;
            let rows = (run.rows_end - first_row) as usize;
            first_row = run.rows_end;
            let indices = &self.indices[run.entries_start as usize..][..rows * len];
            if len == 0 {
                child.extend(std::iter::repeat_n(DVec3::ZERO, rows));
            } else {
                (pattern.kernel)(parent, indices, &self.weights[pattern.start as usize..][..len], child);
            }
        }
    }
}

/// The kernel for a pattern, and the order to store its entries in (empty: as they come).
fn plan(weights: &[f64]) -> (Kernel, SmallVec<[u8; 16]>) {
    if let Some((kernel, order)) = grouped_plan(weights) {
        return (kernel, order);
    }
    (per_entry_kernel(weights.len()), SmallVec::new())
}

/// Groups equal weights (at most three groups, smallest first, ties in order of appearance)
/// when a kernel for the groups' sizes exists.
fn grouped_plan(weights: &[f64]) -> Option<(Kernel, SmallVec<[u8; 16]>)> {
    if weights.len() > 32 {
        return None;
    }
    let mut groups: SmallVec<[(u64, SmallVec<[u8; 16]>); 3]> = SmallVec::new();
    for (k, w) in weights.iter().enumerate() {
        let k = u8::try_from(k).ok()?;
        match groups.iter().position(|(bits, _)| *bits == w.to_bits()) {
            Some(g) => groups[g].1.push(k),
            None if groups.len() < 3 => groups.push((w.to_bits(), SmallVec::from_slice(&[k]))),
            None => return None,
        }
    }
    groups.sort_by_key(|(_, members)| members.len());
    let size = |g: usize| groups.get(g).map_or(0, |(_, members)| members.len());
    let kernel = grouped_kernel(weights.len(), size(0), size(1))?;
    Some((kernel, groups.iter().flat_map(|(_, members)| members.iter().copied()).collect()))
}

/// The kernel for rows of `n` entries in groups of `a`, `b` and `n − a − b` equal weights.
fn grouped_kernel(n: usize, a: usize, b: usize) -> Option<Kernel> {
    macro_rules! kernels {
        ($(($n:literal, $a:literal, $b:literal)),* $(,)?) => {
            match (n, a, b) {
                $(($n, $a, $b) => Some(grouped::<$n, $a, $b> as Kernel),)*
                _ => None,
            }
        };
    }
    kernels!(
        // One weight: copies, midpoints, face points.
        (1, 1, 0),
        (2, 2, 0),
        (3, 3, 0),
        (4, 4, 0),
        (5, 5, 0),
        (6, 6, 0),
        (7, 7, 0),
        (8, 8, 0),
        // A vertex and its ring (Loop's vertex rule, crease rules), an edge and its wings.
        (2, 1, 1),
        (3, 1, 2),
        (4, 1, 3),
        (5, 1, 4),
        (6, 1, 5),
        (7, 1, 6),
        (8, 1, 7),
        (9, 1, 8),
        (10, 1, 9),
        (11, 1, 10),
        (12, 1, 11),
        (13, 1, 12),
        (4, 2, 2),
        (5, 2, 3),
        (6, 2, 4),
        (7, 2, 5),
        (8, 2, 6),
        // A vertex, its edge neighbours and its face neighbours (Catmull-Clark's vertex rule).
        (7, 1, 3),
        (9, 1, 4),
        (11, 1, 5),
        (13, 1, 6),
        (15, 1, 7),
        (17, 1, 8),
    )
}

/// The sum of `parent` over `indices` (not empty), in order.
#[inline(always)]
fn group_sum(parent: &[DVec3], indices: &[u32]) -> DVec3 {
    let mut sum = parent[indices[0] as usize];
    for &i in &indices[1..] {
        sum += parent[i as usize];
    }
    sum
}

/// Rows of `N` entries in three groups of equal weights (`A`, `B`, `N − A − B` entries; `B` or
/// the third may be empty): one multiplication per group.
fn grouped<const N: usize, const A: usize, const B: usize>(
    parent: &[DVec3],
    indices: &[u32],
    weights: &[f64],
    child: &mut Vec<DVec3>,
) {
    let weights: [f64; N] = weights.try_into().expect("pattern of N weights");
    let (w0, w1, w2) = (weights[0], weights[A.min(N - 1)], weights[(A + B).min(N - 1)]);
    let (rows, rest) = indices.as_chunks::<N>();
    debug_assert!(rest.is_empty());
    child.extend(rows.iter().map(move |row| {
        let mut sum = group_sum(parent, &row[..A]) * w0;
        if B > 0 {
            sum += group_sum(parent, &row[A..A + B]) * w1;
        }
        if A + B < N {
            sum += group_sum(parent, &row[A + B..]) * w2;
        }
        sum
    }));
}

/// The kernel for rows of `len` entries with one weight each.
fn per_entry_kernel(len: usize) -> Kernel {
    match len {
        1 => fixed::<1>,
        2 => fixed::<2>,
        3 => fixed::<3>,
        4 => fixed::<4>,
        5 => fixed::<5>,
        6 => fixed::<6>,
        7 => fixed::<7>,
        8 => fixed::<8>,
        9 => fixed::<9>,
        10 => fixed::<10>,
        11 => fixed::<11>,
        12 => fixed::<12>,
        13 => fixed::<13>,
        _ => general,
    }
}

/// Rows of `N` entries sharing `weights`: the weights stay in registers and the loop unrolls.
fn fixed<const N: usize>(parent: &[DVec3], indices: &[u32], weights: &[f64], child: &mut Vec<DVec3>) {
    let weights: [f64; N] = weights.try_into().expect("pattern of N weights");
    let (rows, rest) = indices.as_chunks::<N>();
    debug_assert!(rest.is_empty());
    child.extend(rows.iter().map(move |row| {
        let mut sum = parent[row[0] as usize] * weights[0];
        for k in 1..N {
            sum += parent[row[k] as usize] * weights[k];
        }
        sum
    }));
}

/// Rows of any length sharing `weights`.
fn general(parent: &[DVec3], indices: &[u32], weights: &[f64], child: &mut Vec<DVec3>) {
    child.extend(indices.chunks_exact(weights.len()).map(|row| {
        let mut sum = DVec3::ZERO;
        for (&i, &w) in row.iter().zip(weights) {
            sum += parent[i as usize] * w;
        }
        sum
    }));
}

/// A position in one of the 32-bit-indexed arrays.
fn offset(n: usize) -> u32 {
    u32::try_from(n).expect("stencils of one level fit 32-bit offsets")
}

impl PartialEq for Stencils {
    /// Equal when they have the same shape and every row the same entries in the same order
    /// (the palette is an implementation detail).
    fn eq(&self, other: &Self) -> bool {
        self.parent_count == other.parent_count
            && self.child_count() == other.child_count()
            && self.indices == other.indices
            && (0..self.child_count()).all(|c| self.row(c).map(|(_, w)| w).eq(other.row(c).map(|(_, w)| w)))
    }
}

impl std::fmt::Debug for Stencils {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stencils")
            .field("child_count", &self.child_count())
            .field("parent_count", &self.parent_count)
            .field("entries", &self.indices.len())
            .field("patterns", &self.patterns.len())
            .field("runs", &self.runs.len())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic stream of pseudo-random numbers in [0, 1).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }

        fn below(&mut self, n: usize) -> usize {
            (self.next() * n as f64) as usize
        }
    }

    fn row(entries: &[(u32, f64)]) -> Row {
        let mut row = Row::default();
        for &(v, w) in entries {
            row.add(v, w);
        }
        row
    }

    /// Rows of every kind the kernels distinguish: empty, grouped shapes, per-entry shapes
    /// (more than three distinct weights) and long rows; runs of one pattern and single rows.
    fn rows(parent_count: usize, count: usize, seed: u64) -> Vec<Row> {
        let mut rng = Lcg(seed);
        let palette = [0.5, 0.25, 0.125, 3.0 / 8.0, 1.0 / 16.0, 9.0 / 16.0, 3.0 / 32.0, 1.0 / 64.0, -0.1];
        let mut out = Vec::new();
        while out.len() < count {
            let len = [0, 1, 2, 4, 6, 7, 9, 13, 17, 25][rng.below(10)];
            let distinct = 1 + rng.below(5);
            let weights: Vec<f64> = (0..len).map(|_| palette[rng.below(distinct)]).collect();
            for _ in 0..1 + rng.below(4) {
                let mut r = Row::default();
                for &w in &weights {
                    // Distinct parents, so that `add` keeps every entry.
                    let v = loop {
                        let v = rng.below(parent_count) as u32;
                        if r.0.iter().all(|&(u, _)| u != v) {
                            break v;
                        }
                    };
                    r.add(v, w);
                }
                out.push(r);
            }
        }
        out
    }

    fn stencils(parent_count: usize, rows: &[Row]) -> Stencils {
        let mut stencils = Stencils::with_capacity(rows.len(), 0, parent_count);
        for r in rows {
            stencils.push(r);
        }
        stencils
    }

    fn sorted(entries: impl Iterator<Item = (usize, f64)>) -> Vec<(usize, u64)> {
        let mut out: Vec<_> = entries.map(|(v, w)| (v, w.to_bits())).collect();
        out.sort_unstable();
        out
    }

    #[test]
    fn rows_come_back_as_pushed() {
        let rows = rows(50, 400, 1);
        let s = stencils(50, &rows);
        assert_eq!((s.child_count(), s.parent_count()), (rows.len(), 50));
        for (c, r) in rows.iter().enumerate() {
            assert_eq!(sorted(s.row(c)), sorted(r.0.iter().map(|&(v, w)| (v as usize, w))), "row {c}");
        }
        assert!(s.patterns.len() < s.runs.len() && s.runs.len() < rows.len());
    }

    #[test]
    fn apply_is_the_weighted_sum_of_each_row() {
        let mut rng = Lcg(7);
        let parent: Vec<DVec3> = (0..64).map(|_| DVec3::new(rng.next(), rng.next(), rng.next()) * 8.0 - 4.0).collect();
        let rows = rows(parent.len(), 2000, 2);
        let s = stencils(parent.len(), &rows);
        let mut child = vec![DVec3::ONE; 3];
        s.apply(&parent, &mut child);
        assert_eq!(child.len(), rows.len());
        for (c, (r, got)) in rows.iter().zip(&child).enumerate() {
            let mut sum = DVec3::ZERO;
            for &(v, w) in &r.0 {
                sum += parent[v as usize] * w;
            }
            let bound = 4.0 * f64::EPSILON * r.0.iter().map(|&(_, w)| w.abs() * 4.0 * 8.0).sum::<f64>();
            assert!((sum - *got).abs().max_element() <= bound, "row {c}: {sum} vs {got}");
            // Patterns with more than three distinct weights keep the plain order, bit for bit.
            if s.patterns[s.runs[s.runs.partition_point(|run| run.rows_end as usize <= c)].pattern as usize]
                .order
                .is_empty()
            {
                assert_eq!(sum, *got, "row {c}");
            }
        }
    }

    #[test]
    fn equality_ignores_the_palette() {
        let rows = rows(30, 300, 3);
        let (a, b) = (stencils(30, &rows), stencils(30, &rows));
        assert_eq!(a, b);
        assert_eq!(a, a.clone());
        let mut other = rows.clone();
        other[17] = row(&[(1, 0.5), (2, 0.5)]);
        assert_ne!(a, stencils(30, &other));
        assert_ne!(a, stencils(31, &rows));
    }

    #[test]
    fn repeated_patterns_share_the_palette() {
        let vertex = |v: u32| row(&[(v, 0.75), (v + 1, 0.125), (v + 2, 0.125)]);
        let edge = |v: u32| row(&[(v, 0.5), (v + 1, 0.5)]);
        let rows: Vec<Row> = (0..10).map(vertex).chain((0..10).map(edge)).chain((0..10).map(vertex)).collect();
        let s = stencils(12, &rows);
        assert_eq!((s.patterns.len(), s.runs.len(), s.weights.len()), (2, 3, 5));
    }

    #[test]
    #[should_panic(expected = "stencil names no parent vertex")]
    fn rows_stay_inside_the_parent_level() {
        stencils(4, &[row(&[(4, 1.0)])]);
    }
}
