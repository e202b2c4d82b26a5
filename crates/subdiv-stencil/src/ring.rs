//! The limit stencil at an extraordinary vertex from its ring's frequency blocks
//! ([`RingSpectrum`]): the same position and tangent directions as the dense eigenproblems of
//! [`surface`](crate::surface) and [`tangents`](crate::tangents), in `O(N)` at valence `N`
//! where those cost `O(N³)` (20 s at valence 1000).
//!
//! The dense route groups eigenvalues within [`CLUSTER`] of each other, which at a large valence
//! joins the frequencies' eigenvalues (Catmull-Clark's leading ones of frequencies 1 and 2 are
//! 7e-8 apart at valence 10 000). Here a cluster holds one frequency's eigenvalues within
//! [`CLUSTER`] (and its mirror's, `N − ω`, which are the conjugates), and another frequency's
//! only where they are equal to the rounding ([`SAME`]): eigenvectors of different frequencies
//! turn differently around the vertex, so they are different terms of the surface however close
//! their eigenvalues. Below a valence of a few hundred the two groupings agree.

use faer::c64;
use subdiv_schemes::{Frequency, RingSpectrum};

use crate::surface::Derivatives;
use crate::tangents::{CLUSTER, Term, clusters, semisimple_terms, tangents_from_terms};

/// How close eigenvalues of different frequencies must be to count as one: their rounding.
/// Where they only come close (Catmull-Clark's leading ones of frequencies 1 and 2, 7e-8 apart
/// at valence 10 000 and 7e-10 at 100 000) they stay apart.
const SAME: f64 = 1e-10;

/// Why the blocks do not give an answer.
enum Stop {
    /// Something they do not hold (an eigenvalue of the rest, a defective or repeated one):
    /// the dense route decides.
    Dense,
    /// A failure the dense route would meet as well.
    Failed(String),
}

impl From<String> for Stop {
    fn from(detail: String) -> Self {
        Self::Failed(detail)
    }
}

/// The left eigenvector of `ring`'s matrix for 1, normalised to sum 1 (the limit position's
/// stencil), over all its points; `None` unless 1 is a simple eigenvalue, of frequency 0.
pub(crate) fn ring_position(ring: &RingSpectrum) -> Option<Vec<f64>> {
    let one = c64::new(1.0, 0.0);
    let mut near = ring.eigenvalues().filter(|(_, z)| (z - one).norm() < CLUSTER);
    if near.next()?.0 != Frequency::Ring(0) || near.next().is_some() {
        return None;
    }
    let mut left = ring.left_vectors(0, one)?;
    let w = left.pop().filter(|_| left.is_empty())?;
    let sum: c64 = w.iter().sum();
    (sum.norm() > CLUSTER).then(|| w.iter().map(|z| (z / sum).re).collect())
}

/// The tangent directions of [`irregular_tangents`](crate::tangents::irregular_tangents) at the
/// fixed point of `ring`'s matrix, from the face's `probes`; `Ok(None)` where the terms it
/// reaches are not all semisimple eigenvalues of the ring's blocks (the dense route decides).
pub(crate) fn ring_tangents(ring: &RingSpectrum, probes: &[Vec<f64>]) -> Result<Option<Derivatives>, String> {
    let n = ring.valence();
    // Each frequency with its mirror: their eigenvalues are one cluster's conjugates.
    let class = |f: Frequency| match f {
        Frequency::Ring(w) => Frequency::Ring(w.min(n - w)),
        Frequency::Rest => Frequency::Rest,
    };
    let mut values: Vec<(Frequency, c64)> = ring.eigenvalues().map(|(f, z)| (class(f), z)).collect();
    values.sort_by_key(|v| v.0);
    let per_frequency: Vec<(Frequency, c64, usize)> = values
        .chunk_by(|a, b| a.0 == b.0)
        .flat_map(|group| {
            let zs: Vec<c64> = group.iter().map(|v| v.1).collect();
            clusters(&zs).into_iter().map(move |(lambda, count)| (group[0].0, lambda, count))
        })
        .collect();
    // Equal eigenvalues of different frequencies, to the rounding, are one cluster (Catmull-Clark's
    // ¼ at valence 2, of frequencies 0 and 1: the leading pair).
    let mut all: Vec<(Vec<Frequency>, c64, usize)> = Vec::new();
    for (f, lambda, count) in per_frequency {
        match all.iter_mut().find(|(_, z, _)| (*z - lambda).norm() < SAME) {
            Some((fs, _, k)) => {
                fs.push(f);
                *k += count;
            }
            None => all.push((vec![f], lambda, count)),
        }
    }
    // As the dense clusters: by decreasing modulus, then real part; moduli equal to the rounding
    // are equal (Catmull-Clark's ¼ pair at valence 2 leads the −¼ of frequency 0, whichever
    // rounds larger).
    let modulus = |z: c64| (z.norm() / SAME).round();
    all.sort_by(|a, b| modulus(b.1).total_cmp(&modulus(a.1)).then(b.1.re.total_cmp(&a.1.re)));
    let one = c64::new(1.0, 0.0);
    let after_one = all.into_iter().filter(|(_, lambda, _)| (lambda - one).norm() >= CLUSTER);
    let size = ring.size();
    match tangents_from_terms(
        after_one.map(|(f, lambda, count)| frequency_terms(ring, &f, lambda, count, probes)),
        size,
    ) {
        Ok(pair) => Ok(Some(pair)),
        Err(Stop::Dense) => Ok(None),
        Err(Stop::Failed(detail)) => Err(detail),
    }
}

/// The terms of the cluster of `count` eigenvalues at `lambda` (a real one, or a complex pair)
/// of the `frequencies` and their mirrors: the real and imaginary parts of the blocks' eigenvectors,
/// made orthonormal, with the left vectors dual to them ([`semisimple_terms`]).
fn frequency_terms(
    ring: &RingSpectrum,
    frequencies: &[Frequency],
    lambda: c64,
    count: usize,
    probes: &[Vec<f64>],
) -> Result<Vec<Term>, Stop> {
    let n = ring.valence();
    let mut omegas = Vec::new();
    for &f in frequencies {
        let Frequency::Ring(w) = f else { return Err(Stop::Dense) };
        omegas.extend(if w == 0 || 2 * w == n { vec![w] } else { vec![w, n - w] });
    }
    let complex = lambda.im != 0.0;
    let dimension = if complex { 2 * count } else { count };
    let targets = if complex { vec![lambda, lambda.conj()] } else { vec![lambda] };
    let right_basis = ring.real_eigenspace(&omegas, &targets, false).ok_or(Stop::Dense)?;
    let left_basis = ring.real_eigenspace(&omegas, &targets, true).ok_or(Stop::Dense)?;
    semisimple_terms(&right_basis, &left_basis, dimension, probes)?.ok_or(Stop::Dense)
}
