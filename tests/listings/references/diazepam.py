"""Reference for acsl/diazepam.csl (magnoliasci/PBPK, Diazepam/diazepam.csl).

Whole-body PBPK model of diazepam in the rat (Igari et al. 1983; Gueorguieva et al.
2004): 14 tissue/blood amounts in a flow-limited network, hepatic clearance, and a 5-min
IV infusion repeated every 125 min by two DISCRETE sections that schedule each other.
Units: mL/min, mL, min, amounts in the dose's units. Transcribed from the listing:

    qV = qMu+qTe+qAd+qSk+qHrt+qBr+qSpl+qSt+qHep+qKi+qRe;  qA = qLu = qV
    qLi = qSpl + qSt + qHep;  fub = fu/Ratio   (an INITIAL nested inside DERIVATIVE)
    tissue X in {Mu,Te,Ad,Sk,Hrt,Br,Spl,St,Ki,Re}:  AX' = qX*CA - qX*CX/KpX,  CX = AX/VX
    ALi' = qSt*CSt/KpSt + qSpl*CSpl/KpSpl + qHep*CA - (qSt+qSpl+qHep)*CLi/KpLi
           - CLi*KClLi*fub/KpLi
    totalcleared' = CLi*KClLi*fub/KpLi
    ALu' = qLu*CV - qLu*CLu/KpLu
    AA'  = qLu*CLu/KpLu - qA*CA,                 CA = AA/VA
    AV'  = sum over {Mu,Te,Ad,Sk,Hrt,Br,Ki,Re} of qX*CX/KpX + qLi*CLi/KpLi
           + ivdoserate - qV*CV,                 CV = AV/VV
    totaldose' = IVDoseRate
    SCHEDULE startdose AT doseon (0)             INITIAL;  ivdoserate = 0
    DISCRETE startdose: ivdoserate = dose/(doseoff-doseon); SCHEDULE enddose AT t + doseoff
    DISCRETE enddose:   ivdoserate = 0;  SCHEDULE startdose AT t + 120
    TERMT(t >= tstop)   tstop = 250;  CINTERVAL CINT = 0.1

Infusions therefore run on [0, 5] and [125, 130]; a third start is due at 250, the TERMT
instant (it changes only a rate, so the last row does not depend on its order). The
network conserves mass: sum of amounts + totalcleared = totaldose.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .piecewise import integrate_piecewise

# name: (blood flow mL/min, tissue:blood partition coefficient, volume mL)
TISSUES = {
    "MU": (16.25, 1.88, 125.0), "TE": (1.9, 5.24, 2.5), "AD": (2.55, 21.23, 10.0),
    "SK": (7.1, 3.33, 43.8), "HRT": (4.2, 5.57, 1.0), "BR": (0.78, 1.69, 1.2),
    "SPL": (20.25, 3.70, 15.0), "ST": (1.9, 5.25, 1.1), "KI": (16.61, 5.15, 2.0),
    "RE": (4.91, 18.15, 15.8),
}
QHEP, KPLI, VLI = 3.55, 7.83, 11.0
KPLU, VLU, VA, VV = 4.93, 1.2, 6.8, 13.6
KCLLI, FU, RATIO = 400.0, 0.15, 1.0
DOSEON, DOSEOFF, DOSE = 0.0, 5.0, 1000000.0
TSTOP, CINT, GAP = 250.0, 0.1, 120.0

QV = sum(q for q, _, _ in TISSUES.values()) + QHEP
QA = QLU = QV
QLI = TISSUES["SPL"][0] + TISSUES["ST"][0] + QHEP
FUB = FU / RATIO
NAMES = tuple(f"A{n}" for n in TISSUES) + ("ALI", "ALU", "AA", "AV", "TOTALCLEARED",
                                            "TOTALDOSE")
# tissues whose venous blood returns to the venous pool (spleen and stomach go to liver)
TO_VEIN = ("MU", "TE", "AD", "SK", "HRT", "BR", "KI", "RE")


def rhs(t: float, y: NDArray[np.float64], inputs: dict) -> NDArray[np.float64]:
    n = len(TISSUES)
    amount = dict(zip(TISSUES, y[:n], strict=True))
    ali, alu, aa, av = y[n:n + 4]
    ca, cv = aa / VA, av / VV
    cli, clu = ali / VLI, alu / VLU
    conc = {k: amount[k] / v for k, (_, _, v) in TISSUES.items()}
    d = [q * ca - q * conc[k] / kp for k, (q, kp, _) in TISSUES.items()]
    qst, kpst = TISSUES["ST"][:2]
    qspl, kpspl = TISSUES["SPL"][:2]
    cleared = cli * KCLLI * FUB / KPLI
    dli = (qst * conc["ST"] / kpst + qspl * conc["SPL"] / kpspl + QHEP * ca
           - (qst + qspl + QHEP) * cli / KPLI - cleared)
    dlu = QLU * cv - QLU * clu / KPLU
    da = QLU * clu / KPLU - QA * ca
    back = sum(TISSUES[k][0] * conc[k] / TISSUES[k][1] for k in TO_VEIN)
    dv = back + QLI * cli / KPLI + inputs["RATE"] - QV * cv
    return np.array(d + [dli, dlu, da, dv, cleared, inputs["RATE"]])


def infusion_windows(tstop: float = TSTOP) -> list[tuple[float, float]]:
    """The [start, end] of every infusion the two DISCRETE sections schedule before tstop."""
    out, t = [], DOSEON
    while t < tstop:
        out.append((t, t + DOSEOFF))
        t = t + DOSEOFF + GAP
    return out


def output_times() -> NDArray[np.float64]:
    return np.linspace(0.0, TSTOP, int(round(TSTOP / CINT)) + 1)


def run() -> dict[str, NDArray[np.float64]]:
    def start(t, y, inputs):
        inputs["RATE"] = DOSE / (DOSEOFF - DOSEON)
        return y

    def end(t, y, inputs):
        inputs["RATE"] = 0.0
        return y

    events = []
    for a, b in infusion_windows():
        events += [(a, start), (b, end)]
    t = output_times()
    y = integrate_piecewise(rhs, np.zeros(len(NAMES)), t, events, {"RATE": 0.0})
    return {"T": t} | {name: y[:, i] for i, name in enumerate(NAMES)}
