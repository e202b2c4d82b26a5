//! The limit surface of a linear channel evaluated directly, without patch levels.
//!
//! A face-varying channel in mode [`All`](subdiv_mesh::FaceVaryingInterpolation::All) (the
//! default) refines by the linear split of its scheme's kind (bilinear for quad splits, linear
//! triangles for triangle splits), whose limit over a face is the bilinear or linear
//! interpolation of the face's corners ([`FaceDomain::linear_weights`]). Preparing patch levels,
//! sub-patch matrices and stencils for it, as for any other surface, was a quarter of a fresh
//! `subdiv eval` of a textured mesh.

use subdiv_mesh::{DVec3, FaceId, Mesh};
use subdiv_schemes::{ChannelSurface, RefineOptions, Refiner, Split};

use crate::{FaceDomain, LimitPoint, StencilError};

/// A linear channel's limit surface ([`ChannelSurface::is_linear`]): at a face's `Bfr`
/// parameters, its corners' values combined; the same points [`LimitEvaluator`] gives over the
/// channel's surface, up to rounding.
///
/// ```
/// use subdiv_mesh::{shapes, Channel, FaceId, Mesh};
/// use subdiv_schemes::{Builtin, ChannelSurface, RefineOptions};
/// use subdiv_stencil::LinearEvaluator;
///
/// let mut soup = shapes::quad_grid(2, 2);
/// let xy: Vec<f64> = soup.positions().iter().flat_map(|p| [p.x, p.y]).collect();
/// let corners = soup.raw_faces().1.iter().map(|v| v.raw()).collect();
/// soup.channels.push(Channel::new("uv", 2, xy, corners));
/// let mesh = Mesh::build(soup)?;
/// let uv = ChannelSurface::new(&mesh, &mesh.channels()[0], Builtin::CatmullClark.scheme(), &RefineOptions::DEFAULT)?;
/// let eval = LinearEvaluator::new(&uv)?.expect("mode `all` is linear");
/// let p = eval.eval(FaceId::new(3), 0.25, 0.5)?;
/// assert_eq!((p.position.x, p.position.y), (1.25, 1.5));
/// assert_eq!((p.du.x, p.dv.y), (1.0, 1.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// [`LimitEvaluator`]: crate::LimitEvaluator
#[derive(Clone, Debug)]
pub struct LinearEvaluator {
    /// The channel's mesh with its boundary rule applied (holes included).
    mesh: Mesh,
    split: Split,
}

impl LinearEvaluator {
    /// The evaluator of `surface`, `None` unless it is linear.
    ///
    /// # Errors
    /// [`StencilError::Scheme`] if the channel's boundary rule cannot be applied.
    pub fn new(surface: &ChannelSurface) -> Result<Option<Self>, StencilError> {
        if !surface.is_linear() {
            return Ok(None);
        }
        // As `PatchLevels` prepares level 0: the boundary rule `none` makes holes.
        let mesh = Refiner::new(surface.mesh(), surface.scheme(), 0, &RefineOptions::DEFAULT)?.into_mesh();
        Ok(Some(Self { mesh, split: surface.scheme().split() }))
    }

    /// The number of faces.
    pub fn face_count(&self) -> usize {
        self.mesh.face_count()
    }

    /// The channel's values, one per vertex of its mesh (padded to three components).
    pub fn values(&self) -> &[DVec3] {
        self.mesh.positions()
    }

    /// Whether `face` has a limit surface (it is not a hole).
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn has_surface(&self, face: FaceId) -> Result<bool, StencilError> {
        self.in_range(face)?;
        Ok(!self.mesh.is_hole(face))
    }

    /// The domain of `face`.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn domain(&self, face: FaceId) -> Result<FaceDomain, StencilError> {
        self.in_range(face)?;
        Ok(self.domain_unchecked(face))
    }

    fn domain_unchecked(&self, face: FaceId) -> FaceDomain {
        // The channel's surface takes every face of a mesh its scheme refines.
        FaceDomain::of(self.split, self.mesh.face_size(face)).unwrap_or(FaceDomain::Quad)
    }

    fn in_range(&self, face: FaceId) -> Result<(), StencilError> {
        match face.index() < self.mesh.face_count() {
            true => Ok(()),
            false => Err(StencilError::FaceOutOfRange { face: face.index(), faces: self.mesh.face_count() }),
        }
    }

    /// The value of `face` at `(u, v)` and its derivatives.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::OutsideFace`] (also for a non-finite
    /// parameter), [`StencilError::NoSurface`] for a hole: as [`LimitEvaluator::eval`](crate::LimitEvaluator::eval).
    pub fn eval(&self, face: FaceId, u: f64, v: f64) -> Result<LimitPoint, StencilError> {
        let domain = self.domain(face)?;
        if !domain.contains_f64(u, v) {
            let (u, v) = (format!("{u:?}"), format!("{v:?}"));
            return Err(StencilError::OutsideFace { face: face.index(), u, v, domain: domain.describe() });
        }
        if self.mesh.is_hole(face) {
            return Err(StencilError::NoSurface { face: face.index() });
        }
        let mut row = Vec::new();
        self.corner_weights(face, u, v, &mut row);
        let values = self.values();
        let sum = |r: usize| row.iter().fold(DVec3::ZERO, |acc, &(c, w)| acc + w[r] * values[c as usize]);
        Ok(LimitPoint { position: sum(0), du: sum(1), dv: sum(2), exact_derivatives: true })
    }

    /// The point of `face` at `(u, v)` (in its domain, unchecked) as its corners' weights, into
    /// `row`: per corner, its vertex (an index into [`values`](Self::values)) and its weights in
    /// the value and in the two derivatives.
    pub fn corner_weights(&self, face: FaceId, u: f64, v: f64, row: &mut Vec<(u32, [f64; 3])>) {
        let corners = self.mesh.face_vertices(face);
        let mut weights = Vec::with_capacity(corners.len());
        self.domain_unchecked(face).linear_weights(u, v, &mut weights);
        row.clear();
        row.extend(corners.iter().map(|c| c.raw()).zip(weights));
    }
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::{FaceVaryingInterpolation, PolygonSoup, shapes};
    use subdiv_schemes::Builtin;

    use super::*;
    use crate::LimitEvaluator;

    fn textured(soup: PolygonSoup) -> Mesh {
        Mesh::build(shapes::face_charts(soup)).unwrap()
    }

    /// The direct route gives what exact stencils give over the channel's surface: quads,
    /// N-gons (`Bfr` sub-faces), triangles under a quad split, Loop's triangles, an open grid
    /// with a hole (which the channel's surface covers: the mesh's evaluator skips it), and the same errors.
    #[test]
    fn linear_channels_equal_the_exact_surface() {
        let mut open = shapes::quad_grid(3, 2);
        open.tags.holes.push(FaceId::new(4));
        let cases = [
            (Builtin::CatmullClark, textured(shapes::ngon_prism(5))),
            (Builtin::CatmullClark, textured(shapes::tetrahedron())),
            (Builtin::CatmullClark, textured(shapes::default_model())),
            (Builtin::CatmullClark, textured(open)),
            (Builtin::Loop, textured(shapes::icosahedron())),
        ];
        for (builtin, mesh) in cases {
            let surface =
                ChannelSurface::new(&mesh, &mesh.channels()[0], builtin.scheme(), &RefineOptions::DEFAULT).unwrap();
            let linear = LinearEvaluator::new(&surface).unwrap().unwrap();
            let exact = LimitEvaluator::new(surface.scheme(), surface.mesh(), &RefineOptions::DEFAULT).unwrap();
            assert_eq!(linear.face_count(), exact.face_count());
            for face in mesh.face_ids() {
                assert_eq!(linear.has_surface(face), exact.has_surface(face), "{builtin:?} {face}");
                assert_eq!(linear.domain(face), exact.domain(face));
                for g in linear.domain(face).unwrap().grid(3) {
                    let (got, want) = (linear.eval(face, g.u, g.v), exact.eval(face, g.u, g.v));
                    let (Ok(got), Ok(want)) = (&got, &want) else {
                        assert_eq!(got, want, "{builtin:?} {face} ({}, {})", g.u, g.v);
                        continue;
                    };
                    let worst = [(got.position, want.position), (got.du, want.du), (got.dv, want.dv)]
                        .map(|(a, b)| a.distance(b))
                        .into_iter()
                        .fold(0.0, f64::max);
                    assert!(worst < 1e-12, "{builtin:?} {face} ({}, {}): off by {worst:e}", g.u, g.v);
                    assert!(got.exact_derivatives);
                }
            }
            let faces = mesh.face_count();
            assert_eq!(
                linear.eval(FaceId::new(faces as u32), 0.0, 0.0),
                exact.eval(FaceId::new(faces as u32), 0.0, 0.0)
            );
            assert_eq!(linear.eval(FaceId::new(0), 2.0, f64::NAN), exact.eval(FaceId::new(0), 2.0, f64::NAN));
        }
    }

    /// Other face-varying modes are not linear: no direct evaluator.
    #[test]
    fn other_modes_are_refused() {
        let mesh = textured(shapes::cube());
        let options = RefineOptions::DEFAULT.with_face_varying(FaceVaryingInterpolation::None);
        let surface =
            ChannelSurface::new(&mesh, &mesh.channels()[0], Builtin::CatmullClark.scheme(), &options).unwrap();
        assert!(LinearEvaluator::new(&surface).unwrap().is_none());
    }
}
