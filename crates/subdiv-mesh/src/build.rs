//! Building the half-edge structure from a polygon soup, with every validation rule.
//!
//! Half-edges are the corners of the flattened face list, so `origin` is the soup's own index
//! array and `next`/`prev` follow from the face offsets. Twins are found through a CSR table of
//! the half-edges leaving each vertex: linear time, no hashing, which is what makes a
//! million-face grid build in tens of milliseconds.

use glam::DVec3;

use crate::mesh::{Mesh, NONE};
use crate::{EdgeId, FaceId, HalfEdgeId, MeshError, PolygonSoup, Tags, VertexId};

/// The largest coordinate magnitude a control mesh may have, 2⁵⁰⁰ ≈ 3.3e150.
///
/// Refinement and evaluation form weighted sums of coordinates, and normals, areas and curvature
/// bounds multiply two of them: with coordinates up to 2⁵⁰⁰ such a product is at most 2¹⁰⁰⁰,
/// leaving 2²⁴ of f64's range (2¹⁰²⁴) for the weights and the grid rates. A cage past it (a
/// vertex at 1e308) would refine to infinities and evaluate to NaN; scale it down instead.
pub const MAX_COORDINATE: f64 = 3.273_390_607_896_142e150;

/// Options of [`Mesh::build_with`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildOptions {
    /// Flip faces so that every component is consistently oriented, keeping the orientation
    /// that most of the component's faces already have. Default `false`: an inconsistently
    /// oriented soup is an error ([`MeshError::InconsistentOrientation`]). A non-orientable
    /// component (a Möbius strip) stays an error ([`MeshError::NonOrientable`]).
    pub orient: bool,
    /// Take a non-manifold soup apart into sheets as OpenSubdiv refines it: an edge of more
    /// than two faces becomes a border of each (an infinitely sharp crease where the sheets
    /// end), a vertex whose faces form more than one fan becomes one vertex per fan, and the
    /// copies of a vertex OpenSubdiv sharpens (a non-manifold vertex, unless exactly two
    /// non-manifold edges meet there) are tagged infinitely sharp corners. Default `false`: a
    /// non-manifold soup is an error ([`MeshError::NonManifoldEdge`],
    /// [`MeshError::NonManifoldVertex`]).
    pub split_sheets: bool,
}

impl BuildOptions {
    /// The defaults: no orientation repair, no sheets split.
    pub const DEFAULT: Self = Self { orient: false, split_sheets: false };

    /// Sets [`orient`](Self::orient).
    pub fn with_orient(mut self, orient: bool) -> Self {
        self.orient = orient;
        self
    }

    /// Sets [`split_sheets`](Self::split_sheets).
    pub fn with_split_sheets(mut self, split_sheets: bool) -> Self {
        self.split_sheets = split_sheets;
        self
    }
}

/// Every rule the soup breaks, in a stable order: per-face and per-vertex rules first (in id
/// order), then edges, vertices, tags. Empty when [`Mesh::build`] would succeed.
///
/// Faces that break a per-face rule are left out of the later checks, and vertices on a
/// non-manifold or inconsistently oriented edge are not checked for fans, so each problem is
/// reported once, where it is.
///
/// ```
/// use subdiv_mesh::{validate, MeshError, PolygonSoup, DVec3};
///
/// let soup = PolygonSoup::from_indices(vec![DVec3::ZERO; 4], [[0u32, 1, 1], [0, 2, 3]]);
/// assert!(matches!(validate(&soup)[..], [MeshError::RepeatedVertex { .. }]));
/// ```
pub fn validate(soup: &PolygonSoup) -> Vec<MeshError> {
    let mut sink = Sink { errors: Vec::new(), first_only: false };
    let (offsets, fv) = soup.raw_faces();
    if let Some(topology) = connect(soup.positions(), offsets, fv, &mut sink) {
        apply_tags(&topology, fv, offsets, &soup.tags, &mut sink);
    }
    sink.errors.extend(soup.channels.iter().filter_map(|c| c.check(offsets, fv.len())));
    sink.errors
}

struct Sink {
    errors: Vec<MeshError>,
    first_only: bool,
}

impl Sink {
    /// Records `error`; returns whether to stop.
    fn push(&mut self, error: MeshError) -> bool {
        self.errors.push(error);
        self.first_only
    }
}

/// The connectivity arrays of a mesh (everything but positions, faces and tags).
pub(crate) struct Topology {
    pub(crate) he_face: Vec<FaceId>,
    pub(crate) he_twin: Vec<u32>,
    pub(crate) he_edge: Vec<EdgeId>,
    pub(crate) edge_he: Vec<HalfEdgeId>,
    pub(crate) vertex_he: Vec<u32>,
    pub(crate) valence: Vec<u32>,
}

impl Mesh {
    /// Builds the half-edge mesh of `soup`, or returns the first rule it breaks (see
    /// [`validate`] for all of them).
    ///
    /// ```
    /// use subdiv_mesh::{Mesh, PolygonSoup, DVec3};
    ///
    /// // Two triangles sharing the edge 0-2.
    /// let soup = PolygonSoup::from_indices(
    ///     vec![DVec3::ZERO, DVec3::X, DVec3::ONE, DVec3::Y],
    ///     [[0u32, 1, 2], [0, 2, 3]],
    /// );
    /// let mesh = Mesh::build(soup)?;
    /// assert_eq!(mesh.edge_count(), 5);
    /// assert_eq!(mesh.boundary_edge_count(), 4);
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn build(soup: PolygonSoup) -> Result<Mesh, MeshError> {
        Self::build_with(soup, &BuildOptions::DEFAULT)
    }

    /// Builds the half-edge mesh of `soup` with `options`.
    pub fn build_with(mut soup: PolygonSoup, options: &BuildOptions) -> Result<Mesh, MeshError> {
        let mut sink = Sink { errors: Vec::new(), first_only: true };
        if options.split_sheets {
            crate::sheets::split_sheets(&mut soup);
        }
        if options.orient {
            orient(&mut soup, &mut sink);
            if let Some(error) = sink.errors.pop() {
                return Err(error);
            }
        }
        let (offsets, fv) = soup.raw_faces();
        let topology = connect(soup.positions(), offsets, fv, &mut sink);
        let (Some(topology), None) = (topology, sink.errors.first()) else {
            return Err(sink.errors.swap_remove(0));
        };
        let resolved = apply_tags(&topology, fv, offsets, &soup.tags, &mut sink);
        if let Some(error) = sink.errors.pop() {
            return Err(error);
        }
        if let Some(error) = soup.channels.iter().find_map(|c| c.check(offsets, fv.len())) {
            return Err(error);
        }
        let (positions, face_offsets, he_origin, tags_as_authored, channels) = soup.into_parts();
        let mut mesh = Mesh::from_parts(positions, face_offsets, he_origin, tags_as_authored, topology, resolved);
        // Checked above, against the soup's corners (the mesh's).
        mesh.set_channels(channels)?;
        Ok(mesh)
    }
}

#[inline]
pub(crate) fn next_in_face(offsets: &[u32], he_face: &[FaceId], h: u32) -> u32 {
    let f = he_face[h as usize].index();
    if h + 1 == offsets[f + 1] { offsets[f] } else { h + 1 }
}

#[inline]
pub(crate) fn prev_in_face(offsets: &[u32], he_face: &[FaceId], h: u32) -> u32 {
    let f = he_face[h as usize].index();
    if h == offsets[f] { offsets[f + 1] - 1 } else { h - 1 }
}

/// Checks the per-face and per-vertex rules, then links twins, numbers edges and walks the
/// vertex fans. Returns `None` when the sink asked to stop.
fn connect(positions: &[DVec3], offsets: &[u32], fv: &[VertexId], sink: &mut Sink) -> Option<Topology> {
    let vertex_count = positions.len();
    let face_count = offsets.len() - 1;
    // Ids are u32 with u32::MAX as "none".
    let max = (u32::MAX - 1) as usize;
    for (what, count) in [("vertices", vertex_count), ("face corners", fv.len())] {
        if count > max && sink.push(MeshError::TooLarge { what, count, max }) {
            return None;
        }
    }
    for (v, p) in positions.iter().enumerate() {
        let vertex = VertexId::new(v as u32);
        let error = if !p.is_finite() {
            MeshError::NonFiniteCoordinate { vertex, x: p.x, y: p.y, z: p.z }
        } else if p.abs().max_element() > MAX_COORDINATE {
            MeshError::CoordinateTooLarge { vertex, x: p.x, y: p.y, z: p.z }
        } else {
            continue;
        };
        if sink.push(error) {
            return None;
        }
    }

    // Per-face rules. Bad faces keep their half-edges (ids are corner positions) but take no
    // part in the connectivity, so one bad face does not hide the rest.
    // Allocated on the first bad face only: valid input never pays for it.
    let mut face_ok: Option<Vec<bool>> = None;
    for f in 0..face_count {
        let face = FaceId::new(f as u32);
        let corners = &fv[offsets[f] as usize..offsets[f + 1] as usize];
        let error = face_rule(face, corners, vertex_count);
        if let Some(error) = error {
            face_ok.get_or_insert_with(|| vec![true; face_count])[f] = false;
            if sink.push(error) {
                return None;
            }
        }
    }

    let corner_count = fv.len();
    let mut he_face = vec![FaceId::new(0); corner_count];
    for f in 0..face_count {
        he_face[offsets[f] as usize..offsets[f + 1] as usize].fill(FaceId::new(f as u32));
    }
    let usable = |h: usize| face_ok.as_ref().is_none_or(|ok| ok[he_face[h].index()]);

    // CSR of outgoing half-edges per vertex, each entry (destination, half-edge).
    let mut out_start = vec![0u32; vertex_count + 1];
    for (h, v) in fv.iter().enumerate() {
        if usable(h) {
            out_start[v.index() + 1] += 1;
        }
    }
    for v in 0..vertex_count {
        out_start[v + 1] += out_start[v];
    }
    // Filled back to front, so each vertex's list stays in half-edge order and `out_start`
    // ends up as the list starts without a second offsets array.
    let mut out = vec![(0u32, 0u32); out_start[vertex_count] as usize];
    for f in (0..face_count).rev() {
        if !face_ok.as_ref().is_none_or(|ok| ok[f]) {
            continue;
        }
        let (start, end) = (offsets[f], offsets[f + 1]);
        for h in (start..end).rev() {
            let origin = fv[h as usize].index();
            let dest = fv[if h + 1 == end { start } else { h + 1 } as usize].raw();
            out_start[origin + 1] -= 1;
            out[out_start[origin + 1] as usize] = (dest, h);
        }
    }
    // Now out_start[v + 1] is the start of v's list; shift to the usual CSR form.
    out_start.copy_within(1..vertex_count + 1, 0);
    out_start[vertex_count] = out.len() as u32;
    let outgoing = |v: usize| &out[out_start[v] as usize..out_start[v + 1] as usize];

    // Twins. An undirected edge {a, b} carries the half-edges a→b and b→a; anything but at most
    // one of each breaks a rule. Each problem is reported by the lowest half-edge on the edge.
    let mut he_twin = vec![NONE; corner_count];
    // Vertices touching a broken edge: their fans are not checked (the edge is the problem).
    let mut vertex_on_bad_edge = vec![false; 0];
    for a in 0..vertex_count {
        for &(b, h) in outgoing(a) {
            if he_twin[h as usize] != NONE {
                continue; // linked from its twin's side, which checked this edge already
            }
            let mut same = 0usize;
            let mut lowest = h;
            let mut other_same = NONE;
            for &(d, h2) in outgoing(a) {
                if d == b {
                    same += 1;
                    lowest = lowest.min(h2);
                    if h2 != h {
                        other_same = other_same.min(h2);
                    }
                }
            }
            let mut opposite = 0usize;
            let mut twin = NONE;
            for &(d, h2) in outgoing(b as usize) {
                if d == a as u32 {
                    opposite += 1;
                    lowest = lowest.min(h2);
                    twin = h2;
                }
            }
            if same == 1 && opposite <= 1 {
                if twin != NONE {
                    he_twin[h as usize] = twin;
                    he_twin[twin as usize] = h;
                }
                continue;
            }
            if vertex_on_bad_edge.is_empty() {
                vertex_on_bad_edge = vec![false; vertex_count];
            }
            vertex_on_bad_edge[a] = true;
            vertex_on_bad_edge[b as usize] = true;
            if lowest != h {
                continue;
            }
            let (va, vb) = (VertexId::new(a as u32), VertexId::new(b));
            let error = if same + opposite >= 3 {
                MeshError::NonManifoldEdge { a: va, b: vb, face: he_face[h as usize], face_count: same + opposite }
            } else {
                let other = he_face[other_same as usize];
                MeshError::InconsistentOrientation { face: he_face[h as usize], other, a: va, b: vb }
            };
            if sink.push(error) {
                return None;
            }
        }
    }
    // Edges, numbered in the order of their first half-edge.
    let mut he_edge = vec![EdgeId::new(0); corner_count];
    let mut edge_he = Vec::with_capacity(corner_count / 2 + 1);
    for h in 0..corner_count {
        if !usable(h) {
            continue;
        }
        let twin = he_twin[h];
        if twin == NONE || (h as u32) < twin {
            let e = EdgeId::new(edge_he.len() as u32);
            edge_he.push(HalfEdgeId::new(h as u32));
            he_edge[h] = e;
            if twin != NONE {
                he_edge[twin as usize] = e;
            }
        }
    }

    // Fans. Rotating clockwise from any outgoing half-edge reaches the boundary half-edge of a
    // boundary vertex; the counter-clockwise walk from there must visit every outgoing
    // half-edge, or the vertex has several fans.
    let mut vertex_he = vec![NONE; vertex_count];
    let mut valence = vec![0u32; vertex_count];
    for v in 0..vertex_count {
        let Some(&(_, h0)) = outgoing(v).first() else { continue };
        if vertex_on_bad_edge.get(v).copied().unwrap_or(false) {
            continue;
        }
        let count = outgoing(v).len() as u32;
        // Counter-clockwise from h0 (h -> twin(prev(h))): back at h0 means a closed fan.
        let mut visited = 1u32;
        let mut h = h0;
        let mut boundary = false;
        loop {
            let t = he_twin[prev_in_face(offsets, &he_face, h) as usize];
            if t == NONE {
                boundary = true;
                break;
            }
            if t == h0 || visited > count {
                break;
            }
            h = t;
            visited += 1;
        }
        // An open fan: clockwise from h0 (h -> next(twin(h))) to its boundary half-edge.
        let mut start = h0;
        if boundary {
            loop {
                let t = he_twin[start as usize];
                if t == NONE || visited > count {
                    break;
                }
                start = next_in_face(offsets, &he_face, t);
                visited += 1;
            }
        }
        if visited != count {
            let vertex = VertexId::new(v as u32);
            let fans = count_fans(outgoing(v), offsets, &he_face, &he_twin);
            if sink.push(MeshError::NonManifoldVertex { vertex, fans }) {
                return None;
            }
            continue;
        }
        vertex_he[v] = if boundary { start } else { h0 };
        valence[v] = count + u32::from(boundary);
    }
    Some(Topology { he_face, he_twin, he_edge, edge_he, vertex_he, valence })
}

fn face_rule(face: FaceId, corners: &[VertexId], vertex_count: usize) -> Option<MeshError> {
    if corners.len() < 3 {
        return Some(MeshError::TooFewVertices { face, count: corners.len() });
    }
    if let Some(v) = corners.iter().find(|v| v.index() >= vertex_count) {
        return Some(MeshError::IndexOutOfRange { face, index: v.raw(), vertex_count });
    }
    let repeated = if let [a, b, c] = *corners {
        (a == b || a == c).then_some(a).or((b == c).then_some(b))
    } else if let [a, b, c, d] = *corners {
        (a == b || a == c || a == d).then_some(a).or((b == c || b == d).then_some(b)).or((c == d).then_some(c))
    } else if corners.len() <= 16 {
        corners.iter().enumerate().find(|&(i, v)| corners[..i].contains(v)).map(|(_, &v)| v)
    } else {
        let mut sorted = corners.to_vec();
        sorted.sort_unstable();
        sorted.windows(2).find(|w| w[0] == w[1]).map(|w| w[0])
    };
    repeated.map(|vertex| MeshError::RepeatedVertex { face, vertex })
}

/// How many fans the outgoing half-edges of a vertex form (only called on non-manifold
/// vertices). `outgoing` is sorted by half-edge.
fn count_fans(outgoing: &[(u32, u32)], offsets: &[u32], he_face: &[FaceId], he_twin: &[u32]) -> usize {
    let position = |h: u32| outgoing.binary_search_by_key(&h, |&(_, h)| h).ok();
    let mut seen = vec![false; outgoing.len()];
    let mut fans = 0;
    let mut stack = Vec::new();
    for i in 0..outgoing.len() {
        if seen[i] {
            continue;
        }
        fans += 1;
        seen[i] = true;
        stack.push(outgoing[i].1);
        // Flood both ways around the vertex: clockwise next(twin(h)), counter-clockwise
        // twin(prev(h)).
        while let Some(h) = stack.pop() {
            let t = he_twin[h as usize];
            let cw = if t == NONE { NONE } else { next_in_face(offsets, he_face, t) };
            let ccw = he_twin[prev_in_face(offsets, he_face, h) as usize];
            for n in [cw, ccw] {
                if let Some(j) = (n != NONE).then(|| position(n)).flatten()
                    && !seen[j]
                {
                    seen[j] = true;
                    stack.push(n);
                }
            }
        }
    }
    fans
}

/// Tags resolved onto the mesh: sharpness per edge and per vertex, a hole flag per face.
pub(crate) struct ResolvedTags {
    pub(crate) edge_sharpness: Vec<f64>,
    pub(crate) vertex_sharpness: Vec<f64>,
    pub(crate) holes: Vec<bool>,
}

/// Resolves tags into per-edge and per-vertex sharpness and per-face hole flags (a later tag on
/// the same edge or vertex wins, as in OpenSubdiv).
fn apply_tags(topology: &Topology, fv: &[VertexId], offsets: &[u32], tags: &Tags, sink: &mut Sink) -> ResolvedTags {
    let vertex_count = topology.vertex_he.len();
    let face_count = offsets.len() - 1;
    let mut resolved = ResolvedTags {
        edge_sharpness: vec![0.0; topology.edge_he.len()],
        vertex_sharpness: vec![0.0; vertex_count],
        holes: vec![false; face_count],
    };
    let ResolvedTags { edge_sharpness, vertex_sharpness, holes } = &mut resolved;
    let check_sharpness = |tag: &'static str, index: usize, sharpness: f64| {
        (sharpness.is_nan() || sharpness < 0.0).then_some(MeshError::InvalidSharpness { tag, index, sharpness })
    };
    for (index, crease) in tags.creases.iter().enumerate() {
        let [a, b] = crease.vertices;
        let error = if let Some(v) = [a, b].into_iter().find(|v| v.index() >= vertex_count) {
            Some(MeshError::TagVertexOutOfRange { tag: "crease", index, vertex: v.raw(), vertex_count })
        } else if let Some(error) = check_sharpness("crease", index, crease.sharpness) {
            Some(error)
        } else {
            match find_edge(topology, fv, offsets, a, b) {
                Some(e) => {
                    edge_sharpness[e.index()] = crease.sharpness;
                    None
                }
                None => Some(MeshError::CreaseNotAnEdge { index, a, b }),
            }
        };
        if let Some(error) = error
            && sink.push(error)
        {
            return resolved;
        }
    }
    for (index, corner) in tags.corners.iter().enumerate() {
        let v = corner.vertex;
        let error = if v.index() >= vertex_count {
            Some(MeshError::TagVertexOutOfRange { tag: "corner", index, vertex: v.raw(), vertex_count })
        } else {
            check_sharpness("corner", index, corner.sharpness)
        };
        match error {
            Some(error) => {
                if sink.push(error) {
                    return resolved;
                }
            }
            None => vertex_sharpness[v.index()] = corner.sharpness,
        }
    }
    for (index, face) in tags.holes.iter().enumerate() {
        if face.index() >= face_count {
            if sink.push(MeshError::HoleOutOfRange { index, face: face.raw(), face_count }) {
                return resolved;
            }
        } else {
            holes[face.index()] = true;
        }
    }
    resolved
}

/// The edge between `a` and `b`, walking the fan of `a`.
fn find_edge(topology: &Topology, fv: &[VertexId], offsets: &[u32], a: VertexId, b: VertexId) -> Option<EdgeId> {
    for (from, to) in [(a, b), (b, a)] {
        let h0 = topology.vertex_he[from.index()];
        if h0 == NONE {
            continue;
        }
        let mut h = h0;
        loop {
            let next = next_in_face(offsets, &topology.he_face, h);
            if fv[next as usize] == to {
                return Some(topology.he_edge[h as usize]);
            }
            let t = topology.he_twin[prev_in_face(offsets, &topology.he_face, h) as usize];
            if t == NONE || t == h0 {
                break;
            }
            h = t;
        }
    }
    None
}

/// Flips faces so each component is consistently oriented (majority orientation wins).
fn orient(soup: &mut PolygonSoup, sink: &mut Sink) {
    let vertex_count = soup.vertex_count();
    let face_count = soup.face_count();
    let (offsets, fv) = soup.raw_faces();
    // Skip faces that break per-face rules; `connect` reports them afterwards.
    let face_ok: Vec<bool> = (0..face_count)
        .map(|f| {
            face_rule(FaceId::new(f as u32), &fv[offsets[f] as usize..offsets[f + 1] as usize], vertex_count).is_none()
        })
        .collect();
    // Undirected edge incidences per lower vertex: (upper vertex, face, runs low→high).
    let mut start = vec![0u32; vertex_count + 1];
    let corners = |f: usize| &fv[offsets[f] as usize..offsets[f + 1] as usize];
    for f in (0..face_count).filter(|&f| face_ok[f]) {
        let c = corners(f);
        for i in 0..c.len() {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            start[a.min(b).index() + 1] += 1;
        }
    }
    for v in 0..vertex_count {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut incidences = vec![(0u32, 0u32, false); start[vertex_count] as usize];
    for f in (0..face_count).filter(|&f| face_ok[f]) {
        let c = corners(f);
        for i in 0..c.len() {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            let low = a.min(b).index();
            incidences[fill[low] as usize] = (a.max(b).raw(), f as u32, a < b);
            fill[low] += 1;
        }
    }
    // Breadth-first over faces: flip[g] = flip[f] xor (f and g run the edge the same way).
    const UNSEEN: u8 = 2;
    let mut flip = vec![UNSEEN; face_count];
    let mut queue = std::collections::VecDeque::new();
    let mut to_flip = Vec::new();
    for seed in (0..face_count).filter(|&f| face_ok[f]) {
        if flip[seed] != UNSEEN {
            continue;
        }
        flip[seed] = 0;
        let mut component = vec![seed];
        queue.push_back(seed);
        while let Some(f) = queue.pop_front() {
            let c = corners(f);
            for i in 0..c.len() {
                let (a, b) = (c[i], c[(i + 1) % c.len()]);
                let low = a.min(b).index();
                let range = start[low] as usize..start[low + 1] as usize;
                let on_edge: Vec<_> = incidences[range].iter().filter(|inc| inc.0 == a.max(b).raw()).collect();
                if on_edge.len() != 2 {
                    continue; // boundary, or non-manifold: `connect` reports the latter
                }
                let this_way = a < b;
                for &&(_, g, way) in &on_edge {
                    let g = g as usize;
                    if g == f {
                        continue;
                    }
                    let want = flip[f] ^ u8::from(way == this_way);
                    if flip[g] == UNSEEN {
                        flip[g] = want;
                        component.push(g);
                        queue.push_back(g);
                    } else if flip[g] != want {
                        sink.push(MeshError::NonOrientable { face: FaceId::new(seed as u32) });
                        return;
                    }
                }
            }
        }
        let flipped = component.iter().filter(|&&f| flip[f] == 1).count();
        let majority_flipped = 2 * flipped > component.len();
        to_flip.extend(component.into_iter().filter(|&f| (flip[f] == 1) != majority_flipped));
    }
    for f in to_flip {
        soup.flip_face(FaceId::new(f as u32));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn coordinates_past_the_headroom_are_refused_and_named() {
        assert_eq!(MAX_COORDINATE, 2f64.powi(500));
        // A vertex at 1e308 refined to infinities ("internal error") and evaluated to NaN.
        for (x, rule) in [
            (1e308, "coordinate-too-large"),
            (-4e150, "coordinate-too-large"),
            (f64::INFINITY, "non-finite-coordinate"),
        ] {
            let mut soup = shapes::cube();
            soup.positions_mut()[3].y = x;
            let e = Mesh::build(soup).unwrap_err();
            assert_eq!((e.rule(), e.vertex()), (rule, Some(VertexId::new(3))), "{e}");
        }
        let mut soup = shapes::cube();
        soup.positions_mut()[3].y = MAX_COORDINATE;
        assert!(Mesh::build(soup).is_ok());
    }
}
