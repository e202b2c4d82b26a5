//! The combinatorial half of dual-grid stitching: which output vertices exist (each with its
//! face and exact parameter), and the triangles and quads between them.
//!
//! Output vertices, in this order per input face (then per edge, then per vertex):
//! - **cells**: a quad face at rate `n` is one cell of `n × n` dual points; an N-gon (N ≠ 4,
//!   quad split) is N cells, one per `Bfr` sub-face, at rate `⌈n/2⌉` each (a sub-face is a
//!   quarter-sized quad, so the spacing matches the neighbours'); a triangle (triangle split) is
//!   one cell of `n²` sub-triangle centroids, then its interior primal points `(i/n, j/n)`
//!   (`i, j ≥ 1`, `i + j < n`), which the dual hexagons are fanned around;
//! - an N-gon's centre when `N ≥ 5` (its centre polygon is fanned around it);
//! - **border points** on each edge without a surface on one side (mesh boundary, or next to a
//!   hole), at the parameters of the row of points beside it;
//! - **vertex points**: a mesh vertex's limit point where its polygon is fanned around it (every
//!   vertex under a triangle split; interior vertices of valence ≥ 5 and every border vertex
//!   under a quad split);
//! - **ring points** around an extraordinary point with a ring depth (quad split), made where its
//!   polygon would be (an N-gon's centre: after its cells; a vertex: with the vertex points):
//!   per ring, per face counter-clockwise, the point on the face's first edge (spoke), then the
//!   one on its diagonal; then the point's limit point.
//!
//! Polygons: cell interiors (the dual quad grid; the triangles' hexagons), **strips** along each
//! edge (and each N-gon spoke) merging the two rows nearest it in parameter order, and **rings**
//! around each vertex through the nearest point of each incident face. Every output edge is then
//! shared by exactly two polygons (or one, on the border), by construction.
//!
//! Most triangles follow a pattern (a cell's grid of quads; the ladder of quads between two rows
//! of equal parameters, along an edge between two whole quads of one rate or an N-gon's spoke):
//! those are [`Run`]s of a few numbers, written straight into the output, in parallel, by
//! [`Topology::write_triangles`]; the others are stored, in the order they are made.

use subdiv_mesh::{FaceId, HalfEdgeId, Mesh, VertexId};
use subdiv_stencil::{Dyadic, FaceDomain};

use crate::rates::{RingDepths, first_ring_depth, reach};

/// An output vertex's place on the surface: the input face that evaluates it and the exact
/// `Bfr` parameter there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Site {
    pub face: u32,
    pub point: Dyadic,
}

/// The dual grid of a whole quad face (not a sub-face): its points are `base + j·n + i` at
/// `((i+½)/n, (j+½)/n)`, which the regular fast path evaluates row by row. Their sites are
/// implicit ([`Topology::site`]); `sites` is the number of explicit sites before `base`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Block {
    pub face: u32,
    pub rate: u32,
    pub base: u32,
    pub sites: u32,
}

impl Block {
    /// The number of points.
    pub(super) fn len(&self) -> u32 {
        self.rate * self.rate
    }

    /// The site of its point `k = j · rate + i`.
    #[inline]
    pub(super) fn site(&self, k: u32) -> Site {
        let (i, j, q) = (i64::from(k % self.rate), i64::from(k / self.rate), 2 * i64::from(self.rate));
        Site { face: self.face, point: Dyadic::new(2 * i + 1, 2 * j + 1, q) }
    }
}

/// Triangles that follow a pattern, most of a tessellation's: they are written straight into
/// the output ([`Topology::write_triangles`]), in parallel, and never stored. `explicit` is the
/// number of explicit triangles made before them, `first` the first one's index in the output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Run {
    pub face: u32,
    pub explicit: u32,
    pub first: u32,
    pub shape: RunShape,
}

/// The pattern of a [`Run`]; each quad `a b c d` (counter-clockwise) as `(a, b, c)` and `(a, c, d)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RunShape {
    /// A block's `n × n` points' quads `k, k + 1, k + 1 + n, k + n`, row by row (`k = base + j·n + i`).
    Grid { base: u32, n: u32 },
    /// The quads between two rows of `len` points each, `a + k·da` on the left and `b + k·db` on
    /// the right of their direction (steps in two's complement): `b_k, b_k+1, a_k+1, a_k`, as
    /// [`Builder::strip`] makes them between rows of equal parameters.
    Ladder { a: u32, da: u32, b: u32, db: u32, len: u32 },
}

impl Run {
    /// The number of triangles.
    pub(super) fn triangles(&self) -> u32 {
        match self.shape {
            RunShape::Grid { n, .. } => 2 * (n - 1) * (n - 1),
            RunShape::Ladder { len, .. } => 2 * len.saturating_sub(1),
        }
    }

    /// Its quads, in order.
    #[inline]
    fn quads(&self, mut put: impl FnMut([u32; 4])) {
        match self.shape {
            RunShape::Grid { base, n } => {
                for j in 0..n.saturating_sub(1) {
                    for i in 0..n - 1 {
                        put(grid_quad(base + j * n + i, n));
                    }
                }
            }
            RunShape::Ladder { mut a, da, mut b, db, len } => {
                for _ in 1..len {
                    let (a1, b1) = (a.wrapping_add(da), b.wrapping_add(db));
                    put([b, b1, a1, a]);
                    (a, b) = (a1, b1);
                }
            }
        }
    }

    /// Its triangles' indices (`3 ×` [`triangles`](Self::triangles)): its quads in the order of
    /// [`quads`](Self::quads), each quad's six indices at once (no bounds check or iterator
    /// state per quad).
    fn write(&self, out: &mut [u32]) {
        match self.shape {
            RunShape::Grid { base, n } => {
                let quads = n.saturating_sub(1) as usize;
                for (j, row) in out.chunks_exact_mut(6 * quads.max(1)).take(quads).enumerate() {
                    let start = base + j as u32 * n;
                    for (i, t) in row.as_chunks_mut::<6>().0.iter_mut().enumerate() {
                        *t = quad_triangles(grid_quad(start + i as u32, n));
                    }
                }
            }
            RunShape::Ladder { mut a, da, mut b, db, .. } => {
                for t in out.as_chunks_mut::<6>().0 {
                    let (a1, b1) = (a.wrapping_add(da), b.wrapping_add(db));
                    *t = quad_triangles([b, b1, a1, a]);
                    (a, b) = (a1, b1);
                }
            }
        }
    }
}

/// Quad `k` of a grid run `n` points wide (`k` its first point): counter-clockwise.
#[inline(always)]
fn grid_quad(k: u32, n: u32) -> [u32; 4] {
    [k, k + 1, k + 1 + n, k + n]
}

/// A quad `a b c d` (counter-clockwise) as the triangles `(a, b, c)` and `(a, c, d)`.
#[inline(always)]
fn quad_triangles([a, b, c, d]: [u32; 4]) -> [u32; 6] {
    [a, b, c, a, c, d]
}

/// A point of a row beside an edge, with its parameter `num / den` along the edge.
#[derive(Clone, Copy, Debug)]
struct RowPoint {
    vertex: u32,
    num: u64,
    den: u64,
    /// Whether a border point goes beside it (every point of a quad row; the upward centroids
    /// of a triangle row, the ones nearest the edge).
    near: bool,
}

/// The output's vertices and connectivity.
#[derive(Debug, Default)]
pub(crate) struct Topology {
    /// The number of output vertices.
    pub vertex_count: u32,
    /// The sites of the vertices outside the blocks, in vertex order (a block's are implicit,
    /// which spares writing most of them: [`Self::site`]).
    pub sites: Vec<Site>,
    pub blocks: Vec<Block>,
    /// The triangles made by pattern, in output order.
    pub runs: Vec<Run>,
    /// The explicit triangles (every triangle outside the runs), in output order, and their
    /// faces.
    pub triangles: Vec<[u32; 3]>,
    pub triangle_faces: Vec<FaceId>,
    pub polygon_offsets: Vec<u32>,
    pub polygon_vertices: Vec<u32>,
    pub polygon_faces: Vec<FaceId>,
}

/// A corner at an extraordinary point, in whose frame ring points are placed: face `face`'s
/// corner `corner` at a mesh vertex (the frame's `s` axis along side `corner`, `t` towards
/// corner `corner − 1`), or sub-face `sub`'s inner corner at an N-gon's centre (`s` along the
/// spoke shared with sub-face `sub − 1`, `t` along the one shared with `sub + 1`). Both frames
/// turn counter-clockwise around the point, from one corner of the ring to the next.
#[derive(Clone, Copy, Debug)]
enum RingCorner {
    Vertex { face: u32, corner: u32 },
    Centre { face: u32, sub: u32 },
}

impl Topology {
    /// Vertex `v`'s site.
    pub(super) fn site(&self, v: u32) -> Site {
        // The last block starting at or before `v`.
        let k = self.blocks.partition_point(|b| b.base <= v);
        match k.checked_sub(1).map(|k| &self.blocks[k]) {
            Some(b) if v < b.base + b.len() => b.site(v - b.base),
            Some(b) => self.sites[(b.sites + v - b.base - b.len()) as usize],
            None => self.sites[v as usize],
        }
    }

    /// The explicit sites (every vertex outside the blocks) with their vertex numbers, in
    /// vertex order.
    pub(super) fn explicit_sites(&self) -> impl Iterator<Item = (u32, Site)> + '_ {
        let mut blocks = self.blocks.iter().peekable();
        let mut v = 0;
        self.sites.iter().map(move |&site| {
            // The explicit sites fill the gaps between the blocks.
            while let Some(b) = blocks.next_if(|b| b.base <= v) {
                v = b.base + b.len();
            }
            v += 1;
            (v - 1, site)
        })
    }

    /// The number of triangles, the runs' included: up to the last run's end, then the explicit
    /// triangles made after it.
    pub(super) fn triangle_count(&self) -> u32 {
        let explicit = self.triangles.len() as u32;
        self.runs.last().map_or(explicit, |r| r.first + r.triangles() + explicit - r.explicit)
    }

    /// Every triangle, in output order (three indices each), into `out`, which has
    /// `3 ×` [`triangle_count`](Self::triangle_count) entries: the runs made here, the explicit
    /// triangles copied between them.
    pub(super) fn write_triangles(&self, out: &mut [u32], parallel: bool) {
        self.write_in_order(out, 3, self.triangles.as_flattened(), parallel, &|r, out| r.write(out));
    }

    /// Every triangle's face, in output order, into `out` ([`triangle_count`](Self::triangle_count) entries).
    pub(super) fn write_triangle_faces(&self, out: &mut [FaceId], parallel: bool) {
        self.write_in_order(out, 1, &self.triangle_faces, parallel, &|r, out| out.fill(FaceId::new(r.face)));
    }

    /// The walk of [`write_triangles`](Self::write_triangles) for `width` values per triangle:
    /// the explicit triangles before the first run, then per run its triangles (`made`) and the
    /// explicit triangles after it, halving the runs between rayon's threads while a half has
    /// enough triangles to be worth one.
    fn write_in_order<T: Copy + Send + Sync>(
        &self,
        out: &mut [T],
        width: usize,
        explicit: &[T],
        parallel: bool,
        made: &(dyn Fn(&Run, &mut [T]) + Sync),
    ) {
        assert_eq!(out.len(), width * self.triangle_count() as usize, "one entry per triangle value");
        let lead = self.runs.first().map_or(self.triangles.len(), |r| r.explicit as usize) * width;
        let (head, rest) = out.split_at_mut(lead);
        head.copy_from_slice(&explicit[..lead]);
        write_runs(&self.runs, explicit.len() / width, rest, width, explicit, parallel, made);
    }

    /// Every vertex's site, in vertex order.
    pub(super) fn for_each_site(&self, mut put: impl FnMut(Site)) {
        let mut explicit = self.sites.iter();
        let mut v = 0;
        for b in &self.blocks {
            explicit.by_ref().take((b.base - v) as usize).for_each(|&s| put(s));
            (0..b.len()).for_each(|k| put(b.site(k)));
            v = b.base + b.len();
        }
        explicit.for_each(|&s| put(s));
    }
}

/// [`Topology::write_in_order`] from `runs[0]` on (`out` starts at its first triangle), up to
/// the explicit triangle `end` (that of the run after the last, or the end).
fn write_runs<T: Copy + Send + Sync>(
    runs: &[Run],
    end: usize,
    out: &mut [T],
    width: usize,
    explicit: &[T],
    parallel: bool,
    made: &(dyn Fn(&Run, &mut [T]) + Sync),
) {
    /// Triangles below which a half is written where it is (a few microseconds of work).
    const GRAIN: usize = 1 << 14;
    if parallel && runs.len() > 1 && out.len() > GRAIN * width {
        let mid = runs.len() / 2;
        let (a, b) = out.split_at_mut((runs[mid].first - runs[0].first) as usize * width);
        let next = runs[mid].explicit as usize;
        crate::par::join(
            true,
            || write_runs(&runs[..mid], next, a, width, explicit, parallel, made),
            || write_runs(&runs[mid..], end, b, width, explicit, parallel, made),
        );
        return;
    }
    let mut out = out;
    for (k, r) in runs.iter().enumerate() {
        let (mine, rest) = out.split_at_mut(r.triangles() as usize * width);
        made(r, mine);
        let after = r.explicit as usize..runs.get(k + 1).map_or(end, |next| next.explicit as usize);
        let (copy, rest) = rest.split_at_mut(after.len() * width);
        copy.copy_from_slice(&explicit[after.start * width..after.end * width]);
        out = rest;
    }
}

impl RingCorner {
    fn face(self) -> usize {
        match self {
            Self::Vertex { face, .. } | Self::Centre { face, .. } => face as usize,
        }
    }
}

/// How finely face `f` at `rate` samples next to its corners: a quad split's
/// [`reach`] (a quad's rate, `2⌈n/2⌉` for an N-gon's sub-faces); a triangle's rate.
fn face_reach(mesh: &Mesh, triangle: bool, f: FaceId, rate: u32) -> u32 {
    if triangle { rate } else { reach(mesh, f, rate) }
}

/// The depth `d1` of the first ring around a point whose finest face reach is `finest`: under a
/// quad split [`first_ring_depth`] (`2^−d1` the largest power of two below the nearest dual
/// points' `½ / finest`); under a triangle split the largest power of two below `1 / (3 finest)`,
/// the corner centroids' distance from each side, so that the first ring's points on the edges
/// and at `(r/2, r/2)` lie inside the polygon through the centroids.
fn first_depth(triangle: bool, finest: u32) -> u32 {
    if triangle { (3 * finest + 1).next_power_of_two().trailing_zeros() } else { first_ring_depth(finest) }
}

/// The number of rings around a point at `depth` (> 0) whose first ring is at depth `first`:
/// from `2^−first` down to `2^−max(depth, first)`, one ring per halving (at least one).
fn ring_count(first: u32, depth: u32) -> u32 {
    depth.saturating_sub(first) + 1
}

/// The row of a quad cell's `m × m` points (from `base`, row by row) nearest its side `c`, in
/// the side's direction: its first point (the one nearest corner `c`) and the step between
/// points (in two's complement).
fn quad_side(base: u32, m: u32, c: usize) -> (u32, u32) {
    match c {
        0 => (base, 1),
        1 => (base + m - 1, m),
        2 => (base + m * m - 1, 1u32.wrapping_neg()),
        _ => (base + (m - 1) * m, m.wrapping_neg()),
    }
}

/// One input face's cells.
#[derive(Clone, Copy, Debug)]
struct FaceCells {
    /// The first cell's first vertex (cells of one face are consecutive, `m²` or `n²` each).
    base: u32,
    /// Points per side of a cell: `n` for quads and triangles, `⌈n/2⌉` for sub-faces.
    m: u32,
    /// The face's domain.
    domain: FaceDomain,
}

/// Builds the topology of `mesh` (level 0 of the patch levels, holes tagged) at `rates`.
pub(crate) struct Builder<'a> {
    mesh: &'a Mesh,
    triangle: bool,
    quads: bool,
    out: Topology,
    buf: BuilderBuffers,
}

/// A [`Builder`]'s buffers between calls (kept by the tessellator, so that a call allocates
/// nothing): the buffers of one mesh (`corner` is computed when its length is not the mesh's).
#[derive(Debug, Default)]
pub(crate) struct BuilderBuffers {
    faces: Vec<Option<FaceCells>>,
    /// Per half-edge: its corner number in its face.
    corner: Vec<u32>,
    /// Per half-edge on a border: its first border point and their number.
    border: Vec<(u32, u32)>,
    row: Vec<RowPoint>,
    other: Vec<RowPoint>,
    ring: Vec<u32>,
    starts: Vec<HalfEdgeId>,
    /// The ring's corners, beside `ring` (for the rings around extraordinary points).
    ring_corners: Vec<RingCorner>,
    /// The rates being built, and the ring depths (empty: none).
    rates: Vec<u32>,
    ring_vertices: Vec<u32>,
    ring_centres: Vec<u32>,
}

impl<'a> Builder<'a> {
    /// `domains[f]` is `None` for a hole.
    #[cfg(test)]
    pub(crate) fn new(mesh: &'a Mesh, triangle: bool, quads: bool) -> Self {
        Self::with_buffers(mesh, triangle, quads, BuilderBuffers::default())
    }

    /// A builder on the buffers of an earlier one of `mesh` ([`into_buffers`](Self::into_buffers)).
    pub(crate) fn with_buffers(mesh: &'a Mesh, triangle: bool, quads: bool, mut buf: BuilderBuffers) -> Self {
        if buf.corner.len() != mesh.half_edge_count() {
            buf.corner.clear();
            buf.corner.resize(mesh.half_edge_count(), 0);
            for f in mesh.face_ids() {
                for (k, h) in mesh.face_half_edges(f).enumerate() {
                    buf.corner[h.index()] = k as u32;
                }
            }
        }
        Self { mesh, triangle, quads, out: Topology::default(), buf }
    }

    /// The buffers, for the next builder of the same mesh.
    pub(crate) fn into_buffers(self) -> BuilderBuffers {
        self.buf
    }

    /// The topology at `rates` with `rings` around extraordinary points (both checked by the
    /// caller; rings only under a quad split), reusing `out`'s allocations.
    pub(crate) fn build(
        &mut self,
        domains: &[Option<FaceDomain>],
        rates: &[u32],
        rings: Option<&RingDepths>,
        out: &mut Topology,
    ) {
        self.buf.rates.clear();
        self.buf.rates.extend_from_slice(rates);
        self.buf.ring_vertices.clear();
        self.buf.ring_centres.clear();
        if let Some(r) = rings {
            self.buf.ring_vertices.extend_from_slice(&r.vertices);
            self.buf.ring_centres.extend_from_slice(&r.centres);
        }
        std::mem::swap(&mut self.out, out);
        let o = &mut self.out;
        o.vertex_count = 0;
        o.sites.clear();
        o.blocks.clear();
        o.runs.clear();
        o.triangles.clear();
        o.triangle_faces.clear();
        o.polygon_offsets.clear();
        o.polygon_offsets.push(0);
        o.polygon_vertices.clear();
        o.polygon_faces.clear();
        self.buf.faces.clear();
        self.buf.border.clear();
        self.buf.border.resize(self.mesh.half_edge_count(), (u32::MAX, 0));
        for f in 0..domains.len() {
            self.face(f, domains[f], rates[f]);
        }
        for f in self.mesh.face_ids() {
            if self.buf.faces[f.index()].is_none() {
                continue;
            }
            for h in self.mesh.face_half_edges(f) {
                self.edge(h);
            }
        }
        for v in self.mesh.vertices() {
            self.vertex(v);
        }
        std::mem::swap(&mut self.out, out);
    }

    fn push_site(&mut self, face: usize, point: Dyadic) -> u32 {
        let id = self.out.vertex_count;
        self.out.sites.push(Site { face: face as u32, point });
        self.out.vertex_count += 1;
        id
    }

    fn triangle(&mut self, t: [u32; 3], face: u32) {
        self.out.triangles.push(t);
        self.out.triangle_faces.push(FaceId::new(face));
    }

    /// A quad `a b c d` (counter-clockwise): two triangles, and a polygon if asked for.
    fn quad(&mut self, q: [u32; 4], face: u32) {
        self.triangle([q[0], q[1], q[2]], face);
        self.triangle([q[0], q[2], q[3]], face);
        self.polygon(q, face);
    }

    /// Triangles by pattern (and their quads' polygons, if asked for).
    fn run(&mut self, face: u32, shape: RunShape) {
        let o = &mut self.out;
        let run = Run { face, explicit: o.triangles.len() as u32, first: o.triangle_count(), shape };
        o.runs.push(run);
        if self.quads {
            run.quads(|q| self.polygon(q, face));
        }
    }

    /// A quad's polygon, if asked for (its triangles made or implicit).
    fn polygon(&mut self, q: [u32; 4], face: u32) {
        if self.quads {
            self.out.polygon_vertices.extend_from_slice(&q);
            self.out.polygon_offsets.push(self.out.polygon_vertices.len() as u32);
            self.out.polygon_faces.push(FaceId::new(face));
        }
    }

    /// A closed ring of points (counter-clockwise): a triangle, a quad, or (with `centre`, or
    /// more than 4 points) a fan around `centre`. Rings of fewer than 3 points close nothing:
    /// the strips on either side of them already share their edge.
    fn close_ring(&mut self, ring: &[u32], centre: Option<u32>, face: u32) {
        match (ring.len(), centre) {
            (0..=2, _) => {}
            (_, Some(c)) => {
                for k in 0..ring.len() {
                    self.triangle([c, ring[k], ring[(k + 1) % ring.len()]], face);
                }
            }
            (3, None) => self.triangle([ring[0], ring[1], ring[2]], face),
            (4, None) => self.quad([ring[0], ring[1], ring[2], ring[3]], face),
            // Not reached: callers give a centre to rings of 5 or more.
            (_, None) => {
                for k in 1..ring.len() - 1 {
                    self.triangle([ring[0], ring[k], ring[k + 1]], face);
                }
            }
        }
    }

    /// Cell points and interiors of face `f`.
    fn face(&mut self, f: usize, domain: Option<FaceDomain>, n: u32) {
        let Some(domain) = domain else {
            self.buf.faces.push(None);
            return;
        };
        let base = self.out.vertex_count;
        match domain {
            FaceDomain::Quad => {
                let sites = self.out.sites.len() as u32;
                self.out.blocks.push(Block { face: f as u32, rate: n, base, sites });
                self.quad_cell(f, domain, None, n);
                self.buf.faces.push(Some(FaceCells { base, m: n, domain }));
            }
            FaceDomain::SubFaces { size, .. } => {
                let m = n.div_ceil(2);
                for s in 0..size {
                    self.quad_cell(f, domain, Some(s), m);
                }
                self.buf.faces.push(Some(FaceCells { base, m, domain }));
                let cell = |s: usize, i: u32, j: u32| base + (s as u32) * m * m + j * m + i;
                // Spoke s: sub-face s's side 1 (from the middle of side s to the centre) against
                // sub-face s + 1's side 2, reversed: equal rates, so quads.
                for s in 0..size {
                    let t = (s + 1) % size;
                    let (a, b) = (cell(s, m - 1, 0), cell(t, 0, m - 1));
                    self.run(f as u32, RunShape::Ladder { a, da: m, b, db: 1, len: m });
                }
                // The centre: the sub-faces' inner corners, counter-clockwise.
                let mut ring = std::mem::take(&mut self.buf.ring);
                ring.clear();
                ring.extend((0..size).map(|s| cell(s, m - 1, m - 1)));
                let centre_point = domain.from_sub_face(0, Dyadic::new(1, 1, 1));
                let depth = self.buf.ring_centres.get(f).copied().unwrap_or(0);
                if depth > 0 {
                    let mut corners = std::mem::take(&mut self.buf.ring_corners);
                    corners.clear();
                    corners.extend((0..size as u32).map(|sub| RingCorner::Centre { face: f as u32, sub }));
                    self.rings(&corners, &ring, depth, (f, centre_point));
                    self.buf.ring_corners = corners;
                } else {
                    let centre = (size >= 5).then(|| self.push_site(f, centre_point));
                    self.close_ring(&ring, centre, f as u32);
                }
                self.buf.ring = ring;
            }
            FaceDomain::Triangle => {
                let q = i64::from(3 * n);
                for j in 0..n {
                    for i in 0..n - j {
                        let (i3, j3) = (3 * i64::from(i), 3 * i64::from(j));
                        self.push_site(f, Dyadic::new(i3 + 1, j3 + 1, q));
                        if i + j + 1 < n {
                            self.push_site(f, Dyadic::new(i3 + 2, j3 + 2, q));
                        }
                    }
                }
                self.buf.faces.push(Some(FaceCells { base, m: n, domain }));
                let up = |i: u32, j: u32| base + 2 * n * j - j * j + 2 * i;
                for j in 1..n {
                    for i in 1..n - j {
                        let c = self.push_site(f, Dyadic::new(i64::from(i), i64::from(j), i64::from(n)));
                        // The six sub-triangles around (i, j), counter-clockwise.
                        let hex = [
                            up(i, j),
                            up(i - 1, j) + 1,
                            up(i - 1, j),
                            up(i - 1, j - 1) + 1,
                            up(i, j - 1),
                            up(i, j - 1) + 1,
                        ];
                        self.close_ring(&hex, Some(c), f as u32);
                    }
                }
            }
        }
    }

    /// The `m × m` dual points of a quad cell (a whole quad face, or sub-face `sub`) and the
    /// quads between them.
    fn quad_cell(&mut self, f: usize, domain: FaceDomain, sub: Option<usize>, m: u32) {
        let base = self.out.vertex_count;
        let q = 2 * i64::from(m);
        if let Some(s) = sub {
            for j in 0..m {
                for i in 0..m {
                    let a = Dyadic::new(2 * i64::from(i) + 1, 2 * i64::from(j) + 1, q);
                    self.push_site(f, domain.from_sub_face(s, a));
                }
            }
        } else {
            // A whole face: a block, whose sites are implicit.
            self.out.vertex_count += m * m;
        }
        self.run(f as u32, RunShape::Grid { base, n: m });
    }

    /// The first point and the step of face `f`'s row nearest its side `c` (as
    /// [`side_row`](Self::side_row) lists it), if `f` is a whole quad (a block).
    fn block_side(&self, f: usize, c: usize) -> Option<(u32, u32, u32)> {
        let cells = self.buf.faces[f]?;
        let FaceDomain::Quad = cells.domain else { return None };
        let (start, step) = quad_side(cells.base, cells.m, c);
        Some((start, step, cells.m))
    }

    /// The points of face `f`'s cells nearest its side `c` (from corner `c` to `c + 1`), in
    /// that direction, with their parameters along the side, into `row`.
    fn side_row(&self, f: usize, c: usize, row: &mut Vec<RowPoint>) {
        row.clear();
        let Some(cells) = self.buf.faces[f] else { return };
        let (base, m) = (cells.base, cells.m);
        let m64 = u64::from(m);
        match cells.domain {
            FaceDomain::Quad => {
                let (start, step) = quad_side(base, m, c);
                for k in 0..m {
                    row.push(RowPoint {
                        vertex: start.wrapping_add(k.wrapping_mul(step)),
                        num: u64::from(2 * k + 1),
                        den: 2 * m64,
                        near: true,
                    });
                }
            }
            FaceDomain::SubFaces { size, .. } => {
                let cell = |s: usize, i: u32, j: u32| base + (s as u32) * m * m + j * m + i;
                // Sub-face c's side 0 covers the first half, sub-face c + 1's side 3 the second.
                for k in 0..m {
                    row.push(RowPoint { vertex: cell(c, k, 0), num: u64::from(2 * k + 1), den: 4 * m64, near: true });
                }
                let next = (c + 1) % size;
                for k in 0..m {
                    row.push(RowPoint {
                        vertex: cell(next, 0, m - 1 - k),
                        num: 2 * m64 + u64::from(2 * k + 1),
                        den: 4 * m64,
                        near: true,
                    });
                }
            }
            FaceDomain::Triangle => {
                let n = m;
                let up = |i: u32, j: u32| base + 2 * n * j - j * j + 2 * i;
                for k in 0..n {
                    // Upward centroid k along the side, then the downward one after it.
                    let (u, d) = match c {
                        0 => (up(k, 0), (k + 1 < n).then(|| up(k, 0) + 1)),
                        1 => (up(n - 1 - k, k), (k + 1 < n).then(|| up(n - 2 - k, k) + 1)),
                        _ => (up(0, n - 1 - k), (k + 1 < n).then(|| up(0, n - 2 - k) + 1)),
                    };
                    row.push(RowPoint { vertex: u, num: u64::from(2 * k + 1), den: 2 * m64, near: true });
                    if let Some(d) = d {
                        row.push(RowPoint { vertex: d, num: u64::from(2 * k + 2), den: 2 * m64, near: false });
                    }
                }
            }
        }
    }

    /// The parameter of face `f` at `t = num / den` along its side `c`.
    fn on_side(&self, f: usize, c: usize, num: u64, den: u64) -> Dyadic {
        let (t, d) = (num as i64, den as i64);
        let cells = self.buf.faces[f].expect("a face with a surface");
        match cells.domain {
            FaceDomain::Quad => match c {
                0 => Dyadic::new(t, 0, d),
                1 => Dyadic::new(d, t, d),
                2 => Dyadic::new(d - t, d, d),
                _ => Dyadic::new(0, d - t, d),
            },
            FaceDomain::Triangle => match c {
                0 => Dyadic::new(t, 0, d),
                1 => Dyadic::new(d - t, t, d),
                _ => Dyadic::new(0, d - t, d),
            },
            FaceDomain::SubFaces { size, .. } => {
                if 2 * t < d {
                    cells.domain.from_sub_face(c, Dyadic::new(2 * t, 0, d))
                } else {
                    cells.domain.from_sub_face((c + 1) % size, Dyadic::new(0, 2 * (d - t), d))
                }
            }
        }
        .reduced()
    }

    /// The parameter of face `f`'s corner `c`.
    fn corner_point(&self, f: usize, c: usize) -> Dyadic {
        let cells = self.buf.faces[f].expect("a face with a surface");
        match cells.domain {
            FaceDomain::Quad => {
                [Dyadic::new(0, 0, 1), Dyadic::new(1, 0, 1), Dyadic::new(1, 1, 1), Dyadic::new(0, 1, 1)][c]
            }
            FaceDomain::Triangle => [Dyadic::new(0, 0, 1), Dyadic::new(1, 0, 1), Dyadic::new(0, 1, 1)][c],
            FaceDomain::SubFaces { .. } => cells.domain.from_sub_face(c, Dyadic::new(0, 0, 1)).reduced(),
        }
    }

    /// Face `f`'s point nearest its corner `c`.
    fn corner_vertex(&self, f: usize, c: usize) -> u32 {
        let cells = self.buf.faces[f].expect("a face with a surface");
        let (base, m) = (cells.base, cells.m);
        match cells.domain {
            FaceDomain::Quad => quad_side(base, m, c).0,
            FaceDomain::SubFaces { .. } => base + (c as u32) * m * m,
            FaceDomain::Triangle => {
                let up = |i: u32, j: u32| base + 2 * m * j - j * j + 2 * i;
                [up(0, 0), up(m - 1, 0), up(0, m - 1)][c]
            }
        }
    }

    /// Whether half-edge `h` (of a face with a surface) has no surface across it.
    fn is_border(&self, h: HalfEdgeId) -> bool {
        self.mesh.twin(h).is_none_or(|t| self.buf.faces[self.mesh.face(t).index()].is_none())
    }

    /// The strip along the edge of half-edge `h` (its face has a surface): against the other
    /// face's row, or against new border points.
    fn edge(&mut self, h: HalfEdgeId) {
        let f = self.mesh.face(h).index();
        let c = self.buf.corner[h.index()] as usize;
        let border = self.is_border(h);
        let twin = self.mesh.twin(h).filter(|_| !border);
        // Each interior edge once, from its lower half-edge.
        if twin.is_some_and(|t| t.index() < h.index()) {
            return;
        }
        if let Some(t) = twin {
            let g = self.mesh.face(t).index();
            // Between two blocks of one rate, the strip is a ladder of quads (the other row
            // reversed, as below).
            if let (Some((a, da, m)), Some((b, db, n))) =
                (self.block_side(f, c), self.block_side(g, self.buf.corner[t.index()] as usize))
                && m == n
            {
                let (b, db) = (b.wrapping_add((m - 1).wrapping_mul(db)), db.wrapping_neg());
                self.run(f as u32, RunShape::Ladder { a, da, b, db, len: m });
                return;
            }
        }
        let mut row = std::mem::take(&mut self.buf.row);
        let mut other = std::mem::take(&mut self.buf.other);
        self.side_row(f, c, &mut row);
        if let Some(t) = twin {
            let g = self.mesh.face(t).index();
            self.side_row(g, self.buf.corner[t.index()] as usize, &mut other);
            other.reverse();
            for p in &mut other {
                p.num = p.den - p.num;
            }
            self.strip(&row, &other, f as u32);
        } else {
            other.clear();
            let first = self.out.vertex_count;
            for p in row.iter().filter(|p| p.near) {
                let point = self.on_side(f, c, p.num, p.den);
                let vertex = self.push_site(f, point);
                other.push(RowPoint { vertex, num: p.num, den: p.den, near: true });
            }
            self.buf.border[h.index()] = (first, other.len() as u32);
            self.strip(&row, &other, f as u32);
        }
        (self.buf.row, self.buf.other) = (row, other);
    }

    /// Triangulates the ribbon between row `a` (on the left of the direction) and row `b` (on
    /// the right), both ordered along it: advance the row whose next point comes first; where
    /// both next points have the same parameter, a quad.
    fn strip(&mut self, a: &[RowPoint], b: &[RowPoint], face: u32) {
        let (mut i, mut j) = (0, 0);
        if a.is_empty() || b.is_empty() {
            return;
        }
        while i + 1 < a.len() || j + 1 < b.len() {
            let order = if i + 1 == a.len() {
                std::cmp::Ordering::Greater
            } else if j + 1 == b.len() {
                std::cmp::Ordering::Less
            } else {
                let (x, y) = (a[i + 1], b[j + 1]);
                (x.num * y.den).cmp(&(y.num * x.den))
            };
            match order {
                std::cmp::Ordering::Less => {
                    self.triangle([b[j].vertex, a[i + 1].vertex, a[i].vertex], face);
                    i += 1;
                }
                std::cmp::Ordering::Greater => {
                    self.triangle([b[j].vertex, b[j + 1].vertex, a[i].vertex], face);
                    j += 1;
                }
                std::cmp::Ordering::Equal => {
                    self.quad([b[j].vertex, b[j + 1].vertex, a[i + 1].vertex, a[i].vertex], face);
                    i += 1;
                    j += 1;
                }
            }
        }
    }

    /// The polygons around vertex `v`: one closed ring, or one fan per run of faces between
    /// borders (each run from a border to a border, around the vertex's limit point).
    fn vertex(&mut self, v: VertexId) {
        let mesh = self.mesh;
        let has_surface = |h: HalfEdgeId| self.buf.faces[mesh.face(h).index()].is_some();
        let mut starts = std::mem::take(&mut self.buf.starts);
        starts.clear();
        starts.extend(mesh.outgoing(v).filter(|&h| has_surface(h) && self.is_border(h)));
        let closed = starts.is_empty();
        if closed {
            match mesh.outgoing(v).find(|&h| has_surface(h)) {
                Some(h) => starts.push(h),
                None => {
                    self.buf.starts = starts;
                    return;
                }
            }
        }
        let mut centre = None;
        let mut ring = std::mem::take(&mut self.buf.ring);
        let mut corners = std::mem::take(&mut self.buf.ring_corners);
        for &start in &starts {
            ring.clear();
            corners.clear();
            let f0 = mesh.face(start).index();
            if !closed {
                let (first, _) = self.buf.border[start.index()];
                ring.push(first);
            }
            let mut h = start;
            loop {
                let f = mesh.face(h).index();
                ring.push(self.corner_vertex(f, self.buf.corner[h.index()] as usize));
                corners.push(RingCorner::Vertex { face: f as u32, corner: self.buf.corner[h.index()] });
                let p = mesh.prev(h);
                if self.is_border(p) {
                    if !closed {
                        let (first, count) = self.buf.border[p.index()];
                        ring.push(first + count - 1);
                    }
                    break;
                }
                h = mesh.twin(p).expect("not a border");
                if closed && h == start {
                    break;
                }
            }
            // An extraordinary interior vertex (quad split) with a ring depth: rings down to it,
            // fanned around its limit point, in place of the polygon.
            let depth = self.buf.ring_vertices.get(v.index()).copied().unwrap_or(0);
            let regular = if self.triangle { 6 } else { 4 };
            if closed && depth > 0 && ring.len() >= 3 && ring.len() != regular {
                let point = self.corner_point(f0, self.buf.corner[start.index()] as usize);
                self.rings(&corners, &ring, depth, (f0, point));
                continue;
            }
            // Closed rings of 3 (and 4 under a quad split) are polygons of their own; rings of
            // fewer than 3 close nothing.
            let fan = !closed || (ring.len() >= 3 && (self.triangle || ring.len() >= 5));
            if fan && centre.is_none() {
                let point = self.corner_point(f0, self.buf.corner[start.index()] as usize);
                centre = Some(self.push_site(f0, point));
            }
            if closed {
                self.close_ring(&ring, if fan { centre } else { None }, f0 as u32);
            } else if let Some(c) = centre {
                // An open fan: from the border point on the first edge to the one on the last.
                for k in 0..ring.len() - 1 {
                    self.triangle([c, ring[k], ring[k + 1]], f0 as u32);
                }
            }
        }
        self.buf.ring = ring;
        self.buf.ring_corners = corners;
        self.buf.starts = starts;
    }

    /// The point `(a, b) · 2^−e` (face units, `a, b ≤ 2`, `e ≥ 2`) of `corner`'s frame, as its
    /// face's parameter: a quad's own coordinates turned to the corner; an N-gon's sub-face
    /// coordinates, which are twice the face units (a sub-face is a quarter of the face); a
    /// triangle's turned to the corner (`s` along side `c`, `t` along side `c − 1` reversed).
    fn ring_point(&self, corner: RingCorner, a: i64, b: i64, e: u32) -> Dyadic {
        let domain = self.buf.faces[corner.face()].expect("a face with a surface").domain;
        match corner {
            RingCorner::Vertex { corner: c, .. } => match domain {
                FaceDomain::SubFaces { .. } => domain.from_sub_face(c as usize, Dyadic::new(a, b, 1 << (e - 1))),
                FaceDomain::Triangle => {
                    let d = 1i64 << e;
                    let (u, v) = match c {
                        0 => (a, b),
                        1 => (d - a - b, a),
                        _ => (b, d - a - b),
                    };
                    Dyadic::new(u, v, d)
                }
                FaceDomain::Quad => {
                    let d = 1i64 << e;
                    let (u, v) = match c {
                        0 => (a, b),
                        1 => (d - b, a),
                        2 => (d - a, d - b),
                        _ => (b, d - a),
                    };
                    Dyadic::new(u, v, d)
                }
            },
            // The inner corner (1, 1) of the sub-face, its frame turned half a turn.
            RingCorner::Centre { sub, .. } => {
                let d = 1i64 << (e - 1);
                domain.from_sub_face(sub as usize, Dyadic::new(d - a, d - b, d))
            }
        }
        .reduced()
    }

    /// Rings around an extraordinary point, in place of its polygon `outer` (the faces' nearest
    /// dual points, counter-clockwise, one per corner of `corners`), down to `depth`, fanned at
    /// the end around the point's limit point `centre` (face, parameter).
    ///
    /// Ring `j` (radius `r_j = 2^−(d1 + j − 1)`, `d1` the first depth inside the nearest dual
    /// points, [`first_ring_depth`]) has a point on every edge (or spoke) at `r_j` from the
    /// point, made once in the face whose `s` axis the edge is, and one per face at
    /// `(r_j, r_j)`; its points run `edge_0, diagonal_0, edge_1, diagonal_1, …`, counter-
    /// clockwise. Every triangle lies in one face's region or across one edge, as the bound of
    /// [`ErrorRates::rates`](crate::rates::ErrorRates::rates) assumes: from the polygon's corners
    /// to ring 1 two triangles per face and one across each edge; between rings `j` and `j + 1`
    /// two quads per face in its L-shaped region `[0, r_j]² \ [0, r_{j+1})²`; a fan inside the
    /// last. Under a triangle split (no tolerance policy yet) the same with a triangle's frames:
    /// `d1` from [`first_depth`], the inner point at `(r_j/2, r_j/2)`, and the quads in the
    /// trapezoid `r_{j+1} ≤ s + t ≤ r_j`.
    fn rings(&mut self, corners: &[RingCorner], outer: &[u32], depth: u32, centre: (usize, Dyadic)) {
        let n = corners.len() as u32;
        let finest = corners
            .iter()
            .map(|c| face_reach(self.mesh, self.triangle, FaceId::new(c.face() as u32), self.buf.rates[c.face()]))
            .max()
            .unwrap_or(1);
        let first = first_depth(self.triangle, finest);
        let count = ring_count(first, depth);
        let base = self.out.vertex_count;
        // Per face: the point on its first edge at r, and the inner one: the diagonal point
        // (r, r) of a quad corner; (r/2, r/2) of a triangle corner, on the segment between the
        // corner's two edge points (the triangle's region between rings is a trapezoid).
        let ((edge, inner), shift) = if self.triangle { (((2, 0), (1, 1)), 1) } else { (((1, 0), (1, 1)), 0) };
        for j in 0..count {
            for &c in corners {
                let on_edge = self.ring_point(c, edge.0, edge.1, first + j + shift);
                self.push_site(c.face(), on_edge);
                let diagonal = self.ring_point(c, inner.0, inner.1, first + j + shift);
                self.push_site(c.face(), diagonal);
            }
        }
        let p = self.push_site(centre.0, centre.1);
        // Point k (cyclic) of ring j (from 0): edge points at even k, diagonal points at odd.
        let at = |j: u32, k: u32| base + j * 2 * n + k % (2 * n);
        let face = |k: u32| corners[k as usize].face() as u32;
        for k in 0..n {
            let (d, next) = (outer[k as usize], outer[((k + 1) % n) as usize]);
            let (e, q, e_next) = (at(0, 2 * k), at(0, 2 * k + 1), at(0, 2 * k + 2));
            self.triangle([d, q, e], face(k));
            self.triangle([d, e_next, q], face(k));
            self.triangle([d, next, e_next], face(k));
        }
        for j in 0..count - 1 {
            for k in 0..n {
                let (e, q, e_next) = (2 * k, 2 * k + 1, 2 * k + 2);
                self.quad([at(j + 1, e), at(j, e), at(j, q), at(j + 1, q)], face(k));
                self.quad([at(j + 1, q), at(j, q), at(j, e_next), at(j + 1, e_next)], face(k));
            }
        }
        for k in 0..2 * n {
            self.triangle([p, at(count - 1, k), at(count - 1, k + 1)], face(k / 2));
        }
    }
}

/// The number of output vertices at `rates`, from the construction's counts (for tests and for
/// sizing): cells, triangle interiors, N-gon centres, border points, vertex points.
pub(crate) fn predicted_vertices(mesh: &Mesh, triangle: bool, rates: &[u32], rings: Option<&RingDepths>) -> usize {
    let hole = |f: FaceId| mesh.is_hole(f);
    let rate_of = |f: FaceId| rates[f.index()] as usize;
    let mut count = 0;
    for f in mesh.face_ids().filter(|&f| !hole(f)) {
        let (n, size) = (rate_of(f), mesh.face_size(f));
        count += if triangle {
            n * n + (n.saturating_sub(1) * n.saturating_sub(2)) / 2
        } else if size == 4 {
            n * n
        } else {
            let depth = rings.map_or(0, |r| r.centres[f.index()]);
            let centre = if depth > 0 {
                // Two points per sub-face per ring, and the centre (N = 3 has none without).
                let finest = reach(mesh, f, rates[f.index()]);
                2 * size * ring_count(first_depth(false, finest), depth) as usize + 1
            } else {
                usize::from(size >= 5)
            };
            size * n.div_ceil(2).pow(2) + centre
        };
        for h in mesh.face_half_edges(f) {
            if mesh.twin(h).is_none_or(|t| hole(mesh.face(t))) {
                count += if triangle || size == 4 { n } else { 2 * n.div_ceil(2) };
            }
        }
    }
    for v in mesh.vertices() {
        let faces: Vec<FaceId> = mesh.vertex_faces(v).filter(|&f| !hole(f)).collect();
        if faces.is_empty() {
            continue;
        }
        let border = mesh.outgoing(v).any(|h| mesh.twin(h).is_none_or(|t| hole(mesh.face(t))) || hole(mesh.face(h)))
            || mesh.is_boundary_vertex(v);
        let depth = rings.map_or(0, |r| r.vertices[v.index()]);
        let regular = if triangle { 6 } else { 4 };
        if !border && depth > 0 && faces.len() >= 3 && faces.len() != regular {
            // Two points per face per ring (its edge's and its inner one), and the limit point.
            let finest = faces.iter().map(|&f| face_reach(mesh, triangle, f, rates[f.index()])).max().unwrap_or(1);
            count += 2 * faces.len() * ring_count(first_depth(triangle, finest), depth) as usize + 1;
        } else if border || (faces.len() >= 3 && (triangle || faces.len() >= 5)) {
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;
    use subdiv_mesh::shapes;
    use subdiv_stencil::Grid;

    fn row(vertices: std::ops::Range<u32>, den: u64) -> Vec<RowPoint> {
        vertices.enumerate().map(|(k, vertex)| RowPoint { vertex, num: 2 * k as u64 + 1, den, near: true }).collect()
    }

    /// Rows of equal rates merge into quads; rows of rates 2 and 3 into 3 triangles, each
    /// counter-clockwise with the first row on the left.
    #[test]
    fn strips_merge_rows_in_parameter_order() {
        let mesh = Mesh::build(shapes::quad_torus(3, 3)).unwrap();
        let mut b = Builder::new(&mesh, false, true);
        b.out.polygon_offsets.push(0);
        b.strip(&row(0..3, 6), &row(10..13, 6), 0);
        assert_eq!(b.out.polygon_faces.len(), 2);
        assert_eq!(b.out.polygon_vertices[..4], [10, 11, 1, 0]);
        assert_eq!(b.out.triangles.len(), 4);
        let mut b = Builder::new(&mesh, false, false);
        // a: 1/4, 3/4; b: 1/6, 3/6, 5/6.
        b.strip(&row(0..2, 4), &row(10..13, 6), 0);
        assert_eq!(b.out.triangles, [[10, 11, 0], [10 + 1, 1, 0], [11, 12, 1]]);
    }

    /// The implicit sites of blocks and the explicit ones of the other vertices read the same
    /// by vertex ([`Topology::site`]), in order ([`Topology::for_each_site`]) and, for the
    /// explicit ones, with their numbers ([`Topology::explicit_sites`]): a block's
    /// point `(i, j)` at `((2i+1)/2n, (2j+1)/2n)` of its face, every other site where it was
    /// made, on meshes with N-gons and borders at mixed rates.
    #[test]
    fn block_sites_are_implicit() {
        for soup in [shapes::ngon_prism(5), shapes::quad_grid(3, 2), shapes::default_model()] {
            let mesh = Mesh::build(soup).unwrap();
            let domains: Vec<_> = mesh
                .face_ids()
                .map(|f| Some(FaceDomain::of(subdiv_schemes::Split::Quad, mesh.face_size(f)).unwrap()))
                .collect();
            let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 1 + f % 4).collect();
            let mut out = Topology::default();
            Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut out);
            assert_eq!(out.vertex_count as usize, predicted_vertices(&mesh, false, &rates, None));
            let mut walked = Vec::new();
            out.for_each_site(|s| walked.push(s));
            assert_eq!(walked.len(), out.vertex_count as usize);
            for (v, s) in walked.iter().enumerate() {
                assert_eq!(*s, out.site(v as u32), "vertex {v}");
            }
            let explicit: Vec<(u32, Site)> = out.explicit_sites().collect();
            assert_eq!(explicit.len(), out.sites.len());
            for &(v, s) in &explicit {
                assert!(!out.blocks.iter().any(|b| (b.base..b.base + b.len()).contains(&v)), "vertex {v} in a block");
                assert_eq!(s, out.site(v), "vertex {v}");
            }
            let in_blocks: u32 = out.blocks.iter().map(Block::len).sum();
            assert_eq!(out.sites.len() as u32 + in_blocks, out.vertex_count);
            for b in &out.blocks {
                let n = i64::from(b.rate);
                for j in 0..n {
                    for i in 0..n {
                        let s = out.site(b.base + (j * n + i) as u32);
                        assert_eq!((s.face, s.point), (b.face, Dyadic::new(2 * i + 1, 2 * j + 1, 2 * n)));
                    }
                }
            }
        }
    }

    /// The runs' triangles land where the builder counted them, between the explicit ones,
    /// whether written on one thread or halved between several (at rates where the halving
    /// starts: more than `GRAIN` triangles): every output edge of a closed mesh then has two
    /// triangles, and each run's range holds its face's triangles (a grid's, of its points).
    #[test]
    fn runs_are_written_in_place() {
        for soup in [shapes::default_model(), shapes::ngon_prism(5), shapes::quad_torus(6, 5)] {
            let mesh = Mesh::build(soup).unwrap();
            let domains: Vec<_> = mesh
                .face_ids()
                .map(|f| Some(FaceDomain::of(subdiv_schemes::Split::Quad, mesh.face_size(f)).unwrap()))
                .collect();
            let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 60 + 9 * (f % 5)).collect();
            let mut out = Topology::default();
            Builder::new(&mesh, false, false).build(&domains, &rates, None, &mut out);
            let n = out.triangle_count() as usize;
            assert!(n > 2 << 14, "{n} triangles: too few to halve");
            let (mut serial, mut parallel) = (vec![0; 3 * n], vec![u32::MAX; 3 * n]);
            out.write_triangles(&mut serial, false);
            out.write_triangles(&mut parallel, true);
            assert_eq!(serial, parallel);
            let (mut faces, mut faces_parallel) = (vec![FaceId::new(0); n], vec![FaceId::new(7); n]);
            out.write_triangle_faces(&mut faces, false);
            out.write_triangle_faces(&mut faces_parallel, true);
            assert_eq!(faces, faces_parallel);
            let in_runs: u32 = out.runs.iter().map(Run::triangles).sum();
            assert_eq!(in_runs as usize + out.triangles.len(), n);
            for r in &out.runs {
                let range = r.first as usize..(r.first + r.triangles()) as usize;
                assert!(faces[range.clone()].iter().all(|f| f.index() == r.face as usize));
                if let RunShape::Grid { base, n } = r.shape {
                    let grid = base..base + n * n;
                    assert!(serial[3 * range.start..3 * range.end].iter().all(|v| grid.contains(v)));
                }
            }
            let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
            for t in serial.chunks_exact(3) {
                for k in 0..3 {
                    *edges.entry((t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))).or_default() += 1;
                }
            }
            assert!(edges.values().all(|&c| c == 2), "an edge without two triangles");
        }
    }

    /// A triangle's cell points come in `Grid::Dual`'s order (the tables' order, which the
    /// closed-form indices of the evaluator and the hexagons rely on).
    #[test]
    fn triangle_cells_follow_the_dual_grid_order() {
        let mesh = Mesh::build(shapes::icosahedron()).unwrap();
        let domains = vec![Some(FaceDomain::Triangle); mesh.face_count()];
        for n in [1, 2, 3, 7] {
            let mut out = Topology::default();
            Builder::new(&mesh, true, false).build(&domains, &vec![n; mesh.face_count()], None, &mut out);
            let dual = Grid::Dual.points(3, n);
            let face0: Vec<Dyadic> = out.sites.iter().take(dual.len()).map(|s| s.point).collect();
            assert_eq!(face0, dual, "rate {n}");
            assert_eq!(out.vertex_count as usize, predicted_vertices(&mesh, true, &vec![n; mesh.face_count()], None));
        }
    }
}
