//! The state of one shard of a run: its batches, unfolded, and what is
//! needed to fold them with the other shards' into the whole run's result
//! (`lumest illuminance ... --shard I/M --out PART`, then `lumest merge`).
//!
//! # File format (version 1)
//!
//! The encoding of [`super::state_file`]: a text header of `key = value`
//! lines, ended by an empty line, then a little-endian binary body, then a
//! trailer:
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
//! approximate = 1          optional: the scene's lights approximate it (median cut: the
//!                          `approx` flag on every row); absent, or 0, when they do not
//! wall = <seconds>         the shard's wall time (for the merged summary only)
//! inputs = <paths>         optional: the run's input files (scene, points, the files the
//!                          scene names), canonical, tab-separated, with `%`, tab, CR and
//!                          LF written `%25`, `%09`, `%0D`, `%0A`: `lumest merge --out`
//!                          never writes over them (states without it still merge)
//!
//! body: direct (n f64), the checks watched, near_plain, near_reach and
//! enclosed (each a u64 count, then one byte per receiver), the points table (headers, rows
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
use super::state_file::*;
use std::io::{self, Write};
use std::path::PathBuf;

pub use super::state_file::{RunIdentity, StateError, fnv1a};

/// The first line of a shard file.
pub const MAGIC: &str = "lumest shard state 1";

/// One shard's state.
#[derive(Debug)]
pub struct ShardState {
    /// Which run.
    pub run: RunIdentity,
    /// This shard's index `i` and the number of shards `m`.
    pub shard: (u64, u64),
    /// Wall time of the shard \[s\].
    pub wall: f64,
    /// Exact direct part per receiver \[lx\].
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
    /// The run's input files where the shard ran (scene, points, the files
    /// the scene names; canonical where they resolve), which a merge must
    /// not write over. Not part of the run's identity: shards may run from
    /// other folders or machines.
    pub inputs: Vec<PathBuf>,
}

impl ShardState {
    /// Write the state (format in the module docs).
    pub fn write<W: Write>(&self, w: W) -> io::Result<()> {
        let mut w = hashing(w);
        let mut extra = vec![
            ("shard", format!("{}/{}", self.shard.0, self.shard.1)),
            ("wall", format!("{:e}", self.wall)),
        ];
        // (A path that is not UTF-8 is left out: the check only loses it.)
        let inputs: Vec<String> = self
            .inputs
            .iter()
            .filter_map(|p| p.to_str().map(escape_path))
            .collect();
        if !inputs.is_empty() {
            extra.push(("inputs", inputs.join("\t")));
        }
        write_header(&mut w, MAGIC, &self.run, &extra)?;
        self.direct
            .iter()
            .try_for_each(|x| w.write_all(&x.to_le_bytes()))?;
        for c in &self.checks {
            put_flags(&mut w, c)?;
        }
        put_strings(&mut w, &self.headers)?;
        put_u64(&mut w, self.rows.len() as u64)?;
        for row in &self.rows {
            put_strings(&mut w, row)?;
        }
        put_u64(&mut w, self.comment_lines)?;
        write_batches(&mut w, &self.batches)?;
        finish(w)
    }

    /// Read a state written by [`Self::write`] (all of `bytes`).
    pub fn read(bytes: &[u8]) -> Result<Self, StateError> {
        let (kv, run, mut body) = open(bytes, MAGIC, "shard state")?;
        let shard = key(&kv, "shard")?;
        let shard = shard
            .split_once('/')
            .and_then(|(i, m)| Some((i.parse().ok()?, m.parse().ok()?)))
            .ok_or_else(|| StateError::Header(format!("shard `{shard}` is not I/M")))?;
        let wall = key_f64(&kv, "wall")?;
        let inputs = kv.get("inputs").map_or_else(Vec::new, |v| {
            v.split('\t')
                .map(|p| PathBuf::from(unescape_path(p)))
                .collect()
        });
        let r = &mut body;
        let direct = get_f64s(r, run.receivers as usize)?;
        let checks = [get_flags(r)?, get_flags(r)?, get_flags(r)?, get_flags(r)?];
        let headers = get_strings(r)?;
        let nrows = get_len(r)?;
        let rows = (0..nrows)
            .map(|_| get_strings(r))
            .collect::<Result<Vec<_>, _>>()?;
        let comment_lines = get_u64(r)?;
        let batches = read_batches(r)?;
        if !body.is_empty() {
            return Err(StateError::Damaged(format!(
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
            inputs,
        })
    }
}

/// Write batches as a state holds them: their count, then each batch's
/// index, chains, collisions, scores, sums, direct sums and near hits.
pub fn write_batches<W: Write>(w: &mut W, batches: &[Batch]) -> io::Result<()> {
    put_u64(w, batches.len() as u64)?;
    for b in batches {
        for x in [b.index, b.chains, b.collisions, b.scores] {
            put_u64(w, x)?;
        }
        put_f64v(w, &b.sums)?;
        put_f64v(w, &b.direct_sums)?;
        put_u64v(w, &b.near_hits)?;
    }
    Ok(())
}

/// Read batches written by [`write_batches`] from the front of `r`.
pub fn read_batches(r: &mut &[u8]) -> Result<Vec<Batch>, StateError> {
    let nb = get_len(r)?;
    let mut batches = Vec::with_capacity(nb);
    for _ in 0..nb {
        let (index, chains, collisions, scores) =
            (get_u64(r)?, get_u64(r)?, get_u64(r)?, get_u64(r)?);
        batches.push(Batch {
            index,
            chains,
            sums: get_f64v(r)?,
            collisions,
            scores,
            direct_sums: get_f64v(r)?,
            near_hits: get_u64v(r)?,
        });
    }
    Ok(batches)
}

/// A path as one header value: `%`, tab, CR and LF percent-escaped.
fn escape_path(p: &str) -> String {
    p.replace('%', "%25")
        .replace('\t', "%09")
        .replace('\r', "%0D")
        .replace('\n', "%0A")
}

/// The inverse of [`escape_path`]. Replacing one escape after another is
/// exact: an escaped `%` reads `%25`, so no other escape starts inside one,
/// and `%25` goes last.
fn unescape_path(s: &str) -> String {
    s.replace("%09", "\t")
        .replace("%0D", "\r")
        .replace("%0A", "\n")
        .replace("%25", "%")
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
                approximate: false,
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
            inputs: vec!["/data/a b%0A.toml".into(), "/p\tq\n%.csv".into()],
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
        assert_eq!(r.inputs, s.inputs);
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
            Err(StateError::Magic(_, _))
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
