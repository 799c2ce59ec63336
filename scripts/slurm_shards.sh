#!/usr/bin/env bash
# A sharded lumest run on a Slurm array: one job per shard, then one merge.
#
#   sbatch --array=0-15 scripts/slurm_shards.sh            # the shards
#   sbatch --dependency=afterok:<array job id> --wrap \
#       "lumest merge run/part_*.state --out run/office.csv"   # the merge
#
# Every shard runs the same scene, points, --chains and --seed; shard I of M
# traces batches I, I+M, I+2M, ... of the run and writes their state. The
# merge (shards in any order) writes the CSV a single run would have written,
# byte for byte, and refuses shards of different runs, missing or repeated
# shards, and damaged files. Any batch system works the same way: all it
# needs is the shard index.
#SBATCH --job-name=lumest-shard
#SBATCH --cpus-per-task=8
#SBATCH --time=01:00:00
set -euo pipefail
M=${SLURM_ARRAY_TASK_COUNT:?run as an array job}
I=${SLURM_ARRAY_TASK_ID:?run as an array job}
mkdir -p run
lumest illuminance --scene data/office.toml --points data/office_grid.csv \
    --chains 100000000 --seed 42 --threads "${SLURM_CPUS_PER_TASK:-0}" \
    --shard "$I/$M" --out "run/part_$I.state" --quiet
