"""The listing references (tests/listings/references) against second, independent methods.

These tests do not run amilpy: they make sure the references the implementers will test
amilpy against are right. Each compares a reference with another way of getting the same
numbers (closed form vs numerical integration, event-by-event integration vs matrix
exponentials and superposition, RK4 vs a tight adaptive solve, a mass balance) at a
tolerance stated with its reason.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from listings.references import (
    diazepam,
    flow_limited_fat,
    gefitinib,
    lapatinib_md,
    minmod4,
    spring,
    water_stress,
)


def test_spring_closed_form_matches_integration_and_published_cpp_rows():
    ref = spring.run()
    assert ref["T"][-1] == spring.TSTP and ref["T"].size == 201  # rows 0..3.98 and 3.99

    def rhs(t, y):
        return [y[1], (spring.MASS * spring.G - spring.K * y[1] - spring.A * y[0])
                / spring.MASS, 1.0]

    sol = solve_ivp(rhs, (0, spring.TSTP), [0, 0, 0], method="DOP853", rtol=1e-12,
                    atol=1e-14, t_eval=ref["T"])
    # closed form vs a 1e-12 solve: both exact to ~1e-11 of the amplitude (0.29)
    assert np.max(np.abs(sol.y[0] - ref["X"])) < 1e-10
    assert np.max(np.abs(sol.y[1] - ref["XD"])) < 1e-9
    assert np.max(np.abs(sol.y[2] - ref["TIME"])) < 1e-12
    # the C++ translation's printout has six significant digits: half a unit in the
    # sixth digit is at most 5e-6 relative for these values
    for t, xd, x in spring.PUBLISHED_CPP:
        s = spring.solution(t)
        assert abs(s["XD"] - xd) <= 5e-6 * abs(xd)
        assert abs(s["X"] - x) <= 5e-6 * abs(x)


def test_flow_limited_fat_closed_form_matches_integration_with_breakpoint():
    ref = flow_limited_fat.run()
    f = flow_limited_fat
    lam = f.QF / (f.VF * f.PF)

    def rhs(t, y, cin0):
        return [f.QF * (cin0 - y[0] / (f.VF * f.PF)), f.QF * cin0,
                f.QF * y[0] / (f.VF * f.PF)]

    t = ref["T"]
    before, after = t[t < f.TCHNG], t[t >= f.TCHNG]
    a = solve_ivp(rhs, (0, f.TCHNG), [0, 0, 0], rtol=1e-12, atol=1e-14, args=(f.CIN,),
                  t_eval=np.append(before, f.TCHNG), method="DOP853")
    b = solve_ivp(rhs, (f.TCHNG, f.TSTOP), a.y[:, -1], rtol=1e-12, atol=1e-14,
                  args=(0.0,), t_eval=after, method="DOP853")
    num = np.hstack([a.y[:, :-1], b.y])
    # amounts are O(1e-2..1) mg; 1e-11 absolute is far below the 1e-10 integration error
    # the implementers will allow and far above the two methods' round-off
    assert np.max(np.abs(num[0] - ref["AF"])) < 1e-11
    assert np.max(np.abs(num[1] - ref["TOTAL"])) < 1e-11
    assert np.max(np.abs(num[2] - ref["OUT"])) < 1e-11
    assert np.allclose(ref["TMASS"], ref["TOTAL"], rtol=0, atol=1e-12)  # mass balance
    assert lam > 0 and ref["CIN0"][t >= f.TCHNG].max() == 0.0


def _linear_response(m, b_of_t, y0, times, switch_times):
    """y' = M y + b(t) with b piecewise constant between switch_times, by matrix exponentials
    of the augmented system [[M, b], [0, 0]] (no ODE solver involved)."""
    n = len(y0)
    out, y, t = [], np.asarray(y0, float), 0.0
    edges = sorted(set(switch_times) | set(times))
    for te in edges:
        if te > t:
            aug = np.zeros((n + 1, n + 1))
            aug[:n, :n] = m
            aug[:n, n] = b_of_t(t)
            y = (expm(aug * (te - t)) @ np.append(y, 1.0))[:n]
            t = te
        if te in times:
            out.append(y.copy())
    return np.array(out)


def test_gefitinib_pk_part_matches_matrix_exponential():
    ref = gefitinib.run()
    g = gefitinib
    m = np.array([[-(g.K12 + g.K10), g.K21], [g.K12, -g.K21]])
    rate = g.dose_in_plasma() / 0.01

    def b(t):
        return np.array([rate if t < g.T_END else 0.0, 0.0])

    pick = ref["T"][[0, 1, 2, 10, 100, 500, 1000]]
    exact = _linear_response(m, b, [0.0, 0.0], list(pick), [g.T_END])
    idx = np.searchsorted(ref["T"], pick)
    # C1 peaks near 2.7e-3 mg/mL; rtol 1e-10 of the reference gives ~1e-13 absolute
    assert np.max(np.abs(exact[:, 0] - ref["C1"][idx])) < 1e-12
    assert np.max(np.abs(exact[:, 1] - ref["C2"][idx])) < 1e-12
    # the infusion delivered IVDOSE*BW/Vc into C1 by t = 0.01 (first row is before it)
    assert ref["C1"][0] == 0.0 and ref["T"][-1] == g.TSTOP


def test_diazepam_mass_balance_and_matrix_exponential():
    ref = diazepam.run()
    d = diazepam
    amounts = sum(ref[n] for n in d.NAMES[:-1])
    # the network conserves mass: 1e-9 of the 2e6 dosed is far below any test tolerance
    assert np.max(np.abs(amounts - ref["TOTALDOSE"])) < 1e-9 * d.DOSE
    assert ref["TOTALDOSE"][-1] == pytest.approx(2 * d.DOSE, rel=1e-12)
    n = len(d.NAMES)
    m = np.column_stack([d.rhs(0.0, np.eye(n)[j], {"RATE": 0.0}) for j in range(n)])
    windows = d.infusion_windows()
    vein, total = d.NAMES.index("AV"), d.NAMES.index("TOTALDOSE")

    def b(t):
        on = any(a <= t < e for a, e in windows)
        v = np.zeros(n)
        v[vein] = v[total] = d.DOSE / d.DOSEOFF if on else 0.0
        return v

    pick = ref["T"][[0, 10, 50, 51, 200, 1250, 1300, 2000, 2500]]
    exact = _linear_response(m, b, np.zeros(n), list(pick),
                             [x for w in windows for x in w])
    got = np.array([ref[name][np.searchsorted(ref["T"], pick)] for name in d.NAMES]).T
    scale = np.max(np.abs(got), axis=0) + 1.0
    assert np.max(np.abs(exact - got) / scale) < 1e-8


def test_lapatinib_doses_and_superposition():
    ref = lapatinib_md.run()
    assert lapatinib_md.dose_times() == [0.0, 24.0, 48.0, 72.0, 96.0, 120.0, 144.0, 168.0]
    assert ref["T"].size == 769 and ref["T"][1] == 0.25
    every = slice(None, None, 16)  # every 4 h, including each dose instant
    sup = lapatinib_md.superposition(ref["T"][every])
    got = np.array([ref[n][every] for n in lapatinib_md.STATES]).T
    scale = np.max(np.abs(got), axis=0)
    # event-by-event integration at rtol 1e-10 vs exact exponentials: 1e-8 of each
    # state's range leaves room for 1e-10 per step accumulated over 192 h
    assert np.max(np.abs(sup - got) / scale) < 1e-8
    # the row at a dose instant shows the post-dose lumen amount
    i24 = int(np.searchsorted(ref["T"], 24.0))
    assert ref["A_lumen"][i24] > ref["A_lumen"][i24 - 1] + 0.9 * lapatinib_md.RDOSE


def test_minmod4_rk4_steps_and_tight_solve_agree():
    tight = minmod4.run(rtol=1e-12)
    ref = minmod4.run()
    rk = minmod4.rk4()
    for name in minmod4.STATES:
        scale = np.max(np.abs(tight[name]))
        # rtol 1e-10 reference vs 1e-12: the reference's own error is below 1e-9
        assert np.max(np.abs(ref[name] - tight[name])) < 1e-9 * scale
        # RK4 at DELT = 0.005 has a global error ~h^4 * 1e-2: below 1e-9 of each state,
        # so amilpy's RK4 run and an accurate run must both match the reference
        assert np.max(np.abs(rk[name] - tight[name])) < 1e-9 * scale
    assert ref["T"].size == 21


@pytest.mark.parametrize("name", ["legumes", "maize"])
def test_water_stress_recurrence(name):
    r = water_stress.run(name)
    c = water_stress.LISTINGS[name]
    assert r["TIME"][0] == c["STTIME"] and r["TIME"][-1] == c["FINTIM"]
    assert np.all(np.diff(r["TIME"]) == 1.0)
    # BALANCE is the listing's own check; Euler keeps it exact to round-off
    assert np.max(np.abs(r["BALANCE"])) < 1e-9
    # the tipping bucket never holds more than field capacity after a step
    assert np.max(r["WSOIL"]) <= r["WSOILMAX"][0] + 1e-9
    # the synthetic weather drives both branches of INSW and MAX (else the test of
    # amilpy against this reference would not exercise them)
    assert r["RATIOACTPOT"].min() < 1.0 and r["WPERC"][-1] > 0.0
    # one Euler step by hand, from row k to row k+1 (step-point mode, DELT = 1)
    k = 40
    step = r["RAIN"][k] - r["RTRANSPACT"][k] - r["RPERC"][k]
    assert r["WSOIL"][k + 1] == pytest.approx(r["WSOIL"][k] + step, abs=1e-12)
    assert r["WTOT"][k + 1] == pytest.approx(r["WTOT"][k] + r["GROWTH"][k], abs=1e-12)


@pytest.mark.parametrize("year", [2018, 2019])
def test_weather_files_are_the_generator_output(year):
    path = water_stress.weather_path(year)
    assert path.read_text() == water_stress.cabo_text(year)
    rows = water_stress.read_cabo(path)
    assert sorted(rows) == list(range(1, 366))
    assert all(row["RDD"] > 0 and row["TMMX"] > row["TMMN"] for row in rows.values())


def test_smooth_references_keep_their_listings_balances():
    from listings.references import dcm, isolated_liver, warfarin

    # the perfused liver: what came in is in the liver, metabolized or out
    r = isolated_liver.run()
    assert np.max(np.abs(r["AL"] + r["AM"] + r["OUT"] - r["TOTAL"])) < 1e-9 * r["TOTAL"][-1]
    # the closed chamber: what was in the chamber at the start is in the chamber, in
    # the NMICE mice or metabolized by them
    r = dcm.run()
    total = r["ACH"] + dcm.NMICE * sum(r[n] for n in dcm.STATES[:-1])
    assert np.max(np.abs(total - dcm.ACH0)) < 1e-9 * dcm.ACH0
    # warfarin: the listing's BAL = dose - TMASS is zero
    r = warfarin.run()
    assert np.max(np.abs(sum(r[n] for n in warfarin.STATES) - warfarin.DOSE)) \
        < 1e-9 * warfarin.DOSE


@pytest.mark.parametrize("inter, conc", [(0, None), (1, {"B": 0.0, "T": 17.0, "E": 33.0,
                                                          "X": 33.0})],
                         ids=["as_written", "tardif1997_mixture"])
def test_btex_two_integrators_and_mass_balance(inter, conc):
    from listings.references import btex

    ref = btex.run(conc, inter=inter, with_exhaled=True)
    # DOP853 at rtol 1e-13 against LSODA (multistep, Adams/BDF) at 1e-12: measured
    # 1.2e-11 of AMPE's range as written (LSODA's own error: Radau at 1e-12 agrees to
    # 2.2e-12), far below the 1e-8 the listing tests ask of amilpy
    other = btex.run(conc, inter=inter, method="LSODA", rtol=1e-12, atol=1e-14)
    for k in btex.STATES:
        scale = np.max(np.abs(ref[k])) or 1.0
        assert np.max(np.abs(other[k] - ref[k])) < 1e-10 * scale, k
    inhaled = btex.inhaled(ref["T"], conc)
    for s in btex.CHEMICALS:
        acc = ref["ACC" + s]
        # the listing's BILAN: what stayed in (ACC) is in the tissues or metabolized
        # (measured 3e-15 of ACC's largest value: a linear invariant, kept to round-off)
        tiss = sum(ref[k + s] for k in ("AR", "AG", "AMP", "AF", "MET"))
        assert np.max(np.abs(acc - tiss)) <= 1e-12 * max(1.0, np.max(acc))
        # and what was breathed in (QALV*CEXPO times the time exposed, closed form) is
        # what stayed in plus what was breathed out (measured 1.4e-15)
        assert np.max(np.abs(inhaled[s] - acc - ref["EXHALED_" + s])) \
            <= 1e-12 * max(1.0, inhaled[s][-1])
    if conc is None:  # the 7-hour exposure, and the rows around its end
        assert np.allclose(inhaled["X"][-1], btex.QALV * btex.cexpo(btex.CONC)["X"] * 7.0,
                           rtol=1e-15)
        i = int(np.argmin(np.abs(ref["T"] - 7.0)))
        assert ref["CPPMX"][i] < 0.85 * ref["CPPMX"][i - 1]  # post-event: JOURNE = 0
