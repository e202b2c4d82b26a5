//! Face-varying channels (texture coordinates) through the quadtree: each channel is a
//! subdivision surface over its own topology ([`ChannelSurface`]), evaluated exactly at every
//! output vertex's parameter.
//!
//! A quadtree vertex on a mesh vertex or edge is shared by the faces around it. Where a channel
//! is cut there (a seam), the faces on either side want different values at the same point:
//! the vertex is then split, as the dual tessellator splits a seam's points, by the sinks'
//! extra-normal mechanism — one extra entry (same position and normal, the other side's
//! values and parameter) per further value, which the triangles of that side index. Which
//! faces share a value follows the channels' own topology, not a comparison of numbers: at a
//! mesh vertex the faces whose corners there use the same value of every channel, along an
//! edge the two faces unless the edge is a seam of a channel.

use glam::DVec3;
use subdiv_mesh::{FaceId, FaceVaryingInterpolation, Mesh};
use subdiv_schemes::{ChannelSurface, RefineOptions, Scheme};
use subdiv_stencil::{LimitEvaluator, LinearEvaluator};

use hashbrown::HashMap;

use super::{QuadtreeTessellator, Ring, VertexKey, bfr};
use crate::{SurfaceParameter, TessError, TessVertex};

/// The channels of one mesh, as the quadtree evaluates them.
#[derive(Debug, Default)]
pub(super) struct Channels {
    pub(super) names: Vec<String>,
    pub(super) dimensions: Vec<usize>,
    evaluators: Vec<ChannelEvaluator>,
    /// Per mesh edge, whether it is a seam of some channel.
    seams: Vec<bool>,
    /// The channels' corner value indices (by half-edge: the patch levels' level 0 is the mesh
    /// with its channels cleared, the same half-edges), which say which faces share a value at
    /// a vertex.
    corners: Vec<subdiv_mesh::Channel>,
}

/// How a channel's surface is evaluated at a point.
#[derive(Debug)]
enum ChannelEvaluator {
    /// Linear over every face (face-varying mode `all`, the default): its corners combined.
    Linear(Box<LinearEvaluator>),
    /// Any other mode: exact stencils over the channel's own patches.
    Limit(Box<LimitEvaluator>),
}

/// Which of a shared vertex's values a face takes: the vertex's own (its creator's side), or
/// that of a side found by the channels' topology.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) enum Side {
    /// At a mesh vertex: every channel's value index at the face's corner there.
    Corner(Vec<u32>),
    /// Along a seam edge: the face.
    Face(u32),
}

impl Channels {
    /// The channels of `mesh` under `scheme` in face-varying mode `mode` (`None`: the mesh's
    /// tag, else `all`); none for a mesh without channels.
    ///
    /// # Errors
    /// [`TessError::Scheme`] for a scheme without face-varying rules; [`TessError::Surface`] if
    /// a channel's surface has no patches.
    pub(super) fn new(scheme: &Scheme, mesh: &Mesh, mode: Option<FaceVaryingInterpolation>) -> Result<Self, TessError> {
        let mut channels = Self::default();
        if mesh.channels().is_empty() {
            return Ok(channels);
        }
        let options = RefineOptions { face_varying: mode, ..RefineOptions::DEFAULT };
        channels.seams = vec![false; mesh.edge_count()];
        for channel in mesh.channels() {
            let surface = ChannelSurface::new(mesh, channel, scheme, &options)
                .map_err(|e| TessError::Scheme { scheme: scheme.name().to_string(), reason: e.to_string() })?;
            let evaluator = match LinearEvaluator::new(&surface)? {
                Some(linear) => ChannelEvaluator::Linear(Box::new(linear)),
                None => ChannelEvaluator::Limit(Box::new(LimitEvaluator::new(
                    surface.scheme(),
                    surface.mesh(),
                    &RefineOptions::DEFAULT,
                )?)),
            };
            channels.evaluators.push(evaluator);
            channels.names.push(channel.name().to_owned());
            channels.dimensions.push(channel.dimension());
            for (e, seam) in mesh.edges().zip(&mut channels.seams) {
                *seam |= mesh.is_seam(channel, e);
            }
        }
        channels.corners = mesh.channels().to_vec();
        Ok(channels)
    }

    /// Whether there are none.
    pub(super) fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The number of values per point: the sum of the dimensions.
    pub(super) fn stride(&self) -> usize {
        self.dimensions.iter().sum()
    }

    /// Where the texture coordinates (the `"uv"` channel's first two components) lie within a
    /// point's values, if there are some.
    pub(super) fn texcoords(&self) -> Option<usize> {
        let k = self.names.iter().position(|n| n == subdiv_mesh::Channel::UV)?;
        (self.dimensions[k] >= 2).then(|| self.dimensions[..k].iter().sum())
    }

    /// Every channel's values at `face`'s `(u, v)`, appended to `out`.
    ///
    /// # Errors
    /// [`TessError::Surface`] if a channel's stencil fails.
    pub(super) fn eval(&self, face: FaceId, u: f64, v: f64, out: &mut Vec<f64>) -> Result<(), TessError> {
        for (evaluator, &dimension) in self.evaluators.iter().zip(&self.dimensions) {
            let value: DVec3 = match evaluator {
                ChannelEvaluator::Linear(linear) => linear.eval(face, u, v)?.position,
                ChannelEvaluator::Limit(limit) => limit.eval(face, u, v)?.position,
            };
            out.extend_from_slice(&value.to_array()[..dimension]);
        }
        Ok(())
    }

    /// The side of the vertex keyed `key` that `face` takes: `None` where every face around it
    /// takes one value (a point inside a face, an edge that is no seam).
    pub(super) fn side(&self, mesh: &Mesh, key: VertexKey, face: FaceId) -> Option<Side> {
        match key {
            VertexKey::Vertex(v) => {
                let h = mesh.face_half_edges(face).find(|&h| mesh.origin(h).index() == v as usize)?;
                Some(Side::Corner(self.corners.iter().map(|c| c.corner_value(h)).collect()))
            }
            VertexKey::Edge { edge, .. } if self.seams[edge as usize] => Some(Side::Face(face.index() as u32)),
            _ => None,
        }
    }
}

/// What a tessellation's sinks get of the channels: per vertex its values (at its creator's
/// parameter), and an extra entry per further side of a seam through a vertex, with that
/// side's parameter and values, which that side's triangle corners index.
#[derive(Debug, Default)]
pub(super) struct ChannelEntries {
    /// `stride` values per vertex, in vertex order.
    pub(super) own: Vec<f64>,
    /// Per extra entry, its vertex and the parameter its side evaluates at.
    pub(super) splits: Vec<(u32, SurfaceParameter)>,
    /// `stride` values per extra entry.
    pub(super) split_values: Vec<f64>,
    /// Per root, per leaf, per ring vertex: the vertex, or the extra entry its face takes.
    pub(super) ring_entries: Vec<Vec<Vec<u32>>>,
}

impl QuadtreeTessellator {
    /// The channels' entries of a tessellation whose vertices are `evaluated` (made at
    /// `creators`' root points) and whose leaves' polygons are `rings` (per root); empty
    /// without channels.
    ///
    /// # Errors
    /// [`TessError::Surface`] if a channel's stencil fails.
    pub(super) fn channel_entries(
        &self,
        parallel: bool,
        evaluated: &[TessVertex<'_>],
        rings: &[Vec<Ring>],
        creators: &[(usize, i64, i64)],
    ) -> Result<ChannelEntries, TessError> {
        let mut out = ChannelEntries::default();
        if self.channels.is_empty() {
            return Ok(out);
        }
        let at = |p: &SurfaceParameter| {
            let mut values = Vec::with_capacity(self.channels.stride());
            self.channels.eval(p.face, p.u, p.v, &mut values)?;
            Ok::<_, TessError>(values)
        };
        out.own = crate::par::try_map(parallel, evaluated, |vertex| at(&vertex.parameter))?.concat();
        let mesh = self.levels.mesh(0);
        let mut sides: HashMap<(u32, Side), u32> = HashMap::new();
        let first = evaluated.len() as u32;
        for (root, root_rings) in self.roots.iter().zip(rings) {
            let mut entries = Vec::with_capacity(root_rings.len());
            for (ring, params) in root_rings {
                let entry = ring.iter().zip(params).map(|(&id, &(x, y))| {
                    let Some(side) = self.channels.side(mesh, self.key(*root, x, y), root.face) else { return id };
                    let (r, cx, cy) = creators[id as usize];
                    let creator = self.roots[r];
                    if self.channels.side(mesh, self.key(creator, cx, cy), creator.face).as_ref() == Some(&side) {
                        return id;
                    }
                    *sides.entry((id, side)).or_insert_with(|| {
                        let (u, v) = bfr(*root, x, y);
                        out.splits.push((id, SurfaceParameter { face: root.face, u, v }));
                        first + out.splits.len() as u32 - 1
                    })
                });
                entries.push(entry.collect());
            }
            out.ring_entries.push(entries);
        }
        out.split_values = crate::par::try_map(parallel, &out.splits, |(_, p)| at(p))?.concat();
        Ok(out)
    }
}
