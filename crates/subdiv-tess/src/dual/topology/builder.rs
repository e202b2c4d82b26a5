//! The topology's builder: each face's dual grid, the strips along edges and spokes, the
//! polygons and rings around vertices, and the border points.

use hashbrown::HashMap;

use super::*;

mod rings;
mod sequence;

pub(super) use self::rings::{RunEnd, ring_count};

impl RingCorner {
    pub(super) fn face(self) -> usize {
        match self {
            Self::Vertex { face, .. } | Self::Centre { face, .. } => face as usize,
        }
    }
}

/// The number of faces around a regular interior vertex.
pub(super) fn regular(triangle: bool) -> usize {
    if triangle { 6 } else { 4 }
}

/// Whether `v` is tagged an infinitely sharp corner: its surface is no polynomial at any
/// valence, so it takes rings like an extraordinary vertex.
pub(super) fn sharp_corner(mesh: &Mesh, v: VertexId) -> bool {
    mesh.vertex_sharpness(v) >= subdiv_mesh::Tags::INFINITELY_SHARP
}

/// The row of a quad cell's `m × m` points (from `base`, row by row) nearest its side `c`, in
/// the side's direction: its first point (the one nearest corner `c`) and the step between
/// points (in two's complement).
pub(super) fn quad_side(base: u32, m: u32, c: usize) -> (u32, u32) {
    match c {
        0 => (base, 1),
        1 => (base + m - 1, m),
        2 => (base + m * m - 1, 1u32.wrapping_neg()),
        _ => (base + (m - 1) * m, m.wrapping_neg()),
    }
}

/// The denominator of a graded grid's cell centres.
const GRID_Q: i64 = 2 * GRID_DENOMINATOR as i64;

/// The parameter along side `c` of a quad cell (from its corner `c`) of the side's row point
/// `k` ([`quad_side`]'s order), as `num / den`: `(2k + 1) / 2m` on a uniform grid of `m` cells
/// per side, a cell centre of `grid`'s (mirrored on sides 2 and 3, which run backwards).
fn cell_side_parameter(grid: Option<&GradedGrid>, m: u32, c: usize, k: u32) -> (u64, u64) {
    let Some(grid) = grid else { return (u64::from(2 * k + 1), 2 * u64::from(m)) };
    let den = GRID_Q as u64;
    match c {
        0 => (grid.centre(0, k), den),
        1 => (grid.centre(1, k), den),
        2 => (den - grid.centre(0, m - 1 - k), den),
        _ => (den - grid.centre(1, m - 1 - k), den),
    }
}

/// One input face's cells.
#[derive(Clone, Copy, Debug)]
pub(super) struct FaceCells {
    /// The first cell's first vertex (cells of one face are consecutive, `m²` or `n²` each).
    base: u32,
    /// Points per side of a cell: `n` for quads and triangles, `⌈n/2⌉` for sub-faces.
    m: u32,
    /// The face's domain ([`domain`](Self::domain)).
    domain: PackedDomain,
    /// Whether its grid is graded (a quad's, [`BuilderBuffers::graded`]): explicit sites, no block.
    graded: bool,
}

impl FaceCells {
    /// The face's domain.
    #[inline]
    fn domain(&self) -> FaceDomain {
        self.domain.get().unwrap_or(FaceDomain::Quad)
    }
}

/// Builds the topology of `mesh` (level 0 of the patch levels, holes tagged) at `rates`.
pub(crate) struct Builder<'a> {
    mesh: &'a Mesh,
    /// Per edge, whether it is a seam of a carried face-varying channel (empty: none).
    seams: &'a [bool],
    triangle: bool,
    quads: bool,
    pub(super) out: Topology,
    buf: BuilderBuffers,
    /// The whole output's numbers of `out`'s first vertex and first triangle (`out` is one
    /// chunk of it: [`build_chunks`](Self::build_chunks)).
    first: (u32, u32),
}

/// A border half-edge's border points nearest its origin and nearest its destination (an
/// infinitely sharp edge's two half-edges share their points) and, on the second side of such
/// an edge, the extra normals of those two points (that side's normals).
#[derive(Clone, Copy, Debug)]
struct Border {
    points: (u32, u32),
    extra: Option<(u32, u32)>,
}

/// A [`Builder`]'s buffers between calls (kept by the tessellator, so that a call allocates
/// nothing).
#[derive(Debug, Default)]
pub(crate) struct BuilderBuffers {
    faces: Vec<Option<FaceCells>>,
    /// Per half-edge on a border (by number), its [`Border`]: a map, not an array per
    /// half-edge, since most half-edges are on no border (the arrays were 80 MB of a
    /// million-face grid's peak).
    border: HashMap<u32, Border>,
    /// The extra normals' sites, in order (appended to the topology's sites at the end), their
    /// vertices, and those vertices' own sites.
    extra_sites: Vec<Site>,
    extra_vertices: Vec<u32>,
    extra_vertex_sites: Vec<Site>,
    row: Vec<RowPoint>,
    other: Vec<RowPoint>,
    ring: Vec<u32>,
    starts: Vec<HalfEdgeId>,
    /// The ring's corners, beside `ring` (for the rings around extraordinary points).
    ring_corners: Vec<RingCorner>,
    /// Around the vertex being built, per edge cut between two faces (an infinitely sharp edge,
    /// a seam), the open rings' points on it, by ring: made by the first run that reaches it,
    /// taken (with that run's extra entries) by the run on its other side.
    cut_ring_points: HashMap<u32, Vec<u32>>,
    /// One ring's points, as [`Corner`]s (open rings).
    ring_points: Vec<Corner>,
    /// The rates being built, and the ring depths and graded grids (empty: none).
    rates: Vec<u32>,
    rings: RingDepths,
}

impl<'a> Builder<'a> {
    /// `domains[f]` is `None` for a hole.
    #[cfg(test)]
    pub(crate) fn new(mesh: &'a Mesh, triangle: bool, quads: bool) -> Self {
        Self::with_buffers(mesh, &[], triangle, quads, BuilderBuffers::default())
    }

    /// A builder on the buffers of an earlier one ([`into_buffers`](Self::into_buffers)), which
    /// cuts the edges marked in `seams` (per edge; empty: none) as borders.
    pub(crate) fn with_buffers(
        mesh: &'a Mesh,
        seams: &'a [bool],
        triangle: bool,
        quads: bool,
        buf: BuilderBuffers,
    ) -> Self {
        Self { mesh, seams, triangle, quads, out: Topology::default(), buf, first: (0, 0) }
    }

    /// The buffers, for the next builder of the same mesh.
    pub(crate) fn into_buffers(self) -> BuilderBuffers {
        self.buf
    }

    pub(super) fn push_site(&mut self, face: usize, point: Dyadic) -> u32 {
        let id = self.next_vertex();
        self.out.sites.push(Site { face: face as u32, point });
        self.out.vertex_count += 1;
        id
    }

    /// A further normal of `vertex` (a crease point seen from another smooth sector around
    /// it), evaluated at `point` of `face` (a face of that sector); returns its number. The
    /// vertex is one of the chunk being built, or (`earlier`) one made before it at that site.
    pub(super) fn push_extra(&mut self, vertex: u32, face: usize, point: Dyadic, earlier: Option<Site>) -> u32 {
        let id = self.buf.extra_vertices.len() as u32;
        let site = match vertex.checked_sub(self.first.0) {
            Some(local) => self.out.site(local),
            None => earlier.expect("an earlier chunk's vertex comes with its site"),
        };
        self.buf.extra_vertex_sites.push(site);
        self.buf.extra_sites.push(Site { face: face as u32, point });
        self.buf.extra_vertices.push(vertex);
        id
    }

    pub(super) fn triangle(&mut self, t: [u32; 3], face: u32) {
        self.out.triangles.push(t);
        self.out.triangle_faces.push(FaceId::new(face));
    }

    /// A triangle whose corners may take extra normals.
    pub(super) fn triangle_at(&mut self, t: [Corner; 3], face: u32) {
        let triangle = self.out.triangles.len() as u32;
        for (corner, c) in t.iter().enumerate() {
            if let Some(extra) = c.extra {
                self.out.normal_corners.push(NormalCorner { triangle, corner: corner as u32, extra });
            }
        }
        self.triangle(t.map(|c| c.vertex), face);
    }

    /// A quad `a b c d` (counter-clockwise): two triangles, and a polygon if asked for.
    pub(super) fn quad(&mut self, q: [u32; 4], face: u32) {
        self.quad_at(q.map(Corner::from), face);
    }

    /// [`quad`](Self::quad) with corners that may take extra normals.
    fn quad_at(&mut self, q: [Corner; 4], face: u32) {
        self.triangle_at([q[0], q[1], q[2]], face);
        self.triangle_at([q[0], q[2], q[3]], face);
        self.polygon(q.map(|c| c.vertex), face);
    }

    /// Triangles by pattern (and their quads' polygons, if asked for).
    pub(super) fn run(&mut self, face: u32, shape: RunShape) {
        let o = &mut self.out;
        let run = Run { face, explicit: o.triangles.len() as u32, first: o.triangle_count(), shape };
        o.runs.push(run);
        if self.quads {
            run.quads(|q| self.polygon(q, face));
        }
    }

    /// A quad's polygon, if asked for (its triangles made or implicit).
    pub(super) fn polygon(&mut self, q: [u32; 4], face: u32) {
        if self.quads {
            self.out.polygon_vertices.extend_from_slice(&q);
            self.out.polygon_offsets.push(self.out.polygon_vertices.len() as u32);
            self.out.polygon_faces.push(FaceId::new(face));
        }
    }

    /// A closed ring of points (counter-clockwise): a triangle, a quad, or (with `centre`, or
    /// more than 4 points) a fan around `centre`. Rings of fewer than 3 points close nothing:
    /// the strips on either side of them already share their edge.
    pub(super) fn close_ring(&mut self, ring: &[u32], centre: Option<u32>, face: u32) {
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
    pub(super) fn face(&mut self, f: usize, domain: Option<FaceDomain>, n: u32) {
        let Some(domain) = domain else {
            self.buf.faces.push(None);
            return;
        };
        let base = self.next_vertex();
        match domain {
            FaceDomain::Quad => {
                // A graded grid's sites are explicit; a uniform one is a block (numbered in
                // its chunk).
                let graded = self.graded_grid(f).is_some();
                if !graded {
                    let sites = self.out.sites.len() as u32;
                    let local = self.out.vertex_count;
                    self.out.blocks.push(Block { face: f as u32, rate: n, base: local, sites });
                }
                self.quad_cell(f, domain, None, n);
                self.buf.faces.push(Some(FaceCells { base, m: n, domain: PackedDomain::pack(Some(domain)), graded }));
            }
            FaceDomain::SubFaces { size, .. } => {
                // Graded: the grid's cells per side, `⌈n/2⌉` (checked by the tessellator).
                let m = self.graded_grid(f).map_or(n.div_ceil(2), GradedGrid::rate);
                for s in 0..size {
                    self.quad_cell(f, domain, Some(s), m);
                }
                self.buf.faces.push(Some(FaceCells {
                    base,
                    m,
                    domain: PackedDomain::pack(Some(domain)),
                    graded: false,
                }));
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
                let depth = self.buf.rings.centres.get(f).copied().unwrap_or(0);
                if depth > 0 {
                    let mut corners = std::mem::take(&mut self.buf.ring_corners);
                    corners.clear();
                    corners.extend((0..size as u32).map(|sub| RingCorner::Centre { face: f as u32, sub }));
                    let finest = self.reach(f);
                    self.rings(&corners, &ring, depth, finest, (f, centre_point));
                    self.buf.ring_corners = corners;
                } else {
                    let centre = (size >= 5).then(|| self.push_site(f, centre_point));
                    self.close_ring(&ring, centre, f as u32);
                }
                self.buf.ring = ring;
            }
            FaceDomain::Triangle | FaceDomain::Ternary => {
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
                self.buf.faces.push(Some(FaceCells {
                    base,
                    m: n,
                    domain: PackedDomain::pack(Some(domain)),
                    graded: false,
                }));
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
    pub(super) fn quad_cell(&mut self, f: usize, domain: FaceDomain, sub: Option<usize>, m: u32) {
        let base = self.next_vertex();
        let q = 2 * i64::from(m);
        // A graded grid (a whole quad's, or every sub-face's of an N-gon), out of the buffers
        // while the sites are pushed.
        let grid = self.buf.rings.graded.get_mut(f).and_then(Option::take);
        if sub.is_none() && grid.is_none() {
            // A uniform whole face: a block, whose sites are implicit.
            self.out.vertex_count += m * m;
        } else {
            for j in 0..m {
                for i in 0..m {
                    let a = match &grid {
                        None => Dyadic::new(2 * i64::from(i) + 1, 2 * i64::from(j) + 1, q),
                        Some(g) => Dyadic::new(g.centre(0, i) as i64, g.centre(1, j) as i64, GRID_Q),
                    };
                    self.push_site(f, sub.map_or(a, |s| domain.from_sub_face(s, a)));
                }
            }
        }
        if grid.is_some() {
            self.buf.rings.graded[f] = grid;
        }
        self.run(f as u32, RunShape::Grid { base, n: m });
    }

    /// The first point and the step of face `f`'s row nearest its side `c` (as
    /// [`side_row`](Self::side_row) lists it), if `f` is a whole quad (a block).
    pub(super) fn block_side(&self, f: usize, c: usize) -> Option<(u32, u32, u32)> {
        let cells = self.buf.faces[f].filter(|cells| !cells.graded)?;
        let FaceDomain::Quad = cells.domain() else { return None };
        let (start, step) = quad_side(cells.base, cells.m, c);
        Some((start, step, cells.m))
    }

    /// The points of face `f`'s cells nearest its side `c` (from corner `c` to `c + 1`), in
    /// that direction, with their parameters along the side, into `row`.
    pub(super) fn side_row(&self, f: usize, c: usize, row: &mut Vec<RowPoint>) {
        row.clear();
        let Some(cells) = self.buf.faces[f] else { return };
        let (base, m) = (cells.base, cells.m);
        let m64 = u64::from(m);
        match cells.domain() {
            FaceDomain::Quad => {
                let (start, step) = quad_side(base, m, c);
                let grid = self.graded_grid(f).filter(|_| cells.graded);
                for k in 0..m {
                    let (num, den) = cell_side_parameter(grid, m, c, k);
                    row.push(RowPoint {
                        vertex: start.wrapping_add(k.wrapping_mul(step)),
                        num,
                        den,
                        near: true,
                        extra: None,
                    });
                }
            }
            FaceDomain::SubFaces { size, .. } => {
                let cell = |s: usize, i: u32, j: u32| base + (s as u32) * m * m + j * m + i;
                // Sub-face c's side 0 covers the first half of the face's side, sub-face
                // c + 1's side 3 (from the side's middle) the second: at `s/2` and `(1 + s)/2`
                // for `s` along the sub-face's side.
                let grid = self.graded_grid(f);
                for k in 0..m {
                    let (num, den) = cell_side_parameter(grid, m, 0, k);
                    row.push(RowPoint { vertex: cell(c, k, 0), num, den: 2 * den, near: true, extra: None });
                }
                let next = (c + 1) % size;
                for k in 0..m {
                    let (num, den) = cell_side_parameter(grid, m, 3, k);
                    let vertex = cell(next, 0, m - 1 - k);
                    row.push(RowPoint { vertex, num: den + num, den: 2 * den, near: true, extra: None });
                }
            }
            FaceDomain::Triangle | FaceDomain::Ternary => {
                let n = m;
                let up = |i: u32, j: u32| base + 2 * n * j - j * j + 2 * i;
                for k in 0..n {
                    // Upward centroid k along the side, then the downward one after it.
                    let (u, d) = match c {
                        0 => (up(k, 0), (k + 1 < n).then(|| up(k, 0) + 1)),
                        1 => (up(n - 1 - k, k), (k + 1 < n).then(|| up(n - 2 - k, k) + 1)),
                        _ => (up(0, n - 1 - k), (k + 1 < n).then(|| up(0, n - 2 - k) + 1)),
                    };
                    row.push(RowPoint { vertex: u, num: u64::from(2 * k + 1), den: 2 * m64, near: true, extra: None });
                    if let Some(d) = d {
                        row.push(RowPoint {
                            vertex: d,
                            num: u64::from(2 * k + 2),
                            den: 2 * m64,
                            near: false,
                            extra: None,
                        });
                    }
                }
            }
        }
    }

    /// Face `f`'s graded grid, if it has one.
    pub(super) fn graded_grid(&self, f: usize) -> Option<&GradedGrid> {
        self.buf.rings.grid(FaceId::new(f as u32))
    }

    /// How finely face `f` samples next to its corners ([`RingDepths::reach`]).
    pub(super) fn reach(&self, f: usize) -> u32 {
        self.buf.rings.reach(self.mesh, self.triangle, FaceId::new(f as u32), self.buf.rates[f])
    }

    /// The parameter of face `f` at `t = num / den` along its side `c`.
    pub(super) fn on_side(&self, f: usize, c: usize, num: u64, den: u64) -> Dyadic {
        let (t, d) = (num as i64, den as i64);
        let cells = self.buf.faces[f].expect("a face with a surface");
        match cells.domain() {
            FaceDomain::Quad => match c {
                0 => Dyadic::new(t, 0, d),
                1 => Dyadic::new(d, t, d),
                2 => Dyadic::new(d - t, d, d),
                _ => Dyadic::new(0, d - t, d),
            },
            FaceDomain::Triangle | FaceDomain::Ternary => match c {
                0 => Dyadic::new(t, 0, d),
                1 => Dyadic::new(d - t, t, d),
                _ => Dyadic::new(0, d - t, d),
            },
            FaceDomain::SubFaces { size, .. } => {
                if 2 * t < d {
                    cells.domain().from_sub_face(c, Dyadic::new(2 * t, 0, d))
                } else {
                    cells.domain().from_sub_face((c + 1) % size, Dyadic::new(0, 2 * (d - t), d))
                }
            }
        }
        .reduced()
    }

    /// The parameter of face `f`'s corner `c`.
    pub(super) fn corner_point(&self, f: usize, c: usize) -> Dyadic {
        let cells = self.buf.faces[f].expect("a face with a surface");
        match cells.domain() {
            FaceDomain::Quad => {
                [Dyadic::new(0, 0, 1), Dyadic::new(1, 0, 1), Dyadic::new(1, 1, 1), Dyadic::new(0, 1, 1)][c]
            }
            FaceDomain::Triangle | FaceDomain::Ternary => {
                [Dyadic::new(0, 0, 1), Dyadic::new(1, 0, 1), Dyadic::new(0, 1, 1)][c]
            }
            FaceDomain::SubFaces { .. } => cells.domain().from_sub_face(c, Dyadic::new(0, 0, 1)).reduced(),
        }
    }

    /// Face `f`'s point nearest its corner `c`.
    pub(super) fn corner_vertex(&self, f: usize, c: usize) -> u32 {
        let cells = self.buf.faces[f].expect("a face with a surface");
        let (base, m) = (cells.base, cells.m);
        match cells.domain() {
            FaceDomain::Quad => quad_side(base, m, c).0,
            FaceDomain::SubFaces { .. } => base + (c as u32) * m * m,
            FaceDomain::Triangle | FaceDomain::Ternary => {
                let up = |i: u32, j: u32| base + 2 * m * j - j * j + 2 * i;
                [up(0, 0), up(m - 1, 0), up(0, m - 1)][c]
            }
        }
    }

    /// Whether half-edge `h` (of a face with a surface) is a border: no surface across it, an
    /// infinitely sharp edge, where the surface has a crease that dual points would cut off, or
    /// a seam of a carried channel, whose values jump there (points on the edge then take one
    /// value per side, where a strip across it would blend the two sides' values).
    pub(super) fn is_border(&self, h: HalfEdgeId) -> bool {
        self.across(h).is_none() || self.is_sharp(h) || self.is_seam(h)
    }

    /// Whether `h`'s edge is a seam of a carried channel.
    fn is_seam(&self, h: HalfEdgeId) -> bool {
        self.seams.get(self.mesh.edge(h).index()).copied().unwrap_or(false)
    }

    /// The half-edge across `h` if its face has a surface.
    fn across(&self, h: HalfEdgeId) -> Option<HalfEdgeId> {
        self.mesh.twin(h).filter(|&t| self.buf.faces[self.mesh.face(t).index()].is_some())
    }

    /// Border half-edge `h`'s [`Border`] (made by [`edge`](Self::edge) before it is read).
    fn border(&self, h: HalfEdgeId) -> Border {
        self.buf.border.get(&h.raw()).copied().unwrap_or(Border { points: (u32::MAX, 0), extra: None })
    }

    /// Whether `h`'s edge is infinitely sharp (a crease of the limit surface).
    fn is_sharp(&self, h: HalfEdgeId) -> bool {
        self.mesh.edge_sharpness(self.mesh.edge(h)) >= subdiv_mesh::Tags::INFINITELY_SHARP
    }

    /// The strip along the edge of half-edge `h` (its face has a surface): against the other
    /// face's row, or against new border points.
    pub(super) fn edge(&mut self, h: HalfEdgeId) {
        let f = self.mesh.face(h).index();
        let c = self.mesh.corner(h);
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
                (self.block_side(f, c), self.block_side(g, self.mesh.corner(t)))
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
            self.side_row(g, self.mesh.corner(t), &mut other);
            other.reverse();
            for p in &mut other {
                p.num = p.den - p.num;
            }
            self.strip(&row, &other, f as u32);
        } else if let Some(t) = self.across(h).filter(|&t| t.index() < h.index()) {
            // The second side of an infinitely sharp edge: against the first side's points,
            // so that both sides share them (welded, watertight).
            let g = self.mesh.face(t).index();
            self.side_row(g, self.mesh.corner(t), &mut other);
            other.retain(|p| p.near);
            let (first, _) = self.border(t).points;
            for (k, p) in other.iter_mut().enumerate() {
                p.vertex = first + k as u32;
            }
            other.reverse();
            let tc = self.mesh.corner(t);
            for p in &mut other {
                // The first side's point, where its vertex was made (perhaps in an earlier chunk).
                let made = Site { face: g as u32, point: self.on_side(g, tc, p.num, p.den) };
                p.num = p.den - p.num;
                // This side's normal there: evaluated in this face, at the same point of the edge.
                let point = self.on_side(f, c, p.num, p.den);
                p.extra = Some(self.push_extra(p.vertex, f, point, Some(made)));
            }
            let (near_dest, near_origin) = self.border(t).points;
            let extra = other.first().zip(other.last()).and_then(|(a, b)| a.extra.zip(b.extra));
            self.buf.border.insert(h.raw(), Border { points: (near_origin, near_dest), extra });
            self.strip(&row, &other, f as u32);
        } else {
            other.clear();
            let first = self.next_vertex();
            for p in row.iter().filter(|p| p.near) {
                let point = self.on_side(f, c, p.num, p.den);
                let vertex = self.push_site(f, point);
                other.push(RowPoint { vertex, num: p.num, den: p.den, near: true, extra: None });
            }
            self.buf
                .border
                .insert(h.raw(), Border { points: (first, first + (other.len() as u32).max(1) - 1), extra: None });
            self.strip(&row, &other, f as u32);
        }
        (self.buf.row, self.buf.other) = (row, other);
    }

    /// Triangulates the ribbon between row `a` (on the left of the direction) and row `b` (on
    /// the right), both ordered along it: advance the row whose next point comes first; where
    /// both next points have the same parameter, a quad.
    pub(super) fn strip(&mut self, a: &[RowPoint], b: &[RowPoint], face: u32) {
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
                    self.triangle_at([b[j], a[i + 1], a[i]].map(Corner::from), face);
                    i += 1;
                }
                std::cmp::Ordering::Greater => {
                    self.triangle_at([b[j], b[j + 1], a[i]].map(Corner::from), face);
                    j += 1;
                }
                std::cmp::Ordering::Equal => {
                    self.quad_at([b[j], b[j + 1], a[i + 1], a[i]].map(Corner::from), face);
                    i += 1;
                    j += 1;
                }
            }
        }
    }

    /// The polygons around vertex `v`: one closed ring, or one fan per run of faces between
    /// borders (each run from a border to a border, around the vertex's limit point).
    pub(super) fn vertex(&mut self, v: VertexId) {
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
        let depth = self.buf.rings.vertices.get(v.index()).copied().unwrap_or(0);
        // Rings need the finest reach around the vertex (every run's first ring where the rates
        // put it), and, in open runs, borders with nothing across: a sharp edge or a seam between
        // two faces would have to share its ring points between the runs on its sides.
        let finest =
            mesh.outgoing(v).filter(|&h| has_surface(h)).map(|h| self.reach(mesh.face(h).index())).max().unwrap_or(1);
        self.buf.cut_ring_points.clear();
        for &start in &starts {
            ring.clear();
            corners.clear();
            let f0 = mesh.face(start).index();
            if !closed {
                ring.push(self.border(start).points.0);
            }
            let mut h = start;
            // The run's last half-edge (into `v`, on its last border).
            let mut end_edge = start;
            loop {
                let f = mesh.face(h).index();
                let corner = self.mesh.corner(h);
                ring.push(self.corner_vertex(f, corner));
                corners.push(RingCorner::Vertex { face: f as u32, corner: corner as u32 });
                let p = mesh.prev(h);
                if self.is_border(p) {
                    if !closed {
                        ring.push(self.border(p).points.1);
                    }
                    end_edge = p;
                    break;
                }
                h = mesh.twin(p).expect("not a border");
                if closed && h == start {
                    break;
                }
            }
            // An extraordinary interior point (a valence other than the regular one, or an
            // infinitely sharp corner) with a ring depth: rings down to it, fanned around its
            // limit point, in place of the polygon.
            if closed && depth > 0 && ring.len() >= 3 && (ring.len() != regular(self.triangle) || sharp_corner(mesh, v))
            {
                let point = self.corner_point(f0, self.mesh.corner(start));
                self.rings(&corners, &ring, depth, finest, (f0, point));
                continue;
            }
            // An open run at a border vertex with a ring depth: open rings, sharing their points
            // on an edge cut between two faces with the run across it.
            if !closed && depth > 0 {
                let point = self.corner_point(f0, self.mesh.corner(start));
                let end = |h: HalfEdgeId, extra: Option<u32>| RunEnd {
                    extra,
                    shared: self.across(h).is_some().then(|| mesh.edge(h).index() as u32),
                };
                let ends = [
                    end(start, self.border(start).extra.map(|e| e.0)),
                    end(end_edge, self.border(end_edge).extra.map(|e| e.1)),
                ];
                self.open_rings(&corners, &ring, ends, depth, finest, (f0, point), &mut centre);
                continue;
            }
            // Closed rings of 3 (and 4 under a quad split) are polygons of their own; rings of
            // fewer than 3 close nothing.
            let fan = !closed || (ring.len() >= 3 && (self.triangle || ring.len() >= 5));
            let point = self.corner_point(f0, self.mesh.corner(start));
            // The limit point is made by the first run; each further run (another smooth
            // sector, between infinitely sharp edges) takes its own normal there.
            let centre_corner = match centre {
                None if fan => {
                    let c = self.push_site(f0, point);
                    centre = Some(c);
                    Some(Corner::from(c))
                }
                Some(c) if !closed => Some(Corner { vertex: c, extra: Some(self.push_extra(c, f0, point, None)) }),
                _ => None,
            };
            if closed {
                self.close_ring(&ring, if fan { centre } else { None }, f0 as u32);
            } else if let Some(c) = centre_corner {
                // An open fan: from the border point on the first edge to the one on the last,
                // with this run's normals where a border is the second side of a sharp edge.
                let last = ring.len() - 1;
                for k in 0..last {
                    let mut t = [c, Corner::from(ring[k]), Corner::from(ring[k + 1])];
                    if k == 0 {
                        t[1].extra = self.border(start).extra.map(|e| e.0);
                    }
                    if k + 1 == last {
                        t[2].extra = self.border(end_edge).extra.map(|e| e.1);
                    }
                    self.triangle_at(t, f0 as u32);
                }
            }
        }
        self.buf.ring = ring;
        self.buf.ring_corners = corners;
        self.buf.starts = starts;
    }
}
