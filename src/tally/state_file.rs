//! The encoding shared by the state files of a run (shards,
//! [`super::shard`], and checkpoints, [`super::checkpoint`]): a text header
//! of `key = value` lines naming the run ([`RunIdentity`]), an empty line, a
//! little-endian binary body, and a trailer holding the FNV-1a 64 hash of
//! everything before it, so that a cut or damaged file is refused.

use std::io::{self, Read, Write};

/// FNV-1a 64-bit hash of `bytes` (a fixed, documented function: the same
/// on every machine and in every version).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_more(FNV_OFFSET, bytes)
}

/// FNV-1a 64 offset basis.
pub(super) const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// Continue an FNV-1a 64 hash `h` over `bytes`.
pub(super) fn fnv1a_more(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// What identifies a run: shards merge, and a checkpoint resumes, only
/// when all of it is equal.
#[derive(Clone, Debug, PartialEq)]
pub struct RunIdentity {
    /// Batches of the whole run.
    pub batches: u64,
    /// Chains per batch.
    pub batch_size: u64,
    /// The run's chain count.
    pub chains: u64,
    /// Seed.
    pub seed: u64,
    /// Resolved reflection orders.
    pub orders: u32,
    /// Number of receivers.
    pub receivers: u64,
    /// Hash of the scene and the files it refers to.
    pub scene: u64,
    /// Hash of the points file.
    pub points: u64,
    /// Every other setting that changes the numbers, as text.
    pub config: String,
    /// Whether the scene's lights approximate it (median cut; flag
    /// `approx`): the header line `approximate = 1`, written only then
    /// (older states, without it, read as not).
    pub approximate: bool,
}

/// What is wrong with a state file.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    /// Reading failed.
    #[error("{0}")]
    Io(#[from] io::Error),
    /// Not a file of the expected kind, or a version this program does not read.
    #[error("not a lumest {0} (the first line must be `{1}`)")]
    Magic(&'static str, &'static str),
    /// A header line is missing or malformed.
    #[error("header: {0}")]
    Header(String),
    /// The body is cut short or damaged.
    #[error("the file is damaged or cut short ({0})")]
    Damaged(String),
}

/// A writer that hashes what passes through it.
pub(super) struct Hashing<W> {
    pub(super) inner: W,
    pub(super) hash: u64,
}

impl<W: Write> Write for Hashing<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash = fnv1a_more(self.hash, &buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

pub(super) fn put_u64<W: Write>(w: &mut W, x: u64) -> io::Result<()> {
    w.write_all(&x.to_le_bytes())
}

pub(super) fn put_strings<W: Write>(w: &mut W, s: &[String]) -> io::Result<()> {
    put_u64(w, s.len() as u64)?;
    for x in s {
        put_u64(w, x.len() as u64)?;
        w.write_all(x.as_bytes())?;
    }
    Ok(())
}

pub(super) fn get_bytes<'a>(r: &mut &'a [u8], n: usize) -> Result<&'a [u8], StateError> {
    if r.len() < n {
        return Err(StateError::Damaged("the body is cut short".into()));
    }
    let (a, b) = r.split_at(n);
    *r = b;
    Ok(a)
}

pub(super) fn get_u64(r: &mut &[u8]) -> Result<u64, StateError> {
    let mut b = [0u8; 8];
    get_bytes(r, 8)?.read_exact(&mut b)?;
    Ok(u64::from_le_bytes(b))
}

/// A length that must fit in what is left (8 bytes an element at least
/// would be a looser bound; one byte each keeps it safe for any element).
pub(super) fn get_len(r: &mut &[u8]) -> Result<usize, StateError> {
    let n = get_u64(r)?;
    if n > r.len() as u64 {
        return Err(StateError::Damaged(format!(
            "a length of {n} exceeds the file"
        )));
    }
    Ok(n as usize)
}

pub(super) fn get_f64(r: &mut &[u8]) -> Result<f64, StateError> {
    Ok(f64::from_bits(get_u64(r)?))
}

pub(super) fn get_strings(r: &mut &[u8]) -> Result<Vec<String>, StateError> {
    let n = get_len(r)?;
    (0..n)
        .map(|_| {
            let len = get_len(r)?;
            String::from_utf8(get_bytes(r, len)?.to_vec())
                .map_err(|_| StateError::Damaged("a string is not UTF-8".into()))
        })
        .collect()
}

/// A writer over `w` that hashes what passes through it, for [`finish`].
pub(super) fn hashing<W: Write>(w: W) -> Hashing<W> {
    Hashing {
        inner: w,
        hash: FNV_OFFSET,
    }
}

/// Write the header: `magic`, the run's identity, the `extra` keys, then
/// the empty line that ends it.
pub(super) fn write_header<W: Write>(
    w: &mut W,
    magic: &str,
    r: &RunIdentity,
    extra: &[(&str, String)],
) -> io::Result<()> {
    writeln!(w, "{magic}")?;
    for (k, v) in extra {
        writeln!(w, "{k} = {v}")?;
    }
    writeln!(w, "batches = {}", r.batches)?;
    writeln!(w, "batch_size = {}", r.batch_size)?;
    writeln!(w, "chains = {}", r.chains)?;
    writeln!(w, "seed = {}", r.seed)?;
    writeln!(w, "orders = {}", r.orders)?;
    writeln!(w, "receivers = {}", r.receivers)?;
    writeln!(w, "scene = {:016x}", r.scene)?;
    writeln!(w, "points = {:016x}", r.points)?;
    writeln!(w, "config = {}", r.config.replace('\n', " "))?;
    if r.approximate {
        writeln!(w, "approximate = 1")?;
    }
    writeln!(w)
}

/// Append the trailer (the hash of all written before) and flush.
pub(super) fn finish<W: Write>(mut w: Hashing<W>) -> io::Result<()> {
    let hash = w.hash;
    w.inner.write_all(&hash.to_le_bytes())?;
    w.inner.flush()
}

/// A header's keys and values.
pub(super) type Header = std::collections::BTreeMap<String, String>;

/// A state file checked (trailer, `magic`) and split into its header's
/// keys, the run it names and the body. `what` names the kind of file.
pub(super) fn open<'a>(
    bytes: &'a [u8],
    magic: &'static str,
    what: &'static str,
) -> Result<(Header, RunIdentity, &'a [u8]), StateError> {
    if !bytes.starts_with(magic.as_bytes()) {
        return Err(StateError::Magic(what, magic));
    }
    if bytes.len() < 8 {
        return Err(StateError::Damaged("shorter than its trailer".into()));
    }
    let (content, trailer) = bytes.split_at(bytes.len() - 8);
    let want = u64::from_le_bytes(trailer.try_into().expect("8 bytes"));
    if fnv1a(content) != want {
        return Err(StateError::Damaged("checksum mismatch".into()));
    }
    let end = content
        .windows(2)
        .position(|w| w == b"\n\n")
        .ok_or_else(|| StateError::Header("no empty line ends the header".into()))?;
    let header =
        std::str::from_utf8(&content[..end]).map_err(|_| StateError::Header("not UTF-8".into()))?;
    let mut lines = header.lines();
    if lines.next() != Some(magic) {
        return Err(StateError::Magic(what, magic));
    }
    let mut kv = std::collections::BTreeMap::new();
    for l in lines {
        let (k, v) = l
            .split_once(" = ")
            .ok_or_else(|| StateError::Header(format!("line `{l}` is not `key = value`")))?;
        kv.insert(k.to_string(), v.to_string());
    }
    let run = RunIdentity {
        batches: key_u64(&kv, "batches")?,
        batch_size: key_u64(&kv, "batch_size")?,
        chains: key_u64(&kv, "chains")?,
        seed: key_u64(&kv, "seed")?,
        orders: key_u64(&kv, "orders")? as u32,
        receivers: key_u64(&kv, "receivers")?,
        scene: key_hex(&kv, "scene")?,
        points: key_hex(&kv, "points")?,
        config: key(&kv, "config")?,
        approximate: match kv.get("approximate").map(String::as_str) {
            None | Some("0") => false,
            Some("1") => true,
            Some(v) => {
                return Err(StateError::Header(format!(
                    "`approximate` is `{v}`, not 0 or 1"
                )));
            }
        },
    };
    Ok((kv, run, &content[end + 2..]))
}

/// Header value of `k`.
pub(super) fn key(kv: &Header, k: &str) -> Result<String, StateError> {
    kv.get(k)
        .cloned()
        .ok_or_else(|| StateError::Header(format!("`{k}` is missing")))
}

/// Header value of `k` as a whole number.
pub(super) fn key_u64(kv: &Header, k: &str) -> Result<u64, StateError> {
    key(kv, k)?
        .parse()
        .map_err(|_| StateError::Header(format!("`{k}` is not a whole number")))
}

/// Header value of `k` as a number.
pub(super) fn key_f64(kv: &Header, k: &str) -> Result<f64, StateError> {
    key(kv, k)?
        .parse()
        .map_err(|_| StateError::Header(format!("`{k}` is not a number")))
}

fn key_hex(kv: &Header, k: &str) -> Result<u64, StateError> {
    u64::from_str_radix(&key(kv, k)?, 16)
        .map_err(|_| StateError::Header(format!("`{k}` is not a hash")))
}

/// `n` f64s.
pub(super) fn get_f64s(r: &mut &[u8], n: usize) -> Result<Vec<f64>, StateError> {
    (0..n).map(|_| get_f64(r)).collect()
}

/// A length-prefixed f64 vector.
pub(super) fn put_f64v<W: Write>(w: &mut W, v: &[f64]) -> io::Result<()> {
    put_u64(w, v.len() as u64)?;
    v.iter().try_for_each(|x| w.write_all(&x.to_le_bytes()))
}

/// A length-prefixed f64 vector.
pub(super) fn get_f64v(r: &mut &[u8]) -> Result<Vec<f64>, StateError> {
    let n = get_len(r)?;
    get_f64s(r, n)
}

/// A length-prefixed u64 vector.
pub(super) fn put_u64v<W: Write>(w: &mut W, v: &[u64]) -> io::Result<()> {
    put_u64(w, v.len() as u64)?;
    v.iter().try_for_each(|&x| put_u64(w, x))
}

/// A length-prefixed u64 vector.
pub(super) fn get_u64v(r: &mut &[u8]) -> Result<Vec<u64>, StateError> {
    let n = get_len(r)?;
    (0..n).map(|_| get_u64(r)).collect()
}

/// A length-prefixed flag vector (one byte each).
pub(super) fn put_flags<W: Write>(w: &mut W, v: &[bool]) -> io::Result<()> {
    put_u64(w, v.len() as u64)?;
    w.write_all(&v.iter().map(|&b| b as u8).collect::<Vec<u8>>())
}

/// A length-prefixed flag vector.
pub(super) fn get_flags(r: &mut &[u8]) -> Result<Vec<bool>, StateError> {
    let n = get_len(r)?;
    Ok(get_bytes(r, n)?.iter().map(|&b| b != 0).collect())
}
