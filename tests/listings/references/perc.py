"""Reference for acsl/perc.csl (magnoliasci/PBPK, the MCSim PERC.model example as an
ACSL program): inhaled tetrachloroethylene in a person, five compartments.

Transcribed (no CINTERVAL: CINT = 0.1; TSTOP = 24; PULSE(0, 24, 8): exposure from 0
to 8, which is a breakpoint here: the reference integrates [0, 8] and [8, 24] apart):
    BodyWt = LBW/(1 - Pct_M_fat);  V_fat = Pct_M_fat*BodyWt/0.92;  V_liv, V_wp = their
    percentages of LBW;  V_pp = 0.9*LBW - V_liv - V_wp;  Flow_alv = 0.7*Flow_pul;
    Flow_tot = Flow_alv/Vent_Perf;  Flow_x = Pct_Flow_x*Flow_tot (fat, liv, pp),
    Flow_wp = the rest;  Vmax = sc_Vmax*LBW**0.7
    Cout_x = Q_x/(V_x*PC_x);  C_art = (Flow_alv*C_inh/PPM_per_mg_per_l + sum Flow_x*Cout_x)
    / (Flow_tot + Flow_alv/PC_art);  C_alv = C_art/PC_art
    Q_exh' = Flow_alv*C_alv;  Q_x' = Flow_x*(C_art - Cout_x) (fat, wp, pp);
    Q_liv' = Flow_liv*(C_art - Cout_liv) - Vmax*Q_liv/(Km + Q_liv);  Qmet' = the latter
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from .smooth import ATOL, RTOL, output_times

INHMAG, PERIOD, EXPOSURE, LBW = 50.0, 24.0, 8.0, 55.0
PCT_M_FAT, PCT_LM_LIV, PCT_LM_WP = 0.16, 0.03, 0.17
PCT_FLOW_FAT, PCT_FLOW_LIV, PCT_FLOW_PP = 0.09, 0.34, 0.07
PC_FAT, PC_LIV, PC_WP, PC_PP, PC_ART = 144.0, 4.6, 8.7, 1.4, 12.0
FLOW_PUL, VENT_PERF, SC_VMAX, KM = 8.0, 1.14, 0.0026, 1.0
TSTOP, CINT = 24.0, 0.1

PPM_PER_MG_PER_L = 72.0 / 0.488
BODYWT = LBW / (1 - PCT_M_FAT)
V_FAT = PCT_M_FAT * BODYWT / 0.92
V_LIV, V_WP = PCT_LM_LIV * LBW, PCT_LM_WP * LBW
V_PP = 0.9 * LBW - V_LIV - V_WP
FLOW_ALV = FLOW_PUL * 0.7
FLOW_TOT = FLOW_ALV / VENT_PERF
FLOW_FAT, FLOW_LIV, FLOW_PP = (p * FLOW_TOT for p in (PCT_FLOW_FAT, PCT_FLOW_LIV,
                                                       PCT_FLOW_PP))
FLOW_WP = FLOW_TOT - FLOW_FAT - FLOW_LIV - FLOW_PP
VMAX = SC_VMAX * np.exp(0.7 * np.log(LBW))
STATES = ("Q_EXH", "Q_FAT", "Q_WP", "Q_PP", "Q_LIV", "QMET")


def rhs(c_inh: float):
    def f(t: float, y: NDArray[np.float64]) -> list[float]:
        _, q_fat, q_wp, q_pp, q_liv, _ = y
        c_fat, c_wp = q_fat / (V_FAT * PC_FAT), q_wp / (V_WP * PC_WP)
        c_pp, c_liv = q_pp / (V_PP * PC_PP), q_liv / (V_LIV * PC_LIV)
        ven = FLOW_FAT * c_fat + FLOW_WP * c_wp + FLOW_PP * c_pp + FLOW_LIV * c_liv
        c_art = (FLOW_ALV * c_inh / PPM_PER_MG_PER_L + ven) / (FLOW_TOT + FLOW_ALV / PC_ART)
        met = VMAX * q_liv / (KM + q_liv)
        return [FLOW_ALV * c_art / PC_ART, FLOW_FAT * (c_art - c_fat),
                FLOW_WP * (c_art - c_wp), FLOW_PP * (c_art - c_pp),
                FLOW_LIV * (c_art - c_liv) - met, met]
    return f


def run() -> dict[str, NDArray[np.float64]]:
    t = output_times(TSTOP, CINT)
    y = np.zeros((len(t), len(STATES)))
    state = np.zeros(len(STATES))
    for lo, hi, c_inh in ((0.0, EXPOSURE, INHMAG), (EXPOSURE, TSTOP, 0.0)):
        inside = (t >= lo - 1e-12) & (t <= hi + 1e-12)
        sol = solve_ivp(rhs(c_inh), (lo, hi), state, method="Radau", rtol=RTOL, atol=ATOL,
                        t_eval=t[inside], max_step=CINT, dense_output=True)
        if not sol.success:
            raise RuntimeError(sol.message)
        y[inside] = sol.y.T
        state = sol.sol(hi)
    return {"T": t} | {n: y[:, i] for i, n in enumerate(STATES)}
