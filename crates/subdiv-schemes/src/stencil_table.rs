//! [`StencilTable`]: the last level of a uniform refinement as weighted sums of the cage's
//! vertices (Far's `StencilTable`), composed from the levels' [`Stencils`] once, then applied to
//! any number of moved cages.

use glam::DVec3;
use subdiv_mesh::par::{self, CHUNK};

use crate::stencil::Stencils;

/// Each refined vertex as a weighted sum of cage vertices, in compressed rows.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{Builtin, RefineOptions, Refiner};
///
/// let cage = Mesh::build(shapes::quad_torus(8, 6))?;
/// let refiner = Refiner::new(&cage, Builtin::CatmullClark.scheme(), 3, &RefineOptions::DEFAULT)?;
/// let table = refiner.stencil_table();
/// assert_eq!(table.len(), refiner.mesh().vertex_count());
/// let mut out = Vec::new();
/// table.apply(cage.positions(), &mut out);
/// assert!(out.iter().zip(refiner.mesh().positions()).all(|(a, b)| (*a - *b).length() < 1e-12));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct StencilTable {
    /// Row `i` is `offsets[i]..offsets[i + 1]` of `indices` and `weights`.
    offsets: Vec<u32>,
    indices: Vec<u32>,
    weights: Vec<f64>,
    cage_count: usize,
}

impl StencilTable {
    /// The identity on `cage_count` vertices: what zero levels compose to.
    fn identity(cage_count: usize) -> Self {
        Self {
            offsets: (0..=cage_count as u32).collect(),
            indices: (0..cage_count as u32).collect(),
            weights: vec![1.0; cage_count],
            cage_count,
        }
    }

    /// `levels` composed: the last level over the first's parents, on rayon's threads if
    /// `parallel`.
    pub(crate) fn compose(cage_count: usize, levels: &[Stencils], parallel: bool) -> Self {
        levels.iter().fold(Self::identity(cage_count), |table, level| table.then(level, parallel))
    }

    /// `level` applied after `self`: each child row's parents replaced by their rows here.
    fn then(&self, level: &Stencils, parallel: bool) -> Self {
        let rows = level.child_count();
        let chunks: Vec<usize> = (0..rows.div_ceil(CHUNK)).collect();
        // Each chunk with a dense scratch over the cage and the list of the entries it touched.
        let parts = par::map(parallel, chunks, |k| {
            let (mut dense, mut touched) = (vec![0.0f64; self.cage_count], Vec::new());
            let (mut offsets, mut indices, mut weights) = (Vec::new(), Vec::new(), Vec::new());
            for (parents, ws) in level.rows_in(k * CHUNK..((k + 1) * CHUNK).min(rows)) {
                for (&p, &w) in parents.iter().zip(ws) {
                    let (row_indices, row_weights) = self.row(p as usize);
                    for (&q, &v) in row_indices.iter().zip(row_weights) {
                        if dense[q as usize] == 0.0 {
                            touched.push(q);
                        }
                        dense[q as usize] += w * v;
                    }
                }
                for &q in &touched {
                    let w = std::mem::take(&mut dense[q as usize]);
                    if w != 0.0 {
                        indices.push(q);
                        weights.push(w);
                    }
                }
                touched.clear();
                offsets.push(indices.len() as u32);
            }
            (offsets, indices, weights)
        });
        let mut out = Self {
            offsets: Vec::with_capacity(rows + 1),
            indices: Vec::new(),
            weights: Vec::new(),
            cage_count: self.cage_count,
        };
        out.offsets.push(0);
        for (offsets, indices, weights) in parts {
            let base = out.indices.len() as u32;
            out.offsets.extend(offsets.iter().map(|o| o + base));
            out.indices.extend_from_slice(&indices);
            out.weights.extend_from_slice(&weights);
        }
        out
    }

    /// Number of rows: the refined vertices.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of columns: the cage's vertices.
    pub fn cage_count(&self) -> usize {
        self.cage_count
    }

    /// Row `i`: the cage vertices it reads and their weights.
    ///
    /// # Panics
    /// When `i >= self.len()`.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.offsets[i] as usize..self.offsets[i + 1] as usize;
        (&self.indices[range.clone()], &self.weights[range])
    }

    /// Number of weights, all rows together.
    pub fn weight_count(&self) -> usize {
        self.weights.len()
    }

    /// Applies the table to `cage` (one value per cage vertex), writing one value per refined
    /// vertex into `out` (resized).
    ///
    /// # Panics
    /// When `cage.len() != self.cage_count()`.
    pub fn apply(&self, cage: &[DVec3], out: &mut Vec<DVec3>) {
        assert_eq!(cage.len(), self.cage_count, "one value per cage vertex");
        out.clear();
        out.extend((0..self.len()).map(|i| {
            let (indices, weights) = self.row(i);
            indices.iter().zip(weights).fold(DVec3::ZERO, |sum, (&q, &w)| sum + w * cage[q as usize])
        }));
    }
}
