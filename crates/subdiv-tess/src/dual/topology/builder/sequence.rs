//! The order of the build — every face's cells, then each face's edges, then every vertex —
//! and its cut into chunks for a streamed tessellation: a chunk's vertices and triangles are
//! consecutive in the whole output, so each is evaluated and written like a whole topology.

use super::*;

impl Builder<'_> {
    /// The topology at `rates` with `rings` around extraordinary points (both checked by the
    /// caller; rings only under a quad split), reusing `out`'s allocations.
    pub(crate) fn build(
        &mut self,
        domains: &[PackedDomain],
        rates: &[u32],
        rings: Option<&RingDepths>,
        out: &mut Topology,
    ) {
        std::mem::swap(&mut self.out, out);
        let whole: Result<(), std::convert::Infallible> =
            self.build_chunks(domains, rates, rings, None, 0, |_, _, _| unreachable!("one chunk"));
        let Ok(()) = whole;
        let o = &mut self.out;
        // The extra normals after every vertex: points `vertex_count..`, their sites after
        // every vertex's.
        o.extra_base = o.vertex_count;
        o.extra.clone_from(&self.buf.extra_vertices);
        o.sites.extend_from_slice(&self.buf.extra_sites);
        std::mem::swap(&mut self.out, out);
    }

    /// [`build`](Self::build) by chunks: whenever the topology being built holds at least
    /// `chunk` vertices and triangles (`None`: never), it goes to `emit` with the number of its
    /// first vertex and first triangle in the whole output, and the next chunk starts empty. A
    /// chunk's vertices are numbered from 0 in its blocks and sites (what the evaluation
    /// reads), its triangles' corners in the whole output's numbering. The last chunk stays in
    /// the builder (`build` takes it; [`finish_chunks`](Self::finish_chunks) emits it). The
    /// extra normals are numbered from `extra_base` on (in chunks: the whole vertex count,
    /// predicted by the caller) and are not in any chunk: see
    /// [`extra_topology`](Self::extra_topology).
    pub(crate) fn build_chunks<E>(
        &mut self,
        domains: &[PackedDomain],
        rates: &[u32],
        rings: Option<&RingDepths>,
        chunk: Option<u32>,
        extra_base: u32,
        mut emit: impl FnMut(&mut Topology, u32, u32) -> Result<(), E>,
    ) -> Result<(), E> {
        self.buf.rates.clear();
        self.buf.rates.extend_from_slice(rates);
        match rings {
            Some(r) => self.buf.rings.clone_from(r),
            None => {
                let RingDepths { vertices, centres, graded } = &mut self.buf.rings;
                vertices.clear();
                centres.clear();
                graded.clear();
            }
        }
        self.first = (0, 0);
        self.out.extra_base = extra_base;
        self.clear_chunk();
        self.buf.faces.clear();
        self.buf.border.clear();
        self.buf.extra_sites.clear();
        self.buf.extra_vertices.clear();
        self.buf.extra_vertex_sites.clear();
        let full = |b: &Self| chunk.is_some_and(|c| b.out.vertex_count + b.out.triangle_count() >= c);
        for f in 0..domains.len() {
            self.face(f, domains[f].get(), rates[f]);
            if full(self) {
                self.emit_chunk(&mut emit)?;
            }
        }
        for f in self.mesh.face_ids() {
            if self.buf.faces[f.index()].is_none() {
                continue;
            }
            for h in self.mesh.face_half_edges(f) {
                self.edge(h);
            }
            if full(self) {
                self.emit_chunk(&mut emit)?;
            }
        }
        for v in self.mesh.vertices() {
            self.vertex(v);
            if full(self) {
                self.emit_chunk(&mut emit)?;
            }
        }
        Ok(())
    }

    /// Emits the last chunk of [`build_chunks`](Self::build_chunks) (if it holds anything)
    /// and returns the whole output's vertex count, its extra normals' count and its triangle
    /// count.
    pub(crate) fn finish_chunks<E>(
        &mut self,
        mut emit: impl FnMut(&mut Topology, u32, u32) -> Result<(), E>,
    ) -> Result<(u32, u32, u32), E> {
        if self.out.vertex_count + self.out.triangle_count() > 0 {
            self.emit_chunk(&mut emit)?;
        }
        Ok((self.first.0, self.buf.extra_vertices.len() as u32, self.first.1))
    }

    /// The extra normals of the last [`build_chunks`](Self::build_chunks) as a topology of
    /// their own, into `out`: first their vertices (at those vertices' own sites, evaluated as
    /// the chunks evaluated them, so that each extra normal's position is its vertex's, bit
    /// for bit), then the extra normals, no triangles.
    pub(crate) fn extra_topology(&self, out: &mut Topology) {
        let extras = self.buf.extra_vertices.len() as u32;
        out.clear();
        out.vertex_count = extras;
        out.extra_base = extras;
        out.sites.extend_from_slice(&self.buf.extra_vertex_sites);
        out.sites.extend_from_slice(&self.buf.extra_sites);
        out.extra.extend(0..extras);
    }

    /// Hands the chunk built so far to `emit` and starts the next one.
    fn emit_chunk<E>(&mut self, emit: &mut impl FnMut(&mut Topology, u32, u32) -> Result<(), E>) -> Result<(), E> {
        let (vertices, triangles) = (self.out.vertex_count, self.out.triangle_count());
        emit(&mut self.out, self.first.0, self.first.1)?;
        self.first = (self.first.0 + vertices, self.first.1 + triangles);
        self.clear_chunk();
        Ok(())
    }

    /// Empties the topology being built (its allocations kept), but for its extra base.
    fn clear_chunk(&mut self) {
        let extra_base = self.out.extra_base;
        self.out.clear();
        self.out.extra_base = extra_base;
    }

    /// The whole output's number of the next vertex made.
    pub(super) fn next_vertex(&self) -> u32 {
        self.first.0 + self.out.vertex_count
    }
}
