//! `subdiv merge`: the parts `subdiv tessellate --faces A..B` writes, joined into one mesh.
//!
//! A part's points on its border are the same bits as the neighbouring part's (both evaluate
//! them at the same parameters by the same code), so joining welds *exactly* equal points: a
//! vertex is its position's bits, and a corner's point (`vn`, with its `vt`) is its vertex with
//! its normal's and texture coordinates' bits — a crease's or seam's two sides stay two points,
//! as in the one-job output. OBJ parts in (the tessellation's own `v`/`vn`/`vt`/`f` lines, whose
//! numbers are shortest round-trip decimals), OBJ or GLB out.

use std::collections::HashMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};

use crate::UserError;
use crate::input::{check_output, write_error};

#[derive(clap::Args, Debug)]
pub(crate) struct MergeArgs {
    /// The parts, OBJ files written by `subdiv tessellate --faces A..B` of one mesh, scheme
    /// and rates (any order; each face range once).
    #[arg(required = true, value_name = "PART.obj")]
    parts: Vec<PathBuf>,
    /// Output file, .obj or .glb (triangles only); written atomically.
    #[arg(short, long)]
    output: PathBuf,
}

/// A corner: its vertex, normal and texture coordinates (bits), the welding key of a point.
type PointKey = (u32, [u64; 3], Option<[u64; 2]>);

/// The joined mesh: welded vertices and points, and the faces over them.
#[derive(Default)]
struct Joined {
    positions: Vec<[f64; 3]>,
    vertex_of: HashMap<[u64; 3], u32>,
    /// Per point: its vertex, normal and texture coordinates.
    points: Vec<(u32, [f64; 3], Option<[f64; 2]>)>,
    point_of: HashMap<PointKey, u32>,
    /// Per face, its corners' points.
    faces: Vec<Vec<u32>>,
    /// Whether the parts carry texture coordinates (all or none).
    texcoords: Option<bool>,
}

impl Joined {
    /// The vertex at `p`: an equal one of the parts before `first` (this part's first new
    /// vertex), or a new one.
    fn vertex(&mut self, p: [f64; 3], first: u32) -> u32 {
        let key = p.map(f64::to_bits);
        match self.vertex_of.get(&key) {
            Some(&v) if v < first => v,
            found => {
                let v = self.positions.len() as u32;
                self.positions.push(p);
                if found.is_none() {
                    self.vertex_of.insert(key, v);
                }
                v
            }
        }
    }

    /// The point of `vertex` with `normal` and `uv`, as [`vertex`](Self::vertex) finds it.
    fn point(&mut self, vertex: u32, normal: [f64; 3], uv: Option<[f64; 2]>, first: u32) -> u32 {
        let key = (vertex, normal.map(f64::to_bits), uv.map(|t| t.map(f64::to_bits)));
        match self.point_of.get(&key) {
            Some(&p) if p < first => p,
            found => {
                let p = self.points.len() as u32;
                self.points.push((vertex, normal, uv));
                if found.is_none() {
                    self.point_of.insert(key, p);
                }
                p
            }
        }
    }

    /// Reads one part and joins it: its vertices and points are its own, welded to equal ones
    /// of the parts before (two equal points of one part, as a crease vertex whose sectors have
    /// one normal, stay two).
    fn add(&mut self, path: &Path) -> Result<(), UserError> {
        let file = std::fs::File::open(path).map_err(|e| UserError(format!("{}: {e}", path.display())))?;
        let (mut v, mut vn, mut vt) = (Vec::new(), Vec::new(), Vec::new());
        let mut faces = Vec::new();
        for (number, line) in std::io::BufReader::new(file).lines().enumerate() {
            let at = |what: String| UserError(format!("{}:{}: {what}", path.display(), number + 1));
            let line = line.map_err(|e| at(e.to_string()))?;
            let mut words = line.split_whitespace();
            let numbers = |words: std::str::SplitWhitespace<'_>, n: usize| -> Result<Vec<f64>, UserError> {
                let values: Vec<f64> =
                    words.map(str::parse).collect::<Result<_, _>>().map_err(|e| at(format!("{e}")))?;
                if values.len() != n || values.iter().any(|x| !x.is_finite()) {
                    return Err(at(format!("expected {n} finite numbers")));
                }
                Ok(values)
            };
            match words.next() {
                Some("v") => v.push(<[f64; 3]>::try_from(numbers(words, 3)?).expect("three")),
                Some("vn") => vn.push(<[f64; 3]>::try_from(numbers(words, 3)?).expect("three")),
                Some("vt") => vt.push(<[f64; 2]>::try_from(numbers(words, 2)?).expect("two")),
                Some("f") => {
                    let mut corners = Vec::new();
                    for word in words {
                        corners.push(corner(word, v.len(), vn.len(), vt.len()).ok_or_else(|| {
                            at(format!(
                                "face corner {word:?} is not v//vn or v/vt/vn with indices of lines above (a part of \
                                 `subdiv tessellate --faces`)"
                            ))
                        })?);
                    }
                    if corners.len() < 3 {
                        return Err(at("a face needs three corners or more".into()));
                    }
                    faces.push(corners);
                }
                _ => {}
            }
        }
        let has_uv = faces.iter().flatten().any(|c: &(usize, usize, Option<usize>)| c.2.is_some());
        if *self.texcoords.get_or_insert(has_uv) != has_uv {
            return Err(UserError(format!(
                "{}: {} texture coordinates and the parts before {}: parts of one tessellation all have them or none",
                path.display(),
                if has_uv { "has" } else { "has no" },
                if has_uv { "do not" } else { "do" },
            )));
        }
        let (first_vertex, first_point) = (self.positions.len() as u32, self.points.len() as u32);
        let mut vertices = vec![u32::MAX; v.len()];
        let mut points: HashMap<(usize, usize, Option<usize>), u32> = HashMap::new();
        for face in faces {
            let corners = face
                .into_iter()
                .map(|(p, n, t)| {
                    if vertices[p] == u32::MAX {
                        vertices[p] = self.vertex(v[p], first_vertex);
                    }
                    let vertex = vertices[p];
                    *points.entry((p, n, t)).or_insert_with(|| self.point(vertex, vn[n], t.map(|t| vt[t]), first_point))
                })
                .collect();
            self.faces.push(corners);
        }
        Ok(())
    }

    fn write_obj(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        writeln!(w, "# subdiv merge")?;
        for p in &self.positions {
            writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
        }
        for (_, n, _) in &self.points {
            writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
        }
        for (_, _, t) in &self.points {
            if let Some(t) = t {
                writeln!(w, "vt {} {}", t[0], t[1])?;
            }
        }
        let uv = self.texcoords == Some(true);
        for face in &self.faces {
            write!(w, "f")?;
            for &p in face {
                let v = self.points[p as usize].0 + 1;
                if uv { write!(w, " {v}/{}/{}", p + 1, p + 1)? } else { write!(w, " {v}//{}", p + 1)? }
            }
            writeln!(w)?;
        }
        Ok(())
    }

    /// The flat buffers of a GLB: one vertex per point.
    fn flat(&self) -> Result<subdiv::FlatMesh, UserError> {
        let mut flat = subdiv::FlatMesh::default();
        for &(v, n, t) in &self.points {
            let p = self.positions[v as usize];
            flat.vertices.extend([p[0], p[1], p[2], n[0], n[1], n[2]].map(|x| x as f32));
            if let Some(t) = t {
                flat.texcoords.extend(t.map(|x| x as f32));
            }
        }
        for face in &self.faces {
            if face.len() != 3 {
                return Err(UserError("a GLB holds triangles; these parts have polygons (write .obj)".into()));
            }
            flat.indices.extend_from_slice(face);
        }
        Ok(flat)
    }
}

/// A face corner `v//vn` or `v/vt/vn` (1-based, or negative: relative to the lines above) as
/// 0-based indices, if they name lines read.
fn corner(word: &str, v: usize, vn: usize, vt: usize) -> Option<(usize, usize, Option<usize>)> {
    let index = |text: &str, count: usize| -> Option<usize> {
        let i: i64 = text.parse().ok()?;
        let i = if i < 0 { count as i64 + i } else { i - 1 };
        (0..count as i64).contains(&i).then_some(i as usize)
    };
    let mut fields = word.split('/');
    let (p, t, n) = (fields.next()?, fields.next()?, fields.next()?);
    if fields.next().is_some() {
        return None;
    }
    let t = if t.is_empty() { None } else { Some(index(t, vt)?) };
    Some((index(p, v)?, index(n, vn)?, t))
}

pub(crate) fn run(args: &MergeArgs) -> Result<(), UserError> {
    let glb = match args.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("glb") => true,
        Some("obj") => false,
        _ => return Err(UserError(format!("{}: the output must end in .glb or .obj", args.output.display()))),
    };
    let inputs: Vec<&Path> = args.parts.iter().map(PathBuf::as_path).collect();
    check_output(&inputs, &args.output)?;
    let start = std::time::Instant::now();
    let mut joined = Joined::default();
    let mut read = 0;
    for part in &args.parts {
        joined.add(part)?;
        read += 1;
    }
    let name = format!("{read} parts");
    let written = if glb {
        subdiv::write_flat_glb(&args.output, &joined.flat()?).map_err(|e| e.to_string())
    } else {
        subdiv::io::write_atomic(&args.output, |w| joined.write_obj(w)).map_err(|e| e.to_string())
    };
    written.map_err(|e| write_error(&name, &args.output, e))?;
    eprintln!(
        "subdiv merge: {name}: {} vertices, {} points, {} faces in {:.3} s -> {}",
        joined.positions.len(),
        joined.points.len(),
        joined.faces.len(),
        start.elapsed().as_secs_f64(),
        args.output.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_name_lines_read() {
        assert_eq!(corner("3//2", 3, 2, 0), Some((2, 1, None)));
        assert_eq!(corner("1/2/3", 3, 3, 2), Some((0, 2, Some(1))));
        assert_eq!(corner("-1//-1", 3, 2, 0), Some((2, 1, None)));
        for bad in ["4//1", "1//0", "1", "1/2", "1/2/3/4", "x//1"] {
            assert_eq!(corner(bad, 3, 3, 3), None, "{bad}");
        }
    }

    #[test]
    fn equal_points_weld_and_sides_of_a_crease_do_not() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.obj");
        let b = dir.path().join("b.obj");
        std::fs::write(&a, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n").unwrap();
        // Shares the edge (1, 0, 0)-(0, 1, 0); the point at (1, 0, 0) has another normal here.
        std::fs::write(&b, "v 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 1 0\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n").unwrap();
        let mut joined = Joined::default();
        joined.add(&a).unwrap();
        joined.add(&b).unwrap();
        assert_eq!(joined.positions.len(), 4);
        assert_eq!(joined.points.len(), 5);
        assert_eq!(joined.faces, [vec![0, 1, 2], vec![3, 4, 2]]);
    }
}
