//! Face types and their templates: the cell points of quad faces with the same resolution tree and cage rows, as combinations of the face's own cage points.

use super::*;

/// A face's patch, in the order of [`Evaluator::face_type`]: the patch (level, face on that
/// level), and the number of its first control point among the face's patches' points (all
/// the face's patches' points in order) and its control point count.
#[derive(Clone, Copy, Debug)]
pub(super) struct FacePatch {
    pub(super) patch: (u32, u32),
    pub(super) first: u32,
    pub(super) len: u32,
}

/// The cage rows [`Evaluator::cage_rows`] has composed, by (level, vertex): valid for one
/// evaluator's levels.
#[derive(Debug, Default)]
pub(super) struct CageRowMemo {
    rows: Vec<(u32, f64)>,
    at: HashMap<(u32, u32), (u32, u32)>,
    terms: Vec<(u32, f64)>,
}

/// A quad face's type ([`Evaluator::find_face_types`]): its number, its range of
/// [`Evaluator::face_patches`], and its range of [`Evaluator::face_cage`] (the cage points its
/// patches depend on, in the type's canonical order).
#[derive(Clone, Copy, Debug)]
pub(super) struct FaceType {
    pub(super) id: u32,
    pub(super) patches: (u32, u32),
    pub(super) cage: (u32, u32),
}

/// The typed faces' [`FaceType`]s: per input face an index into them (4 bytes a face, made
/// only once a face has a type: a mesh of bicubic faces has none; an `Option<FaceType>` per
/// face was 28 MB of a million-face grid's peak).
#[derive(Debug, Default)]
pub(super) struct FaceTypes {
    index: Vec<u32>,
    types: Vec<FaceType>,
}

impl FaceTypes {
    const NONE: u32 = u32::MAX;

    /// Face `f`'s type, if it has one.
    #[inline]
    pub(super) fn get(&self, f: usize) -> Option<FaceType> {
        self.index.get(f).filter(|&&k| k != Self::NONE).map(|&k| self.types[k as usize])
    }

    /// Gives face `f` of the mesh's `faces` the type `ty`.
    fn set(&mut self, faces: usize, f: usize, ty: FaceType) {
        if self.index.is_empty() {
            self.index = vec![Self::NONE; faces];
        }
        self.index[f] = self.types.len() as u32;
        self.types.push(ty);
    }
}

/// The cell points of one face type at one rate as combinations of the face's cage points:
/// made by the first face of the type that descends (its records and patch grids, composed
/// down the refinement levels to the cage, with the chain-rule rows folded in), kept across
/// calls, and read by every face of the type with its own cage points.
#[derive(Clone, Debug, Default)]
pub(super) struct Template {
    /// Per group of [`LANES`] cell points (in the block's order, the last group padded with
    /// zeros), per row (position, `∂/∂u`, `∂/∂v`), per cage point `x` (in the type's order,
    /// `len` of them), the group's weights: `weights[((g · 3 + row) · len + x) · LANES + lane]`.
    pub(super) weights: Vec<f64>,
}

/// The most template weights (8 bytes each) one call uses, and [`Evaluator`] keeps into the
/// next: past it, faces take their own records (decided from the call's rates alone, so a
/// face's route, hence its bits, does not depend on earlier calls), and kept templates are
/// dropped at the start of a call.
pub(super) const MAX_TEMPLATE_WEIGHTS: usize = 1 << 24;

/// The most cage points a typed face may depend on (more: its own records).
pub(super) const MAX_TYPED_POINTS: usize = 64;

/// The deepest level a typed face's patches may lie on: the cube's corners need 2. Deeper
/// faces (next to semi-sharp features) take records: a face resolved on level `l` has up to
/// `4^l` patches, and its cage rows sum `25^l` paths per point (the bishop's sharpness 6 made
/// that minutes).
pub(super) const MAX_TYPED_LEVEL: usize = 2;

/// A template's key: the face type (or, with `Evaluator::copy_faces` off, the face, marked by
/// the flag) and the rate.
pub(super) type TemplateKey = (bool, u32, u32);

/// The weights of a [`Template`] at `rate` over `len` cage points.
pub(super) fn template_size(rate: u32, len: u32) -> usize {
    (rate as usize * rate as usize).div_ceil(LANES) * len as usize * 3 * LANES
}

impl Evaluator {
    /// Finds every quad face's type ([`Self::face_type`]; faces on the general route under a
    /// quad split), with its patches and the cage points they depend on.
    ///
    /// A type is the resolution tree up to vertex labels, and the cage rows of the patches'
    /// control points ([`Self::cage_rows`]) up to the order of the cage points: each cage point
    /// is named by its column (the points it enters, with their weights' bits), and the cage
    /// points are put in the order of their columns. Two faces of one type then have equal
    /// cage rows point for point, column for column, and their cell points are the same
    /// combinations of their own cage points.
    pub(super) fn find_face_types(&mut self) {
        let mesh = self.levels.mesh(0);
        self.face_types = FaceTypes::default();
        if self.levels.split() != Split::Quad {
            return;
        }
        let mut types: HashMap<Vec<u64>, u32> = HashMap::new();
        let (mut signature, mut patches) = (Vec::new(), Vec::new());
        let (mut rows, mut starts, mut columns, mut order) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut bucket: Vec<usize> = Vec::new();
        // Per cage vertex, its place in the current face's support (a search per row entry was
        // half of this pass).
        let mut places = vec![u32::MAX; mesh.vertex_count()];
        let mut support = Vec::new();
        let mut memo = CageRowMemo::default();
        let mut wide = HashMap::new();
        for f in mesh.face_ids() {
            if !matches!(self.faces[f.index()], FacePlan::General) {
                continue;
            }
            signature.clear();
            patches.clear();
            if !self.face_type(0, f, &mut signature, &mut patches)
                || self.reads_a_wide_point(&patches, &mut wide)
                || self.cage_support(&patches, &mut support) > MAX_TYPED_POINTS
            {
                continue;
            }
            self.cage_rows(&patches, &mut rows, &mut starts, &mut memo);
            // Each cage point's column: (point, weight bits) by point, bucketed by the cage
            // point's place in the support (each row names a cage point at most once, and the
            // points are visited in order, so every column comes out sorted).
            let cage = &support[0];
            for (i, &c) in cage.iter().enumerate() {
                places[c as usize] = i as u32;
            }
            let place = |x: u32| places[x as usize] as usize;
            bucket.clear();
            bucket.resize(cage.len() + 1, 0);
            for &(x, _) in &rows {
                bucket[place(x) + 1] += 1;
            }
            for i in 1..bucket.len() {
                bucket[i] += bucket[i - 1];
            }
            columns.clear();
            columns.resize(rows.len(), (0, 0));
            for (point, w) in starts.windows(2).enumerate() {
                for &(x, r) in &rows[w[0] as usize..w[1] as usize] {
                    let at = &mut bucket[place(x)];
                    columns[*at] = (point as u32, r.to_bits());
                    *at += 1;
                }
            }
            for &c in cage {
                places[c as usize] = u32::MAX;
            }
            // `bucket[i]` is now where column `i` ends.
            order.clear();
            order.extend((0..cage.len()).map(|i| (if i == 0 { 0 } else { bucket[i - 1] }, bucket[i], cage[i])));
            // The support counted above is these points.
            debug_assert!(order.len() <= MAX_TYPED_POINTS && order.iter().all(|&(a, b, _)| a < b));
            let column = |&(a, b, _): &(usize, usize, u32)| &columns[a..b];
            order.sort_unstable_by(|a, b| column(a).cmp(column(b)).then(a.2.cmp(&b.2)));
            signature.extend([5, order.len() as u64]);
            for range in &order {
                signature.push((range.1 - range.0) as u64);
                signature.extend(column(range).iter().flat_map(|&(point, bits)| [u64::from(point), bits]));
            }
            let next = types.len() as u32;
            let id = *types.entry_ref(&signature).or_insert(next);
            let first = self.face_patches.len() as u32;
            self.face_patches.extend_from_slice(&patches);
            let cage = self.face_cage.len() as u32;
            self.face_cage.extend(order.iter().map(|&(_, _, x)| x));
            let ty = FaceType {
                id,
                patches: (first, self.face_patches.len() as u32),
                cage: (cage, self.face_cage.len() as u32),
            };
            self.face_types.set(mesh.face_count(), f.index(), ty);
        }
    }

    /// Whether a control point of `patches` alone depends on more cage points than a type
    /// holds: a point whose refinement row reads more than [`MAX_TYPED_POINTS`] points (an
    /// extraordinary vertex's own, and its ring's) has its support counted once, in `wide`, by
    /// (level, vertex). The faces around a vertex of valence `N` each hold it, and gathering each
    /// one's support took `O(N)` (a third of a tessellation at valence 3000); the first point of
    /// an extraordinary patch is its vertex, so the test is `O(1)` a face there.
    fn reads_a_wide_point(&self, patches: &[FacePatch], wide: &mut HashMap<(usize, u32), usize>) -> bool {
        let stencils = self.levels.stencils();
        patches.iter().any(|p| {
            let level = p.patch.0 as usize;
            level > 0
                && self.listed_patch(p).vertices.iter().any(|v| {
                    let v = v.index() as u32;
                    let count = match wide.get(&(level, v)) {
                        Some(&count) => count,
                        None if stencils[level - 1].row(v as usize).nth(MAX_TYPED_POINTS).is_none() => return false,
                        None => *wide.entry((level, v)).or_insert_with(|| self.point_support(level, v)),
                    };
                    count > MAX_TYPED_POINTS
                })
        })
    }

    /// The number of cage points vertex `v` of `level` depends on.
    fn point_support(&self, level: usize, v: u32) -> usize {
        let stencils = self.levels.stencils();
        let mut points = vec![v];
        for l in (1..=level).rev() {
            let mut parents: Vec<u32> =
                points.iter().flat_map(|&p| stencils[l - 1].row(p as usize).map(|(parent, _)| parent as u32)).collect();
            parents.sort_unstable();
            parents.dedup();
            points = parents;
        }
        points.len()
    }

    /// The patch of a [`FacePatch`] that [`Self::face_type`] listed.
    fn listed_patch(&self, p: &FacePatch) -> &subdiv_schemes::FoundPatch {
        let Some(Resolved::Patch { patch, .. }) = self.levels.resolve(p.patch.0 as usize, FaceId::new(p.patch.1))
        else {
            unreachable!("face_type lists patches")
        };
        patch
    }

    /// The number of cage points the control points of `patches` depend on (those that
    /// [`Self::cage_rows`] names, in `support[0]`, ascending): the support found level by level,
    /// each level's points once, in time linear in the stencils' sizes, where the cage rows
    /// follow every path. A face next to a vertex of valence `N` depends on its `2N + 1` ring,
    /// and its cage rows cost `O(N)` per control point: a valence-1000 disk spent 385 s on rows
    /// that the limit then refused.
    pub(super) fn cage_support(&self, patches: &[FacePatch], support: &mut Vec<Vec<u32>>) -> usize {
        let stencils = self.levels.stencils();
        let deepest = patches.iter().map(|p| p.patch.0 as usize).max().unwrap_or(0);
        support.iter_mut().for_each(Vec::clear);
        support.resize_with(support.len().max(deepest + 1), Vec::new);
        for p in patches {
            support[p.patch.0 as usize].extend(self.listed_patch(p).vertices.iter().map(|v| v.index() as u32));
        }
        for level in (1..=deepest).rev() {
            let (coarser, finer) = support.split_at_mut(level);
            let points = &mut finer[0];
            points.sort_unstable();
            points.dedup();
            for &v in points.iter() {
                coarser[level - 1].extend(stencils[level - 1].row(v as usize).map(|(parent, _)| parent as u32));
            }
        }
        let cage = &mut support[0];
        cage.sort_unstable();
        cage.dedup();
        cage.len()
    }

    /// The control points of `patches` (in order, each patch's in its order) as combinations
    /// of the cage: point `k`'s entries `(cage vertex, weight)` are
    /// `rows[starts[k]..starts[k + 1]]`, by vertex. Each entry sums the products of the
    /// refinement weights along the paths down to the cage (multiplied level by level) in the
    /// order of the products' bits, so that it does not depend on how the mesh numbers its
    /// vertices. A point's row depends only on its level and vertex, so `memo` keeps each one
    /// for the next patch that names it (neighbouring patches share most of their points).
    pub(super) fn cage_rows(
        &self,
        patches: &[FacePatch],
        rows: &mut Vec<(u32, f64)>,
        starts: &mut Vec<u32>,
        memo: &mut CageRowMemo,
    ) {
        fn expand(stencils: &[Stencils], level: usize, id: usize, w: f64, terms: &mut Vec<(u32, f64)>) {
            if level == 0 {
                terms.push((id as u32, w));
                return;
            }
            for (parent, x) in stencils[level - 1].row(id) {
                expand(stencils, level - 1, parent, w * x, terms);
            }
        }
        rows.clear();
        starts.clear();
        starts.push(0);
        for p in patches {
            let (level, patch) = (p.patch.0, self.listed_patch(p));
            for v in &patch.vertices {
                let key = (level, v.index() as u32);
                let (a, b) = match memo.at.get(&key) {
                    Some(&range) => range,
                    None => {
                        let terms = &mut memo.terms;
                        terms.clear();
                        expand(self.levels.stencils(), level as usize, v.index(), 1.0, terms);
                        terms.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.to_bits().cmp(&b.1.to_bits())));
                        let start = memo.rows.len();
                        for &(x, w) in terms.iter() {
                            match memo.rows[start..].last_mut() {
                                Some(last) if last.0 == x => last.1 += w,
                                _ => memo.rows.push((x, w)),
                            }
                        }
                        let range = (start as u32, memo.rows.len() as u32);
                        memo.at.insert(key, range);
                        range
                    }
                };
                rows.extend_from_slice(&memo.rows[a as usize..b as usize]);
                starts.push(rows.len() as u32);
            }
        }
    }

    /// Decides, per planned block, whether it reads its type's template
    /// ([`TemplateUse::Copy`], or [`Copied`](TemplateUse::Copied) if kept: its cell points
    /// [`Route::Template`], out of the chunks), makes it ([`Make`](TemplateUse::Make): the first block of a key
    /// without a template) or takes its own records (0).
    ///
    /// The (type, rate) pairs past the [`MAX_TEMPLATE_WEIGHTS`] budget, counted in block order
    /// over the call's pairs, take their own records: the decision depends on this call's
    /// rates only (not on the templates kept), so a face's bits do too.
    pub(super) fn plan_copies(&mut self) {
        let blocks = self.planned.len();
        self.block_templates.clear();
        self.block_templates.resize(blocks, TemplateUse::Own);
        if !self.typed_faces {
            return;
        }
        if self.template_weights > self.template_budget {
            self.drop_templates();
        }
        // Per (type, rate) of the call, in block order: whether it fits the budget (decided
        // for the whole call before a streamed one's chunks).
        let (mut fits, mut made) = (std::mem::take(&mut self.fits), std::mem::take(&mut self.made));
        made.clear();
        match &self.fixed_fits {
            Some(fixed) => fits.clone_from(fixed),
            None => {
                fits.clear();
                self.count_fits(self.planned.iter().copied(), &mut fits);
            }
        }
        for (b, &(face, rate)) in self.planned.iter().enumerate() {
            let Some(ty) = self.face_types.get(face as usize) else { continue };
            if !fits[&(ty.id, rate)] {
                continue;
            }
            let key = self.template_key(face, rate, ty);
            if let Some(&t) = self.template_index.get(&key) {
                self.block_templates[b] = TemplateUse::Copied(t);
            } else if made.insert(key) {
                self.block_templates[b] = TemplateUse::Make;
                continue;
            } else {
                self.block_templates[b] = TemplateUse::Copy;
            }
            self.copied[face as usize] = true;
        }
        (self.fits, self.made) = (fits, made);
    }

    /// Whether each (type, rate) of `blocks` (face and rate, in block order) fits the budget,
    /// into `fits`.
    fn count_fits(&self, blocks: impl Iterator<Item = (u32, u32)>, fits: &mut HashMap<(u32, u32), bool>) {
        let mut budget = self.template_budget;
        for (face, rate) in blocks {
            let Some(ty) = self.face_types.get(face as usize) else { continue };
            fits.entry((ty.id, rate)).or_insert_with(|| {
                let size = template_size(rate, ty.cage.1 - ty.cage.0);
                let fit = size <= budget;
                if fit {
                    budget -= size;
                }
                fit
            });
        }
    }

    /// Decides the template fits of a streamed call at `rates` over all its blocks (the whole
    /// quad faces, in order: the blocks of the whole topology), for its chunks to use; `None`
    /// (after the call) goes back to deciding per call.
    pub(crate) fn fix_fits(&mut self, rates: Option<&[u32]>) {
        self.fixed_fits = rates.map(|rates| {
            let blocks = (0..self.faces.len())
                .filter(|&f| self.domains[f].get() == Some(subdiv_stencil::FaceDomain::Quad))
                .map(|f| (f as u32, rates[f]));
            let mut fits = HashMap::new();
            self.count_fits(blocks, &mut fits);
            fits
        });
    }

    /// The key of the template of `face` (of type `ty`) at `rate`.
    pub(super) fn template_key(&self, face: u32, rate: u32, ty: FaceType) -> TemplateKey {
        if self.copy_faces { (false, ty.id, rate) } else { (true, face, rate) }
    }

    /// Forgets the templates.
    pub(super) fn drop_templates(&mut self) {
        self.templates.clear();
        self.template_index.clear();
        self.template_weights = 0;
    }

    /// Appends the resolution tree of `face` on `level` to `signature` (depth first: each
    /// node's kind; a patch's matrices, shape, size and frame), its patches to `patches`.
    /// Two quad faces with equal signatures reach every cell point through the same children
    /// to patches of the same shapes at the same points with the same derivative maps.
    /// `false` if the tree holds a face that is not a quad under a quad split, or no patch.
    pub(super) fn face_type(
        &self,
        level: usize,
        face: FaceId,
        signature: &mut Vec<u64>,
        patches: &mut Vec<FacePatch>,
    ) -> bool {
        if level > MAX_TYPED_LEVEL {
            return false;
        }
        match self.levels.resolve(level, face) {
            Some(Resolved::Children { children, layout }) => {
                if layout != Layout::Domain(FaceDomain::Quad) {
                    return false;
                }
                signature.extend([1, children.len() as u64]);
                children.into_iter().all(|c| self.face_type(level + 1, FaceId::new(c as u32), signature, patches))
            }
            Some(Resolved::Patch { patch, frame, .. }) => {
                // The frame as the images of three points (it is affine).
                let code = [(0, 0), (1, 0), (0, 1)].iter().fold(0u64, |code, &(u, v)| {
                    let p = frame.to_patch(Dyadic::new(u, v, 1));
                    code << 8 | ((p.u + 4) as u64) << 4 | (p.v + 4) as u64
                });
                signature.extend([
                    2,
                    Arc::as_ptr(&patch.matrices) as usize as u64,
                    patch.shape as u64,
                    patch.vertices.len() as u64,
                    code,
                ]);
                let first = patches.last().map_or(0, |p: &FacePatch| p.first + p.len);
                let len = patch.vertices.len() as u32;
                patches.push(FacePatch { patch: (level as u32, face.index() as u32), first, len });
                true
            }
            // Cell points without a patch cannot be composed.
            Some(Resolved::Hole) | None => false,
        }
    }

    /// The template of `block`'s face type at its rate, from its records and patch grids
    /// (`first..last` of `patch_grids`), just made by its own descent: each cell point's three
    /// rows over its patch's points (the position's and, through the chain-rule rows, those of
    /// `∂/∂u` and `∂/∂v`) composed with the cage rows of those points ([`Self::cage_rows`]),
    /// each sum in the order of the patch's points, so a face of the same type makes the same
    /// bits.
    pub(super) fn make_template(&self, block: &crate::dual::topology::Block, (first, last): (u32, u32)) -> Template {
        let ty = self.face_types.get(block.face as usize).expect("a typed face");
        let patches = &self.face_patches[ty.patches.0 as usize..ty.patches.1 as usize];
        let cage = &self.face_cage[ty.cage.0 as usize..ty.cage.1 as usize];
        let len = cage.len();
        let (mut rows, mut starts) = (Vec::new(), Vec::new());
        self.cage_rows(patches, &mut rows, &mut starts, &mut CageRowMemo::default());
        for entry in &mut rows {
            entry.0 = cage.iter().position(|&c| c == entry.0).expect("a cage point of the face") as u32;
        }
        let index = |patch: (u32, u32)| patches.iter().find(|p| p.patch == patch).expect("the face's own patch");
        let mut weights = vec![0.0; template_size(block.rate, len as u32)];
        // Adds cell `k`'s rows over patch `p`'s points.
        let mut add = |k: usize, p: &FacePatch, [wp, ws, wt]: [&[f64]; 3], ju: [f64; 2], jv: [f64; 2]| {
            let (g, lane) = (k / LANES, k % LANES);
            for j in 0..p.len as usize {
                let (du, dv) = (ju[0] * ws[j] + ju[1] * wt[j], jv[0] * ws[j] + jv[1] * wt[j]);
                let point = p.first as usize + j;
                for &(x, r) in &rows[starts[point] as usize..starts[point + 1] as usize] {
                    let at = (g * 3 * len + x as usize) * LANES + lane;
                    weights[at] += wp[j] * r;
                    weights[at + len * LANES] += du * r;
                    weights[at + 2 * len * LANES] += dv * r;
                }
            }
        };
        let base = block.base as usize;
        let mut w = [Vec::new(), Vec::new(), Vec::new()];
        for g in &self.patch_grids[first as usize..last as usize] {
            let p = index(g.patch);
            let (ns, nt) = (g.s as usize, g.t as usize);
            let (ss, ts) = self.grid_basis[g.basis as usize..g.basis as usize + ns + nt].split_at(ns);
            for (b, [bt, dt]) in ts.iter().enumerate() {
                for (a, [bs, ds]) in ss.iter().enumerate() {
                    // The tensor-product weights over the patch's points, as the grid evaluates.
                    for row in &mut w {
                        row.clear();
                        row.resize(p.len as usize, 0.0);
                    }
                    for (k, &c) in g.grid.iter().enumerate() {
                        let (i, j, c) = (k % 4, k / 4, usize::from(c));
                        (w[0][c], w[1][c], w[2][c]) = (bs[i] * bt[j], ds[i] * bt[j], bs[i] * dt[j]);
                    }
                    let v = self.grid_vertices[g.vertices as usize + b * ns + a] as usize;
                    add(v - base, p, [&w[0], &w[1], &w[2]], g.ju, g.jv);
                }
            }
        }
        for (k, &route) in self.routes[base..base + block.len() as usize].iter().enumerate() {
            // The other cells are in patch grids.
            let Route::Record(record) = route.get() else { continue };
            let (r, place) = (&self.records[record as usize], &self.places[record as usize]);
            let p = index(place.patch);
            if r.table == NO_TABLE {
                let pad = padded(r.len as usize);
                let w = &self.weights[r.weights as usize..r.weights as usize + 3 * pad];
                add(k, p, [&w[..pad], &w[pad..2 * pad], &w[2 * pad..]], r.ju, r.jv);
            } else {
                let s = self.tables.tables[r.table as usize].stencil(Grid::Dual, r.weights as usize);
                add(k, p, [&s.position, &s.du, &s.dv], r.ju, r.jv);
            }
        }
        Template { weights }
    }
}
