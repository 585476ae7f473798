//! Batches between two bridges (docs/zenoh.md "Batches between bridges"): several samples of
//! one topic in one Zenoh message on `P/batch/<topic>`, a key that subscribers of the
//! per-topic keys never see.  The message's attachment is the usual one of its first sample
//! (md name, layout hash); its payload, little-endian:
//!
//! ```text
//! 0  2  magic "LB"     4  4  count (u32, >= 1)
//! 2  1  version 1      8  ..  count entries: seq u64, publish time i64 ns, len u32, len bytes
//! 3  1  flags 0
//! ```
//!
//! Each entry keeps its own seq and publish time; the receiving side gives it the attachment
//! of the message with these two patched in (`entry_attachment`), so it is checked and
//! published exactly as a sample of the per-topic key.  A batch that does not decode whole is
//! dropped whole (counted as bad_batches).

pub const MAGIC: &[u8; 2] = b"LB";
pub const VERSION: u8 = 1;
pub const HEAD_SIZE: usize = 8;
pub const ENTRY_HEAD: usize = 20;
/// A batch is sent once it holds this many samples ...
pub const MAX_SAMPLES: usize = 256;
/// ... or this many bytes: about half of Zenoh's default transport batch.
pub const MAX_BYTES: usize = 32 * 1024;
/// Where seq and publish time sit in an attachment (attachment.rs).
const ATT_SEQ: usize = 4;
const ATT_TIME_END: usize = 20;

/// A batch being filled by an outbound topic's reader.
pub struct Builder {
    buf: Vec<u8>,
    count: u32,
    first: Option<(u64, i64)>,
}

impl Default for Builder {
    fn default() -> Self {
        Self::new()
    }
}

impl Builder {
    pub fn new() -> Builder {
        Builder { buf: Vec::new(), count: 0, first: None }
    }

    pub fn len(&self) -> usize {
        self.count as usize
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// True once the batch should go (MAX_SAMPLES or MAX_BYTES reached).
    pub fn full(&self) -> bool {
        self.len() >= MAX_SAMPLES || self.buf.len() >= MAX_BYTES
    }

    /// Adds a sample; what it returns undoes that (`undo`).
    pub fn push(&mut self, seq: u64, publish_time_ns: i64, payload: &[u8]) -> usize {
        let mark = if self.count == 0 { 0 } else { self.buf.len() };
        if self.count == 0 {
            self.buf.clear();
            self.buf.reserve(HEAD_SIZE + ENTRY_HEAD + payload.len());
            self.buf.extend_from_slice(MAGIC);
            self.buf.extend_from_slice(&[VERSION, 0]);
            self.buf.extend_from_slice(&0u32.to_le_bytes());
            self.first = Some((seq, publish_time_ns));
        }
        self.buf.extend_from_slice(&seq.to_le_bytes());
        self.buf.extend_from_slice(&publish_time_ns.to_le_bytes());
        self.buf.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        self.buf.extend_from_slice(payload);
        self.count += 1;
        mark
    }

    /// Takes back the sample the push that returned `mark` added (the last one).
    pub fn undo(&mut self, mark: usize) {
        self.count -= 1;
        if self.count == 0 {
            self.first = None;
        }
        self.buf.truncate(mark);
    }

    /// The batch's bytes, its sample count and its first sample's (seq, publish time); the
    /// builder is empty again.
    pub fn take(&mut self) -> Option<(Vec<u8>, usize, (u64, i64))> {
        let first = self.first.take()?;
        let count = std::mem::replace(&mut self.count, 0);
        self.buf[4..8].copy_from_slice(&count.to_le_bytes());
        let capacity = self.buf.capacity();
        Some((std::mem::replace(&mut self.buf, Vec::with_capacity(capacity)), count as usize,
              first))
    }
}

/// One sample of a received batch; the payload borrows from the batch.
#[derive(Debug, PartialEq)]
pub struct Entry<'a> {
    pub seq: u64,
    pub publish_time_ns: i64,
    pub payload: &'a [u8],
}

fn le<const N: usize>(data: &[u8], at: usize) -> [u8; N] {
    let mut b = [0u8; N];
    b.copy_from_slice(&data[at..at + N]);
    b
}

/// The entries of a batch, or what is wrong with it (byte offsets into the payload).
pub fn decode(data: &[u8]) -> Result<Vec<Entry<'_>>, String> {
    if data.len() < HEAD_SIZE {
        return Err(format!("batch of {} bytes, shorter than {HEAD_SIZE}", data.len()));
    }
    if &data[0..2] != MAGIC {
        return Err(format!("batch magic {:?}, not \"LB\"", String::from_utf8_lossy(&data[0..2])));
    }
    if data[2] != VERSION {
        return Err(format!("batch version {}, not {VERSION}", data[2]));
    }
    let count = u32::from_le_bytes(le(data, 4)) as usize;
    if count == 0 {
        return Err("batch of 0 samples".into());
    }
    // every entry has at least its head: a count that cannot fit is refused before allocating
    if count > (data.len() - HEAD_SIZE) / ENTRY_HEAD {
        return Err(format!("batch says {count} samples, {} bytes cannot hold them", data.len()));
    }
    let mut out = Vec::with_capacity(count);
    let mut at = HEAD_SIZE;
    for i in 0..count {
        if data.len() - at < ENTRY_HEAD {
            return Err(format!("batch cut short in the head of sample {i} at byte {at}"));
        }
        let len = u32::from_le_bytes(le(data, at + 16)) as usize;
        let start = at + ENTRY_HEAD;
        if data.len() - start < len {
            return Err(format!("batch cut short in sample {i} of {len} bytes at byte {start}"));
        }
        out.push(Entry { seq: u64::from_le_bytes(le(data, at)),
                         publish_time_ns: i64::from_le_bytes(le(data, at + 8)),
                         payload: &data[start..start + len] });
        at = start + len;
    }
    if at != data.len() {
        return Err(format!("batch has {} bytes after its {count} samples", data.len() - at));
    }
    Ok(out)
}

/// The attachment of one entry into `out`: the batch's attachment with the entry's seq and
/// publish time; false if the batch's attachment is too short to hold them.
pub fn entry_attachment(batch_att: &[u8], entry: &Entry<'_>, out: &mut Vec<u8>) -> bool {
    if batch_att.len() < ATT_TIME_END {
        return false;
    }
    out.clear();
    out.extend_from_slice(batch_att);
    out[ATT_SEQ..ATT_SEQ + 8].copy_from_slice(&entry.seq.to_le_bytes());
    out[ATT_SEQ + 8..ATT_TIME_END].copy_from_slice(&entry.publish_time_ns.to_le_bytes());
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attachment::{decode as decode_att, Encoder};

    fn three() -> (Vec<u8>, usize, (u64, i64)) {
        let mut b = Builder::new();
        b.push(5, 50, &[1u8; 64]);
        b.push(6, 60, &[2u8; 64]);
        b.push(7, 70, &[]);
        b.take().unwrap()
    }

    #[test]
    fn round_trip_keeps_each_sample() {
        let (bytes, count, first) = three();
        assert_eq!((count, first), (3, (5, 50)));
        let entries = decode(&bytes).unwrap();
        assert_eq!(entries.len(), 3);
        assert_eq!(entries[0], Entry { seq: 5, publish_time_ns: 50, payload: &[1u8; 64] });
        assert_eq!(entries[1], Entry { seq: 6, publish_time_ns: 60, payload: &[2u8; 64] });
        assert_eq!(entries[2], Entry { seq: 7, publish_time_ns: 70, payload: &[] });
    }

    #[test]
    fn builder_empties_and_fills_again() {
        let mut b = Builder::new();
        assert!(b.take().is_none());
        let mark = b.push(9, 9, &[9u8; 4]);
        b.undo(mark);
        assert!(b.is_empty() && b.take().is_none());
        b.push(1, 10, &[1u8; 4]);
        let mark = b.push(2, 20, &[2u8; 4]);
        b.undo(mark);
        let (bytes, count, first) = b.take().unwrap();
        assert_eq!((count, first, decode(&bytes).unwrap().len()), (1, (1, 10), 1));
        for i in 0..MAX_SAMPLES as u64 {
            assert!(!b.full());
            b.push(i, 0, &[0u8; 8]);
        }
        assert!(b.full());
        let (bytes, count, _) = b.take().unwrap();
        assert_eq!((count, decode(&bytes).unwrap().len()), (MAX_SAMPLES, MAX_SAMPLES));
        assert!(b.is_empty());
        b.push(1, 1, &vec![0u8; MAX_BYTES]);
        assert!(b.full()); // one large sample goes alone
        assert_eq!(decode(&b.take().unwrap().0).unwrap().len(), 1);
    }

    #[test]
    fn entries_get_the_batch_attachment_with_their_seq_and_time() {
        let att = Encoder::new("zbtest/sample", 0xabcd).unwrap().encode(5, 50);
        let (bytes, _, _) = three();
        let entries = decode(&bytes).unwrap();
        let mut out = Vec::new();
        assert!(entry_attachment(&att, &entries[1], &mut out));
        let got = decode_att(Some(&out)).unwrap();
        assert_eq!((got.seq, got.layout_hash, got.md_name), (6, 0xabcd, "zbtest/sample"));
        assert_eq!(i64::from_le_bytes(out[12..20].try_into().unwrap()), 60);
        assert!(!entry_attachment(b"LZ\x01", &entries[0], &mut out));
    }

    #[test]
    fn malformed_batches_are_refused_whole() {
        let (good, _, _) = three();
        let refused = |data: &[u8], why: &str| {
            let text = decode(data).err().unwrap_or_else(|| panic!("decoded: {why}"));
            assert!(text.contains(why), "{text:?}, not {why:?}");
        };
        refused(b"LB\x01", "shorter than 8");
        let mut bad = good.clone();
        bad[0] = b'X';
        refused(&bad, "magic");
        let mut bad = good.clone();
        bad[2] = 2;
        refused(&bad, "version 2");
        let mut bad = good.clone();
        bad[4..8].copy_from_slice(&0u32.to_le_bytes());
        refused(&bad, "0 samples");
        let mut bad = good.clone();
        bad[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        refused(&bad, "cannot hold them");
        let mut bad = good.clone();
        bad[4..8].copy_from_slice(&2u32.to_le_bytes());
        refused(&bad, "after its 2 samples");
        refused(&good[..good.len() - 1], "cut short in the head of sample 2");
        let mut one = Builder::new();
        one.push(1, 1, &[0u8; 64]);
        let one = one.take().unwrap().0;
        refused(&one[..one.len() - 10], "cut short in sample 0 of 64 bytes at byte 28");
        let mut bad = good.clone();
        bad[HEAD_SIZE + 16..HEAD_SIZE + 20].copy_from_slice(&1000u32.to_le_bytes());
        refused(&bad, "cut short in sample 0 of 1000 bytes at byte 28");
        decode(&good).unwrap();
    }
}
