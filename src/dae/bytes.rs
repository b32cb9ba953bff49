//! The byte form of saved states: a magic tag, then bytes, little-endian u64s, and
//! length-prefixed byte strings and f64 arrays (the length as a little-endian u64). The
//! reader is bounds-checked and never panics, whatever the input.

/// Builds a byte form, field after field.
#[derive(Clone, Debug, Default)]
pub struct ByteWriter(Vec<u8>);

impl ByteWriter {
    /// A byte form that starts with `magic`.
    pub fn new(magic: &[u8; 8]) -> ByteWriter {
        ByteWriter(magic.to_vec())
    }

    /// One byte.
    pub fn u8(&mut self, v: u8) {
        self.0.push(v);
    }

    /// A little-endian u64.
    pub fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }

    /// A byte string: its length, then the bytes.
    pub fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        self.0.extend_from_slice(b);
    }

    /// An f64 array: its length, then the values (little-endian).
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for x in v {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// Everything written so far (magic included).
    pub fn as_slice(&self) -> &[u8] {
        &self.0
    }

    /// The byte form.
    pub fn finish(self) -> Vec<u8> {
        self.0
    }
}

/// Reads what a [`ByteWriter`] wrote, field after field; every read is None when the
/// bytes end too early.
#[derive(Clone, Debug)]
pub struct ByteReader<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> ByteReader<'a> {
    /// A reader of `body` (the bytes after the magic).
    pub fn new(body: &'a [u8]) -> ByteReader<'a> {
        ByteReader { b: body, pos: 0 }
    }

    /// A reader of the bytes after `magic`; None if `bytes` do not start with it.
    pub fn tagged(bytes: &'a [u8], magic: &[u8; 8]) -> Option<ByteReader<'a>> {
        Some(ByteReader::new(bytes.strip_prefix(magic.as_slice())?))
    }

    /// The next `n` bytes.
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.b.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }

    /// One byte.
    pub fn u8(&mut self) -> Option<u8> {
        Some(self.take(1)?[0])
    }

    /// A little-endian u64.
    pub fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }

    /// A little-endian u64 that must fit a usize (a length, a count).
    pub fn usize(&mut self) -> Option<usize> {
        usize::try_from(self.u64()?).ok()
    }

    /// A byte string written by [`ByteWriter::bytes`].
    pub fn bytes(&mut self) -> Option<&'a [u8]> {
        let n = self.usize()?;
        self.take(n)
    }

    /// An f64 array written by [`ByteWriter::f64s`].
    pub fn f64s(&mut self) -> Option<Vec<f64>> {
        let n = self.usize()?;
        let raw = self.take(n.checked_mul(8)?)?;
        Some(raw.chunks_exact(8).map(|c| f64::from_le_bytes(std::array::from_fn(|k| c[k]))).collect())
    }

    /// True when every byte has been read.
    pub fn at_end(&self) -> bool {
        self.pos == self.b.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<u8> {
        let mut w = ByteWriter::new(b"TESTTAG1");
        w.bytes(b"name");
        w.u8(3);
        w.f64s(&[1.5, -0.0, f64::INFINITY]);
        w.u64(42);
        w.f64s(&[]);
        w.finish()
    }

    #[test]
    fn what_is_written_reads_back_in_order_and_the_layout_is_the_documented_one() {
        let b = sample();
        let mut want = b"TESTTAG1".to_vec();
        want.extend_from_slice(&4u64.to_le_bytes());
        want.extend_from_slice(b"name");
        want.push(3);
        want.extend_from_slice(&3u64.to_le_bytes());
        for x in [1.5f64, -0.0, f64::INFINITY] {
            want.extend_from_slice(&x.to_le_bytes());
        }
        want.extend_from_slice(&42u64.to_le_bytes());
        want.extend_from_slice(&0u64.to_le_bytes());
        assert_eq!(b, want);
        let mut r = ByteReader::tagged(&b, b"TESTTAG1").unwrap();
        assert_eq!(r.bytes(), Some(&b"name"[..]));
        assert_eq!(r.u8(), Some(3));
        let v = r.f64s().unwrap();
        assert_eq!(v.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), [1.5f64, -0.0, f64::INFINITY].map(f64::to_bits));
        assert_eq!(r.usize(), Some(42));
        assert_eq!(r.f64s(), Some(vec![]));
        assert!(r.at_end());
        assert_eq!(r.u8(), None);
        assert!(ByteReader::tagged(&b, b"OTHERTAG").is_none());
    }

    #[test]
    fn truncated_or_absurd_input_gives_none_without_panicking() {
        let b = sample();
        for cut in 8..b.len() {
            let mut r = ByteReader::tagged(&b[..cut], b"TESTTAG1").unwrap();
            let all = (|| Some((r.bytes()?, r.u8()?, r.f64s()?, r.u64()?, r.f64s()?)))();
            assert!(all.is_none(), "cut at {cut}");
        }
        // Lengths that overflow or exceed the input.
        for n in [u64::MAX, u64::MAX / 8 + 1, 1 << 40] {
            let mut w = ByteWriter::new(b"TESTTAG1");
            w.u64(n);
            let b = w.finish();
            assert!(ByteReader::tagged(&b, b"TESTTAG1").unwrap().f64s().is_none());
            assert!(ByteReader::tagged(&b, b"TESTTAG1").unwrap().bytes().is_none());
        }
    }
}
