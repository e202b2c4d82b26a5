//! Face-varying channels through the dual tessellation: each channel is a subdivision surface
//! over its own topology ([`ChannelSurface`]), evaluated exactly at every output point's site.
//!
//! The topology cuts every seam as a border (the builder's `is_border`), so a point never lies
//! between two faces whose values differ: points on a seam are evaluated once per side (the
//! second side's as an extra normal, at the same point of the edge in its own face), and a
//! crease vertex's further runs, between seams, take their own values at the vertex as they
//! take their own normals. Channels do not move with the cage, so the animation paths keep them.

use glam::DVec3;
use subdiv_mesh::{FaceId, FaceVaryingInterpolation, Mesh};
use subdiv_schemes::{ChannelSurface, RefineOptions, Scheme};
use subdiv_stencil::LinearEvaluator;

use super::eval::Evaluator;
use super::topology::{Site, Topology};
use crate::{TessChannels, TessError};

/// The carried channels of one mesh: their names and sizes, and per channel the dual evaluator
/// of its surface with its last values.
#[derive(Debug, Default)]
pub(crate) struct Channels {
    names: Vec<String>,
    dimensions: Vec<usize>,
    surfaces: Vec<Surface>,
}

/// A channel's surface as the dual tessellator evaluates it, at the sites of the positions'
/// topology (a site is a face and a parameter; both meshes have the same faces).
#[derive(Debug)]
struct Surface {
    route: Route,
    values: Vec<DVec3>,
    /// The channel surface's normals: computed by the evaluator, not used.
    normals: Vec<DVec3>,
}

/// How a channel's surface is evaluated.
#[derive(Debug)]
enum Route {
    /// The same routes as the positions (templates, bicubic grids, exact records) over the
    /// channel's own patches.
    Evaluated(Box<Evaluator>),
    /// A channel linear over every face ([`FaceVaryingInterpolation::All`], the default: the
    /// bilinear or linear-triangle split, whose limit over a face is the bilinear or linear
    /// interpolation of its corners' values, over `Bfr` sub-faces for N-gons): each point is
    /// its face's corners combined directly ([`LinearEvaluator`]). Building a whole evaluator
    /// for it (patch levels, templates, records) was a quarter of a fresh process's
    /// tessellation of a textured mesh.
    Linear(Box<LinearEvaluator>),
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
            let route = match LinearEvaluator::new(&surface)? {
                Some(linear) => Route::Linear(Box::new(linear)),
                None => Route::Evaluated(Box::new(Evaluator::new(surface.scheme(), surface.mesh())?)),
            };
            channels.surfaces.push(Surface { route, values: Vec::new(), normals: Vec::new() });
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
            match &mut s.route {
                Route::Evaluated(evaluator) => {
                    evaluator.prepare(t, rates, parallel)?;
                    evaluator.evaluate_points(t, parallel, &mut s.values, &mut s.normals);
                }
                Route::Linear(linear) => {
                    let mut row = Vec::new();
                    s.values.clear();
                    s.values.extend((0..t.point_count()).map(|k| {
                        linear_row(linear, t.site(k), &mut row);
                        let values = linear.values();
                        row.iter().fold(DVec3::ZERO, |acc, &(c, [w, _, _])| acc + w * values[c as usize])
                    }));
                }
            }
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

    /// [`Evaluator::fix_fits`] of every channel surface evaluated as the positions are.
    pub(crate) fn fix_fits(&mut self, rates: Option<&[u32]>) {
        for s in &mut self.surfaces {
            if let Route::Evaluated(evaluator) = &mut s.route {
                evaluator.fix_fits(rates);
            }
        }
    }

    /// Whether the evaluated points get texture coordinates (see [`TessChannels::texcoords`]).
    pub(crate) fn has_texcoords(&self) -> bool {
        self.names.iter().zip(&self.dimensions).any(|(n, &d)| n == subdiv_mesh::Channel::UV && d >= 2)
    }

    /// The names of the channels, in order.
    pub(crate) fn names(&self) -> &[String] {
        &self.names
    }

    /// Channel `k`'s evaluation at `t`'s points as a plan over its own control values (its
    /// surface's mesh: the channel's values padded to three components), and those values.
    pub(crate) fn plan(&self, k: usize, t: &Topology) -> (crate::dual::EvaluationPlan, &[DVec3]) {
        match &self.surfaces[k].route {
            Route::Evaluated(evaluator) => (evaluator.plan(t), evaluator.levels().mesh(0).positions()),
            Route::Linear(linear) => {
                let values = linear.values();
                let mut plan = crate::dual::EvaluationPlan::over_points(values.len() as u32);
                let (mut row, mut ids, mut weights) = (Vec::new(), Vec::new(), [Vec::new(), Vec::new(), Vec::new()]);
                for v in 0..t.point_count() {
                    linear_row(linear, t.site(v), &mut row);
                    ids.clear();
                    ids.extend(row.iter().map(|&(c, _)| c));
                    for (r, out) in weights.iter_mut().enumerate() {
                        out.clear();
                        out.extend(row.iter().map(|(_, w)| w[r]));
                    }
                    plan.push_general(&ids, [&weights[0], &weights[1], &weights[2]]);
                }
                (plan, values)
            }
        }
    }
}

/// A linear channel's value at `site` as a combination of its face's corners.
fn linear_row(linear: &LinearEvaluator, site: Site, row: &mut Vec<(u32, [f64; 3])>) {
    let (u, v) = site.point.to_f64();
    linear.corner_weights(FaceId::new(site.face), u, v, row);
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

#[cfg(test)]
mod tests {
    use subdiv_mesh::{PolygonSoup, shapes};
    use subdiv_schemes::Builtin;

    use super::*;
    use crate::dual::topology::Builder;

    fn textured(soup: PolygonSoup) -> Mesh {
        Mesh::build(shapes::face_charts(soup)).unwrap()
    }

    /// The linear route gives the values (and its plan the values) the general evaluator gives
    /// over the channel's bilinear or linear-triangle surface: on quads, triangles under a quad
    /// split and N-gons (`Bfr` sub-faces), and on Loop's triangles, at mixed rates.
    #[test]
    fn linear_channels_equal_the_evaluated_surface() {
        let cases = [
            (Builtin::CatmullClark, textured(shapes::ngon_prism(5))),
            (Builtin::CatmullClark, textured(shapes::tetrahedron())),
            (Builtin::CatmullClark, textured(shapes::default_model())),
            (Builtin::Loop, textured(shapes::icosahedron())),
        ];
        for (builtin, mesh) in cases {
            let scheme = builtin.scheme();
            let triangle = scheme.split() == subdiv_schemes::Split::Triangle;
            let surface = ChannelSurface::new(&mesh, &mesh.channels()[0], scheme, &RefineOptions::DEFAULT).unwrap();
            assert!(surface.is_linear());
            let mut evaluator = Evaluator::new(surface.scheme(), surface.mesh()).unwrap();
            let positions = Evaluator::new(scheme, &mesh).unwrap();
            let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 2 + f % 4).collect();
            let mut topo = Topology::default();
            Builder::new(&mesh, triangle, false).build(positions.domains(), &rates, None, &mut topo);
            evaluator.prepare(&topo, &rates, false).unwrap();
            let (mut want, mut normals) = (Vec::new(), Vec::new());
            evaluator.evaluate_points(&topo, false, &mut want, &mut normals);
            let linear = LinearEvaluator::new(&surface).unwrap().unwrap();
            let linear = Surface { route: Route::Linear(Box::new(linear)), values: Vec::new(), normals: Vec::new() };
            let mut channels = Channels { names: vec!["uv".into()], dimensions: vec![2], surfaces: vec![linear] };
            let mut out = TessChannels::default();
            channels.evaluate(&topo, &rates, false, &mut out).unwrap();
            let got = &channels.surfaces[0].values;
            assert_eq!(got.len(), want.len());
            let worst = got.iter().zip(&want).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
            assert!(worst < 1e-12, "{builtin:?}: linear route off by {worst:e}");
            let (plan, values) = channels.plan(0, &topo);
            let (mut planned, mut plan_normals) = (Vec::new(), Vec::new());
            plan.evaluate(values, &mut planned, &mut plan_normals);
            let worst = planned.iter().zip(&want).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
            assert!(worst < 1e-12, "{builtin:?}: linear plan off by {worst:e}");
        }
    }
}
