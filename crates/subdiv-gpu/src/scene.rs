//! What the renderer draws, as wgpu buffers: the surface ([`GpuMesh`], or a GPU evaluation's
//! own vertex buffer), its wireframe ([`unique_edges`]) and the control cage ([`GpuCage`]),
//! gathered in a [`Scene`], and the camera that frames them ([`View`]).

use glam::{DVec3, Mat4, Vec3, Vec4};
use subdiv_mesh::Mesh;
use subdiv_tess::FlatMesh;
use subdiv_tess::rates::Camera;
use wgpu::util::DeviceExt;

use crate::render::{CAGE_VERTEX_STRIDE, ErrorScopes, RenderOptions, TEXCOORD_STRIDE, Texture, VERTEX_STRIDE};
use crate::{Gpu, GpuError};

/// A pinhole camera: eye, target, up, vertical field of view, and the depth range drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The eye.
    pub eye: Vec3,
    /// The point at the image's centre.
    pub target: Vec3,
    /// Up: any vector not parallel to the view direction.
    pub up: Vec3,
    /// The vertical field of view in degrees, in `(0, 180)`.
    pub fovy_degrees: f32,
    /// The near clipping distance (> 0).
    pub near: f32,
    /// The far clipping distance (> `near`).
    pub far: f32,
}

impl View {
    /// The direction from the target to the eye of [`framing`](Self::framing): a three-quarter
    /// view from the front right, 35° round from +z and 25° above the horizon (y is up).
    pub const FRAMING_DIRECTION: Vec3 = Vec3::new(0.519_837_5, 0.422_618_26, 0.742_403_85);

    /// The vertical field of view of [`framing`](Self::framing), in degrees.
    pub const FRAMING_FOVY_DEGREES: f32 = 30.0;

    /// The fraction of the image's width and height that [`framing`](Self::framing) lets the
    /// box's projection reach, centred (a margin for deformations).
    pub const FRAMING_FILL: f32 = 0.9;

    /// A camera that fits the box `bounds_min..=bounds_max` in an image of `aspect` (width over
    /// height), seen from [`FRAMING_DIRECTION`](Self::FRAMING_DIRECTION) with y up, looking at
    /// the box's centre: the nearest distance at which every corner of the box lies within the
    /// middle [`FRAMING_FILL`](Self::FRAMING_FILL) of the image's width and height. Depth
    /// range: the box's bounding sphere, twice over (a shape deformed within it stays drawn).
    /// An empty or non-finite box (`min > max`) is framed as the unit cube; a point as a box of
    /// side 1 around it.
    pub fn framing(bounds_min: Vec3, bounds_max: Vec3, aspect: f32) -> Self {
        let (lo, hi) = if bounds_min.is_finite() && bounds_max.is_finite() && bounds_min.cmple(bounds_max).all() {
            (bounds_min, bounds_max)
        } else {
            (Vec3::ZERO, Vec3::ONE)
        };
        let centre = 0.5 * (lo + hi);
        let (lo, hi) = if lo == hi { (centre - 0.5, centre + 0.5) } else { (lo, hi) };
        let radius = 0.5 * (hi - lo).length();
        let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 };
        let back = Self::FRAMING_DIRECTION;
        let right = Vec3::Y.cross(back).normalize();
        let up = back.cross(right);
        // Half the image's height and width at unit distance, times the fill.
        let tan_y = Self::FRAMING_FILL * (0.5 * Self::FRAMING_FOVY_DEGREES.to_radians()).tan();
        let tan_x = aspect * tan_y;
        // A corner at offset o is inside when |o·right| ≤ tan_x (d − o·back), and so for up.
        let distance = (0..8)
            .map(|corner| {
                let o = Vec3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                ) - centre;
                o.dot(back) + (o.dot(right).abs() / tan_x).max(o.dot(up).abs() / tan_y)
            })
            .fold(radius, f32::max);
        Self {
            eye: centre + distance * back,
            target: centre,
            up: Vec3::Y,
            fovy_degrees: Self::FRAMING_FOVY_DEGREES,
            near: (distance - 2.0 * radius).max(0.01 * distance),
            far: distance + 2.0 * radius,
        }
    }

    /// The same camera for the screen-space rate policy ([`ScreenSpace`](subdiv_tess::rates::ScreenSpace)).
    pub fn camera(&self) -> Camera {
        Camera::look_at(self.eye.as_dvec3(), self.target.as_dvec3(), self.up.as_dvec3())
            .with_fovy_degrees(f64::from(self.fovy_degrees))
    }

    /// The view frame `[right, up, back]` (unit, right-handed), or the reason there is none.
    pub(crate) fn frame(&self) -> Result<[Vec3; 3], GpuError> {
        let bad = |reason: &str| Err(GpuError::Scene(format!("view: {reason}")));
        if ![self.eye, self.target, self.up].iter().all(|v| v.is_finite()) {
            return bad("eye, target and up must be finite");
        }
        if !(self.fovy_degrees > 0.0 && self.fovy_degrees < 180.0) {
            return bad("the field of view must be in (0°, 180°)");
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return bad("the depth range must have 0 < near < far");
        }
        let back = (self.eye - self.target).normalize_or_zero();
        let right = self.up.cross(back).normalize_or_zero();
        if back == Vec3::ZERO || right == Vec3::ZERO {
            return bad("the eye is on the target, or up is along the view direction");
        }
        Ok([right, back.cross(right), back])
    }

    /// World to clip space (right-handed view, depth in `[0, 1]`) for the view frame `frame`.
    pub(crate) fn view_projection(&self, aspect: f32, frame: [Vec3; 3]) -> Mat4 {
        let [right, up, back] = frame;
        let e = self.eye;
        let view = Mat4::from_cols(
            Vec4::new(right.x, up.x, back.x, 0.0),
            Vec4::new(right.y, up.y, back.y, 0.0),
            Vec4::new(right.z, up.z, back.z, 0.0),
            Vec4::new(-right.dot(e), -up.dot(e), -back.dot(e), 1.0),
        );
        let f = 1.0 / (0.5 * self.fovy_degrees.to_radians()).tan();
        let (near, far) = (self.near, self.far);
        let projection = Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, far / (near - far), -1.0),
            Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
        );
        projection * view
    }
}

/// The bounding box `[min, max]` of a vertex buffer's positions in [`FlatMesh`] layout (six
/// floats per vertex), or `None` when it has no vertex.
pub fn bounds(vertices: &[f32]) -> Option<[Vec3; 2]> {
    let mut points = vertices.chunks_exact(6).map(|v| Vec3::new(v[0], v[1], v[2]));
    let first = points.next()?;
    Some(points.fold([first, first], |[lo, hi], p| [lo.min(p), hi.max(p)]))
}

/// A line list: `index_count` `u32` indices, two per line.
#[derive(Clone, Copy, Debug)]
pub struct Lines<'a> {
    /// The index buffer (usage `INDEX`).
    pub indices: &'a wgpu::Buffer,
    /// How many indices to draw (even).
    pub index_count: u32,
}

/// The control cage: its own positions and its edges.
#[derive(Clone, Copy, Debug)]
pub struct Cage<'a> {
    /// `x y z` per vertex as `f32` ([`CAGE_VERTEX_STRIDE`] bytes; usage `VERTEX`).
    pub positions: &'a wgpu::Buffer,
    /// The number of cage vertices in `positions`.
    pub vertex_count: u32,
    /// The edges, over `positions`.
    pub lines: Lines<'a>,
}

/// What one image shows. Borrows the buffers, so that buffers written on the device are
/// drawn as they are.
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    /// The surface's vertices in [`FlatMesh`] layout ([`VERTEX_STRIDE`] bytes; usage `VERTEX`).
    pub vertices: &'a wgpu::Buffer,
    /// The number of vertices in `vertices`.
    pub vertex_count: u32,
    /// An image drawn on the surface through its texture coordinates (a checker,
    /// [`TextureImage::checker`](crate::TextureImage::checker), shows the mapping), or the
    /// plain surface.
    pub texture: Option<Texture<'a>>,
    /// The surface's triangles: `u32` indices into `vertices`, three per triangle (usage
    /// `INDEX`).
    pub triangles: &'a wgpu::Buffer,
    /// How many triangle indices to draw (a multiple of 3).
    pub index_count: u32,
    /// The wireframe, a line list over `vertices`, drawn when [`RenderOptions::wireframe`] is
    /// set.
    pub wireframe: Option<Lines<'a>>,
    /// The control cage, drawn when given.
    pub cage: Option<Cage<'a>>,
    /// The camera.
    pub view: View,
}

impl Scene<'_> {
    /// Checks that the buffers hold what the counts say.
    pub(crate) fn check(&self, options: &RenderOptions) -> Result<(), GpuError> {
        let bad = |what: String| Err(GpuError::Scene(format!("scene: {what}")));
        let fits = |buffer: &wgpu::Buffer, count: u32, stride: u64| u64::from(count) * stride <= buffer.size();
        if !fits(self.vertices, self.vertex_count, VERTEX_STRIDE) {
            return bad(format!("{} vertices do not fit a {}-byte buffer", self.vertex_count, self.vertices.size()));
        }
        if let Some(texture) = self.texture
            && !fits(texture.texcoords, self.vertex_count, TEXCOORD_STRIDE)
        {
            return bad(format!(
                "texture coordinates of {} vertices do not fit a {}-byte buffer",
                self.vertex_count,
                texture.texcoords.size()
            ));
        }
        if !self.index_count.is_multiple_of(3) || !fits(self.triangles, self.index_count, 4) {
            return bad(format!(
                "{} triangle indices: not a multiple of 3, or more than the {}-byte buffer holds",
                self.index_count,
                self.triangles.size()
            ));
        }
        let lines = |what: &str, lines: &Lines<'_>| {
            if !lines.index_count.is_multiple_of(2) || !fits(lines.indices, lines.index_count, 4) {
                return bad(format!(
                    "{} {what} line indices: odd, or more than the {}-byte buffer holds",
                    lines.index_count,
                    lines.indices.size()
                ));
            }
            Ok(())
        };
        match (&self.wireframe, options.wireframe) {
            (Some(wire), true) => lines("wireframe", wire)?,
            (None, true) => return bad("the wireframe is asked for but the scene has no line indices".to_string()),
            _ => {}
        }
        if let Some(cage) = &self.cage {
            if !fits(cage.positions, cage.vertex_count, CAGE_VERTEX_STRIDE) {
                return bad(format!(
                    "{} cage vertices do not fit a {}-byte buffer",
                    cage.vertex_count,
                    cage.positions.size()
                ));
            }
            lines("cage", &cage.lines)?;
        }
        self.view.frame().map(|_| ())
    }
}

/// Each edge of `triangles` (three `u32` indices per triangle) once, as a line list: the edges
/// as `(low, high)` index pairs in increasing order.
pub fn unique_edges(triangles: &[u32]) -> Vec<u32> {
    let mut keys: Vec<u64> = triangles
        .chunks_exact(3)
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (u64::from(a.min(b)) << 32) | u64::from(a.max(b)))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.iter().flat_map(|&k| [(k >> 32) as u32, k as u32]).collect()
}

/// A [`FlatMesh`] on the device: the vertex and triangle index buffers a [`Scene`] draws, and on
/// request the wireframe's line list.
///
/// The vertex buffer's usage is `VERTEX | STORAGE | COPY_DST | COPY_SRC`, so that it can be
/// rewritten per animation frame ([`write_vertices`](Self::write_vertices)) or by a compute
/// pass.
#[derive(Debug)]
pub struct GpuMesh {
    /// Per vertex `px py pz nx ny nz` as `f32`.
    pub vertices: wgpu::Buffer,
    /// The number of vertices.
    pub vertex_count: u32,
    /// Three `u32` indices per triangle.
    pub triangles: wgpu::Buffer,
    /// The number of triangle indices.
    pub index_count: u32,
    /// Each edge of the triangles once, as a line list (from
    /// [`upload_with_edges`](Self::upload_with_edges)).
    pub edges: Option<wgpu::Buffer>,
    /// The number of edge indices (0 without edges).
    pub edge_index_count: u32,
}

impl GpuMesh {
    /// Uploads `mesh`'s vertices and triangles.
    ///
    /// # Errors
    /// [`GpuError::Scene`] when the vertex array is not six floats per vertex, the index array
    /// not three per triangle, an index is out of range, or a count exceeds `u32`;
    /// [`GpuError::Wgpu`] if the device refuses the buffers.
    pub fn upload(gpu: &Gpu, mesh: &FlatMesh) -> Result<Self, GpuError> {
        Self::make(gpu, mesh, false)
    }

    /// As [`upload`](Self::upload), with the wireframe's line list ([`unique_edges`]).
    ///
    /// # Errors
    /// As [`upload`](Self::upload).
    pub fn upload_with_edges(gpu: &Gpu, mesh: &FlatMesh) -> Result<Self, GpuError> {
        Self::make(gpu, mesh, true)
    }

    fn make(gpu: &Gpu, mesh: &FlatMesh, with_edges: bool) -> Result<Self, GpuError> {
        let bad = |what: String| Err(GpuError::Scene(format!("flat mesh: {what}")));
        if !mesh.vertices.len().is_multiple_of(6) {
            return bad(format!("{} floats are not six per vertex", mesh.vertices.len()));
        }
        if !mesh.indices.len().is_multiple_of(3) {
            return bad(format!("{} indices are not three per triangle", mesh.indices.len()));
        }
        let count = |n: usize, what: &str| {
            u32::try_from(n).map_err(|_| GpuError::Scene(format!("flat mesh: {n} {what} exceed u32")))
        };
        let vertex_count = count(mesh.vertices.len() / 6, "vertices")?;
        let index_count = count(mesh.indices.len(), "indices")?;
        if let Some(&i) = mesh.indices.iter().find(|&&i| i >= vertex_count) {
            return bad(format!("index {i} is not below the vertex count {vertex_count}"));
        }
        let device = &gpu.device;
        let scopes = ErrorScopes::push(device, "uploading a mesh");
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let vertex_usage = wgpu::BufferUsages::VERTEX
            | wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let index_usage = wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST;
        let vertices = buffer("vertices", bytemuck::cast_slice(&mesh.vertices), vertex_usage);
        let triangles = buffer("triangles", bytemuck::cast_slice(&mesh.indices), index_usage);
        let (edges, edge_index_count) = if with_edges {
            let edges = unique_edges(&mesh.indices);
            let n = count(edges.len(), "edge indices")?;
            (Some(buffer("edges", bytemuck::cast_slice(&edges), index_usage)), n)
        } else {
            (None, 0)
        };
        scopes.pop()?;
        Ok(Self { vertices, vertex_count, triangles, index_count, edges, edge_index_count })
    }

    /// Rewrites the vertex buffer (the animation path: same topology, new positions and
    /// normals). Takes effect with the next submission.
    ///
    /// # Errors
    /// [`GpuError::Scene`] unless `vertices` has six floats per vertex of this mesh.
    pub fn write_vertices(&self, gpu: &Gpu, vertices: &[f32]) -> Result<(), GpuError> {
        if vertices.len() != 6 * self.vertex_count as usize {
            return Err(GpuError::Scene(format!(
                "flat mesh: {} floats for {} vertices (six each)",
                vertices.len(),
                self.vertex_count
            )));
        }
        gpu.queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(vertices));
        Ok(())
    }

    /// A scene of this mesh (with its wireframe, if uploaded) seen by `view`, without a cage.
    pub fn scene(&self, view: View) -> Scene<'_> {
        Scene {
            vertices: &self.vertices,
            vertex_count: self.vertex_count,
            triangles: &self.triangles,
            index_count: self.index_count,
            wireframe: self.edges.as_ref().map(|indices| Lines { indices, index_count: self.edge_index_count }),
            texture: None,
            cage: None,
            view,
        }
    }
}

/// Texture coordinates on the device, `s t` as `f32` per vertex of a surface (a
/// [`FlatMesh::texcoords`]), for a [`Scene::texture`]. They do not move with an animated cage.
#[derive(Debug)]
pub struct GpuTexcoords {
    /// The coordinates ([`TEXCOORD_STRIDE`] bytes per vertex; usage `VERTEX`).
    pub buffer: wgpu::Buffer,
    /// The number of vertices.
    pub vertex_count: u32,
}

impl GpuTexcoords {
    /// Uploads `texcoords`, two per vertex.
    ///
    /// # Errors
    /// [`GpuError::Scene`] for an odd count, no coordinates, or one that is not finite;
    /// [`GpuError::Wgpu`] if the device refuses the buffer.
    pub fn upload(gpu: &Gpu, texcoords: &[f32]) -> Result<Self, GpuError> {
        if texcoords.is_empty() || !texcoords.len().is_multiple_of(2) {
            return Err(GpuError::Scene(format!("texture coordinates: {} floats, two per vertex", texcoords.len())));
        }
        if let Some(k) = texcoords.iter().position(|x| !x.is_finite()) {
            return Err(GpuError::Scene(format!("texture coordinate of vertex {}: not finite", k / 2)));
        }
        let vertex_count = u32::try_from(texcoords.len() / 2)
            .map_err(|_| GpuError::Scene("texture coordinates: more than u32::MAX vertices".to_string()))?;
        let scopes = ErrorScopes::push(&gpu.device, "uploading texture coordinates");
        let buffer = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("texture coordinates"),
            contents: bytemuck::cast_slice(texcoords),
            usage: wgpu::BufferUsages::VERTEX,
        });
        scopes.pop()?;
        debug_assert_eq!(buffer.size(), u64::from(vertex_count) * TEXCOORD_STRIDE);
        Ok(Self { buffer, vertex_count })
    }
}

/// A control cage on the device: its positions and its edges.
#[derive(Debug)]
pub struct GpuCage {
    /// `x y z` per vertex as `f32`.
    pub positions: wgpu::Buffer,
    /// The number of vertices.
    pub vertex_count: u32,
    /// Two `u32` indices per edge.
    pub edges: wgpu::Buffer,
    /// The number of edge indices.
    pub edge_index_count: u32,
}

impl GpuCage {
    /// Uploads `mesh`'s vertices and edges.
    ///
    /// # Errors
    /// [`GpuError::Scene`] if the mesh is too large for `u32` counts; [`GpuError::Wgpu`] if
    /// the device refuses the buffers.
    pub fn upload(gpu: &Gpu, mesh: &Mesh) -> Result<Self, GpuError> {
        let positions: Vec<f32> = mesh.positions().iter().flat_map(|p| p.as_vec3().to_array()).collect();
        let edges: Vec<u32> = mesh
            .edges()
            .flat_map(|e| {
                let [a, b] = mesh.edge_vertices(e);
                [a.index() as u32, b.index() as u32]
            })
            .collect();
        let too_large = || GpuError::Scene("cage: more than u32::MAX vertices or edges".to_string());
        let vertex_count = u32::try_from(mesh.vertex_count()).map_err(|_| too_large())?;
        let edge_index_count = u32::try_from(edges.len()).map_err(|_| too_large())?;
        let device = &gpu.device;
        let scopes = ErrorScopes::push(device, "uploading a cage");
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let positions = buffer(
            "cage positions",
            bytemuck::cast_slice(&positions),
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        );
        let edges = buffer("cage edges", bytemuck::cast_slice(&edges), wgpu::BufferUsages::INDEX);
        scopes.pop()?;
        Ok(Self { positions, vertex_count, edges, edge_index_count })
    }

    /// Rewrites the positions (an animated cage).
    ///
    /// # Errors
    /// [`GpuError::Scene`] unless there is one position per cage vertex.
    pub fn write_positions(&self, gpu: &Gpu, positions: &[DVec3]) -> Result<(), GpuError> {
        if positions.len() != self.vertex_count as usize {
            return Err(GpuError::Scene(format!(
                "cage: {} positions for {} vertices",
                positions.len(),
                self.vertex_count
            )));
        }
        let data: Vec<f32> = positions.iter().flat_map(|p| p.as_vec3().to_array()).collect();
        gpu.queue.write_buffer(&self.positions, 0, bytemuck::cast_slice(&data));
        Ok(())
    }

    /// The cage as a [`Scene`]'s part.
    pub fn lines(&self) -> Cage<'_> {
        Cage {
            positions: &self.positions,
            vertex_count: self.vertex_count,
            lines: Lines { indices: &self.edges, index_count: self.edge_index_count },
        }
    }
}
