"""Reference for acsl/dcm.csl (magnoliasci/PBPK, Dichloromethane/DCM.csl): closed-chamber
inhalation of dichloromethane by mice.

Transcribed (INITIAL in written order; CINT = 0.1, TSTOP = 24):
    VF = VFC*BW; VL = VLC*BW; VRT = 0.91*BW - VL - VF; QC = QCC*BW**0.74;
    QP = QPC*BW**0.74; QL = QLC*QC; QF = QFC*QC; QRT = QC - QF - QL;
    VMAX = VMAXC*BW**0.7; KF = KFC/BW**0.3; VCH = VCHC - NMICE*BW;
    ACH0 = VCH*CONC*MW/24450
    CRT = ART/VRT; CF = AF/VF; CL = AL/VL; CCH = ACH/VCH
    RVB = QL*CL/PL + QRT*CRT/PRT + QF*CF/PF;  CV = RVB/QC
    CA = (QC*CV + QP*CCH)/(QC + QP/PB);  CX = CA/PB
    ART' = QRT*(CA - CRT/PRT);  AF' = QF*(CA - CF/PF)
    AMS' = VMAX*CL/PL/(KM + CL/PL);  AML' = KF*CL/PL*VL
    AL' = QL*(CA - CL/PL) - AMS' - AML';  ACH' = QP*NMICE*(CX - CCH),  ACH(0) = ACH0
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .smooth import integrate

BW, QCC, QPC, QLC, QFC, VLC, VFC = 0.04, 19.0, 30.0, 0.24, 0.05, 0.04, 0.05
PB, PL, PF, PRT, MW, VMAXC, KM, KFC = 8.3, 1.7, 14.5, 1.0, 85.0, 14.0, 0.5, 2.0
NMICE, VCHC, CONC, TSTOP, CINT = 11.0, 9.1, 1500.0, 24.0, 0.1
VF = VFC * BW
VL = VLC * BW
VRT = 0.91 * BW - VL - VF
QC = QCC * BW**0.74
QP = QPC * BW**0.74
QL = QLC * QC
QF = QFC * QC
QRT = QC - QF - QL
VMAX = VMAXC * BW**0.7
KF = KFC / BW**0.3
VCH = VCHC - NMICE * BW
ACH0 = VCH * CONC * MW / 24450.0
STATES = ("ART", "AF", "AL", "AMS", "AML", "ACH")


def rhs(t: float, y: NDArray[np.float64]) -> list[float]:
    art, af, al, _, _, ach = y
    crt, cf, cl, cch = art / VRT, af / VF, al / VL, ach / VCH
    cv = (QL * cl / PL + QRT * crt / PRT + QF * cf / PF) / QC
    ca = (QC * cv + QP * cch) / (QC + QP / PB)
    rams = VMAX * cl / PL / (KM + cl / PL)
    raml = KF * cl / PL * VL
    return [QRT * (ca - crt / PRT), QF * (ca - cf / PF), QL * (ca - cl / PL) - rams - raml,
            rams, raml, QP * NMICE * (ca / PB - cch)]


def run() -> dict[str, NDArray[np.float64]]:
    t, y = integrate(rhs, [0.0] * 5 + [ACH0], TSTOP, CINT)
    return {"T": t} | {n: y[:, i] for i, n in enumerate(STATES)}
