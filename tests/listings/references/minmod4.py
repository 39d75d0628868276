"""Reference for acsl/minmod4.csl (JohnCarlosReed/GlInGgModel: the ACSL program kept as
comments at the end of gl_in_gg_model.pl): glucose / insulin / glucagon with signal pools.

Transcribed (abson = .FALSE., so the PROCEDURAL's ELSE branch gives absGl = 0):

    GNG = VGNG/(1 + KGgGNG/Ggsig + Insig/JInGNG)
    UGl = VGl/(1 + KGlUGl/cGl + KInUGl/Insig + Ggsig/JGgUGl)
    Gl'    = absGl + infGl + GNG - UGl                  Gl(0) = iGl,   cGl = Gl/vol
    HotGl' = absGl*SAabsGl + infGl*SAinfGl + GNG*SAGNG - UGl*SAGl,  SAGl = HotGl/Gl
    In'    = infIn + VIn/(1 + (KGlPIn/cGl)**expIn) + basalIn - kIn*cIn,  cIn = In/vol
    Insig' = kPInsig*cIn - kUInsig*Insig
    Gg'    = infGg + VGg/(1 + (cGl/JGlPGg)**expGg) - kGg*cGg,            cGg = Gg/vol
    Ggsig' = kPGgsig*cGg - kUGgsig*Ggsig
    TERMT (T.GE.TSTP)   tstp = 20;  CONSTANT CINT = 1.0
    ALGORITHM IALG = 5; NSTEPS NSTP = 1; MAXTERVAL MAXT = 0.005

IALG 5 is ACSL's fixed-step 4th-order Runge-Kutta; the contract (section 11) maps it to
RK4 with DELT = min(MAXT, CINT/NSTP) = 0.005. Two references: run() integrates at rtol
1e-10 (what any accurate method must approach) and rk4() takes exactly the listing's
classic RK4 steps (what amilpy's RK4 route must reproduce to round-off).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

TSTP, VOL, CINT, MAXT, NSTP = 20.0, 8.0, 1.0, 0.005, 1
ABSON = False
B0ABS, B1ABS, CABS, FEDGL, TABSON = 1.0, 0.03, 0.015, 0.0, 120.0
IGL, INFGL, JGGUGL, JINGNG = 40.0, 0.0, 125.0, 40.0
KGGGNG, KGLUGL, KINUGL, VGL, VGNG = 125.0, 11.0, 40.0, 7.072, 2.21
FGNGLC, IHOTGL, IHOTLC, LC = 0.10, 1.0e-10, 1.0e-10, 10.0
SAABSGL, SAGNG, SAINFGL = 0.0, 0.0, 0.0
BASALIN, EXPIN, IIN, INFIN, KIN, KGLPIN, VIN = 0.0075, 5.0, 64.0, 0.0, 1.0, 8.0, 91.8
IINSIG, KPINSIG, KUINSIG = 8.0, 1.0, 1.0
EXPGG, IGG, INFGG, JGLPGG, KGG, VGG = 4.0, 640.0, 0.0, 4.0, 0.625, 172.07
IGGSIG, KPGGSIG, KUGGSIG = 80.0, 0.5, 0.5
STATES = ("GL", "HOTGL", "IN", "INSIG", "GG", "GGSIG")
Y0 = (IGL, IHOTGL, IIN, IINSIG, IGG, IGGSIG)
DELT = min(MAXT, CINT / NSTP)


def abs_gl(t: float) -> float:
    """The PROCEDURAL block: a meal absorption curve when abson is true, else 0."""
    if not ABSON:
        return 0.0
    aabs = FEDGL / (1 / CABS - 1 / (B1ABS + CABS))
    return (aabs * (B0ABS - np.exp(-B1ABS * (t - TABSON)))
            * np.exp(-CABS * (t - TABSON)))


def rhs(t: float, y: NDArray[np.float64]) -> NDArray[np.float64]:
    gl, hotgl, ins, insig, gg, ggsig = y
    cgl, cin, cgg = gl / VOL, ins / VOL, gg / VOL
    absgl = abs_gl(t)
    gng = VGNG / (1 + KGGGNG / ggsig + insig / JINGNG)
    ugl = VGL / (1 + KGLUGL / cgl + KINUGL / insig + ggsig / JGGUGL)
    sagl = hotgl / gl
    return np.array([
        absgl + INFGL + gng - ugl,
        absgl * SAABSGL + INFGL * SAINFGL + gng * SAGNG - ugl * sagl,
        INFIN + VIN / (1 + (KGLPIN / cgl) ** EXPIN) + BASALIN - KIN * cin,
        KPINSIG * cin - KUINSIG * insig,
        INFGG + VGG / (1 + (cgl / JGLPGG) ** EXPGG) - KGG * cgg,
        KPGGSIG * cgg - KUGGSIG * ggsig,
    ])


def output_times() -> NDArray[np.float64]:
    return np.linspace(0.0, TSTP, int(round(TSTP / CINT)) + 1)


def _table(t: NDArray[np.float64], y: NDArray[np.float64]) -> dict[str, NDArray[np.float64]]:
    out = {"T": t} | {name: y[:, i] for i, name in enumerate(STATES)}
    out["CGL"], out["CIN"], out["CGG"] = out["GL"] / VOL, out["IN"] / VOL, out["GG"] / VOL
    return out


def run(rtol: float = 1e-10) -> dict[str, NDArray[np.float64]]:
    t = output_times()
    sol = solve_ivp(rhs, (0.0, TSTP), Y0, method="DOP853", rtol=rtol, atol=1e-14,
                    t_eval=t)
    return _table(t, sol.y.T)


def rk4() -> dict[str, NDArray[np.float64]]:
    """Classic RK4 with DELT = 0.005 from 0 to 20, sampled every CINT (200 steps a row)."""
    steps_per_row = int(round(CINT / DELT))
    t_rows = output_times()
    y = np.array(Y0, dtype=float)
    rows = [y.copy()]
    t = 0.0
    for k in range(1, t_rows.size):
        for _ in range(steps_per_row):
            k1 = rhs(t, y)
            k2 = rhs(t + DELT / 2, y + DELT / 2 * k1)
            k3 = rhs(t + DELT / 2, y + DELT / 2 * k2)
            k4 = rhs(t + DELT, y + DELT * k3)
            y = y + DELT / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            t = t_rows[k - 1] + DELT * (_ + 1)
        rows.append(y.copy())
    return _table(t_rows, np.array(rows))
