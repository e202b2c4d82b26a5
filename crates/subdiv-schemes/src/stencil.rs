//! Stencils: each refined vertex as a weighted sum of the parent level's vertices.

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

    /// `self · a + other · (1 − a)`.
    pub(crate) fn blend(self, other: &Row, a: f64) -> Row {
        let mut out = Row::default();
        out.add_row(&self, a);
        out.add_row(other, 1.0 - a);
        out
    }
}

/// The refinement matrix of one level, row by row (CSR): child vertex `c` is
/// `Σ weights[k] · parent[indices[k]]` over `k` in `offsets[c]..offsets[c + 1]`.
///
/// Weights of every row sum to 1 (to rounding): refinement is affine invariant.
#[derive(Clone, Debug, PartialEq)]
pub struct Stencils {
    offsets: Vec<u32>,
    indices: Vec<u32>,
    weights: Vec<f64>,
    parent_count: usize,
}

impl Stencils {
    pub(crate) fn with_capacity(rows: usize, entries: usize, parent_count: usize) -> Self {
        let mut offsets = Vec::with_capacity(rows + 1);
        offsets.push(0);
        Self { offsets, indices: Vec::with_capacity(entries), weights: Vec::with_capacity(entries), parent_count }
    }

    pub(crate) fn push(&mut self, row: &Row) {
        for &(v, w) in &row.0 {
            self.indices.push(v);
            self.weights.push(w);
        }
        self.offsets.push(self.indices.len() as u32);
    }

    /// Number of rows: the refined level's vertices.
    pub fn child_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of columns: the parent level's vertices.
    pub fn parent_count(&self) -> usize {
        self.parent_count
    }

    /// The weights of child vertex `child` as `(parent vertex index, weight)` pairs.
    pub fn row(&self, child: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let range = self.offsets[child] as usize..self.offsets[child + 1] as usize;
        self.indices[range.clone()].iter().map(|&i| i as usize).zip(self.weights[range].iter().copied())
    }

    /// Applies the stencils to `parent` (one value per parent vertex), writing one value per
    /// child vertex into `child` (resized).
    ///
    /// # Panics
    /// When `parent.len() != self.parent_count()`.
    pub fn apply(&self, parent: &[DVec3], child: &mut Vec<DVec3>) {
        assert_eq!(parent.len(), self.parent_count, "one value per parent vertex");
        child.clear();
        child.extend(self.offsets.windows(2).map(|w| {
            let (start, end) = (w[0] as usize, w[1] as usize);
            let mut sum = DVec3::ZERO;
            for (&i, &weight) in self.indices[start..end].iter().zip(&self.weights[start..end]) {
                sum += parent[i as usize] * weight;
            }
            sum
        }));
    }
}
