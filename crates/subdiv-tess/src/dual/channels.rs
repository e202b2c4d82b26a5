//! Face-varying channels through the dual tessellation: each channel is a subdivision surface
//! over its own topology ([`ChannelSurface`]), evaluated exactly at every output point's site.
//!
//! The topology cuts every seam as a border (the builder's `is_border`), so a point never lies
//! between two faces whose values differ: points on a seam are evaluated once per side (the
//! second side's as an extra normal, at the same point of the edge in its own face), and a
//! crease vertex's further runs, between seams, take their own values at the vertex as they
//! take their own normals. Channels do not move with the cage, so the animation paths keep them.

use glam::DVec3;
use subdiv_mesh::{FaceVaryingInterpolation, Mesh};
use subdiv_schemes::{ChannelSurface, RefineOptions, Scheme};

use super::eval::Evaluator;
use super::topology::Topology;
use crate::{TessChannels, TessError};

/// The carried channels of one mesh: their names and sizes, and per channel the dual evaluator
/// of its surface with its last values.
#[derive(Debug, Default)]
pub(crate) struct Channels {
    names: Vec<String>,
    dimensions: Vec<usize>,
    surfaces: Vec<Surface>,
}

/// A channel's surface as the dual tessellator evaluates it: the same routes as the positions
/// (templates, bicubic grids, exact records) over the channel's own patches, at the sites of
/// the positions' topology (a site is a face and a parameter; both meshes have the same faces).
#[derive(Debug)]
struct Surface {
    evaluator: Evaluator,
    values: Vec<DVec3>,
    /// The channel surface's normals: computed by the evaluator, not used.
    normals: Vec<DVec3>,
}

impl Channels {
    /// The channels of `mesh` under `scheme` in face-varying mode `mode` (`None`: the mesh's
    /// tag, else `all`), and per edge whether it is a seam of one of them.
    ///
    /// # Errors
    /// [`TessError::Scheme`] for a scheme without face-varying rules or a channel of more than
    /// three components; [`TessError::Surface`] if a channel's surface has no patches.
    pub(crate) fn new(
        scheme: &Scheme,
        mesh: &Mesh,
        mode: Option<FaceVaryingInterpolation>,
    ) -> Result<(Self, Vec<bool>), TessError> {
        let mut channels = Self::default();
        let mut seams = Vec::new();
        if mesh.channels().is_empty() {
            return Ok((channels, seams));
        }
        let options = RefineOptions { face_varying: mode, ..RefineOptions::DEFAULT };
        seams.resize(mesh.edge_count(), false);
        for channel in mesh.channels() {
            let surface = ChannelSurface::new(mesh, channel, scheme, &options)
                .map_err(|e| TessError::Scheme { scheme: scheme.name().to_string(), reason: e.to_string() })?;
            let evaluator = Evaluator::new(surface.scheme(), surface.mesh())?;
            channels.surfaces.push(Surface { evaluator, values: Vec::new(), normals: Vec::new() });
            channels.names.push(channel.name().to_owned());
            channels.dimensions.push(channel.dimension());
            for (e, seam) in mesh.edges().zip(&mut seams) {
                *seam |= mesh.is_seam(channel, e);
            }
        }
        Ok((channels, seams))
    }

    /// Every point's values at `t`'s sites (the vertices, then the extra normals; built at
    /// `rates`) into `out`.
    ///
    /// # Errors
    /// [`TessError::Surface`] if a channel's stencil fails.
    pub(crate) fn evaluate(
        &mut self,
        t: &Topology,
        rates: &[u32],
        parallel: bool,
        out: &mut TessChannels,
    ) -> Result<(), TessError> {
        out.clear();
        if self.names.is_empty() {
            return Ok(());
        }
        for s in &mut self.surfaces {
            s.evaluator.prepare(t, rates, parallel)?;
            s.evaluator.evaluate_points(t, parallel, &mut s.values, &mut s.normals);
        }
        out.names.clone_from(&self.names);
        out.dimensions.clone_from(&self.dimensions);
        let points = t.point_count() as usize;
        out.values.reserve(points * out.stride());
        for k in 0..points {
            for (s, &dimension) in self.surfaces.iter().zip(&self.dimensions) {
                out.values.extend_from_slice(&s.values[k].to_array()[..dimension]);
            }
        }
        Ok(())
    }

    /// The names of the channels, in order.
    pub(crate) fn names(&self) -> &[String] {
        &self.names
    }

    /// Channel `k`'s evaluation at `t`'s points as a plan over its own control values (its
    /// surface's mesh: the channel's values padded to three components), and those values.
    pub(crate) fn plan(&self, k: usize, t: &Topology) -> (crate::dual::EvaluationPlan, &[DVec3]) {
        let evaluator = &self.surfaces[k].evaluator;
        (evaluator.plan(t), evaluator.levels().mesh(0).positions())
    }
}

/// The texture coordinates of `channels` (if it has them) as f32, two per point, into `out`.
pub(crate) fn write_texcoords(channels: &TessChannels, out: &mut Vec<f32>) {
    out.clear();
    if let Some(start) = channels.texcoords() {
        let stride = channels.stride();
        out.reserve(2 * channels.values.len() / stride);
        for point in channels.values.chunks_exact(stride) {
            out.extend_from_slice(&[point[start] as f32, point[start + 1] as f32]);
        }
    }
}
