//! Tangent directions at an irregular fixed point of a patch's address (a cycle whose matrix
//! is not a regular patch's): the leading terms of the cycle's spectrum that the face sees,
//! Jordan chains included, read through the face's characteristic map.

use faer::Mat;
use faer::c64;
use faer::linalg::solvers::DenseSolveCore;
use subdiv_schemes::PatchMatrices;

use crate::linalg::{null_space, null_spaces};
use crate::surface::{Derivatives, TOLERANCE};
use crate::{Dyadic, StencilError, StencilEvaluator};

/// How far apart eigenvalues may be and count as one: a defective eigenvalue comes out of the
/// solver split by about the square root of the rounding (Catmull-Clark's ½ at a boundary
/// vertex of four faces, a 2 × 2 Jordan block, as ½ ± 1e-8 i).
pub(crate) const CLUSTER: f64 = 1e-6;

/// The smallest sine of the angle between the two side directions, in the characteristic map,
/// that counts as spanning a plane.
const SPAN: f64 = 1e-6;

/// Tangent directions at an irregular fixed point, from the cycle's matrix `m` on the control
/// points that influence the face (so an eigenvector the face cannot see, such as one living
/// across an infinitely sharp edge, is not among them) and the limit stencils of the face's
/// `probes` (see [`face_probes`]: the ends of its two sides first, then points on and inside
/// it).
///
/// Near the point the surface over the face is `x₀ + Σ λⁿ (l·x) φ_r`, one term per eigenvalue
/// `λ` after 1 (left eigenvector `l`, right `r`, `φ_r` the limit function of `r` on the face),
/// so the face's tangent plane — the limit of its normals — is spanned by the `l·x` of the
/// two leading terms that the face sees. A defective eigenvalue adds powers of `n`: on a
/// Jordan chain `r₁ … r_L` (`(M − λ) r_{i+1} = r_i`) with dual left vectors `l₁ … l_L`, `Mⁿ`
/// is `Σ_{i≤k} C(n, k−i) λⁿ⁻⁽ᵏ⁻ⁱ⁾ r_i l_k`, so the chain's top `l_L` leads with
/// `n^{L−1} λⁿ φ_{r₁}` and enters as one term at level `L − 1` (the other `l_k` meet the face
/// through the same functions, weaker; see [`jordan_terms`]). So the terms are taken by decreasing modulus and,
/// within a cluster of equal eigenvalues, by decreasing level (one level at a time, the
/// eigenvectors of a semisimple eigenvalue all at level 0); a level whose terms vanish at
/// every probe is one the face does not see, and is skipped; levels are added until the
/// probes' values (the characteristic map of the face) span a plane. `du` and `dv` are the
/// left vectors, made dual to the right ones, combined with the unit direction of the first
/// and of the last side in that map (the map at corner 1 and at corner `face_size − 1`); a
/// side the terms vanish on (a boundary side, when two modes of the interior lead) takes the
/// probe furthest from the other side instead, the edge of the face's image on its side, which
/// keeps the plane and the orientation. Where the two sides are opposite directions (an
/// interior vertex of valence 2, whose faces each cover half a turn of the map) `dv` is the
/// direction of the probe inside the face furthest from that line instead (the far corner, by
/// the face's symmetry): `du` runs along the first side, `dv` into the face, and `du × dv` is
/// the face's normal, oriented as its neighbour's (whose first side is this face's last and
/// whose interior is the other half turn). That is the normal of the leading pair's plane (¼
/// at Catmull-Clark's valence 2): the normals nearby reach it along the sides, and elsewhere
/// differ from it by a few degrees that depend on the direction of approach and alternate
/// with the level (the −¼ of the same modulus). A complex pair enters as the real and imaginary
/// parts of its eigenvectors (the real 2-plane it turns in). For the smooth interior vertex
/// this is the subdominant pair; at a Catmull-Clark boundary vertex of four faces 0.61 and the
/// top of the defective ½ (whose generalized eigenvector is the boundary curve's tangent); of
/// six faces, on the two faces at the boundary, the two interior modes 0.63 and 0.58, as the
/// limit of their normals is (these boundary rules are not tangent-plane continuous there: the
/// boundary curve's ½ leaves that plane). At an infinitely sharp crease each side is such a
/// fan, and a side of four faces couples its ½ to the crease curve's: a 2 × 2 block beside the
/// other side's own ½, which the faces of that side see at level 0 with the crease's tangent.
pub(crate) fn irregular_tangents(m: &Mat<f64>, probes: &[Vec<f64>]) -> Result<Derivatives, String> {
    let values = m.eigenvalues().map_err(|e| format!("eigen solver: {e:?}"))?;
    let after_one = clusters(&values).into_iter().filter(|(lambda, _)| (lambda - c64::new(1.0, 0.0)).norm() >= CLUSTER);
    tangents_from_terms(after_one.map(|(lambda, count)| eigen_terms(m, lambda, count, probes)), m.nrows())
}

/// The tangent pair of [`irregular_tangents`] from the terms of the spectrum's clusters after 1,
/// by decreasing modulus, over `n` points: the terms of each cluster level by level until they
/// span a plane. `E` is the error of a cluster's terms (a message, or a reason to solve
/// otherwise).
pub(crate) fn tangents_from_terms<E: From<String>>(
    clusters: impl IntoIterator<Item = Result<Vec<Term>, E>>,
    n: usize,
) -> Result<Derivatives, E> {
    let mut terms: Vec<Term> = Vec::new();
    // Each term's order of growth, counted from the fastest: one per level of a cluster.
    let mut classes: Vec<usize> = Vec::new();
    for cluster in clusters {
        let mut cluster = cluster?;
        while let Some(level) = cluster.iter().map(|t| t.level).max() {
            let (top, rest): (Vec<Term>, Vec<Term>) = cluster.into_iter().partition(|t| t.level == level);
            cluster = rest;
            if top.iter().all(|t| t.view.iter().all(|x| x.abs() < TOLERANCE)) {
                continue;
            }
            classes.extend(std::iter::repeat_n(classes.last().map_or(0, |c| c + 1), top.len()));
            terms.extend(top);
            if let Some(pair) = side_directions(&terms, &classes, n)? {
                return Ok(pair);
            }
        }
    }
    Err(String::from("the leading eigenvectors that the face sees do not span a plane over it").into())
}

/// The tangent pair of [`irregular_tangents`] from `terms` (of the orders of growth `classes`,
/// 0 the fastest), vectors of `n` weights, or `None` while the probes' values over them do not
/// span a plane.
fn side_directions(terms: &[Term], classes: &[usize], n: usize) -> Result<Option<Derivatives>, String> {
    let probes = terms.first().map_or(0, |t| t.view.len());
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    // Whether two vectors over the terms are independent.
    let independent = |a: &[f64], b: &[f64]| {
        let (aa, bb, ab) = (dot(a, a), dot(b, b), dot(a, b));
        aa.min(bb) > TOLERANCE * TOLERANCE && aa * bb - ab * ab > SPAN * SPAN * aa * bb
    };
    let at = |probe: usize| -> Vec<f64> { terms.iter().map(|t| t.view[probe]).collect() };
    // The probes' values span a plane: some two probes are independent over the terms.
    if !(0..probes).any(|a| (a + 1..probes).any(|b| independent(&at(a), &at(b)))) {
        return Ok(None);
    }
    let seen = |d: &[f64]| dot(d, d) > TOLERANCE * TOLERANCE;
    let cosine = |p: &[f64], o: &[f64]| dot(p, o) / (dot(p, p) * dot(o, o)).sqrt();
    // A side the terms vanish on takes the probe furthest from the other side's direction:
    // the edge of the face's image on its side.
    let side = |probe: usize, other: usize| {
        let d = at(probe);
        if seen(&d) {
            return d;
        }
        let o = at(other);
        (2..probes).map(at).filter(|p| seen(p)).min_by(|a, b| cosine(a, &o).total_cmp(&cosine(b, &o))).unwrap_or(d)
    };
    let (first, mut last) = (side(0, 1), side(1, 0));
    if !independent(&first, &last) {
        // Opposite sides (valence 2): the face is the half turn between them, and the probe
        // most nearly square to them points into it.
        let sine = |p: &[f64]| 1.0 - cosine(p, &first).powi(2);
        let inside = (2..probes).map(at).filter(|p| independent(&first, p)).max_by(|a, b| sine(a).total_cmp(&sine(b)));
        match inside {
            Some(p) if seen(&last) && dot(&first, &last) < 0.0 => last = p,
            _ => return Err("the face's sides have one direction in its characteristic map".into()),
        }
    }
    // Two terms are the plane whatever the sides mix; with more, a side's point at one scale
    // mixes orders that its limit direction does not have, and the weaker ones tilt the normal.
    let (first, last) = if terms.len() > 2 { leading_pair(classes, &first, &last) } else { (first, last) };
    // A side's unit direction in the characteristic map, on the left vectors.
    let along = |d: &[f64]| -> Vec<f64> {
        let length = dot(d, d).sqrt();
        (0..n).map(|i| d.iter().zip(terms).map(|(c, t)| c * t.left[i]).sum::<f64>() / length).collect()
    };
    Ok(Some((along(&first), along(&last))))
}

/// The leading part of the plane of the side points `a` and `b` (vectors over terms of the
/// orders of growth `classes`) as the map's scale shrinks: the limit of `Dₙa ∧ Dₙb`, `Dₙ`
/// scaling each term by its growth, up to its size. It lies in the fastest order either side
/// sees when both see it in two directions; else that order's direction is one side's, and
/// the other side, less its share of that direction, gives its own leading order. The pair
/// keeps the orientation of `a ∧ b`. At a Catmull-Clark corner between infinitely sharp edges
/// whose sector of two faces has an eigenvalue (0.58) above the crease curves' ½
/// (`catmark_inf_crease1`), the smooth side's point mixes the ½ of the curves' tangents into
/// the 0.58's direction, which its limit has alone; here the curve side keeps its tangent and
/// the smooth side gets the 0.58's, and their cross product is the limit of the normals along
/// the curve.
fn leading_pair(classes: &[usize], a: &[f64], b: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let part = |x: &[f64], class: usize| -> Vec<f64> {
        x.iter().zip(classes).map(|(&value, &c)| if c == class { value } else { 0.0 }).collect()
    };
    let lead = |x: &[f64]| classes.iter().zip(x).filter(|(_, value)| value.abs() > TOLERANCE).map(|(&c, _)| c).min();
    let Some(fastest) = lead(a).into_iter().chain(lead(b)).min() else { return (a.to_vec(), b.to_vec()) };
    let (pa, pb) = (part(a, fastest), part(b, fastest));
    let (aa, bb, ab) = (dot(&pa, &pa), dot(&pb, &pb), dot(&pa, &pb));
    if aa.min(bb) > TOLERANCE * TOLERANCE && aa * bb - ab * ab > SPAN * SPAN * aa * bb {
        return (pa, pb);
    }
    let a_leads = aa >= bb;
    let (x, y, px, py) = if a_leads { (a, b, &pa, &pb) } else { (b, a, &pb, &pa) };
    let share = dot(py, px) / dot(px, px);
    let rest: Vec<f64> =
        y.iter().zip(x).zip(classes).map(|((&q, &p), &c)| if c == fastest { 0.0 } else { q - share * p }).collect();
    let Some(next) = lead(&rest) else { return (a.to_vec(), b.to_vec()) };
    let (dx, dy) = (px.clone(), part(&rest, next));
    if a_leads { (dx, dy) } else { (dy, dx) }
}

/// Where [`irregular_tangents`] reads the characteristic map of a face whose corner 0 is the
/// fixed point, in 1/4 units: corner 1 (the end of the first side), the last corner (of the
/// last side), then points between them on the face's far sides. All lie at one scale: where
/// the leading eigenvalues differ, the map turns points towards the stronger term as they near
/// the fixed point, so directions at two scales do not compare.
const QUAD_PROBES: [(i64, i64); 7] = [(4, 0), (0, 4), (4, 4), (4, 2), (2, 4), (4, 1), (1, 4)];
/// As [`QUAD_PROBES`], for triangles (their far side is `u + v = 1`).
const TRIANGLE_PROBES: [(i64, i64); 5] = [(4, 0), (0, 4), (2, 2), (3, 1), (1, 3)];

/// The limit position stencils, on the control points `influence` lists, of the probe points
/// of the face of `shape` around its fixed point `at`: their values on an eigenvector are its
/// limit function there, the characteristic map (which is 0 at the fixed point, whose position
/// stencil is the left eigenvector for 1). Positions only: a probe's own fixed point may be
/// irregular too (a corner on a ternary patch's boundary), and its tangents are not needed.
///
/// At corner 0 the probes are [`QUAD_PROBES`] (a triangle's, [`TRIANGLE_PROBES`]); a quad's
/// fixed point elsewhere — on a dual boundary shape's boundary side, or at the corner of a derived
/// configuration's child that keeps an extraordinary face — takes the same pattern in the
/// frame of the two rays from it along `u` and `v` into the face (each toward the far side of
/// the square), whose images the self-similarity keeps; the signs say which way each ray runs
/// (`−1` against the axis), so that the directions read along them become `∂/∂u` and `∂/∂v`.
pub(crate) fn face_probes(
    matrices: &PatchMatrices,
    shape: usize,
    influence: &[usize],
    at: Dyadic,
) -> Result<(Vec<Vec<f64>>, [f64; 2]), StencilError> {
    let (points, signs): (Vec<Dyadic>, [f64; 2]) = if matrices.face_size == 3 {
        (TRIANGLE_PROBES.iter().map(|&(u, v)| Dyadic::new(u, v, 4)).collect(), [1.0, 1.0])
    } else {
        // At corner 0 (reduced: (0, 0) / 1) these are QUAD_PROBES themselves.
        let Dyadic { u: a, v: b, denominator: q } = at.reduced();
        // Each ray runs to the far side: toward 1 unless the point is on side 1 already.
        let (far_u, far_v) = (if a < q { q } else { 0 }, if b < q { q } else { 0 });
        let sign = |far: i64, x: i64| if far > x { 1.0 } else { -1.0 };
        let points =
            QUAD_PROBES.iter().map(|&(i, j)| Dyadic::new(4 * a + i * (far_u - a), 4 * b + j * (far_v - b), 4 * q));
        (points.collect(), [sign(far_u, a), sign(far_v, b)])
    };
    let mut evaluator = StencilEvaluator::new(matrices).positions_only();
    let probes = points
        .into_iter()
        .map(|p| {
            let s = evaluator.stencil(shape, p)?;
            Ok(influence.iter().map(|&k| s.position[k]).collect())
        })
        .collect::<Result<_, StencilError>>()?;
    Ok((probes, signs))
}

/// One eigen-term of the surface near an irregular fixed point, as a face's sides see it.
pub(crate) struct Term {
    /// The right vector at each probe: the term's coordinate of the probes' points in the
    /// characteristic map.
    view: Vec<f64>,
    /// The left vector, dual to the right one: the term's coefficient is `left · x`.
    left: Vec<f64>,
    /// The power of `n` its coefficient grows with under `Mⁿ`, beside `λⁿ`: its Jordan
    /// chain's length less 1 (0 for an eigenvector of a semisimple eigenvalue).
    level: usize,
}

/// The eigenvalues of `values` grouped into clusters (within [`CLUSTER`] of each other), with
/// their sizes, by decreasing modulus; a complex pair as its member with positive imaginary
/// part, counted once.
pub(crate) fn clusters(values: &[c64]) -> Vec<(c64, usize)> {
    let mut out: Vec<(c64, usize)> = Vec::new();
    for &z in values {
        let z = if z.im < 0.0 { z.conj() } else { z };
        match out.iter_mut().find(|(c, k)| (*c / *k as f64 - z).norm() < CLUSTER) {
            Some((sum, k)) => {
                *sum += z;
                *k += 1;
            }
            None => out.push((z, 1)),
        }
    }
    // Pairs were folded onto one member: count them once.
    let mut out: Vec<(c64, usize)> = out
        .into_iter()
        .map(|(sum, k)| {
            let mean = sum / k as f64;
            if mean.im.abs() < CLUSTER { (c64::new(mean.re, 0.0), k) } else { (mean, k / 2) }
        })
        .collect();
    out.sort_by(|a, b| b.0.norm().total_cmp(&a.0.norm()).then(b.0.re.total_cmp(&a.0.re)));
    out
}

/// The terms of the cluster of `count` eigenvalues at `lambda` (a real one, or a complex pair
/// with `λ̄`) as the face's `probes` see them: per eigenvector of unit length (for a pair, of
/// its real invariant plane) the left vector dual to it, at level 0. A defective cluster gives
/// one term per vector of its Jordan chains instead (see [`jordan_terms`]).
fn eigen_terms(m: &Mat<f64>, lambda: c64, count: usize, probes: &[Vec<f64>]) -> Result<Vec<Term>, String> {
    let n = m.nrows();
    let complex = lambda.im != 0.0;
    // A pair's real invariant plane is the null space of M² − 2 Re λ M + |λ|².
    let shifted = if complex {
        let (s, p) = (2.0 * lambda.re, lambda.norm_sqr());
        let m2 = m * m;
        Mat::<f64>::from_fn(n, n, |i, j| m2[(i, j)] - s * m[(i, j)] + if i == j { p } else { 0.0 })
    } else {
        Mat::<f64>::from_fn(n, n, |i, j| m[(i, j)] - if i == j { lambda.re } else { 0.0 })
    };
    let (right, left) = null_spaces(&shifted)?;
    let dimension = if complex { 2 * count } else { count };
    let d = right.len();
    if d != left.len() || d == 0 {
        return Err(format!("the eigenspaces of {lambda} have dimensions {d} and {}", left.len()));
    }
    if let Some(terms) = semisimple_terms(&right, &left, dimension, probes)? {
        return Ok(terms);
    }
    jordan_terms(&shifted, dimension, probes)
        .map_err(|detail| format!("the eigenvalue {lambda} ({dimension}-fold, {d} eigenvectors): {detail}"))
}

/// The terms of a semisimple cluster of `dimension` (real) dimensions whose right eigenvectors
/// are the orthonormal `right` and left ones span `left`, as the face's `probes` see them: per
/// right vector the left vector dual to it, at level 0. `None` where the cluster is not
/// semisimple: its eigenspaces have other dimensions, or their vectors do not pair.
pub(crate) fn semisimple_terms(
    right: &[Vec<f64>],
    left: &[Vec<f64>],
    dimension: usize,
    probes: &[Vec<f64>],
) -> Result<Option<Vec<Term>>, String> {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let d = right.len();
    if d != dimension || left.len() != d {
        return Ok(None);
    }
    let n = right.first().map_or(0, Vec::len);
    let gram = Mat::<f64>::from_fn(d, d, |a, b| dot(&left[a], &right[b]));
    let smallest =
        gram.singular_values().map_err(|e| format!("SVD failed: {e:?}"))?.into_iter().fold(f64::MAX, f64::min);
    if smallest <= CLUSTER {
        return Ok(None);
    }
    // l'_a = Σ_c H[a][c] l_c with H = (L R)⁻¹, so that l'_a · r_b = δ_ab.
    let h = gram.partial_piv_lu().inverse();
    Ok(Some(
        (0..d)
            .map(|a| Term {
                view: probes.iter().map(|p| dot(p, &right[a])).collect(),
                left: (0..n).map(|i| (0..d).map(|c| h[(a, c)] * left[c][i]).sum()).collect(),
                level: 0,
            })
            .collect(),
    ))
}

/// The terms of a defective cluster from the Jordan chains of `s` (`M − λ`, or a pair's
/// `M² − 2 Re λ M + |λ|²`, whose chains on the pair's real space have the same lengths) on
/// its generalised kernel of `dimension` vectors: one per chain `r₁ … r_L` (`s r₁ = 0`,
/// `s r_{i+1} = r_i`, scaled so that `|r₁| = 1`), its top's dual left vector `l_L`, at level
/// `L − 1`. At a probe, `l_L`'s coefficient is led by the first of `r₁ … r_L` that the probe
/// sees, so that is its view there: a 2 × 2 block's top is seen through its eigenvector, or
/// through the generalized one where the eigenvector vanishes (the boundary curve at a
/// Catmull-Clark boundary vertex of four faces, whose tangent that vector is). The chain's
/// other left vectors `l_k` are no terms: each meets the face through the same function as
/// `l_L` but `n^{L−k}` times weaker, so in the limit of the normals (the cross product of the
/// map's derivatives) it cancels. At an infinitely sharp corner between two crease curves
/// with two faces (`catmark_inf_crease0`) the tangent plane is thus the 2 × 2 block's top (the
/// curves' mean tangent, growing as `n 2⁻ⁿ`) and the simple ½ (their difference), not the
/// chain's eigenvector term, which leaves that plane.
///
/// The chains are built from the top down: the generalised kernel's layers
/// ([`kernel_layers`]) give each level's new chain tops, the part of the layer independent of
/// what `s` carries down from the chains above, and each chain is its top's images under `s`.
/// The left vectors are made dual within the left generalised kernel, so they vanish on every
/// other eigenvalue's vectors.
fn jordan_terms(s: &Mat<f64>, dimension: usize, probes: &[Vec<f64>]) -> Result<Vec<Term>, String> {
    let n = s.nrows();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let apply = |x: &[f64]| -> Vec<f64> { (0..n).map(|i| (0..n).map(|j| s[(i, j)] * x[j]).sum()).collect() };
    let layers = kernel_layers(s, dimension)?;
    // Each chain top first, down to its eigenvector.
    let mut chains: Vec<Vec<Vec<f64>>> = Vec::new();
    for j in (0..layers.len()).rev() {
        for chain in &mut chains {
            let next = apply(&chain[chain.len() - 1]);
            chain.push(next);
        }
        let below = layers[..j].concat();
        let carried: Vec<Vec<f64>> = chains.iter().map(|c| c[c.len() - 1].clone()).collect();
        let fence = [complete(&below, &carried, carried.len())?, below].concat();
        let tops = layers[j]
            .len()
            .checked_sub(carried.len())
            .ok_or_else(|| format!("level {j} has {} vectors under {} chains", layers[j].len(), carried.len()))?;
        chains.extend(complete(&fence, &layers[j], tops)?.into_iter().map(|t| vec![t]));
    }
    let chains: Vec<Vec<Vec<f64>>> = chains
        .into_iter()
        .map(|mut chain| {
            chain.reverse();
            let length = dot(&chain[0], &chain[0]).sqrt();
            chain.into_iter().map(|r| r.iter().map(|x| x / length).collect()).collect()
        })
        .collect();
    let right: Vec<&Vec<f64>> = chains.iter().flatten().collect();
    let left = kernel_layers(&s.transpose().to_owned(), dimension)?.concat();
    let d = right.len();
    if d != dimension || left.len() != dimension {
        return Err(format!("its chains hold {d} vectors"));
    }
    let gram = Mat::<f64>::from_fn(d, d, |a, b| dot(&left[a], right[b]));
    let sigma = gram.singular_values().map_err(|e| format!("SVD failed: {e:?}"))?;
    if sigma.iter().fold(f64::MAX, |a, &b| a.min(b)) <= CLUSTER * sigma.iter().fold(0.0f64, |a, &b| a.max(b)) {
        return Err("its left and right generalised eigenvectors do not pair".into());
    }
    let h = gram.partial_piv_lu().inverse();
    let mut terms = Vec::with_capacity(chains.len());
    let mut top = 0;
    for chain in &chains {
        top += chain.len();
        let views: Vec<Vec<f64>> = chain.iter().map(|r| probes.iter().map(|p| dot(p, r)).collect()).collect();
        let view = (0..probes.len())
            .map(|p| views.iter().map(|v| v[p]).find(|x| x.abs() > TOLERANCE).unwrap_or(views[chain.len() - 1][p]))
            .collect();
        let left = (0..n).map(|i| (0..d).map(|c| h[(top - 1, c)] * left[c][i]).sum()).collect();
        terms.push(Term { view, left, level: chain.len() - 1 });
    }
    Ok(terms)
}

/// Orthonormal bases of the layers of the generalised kernel of `s`, until it has `dimension`
/// vectors: layer `j` completes `ker sʲ` to `ker sʲ⁺¹`, orthogonally. `ker sʲ⁺¹` is the kernel
/// of `s` followed by the projection off `ker sʲ`, so no power of `s` is formed (whose
/// singular values would shrink with the power, and blur the null space's threshold).
fn kernel_layers(s: &Mat<f64>, dimension: usize) -> Result<Vec<Vec<Vec<f64>>>, String> {
    let n = s.nrows();
    let mut layers: Vec<Vec<Vec<f64>>> = Vec::new();
    let mut below: Vec<Vec<f64>> = Vec::new();
    while below.len() < dimension {
        // (1 − K Kᵀ) s for the orthonormal K of the layers so far.
        let ks: Vec<Vec<f64>> =
            below.iter().map(|k| (0..n).map(|j| (0..n).map(|i| k[i] * s[(i, j)]).sum()).collect()).collect();
        let t = Mat::<f64>::from_fn(n, n, |i, j| {
            s[(i, j)] - below.iter().zip(&ks).map(|(k, row)| k[i] * row[j]).sum::<f64>()
        });
        let kernel = null_space(&t, false)?;
        let new = kernel.len().saturating_sub(below.len());
        if new == 0 || below.len() + new > dimension {
            return Err(format!(
                "its generalised kernel grows from {} to {} of {dimension} dimensions",
                below.len(),
                kernel.len()
            ));
        }
        let layer = complete(&below, &kernel, new)?;
        below.extend(layer.iter().cloned());
        layers.push(layer);
    }
    Ok(layers)
}

/// The smallest part of a vector, relative to its length, that counts as independent of a
/// subspace.
const INDEPENDENT: f64 = 1e-6;

/// `count` orthonormal vectors in the span of `candidates` and orthogonal to the orthonormal
/// `basis`: Gram–Schmidt (twice, for orthogonality to the last bits), each time on the
/// candidate with the largest part left relative to its length.
pub(crate) fn complete(basis: &[Vec<f64>], candidates: &[Vec<f64>], count: usize) -> Result<Vec<Vec<f64>>, String> {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut chosen: Vec<Vec<f64>> = Vec::with_capacity(count);
    let mut rest: Vec<&Vec<f64>> = candidates.iter().collect();
    for _ in 0..count {
        let part = |c: &[f64]| {
            let mut x = c.to_vec();
            for _ in 0..2 {
                for b in basis.iter().chain(&chosen) {
                    let k = dot(&x, b);
                    x.iter_mut().zip(b).for_each(|(y, b)| *y -= k * b);
                }
            }
            let relative = (dot(&x, &x) / dot(c, c)).sqrt();
            (x, if relative.is_finite() { relative } else { 0.0 })
        };
        let (i, (x, relative)) = rest
            .iter()
            .map(|c| part(c))
            .enumerate()
            .max_by(|a, b| a.1.1.total_cmp(&b.1.1))
            .ok_or_else(|| format!("{} vectors do not complete {} by {count}", candidates.len(), basis.len()))?;
        if relative < INDEPENDENT {
            return Err(format!("{} vectors do not complete {} by {count}", candidates.len(), basis.len()));
        }
        let length = dot(&x, &x).sqrt();
        chosen.push(x.iter().map(|y| y / length).collect());
        rest.remove(i);
    }
    Ok(chosen)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(P J P⁻¹, P, P⁻¹)` for a fixed well-conditioned `P`.
    fn similar(j: &Mat<f64>) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
        let n = j.nrows();
        let p = Mat::<f64>::from_fn(n, n, |a, b| f64::from(u8::from(a == b)) + 0.2 * ((7 * a + 3 * b) as f64).sin());
        let inverse = p.partial_piv_lu().inverse();
        (&p * j * &inverse, p, inverse)
    }

    #[test]
    fn jordan_terms_are_the_chains_tops_at_their_levels() {
        // ½ as blocks of 3, 2 and 1 (so 6-fold with 3 eigenvectors) beside 0.3 and 0.1.
        let n = 8;
        let diagonal = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.3, 0.1];
        let j = Mat::<f64>::from_fn(n, n, |a, b| match b.checked_sub(a) {
            Some(0) => diagonal[a],
            Some(1) if [0, 1, 3].contains(&a) => 1.0,
            _ => 0.0,
        });
        let (m, p, inverse) = similar(&j);
        let column = |c: usize| -> Vec<f64> { (0..n).map(|i| p[(i, c)]).collect() };
        let probes: Vec<Vec<f64>> = (0..n).map(|r| (0..n).map(|i| inverse[(r, i)]).collect()).collect();
        let terms = eigen_terms(&m, c64::new(0.5, 0.0), 6, &probes).unwrap();
        assert_eq!(terms.iter().map(|t| t.level).collect::<Vec<_>>(), [2, 1, 0]);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        // A chain's top of length L pairs with its top and vanishes on ker (M − ½)^(L−1) and on
        // the other eigenvalues' vectors, whatever basis the chains were built in.
        for (term, (top, kernel)) in terms.iter().zip([(2, &[0, 1, 3, 4, 5][..]), (4, &[0, 3, 5]), (5, &[])]) {
            assert!(dot(&term.left, &column(top)).abs() > 1e-3, "level {}", term.level);
            for &c in kernel.iter().chain(&[6, 7]) {
                assert!(dot(&term.left, &column(c)).abs() < 1e-9, "level {}: column {c}", term.level);
            }
        }
        // Probe k reads column k: the longest chain's top is seen through its eigenvector
        // (column 0) at probe 0, where that vanishes through the next (column 1, then 2), all
        // of one scale; the other eigenvalues' probes see nothing.
        let top = &terms[0].view;
        assert!(top[0].abs() > 1e-3 && (top[1] - top[0]).abs() < 1e-9 && (top[2] - top[0]).abs() < 1e-9, "{top:?}");
        assert!(top[6].abs() < 1e-9 && top[7].abs() < 1e-9, "{top:?}");
    }

    #[test]
    fn semisimple_clusters_are_level_zero_and_dual() {
        let n = 5;
        let diagonal = [0.5, 0.5, 0.25, 0.25, 0.1];
        let (m, p, _) = similar(&Mat::<f64>::from_fn(n, n, |a, b| if a == b { diagonal[a] } else { 0.0 }));
        let probes: Vec<Vec<f64>> = (0..n).map(|r| (0..n).map(|i| f64::from(u8::from(i == r))).collect()).collect();
        let terms = eigen_terms(&m, c64::new(0.5, 0.0), 2, &probes).unwrap();
        assert_eq!(terms.len(), 2);
        for t in &terms {
            assert_eq!(t.level, 0);
            for c in 2..n {
                let along: f64 = (0..n).map(|i| t.left[i] * p[(i, c)]).sum();
                assert!(along.abs() < 1e-9, "column {c}: {along}");
            }
        }
    }
}
