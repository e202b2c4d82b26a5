//! Patch grids: cell points that fill a grid of a bicubic patch on a refined level, evaluated separably.

use super::*;

/// The points of one bicubic patch on a refined level that form a grid `s × t` in its frame
/// (the dual grid of a quad face over a regular descendant): evaluated separably, as the
/// level-0 blocks are, instead of one stencil per point.
#[derive(Clone, Debug)]
pub(super) struct PatchGrid {
    pub(super) level: u32,
    /// The patch (level, face on it), and its 4 × 4 grid (as [`Place::grid`]).
    pub(super) patch: (u32, u32),
    pub(super) grid: [u8; 16],
    /// Control points, `cv[j * 4 + i]` at `(i − 1, j − 1)` in the patch's frame.
    pub(super) cv: [u32; 16],
    /// The rows turning `(∂/∂s, ∂/∂t)` into the face's `(∂/∂u, ∂/∂v)`.
    pub(super) ju: [f64; 2],
    pub(super) jv: [f64; 2],
    /// The first of the basis and its derivative at each `s`, then at each `t`, in
    /// `grid_basis`.
    pub(super) basis: u32,
    /// The numbers of `s` and of `t`.
    pub(super) s: u32,
    pub(super) t: u32,
    /// The first vertex in `grid_vertices`: the output vertex at `(s[a], t[b])` is
    /// `grid_vertices[vertices + b · s + a]`.
    pub(super) vertices: u32,
}

/// Whether the exact stencil of the shape at a point without symmetry is the tensor product
/// of the cubic B-spline basis over `grid` (position and both derivatives, to 1e-12): then so
/// is every point's, the patch being bicubic, and the grid's orientation is the stencils'.
pub(super) fn tensor_weights_match(
    evaluator: &mut StencilEvaluator<Arc<PatchMatrices>>,
    shape: usize,
    grid: &[u8; 16],
) -> bool {
    let at = Dyadic::new(3, 5, 16);
    let Ok(stencil) = evaluator.stencil(shape, at) else { return false };
    let (s, t) = at.to_f64();
    let (bs, ds, bt, dt) = (basis(s), derivative(s), basis(t), derivative(t));
    (0..16).all(|k| {
        let (i, j) = (k % 4, k / 4);
        let g = usize::from(grid[k]);
        let want = [bs[i] * bt[j], ds[i] * bt[j], bs[i] * dt[j]];
        let got = [stencil.position[g], stencil.du[g], stencil.dv[g]];
        want.iter().zip(got).all(|(w, g)| (w - g).abs() <= 1e-12)
    })
}

/// The 4 × 4 grid of a shape if its sub-patch matrices are those of a bicubic B-spline.
pub(super) fn bicubic_grid(matrices: &PatchMatrices, shape: usize) -> Option<[usize; 16]> {
    let s = &matrices.shapes[shape];
    let grid = regular_grid(s.size, s.parameters.as_ref())?;
    check_bicubic(matrices, shape).then_some(grid)
}

impl Evaluator {
    /// Gathers, per quad face on the general route, the points of each bicubic patch on a
    /// refined level that form a full grid `s × t` in the patch's frame into a [`PatchGrid`]
    /// (the patch shapes' stencils checked once against the tensor products), and marks them
    /// [`Route::PatchGrid`]; the first face of a key without a template makes it from its records
    /// and grids ([`Self::make_template`]), then reads it as the others of its type do.
    pub(super) fn patch_grids(&mut self, topo: &Topology) {
        self.patch_grids.clear();
        self.block_grids.clear();
        self.grid_basis.clear();
        self.grid_params.clear();
        self.grid_vertices.clear();
        let mut scratch = GridScratch::default();
        for (b, block) in topo.blocks.iter().enumerate() {
            let first = self.patch_grids.len() as u32;
            let template = self.block_templates.get(b).copied().unwrap_or(TemplateUse::Own);
            if !template.copies() && matches!(self.faces[block.face as usize], FacePlan::General) {
                self.block_patch_grids(block, &mut scratch);
            }
            if template == TemplateUse::Make {
                let template = self.make_template(block, (first, self.patch_grids.len() as u32));
                let ty = self.face_types.get(block.face as usize).expect("a typed face");
                self.template_index.insert(self.template_key(block.face, block.rate, ty), self.templates.len() as u32);
                self.template_weights += template.weights.len();
                self.templates.push(template);
                // Its records and grids served the template: it reads the template too.
                if let Some(g) = self.patch_grids.get(first as usize) {
                    self.grid_vertices.truncate(g.vertices as usize);
                    self.grid_basis.truncate(g.basis as usize);
                    self.grid_params.truncate(g.basis as usize);
                    self.patch_grids.truncate(first as usize);
                }
                self.routes[block.base as usize..(block.base + block.len()) as usize].fill(Route::Template.into());
            }
            if template != TemplateUse::Own {
                let ty = self.face_types.get(block.face as usize).expect("a typed face");
                let t = self.template_index[&self.template_key(block.face, block.rate, ty)];
                self.block_templates[b] =
                    if template == TemplateUse::Make { TemplateUse::Made(t) } else { TemplateUse::Copied(t) };
            }
            self.block_grids.push((first, self.patch_grids.len() as u32));
        }
    }

    /// The [`PatchGrid`]s of the cells of `block` (a face on the general route): per distinct
    /// patch (few) its cells, by a counting sort (in vertex order within each), gathered into
    /// a grid where they form one.
    pub(super) fn block_patch_grids(&mut self, block: &crate::dual::topology::Block, scratch: &mut GridScratch) {
        let GridScratch { s, t, keys, group, starts, sorted } = scratch;
        keys.clear();
        group.clear();
        let base = block.base as usize;
        let mut last = usize::MAX;
        for v in base..base + (block.rate * block.rate) as usize {
            let Route::Record(record) = self.routes[v].get() else { continue };
            if self.places[record as usize].grid.is_none() {
                continue;
            }
            let key = self.places[record as usize].patch;
            if last == usize::MAX || keys[last] != key {
                last = keys.iter().position(|&k| k == key).unwrap_or_else(|| {
                    keys.push(key);
                    keys.len() - 1
                });
            }
            group.push((last as u32, v as u32));
        }
        starts.clear();
        starts.resize(keys.len() + 1, 0u32);
        for &(g, _) in group.iter() {
            starts[g as usize + 1] += 1;
        }
        for g in 0..keys.len() {
            starts[g + 1] += starts[g];
        }
        sorted.clear();
        sorted.resize(group.len(), 0u32);
        let mut next = starts.clone();
        for &(g, v) in group.iter() {
            sorted[next[g as usize] as usize] = v;
            next[g as usize] += 1;
        }
        for g in 0..keys.len() {
            let vertices = &sorted[starts[g] as usize..starts[g + 1] as usize];
            if let Some(grid) = self.patch_grid(vertices, s, t) {
                for &v in vertices {
                    self.routes[v as usize] = Route::PatchGrid.into();
                }
                self.patch_grids.push(grid);
            }
        }
    }

    /// The [`PatchGrid`] of `vertices` (records of one bicubic patch, whose shape's stencils were
    /// checked to be the tensor products over its grid) if they form a full grid with one
    /// derivative map;
    /// its bases and vertices are appended to `grid_basis` and `grid_vertices` (`s` and `t`:
    /// scratch).
    pub(super) fn patch_grid(&mut self, vertices: &[u32], s: &mut Vec<f64>, t: &mut Vec<f64>) -> Option<PatchGrid> {
        let (records, places, routes) = (&self.records, &self.places, &self.routes);
        let index = |v: u32| match routes[v as usize].get() {
            Route::Record(r) => r as usize,
            _ => unreachable!("patch grids gather records"),
        };
        let record = |v: u32| &records[index(v)];
        let place = |v: u32| &places[index(v)];
        let r0 = *record(vertices[0]);
        let grid = place(vertices[0]).grid?;
        s.clear();
        t.clear();
        for &v in vertices {
            let (a, b) = place(v).at.to_f64();
            // Few distinct values (at most the face's rate): a scan, then a sort of those.
            if !s.contains(&a) {
                s.push(a);
            }
            if !t.contains(&b) {
                t.push(b);
            }
        }
        s.sort_unstable_by(f64::total_cmp);
        t.sort_unstable_by(f64::total_cmp);
        if s.len() * t.len() != vertices.len() || s.len() < 2 || t.len() < 2 {
            return None;
        }
        let pad = padded(r0.len as usize);
        let ids0 = &self.ids[r0.ids as usize..r0.ids as usize + pad];
        let first = self.grid_vertices.len();
        self.grid_vertices.resize(first + vertices.len(), u32::MAX);
        let slots = &mut self.grid_vertices[first..];
        let fail = |this: &mut Self| {
            this.grid_vertices.truncate(first);
            None
        };
        for &v in vertices {
            let r = record(v);
            let same_patch = r.ids == r0.ids || self.ids[r.ids as usize..r.ids as usize + pad] == *ids0;
            if r.level != r0.level || r.len != r0.len || !same_patch || r.ju != r0.ju || r.jv != r0.jv {
                return fail(self);
            }
            let (u, w) = place(v).at.to_f64();
            let (Ok(a), Ok(b)) = (s.binary_search_by(|x| x.total_cmp(&u)), t.binary_search_by(|x| x.total_cmp(&w)))
            else {
                return fail(self);
            };
            let slot = &mut slots[b * s.len() + a];
            if *slot != u32::MAX {
                return fail(self);
            }
            *slot = v;
        }
        let at = self.grid_basis.len() as u32;
        self.grid_basis.extend(s.iter().chain(t.iter()).map(|&x| [basis(x), derivative(x)]));
        self.grid_params.extend(s.iter().chain(t.iter()));
        Some(PatchGrid {
            level: r0.level,
            patch: place(vertices[0]).patch,
            grid,
            cv: std::array::from_fn(|k| ids0[usize::from(grid[k])]),
            ju: r0.ju,
            jv: r0.jv,
            basis: at,
            s: s.len() as u32,
            t: t.len() as u32,
            vertices: first as u32,
        })
    }

    /// A [`PatchGrid`] on its level's points, row by row: `put(vertex, position, normal)`.
    #[inline(always)]
    pub(super) fn patch_grid_eval(
        &self,
        g: &PatchGrid,
        points: &[DVec3],
        (xs, cs): (&mut [DVec3; BATCH], &mut [DVec3; BATCH]),
        mut put: impl FnMut(u32, DVec3, DVec3),
    ) {
        let c: [DVec3; 16] = std::array::from_fn(|k| points[g.cv[k] as usize]);
        let (ns, nt) = (g.s as usize, g.t as usize);
        let (ss, ts) = self.grid_basis[g.basis as usize..g.basis as usize + ns + nt].split_at(ns);
        let vertices = &self.grid_vertices[g.vertices as usize..g.vertices as usize + ns * nt];
        let mut ks = [0u32; BATCH];
        let mut m = 0;
        for ([bt, dt], row) in ts.iter().zip(vertices.chunks_exact(ns)) {
            let (col, dcol) = (columns(&c, *bt), columns(&c, *dt));
            // By batches (across rows): positions and cross products, then the normalisations.
            for ([bs, ds], &v) in ss.iter().zip(row) {
                let (p, s, t) = (combine(*bs, &col), combine(*ds, &col), combine(*bs, &dcol));
                let (du, dv) = (g.ju[0] * s + g.ju[1] * t, g.jv[0] * s + g.jv[1] * t);
                (xs[m], cs[m], ks[m]) = (p, du.cross(dv), v);
                m += 1;
                if m == BATCH {
                    for ((x, c), &k) in xs.iter().zip(cs.iter()).zip(ks.iter()) {
                        put(k, *x, crate::unit_normal(*c));
                    }
                    m = 0;
                }
            }
        }
        for ((x, c), &k) in xs.iter().zip(cs.iter()).zip(ks.iter()).take(m) {
            put(k, *x, crate::unit_normal(*c));
        }
    }
}

/// [`Evaluator::block_patch_grids`]' buffers, kept across blocks.
#[derive(Debug, Default)]
pub(super) struct GridScratch {
    s: Vec<f64>,
    t: Vec<f64>,
    keys: Vec<(u32, u32)>,
    group: Vec<(u32, u32)>,
    starts: Vec<u32>,
    sorted: Vec<u32>,
}
