//! Rings of exact points around extraordinary points, in place of their polygons: closed around
//! an interior vertex or an N-gon's centre, open in each run of faces at a border vertex.

use super::*;

/// The number of rings around a point at `depth` (> 0) whose first ring is at depth `first`:
/// from `2^−first` down to `2^−max(depth, first)`, one ring per halving (at least one).
pub(in crate::dual::topology) fn ring_count(first: u32, depth: u32) -> u32 {
    depth.saturating_sub(first) + 1
}

/// One end of an open run of faces around a border vertex: its border point's extra entry on
/// this side (the second side of a cut edge), and, on an edge cut between two faces with a
/// surface, the edge, whose ring points the runs on its two sides share.
#[derive(Clone, Copy, Debug)]
pub(in crate::dual::topology) struct RunEnd {
    pub extra: Option<u32>,
    pub shared: Option<u32>,
}

/// A ring's points in a corner's frame, each at `(a, b) · 2^−(e + shift)` for ring depth `e`: a
/// quad corner's are `(r, 0)` on its first edge, the diagonal point `(r, r)` and `(0, r)` on its
/// last edge; a triangle corner's `(r, 0)`, `(r/2, r/2)` (on the segment between the corner's
/// two edge points: the triangle's region between rings is a trapezoid) and `(0, r)`.
struct RingFrame {
    edge: (i64, i64),
    inner: (i64, i64),
    last_edge: (i64, i64),
    shift: u32,
}

impl Builder<'_> {
    /// The point `(a, b) · 2^−e` (face units, `a, b ≤ 2`, `e ≥ 2`) of `corner`'s frame, as its
    /// face's parameter: a quad's own coordinates turned to the corner; an N-gon's sub-face
    /// coordinates, which are twice the face units (a sub-face is a quarter of the face); a
    /// triangle's turned to the corner (`s` along side `c`, `t` along side `c − 1` reversed).
    pub(in crate::dual::topology) fn ring_point(&self, corner: RingCorner, a: i64, b: i64, e: u32) -> Dyadic {
        let domain = self.buf.faces[corner.face()].expect("a face with a surface").domain();
        match corner {
            RingCorner::Vertex { corner: c, .. } => match domain {
                FaceDomain::SubFaces { .. } => domain.from_sub_face(c as usize, Dyadic::new(a, b, 1 << (e - 1))),
                FaceDomain::Triangle | FaceDomain::Ternary => {
                    let d = 1i64 << e;
                    let (u, v) = match c {
                        0 => (a, b),
                        1 => (d - a - b, a),
                        _ => (b, d - a - b),
                    };
                    Dyadic::new(u, v, d)
                }
                FaceDomain::Quad => {
                    let d = 1i64 << e;
                    let (u, v) = match c {
                        0 => (a, b),
                        1 => (d - b, a),
                        2 => (d - a, d - b),
                        _ => (b, d - a),
                    };
                    Dyadic::new(u, v, d)
                }
            },
            // The inner corner (1, 1) of the sub-face, its frame turned half a turn.
            RingCorner::Centre { sub, .. } => {
                let d = 1i64 << (e - 1);
                domain.from_sub_face(sub as usize, Dyadic::new(d - a, d - b, d))
            }
        }
        .reduced()
    }

    /// Rings around an extraordinary point, in place of its polygon `outer` (the faces' nearest
    /// dual points, counter-clockwise, one per corner of `corners`), down to `depth`, fanned at
    /// the end around the point's limit point `centre` (face, parameter).
    ///
    /// Ring `j` (radius `r_j = 2^−(d1 + j − 1)`, `d1` the first depth inside the nearest dual
    /// points, [`first_ring_depth`]) has a point on every edge (or spoke) at `r_j` from the
    /// point, made once in the face whose `s` axis the edge is, and one per face at
    /// `(r_j, r_j)`; its points run `edge_0, diagonal_0, edge_1, diagonal_1, …`, counter-
    /// clockwise. Every triangle lies in one face's region or across one edge, as the bound of
    /// [`ErrorRates::rates`](crate::rates::ErrorRates::rates) assumes: from the polygon's corners
    /// to ring 1 two triangles per face and one across each edge; between rings `j` and `j + 1`
    /// two quads per face in its L-shaped region `[0, r_j]² \ [0, r_{j+1})²`; a fan inside the
    /// last. Under a triangle split the same with a triangle's frames: the inner point at `(r_j/2, r_j/2)`, and the quads in the
    /// trapezoid `r_{j+1} ≤ s + t ≤ r_j`.
    pub(in crate::dual::topology) fn rings(
        &mut self,
        corners: &[RingCorner],
        outer: &[u32],
        depth: u32,
        finest: u32,
        centre: (usize, Dyadic),
    ) {
        let n = corners.len() as u32;
        let first = first_ring_depth(self.triangle, finest);
        let count = ring_count(first, depth);
        let base = self.next_vertex();
        let RingFrame { edge, inner, shift, .. } = self.ring_frame();
        for j in 0..count {
            for &c in corners {
                let on_edge = self.ring_point(c, edge.0, edge.1, first + j + shift);
                self.push_site(c.face(), on_edge);
                let diagonal = self.ring_point(c, inner.0, inner.1, first + j + shift);
                self.push_site(c.face(), diagonal);
            }
        }
        let p = self.push_site(centre.0, centre.1);
        // Point k (cyclic) of ring j (from 0): edge points at even k, diagonal points at odd.
        let at = |j: u32, k: u32| base + j * 2 * n + k % (2 * n);
        let face = |k: u32| corners[k as usize].face() as u32;
        for k in 0..n {
            let (d, next) = (outer[k as usize], outer[((k + 1) % n) as usize]);
            let (e, q, e_next) = (at(0, 2 * k), at(0, 2 * k + 1), at(0, 2 * k + 2));
            self.triangle([d, q, e], face(k));
            self.triangle([d, e_next, q], face(k));
            self.triangle([d, next, e_next], face(k));
        }
        self.ring_bands(count, n, |j, k| Corner::from(at(j, k)), face);
        for k in 0..2 * n {
            self.triangle([p, at(count - 1, k), at(count - 1, k + 1)], face(k / 2));
        }
    }

    /// A ring's points in a corner's frame ([`RingFrame`]) under this split.
    fn ring_frame(&self) -> RingFrame {
        if self.triangle {
            RingFrame { edge: (2, 0), inner: (1, 1), last_edge: (0, 2), shift: 1 }
        } else {
            RingFrame { edge: (1, 0), inner: (1, 1), last_edge: (0, 1), shift: 0 }
        }
    }

    /// The bands between `count` rings of `n` faces: two quads per face in its L-shaped region
    /// between ring `j` and `j + 1`, `at(j, k)` point `k` of ring `j` (edge points at even `k`,
    /// diagonal points at odd).
    fn ring_bands(&mut self, count: u32, n: u32, at: impl Fn(u32, u32) -> Corner, face: impl Fn(u32) -> u32) {
        for j in 0..count - 1 {
            for k in 0..n {
                let (e, q, e_next) = (2 * k, 2 * k + 1, 2 * k + 2);
                self.quad_at([at(j + 1, e), at(j, e), at(j, q), at(j + 1, q)], face(k));
                self.quad_at([at(j + 1, q), at(j, q), at(j, e_next), at(j + 1, e_next)], face(k));
            }
        }
    }

    /// [`rings`](Self::rings) in an open run of faces around a border vertex: `outer` is the
    /// run's polygon, the border point on its first edge, each face's nearest dual point, the
    /// border point on its last edge; `corners` one per face; `ends` its first and last edges
    /// ([`RunEnd`]). Each ring has a point on every edge of the run at `r_j` (the last edge's
    /// made in the last face, on its `t` axis) and one inner point per face, so the bands are the
    /// closed case's without the wrap, plus a triangle from the first border point. On an edge
    /// cut between two faces (an infinitely sharp edge, a seam) the ring points are made once,
    /// by the first run that reaches the edge; the run across takes them with extra entries of
    /// its own (its normals, its channel values), as the border points there. The limit point
    /// is `centre`'s vertex if an earlier run made it (this run's normal an extra one), else
    /// made here.
    #[allow(clippy::too_many_arguments)]
    pub(in crate::dual::topology) fn open_rings(
        &mut self,
        corners: &[RingCorner],
        outer: &[u32],
        ends: [RunEnd; 2],
        depth: u32,
        finest: u32,
        point: (usize, Dyadic),
        centre: &mut Option<u32>,
    ) {
        let n = corners.len() as u32;
        let first = first_ring_depth(self.triangle, finest);
        let count = ring_count(first, depth);
        let RingFrame { edge, inner, last_edge, shift } = self.ring_frame();
        let last = corners[corners.len() - 1];
        let mut points = std::mem::take(&mut self.buf.ring_points);
        points.clear();
        for j in 0..count {
            let e = first + j + shift;
            for (k, &c) in corners.iter().enumerate() {
                let on_edge = self.ring_point(c, edge.0, edge.1, e);
                let shared = if k == 0 { ends[0].shared } else { None };
                points.push(self.run_point(c.face(), on_edge, shared, j));
                let diagonal = self.ring_point(c, inner.0, inner.1, e);
                points.push(Corner::from(self.push_site(c.face(), diagonal)));
            }
            let on_last = self.ring_point(last, last_edge.0, last_edge.1, e);
            points.push(self.run_point(last.face(), on_last, ends[1].shared, j));
        }
        let p = match *centre {
            Some(c) => Corner { vertex: c, extra: Some(self.push_extra(c, point.0, point.1, None)) },
            None => {
                let c = self.push_site(point.0, point.1);
                *centre = Some(c);
                Corner::from(c)
            }
        };
        // Point k of ring j (from 0): edge points at even k, inner points at odd, 2n + 1.
        let at = |j: u32, k: u32| points[(j * (2 * n + 1) + k) as usize];
        let face = |k: u32| corners[k.min(n - 1) as usize].face() as u32;
        let d = |k: u32| Corner::from(outer[k as usize + 1]);
        let first_border = Corner { vertex: outer[0], extra: ends[0].extra };
        let last_border = Corner { vertex: outer[outer.len() - 1], extra: ends[1].extra };
        self.triangle_at([first_border, d(0), at(0, 0)], face(0));
        for k in 0..n {
            let (e, q, e_next) = (at(0, 2 * k), at(0, 2 * k + 1), at(0, 2 * k + 2));
            let next = if k + 1 == n { last_border } else { d(k + 1) };
            self.triangle_at([d(k), q, e], face(k));
            self.triangle_at([d(k), e_next, q], face(k));
            self.triangle_at([d(k), next, e_next], face(k));
        }
        self.ring_bands(count, n, at, face);
        for k in 0..2 * n {
            self.triangle_at([p, at(count - 1, k), at(count - 1, k + 1)], face(k / 2));
        }
        self.buf.ring_points = points;
    }

    /// A run's ring point `j` at `site` of `face`: made here, or on an edge cut between two
    /// faces (`shared`) the point the run across made, with an extra entry for this side.
    fn run_point(&mut self, face: usize, site: Dyadic, shared: Option<u32>, j: u32) -> Corner {
        let Some(edge) = shared else { return Corner::from(self.push_site(face, site)) };
        match self.buf.cut_ring_points.get(&edge).and_then(|made| made.get(j as usize)).copied() {
            Some(vertex) => Corner { vertex, extra: Some(self.push_extra(vertex, face, site, None)) },
            None => {
                let vertex = self.push_site(face, site);
                self.buf.cut_ring_points.entry(edge).or_default().push(vertex);
                Corner::from(vertex)
            }
        }
    }
}
