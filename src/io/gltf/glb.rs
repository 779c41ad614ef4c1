//! The binary glTF container (`.glb`): a 12-byte header (`glTF`, version 2, total length), then
//! chunks of `length, type, data`, each padded to 4 bytes: JSON first, then an optional BIN.
//! Chunks of other types are skipped, as the specification says.

use crate::io::error::{malformed, IoError, Location, ProblemKind};
use std::path::Path;

/// The magic at the start of every binary glTF.
pub const MAGIC: &[u8; 4] = b"glTF";
/// The type of the JSON chunk (`JSON` little-endian).
pub const JSON: u32 = 0x4E4F_534A;
/// The type of the binary chunk (`BIN\0` little-endian).
pub const BIN: u32 = 0x004E_4942;

/// The chunks of a binary glTF: its JSON and its BIN chunk, if any.
#[derive(Debug)]
pub struct Chunks<'a> {
    /// The JSON chunk (trailing padding spaces included).
    pub json: &'a [u8],
    /// The BIN chunk (trailing padding zeros included).
    pub bin: Option<&'a [u8]>,
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

/// A problem of the binary glTF at `path`, at byte `offset` of `record`.
fn problem(path: &Path, offset: u64, record: &str, kind: ProblemKind) -> IoError {
    let at = Location::Byte {
        offset,
        record: record.into(),
    };
    malformed(path, "binary glTF", at, kind)
}

/// Splits a binary glTF into its chunks, checking the header against the file's size.
pub fn split<'a>(path: &Path, bytes: &'a [u8]) -> Result<Chunks<'a>, IoError> {
    check_header(path, bytes)?;
    let chunks = chunk_list(path, bytes)?;
    let err = |offset: u64, record: &str, kind| problem(path, offset, record, kind);
    match chunks.first() {
        Some(&(JSON, json, _)) => Ok(Chunks {
            json,
            // The BIN chunk, when there is one, comes second.
            bin: chunks.get(1).filter(|c| c.0 == BIN).map(|c| c.1),
        }),
        Some(&(ty, _, at)) => Err(err(
            at as u64,
            "chunk 0",
            ProblemKind::GlbChunk {
                reason: format!("the first chunk has type 0x{ty:08X}, expected JSON (0x4E4F534A)"),
            },
        )),
        None => Err(err(
            12,
            "chunk 0",
            ProblemKind::GlbChunk {
                reason: "the file has no JSON chunk".into(),
            },
        )),
    }
}

/// The 12-byte header: the magic, version 2, and a length that is the file's size.
fn check_header(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    let err = |offset: u64, record: &str, kind| problem(path, offset, record, kind);
    let size = bytes.len() as u64;
    if !bytes.starts_with(MAGIC) {
        let head = &bytes[..bytes.len().min(4)];
        let found = format!("{:?}", String::from_utf8_lossy(head));
        return Err(err(0, "magic", ProblemKind::GlbMagic { found }));
    }
    if bytes.len() < 12 {
        let what = "the 12-byte header".into();
        return Err(err(0, "header", truncated(what, 12, size)));
    }
    let version = u32_at(bytes, 4);
    if version != 2 {
        return Err(err(4, "version", ProblemKind::GlbVersion { version }));
    }
    let declared = u64::from(u32_at(bytes, 8));
    if declared != size {
        let what = "the file, by the header's length field,".to_string();
        return Err(err(8, "length", truncated(what, declared, size)));
    }
    Ok(())
}

/// A chunk: its type, its data, and its offset in the file.
type Chunk<'a> = (u32, &'a [u8], usize);

/// The chunks after the header, in order, every one checked to end within the file.
fn chunk_list<'a>(path: &Path, bytes: &'a [u8]) -> Result<Vec<Chunk<'a>>, IoError> {
    let err = |offset: u64, record: &str, kind| problem(path, offset, record, kind);
    let size = bytes.len() as u64;
    let mut chunks = Vec::new();
    let mut at = 12usize;
    while at < bytes.len() {
        let i = chunks.len();
        if bytes.len() - at < 8 {
            let what = format!("chunk {i}'s 8-byte header at byte {at}");
            return Err(err(
                at as u64,
                "chunk",
                truncated(what, at as u64 + 8, size),
            ));
        }
        let (len, ty) = (u32_at(bytes, at) as usize, u32_at(bytes, at + 4));
        let end = at as u64 + 8 + len as u64;
        if end > size {
            let what = format!("chunk {i} of {len} bytes at byte {at}");
            return Err(err(at as u64, "chunk", truncated(what, end, size)));
        }
        chunks.push((ty, &bytes[at + 8..end as usize], at));
        at = end as usize;
    }
    Ok(chunks)
}

fn truncated(what: String, needed: u64, size: u64) -> ProblemKind {
    ProblemKind::GlbTruncated { what, needed, size }
}

/// Joins a JSON document and a binary buffer into a binary glTF: the JSON padded with spaces and
/// the buffer with zeros to multiples of 4 bytes. Fails when the whole exceeds 4 GiB.
pub fn join(json: &[u8], bin: &[u8]) -> Result<Vec<u8>, String> {
    let pad = |n: usize| (4 - n % 4) % 4;
    let json_len = json.len() + pad(json.len());
    let bin_len = bin.len() + pad(bin.len());
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin_len };
    let total = 12 + 8 + json_len + bin_chunk;
    let total32 = u32::try_from(total)
        .map_err(|_| format!("{total} bytes exceed the 4 GiB a binary glTF holds"))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(&JSON.to_le_bytes());
    out.extend_from_slice(json);
    out.resize(out.len() + pad(json.len()), b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_len as u32).to_le_bytes());
        out.extend_from_slice(&BIN.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(out.len() + pad(bin.len()), 0);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn join_then_split_gives_the_chunks_back_padded() {
        let g = join(b"{\"asset\":1}", &[1, 2, 3, 4, 5]).unwrap();
        assert_eq!(g.len(), 12 + 8 + 12 + 8 + 8);
        assert_eq!(u32_at(&g, 8) as usize, g.len());
        let c = split(Path::new("x.glb"), &g).unwrap();
        assert_eq!(c.json, b"{\"asset\":1} ");
        assert_eq!(c.bin.unwrap(), [1, 2, 3, 4, 5, 0, 0, 0]);
    }

    #[test]
    fn a_cut_file_names_the_header_length() {
        let g = join(b"{}", &[7; 16]).unwrap();
        let e = split(Path::new("x.glb"), &g[..g.len() - 5]).unwrap_err();
        let s = e.to_string();
        assert!(
            s.contains("byte 8 (length): truncated binary glTF: the file, by the header's length field, needs 48 bytes, the file has 43"),
            "{s}"
        );
    }
}
