//! A checkpoint of a run in progress: the tallies after its first `F`
//! batches, from which `--resume` continues with batch `F` and ends with
//! the result an uninterrupted run would have given, bit for bit.
//!
//! # File format (version 1)
//!
//! The encoding of [`super::state_file`]: the header names the run (as a
//! shard state's does: batches, batch size, chains, seed, orders,
//! receivers, the hashes of the compiled scene and of the points, the
//! settings, and `approximate = 1` where the scene's lights approximate it)
//! and adds `folded = F` (batches folded), `chains_done`,
//! `collisions`, `scores` and `wall` (seconds so far); the body holds the
//! tallies: every accumulator's exact state (count, then mean, M2, M3, M4,
//! min, max as f64 bits) for the estimated part, the sampled direct light
//! and each order bucket, the FOM snapshots, the `sparse` counts, the
//! per-receiver checks and the kept batch means of grid points (for the
//! grid figures); then the checksum trailer.

use super::state_file::*;
use super::{Tallies, Welford};
use std::io::{self, Write};

pub use super::state_file::{RunIdentity, StateError};

/// The first line of a checkpoint file.
pub const MAGIC: &str = "lumest checkpoint 1";

/// A run's state after `folded` batches.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// Which run.
    pub run: RunIdentity,
    /// Batches folded (batches `0 .. folded`).
    pub folded: u64,
    /// Chains traced in them.
    pub chains: u64,
    /// Collisions in them.
    pub collisions: u64,
    /// Receiver scores evaluated in them.
    pub scores: u64,
    /// Wall time so far \[s\].
    pub wall: f64,
    /// The tallies.
    pub tallies: Tallies,
}

fn put_welfords<W: Write>(w: &mut W, v: &[Welford]) -> io::Result<()> {
    put_u64(w, v.len() as u64)?;
    for a in v {
        let (n, x) = a.to_parts();
        put_u64(w, n)?;
        x.iter().try_for_each(|x| w.write_all(&x.to_le_bytes()))?;
    }
    Ok(())
}

fn get_welfords(r: &mut &[u8]) -> Result<Vec<Welford>, StateError> {
    let n = get_len(r)?;
    (0..n)
        .map(|_| {
            let c = get_u64(r)?;
            let x = get_f64s(r, 6)?;
            Ok(Welford::from_parts(c, x.try_into().expect("six")))
        })
        .collect()
}

impl Checkpoint {
    /// Write the checkpoint (format in the module docs).
    pub fn write<W: Write>(&self, w: W) -> io::Result<()> {
        let mut w = hashing(w);
        let extra = [
            ("folded", self.folded.to_string()),
            ("chains_done", self.chains.to_string()),
            ("collisions", self.collisions.to_string()),
            ("scores", self.scores.to_string()),
            ("wall", format!("{:e}", self.wall)),
        ];
        write_header(&mut w, MAGIC, &self.run, &extra)?;
        let t = &self.tallies;
        put_welfords(&mut w, &t.estimated)?;
        put_welfords(&mut w, &t.sampled_direct)?;
        put_u64(&mut w, t.orders.len() as u64)?;
        for b in &t.orders {
            put_welfords(&mut w, b)?;
        }
        put_u64(&mut w, t.snapshots.len() as u64)?;
        for (b, v) in &t.snapshots {
            put_u64(&mut w, *b)?;
            put_f64v(&mut w, v)?;
        }
        put_u64v(&mut w, &t.near_hits)?;
        for f in [&t.watched, &t.near_plain, &t.near_reach, &t.enclosed] {
            put_flags(&mut w, f)?;
        }
        let flat: Vec<u64> = t.near_vertices.iter().flatten().copied().collect();
        put_u64v(&mut w, &flat)?;
        put_u64(&mut w, t.batch_means.receivers() as u64)?;
        put_f64v(&mut w, t.batch_means.values())?;
        finish(w)
    }

    /// Read a checkpoint written by [`Self::write`] (all of `bytes`).
    pub fn read(bytes: &[u8]) -> Result<Self, StateError> {
        let (kv, run, mut body) = open(bytes, MAGIC, "checkpoint")?;
        let r = &mut body;
        let estimated = get_welfords(r)?;
        let sampled_direct = get_welfords(r)?;
        let nb = get_len(r)?;
        let orders = (0..nb)
            .map(|_| get_welfords(r))
            .collect::<Result<Vec<_>, _>>()?;
        let ns = get_len(r)?;
        let snapshots = (0..ns)
            .map(|_| Ok((get_u64(r)?, get_f64v(r)?)))
            .collect::<Result<Vec<_>, StateError>>()?;
        let near_hits = get_u64v(r)?;
        let [watched, near_plain, near_reach, enclosed] =
            [get_flags(r)?, get_flags(r)?, get_flags(r)?, get_flags(r)?];
        let flat = get_u64v(r)?;
        let kept = get_u64(r)? as usize;
        let batch_means = super::batch_means::BatchMeans::from_values(kept, get_f64v(r)?);
        // Every per-receiver list one per receiver (or empty where a run
        // keeps none), the order tallies as the header's orders make them,
        // the batch means whole batches of at most every receiver: a
        // checkpoint edited by hand with its checksum made good is refused
        // here, not met later as a panic.
        let n = estimated.len();
        let buckets = if run.orders == 0 {
            0
        } else {
            run.orders as usize + 1
        };
        let per_receiver = |len: usize| len == 0 || len == n;
        let fits = body.is_empty()
            && n as u64 == run.receivers
            && per_receiver(sampled_direct.len())
            && orders.len() == buckets
            && orders.iter().all(|o| o.len() == n)
            && snapshots.iter().all(|(_, v)| v.len() == n)
            && near_hits.len() == n
            && [&watched, &near_plain, &near_reach, &enclosed]
                .iter()
                .all(|f| per_receiver(f.len()))
            && flat.len() == 2 * n
            && kept <= n
            && batch_means.batches() * kept == batch_means.values().len();
        if !fits {
            return Err(StateError::Damaged(
                "the tallies do not fit the header".into(),
            ));
        }
        let tallies = Tallies {
            estimated,
            sampled_direct,
            orders,
            snapshots,
            near_hits,
            watched,
            near_plain,
            near_reach,
            enclosed,
            near_vertices: flat.chunks(2).map(|c| [c[0], c[1]]).collect(),
            batch_means,
            approximate: run.approximate,
        };
        Ok(Self {
            run,
            folded: key_u64(&kv, "folded")?,
            chains: key_u64(&kv, "chains_done")?,
            collisions: key_u64(&kv, "collisions")?,
            scores: key_u64(&kv, "scores")?,
            wall: key_f64(&kv, "wall")?,
            tallies,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_every_bit_and_damage_is_refused() {
        let mut t = Tallies::new(3, 2);
        let mut means = vec![0.0; 9];
        for b in 0..40 {
            let sums: Vec<f64> = (0..9).map(|k| ((b * 9 + k) as f64).sin() * 1e3).collect();
            t.fold(&sums, &[1.0, 2.0, b as f64], 100, &[1, 2, 3], &mut means);
            if b == 31 {
                t.snapshot(&[0.5, 0.0, 1e-300]);
            }
        }
        t.enclosed = vec![false, true, false];
        let c = Checkpoint {
            run: RunIdentity {
                batches: 64,
                batch_size: 100,
                chains: 6400,
                seed: 9,
                orders: 2,
                receivers: 3,
                scene: 1,
                points: 2,
                config: "x".into(),
                approximate: false,
            },
            folded: 40,
            chains: 4000,
            collisions: 12345,
            scores: 678,
            wall: 1.5,
            tallies: t.clone(),
        };
        let mut bytes = Vec::new();
        c.write(&mut bytes).unwrap();
        let r = Checkpoint::read(&bytes).unwrap();
        assert_eq!(r.run, c.run);
        assert_eq!(
            (r.folded, r.chains, r.collisions, r.scores, r.wall),
            (40, 4000, 12345, 678, 1.5)
        );
        let parts = |v: &[Welford]| v.iter().map(|w| w.to_parts()).collect::<Vec<_>>();
        assert_eq!(parts(&r.tallies.estimated), parts(&t.estimated));
        assert_eq!(parts(&r.tallies.sampled_direct), parts(&t.sampled_direct));
        for (a, b) in r.tallies.orders.iter().zip(&t.orders) {
            assert_eq!(parts(a), parts(b));
        }
        assert_eq!(r.tallies.snapshots, t.snapshots);
        assert_eq!(r.tallies.near_hits, t.near_hits);
        assert_eq!(r.tallies.enclosed, t.enclosed);
        assert_eq!(r.tallies.near_vertices, t.near_vertices);
        for cut in [0, 10, bytes.len() / 2, bytes.len() - 1] {
            assert!(Checkpoint::read(&bytes[..cut]).is_err());
        }
        let mut b = bytes.clone();
        let k = b.len() - 20;
        b[k] ^= 4;
        assert!(Checkpoint::read(&b).is_err());
        // Well made, checksum and all, but the tallies do not fit the
        // header: refused (before, the resumed run met them as a panic).
        let misfit = |edit: &dyn Fn(&mut Checkpoint)| {
            let mut e = c.clone();
            edit(&mut e);
            let mut bytes = Vec::new();
            e.write(&mut bytes).unwrap();
            Checkpoint::read(&bytes).err()
        };
        assert!(misfit(&|_| {}).is_none());
        assert!(misfit(&|e| e.run.orders = 3).is_some());
        assert!(misfit(&|e| e.run.orders = 0).is_some());
        assert!(misfit(&|e| e.tallies.orders[1].pop().map(|_| ()).unwrap()).is_some());
        assert!(misfit(&|e| e.tallies.sampled_direct.truncate(2)).is_some());
        assert!(misfit(&|e| e.tallies.watched.push(true)).is_some());
        assert!(misfit(&|e| e.tallies.near_vertices.push([1, 2])).is_some());
        assert!(misfit(&|e| e.tallies.near_vertices.clear()).is_some());
        assert!(misfit(&|e| e.tallies.near_hits.clear()).is_some());
        assert!(misfit(&|e| e.tallies.snapshots[0].1.push(0.0)).is_some());
        assert!(
            misfit(
                &|e| e.tallies.batch_means = crate::tally::BatchMeans::from_values(2, vec![1.0; 5])
            )
            .is_some()
        );
        assert!(
            misfit(
                &|e| e.tallies.batch_means = crate::tally::BatchMeans::from_values(2, vec![1.0; 6])
            )
            .is_none()
        );
    }
}
