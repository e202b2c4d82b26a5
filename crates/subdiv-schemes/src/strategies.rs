//! [`proptest`](mod@proptest) strategies for schemes (feature `proptest`): the built-ins, all or
//! by split, perturbed variants with a free parameter, and schemes paired with meshes they take
//! (from [`subdiv_mesh::strategies`], which this feature enables).
//!
//! ```
//! use proptest::prelude::*;
//! use subdiv_mesh::Mesh;
//! use subdiv_schemes::strategies::mesh_and_scheme;
//! use subdiv_schemes::{RefineOptions, refine};
//!
//! proptest! {
//!     #![proptest_config(ProptestConfig::with_cases(8))]
//!     // In a test file, `#[test]` goes here; a doc example calls the function itself.
//!     fn every_scheme_refines_the_meshes_it_takes((scheme, soup) in mesh_and_scheme()) {
//!         let mesh = Mesh::build(soup).unwrap();
//!         let refined = refine(&mesh, &scheme, &RefineOptions::DEFAULT).unwrap();
//!         prop_assert!(refined.face_count() >= mesh.face_count());
//!     }
//! }
//! # every_scheme_refines_the_meshes_it_takes();
//! ```

use proptest::prelude::*;
use subdiv_mesh::PolygonSoup;
use subdiv_mesh::strategies::{Closure, Faces, MeshParams, meshes};

use crate::{Builtin, Expr, Rules, Scheme, Split};

/// Any built-in.
pub fn builtins() -> impl Strategy<Value = Builtin> {
    prop::sample::select(Builtin::ALL.to_vec())
}

/// Any built-in's scheme.
pub fn builtin_schemes() -> impl Strategy<Value = Scheme> {
    builtins().prop_map(|b| b.scheme().clone())
}

fn builtins_where(keep: impl Fn(&Scheme) -> bool) -> impl Strategy<Value = Scheme> {
    let schemes: Vec<Scheme> = Builtin::ALL.iter().map(|b| b.scheme()).filter(|s| keep(s)).cloned().collect();
    prop::sample::select(schemes)
}

/// The built-ins with a primal quad split (Catmull-Clark, Kobbelt, sw-quad, bilinear).
pub fn quad_schemes() -> impl Strategy<Value = Scheme> {
    builtins_where(|s| s.split() == Split::Quad)
}

/// The built-ins that take triangles only (Loop, √3, Butterfly).
pub fn triangle_schemes() -> impl Strategy<Value = Scheme> {
    builtins_where(|s| s.face_size() == Some(3))
}

/// The built-ins with rules for boundaries, creases and corners.
pub fn crease_schemes() -> impl Strategy<Value = Scheme> {
    builtins_where(Scheme::has_crease_rules)
}

/// Variants of the built-ins with one free parameter, each valid ([`Scheme::validate`]):
/// Kobbelt's four-point tension `w = i/64`, `i` in 0..=8 (1/16 is Kobbelt's); Loop with the
/// vertex spoke weight `i/(16 k)`, `i` in 4..=8 (6 is Warren's 3/(8k)); Catmull-Clark with
/// vertex spoke and face weights `a/(4 k²)` and `b/(4 k²)`, `a`, `b` in 2..=6 (4 and 4 are
/// Catmull-Clark's). Their names say the parameter.
pub fn perturbed_schemes() -> impl Strategy<Value = Scheme> {
    prop_oneof![
        (0u32..=8).prop_map(|i| {
            let mut scheme = Builtin::Kobbelt.scheme().clone();
            if let Rules::FourPointQuad { weight, .. } = &mut scheme.rules {
                *weight = formula(&format!("{i}/64"));
            }
            scheme.name = format!("kobbelt-w{i}/64");
            scheme
        }),
        (4u32..=8).prop_map(|i| {
            let mut scheme = Builtin::Loop.scheme().clone();
            if let Rules::Triangle { vertex, .. } = &mut scheme.rules {
                vertex.centre = None;
                vertex.spoke = formula(&format!("{i}/(16*k)"));
            }
            scheme.name = format!("loop-spoke{i}/16k");
            scheme
        }),
        (2u32..=6, 2u32..=6).prop_map(|(a, b)| {
            let mut scheme = Builtin::CatmullClark.scheme().clone();
            if let Rules::Quad { vertex, .. } = &mut scheme.rules {
                vertex.centre = None;
                vertex.spoke = formula(&format!("{a}/(4*k^2)"));
                vertex.face = formula(&format!("{b}/(4*k^2)"));
            }
            scheme.name = format!("catmull-clark-{a}-{b}");
            scheme
        }),
    ]
}

fn formula(source: &str) -> Expr {
    match source.parse() {
        Ok(expr) => expr,
        // The formulas above are this module's own; reaching this is a bug here.
        Err(error) => unreachable!("formula {source} does not parse, please report: {error}"),
    }
}

/// `params` restricted to the meshes `scheme` takes: triangles only for triangle schemes, quads
/// only for Kobbelt's, closed and untagged meshes for schemes without crease rules. Other
/// fields are kept.
pub fn mesh_params(scheme: &Scheme, params: MeshParams) -> MeshParams {
    let params = match scheme.face_size() {
        Some(3) => params.with_faces(Faces::Triangles),
        Some(4) => params.with_faces(Faces::Quads),
        _ => params,
    };
    if scheme.has_crease_rules() { params } else { params.with_closure(Closure::Closed).untagged() }
}

/// Meshes that `scheme` takes, as `params` asks within [`mesh_params`].
pub fn meshes_for(scheme: &Scheme, params: MeshParams) -> impl Strategy<Value = PolygonSoup> + use<> {
    meshes(mesh_params(scheme, params))
}

/// Each scheme of `schemes` with a mesh it takes, as `params` asks within [`mesh_params`].
pub fn with_meshes(
    schemes: impl Strategy<Value = Scheme>,
    params: MeshParams,
) -> impl Strategy<Value = (Scheme, PolygonSoup)> {
    schemes.prop_flat_map(move |scheme| {
        let soups = meshes_for(&scheme, params.clone());
        (Just(scheme), soups)
    })
}

/// Any built-in with a mesh it takes ([`MeshParams::DEFAULT`] within [`mesh_params`]).
pub fn mesh_and_scheme() -> impl Strategy<Value = (Scheme, PolygonSoup)> {
    with_meshes(builtin_schemes(), MeshParams::DEFAULT)
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::Mesh;

    use super::*;
    use crate::{RefineOptions, refine};

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        #[test]
        fn every_pair_refines((scheme, soup) in with_meshes(prop_oneof![builtin_schemes(), perturbed_schemes()], MeshParams::DEFAULT)) {
            let mesh = Mesh::build(soup).unwrap();
            let refined = refine(&mesh, &scheme, &RefineOptions::DEFAULT);
            prop_assert!(refined.is_ok(), "{scheme}: {:?}", refined.err());
        }

        #[test]
        fn perturbed_schemes_are_valid(scheme in perturbed_schemes()) {
            prop_assert!(scheme.validate().is_ok(), "{scheme}: {:?}", scheme.validate());
            // Through text and back, as a user's file would come.
            prop_assert_eq!(Scheme::from_toml_str(&scheme.to_toml_string()).unwrap(), scheme);
        }

        #[test]
        fn filtered_builtins_have_their_split(quad in quad_schemes(), triangle in triangle_schemes(), crease in crease_schemes()) {
            prop_assert_eq!(quad.split(), Split::Quad);
            prop_assert_eq!(triangle.face_size(), Some(3));
            prop_assert!(crease.has_crease_rules());
        }
    }
}
