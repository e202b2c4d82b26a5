//! The flat f32 paths of the dual tessellator (what renderers upload and GLB files hold): one
//! normal per vertex, a crease vertex split once per extra normal. Whole
//! ([`DualTessellator::tessellate_flat`], and the animation path
//! [`DualTessellator::update_cage_flat`]) or in chunks of the topology
//! ([`DualTessellator::tessellate_stream`] into a [`FlatStream`]), the same bytes either way.

use glam::DVec3;
use subdiv_mesh::Mesh;

use super::topology::{Builder, PackedDomain, Topology};
use super::{DualTessellator, TopologyBuilder, channels, topology};
use crate::{FlatStream, TessError, par};

/// Flat output buffers for GPUs, GLB files and benchmarks: one normal per vertex, so a
/// vertex with extra normals (on an infinitely sharp crease or a channel's seam, see
/// [`TessMesh`]) is split.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatMesh {
    /// Per flat vertex `px py pz nx ny nz`: the [`TessMesh`]'s vertices, then one per extra
    /// normal (its vertex's position, that normal).
    pub vertices: Vec<f32>,
    /// Per flat vertex its texture coordinates `s t` (the `"uv"` channel's first two
    /// components, [`TessChannels::texcoords`](crate::TessChannels::texcoords)), if the
    /// tessellation carries them; else empty.
    pub texcoords: Vec<f32>,
    /// Three indices per triangle, counter-clockwise: its [`triangle_normals`](TessMesh::triangle_normals).
    pub indices: Vec<u32>,
}

impl DualTessellator {
    /// The animation path straight into flat f32 buffers (what a renderer uploads): as
    /// [`update_cage`](Self::update_cage) followed by [`write_flat`](Self::write_flat), without
    /// the f64 positions and normals in between, so [`mesh`](Self::mesh) keeps the previous
    /// cage's positions and normals until the next [`update_cage`](Self::update_cage) or
    /// [`tessellate`](Self::tessellate). Reuses `out`'s allocations (buffers of the right
    /// lengths are overwritten in place).
    ///
    /// # Errors
    /// As [`update_cage`](Self::update_cage).
    pub fn update_cage_flat(&mut self, positions: &[DVec3], out: &mut FlatMesh) -> Result<(), TessError> {
        self.check_cage(positions)?;
        self.evaluator.set_cage(positions);
        let (t, parallel) = (&self.topology, self.options.parallelism.forks());
        // The same indices every frame: copied from the output's triangles, or from a copy
        // made once (a copy runs at the memory's speed, which writing them anew does not reach
        // on large meshes).
        let indices = if self.output_current {
            self.output.triangle_normals.as_flattened()
        } else {
            if self.flat_indices.is_empty() && t.triangle_count() > 0 {
                write_indices(t, parallel, &mut self.flat_indices);
            }
            &self.flat_indices
        };
        let evaluator = &self.evaluator;
        // The channels do not move with the cage: the values of the last tessellation.
        channels::write_texcoords(&self.channel_values, &mut out.texcoords);
        beside(
            t,
            parallel,
            out,
            |vertices| {
                evaluator.evaluate_flat(t, parallel, vertices);
                Ok(())
            },
            |out| copy_indices(indices, parallel, out),
        )
    }

    /// [`tessellate`](Self::tessellate) straight into flat f32 buffers (what a renderer
    /// uploads; the same values as [`tessellate`](Self::tessellate) then
    /// [`write_flat`](Self::write_flat)), without the f64 positions and normals and without the
    /// vertices' and triangles' surface parameters. Afterwards [`mesh`](Self::mesh) is empty
    /// until the next [`update_cage`](Self::update_cage), which makes the whole [`TessMesh`] of
    /// these rates, or [`tessellate`](Self::tessellate);
    /// [`update_cage_flat`](Self::update_cage_flat) works as after
    /// [`tessellate`](Self::tessellate). Reuses `out`'s allocations (buffers of the right
    /// lengths are overwritten in place).
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate); `out` is then left empty if the rates were
    /// accepted (the failure came from a stencil), untouched if not.
    pub fn tessellate_flat(&mut self, rates: &[u32], out: &mut FlatMesh) -> Result<(), TessError> {
        self.check_rates(rates)?;
        let done = self.build_flat(rates, out).and_then(|()| {
            self.channels.evaluate(&self.topology, rates, self.options.parallelism.forks(), &mut self.channel_values)
        });
        match done {
            Ok(()) => channels::write_texcoords(&self.channel_values, &mut out.texcoords),
            Err(_) => {
                out.vertices.clear();
                out.texcoords.clear();
                out.indices.clear();
            }
        }
        self.settle(rates, done)?;
        // Cleared, not dropped: the next `update_cage` or `tessellate` refills the buffers.
        self.output.clear();
        Ok(())
    }

    /// [`tessellate_flat`](Self::tessellate_flat) in chunks: the topology is built, evaluated
    /// and handed to `sink` a chunk at a time ([`DualOptions::chunk`]), so that what the call
    /// holds is the mesh's preparation and one chunk, not the whole output (a file writer
    /// such as `subdiv-io`'s GLB stream then holds none of it). The sink gets the same bytes as
    /// [`tessellate_flat`](Self::tessellate_flat)'s buffers: the chunks follow the output's own
    /// order (the faces' cells, the edges' strips, the vertices' polygons), each point is made
    /// once and evaluated as in one call (an extra normal's position is its vertex's, bit for
    /// bit), and the extra normals come last. Returns the numbers of flat vertices and
    /// triangles.
    ///
    /// Afterwards the tessellator holds no tessellation: [`mesh`](Self::mesh) and
    /// [`rates`](Self::rates) are empty and the animation paths evaluate nothing until the next
    /// [`tessellate`](Self::tessellate) (a streamed output is not kept).
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate). The sink may then have had some chunks, and gets
    /// no [`end`](FlatStream::end).
    pub fn tessellate_stream<S: FlatStream + ?Sized>(
        &mut self,
        rates: &[u32],
        sink: &mut S,
    ) -> Result<(usize, usize), TessError> {
        self.check_rates(rates)?;
        self.rates.clear();
        self.topology = Topology::default();
        self.output.clear();
        let Self { evaluator, builder, channels, channel_values, options, .. } = self;
        let parallel = options.parallelism.forks();
        let (levels, domains) = evaluator.shared();
        let mesh = levels.mesh(0);
        let vertices = topology::predicted_vertices_cut(mesh, levels.split(), rates, None, Some(&builder.seams)) as u32;
        let texcoords = channels.has_texcoords();
        // Each chunk routes its faces to templates as one call would (the budget is the call's).
        evaluator.fix_fits(Some(rates));
        channels.fix_fits(Some(rates));
        sink.begin(vertices as usize, texcoords);
        let mut buffers = FlatMesh::default();
        let mut emit = |t: &mut Topology, first: u32, first_triangle: u32| -> Result<(), TessError> {
            evaluator.prepare(t, rates, parallel)?;
            buffers.vertices.resize(6 * t.point_count() as usize, 0.0);
            evaluator.evaluate_flat(t, parallel, &mut buffers.vertices);
            channels.evaluate(t, rates, parallel, channel_values)?;
            channels::write_texcoords(channel_values, &mut buffers.texcoords);
            write_indices(t, parallel, &mut buffers.indices);
            // The extra normals' chunk: its vertices were handed on with their chunks.
            let (skip, at) = if t.triangle_count() == 0 && !t.extra.is_empty() {
                (t.vertex_count as usize, vertices)
            } else {
                (0, first)
            };
            let texcoords = buffers.texcoords.get(2 * skip..).unwrap_or_default();
            sink.vertices(at as usize, &buffers.vertices[6 * skip..], texcoords);
            sink.triangles(first_triangle as usize, &buffers.indices);
            Ok(())
        };
        let streamed = builder.stream(mesh, &domains, rates, vertices, options.chunk, &mut emit);
        evaluator.fix_fits(None);
        channels.fix_fits(None);
        let (made, extras, triangles) = streamed?;
        if made != vertices {
            return Err(TessError::Internal(format!("{made} vertices made where {vertices} were predicted")));
        }
        let flat = (made + extras) as usize;
        sink.end(flat, triangles as usize);
        Ok((flat, triangles as usize))
    }

    /// [`tessellate_flat`](Self::tessellate_flat) after its rates' check: the topology, then
    /// its indices beside (on a second thread, for large calls) the preparation and evaluation.
    fn build_flat(&mut self, rates: &[u32], out: &mut FlatMesh) -> Result<(), TessError> {
        let Self { evaluator, builder, topology, options, .. } = self;
        builder.build(evaluator.levels().mesh(0), evaluator.domains(), rates, None, topology);
        let (t, parallel) = (&*topology, options.parallelism.forks());
        // The indices go beside the preparation too (they need the topology alone): the second
        // thread is then awake when the evaluation shares its pieces, where after the
        // preparation alone it would have gone to sleep (and waking one costs tens of
        // microseconds in a virtual machine).
        beside(
            t,
            parallel,
            out,
            |vertices| {
                evaluator.prepare(t, rates, parallel)?;
                evaluator.evaluate_flat(t, parallel, vertices);
                Ok(())
            },
            |indices| write_indices(t, parallel, indices),
        )
    }
}

impl TopologyBuilder {
    /// The topology of `mesh` (level 0) at `rates` (checked) in chunks of at least `chunk`
    /// vertices and triangles, each to `emit` with its first vertex and triangle in the whole
    /// output; then, if there are extra normals, their own topology (their vertices, then
    /// them, no triangles; the first extra normal numbered `vertices`, the predicted vertex
    /// count). Returns the vertices made, the extra normals and the triangles. No polygons.
    fn stream<E>(
        &mut self,
        mesh: &Mesh,
        domains: &[PackedDomain],
        rates: &[u32],
        vertices: u32,
        chunk: u32,
        emit: &mut impl FnMut(&mut Topology, u32, u32) -> Result<(), E>,
    ) -> Result<(u32, u32, u32), E> {
        let buffers = std::mem::take(&mut self.buffers);
        let mut builder = Builder::with_buffers(mesh, &self.seams, self.triangle, false, buffers);
        let streamed = builder.build_chunks(domains, rates, None, Some(chunk), vertices, &mut *emit).and_then(|()| {
            let (made, extras, triangles) = builder.finish_chunks(&mut *emit)?;
            if extras > 0 {
                let mut t = Topology::default();
                builder.extra_topology(&mut t);
                emit(&mut t, made, triangles)?;
            }
            Ok((made, extras, triangles))
        });
        self.buffers = builder.into_buffers();
        streamed
    }
}

/// `t`'s flat triangles (their corners' normals: the indices of the flat vertices) into
/// `indices` (resized), written straight from the topology's runs: no stored copy of most of
/// them.
fn write_indices(t: &Topology, parallel: bool, indices: &mut Vec<u32>) {
    indices.resize(3 * t.triangle_count() as usize, 0);
    t.write_triangle_normals(indices, parallel);
}

/// The most triangles for which the flat paths write their indices after the evaluation, on
/// the same thread: below, waking a second thread for them costs more than it saves (the cube
/// at rate 8, 2 threads, full path: 126-131 M triangles/s with it, 104-108 without; `70f0147`,
/// docs/perf-log.md).
const BESIDE: u32 = 1 << 12;

/// The flat paths' two halves for the vertices and triangles of `t`: `evaluate` fills
/// `out.vertices` (resized first, every value to be overwritten: a buffer of the right length
/// is kept as is) and `indices` fills `out.indices`, on two of rayon's threads when `parallel`
/// and there are more than [`BESIDE`] triangles (the output is the same), else one after the
/// other (the indices only if the evaluation succeeds).
fn beside<E: Send>(
    t: &Topology,
    parallel: bool,
    out: &mut FlatMesh,
    evaluate: impl FnOnce(&mut [f32]) -> Result<(), E> + Send,
    indices: impl FnOnce(&mut Vec<u32>) + Send,
) -> Result<(), E> {
    let FlatMesh { vertices, indices: out_indices, .. } = out;
    vertices.resize(6 * t.point_count() as usize, 0.0);
    if parallel && t.triangle_count() > BESIDE {
        par::join(true, || evaluate(vertices), || indices(out_indices)).0
    } else {
        evaluate(vertices)?;
        indices(out_indices);
        Ok(())
    }
}

/// The fewest indices [`copy_indices`] copies on rayon's threads. Not measured on its own
/// (it came with the animation path's copy, `f7b878e`); a copy below it is a few microseconds.
const PARALLEL_COPY: usize = 1 << 16;

/// `indices` into `out` (which keeps its allocation), on rayon's threads if `parallel` and
/// there are enough to be worth waking them (a copy of tens of megabytes at high rates, which
/// one core does at a fraction of the memory's speed).
fn copy_indices(indices: &[u32], parallel: bool, out: &mut Vec<u32>) {
    out.clear();
    if parallel && indices.len() >= PARALLEL_COPY {
        par::extend_map(true, out, indices, |&k| k);
    } else {
        out.extend_from_slice(indices);
    }
}
