"""Step-point mode (contract section 14): METHOD RECT/EULER reproduce the classic
fixed-step translators' loop exactly, and `--step-point` / `step_point=True` put any
fixed-step method in it.

At each step point t_k = t0 + k*DELT: the sorted code with the states at t_k (every
switch read there, memory updated there), a row on the PRDEL grid or at the end,
FINISH/TERMT tested, then the step (y += DELT*rates with DELT itself). The
references below are that loop written out in plain Python/NumPy, independently of
amilpy. They agree bit for bit today (the generated code adds the same terms in the
same order); the bound is round-off, 1e-14, so that a compiler folding constants in
another order is not mistaken for a fault.
"""

import math

import numpy as np
import pytest
from conftest import run1

import amilpy
from amilpy.diagnostics import AmilError
from amilpy.run.steppoint import steps

ROUND_OFF = 1e-14

EULER_MODEL = """TITLE EULER IN STEP-POINT MODE
PARAM K = 2.0
X = INTGRL(1.0, -K*X + S + F)
S = STEP(0.25)
F = FSW(X - 0.9, 0.5, 0.0, -0.5)
H = HSTRSS(0.0, -0.05, 0.05, X)
D = DELAY(4, 0.2, X)
Y = INTGRL(0.0, H + D)
TIMER FINTIM = 3.0, DELT = 0.1, PRDEL = 0.2
METHOD {method}
END
"""


def euler_reference(n: int, delt: float = 0.1):
    """The same model as the classic loop: switches read at t_k (STEP(0.25) is 1 from
    the first point at or after 0.25), HSTRSS from its value at the last point, the
    delay X(t_k - 0.2) = X_{k-2} (X(0) before 0.2), then y += DELT*rates."""
    k_, x, y, h = 2.0, 1.0, 0.0, 0.0
    xs, ys, hs, ds, ts = [], [], [], [], []
    for k in range(n + 1):
        t = k * delt
        h = min(x + 0.05, max(x - 0.05, h))
        d = xs[k - 2] if k >= 2 else (xs[0] if xs else x)
        s = 0.0 if t < 0.25 else 1.0
        f = 0.5 if x - 0.9 < 0 else (0.0 if x - 0.9 == 0 else -0.5)
        ts.append(t), xs.append(x), ys.append(y), hs.append(h), ds.append(d)
        x, y = x + delt * (-k_ * x + s + f), y + delt * (h + d)
    return tuple(np.array(v) for v in (ts, xs, ys, hs, ds))


@pytest.mark.parametrize("method", ["EULER", "RECT"])
def test_euler_is_the_plain_recurrence(method):
    """A STEP, a switch on a state, HSTRSS and DELAY, against the loop written out:
    every row, to round-off (it was located switching before section 14: the STEP at
    0.25 exactly, the FSW where X crossed 0.9)."""
    r = run1(EULER_MODEL.format(method=method))
    assert r.ok and r.settings == "DELT 0.1, step-point mode"
    t, x, y, h, d = euler_reference(30)
    rows = np.arange(0, 31, 2)  # PRDEL = 2*DELT
    assert np.array_equal(r.t, t[rows])
    for name, ref in (("X", x), ("Y", y), ("H", h), ("D", d)):
        assert np.max(np.abs(r[name] - ref[rows])) <= ROUND_OFF, name
    # the branch changes are listed at the step points where they were seen
    assert [(round(e.time, 12), e.switch.split("(")[0]) for e in r.events][:2] == \
        [(0.1, "FSW"), (0.3, "STEP")]


def test_step_switches_at_the_next_step_point():
    """No breakpoints in step-point mode: STEP(2.5) with DELT = 1 switches at t = 3."""
    body = "X = INTGRL(0.0, STEP(2.5))\nTIMER FINTIM = 5, DELT = 1, PRDEL = 1\n"
    r = run1(body + "METHOD EULER\nEND\n")
    assert list(r["X"]) == [0, 0, 0, 0, 1, 2]
    located = run1(body + "METHOD RK4\nEND\n")  # the other fixed-step routes locate it
    assert list(located["X"]) == [0, 0, 0, 0.5, 1.5, 2.5]


@pytest.mark.parametrize("stop", ["FINISH X = 0.55", "TERMT(X - 0.55)"])
def test_finish_and_termt_stop_at_the_step_point_with_its_row(stop):
    """X = t in steps of 0.1: X first reaches 0.55 at the step point 0.6, which is
    not on the PRDEL grid: the run stops there and that is its last row."""
    termt = stop.startswith("TERMT")
    r = run1("X = INTGRL(0.0, 1.0)\n" + (stop + "\n" if termt else "")
             + "TIMER FINTIM = 2.0, DELT = 0.1, PRDEL = 0.5\n"
             + ("" if termt else stop + "\n") + "METHOD EULER\nEND\n")
    assert r.status == "stopped"
    assert r.t[-1] == pytest.approx(0.6, abs=1e-15) and list(r.t[:-1]) == [0.0, 0.5]
    assert r["X"][-1] == pytest.approx(0.6, abs=1e-15)
    assert r.events[-1].time == r.t[-1] and r.events[-1].kind in ("finish", "termt")


def test_termt_is_tested_at_t0():
    r = run1("X = INTGRL(1.0, 1.0)\nTERMT(X - 0.5)\nTIMER FINTIM = 1.0, DELT = 0.1\n"
             "METHOD EULER\nEND\n")
    assert r.status == "stopped" and list(r.t) == [0.0]


@pytest.mark.parametrize("fintim, last", [(1.05, 1.1), (1.0005, 1.0), (1.002, 1.1),
                                          (0.96, 1.0), (0.999, 1.0)])
def test_the_number_of_steps_rule(fintim, last):
    """N = round((FINTIM - t0)/DELT), plus one when the rest exceeds 0.01*DELT: the
    run may end a little past FINTIM or a little short of it."""
    assert steps(fintim, 0.1) == round(last / 0.1)
    r = run1(f"X = INTGRL(0.0, 1.0)\nTIMER FINTIM = {fintim}, DELT = 0.1, PRDEL = 0.5\n"
             "METHOD EULER\nEND\n")
    assert r.t[-1] == pytest.approx(last, abs=1e-12)
    assert r["X"][-1] == pytest.approx(last, abs=1e-12)
    # rows on the PRDEL grid, then the last point
    assert list(np.round(r.t, 12)) == sorted({0.0, 0.5, 1.0} - ({1.0} if last < 1 else set())
                                             | {last})


def test_prdel_must_be_a_multiple_of_delt():
    text = "X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0, DELT = 0.1, PRDEL = 0.25\n" \
           "METHOD EULER\nEND\n"
    with pytest.raises(AmilError) as err:
        amilpy.loads(text).run()
    message = err.value.render()
    assert "PRDEL = 0.25 is not a multiple of DELT = 0.1" in message
    assert "write PRDEL = 0.2 or 0.3, or DELT = 0.0833333" in message
    assert err.value.line == 2
    # the located routes make DELT divide the output interval instead
    assert amilpy.loads(text.replace("EULER", "RK4")).run()[0].ok


def test_step_point_needs_a_fixed_step_method():
    model = amilpy.loads("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nMETHOD RKS\nEND\n")
    with pytest.raises(AmilError, match="step-point mode needs a fixed-step method .* "
                                        "METHOD RKS chooses its own steps"):
        model.run(step_point=True)
    with pytest.raises(AmilError, match="METHOD AUTO chooses its own steps"):
        model.run(method="AUTO", step_point=True)


def test_step_point_false_takes_euler_back_to_located_switching():
    r = run1("X = INTGRL(0.0, STEP(2.5))\nTIMER FINTIM = 5, DELT = 1, PRDEL = 1\n"
             "METHOD EULER\nEND\n", step_point=False)
    assert list(r["X"]) == [0, 0, 0, 0.5, 1.5, 2.5] and r.settings == "DELT 1"


RK4_MODEL = """X = INTGRL(1.0, V)
V = INTGRL(0.0, -X - FSW(V, -0.4, 0.0, 0.4) + STEP(0.55))
H = ZHOLD(IMPULS(0.0, 0.5), X)
W = INTGRL(0.0, H)
TIMER FINTIM = 4.0, DELT = 0.1, PRDEL = 0.1
END
"""


def rk4_reference(n: int, delt: float = 0.1):
    """RK4 as CSMP's RKSFX ran it: the derivative section, switches and all, read at
    each stage point (ZHOLD passes X through while IMPULS reads 1, which it does for
    an instant in (t - DELT, t]); its memory changes only at the step points."""
    def impulse(t):  # IMPULS(0.0, 0.5) by the step-point rule
        j = math.ceil((t - delt + 1e-9 * delt) / 0.5)
        return j * 0.5 <= t + 1e-9 * delt

    def rates(t, s, held):
        x, v, w = s
        friction = -0.4 if v < 0 else (0.0 if v == 0 else 0.4)
        return np.array([v, -x - friction + (1.0 if t >= 0.55 else 0.0),
                         x if impulse(t) else held])

    s, held, rows = np.array([1.0, 0.0, 0.0]), 0.0, []
    for k in range(n + 1):
        t = k * delt
        if impulse(t):
            held = s[0]
        rows.append((t, *s, held))
        k1 = rates(t, s, held)
        k2 = rates(t + delt / 2, s + delt / 2 * k1, held)
        k3 = rates(t + delt / 2, s + delt / 2 * k2, held)
        k4 = rates(t + delt, s + delt * k3, held)
        s = s + delt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return np.array(rows)


def test_rk4_in_step_point_mode_reads_switches_at_each_stage():
    """--step-point with RK4: the classic RKSFX, against its loop written out."""
    r = run1(RK4_MODEL + "", method="RK4", step_point=True)
    ref = rk4_reference(40)
    assert r.settings == "DELT 0.1, step-point mode"
    for i, name in enumerate(("X", "V", "W", "H"), start=1):
        assert np.max(np.abs(r[name] - ref[:, i])) <= ROUND_OFF, name


@pytest.mark.parametrize("method", ["EULER", "RK4", "TRAPZ", "ADAMS"])
def test_an_impulse_weighs_delt_on_every_method(method):
    """IMPULS in step-point mode is 1 at the first step point at or after each
    instant; integrated by any of the fixed-step methods, each instant weighs
    exactly DELT, so INTGRL(0, IMPULS/DELT) counts the instants (0.35, 1.35, 2.35:
    off the grid, like the classic translators' impulses)."""
    r = run1("N = INTGRL(0.0, IMPULS(0.35, 1.0)/DELT)\nTIMER FINTIM = 3.0, DELT = 0.1, "
             "PRDEL = 0.1\nEND\n", method=method, step_point=True)
    t = r.t
    # the count steps up after the step point 0.4 (EULER: the next point), by 1
    assert r["N"][-1] == pytest.approx(3.0, abs=1e-12)
    assert np.all(r["N"][t < 0.35] == 0.0)


def test_memory_and_limits_on_a_run_with_many_steps():
    """A long step-point run keeps its counts and stops at the step limit with its rows."""
    r = run1("X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 100.0, DELT = 0.01, PRDEL = 1\n"
             "METHOD EULER\nEND\n", max_steps=2500)
    assert not r.ok and "step" in r.message and r.t[-1] == pytest.approx(25.0)
    assert r.stats["nsteps"] == 2500


def test_printout_header_shows_the_mode():
    from amilpy.output.printout import format_runs

    r = run1(EULER_MODEL.format(method="RECT"))
    assert "(METHOD RECT, DELT 0.1, step-point mode)" in format_runs([r])


def test_flow_in_step_point_mode_advances_like_the_run():
    model = amilpy.loads(EULER_MODEL.format(method="EULER"))
    run, = model.run()
    flow = model.flow()
    end, events = flow.advance(flow.initial_state(), 0.0, 3.0)
    assert end.t == pytest.approx(3.0) and end.y[0] == run.final["X"]
    assert [e.time for e in events] == [e.time for e in run.events]
