//! `mpirun -np R lumest illuminance ... --mpi`: the batches of a run over R
//! MPI ranks. Rank r runs shard r/R ([`super::merge::shard_state`]: batches
//! r, r + R, ...; with `--rel-error` the ranks grow their own batches and
//! exchange the parts at every stage, so that all measure all 32 and plan
//! alike ([`crate::run::grow`]), and with an `--rms-error` planned on the
//! run's own first 32 batches they trace their shares of those and
//! exchange them, [`crate::run::RunConfig::share`]; where neither applies
//! every rank runs the same deterministic pilot), sends its state to rank 0, which folds all the
//! batches in index order ([`super::merge::merge_states`]) and writes
//! `--out`: byte for byte what one process writes. Built only with the
//! cargo feature `mpi` (the `mpi` crate over the system's MPI library).

use super::illuminance::IlluminanceArgs;

/// Run `lumest illuminance ... --mpi`.
#[cfg(feature = "mpi")]
pub fn run(a: &IlluminanceArgs) -> anyhow::Result<()> {
    use crate::tally::shard::ShardState;
    use mpi::datatype::PartitionMut;
    use mpi::traits::*;
    let universe =
        mpi::initialize().ok_or_else(|| anyhow::anyhow!("MPI was initialised already"))?;
    let world = universe.world();
    let (rank, size) = (world.rank(), world.size());
    let root = world.process_at_rank(0);
    // Rank 0 checks the output (it alone writes it) and tells the others,
    // so that a refused output stops every rank rather than leaving them
    // waiting in the gather.
    let check = if rank == 0 {
        let referenced = crate::scene::referenced_files(&a.scene);
        let mut inputs = vec![a.scene.as_path(), std::path::Path::new(&a.points)];
        inputs.extend(referenced.iter().map(|p| p.as_path()));
        super::outputs::check_outputs(&inputs, &[("--out", std::path::Path::new(&a.out))])
    } else {
        Ok(())
    };
    let mut refused = u8::from(check.is_err());
    root.broadcast_into(&mut refused);
    if refused != 0 {
        return check;
    }
    let t = std::time::Instant::now();
    // A rank that fails still takes part in the gather (with an empty state),
    // so that no rank waits forever; rank 0 then reports it.
    // An RMS plan measured on the run's first batches: each rank traces
    // its own among them and all ranks exchange them (called on this
    // thread, by every rank alike).
    let share = crate::run::Share(std::sync::Arc::new(move |own: Vec<crate::run::Batch>| {
        let world = mpi::topology::SimpleCommunicator::world();
        let mut bytes = Vec::new();
        crate::tally::shard::write_batches(&mut bytes, &own).expect("writing to memory");
        let mut lens = vec![0u64; size as usize];
        world.all_gather_into(&(bytes.len() as u64), &mut lens[..]);
        let counts: Vec<i32> = lens.iter().map(|&l| l as i32).collect();
        let displs = displacements(&counts);
        let mut all = vec![0u8; lens.iter().sum::<u64>() as usize];
        {
            let mut partition = PartitionMut::new(&mut all[..], counts.clone(), &displs[..]);
            world.all_gather_varcount_into(&bytes[..], &mut partition);
        }
        let mut batches = Vec::new();
        for (&d, &c) in displs.iter().zip(&counts) {
            let mut r = &all[d as usize..(d + c) as usize];
            batches.extend(
                crate::tally::shard::read_batches(&mut r).expect("batches a rank wrote just now"),
            );
        }
        batches
    }));
    let (bytes, failure) = match super::merge::shard_state(a, rank as u64, size as u64, Some(share))
    {
        Ok(state) => {
            let mut b = Vec::new();
            state.write(&mut b)?;
            (b, None)
        }
        Err(e) => (Vec::new(), Some(e)),
    };
    let len = bytes.len() as u64;
    if rank != 0 {
        root.gather_into(&len);
        root.gather_varcount_into(&bytes[..]);
        if let Some(e) = failure {
            return Err(e.context(format!("rank {rank}")));
        }
        return Ok(());
    }
    let mut lens = vec![0u64; size as usize];
    root.gather_into_root(&len, &mut lens[..]);
    let counts: Vec<i32> = lens.iter().map(|&l| l as i32).collect();
    let displs = displacements(&counts);
    let mut all = vec![0u8; lens.iter().sum::<u64>() as usize];
    {
        let mut partition = PartitionMut::new(&mut all[..], counts.clone(), &displs[..]);
        root.gather_varcount_into_root(&bytes[..], &mut partition);
    }
    if let Some(e) = failure {
        return Err(e.context("rank 0"));
    }
    let mut states = Vec::with_capacity(size as usize);
    for (r, (&d, &c)) in displs.iter().zip(&counts).enumerate() {
        anyhow::ensure!(c > 0, "rank {r} failed: see its message");
        let s = ShardState::read(&all[d as usize..(d + c) as usize])
            .map_err(|e| anyhow::anyhow!("rank {r}'s state: {e}"))?;
        states.push((format!("rank {r}"), s));
    }
    let gathered = t.elapsed().as_secs_f64();
    super::merge::merge_states(states, &a.out)?;
    eprintln!(
        "lumest: {size} MPI rank(s): {:.3} s to run and gather ({} bytes of batch state), {:.3} s in all",
        gathered,
        all.len(),
        t.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Where each rank's bytes start in a gather of `counts` bytes per rank.
#[cfg(feature = "mpi")]
fn displacements(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0i32, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect()
}

/// Without the `mpi` feature: a clear error.
#[cfg(not(feature = "mpi"))]
pub fn run(_a: &IlluminanceArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "--mpi needs a lumest built with MPI: `cargo build --release --features mpi` \
         (with an MPI library and libclang installed, e.g. Debian's libopenmpi-dev and libclang-dev)"
    )
}
