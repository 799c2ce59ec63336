#!/usr/bin/env python3
"""Coverage of lumest's 95 % intervals over independent runs, against a reference run.

Runs `lumest illuminance` once per seed (SEED0, SEED0 + 1, ...) with the given stopping
rule, and compares every point's E with the reference CSV's: z = (E - E_ref) /
hypot(E_stderr, E_ref_stderr), covered when |E - E_ref| <= hypot(E_ci95, 1.96 E_ref_stderr)
(E_ci95 is the run's own Student-t half-width). Prints the coverage and mean z^2 over all
rows, their means and standard errors over runs (the points of a run share its chains, so
only the runs are independent), the coverage per flag, the mean z, and the point whose
mean z lies farthest from 0 in standard errors. With --dump, writes seed,point,flag,z rows.

Example (the README's calibration table; a reference of 16,777,216 chains first):

    lumest illuminance --scene data/office.toml --points data/office_grid.csv \
        --out ref.csv --chains 16777216 --seed 777 --quiet
    python3 validation/calibration/coverage.py --lumest target/release/lumest \
        --scene data/office.toml --points data/office_grid.csv --reference ref.csv \
        --runs 200 -- --rel-error 5e-3

Everything after `--` is passed to each run. Plain Python 3, no packages.
"""

import argparse
import csv
import math
import os
import statistics
import subprocess
import sys
import tempfile


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lumest", default="target/release/lumest")
    ap.add_argument("--scene", required=True)
    ap.add_argument("--points", required=True)
    ap.add_argument("--reference", required=True, help="CSV of a long run at the same points")
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--seed0", type=int, default=1001)
    ap.add_argument("--dump", help="write seed,point,flag,z rows here")
    ap.add_argument("rule", nargs=argparse.REMAINDER, help="-- then the run's stopping rule")
    a = ap.parse_args()
    rule = a.rule[1:] if a.rule[:1] == ["--"] else a.rule
    if not rule:
        sys.exit("give the run's stopping rule after --, e.g. -- --rel-error 5e-3")

    ref = [(float(r["E"]), float(r["E_stderr"])) for r in rows(a.reference)]
    dump = open(a.dump, "w") if a.dump else None
    out = os.path.join(tempfile.mkdtemp(prefix="lumest_coverage_"), "run.csv")
    all_z2, all_z, run_z2, run_cov = [], [], [], []
    per_flag = {}
    per_point = [[] for _ in ref]
    covered_total = 0
    for seed in range(a.seed0, a.seed0 + a.runs):
        cmd = [a.lumest, "illuminance", "--scene", a.scene, "--points", a.points,
               "--out", out, "--seed", str(seed), "--quiet"] + rule
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        run = rows(out)
        if len(run) != len(ref):
            sys.exit(f"seed {seed}: {len(run)} rows against the reference's {len(ref)}")
        z2_run, cov_run = [], 0
        for k, ((e0, s0), r) in enumerate(zip(ref, run)):
            e, se, ci = float(r["E"]), float(r["E_stderr"]), float(r["E_ci95"])
            sd = math.hypot(se, s0)
            # A row with no spread on either side (an unlit point) counts as z = 0
            # when it agrees exactly, and as an infinite z otherwise: never dropped.
            z = (e - e0) / sd if sd > 0 else (0.0 if e == e0 else math.inf)
            covered = abs(e - e0) <= math.hypot(ci, 1.959964 * s0)
            cov_run += covered
            covered_total += covered
            z2_run.append(z * z)
            all_z.append(z)
            per_point[k].append(z)
            n, c = per_flag.get(r["E_flag"], (0, 0))
            per_flag[r["E_flag"]] = (n + 1, c + covered)
            if dump:
                dump.write(f"{seed},{k},{r['E_flag']},{z:.6f}\n")
        all_z2 += z2_run
        run_z2.append(statistics.mean(z2_run))
        run_cov.append(cov_run / len(run))
    n = len(all_z)
    se = lambda v: statistics.stdev(v) / math.sqrt(len(v)) if len(v) > 1 else math.nan
    print(f"{a.runs} runs x {len(ref)} points: coverage {covered_total / n:.4f} "
          f"(+- {se(run_cov):.4f} over runs), mean z^2 {statistics.mean(all_z2):.3f} "
          f"(+- {se(run_z2):.3f}), mean z {statistics.mean(all_z):+.3f}, "
          f"largest |z| {max(abs(z) for z in all_z):.2f}")
    print("coverage by flag: " + ", ".join(
        f"{f or '(none)'} {c / m:.4f} of {m}" for f, (m, c) in sorted(per_flag.items())))
    if a.runs > 1:
        k, t = max(((k, statistics.mean(v) / se(v)) for k, v in enumerate(per_point) if se(v) > 0),
                   key=lambda kt: abs(kt[1]), default=(None, 0.0))
        print(f"farthest point mean z: point {k} (0-based row), {t:+.2f} standard errors")


if __name__ == "__main__":
    main()
