//! The rules every [`EvaluationPlan`] meets, checked before an evaluator elsewhere (the
//! GPU's upload) indexes its arrays.

use super::*;

impl EvaluationPlan {
    /// Checks every rule an evaluator relies on, so that evaluating the plan indexes only what
    /// exists and computes with finite numbers:
    /// - the refinement: `refine_ids` and `refine_weights` have one length, the rows start at
    ///   0, never go back and end at that length; the levels follow each other from
    ///   `cage_len` to [`point_count`](Self::point_count); each refined point's row reads only
    ///   the level before (the cage, for the first level);
    /// - every point index of a patch names a point, and every weight, parameter and
    ///   chain-rule entry is finite;
    /// - every record's run of point indices (16 for bicubic patches, `len` for stencils) and
    ///   of weights (3 · `len`) lies inside its array; stencils have at least one point;
    /// - every entry names a record that exists; a block's rate is at least 1, its cells
    ///   (`base..base + rate²`) are output vertices, and they are exactly the vertices whose
    ///   entry names it.
    ///
    /// A plan from [`DualTessellator::evaluation_plan`](crate::DualTessellator::evaluation_plan)
    /// passes; evaluators of plans from elsewhere (the GPU's upload) check first.
    ///
    /// # Errors
    /// The first rule broken, naming the item ([`PlanItem`]) that breaks it.
    pub fn validate(&self) -> Result<(), PlanError> {
        let len = |n: usize| n as u64;
        let (cage, points) = (self.cage_len as usize, self.point_count());
        // The refinement.
        if self.refine_weights.len() != self.refine_ids.len() {
            return Err(PlanError::Length {
                at: PlanItem::Plan,
                what: "the number of refinement weights",
                got: len(self.refine_weights.len()),
                expected: len(self.refine_ids.len()),
            });
        }
        if let (Some(&first), Some(&last)) = (self.refine_rows.first(), self.refine_rows.last()) {
            if first != 0 {
                return Err(PlanError::Length {
                    at: PlanItem::Plan,
                    what: "the first refinement row's start",
                    got: first.into(),
                    expected: 0,
                });
            }
            if last as usize != self.refine_ids.len() {
                return Err(PlanError::Length {
                    at: PlanItem::Plan,
                    what: "the last refinement row's end",
                    got: last.into(),
                    expected: len(self.refine_ids.len()),
                });
            }
        }
        let mut previous = 0..cage;
        for (k, level) in self.levels.iter().enumerate() {
            if level.start as usize != previous.end {
                return Err(PlanError::Length {
                    at: PlanItem::Level(k),
                    what: "the first point",
                    got: level.start.into(),
                    expected: len(previous.end),
                });
            }
            if level.end < level.start || level.end as usize > points {
                return Err(PlanError::OutOfRange {
                    at: PlanItem::Level(k),
                    what: "the end",
                    index: level.end.into(),
                    valid: u64::from(level.start)..len(points) + 1,
                });
            }
            let here = level.start as usize..level.end as usize;
            for p in here.clone() {
                let (start, end) = (self.refine_rows[p - cage], self.refine_rows[p - cage + 1]);
                if end < start {
                    return Err(PlanError::Structure {
                        at: PlanItem::RefinedPoint(p),
                        rule: "its refinement row ends before it starts",
                    });
                }
                if end as usize > self.refine_ids.len() {
                    return Err(PlanError::PastEnd {
                        at: PlanItem::RefinedPoint(p),
                        array: "refinement rows' entries",
                        start: start.into(),
                        end: end.into(),
                        len: len(self.refine_ids.len()),
                    });
                }
                for e in start as usize..end as usize {
                    let id = self.refine_ids[e] as usize;
                    if !previous.contains(&id) {
                        return Err(PlanError::OutOfRange {
                            at: PlanItem::RefinedPoint(p),
                            what: "point (of the level before)",
                            index: len(id),
                            valid: len(previous.start)..len(previous.end),
                        });
                    }
                    finite(PlanItem::RefinedPoint(p), "weight", self.refine_weights[e])?;
                }
            }
            previous = here;
        }
        if previous.end != points {
            return Err(PlanError::Length {
                at: PlanItem::Plan,
                what: "the end of the last level",
                got: len(previous.end),
                expected: len(points),
            });
        }
        // The patches' points and the stencils' weights.
        for (k, &p) in self.points.iter().enumerate() {
            check_index(PlanItem::PatchPoint(k), "point", p, points)?;
        }
        for (k, &w) in self.weights.iter().enumerate() {
            finite(PlanItem::Weight(k), "weight", w)?;
        }
        // The records.
        let run = |at: PlanItem, array: &'static str, start: u32, count: u64, of: usize| {
            let end = u64::from(start) + count;
            if end > len(of) {
                return Err(PlanError::PastEnd { at, array, start: start.into(), end, len: len(of) });
            }
            Ok(())
        };
        let (vertices, patch_points) = (self.vertices.len(), self.points.len());
        for (k, b) in self.blocks.iter().enumerate() {
            let at = PlanItem::Block(k);
            if b.rate == 0 {
                return Err(PlanError::Structure { at, rule: "a rate of 0: a block without cells" });
            }
            run(at, "patch point indices", b.points, 16, patch_points)?;
            run(at, "cell vertices", b.base, u64::from(b.rate) * u64::from(b.rate), vertices)?;
            let cells = b.base as usize..b.base as usize + (b.rate as usize).pow(2);
            let own = pack(PLAN_BLOCK, k);
            if let Some(v) = cells.clone().find(|&v| self.vertices[v] != own) {
                return Err(PlanError::Structure {
                    at: PlanItem::Vertex(v),
                    rule: "a block's cell whose entry names another record",
                });
            }
        }
        for (k, b) in self.bicubic.iter().enumerate() {
            let at = PlanItem::Bicubic(k);
            run(at, "patch point indices", b.points, 16, patch_points)?;
            finite(at, "s", b.s)?;
            finite(at, "t", b.t)?;
            b.ju.iter().try_for_each(|&x| finite(at, "ju", x))?;
            b.jv.iter().try_for_each(|&x| finite(at, "jv", x))?;
        }
        for (k, g) in self.general.iter().enumerate() {
            let at = PlanItem::General(k);
            if g.len == 0 {
                return Err(PlanError::Structure { at, rule: "a stencil over no points" });
            }
            run(at, "patch point indices", g.points, g.len.into(), patch_points)?;
            run(at, "weights", g.weights, 3 * u64::from(g.len), self.weights.len())?;
            g.ju.iter().try_for_each(|&x| finite(at, "ju", x))?;
            g.jv.iter().try_for_each(|&x| finite(at, "jv", x))?;
        }
        // The entries.
        let counts = [self.blocks.len(), self.bicubic.len(), self.general.len()];
        for (v, &e) in self.vertices.iter().enumerate() {
            let (kind, index) = unpack(e);
            let Some(&count) = counts.get(kind as usize) else {
                return Err(PlanError::Structure { at: PlanItem::Vertex(v), rule: "an entry of no kind" });
            };
            check_index(PlanItem::Vertex(v), RECORD_NAMES[kind as usize], index, count)?;
            if kind == PLAN_BLOCK {
                let b = &self.blocks[index as usize];
                if !(b.base as usize..b.base as usize + (b.rate as usize).pow(2)).contains(&v) {
                    return Err(PlanError::Structure { at: PlanItem::Vertex(v), rule: "not one of its block's cells" });
                }
            }
        }
        Ok(())
    }
}

/// [`PlanError::OutOfRange`] unless `index < count`.
pub(super) fn check_index(at: PlanItem, what: &'static str, index: u32, count: usize) -> Result<(), PlanError> {
    if index as usize >= count {
        return Err(PlanError::OutOfRange { at, what, index: index.into(), valid: 0..count as u64 });
    }
    Ok(())
}

/// [`PlanError::NonFinite`] unless `value` is finite.
fn finite(at: PlanItem, what: &'static str, value: f64) -> Result<(), PlanError> {
    if !value.is_finite() {
        return Err(PlanError::NonFinite { at, what, value });
    }
    Ok(())
}
