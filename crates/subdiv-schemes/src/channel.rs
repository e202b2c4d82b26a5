//! [`ChannelSurface`]: the surface a face-varying channel's values lie on.

use std::sync::OnceLock;

use subdiv_mesh::{Channel, FaceVaryingInterpolation, Mesh};

use crate::primal::face_varying;
use crate::refine::prepared;
use crate::{Builtin, RefineOptions, Scheme, SchemeError, Split};

/// The triangle split with linear masks: what a triangle scheme's channels are under
/// [`FaceVaryingInterpolation::All`] (each value the linear interpolation of its parent
/// triangle's), as the bilinear scheme is for the quad split.
const LINEAR_TRIANGLES: &str = r#"
name = "linear-triangles"

[rules.triangle]
edge = { endpoint = "1/2", opposite = 0 }
vertex = { centre = 1, spoke = 0 }
crease = { own = 1, neighbour = 0 }
"#;

/// A face-varying channel as a subdivision surface of its own: the channel's values are the
/// vertices of a mesh over the channel's topology (one vertex per value and run of faces around
/// a vertex, so seams and channel boundaries are boundaries), with the channel's rules — the
/// face-varying interpolation mode of [`RefineOptions::face_varying`], OpenSubdiv's — written
/// as sharpness. Its faces are the mesh's, corner for corner, so the channel's value at a
/// face's `(u, v)` is this surface's position there: any evaluator of positions (eigenbasis,
/// exact stencils, tessellation) evaluates the channel, derivatives included.
///
/// Refining [`mesh`](Self::mesh) with [`scheme`](Self::scheme) gives the channel's
/// face-varying refinement corner for corner (the tests compare the two on the shared corpus).
///
/// ```
/// use subdiv_mesh::{shapes, Channel, FaceVaryingInterpolation, Mesh};
/// use subdiv_schemes::{Builtin, ChannelSurface, RefineOptions};
///
/// // A cube whose faces each carry their own square of texture coordinates: every edge is a
/// // seam, so each face is a component of the channel's surface.
/// let mut soup = shapes::cube();
/// let square = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
/// soup.channels.push(Channel::new("uv", 2, square.repeat(6), (0..24).map(|i| i % 4).collect()));
/// let cube = Mesh::build(soup)?;
/// let options = RefineOptions::DEFAULT.with_face_varying(FaceVaryingInterpolation::None);
/// let uv = ChannelSurface::new(&cube, &cube.channels()[0], Builtin::CatmullClark.scheme(), &options)?;
/// assert_eq!((uv.mesh().vertex_count(), uv.mesh().face_count()), (24, 6));
/// assert_eq!(uv.mesh().components().count(), 6);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct ChannelSurface {
    mesh: Mesh,
    scheme: Scheme,
    linear: bool,
}

impl ChannelSurface {
    /// The surface of `channel` (one of `mesh`'s) under `scheme`, with `options`' face-varying
    /// mode (else the mesh's tag, else [`FaceVaryingInterpolation::All`]) and boundary rule.
    ///
    /// # Errors
    /// [`SchemeError::FeatureNotSupported`] where the scheme does not take the channel
    /// ([`takes`](Self::takes)) or for a channel of more than three components.
    pub fn new(mesh: &Mesh, channel: &Channel, scheme: &Scheme, options: &RefineOptions) -> Result<Self, SchemeError> {
        let unsupported =
            |feature, element| SchemeError::FeatureNotSupported { scheme: scheme.name.clone(), feature, element };
        if !Self::takes(mesh, scheme, options) {
            return Err(unsupported(
                "face-varying channels other than linear ones (FaceVaryingInterpolation::All)",
                format!("channel {:?}", channel.name()),
            ));
        }
        if channel.dimension() > 3 {
            let element = format!("channel {:?} of {} components", channel.name(), channel.dimension());
            return Err(unsupported("face-varying channels of more than 3 components", element));
        }
        let rules = options.rules_for(mesh).channels;
        let base = prepared(mesh, options);
        let level = face_varying::analyze(&base, channel, rules);
        let soup = face_varying::channel_soup(&base, channel, &level);
        let mesh = Mesh::build(soup).map_err(|e| {
            SchemeError::Internal(format!("the surface of channel {:?} is invalid: {e}", channel.name()))
        })?;
        let scheme = match (rules.mode, scheme.split()) {
            (FaceVaryingInterpolation::All, Split::Triangle) => linear_triangles().clone(),
            (FaceVaryingInterpolation::All, _) => Builtin::Bilinear.scheme().clone(),
            _ => scheme.clone(),
        };
        Ok(Self { mesh, scheme, linear: rules.mode == FaceVaryingInterpolation::All })
    }

    /// Whether `scheme` takes `mesh`'s face-varying channels under `options` (its face-varying
    /// mode, else the mesh's tag, else [`FaceVaryingInterpolation::All`]): a primal scheme with
    /// crease rules in every mode (the face-varying rules are theirs), and in mode `All` — linear
    /// interpolation of the corners, a rule every scheme whose faces have `Bfr`'s domains can
    /// take — every other scheme but √3 (butterfly, Kobbelt, `sw-quad`, and the dual splits,
    /// Doo-Sabin and mid-edge, whose faces take the quad split's domains).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, FaceVaryingInterpolation, Mesh};
    /// use subdiv_schemes::{Builtin, ChannelSurface, RefineOptions};
    ///
    /// let mesh = Mesh::build(shapes::octahedron())?;
    /// let linear = RefineOptions::DEFAULT.with_face_varying(FaceVaryingInterpolation::All);
    /// let smooth = RefineOptions::DEFAULT.with_face_varying(FaceVaryingInterpolation::None);
    /// assert!(ChannelSurface::takes(&mesh, Builtin::Butterfly.scheme(), &linear));
    /// assert!(!ChannelSurface::takes(&mesh, Builtin::Butterfly.scheme(), &smooth));
    /// assert!(ChannelSurface::takes(&mesh, Builtin::Loop.scheme(), &smooth));
    /// assert!(ChannelSurface::takes(&mesh, Builtin::DooSabin.scheme(), &linear));
    /// assert!(!ChannelSurface::takes(&mesh, Builtin::Sqrt3.scheme(), &linear));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn takes(mesh: &Mesh, scheme: &Scheme, options: &RefineOptions) -> bool {
        scheme.has_crease_rules()
            || (options.rules_for(mesh).channels.mode == FaceVaryingInterpolation::All
                && scheme.split() != Split::Sqrt3)
    }

    /// Whether the channel is linear over every face ([`FaceVaryingInterpolation::All`]): its
    /// value at a face's `(u, v)` is then the bilinear (quads), linear (triangles under a
    /// triangle split) or sub-face bilinear (other polygons, over the bilinear split's first
    /// level) interpolation of the face's corners, which an evaluator may compute directly.
    pub fn is_linear(&self) -> bool {
        self.linear
    }

    /// The channel's mesh: its vertices are the channel's values (padded to three components
    /// with zeros), its faces the mesh's, its tags the channel's rules.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The scheme that refines [`mesh`](Self::mesh) as the channel refines: the mesh's, or under
    /// [`FaceVaryingInterpolation::All`] the linear split of the same kind (bilinear for quad
    /// splits, linear triangles for triangle splits).
    pub fn scheme(&self) -> &Scheme {
        &self.scheme
    }
}

fn linear_triangles() -> &'static Scheme {
    static SCHEME: OnceLock<Scheme> = OnceLock::new();
    SCHEME.get_or_init(|| Scheme::from_toml_str(LINEAR_TRIANGLES).expect("the linear triangle scheme is valid"))
}
