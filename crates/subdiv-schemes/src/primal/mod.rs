//! Primal splits: every n-gon into n quads (quad schemes) or every triangle into four
//! (triangle schemes). The vertex and edge rules come from the scheme's masks; where the
//! scheme has crease rules, boundaries, creases and corners follow OpenSubdiv (smooth, dart,
//! crease, corner, and the fractional blend where a semi-sharp feature fades out).
//!
//! The topology is [`Mesh::split`]'s (child vertex numbering as Far's: vertex points in parent
//! order, then face points for quad schemes, then edge points); the positions come from
//! `values.rs` (the masks applied to them) or from [`stencil_rows`] when stencils are wanted.

use std::borrow::Cow;

use smallvec::SmallVec;
use subdiv_mesh::{EdgeId, FaceId, HalfEdgeId, Mesh, PrimalSplit, VertexId};

pub(crate) mod face_varying;
mod values;

pub(crate) use face_varying::{ChannelLevel, ChannelRules};

use crate::crease::{self, Rule};
use crate::refine::Options;
use crate::scheme::{CreaseMask, ExtraordinaryEdgeMask, Rules, Scheme, TriangleEdgeMask, extraordinary_spokes};
use crate::stencil::{Row, Stencils};
use crate::{Expr, SchemeError};

/// A scheme's primal masks, evaluated for the valences and face sizes of one level.
struct Masks {
    kind: Kind,
    /// `(centre, spoke, face)` per valence.
    vertex: Vec<(f64, f64, f64)>,
    /// `(own, neighbour)` along creases; `None`: no crease rules.
    crease: Option<(f64, f64)>,
}

enum Kind {
    Quad {
        /// Corner weights per face size.
        corners: Vec<Vec<f64>>,
        endpoint: f64,
        face: f64,
        /// The face-point weight of an adjacent triangle, when the scheme has a smooth-triangle
        /// rule and the options ask for it.
        triangle_face: Option<f64>,
    },
    FourPoint {
        weight: f64,
        /// Whether boundaries take the four-point rule along them ([`FourPointBoundary`]).
        boundary: bool,
    },
    Triangle {
        endpoint: f64,
        opposite: f64,
        wing: f64,
        /// `(centre, spokes)` per valence, for edges at an extraordinary vertex.
        extraordinary: Option<Vec<(f64, Vec<f64>)>>,
        /// Whether boundaries take the four-point rule along them ([`FourPointBoundary`]).
        boundary: bool,
    },
}

impl Masks {
    fn new(scheme: &Scheme, mesh: &Mesh, options: Options) -> Self {
        let max_valence = mesh.vertices().map(|v| mesh.valence(v)).max().unwrap_or(0);
        let max_face = mesh.face_ids().map(|f| mesh.face_size(f)).max().unwrap_or(0);
        let vertex_table = |mask| (0..=max_valence).map(|k| crate::scheme::vertex_weights(mask, k)).collect();
        let crease_pair = |c: &Option<CreaseMask>| c.as_ref().map(|c| (c.own.eval(2, 0), c.neighbour.eval(2, 0)));
        match &scheme.rules {
            Rules::Quad { face, edge, vertex, crease } => {
                let corners =
                    (0..=max_face).map(|n| (0..n).map(|j| face.corner.eval(n, j)).collect::<Vec<f64>>()).collect();
                let triangle_face = edge.triangle_face.as_ref().filter(|_| options.smooth_triangles);
                Self {
                    kind: Kind::Quad {
                        corners,
                        endpoint: edge.endpoint.eval(4, 0),
                        face: edge.face.eval(4, 0),
                        triangle_face: triangle_face.map(|w| w.eval(3, 0)),
                    },
                    vertex: vertex_table(vertex),
                    crease: crease_pair(crease),
                }
            }
            Rules::FourPointQuad { weight, boundary } => Self {
                kind: Kind::FourPoint { weight: weight.eval(4, 0), boundary: boundary.is_some() },
                vertex: vec![(1.0, 0.0, 0.0); max_valence + 1],
                crease: None,
            },
            Rules::Triangle { edge, vertex, crease, boundary } => {
                let TriangleEdgeMask { endpoint, opposite, wing, extraordinary } = edge;
                let extraordinary = extraordinary.as_ref().map(|m: &ExtraordinaryEdgeMask| {
                    (0..=max_valence).map(|k| (m.centre.eval(k, 0), extraordinary_spokes(m, k))).collect()
                });
                let eval = |e: &Expr| e.eval(6, 0);
                Self {
                    kind: Kind::Triangle {
                        endpoint: eval(endpoint),
                        opposite: eval(opposite),
                        wing: eval(wing),
                        extraordinary,
                        boundary: boundary.is_some(),
                    },
                    vertex: vertex_table(vertex),
                    crease: crease_pair(crease),
                }
            }
            Rules::Dual { .. } | Rules::Midedge | Rules::Sqrt3 { .. } => {
                unreachable!("primal::refine is only called for primal splits")
            }
        }
    }

    /// The four-point tension along boundaries, where the scheme has the [`FourPointBoundary`]
    /// rule: Kobbelt's weight, the Butterfly's `-wing`.
    fn boundary_tension(&self) -> Option<f64> {
        match self.kind {
            Kind::FourPoint { weight, boundary: true } => Some(weight),
            Kind::Triangle { wing, boundary: true, .. } => Some(-wing),
            _ => None,
        }
    }

    fn splits_into_quads(&self) -> bool {
        !matches!(self.kind, Kind::Triangle { .. })
    }

    fn split(&self) -> PrimalSplit {
        if self.splits_into_quads() { PrimalSplit::Quads } else { PrimalSplit::Triangles }
    }
}

/// Where a mask's face points come from: their own stencil rows over the parent's vertices, or
/// symbolic parents `base + face` (the channels' masks, and rows applied to values whose face
/// points are computed already).
#[derive(Clone, Copy)]
enum FacePoints<'a> {
    Rows(&'a [Row]),
    Symbolic(u32),
}

impl FacePoints<'_> {
    fn add(self, row: &mut Row, f: FaceId, weight: f64) {
        match self {
            Self::Rows(rows) => row.add_row(&rows[f.index()], weight),
            Self::Symbolic(base) => row.add(base + f.raw(), weight),
        }
    }
}

/// How an edge point refines where crease rules apply.
#[derive(Clone, Copy, Debug, PartialEq)]
enum EdgeRule {
    /// The smooth rule.
    Smooth,
    /// The midpoint: both child edges stay sharp.
    Crease,
    /// `s ·` midpoint `+ (1 − s) ·` smooth rule: a semi-sharp edge fading out.
    Blend(f64),
}

/// The rule of edge `e`'s point.
fn edge_rule(mesh: &Mesh, masks: &Masks, options: Options, e: EdgeId) -> EdgeRule {
    let s = sharpness(mesh.edge_sharpness(e));
    if !crease::is_sharp(s) || masks.crease.is_none() {
        return EdgeRule::Smooth;
    }
    let [a, b] = mesh.edge_vertices(e);
    // The child vertex is a crease if both halves stay sharp; otherwise blend by sharpness.
    let half = |v: VertexId| {
        let around: SmallVec<[f32; 8]> =
            vertex_edges(mesh, v).iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
        crease::child_edge_sharpness(options.crease_method, s, &around)
    };
    if crease::is_sharp(half(a)) && crease::is_sharp(half(b)) {
        EdgeRule::Crease
    } else {
        EdgeRule::Blend(f64::from(s))
    }
}

/// The `(endpoint, face)` weights of a quad scheme's smooth edge rule between faces `g0` and
/// `g1`: the scheme's, or OpenSubdiv's (and Hbr's) "smooth triangle" weights next to a triangle
/// when the options ask for them, in their order of operations: each side's face weight,
/// averaged; the endpoints take the rest.
fn quad_edge_weights(
    mesh: &Mesh,
    endpoint: f64,
    face: f64,
    triangle_face: Option<f64>,
    g0: FaceId,
    g1: FaceId,
) -> (f64, f64) {
    let (tri0, tri1) = (mesh.face_size(g0) == 3, mesh.face_size(g1) == 3);
    match triangle_face {
        Some(w) if tri0 || tri1 => {
            let face_weight = 0.5 * (if tri0 { w } else { face } + if tri1 { w } else { face });
            (0.5 * (1.0 - 2.0 * face_weight), face_weight)
        }
        _ => (endpoint, face),
    }
}

/// Whether any edge or vertex of `mesh` is sharp.
fn has_sharpness(mesh: &Mesh) -> bool {
    mesh.edges().any(|e| mesh.edge_sharpness(e) > 0.0) || mesh.vertices().any(|v| mesh.vertex_sharpness(v) > 0.0)
}

/// The edges at `v` in fan order, each with its far end; for a boundary vertex the trailing
/// boundary edge comes last.
pub(crate) fn vertex_edges(mesh: &Mesh, v: VertexId) -> SmallVec<[(EdgeId, VertexId); 8]> {
    let mut edges: SmallVec<[(EdgeId, VertexId); 8]> = SmallVec::new();
    let mut last = None;
    for h in mesh.outgoing(v) {
        edges.push((mesh.edge(h), mesh.dest(h)));
        last = Some(h);
    }
    if let Some(h) = last
        && mesh.is_boundary_vertex(v)
    {
        let incoming = mesh.prev(h);
        edges.push((mesh.edge(incoming), mesh.origin(incoming)));
    }
    edges
}

fn sharpness(s: f64) -> f32 {
    // Sharpness is single precision in OpenSubdiv; rounding here keeps fractional weights equal.
    s as f32
}

/// Child vertex numbering: vertex points (parent order), then face points (quad schemes), then
/// edge points — the order of OpenSubdiv's `Far` levels as the peer harness writes them.
struct Numbering {
    face_base: u32,
    edge_base: u32,
}

/// One primal level; `channels` holds the face-varying topology of `mesh`'s channels (empty at
/// the base level, where it is derived) and is replaced by the child's. The level's stencils
/// are made when `stencils` asks for them (or when the scheme's rules have no direct path);
/// otherwise the positions are refined by applying the masks to them.
pub(crate) fn refine(
    mesh: &Mesh,
    scheme: &Scheme,
    options: Options,
    channels: &mut Vec<ChannelLevel>,
    stencils: bool,
) -> Result<(Mesh, Option<Stencils>), SchemeError> {
    let masks = Masks::new(scheme, mesh, options);
    let split = masks.split();
    let nv = mesh.vertex_count() as u32;
    let face_points = if masks.splits_into_quads() { mesh.face_count() as u32 } else { 0 };
    let numbering = Numbering { face_base: nv, edge_base: nv + face_points };

    let sharp = has_sharpness(mesh);
    let (positions, level_stencils) = if stencils || !values::supports(&masks) {
        let level_stencils = stencil_rows(mesh, &masks, options, &numbering);
        let mut positions = Vec::new();
        level_stencils.apply(mesh.positions(), &mut positions);
        (positions, stencils.then_some(level_stencils))
    } else {
        let mut positions = Vec::new();
        values::refine(mesh, &masks, options, sharp, mesh.positions(), &mut positions);
        (positions, None)
    };
    let mut child = mesh.split(split, positions, options.parallelism);

    // Sharpness of the child level, where the parent has any (infinitely sharp creases and
    // corners only, for the four-point boundary rule: the input check refuses the rest).
    if (masks.crease.is_some() || masks.boundary_tension().is_some()) && sharp {
        for v in mesh.vertices() {
            child.set_vertex_sharpness(v, f64::from(crease::decrement(sharpness(mesh.vertex_sharpness(v)))));
        }
        for e in mesh.edges() {
            let s = sharpness(mesh.edge_sharpness(e));
            if !crease::is_sharp(s) {
                continue;
            }
            let ends = mesh.edge_vertices(e);
            for (end, half) in ends.into_iter().zip(split.edge_children(mesh, &child, e)) {
                let around: SmallVec<[f32; 8]> =
                    vertex_edges(mesh, end).iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
                child.set_edge_sharpness(
                    half,
                    f64::from(crease::child_edge_sharpness(options.crease_method, s, &around)),
                );
            }
        }
    }
    refine_channels(mesh, &mut child, &masks, options, &numbering, channels)?;
    Ok((child, level_stencils))
}

/// One stencil row per child vertex, in child order.
fn stencil_rows(mesh: &Mesh, masks: &Masks, options: Options, numbering: &Numbering) -> Stencils {
    let child_count = (numbering.edge_base as usize) + mesh.edge_count();
    let mut stencils = Stencils::with_capacity(child_count, 8 * child_count, mesh.vertex_count());
    // Face points of the averaging quad schemes, which their edge and vertex rules reuse.
    let face_rows: Vec<Row> = match &masks.kind {
        Kind::Quad { corners, .. } => mesh.face_ids().map(|f| face_point(mesh, corners, f)).collect(),
        _ => vec![],
    };
    let faces = FacePoints::Rows(&face_rows);
    let edge_rows: Vec<Row> = mesh.edges().map(|e| edge_row(mesh, masks, faces, options, e)).collect();
    for v in mesh.vertices() {
        stencils.push(&vertex_row(mesh, masks, faces, options.crease_method, v));
    }
    match &masks.kind {
        Kind::FourPoint { weight, .. } => {
            for f in mesh.face_ids() {
                stencils.push(&four_point_face(mesh, &edge_rows, *weight, f));
            }
        }
        _ => {
            for row in &face_rows {
                stencils.push(row);
            }
        }
    }
    for row in &edge_rows {
        stencils.push(row);
    }
    stencils
}

/// The child level's channels, for the schemes with crease rules (the face-varying rules are
/// OpenSubdiv's, which its seams and channel boundaries follow); the others drop them.
fn refine_channels(
    mesh: &Mesh,
    child: &mut Mesh,
    masks: &Masks,
    options: Options,
    numbering: &Numbering,
    levels: &mut Vec<ChannelLevel>,
) -> Result<(), SchemeError> {
    let Some(crease) = masks.crease.filter(|_| !mesh.channels().is_empty()) else {
        levels.clear();
        return Ok(());
    };
    let rules = options.channels;
    if levels.len() != mesh.channels().len() {
        *levels = mesh.channels().iter().map(|c| face_varying::analyze(mesh, c, rules)).collect();
    }
    // The positions' masks with each face point as one symbolic parent, `vertex_count + face`:
    // matched values apply them to the face points' values.
    let face_points = FacePoints::Symbolic(mesh.vertex_count() as u32);
    let edge_mask = |e| edge_row(mesh, masks, face_points, options, e);
    let vertex_mask = |v| vertex_row(mesh, masks, face_points, options.crease_method, v);
    let at = face_varying::Children {
        parent: mesh,
        child,
        face_base: numbering.face_base,
        edge_base: numbering.edge_base,
        split: masks.split(),
        crease,
    };
    let mut refined = Vec::with_capacity(levels.len());
    let mut next = Vec::with_capacity(levels.len());
    for (channel, level) in mesh.channels().iter().zip(levels.iter()) {
        let (c, l) = face_varying::refine(&at, channel, level, rules, edge_mask, vertex_mask)?;
        refined.push(c);
        next.push(l);
    }
    child.set_channels(refined).map_err(|e| SchemeError::Internal(format!("a refined channel is invalid: {e}")))?;
    *levels = next;
    Ok(())
}

/// The smooth edge point of the edge of `h` (its rule away from creases).
fn smooth_edge_row(mesh: &Mesh, masks: &Masks, faces: FacePoints<'_>, h: HalfEdgeId) -> Row {
    let (a, b) = (mesh.origin(h), mesh.dest(h));
    if let Some(weight) = masks.boundary_tension()
        && bounds(mesh, mesh.edge(h))
    {
        return four_point_along_crease(mesh, a, b, weight);
    }
    let Some(t) = mesh.twin(h) else {
        return midpoint(a, b);
    };
    let mut row = Row::default();
    match &masks.kind {
        Kind::Quad { endpoint, face, triangle_face, .. } => {
            let (g0, g1) = (mesh.face(h), mesh.face(t));
            let (vertex_weight, face_weight) = quad_edge_weights(mesh, *endpoint, *face, *triangle_face, g0, g1);
            add(&mut row, a, vertex_weight);
            add(&mut row, b, vertex_weight);
            if face_weight != 0.0 {
                faces.add(&mut row, g0, face_weight);
                faces.add(&mut row, g1, face_weight);
            }
        }
        Kind::FourPoint { weight, .. } => {
            let w = *weight;
            row.add_row(&beyond(mesh, t), -w);
            add(&mut row, a, 0.5 + w);
            add(&mut row, b, 0.5 + w);
            row.add_row(&beyond(mesh, h), -w);
        }
        Kind::Triangle { endpoint, opposite, wing, extraordinary, .. } => {
            // Vertices on the boundary or a crease count as regular (the boundary rule's
            // reading of the ten-point rule; closed smooth meshes have none).
            let regular = |v: VertexId| mesh.valence(v) == 6 || on_crease(mesh, v);
            if let Some(table) = extraordinary
                && !(regular(a) && regular(b))
            {
                // The modified Butterfly rule from each extraordinary end, averaged over both.
                let ends: SmallVec<[HalfEdgeId; 2]> =
                    [h, t].into_iter().filter(|&x| !regular(mesh.origin(x))).collect();
                let share = 1.0 / ends.len() as f64;
                for x in ends {
                    let centre = mesh.origin(x);
                    let (w, spokes) = &table[mesh.valence(centre)];
                    add(&mut row, centre, w * share);
                    for (q, s) in fan_from(mesh, x).into_iter().zip(spokes) {
                        add(&mut row, q, s * share);
                    }
                }
                return row;
            }
            add(&mut row, a, *endpoint);
            add(&mut row, b, *endpoint);
            add(&mut row, mesh.origin(mesh.prev(h)), *opposite);
            add(&mut row, mesh.origin(mesh.prev(t)), *opposite);
            if *wing != 0.0 {
                for x in [h, t] {
                    for side in [mesh.next(x), mesh.prev(x)] {
                        match mesh.twin(side) {
                            Some(across) if !bounds(mesh, mesh.edge(side)) => {
                                add(&mut row, mesh.origin(mesh.prev(across)), *wing);
                            }
                            _ => {
                                // Across a boundary or crease side: the triangle's third vertex
                                // reflected through the side's middle (only with a boundary
                                // rule: the input check refuses boundaries otherwise).
                                add(&mut row, mesh.origin(side), *wing);
                                add(&mut row, mesh.dest(side), *wing);
                                add(&mut row, mesh.origin(mesh.prev(side)), -*wing);
                            }
                        }
                    }
                }
            }
        }
    }
    row
}

/// Whether edge `e` bounds the surface for the four-point boundary rule: a boundary edge, or
/// one tagged infinitely sharp (the boundary rule then applies on each side of it).
fn bounds(mesh: &Mesh, e: EdgeId) -> bool {
    mesh.is_boundary_edge(e) || crease::is_infinite(sharpness(mesh.edge_sharpness(e)))
}

/// Whether `v` lies on the boundary or a crease, or is a tagged corner: the rules of the
/// interior stop there as at a boundary.
fn on_crease(mesh: &Mesh, v: VertexId) -> bool {
    mesh.is_boundary_vertex(v)
        || crease::is_infinite(sharpness(mesh.vertex_sharpness(v)))
        || vertex_edges(mesh, v).iter().any(|&(e, _)| bounds(mesh, e))
}

/// The vertex before `a` on the boundary or crease curve through `b` and `a`, or `None` where
/// the curve ends at `a`: a tagged corner, a vertex where other than two such curves' edges
/// meet, or one with a single face between its two on either side (a boundary vertex of one
/// face, a crease turning around one face: rounding it would fold the tangent plane there).
fn curve_before(mesh: &Mesh, a: VertexId, b: VertexId) -> Option<VertexId> {
    if crease::is_infinite(sharpness(mesh.vertex_sharpness(a))) {
        return None;
    }
    let edges = vertex_edges(mesh, a);
    let along: SmallVec<[usize; 4]> = (0..edges.len()).filter(|&i| bounds(mesh, edges[i].0)).collect();
    let &[i, j] = along.as_slice() else {
        return None;
    };
    // Faces between the two in fan order, and (around an interior vertex) on the other side.
    let inner = j - i;
    let outer = (!mesh.is_boundary_vertex(a)).then(|| edges.len() - inner);
    if inner == 1 || outer == Some(1) {
        return None;
    }
    match (edges[i].1, edges[j].1) {
        (x, y) if x == b && y != b => Some(y),
        (x, y) if y == b && x != b => Some(x),
        _ => None,
    }
}

/// The point of the boundary or crease edge `a → b` by the four-point rule along its curve:
/// `a'` before `a`, `b'` after `b`; where the curve ends, the point beyond it is extrapolated
/// (`2a − b`), the four-point curve's end rule.
fn four_point_along_crease(mesh: &Mesh, a: VertexId, b: VertexId, weight: f64) -> Row {
    let mut row = Row::default();
    for (end, other) in [(a, b), (b, a)] {
        match curve_before(mesh, end, other) {
            Some(outer) => add(&mut row, outer, -weight),
            None => {
                add(&mut row, end, -2.0 * weight);
                add(&mut row, other, weight);
            }
        }
    }
    add(&mut row, a, 0.5 + weight);
    add(&mut row, b, 0.5 + weight);
    row
}

fn add(row: &mut Row, v: VertexId, weight: f64) {
    if weight != 0.0 {
        row.add(v.raw(), weight);
    }
}

fn midpoint(a: VertexId, b: VertexId) -> Row {
    let mut row = Row::default();
    row.add(a.raw(), 0.5);
    row.add(b.raw(), 0.5);
    row
}

/// The far ends of the edges at `origin(h)`, counter-clockwise from `h`'s.
fn fan_from(mesh: &Mesh, h: HalfEdgeId) -> SmallVec<[VertexId; 8]> {
    let mut fan: SmallVec<[VertexId; 8]> = SmallVec::new();
    let mut x = h;
    loop {
        fan.push(mesh.dest(x));
        match mesh.twin(mesh.prev(x)) {
            Some(next) if next != h => x = next,
            _ => break,
        }
    }
    fan
}

/// The point that continues the grid line of `h` beyond its end `dest(h)`: the opposite
/// neighbour at a vertex of valence 4; elsewhere the virtual point `4/k · Σ q − q_{i−1} − q_i −
/// q_{i+1}` over `dest(h)`'s neighbours `q`, `q_i = origin(h)`, which is the opposite neighbour
/// when `k = 4`.
fn beyond(mesh: &Mesh, h: HalfEdgeId) -> Row {
    let end = mesh.dest(h);
    if on_crease(mesh, end) {
        let mut row = Row::default();
        row.add(end.raw(), 2.0);
        row.add(mesh.origin(h).raw(), -1.0);
        return row;
    }
    let back = mesh.twin(h).expect("an edge into an interior vertex has a twin");
    let fan = fan_from(mesh, back);
    let k = fan.len();
    let mut row = Row::default();
    if k == 4 {
        row.add(fan[2].raw(), 1.0);
        return row;
    }
    for &q in &fan {
        row.add(q.raw(), 4.0 / k as f64);
    }
    for q in [fan[k - 1], fan[0], fan[1]] {
        row.add(q.raw(), -1.0);
    }
    row
}

/// Kobbelt's face point: the four-point rule across the face through the new points of two
/// opposite edges and of the edges opposite them in the neighbouring quads, taken in both
/// directions and averaged (the two agree on a regular grid).
fn four_point_face(mesh: &Mesh, edge_rows: &[Row], w: f64, f: FaceId) -> Row {
    let halves: SmallVec<[HalfEdgeId; 4]> = mesh.face_half_edges(f).collect();
    let edge = |h: HalfEdgeId| &edge_rows[mesh.edge(h).index()];
    // The edge point beyond side `h`, or at a boundary or crease side 2 E(h) − E(opposite).
    let across = |h: HalfEdgeId, opposite: HalfEdgeId| -> Cow<'_, Row> {
        match mesh.twin(h) {
            Some(t) if !bounds(mesh, mesh.edge(h)) => Cow::Borrowed(edge(mesh.next(mesh.next(t)))),
            _ => {
                let mut row = Row::default();
                row.add_row(edge(h), 2.0);
                row.add_row(edge(opposite), -1.0);
                Cow::Owned(row)
            }
        }
    };
    let mut row = Row::default();
    for (first, second) in [(halves[0], halves[2]), (halves[1], halves[3])] {
        row.add_row(&across(first, second), -w / 2.0);
        row.add_row(edge(first), (0.5 + w) / 2.0);
        row.add_row(edge(second), (0.5 + w) / 2.0);
        row.add_row(&across(second, first), -w / 2.0);
    }
    row
}

/// The stencil of the point of edge `e`.
fn edge_row(mesh: &Mesh, masks: &Masks, faces: FacePoints<'_>, options: Options, e: EdgeId) -> Row {
    let h = mesh.edge_half_edge(e);
    let smooth = smooth_edge_row(mesh, masks, faces, h);
    let (a, b) = (mesh.origin(h), mesh.dest(h));
    match edge_rule(mesh, masks, options, e) {
        EdgeRule::Smooth => smooth,
        EdgeRule::Crease => midpoint(a, b),
        EdgeRule::Blend(s) => midpoint(a, b).blend(&smooth, s),
    }
}

/// The stencil of the face point of `f`, from the corner weights per face size.
fn face_point(mesh: &Mesh, corners: &[Vec<f64>], f: FaceId) -> Row {
    let face = mesh.face_vertices(f);
    let mut row = Row::default();
    for (v, &w) in face.iter().zip(&corners[face.len()]) {
        add(&mut row, *v, w);
    }
    row
}

/// The stencil of the child of vertex `v`: the smooth, crease or corner mask, or a blend of the
/// parent's and the child's where a semi-sharp feature fades out.
fn vertex_row(
    mesh: &Mesh,
    masks: &Masks,
    faces: FacePoints<'_>,
    method: subdiv_mesh::CreaseMethod,
    v: VertexId,
) -> Row {
    if mesh.is_isolated(v) {
        return Row::single(v.raw());
    }
    let edges = vertex_edges(mesh, v);
    let smooth = || -> Row {
        let (centre, spoke, face) = masks.vertex[edges.len()];
        let mut row = Row::default();
        add(&mut row, v, centre);
        if spoke != 0.0 {
            for &(_, w) in &edges {
                row.add(w.raw(), spoke);
            }
        }
        if face != 0.0 {
            for f in mesh.vertex_faces(v) {
                faces.add(&mut row, f, face);
            }
        }
        row
    };
    let Some((own, neighbour)) = masks.crease else {
        return smooth();
    };
    let parent_edges: SmallVec<[f32; 8]> = edges.iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
    let parent_vertex = sharpness(mesh.vertex_sharpness(v));
    let crease_along = |sharp: &[f32]| -> Row {
        let mut row = Row::default();
        row.add(v.raw(), own);
        for (&(_, w), _) in edges.iter().zip(sharp).filter(|&(_, &s)| crease::is_sharp(s)).take(2) {
            add(&mut row, w, neighbour);
        }
        row
    };
    let mask = |rule: Rule, sharp: &[f32]| match rule {
        Rule::Smooth | Rule::Dart => smooth(),
        Rule::Crease => crease_along(sharp),
        Rule::Corner => Row::single(v.raw()),
    };
    let parent_rule = crease::vertex_rule(parent_vertex, &parent_edges);
    if matches!(parent_rule, Rule::Smooth | Rule::Dart) {
        return smooth();
    }
    let child_vertex = crease::decrement(parent_vertex);
    let child_edges: SmallVec<[f32; 8]> =
        parent_edges.iter().map(|&s| crease::child_edge_sharpness(method, s, &parent_edges)).collect();
    let child_rule = crease::vertex_rule(child_vertex, &child_edges);
    if child_rule == parent_rule {
        return mask(parent_rule, &parent_edges);
    }
    let w = f64::from(crease::fractional_weight(parent_vertex, child_vertex, &parent_edges, &child_edges));
    mask(parent_rule, &parent_edges).blend(&mask(child_rule, &child_edges), w)
}
