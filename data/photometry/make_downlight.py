#!/usr/bin/env python3
"""Write data/downlight.ldt: a recessed LED downlight, EULUMDAT, rotationally
symmetric (Isym 1), I = I0 cos(gamma)^1.5 below the horizon and nothing above,
1800 lm of LED, light output ratio 100 %, round luminous opening 150 mm.

The table is in cd/klm: the flux of I0 cos^1.5 is 2 pi I0 / 2.5, so
I0 = 1000 * 2.5 / (2 pi) cd/klm. Run from the repository root:
    python3 data/photometry/make_downlight.py
"""
import math

i0 = 1000 * 2.5 / (2 * math.pi)
gammas = [5 * k for k in range(19)]  # 0..90 degrees
values = [i0 * max(math.cos(math.radians(g)), 0.0) ** 1.5 for g in gammas]
lines = [
    "lumest example luminaires",  # 1 company
    "1",  # 2 Ityp: point source, symmetric about the vertical axis
    "1",  # 3 Isym
    "24", "15",  # 4-5 Mc, Dc
    "19", "5",  # 6-7 Ng, Dg
    "LE-1", "Recessed LED downlight 150", "DL150", "downlight.ldt", "2026-11-23 lumest",  # 8-12
    "200", "0", "100",  # 13-15 luminaire diameter, width (0: round), height [mm]
    "150", "0", "0", "0", "0", "0",  # 16-21 luminous area diameter, width, heights [mm]
    "100", "100", "1.0", "0",  # 22-25 DFF, LOR, CFLI, tilt
    "1",  # 26 lamp sets
    "1", "LED", "1800", "3000K", "80", "15",  # number, type, flux [lm], colour, CRI, watts
]
lines += ["0.5"] * 10  # direct ratios
lines += [str(15 * k) for k in range(24)]
lines += [str(g) for g in gammas]
lines += [f"{v:.3f}" for v in values]
with open("data/downlight.ldt", "w", newline="\r\n") as f:
    f.write("\n".join(lines) + "\n")
