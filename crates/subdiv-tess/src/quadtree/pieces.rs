//! The quadtree's pieces of surface and their subdivision: a patch shape classified once
//! (bicubic, checked against the B-spline's quarters, or extraordinary, with its limit
//! stencils), a root's piece (a refined face without a patch, the sub-patch at an
//! extraordinary corner, or a bicubic Bézier patch) and its quarters.

use super::*;

/// How a patch shape is tessellated.
#[derive(Clone, Debug)]
pub(super) enum ShapeKind {
    /// A bicubic B-spline patch: `grid[j * 4 + i]` is the control point at `(i − 1, j − 1)`.
    Regular { grid: [usize; 16] },
    /// The extraordinary vertex at corner 0: the child kept at the corner, and the vertex's
    /// limit position and tangent-direction stencils.
    Extraordinary { position: Vec<f64>, du: Vec<f64>, dv: Vec<f64> },
}

/// A set of sub-patch matrices and one of its shapes, identified by address.
pub(super) type ShapeKey = (usize, usize);

/// The surface over a node.
#[derive(Clone)]
pub(super) enum Piece {
    /// A face of refinement level `level` that reaches its patch through its children.
    Face { level: usize, face: FaceId },
    /// The sub-patch at the extraordinary corner, in the patch's frame.
    Extraordinary { matrices: Arc<PatchMatrices>, shape: usize, points: Vec<DVec3>, frame: PatchFrame },
    /// A polynomial piece, in the node's own coordinates (boxed: 384 bytes).
    Regular(Box<Bicubic>),
}

/// The Bézier net, in the face's coordinates, of a regular patch whose B-spline control points
/// `points` are ordered by `grid` in the patch's frame.
pub(super) fn bezier_in_frame(grid: &[usize; 16], points: &[DVec3], frame: PatchFrame) -> Bicubic {
    let ordered: [[DVec3; 4]; 4] = std::array::from_fn(|j| std::array::from_fn(|i| points[grid[j * 4 + i]]));
    let patch = Bicubic::from_bspline(&ordered);
    // The frame is a turn of the unit square: face control point (i, j) is the patch's at
    // to_patch(i/3, j/3).
    let net = std::array::from_fn(|j| {
        std::array::from_fn(|i| {
            let p = frame.to_patch(Dyadic::new(i as i64, j as i64, 3));
            patch.net[p.v as usize][p.u as usize]
        })
    });
    Bicubic { net }
}

/// Classifies `shape` of `matrices` and every shape it reaches, checking what the bounds need.
pub(super) fn classify(
    matrices: &Arc<PatchMatrices>,
    shape: usize,
    out: &mut HashMap<ShapeKey, ShapeKind>,
) -> Result<(), String> {
    let key = (Arc::as_ptr(matrices) as usize, shape);
    if out.contains_key(&key) {
        return Ok(());
    }
    let s = &matrices.shapes[shape];
    if let Some(grid) = regular_grid(s.size, s.parameters.as_ref()) {
        check_bicubic(matrices, shape, &grid)?;
        out.insert(key, ShapeKind::Regular { grid });
        for child in &s.children {
            classify(matrices, child.shape, out)?;
        }
        return Ok(());
    }
    let (_, keep) = matrices
        .keeping(shape)
        .ok_or_else(|| format!("patch shape {shape} is neither regular nor keeps an extraordinary corner"))?;
    if keep.domain.offset != [0, 0] {
        return Err(format!("patch shape {shape} keeps its shape away from corner 0"));
    }
    for child in &s.children {
        for r in 0..child.rows() {
            let row = child.row(r);
            if row.iter().any(|&w| w < 0.0) || (row.iter().sum::<f64>() - 1.0).abs() > 1e-12 {
                return Err(format!("sub-patch matrices of shape {shape} are not convex combinations"));
            }
        }
    }
    let stencil = surface_stencil(matrices, shape, Dyadic::new(0, 0, 1)).map_err(|e| e.to_string())?;
    out.insert(key, ShapeKind::Extraordinary { position: stencil.position, du: stencil.du, dv: stencil.dv });
    for child in &s.children {
        if child.shape != shape {
            classify(matrices, child.shape, out)?;
            if !matches!(out.get(&(key.0, child.shape)), Some(ShapeKind::Regular { .. })) {
                return Err(format!("a child of extraordinary shape {shape} is neither regular nor the shape itself"));
            }
        }
    }
    Ok(())
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

/// Checks that the regular shape's children are the quarters of the bicubic B-spline patch,
/// on every basis function: what makes the pieces polynomials of bidegree 3.
pub(crate) fn check_bicubic(matrices: &PatchMatrices, shape: usize, grid: &[usize; 16]) -> Result<(), String> {
    let s = &matrices.shapes[shape];
    for child in &s.children {
        let Some(child_grid) =
            regular_grid(matrices.shapes[child.shape].size, matrices.shapes[child.shape].parameters.as_ref())
        else {
            return Err(format!("a child of regular shape {shape} is not regular"));
        };
        let [qx, qy] = child.domain.offset.map(usize::from);
        for k in 0..16 {
            let basis: Vec<DVec3> = (0..16).map(|m| if m == k { DVec3::X } else { DVec3::ZERO }).collect();
            let parent =
                Bicubic::from_bspline(&std::array::from_fn(|j| std::array::from_fn(|i| basis[grid[j * 4 + i]])));
            let points = child.apply(&basis);
            let mine =
                Bicubic::from_bspline(&std::array::from_fn(|j| std::array::from_fn(|i| points[child_grid[j * 4 + i]])));
            let expected = parent.quarter(qx, qy);
            let diff = mine.net.iter().flatten().zip(expected.net.iter().flatten()).map(|(a, b)| (*a - *b).length());
            if diff.fold(0.0, f64::max) > 1e-12 {
                return Err(
                    "its regular patches are not bicubic B-splines (the quadtree's bounds need Catmull-Clark)".into()
                );
            }
        }
    }
    Ok(())
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
            Some(Resolved::Children { .. }) => Ok(Piece::Face { level, face }),
            Some(Resolved::Patch { mesh, patch, frame }) => {
                let points: Vec<DVec3> = patch.vertices.iter().map(|&v| mesh.position(v)).collect();
                let key = (Arc::as_ptr(&patch.matrices) as usize, patch.shape);
                match self.shapes.get(&key) {
                    Some(ShapeKind::Regular { grid }) => {
                        Ok(Piece::Regular(Box::new(bezier_in_frame(grid, &points, frame))))
                    }
                    Some(ShapeKind::Extraordinary { .. }) => {
                        Ok(Piece::Extraordinary { matrices: patch.matrices.clone(), shape: patch.shape, points, frame })
                    }
                    None => Err(TessError::Internal(format!("shape of level {level} {face} not classified"))),
                }
            }
            Some(Resolved::Hole) => Err(TessError::Unsupported { feature: "holes", element: format!("{face}") }),
            None => Err(TessError::Internal(format!("level {level} {face} was not prepared"))),
        }
    }

    /// The quarter `(qx, qy)` of a piece, in the quarter's own coordinates.
    pub(super) fn quarter(&self, piece: &Piece, qx: usize, qy: usize) -> Result<Piece, TessError> {
        match piece {
            Piece::Regular(b) => Ok(Piece::Regular(Box::new(b.quarter(qx, qy)))),
            Piece::Face { level, face } => match self.levels.resolve(*level, *face) {
                Some(Resolved::Children { children, domain }) => {
                    let (child, ..) = domain.child_of(Dyadic::new(2 * qx as i64 + 1, 2 * qy as i64 + 1, 4));
                    self.piece(level + 1, FaceId::new((children.start + child) as u32))
                }
                _ => Err(TessError::Internal(format!("level {level} {face} has no children"))),
            },
            Piece::Extraordinary { matrices, shape, points, frame } => {
                let centre = frame.to_patch(Dyadic::new(2 * qx as i64 + 1, 2 * qy as i64 + 1, 4));
                let offset = [u8::from(centre.u > 2), u8::from(centre.v > 2)];
                let sub = matrices.shapes[*shape]
                    .children
                    .iter()
                    .find(|c| c.domain.offset == offset && !c.domain.flipped)
                    .ok_or_else(|| TessError::Internal(format!("no child at {offset:?}")))?;
                let child = sub.apply(points);
                match self.shapes.get(&(Arc::as_ptr(matrices) as usize, sub.shape)) {
                    Some(ShapeKind::Regular { grid }) => {
                        Ok(Piece::Regular(Box::new(bezier_in_frame(grid, &child, *frame))))
                    }
                    Some(ShapeKind::Extraordinary { .. }) => Ok(Piece::Extraordinary {
                        matrices: matrices.clone(),
                        shape: sub.shape,
                        points: child,
                        frame: *frame,
                    }),
                    None => Err(TessError::Internal("child shape not classified".into())),
                }
            }
        }
    }
}
