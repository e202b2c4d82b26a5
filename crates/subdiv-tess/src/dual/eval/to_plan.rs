//! The evaluation as plain arrays ([`EvaluationPlan`]) for evaluators elsewhere (the GPU).

use super::*;

impl Evaluator {
    /// The evaluation of `topo`'s vertices (prepared) as plain arrays: see [`EvaluationPlan`].
    pub(crate) fn plan(&self, topo: &Topology) -> EvaluationPlan {
        let mut plan = EvaluationPlan { cage_len: self.positions[0].len() as u32, ..EvaluationPlan::default() };
        let starts = self.plan_levels(&mut plan);
        plan.vertices = vec![UNSET; topo.point_count() as usize];
        self.plan_bicubic(topo, &starts, &mut plan);
        self.plan_typed(topo, &mut plan);
        self.plan_records(topo, &starts, &mut plan);
        plan
    }

    /// The refined levels' rows into `plan`; returns each level's first point in the one
    /// array of points.
    fn plan_levels(&self, plan: &mut EvaluationPlan) -> Vec<u32> {
        // Each level's first point in the one array of points.
        let mut starts = Vec::with_capacity(self.positions.len());
        let mut total = 0u32;
        for level in &self.positions {
            starts.push(total);
            total += level.len() as u32;
        }
        if !self.levels.stencils().is_empty() {
            plan.refine_rows.push(0);
            for (l, stencils) in self.levels.stencils().iter().enumerate() {
                for child in 0..stencils.child_count() {
                    for (parent, w) in stencils.row(child) {
                        plan.refine_ids.push(starts[l] + parent as u32);
                        plan.refine_weights.push(w);
                    }
                    plan.refine_rows.push(plan.refine_ids.len() as u32);
                }
                plan.levels.push(starts[l + 1]..starts[l + 1] + stencils.child_count() as u32);
            }
        }
        starts
    }

    /// The bicubic faces' blocks, the patch grids and the pointwise bicubic vertices.
    fn plan_bicubic(&self, topo: &Topology, starts: &[u32], plan: &mut EvaluationPlan) {
        let mut face_patches: HashMap<u32, u32> = HashMap::new();
        for block in &topo.blocks {
            if let Some(cv) = self.cv(block.face) {
                let at = plan.points.len() as u32;
                plan.points.extend_from_slice(&cv);
                face_patches.insert(block.face, at);
                let base = block.base as usize;
                let end = base + (block.rate * block.rate) as usize;
                plan.vertices[base..end].fill(crate::plan::pack(PLAN_BLOCK, plan.blocks.len()));
                plan.blocks.push(PlanBlock { base: block.base, rate: block.rate, points: at });
            }
        }
        for g in &self.patch_grids {
            let at = plan.points.len() as u32;
            plan.points.extend(g.cv.iter().map(|&c| starts[g.level as usize] + c));
            let (ns, nt) = (g.s as usize, g.t as usize);
            let params = &self.grid_params[g.basis as usize..g.basis as usize + ns + nt];
            for b in 0..nt {
                for a in 0..ns {
                    let v = self.grid_vertices[g.vertices as usize + b * ns + a];
                    plan.vertices[v as usize] = crate::plan::pack(PLAN_BICUBIC, plan.bicubic.len());
                    plan.bicubic.push(PlanBicubic { points: at, s: params[a], t: params[ns + b], ju: g.ju, jv: g.jv });
                }
            }
        }
        for &(v, face, [s, t]) in &self.pointwise {
            let Some(cv) = self.cv(face) else { unreachable!("bicubic face") };
            let at = *face_patches.entry(face).or_insert_with(|| {
                plan.points.extend_from_slice(&cv);
                plan.points.len() as u32 - 16
            });
            plan.vertices[v as usize] = crate::plan::pack(PLAN_BICUBIC, plan.bicubic.len());
            plan.bicubic.push(PlanBicubic { points: at, s, t, ju: [1.0, 0.0], jv: [0.0, 1.0] });
        }
    }

    /// The typed faces' cell points.
    fn plan_typed(&self, topo: &Topology, plan: &mut EvaluationPlan) {
        // The typed faces' cell points: their templates' rows (`∂/∂u` and `∂/∂v` already) over
        // their cage points, each template's cell once.
        let mut cells: HashMap<(u32, u32), u32> = HashMap::new();
        for (block, &t) in topo.blocks.iter().zip(&self.block_templates) {
            let Some(t) = t.template() else { continue };
            let template = &self.templates[t as usize];
            let ty = self.face_types.get(block.face as usize).expect("a typed face");
            let points = plan.points.len() as u32;
            plan.points.extend_from_slice(&self.face_cage[ty.cage.0 as usize..ty.cage.1 as usize]);
            let len = (ty.cage.1 - ty.cage.0) as usize;
            for k in 0..block.len() {
                let weights = *cells.entry((t, k)).or_insert_with(|| {
                    let at = plan.weights.len() as u32;
                    let (g, lane) = (k as usize / LANES, k as usize % LANES);
                    for row in 0..3 {
                        plan.weights
                            .extend((0..len).map(|x| template.weights[((g * 3 + row) * len + x) * LANES + lane]));
                    }
                    at
                });
                plan.vertices[(block.base + k) as usize] = crate::plan::pack(PLAN_GENERAL, plan.general.len());
                plan.general.push(PlanGeneral { points, len: len as u32, weights, ju: [1.0, 0.0], jv: [0.0, 1.0] });
            }
        }
    }

    /// The general records (every vertex not planned yet).
    fn plan_records(&self, topo: &Topology, starts: &[u32], plan: &mut EvaluationPlan) {
        // The general records' patches and weights, each once.
        let mut patches: HashMap<(u32, u32), u32> = HashMap::new();
        let mut weights: HashMap<(u32, u32), u32> = HashMap::new();
        for v in 0..topo.point_count() as usize {
            if plan.vertices[v] != UNSET {
                continue;
            }
            let Route::Record(record) = self.routes[v].get() else { unreachable!("vertex {v} has no plan") };
            let r = &self.records[record as usize];
            let len = r.len as usize;
            let points = *patches.entry((r.level, r.ids)).or_insert_with(|| {
                let ids = &self.ids[r.ids as usize..r.ids as usize + len];
                plan.points.extend(ids.iter().map(|&i| starts[r.level as usize] + i));
                plan.points.len() as u32 - r.len
            });
            let w = *weights.entry((r.table, r.weights)).or_insert_with(|| {
                let at = plan.weights.len() as u32;
                if r.table == NO_TABLE {
                    let pad = padded(len);
                    for row in 0..3 {
                        let start = r.weights as usize + row * pad;
                        plan.weights.extend_from_slice(&self.weights[start..start + len]);
                    }
                } else {
                    let stencil = self.tables.tables[r.table as usize].stencil(Grid::Dual, r.weights as usize);
                    for row in [&stencil.position, &stencil.du, &stencil.dv] {
                        plan.weights.extend_from_slice(row);
                    }
                }
                at
            });
            plan.vertices[v] = crate::plan::pack(PLAN_GENERAL, plan.general.len());
            plan.general.push(PlanGeneral { points, len: r.len, weights: w, ju: r.ju, jv: r.jv });
        }
    }
}

/// A vertex not planned yet.
const UNSET: u32 = u32::MAX;
