//! The discrete Fourier structure of an extraordinary vertex's matrix (Stam's and Lai and
//! Cheng's analyses): the canonical interior patch is symmetric under the rotation that takes
//! each face around the vertex to the next, so the matrix of the child that keeps the vertex
//! maps the *ring* (the points that rotation permutes in whole orbits: the vertex and its
//! rings of neighbours) onto itself, block-circulant. Its eigenvalues and eigenvectors come from
//! one small block per frequency, each of the size of the orbits' count (2 for Catmull-Clark, 1
//! for Loop, plus the vertex at frequency 0), so the spectrum of a valence-`N` vertex costs
//! `O(N)` where the dense matrix's costs `O(N³)`.

use std::collections::HashMap;
use std::f64::consts::TAU;

use faer::linalg::solvers::Solve;
use faer::{Mat, c64};
use subdiv_mesh::{HalfEdgeId, Mesh, VertexId};

/// Singular values of a block's shifted matrix below this count as zero (the dense eigenspaces'
/// tolerance, on the same scale: each block is the matrix on orthonormal vectors).
const NULL_TOLERANCE: f64 = 1e-9;

/// How far apart eigenvalues may be and count as one (the stencils' eigenvalue clusters').
pub(super) const CLUSTER: f64 = 1e-6;

/// Two matrix entries that the rotation maps onto each other may differ by this much.
const SYMMETRY_TOLERANCE: f64 = 1e-12;

/// The rotation of the patch at `start` about its corner 0: per control point, the place of the
/// same vertex in the patch of the next face around corner 0 (across the face's last side), or
/// `None` where that patch does not hold it. `None` when the two patches' shapes differ (a
/// sharp spoke, a boundary: no rotation maps one onto the other).
pub(crate) fn patch_rotation(mesh: &Mesh, start: HalfEdgeId, radius: usize) -> Option<Vec<Option<u32>>> {
    let next = mesh.twin(mesh.prev(start))?;
    let (here, there) = (mesh.patch(start, radius), mesh.patch(next, radius));
    if here.signature != there.signature {
        return None;
    }
    let place: HashMap<VertexId, u32> = there.vertices.iter().enumerate().map(|(k, &v)| (v, k as u32)).collect();
    Some(here.vertices.iter().map(|v| place.get(v).copied()).collect())
}

/// Where a point of the matrix sits in the ring's structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Place {
    /// A point the rotation keeps (the extraordinary vertex), by its number among them.
    Fixed(usize),
    /// Point `k` of orbit `q`: the orbit's first point turned `k` times.
    Orbit(usize, usize),
    /// A point outside the ring (of the face's far side), by its number among them.
    Rest(usize),
}

/// Which block an eigenvalue of a [`RingSpectrum`] comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Frequency {
    /// The ring's block of frequency `ω` (`0..N`): eigenvectors that turn by `e^{2πiω/N}` from
    /// one face to the next.
    Ring(usize),
    /// The points outside the ring (their own block of the matrix, below the ring's).
    Rest,
}

/// The spectrum of a square matrix over a patch's points that commutes with a rotation of its
/// ring (see the module's doc): per frequency `ω` the block `B(ω)`, the matrix on the ring's
/// vectors of that frequency (orthonormal: `e^{2πiωk/N}/√N` on an orbit's `k`-th point, and the
/// fixed points at `ω = 0`), and the dense block of the points outside the ring.
///
/// With the ring first, the matrix is `[[R, 0], [X, Y]]` (ring rows read the ring only), and
/// `R` is unitarily similar to the blocks' direct sum. A right eigenvector of `R` for `λ`
/// extends to the matrix's as `(r, (λ − Y)⁻¹ X r)`; a left one as `(l, 0)`.
#[derive(Clone, Debug)]
pub struct RingSpectrum {
    valence: usize,
    /// The matrix's size.
    size: usize,
    fixed: Vec<usize>,
    /// `orbits[q][k]`: the `k`-th point of orbit `q`.
    orbits: Vec<Vec<usize>>,
    rest: Vec<usize>,
    /// `B(ω)` for `ω` in `0..N`.
    blocks: Vec<Mat<c64>>,
    /// The eigenvalues of each block.
    values: Vec<Vec<c64>>,
    /// `Y`: the rest's rows over the rest.
    rest_block: Mat<f64>,
    /// `X`: the rest's rows over the ring, as (point, weight).
    coupling: Vec<Vec<(usize, f64)>>,
    rest_values: Vec<c64>,
}

impl RingSpectrum {
    /// The spectrum of the `rows.len()`-square matrix whose row `i` holds the weights `rows[i]`
    /// (column, weight), under `rotation` (per point, its image: its vertex's place in the next
    /// face's patch) of `valence` steps. `None` unless the ring is invariant and the matrix commutes with the
    /// rotation on it, every orbit of `valence` points.
    pub fn new(rows: &[Vec<(usize, f64)>], rotation: &[Option<usize>], valence: usize) -> Option<Self> {
        let size = rows.len();
        if rotation.len() != size || valence < 2 {
            return None;
        }
        // The orbits: a point whose images come back to it after `valence` turns, each defined.
        let mut place = vec![None; size];
        let (mut fixed, mut orbits) = (Vec::new(), Vec::new());
        for i in 0..size {
            if place[i].is_some() {
                continue;
            }
            if rotation[i] == Some(i) {
                place[i] = Some(Place::Fixed(fixed.len()));
                fixed.push(i);
                continue;
            }
            let mut orbit = vec![i];
            let mut j = i;
            while let Some(next) = rotation[j].filter(|&n| n < size && orbit.len() <= valence) {
                if next == i {
                    break;
                }
                orbit.push(next);
                j = next;
            }
            if rotation[j] == Some(i) && orbit.len() == valence && orbit.iter().all(|&k| place[k].is_none()) {
                let q = orbits.len();
                orbit.iter().enumerate().for_each(|(k, &p)| place[p] = Some(Place::Orbit(q, k)));
                orbits.push(orbit);
            }
        }
        if orbits.is_empty() {
            return None;
        }
        let mut rest = Vec::new();
        let place: Vec<Place> = place
            .into_iter()
            .enumerate()
            .map(|(i, p)| {
                p.unwrap_or_else(|| {
                    rest.push(i);
                    Place::Rest(rest.len() - 1)
                })
            })
            .collect();
        let in_ring = |p: Place| !matches!(p, Place::Rest(_));
        let turn = |i: usize| rotation[i].expect("a ring point has an image");
        // The ring rows read the ring only, and the rotation maps each onto its image's row.
        let mut image_row = vec![0.0; size];
        for i in (0..size).filter(|&i| in_ring(place[i])) {
            let row = &rows[i];
            if row.iter().any(|&(j, w)| w != 0.0 && !in_ring(place[j])) {
                return None;
            }
            let image = &rows[turn(i)];
            image.iter().for_each(|&(j, w)| image_row[j] += w);
            let matches = row.iter().all(|&(j, w)| (image_row[turn(j)] - w).abs() <= SYMMETRY_TOLERANCE)
                && image.iter().filter(|e| e.1 != 0.0).count() == row.iter().filter(|e| e.1 != 0.0).count();
            image.iter().for_each(|&(j, _)| image_row[j] = 0.0);
            if !matches {
                return None;
            }
        }
        let (nf, p) = (fixed.len(), orbits.len());
        let root = (valence as f64).sqrt();
        // ζ^m for m in 0..N, from the exact residue.
        let powers: Vec<c64> = (0..valence)
            .map(|m| {
                let angle = TAU * m as f64 / valence as f64;
                c64::new(angle.cos(), angle.sin())
            })
            .collect();
        let mut blocks: Vec<Mat<c64>> =
            (0..valence).map(|w| if w == 0 { Mat::zeros(nf + p, nf + p) } else { Mat::zeros(p, p) }).collect();
        for (a, &f) in fixed.iter().enumerate() {
            for &(j, w) in &rows[f] {
                match place[j] {
                    Place::Fixed(b) => blocks[0][(a, b)] += c64::new(w, 0.0),
                    Place::Orbit(q, _) => blocks[0][(a, nf + q)] += c64::new(w / root, 0.0),
                    Place::Rest(_) => unreachable!("checked: ring rows read the ring"),
                }
            }
        }
        for (q, orbit) in orbits.iter().enumerate() {
            for &(j, w) in &rows[orbit[0]] {
                match place[j] {
                    Place::Fixed(a) => blocks[0][(nf + q, a)] += c64::new(w * root, 0.0),
                    Place::Orbit(r, k) => {
                        for (omega, block) in blocks.iter_mut().enumerate() {
                            let at = if omega == 0 { (nf + q, nf + r) } else { (q, r) };
                            block[at] += powers[omega * k % valence] * w;
                        }
                    }
                    Place::Rest(_) => unreachable!("checked: ring rows read the ring"),
                }
            }
        }
        let values = blocks.iter().map(|b| b.eigenvalues().ok()).collect::<Option<Vec<_>>>()?;
        let index_in_rest = |j: usize| match place[j] {
            Place::Rest(r) => Some(r),
            _ => None,
        };
        let mut rest_block = Mat::<f64>::zeros(rest.len(), rest.len());
        let mut coupling = Vec::with_capacity(rest.len());
        for (r, &i) in rest.iter().enumerate() {
            let mut ring = Vec::new();
            for &(j, w) in &rows[i] {
                match index_in_rest(j) {
                    Some(c) => rest_block[(r, c)] += w,
                    None => ring.push((j, w)),
                }
            }
            coupling.push(ring);
        }
        let rest_values = if rest.is_empty() { Vec::new() } else { rest_block.eigenvalues().ok()? };
        Some(Self { valence, size, fixed, orbits, rest, blocks, values, rest_block, coupling, rest_values })
    }

    /// The rotation's order: the faces around the vertex.
    pub fn valence(&self) -> usize {
        self.valence
    }

    /// The matrix's size: the points it is over.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The eigenvalues of the ring's block of frequency `omega` (none past the valence).
    pub fn block_eigenvalues(&self, omega: usize) -> &[c64] {
        self.values.get(omega).map_or(&[], Vec::as_slice)
    }

    /// The matrix's eigenvalues, each with the block it comes from.
    pub fn eigenvalues(&self) -> impl Iterator<Item = (Frequency, c64)> + '_ {
        let ring = self.values.iter().enumerate().flat_map(|(w, v)| v.iter().map(move |&z| (Frequency::Ring(w), z)));
        ring.chain(self.rest_values.iter().map(|&z| (Frequency::Rest, z)))
    }

    /// Right eigenvectors of the matrix for the eigenvalue `lambda` of the ring's block `omega`
    /// (a basis of that block's eigenspace, orthonormal on the ring), over all the matrix's
    /// points. `None` where `lambda` is also an eigenvalue of the rest's block (within
    /// `separation`), whose vectors these are not.
    pub fn right_vectors(&self, omega: usize, lambda: c64, separation: f64) -> Option<Vec<Vec<c64>>> {
        if self.rest_values.iter().any(|&z| (z - lambda).norm() < separation) {
            return None;
        }
        let (right, _) = self.block_null_vectors(omega, lambda)?;
        // (λ − Y) y = X r, the rest's part of each vector.
        let shifted = Mat::<c64>::from_fn(self.rest.len(), self.rest.len(), |i, j| {
            let diagonal = if i == j { lambda } else { c64::new(0.0, 0.0) };
            diagonal - c64::new(self.rest_block[(i, j)], 0.0)
        });
        let lu = (!self.rest.is_empty()).then(|| shifted.partial_piv_lu());
        Some(
            right
                .into_iter()
                .map(|v| {
                    let mut full = self.spread(omega, &v, false);
                    if let Some(lu) = &lu {
                        let x = Mat::<c64>::from_fn(self.rest.len(), 1, |r, _| {
                            self.coupling[r].iter().map(|&(j, w)| full[j] * w).sum::<c64>()
                        });
                        let y = lu.solve(&x);
                        self.rest.iter().enumerate().for_each(|(r, &i)| full[i] = y[(r, 0)]);
                    }
                    full
                })
                .collect(),
        )
    }

    /// Left eigenvectors of the matrix for the eigenvalue `lambda` of the ring's block `omega`,
    /// over all its points (zero outside the ring): the dual vectors of the block's left
    /// eigenspace.
    pub fn left_vectors(&self, omega: usize, lambda: c64) -> Option<Vec<Vec<c64>>> {
        let (_, left) = self.block_null_vectors(omega, lambda)?;
        Some(left.into_iter().map(|w| self.spread(omega, &w, true)).collect())
    }

    /// An orthonormal basis of the real space that the right eigenvectors (or the left ones,
    /// if `left`) of the blocks `omegas` for the eigenvalues `targets` span: their real and
    /// imaginary parts (a complex pair's real invariant plane, a real eigenvalue's eigenspace
    /// with its mirror frequency's). Only blocks that hold a target (within `CLUSTER`) are
    /// asked. `None` where the rest's block holds a target too.
    pub fn real_eigenspace(&self, omegas: &[usize], targets: &[c64], left: bool) -> Option<Vec<Vec<f64>>> {
        let mut parts = Vec::new();
        for &omega in omegas {
            for &target in targets {
                if !self.block_eigenvalues(omega).iter().any(|z| (z - target).norm() < CLUSTER) {
                    continue;
                }
                let vectors =
                    if left { self.left_vectors(omega, target)? } else { self.right_vectors(omega, target, CLUSTER)? };
                for v in vectors {
                    parts.push(v.iter().map(|z| z.re).collect::<Vec<f64>>());
                    parts.push(v.iter().map(|z| z.im).collect());
                }
            }
        }
        Some(orthonormal(parts))
    }

    /// A block's vector over the whole matrix: `v_q e^{±2πiωk/N}/√N` on orbit `q`'s `k`-th point
    /// (the sign `−` for a left vector), `v_a` on fixed point `a` at `ω = 0`.
    fn spread(&self, omega: usize, v: &[c64], left: bool) -> Vec<c64> {
        let n = self.valence;
        let nf = if omega == 0 { self.fixed.len() } else { 0 };
        let mut out = vec![c64::new(0.0, 0.0); self.size];
        self.fixed.iter().take(nf).enumerate().for_each(|(a, &i)| out[i] = v[a]);
        let root = (n as f64).sqrt();
        for (q, orbit) in self.orbits.iter().enumerate() {
            for (k, &i) in orbit.iter().enumerate() {
                let m = omega * k % n;
                let angle = TAU * m as f64 / n as f64 * if left { -1.0 } else { 1.0 };
                out[i] = v[nf + q] * c64::new(angle.cos(), angle.sin()) / root;
            }
        }
        out
    }

    /// Orthonormal bases of the right and left null spaces of `B(ω) − λ` (left ones as row
    /// vectors: `w (B − λ) = 0`), from one SVD; `None` if the SVD fails.
    #[allow(clippy::type_complexity)]
    fn block_null_vectors(&self, omega: usize, lambda: c64) -> Option<(Vec<Vec<c64>>, Vec<Vec<c64>>)> {
        let block = self.blocks.get(omega)?;
        let n = block.nrows();
        let shifted =
            Mat::<c64>::from_fn(n, n, |i, j| block[(i, j)] - if i == j { lambda } else { c64::new(0.0, 0.0) });
        let svd = shifted.svd().ok()?;
        let sigma = svd.S().column_vector();
        let null: Vec<usize> = (0..n).filter(|&c| sigma[c].re < NULL_TOLERANCE).collect();
        // A = U Σ Vᴴ: A v = 0 for V's null columns, and uᴴ A = 0 for U's.
        let right = null.iter().map(|&c| (0..n).map(|r| svd.V()[(r, c)]).collect()).collect();
        let left = null.iter().map(|&c| (0..n).map(|r| svd.U()[(r, c)].conj()).collect()).collect();
        Some((right, left))
    }
}

/// The smallest part of a vector, relative to its length, that counts as independent of the
/// vectors before it.
const INDEPENDENT: f64 = 1e-6;

/// An orthonormal basis of the span of `vectors`: Gram-Schmidt, twice (for orthogonality to
/// the last bits), dropping a vector whose part outside the basis so far is below
/// [`INDEPENDENT`] of its length or of the longest vector's (a real eigenvector's imaginary
/// part is its rounding, in no direction in particular).
fn orthonormal(vectors: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let longest = vectors.iter().map(|x| dot(x, x).sqrt()).fold(0.0, f64::max);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for mut x in vectors {
        let length = dot(&x, &x).sqrt().max(longest);
        for _ in 0..2 {
            for b in &basis {
                let k = dot(&x, b);
                x.iter_mut().zip(b).for_each(|(y, b)| *y -= k * b);
            }
        }
        let part = dot(&x, &x).sqrt();
        if part > INDEPENDENT * length {
            basis.push(x.into_iter().map(|y| y / part).collect());
        }
    }
    basis
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Builtin, PatchMatrices, PatchType};
    use subdiv_mesh::BoundaryInterpolation;

    /// The ring's blocks hold the dense matrix's eigenvalues, with the rest's, for Catmull-Clark
    /// and Loop at valences 3 to 12.
    #[test]
    fn the_blocks_hold_the_dense_spectrum() {
        for builtin in [Builtin::CatmullClark, Builtin::Loop] {
            for valence in (3..=12).filter(|&v| v != builtin.scheme().regular_valence()) {
                let m =
                    PatchMatrices::of(builtin.scheme(), PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)
                        .unwrap();
                let spectrum = m.ring_spectrum(0).unwrap_or_else(|| panic!("{builtin} {valence}: no ring"));
                let mut ours: Vec<c64> = spectrum.eigenvalues().map(|(_, z)| z).collect();
                let influence: Vec<usize> = m.shapes[0].influence.iter().map(|&k| k as usize).collect();
                let child = &m.shapes[0].children[0];
                let dense =
                    Mat::<f64>::from_fn(influence.len(), influence.len(), |i, j| child.get(influence[i], influence[j]));
                let mut theirs = dense.eigenvalues().unwrap();
                let key = |z: &c64| (z.re * 1e6).round() as i64 * 1_000_000_000 + (z.im.abs() * 1e6).round() as i64;
                ours.sort_by_key(key);
                theirs.sort_by_key(key);
                assert_eq!(ours.len(), theirs.len(), "{builtin} {valence}");
                for (a, b) in ours.iter().zip(&theirs) {
                    assert!(
                        (a.re - b.re).abs() < 1e-7 && (a.im.abs() - b.im.abs()).abs() < 1e-7,
                        "{builtin} {valence}: {a} {b}"
                    );
                }
                // Eigenvectors: M r = λ r and l M = λ l for the subdominant block's.
                let lambda = spectrum.values[1].iter().copied().max_by(|a, b| a.norm().total_cmp(&b.norm())).unwrap();
                let rights = spectrum.right_vectors(1, lambda, 1e-9).unwrap();
                let lefts = spectrum.left_vectors(1, lambda).unwrap();
                assert!(!rights.is_empty() && rights.len() == lefts.len());
                let n = influence.len();
                for (r, l) in rights.iter().zip(&lefts) {
                    for i in 0..n {
                        let mr: c64 = (0..n).map(|j| r[j] * dense[(i, j)]).sum();
                        let lm: c64 = (0..n).map(|j| l[j] * dense[(j, i)]).sum();
                        assert!((mr - r[i] * lambda).norm() < 1e-12, "{builtin} {valence}: right");
                        assert!((lm - l[i] * lambda).norm() < 1e-12, "{builtin} {valence}: left");
                    }
                }
            }
        }
    }
}
