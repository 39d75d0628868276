"""Reference for acsl/flow_limited_fat.csl (magnoliasci/PBPK, Isolated Flow-Limited Fat).

An isolated, perfused fat compartment: inflow concentration CIN until TCHNG, zero after.
Transcribed (Magnolia's `IF(T >= TCHNG)` ... `END` block in DERIVATIVE):

    QC = QCC*BW**0.7;  QF = QFC*QC;  VF = VFC*BW;  CIN0 = CIN (INITIAL)
    IF (T >= TCHNG) CIN0 = 0.0               a test on T alone: a breakpoint at TCHNG
    RAF = QF*(CIN0 - CVF);  AF = INTEG(RAF, 0);  CF = AF/VF;  CVF = CF/PF
    TOTAL = INTEG(QF*CIN0, 0);  OUT = INTEG(QF*CVF, 0);  TMASS = OUT + AF
    TERMT(T >= TSTOP)                        TSTOP = 24;  CINTERVAL CINT = 0.1

Closed form (exact): with lam = QF/(VF*PF) and Amax = VF*PF*CIN,
    AF = Amax*(1 - exp(-lam t))                              t <= TCHNG
    AF = AF(TCHNG)*exp(-lam (t - TCHNG))                    t >= TCHNG
    TOTAL = QF*CIN*min(t, TCHNG);  OUT = TOTAL - AF  (mass balance: TMASS = TOTAL).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

BW, QCC, VFC, QFC, PF = 0.25, 15.0, 0.10, 0.06, 350.0
CIN, TSTOP, TCHNG, CINT = 1.0, 24.0, 12.0, 0.1
QC = QCC * BW**0.7
QF = QFC * QC
VF = VFC * BW


def output_times() -> NDArray[np.float64]:
    return np.linspace(0.0, TSTOP, int(round(TSTOP / CINT)) + 1)


def solution(t: NDArray[np.float64] | float) -> dict[str, NDArray[np.float64]]:
    t = np.asarray(t, dtype=float)
    lam = QF / (VF * PF)
    amax = VF * PF * CIN
    a_chng = amax * (1.0 - np.exp(-lam * TCHNG))
    af = np.where(t <= TCHNG, amax * (1.0 - np.exp(-lam * t)),
                  a_chng * np.exp(-lam * (t - TCHNG)))
    total = QF * CIN * np.minimum(t, TCHNG)
    out = total - af
    return {"T": t, "AF": af, "CF": af / VF, "CVF": af / (VF * PF), "TOTAL": total,
            "OUT": out, "TMASS": out + af,
            "CIN0": np.where(t < TCHNG, CIN, 0.0)}


def run() -> dict[str, NDArray[np.float64]]:
    return solution(output_times())
