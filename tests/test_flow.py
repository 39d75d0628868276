"""The run loop as a flow map (`amilpy.run.Flow.advance`): the state after an
interval, its events, and the monodromy matrix d(final state)/d(initial state),
against closed forms: a linear oscillator (e^{AT}) and a dead-zone oscillator
whose flow crosses two switches (the saltation at each in the matrix)."""

import math
import os

import numpy as np
import pytest
from conftest import METHODS, ROOT
from scipy.linalg import expm

import amilpy
from amilpy.run import Flow, Options

K, C = 4.0, 0.3  # X'' + C X' + K X = 0
OSCILLATOR = f"""PARAM K = {K}, C = {C}
X = INTGRL(1.0, V)
V = INTGRL(0.5, -K*X - C*V)
TIMER FINTIM = 10.0, OUTDEL = 0.1
END
"""

D, KD = 0.5, 4.0  # a spring that acts only outside |X| <= D
DEAD_ZONE = f"""PARAM D = {D}, K = {KD}
X = INTGRL(0.0, V)
V = INTGRL(1.0, -K*DEADSP(-D, D, X))
TIMER FINTIM = 5.0, OUTDEL = 0.1
END
"""

VARIABLE = [m for m in METHODS if amilpy.routes.route_for(m).uses_tolerances]
TIGHT = dict(rtol=1e-11, atol=1e-13)


def _xv(flow: Flow, v: np.ndarray) -> np.ndarray:
    """A state vector (or the rows and columns of a matrix) in (X, V) order."""
    idx = [flow.state_names.index("X"), flow.state_names.index("V")]
    return v[idx] if v.ndim == 1 else v[np.ix_(idx, idx)]


@pytest.mark.parametrize("method", VARIABLE)
def test_linear_oscillator_flow_and_monodromy(method):
    # exact: y(T) = e^{AT} y0 and M = e^{AT}. The states to 1e-9 (RELERR 1e-11 over
    # a few periods); M is a central difference of the flow map, whose error is
    # about RELERR**(2/3) ~ 5e-8: 1e-6 relative is the accuracy promised.
    flow = amilpy.loads(OSCILLATOR).flow(method=method, **TIGHT)
    A = np.array([[0.0, 1.0], [-K, -C]])
    T = 3.7
    end, events, M = flow.advance(flow.initial_state(), 0.0, T, sensitivity=True)
    exact = expm(A * T)
    assert end.t == T and events == []
    assert np.max(np.abs(_xv(flow, end.y) - exact @ [1.0, 0.5])) <= 1e-9
    assert np.max(np.abs(_xv(flow, M) - exact)) <= 1e-6 * np.max(np.abs(exact))


@pytest.mark.parametrize("method", VARIABLE + ["RK4"])
def test_dead_zone_flow_crosses_two_switches_with_saltation(method):
    # From X = 0 at speed 1: free flight to X = D (t1 = D), half a period of the
    # spring (pi/w) back to X = D at speed -1, free flight again. For any start
    # (X0, V0 > 0) that keeps this sequence: X(T) = 2D - X0 - V0 (T - pi/w),
    # V(T) = -V0, so M = [[-1, -(T - pi/w)], [0, -1]]: the two switches' saltations
    # are what make dX/dX0 = -1 (without them a free flight gives +1).
    w = math.sqrt(KD)
    T = 2.5
    options = TIGHT if method != "RK4" else {}
    flow = amilpy.loads(DEAD_ZONE).flow(method=method, **options)
    end, events, M = flow.advance(flow.initial_state(), 0.0, T, sensitivity=True)
    assert _xv(flow, end.y) == pytest.approx([2 * D - (T - math.pi / w), -1.0], abs=1e-8)
    assert [e.time for e in events] == pytest.approx([D, D + math.pi / w], abs=1e-8)
    exact = np.array([[-1.0, -(T - math.pi / w)], [0.0, -1.0]])
    assert np.max(np.abs(_xv(flow, M) - exact)) <= 1e-6


def test_advance_stops_at_the_first_event():
    flow = amilpy.loads(DEAD_ZONE).flow(**TIGHT)
    s0 = flow.initial_state()
    end, events = flow.advance(s0, 0.0, 5.0, stop_at_event=True)
    assert end.t == pytest.approx(D, abs=1e-12) and len(events) == 1
    assert _xv(flow, end.y) == pytest.approx([D, 1.0], abs=1e-10)
    assert end.modes != s0.modes  # the branch entered at the event
    # and goes on from there to the next one, in the new branch
    later, events = flow.advance(end, end.t, 5.0, stop_at_event=True)
    assert later.t == pytest.approx(D + math.pi / 2.0, abs=1e-9)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RK4"])
def test_advance_over_the_run_ends_where_the_run_ends(method):
    # the same route, grid of check instants, breakpoints and events as simulate
    model = amilpy.loads(DEAD_ZONE)
    run, = model.run(method=method, advice=False)
    flow = model.flow(method=method)
    end, events = flow.advance(flow.initial_state(), 0.0, 5.0)
    assert np.array_equal(end.y, run.final_state["y"])
    assert [e.time for e in events] == [e.time for e in run.events]


def test_flow_beyond_fintim_and_from_a_given_state():
    # breakpoints and check instants past the listing's FINTIM, and a state given
    # by value: STEP(6.0) switches the input on at TIME = 6 > FINTIM = 5
    model = amilpy.loads("X = INTGRL(0.0, STEP(6.0) - X)\nTIMER FINTIM = 5.0\nEND\n")
    flow = Flow(model.ir, model.ir.runs[0], Options(rtol=1e-10, atol=1e-12))
    start = flow.state([0.0])
    end, events = flow.advance(start, 0.0, 8.0)
    assert end.y[0] == pytest.approx(1.0 - math.exp(-2.0), abs=1e-8)
    assert [e.time for e in events] == [6.0]


# (FINTIM 30: a step is at most a hundredth of the run, and DOP853's here are 0.2 s)
GRAZE = """PARAM D = 0.999999, K = 100.0
X = INTGRL(0.0, V)
V = INTGRL(1.0, -X + FCNSW(X - D, 0.0, 0.0, -K*(X - D)))
TIMER FINTIM = 30.0, OUTDEL = 0.5
END
"""


def test_a_dip_inside_one_step_is_found_by_the_grazing_guard():
    # X = sin(t) rises above D = 1 - 1e-6 for 2.8 ms around t = pi/2, inside one
    # step of DOP853 (~0.2 s): the loop, which looks at step ends, sees nothing;
    # with the guard the flow takes that step again in pieces and locates both
    # crossings, at asin(D) and pi - asin(D) to the integration's accuracy
    flow = amilpy.loads(GRAZE).flow(method="DOP853", rtol=1e-10, atol=1e-12)
    _, events = flow.advance(flow.initial_state(), 0.0, 3.0)
    assert events == []
    flow.grazing = True
    _, events = flow.advance(flow.initial_state(), 0.0, 3.0)
    t_in = math.asin(0.999999)
    assert [e.time for e in events] == pytest.approx([t_in, math.pi - t_in], abs=1e-6)


def test_a_data_value_as_a_state_of_one_flow():
    # the continuation's trick (analysis.problem.parameter_model): W, read only in
    # DYNAMIC, becomes a state whose derivative is 0; a flow started with W = 71
    # ends where a flow compiled with W = 71 does. ZETA is read by INITIAL: not so.
    from amilpy.analysis.problem import parameter_model
    from amilpy.run import Cache

    model = amilpy.load(os.path.join(ROOT, "models", "hoist_backlash.amil"))
    spec = model._specs({"W": 70.0})[0]
    moved, moved_spec = parameter_model(model.ir, spec, "W")
    assert "W" not in moved_spec.data and moved.states[-1].name == "W"
    assert parameter_model(model.ir, spec, "ZETA") is None
    one = Flow(moved, moved_spec, Options(rtol=1e-10, atol=1e-12), Cache())
    y = np.array(one.initial_state().y)
    y[one.state_names.index("W")] = 71.0
    end, _ = one.advance(one.state(y), 0.0, 0.5)
    other = model.flow(rtol=1e-10, atol=1e-12, W=71.0)
    want, _ = other.advance(other.initial_state(), 0.0, 0.5)
    got = [end.y[one.state_names.index(n)] for n in other.state_names]
    # two integrations of one motion, whose state vectors differ (W a state of one):
    # LSODA's steps differ; each flow is within 1.2e-8 (V2, relative) of a solve at
    # RELERR 1e-13 over these 22 contact events, and AUTO's global error on the hoist
    # at RELERR 1e-10 is up to 2.6e-8 of the range (benchmarks/results/tolerances.md)
    assert got == pytest.approx(list(want.y), rel=3e-8, abs=1e-12)


def test_observers_of_a_step_share_one_evaluation_of_its_dense_output():
    """The variational equations, the grazing guard and a measure each sample every
    step; `Observers` evaluates the step's dense output once at all their instants
    (SciPy's costs about the same for twenty instants as for one). What each reads
    is what it would have read by itself: the same instants, the same states (the
    ends exactly ta and tb)."""
    from scipy.integrate import DenseOutput, solve_ivp

    from amilpy.run.dense import Observers, sample, sample_step

    sol = solve_ivp(lambda t, y: [y[1], -y[0]], (0.0, 1.0), [1.0, 0.0], method="DOP853",
                    dense_output=True)
    calls = []

    class Counted(DenseOutput):  # a step's interpolant, counting its evaluations
        def _call_impl(self, t):
            calls.append(np.ndim(t))
            return sol.sol(t)

    counted = Counted(0.0, 1.0)

    seen = {}

    class Looker:
        def __init__(self, name, fractions):
            self.name, self.fractions = name, np.asarray(fractions, dtype=float)

        def __call__(self, ta, tb, interp, m, z):
            seen[self.name] = (sample_step(interp, ta, tb, self.fractions), interp(ta),
                               interp(tb))

    gauss = Looker("gauss", [0.0, 0.1127, 0.5, 0.8873, 1.0])
    even = Looker("even", np.arange(9) / 8)
    plain = []  # an observer that declares nothing still sees the interpolant
    inner = Observers([even, lambda ta, tb, interp, m, z: plain.append(interp(0.55))])
    Observers([gauss, inner])(0.3, 0.7, counted, [], [])
    assert calls == [1, 0]  # one call for every declared instant, one for the plain one
    for looker in (gauss, even):
        (times, states), at_a, at_b = seen[looker.name]
        expected = 0.3 + (0.7 - 0.3) * looker.fractions
        expected[0], expected[-1] = 0.3, 0.7
        assert np.array_equal(times, expected)
        assert np.array_equal(states, sample(sol.sol, expected))
        assert np.array_equal(at_a, sol.sol(0.3)) and np.array_equal(at_b, sol.sol(0.7))
    assert np.array_equal(plain[0], sol.sol(0.55))
