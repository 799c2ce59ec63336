//! The state of one shard of a run: its batches, unfolded, and what is
//! needed to fold them with the other shards' into the whole run's result
//! (`lumest illuminance ... --shard I/M --out PART`, then `lumest merge`).
//!
//! # File format (version 1)
//!
//! A text header of `key = value` lines, ended by an empty line, then a
//! little-endian binary body, then a trailer:
//!
//! ```text
//! lumest shard state 1
//! shard = I/M              this shard's index and the number of shards
//! batches = B              batches of the whole run; this shard holds I, I+M, ... < B
//! batch_size = bs          chains per batch
//! chains = N               the run's --chains
//! seed = K
//! orders = K               resolved reflection orders (bucket count = K + 1, or 1)
//! receivers = n
//! scene = <16 hex digits>  FNV-1a 64 of the scene file and the files it refers to
//! points = <16 hex digits> FNV-1a 64 of the points file
//! config = <text>          every run setting that changes the numbers, which must match
//! wall = <seconds>         the shard's wall time (for the merged summary only)
//!
//! body: direct (n f64), the checks watched, near_plain, near_reach (n u8
//! each), enclosed (u64 count, then u8s), the points table (headers, rows
//! and the comment-line count: u64 counts and length-prefixed UTF-8
//! strings), then u64 count of batches, each: index, chains, collisions,
//! scores (u64), sums, direct_sums (u64 length, f64s), near_hits (u64
//! length, u64s)
//! trailer: FNV-1a 64 of everything before it (u64), so a cut or damaged
//! file is refused
//! ```
//!
//! Shards of one run differ only in `shard`, `wall` and their batches;
//! merging refuses states of different scenes, points, seeds or settings,
//! a shard missing or given twice, and a damaged file.

use super::Batch;
use std::io::{self, Read, Write};

/// The first line of a shard file.
pub const MAGIC: &str = "lumest shard state 1";

/// FNV-1a 64-bit hash of `bytes` (a fixed, documented function: the same
/// on every machine and in every version).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_more(FNV_OFFSET, bytes)
}

/// FNV-1a 64 offset basis.
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// Continue an FNV-1a 64 hash `h` over `bytes`.
fn fnv1a_more(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// What identifies the run a shard belongs to: shards merge only when all
/// of it is equal.
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
}

/// One shard's state.
#[derive(Debug)]
pub struct ShardState {
    /// Which run.
    pub run: RunIdentity,
    /// This shard's index `i` and the number of shards `m`.
    pub shard: (u64, u64),
    /// Wall time of the shard [s].
    pub wall: f64,
    /// Exact direct part per receiver [lx].
    pub direct: Vec<f64>,
    /// The per-receiver checks: watched, near_plain, near_reach, enclosed.
    pub checks: [Vec<bool>; 4],
    /// The points file's header names.
    pub headers: Vec<String>,
    /// The points file's rows (raw cells).
    pub rows: Vec<Vec<String>>,
    /// Comment lines before the points file's header.
    pub comment_lines: u64,
    /// The shard's batches in index order.
    pub batches: Vec<Batch>,
}

/// What is wrong with a shard file.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// Reading failed.
    #[error("{0}")]
    Io(#[from] io::Error),
    /// Not a shard file, or a version this program does not read.
    #[error("not a lumest shard state (the first line must be `{MAGIC}`)")]
    Magic,
    /// A header line is missing or malformed.
    #[error("header: {0}")]
    Header(String),
    /// The body is cut short or damaged.
    #[error("the file is damaged or cut short ({0})")]
    Damaged(String),
}

/// A writer that hashes what passes through it.
struct Hashing<W> {
    inner: W,
    hash: u64,
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

impl ShardState {
    /// Write the state (format in the module docs).
    pub fn write<W: Write>(&self, w: W) -> io::Result<()> {
        let mut w = Hashing {
            inner: w,
            hash: FNV_OFFSET,
        };
        let r = &self.run;
        writeln!(w, "{MAGIC}")?;
        writeln!(w, "shard = {}/{}", self.shard.0, self.shard.1)?;
        writeln!(w, "batches = {}", r.batches)?;
        writeln!(w, "batch_size = {}", r.batch_size)?;
        writeln!(w, "chains = {}", r.chains)?;
        writeln!(w, "seed = {}", r.seed)?;
        writeln!(w, "orders = {}", r.orders)?;
        writeln!(w, "receivers = {}", r.receivers)?;
        writeln!(w, "scene = {:016x}", r.scene)?;
        writeln!(w, "points = {:016x}", r.points)?;
        writeln!(w, "config = {}", r.config.replace('\n', " "))?;
        writeln!(w, "wall = {:e}", self.wall)?;
        writeln!(w)?;
        for &x in &self.direct {
            w.write_all(&x.to_le_bytes())?;
        }
        for c in &self.checks[..3] {
            w.write_all(&c.iter().map(|&b| b as u8).collect::<Vec<u8>>())?;
        }
        put_u64(&mut w, self.checks[3].len() as u64)?;
        w.write_all(&self.checks[3].iter().map(|&b| b as u8).collect::<Vec<u8>>())?;
        put_strings(&mut w, &self.headers)?;
        put_u64(&mut w, self.rows.len() as u64)?;
        for row in &self.rows {
            put_strings(&mut w, row)?;
        }
        put_u64(&mut w, self.comment_lines)?;
        put_u64(&mut w, self.batches.len() as u64)?;
        for b in &self.batches {
            for x in [b.index, b.chains, b.collisions, b.scores] {
                put_u64(&mut w, x)?;
            }
            put_u64(&mut w, b.sums.len() as u64)?;
            for x in &b.sums {
                w.write_all(&x.to_le_bytes())?;
            }
            put_u64(&mut w, b.direct_sums.len() as u64)?;
            for x in &b.direct_sums {
                w.write_all(&x.to_le_bytes())?;
            }
            put_u64(&mut w, b.near_hits.len() as u64)?;
            for &x in &b.near_hits {
                put_u64(&mut w, x)?;
            }
        }
        let hash = w.hash;
        w.inner.write_all(&hash.to_le_bytes())?;
        w.flush()
    }

    /// Read a state written by [`Self::write`] (all of `bytes`).
    pub fn read(bytes: &[u8]) -> Result<Self, ShardError> {
        if bytes.len() < 8 {
            return Err(ShardError::Damaged("shorter than its trailer".into()));
        }
        let (content, trailer) = bytes.split_at(bytes.len() - 8);
        let want = u64::from_le_bytes(trailer.try_into().expect("8 bytes"));
        if !content.starts_with(MAGIC.as_bytes()) {
            return Err(ShardError::Magic);
        }
        if fnv1a(content) != want {
            return Err(ShardError::Damaged("checksum mismatch".into()));
        }
        // The header: lines up to the first empty one.
        let end = content
            .windows(2)
            .position(|w| w == b"\n\n")
            .ok_or_else(|| ShardError::Header("no empty line ends the header".into()))?;
        let header = std::str::from_utf8(&content[..end])
            .map_err(|_| ShardError::Header("not UTF-8".into()))?;
        let mut lines = header.lines();
        if lines.next() != Some(MAGIC) {
            return Err(ShardError::Magic);
        }
        let mut kv = std::collections::BTreeMap::new();
        for l in lines {
            let (k, v) = l
                .split_once(" = ")
                .ok_or_else(|| ShardError::Header(format!("line `{l}` is not `key = value`")))?;
            kv.insert(k.to_string(), v.to_string());
        }
        let get = |k: &str| {
            kv.get(k)
                .cloned()
                .ok_or_else(|| ShardError::Header(format!("`{k}` is missing")))
        };
        let num = |k: &str| -> Result<u64, ShardError> {
            get(k)?
                .parse()
                .map_err(|_| ShardError::Header(format!("`{k}` is not a whole number")))
        };
        let hex = |k: &str| -> Result<u64, ShardError> {
            u64::from_str_radix(&get(k)?, 16)
                .map_err(|_| ShardError::Header(format!("`{k}` is not a hash")))
        };
        let shard = get("shard")?;
        let shard = shard
            .split_once('/')
            .and_then(|(i, m)| Some((i.parse().ok()?, m.parse().ok()?)))
            .ok_or_else(|| ShardError::Header(format!("shard `{shard}` is not I/M")))?;
        let run = RunIdentity {
            batches: num("batches")?,
            batch_size: num("batch_size")?,
            chains: num("chains")?,
            seed: num("seed")?,
            orders: num("orders")? as u32,
            receivers: num("receivers")?,
            scene: hex("scene")?,
            points: hex("points")?,
            config: get("config")?,
        };
        let wall: f64 = get("wall")?
            .parse()
            .map_err(|_| ShardError::Header("`wall` is not a number".into()))?;
        let mut body = &content[end + 2..];
        let n = run.receivers as usize;
        let r = &mut body;
        let direct = (0..n).map(|_| get_f64(r)).collect::<Result<Vec<_>, _>>()?;
        let mut checks: [Vec<bool>; 4] = Default::default();
        for c in checks.iter_mut().take(3) {
            *c = get_bytes(r, n)?.iter().map(|&b| b != 0).collect();
        }
        let ne = get_len(r)?;
        checks[3] = get_bytes(r, ne)?.iter().map(|&b| b != 0).collect();
        let headers = get_strings(r)?;
        let nrows = get_len(r)?;
        let rows = (0..nrows)
            .map(|_| get_strings(r))
            .collect::<Result<Vec<_>, _>>()?;
        let comment_lines = get_u64(r)?;
        let nb = get_len(r)?;
        let mut batches = Vec::with_capacity(nb.min(1 << 20));
        for _ in 0..nb {
            let (index, chains, collisions, scores) =
                (get_u64(r)?, get_u64(r)?, get_u64(r)?, get_u64(r)?);
            let len = get_len(r)?;
            let sums = (0..len)
                .map(|_| get_f64(r))
                .collect::<Result<Vec<_>, _>>()?;
            let len = get_len(r)?;
            let direct_sums = (0..len)
                .map(|_| get_f64(r))
                .collect::<Result<Vec<_>, _>>()?;
            let len = get_len(r)?;
            let near_hits = (0..len)
                .map(|_| get_u64(r))
                .collect::<Result<Vec<_>, _>>()?;
            batches.push(Batch {
                index,
                chains,
                sums,
                collisions,
                scores,
                direct_sums,
                near_hits,
            });
        }
        if !body.is_empty() {
            return Err(ShardError::Damaged(format!(
                "{} bytes after the last batch",
                body.len()
            )));
        }
        Ok(Self {
            run,
            shard,
            wall,
            direct,
            checks,
            headers,
            rows,
            comment_lines,
            batches,
        })
    }
}

fn put_u64<W: Write>(w: &mut W, x: u64) -> io::Result<()> {
    w.write_all(&x.to_le_bytes())
}

fn put_strings<W: Write>(w: &mut W, s: &[String]) -> io::Result<()> {
    put_u64(w, s.len() as u64)?;
    for x in s {
        put_u64(w, x.len() as u64)?;
        w.write_all(x.as_bytes())?;
    }
    Ok(())
}

fn get_bytes<'a>(r: &mut &'a [u8], n: usize) -> Result<&'a [u8], ShardError> {
    if r.len() < n {
        return Err(ShardError::Damaged("the body is cut short".into()));
    }
    let (a, b) = r.split_at(n);
    *r = b;
    Ok(a)
}

fn get_u64(r: &mut &[u8]) -> Result<u64, ShardError> {
    let mut b = [0u8; 8];
    get_bytes(r, 8)?.read_exact(&mut b)?;
    Ok(u64::from_le_bytes(b))
}

/// A length that must fit in what is left (8 bytes an element at least
/// would be a looser bound; one byte each keeps it safe for any element).
fn get_len(r: &mut &[u8]) -> Result<usize, ShardError> {
    let n = get_u64(r)?;
    if n > r.len() as u64 {
        return Err(ShardError::Damaged(format!(
            "a length of {n} exceeds the file"
        )));
    }
    Ok(n as usize)
}

fn get_f64(r: &mut &[u8]) -> Result<f64, ShardError> {
    Ok(f64::from_bits(get_u64(r)?))
}

fn get_strings(r: &mut &[u8]) -> Result<Vec<String>, ShardError> {
    let n = get_len(r)?;
    (0..n)
        .map(|_| {
            let len = get_len(r)?;
            String::from_utf8(get_bytes(r, len)?.to_vec())
                .map_err(|_| ShardError::Damaged("a string is not UTF-8".into()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> ShardState {
        ShardState {
            run: RunIdentity {
                batches: 5,
                batch_size: 100,
                chains: 500,
                seed: 7,
                orders: 1,
                receivers: 2,
                scene: 0xdead_beef,
                points: 42,
                config: "near (0.0, 16)".into(),
            },
            shard: (1, 2),
            wall: 0.25,
            direct: vec![1.5, f64::MIN_POSITIVE],
            checks: [
                vec![true, false],
                vec![false, false],
                vec![false, true],
                vec![],
            ],
            headers: vec!["id".into(), "x".into()],
            rows: vec![
                vec!["a".into(), "1".into()],
                vec!["b, c".into(), "2".into()],
            ],
            comment_lines: 3,
            batches: [1u64, 3]
                .iter()
                .map(|&i| Batch {
                    index: i,
                    chains: 100,
                    sums: vec![0.1 * i as f64, -0.0, 1e-300, 3.0],
                    collisions: 250,
                    scores: 500,
                    direct_sums: vec![],
                    near_hits: vec![4, 5],
                })
                .collect(),
        }
    }

    #[test]
    fn round_trip_keeps_every_bit() {
        let s = state();
        let mut bytes = Vec::new();
        s.write(&mut bytes).unwrap();
        let r = ShardState::read(&bytes).unwrap();
        assert_eq!(r.run, s.run);
        assert_eq!(
            (r.shard, r.wall, r.comment_lines),
            (s.shard, s.wall, s.comment_lines)
        );
        assert_eq!(r.checks, s.checks);
        assert_eq!((r.headers, r.rows), (s.headers, s.rows));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&r.direct), bits(&s.direct));
        for (a, b) in r.batches.iter().zip(&s.batches) {
            assert_eq!(bits(&a.sums), bits(&b.sums));
            assert_eq!(
                (a.index, a.chains, a.collisions, a.scores),
                (b.index, b.chains, b.collisions, b.scores)
            );
            assert_eq!(a.near_hits, b.near_hits);
        }
    }

    #[test]
    fn damaged_or_foreign_files_are_refused() {
        let mut bytes = Vec::new();
        state().write(&mut bytes).unwrap();
        // Cut short anywhere, or one bit flipped anywhere: refused.
        for cut in [0, 7, 30, bytes.len() / 2, bytes.len() - 1] {
            assert!(ShardState::read(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        for k in (0..bytes.len()).step_by(17) {
            let mut b = bytes.clone();
            b[k] ^= 0x10;
            assert!(ShardState::read(&b).is_err(), "flip at {k}");
        }
        assert!(matches!(
            ShardState::read(b"x,y,z\n1,2,3\n00000000"),
            Err(ShardError::Magic)
        ));
    }

    #[test]
    fn fnv1a_known_answers() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
