//! Subdivision schemes: uniform refinement of a [`Mesh`](subdiv_mesh::Mesh) with Catmull-Clark,
//! Loop or bilinear rules, following OpenSubdiv's `Sdc` exactly — boundaries (edge-only,
//! edge-and-corner, none), infinitely sharp and semi-sharp creases and corners (uniform and
//! Chaikin creasing), holes, and N-gons for Catmull-Clark.
//!
//! Child vertices are numbered as OpenSubdiv's `Far` levels: the children of the parent's
//! vertices first (vertex `v` stays vertex `v` at every level), then one point per face
//! (quad schemes), then one per edge. Child faces follow their parent's, in corner order.
//!
//! **Architecture invariant:** this crate knows no file format and does no I/O.
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh};
//! use subdiv_schemes::{refine, RefineOptions, Scheme};
//!
//! let icosahedron = Mesh::build(shapes::icosahedron())?;
//! let refined = refine(&icosahedron, Scheme::Loop, &RefineOptions::DEFAULT)?;
//! assert_eq!((refined.vertex_count(), refined.face_count()), (42, 80));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod analysis;
mod crease;
mod error;
mod refine;
mod stencil;

pub use analysis::{LocalMatrix, Spectrum};
pub use error::SchemeError;
pub use refine::{RefineOptions, Refiner, refine, refine_uniform};
pub use stencil::Stencils;

/// A subdivision scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Scheme {
    /// Catmull-Clark (`catmull-clark`): any polygons, split into quads.
    CatmullClark,
    /// Loop (`loop`): triangles only.
    Loop,
    /// Bilinear (`bilinear`): any polygons, split into quads; points stay on the cage.
    Bilinear,
}

impl Scheme {
    /// Every scheme, in CLI order.
    pub const ALL: [Self; 3] = [Self::CatmullClark, Self::Loop, Self::Bilinear];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Self::CatmullClark => "catmull-clark",
            Self::Loop => "loop",
            Self::Bilinear => "bilinear",
        }
    }

    /// The scheme of a CLI name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Whether faces split into quads (one per corner) rather than into four triangles.
    pub fn splits_into_quads(self) -> bool {
        !matches!(self, Self::Loop)
    }
}

impl std::fmt::Display for Scheme {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
