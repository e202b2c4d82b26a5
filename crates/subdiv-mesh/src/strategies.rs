//! [`proptest`](mod@proptest) strategies for valid meshes (feature `proptest`): closed or
//! open, quads, triangles or N-gons, interior valences in a given range, creases, corners and
//! jittered positions. Every soup they generate passes [`Mesh::build`].
//!
//! Each mesh starts from a procedural shape ([`shapes`], some of them quadrangulated or
//! triangulated through face centres), then takes a few random operations that keep it a
//! manifold of the requested kind: face splits and merges (N-gons), edge bisections
//! (triangles), removing a face to open a closed mesh; then its positions are jittered and its
//! edges and vertices tagged. Shrinking removes operations and moves towards the first shapes,
//! the smallest.
//!
//! ```
//! use proptest::prelude::*;
//! use subdiv_mesh::strategies::{Closure, Faces, MeshParams, meshes};
//! use subdiv_mesh::Mesh;
//!
//! proptest! {
//!     #![proptest_config(ProptestConfig::with_cases(16))]
//!     // In a test file, `#[test]` goes here; a doc example calls the function itself.
//!     fn closed_triangle_meshes_have_even_face_counts(
//!         soup in meshes(MeshParams::DEFAULT.with_closure(Closure::Closed).with_faces(Faces::Triangles))
//!     ) {
//!         let mesh = Mesh::build(soup).unwrap();
//!         prop_assert!(mesh.boundary_loops().is_empty());
//!         // 3 F = 2 E on a closed triangle mesh.
//!         prop_assert_eq!(3 * mesh.face_count(), 2 * mesh.edge_count());
//!     }
//! }
//! # closed_triangle_meshes_have_even_face_counts();
//! ```

use std::ops::RangeInclusive;

use glam::DVec3;
use hashbrown::HashSet;
use proptest::prelude::*;

use crate::{CornerTag, CreaseTag, Mesh, PolygonSoup, Tags, VertexId, shapes};

/// Whether generated meshes have a boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Closure {
    /// Closed surfaces only (no boundary edge).
    Closed,
    /// Open surfaces only (at least one boundary loop).
    Open,
    /// Either.
    Any,
}

/// The face sizes generated meshes may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Faces {
    /// Quads only.
    Quads,
    /// Triangles only.
    Triangles,
    /// Any sizes from 3 to `max` (at least 4), mixed in one mesh.
    Polygons {
        /// The largest face size.
        max: usize,
    },
}

impl Faces {
    fn allows(self, size: usize) -> bool {
        match self {
            Self::Quads => size == 4,
            Self::Triangles => size == 3,
            Self::Polygons { max } => (3..=max.max(4)).contains(&size),
        }
    }
}

/// What [`meshes`] generates. Start from [`MeshParams::DEFAULT`] and change fields with the
/// `with_*` methods.
///
/// ```
/// use subdiv_mesh::strategies::{Closure, Faces, MeshParams};
///
/// let params = MeshParams::DEFAULT.with_closure(Closure::Open).with_faces(Faces::Quads).with_valences(4..=4);
/// assert_eq!(params.crease_probability, MeshParams::DEFAULT.crease_probability);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct MeshParams {
    /// Closed, open or either. Default [`Closure::Any`].
    pub closure: Closure,
    /// The face sizes. Default `Faces::Polygons { max: 6 }`.
    pub faces: Faces,
    /// The valences interior vertices may have (boundary vertices are not constrained).
    /// Default `3..=8`. It must admit some shape: valence 4 for quads, 6 for triangles, or 3 for
    /// the cube-like shapes; [`meshes`] panics when no shape fits.
    pub valences: RangeInclusive<usize>,
    /// The probability that an edge is tagged as a crease. Default 0.1. Sharpness is
    /// [`Tags::INFINITELY_SHARP`] in a third of the cases, else semi-sharp in 0.25..=4.
    pub crease_probability: f64,
    /// The probability that a vertex is tagged as a corner, sharpness as for creases. Default
    /// 0.05.
    pub corner_probability: f64,
    /// Each coordinate moves by up to this much (the shapes' edges are 0.4 to 2 long). Default
    /// 0.05; 0 keeps the shapes' positions.
    pub jitter: f64,
    /// At most this many random face splits, merges or edge bisections. Default 4.
    pub max_operations: usize,
    /// At least this many faces. Default 1.
    pub min_faces: usize,
}

impl MeshParams {
    /// The defaults: any closure, faces of 3 to 6 vertices, interior valences 3 to 8, a few
    /// creases and corners, small jitter, up to 4 operations.
    pub const DEFAULT: Self = Self {
        closure: Closure::Any,
        faces: Faces::Polygons { max: 6 },
        valences: 3..=8,
        crease_probability: 0.1,
        corner_probability: 0.05,
        jitter: 0.05,
        max_operations: 4,
        min_faces: 1,
    };

    /// With `closure`.
    pub fn with_closure(mut self, closure: Closure) -> Self {
        self.closure = closure;
        self
    }

    /// With `faces`.
    pub fn with_faces(mut self, faces: Faces) -> Self {
        self.faces = faces;
        self
    }

    /// With interior valences in `valences`.
    pub fn with_valences(mut self, valences: RangeInclusive<usize>) -> Self {
        self.valences = valences;
        self
    }

    /// With `crease_probability`.
    pub fn with_crease_probability(mut self, probability: f64) -> Self {
        self.crease_probability = probability;
        self
    }

    /// With `corner_probability`.
    pub fn with_corner_probability(mut self, probability: f64) -> Self {
        self.corner_probability = probability;
        self
    }

    /// Without creases or corners.
    pub fn untagged(self) -> Self {
        self.with_crease_probability(0.0).with_corner_probability(0.0)
    }

    /// With `jitter`.
    pub fn with_jitter(mut self, jitter: f64) -> Self {
        self.jitter = jitter;
        self
    }

    /// With at least `min_faces` faces.
    pub fn with_min_faces(mut self, min_faces: usize) -> Self {
        self.min_faces = min_faces;
        self
    }

    /// With at most `max_operations` random operations.
    pub fn with_max_operations(mut self, max_operations: usize) -> Self {
        self.max_operations = max_operations;
        self
    }
}

impl Default for MeshParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Valid meshes as `params` asks.
///
/// # Panics
/// When no shape fits `params` (for example quads with interior valences `5..=5` only).
pub fn meshes(params: MeshParams) -> impl Strategy<Value = PolygonSoup> {
    let bases = catalog(&params);
    assert!(!bases.is_empty(), "subdiv_mesh::strategies::meshes: no shape fits {params:?}");
    let count = bases.len();
    (0..count, prop::collection::vec(any::<(usize, usize)>(), 0..=params.max_operations), any::<usize>(), any::<u64>())
        .prop_map(move |(base, operations, opening, seed)| generate(&bases[base], &params, &operations, opening, seed))
}

/// Closed meshes with the default parameters.
pub fn closed_meshes() -> impl Strategy<Value = PolygonSoup> {
    meshes(MeshParams::DEFAULT.with_closure(Closure::Closed))
}

/// Open meshes with the default parameters.
pub fn open_meshes() -> impl Strategy<Value = PolygonSoup> {
    meshes(MeshParams::DEFAULT.with_closure(Closure::Open))
}

/// `soup` with its vertices renamed, its faces reordered and each face's corners rotated at
/// random: the same mesh, written differently. Tags are renamed with the vertices; holes, which
/// name faces, are dropped.
pub fn relabelled(soup: PolygonSoup) -> impl Strategy<Value = PolygonSoup> {
    any::<u64>().prop_map(move |seed| relabel(&soup, seed))
}

fn relabel(soup: &PolygonSoup, seed: u64) -> PolygonSoup {
    let mut rng = Rng(seed);
    let n = soup.vertex_count();
    let mut permutation: Vec<u32> = (0..n as u32).collect();
    rng.shuffle(&mut permutation);
    let mut positions = vec![DVec3::ZERO; n];
    for (old, &new) in permutation.iter().enumerate() {
        positions[new as usize] = soup.positions()[old];
    }
    let mut faces: Vec<Vec<u32>> = soup.faces().map(|f| f.iter().map(|v| permutation[v.index()]).collect()).collect();
    rng.shuffle(&mut faces);
    for face in &mut faces {
        let k = rng.below(face.len());
        face.rotate_left(k);
    }
    let mut out = PolygonSoup::from_indices(positions, faces);
    let rename = |v: VertexId| VertexId::new(permutation[v.index()]);
    out.tags = Tags {
        creases: soup.tags.creases.iter().map(|c| CreaseTag { vertices: c.vertices.map(rename), ..*c }).collect(),
        corners: soup.tags.corners.iter().map(|c| CornerTag { vertex: rename(c.vertex), ..*c }).collect(),
        holes: Vec::new(),
        ..soup.tags.clone()
    };
    out
}

/// A shape and whether it is closed.
#[derive(Clone, Debug)]
struct Base {
    soup: PolygonSoup,
    closed: bool,
}

/// Every shape that fits `params` (an open one may also come from a closed one by removing a
/// face).
fn catalog(params: &MeshParams) -> Vec<Base> {
    let mut closed: Vec<PolygonSoup> = vec![shapes::cube(), shapes::tetrahedron(), shapes::octahedron()];
    closed.extend([shapes::icosahedron(), shapes::dodecahedron()]);
    closed.extend([(3, 3), (4, 3), (5, 4), (6, 5)].map(|(m, n)| shapes::quad_torus(m, n)));
    closed.extend([(3, 3), (5, 4)].map(|(m, n)| shapes::triangle_torus(m, n)));
    closed.extend((3..=8).map(shapes::ngon_prism));
    let mut derived = Vec::new();
    for soup in [shapes::tetrahedron(), shapes::octahedron(), shapes::dodecahedron()]
        .into_iter()
        .chain((3..=8).map(shapes::ngon_prism))
    {
        derived.push(quadrangulate(&soup));
        derived.push(triangulate(&soup));
    }
    derived.push(triangulate(&shapes::cube()));
    closed.extend(derived);
    closed.push(shapes::default_model());

    let mut open: Vec<PolygonSoup> = [(1, 1), (2, 1), (3, 2), (3, 3)].map(|(m, n)| shapes::quad_grid(m, n)).into();
    open.extend((3..=8).map(shapes::pole));
    open.extend([(2, 2), (3, 2)].map(|(m, n)| split_diagonals(&shapes::quad_grid(m, n))));
    open.extend([shapes::quad_grid(2, 2), shapes::pole(3), shapes::pole(5)].iter().map(triangulate));

    let mut bases = Vec::new();
    // A closed shape may lose a face to open it.
    let opened = usize::from(params.closure != Closure::Closed);
    let fits = |soup: &PolygonSoup, extra: usize| {
        soup.face_count() >= params.min_faces + extra
            && soup.faces().all(|f| params.faces.allows(f.len()))
            && Mesh::build(soup.clone()).is_ok_and(|mesh| valences_fit(&mesh, &params.valences))
    };
    // Closed shapes also give open ones, with a face removed.
    bases.extend(closed.into_iter().filter(|s| fits(s, opened)).map(|soup| Base { soup, closed: true }));
    if params.closure != Closure::Closed {
        bases.extend(open.into_iter().filter(|s| fits(s, 0)).map(|soup| Base { soup, closed: false }));
    }
    // Smallest first, so that shrinking moves towards small meshes.
    bases.sort_by_key(|b| b.soup.face_count());
    bases
}

fn valences_fit(mesh: &Mesh, valences: &RangeInclusive<usize>) -> bool {
    mesh.vertices().all(|v| mesh.is_isolated(v) || mesh.is_boundary_vertex(v) || valences.contains(&mesh.valence(v)))
}

fn generate(base: &Base, params: &MeshParams, operations: &[(usize, usize)], opening: usize, seed: u64) -> PolygonSoup {
    let mut soup = base.soup.clone();
    let mut rng = Rng(seed);
    let open = match params.closure {
        Closure::Closed => false,
        Closure::Open => true,
        Closure::Any => rng.below(2) == 1,
    };
    let min_faces = params.min_faces + usize::from(base.closed && open);
    for &(which, how) in operations {
        let candidate = match params.faces {
            Faces::Quads => None,
            Faces::Triangles => bisect_edge(&soup, which, how),
            Faces::Polygons { .. } => match rng.below(3) {
                0 => split_face(&soup, which, how),
                1 => merge_faces(&soup, which, how),
                _ => bisect_edge(&soup, which, how),
            },
        };
        if let Some(candidate) = candidate
            && candidate.face_count() >= min_faces
            && candidate.faces().all(|f| params.faces.allows(f.len()))
            && Mesh::build(candidate.clone()).is_ok_and(|mesh| valences_fit(&mesh, &params.valences))
        {
            soup = candidate;
        }
    }
    if base.closed && open {
        soup = remove_face(&soup, opening % soup.face_count());
    }
    for p in soup.positions_mut() {
        *p += DVec3::new(rng.unit(), rng.unit(), rng.unit()) * params.jitter;
    }
    let mesh = built(soup.clone());
    let sharpness = |rng: &mut Rng| {
        if rng.below(3) == 0 { Tags::INFINITELY_SHARP } else { (1 + rng.below(16)) as f64 * 0.25 }
    };
    for e in mesh.edges() {
        if rng.chance(params.crease_probability) {
            soup.tags.creases.push(CreaseTag { vertices: mesh.edge_vertices(e), sharpness: sharpness(&mut rng) });
        }
    }
    for v in mesh.vertices() {
        if rng.chance(params.corner_probability) {
            soup.tags.corners.push(CornerTag { vertex: v, sharpness: sharpness(&mut rng) });
        }
    }
    soup
}

fn faces_of(soup: &PolygonSoup) -> Vec<Vec<VertexId>> {
    soup.faces().map(<[VertexId]>::to_vec).collect()
}

fn with_faces(soup: &PolygonSoup, positions: Vec<DVec3>, faces: Vec<Vec<VertexId>>) -> PolygonSoup {
    let mut out = PolygonSoup::with_capacity(positions.len(), faces.len(), 0);
    for p in positions {
        out.push_vertex(p);
    }
    for face in faces {
        out.push_face(face);
    }
    out.tags = soup.tags.clone();
    out
}

fn centroid(soup: &PolygonSoup, face: &[VertexId]) -> DVec3 {
    face.iter().map(|v| soup.positions()[v.index()]).sum::<DVec3>() / face.len() as f64
}

/// Every face split into quads through its centroid and edge midpoints (one Catmull-Clark
/// split, positions averaged): face centres get the face's size as valence.
fn quadrangulate(soup: &PolygonSoup) -> PolygonSoup {
    let mut positions = soup.positions().to_vec();
    let mut midpoints = hashbrown::HashMap::new();
    let mut faces = Vec::new();
    for face in soup.faces() {
        let centre = VertexId::new(positions.len() as u32);
        positions.push(centroid(soup, face));
        let mut midpoint = |a: VertexId, b: VertexId| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push((soup.positions()[a.index()] + soup.positions()[b.index()]) / 2.0);
                VertexId::new(positions.len() as u32 - 1)
            })
        };
        let n = face.len();
        let mids: Vec<VertexId> = (0..n).map(|i| midpoint(face[i], face[(i + 1) % n])).collect();
        for i in 0..n {
            faces.push(vec![face[i], mids[i], centre, mids[(i + n - 1) % n]]);
        }
    }
    with_faces(soup, positions, faces)
}

/// Every face split into a fan of triangles around its centroid.
fn triangulate(soup: &PolygonSoup) -> PolygonSoup {
    let mut positions = soup.positions().to_vec();
    let mut faces = Vec::new();
    for face in soup.faces() {
        let centre = VertexId::new(positions.len() as u32);
        positions.push(centroid(soup, face));
        let n = face.len();
        faces.extend((0..n).map(|i| vec![face[i], face[(i + 1) % n], centre]));
    }
    with_faces(soup, positions, faces)
}

/// Every quad split along its diagonal from its first corner.
fn split_diagonals(soup: &PolygonSoup) -> PolygonSoup {
    let faces = soup.faces().flat_map(|f| [vec![f[0], f[1], f[2]], vec![f[0], f[2], f[3]]]).collect();
    with_faces(soup, soup.positions().to_vec(), faces)
}

fn edges_of(soup: &PolygonSoup) -> HashSet<(VertexId, VertexId)> {
    soup.faces()
        .flat_map(|f| (0..f.len()).map(move |i| (f[i].min(f[(i + 1) % f.len()]), f[i].max(f[(i + 1) % f.len()]))))
        .collect()
}

/// A face of at least 4 corners cut along a chord between two non-adjacent corners that are not
/// already joined by an edge.
fn split_face(soup: &PolygonSoup, which: usize, how: usize) -> Option<PolygonSoup> {
    let mut faces = faces_of(soup);
    let f = which % faces.len();
    let face = faces[f].clone();
    let n = face.len();
    if n < 4 {
        return None;
    }
    // Corner 0 to corner j, 2 <= j <= n - 2.
    let start = how % n;
    let face: Vec<VertexId> = face[start..].iter().chain(&face[..start]).copied().collect();
    let j = 2 + how / n % (n - 3);
    let (a, b) = (face[0], face[j]);
    if edges_of(soup).contains(&(a.min(b), a.max(b))) {
        return None;
    }
    faces[f] = face[..=j].to_vec();
    faces.push(face[j..].iter().chain([&face[0]]).copied().collect());
    Some(with_faces(soup, soup.positions().to_vec(), faces))
}

/// Two faces that share an edge joined into one, where the result repeats no vertex.
fn merge_faces(soup: &PolygonSoup, which: usize, how: usize) -> Option<PolygonSoup> {
    let mut faces = faces_of(soup);
    let f = which % faces.len();
    let n = faces[f].len();
    let i = how % n;
    let (a, b) = (faces[f][i], faces[f][(i + 1) % n]);
    // The face on the other side runs b -> a.
    let g = faces.iter().position(|g| (0..g.len()).any(|k| g[k] == b && g[(k + 1) % g.len()] == a))?;
    let rotate = |face: &[VertexId], first: VertexId| -> Vec<VertexId> {
        let k = face.iter().position(|&v| v == first).unwrap_or(0);
        face[k..].iter().chain(&face[..k]).copied().collect()
    };
    let (fr, gr) = (rotate(&faces[f], a), rotate(&faces[g], b));
    // fr = [a, b, x..], gr = [b, a, y..]: the merged face is [b, x.., a, y..].
    let merged: Vec<VertexId> =
        [b].into_iter().chain(fr[2..].iter().copied()).chain([a]).chain(gr[2..].iter().copied()).collect();
    let distinct: HashSet<VertexId> = merged.iter().copied().collect();
    if distinct.len() != merged.len() || merged.len() < 3 {
        return None;
    }
    faces[f] = merged;
    faces.remove(g);
    let mut out = with_faces(soup, soup.positions().to_vec(), faces);
    out.tags.creases.retain(|c| c.vertices != [a, b] && c.vertices != [b, a]);
    Some(out)
}

/// An edge whose faces are all triangles cut at its midpoint, each of its triangles into two.
fn bisect_edge(soup: &PolygonSoup, which: usize, how: usize) -> Option<PolygonSoup> {
    let mut faces = faces_of(soup);
    let f = which % faces.len();
    let n = faces[f].len();
    let i = how % n;
    let (a, b) = (faces[f][i], faces[f][(i + 1) % n]);
    let sides: Vec<usize> = faces
        .iter()
        .enumerate()
        .filter(|(_, g)| g.contains(&a) && g.contains(&b) && g.len() == 3)
        .map(|(k, _)| k)
        .collect();
    if faces.iter().filter(|g| g.contains(&a) && g.contains(&b)).count() != sides.len() {
        return None;
    }
    let mut positions = soup.positions().to_vec();
    let m = VertexId::new(positions.len() as u32);
    positions.push((positions[a.index()] + positions[b.index()]) / 2.0);
    for &k in &sides {
        // The triangle rotated to [p, q, r] with p -> q the edge (either direction).
        let g = faces[k].clone();
        let s = (0..3).find(|&s| [g[s], g[(s + 1) % 3]] == [a, b] || [g[s], g[(s + 1) % 3]] == [b, a])?;
        let (p, q, r) = (g[s], g[(s + 1) % 3], g[(s + 2) % 3]);
        faces[k] = vec![p, m, r];
        faces.push(vec![m, q, r]);
    }
    let mut out = with_faces(soup, positions, faces);
    out.tags.creases.retain(|c| c.vertices != [a, b] && c.vertices != [b, a]);
    Some(out)
}

/// The soup without face `face`, its now unused vertices removed.
fn remove_face(soup: &PolygonSoup, face: usize) -> PolygonSoup {
    let mut faces = faces_of(soup);
    faces.remove(face);
    let mut used = vec![false; soup.vertex_count()];
    for v in faces.iter().flatten() {
        used[v.index()] = true;
    }
    let mut renumber = vec![0u32; used.len()];
    let mut positions = Vec::new();
    for (v, &u) in used.iter().enumerate() {
        if u {
            renumber[v] = positions.len() as u32;
            positions.push(soup.positions()[v]);
        }
    }
    let faces =
        faces.into_iter().map(|f| f.into_iter().map(|v| VertexId::new(renumber[v.index()])).collect()).collect();
    let mut out = with_faces(soup, positions, faces);
    out.tags = Tags::default();
    out
}

fn built(soup: PolygonSoup) -> Mesh {
    match Mesh::build(soup) {
        Ok(mesh) => mesh,
        // Every step above keeps the soup valid; reaching this is a bug in this module.
        Err(error) => unreachable!("generated mesh is invalid, please report: {error}"),
    }
}

/// A small deterministic generator (an LCG), so that one seed gives one mesh.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0 >> 11
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// Uniform in [-1, 1).
    fn unit(&mut self) -> f64 {
        self.next() as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn chance(&mut self, probability: f64) -> bool {
        probability > 0.0 && (self.next() as f64 / (1u64 << 53) as f64) < probability
    }

    fn shuffle<T>(&mut self, items: &mut [T]) {
        for i in (1..items.len()).rev() {
            let j = self.below(i + 1);
            items.swap(i, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(soup: &PolygonSoup, params: &MeshParams) -> Result<Mesh, TestCaseError> {
        let mesh = Mesh::build(soup.clone()).map_err(|e| TestCaseError::fail(format!("{e}: {soup:?}")))?;
        prop_assert!(soup.faces().all(|f| params.faces.allows(f.len())), "face sizes: {soup:?}");
        prop_assert!(valences_fit(&mesh, &params.valences), "valences: {:?}", mesh.valence_histogram());
        match params.closure {
            Closure::Closed => prop_assert!(mesh.boundary_loops().is_empty()),
            Closure::Open => prop_assert!(!mesh.boundary_loops().is_empty()),
            Closure::Any => {}
        }
        prop_assert!(mesh.vertices().all(|v| !mesh.is_isolated(v)));
        prop_assert!(mesh.face_count() >= params.min_faces);
        Ok(mesh)
    }

    fn params() -> impl Strategy<Value = MeshParams> {
        let closure = prop::sample::select(vec![Closure::Closed, Closure::Open, Closure::Any]);
        let faces = prop_oneof![
            Just(Faces::Quads),
            Just(Faces::Triangles),
            (4usize..9).prop_map(|max| Faces::Polygons { max })
        ];
        let valences = prop_oneof![Just(3..=8), Just(3..=16), Just(4..=4), Just(6..=6), Just(3..=5), Just(4..=6)];
        (closure, faces, valences, 0.0..0.5f64, 1usize..12).prop_filter_map(
            "no shape fits",
            |(closure, faces, valences, p, min_faces)| {
                let params = MeshParams::DEFAULT
                    .with_closure(closure)
                    .with_faces(faces)
                    .with_valences(valences)
                    .with_crease_probability(p)
                    .with_corner_probability(p / 2.0)
                    .with_max_operations(8)
                    .with_min_faces(min_faces);
                (!catalog(&params).is_empty()).then_some(params)
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn every_generated_soup_builds(
            (params, soup) in params().prop_flat_map(|p| (Just(p.clone()), meshes(p)))
        ) {
            check(&soup, &params)?;
        }

        #[test]
        fn default_meshes_build(soup in meshes(MeshParams::DEFAULT)) {
            check(&soup, &MeshParams::DEFAULT)?;
        }

        #[test]
        fn closed_and_open_meshes_are_closed_and_open(closed in closed_meshes(), open in open_meshes()) {
            check(&closed, &MeshParams::DEFAULT.with_closure(Closure::Closed))?;
            check(&open, &MeshParams::DEFAULT.with_closure(Closure::Open))?;
        }

        #[test]
        fn relabelled_meshes_are_the_same_mesh(soup in closed_meshes().prop_flat_map(|s| (Just(s.clone()), relabelled(s)))) {
            let (original, relabelled) = (Mesh::build(soup.0).unwrap(), Mesh::build(soup.1).unwrap());
            prop_assert_eq!(original.valence_histogram(), relabelled.valence_histogram());
            prop_assert_eq!(original.edge_count(), relabelled.edge_count());
            let sharp = |m: &Mesh| m.edges().filter(|&e| m.edge_sharpness(e) > 0.0).count();
            prop_assert_eq!(sharp(&original), sharp(&relabelled));
        }
    }

    #[test]
    fn operations_and_tags_happen() {
        // Over a fixed set of seeds, N-gon meshes get every operation and tags.
        let params = MeshParams::DEFAULT.with_closure(Closure::Closed).with_max_operations(8);
        let bases = catalog(&params);
        let (mut changed, mut creases, mut corners) = (0, 0, 0);
        for seed in 0..64u64 {
            let mut rng = Rng(seed);
            let ops: Vec<(usize, usize)> = (0..8).map(|_| (rng.next() as usize, rng.next() as usize)).collect();
            let base = &bases[seed as usize % bases.len()];
            let soup = generate(base, &params, &ops, 0, seed);
            changed += usize::from(soup.face_count() != base.soup.face_count());
            creases += soup.tags.creases.len();
            corners += soup.tags.corners.len();
        }
        assert!(changed > 10 && creases > 10 && corners > 0, "{changed} {creases} {corners}");
    }

    #[test]
    #[should_panic(expected = "no shape fits")]
    fn impossible_params_panic() {
        let _ = meshes(MeshParams::DEFAULT.with_faces(Faces::Quads).with_valences(5..=5).with_closure(Closure::Closed));
    }
}
