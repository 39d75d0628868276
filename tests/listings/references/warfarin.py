"""Reference for acsl/warfarin.csl (magnoliasci/PBPK, Warfarin/warfarin.csl): a warfarin
PBPK model with plasma binding and an oral dose.

Transcribed (CINT = 0.01, TSTOP = 100; `Tstop` in CONSTANT, `TSTOP` in TERMT: one name):
    BFPlas = 1 - FFPlas;  FFx = FFPlas/Px (x = R, S, L);  dose = frac*pdose*BW;
    Vx = VxC*BW;  QC = QCC*BW**0.74;  Qx = QxC*QC;  VMAX = VMAXC*BW**0.74
    CA = APlas/VPlas;  CF = CA*FFPlas;  CB = CA*BFPlas;  Cx = Ax/Vx;  CxF = Cx*FFx
    ASt' = -kas*ASt (ASt(0) = dose);  AR' = QR*(CF - CRF);  AS' = QS*(CF - CSF)
    RAM = VMAX*CLF/(KM + CLF);  AL' = QL*(CF - CLF) - RAM + kas*ASt;  AM' = RAM
    APlas' = QL*(CB + CLF) + QS*(CB + CSF) + QR*(CB + CRF) - QC*CA
The network conserves the dose: BAL = dose - (ASt + AS + AR + AL + AM + APlas) = 0.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .smooth import integrate

BW, VLC, VRC, VSC, VPLASC, QCC, QLC, QRC, QSC = 70.0, 0.03, 0.05, 0.79, 0.04, 9.0, 0.24, \
    0.52, 0.24
PR, PS, PL, VMAXC, KM, FFPLAS = 0.2, 0.02, 0.2, 1.7, 2.0, 0.008
TSTOP, PDOSE, KAS, FRAC, CINT = 100.0, 1.0, 1.0, 0.5, 0.01
BFPLAS = 1.0 - FFPLAS
FFR, FFS, FFL = FFPLAS / PR, FFPLAS / PS, FFPLAS / PL
DOSE = FRAC * PDOSE * BW
VL, VPLAS, VR, VS = VLC * BW, VPLASC * BW, VRC * BW, VSC * BW
QC = QCC * BW**0.74
QL, QR, QS = QLC * QC, QRC * QC, QSC * QC
VMAX = VMAXC * BW**0.74
STATES = ("AST", "AR", "AS", "AL", "AM", "APLAS")


def rhs(t: float, y: NDArray[np.float64]) -> list[float]:
    ast, ar, as_, al, _, aplas = y
    ca = aplas / VPLAS
    cf, cb = ca * FFPLAS, ca * BFPLAS
    crf, csf, clf = ar / VR * FFR, as_ / VS * FFS, al / VL * FFL
    ram = VMAX * clf / (KM + clf)
    return [-KAS * ast, QR * (cf - crf), QS * (cf - csf), QL * (cf - clf) - ram + KAS * ast,
            ram, QL * (cb + clf) + QS * (cb + csf) + QR * (cb + crf) - QC * ca]


def run() -> dict[str, NDArray[np.float64]]:
    t, y = integrate(rhs, [DOSE, 0, 0, 0, 0, 0], TSTOP, CINT)
    return {"T": t} | {n: y[:, i] for i, n in enumerate(STATES)}
