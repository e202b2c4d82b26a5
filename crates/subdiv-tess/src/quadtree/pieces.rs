//! The quadtree's pieces of surface and their subdivision: a patch shape classified once
//! (bicubic, checked against its children's quarters, or extraordinary, with its limit
//! stencils), a root's piece (a refined face without a patch, the sub-patch at an
//! extraordinary corner, or a bicubic Bézier patch) and its quarters.

use super::*;

/// How a patch shape is tessellated.
#[derive(Clone, Debug)]
pub(super) enum ShapeKind {
    /// A bicubic polynomial: Bézier net point `k` (`net[j][i]` at `k = 4j + i`, in the
    /// patch's frame) is `Σ_m net[k · size + m] · points[m]` over the shape's `size` points.
    /// Regular interior patches, and the regular patches along an infinitely sharp crease or a
    /// boundary, whose rows across it are the crease rule's, not the B-spline's.
    Regular { net: Vec<f64> },
    /// A quartic triangle (a triangle split's polynomial patch: Loop's box spline, and its
    /// patches along creases and boundaries): Bézier point `k` ([`Quartic::index`]) is
    /// `Σ_m net[k · size + m] · points[m]`, in the patch's frame.
    Quartic { net: Vec<f64> },
    /// A shape that is no polynomial (a non-polynomial scheme's, such as `sw-quad`'s regular
    /// patch) but whose matrices, from it on, are convex combinations that reproduce linear
    /// functions of its control points' parameters: bounded by how far its control points are
    /// from an affine function of their parameters ([`flatness::linear_is_flat`]). With the
    /// position stencils of its square's points `(i/2, j/2)`, `sides[j][i]` (quads), which the
    /// budget's prediction tests its nodes' sides with.
    Linear { sides: Option<Box<SidePoints>> },
    /// The extraordinary vertex at corner 0: the child kept at the corner, and the vertex's
    /// limit position and tangent-direction stencils.
    Extraordinary { position: Vec<f64>, du: Vec<f64>, dv: Vec<f64> },
}

/// Position stencils at the points `(i/2, j/2)` of a square shape, `[j][i]`.
pub(super) type SidePoints = [[Vec<f64>; 3]; 3];

/// A set of sub-patch matrices and one of its shapes, identified by address.
pub(super) type ShapeKey = (usize, usize);

/// The surface over a node.
#[derive(Clone)]
pub(super) enum Piece {
    /// A face of refinement level `level` that reaches its patch through its children.
    Face { level: usize, face: FaceId },
    /// The sub-patch at the extraordinary corner, in the patch's frame.
    Extraordinary { matrices: Arc<PatchMatrices>, shape: usize, points: Vec<DVec3>, frame: PatchFrame },
    /// A sub-patch of a [`ShapeKind::Linear`] shape, in the patch's frame.
    Linear { matrices: Arc<PatchMatrices>, shape: usize, points: Vec<DVec3>, frame: PatchFrame },
    /// A polynomial piece, in the node's own coordinates (boxed: 384 bytes).
    Regular(Box<Bicubic>),
    /// A polynomial triangle, in the node's own coordinates.
    Quartic(Box<Quartic>),
}

/// How many levels below a linear piece its bound samples the control points
/// ([`linear_samples`]).
pub(super) const LINEAR_LEVELS: u32 = 2;

/// The control points of a linear piece's descendants `levels` levels down (those with
/// influence), with their parameters in the piece's frame: the surface over the piece is
/// theirs over domains that tile it, each a convex combination reproducing linear functions of
/// those parameters, so one affine fit bounds it as the piece's own points do, over a footprint
/// nearer the piece. `None` where a descendant has no parameters.
pub(super) fn linear_samples(
    matrices: &PatchMatrices,
    shape: usize,
    points: &[DVec3],
    levels: u32,
) -> Option<(Vec<DVec3>, [Vec<f64>; 2])> {
    let s = &matrices.shapes[shape];
    let [us, vs] = s.parameters.as_ref()?;
    if levels == 0 {
        let used: Vec<usize> = if s.influence.is_empty() {
            (0..points.len()).collect()
        } else {
            s.influence.iter().map(|&k| k as usize).collect()
        };
        let samples = used.iter().map(|&k| points[k]).collect();
        return Some((samples, [used.iter().map(|&k| us[k]).collect(), used.iter().map(|&k| vs[k]).collect()]));
    }
    let mut out = (Vec::new(), [Vec::new(), Vec::new()]);
    for child in &s.children {
        let (samples, [cu, cv]) = linear_samples(matrices, child.shape, &child.apply(points), levels - 1)?;
        out.0.extend(samples);
        for (u, v) in cu.into_iter().zip(cv) {
            let (pu, pv) = child.domain.to_parent(u, v);
            out.1[0].push(pu);
            out.1[1].push(pv);
        }
    }
    Some(out)
}

/// The quartic triangle, in the face's coordinates, of a shape with net weights `net` (see
/// [`ShapeKind::Quartic`]) over the control points `points`, in the patch's frame.
pub(super) fn quartic_in_frame(net: &[f64], points: &[DVec3], frame: PatchFrame) -> Quartic {
    let size = points.len();
    let point = |k: usize| -> DVec3 { net[k * size..(k + 1) * size].iter().zip(points).map(|(&w, &p)| w * p).sum() };
    // The frame maps the triangle onto itself: face control point (i, j) is the patch's at
    // to_patch(i/4, j/4).
    Quartic {
        net: quartic::per_point(|i, j| {
            let p = frame.to_patch(Dyadic::new(i as i64, j as i64, 4));
            point(Quartic::index(p.u as usize, p.v as usize))
        }),
    }
}

/// The Bézier net weights of the quartic that interpolates a triangle `shape`'s limit surface
/// at its 15 domain points `(i/4, j/4)` (its exact stencils): the shape's net if it is a
/// quartic.
fn candidate_quartic(
    evaluator: &mut StencilEvaluator<&PatchMatrices>,
    size: usize,
    shape: usize,
) -> Result<Vec<f64>, String> {
    let mut values = vec![0.0; quartic::POINTS * size];
    for (value, (i, j)) in values.chunks_exact_mut(size).zip(quartic::domain_points(4)) {
        let stencil = evaluator.stencil(shape, Dyadic::new(i as i64, j as i64, 4)).map_err(|e| e.to_string())?;
        value.copy_from_slice(&stencil.position);
    }
    let inverse = quartic::collocation_inverse();
    let mut net = vec![0.0; quartic::POINTS * size];
    for (b, row) in net.chunks_exact_mut(size).enumerate() {
        for (a, value) in values.chunks_exact(size).enumerate() {
            let w = inverse[b][a];
            row.iter_mut().zip(value).for_each(|(r, &x)| *r += w * x);
        }
    }
    Ok(net)
}

/// Whether every child of triangle `shape` is the matching sub-triangle of its quartic, on
/// every basis function, to `tolerance` (`net` as in [`children_are_quarters`]).
fn children_are_sub_triangles(
    matrices: &PatchMatrices,
    shape: usize,
    tolerance: f64,
    net: impl Fn(usize, &[DVec3]) -> Quartic,
) -> bool {
    let s = &matrices.shapes[shape];
    s.children.iter().all(|child| {
        (0..s.size).all(|k| {
            let basis: Vec<DVec3> = (0..s.size).map(|m| if m == k { DVec3::X } else { DVec3::ZERO }).collect();
            let expected = net(shape, &basis).child(child.domain.offset, child.domain.flipped);
            let mine = net(child.shape, &child.apply(&basis));
            mine.net.iter().zip(&expected.net).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max) <= tolerance
        })
    })
}

/// The Bézier net, in the face's coordinates, of a polynomial shape with net weights `net`
/// (see [`ShapeKind::Regular`]) over the control points `points`, in the patch's frame.
pub(super) fn bezier_in_frame(net: &[f64], points: &[DVec3], frame: PatchFrame) -> Bicubic {
    let size = points.len();
    let point = |k: usize| -> DVec3 { net[k * size..(k + 1) * size].iter().zip(points).map(|(&w, &p)| w * p).sum() };
    let patch: [[DVec3; 4]; 4] = std::array::from_fn(|j| std::array::from_fn(|i| point(4 * j + i)));
    // The frame is a turn of the unit square: face control point (i, j) is the patch's at
    // to_patch(i/3, j/3).
    let net = std::array::from_fn(|j| {
        std::array::from_fn(|i| {
            let p = frame.to_patch(Dyadic::new(i as i64, j as i64, 3));
            patch[p.v as usize][p.u as usize]
        })
    });
    Bicubic { net }
}

/// The collocation parameters of [`candidate_net`]: dyadic, so the exact stencils reach them,
/// and symmetric.
const NODES: [(i64, i64); 4] = [(0, 1), (1, 4), (3, 4), (1, 1)];

/// The inverse of the cubic Bernstein collocation matrix at [`NODES`]: `inverse[i][a]`.
fn bernstein_inverse() -> [[f64; 4]; 4] {
    let mut m: [[f64; 8]; 4] = std::array::from_fn(|a| {
        let (num, den) = NODES[a];
        let b = crate::bezier::bernstein3(num as f64 / den as f64);
        std::array::from_fn(|c| if c < 4 { b[c] } else { f64::from(u8::from(c - 4 == a)) })
    });
    // Gauss-Jordan with partial pivoting on [B | I]: rows a (nodes), columns i (degrees).
    for col in 0..4 {
        let pivot = (col..4).max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs())).unwrap_or(col);
        m.swap(col, pivot);
        let d = m[col][col];
        m[col].iter_mut().for_each(|x| *x /= d);
        for r in (0..4).filter(|&r| r != col) {
            let f = m[r][col];
            let pivot_row = m[col];
            m[r].iter_mut().zip(pivot_row).for_each(|(x, p)| *x -= f * p);
        }
    }
    std::array::from_fn(|i| std::array::from_fn(|a| m[i][4 + a]))
}

/// The Bézier net weights of the bicubic that interpolates `shape`'s limit surface at the
/// 4 × 4 parameters [`NODES`]² (its exact stencils): the shape's net if it is a bicubic.
fn candidate_net(
    evaluator: &mut StencilEvaluator<&PatchMatrices>,
    size: usize,
    shape: usize,
) -> Result<Vec<f64>, String> {
    let inverse = bernstein_inverse();
    let mut values = vec![0.0; 16 * size];
    for (b, &(vn, vd)) in NODES.iter().enumerate() {
        for (a, &(un, ud)) in NODES.iter().enumerate() {
            let d = ud.max(vd);
            let point = Dyadic::new(un * (d / ud), vn * (d / vd), d);
            let stencil = evaluator.stencil(shape, point).map_err(|e| e.to_string())?;
            values[(4 * b + a) * size..(4 * b + a + 1) * size].copy_from_slice(&stencil.position);
        }
    }
    // net[j][i] = Σ_{a,b} inverse[i][a] · inverse[j][b] · value(a, b).
    let mut net = vec![0.0; 16 * size];
    for j in 0..4 {
        for i in 0..4 {
            let row = &mut net[(4 * j + i) * size..(4 * j + i + 1) * size];
            for b in 0..4 {
                for a in 0..4 {
                    let w = inverse[i][a] * inverse[j][b];
                    let value = &values[(4 * b + a) * size..(4 * b + a + 1) * size];
                    row.iter_mut().zip(value).for_each(|(r, &x)| *r += w * x);
                }
            }
        }
    }
    Ok(net)
}

/// Whether every child of `shape` is the matching de Casteljau quarter of its net, on every
/// basis function, to `tolerance`: `net(shape, points)` gives a shape's Bézier net over its
/// control points (`None`: it has none, and the check fails).
fn children_are_quarters(
    matrices: &PatchMatrices,
    shape: usize,
    tolerance: f64,
    net: impl Fn(usize, &[DVec3]) -> Option<Bicubic>,
) -> bool {
    let s = &matrices.shapes[shape];
    s.children.iter().all(|child| {
        !child.domain.flipped
            && (0..s.size).all(|k| {
                let basis: Vec<DVec3> = (0..s.size).map(|m| if m == k { DVec3::X } else { DVec3::ZERO }).collect();
                let [qx, qy] = child.domain.offset.map(usize::from);
                let (Some(parent), Some(mine)) = (net(shape, &basis), net(child.shape, &child.apply(&basis))) else {
                    return false;
                };
                let expected = parent.quarter(qx, qy);
                let diff =
                    mine.net.iter().flatten().zip(expected.net.iter().flatten()).map(|(a, b)| (*a - *b).length());
                diff.fold(0.0, f64::max) <= tolerance
            })
    })
}

/// Classifies every shape of `matrices`, checking what the bounds need.
///
/// A shape is a bicubic when the net interpolating its exact surface at 16 points
/// ([`candidate_net`]) splits into its children's nets (de Casteljau quarters) and so do all
/// its descendants': then the net agrees with the surface at every dyadic point (each
/// descendant's net interpolates it at its corners), so everywhere. The set is the largest one
/// closed under children. A shape that is none is [`ShapeKind::Linear`] when it has parameters
/// (its matrices reproduce linear functions of them) and its matrices and its descendants' are
/// convex combinations, the largest such set closed under children. Every other shape must
/// keep an extraordinary corner whose sub-patch matrices are convex combinations (the hull
/// bound), its other children polynomials or linear ones.
pub(super) fn classify(matrices: &Arc<PatchMatrices>, out: &mut HashMap<ShapeKey, ShapeKind>) -> Result<(), String> {
    let id = Arc::as_ptr(matrices) as usize;
    if out.contains_key(&(id, 0)) {
        return Ok(());
    }
    let shapes = &matrices.shapes;
    // A triangle split's shapes have a flipped middle child.
    let triangle = shapes.iter().any(|s| s.children.iter().any(|c| c.domain.flipped));
    let mut evaluator = StencilEvaluator::new(&**matrices);
    let candidate = if triangle { candidate_quartic } else { candidate_net };
    let nets: Vec<Vec<f64>> =
        (0..shapes.len()).map(|s| candidate(&mut evaluator, shapes[s].size, s)).collect::<Result<_, _>>()?;
    let net_of = |shape: usize, points: &[DVec3]| Some(bezier_in_frame(&nets[shape], points, PatchFrame::new(4, 0)));
    let quartic_of = |shape: usize, points: &[DVec3]| quartic_in_frame(&nets[shape], points, PatchFrame::new(3, 0));
    let mut polynomial: Vec<bool> = (0..shapes.len())
        .map(|s| {
            if triangle {
                children_are_sub_triangles(matrices, s, 1e-11, quartic_of)
            } else {
                children_are_quarters(matrices, s, 1e-11, net_of)
            }
        })
        .collect();
    close_under_children(matrices, &mut polynomial, |_| false);
    let convex = |s: usize| {
        shapes[s]
            .children
            .iter()
            .all(|child| (0..child.rows()).all(|r| is_convex_combination(child.row(r).map(|e| e.1))))
    };
    let mut linear: Vec<bool> =
        (0..shapes.len()).map(|s| !polynomial[s] && shapes[s].parameters.is_some() && convex(s)).collect();
    close_under_children(matrices, &mut linear, |c| polynomial[c]);
    for (shape, net) in nets.into_iter().enumerate() {
        if polynomial[shape] {
            out.insert((id, shape), if triangle { ShapeKind::Quartic { net } } else { ShapeKind::Regular { net } });
            continue;
        }
        // A shape that keeps itself at corner 0 alone has its special point there (an
        // extraordinary vertex, a dart, a sharp corner): the hull bound, and rings in the dual
        // method, whatever its parameters; one that is itself everywhere (a non-polynomial
        // scheme's regular patch) is linear.
        let corner_only = matches!(matrices.keeping(shape), Some((_, keep)) if keep.domain.offset == [0, 0])
            && shapes[shape].children.iter().any(|c| c.shape != shape);
        if linear[shape] && !corner_only {
            let mut at = |i: usize, j: usize| {
                evaluator.stencil(shape, Dyadic::new(i as i64, j as i64, 2)).ok().map(|s| s.position.clone())
            };
            let sides = (!triangle)
                .then(|| -> Option<SidePoints> {
                    let mut rows: [[Vec<f64>; 3]; 3] = Default::default();
                    for (j, row) in rows.iter_mut().enumerate() {
                        for (i, cell) in row.iter_mut().enumerate() {
                            *cell = at(i, j)?;
                        }
                    }
                    Some(rows)
                })
                .flatten()
                .map(Box::new);
            out.insert((id, shape), ShapeKind::Linear { sides });
            continue;
        }
        let s = &shapes[shape];
        let (_, keep) = matrices
            .keeping(shape)
            .ok_or_else(|| format!("patch shape {shape} is neither a polynomial nor keeps an extraordinary corner"))?;
        if keep.domain.offset != [0, 0] {
            return Err(format!("patch shape {shape} keeps its shape away from corner 0"));
        }
        if !convex(shape) {
            return Err(format!("sub-patch matrices of shape {shape} are not convex combinations"));
        }
        for child in &s.children {
            if child.shape != shape && !polynomial[child.shape] && !linear[child.shape] {
                return Err(format!(
                    "a child of extraordinary shape {shape} is neither a polynomial, nor reproduces linear functions \
                     by convex combinations, nor is the shape itself"
                ));
            }
        }
        let stencil = evaluator.stencil(shape, Dyadic::new(0, 0, 1)).map_err(|e| e.to_string())?;
        out.insert(
            (id, shape),
            ShapeKind::Extraordinary {
                position: stencil.position.clone(),
                du: stencil.du.clone(),
                dv: stencil.dv.clone(),
            },
        );
    }
    Ok(())
}

/// Shrinks `set` to its largest subset closed under children: a shape stays only if each child
/// is in the set or `also(child)`.
fn close_under_children(matrices: &PatchMatrices, set: &mut [bool], also: impl Fn(usize) -> bool) {
    let shapes = &matrices.shapes;
    loop {
        let drop: Vec<usize> = (0..shapes.len())
            .filter(|&s| set[s] && shapes[s].children.iter().any(|c| !set[c.shape] && !also(c.shape)))
            .collect();
        if drop.is_empty() {
            return;
        }
        drop.into_iter().for_each(|s| set[s] = false);
    }
}

/// Whether weights (a matrix row, a refinement stencil) are a convex combination: none
/// negative, summing to 1 (to rounding). The hull bounds rest on it.
pub(super) fn is_convex_combination(weights: impl IntoIterator<Item = f64>) -> bool {
    let (mut sum, mut negative) = (0.0, false);
    for w in weights {
        sum += w;
        negative |= w < 0.0;
    }
    !negative && (sum - 1.0).abs() <= 1e-12
}

/// The 4 × 4 grid order of a 16-point shape whose control points sit at the integer
/// parameters `−1..=2` (a regular B-spline patch), if it is one.
pub(crate) fn regular_grid(size: usize, parameters: Option<&[Vec<f64>; 2]>) -> Option<[usize; 16]> {
    let [us, vs] = parameters?;
    if size != 16 || us.len() != 16 || vs.len() != 16 {
        return None;
    }
    let mut grid = [usize::MAX; 16];
    for (k, (&u, &v)) in us.iter().zip(vs).enumerate() {
        // The parameters are read back from the matrices: integers up to rounding.
        let (i, j) = ((u + 1.0).round(), (v + 1.0).round());
        if (u + 1.0 - i).abs() > 1e-9
            || (v + 1.0 - j).abs() > 1e-9
            || !(0.0..4.0).contains(&i)
            || !(0.0..4.0).contains(&j)
        {
            return None;
        }
        let slot = &mut grid[j as usize * 4 + i as usize];
        if *slot != usize::MAX {
            return None;
        }
        *slot = k;
    }
    Some(grid)
}

/// Whether the regular shape's children (regular too) are the quarters of its bicubic B-spline
/// patch on every basis function: what makes the pieces polynomials of bidegree 3.
pub(crate) fn check_bicubic(matrices: &PatchMatrices, shape: usize) -> bool {
    let net = |shape: usize, points: &[DVec3]| {
        let s = &matrices.shapes[shape];
        let grid = regular_grid(s.size, s.parameters.as_ref())?;
        Some(Bicubic::from_bspline(&std::array::from_fn(|j| std::array::from_fn(|i| points[grid[j * 4 + i]]))))
    };
    children_are_quarters(matrices, shape, 1e-12, net)
}

impl QuadtreeTessellator {
    /// The piece of a root.
    pub(super) fn root_piece(&self, root: Root) -> Result<Piece, TessError> {
        match root.sub {
            None => self.piece(0, root.face),
            Some((s, ..)) => match self.levels.resolve(0, root.face) {
                Some(Resolved::Children { children, .. }) => self.piece(1, FaceId::new((children.start + s) as u32)),
                _ => Err(TessError::Internal(format!("{} has no sub-faces", root.face))),
            },
        }
    }

    /// The piece of face `face` of `level`, in the face's coordinates.
    pub(super) fn piece(&self, level: usize, face: FaceId) -> Result<Piece, TessError> {
        match self.levels.resolve(level, face) {
            // Its pieces stretch across it, where the tree's nodes split in quarters.
            Some(Resolved::Children { layout: Layout::DualBoundaryQuad { .. }, .. }) => {
                Err(TessError::Unsupported { feature: DUAL_BOUNDARY, element: format!("{face}") })
            }
            Some(Resolved::Children { .. }) => Ok(Piece::Face { level, face }),
            Some(Resolved::Patch { mesh, patch, frame }) => {
                let points: Vec<DVec3> = patch.vertices.iter().map(|&v| mesh.position(v)).collect();
                let key = (Arc::as_ptr(&patch.matrices) as usize, patch.shape);
                match self.shapes.get(&key) {
                    Some(ShapeKind::Regular { net }) => {
                        Ok(Piece::Regular(Box::new(bezier_in_frame(net, &points, frame))))
                    }
                    Some(ShapeKind::Quartic { net }) => {
                        Ok(Piece::Quartic(Box::new(quartic_in_frame(net, &points, frame))))
                    }
                    Some(ShapeKind::Extraordinary { .. }) => {
                        Ok(Piece::Extraordinary { matrices: patch.matrices.clone(), shape: patch.shape, points, frame })
                    }
                    Some(ShapeKind::Linear { .. }) => {
                        Ok(Piece::Linear { matrices: patch.matrices.clone(), shape: patch.shape, points, frame })
                    }
                    None => Err(TessError::Internal(format!("shape of level {level} {face} not classified"))),
                }
            }
            Some(Resolved::Hole) => Err(TessError::Unsupported { feature: "holes", element: format!("{face}") }),
            None => Err(TessError::Internal(format!("level {level} {face} was not prepared"))),
        }
    }

    /// The child `domain` of a piece of `root`, in the child's own coordinates.
    pub(super) fn child(&self, root: Root, piece: &Piece, domain: ChildDomain) -> Result<Piece, TessError> {
        // A point inside the child, in the node's coordinates: its image of (½, ½) in a
        // square, of (¼, ¼) in a triangle.
        let [a, b] = domain.offset.map(i64::from);
        let inside = if root.triangle {
            let sign = if domain.flipped { -1 } else { 1 };
            Dyadic::new(sign + 4 * a, sign + 4 * b, 8)
        } else {
            Dyadic::new(2 * a + 1, 2 * b + 1, 4)
        };
        match piece {
            Piece::Regular(p) => Ok(Piece::Regular(Box::new(p.quarter(a as usize, b as usize)))),
            Piece::Quartic(q) => Ok(Piece::Quartic(Box::new(q.child(domain.offset, domain.flipped)))),
            Piece::Face { level, face } => match self.levels.resolve(*level, *face) {
                Some(Resolved::Children { children, layout }) => {
                    let (child, ..) = layout.child_of(inside);
                    self.piece(level + 1, FaceId::new((children.start + child) as u32))
                }
                _ => Err(TessError::Internal(format!("level {level} {face} has no children"))),
            },
            Piece::Extraordinary { matrices, shape, points, frame }
            | Piece::Linear { matrices, shape, points, frame } => {
                // The patch's child holding the node's child (the frame maps children onto
                // children, the middle triangle onto itself, and keeps its offset).
                let (patch_domain, size) =
                    if root.triangle { (FaceDomain::Triangle, 3) } else { (FaceDomain::Quad, 4) };
                let (k, ..) = patch_domain.child_of(frame.to_patch(inside));
                let want = ChildDomain::of_face(size)[k];
                let sub = matrices.shapes[*shape]
                    .children
                    .iter()
                    .find(|c| c.domain == want)
                    .ok_or_else(|| TessError::Internal(format!("no child {want:?}")))?;
                let child = sub.apply(points);
                match self.shapes.get(&(Arc::as_ptr(matrices) as usize, sub.shape)) {
                    Some(ShapeKind::Regular { net }) => {
                        Ok(Piece::Regular(Box::new(bezier_in_frame(net, &child, *frame))))
                    }
                    Some(ShapeKind::Quartic { net }) => {
                        Ok(Piece::Quartic(Box::new(quartic_in_frame(net, &child, *frame))))
                    }
                    Some(ShapeKind::Extraordinary { .. }) => Ok(Piece::Extraordinary {
                        matrices: matrices.clone(),
                        shape: sub.shape,
                        points: child,
                        frame: *frame,
                    }),
                    Some(ShapeKind::Linear { .. }) => {
                        Ok(Piece::Linear { matrices: matrices.clone(), shape: sub.shape, points: child, frame: *frame })
                    }
                    None => Err(TessError::Internal("child shape not classified".into())),
                }
            }
        }
    }
}
