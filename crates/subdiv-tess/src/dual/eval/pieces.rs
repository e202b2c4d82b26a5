//! The evaluation pass: disjoint pieces of the vertex range (blocks, typed faces, runs), shared among threads, written through a [`Sink`].

use super::*;

/// The fewest vertices [`Evaluator::evaluate_into`] shares among threads: waking a sleeping
/// thread costs about what a thousand vertices take (tens of microseconds in a virtual
/// machine), and past that the pieces stay small, so that the calling thread can do them all
/// when the others wake late. Measured on 16 cores (`cargo xtask bench tess --threads 16`, the
/// cube at rate 8, full path): 36-43 M triangles/s without it, 60-108 with it, 57-68 on one
/// thread; on two cores it is neutral (docs/perf-log.md, `1e2d766`).
pub(super) const PARALLEL_VERTICES: usize = 1024;

/// What the blocks and typed faces of one thread reuse from piece to piece (made anew for
/// each, their zeroing showed in profiles as a `memset` of 4 % of the full path's time).
pub(super) struct Scratch {
    pub(super) pending: Pending,
    /// A typed face's cage points by coordinate.
    pub(super) gathered: [[f64; MAX_TYPED_POINTS]; 3],
}

impl Scratch {
    pub(super) fn new() -> Self {
        Self { pending: Pending::new(), gathered: [[0.0; MAX_TYPED_POINTS]; 3] }
    }
}

/// Vertices per piece of a run of vertices outside the blocks in [`Evaluator::evaluate_into`].
pub(super) const RUN: usize = 1024;

/// Vertices per batch of a run's normalisations.
pub(super) const BATCH: usize = 64;

/// A piece of [`Evaluator::evaluate_into`]'s work.
pub(super) enum Piece<'a, S> {
    /// The dual grids of consecutive bicubic faces' blocks (contiguous in the vertex range):
    /// one piece for many small blocks, not one each (a piece per block of a million-face
    /// grid at rate 2 was a 96 MB list of pieces).
    Blocks { blocks: &'a [Block], out: S },
    /// A typed face's cell points: its template over its cage points.
    Typed { template: &'a Template, cage: &'a [u32], out: S },
    /// Vertices `start..start + out.len()`: the patch grids' (all in the range), then each
    /// other one on its own.
    Run { start: usize, out: S, grids: &'a [PatchGrid] },
}

/// Where [`Evaluator::evaluate_into`] writes a range of vertices.
pub(super) trait Sink: Send + Sized {
    /// An empty range.
    fn empty() -> Self;
    /// The number of vertices.
    fn len(&self) -> usize;
    /// The first `k` vertices and the rest.
    fn split(self, k: usize) -> (Self, Self);
    /// Writes vertex `k`'s position and unit normal.
    fn put(&mut self, k: usize, p: DVec3, n: DVec3);
}

/// The part of [`Evaluator::evaluate_into`]'s output not yet cut into pieces: vertices from
/// `at` on.
struct Cut<S> {
    rest: S,
    at: usize,
}

impl<S: Sink> Cut<S> {
    /// The next `len` vertices: their first vertex and their output.
    fn take(&mut self, len: usize) -> (usize, S) {
        let (piece, tail) = std::mem::replace(&mut self.rest, S::empty()).split(len);
        self.rest = tail;
        let start = self.at;
        self.at += len;
        (start, piece)
    }
}

/// Interleaved f32: per vertex `px py pz nx ny nz`.
pub(super) struct FlatSink<'a>(pub(super) &'a mut [f32]);

impl Sink for FlatSink<'_> {
    fn empty() -> Self {
        Self(&mut [])
    }
    fn len(&self) -> usize {
        self.0.len() / 6
    }
    fn split(self, k: usize) -> (Self, Self) {
        let (a, b) = self.0.split_at_mut(6 * k);
        (Self(a), Self(b))
    }
    #[inline]
    fn put(&mut self, k: usize, p: DVec3, n: DVec3) {
        self.0[6 * k..6 * k + 6].copy_from_slice(&crate::dual::flat_vertex(p, n));
    }
}

/// f64 positions and normals.
pub(super) struct WideSink<'a>(pub(super) &'a mut [DVec3], pub(super) &'a mut [DVec3]);

impl Sink for WideSink<'_> {
    fn empty() -> Self {
        Self(&mut [], &mut [])
    }
    fn len(&self) -> usize {
        self.0.len()
    }
    fn split(self, k: usize) -> (Self, Self) {
        let (a, b) = self.0.split_at_mut(k);
        let (c, d) = self.1.split_at_mut(k);
        (Self(a, c), Self(b, d))
    }
    #[inline]
    fn put(&mut self, k: usize, p: DVec3, n: DVec3) {
        self.0[k] = p;
        self.1[k] = n;
    }
}

impl Evaluator {
    /// [`evaluate`](Self::evaluate) straight into interleaved f32 (`6 ·` points long, the
    /// flat vertices: the vertices, then one per extra normal), without the f64 arrays. An
    /// extra normal's vertex takes its vertex's position, bit for bit, so that both sides of a
    /// crease meet exactly.
    pub(crate) fn evaluate_flat(&self, topo: &Topology, parallel: bool, out: &mut [f32]) {
        self.evaluate_into(topo, parallel, FlatSink(out));
        for (k, &v) in topo.extra.iter().enumerate() {
            let (vertices, extra) = out.split_at_mut(6 * topo.vertex_count as usize);
            let v = 6 * v as usize;
            extra[6 * k..6 * k + 3].copy_from_slice(&vertices[v..v + 3]);
        }
    }

    /// Evaluates every point of `topo` (prepared) on the current cage: `positions` gets the
    /// vertices' (an extra normal's position is its vertex's, up to rounding, and is not
    /// kept), `normals` the vertices' then the extra normals.
    pub(crate) fn evaluate(
        &self,
        topo: &Topology,
        parallel: bool,
        positions: &mut Vec<DVec3>,
        normals: &mut Vec<DVec3>,
    ) {
        self.evaluate_points(topo, parallel, positions, normals);
        positions.truncate(topo.vertex_count as usize);
    }

    /// As [`evaluate`](Self::evaluate), keeping every point's position (an extra normal's at
    /// its own site: a channel's value on a seam's second side).
    pub(crate) fn evaluate_points(
        &self,
        topo: &Topology,
        parallel: bool,
        positions: &mut Vec<DVec3>,
        normals: &mut Vec<DVec3>,
    ) {
        let n = topo.point_count() as usize;
        positions.resize(n, DVec3::ZERO);
        normals.resize(n, DVec3::ZERO);
        self.evaluate_into(topo, parallel, WideSink(positions, normals));
    }

    /// Every vertex into `out`, in one pass over
    /// disjoint pieces of the vertex range: the bicubic blocks, the typed faces, the faces with
    /// patch grids, and the runs between them (general-route and pointwise bicubic vertices)
    /// cut to at most [`RUN`] vertices. Each vertex is computed alone, so the output does not
    /// depend on how the pieces are shared among threads.
    pub(super) fn evaluate_into<'a, S: Sink>(&'a self, topo: &'a Topology, parallel: bool, out: S) {
        let mut pieces: Vec<Piece<'a, S>> = Vec::new();
        let mut cut = Cut { rest: out, at: 0 };
        let push_run = |cut: &mut Cut<S>, end: usize, pieces: &mut Vec<Piece<'a, S>>| {
            while cut.at < end {
                let (start, out) = cut.take((end - cut.at).min(RUN));
                pieces.push(Piece::Run { start, out, grids: &[] });
            }
        };
        // Consecutive bicubic blocks not pushed yet (their vertices start at `cut.at`).
        let mut group = 0..0;
        let push_group = |cut: &mut Cut<S>, group: &std::ops::Range<usize>, pieces: &mut Vec<Piece<'a, S>>| {
            if let Some(last) = topo.blocks[group.clone()].last() {
                let (_, out) = cut.take((last.base + last.len()) as usize - cut.at);
                pieces.push(Piece::Blocks { blocks: &topo.blocks[group.clone()], out });
            }
        };
        for (b, (block, &(first, last))) in topo.blocks.iter().zip(&self.block_grids).enumerate() {
            let template = self.block_templates[b].template();
            let bicubic = template.is_none() && matches!(self.faces[block.face as usize], FacePlan::Bicubic { .. });
            let len = block.len() as usize;
            if bicubic && !group.is_empty() {
                let end = (block.base + block.len()) as usize;
                if topo.blocks[group.end - 1].base + topo.blocks[group.end - 1].len() == block.base
                    && end - cut.at <= RUN
                {
                    group.end = b + 1;
                    continue;
                }
            }
            push_group(&mut cut, &group, &mut pieces);
            group = b..b;
            if !(template.is_some() || bicubic || first < last) {
                continue;
            }
            push_run(&mut cut, block.base as usize, &mut pieces);
            if bicubic {
                group = b..b + 1;
                continue;
            }
            let (start, out) = cut.take(len);
            pieces.push(match template {
                Some(template) => {
                    let ty = self.face_types.get(block.face as usize).expect("a typed face");
                    let cage = &self.face_cage[ty.cage.0 as usize..ty.cage.1 as usize];
                    Piece::Typed { template: &self.templates[template as usize], cage, out }
                }
                // A general face with patch grids: one piece (its grids write anywhere in it).
                None => Piece::Run { start, out, grids: &self.patch_grids[first as usize..last as usize] },
            });
        }
        push_group(&mut cut, &group, &mut pieces);
        push_run(&mut cut, topo.point_count() as usize, &mut pieces);
        self.run_pieces(pieces, parallel && topo.point_count() as usize >= PARALLEL_VERTICES);
    }

    /// Evaluates `pieces`, on rayon's threads if `parallel`.
    pub(super) fn run_pieces<S: Sink>(&self, pieces: Vec<Piece<'_, S>>, parallel: bool) {
        if pieces.is_empty() {
            return;
        }
        // The CPU's features, looked up once per call.
        let arch = pulp::Arch::new();
        crate::par::for_each_init(parallel, pieces, Scratch::new, |scratch, piece| {
            self.run_piece(arch, piece, scratch);
        });
    }

    /// One piece, with the widest vector instructions the CPU has (AVX2 on x86-64), chosen at
    /// run time: the same operations in the same order (Rust never fuses a product and a sum
    /// on its own; the typed faces' `mul_add` is one rounding on every target), so the same
    /// bits as the baseline build. The piece's work is inlined into the dispatched function,
    /// which compiles it for the CPU's features.
    #[inline(always)]
    pub(super) fn run_piece<S: Sink>(&self, arch: pulp::Arch, piece: Piece<'_, S>, scratch: &mut Scratch) {
        arch.dispatch(
            #[inline(always)]
            || self.evaluate_piece(piece, scratch),
        );
    }

    /// One piece of [`evaluate_into`](Self::evaluate_into)'s work.
    #[inline(always)]
    pub(super) fn evaluate_piece<S: Sink>(&self, piece: Piece<'_, S>, scratch: &mut Scratch) {
        let cage = &self.positions[0];
        match piece {
            Piece::Blocks { blocks, mut out } => {
                for block in blocks {
                    let (mut piece, tail) = out.split(block.len() as usize);
                    out = tail;
                    let Some(cv) = self.cv(block.face) else { unreachable!("a group of bicubic blocks") };
                    let basis = self.bases[block.rate as usize].as_deref().expect("prepared");
                    grid_block(&cv, cage, basis, &mut piece, &mut scratch.pending);
                }
            }
            Piece::Typed { template, cage: ids, mut out } => {
                typed_block(template, ids, cage, &mut out, scratch);
            }
            Piece::Run { start, mut out, grids } => {
                // By batches: first the positions and the tangents' cross products, then the
                // normalisations (their square roots and divisions overlap).
                let mut xs = [DVec3::ZERO; BATCH];
                let mut cs = [DVec3::ZERO; BATCH];
                for grid in grids {
                    let points = &self.positions[grid.level as usize];
                    self.patch_grid_eval(grid, points, (&mut xs, &mut cs), |v, p, n| out.put(v as usize - start, p, n));
                }
                let mut ks = [0usize; BATCH];
                // The piece's first pointwise vertex; the others follow in order.
                let mut next = self.pointwise.partition_point(|&(v, ..)| (v as usize) < start);
                let routes = &self.routes[start..start + out.len()];
                for (b, batch) in routes.chunks(BATCH).enumerate() {
                    let mut m = 0;
                    for (k, &route) in batch.iter().enumerate() {
                        let (x, du, dv) = match route.get() {
                            // Written by their grids above.
                            Route::PatchGrid => continue,
                            Route::BicubicPoint => {
                                let (vertex, face, [u, v]) = self.pointwise[next];
                                debug_assert_eq!(vertex as usize, start + b * BATCH + k);
                                next += 1;
                                let Some(cv) = self.cv(face) else { unreachable!("bicubic face") };
                                bicubic(&cv, cage, u, v)
                            }
                            Route::Record(r) => self.general(&self.records[r as usize]),
                            Route::BlockCell | Route::Template => unreachable!("blocks are pieces of their own"),
                        };
                        (xs[m], cs[m], ks[m]) = (x, du.cross(dv), b * BATCH + k);
                        m += 1;
                    }
                    for ((x, c), &k) in xs.iter().zip(&cs).zip(&ks).take(m) {
                        out.put(k, *x, crate::unit_normal(*c));
                    }
                }
            }
        }
    }
}
