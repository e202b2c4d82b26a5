//! The tree's growth: each root's pieces split until flat ([`flatness`]), within the budget.

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use subdiv_mesh::FaceId;

use super::pieces::{LINEAR_LEVELS, Piece, linear_samples};
use super::{Corners, Leaf, QuadtreeOptions, QuadtreeTessellator, Root};
use crate::TessError;
use crate::flatness;

impl QuadtreeTessellator {
    /// Splits `piece` (the node `node` of `root`) until flat, appending the leaves, and the
    /// extraordinary pieces it splits to `corners`.
    pub(super) fn build(
        &self,
        root: Root,
        piece: Piece,
        node: Leaf,
        budget: &Budget<'_>,
        leaves: &mut Vec<Leaf>,
        corners: &mut Corners,
    ) -> Result<(), TessError> {
        let (flat, epsilon) = self.flatness(&piece, budget);
        if flat {
            if budget.count.fetch_add(1, Ordering::Relaxed) >= budget.options.max_polygons {
                let limit = budget.options.max_polygons;
                return Err(TessError::TooManyPolygons { needed: limit + 1, limit, bound: budget.bound() });
            }
            leaves.push(Leaf { extraordinary: matches!(piece, Piece::Extraordinary { .. }), ..node });
            return Ok(());
        }
        if node.depth >= budget.max_depth {
            return Err(TessError::DepthLimit { face: root.face.index(), depth: node.depth + root.depth(), epsilon });
        }
        // The engine's order of the children keeps leaf order (and ids) deterministic.
        for &domain in root.child_domains() {
            let child = node.child(root, domain);
            self.build(root, self.child(root, &piece, domain)?, child, budget, leaves, corners)?;
        }
        if matches!(piece, Piece::Extraordinary { .. }) {
            corners.insert((node.depth, node.x, node.y), piece);
        }
        Ok(())
    }

    /// Whether `piece` is flat, and the `ε` it was measured against (its own on the screen).
    pub(super) fn flatness(&self, piece: &Piece, budget: &Budget<'_>) -> (bool, f64) {
        // A level's face without a patch is bounded by the hull of its ring, where the rules
        // between the levels are convex combinations; else it is always split.
        let ring = match piece {
            Piece::Face { level, face } if self.convex_levels => self.face_ring(*level, *face),
            _ => Vec::new(),
        };
        // The piece's own ε on the screen (none: wholly behind the near plane, flat at once).
        let epsilon = match (&budget.screen, piece) {
            (None, _) => Some(budget.epsilon),
            (Some(_), Piece::Face { .. }) if ring.is_empty() => Some(budget.epsilon),
            (Some(screen), Piece::Face { .. }) => screen.epsilon(&ring),
            (Some(screen), Piece::Extraordinary { points, .. } | Piece::Linear { points, .. }) => {
                screen.epsilon(points)
            }
            (Some(screen), Piece::Regular(b)) => screen.epsilon(b.net.as_flattened()),
            (Some(screen), Piece::Quartic(q)) => screen.epsilon(&q.net),
        };
        let flat = match (piece, epsilon) {
            (Piece::Face { .. }, _) if ring.is_empty() => false,
            (_, None) => true,
            (Piece::Face { .. }, Some(e)) => flatness::extraordinary_is_flat(&ring, e),
            (Piece::Extraordinary { points, .. }, Some(e)) => flatness::extraordinary_is_flat(points, e),
            (Piece::Linear { matrices, shape, points, .. }, Some(e)) => {
                // Two levels down: the grandchildren's rings hug the piece (a footprint of about
                // 1.5 times its side, against 3 for its own points), for a bound 4 times tighter.
                let (samples, parameters) = linear_samples(matrices, *shape, points, LINEAR_LEVELS)
                    .or_else(|| linear_samples(matrices, *shape, points, 0))
                    .unwrap_or_default();
                !samples.is_empty() && flatness::linear_is_flat(&samples, &parameters, e)
            }
            (Piece::Regular(b), Some(e)) => flatness::regular_is_flat(b, e),
            (Piece::Quartic(q), Some(e)) => flatness::quartic_is_flat(q, e),
        };
        (flat, epsilon.unwrap_or(budget.epsilon))
    }
}

impl QuadtreeTessellator {
    /// The control points that the surface over `face` of `level` (a face without a patch yet)
    /// depends on: the vertices of every face around its corners. Each finer level's points
    /// over it are convex combinations of these (the refinement rules of a vertex, an edge and a
    /// face reach no further), so where every rule is ([`Self::convex_levels`]) the surface
    /// over the face lies in their hull, and so does any triangle with its corners on it.
    fn face_ring(&self, level: usize, face: FaceId) -> Vec<DVec3> {
        let mesh = self.levels.mesh(level);
        let mut seen: Vec<subdiv_mesh::VertexId> = Vec::new();
        for &v in mesh.face_vertices(face) {
            for g in mesh.vertex_faces(v) {
                seen.extend_from_slice(mesh.face_vertices(g));
            }
        }
        seen.sort_unstable();
        seen.dedup();
        seen.into_iter().map(|v| mesh.position(v)).collect()
    }
}

impl Budget<'_> {
    /// The bound asked for, as a refusal states it.
    pub(super) fn bound(&self) -> crate::ErrorBound {
        error_bound(self.screen.as_ref(), self.epsilon)
    }
}

/// The bound asked for, as a refusal states it: the screen's pixels, else `epsilon`.
pub(super) fn error_bound(screen: Option<&crate::rates::ScreenBound>, epsilon: f64) -> crate::ErrorBound {
    match screen {
        Some(screen) => crate::ErrorBound::Pixels(screen.pixels),
        None => crate::ErrorBound::Absolute(epsilon),
    }
}

/// What a root's recursion may spend.
pub(super) struct Budget<'a> {
    pub(super) epsilon: f64,
    pub(super) screen: Option<crate::rates::ScreenBound>,
    pub(super) max_depth: u32,
    pub(super) count: &'a AtomicUsize,
    pub(super) options: &'a QuadtreeOptions,
}
