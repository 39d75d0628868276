"""Reference for acsl/lapatinib_md.csl (magnoliasci/PBPK, Lapatinib/lapatinib_human_MD.csl).

Human PBPK model of lapatinib (Hudachek & Gustafson 2013, PMID 23315145, ported to
Magnolia), repeated oral doses. Amounts in nmol, volumes in L, flows in L/h, time in h.
Transcribed from the listing (INITIAL in written order; DERIVATIVE directly in the model,
no DYNAMIC; one DISCRETE section with INTERVAL):

    Q_x = FQ_x*CO, V_x = FV_x*BW for x in liv, int, kid, brn, hrt, lng, sp, bld;
    FQ_sp = 1 - FQ_liv - FQ_int - FQ_kid - FQ_brn - FQ_hrt;  FV_sp = 1 - (all other FV);
    V_pl = V_bld/2;  k_imet = k_lmet*0.013 (k_lmet is a CONSTANT, so known in INITIAL)
    tissue x in brn, hrt, sp, kid:  A_x' = Q_x*(C_art - C_x/(P_x*fu)),  C_x = A_x/V_x
    A_lng'   = Q_lng*(C_ven - C_lng/(P_lng*fu))
    A_lumen' = -ka*A_lumen                       A_lumen(0) = DDose = 0 (PODose = 0)
    A_imet'  = k_imet*C_v_int*V_int              C_v_int = C_int/(P_int*fu)
    A_int'   = Q_int*(C_art - C_v_int) + ka*A_lumen - A_imet'
    A_lmet'  = k_lmet*C_v_liv*V_liv              C_v_liv = C_liv/P_liv  (no fu)
    A_liv'   = Q_liv*C_art + Q_int*C_v_int - (Q_liv+Q_int)*C_v_liv - A_lmet'
    A_ven'   = sum_x Q_x*C_v_x (brn,hrt,sp,kid,lng) + (Q_liv+Q_int)*C_v_liv
               - (Q_brn+Q_hrt+Q_sp+Q_kid+Q_int+Q_liv)*C_art - Q_lng*C_ven
    C_ven = A_ven/V_bld;  C_art = C_ven;  C_pl = A_ven/V_pl;  AUC_x = INTEG(C_x, 0)
    DISCRETE oraldose: RDose = repeated_PODose*1e6/MW; INTERVAL doseint = 24;
                       IF (t <= 24*7) A_lumen = A_lumen + RDose
    TERMT(t >= tstop, 'time limit')   tstop = 192; CINT = TSTOP/POINTS = 0.25

INTERVAL runs the section at t0 and every 24 h (contract section 11): doses at
t = 0, 24, ..., 168 (eight), none at 192. The system is linear, so the run equals the sum
of eight shifted single-dose responses (a check that does not share the event code).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .piecewise import integrate_piecewise

CO, BW, FU, MW = 312.0, 70.0, 0.01, 581.06
FQ = {"liv": 0.046, "int": 0.181, "kid": 0.175, "brn": 0.114, "hrt": 0.04, "lng": 1.0}
FV = {"liv": 0.026, "int": 0.017, "kid": 0.004, "brn": 0.02, "hrt": 0.005, "lng": 0.008,
      "bld": 0.079}
P = {"liv": 12.0, "int": 531.0, "kid": 1064.0, "brn": 10.0, "hrt": 215.0, "lng": 1643.0,
     "sp": 65.0}
PODOSE, REPEATED_PODOSE = 0.0, 1250.0
KA, K_LMET = 0.07, 75.0
K_IMET = K_LMET * 0.013
TSTOP, POINTS = 192.0, 768.0
CINT = TSTOP / POINTS
DOSEINT, LAST_DOSE = 24.0, 24.0 * 7

FQ["sp"] = 1 - FQ["liv"] - FQ["int"] - FQ["kid"] - FQ["brn"] - FQ["hrt"]
FV["sp"] = 1 - sum(FV[k] for k in ("liv", "int", "kid", "brn", "hrt", "lng", "bld"))
Q = {k: f * CO for k, f in FQ.items()}
V = {k: f * BW for k, f in FV.items()}
V_PL = V["bld"] / 2
DDOSE = PODOSE * 1e6 / MW
RDOSE = REPEATED_PODOSE * 1e6 / MW

AMOUNTS = ("A_brn", "A_hrt", "A_lng", "A_sp", "A_kid", "A_lumen", "A_imet", "A_int",
           "A_lmet", "A_liv", "A_ven")
AUCS = ("AUC_brn", "AUC_hrt", "AUC_lng", "AUC_sp", "AUC_kid", "AUC_int", "AUC_liv",
        "AUC_pl")
STATES = AMOUNTS + AUCS
LUMEN = STATES.index("A_lumen")


def matrix() -> NDArray[np.float64]:
    """The (constant) Jacobian: the model is y' = M y between doses."""
    n = len(STATES)
    m = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1.0
        m[:, j] = rhs(0.0, e, {})
    return m


def rhs(t: float, y: NDArray[np.float64], inputs: dict) -> NDArray[np.float64]:
    a = dict(zip(AMOUNTS, y[:len(AMOUNTS)], strict=True))
    c = {x: a["A_" + x] / V[x] for x in ("brn", "hrt", "lng", "sp", "kid", "int", "liv")}
    c_ven = a["A_ven"] / V["bld"]
    c_art = c_ven
    cv = {x: c[x] / (P[x] * FU) for x in ("brn", "hrt", "lng", "sp", "kid", "int")}
    cv["liv"] = c["liv"] / P["liv"]
    d = {x: Q[x] * (c_art - cv[x]) for x in ("brn", "hrt", "sp", "kid")}
    d["lng"] = Q["lng"] * (c_ven - cv["lng"])
    d_lumen = -KA * a["A_lumen"]
    d_imet = K_IMET * cv["int"] * V["int"]
    d_int = Q["int"] * (c_art - cv["int"]) + KA * a["A_lumen"] - d_imet
    d_lmet = K_LMET * cv["liv"] * V["liv"]
    d_liv = (Q["liv"] * c_art + Q["int"] * cv["int"] - (Q["liv"] + Q["int"]) * cv["liv"]
             - d_lmet)
    d_ven = (sum(Q[x] * cv[x] for x in ("brn", "hrt", "sp", "kid", "lng"))
             + (Q["liv"] + Q["int"]) * cv["liv"]
             - sum(Q[x] for x in ("brn", "hrt", "sp", "kid", "int", "liv")) * c_art
             - Q["lng"] * c_ven)
    return np.array([d["brn"], d["hrt"], d["lng"], d["sp"], d["kid"], d_lumen, d_imet,
                     d_int, d_lmet, d_liv, d_ven,
                     c["brn"], c["hrt"], c["lng"], c["sp"], c["kid"], c["int"], c["liv"],
                     a["A_ven"] / V_PL])


def dose_times() -> list[float]:
    """INTERVAL instants at which IF (t <= 24*7) adds a dose."""
    k = np.arange(int(TSTOP // DOSEINT) + 1) * DOSEINT
    return [float(t) for t in k if t <= LAST_DOSE]


def output_times() -> NDArray[np.float64]:
    return np.linspace(0.0, TSTOP, int(round(POINTS)) + 1)


def run() -> dict[str, NDArray[np.float64]]:
    def dose(t, y, inputs):
        y = y.copy()
        y[LUMEN] += RDOSE
        return y

    t = output_times()
    y0 = np.zeros(len(STATES))
    y0[LUMEN] = DDOSE
    y = integrate_piecewise(rhs, y0, t, [(td, dose) for td in dose_times()], {})
    out = {"T": t} | {name: y[:, i] for i, name in enumerate(STATES)}
    out["C_pl"] = out["A_ven"] / V_PL
    return out


def superposition(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """States at t as a sum of shifted single-dose responses exp(M (t - td)) e_lumen RDose."""
    from scipy.linalg import expm

    m = matrix()
    out = np.zeros((len(t), len(STATES)))
    e = np.zeros(len(STATES))
    e[LUMEN] = RDOSE
    for td in dose_times():
        for i, ti in enumerate(t):
            if ti >= td:
                out[i] += expm(m * (ti - td)) @ e
    return out
