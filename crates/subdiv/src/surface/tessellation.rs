//! [`Surface`]'s tessellations: the rate policies' glue, the dual and quadtree tessellators it
//! keeps, parts of a tessellation for batches.

use std::ops::Range;

use subdiv_mesh::{FaceId, Mesh};
use subdiv_schemes::{RefineOptions, Scheme};
use subdiv_tess::rates::{DualRates, ErrorRates, RingDepths, ScreenError, ScreenSpace};
use subdiv_tess::{
    DualOptions, DualTessellator, FlatMesh, FlatStream, QuadtreeOptions, QuadtreeTessellator, TessCounts, TessError,
    TessMesh, TessSink, TessTriangle, TessVertex,
};

use super::Surface;
use crate::Error;
use crate::tessellate::{FaceRates, Method, Rates, TessInfo, TessOptions, Tessellation};

impl Surface {
    /// The per-face rates (and, for a tolerance, the rings around extraordinary points) that
    /// `options.rates` gives the dual tessellator, capped at `options.max_rate` for
    /// [`Rates::Tolerance`] and [`Rates::Screen`].
    ///
    /// # Errors
    /// [`Error::ToleranceBounds`] for a tolerance policy on a mesh the quadtree's bounds do not
    /// take (extraordinary border vertices, schemes other than Catmull-Clark); [`Error::Tess`] for
    /// a face needing more than `max_rate`, a bad tolerance, camera or viewport;
    /// [`Error::Budget`] for rates that would make more than [`TessOptions::max_vertices`]
    /// vertices.
    pub fn face_rates(&mut self, options: &TessOptions) -> Result<FaceRates, Error> {
        let rates = self.policy_rates(options)?;
        self.check_vertex_budget(&rates, options)?;
        Ok(rates)
    }

    /// [`face_rates`](Self::face_rates) before the budget's check.
    fn policy_rates(&mut self, options: &TessOptions) -> Result<FaceRates, Error> {
        let faces = self.mesh.face_count();
        Ok(match &options.rates {
            Rates::Uniform(rate) => FaceRates { faces: vec![*rate; faces], rings: None, epsilon: None },
            Rates::PerFace(rates) => FaceRates { faces: rates.clone(), rings: None, epsilon: None },
            Rates::Tolerance(tolerance) => {
                let mode = self.refine_options.face_varying;
                let bounds = quadtree(&mut self.quadtree, &self.scheme, &self.mesh, mode).map_err(|e| match e {
                    Error::Tess(e) => Error::ToleranceBounds(e),
                    e => e,
                })?;
                let policy = ErrorRates { max_rate: options.max_rate, ..ErrorRates::new(*tolerance) };
                let DualRates { faces, rings } = policy.rates(bounds, &self.mesh).map_err(|e| match e {
                    subdiv_tess::TessError::Unsupported { .. } => Error::ToleranceBounds(e),
                    e => Error::Tess(e),
                })?;
                let epsilon = tolerance.absolute(bounds.diagonal())?;
                FaceRates { faces, rings: Some(rings), epsilon: Some(epsilon) }
            }
            Rates::ScreenError { .. } => return Err(Error::DualScreenError),
            Rates::Screen { camera, viewport, pixels_per_edge } => {
                let policy = ScreenSpace {
                    max_rate: options.max_rate,
                    ..ScreenSpace::new(*camera, *viewport, *pixels_per_edge)
                };
                FaceRates { faces: policy.face_rates(&self.mesh)?, rings: None, epsilon: None }
            }
        })
    }

    /// Tessellates the limit surface: watertight, every vertex an exact limit point with its
    /// unit normal and `Bfr` parameters. The tessellators are kept for the next call (a new
    /// one is made when [`TessOptions::polygons`] or [`TessOptions::parallelism`] change).
    ///
    /// # Errors
    /// [`Error::QuadtreeRates`] for [`Method::Quadtree`] without [`Rates::Tolerance`]; as
    /// [`face_rates`](Self::face_rates); [`Error::Tess`] for a mesh or scheme the tessellator
    /// does not take (the quadtree: Catmull-Clark and Loop meshes; the dual: primal schemes
    /// with sub-patch matrices), rates outside `1..=1024`, or a
    /// tolerance the quadtree cannot meet within its depth and polygon limits.
    pub fn tessellate(&mut self, options: &TessOptions) -> Result<Tessellation, Error> {
        if options.method == Method::Dual {
            // The dual tessellator's own output, copied whole rather than vertex by vertex.
            let (info, rings, tess) = self.prepared_dual(options)?;
            let mesh = match &rings {
                Some(rings) => tess.tessellate_with_rings(&info.rates, rings)?,
                None => tess.tessellate(&info.rates)?,
            };
            return Ok(Tessellation { mesh: mesh.clone(), info });
        }
        let mut mesh = TessMesh::default();
        let info = self.tessellate_into(options, &mut mesh)?;
        // A sink gets the channels' values, not their names.
        let (names, dimensions) = self.quadtree_mut()?.channels();
        mesh.channels.names = names.to_vec();
        mesh.channels.dimensions = dimensions.to_vec();
        Ok(Tessellation { mesh, info })
    }

    /// The part of [`tessellate`](Self::tessellate)'s output (dual method) that faces
    /// `faces` own — their cells, the strips and vertex polygons they make, and the points
    /// those use — for tessellations larger than one machine: each part is a job of its own,
    /// and the points on a part's border are the same bits as the neighbouring part's, so
    /// joining the parts and welding equal points (`subdiv merge`) gives the whole tessellation.
    /// A part costs the whole mesh's patches, the rates of the faces around it and one point
    /// per other face (they are tessellated at rate 1 and left out), except under a tolerance,
    /// whose rings around extraordinary points keep every face at its rate (a part then saves
    /// only the writing).
    ///
    /// ```
    /// use subdiv::mesh::shapes;
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{Surface, TessOptions};
    ///
    /// let mut surface = Surface::build(shapes::default_model(), Builtin::CatmullClark.scheme())?;
    /// let whole = surface.tessellate(&TessOptions::DEFAULT)?;
    /// let half = surface.mesh().face_count() / 2;
    /// let a = surface.tessellate_part(&TessOptions::DEFAULT, 0..half)?;
    /// let b = surface.tessellate_part(&TessOptions::DEFAULT, half..surface.mesh().face_count())?;
    /// assert_eq!(a.mesh.triangles.len() + b.mesh.triangles.len(), whole.mesh.triangles.len());
    /// // Every point of a part is a point of the whole, bit for bit.
    /// let points: std::collections::HashSet<_> = whole.mesh.positions.iter().map(|p| p.to_array().map(f64::to_bits)).collect();
    /// assert!(a.mesh.positions.iter().all(|p| points.contains(&p.to_array().map(f64::to_bits))));
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::FaceRange`] for an empty range, one that starts past the mesh's faces (one that
    /// ends past them stops at the last), or [`Method::Quadtree`]; as
    /// [`tessellate`](Self::tessellate).
    pub fn tessellate_part(&mut self, options: &TessOptions, faces: Range<usize>) -> Result<Tessellation, Error> {
        let count = self.mesh.face_count();
        let refuse = |reason| Error::FaceRange { start: faces.start, end: faces.end, faces: count, reason };
        if faces.is_empty() || faces.start >= count {
            return Err(refuse("a part is a non-empty range that starts at a face of the mesh"));
        }
        // A batch of fixed-size ranges may run past the last face.
        let faces = faces.start..faces.end.min(count);
        if options.method != Method::Dual {
            return Err(refuse(
                "parts are cut from the dual method's tessellation (the quadtree's points depend on every face's leaves)",
            ));
        }
        let FaceRates { faces: rates, rings, epsilon } = self.policy_rates(options)?;
        // The faces around the part's vertices keep their rates: the part's strips and vertex
        // polygons are made with their points. The others take rate 1, unless rings (around
        // extraordinary points, graded to the rates) need them as they are. (A point's bits do
        // not depend on the far faces' rates: each reads only its own face's dual-grid table.)
        let keep_all = rings.is_some();
        let mut near = vec![keep_all; count];
        for f in faces.clone() {
            for &v in self.mesh.face_vertices(FaceId::new(f as u32)) {
                for g in self.mesh.vertex_faces(v) {
                    near[g.index()] = true;
                }
            }
        }
        let part_rates: Vec<u32> = rates.iter().zip(&near).map(|(&r, &near)| if near { r } else { 1 }).collect();
        let check = FaceRates { faces: part_rates, rings, epsilon };
        self.check_vertex_budget(&check, options)?;
        let FaceRates { faces: part_rates, rings, .. } = check;
        let tess = self.dual(options)?;
        let whole = match &rings {
            Some(rings) => tess.tessellate_with_rings(&part_rates, rings)?,
            None => tess.tessellate(&part_rates)?,
        };
        let mesh = whole.part(|f| faces.contains(&f.index()));
        Ok(Tessellation { mesh, info: TessInfo { method: Method::Dual, rates, epsilon, quadtree: None } })
    }

    /// [`tessellate_into`](Self::tessellate_into) a [`FlatMesh`], by the dual tessellator's own
    /// flat path where it has one (uniform, per-face and screen-space rates): straight into f32
    /// buffers, without the f64 output and its parameters in between — the lean way to a GLB
    /// file ([`write_flat_glb`](crate::write_flat_glb)). The same buffers either way.
    ///
    /// ```
    /// use subdiv::mesh::shapes;
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{FlatMesh, Surface, TessOptions};
    ///
    /// let mut surface = Surface::build(shapes::ngon_prism(5), Builtin::CatmullClark.scheme())?;
    /// let (mut lean, mut replayed) = (FlatMesh::default(), FlatMesh::default());
    /// surface.tessellate_flat(&TessOptions::DEFAULT, &mut lean)?;
    /// surface.tessellate_into(&TessOptions::DEFAULT, &mut replayed)?;
    /// assert_eq!(lean, replayed);
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate).
    pub fn tessellate_flat(&mut self, options: &TessOptions, out: &mut FlatMesh) -> Result<TessInfo, Error> {
        if options.method == Method::Dual {
            let (info, rings, tess) = self.prepared_dual(options)?;
            match &rings {
                Some(rings) => tess.tessellate_with_rings_into(&info.rates, rings, out)?,
                None => tess.tessellate_flat(&info.rates, out)?,
            }
            return Ok(info);
        }
        self.tessellate_into(options, out)
    }

    /// [`tessellate_flat`](Self::tessellate_flat) into a [`FlatStream`], in chunks where the
    /// dual tessellator streams (uniform, per-face and screen-space rates: see
    /// [`DualTessellator::tessellate_stream`]), so that what is held at a time is one chunk of
    /// the output, not all of it; otherwise (a tolerance's rings, the quadtree) made whole and
    /// handed on as one chunk. The same bytes either way as
    /// [`tessellate_flat`](Self::tessellate_flat)'s buffers.
    /// [`write_glb_stream`](Self::write_glb_stream) puts it in a file.
    ///
    /// ```
    /// use subdiv::mesh::shapes;
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{FlatMesh, Surface, TessOptions};
    ///
    /// let mut surface = Surface::build(shapes::ngon_prism(5), Builtin::CatmullClark.scheme())?;
    /// let (mut streamed, mut whole) = (FlatMesh::default(), FlatMesh::default());
    /// surface.tessellate_stream(&TessOptions::DEFAULT, &mut streamed)?;
    /// surface.tessellate_flat(&TessOptions::DEFAULT, &mut whole)?;
    /// assert_eq!(streamed, whole);
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate); the sink may then have had some chunks.
    pub fn tessellate_stream<S: FlatStream + ?Sized>(
        &mut self,
        options: &TessOptions,
        sink: &mut S,
    ) -> Result<TessInfo, Error> {
        let mut flat = FlatMesh::default();
        let info = if options.method == Method::Dual {
            let (info, rings, tess) = self.prepared_dual(options)?;
            match &rings {
                None => {
                    tess.tessellate_stream(&info.rates, sink)?;
                    return Ok(info);
                }
                Some(rings) => tess.tessellate_with_rings_into(&info.rates, rings, &mut flat)?,
            }
            info
        } else {
            self.tessellate_into(options, &mut flat)?
        };
        let (vertices, triangles) = (flat.vertices.len() / 6, flat.indices.len() / 3);
        sink.begin(vertices, !flat.texcoords.is_empty());
        sink.vertices(0, &flat.vertices, &flat.texcoords);
        sink.triangles(0, &flat.indices);
        sink.end(vertices, triangles);
        Ok(info)
    }

    /// [`tessellate_stream`](Self::tessellate_stream) into a GLB file at `path`, through
    /// [`GlbWriter`](subdiv_io::GlbWriter): the file of [`write_flat_glb`](crate::write_flat_glb)
    /// of [`tessellate_flat`](Self::tessellate_flat)'s buffers, without holding them (a
    /// 1000 × 1000 grid at rate 2: docs/perf-log.md). Returns how the tessellation was made
    /// and the numbers of flat vertices and triangles written. The cage's coordinates are the
    /// caller's to check first ([`check_glb_positions`](subdiv_io::check_glb_positions)): f32
    /// output can no longer tell a coordinate flushed to 0 from a 0.
    ///
    /// ```
    /// use subdiv::mesh::shapes;
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{FlatMesh, Surface, TessOptions};
    ///
    /// let mut surface = Surface::build(shapes::cube(), Builtin::CatmullClark.scheme())?;
    /// let dir = tempfile::tempdir().unwrap();
    /// let (streamed, whole) = (dir.path().join("streamed.glb"), dir.path().join("whole.glb"));
    /// let (_, vertices, triangles) = surface.write_glb_stream(&TessOptions::DEFAULT, &streamed)?;
    /// let mut flat = FlatMesh::default();
    /// surface.tessellate_flat(&TessOptions::DEFAULT, &mut flat)?;
    /// subdiv::write_flat_glb(&whole, &flat)?;
    /// assert_eq!(std::fs::read(streamed).unwrap(), std::fs::read(whole).unwrap());
    /// assert_eq!((vertices, triangles), (flat.vertices.len() / 6, flat.indices.len() / 3));
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate) and [`write_flat_glb`](crate::write_flat_glb);
    /// `path` is then left as it was.
    pub fn write_glb_stream(
        &mut self,
        options: &TessOptions,
        path: impl AsRef<std::path::Path>,
    ) -> Result<(TessInfo, usize, usize), Error> {
        let mut sink =
            GlbSink { path: path.as_ref(), writer: None, texcoords: Vec::new(), error: None, counts: (0, 0) };
        let info = self.tessellate_stream(options, &mut sink)?;
        if let Some(e) = sink.error {
            return Err(e.into());
        }
        let (vertices, triangles) = sink.counts;
        // Both routes of `tessellate_stream` begin the stream before they succeed.
        let writer = sink.writer.ok_or_else(|| TessError::Internal("the stream never began".into()))?;
        writer.finish()?;
        Ok((info, vertices, triangles))
    }

    /// [`tessellate`](Self::tessellate) into `sink` (the caller's buffers and vertex type, see
    /// [`TessSink`]); polygons go to sinks that want them when [`TessOptions::polygons`] is set.
    /// Returns how the tessellation was made.
    ///
    /// ```
    /// use subdiv::mesh::shapes;
    /// use subdiv::schemes::Builtin;
    /// use subdiv::{FlatMesh, Surface, TessOptions};
    ///
    /// let mut surface = Surface::build(shapes::ngon_prism(5), Builtin::CatmullClark.scheme())?;
    /// let mut flat = FlatMesh::default(); // px py pz nx ny nz (f32) and u32 indices
    /// let info = surface.tessellate_into(&TessOptions::DEFAULT, &mut flat)?;
    /// assert!(info.rates.iter().all(|&r| r == 8));
    /// assert_eq!(flat.indices.len() % 3, 0);
    /// # Ok::<(), subdiv::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`tessellate`](Self::tessellate); `sink` is then not called.
    pub fn tessellate_into<S: TessSink + ?Sized>(
        &mut self,
        options: &TessOptions,
        sink: &mut S,
    ) -> Result<TessInfo, Error> {
        match options.method {
            Method::Dual => {
                let (info, rings, tess) = self.prepared_dual(options)?;
                match &rings {
                    Some(rings) => tess.tessellate_with_rings_into(&info.rates, rings, sink)?,
                    None => tess.tessellate_into(&info.rates, sink)?,
                }
                Ok(info)
            }
            Method::Quadtree => {
                let (tolerance, screen) = match options.rates {
                    Rates::Tolerance(tolerance) => (tolerance, None),
                    Rates::ScreenError { camera, viewport, pixels } => {
                        (QuadtreeOptions::DEFAULT.tolerance, Some(ScreenError { camera, viewport, pixels }))
                    }
                    _ => return Err(Error::QuadtreeRates { given: options.rates.name() }),
                };
                let tess = self.quadtree_mut()?;
                let epsilon = tolerance.absolute(tess.diagonal())?;
                let quadtree_options = QuadtreeOptions::DEFAULT
                    .with_tolerance(tolerance)
                    .with_screen(screen)
                    .with_parallelism(options.parallelism)
                    .with_max_polygons(options.max_vertices / (QUADTREE_VERTICES_PER_POLYGON * QUADTREE_VERTEX_WEIGHT));
                let stats = if options.polygons {
                    tess.tessellate_into(&quadtree_options, sink)?
                } else {
                    tess.tessellate_into(&quadtree_options, &mut WithoutPolygons(sink))?
                };
                Ok(TessInfo {
                    method: Method::Quadtree,
                    rates: Vec::new(),
                    epsilon: screen.is_none().then_some(epsilon),
                    quadtree: Some(stats),
                })
            }
        }
    }

    /// The dual method's rates as a [`TessInfo`], its rings, and the dual tessellator to cut them
    /// (the budget checked first, by [`face_rates`](Self::face_rates), before it is made).
    fn prepared_dual(
        &mut self,
        options: &TessOptions,
    ) -> Result<(TessInfo, Option<RingDepths>, &mut DualTessellator), Error> {
        let FaceRates { faces, rings, epsilon } = self.face_rates(options)?;
        let info = TessInfo { method: Method::Dual, rates: faces, epsilon, quadtree: None };
        Ok((info, rings, self.dual(options)?))
    }

    /// [`check_vertex_budget`](crate::check_vertex_budget) of `rates` with
    /// [`TessOptions::max_vertices`].
    fn check_vertex_budget(&self, rates: &FaceRates, options: &TessOptions) -> Result<(), Error> {
        crate::check_vertex_budget(&self.mesh, &self.scheme, &rates.faces, rates.rings.as_ref(), options.max_vertices)
    }

    /// Whether the tessellations and evaluations of the mesh's face-varying channels (texture
    /// coordinates) are made under the scheme and face-varying mode
    /// ([`ChannelSurface::takes`](subdiv_schemes::ChannelSurface::takes)): every mode under a
    /// primal scheme with crease rules, the linear mode under any quad or triangle split. Where
    /// not, tessellations leave the channels out.
    pub fn takes_channels(&self) -> bool {
        subdiv_schemes::ChannelSurface::takes(&self.mesh, &self.scheme, &self.refine_options)
    }

    /// The dual tessellator with `options`' quads and parallelism, made on first use (later
    /// calls keep its patches, stencils and templates whatever their options).
    fn dual(&mut self, options: &TessOptions) -> Result<&mut DualTessellator, Error> {
        // Channels the scheme does not take (smooth modes under the interpolating schemes) are
        // not carried: the surface is still tessellated, without them.
        let wanted = DualOptions {
            quads: options.polygons,
            parallelism: options.parallelism,
            channels: self.takes_channels(),
            face_varying: self.refine_options.face_varying,
            ..DualOptions::DEFAULT
        };
        let tess = match self.dual.take() {
            Some(tess) => tess,
            None => DualTessellator::new(&self.scheme, &self.mesh, &wanted)?,
        };
        let tess = self.dual.insert(tess);
        tess.set_options(&wanted);
        Ok(tess)
    }

    /// The quadtree tessellator, made on first use.
    fn quadtree_mut(&mut self) -> Result<&mut QuadtreeTessellator, Error> {
        quadtree(&mut self.quadtree, &self.scheme, &self.mesh, self.refine_options.face_varying)
    }
}

/// How many output vertices a quadtree leaf brings, about: its corner and the hanging
/// vertices it shares (measured: 821,426 vertices for 410,352 leaves on `catmark_cube` at ε =
/// 1e-5). [`TessOptions::max_vertices`] allows the quadtree this many times fewer polygons.
const QUADTREE_VERTICES_PER_POLYGON: usize = 2;

/// How many of [`TessOptions::max_vertices`] a quadtree vertex counts for: the quadtree holds
/// its leaves, its hanging vertices and its whole f64 output, about 420 bytes a vertex
/// (`catmark_cube` at ε = 1e-6: 12.6 million vertices, 5.3 GB), twice the dual method's whole
/// f64 output and four times its streamed GLB, so the budget that lets the dual method make
/// a 2000 × 2000 grid at rate 2 lets the quadtree make half as many vertices.
const QUADTREE_VERTEX_WEIGHT: usize = 2;

/// The quadtree tessellator in `slot`, made there on first use, carrying the mesh's channels in
/// face-varying mode `mode` where the scheme has rules for them (as the dual tessellator does).
fn quadtree<'a>(
    slot: &'a mut Option<QuadtreeTessellator>,
    scheme: &Scheme,
    mesh: &Mesh,
    mode: Option<subdiv_mesh::FaceVaryingInterpolation>,
) -> Result<&'a mut QuadtreeTessellator, Error> {
    let tess = match slot.take() {
        Some(tess) => tess,
        None if subdiv_schemes::ChannelSurface::takes(
            mesh,
            scheme,
            &RefineOptions { face_varying: mode, ..RefineOptions::DEFAULT },
        ) =>
        {
            QuadtreeTessellator::new(scheme, mesh)?.with_channels(scheme, mesh, mode)?
        }
        None => QuadtreeTessellator::new(scheme, mesh)?,
    };
    Ok(slot.insert(tess))
}

/// A sink's view that takes no polygons.
struct WithoutPolygons<'a, S: ?Sized>(&'a mut S);

impl<S: TessSink + ?Sized> TessSink for WithoutPolygons<'_, S> {
    fn begin(&mut self, counts: &TessCounts) {
        self.0.begin(counts);
    }

    #[inline]
    fn vertex(&mut self, index: u32, vertex: &TessVertex<'_>) {
        self.0.vertex(index, vertex);
    }

    fn normal(&mut self, index: u32, vertex: u32, split: &TessVertex<'_>) {
        self.0.normal(index, vertex, split);
    }

    #[inline]
    fn triangle(&mut self, index: u32, triangle: &TessTriangle) {
        self.0.triangle(index, triangle);
    }

    fn end(&mut self) {
        self.0.end();
    }
}

/// A [`FlatStream`] into a [`GlbWriter`](subdiv_io::GlbWriter), made when the stream begins
/// (it then knows whether there are texture coordinates), keeping the first error.
struct GlbSink<'a> {
    path: &'a std::path::Path,
    writer: Option<subdiv_io::GlbWriter>,
    /// A chunk's texture coordinates as pairs (the writer's type).
    texcoords: Vec<glam::Vec2>,
    error: Option<subdiv_io::IoError>,
    counts: (usize, usize),
}

impl GlbSink<'_> {
    fn write(&mut self, push: impl FnOnce(&mut subdiv_io::GlbWriter, &[glam::Vec2]) -> Result<(), subdiv_io::IoError>) {
        if self.error.is_some() {
            return;
        }
        if let Some(writer) = &mut self.writer
            && let Err(e) = push(writer, &self.texcoords)
        {
            self.error = Some(e);
        }
    }
}

impl FlatStream for GlbSink<'_> {
    fn begin(&mut self, _: usize, texcoords: bool) {
        match subdiv_io::GlbWriter::create(self.path, texcoords) {
            Ok(writer) => self.writer = Some(writer),
            Err(e) => self.error = Some(e),
        }
    }

    fn vertices(&mut self, _: usize, vertices: &[f32], texcoords: &[f32]) {
        self.texcoords.clear();
        self.texcoords.extend(texcoords.chunks_exact(2).map(glam::Vec2::from_slice));
        let (vertices, _) = vertices.as_chunks::<6>();
        self.write(|w, texcoords| w.push_vertices(vertices, texcoords));
    }

    fn triangles(&mut self, _: usize, indices: &[u32]) {
        self.write(|w, _| w.push_indices(indices));
    }

    fn end(&mut self, vertices: usize, triangles: usize) {
        self.counts = (vertices, triangles);
    }
}
