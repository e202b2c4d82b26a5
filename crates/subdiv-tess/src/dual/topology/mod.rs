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
use subdiv_schemes::Split;
use subdiv_stencil::{Dyadic, FaceDomain};

use crate::rates::{GRID_DENOMINATOR, GradedGrid, RingDepths, first_ring_depth};

mod builder;
#[cfg(test)]
mod tests;

use self::builder::*;
pub(crate) use self::builder::{Builder, BuilderBuffers};

/// A face's [`FaceDomain`], or none (a hole), in four bytes: the domains follow from the split
/// and the face's size ([`FaceDomain::of`]), so an N-gon's is its size (an
/// `Option<FaceDomain>` per face was 24 bytes, the builder's copy in each face's cells 40 with
/// them: 64 MB of a million-face grid's peak).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PackedDomain(u32);

impl PackedDomain {
    const HOLE: u32 = u32::MAX;
    const QUAD: u32 = 0;
    const TRIANGLE: u32 = 1;
    const TERNARY: u32 = 2;

    /// `domain` packed; an N-gon of `u32::MAX` sides or more (no mesh has one) packs as a hole.
    pub(crate) fn pack(domain: Option<FaceDomain>) -> Self {
        Self(match domain {
            None => Self::HOLE,
            Some(FaceDomain::Quad) => Self::QUAD,
            Some(FaceDomain::Triangle) => Self::TRIANGLE,
            Some(FaceDomain::Ternary) => Self::TERNARY,
            Some(FaceDomain::SubFaces { size, columns }) => {
                debug_assert_eq!(
                    Some(FaceDomain::SubFaces { size, columns }),
                    FaceDomain::of(subdiv_schemes::Split::Quad, size)
                );
                u32::try_from(size).ok().filter(|&s| s != Self::HOLE).unwrap_or(Self::HOLE)
            }
        })
    }

    /// The domain (`None`: a hole).
    #[inline]
    pub(crate) fn get(self) -> Option<FaceDomain> {
        match self.0 {
            Self::HOLE => None,
            Self::QUAD => Some(FaceDomain::Quad),
            Self::TRIANGLE => Some(FaceDomain::Triangle),
            Self::TERNARY => Some(FaceDomain::Ternary),
            // Sizes 3 and up (N-gons under a quad split, triangles included): never 0..=2.
            size => FaceDomain::of(subdiv_schemes::Split::Quad, size as usize),
        }
    }
}

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
    /// The extra normal it takes in the triangles made with this row (a point of the other
    /// side of an infinitely sharp edge), if any.
    extra: Option<u32>,
}

/// The output's vertices and connectivity.
#[derive(Debug, Default)]
pub(crate) struct Topology {
    /// The number of output vertices.
    pub vertex_count: u32,
    /// The sites of the vertices outside the blocks, in vertex order (a block's are implicit,
    /// which spares writing most of them: [`Self::site`]), then those of the extra normals.
    pub sites: Vec<Site>,
    /// Per extra normal (numbered after the vertices: point `vertex_count + k`), its vertex: a
    /// point of an infinitely sharp crease seen from a further smooth sector around it, whose
    /// normal is evaluated at its own site (in a face of that sector).
    pub extra: Vec<u32>,
    /// The number the triangles' corners give extra normal 0: `vertex_count`, but in a chunk
    /// of a streamed output, whose extra normals come after the whole output's vertices.
    pub extra_base: u32,
    /// The explicit triangles' corners that take an extra normal instead of their vertex's.
    pub normal_corners: Vec<NormalCorner>,
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

/// Corner `corner` of explicit triangle `triangle` takes extra normal `extra`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct NormalCorner {
    pub triangle: u32,
    pub corner: u32,
    pub extra: u32,
}

/// A triangle corner as the builder makes it: its vertex and, on the second side of an
/// infinitely sharp edge or in a further sector around a crease vertex, its extra normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Corner {
    vertex: u32,
    extra: Option<u32>,
}

impl From<u32> for Corner {
    fn from(vertex: u32) -> Self {
        Self { vertex, extra: None }
    }
}

impl From<RowPoint> for Corner {
    fn from(p: RowPoint) -> Self {
        Self { vertex: p.vertex, extra: p.extra }
    }
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
    /// Empties it, keeping its allocations.
    pub(crate) fn clear(&mut self) {
        self.vertex_count = 0;
        self.extra_base = 0;
        self.sites.clear();
        self.extra.clear();
        self.normal_corners.clear();
        self.blocks.clear();
        self.runs.clear();
        self.triangles.clear();
        self.triangle_faces.clear();
        self.polygon_offsets.clear();
        self.polygon_offsets.push(0);
        self.polygon_vertices.clear();
        self.polygon_faces.clear();
    }

    /// The number of evaluated points: the vertices, then the extra normals (each evaluated at
    /// its own site; its position is its vertex's up to rounding).
    pub(crate) fn point_count(&self) -> u32 {
        self.vertex_count + self.extra.len() as u32
    }

    /// Point `v`'s site (a vertex, or an extra normal past the vertices).
    pub(super) fn site(&self, v: u32) -> Site {
        // The last block starting at or before `v`.
        let k = self.blocks.partition_point(|b| b.base <= v);
        match k.checked_sub(1).map(|k| &self.blocks[k]) {
            Some(b) if v < b.base + b.len() => b.site(v - b.base),
            Some(b) => self.sites[(b.sites + v - b.base - b.len()) as usize],
            None => self.sites[v as usize],
        }
    }

    /// The explicit sites (every point outside the blocks: vertices, then extra normals) with
    /// their point numbers, in order.
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

    /// Every triangle's normals (indices into the points: a vertex's own normal, or an extra
    /// normal), in output order, into `out` (as [`write_triangles`](Self::write_triangles)):
    /// the triangles, with the corners that take an extra normal set.
    pub(super) fn write_triangle_normals(&self, out: &mut [u32], parallel: bool) {
        self.write_triangles(out, parallel);
        self.set_normal_corners(out);
    }

    /// Sets the corners that take an extra normal in `out`, the triangles' indices (three per
    /// triangle, in output order).
    pub(super) fn set_normal_corners(&self, out: &mut [u32]) {
        for c in &self.normal_corners {
            // The runs made before this explicit triangle, and their triangles.
            let runs = self.runs.partition_point(|r| r.explicit <= c.triangle);
            let before = runs.checked_sub(1).map_or(0, |k| {
                let r = &self.runs[k];
                r.first + r.triangles() - r.explicit
            });
            out[3 * (before + c.triangle) as usize + c.corner as usize] = self.extra_base + c.extra;
        }
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

    /// Every vertex's site, in vertex order (not the extra normals').
    pub(super) fn for_each_site(&self, mut put: impl FnMut(Site)) {
        let mut explicit = self.sites[..self.sites.len() - self.extra.len()].iter();
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
    /// Triangles below which a half is written where it is (a few microseconds of work; not
    /// measured on its own: the calls that fork here are large, `BESIDE` gates the small ones).
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

/// The number of output vertices at `rates`, from the construction's counts (for tests and for
/// sizing): cells, triangle interiors, N-gon centres, border points (boundaries, holes,
/// infinitely sharp edges and the seams of the mesh's channels), vertex points.
pub(crate) fn predicted_vertices(mesh: &Mesh, split: Split, rates: &[u32], rings: Option<&RingDepths>) -> usize {
    predicted_vertices_cut(mesh, split, rates, rings, None)
}

/// [`predicted_vertices`] with the channel seams the builder cuts (per edge, as
/// [`Builder::with_buffers`] takes them), or (`None`) those of every channel of the mesh.
pub(crate) fn predicted_vertices_cut(
    mesh: &Mesh,
    split: Split,
    rates: &[u32],
    rings: Option<&RingDepths>,
    seams: Option<&[bool]>,
) -> usize {
    // The vertex rules are a triangle split's under Loop's split alone (the builder's
    // `triangle`); √3's faces are triangle cells too (`FaceDomain::Ternary`).
    let triangle = split == Split::Triangle;
    let triangle_cells = matches!(split, Split::Triangle | Split::Sqrt3);
    let hole = |f: FaceId| mesh.is_hole(f);
    let rate_of = |f: FaceId| rates[f.index()] as usize;
    let no_rings = RingDepths::default();
    let reach_of = |f: FaceId| rings.unwrap_or(&no_rings).reach(mesh, triangle, f, rates[f.index()]);
    // Edges the construction cuts between two faces: infinitely sharp ones, and the seams of
    // the mesh's channels (carried by default).
    let cut = |h: HalfEdgeId| {
        let e = mesh.edge(h);
        let seam = match seams {
            Some(seams) => seams.get(e.index()).copied().unwrap_or(false),
            None => mesh.channels().iter().any(|c| mesh.is_seam(c, e)),
        };
        mesh.edge_sharpness(e) >= subdiv_mesh::Tags::INFINITELY_SHARP || seam
    };
    let mut count = 0;
    for f in mesh.face_ids().filter(|&f| !hole(f)) {
        let (n, size) = (rate_of(f), mesh.face_size(f));
        count += if triangle_cells {
            n * n + (n.saturating_sub(1) * n.saturating_sub(2)) / 2
        } else if size == 4 {
            n * n
        } else {
            let depth = rings.map_or(0, |r| r.centres[f.index()]);
            let centre = if depth > 0 {
                // Two points per sub-face per ring, and the centre (N = 3 has none without).
                let finest = reach_of(f);
                2 * size * ring_count(first_ring_depth(false, finest), depth) as usize + 1
            } else {
                usize::from(size >= 5)
            };
            size * n.div_ceil(2).pow(2) + centre
        };
        for h in mesh.face_half_edges(f) {
            // A border's points are on its first side (an edge cut between two faces: the
            // lower half-edge's).
            let first = match mesh.twin(h) {
                None => true,
                Some(t) => hole(mesh.face(t)) || (cut(h) && h.index() < t.index()),
            };
            if first {
                count += if triangle_cells || size == 4 { n } else { 2 * n.div_ceil(2) };
            }
        }
    }
    for v in mesh.vertices() {
        let faces: Vec<FaceId> = mesh.vertex_faces(v).filter(|&f| !hole(f)).collect();
        if faces.is_empty() {
            continue;
        }
        let border =
            mesh.outgoing(v).any(|h| mesh.twin(h).is_none_or(|t| hole(mesh.face(t))) || hole(mesh.face(h)) || cut(h))
                || mesh.is_boundary_vertex(v);
        let depth = rings.map_or(0, |r| r.vertices[v.index()]);
        if border && depth > 0 {
            // Open rings: per ring two points per face, and one more per run that starts at a
            // border with nothing across (a run that starts at an edge cut between two faces
            // shares its points there with the run across, whose last edge it is); the limit
            // point once.
            let finest = faces.iter().map(|&f| reach_of(f)).max().unwrap_or(1);
            let runs = mesh
                .outgoing(v)
                .filter(|&h| !hole(mesh.face(h)) && mesh.twin(h).is_none_or(|t| hole(mesh.face(t))))
                .count();
            count += (2 * faces.len() + runs) * ring_count(first_ring_depth(triangle, finest), depth) as usize + 1;
        } else if !border
            && depth > 0
            && faces.len() >= 3
            && (faces.len() != regular(triangle) || sharp_corner(mesh, v))
        {
            // Two points per face per ring (its edge's and its inner one), and the limit point.
            let finest = faces.iter().map(|&f| reach_of(f)).max().unwrap_or(1);
            count += 2 * faces.len() * ring_count(first_ring_depth(triangle, finest), depth) as usize + 1;
        } else if border || (faces.len() >= 3 && (triangle || faces.len() >= 5)) {
            count += 1;
        }
    }
    count
}
