//! The canonical meshes the analysis and the sub-patch matrices run the engine on: fans of
//! regular grid sectors around vertex 0, closed into a pillow for interior vertices or left
//! open for boundary ones.

use std::collections::HashMap;

use subdiv_mesh::{CornerTag, CreaseTag, DVec3, PolygonSoup, Tags, VertexId};

use crate::SharpFeatures;

/// `k` sectors of a regular grid of `rings` rings around vertex 0 in the plane z = 0 (quads, or
/// triangles), and a mirrored copy far below, joined along their rims by a band of quads (split
/// into triangles for triangle schemes) so that the mesh is closed and every vertex has valence
/// 3 or more. Sector `s` spans the directions `e_s` and `e_{s+1}` (`e_s` at angle 2πs/k); its
/// grid point `(i, j)` sits at `i·e_s + j·e_{s+1}`. Vertex 1 is sector 0's `(1, 0)`, and the
/// first face is sector 0's cell at the centre, starting at vertex 0. `sharp` makes spokes of
/// the top sheet infinitely sharp all the way to the rim, and vertex 0 a corner.
pub(crate) fn pillow(k: usize, rings: usize, triangles: bool, sharp: SharpFeatures) -> PolygonSoup {
    let mut soup = PolygonSoup::new();
    let fan = Fan { sectors: k, closed: true, rings, triangles };
    let top = fan.sheet(&mut soup, DVec3::ZERO, false);
    let bottom = fan.sheet(&mut soup, -DVec3::Z * 4.0 * rings as f64, true);
    // The rim, counter-clockwise: per sector from (R, 0) to just before the next spoke.
    let mut rim = Vec::new();
    for s in 0..k {
        if triangles {
            rim.extend((0..rings).map(|j| (s, rings - j, j)));
        } else {
            rim.extend((0..=rings).map(|j| (s, rings, j)));
            rim.extend((1..rings).rev().map(|i| (s, i, rings)));
        }
    }
    for (n, &(s, i, j)) in rim.iter().enumerate() {
        let (t, p, q) = rim[(n + 1) % rim.len()];
        let (a, b) = (top.id(s, i, j), top.id(t, p, q));
        let (a2, b2) = (bottom.id(s, i, j), bottom.id(t, p, q));
        if triangles {
            soup.push_face([b, a, a2]);
            soup.push_face([b, a2, b2]);
        } else {
            soup.push_face([b, a, a2, b2]);
        }
    }
    top.sharpen(&mut soup, (0..k).filter(|&s| sharp.edge(s)), rings, sharp.corner);
    soup
}

/// `faces` sectors of a regular grid of `rings` rings around vertex 0, open: vertex 0 is on
/// the boundary with `faces` faces around it, and sector 0's spoke (from vertex 0 through
/// vertex 1) is a boundary edge. The first face is sector 0's cell at the centre, starting at
/// vertex 0, so its first side lies on the boundary. `sharp` makes interior spokes
/// infinitely sharp, and vertex 0 a corner.
pub(crate) fn open_fan(faces: usize, rings: usize, triangles: bool, sharp: SharpFeatures) -> PolygonSoup {
    let mut soup = PolygonSoup::new();
    let sheet = Fan { sectors: faces, closed: false, rings, triangles }.sheet(&mut soup, DVec3::ZERO, false);
    sheet.sharpen(&mut soup, (1..faces).filter(|&s| sharp.edge(s)), rings, sharp.corner);
    soup
}

struct Fan {
    sectors: usize,
    closed: bool,
    rings: usize,
    triangles: bool,
}

/// One sheet of a fan: its centre and its other points by (sector, i, j).
struct Sheet {
    /// The sector count of a closed fan, whose last sector wraps onto the first; `None` if open.
    wrap: Option<usize>,
    centre: VertexId,
    ids: HashMap<(usize, usize, usize), VertexId>,
}

impl Sheet {
    /// Tags the edges of `spokes` infinitely sharp from the centre to the rim, and the centre
    /// a corner if `corner`: a straight crease through every vertex on the way, so that the
    /// only irregular place is the centre.
    fn sharpen(&self, soup: &mut PolygonSoup, spokes: impl Iterator<Item = usize>, rings: usize, corner: bool) {
        for s in spokes {
            let mut from = self.centre;
            for i in 1..=rings {
                let to = self.id(s, i, 0);
                soup.tags.creases.push(CreaseTag { vertices: [from, to], sharpness: Tags::INFINITELY_SHARP });
                from = to;
            }
        }
        if corner {
            soup.tags.corners.push(CornerTag { vertex: self.centre, sharpness: Tags::INFINITELY_SHARP });
        }
    }

    /// Sector `s`'s grid point `(i, j)`; points with `i = 0` belong to the next sector, as its
    /// `(j, 0)` (for an open fan, the last spoke is a sector of its own with `j = 0` only).
    fn id(&self, s: usize, i: usize, j: usize) -> VertexId {
        match (i, j) {
            (0, 0) => self.centre,
            (0, j) => self.ids[&(self.wrap.map_or(s + 1, |k| (s + 1) % k), j, 0)],
            _ => self.ids[&(s, i, j)],
        }
    }
}

impl Fan {
    fn inside(&self, i: usize, j: usize) -> bool {
        if self.triangles { i + j <= self.rings } else { i.max(j) <= self.rings }
    }

    /// Pushes the sheet's points and faces, offset by `offset`, with reversed faces if
    /// `mirrored`.
    fn sheet(&self, soup: &mut PolygonSoup, offset: DVec3, mirrored: bool) -> Sheet {
        let step = if self.closed {
            std::f64::consts::TAU / self.sectors as f64
        } else {
            (std::f64::consts::PI / self.sectors as f64).min(std::f64::consts::FRAC_PI_2)
        };
        let direction = |s: usize| DVec3::new((step * s as f64).cos(), (step * s as f64).sin(), 0.0);
        let centre = soup.push_vertex(offset);
        let mut ids = HashMap::new();
        let spokes = if self.closed { self.sectors } else { self.sectors + 1 };
        for s in 0..spokes {
            // An open fan's last spoke has no sector after it.
            let widths = if s < self.sectors { 0..=self.rings } else { 0..=0 };
            for i in 1..=self.rings {
                for j in widths.clone() {
                    if self.inside(i, j) {
                        let p = direction(s) * i as f64 + direction(s + 1) * j as f64 + offset;
                        ids.insert((s, i, j), soup.push_vertex(p));
                    }
                }
            }
        }
        let sheet = Sheet { wrap: self.closed.then_some(self.sectors), centre, ids };
        let mut face = |s: usize, cell: &[(usize, usize)]| {
            let mut vs: Vec<VertexId> = cell.iter().map(|&(i, j)| sheet.id(s, i, j)).collect();
            if mirrored {
                vs.reverse();
            }
            soup.push_face(vs);
        };
        for s in 0..self.sectors {
            for i in 0..self.rings {
                for j in 0..self.rings {
                    if !self.triangles {
                        face(s, &[(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]);
                        continue;
                    }
                    if i + j < self.rings {
                        face(s, &[(i, j), (i + 1, j), (i, j + 1)]);
                    }
                    if i + j + 1 < self.rings {
                        face(s, &[(i + 1, j), (i + 1, j + 1), (i, j + 1)]);
                    }
                }
            }
        }
        sheet
    }
}
