#!/usr/bin/env python3
"""Convergence order and FOM of `--qmc off|shift|owen` (issue 15 item 4).

For each case, chain count N and seed, runs
  lumest illuminance --scene S --points P --chains N --seed K --qmc Q --threads 1 --quiet
with the three methods interleaved (the machine is shared), and reports per
(case, method, N): R = RMS over points of the relative standard deviation of
E across seeds (and of E_indirect), the mean CPU time T (user + sys of the
run) and FOM = 1/(R^2 T); the convergence order is the least-squares slope
of log R against log N. Usage: measure.py [lumest binary] [seeds]
"""
import csv, math, os, subprocess, sys, resource, tempfile, time

BIN = sys.argv[1] if len(sys.argv) > 1 else "target/release/lumest"
SEEDS = int(sys.argv[2]) if len(sys.argv) > 2 else 10
CASES = [
    ("sobolev", "data/sobolev.toml", "data/sobolev_points.csv", [4096, 16384, 65536, 262144]),
    ("room", "validation/qmc/room.toml", "validation/qmc/room_points.csv", [4096, 16384, 65536, 262144]),
    ("office", "data/office.toml", "data/office_grid.csv", [4096, 16384, 65536]),
]
METHODS = ["off", "shift", "owen"]


def run(scene, points, n, seed, q, out):
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([BIN, "illuminance", "--scene", scene, "--points", points, "--chains", str(n),
                    "--seed", str(seed), "--qmc", q, "--threads", "1", "--quiet", "--out", out],
                   check=True, stderr=subprocess.DEVNULL)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    with open(out) as f:
        rows = list(csv.DictReader(f))
    return cpu, [float(r["E"]) for r in rows], [float(r["E_indirect"]) for r in rows]


def rel_rms(samples):
    """RMS over points of std/mean across runs."""
    k = len(samples)
    acc = []
    for col in zip(*samples):
        m = sum(col) / k
        v = sum((x - m) ** 2 for x in col) / (k - 1)
        acc.append(v / m ** 2)
    return math.sqrt(sum(acc) / len(acc))


def slope(xs, ys):
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def main():
    tmp = tempfile.mkdtemp()
    out = os.path.join(tmp, "o.csv")
    print(f"# {BIN}, {SEEDS} seeds, --threads 1, {time.strftime('%Y-%m-%d %H:%M:%S')}")
    print("| case | qmc | N | R(E) | R(E_ind) | T cpu [s] | FOM(E) [1/s] | FOM(E_ind) [1/s] |")
    print("|---|---|---|---|---|---|---|---|")
    summary = []
    for name, scene, points, ns in CASES:
        res = {q: [] for q in METHODS}
        for n in ns:
            data = {q: ([], [], []) for q in METHODS}
            for seed in range(1, SEEDS + 1):
                for q in METHODS:  # interleaved
                    cpu, e, ei = run(scene, points, n, seed, q, out)
                    data[q][0].append(cpu)
                    data[q][1].append(e)
                    data[q][2].append(ei)
            for q in METHODS:
                t = sum(data[q][0]) / SEEDS
                r, ri = rel_rms(data[q][1]), rel_rms(data[q][2])
                res[q].append((n, r, ri, t))
                print(f"| {name} | {q} | {n} | {r:.3e} | {ri:.3e} | {t:.3f} | {1/(r*r*t):.3e} | {1/(ri*ri*t):.3e} |",
                      flush=True)
        for q in METHODS:
            xs = [x[0] for x in res[q]]
            summary.append((name, q, slope(xs, [x[1] for x in res[q]]), slope(xs, [x[2] for x in res[q]])))
    print()
    print("| case | qmc | order of R(E) in N | order of R(E_ind) in N |")
    print("|---|---|---|---|")
    for name, q, s, si in summary:
        print(f"| {name} | {q} | {s:.3f} | {si:.3f} |")


main()
