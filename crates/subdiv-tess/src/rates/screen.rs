//! Rates and error bounds from the screen (paper 000 §6, paper 003 §7.5): a pinhole camera,
//! per-face rates from projected edge lengths, and the quadtree's screen-space bound.

use glam::DVec3;
use subdiv_mesh::Mesh;

use super::DEFAULT_MAX_RATE;
use crate::TessError;

/// A pinhole camera: where it is, what it looks at, which way is up, and its vertical field of
/// view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The eye.
    pub eye: DVec3,
    /// The point looked at (the centre of the image).
    pub target: DVec3,
    /// Up: any vector not parallel to the view direction (made orthogonal to it).
    pub up: DVec3,
    /// The vertical field of view, in degrees, in `(0, 180)`.
    pub fovy_degrees: f64,
}

impl Camera {
    /// A camera at `eye` looking at `target` with `up` and a 45° vertical field of view.
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3) -> Self {
        Self { eye, target, up, fovy_degrees: 45.0 }
    }

    /// The camera with another vertical field of view.
    #[must_use]
    pub fn with_fovy_degrees(self, fovy_degrees: f64) -> Self {
        Self { fovy_degrees, ..self }
    }

    /// The view frame (right, up, forward) and the focal length in pixels for an image
    /// `height` pixels high.
    fn frame(&self, height: u32) -> Result<([DVec3; 3], f64), TessError> {
        let bad = |reason: String| Err(TessError::Camera { reason });
        if ![self.eye, self.target, self.up].iter().all(|v| v.is_finite()) {
            return bad("eye, target and up must be finite".to_string());
        }
        if !(self.fovy_degrees > 0.0 && self.fovy_degrees < 180.0) {
            return bad(format!("the field of view {}° is not in (0°, 180°)", self.fovy_degrees));
        }
        let forward = (self.target - self.eye).normalize_or_zero();
        if forward == DVec3::ZERO {
            return bad("the eye and the target are the same point".to_string());
        }
        let right = forward.cross(self.up).normalize_or_zero();
        if right == DVec3::ZERO {
            return bad("up is parallel to the view direction".to_string());
        }
        let up = right.cross(forward);
        let focal = 0.5 * f64::from(height) / (0.5 * self.fovy_degrees.to_radians()).tan();
        Ok(([right, up, forward], focal))
    }
}

/// The viewport's height, after checking that it has no zero side and that `pixels` (what
/// `what` names) is a positive finite number.
fn check_screen([width, height]: [u32; 2], pixels: f64, what: &str) -> Result<u32, TessError> {
    if width == 0 || height == 0 {
        return Err(TessError::Camera { reason: format!("the viewport {width}×{height} is empty") });
    }
    if !(pixels.is_finite() && pixels > 0.0) {
        return Err(TessError::Camera { reason: format!("{what} {pixels} is not a positive finite number") });
    }
    Ok(height)
}

/// Screen-space rates: each face cut so that its output edges are about `pixels_per_edge`
/// pixels long on the screen.
///
/// A face's rate is its longest projected control-mesh edge in pixels divided by
/// `pixels_per_edge`, rounded up and clamped to `1..=max_rate` (paper 000 §6: "projecting each
/// quad … computing its maximal edge length and dividing by the maximal number of pixels").
/// Each face decides alone: the dual-grid stitching needs no agreement along edges (paper 003
/// §7.5 needs equal edge rates because its tessellation shares edge points). Points behind the
/// eye count as if on a near plane at `1e−6 ×` the eye–target distance, so faces that cross
/// it get the finest rate and faces wholly behind it the coarsest.
///
/// ```
/// use glam::DVec3;
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_tess::rates::{Camera, ScreenSpace};
///
/// let mesh = Mesh::build(shapes::quad_torus(16, 8))?;
/// let camera = Camera::look_at(DVec3::new(0.0, -6.0, 2.0), DVec3::ZERO, DVec3::Z);
/// let near = ScreenSpace::new(camera, [1920, 1080], 4.0).face_rates(&mesh)?;
/// let far = ScreenSpace::new(Camera { eye: 4.0 * camera.eye, ..camera }, [1920, 1080], 4.0).face_rates(&mesh)?;
/// assert!(near.iter().sum::<u32>() > far.iter().sum::<u32>());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenSpace {
    /// The camera.
    pub camera: Camera,
    /// The image size in pixels, `[width, height]`.
    pub viewport: [u32; 2],
    /// The wanted length of an output edge, in pixels (> 0).
    pub pixels_per_edge: f64,
    /// The largest rate given to a face.
    pub max_rate: u32,
}

impl ScreenSpace {
    /// Rates for `camera` on a `viewport` with edges of `pixels_per_edge` pixels, at most
    /// [`DEFAULT_MAX_RATE`].
    pub fn new(camera: Camera, viewport: [u32; 2], pixels_per_edge: f64) -> Self {
        Self { camera, viewport, pixels_per_edge, max_rate: DEFAULT_MAX_RATE }
    }

    /// The rate of every face of `mesh`, in face order.
    ///
    /// # Errors
    /// [`TessError::Camera`] for a degenerate camera (eye on the target, up along the view,
    /// field of view outside `(0°, 180°)`, non-finite values) or viewport (a zero side), a
    /// `pixels_per_edge` that is not a positive finite number, or a `max_rate` of 0.
    pub fn face_rates(&self, mesh: &Mesh) -> Result<Vec<u32>, TessError> {
        let height = check_screen(self.viewport, self.pixels_per_edge, "pixels per edge")?;
        if self.max_rate == 0 {
            return Err(TessError::Camera { reason: "the largest rate must be at least 1".to_string() });
        }
        let ([right, up, forward], focal) = self.camera.frame(height)?;
        let near = 1e-6 * (self.camera.target - self.camera.eye).length();
        let project = |p: DVec3| {
            let d = p - self.camera.eye;
            let z = d.dot(forward);
            (glam::DVec2::new(d.dot(right), d.dot(up)) * (focal / z.max(near)), z > near)
        };
        let projected: Vec<_> = mesh.vertices().map(|v| project(mesh.position(v))).collect();
        Ok(mesh
            .face_ids()
            .map(|f| {
                let corners: Vec<_> = mesh.face_vertices(f).iter().map(|v| projected[v.index()]).collect();
                if corners.iter().all(|&(_, in_front)| !in_front) {
                    return 1;
                }
                let longest = (0..corners.len())
                    .map(|i| corners[i].0.distance(corners[(i + 1) % corners.len()].0))
                    .fold(0.0, f64::max);
                // Rounding noise (tan 45° < 1 by an ulp) must not push an exact ratio up a rate.
                let rate = (longest / self.pixels_per_edge * (1.0 - 1e-12)).ceil();
                // `as` saturates; NaN cannot occur (finite inputs, near > 0).
                (rate as u32).clamp(1, self.max_rate)
            })
            .collect())
    }
}

/// A screen-space error bound: every limit point within `pixels` pixels, on a `viewport` seen by
/// `camera`, of the output (the quadtree's leaves, [`QuadtreeOptions::screen`](crate::QuadtreeOptions)).
///
/// Each piece of surface gets its own `ε`: a 3D error `e` between two points of the piece's
/// control hull projects to at most `f · √(1 + r²) / z · ‖e‖` pixels — `f` the focal length in
/// pixels, `z` the least depth and `r` the largest `‖(x, y)‖ / z` over the hull (the Jacobian of
/// the projection `f (x/z, y/z)` is `f/z [I | −(x/z, y/z)]`, of norm `f/z · √(1 + r²)`; depth is
/// linear and `r` quasi-convex, so both extremes lie at the hull's vertices). A leaf's output and
/// the surface it stands for both lie in that hull, so `ε = pixels · z / (f √(1 + r²))` bounds
/// the error on the screen. Geometry nearer than the near plane, at [`NEAR_PLANE`] `×` the
/// eye–target distance, is clipped by a renderer and gets no bound: a piece wholly in front of the eye's
/// near plane is bounded as above, one that crosses it takes `z` at the plane, one wholly
/// behind it is flat at once.
///
/// ```
/// use glam::DVec3;
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::rates::{Camera, ScreenError};
/// use subdiv_tess::{QuadtreeOptions, QuadtreeTessellator};
///
/// let mesh = Mesh::build(shapes::cube())?;
/// let tess = QuadtreeTessellator::new(Builtin::CatmullClark.scheme(), &mesh)?;
/// let near = Camera::look_at(DVec3::new(0.0, -4.0, 1.0), DVec3::ZERO, DVec3::Z);
/// let far = Camera { eye: 4.0 * near.eye, ..near };
/// let leaves = |camera| {
///     let screen = ScreenError { camera, viewport: [1920, 1080], pixels: 0.5 };
///     tess.tessellate(&QuadtreeOptions::DEFAULT.with_screen(Some(screen))).map(|m| m.polygon_count())
/// };
/// assert!(leaves(near)? > leaves(far)?);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenError {
    /// The camera.
    pub camera: Camera,
    /// The image size in pixels, `[width, height]`.
    pub viewport: [u32; 2],
    /// The largest error on the screen, in pixels (> 0).
    pub pixels: f64,
}

/// Where [`ScreenError`]'s near plane lies, as a fraction of the eye–target distance: `1e−2`, a
/// renderer's usual near/far ratio. Pieces just in front of it need an `ε` of `pixels · near /
/// f`, so a nearer plane makes a camera inside a model cut very finely along it.
pub const NEAR_PLANE: f64 = 1e-2;

/// [`ScreenError`] prepared: the view frame and the focal length.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScreenBound {
    eye: DVec3,
    frame: [DVec3; 3],
    focal: f64,
    near: f64,
    pub(crate) pixels: f64,
}

impl ScreenError {
    /// The bound, checked.
    ///
    /// # Errors
    /// [`TessError::Camera`] for a degenerate camera or viewport (as [`ScreenSpace`]) or
    /// `pixels` not a positive finite number.
    pub(crate) fn bound(&self) -> Result<ScreenBound, TessError> {
        let height = check_screen(self.viewport, self.pixels, "a screen error in pixels of")?;
        let (frame, focal) = self.camera.frame(height)?;
        let near = NEAR_PLANE * (self.camera.target - self.camera.eye).length();
        Ok(ScreenBound { eye: self.camera.eye, frame, focal, near, pixels: self.pixels })
    }
}

impl ScreenBound {
    /// The `ε` of a piece whose control hull has the vertices `points` (see [`ScreenError`]);
    /// `None` for a piece wholly behind the near plane.
    pub(crate) fn epsilon(&self, points: &[DVec3]) -> Option<f64> {
        let [right, up, forward] = self.frame;
        let (mut depth, mut spread, mut in_front) = (f64::INFINITY, 0.0f64, false);
        for &p in points {
            let d = p - self.eye;
            let z = d.dot(forward);
            in_front |= z > self.near;
            let z = z.max(self.near);
            depth = depth.min(z);
            spread = spread.max(glam::DVec2::new(d.dot(right), d.dot(up)).length() / z);
        }
        in_front.then(|| self.pixels * depth / (self.focal * (1.0 + spread * spread).sqrt()))
    }
}
