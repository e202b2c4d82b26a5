//! Little-endian reading and writing for the committed table files (sub-patch matrices here,
//! eigenbases in `subdiv-eval`, stencil tables in `subdiv-stencil`): one reader that names the
//! offset of what it could not read, and the checksum they share.
//!
//! ```
//! use subdiv_schemes::binary::{ByteReader, ByteWriter};
//!
//! let mut w = ByteWriter::default();
//! w.u32(7);
//! w.varint(300);
//! w.f64s(&[0.5, -1.0]);
//! let bytes = w.finish();
//! let mut r = ByteReader::new(&bytes);
//! assert_eq!(r.u32()?, 7);
//! assert_eq!(r.varint()?, 300);
//! assert_eq!(r.f64s()?, [0.5, -1.0]);
//! assert!(r.u8().is_err()); // past the end: an error with the offset, not a panic
//! # Ok::<(), subdiv_schemes::binary::Corrupt>(())
//! ```

/// FNV-1a (64 bits) of `bytes`: the files' checksums and the schemes' identities.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

/// Bytes that cannot be read: where, and what was expected.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("corrupt at byte {offset}: {detail}")]
pub struct Corrupt {
    /// The offset of the first byte not read.
    pub offset: usize,
    /// What was wrong.
    pub detail: String,
}

/// Appends little-endian values; lists carry their length (u32).
#[derive(Clone, Debug, Default)]
pub struct ByteWriter {
    bytes: Vec<u8>,
}

impl ByteWriter {
    /// The bytes written.
    pub fn finish(self) -> Vec<u8> {
        self.bytes
    }

    /// The bytes written so far.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Raw bytes, without a length.
    pub fn raw(&mut self, bytes: &[u8]) {
        self.bytes.extend_from_slice(bytes);
    }

    /// One byte.
    pub fn u8(&mut self, x: u8) {
        self.bytes.push(x);
    }

    /// A `u32`.
    pub fn u32(&mut self, x: u32) {
        self.bytes.extend_from_slice(&x.to_le_bytes());
    }

    /// A `usize`, as a `u32` (sizes in tables are small; a larger one is a bug).
    pub fn len(&mut self, x: usize) {
        self.u32(u32::try_from(x).expect("table sizes fit in u32"));
    }

    /// A `u64`.
    pub fn u64(&mut self, x: u64) {
        self.bytes.extend_from_slice(&x.to_le_bytes());
    }

    /// An unsigned integer in LEB128 (seven bits a byte, small numbers in one byte).
    pub fn varint(&mut self, mut x: u64) {
        while x >= 0x80 {
            self.bytes.push((x as u8 & 0x7f) | 0x80);
            x >>= 7;
        }
        self.bytes.push(x as u8);
    }

    /// An `f64`, its exact bits.
    pub fn f64(&mut self, x: f64) {
        self.u64(x.to_bits());
    }

    /// A string: its length and UTF-8 bytes.
    pub fn str(&mut self, s: &str) {
        self.len(s.len());
        self.raw(s.as_bytes());
    }

    /// A list of `u32`.
    pub fn u32s(&mut self, xs: &[u32]) {
        self.len(xs.len());
        xs.iter().for_each(|&x| self.u32(x));
    }

    /// A list of `f64`.
    pub fn f64s(&mut self, xs: &[f64]) {
        self.len(xs.len());
        xs.iter().for_each(|&x| self.f64(x));
    }
}

/// Reads what [`ByteWriter`] wrote; every read past the end or of a malformed value is a
/// [`Corrupt`] naming the offset.
#[derive(Clone, Debug)]
pub struct ByteReader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> ByteReader<'a> {
    /// A reader at the start of `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    /// The offset of the next byte.
    pub fn offset(&self) -> usize {
        self.at
    }

    /// Whether every byte has been read.
    pub fn is_at_end(&self) -> bool {
        self.at == self.bytes.len()
    }

    /// An error at the current offset.
    pub fn corrupt(&self, detail: impl Into<String>) -> Corrupt {
        Corrupt { offset: self.at, detail: detail.into() }
    }

    /// The next `n` bytes.
    pub fn take(&mut self, n: usize) -> Result<&'a [u8], Corrupt> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or_else(|| {
            self.corrupt(format!("truncated: {n} more bytes expected, {} left", self.bytes.len() - self.at))
        })?;
        let taken = &self.bytes[self.at..end];
        self.at = end;
        Ok(taken)
    }

    /// One byte.
    pub fn u8(&mut self) -> Result<u8, Corrupt> {
        Ok(self.take(1)?[0])
    }

    /// A `u32`.
    pub fn u32(&mut self) -> Result<u32, Corrupt> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }

    /// A length written by [`ByteWriter::len`], refused when more items of `item_bytes` each
    /// than bytes are left (so a corrupt length cannot ask for a huge allocation).
    pub fn len(&mut self, item_bytes: usize) -> Result<usize, Corrupt> {
        let n = self.u32()? as usize;
        if n.saturating_mul(item_bytes.max(1)) > self.bytes.len() - self.at {
            return Err(self.corrupt(format!("a list of {n} items is longer than the rest of the file")));
        }
        Ok(n)
    }

    /// A `u64`.
    pub fn u64(&mut self) -> Result<u64, Corrupt> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }

    /// An integer written by [`ByteWriter::varint`].
    pub fn varint(&mut self) -> Result<u64, Corrupt> {
        let mut x = 0u64;
        for shift in (0..64).step_by(7) {
            let byte = self.u8()?;
            x |= u64::from(byte & 0x7f) << shift;
            if byte & 0x80 == 0 {
                return Ok(x);
            }
        }
        Err(self.corrupt("a varint longer than 64 bits"))
    }

    /// A varint that must fit a `usize` below `bound`.
    pub fn varint_below(&mut self, bound: usize) -> Result<usize, Corrupt> {
        let x = self.varint()?;
        usize::try_from(x).ok().filter(|&x| x < bound).ok_or_else(|| self.corrupt(format!("{x} is not below {bound}")))
    }

    /// An `f64`.
    pub fn f64(&mut self) -> Result<f64, Corrupt> {
        Ok(f64::from_bits(self.u64()?))
    }

    /// A string.
    pub fn str(&mut self) -> Result<&'a str, Corrupt> {
        let n = self.len(1)?;
        let at = self.at;
        std::str::from_utf8(self.take(n)?).map_err(|_| Corrupt { offset: at, detail: "not UTF-8".into() })
    }

    /// A list of `u32`.
    pub fn u32s(&mut self) -> Result<Vec<u32>, Corrupt> {
        let n = self.len(4)?;
        (0..n).map(|_| self.u32()).collect()
    }

    /// A list of `f64`.
    pub fn f64s(&mut self) -> Result<Vec<f64>, Corrupt> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
}

/// The layout the committed table files share (sub-patch matrices, eigenbases): a header that
/// names what the file holds, then entries in key order, each a key, a payload and its
/// checksum, so that a reader finds one entry by binary search and decodes only that one.
///
/// The bytes (little-endian but the keys): the magic (8 bytes), the version (u32), the scheme's
/// name (a string) and identity (u64), the entry count (u32); per entry its key
/// ([`key_len`](Self::key_len) bytes, compared as bytes: numbers in it are big-endian so that
/// they sort as numbers), the payload's length (u32) and FNV-1a (u64), and the payload.
///
/// ```
/// use subdiv_schemes::binary::TableFile;
///
/// const FILE: TableFile = TableFile { what: "a test table", magic: *b"TESTTABL", version: 1, key_len: 2 };
/// let bytes = FILE.write("loop", 7, &[(vec![0, 1], vec![10, 20]), (vec![0, 2], vec![30])]);
/// let index = FILE.index(&bytes, "loop")?;
/// assert_eq!(index.identity(), 7);
/// let at = index.find(&[0, 2]).unwrap();
/// assert_eq!(index.payload(at)?, [30]);
/// assert!(FILE.index(&bytes, "catmull-clark").is_err());
/// # Ok::<(), subdiv_schemes::binary::Corrupt>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct TableFile {
    /// What the file is, with its article, for messages (`a patch table`).
    pub what: &'static str,
    /// The first bytes.
    pub magic: [u8; 8],
    /// The format version this build reads and writes.
    pub version: u32,
    /// The length of every key.
    pub key_len: usize,
}

impl TableFile {
    /// The file of `scheme` (name and identity) holding `entries` (key, payload), which are
    /// sorted by key here.
    ///
    /// # Panics
    /// If a key is not [`key_len`](Self::key_len) long, or two keys are equal (a bug of the
    /// caller's).
    pub fn write(&self, scheme: &str, identity: u64, entries: &[(Vec<u8>, Vec<u8>)]) -> Vec<u8> {
        let mut sorted: Vec<&(Vec<u8>, Vec<u8>)> = entries.iter().collect();
        sorted.sort_by(|a, b| a.0.cmp(&b.0));
        assert!(sorted.iter().all(|(k, _)| k.len() == self.key_len), "keys of {} bytes", self.key_len);
        assert!(sorted.windows(2).all(|w| w[0].0 != w[1].0), "distinct keys");
        let mut w = ByteWriter::default();
        w.raw(&self.magic);
        w.u32(self.version);
        w.str(scheme);
        w.u64(identity);
        w.len(sorted.len());
        for (key, payload) in sorted {
            w.raw(key);
            w.len(payload.len());
            w.u64(fnv1a(payload));
            w.raw(payload);
        }
        w.finish()
    }

    /// The header and the entries' places in `bytes`, a file of `scheme` (by name); the
    /// payloads' checksums are checked when they are read ([`TableIndex::payload`]): hashing a
    /// whole file cost more than a first tessellation's matrices.
    ///
    /// # Errors
    /// Another kind of file, another version or scheme, entries out of order, and truncated
    /// bytes, each with its offset.
    pub fn index<'a>(&self, bytes: &'a [u8], scheme: &str) -> Result<TableIndex<'a>, Corrupt> {
        let mut r = ByteReader::new(bytes);
        if r.take(8).ok() != Some(&self.magic[..]) {
            let magic = String::from_utf8_lossy(&self.magic);
            return Err(Corrupt { offset: 0, detail: format!("not {} file (no {magic} magic)", self.what) });
        }
        let version = r.u32()?;
        if version != self.version {
            return Err(r.corrupt(format!("format version {version}, this build reads {}", self.version)));
        }
        let name = r.str()?;
        if name != scheme {
            return Err(r.corrupt(format!("tables of `{name}`, not of `{scheme}`")));
        }
        let identity = r.u64()?;
        let count = r.len(self.key_len + 12)?;
        let mut entries = Vec::with_capacity(count);
        for _ in 0..count {
            let key = r.take(self.key_len)?;
            let len = r.len(1)?;
            let sum = r.u64()?;
            let offset = r.offset();
            entries.push(Entry { key, payload: r.take(len)?, offset, sum });
        }
        if !r.is_at_end() {
            return Err(r.corrupt("bytes after the last entry"));
        }
        if entries.windows(2).any(|w| w[0].key >= w[1].key) {
            return Err(Corrupt { offset: 0, detail: "entries out of order or repeated".into() });
        }
        Ok(TableIndex { identity, entries })
    }
}

/// One entry of a [`TableIndex`].
#[derive(Clone, Copy, Debug)]
struct Entry<'a> {
    key: &'a [u8],
    payload: &'a [u8],
    offset: usize,
    sum: u64,
}

/// A table file's header and entries ([`TableFile::index`]).
#[derive(Clone, Debug)]
pub struct TableIndex<'a> {
    identity: u64,
    entries: Vec<Entry<'a>>,
}

impl<'a> TableIndex<'a> {
    /// The scheme identity the file was written for.
    pub fn identity(&self) -> u64 {
        self.identity
    }

    /// The number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The entry with `key`, if there is one.
    pub fn find(&self, key: &[u8]) -> Option<usize> {
        self.entries.binary_search_by(|e| e.key.cmp(key)).ok()
    }

    /// Entry `at`'s key.
    pub fn key(&self, at: usize) -> &'a [u8] {
        self.entries[at].key
    }

    /// Entry `at`'s payload, its checksum checked.
    ///
    /// # Errors
    /// A payload whose checksum does not match.
    pub fn payload(&self, at: usize) -> Result<&'a [u8], Corrupt> {
        let e = &self.entries[at];
        if fnv1a(e.payload) == e.sum {
            Ok(e.payload)
        } else {
            Err(Corrupt { offset: e.offset, detail: "an entry's checksum does not match".into() })
        }
    }
}
