//! Committed eigenbases: the power bases, eigen decompositions and tangent stencils of the
//! smooth interior patch types of
//! [`DEFAULT_PATCH_TABLES`](subdiv_schemes::DEFAULT_PATCH_TABLES), derived once by `cargo xtask
//! tables` and read by [`EigenBasis::of`] instead of fitting and decomposing again in every
//! process (the fits check their polynomials against exact rational stencils: most of a first
//! `subdiv eval`).
//!
//! Like the patch tables, a file is identified by a format version and the scheme's identity
//! ([`Scheme::identity`](subdiv_schemes::Scheme::identity), which the matrices carry); one that
//! cannot be read is never an error for a user (the basis is then derived).

use std::sync::{Arc, OnceLock};

use subdiv_mesh::BoundaryInterpolation;
use subdiv_schemes::binary::{ByteReader, ByteWriter, Corrupt, TableFile, TableIndex};
use subdiv_schemes::{Builtin, ChildDomain, PatchMatrices, PatchTableSpec, PatchType};

use crate::EvalError;
use crate::basis::{Child, Complex, EigenBasis, EigenBasisSpectrum, Extraordinary, Kind};
use crate::poly::{PolyKind, PowerBasis};

/// The first bytes of an eigenbasis table file.
pub const EIGEN_TABLE_MAGIC: [u8; 8] = *b"SUBDIVEB";

/// The eigenbasis table format version this build reads and writes.
pub const EIGEN_TABLE_VERSION: u32 = 1;

/// The file of `spec`'s eigenbases in `crates/subdiv-eval/tables` (its patch table's name,
/// `.eigen` for `.patches`).
pub fn eigen_table_file(spec: &PatchTableSpec) -> String {
    format!("{}.eigen", spec.file.trim_end_matches(".patches"))
}

/// The committed tables, as statics (one copy in the binary; see the patch tables').
static CATMULL_CLARK: &[u8] = include_bytes!("../tables/catmull-clark.eigen");
static LOOP: &[u8] = include_bytes!("../tables/loop.eigen");

fn committed_bytes(scheme: Builtin) -> &'static [u8] {
    match scheme {
        Builtin::CatmullClark => CATMULL_CLARK,
        Builtin::Loop => LOOP,
        _ => &[],
    }
}

/// The eigenbases of one scheme's smooth interior patch types, by (valence, shape), and their
/// file format.
///
/// The file is a [`TableFile`] (magic `SUBDIVEB`) keyed by valence and shape (big-endian u32
/// each); each payload (little-endian; lists are a u32 length and their items; complex numbers
/// two f64, real first) holds the power basis (u8 kind: 0 bicubic, 1 quartic; its size, u32; its weights, an f64 list —
/// an extraordinary shape's is its regular children's), then u8 0 for a
/// polynomial shape, or 1 and the extraordinary part — per non-keeping child its domain (3 ×
/// u8), power-basis matrix (f64 list) and modes (complex list); the child lookup (4 × u8);
/// the kept eigenvalues and left eigenvectors (complex lists); the limit and the two tangent
/// stencils (f64 lists); the spectrum: every eigenvalue (complex list), the kept count (u32),
/// and the subdominant modulus, right residual, biorthogonality, reconstruction and
/// eigenvector condition (f64 each). The keeping child's matrix is not stored: it is the
/// matrices' own.
///
/// ```
/// use subdiv_eval::EigenTables;
/// use subdiv_schemes::DEFAULT_PATCH_TABLES;
///
/// let committed = EigenTables::committed(&DEFAULT_PATCH_TABLES[0])?;
/// // Valences 3 to 16: the extraordinary shape and the regular one of each.
/// assert!(committed.len() >= 2 * 14);
/// assert_eq!(EigenTables::from_bytes(&committed.to_bytes(), &DEFAULT_PATCH_TABLES[0])?.len(), committed.len());
/// # Ok::<(), subdiv_eval::EvalError>(())
/// ```
#[derive(Clone, Debug)]
pub struct EigenTables {
    scheme: String,
    identity: u64,
    entries: Vec<(usize, usize, Arc<EigenBasis>)>,
}

impl EigenTables {
    /// Derives the eigenbases of every shape of `spec`'s interior types that has one, from
    /// freshly derived matrices (never from a committed file).
    ///
    /// # Errors
    /// As [`PatchMatrices::compute`].
    pub fn compute(spec: &PatchTableSpec) -> Result<Self, EvalError> {
        let scheme = spec.scheme.scheme();
        let mut entries = Vec::new();
        for valence in spec.interior.clone() {
            let t = PatchType::interior(valence);
            let matrices = Arc::new(PatchMatrices::compute(scheme, t, BoundaryInterpolation::EdgeOnly)?);
            for shape in 0..matrices.shapes.len() {
                if let Ok(basis) = EigenBasis::compute(matrices.clone(), shape) {
                    entries.push((valence, shape, Arc::new(basis)));
                }
            }
        }
        Ok(Self { scheme: scheme.name().to_string(), identity: scheme.identity(), entries })
    }

    /// The committed tables of `spec`, every entry read.
    ///
    /// # Errors
    /// As [`from_bytes`](Self::from_bytes).
    pub fn committed(spec: &PatchTableSpec) -> Result<Self, EvalError> {
        Self::from_bytes(committed_bytes(spec.scheme), spec)
    }

    /// The number of eigenbases.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The entries: valence, shape and eigenbasis.
    pub fn entries(&self) -> &[(usize, usize, Arc<EigenBasis>)] {
        &self.entries
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let entries: Vec<(Vec<u8>, Vec<u8>)> =
            self.entries.iter().map(|(valence, shape, basis)| (key(*valence, *shape), payload(basis))).collect();
        FILE.write(&self.scheme, self.identity, &entries)
    }

    /// Reads a file written for `spec`'s scheme, every entry (over matrices read from the
    /// patch tables, or derived).
    ///
    /// # Errors
    /// [`EvalError::Table`] for a file of another kind, version or scheme, and for corrupt
    /// bytes; as [`PatchMatrices::of`].
    pub fn from_bytes(bytes: &[u8], spec: &PatchTableSpec) -> Result<Self, EvalError> {
        let scheme = spec.scheme.scheme();
        let index = FILE.index(bytes, scheme.name()).map_err(table_error)?;
        let mut entries = Vec::with_capacity(index.len());
        for at in 0..index.len() {
            let (valence, shape) = read_key(index.key(at));
            let payload = index.payload(at).map_err(table_error)?;
            let matrices = PatchMatrices::of(scheme, PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)?;
            entries.push((valence, shape, Arc::new(decode(payload, matrices, shape).map_err(table_error)?)));
        }
        Ok(Self { scheme: scheme.name().to_string(), identity: index.identity(), entries })
    }

    /// The largest difference between the numbers of two tables with the same entries and
    /// structure, or why they are not comparable.
    ///
    /// # Errors
    /// A description of the first difference in entries or structure.
    pub fn max_difference(&self, other: &Self) -> Result<f64, String> {
        if (self.entries.len(), self.identity) != (other.entries.len(), other.identity) {
            return Err(format!(
                "{} entries against {}, or another scheme identity",
                self.entries.len(),
                other.entries.len()
            ));
        }
        let mut worst = 0.0_f64;
        for ((v, s, a), (w, t, b)) in self.entries.iter().zip(&other.entries) {
            let (x, y) = (numbers(a), numbers(b));
            if (v, s, x.len(), structure(a)) != (w, t, y.len(), structure(b)) {
                return Err(format!("valence {w} shape {t}: the structure differs"));
            }
            worst = x.iter().zip(&y).map(|(p, q)| (p - q).abs()).fold(worst, f64::max);
        }
        Ok(worst)
    }
}

fn table_error(e: Corrupt) -> EvalError {
    EvalError::Table(e.to_string())
}

/// The committed eigenbasis of `shape` of `matrices`, if the tables hold it for their scheme.
pub(crate) fn committed(matrices: &Arc<PatchMatrices>, shape: usize) -> Option<EigenBasis> {
    let PatchType::Interior { valence, sharp } = matrices.patch_type else { return None };
    if !sharp.is_smooth() {
        return None;
    }
    let builtin = Builtin::from_name(&matrices.scheme)?;
    static INDEXES: [OnceLock<Option<TableIndex<'static>>>; Builtin::ALL.len()] =
        [const { OnceLock::new() }; Builtin::ALL.len()];
    let at = Builtin::ALL.iter().position(|&b| b == builtin)?;
    let index = INDEXES[at].get_or_init(|| FILE.index(committed_bytes(builtin), builtin.name()).ok()).as_ref()?;
    if matrices.scheme_identity() != index.identity() {
        return None;
    }
    let at = index.find(&key(valence, shape))?;
    decode(index.payload(at).ok()?, matrices.clone(), shape).ok()
}

/// The layout of an eigenbasis table file.
const FILE: TableFile =
    TableFile { what: "an eigenbasis table", magic: EIGEN_TABLE_MAGIC, version: EIGEN_TABLE_VERSION, key_len: 8 };

/// The key of a basis: valence and shape, big-endian.
fn key(valence: usize, shape: usize) -> Vec<u8> {
    [valence as u32, shape as u32].iter().flat_map(|x| x.to_be_bytes()).collect()
}

fn read_key(k: &[u8]) -> (usize, usize) {
    let at = |i: usize| u32::from_be_bytes(k[i..i + 4].try_into().expect("4 bytes")) as usize;
    (at(0), at(4))
}

fn complexes(w: &mut ByteWriter, xs: &[Complex]) {
    w.len(xs.len());
    for x in xs {
        w.f64(x.re);
        w.f64(x.im);
    }
}

fn read_complexes(r: &mut ByteReader<'_>) -> Result<Vec<Complex>, Corrupt> {
    let n = r.len(16)?;
    (0..n).map(|_| Ok(Complex { re: r.f64()?, im: r.f64()? })).collect()
}

fn payload(basis: &EigenBasis) -> Vec<u8> {
    let mut w = ByteWriter::default();
    w.u8(match basis.power.kind {
        PolyKind::Bicubic => 0,
        PolyKind::Quartic => 1,
    });
    w.len(basis.power.size);
    w.f64s(&basis.power.weights);
    match &basis.kind {
        Kind::Regular => w.u8(0),
        Kind::Extraordinary(x) => {
            w.u8(1);
            w.len(x.children.len());
            for c in &x.children {
                w.raw(&[c.domain.offset[0], c.domain.offset[1], u8::from(c.domain.flipped)]);
                w.f64s(&c.to_power);
                complexes(&mut w, &c.modes);
            }
            w.raw(&x.lookup);
            complexes(&mut w, &x.eigenvalues);
            complexes(&mut w, &x.left);
            w.f64s(&x.limit);
            w.f64s(&x.tangents[0]);
            w.f64s(&x.tangents[1]);
            let s = &x.spectrum;
            complexes(&mut w, &s.eigenvalues.iter().map(|&(re, im)| Complex { re, im }).collect::<Vec<_>>());
            w.len(s.kept);
            for v in [s.subdominant, s.right_residual, s.biorthogonality, s.reconstruction, s.eigenvector_condition] {
                w.f64(v);
            }
        }
    }
    w.finish()
}

/// The eigenbasis of a payload over `matrices` (the sizes checked against the shape's).
fn decode(bytes: &[u8], matrices: Arc<PatchMatrices>, shape: usize) -> Result<EigenBasis, Corrupt> {
    let mut r = ByteReader::new(bytes);
    let size = matrices.shapes.get(shape).ok_or_else(|| r.corrupt(format!("no shape {shape}")))?.size;
    let kind = match r.u8()? {
        0 => PolyKind::Bicubic,
        1 => PolyKind::Quartic,
        k => return Err(r.corrupt(format!("polynomial kind {k}"))),
    };
    // The shape's own size for a polynomial shape; an extraordinary one keeps its regular
    // children's.
    let power_size = r.u32()? as usize;
    let weights = r.f64s()?;
    let n = kind.monomials();
    let bad = |r: &ByteReader<'_>| r.corrupt("sizes that are not the shape's");
    let kind_of = match r.u8()? {
        0 => Kind::Regular,
        1 => {
            let PatchType::Interior { valence, .. } = matrices.patch_type else {
                return Err(r.corrupt("not interior"));
            };
            let (_, a) = matrices.keeping(shape).ok_or_else(|| r.corrupt("no child keeps the shape"))?;
            if a.rows() != size {
                return Err(bad(&r));
            }
            let a: Vec<f64> = (0..size).flat_map(|row| a.dense_row(row)).collect();
            let children = (0..r.len(3)?)
                .map(|_| {
                    let d = r.take(3)?;
                    let domain = ChildDomain::binary([d[0], d[1]], d[2] != 0);
                    Ok(Child { domain, to_power: r.f64s()?, modes: read_complexes(&mut r)? })
                })
                .collect::<Result<Vec<_>, Corrupt>>()?;
            let lookup: [u8; 4] = r.take(4)?.try_into().expect("4 bytes");
            let eigenvalues = read_complexes(&mut r)?;
            let left = read_complexes(&mut r)?;
            let limit = r.f64s()?;
            let tangents = [r.f64s()?, r.f64s()?];
            let all = read_complexes(&mut r)?.into_iter().map(|c| (c.re, c.im)).collect();
            let kept = r.u32()? as usize;
            let mut f = || r.f64();
            let spectrum = EigenBasisSpectrum {
                eigenvalues: all,
                kept,
                subdominant: f()?,
                right_residual: f()?,
                biorthogonality: f()?,
                reconstruction: f()?,
                eigenvector_condition: f()?,
            };
            let k = eigenvalues.len();
            let fits = children.iter().all(|c| c.to_power.len() == n * size && c.modes.len() == n * k)
                && lookup.iter().all(|&l| usize::from(l) < children.len())
                && left.len() == k * size
                && [&limit, &tangents[0], &tangents[1]].iter().all(|v| v.len() == size);
            if !fits {
                return Err(bad(&r));
            }
            Kind::Extraordinary(Box::new(Extraordinary {
                valence,
                a,
                children,
                lookup,
                eigenvalues,
                left,
                limit,
                tangents,
                spectrum,
            }))
        }
        k => return Err(r.corrupt(format!("basis kind {k}"))),
    };
    let regular = matches!(kind_of, Kind::Regular);
    if Some(weights.len()) != n.checked_mul(power_size) || (regular && power_size != size) || !r.is_at_end() {
        return Err(bad(&r));
    }
    Ok(EigenBasis { matrices, shape, power: PowerBasis { kind, size: power_size, weights }, kind: kind_of })
}

/// Every number of a basis, in the payload's order (for comparisons).
fn numbers(b: &EigenBasis) -> Vec<f64> {
    let mut out = b.power.weights.clone();
    if let Kind::Extraordinary(x) = &b.kind {
        let c = |v: &[Complex]| v.iter().flat_map(|c| [c.re, c.im]).collect::<Vec<_>>();
        for child in &x.children {
            out.extend(&child.to_power);
            out.extend(c(&child.modes));
        }
        out.extend(c(&x.eigenvalues));
        out.extend(c(&x.left));
        out.extend(&x.limit);
        out.extend(x.tangents.iter().flatten());
        out.extend(x.spectrum.eigenvalues.iter().flat_map(|&(re, im)| [re, im]));
    }
    out
}

/// The structure of a basis: its kind, kept count and children's domains.
fn structure(b: &EigenBasis) -> (u8, usize, Vec<ChildDomain>, [u8; 4]) {
    match &b.kind {
        Kind::Regular => (0, 0, Vec::new(), [0; 4]),
        Kind::Extraordinary(x) => (1, x.spectrum.kept, x.children.iter().map(|c| c.domain).collect(), x.lookup),
    }
}

#[cfg(test)]
mod tests {
    use subdiv_schemes::DEFAULT_PATCH_TABLES;

    use super::*;

    /// The committed eigenbases are what a fresh derivation gives (to the eigen solver's
    /// platform rounding; `cargo xtask tables --check` compares the same way in CI).
    #[test]
    fn committed_tables_are_a_fresh_derivation() {
        for spec in &DEFAULT_PATCH_TABLES {
            let committed = EigenTables::committed(spec).unwrap();
            let fresh = EigenTables::compute(spec).unwrap();
            let worst = committed.max_difference(&fresh).unwrap();
            assert!(worst <= 1e-10, "{}: {worst:e}", spec.file);
            // Every interior valence has its extraordinary shape (or, at the regular
            // valence, its polynomial one) in the tables.
            for valence in spec.interior.clone() {
                assert!(committed.entries().iter().any(|(v, s, _)| (*v, *s) == (valence, 0)), "{valence}");
            }
        }
    }

    /// `EigenBasis::of` reads the committed basis: the same numbers as its derivation.
    #[test]
    fn of_reads_the_committed_basis() {
        let cc = Builtin::CatmullClark.scheme();
        let m = PatchMatrices::of(cc, PatchType::interior(7), BoundaryInterpolation::EdgeOnly).unwrap();
        let read = committed(&m, 0).expect("valence 7 is in the tables");
        let derived = EigenBasis::compute(m.clone(), 0).unwrap();
        let worst = numbers(&read).iter().zip(&numbers(&derived)).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-10 && structure(&read) == structure(&derived), "{worst:e}");
        assert_eq!(read.valence(), Some(7));
        // Outside the tables: derived.
        let past = PatchMatrices::of(cc, PatchType::interior(17), BoundaryInterpolation::EdgeOnly).unwrap();
        assert!(committed(&past, 0).is_none());
    }

    /// Foreign, truncated and altered files are errors that say so.
    #[test]
    fn bad_files_are_refused() {
        let spec = &DEFAULT_PATCH_TABLES[0];
        let bytes = EigenTables::committed(spec).unwrap().to_bytes();
        let message =
            |bytes: &[u8], spec: &PatchTableSpec| EigenTables::from_bytes(bytes, spec).unwrap_err().to_string();
        assert!(message(b"SUBDIVPM", spec).contains("not an eigenbasis table"));
        assert!(message(&bytes, &DEFAULT_PATCH_TABLES[1]).contains("not of `loop`"));
        for cut in [9, 30, bytes.len() / 2, bytes.len() - 1] {
            assert!(message(&bytes[..cut], spec).contains("corrupt"), "cut at {cut}");
        }
        let mut flipped = bytes;
        let last = flipped.len() - 5;
        flipped[last] ^= 0x01;
        assert!(message(&flipped, spec).contains("checksum"));
    }
}
