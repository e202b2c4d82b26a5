//! `EvaluationPlan`'s checks: a plan taken apart and put together is the same plan, and a
//! malformed one is refused with the rule it breaks and where, never a panic.

use subdiv_mesh::{Mesh, shapes};
use subdiv_schemes::Builtin;
use subdiv_tess::dual::{EvaluationPlan, PlanBicubic, PlanEntry, PlanError, PlanItem, PlanParts, PlanRecord};
use subdiv_tess::{DualOptions, DualTessellator};

/// The built-in model's vertex count: its first refined point.
const CAGE: usize = 62;

/// A plan with refined levels and exact stencils: the built-in model (its faces at extraordinary
/// vertices have their patches on refined levels) at mixed rates.
fn refined() -> PlanParts {
    let mesh = Mesh::build(shapes::default_model()).unwrap();
    let plan = plan_of(&mesh);
    assert!(!plan.levels().is_empty() && plan.entries().all(|e| matches!(e, PlanEntry::General(_))));
    assert_eq!(plan.cage_len(), CAGE);
    plan.into_parts()
}

/// A plan with every kind of entry: a grid's blocks (inner faces) and stencils (the border),
/// with its first block rewritten as bicubic points at the same parameters.
fn grid() -> PlanParts {
    let mesh = Mesh::build(shapes::quad_grid(6, 6)).unwrap();
    let plan = plan_of(&mesh);
    let mut parts = plan.clone().into_parts();
    let b = parts.blocks.remove(0);
    // Renumbered (block 0's own cells are rewritten below).
    for record in &mut parts.vertices {
        if let PlanRecord::Block(k) = record {
            *k = k.saturating_sub(1);
        }
    }
    for j in 0..b.rate {
        for i in 0..b.rate {
            let (s, t) = ((f64::from(i) + 0.5) / f64::from(b.rate), (f64::from(j) + 0.5) / f64::from(b.rate));
            parts.vertices[(b.base + j * b.rate + i) as usize] = PlanRecord::Bicubic(parts.bicubic.len() as u32);
            parts.bicubic.push(PlanBicubic { points: b.points, s, t, ju: [1.0, 0.0], jv: [0.0, 1.0] });
        }
    }
    // Still a plan, and the same surface.
    let rewritten = EvaluationPlan::from_parts(parts.clone()).unwrap();
    let [a, b] = [&plan, &rewritten].map(|p| {
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        p.evaluate(mesh.positions(), &mut positions, &mut normals);
        positions
    });
    assert!(a.iter().zip(&b).all(|(p, q)| p.distance(*q) < 1e-12));
    let has = |kind: fn(&PlanEntry<'_>) -> bool| rewritten.entries().any(|e| kind(&e));
    assert!(has(|e| matches!(e, PlanEntry::Block(_))) && has(|e| matches!(e, PlanEntry::General(_))));
    parts
}

fn plan_of(mesh: &Mesh) -> EvaluationPlan {
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), mesh, &DualOptions::default()).unwrap();
    let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 2 + f % 4).collect();
    tess.tessellate(&rates).unwrap();
    tess.evaluation_plan()
}

/// `parts`, broken by `change`, refused by `from_parts` with an error `expected` accepts;
/// `from_parts_unchecked` then `validate` find the same.
fn refused(
    name: &str,
    mut parts: PlanParts,
    change: impl FnOnce(&mut PlanParts),
    expected: impl Fn(&PlanError) -> bool,
) {
    change(&mut parts);
    let error = EvaluationPlan::from_parts(parts.clone()).expect_err(name);
    assert!(expected(&error), "{name}: {error:?}");
    // The message names the item.
    assert!(error.to_string().starts_with("evaluation plan"), "{name}: {error}");
    if let Ok(unchecked) = EvaluationPlan::from_parts_unchecked(parts) {
        // (Compared as text: NaN values are not equal to themselves.)
        assert_eq!(unchecked.validate().map_err(|e| e.to_string()), Err(error.to_string()), "{name}");
    }
}

#[test]
fn a_plan_taken_apart_is_put_together_again() {
    for parts in [refined(), grid()] {
        let plan = EvaluationPlan::from_parts(parts.clone()).unwrap();
        assert_eq!(plan.vertex_count(), parts.vertices.len());
        for (record, entry) in parts.vertices.iter().zip(plan.entries()) {
            match (record, entry) {
                (PlanRecord::Block(k), PlanEntry::Block(b)) => assert_eq!(&parts.blocks[*k as usize], b),
                (PlanRecord::Bicubic(k), PlanEntry::Bicubic(b)) => assert_eq!(&parts.bicubic[*k as usize], b),
                (PlanRecord::General(k), PlanEntry::General(g)) => assert_eq!(&parts.general[*k as usize], g),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(plan.entry(plan.vertex_count()), None);
        assert_eq!(plan.clone().into_parts(), parts);
        // Over the cage: still a plan.
        plan.over_cage().validate().unwrap();
    }
    assert!(EvaluationPlan::default().validate().is_ok());
}

#[test]
fn malformed_plans_name_the_item_and_the_rule() {
    refused(
        "a NaN weight",
        refined(),
        |p| p.weights[5] = f64::NAN,
        |e| matches!(e, PlanError::NonFinite { at: PlanItem::Weight(5), what: "weight", .. }),
    );
    refused(
        "an infinite parameter",
        grid(),
        |p| p.bicubic[0].s = f64::INFINITY,
        |e| matches!(e, PlanError::NonFinite { at: PlanItem::Bicubic(0), what: "s", .. }),
    );
    refused(
        "a NaN chain-rule entry",
        refined(),
        |p| p.general[3].jv[1] = f64::NAN,
        |e| matches!(e, PlanError::NonFinite { at: PlanItem::General(3), what: "jv", .. }),
    );
    refused(
        "a point index past the points",
        refined(),
        |p| p.points[2] = 1 << 20,
        |e| matches!(e, PlanError::OutOfRange { at: PlanItem::PatchPoint(2), what: "point", index, .. } if *index == 1 << 20),
    );
    refused(
        "a stencil's weights past the end",
        refined(),
        |p| p.general[1].weights = p.weights.len() as u32,
        |e| matches!(e, PlanError::PastEnd { at: PlanItem::General(1), array: "weights", .. }),
    );
    refused(
        "a stencil's patch past the end",
        refined(),
        |p| p.general[0].points = u32::MAX,
        |e| matches!(e, PlanError::PastEnd { at: PlanItem::General(0), array: "patch point indices", .. }),
    );
    refused(
        "a stencil over no points",
        refined(),
        |p| p.general[2].len = 0,
        |e| matches!(e, PlanError::Structure { at: PlanItem::General(2), .. }),
    );
    refused(
        "a bicubic patch past the end",
        grid(),
        |p| p.bicubic[1].points = p.points.len() as u32 - 8,
        |e| matches!(e, PlanError::PastEnd { at: PlanItem::Bicubic(1), array: "patch point indices", .. }),
    );
    refused(
        "a block of rate 0",
        grid(),
        |p| p.blocks[0].rate = 0,
        |e| matches!(e, PlanError::Structure { at: PlanItem::Block(0), .. }),
    );
    refused(
        "a block past the vertices",
        grid(),
        |p| p.blocks[0].rate = u32::MAX,
        |e| matches!(e, PlanError::PastEnd { at: PlanItem::Block(0), array: "cell vertices", .. }),
    );
    refused(
        "a block whose cells are others' vertices",
        grid(),
        |p| p.blocks[0].base += 1,
        |e| matches!(e, PlanError::Structure { at: PlanItem::Vertex(_), .. }),
    );
    refused(
        "an entry naming no record",
        refined(),
        |p| p.vertices[7] = PlanRecord::General(p.general.len() as u32),
        |e| matches!(e, PlanError::OutOfRange { at: PlanItem::Vertex(7), what: "stencil point", .. }),
    );
    refused(
        "a vertex outside its block",
        grid(),
        |p| {
            let v = p.vertices.iter().position(|r| !matches!(r, PlanRecord::Block(_))).unwrap();
            p.vertices[v] = PlanRecord::Block(0);
        },
        |e| matches!(e, PlanError::Structure { at: PlanItem::Vertex(_), rule } if rule.contains("block's cells")),
    );
    refused(
        "refinement weights that disagree with the ids",
        refined(),
        |p| {
            p.refine_weights.pop();
        },
        |e| matches!(e, PlanError::Length { at: PlanItem::Plan, .. }),
    );
    refused(
        "a refinement row reading its own level",
        refined(),
        |p| {
            let own = p.levels[0].start;
            p.refine_ids[0] = own;
        },
        |e| matches!(e, PlanError::OutOfRange { at: PlanItem::RefinedPoint(_), what, .. } if what.contains("level before")),
    );
    refused(
        "a NaN refinement weight",
        refined(),
        |p| p.refine_weights[3] = f64::NAN,
        |e| matches!(e, PlanError::NonFinite { at: PlanItem::RefinedPoint(_), .. }),
    );
    refused(
        "a refinement row that ends before it starts",
        refined(),
        |p| p.refine_rows[1] = p.refine_rows[2] + 1,
        |e| matches!(e, PlanError::Structure { at: PlanItem::RefinedPoint(p), rule } if *p == CAGE + 1 && rule.contains("before it starts")),
    );
    refused(
        "a refinement row past the entries",
        refined(),
        |p| p.refine_rows[1] = p.refine_ids.len() as u32 + 5,
        |e| matches!(e, PlanError::PastEnd { at: PlanItem::RefinedPoint(CAGE), .. }),
    );
    refused(
        "a missing level",
        refined(),
        |p| {
            p.levels.pop();
        },
        |e| matches!(e, PlanError::Length { at: PlanItem::Plan, what, .. } if what.contains("last level")),
    );
    refused(
        "a cage of another size",
        refined(),
        |p| p.cage_len += 1,
        |e| matches!(e, PlanError::Length { at: PlanItem::Level(0), .. }),
    );
}
