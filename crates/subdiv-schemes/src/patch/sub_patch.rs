//! One child of a patch shape: where its domain lies in the parent's ([`ChildDomain`]) and the
//! matrix taking the parent patch's control points to its own ([`SubPatch`]), stored by rows of
//! nonzeros.

use subdiv_mesh::DVec3;

use crate::SchemeError;

/// Where a child's domain lies in its parent's: the child's parameters are
/// `sign · (scale·(u, v) − offset)`, with `sign = −1` for a flipped (upside-down) triangle.
/// `scale` is 2 for the binary splits (a quad's quarters, a triangle's four children) and 3 for
/// the ternary one (√3's two steps: a triangle's nine children).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChildDomain {
    /// The offset, in units of the child's size.
    pub offset: [u8; 2],
    /// Whether the child is turned by half a turn (a triangle upside down in its parent).
    pub flipped: bool,
    /// How many children fit along a side of the parent: 2 or 3.
    pub scale: u8,
}

impl ChildDomain {
    /// A child of a binary split (scale 2).
    pub const fn binary(offset: [u8; 2], flipped: bool) -> Self {
        Self { offset, flipped, scale: 2 }
    }

    /// The child's parameters of the parent's point `(u, v)`.
    pub fn to_child(self, u: f64, v: f64) -> (f64, f64) {
        let (sign, scale) = (if self.flipped { -1.0 } else { 1.0 }, f64::from(self.scale));
        (sign * (scale * u - f64::from(self.offset[0])), sign * (scale * v - f64::from(self.offset[1])))
    }

    /// The parent's parameters of the child's point `(u, v)`.
    pub fn to_parent(self, u: f64, v: f64) -> (f64, f64) {
        let (sign, scale) = (if self.flipped { -1.0 } else { 1.0 }, f64::from(self.scale));
        ((sign * u + f64::from(self.offset[0])) / scale, (sign * v + f64::from(self.offset[1])) / scale)
    }

    /// The children of a face of `size` sides (3: triangles, anything else: quads) under a
    /// binary split, in the engine's order.
    pub fn of_face(size: usize) -> &'static [ChildDomain] {
        const fn at(u: u8, v: u8, flipped: bool) -> ChildDomain {
            ChildDomain::binary([u, v], flipped)
        }
        const QUAD: [ChildDomain; 4] = [at(0, 0, false), at(1, 0, false), at(1, 1, false), at(0, 1, false)];
        const TRIANGLE: [ChildDomain; 4] = [at(0, 0, false), at(1, 0, false), at(0, 1, false), at(1, 1, true)];
        if size == 3 { &TRIANGLE } else { &QUAD }
    }

    /// The nine children of a triangle under the ternary split (√3's two steps), in the order
    /// of [`PatchShape::children`](crate::PatchShape::children): the upright cells `(i, j)` (`i + j ≤ 2`, row by row, so the
    /// child at corner 0 is first), then the three upside-down ones, whose corner 0 is the
    /// lattice point `(i + 1, j + 1)` of cell `(i, j)`.
    ///
    /// ```
    /// use subdiv_schemes::ChildDomain;
    ///
    /// let children = ChildDomain::ternary();
    /// // The parent's centroid (1/3, 1/3) is corner 0 of the first upside-down child.
    /// assert_eq!(children[6].to_child(1.0 / 3.0, 1.0 / 3.0), (0.0, 0.0));
    /// assert_eq!(children[6].to_parent(1.0, 0.0), (0.0, 1.0 / 3.0));
    /// ```
    pub fn ternary() -> &'static [ChildDomain; 9] {
        const fn at(u: u8, v: u8, flipped: bool) -> ChildDomain {
            ChildDomain { offset: [u, v], flipped, scale: 3 }
        }
        const TERNARY: [ChildDomain; 9] = [
            at(0, 0, false),
            at(1, 0, false),
            at(2, 0, false),
            at(0, 1, false),
            at(1, 1, false),
            at(0, 2, false),
            at(1, 1, true),
            at(2, 1, true),
            at(1, 2, true),
        ];
        &TERNARY
    }
}

/// One child of a [`PatchShape`](crate::PatchShape): its shape, where its domain lies, and the matrix taking the
/// parent patch's control points to its own.
///
/// The matrix is stored by rows of its nonzero entries: a child point's rule reads a few parent
/// points, except at an extraordinary vertex, whose own point reads its whole ring, so a row
/// holds `O(1)` entries and the matrix `O(N)` at valence `N` (dense, the child at the vertex of
/// valence 10 000 was 3.2 GB).
#[derive(Clone, Debug, PartialEq)]
pub struct SubPatch {
    /// The child's shape, an index into [`PatchMatrices::shapes`](crate::PatchMatrices::shapes).
    pub shape: usize,
    /// Where the child lies in the parent's domain.
    pub domain: ChildDomain,
    columns: usize,
    /// Row `r`'s entries are `starts[r]..starts[r + 1]` of `places` and `weights`.
    starts: Vec<u32>,
    /// Each entry's column, ascending within a row.
    places: Vec<u32>,
    /// Each entry's weight: every entry whose bits are not those of `+0.0` (so `-0.0` too: the
    /// dense matrix's bits, all of them, are those of the stored entries and zeros).
    weights: Vec<f64>,
}

impl SubPatch {
    /// Rows: the child patch's size.
    pub fn rows(&self) -> usize {
        self.starts.len() - 1
    }

    /// Columns: the parent patch's size.
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// The weight of parent control point `column` in child control point `row`.
    pub fn get(&self, row: usize, column: usize) -> f64 {
        let range = self.starts[row] as usize..self.starts[row + 1] as usize;
        let places = &self.places[range.clone()];
        places.binary_search(&(column as u32)).map_or(0.0, |at| self.weights[range.start + at])
    }

    /// A child of `shape` at `domain` with `rows` rows of `entries` (row-major).
    pub(crate) fn from_entries(shape: usize, domain: ChildDomain, rows: usize, entries: Vec<f64>) -> Self {
        let columns = entries.len().checked_div(rows).unwrap_or(0);
        Self::from_rows(
            shape,
            domain,
            columns,
            (0..rows).map(|r| entries[r * columns..(r + 1) * columns].iter().copied().enumerate()),
        )
    }

    /// A child of `shape` at `domain` over `columns` parent points from its rows' entries
    /// (column, weight), each row's columns ascending; entries of weight `+0.0` are dropped.
    pub(crate) fn from_rows<R: IntoIterator<Item = (usize, f64)>>(
        shape: usize,
        domain: ChildDomain,
        columns: usize,
        rows: impl IntoIterator<Item = R>,
    ) -> Self {
        let (mut starts, mut places, mut weights) = (vec![0u32], Vec::new(), Vec::new());
        for row in rows {
            for (c, w) in row {
                debug_assert!(c < columns, "a column past the parent's points");
                if w.to_bits() != 0 {
                    places.push(c as u32);
                    weights.push(w);
                }
            }
            starts.push(places.len() as u32);
        }
        Self { shape, domain, columns, starts, places, weights }
    }

    /// Row `row`'s entries over the parent's control points, (column, weight), columns
    /// ascending; the columns not listed have weight 0.
    pub fn row(&self, row: usize) -> impl ExactSizeIterator<Item = (usize, f64)> + '_ {
        let range = self.starts[row] as usize..self.starts[row + 1] as usize;
        self.places[range.clone()].iter().zip(&self.weights[range]).map(|(&c, &w)| (c as usize, w))
    }

    /// Row `row` over all the parent's control points.
    pub fn dense_row(&self, row: usize) -> Vec<f64> {
        let mut out = vec![0.0; self.columns];
        self.row(row).for_each(|(c, w)| out[c] = w);
        out
    }

    /// The eigenvalues of a square sub-patch matrix (one that keeps its shape), largest
    /// modulus first, as `(re, im)`.
    ///
    /// # Errors
    /// [`SchemeError::Eigen`] when the matrix is not square or the solver does not converge.
    pub fn eigenvalues(&self) -> Result<Vec<(f64, f64)>, SchemeError> {
        if self.rows() != self.columns {
            return Err(SchemeError::Eigen(format!(
                "a {}×{} sub-patch matrix has no eigenvalues",
                self.rows(),
                self.columns
            )));
        }
        crate::eigen::eigenvalues(self.columns, |i, j| self.get(i, j)).map_err(SchemeError::Eigen)
    }

    /// The child's control points from the parent's.
    ///
    /// # Panics
    /// If `parent` does not have [`columns`](Self::columns) points.
    pub fn apply(&self, parent: &[DVec3]) -> Vec<DVec3> {
        assert_eq!(parent.len(), self.columns, "the parent patch has {} control points", self.columns);
        (0..self.rows()).map(|r| self.row(r).map(|(c, w)| w * parent[c]).sum()).collect()
    }
}
