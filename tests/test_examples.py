"""The example listings of models/examples, one per form (issue 11.9), each run as
shipped and checked against an independent reference written here: a closed form
or the plain recurrence the form's translator runs."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from references import cabo

import amilpy

EXAMPLES = Path(__file__).resolve().parent.parent / "models" / "examples"


def test_acsl_oral_dosing_is_the_superposition_of_bateman_curves():
    # one dose D at t_k gives AG = D exp(-KA s) and AB = D KA/(KA - KE) (exp(-KE s) -
    # exp(-KA s)), s = t - t_k; doses at 0, 12, ..., 72 (the one due at TSTOP is
    # given before the run ends: DISCRETE runs before the TERMT test). The run's
    # default RELERR is 1e-6 per step: 1e-5 relative over 72 h.
    run, = amilpy.load(EXAMPLES / "oral_dosing.csl").run(advice=False)
    dose, ka, ke, vd = 500.0, 1.2, 0.173, 42.0
    assert run.t_end == 72.0 and run.values["NDOSE"][-1] == 7.0
    for t, cp, ag in zip(run.times, run.values["CP"], run.values["AG"], strict=True):
        doses = [12.0 * k for k in range(7) if 12.0 * k <= t + 1e-9]
        ab = sum(dose * ka / (ka - ke) * (math.exp(-ke * (t - tk)) - math.exp(-ka * (t - tk)))
                 for tk in doses)
        assert cp == pytest.approx(ab / vd, rel=1e-5, abs=1e-9)
        assert ag == pytest.approx(sum(dose * math.exp(-ka * (t - tk)) for tk in doses),
                                   rel=1e-5, abs=1e-7)
    assert run.terminal["CTROUGH"] == pytest.approx(run.values["CP"][-1])




def test_fst_wheat_is_the_euler_recurrence_over_its_weather_file():
    # FST's EUDRIV from day 90 with DELT = 1: every state advanced by one day's rate,
    # the rates from the states and that day's weather (RDD in J: the file's kJ x
    # 1000); the INSW on DVS - 1 read at the day; FINISH DVS > 2 at the first day
    # it holds. Exact to round-off.
    run, = amilpy.load(EXAMPLES / "fst_wheat.fst").run(advice=False)
    weather = cabo.days(EXAMPLES / "weather" / "NLD1.020")
    tbase, tsuma, tsumm, rue, k, sla, flv = 0.0, 1000.0, 800.0, 2.8, 0.6, 0.018, 0.35
    dvs, wlv, wt, day, rows = 0.0, 2.0, 4.0, 90, {}
    while True:
        rad, tmin, tmax = weather[day][:3]
        lai = sla * wlv
        rows[day] = (dvs, lai, wt, rad * 1000.0)
        if dvs > 2.0:
            break
        dteff = max(0.0, 0.5 * (tmin + tmax) - tbase)
        dvr = dteff / tsuma if dvs - 1.0 < 0 else dteff / tsumm
        gtw = rue * 0.5 * rad * 1000.0 * 1e-6 * (1.0 - math.exp(-k * lai))
        dvs, wlv, wt = dvs + dvr, wlv + (flv * gtw if dvs - 1.0 < 0 else 0.0), wt + gtw
        day += 1
    assert run.t_end == day
    for i, t in enumerate(run.times):
        got = tuple(run.values[n][i] for n in ("DVS", "LAI", "WT", "RDD"))
        assert got == pytest.approx(rows[round(t)], rel=1e-12)


def test_csmp_diode_filter_against_scipy_with_the_current_by_brentq():
    # the same equations written for SciPy: V' = -I/C with I the root of
    # R I + VT ln(1 + I/IS) = V (brentq), and the two FILT2 macros' four lags; RK45 at
    # rtol 1e-11. The run at RELERR 1e-9: V to 1e-7, the filters to 1e-6.
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    c, r, vt, i_s = 1e-3, 100.0, 0.02585, 1e-12

    def current(v: float) -> float:
        if v <= 0.0:
            return 0.0
        return brentq(lambda i: r * i + vt * math.log1p(i / i_s) - v, 0.0, v / r,
                      xtol=1e-16, rtol=1e-15)

    def rhs(t, y):
        v, a1, a2, b1, b2 = y
        i = current(v)
        return [-i / c, (i - a1) / 0.01, (a1 - a2) / 0.01, (v - b1) / 0.05, (b1 - b2) / 0.05]

    run, = amilpy.load(EXAMPLES / "csmp_diode_filter.amil").run(rtol=1e-9, atol=1e-12,
                                                                   advice=False)
    sol = solve_ivp(rhs, (0.0, 0.5), [5.0, 0, 0, 0, 0], t_eval=run.times, rtol=1e-11,
                    atol=1e-14, method="RK45")
    v, _, if2, _, vf2 = sol.y
    assert run.values["V"] == pytest.approx(v, rel=1e-7)
    # IMPL stops at |FI - I| <= 1E-10 (its P, absolute below 1 A): I within ~1e-10
    assert run.values["I"] == pytest.approx([current(x) for x in v], rel=1e-7, abs=3e-10)
    assert run.values["IF2"] == pytest.approx(if2, rel=1e-6, abs=1e-12)
    assert run.values["VF2"] == pytest.approx(vf2, rel=1e-6, abs=1e-12)
