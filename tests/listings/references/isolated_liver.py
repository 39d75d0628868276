"""Reference for acsl/isolated_liver.csl (magnoliasci/PBPK, Isolated Perfused Liver).

Transcribed (INITIAL: QC = QCC*BW**0.7, QL = QLC*QC, VL = VLC*BW, CINT = TSTOP/POINTS):
    CL = AL/VL;  CVL = CL/PL;  RAM = VMAXC*CVL/(KM + CVL)   (VMAXC, not VMAX: as written)
    AL' = QL*(CIN - CVL) - RAM;  AM' = RAM;  TOTAL' = QL*CIN;  OUT' = QL*CL/PL
    HE = (CIN - CVL)/CIN;  TMASS = OUT + AL + RAM            (RAM, a rate: as written)
    TERMT(T >= TSTOP, 'simulation stopped on time')   TSTOP = 6, POINTS = 100
A smooth system: a tight Radau solve (smooth.integrate).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .smooth import integrate

BW, QCC, VLC, QLC = 0.25, 15.0, 0.03, 0.20
PL, VMAXC, KM = 5.0, 5.0, 0.5
CIN, TSTOP, POINTS = 1.0, 6.0, 100.0
CINT = TSTOP / POINTS
QC = QCC * BW**0.7
QL = QLC * QC
VL = VLC * BW
STATES = ("AL", "AM", "TOTAL", "OUT")


def _algebra(al):
    cl = al / VL
    cvl = cl / PL
    ram = VMAXC * cvl / (KM + cvl)
    return cl, cvl, ram


def rhs(t: float, y: NDArray[np.float64]) -> list[float]:
    al = y[0]
    cl, cvl, ram = _algebra(al)
    return [QL * (CIN - cvl) - ram, ram, QL * CIN, QL * cl / PL]


def run() -> dict[str, NDArray[np.float64]]:
    t, y = integrate(rhs, [0.0] * 4, TSTOP, CINT)
    out = {"T": t} | {n: y[:, i] for i, n in enumerate(STATES)}
    cl, cvl, ram = _algebra(out["AL"])
    out["HE"] = (CIN - cvl) / CIN
    out["TMASS"] = out["OUT"] + out["AL"] + ram
    return out
