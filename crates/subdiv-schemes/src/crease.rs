//! OpenSubdiv's creasing rules (`Sdc::Crease`), in single precision as OpenSubdiv computes
//! them, so that fractional weights of semi-sharp features match bit for bit.

use subdiv_mesh::CreaseMethod;

/// Sharpness at or above which a feature is infinitely sharp.
pub(crate) const INFINITE: f32 = 10.0;

/// How a vertex refines (`Sdc::Crease::Rule`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rule {
    /// No sharp edge.
    Smooth,
    /// One sharp edge: refined with the smooth rule.
    Dart,
    /// Two sharp edges: the curve rule along them.
    Crease,
    /// A sharp vertex, or more than two sharp edges: the vertex stays.
    Corner,
}

pub(crate) fn is_sharp(s: f32) -> bool {
    s > 0.0
}

pub(crate) fn is_infinite(s: f32) -> bool {
    s >= INFINITE
}

pub(crate) fn is_semi_sharp(s: f32) -> bool {
    s > 0.0 && s < INFINITE
}

/// `Sdc::Crease::DetermineVertexVertexRule`.
pub(crate) fn vertex_rule(vertex_sharpness: f32, edge_sharpness: &[f32]) -> Rule {
    if is_sharp(vertex_sharpness) {
        return Rule::Corner;
    }
    match edge_sharpness.iter().filter(|&&s| is_sharp(s)).count() {
        0 => Rule::Smooth,
        1 => Rule::Dart,
        2 => Rule::Crease,
        _ => Rule::Corner,
    }
}

/// One level less sharp: infinite stays infinite, values at or below 1 become smooth.
pub(crate) fn decrement(s: f32) -> f32 {
    if is_infinite(s) {
        INFINITE
    } else if s > 1.0 {
        s - 1.0
    } else {
        0.0
    }
}

/// The sharpness of the child of an edge of sharpness `s` at one of its end vertices, whose
/// incident edges have `around` sharpness (`Sdc::Crease::SubdivideEdgeSharpnessAtVertex`).
pub(crate) fn child_edge_sharpness(method: CreaseMethod, s: f32, around: &[f32]) -> f32 {
    if method == CreaseMethod::Uniform || around.len() < 2 {
        return decrement(s);
    }
    if !is_sharp(s) {
        return 0.0;
    }
    if is_infinite(s) {
        return INFINITE;
    }
    let (mut sum, mut count) = (0.0f32, 0u32);
    for &a in around {
        if is_semi_sharp(a) {
            sum += a;
            count += 1;
        }
    }
    let mut s = s;
    if count > 1 {
        // Chaikin: three quarters of the edge's own sharpness, a quarter of its neighbours'.
        let average = (sum - s) / (count - 1) as f32;
        s = 0.75 * s + 0.25 * average;
    }
    s -= 1.0;
    if is_sharp(s) { s } else { 0.0 }
}

/// How much of the parent rule survives a rule change at a vertex
/// (`Sdc::Crease::ComputeFractionalWeightAtVertex`): the mean sharpness of the features that
/// stop being sharp, at most 1.
pub(crate) fn fractional_weight(
    parent_vertex: f32,
    child_vertex: f32,
    parent_edges: &[f32],
    child_edges: &[f32],
) -> f32 {
    let (mut sum, mut count) = (0.0f32, 0u32);
    if is_sharp(parent_vertex) && !is_sharp(child_vertex) {
        sum += parent_vertex;
        count += 1;
    }
    for (&p, &c) in parent_edges.iter().zip(child_edges) {
        if is_sharp(p) && !is_sharp(c) {
            sum += p;
            count += 1;
        }
    }
    if count == 0 {
        return 0.0;
    }
    (sum / count as f32).min(1.0)
}
