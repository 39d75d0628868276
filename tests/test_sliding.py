"""Sliding per surface and on several surfaces at once (issue 15): the convex
combination on the intersection of the sliding surfaces, on every method,
against exact solutions."""

import math

import numpy as np
import pytest
from conftest import METHODS, run1

import amilpy

RELAY = "FSW(X, -1.0, 0.0, 1.0)"
# Sliding is located switching. METHOD EULER runs in step-point mode by default (the
# classic translators' loop: a relay there chatters from step to step, as it did in
# CSMP), so these tests ask every method for located switching (step_point=False).
LOCATED = {"step_point": False, "advice": False}


@pytest.mark.parametrize("shared", [False, True], ids=["two_switches", "shared_variable"])
@pytest.mark.parametrize("method", METHODS)
def test_switches_on_one_surface_slide_together(method, shared):
    # X' = -s, Y' = s with s the relay on X: X reaches 0 at TIME 1 and slides there,
    # where s = 0 keeps it; so Y(3) = Y(1) = 1 exactly. Written with the relay twice,
    # the second switch flipped at the slide and gave Y(3) = 3.
    body = (f"S = {RELAY}\nX = INTGRL(1.0, -S)\nY = INTGRL(0.0, S)\n" if shared else
            f"X = INTGRL(1.0, -{RELAY})\nY = INTGRL(0.0, {RELAY})\n")
    r = run1(body + "TIMER FINTIM = 3.0, OUTDEL = 0.1\nEND\n", method=method, **LOCATED)
    assert r.status == "finished", r.message
    assert r["Y"][-1] == pytest.approx(1.0, abs=1e-9)
    assert r["X"][-1] == pytest.approx(0.0, abs=1e-9)
    assert all(e.kind == "slide" and e.time == pytest.approx(1.0) for e in r.events)


TWO_RELAYS = """X = INTGRL(1.0, -FSW(X, -1.0, 0.0, 1.0) - 0.5*FSW(Y, -1.0, 0.0, 1.0))
Y = INTGRL(1.0, -FSW(Y, -1.0, 0.0, 1.0) + 0.5*FSW(X, -1.0, 0.0, 1.0))
TIMER FINTIM = 4.0, OUTDEL = 0.1
END
"""

TWO_RELAYS_SHARED = """SX = FSW(X, -1.0, 0.0, 1.0)
SY = FSW(Y, -1.0, 0.0, 1.0)
X = INTGRL(1.0, -SX - 0.5*SY)
Y = INTGRL(1.0, -SY + 0.5*SX)
TIMER FINTIM = 4.0, OUTDEL = 0.1
END
"""


@pytest.mark.parametrize("method", METHODS)
def test_two_relays_slide_to_the_origin(method):
    # Both relays end sliding at X = Y = 0 (both surfaces at once: the weights solve
    # X' = Y' = 0, each relay reading 0). The exact Y(4) is 0; it used to end at
    # -4.53 or -1.20 depending on the method.
    r = run1(TWO_RELAYS, method=method, **LOCATED)
    assert r.status == "finished", r.message
    assert abs(r["X"][-1]) <= 1e-9 and abs(r["Y"][-1]) <= 1e-9


@pytest.mark.parametrize("method", METHODS)
def test_two_relays_trajectory(method):
    # X' = -1.5, Y' = -0.5 until X = 0 at 2/3 (Y = 2/3); then X slides (SX = -0.5
    # keeps X' = 0) and Y' = -1.25 until Y = 0 at 1.2; then both slide at the origin.
    # Piecewise linear: every method is exact up to where the slides are located.
    r = run1(TWO_RELAYS_SHARED, method=method, **LOCATED)
    t = r.t
    x = np.where(t < 2 / 3, 1.0 - 1.5 * t, 0.0)
    y = np.where(t < 2 / 3, 1.0 - 0.5 * t, np.maximum(2 / 3 - 1.25 * (t - 2 / 3), 0.0))
    assert np.max(np.abs(r["X"] - x)) <= 1e-9 and np.max(np.abs(r["Y"] - y)) <= 1e-9
    slides = [e.time for e in r.events if e.kind == "slide"]
    assert slides == pytest.approx([2 / 3, 1.2], abs=1e-9)


TWO_FRICTIONS = """PARAM K = 1.0, F1 = 0.3, F2 = 0.2, VB = 1.0, M = 1.0
X = INTGRL(0.0, V)
V = INTGRL(1.0, (FSW(V - VB, F1, 0.0, -F1) + FSW(V - VB, F2, 0.0, -F2) - K*X)/M)
TIMER FINTIM = 1.5, OUTDEL = 0.1
END
"""


@pytest.mark.parametrize("method", METHODS)
def test_stick_slip_with_two_friction_terms_on_one_velocity(method):
    # A block on a belt (speed VB) held by a spring, with two dry-friction terms on
    # the same slip velocity: it sticks (both surfaces slide together) until K*X
    # reaches F1 + F2 = 0.5 at TIME 0.5, then slips: X = 0.5 + sin(TIME - 0.5).
    # One term alone cannot hold past K*X = F1 = 0.3: a per-switch slide let go there.
    # Both terms stand on one surface (V - VB), so the stick ends in one event.
    r = run1(TWO_FRICTIONS, method=method, **LOCATED)
    assert r.status == "finished", r.message
    t = r.t
    x = np.where(t <= 0.5, t, 0.5 + np.sin(t - 0.5))
    # ten RELERR units over the slip arc; the fixed steps at DELT = OUTDEL/16
    tol = {"EULER": 5e-3, "TRAPZ": 1e-5, "ADAMS": 1e-5}.get(method, 1e-5)
    assert np.max(np.abs(r["X"] - x)) <= tol
    leave = [e.time for e in r.events if e.old == 0.5]
    assert leave == pytest.approx([0.5], abs=1e-6)


GAP = """Y = INTGRL(-1.0, 1.0)
S = FSW(Y, -1.0, 0.0, 1.0)
C = INSW(S*Y - 0.5, 0.0, 1.0)
X = INTGRL(0.0, C)
TIMER FINTIM = 3.0, OUTDEL = 3.0
END
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "RADAU", "COMPILED"])
@pytest.mark.parametrize("form", ["FSW", "ABS"])
def test_a_switch_read_only_by_another_surface_never_hides_its_crossing(method, form):
    # Y = t - 1 crosses the gap |Y| < 0.5 from t = 0.5 to 1.5; C is 1 outside it, so
    # X(3) = 0.5 + 1.5 = 2 exactly. S (or ABS's own switch) changes no derivative: its
    # crossing at t = 1 is followed without an event. The motion is linear, so one
    # step can span the whole gap: the contact at 1.5 was then read with S's branch
    # from before t = 1 (-Y - 0.5 < 0, still in the gap) and missed (X = 0.5).
    text = GAP if form == "FSW" else \
        GAP.replace("S = FSW(Y, -1.0, 0.0, 1.0)\n", "").replace("S*Y", "ABS(Y)")
    r = run1(text, method=method, advice=False)
    assert r["X"][-1] == pytest.approx(2.0, abs=1e-12)
    assert [e.time for e in r.events] == pytest.approx([0.5, 1.5], abs=1e-12)


def test_more_surfaces_sliding_at_the_start_than_allowed_is_a_failed_run():
    # eight masses at rest, each held by dry friction (1.5 > the drive): the start
    # would slide on more than MAX_SLIDING surfaces at once; the run says so (it was
    # an uncaught exception), and so does a flow asked for its initial state
    text = "\n".join(f"V{i} = INTGRL(0.0, (SIN(TIME) - 1.5*SIGN(1.0, V{i}))/{i + 1}.0)"
                     for i in range(8)) + "\nTIMER FINTIM = 2.0\nEND\n"
    r = run1(text, advice=False)
    assert r.status == "failed" and "switching surfaces slide at once (at most 6)" in r.message
    with pytest.raises(amilpy.AmilError, match="slide at once"):
        amilpy.loads(text, name="s.amil").flow().initial_state()


PUSHED_OFF = """PARAM MU = 0.3, P = 4.0, T1 = 1.5
CONST G = 9.81
A = FSW(V, MU*G, 0.0, -MU*G) + P*STEP(T1)
V = INTGRL(2.0, A)
X = INTGRL(0.0, V)
TIMER FINTIM = 3.0, OUTDEL = 0.1
END
"""


@pytest.mark.parametrize("method", METHODS)
def test_a_push_on_time_ends_the_slide_at_its_instant(method):
    # Stuck by dry friction from 2/(MU G) = 0.68 s, the block is pushed at T1 = 1.5 by
    # P > MU G: it leaves at once, V = (P - MU G)(t - T1). The exit is an event at
    # 1.5 (it was put one step later, 1.5000095 on AUTO and 1.526 on RKS, while the
    # motion itself moved on the right branch from 1.5).
    r = run1(PUSHED_OFF, method=method, **LOCATED)
    leave = [e.time for e in r.events if e.old == 0.5]
    assert leave == pytest.approx([1.5], abs=1e-12)
    t = r.t
    v = np.where(t < 2 / (0.3 * 9.81), 2.0 - 0.3 * 9.81 * t,
                 np.maximum(t - 1.5, 0.0) * (4.0 - 0.3 * 9.81))
    tol = {"EULER": 5e-3}.get(method, 1e-8)
    assert np.max(np.abs(r["V"] - v)) <= tol


SET_POINT_STEPPED = """R = 0.2 + 2.0*STEP(3.0)
X = INTGRL(1.0, -FSW(X - R, -1.0, 0.0, 1.0))
TIMER FINTIM = 8.0, OUTDEL = 0.1
END
"""


@pytest.mark.parametrize("method", METHODS)
def test_a_switch_that_moves_the_sliding_surface_ends_the_slide(method):
    # A relay holds X on R = 0.2 from 0.8 s; at 3 s a STEP moves R to 2.2, the surface
    # X - R jumps to -2 and X rises at 1 until it reaches 2.2 at 5 s, then slides
    # again. Until review 48 every route kept sliding at 0.2 for the rest of the run.
    r = run1(SET_POINT_STEPPED, method=method, **LOCATED)
    t = r.t
    x = np.where(t < 0.8, 1.0 - t, np.where(t < 3.0, 0.2, np.minimum(0.2 + (t - 3.0), 2.2)))
    tol = {"EULER": 5e-3}.get(method, 1e-8)
    assert np.max(np.abs(r["X"] - x)) <= tol
    slides = [e.time for e in r.events if e.kind == "slide"]
    assert slides == pytest.approx([0.8, 5.0], abs=1e-6)


# --- level edges: a quantizer in a feedback loop ------------------------------------
# X' = A - 0.3 Q with Q = QNTZR(0.5, X) (or 0.5 NINT(2 X): the same levels, NINT's
# halves going up). Below the edge X = 3.25 the level is Q = 3 (X' = A - 0.9), above it
# Q = 3.5 (X' = A - 1.05): with A = 1 both push X back to the edge, and it slides there
# (Q between its levels, X' = 0). From TIME 12, A = 1 + 0.05 (TIME - 12): the upper
# level's rate reaches 0 at TIME 13, where X leaves the edge upwards, X = 3.25 +
# 0.025 (TIME - 13)^2, until the next edge 3.75 at t1 = 13 + sqrt(20), which it
# crosses into Q = 4: X' = 0.05 TIME - 0.8.
# Before, RKS and RADAU stopped with a step-size underflow at the edge and AUTO's X
# depended on OUTDEL (2e-3 off at 0.05, 6e-2 at 1.5).
QUANTIZED = {
    "QNTZR": "Q = QNTZR(0.5, X)",
    "NINT": "Q = 0.5*NINT(2.0*X)",
}


def _through_levels(t: np.ndarray, edges: list[float], rates: list[float], then
                    ) -> np.ndarray:
    """X from edges[0] at TIME 0, at rates[k] between edges[k] and edges[k + 1], held
    on the last edge from where it reaches it; `then(t)`, from a TIME on, the value
    past that hold (None before it)."""
    times = [0.0]
    for k, rate in enumerate(rates):
        times.append(times[-1] + (edges[k + 1] - edges[k]) / rate)
    out = np.empty_like(t)
    for i, ti in enumerate(t):
        after = then(ti)
        if after is not None:
            out[i] = after
        elif ti >= times[-1]:
            out[i] = edges[-1]
        else:
            j = int(np.searchsorted(times, ti, side="right")) - 1
            out[i] = edges[j] + rates[j] * (ti - times[j])
    return out


def _quantized_exact(t: np.ndarray) -> np.ndarray:
    """X of the loop above: through the levels k = 0 ... 6 (X' = 1 - 0.15 k, edges at
    0.25 + 0.5 (k - 1)), on the edge 3.25 from t_s to 13, then off it."""
    t1 = 13.0 + 20 ** 0.5

    def then(ti: float) -> float | None:
        if ti >= t1:
            return 3.75 + 0.025 * (ti ** 2 - t1 ** 2) - 0.8 * (ti - t1)
        return 3.25 + 0.025 * (ti - 13.0) ** 2 if ti >= 13.0 else None

    return _through_levels(t, [0.0, 0.25] + [0.25 + 0.5 * k for k in range(1, 7)],
                           [1.0 - 0.15 * k for k in range(7)], then)


@pytest.mark.parametrize("outdel", [0.05, 1.5])
@pytest.mark.parametrize("form", sorted(QUANTIZED))
@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "RADAU", "BDF"])
def test_a_quantizer_in_a_loop_slides_on_the_edge_its_levels_push_back_to(
        method, form, outdel):
    listing = (f"X = INTGRL(0.0, A - 0.3*Q)\n{QUANTIZED[form]}\n"
               "A = 1.0 + 0.05*RAMP(12.0)\n"
               f"TIMER FINTIM = 18.0, OUTDEL = {outdel}\nRANGE X\nEND\n")
    r = run1(listing, method=method, **LOCATED)
    assert r.status == "finished", r.message
    t = np.asarray(r.times)
    # the slide's start is located to rounding and X is held at the edge to 1e-9; the
    # exit, where the upper level's rate is 0 (a tangential departure), to 1e-8 in
    # TIME, and the quadratic after it integrated to the default RELERR's order
    assert np.max(np.abs(np.asarray(r["X"]) - _quantized_exact(t))) <= 3e-8
    slides = [e for e in r.events if e.kind == "slide"]
    t_slide = 10.711611917494004
    assert len(slides) == 1 and slides[0].time == pytest.approx(t_slide, abs=1e-9)
    # the motion leaves the edge where the upper level's rate turns (13), and crosses
    # the next edge (13 + sqrt(20)) into level 8 (QNTZR's 4)
    leave = [e for e in r.events if e.time > t_slide + 1e-6 and e.kind == "level"]
    assert [e.time for e in leave] == pytest.approx([13.0, 13.0 + 20 ** 0.5], abs=1e-6)
    assert str(slides[0]).endswith("stays at 6.5, on the edge between levels 6 and 7: "
                                   "both push it back") if form == "QNTZR" else True
    assert r.range["X"][2] == r["X"][-1]  # (rising to the end)


def test_sensitivities_through_a_level_edge_slide_are_the_closed_form():
    # The loop above with its gain G free: on the edge X = 3.25 whatever G (dX/dG = 0);
    # the upper level Q = 3.5 lets go where A = 3.5 G, at t_e = 12 + (3.5 G - 1)/0.05
    # (dt_e/dG = 70), so X = 3.25 + 0.025 (t - t_e)^2 gives dX/dG = -3.5 (t - 13). At
    # TIME 1, in level 2 since t2 = 0.25 + 0.5/(1 - 0.5 G): dX/dG = -(t - t2) - (1 - G)
    # dt2/dG. From the sensitivity equations, with the slide's entry and exit.
    listing = ("PARAM G = 0.3\nX = INTGRL(0.0, A - G*Q)\nQ = QNTZR(0.5, X)\n"
               "A = 1.0 + 0.05*RAMP(12.0)\nTIMER FINTIM = 16.0, OUTDEL = 1.0\nEND\n")
    s = amilpy.loads(listing, "t.amil").sensitivity(["G"], outputs=["X"])
    assert s.how == "sensitivity equations"
    d = dict(zip(s.times.tolist(), s.raw[:, 0, 0].tolist(), strict=True))
    t2 = 0.25 + 0.5 / 0.85
    assert d[1.0] == pytest.approx(-(1.0 - t2) - 0.7 * 0.25 / 0.85 ** 2, abs=1e-7)
    for t in (11.0, 12.0, 13.0):
        assert abs(d[t]) <= 1e-9
    for t in (14.0, 15.0, 16.0):
        assert d[t] == pytest.approx(-3.5 * (t - 13.0), abs=1e-6)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU"])
def test_a_tight_tolerance_leaves_the_edge_once(method):
    # At RELERR 1e-12 the slide's drift (2.3 s of it) put X a few tolerance units below
    # the edge where it left, past the band a tangential departure is given: the
    # first steps saw a crossing back to the lower level and a return at once (two
    # spurious events at 13.00001). The band takes the drift the exit left in.
    listing = (f"X = INTGRL(0.0, A - 0.3*Q)\n{QUANTIZED['QNTZR']}\n"
               "A = 1.0 + 0.05*RAMP(12.0)\nTIMER FINTIM = 18.0, OUTDEL = 1.5\nEND\n")
    r = run1(listing, method=method, rtol=1e-12, atol=1e-15, **LOCATED)
    after = [e.time for e in r.events if e.time > 12.5]
    assert after == pytest.approx([13.0, 13.0 + 20 ** 0.5], abs=1e-6)
    assert r["X"][-1] == pytest.approx(_quantized_exact(np.array([18.0]))[0], abs=1e-9)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "RADAU", "BDF"])
@pytest.mark.parametrize("outdel", [0.01, 5.0])
def test_a_start_on_an_edge_its_levels_push_back_to_slides_there(method, outdel):
    # X = 0.5 from the start: below it NINT(X) = 0 (X' = 0.4), above it 1 (X' = -0.2).
    # With a TIME switch in the listing (RAMP(20), 0 all run) the level was chosen
    # before RAMP's branch, in its placeholder (RAMP read TIME - 20: both levels
    # pushed X down), and AUTO's X went to 2.5 at OUTDEL 5. Hunt 50, F1.
    r = run1("X = INTGRL(0.5, 0.4 - 0.6*NINT(X) + 0.05*RAMP(20.0))\n"
             f"TIMER FINTIM = 10.0, OUTDEL = {outdel}\nEND\n", method=method, **LOCATED)
    assert r.status == "finished", r.message
    assert np.max(np.abs(np.asarray(r["X"]) - 0.5)) <= 1e-12
    assert [e.kind for e in r.events] == ["slide"] and r.events[0].time == 0.0


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU", "BDF"])
@pytest.mark.parametrize("form", ["AMOD(X, 1.0)", "X - AINT(X)"])
def test_a_slide_whose_levels_rates_move_with_the_state_is_cheap_on_every_route(method,
                                                                               form):
    # X' = AMOD(X, 1) - 0.5 from 0.6: X = 0.5 + 0.1 e^t up to 1 at ln 5, then held there
    # (below the edge AMOD -> 1, X' = 0.5; above, 0, X' = -0.5). The sliding weight
    # read each level's rate by a look-ahead of 1e-8 of the run, whose rounding (5e-9)
    # the Filippov field then carried: RADAU and BDF took steps of 1e-5 and did not
    # finish in minutes. Hunt 50, F3.
    r = run1(f"X = INTGRL(0.6, -0.5 + {form})\nTIMER FINTIM = 10.0, OUTDEL = 1.0\nEND\n",
             method=method, **LOCATED)
    assert r.status == "finished", r.message
    assert [e.kind for e in r.events] == ["slide"]
    # (the instant to the route's own error in X: BDF's is the largest, 8e-8 here)
    assert r.events[0].time == pytest.approx(math.log(5.0), abs=3e-7)
    assert np.max(np.abs(np.asarray(r["X"])[r.t > 2.0] - 1.0)) <= 1e-9
    assert r.stats["nsteps"] < 2000  # (it took 10^5 and more)


def _slides_against(listing: str, method: str, exact, tolerance: float) -> list[float]:
    """Run `listing` on `method` to its end, X within `tolerance` of `exact(t)` at
    every row; the instants slides start at (to 1e-6)."""
    r = run1(listing, method=method, **LOCATED)
    assert r.status == "finished", r.message
    assert np.max(np.abs(np.asarray(r["X"]) - exact(r.t))) <= tolerance
    return [round(e.time, 6) for e in r.events if e.kind == "slide"]


def _two_quantizers_exact(t: np.ndarray) -> np.ndarray:
    """X' = A - 0.3 QNTZR(0.5, X) - 0.2 QNTZR(0.3, X), A = 0.4 + 0.05 RAMP(5) from 0:
    through the edges 0.15, 0.25, 0.45 (rates 0.4, 0.34, 0.19, 0.13), on the edge 0.75
    both jump at (0.27 below, 0.48 above) until A = 0.48 at 6.6, then 0.75 + 0.025
    (t - 6.6)^2 up to the next edge, 1.05 at 6.6 + sqrt 12."""
    return _through_levels(t, [0.0, 0.15, 0.25, 0.45, 0.75], [0.4, 0.34, 0.19, 0.13],
                           lambda ti: 0.75 + 0.025 * (ti - 6.6) ** 2 if ti >= 6.6 else None)


@pytest.mark.parametrize("outdel", [0.5, 2.5])
@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU", "BDF"])
def test_two_quantizers_that_jump_at_one_edge_slide_there_together(method, outdel):
    # Alone, each sees the other's level as it is, and neither pushes back: the run
    # chattered across 0.75 (200 restarts, a step-size underflow) or hung on DOP853,
    # RADAU and LSODA. Both are chosen together now: all below push up, all above down.
    # Hunt 50, F2.
    slides = _slides_against("X = INTGRL(0.0, A - 0.3*QNTZR(0.5, X) - 0.2*QNTZR(0.3, X))\n"
                             "A = 0.4 + 0.05*RAMP(5.0)\n"
                             f"TIMER FINTIM = 10.0, OUTDEL = {outdel}\nEND\n", method,
                             _two_quantizers_exact, 3e-8)
    assert set(slides) == {4.029442}


def _relay_on_a_quantized_sensor_exact(t: np.ndarray) -> np.ndarray:
    """X' = HEAT - L, HEAT = FSW(1.2 - QNTZR(1.0, X), 0, 0, 1), L = 0.5 + 0.1 t, X(0)
    = 1: the heater is on while the sensor reads 0 or 1 (X < 1.5), off above. X = 1 +
    0.5 t - 0.05 t^2 reaches the edge 1.5 at 5 - sqrt 15; above it X' = -L < 0, below
    X' = 1 - L > 0 until L = 1 at t = 5: it slides on the edge, then leaves it
    downwards, X = 1.5 - 0.05 (t - 5)^2 (the next edge, 0.5, at 5 + sqrt 20)."""
    t1 = 5.0 - np.sqrt(15.0)
    return np.where(t < t1, 1.0 + 0.5 * t - 0.05 * t * t,
                    np.where(t < 5.0, 1.5, 1.5 - 0.05 * (t - 5.0) ** 2))


@pytest.mark.parametrize("outdel", [0.5, 2.5])
@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "RADAU", "BDF", "LSODA"])
def test_a_relay_on_a_quantized_sensor_slides_on_the_sensor_s_edge(method, outdel):
    # The relay's argument jumps with the sensor's level, so at the edge each level
    # must read the relay in the level's own branch: with the relay as it was, neither
    # level pushed back, RKS chattered (200 restarts) and AUTO followed the edge only
    # at its output instants (X(4) = 1.0 for 1.5 at OUTDEL 1). Hunt 50, F4 (fixed
    # 2026-12-01: `SurfaceWatch.follow`). The exit at 5 is tangential, found after
    # the step across it, and the state there is that step's dense output, whose
    # polynomial spans the field's kink: 4e-8 on RKS at the default RELERR (printed
    # to 7 digits: right). To 1e-7.
    slides = _slides_against("X = INTGRL(1.0, HEAT - L)\n"
                             "HEAT = FSW(1.2 - QNTZR(1.0, X), 0.0, 0.0, 1.0)\n"
                             "L = 0.5 + 0.1*TIME\n"
                             f"TIMER FINTIM = 8.0, OUTDEL = {outdel}\nEND\n", method,
                             _relay_on_a_quantized_sensor_exact, 1e-7)
    assert slides == [round(5.0 - np.sqrt(15.0), 6)]


def test_sensitivities_through_a_relay_on_a_quantized_sensor_are_the_closed_form():
    """The same loop with L = L0 + 0.1 TIME: the slide ends at t_e = (1 - L0)/0.1, so
    d X/d L0 = -t before the edge, 0 on it, -(t - t_e) after (X = 1.5 - 0.05 (t -
    t_e)^2): the tangent reads each corner's relay in its level too. To 1e-6 (exact
    to print, measured)."""
    model = amilpy.loads("PARAM L0 = 0.5\nX = INTGRL(1.0, HEAT - L)\n"
                         "HEAT = FSW(1.2 - QNTZR(1.0, X), 0.0, 0.0, 1.0)\nL = L0 + 0.1*TIME\n"
                         "TIMER FINTIM = 8.0, OUTDEL = 0.5\nEND\n", "relay.amil")
    loc = model.sensitivity(["L0"], outputs=["X"], rtol=1e-10, atol=1e-12)
    assert loc.how == "sensitivity equations"
    t = loc.times
    exact = np.where(t > 5.0, -(t - 5.0), np.where(t < 5.0 - np.sqrt(15.0), -t, 0.0))
    assert loc.raw[:, 0, 0] == pytest.approx(exact, abs=1e-6)


@pytest.mark.parametrize("free", ["Q", "TH"])
def test_a_relay_on_a_quantized_sensor_with_its_quantum_or_threshold_free(free):
    """The relay loop with the sensor's quantum Q and the relay's threshold TH free: on
    the edge X = 1.5 Q (d X/d Q = 1.5 there), and TH moves nothing while it stays
    between the levels. At the slide's exit the relay turns with the level the motion
    leaves the edge to; that change was taken for a PULSE train's and the fit went
    to differences (hunt 51 F5). To 1e-6 against the closed form."""
    model = amilpy.loads("PARAM L0 = 0.5, Q = 1.0, TH = 1.2\nX = INTGRL(1.0, HEAT - L)\n"
                         "HEAT = FSW(TH - QNTZR(Q, X), 0.0, 0.0, 1.0)\nL = L0 + 0.1*TIME\n"
                         "TIMER FINTIM = 8.0, OUTDEL = 0.5\nEND\n", "relay.amil")
    loc = model.sensitivity([free], outputs=["X"], rtol=1e-10, atol=1e-12)
    assert loc.how == "sensitivity equations"
    t = loc.times
    if free == "TH":
        assert loc.raw[:, 0, 0] == pytest.approx(np.zeros_like(t), abs=1e-9)
        return
    # d/dQ: the slide holds X = 1.5 Q to t = 5; after it, X = 1.5 Q - 0.05 (t - 5)^2
    t1 = 5.0 - np.sqrt(15.0)
    exact = np.where(t < t1, 0.0, 1.5)
    assert loc.raw[:, 0, 0] == pytest.approx(exact, abs=1e-6)
