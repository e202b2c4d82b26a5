//! Face-varying channels through the primal splits: OpenSubdiv's face-varying topology
//! (`Vtr::FVarLevel::completeTopologyFromFaceValues`), its refinement
//! (`Vtr::FVarRefinement`) and its interpolation (`Far::PrimvarRefiner::InterpolateFaceVarying`),
//! in the six modes of [`FaceVaryingInterpolation`].
//!
//! A channel has its own topology. Where the faces around a vertex use different values, the
//! vertex has one *sibling* value per run of faces (its *span*), and the edges between runs are
//! seams. At the base level each sibling is tagged: *matched* (the vertex's topology and the
//! channel's agree: refined with the vertex's own masks, applied to the channel's values), a
//! *crease* (the curve rule along the two edges that bound its span), *semi-sharp* (kept like a
//! corner until the vertex's semi-sharp features decay, then blended into a crease) or a
//! *corner* (kept). The tags are carried down level by level as OpenSubdiv carries them rather
//! than derived again from each level's topology: the two differ in a few places OpenSubdiv's
//! output shows (a boundary edge whose ends were both seams when visited is not made linear;
//! a value made sharp by its partner stays sharp one level longer), and the comparison with
//! `osd_refine --fvar` is per value.

use smallvec::{SmallVec, smallvec};
use subdiv_mesh::{
    Channel, ChildOrigin, CreaseMethod, EdgeId, FaceId, FaceVaryingInterpolation as Mode, HalfEdgeId, Mesh,
    PolygonSoup, PrimalSplit, VertexId,
};

use super::{sharpness, vertex_edges};
use crate::SchemeError;
use crate::crease;
use crate::stencil::Row;

/// What decides a channel's rules besides its topology.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ChannelRules {
    pub(crate) mode: Mode,
    /// The positions' boundary rule makes corners (one-face boundary vertices) sharp.
    pub(crate) sharp_mesh_corners: bool,
    pub(crate) crease_method: CreaseMethod,
}

impl ChannelRules {
    /// Every value interpolates its parent face's values (`FVarLevel::_isLinear`).
    fn is_linear(self) -> bool {
        self.mode == Mode::All
    }

    fn has_linear_boundaries(self) -> bool {
        matches!(self.mode, Mode::All | Mode::Boundaries)
    }

    fn has_smooth_boundaries(self) -> bool {
        !self.has_linear_boundaries()
    }

    fn has_dependent_sharpness(self) -> bool {
        matches!(self.mode, Mode::CornersPlus1 | Mode::CornersPlus2)
    }
}

/// A sibling value's rule (`FVarLevel::ValueTag`, the bits refinement reads).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct ValueTag {
    /// The channel's topology differs from the vertex's here; all other bits are then meaningful.
    mismatch: bool,
    crease: bool,
    semi_sharp: bool,
    /// Semi-sharp because the vertex's other value is (corners-plus modes).
    dep_sharp: bool,
}

impl ValueTag {
    /// Kept as it is when refined: neither a crease nor blending into one yet (semi-sharp
    /// values are corners until their sharpness is gone).
    fn is_corner(self) -> bool {
        !self.crease
    }

    fn is_inf_sharp(self) -> bool {
        !self.semi_sharp && !self.crease
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct EdgeTag {
    /// The edge's two faces use different values at one of its ends (a seam).
    mismatch: bool,
    /// The channel is linear along the edge (seams and boundaries under the linear-boundary
    /// modes).
    linear: bool,
}

#[derive(Clone, Copy, Debug)]
struct Sibling {
    /// The value's index in the level's channel.
    value: u32,
    tag: ValueTag,
    /// For a crease or semi-sharp value: the vertex's outgoing half-edges in the first and the
    /// last face of its span. The crease's end values are at `next(first)` and `prev(last)`.
    ends: Option<[HalfEdgeId; 2]>,
}

/// One channel's face-varying topology on one level.
#[derive(Clone, Debug)]
pub(crate) struct ChannelLevel {
    /// Vertex `v`'s siblings are `siblings[first[v]..first[v + 1]]`.
    first: Vec<u32>,
    siblings: Vec<Sibling>,
    /// Per half-edge: which sibling of its origin its face uses.
    corner_sibling: Vec<u32>,
    edges: Vec<EdgeTag>,
}

impl ChannelLevel {
    fn of(&self, v: VertexId) -> &[Sibling] {
        &self.siblings[self.first[v.index()] as usize..self.first[v.index() + 1] as usize]
    }

    fn is_matched(&self, v: VertexId) -> bool {
        !self.of(v)[0].tag.mismatch
    }
}

/// The vertex's outgoing half-edges, one per face, in fan order (a boundary fan starts at its
/// boundary edge): Vtr's ring order, whose edge `i` lies between faces `i − 1` and `i`.
fn ring(mesh: &Mesh, v: VertexId) -> SmallVec<[HalfEdgeId; 8]> {
    mesh.outgoing(v).collect()
}

/// Edge `i` of a ring: the leading edge of face `i`, or past the last face of a boundary fan,
/// its trailing boundary edge.
fn ring_edge(mesh: &Mesh, ring: &[HalfEdgeId], i: usize) -> EdgeId {
    match ring.get(i) {
        Some(&h) => mesh.edge(h),
        None => mesh.edge(mesh.prev(ring[ring.len() - 1])),
    }
}

/// A sibling's run of faces (`FVarLevel::ValueSpan`).
#[derive(Clone, Copy, Debug, Default)]
struct Span {
    size: usize,
    start: usize,
    /// Seams inside the span, or re-entries of the value: a disjoint span, whose value is a corner.
    discontinuous: i32,
    semi_sharp: u32,
    inf_sharp: u32,
}

/// The face-varying topology of `channel` on the base level `mesh` (which has the boundary
/// rule applied): `FVarLevel::completeTopologyFromFaceValues`, its two passes in vertex order.
pub(crate) fn analyze(mesh: &Mesh, channel: &Channel, rules: ChannelRules) -> ChannelLevel {
    let nv = mesh.vertex_count();
    let linear_boundaries = rules.has_linear_boundaries();
    let make_smooth_corners_sharp = !rules.sharp_mesh_corners && rules.mode != Mode::None;
    let mut mismatch = vec![false; nv];
    let mut edges = vec![EdgeTag::default(); mesh.edge_count()];
    let mut corner_sibling = vec![0u32; mesh.half_edge_count()];
    let mut counts = vec![1u32; nv];

    // Pass 1: seams, boundary vertices, sibling values. The order matters: whether a boundary
    // vertex makes its boundary edges linear depends on the seams seen so far.
    for v in mesh.vertices() {
        let ring = ring(mesh, v);
        let nf = ring.len();
        if nf == 0 {
            continue;
        }
        let boundary = mesh.is_boundary_vertex(v);
        let values: SmallVec<[u32; 8]> = ring.iter().map(|&h| channel.corner_value(h)).collect();
        for i in usize::from(boundary)..nf {
            let prev = if i == 0 { nf - 1 } else { i - 1 };
            if values[i] != values[prev] {
                let e = mesh.edge(ring[i]);
                for end in mesh.edge_vertices(e) {
                    mismatch[end.index()] = true;
                }
                edges[e.index()].mismatch = true;
                edges[e.index()].linear |= linear_boundaries;
            }
        }
        if boundary && !mismatch[v.index()] {
            if linear_boundaries {
                mismatch[v.index()] = true;
                edges[ring_edge(mesh, &ring, 0).index()].linear = true;
                edges[ring_edge(mesh, &ring, nf).index()].linear = true;
            } else if nf == 1 && make_smooth_corners_sharp {
                mismatch[v.index()] = true;
            }
        }
        // Siblings in order of first appearance. OpenSubdiv's test with two values known
        // compares with the first only, so a fan A, B, A, B gives three siblings A, B, B.
        let mut unique: SmallVec<[u32; 4]> = smallvec![values[0]];
        let mut sibling = 0u32;
        corner_sibling[ring[0].index()] = 0;
        for i in 1..nf {
            if values[i] != values[i - 1] {
                sibling = unique.len() as u32;
                if unique.len() == 1 || (unique.len() == 2 && unique[0] != values[i]) {
                    unique.push(values[i]);
                } else {
                    match unique.iter().position(|&u| u == values[i]) {
                        Some(k) => sibling = k as u32,
                        None => unique.push(values[i]),
                    }
                }
            }
            corner_sibling[ring[i].index()] = sibling;
        }
        counts[v.index()] = unique.len() as u32;
    }

    let mut first = Vec::with_capacity(nv + 1);
    first.push(0u32);
    for &c in &counts {
        first.push(first.last().copied().unwrap_or(0) + c);
    }
    let placeholder = Sibling { value: 0, tag: ValueTag::default(), ends: None };
    let mut siblings = vec![placeholder; first[nv] as usize];

    // Pass 2: each sibling's value and rule.
    for v in mesh.vertices() {
        let ring = ring(mesh, v);
        let nf = ring.len();
        let slots = first[v.index()] as usize..first[v.index() + 1] as usize;
        if nf == 0 {
            continue;
        }
        let sib: SmallVec<[usize; 8]> = ring.iter().map(|&h| corner_sibling[h.index()] as usize).collect();
        let own = &mut siblings[slots];
        for (i, &h) in ring.iter().enumerate().rev() {
            own[sib[i]].value = channel.corner_value(h);
        }
        if !mismatch[v.index()] {
            continue;
        }
        let n = own.len();
        let boundary = mesh.is_boundary_vertex(v);
        let vertex = sharpness(mesh.vertex_sharpness(v));
        let sharpen_both_if_one_corner = rules.mode == Mode::CornersPlus2;
        let sharpen_darts = sharpen_both_if_one_corner || linear_boundaries;
        let mut all_corners_sharp = linear_boundaries
            || crease::is_infinite(vertex)
            || (rules.has_dependent_sharpness() && n > 2)
            || (sharpen_darts && n == 1 && !boundary);
        let spans = value_spans(mesh, &ring, &sib, n, &edges);
        let mut dependent_values_to_sharpen = false;
        if !all_corners_sharp && rules.has_dependent_sharpness() && n == 2 {
            all_corners_sharp = spans.iter().any(|s| s.inf_sharp > 0 || s.discontinuous > 0);
            if sharpen_both_if_one_corner {
                all_corners_sharp |= spans.iter().any(|s| s.size == 1);
            }
            dependent_values_to_sharpen = (spans[0].semi_sharp > 0) != (spans[1].semi_sharp > 0);
        }
        for (j, (sibling, span)) in own.iter_mut().zip(&spans).enumerate() {
            let mut tag = ValueTag { mismatch: true, ..ValueTag::default() };
            if span.discontinuous <= 0 {
                let inf_sharp = all_corners_sharp || span.inf_sharp > 0 || (span.size == 1 && rules.mode != Mode::None);
                if !inf_sharp {
                    if span.semi_sharp > 0 || crease::is_semi_sharp(vertex) {
                        tag.semi_sharp = true;
                    } else if dependent_values_to_sharpen {
                        tag.semi_sharp = true;
                        tag.dep_sharp = true;
                    } else {
                        tag.crease = true;
                    }
                    if rules.has_smooth_boundaries() {
                        // Sibling 0's span may wrap around the fan's start.
                        let last = span.start + span.size - 1;
                        let last = if j == 0 && span.start != 0 { last - nf } else { last };
                        sibling.ends = Some([ring[span.start], ring[last]]);
                    }
                }
            }
            sibling.tag = tag;
        }
    }
    ChannelLevel { first, siblings, corner_sibling, edges }
}

/// Each sibling's span around a manifold vertex (`FVarLevel::gatherValueSpans`): where it
/// starts in the ring, how many faces, and which edges inside it are seams or sharp.
fn value_spans(mesh: &Mesh, ring: &[HalfEdgeId], sib: &[usize], n: usize, edges: &[EdgeTag]) -> SmallVec<[Span; 4]> {
    let nf = ring.len();
    let boundary = mesh.is_boundary_vertex(mesh.origin(ring[0]));
    let ne = nf + usize::from(boundary);
    let mut spans: SmallVec<[Span; 4]> = smallvec![Span::default(); n];
    let count = |span: &mut Span, e: EdgeId| {
        let s = sharpness(mesh.edge_sharpness(e));
        if edges[e.index()].mismatch {
            span.discontinuous += 1;
        } else if crease::is_infinite(s) {
            span.inf_sharp += 1;
        } else if crease::is_sharp(s) {
            span.semi_sharp += 1;
        }
    };
    if n == 1 && !boundary {
        // One value around an interior vertex: the span starts at its one seam (a dart of the
        // channel); two seams make it disjoint.
        let span = &mut spans[0];
        for i in 0..ne {
            let e = ring_edge(mesh, ring, i);
            if edges[e.index()].mismatch {
                if span.size > 0 {
                    span.discontinuous = 1;
                    break;
                }
                span.size = nf;
                span.start = i;
            } else {
                count(span, e);
            }
        }
        span.size = nf;
        return spans;
    }
    spans[0].size = 1;
    if !boundary && sib[nf - 1] == 0 {
        count(&mut spans[0], ring_edge(mesh, ring, 0));
    }
    for i in 1..nf {
        let span = &mut spans[sib[i]];
        if sib[i] == sib[i - 1] {
            count(span, ring_edge(mesh, ring, i));
        } else {
            if span.size > 0 {
                span.discontinuous += 1;
            }
            span.start = i;
        }
        span.size += 1;
    }
    if sib[nf - 1] == 0 && !boundary {
        spans[0].discontinuous -= 1;
    }
    spans
}

/// Where the children of one level's elements are: the child numbering of the primal split
/// and each parent face's first child face.
pub(crate) struct Children<'a> {
    pub(crate) parent: &'a Mesh,
    pub(crate) child: &'a Mesh,
    pub(crate) face_base: u32,
    pub(crate) edge_base: u32,
    /// The split: quads (one face point per face) or triangles into four.
    pub(crate) split: PrimalSplit,
    /// The scheme's crease mask `(own, neighbour)`, which a channel's creases follow
    /// (OpenSubdiv writes Catmull-Clark's and Loop's `(3/4, 1/8)` into its face-varying code
    /// and makes the bilinear scheme's channels linear: the bilinear mask `(1, 0)` is that).
    pub(crate) crease: (f64, f64),
}

/// The parent element a child vertex comes from.
#[derive(Clone, Copy)]
enum Parent {
    Vertex(VertexId),
    Face,
    Edge(EdgeId),
}

impl Children<'_> {
    fn parent_of(&self, child: VertexId) -> Parent {
        let c = child.raw();
        if c < self.face_base {
            Parent::Vertex(child)
        } else if c < self.edge_base {
            Parent::Face
        } else {
            Parent::Edge(EdgeId::new(c - self.edge_base))
        }
    }

    fn face_child(&self, f: FaceId) -> VertexId {
        VertexId::new(self.face_base + f.raw())
    }

    fn edge_child(&self, e: EdgeId) -> VertexId {
        VertexId::new(self.edge_base + e.raw())
    }
}

/// The half-edge of face `f` that leaves `v`.
fn half_edge_from(mesh: &Mesh, f: FaceId, v: VertexId) -> Option<HalfEdgeId> {
    mesh.face_half_edges(f).find(|&h| mesh.origin(h) == v)
}

/// The half-edges of `e` on its sides: its first half-edge, then its twin if it has one (an
/// edge point's siblings in that order).
fn edge_sides(mesh: &Mesh, e: EdgeId) -> SmallVec<[HalfEdgeId; 2]> {
    let h = mesh.edge_half_edge(e);
    std::iter::once(h).chain(mesh.twin(h)).collect()
}

fn internal(what: &str) -> SchemeError {
    SchemeError::Internal(format!("face-varying refinement: {what}"))
}

/// Refines one channel one level: the child channel (its values in child-vertex order, siblings
/// consecutive) and its topology. `edge_mask` and `vertex_mask` are the positions' rows with
/// face points as `vertex_count + face` (the matched values reuse them).
pub(crate) fn refine(
    at: &Children<'_>,
    channel: &Channel,
    level: &ChannelLevel,
    rules: ChannelRules,
    edge_mask: impl Fn(EdgeId) -> Row,
    vertex_mask: impl Fn(VertexId) -> Row,
) -> Result<(Channel, ChannelLevel), SchemeError> {
    let (parent, child) = (at.parent, at.child);

    // Sibling counts, in child-vertex order.
    let mut first = Vec::with_capacity(child.vertex_count() + 1);
    first.push(0u32);
    for cv in child.vertices() {
        let count = match at.parent_of(cv) {
            Parent::Vertex(v) if !level.is_matched(v) => level.of(v).len(),
            Parent::Edge(e) if level.edges[e.index()].mismatch => 1 + usize::from(!parent.is_boundary_edge(e)),
            _ => 1,
        };
        first.push(first[cv.index()] + count as u32);
    }
    let total = first[child.vertex_count()] as usize;

    // Each child corner's sibling, and the child channel's indices. An edge point's siblings
    // are its edge's sides: 0 in the face of `edge_half_edge`, 1 in its twin's.
    let corner_sibling: Vec<u32> = (0..child.half_edge_count() as u32)
        .map(|c| match at.split.child_origin(parent, HalfEdgeId::new(c)) {
            ChildOrigin::Vertex(h) if !level.is_matched(parent.origin(h)) => level.corner_sibling[h.index()],
            ChildOrigin::Edge(h) if level.edges[parent.edge(h).index()].mismatch => {
                u32::from(parent.edge_half_edge(parent.edge(h)) != h)
            }
            _ => 0,
        })
        .collect();
    let indices: Vec<u32> = (0..child.half_edge_count())
        .map(|h| first[child.origin(HalfEdgeId::new(h as u32)).index()] + corner_sibling[h])
        .collect();

    // Edge tags: both halves of a parent edge inherit its tag.
    let mut edges = vec![EdgeTag::default(); child.edge_count()];
    for e in parent.edges() {
        for half in at.split.edge_children(parent, child, e) {
            edges[half.index()] = level.edges[e.index()];
        }
    }

    // Value tags and crease ends.
    let placeholder = Sibling { value: 0, tag: ValueTag::default(), ends: None };
    let mut siblings: Vec<Sibling> = (0..total as u32).map(|value| Sibling { value, ..placeholder }).collect();
    let smooth_boundaries = rules.has_smooth_boundaries();
    for v in parent.vertices() {
        let slots = first[v.index()] as usize..first[v.index() + 1] as usize;
        for (sibling, from) in siblings[slots].iter_mut().zip(level.of(v)) {
            sibling.tag = from.tag;
            if let (true, Some([h0, h1])) = (smooth_boundaries && !from.tag.is_inf_sharp(), from.ends) {
                sibling.ends = Some([h0, h1].map(|h| at.split.corner_child(parent, h, 0)));
            }
        }
    }
    for e in parent.edges() {
        let tag = level.edges[e.index()];
        if !(tag.mismatch || tag.linear) {
            continue;
        }
        let point = at.edge_child(e);
        let slots = first[point.index()] as usize..first[point.index() + 1] as usize;
        let sides = edge_sides(parent, e);
        for (&h, sibling) in sides.iter().zip(&mut siblings[slots]) {
            sibling.tag = ValueTag { mismatch: true, crease: smooth_boundaries, ..ValueTag::default() };
            if smooth_boundaries && tag.mismatch {
                // The crease runs along the edge's two halves on `h`'s side: from the point
                // in the child at `h`'s next corner to the point in the child at `h`'s corner.
                let last = at.split.child_face_size() - 1;
                let lead = at.split.corner_child(parent, parent.next(h), last);
                sibling.ends = Some([lead, at.split.corner_child(parent, h, 1)]);
            }
        }
    }
    if smooth_boundaries {
        reclassify_semi_sharp(parent, child, &first, &mut siblings, rules);
    }
    let child_level = ChannelLevel { first, siblings, corner_sibling, edges };
    let values = interpolate(at, channel, level, &child_level, rules, edge_mask, vertex_mask)?;
    Ok((Channel::new(channel.name(), channel.dimension(), values, indices), child_level))
}

/// `FVarRefinement::reclassifySemisharpValues`: a semi-sharp value of a child vertex whose
/// span holds no semi-sharp edge any more becomes a crease.
fn reclassify_semi_sharp(parent: &Mesh, child: &Mesh, first: &[u32], siblings: &mut [Sibling], rules: ChannelRules) {
    let semi_sharp = |s: f64| crease::is_semi_sharp(sharpness(s));
    if !parent.vertices().any(|v| semi_sharp(parent.vertex_sharpness(v)))
        && !parent.edges().any(|e| semi_sharp(parent.edge_sharpness(e)))
    {
        return;
    }
    // Which parent vertices have a semi-sharp edge, in the parent and in the child: one pass
    // over each level's edges.
    let semi_edge_ends = |mesh: &Mesh| {
        let mut ends = vec![false; parent.vertex_count()];
        for e in mesh.edges().filter(|&e| semi_sharp(mesh.edge_sharpness(e))) {
            for v in mesh.edge_vertices(e) {
                if let Some(flag) = ends.get_mut(v.index()) {
                    *flag = true;
                }
            }
        }
        ends
    };
    let (parent_semi, child_semi) = (semi_edge_ends(parent), semi_edge_ends(child));
    for v in parent.vertices() {
        let own = &mut siblings[first[v.index()] as usize..first[v.index() + 1] as usize];
        if !own[0].tag.mismatch {
            continue;
        }
        if !crease::is_semi_sharp(sharpness(parent.vertex_sharpness(v))) && !parent_semi[v.index()] {
            continue;
        }
        if crease::is_sharp(sharpness(child.vertex_sharpness(v))) {
            continue;
        }
        let to_crease = |tag: &mut ValueTag| {
            tag.semi_sharp = false;
            tag.dep_sharp = false;
            tag.crease = true;
        };
        if !child_semi[v.index()] {
            for s in own.iter_mut().filter(|s| s.tag.semi_sharp) {
                to_crease(&mut s.tag);
            }
            continue;
        }
        for s in own.iter_mut().filter(|s| s.tag.semi_sharp && !s.tag.dep_sharp) {
            let still = s.ends.is_some_and(|ends| {
                span_edges(child, ends).iter().any(|&e| crease::is_semi_sharp(sharpness(child.edge_sharpness(e))))
            });
            if !still {
                to_crease(&mut s.tag);
            }
        }
        if own.len() == 2 && rules.has_dependent_sharpness() {
            if own[0].tag.dep_sharp && !own[1].tag.semi_sharp {
                own[0].tag.dep_sharp = false;
            } else if own[1].tag.dep_sharp && !own[0].tag.semi_sharp {
                own[1].tag.dep_sharp = false;
            }
        }
    }
}

/// The edges inside a span, between its first and last face (not the two bounding edges).
fn span_edges(mesh: &Mesh, [first, last]: [HalfEdgeId; 2]) -> SmallVec<[EdgeId; 8]> {
    let mut inside = SmallVec::new();
    let mut h = first;
    while mesh.face(h) != mesh.face(last) {
        match mesh.twin(mesh.prev(h)) {
            Some(next) if next != first => {
                h = next;
                inside.push(mesh.edge(h));
            }
            _ => break,
        }
    }
    inside
}

/// `Sdc::Crease::ComputeFractionalWeightAtVertex` over the edges inside a span
/// (`FVarRefinement::getFractionalWeight`).
fn span_fractional_weight(mesh: &Mesh, v: VertexId, ends: [HalfEdgeId; 2], method: CreaseMethod) -> f32 {
    let around: SmallVec<[f32; 8]> =
        vertex_edges(mesh, v).iter().map(|&(e, _)| sharpness(mesh.edge_sharpness(e))).collect();
    let parent_edges: SmallVec<[f32; 8]> =
        span_edges(mesh, ends).iter().map(|&e| sharpness(mesh.edge_sharpness(e))).collect();
    let child_edges: SmallVec<[f32; 8]> =
        parent_edges.iter().map(|&s| crease::child_edge_sharpness(method, s, &around)).collect();
    let vertex = sharpness(mesh.vertex_sharpness(v));
    crease::fractional_weight(vertex, crease::decrement(vertex), &parent_edges, &child_edges)
}

/// The child level's values (`PrimvarRefiner::InterpolateFaceVarying`): face points, then
/// edge points, then vertex points.
fn interpolate(
    at: &Children<'_>,
    channel: &Channel,
    level: &ChannelLevel,
    child_level: &ChannelLevel,
    rules: ChannelRules,
    edge_mask: impl Fn(EdgeId) -> Row,
    vertex_mask: impl Fn(VertexId) -> Row,
) -> Result<Vec<f64>, SchemeError> {
    let parent = at.parent;
    let d = channel.dimension();
    let nv = parent.vertex_count() as u32;
    let mut out = vec![0.0; child_level.siblings.len() * d];
    let slot = |cv: VertexId| child_level.first[cv.index()] as usize;
    // `out[value] += w · parent value`.
    let add = |out: &mut [f64], value: usize, parent_value: u32, w: f64| {
        for (o, x) in out[value * d..(value + 1) * d].iter_mut().zip(channel.value(parent_value)) {
            *o += w * x;
        }
    };
    let add_child = |out: &mut [f64], value: usize, other: usize, w: f64| {
        for k in 0..d {
            out[value * d + k] += w * out[other * d + k];
        }
    };

    // Face points (triangle splits have none).
    for f in parent.face_ids().filter(|_| at.split == PrimalSplit::Quads) {
        let value = slot(at.face_child(f));
        let w = 1.0 / parent.face_size(f) as f64;
        for h in parent.face_half_edges(f) {
            add(&mut out, value, channel.corner_value(h), w);
        }
    }

    // A parent row over vertices and face points, applied with `value_at` naming each
    // vertex's value.
    let apply_row = |out: &mut [f64], value: usize, row: &Row, value_at: &dyn Fn(VertexId) -> Option<u32>| {
        for &(i, w) in row.entries() {
            if i >= nv {
                add_child(out, value, slot(at.face_child(FaceId::new(i - nv))), w);
            } else {
                let v = value_at(VertexId::new(i)).ok_or_else(|| internal("a mask's vertex has no value"))?;
                add(out, value, v, w);
            }
        }
        Ok::<(), SchemeError>(())
    };

    for e in parent.edges() {
        let point = at.edge_child(e);
        let base = slot(point);
        let sides = edge_sides(parent, e);
        let midpoint = |out: &mut [f64], value: usize, h: HalfEdgeId| {
            add(out, value, channel.corner_value(h), 0.5);
            add(out, value, channel.corner_value(parent.next(h)), 0.5);
        };
        if child_level.of(point)[0].tag.mismatch {
            for (j, &h) in sides.iter().enumerate() {
                midpoint(&mut out, base + j, h);
            }
        } else if rules.is_linear() {
            midpoint(&mut out, base, sides[0]);
        } else {
            let value_at = |u: VertexId| {
                sides.iter().find_map(|&h| half_edge_from(parent, parent.face(h), u)).map(|h| channel.corner_value(h))
            };
            apply_row(&mut out, base, &edge_mask(e), &value_at)?;
        }
    }

    for v in parent.vertices() {
        let base = slot(v);
        let parents = level.of(v);
        let children = child_level.of(v);
        if !children[0].tag.mismatch {
            if rules.is_linear() || parent.is_isolated(v) {
                add(&mut out, base, parents[0].value, 1.0);
                continue;
            }
            let ring = ring(parent, v);
            let own = parents[0].value;
            let value_at = |u: VertexId| {
                if u == v {
                    return Some(own);
                }
                if let Some(&h) = ring.iter().find(|&&h| parent.dest(h) == u) {
                    return Some(channel.corner_value(parent.next(h)));
                }
                let last = parent.prev(*ring.last()?);
                (parent.origin(last) == u).then(|| channel.corner_value(last))
            };
            apply_row(&mut out, base, &vertex_mask(v), &value_at)?;
            continue;
        }
        for (j, (p, c)) in parents.iter().zip(children).enumerate() {
            if rules.is_linear() || c.tag.is_corner() {
                add(&mut out, base + j, p.value, 1.0);
                continue;
            }
            let [h0, h1] = p.ends.ok_or_else(|| internal("a crease value has no ends"))?;
            let (e0, e1) = (channel.corner_value(parent.next(h0)), channel.corner_value(parent.prev(h1)));
            let (crease_own, crease_end) = at.crease;
            let (mut own, mut end) = at.crease;
            if p.tag.semi_sharp {
                // The transition from corner to crease, by the features that stop being sharp
                // (a dependent value by its partner's).
                let from = if p.tag.dep_sharp { parents.get(usize::from(j == 0)) } else { Some(p) };
                let ends = from.and_then(|s| s.ends).ok_or_else(|| internal("a semi-sharp value has no span"))?;
                let corner = f64::from(span_fractional_weight(parent, v, ends, rules.crease_method));
                let crease = 1.0 - corner;
                own = crease * crease_own + corner;
                end = crease * crease_end;
            }
            add(&mut out, base + j, e0, end);
            add(&mut out, base + j, e1, end);
            add(&mut out, base + j, p.value, own);
        }
    }
    Ok(out)
}

/// The channel's own mesh: one vertex per run of faces that share a value around a vertex
/// (a value's span, split where a seam ends inside it), placed at the value (padded to three
/// components), the mesh's faces over them, and the channel's rules as sharpness — so that the
/// scheme's refinement of this mesh's positions is the channel's face-varying refinement and
/// its limit surface is the channel's (see [`crate::ChannelSurface`]).
///
/// The one rule sharpness cannot say exactly is a corners-plus mode's *dependent* value (sharp
/// because its vertex's other value is): its corner sharpness is the largest semi-sharp edge
/// of its partner's span, which is OpenSubdiv's rule when that span has one semi-sharp edge.
pub(crate) fn channel_soup(mesh: &Mesh, channel: &Channel, level: &ChannelLevel) -> PolygonSoup {
    let mut soup = PolygonSoup::with_capacity(level.siblings.len(), mesh.face_count(), mesh.half_edge_count());
    let mut corner_vertex = vec![u32::MAX; mesh.half_edge_count()];
    let mut corners: Vec<(VertexId, f64)> = Vec::new();
    for v in mesh.vertices() {
        let ring = ring(mesh, v);
        let nf = ring.len();
        if nf == 0 {
            continue;
        }
        let own = level.of(v);
        let sibling = |i: usize| level.corner_sibling[ring[i].index()] as usize;
        // Runs break where the sibling changes or a seam crosses (edge i lies between faces
        // i − 1 and i).
        let breaks =
            |i: usize| sibling(i) != sibling((i + nf - 1) % nf) || level.edges[mesh.edge(ring[i]).index()].mismatch;
        let boundary = mesh.is_boundary_vertex(v);
        let start = if boundary { 0 } else { (0..nf).find(|&i| breaks(i)).unwrap_or(0) };
        let mut pieces: SmallVec<[(usize, VertexId); 4]> = SmallVec::new();
        for k in 0..nf {
            let i = (start + k) % nf;
            if k == 0 || breaks(i) {
                let s = sibling(i);
                let value = channel.value(own[s].value);
                let at = |c: usize| value.get(c).copied().unwrap_or(0.0);
                pieces.push((s, soup.push_vertex(glam::DVec3::new(at(0), at(1), at(2)))));
            }
            corner_vertex[ring[i].index()] = pieces[pieces.len() - 1].1.raw();
        }
        for &(s, vertex) in &pieces {
            let tag = own[s].tag;
            let disjoint = pieces.iter().filter(|p| p.0 == s).count() > 1;
            let sharpness = if !tag.mismatch {
                mesh.vertex_sharpness(v)
            } else if disjoint || tag.is_inf_sharp() {
                f64::from(crease::INFINITE)
            } else if tag.dep_sharp {
                let partner = own.get(usize::from(s == 0)).and_then(|p| p.ends);
                partner.map_or(0.0, |ends| {
                    span_edges(mesh, ends).iter().map(|&e| mesh.edge_sharpness(e)).fold(0.0, f64::max)
                })
            } else if tag.semi_sharp {
                mesh.vertex_sharpness(v)
            } else {
                0.0
            };
            if sharpness > 0.0 {
                corners.push((vertex, sharpness));
            }
        }
    }
    for f in mesh.face_ids() {
        soup.push_face(mesh.face_half_edges(f).map(|h| VertexId::new(corner_vertex[h.index()])));
    }
    // Interior edges the channel does not cut keep the mesh's sharpness.
    for e in mesh.edges().filter(|&e| !mesh.is_boundary_edge(e) && !level.edges[e.index()].mismatch) {
        let s = mesh.edge_sharpness(e);
        if s > 0.0 {
            let h = mesh.edge_half_edge(e);
            let vertices = [h, mesh.next(h)].map(|x| VertexId::new(corner_vertex[x.index()]));
            soup.tags.creases.push(subdiv_mesh::CreaseTag { vertices, sharpness: s });
        }
    }
    soup.tags.corners =
        corners.into_iter().map(|(vertex, sharpness)| subdiv_mesh::CornerTag { vertex, sharpness }).collect();
    soup.tags.boundary_interpolation = Some(subdiv_mesh::BoundaryInterpolation::EdgeOnly);
    soup.tags.crease_method = mesh.tags().crease_method;
    soup.tags.triangle_subdivision = mesh.tags().triangle_subdivision;
    soup
}
