//! The attachment of every bridged sample (docs/zenoh.md; described in
//! python/links_and_nodes/wire/zenoh.schema, the Python codec in zenoh_bridge/wire.py),
//! little-endian, 29 + N bytes: magic "LZ", version 1, flags 0, seq u64, publish time i64 ns,
//! layout hash u64, N (u8), md name (N bytes of UTF-8).  Both codecs are held to the golden
//! vectors of tests/golden/zenoh_attachment.txt (the tests below, and pytest).

pub const HEAD_SIZE: usize = 29;
const MAGIC: &[u8; 2] = b"LZ";
const VERSION: u8 = 1;

/// The md part of one topic's attachments, packed once.
pub struct Encoder {
    tail: Vec<u8>,
}

impl Encoder {
    pub fn new(md_name: &str, layout_hash: u64) -> Result<Encoder, String> {
        let name = md_name.as_bytes();
        if name.is_empty() || name.len() > 255 {
            return Err(format!("md name {md_name:?} must be 1..255 bytes"));
        }
        let mut tail = Vec::with_capacity(9 + name.len());
        tail.extend_from_slice(&layout_hash.to_le_bytes());
        tail.push(name.len() as u8);
        tail.extend_from_slice(name);
        Ok(Encoder { tail })
    }

    pub fn encode(&self, seq: u64, publish_time_ns: i64) -> Vec<u8> {
        let mut out = Vec::with_capacity(20 + self.tail.len());
        out.extend_from_slice(MAGIC);
        out.push(VERSION);
        out.push(0);
        out.extend_from_slice(&seq.to_le_bytes());
        out.extend_from_slice(&publish_time_ns.to_le_bytes());
        out.extend_from_slice(&self.tail);
        out
    }
}

/// A decoded attachment; the md name borrows from the bytes.
pub struct Attachment<'a> {
    pub seq: u64,
    pub layout_hash: u64,
    pub md_name: &'a str,
}

fn u64_at(data: &[u8], at: usize) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&data[at..at + 8]);
    u64::from_le_bytes(b)
}

/// The attachment of a sample, or what is wrong with it (the texts of wire.py).
pub fn decode(data: Option<&[u8]>) -> Result<Attachment<'_>, String> {
    let data = match data {
        Some(d) if !d.is_empty() => d,
        _ => return Err("no attachment".into()),
    };
    if data.len() < HEAD_SIZE {
        return Err(format!("attachment of {} bytes, shorter than {HEAD_SIZE}", data.len()));
    }
    if &data[0..2] != MAGIC {
        return Err(format!("attachment magic {:?}, not {:?}",
                           String::from_utf8_lossy(&data[0..2]), "LZ"));
    }
    if data[2] != VERSION {
        return Err(format!("attachment version {}, not {VERSION}", data[2]));
    }
    let n = data[28] as usize;
    if data.len() != HEAD_SIZE + n || n == 0 {
        return Err(format!("attachment of {} bytes for an md name of {n}", data.len()));
    }
    let md_name = std::str::from_utf8(&data[HEAD_SIZE..])
        .map_err(|_| "md name in the attachment is not UTF-8".to_string())?;
    Ok(Attachment { seq: u64_at(data, 4), layout_hash: u64_at(data, 20), md_name })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let enc = Encoder::new("lnbench/sample_64", 0x0123_4567_89ab_cdef).unwrap();
        let bytes = enc.encode(42, -7);
        assert_eq!(bytes.len(), HEAD_SIZE + "lnbench/sample_64".len());
        let att = decode(Some(&bytes)).unwrap();
        assert_eq!((att.seq, att.layout_hash, att.md_name),
                   (42, 0x0123_4567_89ab_cdef, "lnbench/sample_64"));
    }

    #[test]
    fn refuses_what_is_not_ours() {
        assert_eq!(decode(None).err().unwrap(), "no attachment");
        assert!(decode(Some(b"LZ")).err().unwrap().contains("shorter than 29"));
        let mut bytes = Encoder::new("a/b", 1).unwrap().encode(1, 1);
        bytes[2] = 9;
        assert!(decode(Some(&bytes)).err().unwrap().contains("version 9"));
        bytes[2] = 1;
        bytes.push(0);
        assert!(decode(Some(&bytes)).err().unwrap().contains("for an md name of 3"));
        assert!(Encoder::new("", 1).is_err());
    }

    const GOLDEN: &str = include_str!("../../tests/golden/zenoh_attachment.txt");

    /// The values of a golden `json` line: a flat object of strings and integers.
    fn flat_json(text: &str) -> std::collections::HashMap<String, String> {
        let mut out = std::collections::HashMap::new();
        let body = text.trim().strip_prefix('{').and_then(|t| t.strip_suffix('}')).unwrap();
        let mut rest = body.trim();
        while !rest.is_empty() {
            let (key, after) = quoted(rest);
            let after = after.trim_start().strip_prefix(':').unwrap().trim_start();
            let (value, after) = if after.starts_with('"') {
                quoted(after)
            } else {
                let end = after.find(',').unwrap_or(after.len());
                (after[..end].trim().to_string(), &after[end..])
            };
            out.insert(key, value);
            rest = after.trim_start().strip_prefix(',').unwrap_or(after).trim_start();
        }
        out
    }

    /// A JSON string at the start of `text` (no escapes but \" and \\) and what follows.
    fn quoted(text: &str) -> (String, &str) {
        let mut value = String::new();
        let mut chars = text.strip_prefix('"').unwrap().char_indices();
        while let Some((i, c)) = chars.next() {
            match c {
                '"' => return (value, &text[i + 2..]),
                '\\' => value.push(chars.next().unwrap().1),
                c => value.push(c),
            }
        }
        panic!("unterminated string in {text:?}");
    }

    fn hex(text: &str) -> Vec<u8> {
        (0..text.len()).step_by(2).map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
            .collect()
    }

    #[test]
    fn golden_vectors() {
        // (line, values, bytes) of each `message` vector
        let mut vectors: Vec<(usize, std::collections::HashMap<String, String>, Vec<u8>)> = vec![];
        let mut refusals = 0;
        for (number, line) in GOLDEN.lines().enumerate().map(|(i, l)| (i + 1, l)) {
            let (word, rest) = line.split_once(' ').unwrap_or((line, ""));
            match word {
                "message" => vectors.push((number, Default::default(), vec![])),
                "json" => vectors.last_mut().unwrap().1 = flat_json(rest),
                "hex" => vectors.last_mut().unwrap().2.extend(hex(rest.trim())),
                "refuse" => {
                    let (data, why) = rest.split_once(' ').unwrap();
                    let bytes = if data == "none" { None } else { Some(hex(data.trim_matches('-'))) };
                    let got = decode(bytes.as_deref());
                    let text = got.err().unwrap_or_else(|| panic!("line {number}: decoded"));
                    assert!(text.starts_with(why), "line {number}: {text:?}, not {why:?}");
                    refusals += 1;
                }
                _ => {}
            }
        }
        assert!(vectors.len() >= 3 && refusals >= 5);
        for (line, values, bytes) in &vectors {
            let num = |name: &str| values[name].parse::<i128>().unwrap();
            let (seq, time, hash) = (num("seq") as u64, num("publish_time_ns") as i64,
                                     num("layout_hash") as u64);
            let md_name = values["md_name"].as_str();
            assert_eq!((values["magic"].as_str(), num("version"), num("flags")),
                       ("4c5a", 1, 0), "line {line}");
            let encoded = Encoder::new(md_name, hash).unwrap().encode(seq, time);
            assert_eq!(&encoded, bytes, "line {line}: encoded");
            let att = decode(Some(bytes)).unwrap_or_else(|e| panic!("line {line}: {e}"));
            assert_eq!((att.seq, att.layout_hash, att.md_name), (seq, hash, md_name),
                       "line {line}: decoded");
            assert_eq!(i64::from_le_bytes(bytes[12..20].try_into().unwrap()), time,
                       "line {line}: publish time");
        }
    }
}
