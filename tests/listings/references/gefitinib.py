"""Reference for acsl/gefitinib.csl (magnoliasci/PBPK, Gefitinib/gefitinib.csl).

Hybrid PK / tumour PBPK / PD model of Wang et al., Mol Cancer Ther 2008;7(2), as the
Magnolia listing writes it (ACSL form; INITIAL nested inside DYNAMIC; CONSTANTs inside
DERIVATIVE). Transcribed:

    INITIAL:  SCHEDULE startdose AT 0.0;  SCHEDULE enddose AT 0.01;  IVrate = 0
    DISCRETE startdose:  IVrate = (IVDOSE*BW/0.01)/Vc      a 0.01 h IV infusion
    DISCRETE enddose:    IVrate = 0
    POrate = F*Ka*PODOSE*exp(-Ka*t)/Vc                      (PODOSE = 0: zero)
    C1' = IVrate + POrate - C1*K12 + C2*K21 - C1*K10        C1(0) = C10 = 0
    C2' = C1*K12 - C2*K21                                   C2(0) = C20 = 0
    Cp  = 1000*C1
    Ct' = Q*(Cp - Ct/Ri)/Vt                                 Ct(0) = Ct0 = 0
    pEGFR' = Kin*(pEGFR0 - Imax*Ct/(IC50 + Ct)) - Ktr*pEGFR pEGFR(0) = pEGFR0 = 1
    pERK'  = Ktr*pEGFR - Kout*pERK                          pERK(0) = pERK0 = 1
    TERMT(T >= TSTOP, 'Time limit.')   TSTOP = 50;  CINTERVAL CINT = 0.05

The start dose is due at t0, so it runs before the first row (contract section 9: events
due at t0 come before the first output row); the end dose is a scheduled event at 0.01,
between the first two rows. Integration: piecewise.integrate_piecewise, rtol 1e-10.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .piecewise import integrate_piecewise

IVDOSE, PODOSE, BW, VC, VT = 10.0, 0.0, 0.02, 75.0, 1.3
F, KA = 0.45, 0.88
K10, K12, K21 = 0.85, 1.57, 0.41
C10 = C20 = 0.0
Q, RI, CT0 = 4.5, 8.2, 0.0
PEGFR0, IMAX, IC50, KIN, KOUT, KTR = 1.0, 1.0, 12.1, 3.6, 3.3, 0.92
PERK0 = 1.0
TSTOP, CINT = 50.0, 0.05
T_START, T_END = 0.0, 0.01
STATES = ("C1", "C2", "CT", "PEGFR", "PERK")


def rhs(t: float, y: NDArray[np.float64], inputs: dict) -> NDArray[np.float64]:
    c1, c2, ct, pegfr, perk = y
    porate = F * KA * PODOSE * np.exp(-KA * t) / VC
    cp = 1000.0 * c1
    return np.array([
        inputs["IVRATE"] + porate - c1 * K12 + c2 * K21 - c1 * K10,
        c1 * K12 - c2 * K21,
        Q * (cp - ct / RI) / VT,
        KIN * (PEGFR0 - (IMAX * ct) / (IC50 + ct)) - KTR * pegfr,
        KTR * pegfr - KOUT * perk,
    ])


def output_times() -> NDArray[np.float64]:
    return np.linspace(0.0, TSTOP, int(round(TSTOP / CINT)) + 1)


def run() -> dict[str, NDArray[np.float64]]:
    """T, the five states and CP at every CINT row up to the TERMT instant 50."""

    def startdose(t, y, inputs):
        inputs["IVRATE"] = (IVDOSE * BW / 0.01) / VC
        return y

    def enddose(t, y, inputs):
        inputs["IVRATE"] = 0.0
        return y

    t = output_times()
    y = integrate_piecewise(rhs, [C10, C20, CT0, PEGFR0, PERK0], t,
                            [(T_START, startdose), (T_END, enddose)], {"IVRATE": 0.0})
    out = {"T": t} | {name: y[:, i] for i, name in enumerate(STATES)}
    out["CP"] = 1000.0 * out["C1"]
    return out


def dose_in_plasma() -> float:
    """mg/mL put into the central compartment by the infusion: IVDOSE*BW/VC."""
    return IVDOSE * BW / VC
