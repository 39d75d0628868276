"""Exact by default: what a run prints does not depend on the output grid.

A switch that flips and flips back between two output instants, or a peak between
them, is found on every route whatever OUTDEL is: the surfaces are looked at after
every step the integrator takes (AUTO too: LSODA's own steps, recovered from the
evaluations odeint makes), and RANGE reads every step's end as well as the rows.
The references are closed forms and the exact piecewise solution of the clutch
drive (`references/ex4.py`, DOP853 at rtol 1e-12 between located switches).
"""

from __future__ import annotations

import math
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from references import ex4
from scipy.optimize import minimize_scalar

import amilpy

MODELS = Path(__file__).resolve().parents[1] / "models"
WEATHER_DIR = Path(__file__).resolve().parent / "listings" / "weather"  # synthetic CABO files
ROUTES = ["AUTO", "RKS", "DOP853", "STIFF", "COMPILED"]


def with_outdel(path: Path, old: str, new: str) -> amilpy.Model:
    text = path.read_text(encoding="utf-8")
    assert old in text
    return amilpy.loads(text.replace(old, new), path.stem)


# --- a switch that flips and flips back between two rows -------------------------------

HIDDEN = """\
TITLE HIDDEN CROSSINGS: X = SIN(W*TIME) ABOVE 0.5 FOR A THIRD OF EACH PERIOD
PARAM W = 62.83185307179586
DYNAMIC
   X = INTGRL(0.0, W*COS(W*TIME))
   S = FSW(X - 0.5, 0.0, 0.0, 1.0)
   N = INTGRL(0.0, S)
TIMER FINTIM = 1.0, OUTDEL = {outdel}
RANGE X
END
STOP
"""
W = 20.0 * math.pi  # 10 periods in the run


def hidden_crossings() -> list[float]:
    """X = sin(W t) passes 0.5 upwards at (pi/6 + 2 pi k)/W, downwards at (5 pi/6 + ...)."""
    times = [(a + 2.0 * math.pi * k) / W for k in range(10) for a in (math.pi / 6, 5 * math.pi / 6)]
    return sorted(times)


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("outdel", ["0.001", "0.35"])
def test_a_switch_between_two_rows_is_located_on_every_route(route: str, outdel: str) -> None:
    # At OUTDEL 0.35 three rows span ten periods: every crossing pair lies between two
    # rows, and the printout used to show none of them on AUTO. X's error at the
    # default tolerances is below 5e-7, so the crossing instants are right to
    # 5e-7 / (W cos(pi/6)) = 9e-9 s; the time spent above 0.5 is a third of the run.
    run, = amilpy.loads(HIDDEN.format(outdel=outdel), "hidden").run(method=route)
    times = [e.time for e in run.events if e.switch.startswith("FSW")]
    want = hidden_crossings()
    assert len(times) == len(want), (route, outdel, times)
    assert max(abs(a - b) for a, b in zip(times, want, strict=True)) < 1e-8
    assert abs(run.final["N"] - 1.0 / 3.0) < 1e-7
    lo, t_lo, hi, t_hi = run.extrema["X"]
    # the peaks between the rows: 1 at pi/(2W), -1 at 3 pi/(2W) (to the error of X)
    assert abs(hi - 1.0) < 1e-6 and abs(lo + 1.0) < 1e-6
    assert abs(math.sin(W * t_hi) - 1.0) < 1e-6 and abs(math.sin(W * t_lo) + 1.0) < 1e-6


BEFORE_ANOTHER = """\
TITLE FLIPS OF SIN(10*X) BEFORE ANOTHER SWITCH, IN ONE OUTPUT INTERVAL
DYNAMIC
   X  = INTGRL(0.0, 1.0)
   S5 = INTGRL(0.0, FSW(SIN(10.0*X), -1.0, 0.0, 1.0))
   S7 = INTGRL(0.0, FSW(X - 0.75, 0.0, 1.0, 1.0))
TIMER FINTIM = 2.0, OUTDEL = {outdel}
PRINT S5, S7
END
STOP
"""


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("outdel", ["0.1", "2.0"])
def test_flips_before_another_switch_in_the_same_interval_are_located(route, outdel):
    """SIN(10 X) changes sign at k pi/10; X - 0.75 once, at 0.75. At OUTDEL 2.0 the
    one row at 2.0 shows the second crossed and the first as it was (six flips, an
    even number): AUTO located 0.75 alone, and S5 = integral of SIGN(SIN(10 t)) was
    0.743 instead of 2 - 6 pi/10 = 0.115 (hunt 53). Every flip, to 1e-8 in TIME (the
    default tolerances), and S5, S7 to 1e-8."""
    run, = amilpy.loads(BEFORE_ANOTHER.format(outdel=outdel), "flips").run(method=route)
    want = sorted([k * math.pi / 10 for k in range(1, 7)] + [0.75])
    times = sorted(e.time for e in run.events if e.kind == "switch")
    assert len(times) == len(want), (route, outdel, times)
    assert max(abs(a - b) for a, b in zip(times, want, strict=True)) < 1e-8
    assert abs(run.final["S5"] - (2.0 - 6.0 * math.pi / 10)) < 1e-8
    assert abs(run.final["S7"] - 1.25) < 1e-8


ODD_FLIPS = """\
TITLE SIGN OF SIN(W*TIME + PH): ITS FIRST SIGN CHANGE IN EACH ROW INTERVAL
PARAM W = 10.0, PH = 0.1
DYNAMIC
   S = INTGRL(0.0, FSW(SIN(W*TIME + PH), -1.0, 0.0, 1.0))
TIMER FINTIM = 2.0, OUTDEL = {outdel}
PRINT S
END
STOP
"""


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("w, ph, outdel", [(10.0, 0.1, "1.0"), (40.0, 2.0, "2.0"),
                                           (7.0, 1.0, "0.5")])
def test_the_first_of_several_crossings_in_a_row_interval_is_the_one_located(
        route, w, ph, outdel):
    """SIN(W t + PH) changes sign at (k pi - PH)/W: three times in (0, 1) for W = 10,
    PH = 0.1, where the row at 1 shows one change. AUTO searched the root over the
    whole row interval and found the third (S(2) = 0.743 for 0.115, hunt 53; 24 of 25
    changes lost for W = 40, OUTDEL 2). Each change to 1e-8 in TIME, S to 1e-8."""
    run, = amilpy.loads(ODD_FLIPS.format(outdel=outdel), "odd").run(method=route, W=w, PH=ph)
    want = [(k * math.pi - ph) / w for k in range(1, 100) if 0 < (k * math.pi - ph) / w < 2]
    times = [e.time for e in run.events if e.kind == "switch"]
    assert len(times) == len(want), (route, times)
    assert max(abs(a - b) for a, b in zip(times, want, strict=True)) < 1e-8
    edges = [0.0, *want, 2.0]
    exact = sum((b - a) * (1 if k % 2 == 0 else -1)
                for k, (a, b) in enumerate(zip(edges, edges[1:], strict=False)))
    assert abs(run.final["S"] - exact) < 1e-8


@pytest.mark.parametrize("route", ROUTES + ["LSODA", "RADAU", "BDF"])
def test_a_level_edge_at_a_breakpoint_takes_the_level_the_motion_goes_to(route):
    """QNTZR(0.3, X), X = t, has an edge at X = 0.75, where STEP(0.75) restarts the
    run: the level there is the one X goes into (3), as at a located crossing. It
    stayed at 2 until the next step's end (LSODA 0.7568, RADAU 0.7579) or, on AUTO
    with OUTDEL = FINTIM, until the end of the run (S5 = 1.02, hunt 53). S5 =
    integral of the levels 0.3 k = 0.09*21 + 2.1*0.05 = 1.995, to 1e-9."""
    run, = amilpy.loads("TITLE Q\nDYNAMIC\n   X = INTGRL(0.0, 1.0)\n"
                        "   S5 = INTGRL(0.0, QNTZR(0.3, X))\n"
                        "   S7 = INTGRL(0.0, STEP(0.75))\n"
                        "TIMER FINTIM = 2.0, OUTDEL = 2.0\nEND\nSTOP\n", "q").run(method=route)
    assert abs(run.final["S5"] - 1.995) < 1e-9
    assert abs(run.final["S7"] - 1.25) < 1e-9
    levels = [e.time for e in run.events if e.kind == "level"]
    assert levels == pytest.approx([0.15, 0.45, 0.75, 1.05, 1.35, 1.65, 1.95], abs=1e-9)


# --- the clutch drive: the lab report's numbers on every route and grid -------------------

CLUTCH = MODELS / "ex4_clutch.amil"
OUTDEL_AS_SHIPPED = "OUTDEL = 5.0E-5"
RUN_LENGTH = 0.06  # the start-up, the engagement at 35.1 ms and both reversals


@cache
def clutch_reference() -> dict[str, object]:
    """The exact drive's switching instants after T1, W1's minimum and MC's maximum,
    each located on its dense output to rounding."""
    tr = ex4.simulate(ex4.clutch_chain(), RUN_LENGTH, rtol=1e-13, atol=1e-20)
    crossings = tr.crossings()
    t1 = ex4.clutch_time()

    def extremum(name: str, lo: float, hi: float, sign: float) -> float:
        res = minimize_scalar(lambda t: sign * float(tr.sample([t])[name][0]),
                              bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-13})
        return float(tr.sample([res.x])[name][0])

    return {"crossings": crossings, "breakaway": tr.events[0][0],
            "W1 min": extremum("W1", crossings[0], crossings[1], 1.0),
            "MC max": extremum("MC1", t1, crossings[0], -1.0)}


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("outdel", ["5.0E-5", "1.0E-3", "5.0E-3", "0.05"])
def test_clutch_events_and_range_do_not_depend_on_the_grid(route: str, outdel: str) -> None:
    # Exercise 4's clutch: the rotor reverses for 0.24 ms after the engagement; at
    # OUTDEL 1E-3 and coarser no row falls inside. The reversal instants must be the
    # exact drive's to 1e-9 s (W1 passes zero at 1.5e6 rad/s^2: 1e-9 s is an error of
    # 1.5e-3 rad/s in W1, 1.5e-6 of its range), and W1's minimum (-147.92 rad/s) and
    # MC's peak (0.2717 N*m) to 1e-5 of their value.
    ref = clutch_reference()
    model = with_outdel(CLUTCH, OUTDEL_AS_SHIPPED, f"OUTDEL = {outdel}")
    run, = model.run(method=route, fintim=RUN_LENGTH)
    assert run.status == "finished", run.message
    t1 = ex4.clutch_time()
    reversals = [e.time for e in run.events if e.switch.startswith("FSW(W1")
                 and e.time > t1]
    assert len(reversals) == 2, [str(e) for e in run.events]
    for got, want in zip(reversals, ref["crossings"], strict=True):
        assert abs(got - want) < 1e-9, (got, want)
    breakaway = [e.time for e in run.events if e.switch.startswith("FSW(W1")][1]
    assert abs(breakaway - ref["breakaway"]) < 1e-9
    # the breakaway is one switch out of the slide, on every route (the Runge-Kutta
    # routes once listed it as -1 and back to +1 within 3e-16 s)
    switches = [e for e in run.events if e.switch.startswith("FSW(W1") and e.kind == "switch"]
    assert len(switches) == 3, [str(e) for e in run.events]
    w1_min, _, _, _ = run.extrema["W1"]
    _, _, mc_max, _ = run.extrema["MC"]
    assert abs(w1_min - ref["W1 min"]) < 1e-5 * abs(ref["W1 min"]), (w1_min, ref["W1 min"])
    assert abs(mc_max - ref["MC max"]) < 1e-5 * ref["MC max"], (mc_max, ref["MC max"])


@cache
def hoist_edges(fintim: float) -> list[float]:
    from references import hoist

    return hoist.simulate(hoist.Hoist(), 70.0, (0.0, fintim), rtol=1e-13, atol=1e-15).edges


@pytest.mark.parametrize("outdel", ["1.0E-3", "0.05", "0.25"])
def test_hoist_contacts_do_not_depend_on_the_grid(outdel: str) -> None:
    # The hoist's teeth meet or part 18 times in 0.8 s; at OUTDEL 0.05 a single
    # interval holds the first contact (9.694 ms) and the first steps after Y(0) = 0,
    # where ABS(Y) leaves zero. The crossing is located in the LSODA step where the
    # contact surface crosses, not where ABS(Y) leaves zero (the first contact was put
    # at 8.77 ms), and ABS(Y) leaving zero is no event on any grid. Edges to 1e-9 s of
    # the reference (rtol 1e-13, located by its own events): a contact edge moves at
    # |dY/dt| ~ 0.1 m/s, 1e-9 s is 1e-10 of the 4.35 mm half gap.
    model = with_outdel(MODELS / "hoist_backlash.amil",
                        "FINTIM = 5.0, PRDEL = 0.05, OUTDEL = 1.0E-3",
                        f"FINTIM = 0.8, PRDEL = 0.05, OUTDEL = {outdel}")
    run, = model.run()
    assert run.status == "finished", run.message
    contacts = [e.time for e in run.events if e.switch.startswith("INSW(ABS(Y)")]
    assert all(e.switch.startswith(("INSW(ABS(Y)", "DEADSP")) for e in run.events), \
        [str(e) for e in run.events]
    ref = hoist_edges(0.8)
    assert len(contacts) == len(ref) == 18
    assert max(abs(a - b) for a, b in zip(contacts, ref, strict=True)) < 1e-9


# --- grids that cannot be right are refused ------------------------------------------------

def test_an_output_interval_longer_than_the_run_is_refused() -> None:
    # FINTIM 0.5 with OUTDEL 1.0 printed two rows and plotted a straight line
    model = with_outdel(CLUTCH, OUTDEL_AS_SHIPPED, "OUTDEL = 1.0")
    with pytest.raises(amilpy.AmilError) as err:
        model.run()
    text = err.value.render()
    assert "OUTDEL = 1 is longer than the run" in text and "hint" in text
    assert err.value.line == 61  # the TIMER statement
    with pytest.raises(amilpy.AmilError, match="PRDEL = 0.01 is longer than the run"):
        amilpy.load(CLUTCH).run(fintim=0.005)


# --- ACSL: an instant that changes nothing the derivatives read costs no restart ----------

DYNAMIC_OUTPUTS = """\
PROGRAM decay with outputs computed at every CINT instant
  CONSTANT K = 0.5, TSTOP = 10.0
  CINTERVAL CINT = 0.01
  INITIAL
    Y0 = 1.0
    KR = K
  END
  DYNAMIC
    DERIVATIVE
      Y = INTEG(-KR*Y, Y0)
      Z = INTEG(Y, 0.0)
    END
    {dynamic}
    TERMT(T >= TSTOP)
  END
END
"""


def acsl_run(dynamic: str) -> amilpy.Run:
    run, = amilpy.loads(DYNAMIC_OUTPUTS.format(dynamic=dynamic), "decay").run()
    assert run.status == "stopped", run.message
    return run


@pytest.mark.parametrize("dynamic", [
    "YPCT = 100.0*Y/Y0\n    KR = K",  # an output, and a value the derivatives read, unchanged
    "KR = K\n    IF (T > 100.0) KR = 2.0*K",  # a test that never changes it
])
def test_acsl_instants_that_change_nothing_cost_no_restart(dynamic: str) -> None:
    # 1000 CINT instants: each used to restart LSODA from order 1 (7016 evaluations,
    # Y off by 2.4e-5); going on with the same integration takes the evaluations of a
    # run without DYNAMIC statements and is as exact as the tolerance
    run = acsl_run(dynamic)
    plain = acsl_run("KR = K") if "IF" in dynamic else None
    t = run.t
    assert np.max(np.abs(run["Y"] - np.exp(-0.5 * t))) < 2e-6
    assert np.max(np.abs(run["Z"] - (1.0 - np.exp(-0.5 * t)) / 0.5)) < 4e-6
    assert run.stats["nfev"] < 2500
    if plain is not None:
        assert abs(run.stats["nfev"] - plain.stats["nfev"]) <= 0.05 * plain.stats["nfev"]


WITHOUT_DYNAMIC = DYNAMIC_OUTPUTS.replace(
    "      Z = INTEG(Y, 0.0)\n", "      Z = INTEG(Y, 0.0)\n      TERMT(T >= TSTOP)\n").replace(
    "    {dynamic}\n    TERMT(T >= TSTOP)\n", "").replace(
    "  CINTERVAL CINT = 0.01\n", "  CINTERVAL CINT = 0.01\n  MAXTERVAL MAXT = 0.01\n")


@pytest.mark.parametrize("method", ["LSODA", "BDF", "RADAU", "DOP853", "RKS"])
def test_acsl_instants_that_change_nothing_cost_no_restart_on_the_step_routes(method):
    # The step-by-step routes ended a segment at each of the 1000 CINT instants and
    # started the next afresh (LSODA from order 1: 28,899 evaluations, BDF 27,000);
    # the step over an instant is now handed out in two, and the same integration
    # goes on. It costs what the program without a DYNAMIC block costs with its
    # steps capped at CINT as this one's are (TERMT in DYNAMIC: the run's length is
    # unknown): measured equal to 3 evaluations in 1,000 to 15,000; within 2 %.
    run, = amilpy.loads(DYNAMIC_OUTPUTS.format(dynamic="YPCT = 100.0*Y/Y0\n    KR = K"),
                        "decay").run(method=method, advice=False)
    plain, = amilpy.loads(WITHOUT_DYNAMIC, "decay").run(method=method, advice=False)
    assert run.status == plain.status == "stopped"
    assert run.stats["nfev"] <= 1.02 * plain.stats["nfev"]
    # (the tolerance of the defaults, RELERR 1e-11: measured 1.5e-11 on BDF)
    assert np.max(np.abs(run["Y"] - np.exp(-0.5 * run.t))) < 1e-9


@pytest.mark.parametrize("method", ["AUTO", "LSODA", "BDF", "DOP853"])
def test_acsl_instant_that_changes_a_rate_restarts_there(method: str) -> None:
    # KR doubles at T = 4 (a CINT instant): Y = exp(-0.5 t) before, then
    # exp(-2 - 1.0 (t - 4)); the change is seen at the instant, not stepped over
    # (the step routes go on through the instants that change nothing: not this one)
    run, = amilpy.loads(DYNAMIC_OUTPUTS.format(dynamic="KR = K\n    IF (T >= 4.0) KR = 2.0*K"),
                        "decay").run(method=method, advice=False)
    t = run.t
    want = np.where(t <= 4.0, np.exp(-0.5 * t), np.exp(-2.0 - 1.0 * (t - 4.0)))
    assert np.max(np.abs(run["Y"] - want)) < 2e-6


# --- draws and weather days: a restart only where the derivatives see a change -----------

DRAWN = """\
TITLE DECAY AND A DRAW HELD FOR EACH OUTPUT INTERVAL
PARAM K = 2.0
X = INTGRL(1.0, {rate})
{reading}
TIMER FINTIM = 10.0, OUTDEL = 0.1
END
STOP
"""


def test_a_draw_only_printed_costs_no_restart() -> None:
    # 100 draws, each due at an output instant: a restart at each cost 1926
    # evaluations where the decay alone takes 455; the run goes on through them and
    # prints the stream's own draws (normal_draw(seed, site 0, 0, k) on interval k)
    from amilpy.library.runtime import normal_draw

    printed = amilpy.loads(DRAWN.format(rate="-K*X", reading="G = GAUSS(0.0, 1.0)\n"
                                        "Y = X + 0.01*G")).run(seed=3)[0]
    plain = amilpy.loads(DRAWN.format(rate="-K*X", reading="")).run()[0]
    assert printed.stats["nfev"] == plain.stats["nfev"]
    assert np.array_equal(printed["G"], [normal_draw(3, 0, 0, k) for k in range(101)])
    assert np.array_equal(printed["X"], plain["X"])
    assert np.max(np.abs(printed["X"] - np.exp(-2.0 * printed.t))) < 1e-10


def test_a_draw_the_derivatives_read_restarts_where_it_changes() -> None:
    # X' = -K X + G with G held at g_k on [t_k, t_k + h): exactly
    # X(t_k + h) = g_k/K + (X(t_k) - g_k/K) exp(-K h), a recurrence over the draws
    run = amilpy.loads(DRAWN.format(rate="-K*X + G", reading="G = GAUSS(0.0, 1.0)")
                       ).run(seed=3)[0]
    x, decay, want = 1.0, math.exp(-2.0 * 0.1), [1.0]
    for g in run["G"][:-1]:
        x = g / 2.0 + (x - g / 2.0) * decay
        want.append(x)
    assert np.max(np.abs(run["X"] - want)) < 1e-9  # RELERR 1e-10 over 100 restarts


FST_WEATHER = """\
TITLE FST LOGISTIC GROWTH, THE DAY'S MEAN TEMPERATURE {printed}
WEATHER WTRDIR = 'C:\\DATA\\NOWHERE\\'; CNTR = 'TZ'; ISTN = 2
WEATHER IYEAR = 2018
TIMER STTIME = 100.; FINTIM = 300.; DELT = 1.; PRDEL = 10.
PARAM RGR = 0.05; WMAX = 100.
W = INTGRL(1., {rate})
TAVG = (TMMN + TMMX)/2.
PRINT W, TAVG
END
STOP
"""


def test_weather_days_restart_only_where_the_derivatives_read_the_weather() -> None:
    # printed only: the integration goes through the 200 day starts without a restart
    # (3144 evaluations when each was one, 277 now: the logistic's own); read by
    # the rate (W grows only on days warmer than 24.5): a restart at every day start,
    # and W is the product of each day's exact logistic factor
    from references import cabo

    days = cabo.days(WEATHER_DIR / "TZ2.018")
    printed = amilpy.loads(FST_WEATHER.format(printed="PRINTED", rate="RGR*W*(1. - W/WMAX)"),
                           "printed").run(weather_dir=str(WEATHER_DIR), advice=False)[0]
    t = printed.t
    assert np.max(np.abs(printed["W"] - 100.0 / (1.0 + 99.0 * np.exp(-0.05 * (t - 100.0))))
                  ) < 1e-7  # RELERR 1e-10 of W ~ 100, over 200 days
    assert printed["TAVG"].tolist() == [(days[int(d)][1] + days[int(d)][2]) / 2.0 for d in t]
    assert printed.stats["nfev"] < 300

    grows = "INSW(TAVG - 24.5, 0., RGR*W*(1. - W/WMAX))"
    read = amilpy.loads(FST_WEATHER.format(printed="READ", rate=grows), "read").run(
        weather_dir=str(WEATHER_DIR), advice=False)[0]
    w, want = 1.0, {100: 1.0}
    for d in range(100, 300):
        if (days[d][1] + days[d][2]) / 2.0 >= 24.5:
            w = 100.0 / (1.0 + (100.0 / w - 1.0) * math.exp(-0.05))
        want[d + 1] = w
    assert np.max(np.abs(read["W"] - [want[round(d)] for d in read.t])) < 1e-7


# --- events located to a few ulps at the default tolerances -----------------------------

BALL = """\
PROGRAM bouncing ball
  CONSTANT G = 9.81, E = 0.8, H0 = 10.0, TSTOP = 10.0
  CINTERVAL CINT = 0.5
  DERIVATIVE
    V = INTEG(-G, 0.0)
    H = INTEG(V, H0)
    SCHEDULE BOUNCE .XN. H
    TERMT(T >= TSTOP, 'time limit')
  END
  DISCRETE BOUNCE
    V = -E*V
  END
END
"""


def ball_impacts(g: float = 9.81, e: float = 0.8, h0: float = 10.0, t_end: float = 10.0
                 ) -> list[float]:
    """The flights are parabolas: the first impact at sqrt(2 h0/g), then each flight
    lasts 2 v/g with v the rebound speed."""
    t, v = math.sqrt(2.0 * h0 / g), math.sqrt(2.0 * g * h0)
    out = []
    while t < t_end:
        out.append(t)
        v *= e
        t += 2.0 * v / g
    return out


@pytest.mark.parametrize("route", ROUTES + ["LSODA", "BDF"])
def test_bouncing_ball_impacts_at_the_default_tolerances(route: str) -> None:
    # Every Runge-Kutta route integrates a parabola exactly: its impacts are the
    # locator's alone, a few ulps of TIME. LSODA (AUTO's odeint, SciPy's LSODA class)
    # starts each flight at order 1: its impacts carry its trajectory's error, 1.7e-10
    # s at the ACSL form's default RELERR 1e-11. BDF's default is RELERR 1e-8 (SciPy's
    # BDF gives up tighter on the Exercise 4 drives): 0.8 RELERR, 8e-9 s.
    run, = amilpy.loads(BALL, "ball.csl").run(method=route)
    got = [e.time for e in run.events if e.kind == "discrete"]
    want = ball_impacts()
    assert len(got) == len(want) == 7
    bound = {"BDF": 1e-8, "AUTO": 1e-9, "LSODA": 1e-9}.get(route, 64 * 2.2e-16 * 10.0)
    assert max(abs(a - b) for a, b in zip(got, want, strict=True)) <= bound, route


def test_default_tolerances_make_the_printed_digits_right() -> None:
    # The clutch drive at the defaults against its exact solution (matrix exponentials
    # between located switches): every state within 5e-7 of its range, which every
    # digit of the %.6E printout needs (measured on every listing amilpy runs:
    # benchmarks/tolerances.py)
    run, = amilpy.load(CLUTCH).run(fintim=RUN_LENGTH)
    assert run.settings == "RELERR 1e-10, ABSERR 1e-13"
    ref = ex4.simulate(ex4.clutch_chain(), RUN_LENGTH, rtol=1e-13, atol=1e-20).sample(run.t)
    for name, key in (("IA", "IA"), ("W1", "W1"), ("W2", "W2"), ("TH", "TH1")):
        scale = float(np.max(np.abs(ref[key])))
        assert float(np.max(np.abs(run[name] - ref[key]))) <= 5e-7 * scale, name


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "LSODA", "RADAU", "BDF", "STIFF"])
@pytest.mark.parametrize("rtol", [1e-5, 1e-7])
def test_a_switch_only_printed_shows_its_sign_at_every_row(method, rtol):
    """A switch no derivative reads crosses silently (no event: its mode follows the
    sign). Its mode was set where the step ended, and the rows inside that step were
    printed with it: S = -1 at TIME 0.68 and 0.69 where X = 0.5066 and 0.5016 (RKS and
    LSODA at RELERR 1e-7). Every row must show the sign of X - 0.5 where it is."""
    text = ("TITLE DECAY\nX = INTGRL(1.0, -X)\nS = FSW(X - 0.5, -1.0, 0.0, 1.0)\n"
            "TIMER FINTIM = 3.0, OUTDEL = 0.01\nPRINT X, S\nEND\n")
    run, = amilpy.loads(text).run(method=method, rtol=rtol, atol=rtol * 1e-3)
    rows = run.outdel_mask | run.prdel_mask
    assert np.array_equal(run["S"][rows], np.sign(run["X"][rows] - 0.5))
