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
