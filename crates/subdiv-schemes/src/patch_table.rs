//! Committed sub-patch matrices: what every Catmull-Clark and Loop mesh needs, derived once by
//! `cargo xtask tables` and read by [`PatchMatrices::of`] instead of deriving them again in
//! every process.
//!
//! A table file holds [`PatchMatrices`] per (patch type, boundary rule) of one scheme. It is
//! identified by a format version and the scheme's identity ([`Scheme::identity`], a hash of
//! its TOML text): a user's scheme of the same name with other rules never reads it, and a
//! change to a built-in's rules makes its tables stale, which `cargo xtask tables --check`
//! (run by CI) reports. A file that cannot be read is never an error for a user: the matrices
//! are then derived, as for any type outside the tables.

use std::ops::RangeInclusive;
use std::sync::OnceLock;

use subdiv_mesh::BoundaryInterpolation;

use crate::binary::{ByteReader, ByteWriter, Corrupt, TableFile, TableIndex};
use crate::patch::{ChildDomain, PatchMatrices, PatchShape, PatchType, SharpFeatures, SubPatch};
use crate::{Builtin, Scheme, SchemeError};

/// The first bytes of a patch table file.
pub const PATCH_TABLE_MAGIC: [u8; 8] = *b"SUBDIVPM";

/// The patch table format version this build reads and writes.
pub const PATCH_TABLE_VERSION: u32 = 1;

/// Which patch types a committed table holds: smooth interior vertices of the valences in
/// `interior`, and smooth boundary fans of `boundary_faces` faces (every face of the fan)
/// under each rule of `boundaries`.
#[derive(Clone, Debug)]
pub struct PatchTableSpec {
    /// The scheme.
    pub scheme: Builtin,
    /// The file name in `crates/subdiv-schemes/tables`.
    pub file: &'static str,
    /// Interior valences.
    pub interior: RangeInclusive<usize>,
    /// Faces of boundary fans.
    pub boundary_faces: RangeInclusive<usize>,
    /// The boundary rules of the boundary types.
    pub boundaries: &'static [BoundaryInterpolation],
}

/// The boundary rules refinement uses: OpenSubdiv's default and its corner variant (`None`
/// makes no surface over boundary faces).
const BOUNDARY_RULES: &[BoundaryInterpolation] =
    &[BoundaryInterpolation::EdgeOnly, BoundaryInterpolation::EdgeAndCorner];

/// The committed tables: Catmull-Clark and Loop, interior valences 3 to 16, boundary fans of
/// 1 to 8 faces (the shared corpus's vertices are within these but for its poles).
pub const DEFAULT_PATCH_TABLES: [PatchTableSpec; 2] = [
    PatchTableSpec {
        scheme: Builtin::CatmullClark,
        file: "catmull-clark.patches",
        interior: 3..=16,
        boundary_faces: 1..=8,
        boundaries: BOUNDARY_RULES,
    },
    PatchTableSpec {
        scheme: Builtin::Loop,
        file: "loop.patches",
        interior: 3..=16,
        boundary_faces: 1..=8,
        boundaries: BOUNDARY_RULES,
    },
];

/// The committed tables, as statics: a constant would be copied into every codegen unit that
/// inlines its use (three copies, 4.3 MB more binary, before).
static CATMULL_CLARK: &[u8] = include_bytes!("../tables/catmull-clark.patches");
static LOOP: &[u8] = include_bytes!("../tables/loop.patches");

/// The bytes of the committed tables, by scheme (empty where a scheme has none).
fn committed_bytes(scheme: Builtin) -> &'static [u8] {
    match scheme {
        Builtin::CatmullClark => CATMULL_CLARK,
        Builtin::Loop => LOOP,
        _ => &[],
    }
}

impl PatchTableSpec {
    /// The (patch type, boundary rule) pairs, in file order (interior, then boundary types by
    /// faces, index and rule).
    pub fn keys(&self) -> Vec<(PatchType, BoundaryInterpolation)> {
        let interior = self.interior.clone().map(|v| (PatchType::interior(v), BoundaryInterpolation::EdgeOnly));
        let boundary = self.boundaries.iter().flat_map(|&rule| {
            self.boundary_faces.clone().flat_map(move |f| (0..f).map(move |i| (PatchType::boundary(f, i), rule)))
        });
        let mut keys: Vec<_> = interior.chain(boundary).collect();
        keys.sort_by_cached_key(|&(t, rule)| key(t, rule));
        keys
    }

    /// Derives the tables (with [`PatchMatrices::compute`], never from a committed file).
    ///
    /// # Errors
    /// As [`PatchMatrices::compute`].
    pub fn compute(&self) -> Result<PatchTables, SchemeError> {
        let scheme = self.scheme.scheme();
        let entries = self
            .keys()
            .into_iter()
            .map(|(t, rule)| PatchMatrices::compute(scheme, t, rule).map(|m| (rule, m)))
            .collect::<Result<_, _>>()?;
        Ok(PatchTables::new(scheme, entries))
    }

    /// The committed bytes of this table (what the build embeds).
    pub fn committed(&self) -> &'static [u8] {
        committed_bytes(self.scheme)
    }
}

/// Sub-patch matrices of one scheme by (patch type, boundary rule), and their file format.
///
/// The file is a [`TableFile`] (magic `SUBDIVPM`): its keys are the patch type (u8 kind, u32
/// valence or faces, u32 index, u64 sharp spokes, u8 corner) and the boundary rule (u8), in
/// that order (so interior types come first, then boundary types by faces, index and rule);
/// each payload (little-endian; lists are a u32 length and their items) holds the distinct
/// nonzero matrix entries (an f64 list), radius, face size and shape count (u32 each), then per
/// shape its size (u32), signature (u32 list), children (per child: shape (u32), domain
/// offsets and flip (3 × u8), rows and columns (u32), the nonzero entries (a u32 count, then
/// per entry its row-major place less the last one's and its value's place in the payload's
/// values, LEB128 varints each)),
/// influence (u32 list), parameters (u8 flag, then two f64 lists) and mirror (u8 flag, then
/// a u32 list). An entry is decoded only when asked for.
///
/// ```
/// use subdiv_mesh::BoundaryInterpolation;
/// use subdiv_schemes::{Builtin, PatchMatrices, PatchTables, PatchType};
///
/// let cc = Builtin::CatmullClark.scheme();
/// let five = PatchMatrices::compute(cc, PatchType::interior(5), BoundaryInterpolation::EdgeOnly)?;
/// let tables = PatchTables::new(cc, vec![(BoundaryInterpolation::EdgeOnly, five.clone())]);
/// let read = PatchTables::from_bytes(&tables.to_bytes(), cc)?;
/// assert_eq!(read.entries()[0].1, five);
/// # Ok::<(), subdiv_schemes::SchemeError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PatchTables {
    scheme: String,
    identity: u64,
    entries: Vec<(BoundaryInterpolation, PatchMatrices)>,
}

impl PatchTables {
    /// Tables of `scheme` holding `entries` (kept in the order of their keys: interior, then
    /// boundary types by faces, index and rule).
    pub fn new(scheme: &Scheme, mut entries: Vec<(BoundaryInterpolation, PatchMatrices)>) -> Self {
        entries.sort_by_cached_key(|(rule, m)| key(m.patch_type, *rule));
        Self { scheme: scheme.name().to_string(), identity: scheme.identity(), entries }
    }

    /// The entries: boundary rule and matrices (whose patch type is theirs).
    pub fn entries(&self) -> &[(BoundaryInterpolation, PatchMatrices)] {
        &self.entries
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let entries: Vec<(Vec<u8>, Vec<u8>)> =
            self.entries.iter().map(|(rule, m)| (key(m.patch_type, *rule), payload(m))).collect();
        FILE.write(&self.scheme, self.identity, &entries)
    }

    /// Reads a file written for `scheme`, every entry.
    ///
    /// # Errors
    /// [`SchemeError::Table`] for a file of another kind, version or scheme (name or
    /// identity), and for corrupt bytes, with the offset.
    pub fn from_bytes(bytes: &[u8], scheme: &Scheme) -> Result<Self, SchemeError> {
        let index = FILE.index(bytes, scheme.name()).map_err(table_error)?;
        let entries = (0..index.len())
            .map(|at| {
                let (t, rule) = read_key(index.key(at))?;
                decode(index.payload(at)?, t, scheme).map(|m| (rule, m))
            })
            .collect::<Result<_, _>>()
            .map_err(table_error)?;
        Ok(Self { scheme: scheme.name().to_string(), identity: index.identity(), entries })
    }
}

/// The layout of a patch table file.
const FILE: TableFile =
    TableFile { what: "a patch table", magic: PATCH_TABLE_MAGIC, version: PATCH_TABLE_VERSION, key_len: KEY_LEN };

/// A key's bytes: kind, valence or faces, index, sharp spokes, corner, boundary rule.
const KEY_LEN: usize = 1 + 4 + 4 + 8 + 1 + 1;

fn table_error(e: Corrupt) -> SchemeError {
    SchemeError::Table(e.to_string())
}

/// The committed matrices of `(patch_type, boundary)` under `scheme`, if the tables hold them
/// and were written for this scheme's rules.
pub(crate) fn committed(
    scheme: &Scheme,
    patch_type: PatchType,
    boundary: BoundaryInterpolation,
) -> Option<PatchMatrices> {
    let builtin = Builtin::from_name(scheme.name())?;
    // Each built-in's index read at its first use (a Catmull-Clark mesh never reads Loop's).
    static INDEXES: [OnceLock<Option<TableIndex<'static>>>; Builtin::ALL.len()] =
        [const { OnceLock::new() }; Builtin::ALL.len()];
    let at = Builtin::ALL.iter().position(|&b| b == builtin)?;
    let index = INDEXES[at].get_or_init(|| FILE.index(committed_bytes(builtin), builtin.name()).ok()).as_ref()?;
    let at = index.find(&key(patch_type, boundary))?;
    // A user's scheme of a built-in's name with other rules: not these tables.
    if scheme.identity() != index.identity() {
        return None;
    }
    decode(index.payload(at).ok()?, patch_type, scheme).ok()
}

/// The key of `(t, rule)`: big-endian, so that keys sort as the types do (interior first, then
/// boundary types by faces and index), then by rule.
fn key(t: PatchType, rule: BoundaryInterpolation) -> Vec<u8> {
    let (kind, a, b, sharp) = match t {
        PatchType::Interior { valence, sharp } => (0u8, valence, 0, sharp),
        PatchType::Boundary { faces, index, sharp } => (1u8, faces, index, sharp),
        // Never in a file: a key no entry has.
        PatchType::Derived { id } => (2u8, id as usize, 0, SharpFeatures::SMOOTH),
    };
    let mut k = Vec::with_capacity(KEY_LEN);
    k.push(kind);
    k.extend_from_slice(&(a as u32).to_be_bytes());
    k.extend_from_slice(&(b as u32).to_be_bytes());
    k.extend_from_slice(&sharp.edges.to_be_bytes());
    k.extend([u8::from(sharp.corner), rule.code()]);
    k
}

fn read_key(k: &[u8]) -> Result<(PatchType, BoundaryInterpolation), Corrupt> {
    let bad = |detail: String| Corrupt { offset: 0, detail };
    let u32_at = |i: usize| u32::from_be_bytes(k[i..i + 4].try_into().expect("4 bytes")) as usize;
    let (a, b) = (u32_at(1), u32_at(5));
    let sharp = SharpFeatures { edges: u64::from_be_bytes(k[9..17].try_into().expect("8 bytes")), corner: k[17] != 0 };
    let t = match k[0] {
        0 => PatchType::Interior { valence: a, sharp },
        1 => PatchType::Boundary { faces: a, index: b, sharp },
        kind => return Err(bad(format!("patch type kind {kind}"))),
    };
    let rule = BoundaryInterpolation::from_code(k[18].into()).ok_or_else(|| bad(format!("boundary rule {}", k[18])))?;
    Ok((t, rule))
}

/// An entry's payload: the matrices but their patch type (the key's) and scheme.
fn payload(m: &PatchMatrices) -> Vec<u8> {
    let mut w = ByteWriter::default();
    // The distinct nonzero weights, first: a scheme's rules make few (1/64, 3/32, …).
    let mut values: Vec<u64> = m
        .shapes
        .iter()
        .flat_map(|s| s.children.iter().flat_map(|c| (0..c.rows()).flat_map(|r| c.row(r).map(|(_, x)| x.to_bits()))))
        .filter(|&bits| bits != 0)
        .collect();
    values.sort_unstable();
    values.dedup();
    w.len(values.len());
    values.iter().for_each(|&bits| w.u64(bits));
    w.len(m.radius);
    w.len(m.face_size);
    w.len(m.shapes.len());
    for shape in &m.shapes {
        w.len(shape.size);
        w.u32s(&shape.signature);
        w.len(shape.children.len());
        for c in &shape.children {
            w.len(c.shape);
            w.raw(&[c.domain.offset[0], c.domain.offset[1], u8::from(c.domain.flipped)]);
            w.len(c.rows());
            w.len(c.columns());
            // Sparse: most of a row's weights are 0 (a point's rule reaches a few neighbours),
            // each nonzero as its distance from the last one and its value's place.
            let nonzero: Vec<(usize, u64)> = (0..c.rows())
                .flat_map(|r| c.row(r).map(move |(column, x)| (r * c.columns() + column, x.to_bits())))
                .filter(|&(_, x)| x != 0)
                .collect();
            w.len(nonzero.len());
            let mut last = 0;
            for (at, bits) in nonzero {
                w.varint((at - last) as u64);
                last = at;
                w.varint(values.binary_search(&bits).expect("a listed value") as u64);
            }
        }
        w.u32s(&shape.influence);
        match &shape.parameters {
            Some([u, v]) => {
                w.u8(1);
                w.f64s(u);
                w.f64s(v);
            }
            None => w.u8(0),
        }
        match &shape.mirror {
            Some(mirror) => {
                w.u8(1);
                w.u32s(mirror);
            }
            None => w.u8(0),
        }
    }
    w.finish()
}

/// The matrices of a payload (see [`payload`]), checked for consistency: every child names a
/// shape, its matrix has the child's rows and the parent's columns.
fn decode(bytes: &[u8], patch_type: PatchType, scheme: &Scheme) -> Result<PatchMatrices, Corrupt> {
    let mut r = ByteReader::new(bytes);
    let values: Vec<f64> = (0..r.len(8)?).map(|_| r.f64()).collect::<Result<_, _>>()?;
    let (radius, face_size, count) = (r.u32()? as usize, r.u32()? as usize, r.len(8)?);
    let mut shapes = Vec::with_capacity(count);
    for _ in 0..count {
        let size = r.u32()? as usize;
        let signature = r.u32s()?;
        let children = (0..r.len(16)?)
            .map(|_| {
                let shape = r.u32()? as usize;
                let d = r.take(3)?;
                let domain = ChildDomain::binary([d[0], d[1]], d[2] != 0);
                let (rows, columns) = (r.u32()? as usize, r.u32()? as usize);
                if columns != size || rows > bytes.len() {
                    return Err(r.corrupt("a child matrix whose size is not its shapes'"));
                }
                let mut entries = vec![0.0; rows * columns];
                let mut at = 0;
                for _ in 0..r.len(2)? {
                    at += r.varint_below(entries.len() - at)?;
                    entries[at] = values[r.varint_below(values.len())?];
                }
                Ok(SubPatch::from_entries(shape, domain, rows, entries))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let influence = r.u32s()?;
        let parameters = match r.u8()? {
            0 => None,
            _ => Some([r.f64s()?, r.f64s()?]),
        };
        let mirror = match r.u8()? {
            0 => None,
            _ => Some(r.u32s()?),
        };
        shapes.push(PatchShape { size, signature, children, influence, parameters, mirror });
    }
    if !r.is_at_end() {
        return Err(r.corrupt("bytes after the last shape"));
    }
    let sizes: Vec<usize> = shapes.iter().map(|s| s.size).collect();
    let consistent = shapes.iter().all(|s| {
        s.children.iter().all(|c| sizes.get(c.shape) == Some(&c.rows()))
            && s.influence.iter().all(|&i| (i as usize) < s.size)
            && s.mirror.as_ref().is_none_or(|m| m.len() == s.size && m.iter().all(|&i| (i as usize) < s.size))
            && s.parameters.as_ref().is_none_or(|[u, v]| u.len() == s.size && v.len() == s.size)
    });
    if shapes.is_empty() || !consistent {
        return Err(Corrupt { offset: 0, detail: "shapes that do not fit together".into() });
    }
    Ok(PatchMatrices::from_shapes(scheme, patch_type, radius, face_size, shapes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every committed entry is what a fresh derivation gives: the matrices bit for bit (the
    /// engine's arithmetic is exact sums of the rules' weights), the parameters (a least-squares
    /// fit whose last bits follow the machine's floating point) to 1e-13. `cargo xtask tables
    /// --check` makes the same comparison in CI; this keeps a stale file from passing the
    /// tests first.
    #[test]
    fn committed_tables_are_a_fresh_derivation() {
        for spec in &DEFAULT_PATCH_TABLES {
            let scheme = spec.scheme.scheme();
            let read = PatchTables::from_bytes(spec.committed(), scheme).unwrap();
            assert_eq!(read.entries().len(), spec.keys().len(), "{}", spec.file);
            for ((rule, m), (t, key_rule)) in read.entries().iter().zip(spec.keys()) {
                assert_eq!((m.patch_type, *rule), (t, key_rule));
                let fresh = PatchMatrices::compute(scheme, t, key_rule).unwrap();
                assert_eq!(m.shapes.len(), fresh.shapes.len(), "{t:?}");
                for (a, b) in m.shapes.iter().zip(&fresh.shapes) {
                    assert_eq!(
                        (a.size, &a.signature, &a.children, &a.influence, &a.mirror),
                        (b.size, &b.signature, &b.children, &b.influence, &b.mirror)
                    );
                    match (&a.parameters, &b.parameters) {
                        (Some([u, v]), Some([p, q])) => {
                            let worst = u.iter().chain(v).zip(p.iter().chain(q)).map(|(x, y)| (x - y).abs());
                            assert!(worst.fold(0.0, f64::max) <= 1e-13, "{t:?}");
                        }
                        (None, None) => {}
                        _ => panic!("{t:?}: parameters on one side only"),
                    }
                }
                assert_eq!(
                    (m.radius, m.face_size, m.scheme_identity()),
                    (fresh.radius, fresh.face_size, fresh.scheme_identity())
                );
            }
        }
    }

    /// `PatchMatrices::of` reads a committed type (the same matrices a derivation gives) and
    /// derives one outside the tables; a scheme with a built-in's name and other rules never
    /// reads the built-in's tables.
    #[test]
    fn of_reads_tables_only_for_their_scheme() {
        let cc = Builtin::CatmullClark.scheme();
        let edge = BoundaryInterpolation::EdgeOnly;
        assert!(committed(cc, PatchType::interior(5), edge).is_some());
        assert!(committed(cc, PatchType::interior(17), edge).is_none());
        assert!(committed(cc, PatchType::boundary(3, 1), BoundaryInterpolation::EdgeAndCorner).is_some());
        let five = PatchMatrices::of(cc, PatchType::interior(5), edge).unwrap();
        assert_eq!(five.shapes, PatchMatrices::compute(cc, PatchType::interior(5), edge).unwrap().shapes);
        // Catmull-Clark's rules with another edge weight, under the same name.
        let text = cc.to_toml_string();
        assert!(text.contains("0.47"));
        let changed = Scheme::from_toml_str(&text.replacen("0.47", "0.48", 1)).unwrap();
        assert_eq!(changed.name(), cc.name());
        assert_ne!(changed.identity(), cc.identity());
        assert!(committed(&changed, PatchType::interior(5), edge).is_none());
    }

    /// Foreign, truncated, altered and mislabelled files are errors that say so, never panics.
    #[test]
    fn bad_files_are_refused() {
        let cc = Builtin::CatmullClark.scheme();
        let m = PatchMatrices::compute(cc, PatchType::interior(3), BoundaryInterpolation::EdgeOnly).unwrap();
        let bytes = PatchTables::new(cc, vec![(BoundaryInterpolation::EdgeOnly, m)]).to_bytes();
        assert!(PatchTables::from_bytes(&bytes, cc).is_ok());
        let message = |bytes: &[u8], scheme: &Scheme| PatchTables::from_bytes(bytes, scheme).unwrap_err().to_string();
        assert!(message(b"SUBDIVST", cc).contains("not a patch table"));
        assert!(message(&bytes, Builtin::Loop.scheme()).contains("not of `loop`"));
        for cut in [9, 20, bytes.len() / 2, bytes.len() - 1] {
            assert!(message(&bytes[..cut], cc).contains("corrupt"), "cut at {cut}");
        }
        let mut flipped = bytes.clone();
        let last = flipped.len() - 3;
        flipped[last] ^= 0x10;
        assert!(message(&flipped, cc).contains("checksum"));
        let mut version = bytes;
        version[8] = 9;
        assert!(message(&version, cc).contains("format version 9"));
    }
}
