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
use subdiv_stencil::FaceDomain;

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
    /// its face's corners combined directly ([`linear_row`]). Building a whole evaluator for it
    /// (patch levels, templates, records) was a quarter of a fresh process's tessellation of a
    /// textured mesh.
    Linear(Box<ChannelSurface>),
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
            let route = if surface.is_linear() {
                Route::Linear(Box::new(surface))
            } else {
                Route::Evaluated(Box::new(Evaluator::new(surface.scheme(), surface.mesh())?))
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
                Route::Linear(surface) => {
                    let mut row = Vec::new();
                    s.values.clear();
                    s.values.extend((0..t.point_count()).map(|k| {
                        linear_row(surface, t.site(k), &mut row);
                        let values = surface.mesh().positions();
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

    /// The names of the channels, in order.
    pub(crate) fn names(&self) -> &[String] {
        &self.names
    }

    /// Channel `k`'s evaluation at `t`'s points as a plan over its own control values (its
    /// surface's mesh: the channel's values padded to three components), and those values.
    pub(crate) fn plan(&self, k: usize, t: &Topology) -> (crate::dual::EvaluationPlan, &[DVec3]) {
        match &self.surfaces[k].route {
            Route::Evaluated(evaluator) => (evaluator.plan(t), evaluator.levels().mesh(0).positions()),
            Route::Linear(surface) => {
                let values = surface.mesh().positions();
                let mut plan = crate::dual::EvaluationPlan::over_points(values.len() as u32);
                let (mut row, mut ids, mut weights) = (Vec::new(), Vec::new(), [Vec::new(), Vec::new(), Vec::new()]);
                for v in 0..t.point_count() {
                    linear_row(surface, t.site(v), &mut row);
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

/// A linear channel's value at `site` as a combination of its face's corners (vertices of
/// the channel's mesh) into `row`: per corner, its weights in the value and in the two
/// derivatives of the face's parameters. A quad's is the bilinear interpolation, a
/// triangle's (triangle split) the linear one; an N-gon's point lies on a `Bfr` sub-face, the
/// quad of its corner `s`, the midpoints of its sides `s` and `s − 1` and its centroid (the
/// bilinear split's first level), bilinear there.
fn linear_row(surface: &ChannelSurface, site: Site, row: &mut Vec<(u32, [f64; 3])>) {
    let mesh = surface.mesh();
    let corners = mesh.face_vertices(FaceId::new(site.face));
    let n = corners.len();
    let id = |k: usize| corners[k % n].index() as u32;
    let (u, v) = site.point.to_f64();
    row.clear();
    let bilinear = |u: f64, v: f64| {
        [
            [(1.0 - u) * (1.0 - v), v - 1.0, u - 1.0],
            [u * (1.0 - v), 1.0 - v, -u],
            [u * v, v, u],
            [(1.0 - u) * v, -v, 1.0 - u],
        ]
    };
    match FaceDomain::of(surface.scheme().split(), n) {
        Some(FaceDomain::Triangle) => {
            row.extend([(id(0), [1.0 - u - v, -1.0, -1.0]), (id(1), [u, 1.0, 0.0]), (id(2), [v, 0.0, 1.0])]);
        }
        Some(FaceDomain::Quad) => row.extend((0..4).map(id).zip(bilinear(u, v))),
        Some(domain @ FaceDomain::SubFaces { .. }) => {
            let (sub, a, b, scale) = domain.child_of_f64(u, v);
            let [w0, w1, w2, w3] = bilinear(a, b).map(|[p, du, dv]| [p, scale * du, scale * dv]);
            // The centroid's share, then each corner's.
            row.extend((0..n).map(|k| (id(k), w2.map(|x| x / n as f64))));
            let mut add = |k: usize, w: [f64; 3], f: f64| {
                let e = &mut row[k % n].1;
                (0..3).for_each(|r| e[r] += f * w[r]);
            };
            add(sub, w0, 1.0);
            add(sub, w1, 0.5);
            add(sub + 1, w1, 0.5);
            add(sub, w3, 0.5);
            add(sub + n - 1, w3, 0.5);
        }
        None => unreachable!("channel surfaces are of primal splits"),
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

#[cfg(test)]
mod tests {
    use subdiv_mesh::{Channel, PolygonSoup, shapes};
    use subdiv_schemes::Builtin;

    use super::*;
    use crate::dual::topology::Builder;

    /// `soup` with a texture channel: per corner, its vertex's `(x + 2y, z − x)` plus a
    /// per-face offset, so every edge is a seam and every face a component of the channel.
    fn textured(mut soup: PolygonSoup) -> Mesh {
        let mut values = Vec::new();
        for (f, face) in soup.faces().enumerate() {
            for v in face {
                let p = soup.positions()[v.index()];
                values.extend([p.x + 2.0 * p.y + f as f64, p.z - p.x]);
            }
        }
        let indices = (0..values.len() as u32 / 2).collect();
        soup.channels.push(Channel::new("uv", 2, values, indices));
        Mesh::build(soup).unwrap()
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
            let linear = Surface { route: Route::Linear(Box::new(surface)), values: Vec::new(), normals: Vec::new() };
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
