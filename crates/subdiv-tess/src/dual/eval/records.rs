//! The general route: per-vertex exact stencil records (prepared by chunks, in parallel), the dual-grid tables they read, and their dot products.

use super::*;

/// A vertex on the general route: its patch's control points, its stencil, and the rows that
/// turn the patch's `(∂/∂s, ∂/∂t)` into the input face's `(∂/∂u, ∂/∂v)`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Record {
    pub(super) level: u32,
    pub(super) ids: u32,
    pub(super) len: u32,
    /// The first of the record's weights in `weights` (three rows of [`padded`]`(len)`: position,
    /// `∂/∂s`, `∂/∂t`, zeros after `len`), or, when `table` is not
    /// [`NO_TABLE`], the point's index in that table's dual grid.
    pub(super) weights: u32,
    pub(super) table: u32,
    pub(super) ju: [f64; 2],
    pub(super) jv: [f64; 2],
}

/// Stencil evaluators per matrices (keyed by the matrices' address), and the bicubic grids of
/// patch shapes (per matrices and shape; `None`: not bicubic).
#[derive(Debug, Default)]
pub(super) struct Evaluators {
    pub(super) stencils: HashMap<usize, StencilEvaluator<Arc<PatchMatrices>>>,
    pub(super) grids: HashMap<(usize, usize), Option<[u8; 16]>>,
}

/// Vertices per chunk of [`Evaluator::prepare`].
pub(super) const CHUNK: usize = 4096;

/// One chunk's stencil records, with offsets into its own `ids` and `weights`.
#[derive(Debug, Default)]
pub(super) struct Chunk {
    /// `(vertex, record)` pairs.
    pub(super) assigned: Vec<(u32, u32)>,
    pub(super) records: Vec<Record>,
    /// Per record: where it is, for gathering the points of one bicubic patch into a grid.
    pub(super) places: Vec<Place>,
    pub(super) ids: Vec<u32>,
    /// Weights of stencils not in the evaluator's `stencil_index` (records name them by their
    /// number `k` here, with `table` [`FRESH`]), and per such stencil its key and first weight
    /// here.
    pub(super) weights: Vec<f64>,
    pub(super) fresh: Vec<((usize, usize, Dyadic), u32)>,
}

/// The `table` of a chunk record whose `weights` is the number of one of the chunk's fresh
/// stencils.
pub(super) const FRESH: u32 = u32::MAX - 1;

/// A record's patch and parameter there, for [`Evaluator::patch_grids`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Place {
    /// The patch's level and face on that level.
    pub(super) patch: (u32, u32),
    /// The point in the patch's frame.
    pub(super) at: Dyadic,
    /// The patch's 4 × 4 grid (indices into its control points, `grid[j * 4 + i]` at
    /// `(i − 1, j − 1)` in the patch's frame) if its sub-patch matrices are bicubic.
    pub(super) grid: Option<[u8; 16]>,
}

/// A record with its own weights.
pub(super) const NO_TABLE: u32 = u32::MAX;

/// The most control points a table record gathers on the stack (Catmull-Clark valence 12).
pub(super) const MAX_GATHER: usize = 32;

/// Dual-grid stencil tables of level-0 patches, per (matrices, rate), kept across calls.
#[derive(Debug, Default)]
pub(super) struct DualTables {
    pub(super) tables: Vec<Arc<StencilTable>>,
    pub(super) index: HashMap<(usize, u32), u32>,
}

/// Whether the points of level-0 `patch`'s own dual grid read a dual-grid table (shape 0, at
/// most [`MAX_GATHER`] control points), rather than stencils of their own.
pub(super) fn reads_table(patch: &subdiv_schemes::FoundPatch) -> bool {
    patch.shape == 0 && patch.vertices.len() <= MAX_GATHER
}

/// Computes the dual-grid table of `patch`'s shape at `rate` unless it is held.
pub(super) fn ensure_table(
    tables: &mut DualTables,
    patch: &subdiv_schemes::FoundPatch,
    rate: u32,
) -> Result<(), TessError> {
    let key = (Arc::as_ptr(&patch.matrices) as usize, rate);
    if !tables.index.contains_key(&key) {
        let computed =
            StencilTable::compute_rates(&patch.matrices, BoundaryInterpolation::EdgeOnly, rate..=rate)?.remove(0);
        tables.tables.push(Arc::new(computed));
        tables.index.insert(key, (tables.tables.len() - 1) as u32);
    }
    Ok(())
}

/// The table and index of `point` (in the patch's frame, as the face's grid gave it: not
/// reduced) if it is a point of its face's own dual grid (at `face_rate`) and that table of
/// the patch's shape is held.
pub(super) fn dual_table(
    tables: &DualTables,
    patch: &subdiv_schemes::FoundPatch,
    point: Dyadic,
    face_rate: u32,
) -> Option<(u32, u32)> {
    let Dyadic { u: a, v: b, denominator: q } = point;
    let triangle = patch.matrices.face_size == 3;
    let (rate, index) = if triangle {
        // Centroids ((3i+1)/3n, (3j+1)/3n) up, ((3i+2)/3n, (3j+2)/3n) down.
        let r = a.rem_euclid(3);
        if q % 3 != 0 || r == 0 || b.rem_euclid(3) != r {
            return None;
        }
        let (n, i, j) = (q / 3, (a - r) / 3, (b - r) / 3);
        (n, 2 * n * j - j * j + 2 * i + i64::from(r == 2))
    } else {
        if q % 2 != 0 || a % 2 == 0 || b % 2 == 0 {
            return None;
        }
        let n = q / 2;
        (n, (b - 1) / 2 * n + (a - 1) / 2)
    };
    // Only the face's own grid: a point of another rate's grid (a triangle's primal point at a
    // rate of 3n is a cell centroid at n) would read whichever table another face's rate made,
    // and its bits would depend on the rates of faces far away (a face-range part's).
    let rate = u32::try_from(rate).ok().filter(|&r| r == face_rate)?;
    let table = *tables.index.get(&(Arc::as_ptr(&patch.matrices) as usize, rate))?;
    let t = &tables.tables[table as usize];
    // The closed-form index, checked against the table's own order.
    let index = usize::try_from(index).ok().filter(|&k| k < t.len(Grid::Dual) && t.point(Grid::Dual, k) == point)?;
    Some((table, index as u32))
}

impl Evaluator {
    /// [`prepare`](Self::prepare) but the patch grids: every general-route vertex on its record,
    /// but the typed faces' cell points that read a template ([`Route::Template`]).
    pub(super) fn prepare_records(&mut self, topo: &Topology, rates: &[u32], parallel: bool) -> Result<(), TessError> {
        let n = topo.point_count() as usize;
        self.routes.clear();
        self.routes.resize(n, Route::BicubicPoint.into());
        self.records.clear();
        self.ids.clear();
        for (b, block) in topo.blocks.iter().enumerate() {
            let cells = block.base as usize..(block.base + block.len()) as usize;
            if let FacePlan::Bicubic { .. } = self.faces[block.face as usize] {
                self.routes[cells].fill(Route::BlockCell.into());
            } else if self.block_templates[b].copies() {
                self.routes[cells].fill(Route::Template.into());
            }
        }
        // The dual-grid tables the level-0 patches' cell points read (but those of faces that
        // copy a template), first: the chunks below only read them. The faces of this topology
        // only (a chunk of a streamed tessellation is not the mesh), each once per run of its
        // points.
        let mut last = None;
        for f in topo.blocks.iter().map(|b| b.face).chain(topo.sites.iter().map(|s| s.face)) {
            if last.replace(f) == Some(f) || !self.table_faces[f as usize] || self.copied[f as usize] {
                continue;
            }
            if let Some(Resolved::Patch { patch, .. }) = self.levels.resolve(0, FaceId::new(f)) {
                ensure_table(&mut self.tables, patch, rates[f as usize])?;
            }
        }
        // Stencil records by chunks of vertices, in parallel; each chunk borrows a set of
        // stencil evaluators from the pool (their results do not depend on what they solved
        // before, so neither does the output on the thread count).
        let spans = self.record_spans(topo);
        let chunks = chunks_of(&spans);
        let pool = std::sync::Mutex::new(std::mem::take(&mut self.pool));
        // The chunks' buffers are kept across calls too (no fresh pages per call).
        let spare = std::sync::Mutex::new(std::mem::take(&mut self.spare));
        let this = &*self;
        let work = |spans: &[std::ops::Range<usize>]| -> Result<Chunk, TessError> {
            let mut evaluators =
                pool.lock().unwrap_or_else(std::sync::PoisonError::into_inner).pop().unwrap_or_default();
            let out = spare.lock().unwrap_or_else(std::sync::PoisonError::into_inner).pop().unwrap_or_default();
            let chunk = this.chunk(topo, rates, spans, &mut evaluators, out);
            pool.lock().unwrap_or_else(std::sync::PoisonError::into_inner).push(evaluators);
            chunk
        };
        let results: Vec<Result<Chunk, TessError>> = crate::par::map(parallel, chunks, work);
        self.spans = spans;
        self.pool = pool.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
        self.spare = spare.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
        self.places.clear();
        let mut fresh = Vec::new();
        for chunk in results {
            let chunk = chunk?;
            self.absorb(&chunk, &mut fresh);
            self.spare.push(chunk);
        }
        Ok(())
    }

    /// One chunk's records joined to the evaluator's (`fresh`: scratch).
    pub(super) fn absorb(&mut self, chunk: &Chunk, fresh: &mut Vec<u32>) {
        self.places.extend_from_slice(&chunk.places);
        let (records, ids) = (self.records.len() as u32, self.ids.len() as u32);
        for &(vertex, record) in &chunk.assigned {
            self.routes[vertex as usize] = Route::Record(records + record).into();
        }
        // The chunk's fresh stencils join the kept ones (a key an earlier chunk added takes
        // that copy: the same weights).
        fresh.clear();
        for (k, &(key, at)) in chunk.fresh.iter().enumerate() {
            let end = chunk.fresh.get(k + 1).map_or(chunk.weights.len(), |&(_, next)| next as usize);
            let weights = &mut self.weights;
            fresh.push(*self.stencil_index.entry(key).or_insert_with(|| {
                weights.extend_from_slice(&chunk.weights[at as usize..end]);
                (weights.len() - (end - at as usize)) as u32
            }));
        }
        self.records.extend(chunk.records.iter().map(|r| Record {
            ids: r.ids + ids,
            weights: if r.table == FRESH { fresh[r.weights as usize] } else { r.weights },
            table: if r.table == FRESH { NO_TABLE } else { r.table },
            ..*r
        }));
        self.ids.extend_from_slice(&chunk.ids);
    }

    /// The vertices that may take records, as ranges of at most [`CHUNK`] vertices, in order:
    /// all but the blocks whose points are evaluated without (bicubic faces' grids and typed
    /// faces' cells), which a scan vertex by vertex would only skip (most of a tessellation's
    /// vertices, often all). In a buffer kept across calls.
    pub(super) fn record_spans(&mut self, topo: &Topology) -> Vec<std::ops::Range<usize>> {
        let mut spans = std::mem::take(&mut self.spans);
        spans.clear();
        let mut push = |start: usize, end: usize| {
            spans.extend((start..end).step_by(CHUNK).map(|s| s..(s + CHUNK).min(end)));
        };
        let mut at = 0;
        for block in &topo.blocks {
            let (base, end) = (block.base as usize, (block.base + block.len()) as usize);
            // A block's points are all of one kind (`prepare_records` marks them together).
            if base < end && matches!(self.routes[base].get(), Route::BlockCell | Route::Template) {
                push(at, base);
                at = end;
            }
        }
        push(at, topo.point_count() as usize);
        spans
    }

    /// The stencil records of the general-route vertices of `spans`, with chunk-local offsets.
    pub(super) fn chunk(
        &self,
        topo: &Topology,
        rates: &[u32],
        spans: &[std::ops::Range<usize>],
        evaluators: &mut Evaluators,
        mut out: Chunk,
    ) -> Result<Chunk, TessError> {
        out.assigned.clear();
        out.records.clear();
        out.places.clear();
        out.ids.clear();
        out.weights.clear();
        out.fresh.clear();
        let mut patches: HashMap<(usize, u32), (u32, u32)> = HashMap::new();
        let mut last: Vec<Option<(FaceId, Option<Resolved<'_>>)>> = vec![None; self.levels.level_count()];
        let mut shared: HashMap<(usize, usize, Dyadic), u32> = HashMap::new();
        for i in spans.iter().flat_map(Clone::clone) {
            // `record_spans` left out the blocks of those kinds, and only blocks have them.
            debug_assert!(
                !matches!(self.routes[i].get(), Route::BlockCell | Route::Template),
                "vertex {i} outside the record spans"
            );
            let site = topo.site(i as u32);
            if !matches!(self.faces[site.face as usize], FacePlan::General) {
                continue;
            }
            let face = FaceId::new(site.face);
            // Reduced once, as `LimitEvaluator::eval_exact` does: the descent's maps keep it exact.
            let (mut f, mut p) = (face, site.point.reduced());
            let mut j = [[1.0, 0.0], [0.0, 1.0]];
            let mut done = false;
            for (level, kept) in last.iter_mut().enumerate() {
                match self.resolve_kept(level, f, kept) {
                    Some(Resolved::Children { children, layout }) => {
                        let (child, at, [fu, fv]) = layout.child_of(p);
                        f = FaceId::new((children.start + child) as u32);
                        p = at;
                        j = j.map(|[a, b]| [a * fu, b * fv]);
                    }
                    Some(Resolved::Patch { patch, frame, .. }) => {
                        let (ids, len) =
                            *patches.entry((level, f.index() as u32)).or_insert_with(|| patch_ids(patch, &mut out.ids));
                        let (ju, jv) = frame.chain(j);
                        out.assigned.push((i as u32, out.records.len() as u32));
                        // A point of a level-0 patch's own dual grid reads the shared table.
                        let table = if level == 0 && reads_table(patch) {
                            dual_table(&self.tables, patch, frame.to_patch(site.point), rates[site.face as usize])
                        } else {
                            None
                        };
                        if let Some((table, index)) = table {
                            out.records.push(Record { level: 0, ids, len, weights: index, table, ju, jv });
                            out.places.push(Place { patch: (0, f.index() as u32), at: site.point, grid: None });
                            done = true;
                            break;
                        }
                        // Points at the same place of the same patch shape (the same sub-face
                        // point on every face of the cube) share one copy of their weights.
                        let matrices = Arc::as_ptr(&patch.matrices) as usize;
                        let at = frame.to_patch(p);
                        let key = (matrices, patch.shape, at);
                        let (weights, table) = self.stencil_weights(key, patch, evaluators, &mut shared, &mut out)?;
                        out.records.push(Record { level: level as u32, ids, len, weights, table, ju, jv });
                        let grid = if level > 0 && len == 16 { bicubic_grid_of(patch, evaluators) } else { None };
                        out.places.push(Place { patch: (level as u32, f.index() as u32), at, grid });
                        done = true;
                        break;
                    }
                    _ => break,
                }
            }
            if !done {
                return Err(TessError::Internal(format!("{face}: no patch holds point {:?}", site.point)));
            }
        }
        Ok(out)
    }

    /// The weights of the stencil at `key` (matrices, shape, point in the patch's frame) of
    /// `patch`: a kept stencil's (`NO_TABLE`), or one of the chunk's fresh ones (`FRESH`,
    /// solved now unless `shared` has it already).
    pub(super) fn stencil_weights(
        &self,
        key: (usize, usize, Dyadic),
        patch: &subdiv_schemes::FoundPatch,
        evaluators: &mut Evaluators,
        shared: &mut HashMap<(usize, usize, Dyadic), u32>,
        out: &mut Chunk,
    ) -> Result<(u32, u32), TessError> {
        if let Some(&w) = self.stencil_index.get(&key) {
            return Ok((w, NO_TABLE));
        }
        if let Some(&k) = shared.get(&key) {
            return Ok((k, FRESH));
        }
        let evaluator =
            evaluators.stencils.entry(key.0).or_insert_with(|| StencilEvaluator::new(patch.matrices.clone()));
        let stencil = evaluator.stencil(patch.shape, key.2)?;
        let k = out.fresh.len() as u32;
        out.fresh.push((key, out.weights.len() as u32));
        let pad = padded(stencil.position.len());
        for row in [&stencil.position, &stencil.du, &stencil.dv] {
            out.weights.extend_from_slice(row);
            out.weights.resize(out.weights.len() + pad - row.len(), 0.0);
        }
        shared.insert(key, k);
        Ok((k, FRESH))
    }

    /// `f`'s resolution on `level`, kept in `kept` for the next point (neighbouring points
    /// share their faces).
    fn resolve_kept<'a>(
        &'a self,
        level: usize,
        f: FaceId,
        kept: &mut Option<(FaceId, Option<Resolved<'a>>)>,
    ) -> Option<Resolved<'a>> {
        match kept {
            Some((g, r)) if *g == f => r.clone(),
            _ => {
                let r = self.levels.resolve(level, f);
                *kept = Some((f, r.clone()));
                r
            }
        }
    }

    /// A general-route vertex on the current cage.
    #[inline(always)]
    pub(super) fn general(&self, r: &Record) -> (DVec3, DVec3, DVec3) {
        let points = &self.positions[r.level as usize];
        let len = r.len as usize;
        let ids = &self.ids[r.ids as usize..r.ids as usize + len];
        if r.table != NO_TABLE {
            let mut gathered = [DVec3::ZERO; MAX_GATHER];
            for (g, &id) in gathered.iter_mut().zip(ids) {
                *g = points[id as usize];
            }
            let [p, s, t] =
                self.tables.tables[r.table as usize].apply(Grid::Dual, r.weights as usize, &gathered[..len]);
            return (p, r.ju[0] * s + r.ju[1] * t, r.jv[0] * s + r.jv[1] * t);
        }
        let pad = padded(len);
        let ids = &self.ids[r.ids as usize..r.ids as usize + pad];
        let w = &self.weights[r.weights as usize..r.weights as usize + 3 * pad];
        let [p, s, t] = dot3(points, ids, w);
        (p, r.ju[0] * s + r.ju[1] * t, r.jv[0] * s + r.jv[1] * t)
    }
}

/// The 4 × 4 grid of `patch` if its shape's sub-patch matrices are bicubic and its stencils
/// are the tensor products over that grid (checked once per matrices and shape).
fn bicubic_grid_of(patch: &subdiv_schemes::FoundPatch, evaluators: &mut Evaluators) -> Option<[u8; 16]> {
    let matrices = Arc::as_ptr(&patch.matrices) as usize;
    if let Some(&grid) = evaluators.grids.get(&(matrices, patch.shape)) {
        return grid;
    }
    let grid = bicubic_grid(&patch.matrices, patch.shape).map(|g| g.map(|k| k as u8)).filter(|g| {
        let evaluator =
            evaluators.stencils.entry(matrices).or_insert_with(|| StencilEvaluator::new(patch.matrices.clone()));
        tensor_weights_match(evaluator, patch.shape, g)
    });
    evaluators.grids.insert((matrices, patch.shape), grid);
    grid
}

/// Runs of consecutive `spans` of at most [`CHUNK`] vertices in all (no span is longer).
fn chunks_of(spans: &[std::ops::Range<usize>]) -> Vec<&[std::ops::Range<usize>]> {
    let mut chunks = Vec::new();
    let (mut first, mut len) = (0, 0);
    for (k, span) in spans.iter().enumerate() {
        if len + span.len() > CHUNK {
            chunks.push(&spans[first..k]);
            (first, len) = (k, 0);
        }
        len += span.len();
    }
    if first < spans.len() {
        chunks.push(&spans[first..]);
    }
    chunks
}

/// `patch`'s control points appended to `ids`, padded to a multiple of [`LANES`] with the
/// first (its weights are 0): their first index and their number.
fn patch_ids(patch: &subdiv_schemes::FoundPatch, ids: &mut Vec<u32>) -> (u32, u32) {
    let start = ids.len();
    ids.extend(patch.vertices.iter().map(|v| v.index() as u32));
    let first = ids[start];
    ids.resize(start + padded(patch.vertices.len()), first);
    (start as u32, patch.vertices.len() as u32)
}
