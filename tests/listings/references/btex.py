"""Reference for acsl/btex_ruiz2020.csl (magnoliasci/PBPK, `BTEX Mixture/BTEX_ruiz2020.csl`):
inhaled benzene, toluene, ethylbenzene and xylene in a person, four tissues each, with
the liver's metabolism of each inhibited (INTER = 1, 2, 3) or not (INTER = 0) by the others.

What acts, as written (TSTOP = 12, CINT = 0.05, INTER = 0, every CONC 100 ppm):
- the exposure is `JOURNE = pulse(0.0, 24.0, DUREE)` in DERIVATIVE with DUREE = 7: the
  inhaled air holds CEXPO on [24k, 24k + DUREE) and nothing otherwise; within TSTOP = 12
  on [0, 7) only. Its edges are breakpoints: the reference integrates each piece apart.
- the INITIAL's two FOR loops (`schedule exp_on/exp_off at ...`, with DIMENSION and
  CONSTANT value lists) and DISCRETE exp_on_2 (`interval exp_interval = 24.0`, which
  schedules exp_off at t + exp_dur) only schedule sections: exp_on, exp_off and
  exp_on_2 hold nothing but comments and SCHEDULE (their `EXPFLAG = ...` lines are
  commented out), so they change no value; within TSTOP they fire at 0 and 8. The
  reference has no events for them (a solver restart changes nothing exact).

Transcribed per chemical s in (X, T, E, B) (no blood compartment; flows sum to QC):
    QC = KQCR*BW**0.75;  QALV = KQALVR*BW**0.75;  VMAXs = KVMAXs*BW**0.75
    VR, VMP, VG, VF = KVR, KVMP, KVG, KVF times BW;  QG, QF, QR, QMP = KQGR, KQFR, KQR,
    KQMP times QC;  PRxs = KPRxs/PRBs (F, G, R, MP);  CEXPOs = CONCs*PMs/(24.45*1000)
    CIs = JOURNE*CEXPOs
    CVFs = AFs/VF/PRFs (likewise CVRs, CVGs, CVMPs with AR, AG, AMP and VR, VG, VMP)
    CVs = (QF*CVFs + QG*CVGs + QR*CVRs + QMP*CVMPs)/QC;  SSs' = CVs
    CAs = (QC*CVs + QALV*CIs)/(QC + QALV/PRBs);  CEXPs = CAs/PRBs
    CPPMs = CEXPs*1000*24.45/PMs
    AFs' = QF*CAs - QF*CVFs - TMETs;  ARs' = QR*(CAs - CVRs);  AGs' = QG*(CAs - CVGs);
    AMPs' = QMP*(CAs - CVMPs);  METs' = TMETs;  ACCs' = QALV*(CIs - CEXPs)
    TMETs, with Ss = sum over the other chemicals y of CVFy/Kiys (Kiys: "y vs s"):
      INTER 0: VMAXs*CVFs/(KMs + CVFs)            1: VMAXs*CVFs/(KMs*(1 + Ss) + CVFs)
      INTER 2: VMAXs*CVFs/((KMs + CVFs)*(1 + Ss)) else: VMAXs*CVFs/(KMs + CVFs*(1 + Ss))
    BILANs = ACCs - (ARs + AGs + AMPs + AFs + METs)   (zero: the listing's own check)
Rows at the exposure's end (t = 7) show the post-event values (JOURNE = 0 in CPPM).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from .smooth import output_times

# DOP853 at rtol 1e-13: at 1e-11 it is 7.7e-11 of AFB's range off a 1e-13 solve (the
# benzene liver, the fastest part: VMAXB/KMB/(VF*PRFB) ~ 260/h); at 1e-13 it agrees with
# Radau at 1e-12 to 2.2e-12 and with LSODA at 1e-12 to 1.2e-11 of each state's range
RTOL = 1e-13
ATOL = 1e-15

# the listing's values
CONC = {"X": 100.0, "T": 100.0, "E": 100.0, "B": 100.0}
DUREE, TSTOP, CINT, INTER = 7.0, 12.0, 0.05, 0
BW, KQCR, KQALVR = 60.0, 18.0, 18.0
KVG, KVF, KVMP, KVR = 0.19, 0.026, 0.62, 0.05
KQGR, KQFR, KQR, KQMP = 0.05, 0.26, 0.44, 0.25
CHEMICALS = ("X", "T", "E", "B")
# PRB, KPRF, KPRG, KPRR, KPRMP, PM, KVMAX, KM
CHEM = {
    "E": (28.0, 83.8, 1556.0, 60.3, 26.0, 106.16, 7.3, 1.39),
    "T": (15.6, 83.6, 1021.0, 83.6, 27.7, 92.14, 4.8, 0.134),
    "X": (26.4, 90.9, 1859.0, 90.9, 41.9, 106.17, 5.5, 0.22),
    "B": (15.0, 17.0, 500.0, 17.0, 15.0, 78.2, 2.11, 0.099),
}
# KI[y][s]: the listing's Ki<y><s>, "inhibition constant of y vs s" (mg/l)
KI = {
    "E": {"X": 0.505, "T": 0.168, "B": 0.256},
    "T": {"X": 0.357, "E": 0.948, "B": 0.144},
    "X": {"T": 0.328, "E": 1.667, "B": 0.216},
    "B": {"T": 0.223, "E": 0.626, "X": 0.226},
}

QC = KQCR * BW**0.75
QALV = KQALVR * BW**0.75
VR, VMP, VG, VF = KVR * BW, KVMP * BW, KVG * BW, KVF * BW
QG, QF, QR, QMP = KQGR * QC, KQFR * QC, KQR * QC, KQMP * QC
PRB = {s: CHEM[s][0] for s in CHEMICALS}
PRF = {s: CHEM[s][1] / CHEM[s][0] for s in CHEMICALS}
PRG = {s: CHEM[s][2] / CHEM[s][0] for s in CHEMICALS}
PRR = {s: CHEM[s][3] / CHEM[s][0] for s in CHEMICALS}
PRMP = {s: CHEM[s][4] / CHEM[s][0] for s in CHEMICALS}
PM = {s: CHEM[s][5] for s in CHEMICALS}
VMAX = {s: CHEM[s][6] * BW**0.75 for s in CHEMICALS}
KM = {s: CHEM[s][7] for s in CHEMICALS}

# the 28 states of the listing, per chemical; with_exhaled adds EXHALED_s (not in the
# listing): the amount breathed out, QALV*CEXPs integrated, for the mass balance
KINDS = ("SS", "AF", "AR", "AG", "AMP", "MET", "ACC")
STATES = tuple(k + s for s in CHEMICALS for k in KINDS)


def cexpo(conc: dict[str, float]) -> dict[str, float]:
    return {s: conc[s] * PM[s] / (24.45 * 1000) for s in CHEMICALS}


def exposure_edges(duree: float, tstop: float) -> list[tuple[float, float]]:
    """[on, off) intervals of PULSE(0, 24, DUREE) that start before TSTOP."""
    return [(24.0 * k, 24.0 * k + duree) for k in range(int(np.ceil(tstop / 24.0)) + 1)
            if 24.0 * k < tstop]


def venous(y: NDArray[np.float64], i: int):
    """CVF, CVR, CVG, CVMP, CV of chemical number i from its block of states y."""
    s = CHEMICALS[i]
    af, ar, ag, amp = y[1], y[2], y[3], y[4]
    cvf = af / VF / PRF[s]
    cvr = ar / VR / PRR[s]
    cvg = ag / VG / PRG[s]
    cvmp = amp / VMP / PRMP[s]
    return cvf, cvr, cvg, cvmp, (QF * cvf + QG * cvg + QR * cvr + QMP * cvmp) / QC


def tmet(cvf: dict[str, float], inter: int) -> dict[str, float]:
    out = {}
    for s in CHEMICALS:
        c = cvf[s]
        inhib = sum(cvf[y] / KI[y][s] for y in CHEMICALS if y != s)
        if inter == 0:
            out[s] = VMAX[s] * c / (KM[s] + c)
        elif inter == 1:
            out[s] = VMAX[s] * c / (KM[s] * (1 + inhib) + c)
        elif inter == 2:
            out[s] = VMAX[s] * c / ((KM[s] + c) * (1 + inhib))
        else:
            out[s] = VMAX[s] * c / (KM[s] + c * (1 + inhib))
    return out


def make_rhs(ci: dict[str, float], inter: int, n: int):
    """y' for inhaled concentrations ci; n states per chemical (7, or 8 with EXHALED)."""
    def f(t: float, y: NDArray[np.float64]) -> NDArray[np.float64]:
        dy = np.empty_like(y)
        parts = {s: venous(y[i * n:(i + 1) * n], i) for i, s in enumerate(CHEMICALS)}
        met = tmet({s: parts[s][0] for s in CHEMICALS}, inter)
        for i, s in enumerate(CHEMICALS):
            cvf, cvr, cvg, cvmp, cv = parts[s]
            ca = (QC * cv + QALV * ci[s]) / (QC + QALV / PRB[s])
            cexp = ca / PRB[s]
            j = i * n
            dy[j] = cv                                   # SS
            dy[j + 1] = QF * ca - QF * cvf - met[s]      # AF
            dy[j + 2] = QR * (ca - cvr)                  # AR
            dy[j + 3] = QG * (ca - cvg)                  # AG
            dy[j + 4] = QMP * (ca - cvmp)                # AMP
            dy[j + 5] = met[s]                           # MET
            dy[j + 6] = QALV * (ci[s] - cexp)            # ACC
            if n == 8:
                dy[j + 7] = QALV * cexp                  # EXHALED (reference only)
        return dy
    return f


def run(conc: dict[str, float] | None = None, duree: float = DUREE, tstop: float = TSTOP,
        inter: int = INTER, *, method: str = "DOP853", rtol: float = RTOL,
        atol: float = ATOL, with_exhaled: bool = False) -> dict[str, NDArray[np.float64]]:
    """The printout every CINT to TSTOP: the 28 states, CV and CPPM of each chemical
    (and EXHALED_s with with_exhaled; BILAN, zero but for round-off, is left out: a
    relative error means nothing there). conc, duree, tstop, inter: the
    listing's CONCx..., DUREE, TSTOP and INTER (the values RMagnolia's runsim sets)."""
    conc = CONC if conc is None else conc
    expo = cexpo(conc)
    n = 8 if with_exhaled else 7
    t = output_times(tstop, CINT)
    # pieces: exposure on/off switch instants within (0, tstop)
    edges = exposure_edges(duree, tstop)
    switches = sorted({x for e in edges for x in e if 0.0 < x < tstop} | {0.0, tstop})

    def on(ti: float) -> bool:  # PULSE after any switch at ti (post-event, as printed)
        return any(a <= ti < b for a, b in edges)

    y = np.zeros((t.size, 4 * n))
    journe = np.zeros(t.size)
    state = np.zeros(4 * n)
    for lo, hi in zip(switches[:-1], switches[1:], strict=True):
        ci = {s: (expo[s] if on(lo) else 0.0) for s in CHEMICALS}
        last = hi == switches[-1]
        inside = (t >= lo) & ((t <= hi) if last else (t < hi))
        grid = np.append(t[inside], hi) if not last else t[inside]
        sol = solve_ivp(make_rhs(ci, inter, n), (lo, hi), state, method=method, rtol=rtol,
                        atol=atol, t_eval=grid, max_step=CINT)
        if not sol.success:
            raise RuntimeError(sol.message)
        k = int(inside.sum())
        y[inside] = sol.y[:, :k].T
        journe[inside] = 1.0 if on(lo) else 0.0
        state = sol.y[:, -1].copy()
    out: dict[str, NDArray[np.float64]] = {"T": t}
    for i, s in enumerate(CHEMICALS):
        block = y[:, i * n:(i + 1) * n]
        for j, kind in enumerate(KINDS):
            out[kind + s] = block[:, j]
        cv = np.array([venous(row, i)[4] for row in block])
        ca = (QC * cv + QALV * journe * expo[s]) / (QC + QALV / PRB[s])
        out["CV" + s] = cv
        out["CPPM" + s] = ca / PRB[s] * 1000 * 24.45 / PM[s]
        if with_exhaled:
            out["EXHALED_" + s] = block[:, 7]
    return out


def inhaled(t: NDArray[np.float64], conc: dict[str, float] | None = None,
            duree: float = DUREE) -> dict[str, NDArray[np.float64]]:
    """Amount breathed in by t, in closed form: QALV*CEXPOs times the time exposed."""
    expo = cexpo(CONC if conc is None else conc)
    tstop = float(np.max(t))
    exposed = sum(np.clip(t - a, 0.0, b - a) for a, b in exposure_edges(duree, tstop))
    return {s: QALV * expo[s] * exposed for s in CHEMICALS}
