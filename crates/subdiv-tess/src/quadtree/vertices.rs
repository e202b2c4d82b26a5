//! The quadtree's output vertices: each a parameter point with a canonical key, evaluated once
//! (through the pieces, or the limit stencil at an extraordinary vertex), and the leaves'
//! polygons through them with their finer neighbours' hanging vertices.

use super::*;

/// A leaf's polygon: vertex ids and their root coordinates.
pub(super) type Ring = (Vec<u32>, Vec<(i64, i64)>);

/// The `Bfr` parameters of root point `(x, y)`, laid out by [`FaceDomain`] (exact in f64 where
/// the point is dyadic: a triangle's `3 · FULL` divides exactly into its multiples of 3).
pub(super) fn bfr(root: Root, x: i64, y: i64) -> (f64, f64) {
    if root.triangle {
        let full = root.full() as f64;
        return (x as f64 / full, y as f64 / full);
    }
    let p = Dyadic::new(x, y, FULL);
    match root.sub {
        None => p,
        Some((s, size, columns)) => FaceDomain::SubFaces { size, columns }.from_sub_face(s, p),
    }
    .to_f64()
}

impl QuadtreeTessellator {
    /// The limit position and unit normal at root point `(x, y)` (over [`FULL`]), descending
    /// through `corners`' extraordinary pieces where the root has them.
    pub(super) fn eval(
        &self,
        root: Root,
        x: i64,
        y: i64,
        corners: Option<&Corners>,
    ) -> Result<(DVec3, DVec3), TessError> {
        let full = root.full();
        let mut piece = self.root_piece(root)?;
        let at_root = (x, y);
        // The point in the node's coordinates (over `full`), and the node.
        let (mut x, mut y) = (x, y);
        let mut node = Leaf::ROOT;
        // A point moves away from the special corner of every extraordinary piece, so it
        // reaches a polynomial or linear piece within a few levels of the depth where it is a
        // node's corner; the bound only turns a mistake into an error instead of a hang.
        // Whether the last piece was extraordinary with the point at a corner of its node.
        let mut cornered = false;
        for _ in 0..=DEPTH_LIMIT + FULL_BITS + 8 {
            let corner = match &piece {
                Piece::Regular(b) => {
                    let (p, du, dv) = b.eval_with_derivatives(x as f64 / full as f64, y as f64 / full as f64);
                    return Ok((p, crate::unit_normal(du.cross(dv))));
                }
                Piece::Quartic(q) => {
                    let (p, du, dv) = q.eval_with_derivatives(x as f64 / full as f64, y as f64 / full as f64);
                    return Ok((p, crate::unit_normal(du.cross(dv))));
                }
                Piece::Linear { .. } => {
                    // No closed form: the surface's exact stencils at the point.
                    let limit = self.limit.as_ref().ok_or_else(|| TessError::Internal("no exact evaluator".into()))?;
                    let (u, v) = bfr(root, at_root.0, at_root.1);
                    let p = limit.eval(root.face, u, v)?;
                    return Ok((p.position, crate::unit_normal(p.du.cross(p.dv))));
                }
                Piece::Face { .. } => {
                    cornered = false;
                    None
                }
                Piece::Extraordinary { matrices, shape, points, frame } => {
                    let corner = frame.to_face(Dyadic::new(0, 0, 1));
                    let corner = (corner.u * full, corner.v * full);
                    let apply = |w: &[f64]| -> DVec3 { w.iter().zip(points).map(|(&w, &p)| w * p).sum() };
                    if (x, y) == corner {
                        let key = (Arc::as_ptr(matrices) as usize, *shape);
                        let Some(ShapeKind::Extraordinary { position, du, dv }) = self.shapes.get(&key) else {
                            return Err(TessError::Internal("extraordinary shape not classified".into()));
                        };
                        // The patch frame keeps the face's orientation (determinant 1).
                        return Ok((apply(position), crate::unit_normal(apply(du).cross(apply(dv)))));
                    }
                    let at_node_corner = (x == 0 || x == full) && (y == 0 || y == full);
                    if at_node_corner && cornered {
                        // A second extraordinary piece in a row with the point at another corner
                        // than its special one (a non-polynomial scheme's crease, whose every
                        // vertex is special): descending would keep it at a far corner for
                        // ever, so its stencil comes from the address's eigenvectors.
                        let at = frame.to_patch(Dyadic::new(x, y, full).reduced());
                        let s = subdiv_stencil::surface_stencil(matrices, *shape, at)?;
                        return Ok((apply(&s.position), crate::unit_normal(apply(&s.du).cross(apply(&s.dv)))));
                    }
                    cornered = at_node_corner;
                    Some(corner)
                }
            };
            // The child holding the point; on a border between children, one away from the
            // extraordinary corner: the point then reaches a polynomial piece.
            let local = |d: &ChildDomain, (px, py): (i64, i64)| {
                let sign = if d.flipped { -1 } else { 1 };
                (sign * (2 * px - i64::from(d.offset[0]) * full), sign * (2 * py - i64::from(d.offset[1]) * full))
            };
            let holds = |(cx, cy): (i64, i64)| {
                cx >= 0 && cy >= 0 && if root.triangle { cx + cy <= full } else { cx <= full && cy <= full }
            };
            let mut holding = root.child_domains().iter().filter(|d| holds(local(d, (x, y))));
            let first =
                *holding.clone().next().ok_or_else(|| TessError::Internal("a point outside its root".into()))?;
            let domain = match corner {
                Some(c) => *holding.find(|d| !holds(local(d, c))).unwrap_or(&first),
                None => first,
            };
            (x, y) = local(&domain, (x, y));
            node = node.child(root, domain);
            piece = match corners.and_then(|c| c.get(&(node.depth, node.x, node.y))) {
                Some(kept) if !node.flipped => kept.clone(),
                _ => self.child(root, &piece, domain)?,
            };
        }
        Err(TessError::Internal(format!("{}: the point ({x}, {y}) reached no piece that evaluates it", root.face)))
    }

    /// A normal where the limit tangents are parallel (a valence-2 vertex between two faces
    /// folded back to back, where no normal exists): the limit normal a little way into the
    /// root, toward its centre (`2^-20` of the way; deterministic), else the root face's
    /// control-polygon normal (Newell's), so that every vertex has a direction.
    pub(super) fn fallback_normal(&self, root: Root, x: i64, y: i64) -> Result<DVec3, TessError> {
        let (_, _, centre) = Leaf::ROOT.corners(root);
        let inward = |t: i64, c: i64| t + ((c - t) >> 20);
        let (x, y) = (inward(x, centre.0), inward(y, centre.1));
        let (_, normal) = self.eval(root, x, y, None)?;
        if normal != DVec3::ZERO {
            return Ok(normal);
        }
        let mesh = self.levels.mesh(0);
        let corners: Vec<DVec3> = mesh.face_vertices(root.face).iter().map(|&v| mesh.position(v)).collect();
        let newell = (0..corners.len()).map(|k| corners[k].cross(corners[(k + 1) % corners.len()])).sum::<DVec3>();
        let normal = crate::unit_normal(newell);
        Ok(if normal == DVec3::ZERO { DVec3::Z } else { normal })
    }

    /// The canonical key of root point `(x, y)`.
    pub(super) fn key(&self, root: Root, x: i64, y: i64) -> VertexKey {
        let face = root.face;
        let mesh = self.levels.mesh(0);
        let corners = &self.corners[face.index()];
        let n = corners.len();
        let vertex = |k: usize| VertexKey::Vertex(mesh.origin(corners[k % n]).index() as u32);
        // A point of side k (corner k to k + 1) at t / FULL from corner k.
        let on_side = |k: usize, t: i64| {
            let h = corners[k % n];
            let e = mesh.edge(h);
            let forward = mesh.edge_vertices(e)[0] == mesh.origin(h);
            VertexKey::Edge { edge: e.index() as u32, t: if forward { t } else { FULL - t } }
        };
        let inner = |sub: usize| VertexKey::Inner { face: face.index() as u32, sub: sub as u32, x, y };
        if root.triangle {
            // Points on the sides are multiples of 3 (dyadic points of the side), over 3 · FULL.
            let full = root.full();
            return match (x, y) {
                (0, 0) => vertex(0),
                (_, 0) if x == full => vertex(1),
                (0, _) if y == full => vertex(2),
                (_, 0) => on_side(0, x / 3),
                _ if x + y == full => on_side(1, y / 3),
                (0, _) => on_side(2, (full - y) / 3),
                _ => inner(0),
            };
        }
        match root.sub {
            None => match (x, y) {
                (0, 0) => vertex(0),
                (FULL, 0) => vertex(1),
                (FULL, FULL) => vertex(2),
                (0, FULL) => vertex(3),
                (_, 0) => on_side(0, x),
                (FULL, _) => on_side(1, y),
                (_, FULL) => on_side(2, FULL - x),
                (0, _) => on_side(3, FULL - y),
                _ => inner(0),
            },
            Some((s, ..)) => match (x, y) {
                (0, 0) => vertex(s),
                (_, 0) => on_side(s, x / 2),
                (0, _) => on_side(s + n - 1, FULL - y / 2),
                (FULL, FULL) => VertexKey::Centre(face.index() as u32),
                (FULL, _) => VertexKey::Spoke { face: face.index() as u32, spoke: s as u32, t: y },
                (_, FULL) => VertexKey::Spoke { face: face.index() as u32, spoke: ((s + n - 1) % n) as u32, t: x },
                _ => inner(s),
            },
        }
    }

    /// A leaf's polygon: its corners and the hanging vertices on its edges, counter-clockwise,
    /// with their root coordinates.
    pub(super) fn ring(&self, root: Root, leaf: &Leaf, ids: &HashMap<VertexKey, u32>) -> Ring {
        let (c, n, _) = leaf.corners(root);
        let mut ring = Vec::with_capacity(2 * n);
        let mut params = Vec::with_capacity(2 * n);
        for k in 0..n {
            let (a, b) = (c[k], c[(k + 1) % n]);
            ring.push(ids[&self.key(root, a.0, a.1)]);
            params.push(a);
            self.hanging(root, a, b, ids, &mut ring, &mut params);
        }
        (ring, params)
    }

    /// The vertices strictly inside segment `a → b`, in order: its midpoint is one iff some
    /// vertex is (see the module docs).
    fn hanging(
        &self,
        root: Root,
        a: (i64, i64),
        b: (i64, i64),
        ids: &HashMap<VertexKey, u32>,
        ring: &mut Vec<u32>,
        params: &mut Vec<(i64, i64)>,
    ) {
        if (a.0 - b.0).abs() + (a.1 - b.1).abs() < 2 {
            return;
        }
        let m = ((a.0 + b.0) / 2, (a.1 + b.1) / 2);
        if let Some(&id) = ids.get(&self.key(root, m.0, m.1)) {
            self.hanging(root, a, m, ids, ring, params);
            ring.push(id);
            params.push(m);
            self.hanging(root, m, b, ids, ring, params);
        }
    }
}
