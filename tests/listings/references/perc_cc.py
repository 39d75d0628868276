"""Reference for acsl/perc_cc.csl (magnoliasci/PBPK, OTSS2023/PERC_CC.csl): closed-chamber
uptake of tetrachloroethylene by a mouse.

Transcribed (no CINTERVAL: CINT = 0.1; TSTOP = 8):
    QSC = 1 - QFC - QLC - QRC;  VSC = 1 - VFC - VLC - VRC;  QC = QCC*BW**0.74;
    QP = QPC*BW**0.74;  Qx = QxC*QC, Vx = VxC*BW (x = F, L, R, S);  VCH = VCHC - MICE*BW;
    AI0 = CONC*VCH*MW/24451;  VMAX = VMAXC*BW**0.70
    CI = AI/VCH;  CVx = Ax/(Vx*Px);  CV = (QF*CVF + QL*CVL + QS*CVS + QR*CVR)/QC
    CA = (QP*CI + QC*CV)/(QC + QP/PB);  CX = CA/PB;  RAM = VMAX*CVL/(KM + CVL)
    AI' = MICE*QP*(CX - CI);  AF' = QF*(CA - CVF);  AL' = QL*(CA - CVL) - RAM;
    AS' = QS*(CA - CVS);  AR' = QR*(CA - CVR)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .smooth import integrate

MW, CONC, VCHC, MICE, BW = 165.85, 200.0, 0.7, 1.0, 0.035
QCC, QPC, QFC, QLC, QRC = 18.0, 30.0, 0.07, 0.16, 0.59
VFC, VLC, VRC = 0.07, 0.057, 0.21
PF, PL, PR, PS, PB = 70.37, 2.34, 2.34, 3.69, 21.47
KM, VMAXC, TSTOP, CINT = 0.45, 1.0, 8.0, 0.1
QSC = 1 - QFC - QLC - QRC
VSC = 1 - VFC - VLC - VRC
QC = QCC * BW**0.74
QP = QPC * BW**0.74
QF, QL, QR, QS = QFC * QC, QLC * QC, QRC * QC, QSC * QC
VF, VL, VR, VS = VFC * BW, VLC * BW, VRC * BW, VSC * BW
VCH = VCHC - MICE * BW
AI0 = CONC * VCH * MW / 24451.0
VMAX = VMAXC * BW**0.70
STATES = ("AI", "AF", "AL", "AS", "AR")


def rhs(t: float, y: NDArray[np.float64]) -> list[float]:
    ai, af, al, as_, ar = y
    ci = ai / VCH
    cvf, cvl, cvs, cvr = af / (VF * PF), al / (VL * PL), as_ / (VS * PS), ar / (VR * PR)
    cv = (QF * cvf + QL * cvl + QS * cvs + QR * cvr) / QC
    ca = (QP * ci + QC * cv) / (QC + QP / PB)
    ram = VMAX * cvl / (KM + cvl)
    return [MICE * QP * (ca / PB - ci), QF * (ca - cvf), QL * (ca - cvl) - ram,
            QS * (ca - cvs), QR * (ca - cvr)]


def run() -> dict[str, NDArray[np.float64]]:
    t, y = integrate(rhs, [AI0, 0.0, 0.0, 0.0, 0.0], TSTOP, CINT)
    return {"T": t} | {n: y[:, i] for i, n in enumerate(STATES)}
