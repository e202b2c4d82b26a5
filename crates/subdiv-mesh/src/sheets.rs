//! Non-manifold soups taken apart into sheets, as OpenSubdiv refines them
//! ([`BuildOptions::split_sheets`](crate::BuildOptions::split_sheets)).
//!
//! OpenSubdiv makes an edge of more than two faces infinitely sharp (the sheets on it end on one
//! crease curve) and sharpens a non-manifold vertex into a corner, unless exactly two
//! non-manifold edges meet there (a crease runs through it). Cutting every such edge (each face
//! on it keeps its own copy, a border) and splitting every vertex into one copy per fan of
//! faces gives the same limit surface on a half-edge mesh: a border's rule is the crease rule on
//! the same two neighbours along the cut, and the copies OpenSubdiv would sharpen are tagged
//! infinitely sharp corners. (Under `EdgeAndCorner` boundaries a copy left with a single face
//! becomes a corner where OpenSubdiv's vertex would be a crease; OpenSubdiv's regression meshes
//! with non-manifold edges use `EdgeOnly`.)

use std::collections::{HashMap, HashSet};

use crate::VertexId;
use crate::soup::{CornerTag, CreaseTag, PolygonSoup, Tags};

/// Cuts `soup`'s non-manifold edges and splits its non-manifold vertices (see the module docs);
/// a manifold soup is left as it is. Faces with out-of-range or repeated vertices are left out
/// of the fans (the build reports them).
pub(crate) fn split_sheets(soup: &mut PolygonSoup) {
    let vertex_count = soup.vertex_count();
    let (offsets, fv) = soup.raw_faces();
    let offsets = offsets.to_vec();
    let mut fv: Vec<u32> = fv.iter().map(|v| v.index() as u32).collect();
    let face_count = offsets.len() - 1;
    let valid = |f: usize| {
        let corners = &fv[offsets[f] as usize..offsets[f + 1] as usize];
        corners.len() >= 3
            && corners.iter().all(|&v| (v as usize) < vertex_count)
            && corners.iter().enumerate().all(|(i, v)| !corners[..i].contains(v))
    };
    let faces: Vec<usize> = (0..face_count).filter(|&f| valid(f)).collect();
    let next = |h: usize, f: usize| if h + 1 == offsets[f + 1] as usize { offsets[f] as usize } else { h + 1 };
    // The sides on each undirected edge: (corner, face), the side running from the corner's
    // vertex to the next corner's.
    let mut sides: HashMap<(u32, u32), Vec<(usize, usize)>> = HashMap::new();
    for &f in &faces {
        for h in offsets[f] as usize..offsets[f + 1] as usize {
            let (a, b) = (fv[h], fv[next(h, f)]);
            sides.entry((a.min(b), a.max(b))).or_default().push((h, f));
        }
    }
    // Corners around one vertex joined across the edges of exactly two sides (a pair in the same
    // direction is joined too: the build reports its orientation).
    let mut parent: Vec<usize> = (0..fv.len()).collect();
    let mut non_manifold = vec![0u32; vertex_count];
    for (&(a, b), on) in &sides {
        match on[..] {
            [(h1, f1), (h2, f2)] => {
                let (n1, n2) = (next(h1, f1), next(h2, f2));
                if fv[h1] == fv[h2] {
                    union(&mut parent, h1, h2);
                    union(&mut parent, n1, n2);
                } else {
                    union(&mut parent, h1, n2);
                    union(&mut parent, n1, h2);
                }
            }
            [_] => {}
            _ => {
                non_manifold[a as usize] += 1;
                non_manifold[b as usize] += 1;
            }
        }
    }
    // One vertex per fan: the first keeps the vertex, the others are copies at its position.
    let fans = |parent: &mut Vec<usize>| {
        let mut roots: Vec<(u32, usize)> = faces
            .iter()
            .flat_map(|&f| offsets[f] as usize..offsets[f + 1] as usize)
            .map(|h| (fv[h], find(parent, h)))
            .collect();
        roots.sort_unstable();
        roots.dedup();
        roots.windows(2).any(|w| w[0].0 == w[1].0)
    };
    if non_manifold.iter().all(|&n| n == 0) && !fans(&mut parent) {
        return;
    }
    let mut copies: Vec<Vec<u32>> = (0..vertex_count as u32).map(|v| vec![v]).collect();
    let mut fan_vertex: HashMap<usize, u32> = HashMap::new();
    let mut first_fan: Vec<Option<usize>> = vec![None; vertex_count];
    for &f in &faces {
        let start = offsets[f] as usize;
        for (h, corner) in (start..).zip(&mut fv[start..offsets[f + 1] as usize]) {
            let root = find(&mut parent, h);
            let v = *corner as usize;
            let vertex = *fan_vertex.entry(root).or_insert_with(|| match first_fan[v] {
                None => {
                    first_fan[v] = Some(root);
                    v as u32
                }
                Some(_) => {
                    let copy = soup.push_vertex(soup.positions()[v]).index() as u32;
                    copies[v].push(copy);
                    copy
                }
            });
            *corner = vertex;
        }
    }
    // OpenSubdiv sharpens a non-manifold vertex unless exactly two non-manifold edges meet there.
    let mut tags = std::mem::take(&mut soup.tags);
    let sharpened: Vec<u32> = (0..vertex_count)
        .filter(|&v| (copies[v].len() > 1 || non_manifold[v] > 0) && non_manifold[v] != 2)
        .flat_map(|v| copies[v].clone())
        .collect();
    let corners = std::mem::take(&mut tags.corners);
    let copies_of = |v: VertexId| copies.get(v.index()).cloned().unwrap_or_else(|| vec![v.index() as u32]);
    tags.corners = corners
        .iter()
        .flat_map(|c| copies_of(c.vertex).into_iter().map(|v| CornerTag { vertex: VertexId::new(v), ..*c }))
        .chain(sharpened.iter().map(|&v| CornerTag { vertex: VertexId::new(v), sharpness: Tags::INFINITELY_SHARP }))
        .collect();
    // A crease on a cut edge goes to every copy of the edge (the new edges are listed only for
    // a soup with creases).
    let creases = std::mem::take(&mut tags.creases);
    let mut edges: HashSet<(u32, u32)> = HashSet::new();
    for &f in faces.iter().filter(|_| !creases.is_empty()) {
        for h in offsets[f] as usize..offsets[f + 1] as usize {
            let (a, b) = (fv[h], fv[next(h, f)]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    for c in creases {
        let [a, b] = c.vertices.map(copies_of);
        let mut pushed = false;
        for &x in &a {
            for &y in &b {
                if edges.contains(&(x.min(y), x.max(y))) {
                    tags.creases.push(CreaseTag { vertices: [VertexId::new(x), VertexId::new(y)], ..c });
                    pushed = true;
                }
            }
        }
        if !pushed {
            // Not an edge of the soup: kept, for the build to report.
            tags.creases.push(c);
        }
    }
    soup.tags = tags;
    for (corner, &v) in soup.corners_mut().iter_mut().zip(&fv) {
        *corner = VertexId::new(v);
    }
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (a, b) = (find(parent, a), find(parent, b));
    if a != b {
        parent[a.max(b)] = a.min(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BuildOptions, DVec3, Mesh, MeshError, shapes};

    fn soup(positions: usize, faces: &[&[u32]]) -> PolygonSoup {
        let positions = (0..positions).map(|i| DVec3::new(i as f64, (i * i % 7) as f64, (i % 3) as f64)).collect();
        PolygonSoup::from_indices(positions, faces.iter().copied())
    }

    /// Three pages of two quads each on the spine 0-1-2 (its two edges each of three faces).
    fn book() -> PolygonSoup {
        let mut faces: Vec<Vec<u32>> = Vec::new();
        for page in 0..3u32 {
            let [p0, p1, p2] = [3 + 3 * page, 4 + 3 * page, 5 + 3 * page];
            faces.push(vec![0, 1, p1, p0]);
            faces.push(vec![1, 2, p2, p1]);
        }
        let faces: Vec<&[u32]> = faces.iter().map(Vec::as_slice).collect();
        soup(12, &faces)
    }

    fn sharp(mesh: &Mesh) -> usize {
        mesh.vertices().filter(|&v| mesh.vertex_sharpness(v) >= Tags::INFINITELY_SHARP).count()
    }

    #[test]
    fn pages_on_a_spine_become_sheets_with_corners_at_its_ends() {
        let mut book = book();
        book.tags.creases.push(CreaseTag { vertices: [VertexId::new(0), VertexId::new(1)], sharpness: 2.0 });
        assert!(matches!(Mesh::build(book.clone()), Err(MeshError::NonManifoldEdge { .. })));
        let mut split = book.clone();
        split_sheets(&mut split);
        // The spine's three vertices, one per page; the crease on each page's copy of its edge.
        assert_eq!(split.vertex_count(), 12 + 3 * 2);
        assert_eq!(split.tags.creases.len(), 3);
        let mesh = Mesh::build_with(book, &BuildOptions::DEFAULT.with_split_sheets(true)).unwrap();
        assert_eq!(mesh.vertex_count(), 18);
        assert_eq!(mesh.boundary_edge_count(), 3 * 6);
        // The spine's ends are sharpened on every page; its middle, where two non-manifold edges
        // meet, is a crease (each page's border rule), not a corner.
        assert_eq!(sharp(&mesh), 6);
        for v in [0usize, 2] {
            assert!(mesh.vertex_sharpness(VertexId::new(v as u32)) >= Tags::INFINITELY_SHARP);
        }
        assert_eq!(mesh.vertex_sharpness(VertexId::new(1)), 0.0);
    }

    #[test]
    fn cones_touching_at_a_point_get_a_vertex_each_sharpened() {
        let hourglass = soup(7, &[&[0, 1, 2], &[0, 2, 3], &[0, 3, 1], &[0, 4, 5], &[0, 5, 6], &[0, 6, 4]]);
        assert!(matches!(Mesh::build(hourglass.clone()), Err(MeshError::NonManifoldVertex { .. })));
        let mesh = Mesh::build_with(hourglass, &BuildOptions::DEFAULT.with_split_sheets(true)).unwrap();
        assert_eq!(mesh.vertex_count(), 8);
        assert_eq!(sharp(&mesh), 2);
    }

    #[test]
    fn manifold_soups_are_left_as_they_are() {
        for manifold in [shapes::cube(), shapes::pole(5), shapes::default_model()] {
            let mut split = manifold.clone();
            split_sheets(&mut split);
            assert_eq!(split, manifold);
        }
    }
}
