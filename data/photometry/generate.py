#!/usr/bin/env python3
"""Write the photometric test files of data/photometry/ (see README.md there).

Every file tabulates a known analytic distribution, so that tests can check
the parsed intensities and flux against it. Run from the repository root:
    python3 data/photometry/generate.py
Type C files: I = I0 cos(gamma) (1 + f(C)) for gamma <= 90 deg, zero above,
with f depending on the symmetry the file stores; every f integrates to
zero over C, so the flux is pi I0. Types B and A: I = I0 cos(H) cos(V)
(1 + 0.4 sin H), flux pi I0 (type B: V the plane's angle, H the lateral
one; type A: H the plane's angle, V the one out of it).
I0 = 1000 cd.
"""
import math

I0 = 1000.0
OUT = "data/photometry/"


def f_of(sym):
    return {
        "rot": lambda c: 0.0,
        "quad": lambda c: 0.3 * math.cos(2 * c),
        "c0180": lambda c: 0.3 * math.cos(c),
        "c90270": lambda c: 0.3 * math.sin(c),
        "full": lambda c: 0.3 * math.cos(c) + 0.2 * math.sin(2 * c),
    }[sym]


def type_c(sym, c_deg, g_deg):
    f = f_of(sym)
    return [[I0 * max(math.cos(math.radians(g)), 0.0) * (1 + f(math.radians(c))) if g <= 90 else 0.0
             for g in g_deg] for c in c_deg]


C_GRID = {
    "rot": [0.0],
    "quad": [15.0 * k for k in range(7)],
    "c0180": [15.0 * k for k in range(13)],
    "c90270": [90.0 + 15.0 * k for k in range(13)],
    "full": [15.0 * k for k in range(25)],
}
GAMMA = [5.0 * k for k in range(19)]  # 0..90


def wrap(values, per_line=7):
    """Numbers as a token stream wrapped every few values (LM-63 allows any wrap)."""
    out, line = [], []
    for v in values:
        line.append(f"{v:.6f}".rstrip("0").rstrip(".") if isinstance(v, float) else str(v))
        if len(line) == per_line:
            out.append(" ".join(line))
            line = []
    if line:
        out.append(" ".join(line))
    return "\n".join(out)


def ies(name, header, sym, ptype=1, lumens=-1, tilt="TILT=NONE", h=None, v=None, table=None,
        line11="1.0 1.0 20"):
    h = C_GRID[sym] if h is None else h
    v = GAMMA if v is None else v
    table = type_c(sym, h, v) if table is None else table
    lines = []
    if header:
        lines.append(header)
        lines.append("[TEST] lumest test file")
        lines.append(f"[LUMINAIRE] {name}")
    else:
        lines.append(f"lumest test file {name} (LM-63-1986: no header line)")
    lines.append(tilt)
    lines.append(f"1 {lumens} 1 {len(v)} {len(h)} {ptype} 2 0.2 0.3 0")
    lines.append(line11)
    lines.append(wrap(v))
    lines.append(wrap(h))
    for row in table:
        lines.append(wrap(row))
    with open(OUT + name, "w", newline="\r\n") as fh:
        fh.write("\n".join(lines) + "\n")


def type_ba(h_deg, v_deg):
    # Asymmetric in H (not in V), so that a reader swapping the two gives
    # other values; the flux stays pi I0 in either reading (sin H
    # integrates to 0 against cos H and cos^2 H over [-90, 90]).
    return [[I0 * math.cos(math.radians(hh)) * math.cos(math.radians(vv))
             * (1.0 + 0.4 * math.sin(math.radians(hh))) for vv in v_deg] for hh in h_deg]


# One file per LM-63 version (rotational), then every symmetry, types A and B,
# TILT=INCLUDE, absolute photometry.
ies("lm63_1986.ies", None, "rot", lumens=1000)
ies("lm63_1991.ies", "IESNA91", "rot", lumens=1000)
ies("lm63_1995.ies", "IESNA:LM-63-1995", "rot", lumens=1000, line11="1.0 1.0 20")
ies("lm63_2002.ies", "IESNA:LM-63-2002", "rot", lumens=1000)
# 2019: the second number of line 11 is the file generation type (1.10001): never a factor.
ies("lm63_2019.ies", "IES:LM-63-2019", "rot", lumens=1000, line11="1.0 1.10001 20")
ies("sym_quadrant.ies", "IESNA:LM-63-2002", "quad")
ies("sym_c0_c180.ies", "IESNA:LM-63-2002", "c0180")
ies("sym_c90_c270.ies", "IESNA:LM-63-2002", "c90270")
ies("sym_full.ies", "IESNA:LM-63-2002", "full")
HV = [10.0 * k - 90.0 for k in range(19)]
ies("type_b.ies", "IESNA:LM-63-2002", "rot", ptype=2, h=HV, v=HV, table=type_ba(HV, HV))
ies("type_a.ies", "IESNA:LM-63-2002", "rot", ptype=3, h=HV, v=HV, table=type_ba(HV, HV))
# TILT=INCLUDE with factor 1 at 0 degrees (lamp-to-luminaire geometry 1, 3 angles).
ies("tilt_include.ies", "IESNA:LM-63-1995", "rot", lumens=1000,
    tilt="TILT=INCLUDE\n1\n3\n0 45 90\n1.0 0.9 0.8")
# The pair: the full distribution also as EULUMDAT (below).
ies("pair.ies", "IESNA:LM-63-2002", "full", lumens=-1)


def ldt(name, isym, sym, lamp_sets=1, absolute=False, comma=False):
    mc, dc, ng, dg = 24, 15.0, 19, 5.0
    flux = 1000.0
    c_all = [dc * k for k in range(mc)]
    stored = {
        0: list(range(mc)),
        1: [0],
        2: list(range(mc // 2 + 1)),
        3: [(3 * mc // 4 + k) % mc for k in range(mc // 2 + 1)],
        4: list(range(mc // 4 + 1)),
    }[isym]
    rows = type_c(sym, [c_all[k] for k in stored], GAMMA)
    # cd/klm for a lamp flux of 1000 lm: the same numbers as cd.
    lines = ["lumest test file", "1", str(isym), str(mc), f"{dc}", str(ng), f"{dg}",
             "T-1", name, "1", name, "2026-11-23",
             "300", "0", "50", "300", "0", "0", "0", "0", "0",
             "100", "100", "1.0", "0", str(lamp_sets)]
    count = "-1" if absolute else "1"
    sets = [(count, "LED A", f"{flux}", "3000K", "80", "20")]
    for k in range(1, lamp_sets):
        sets.append(("1", f"LED alt {k}", f"{flux * (1 + k)}", "4000K", "90", f"{20 + k}"))
    for field in range(6):
        lines += [s[field] for s in sets]
    lines += ["0.5"] * 10
    lines += [f"{c}" for c in c_all]
    lines += [f"{g}" for g in GAMMA]
    for row in rows:
        lines += [f"{x:.6f}" for x in row]
    text = "\n".join(lines) + "\n"
    if comma:
        text = text.replace(".", ",")
    with open(OUT + name, "w", newline="\r\n") as fh:
        fh.write(text)


ldt("isym0.ldt", 0, "full")
ldt("isym1.ldt", 1, "rot")
ldt("isym2.ldt", 2, "c0180")
ldt("isym3.ldt", 3, "c90270")
ldt("isym4.ldt", 4, "quad")
ldt("lamp_sets.ldt", 1, "rot", lamp_sets=3)
ldt("absolute_commas.ldt", 1, "rot", absolute=True, comma=True)
ldt("pair.ldt", 0, "full")
