"""Jacobians from the model (issue 14.3): the derivative of the frozen-branch vector
field by differentiating the generated right-hand side, checked against central
differences; its sparsity from the dependency graph; a large chain's right side
rolled into NumPy operations on groups of alike equations."""

from __future__ import annotations

import ast
import math
import os
import sys

import numpy as np
import pytest

import amilpy
from amilpy.codegen import jacobian, rolled
from amilpy.run import prepare

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHIPPED = ["ex4_elastic", "ex4_clutch", "ex4_torque_meter", "hoist_backlash",
           "crank_slider_startup", "machine_unit"]


def _compiled(text_or_path):
    model = amilpy.load(text_or_path) if text_or_path.endswith(".amil") else \
        amilpy.loads(text_or_path)
    return prepare(model.ir, model.ir.runs[0]).code


@pytest.mark.parametrize("name", SHIPPED)
def test_jacobian_of_every_branch_matches_differences(name):
    """At random states and in random branches of every switch (-1, 0, +1), the
    generated Jacobian equals central differences of the same frozen-branch field
    to 1e-7 of its largest entry (the differences' own error, step 1e-7: ~1e-9)."""
    c = _compiled(os.path.join(HERE, "models", f"{name}.amil"))
    jac = jacobian.for_compiled(c)
    n = len(c.state_names)
    rng = np.random.default_rng(7)
    for _ in range(10):
        y = rng.normal(size=n)
        modes = [float(rng.choice([-1.0, 0.0, 1.0])) for _ in c.watched]
        z = list(c.z0)
        exact = jac.dense(0.3, y.tolist(), modes, z)
        diff = jacobian.finite_difference(
            lambda t, v, modes=modes, z=z: c.rhs(t, list(v), modes, z), 0.3, y)
        scale = np.abs(diff).max()
        assert np.abs(exact - diff).max() <= 1e-7 * scale
        # the sparsity holds every entry that differences see
        seen = np.abs(diff) > 1e-9 * scale
        pattern = np.zeros((n, n), bool)
        pattern[jac.rows, jac.cols] = True
        assert not np.any(seen & ~pattern)


FUNCTIONS = """TITLE EVERY RULE
FUNCTION TAB = (0.0, 0.0), (1.0, 2.0), (2.0, 3.0)
DYNAMIC
   A = INTGRL(0.3, SIN(B) + COS(A)*EXP(-A) + SQRT(1.5 + B*B) + ALOG(2.0 + A*A))
   B = INTGRL(0.2, ATAN(A) + TANH(B) + ABS(A - 0.1)*B + AFGEN(TAB, 1.0 + A) + A**3)
   C = INTGRL(0.1, AMAX1(A, B) + ASIN(0.5*B) + SINH(A) - COSH(B) + (A + 1.0)**B + C/(1.0 + A))
TIMER FINTIM = 1.0
END
"""


def test_rules_and_numeric_fallback():
    """Every elementary function's rule, the power rule, and the numeric fallback
    (AFGEN, a state to a state's power) agree with differences; ABS and AMAX1 are
    switches, differentiated in the branch they are in at y."""
    c = _compiled(FUNCTIONS)
    jac = jacobian.for_compiled(c)
    for y in ([0.3, 0.2, 0.1], [0.7, -0.4, 1.5]):
        m = c.modes_literal(0.0, y, [0.0] * len(c.watched), [])
        exact = jac.dense(0.0, y, m, [])
        diff = jacobian.finite_difference(lambda t, v, m=m: c.rhs(t, list(v), m, []), 0.0,
                                          np.array(y))
        assert np.abs(exact - diff).max() <= 1e-7 * np.abs(diff).max()
    assert "_DIFF(_AFGEN" in jac.source  # tables go by the numeric route


BRANCHES = """PARAM K = 0.7
X = INTGRL(0.5, -K*W + Y)
Y = INTGRL(0.2, -V)
PROCEDURE W, V = BRANCHES(X, Y)
   W = K*X
   V = 2.0*Y
   IF (X > 0.3) THEN
      W = W*X + Y
      IF (Y > 0.0) THEN
         V = V*Y
      ELSE
         V = 3.0
      ENDIF
   ELSE
      W = SIN(X)*K
   ENDIF
ENDPRO
TIMER FINTIM = 1.0
END
"""


@pytest.mark.parametrize("y", [[0.5, 0.2], [0.5, -0.2], [0.1, 0.2]])
def test_a_procedure_s_if_is_differentiated_branch_by_branch(y):
    """A unit's IF (nested, a name assigned again, a branch whose derivative is a
    constant, one that assigns nothing of V): each branch is differentiated as it
    runs, its test a frozen branch, and every derivative either branch assigns is
    stored at both ends. (The Jacobian refused it, and the callers differenced.)
    d f/d y against central differences of the same branch to 1e-7 of its largest
    entry; d f/d K against its closed form, -W - K dW/dK, to rounding."""
    c = _compiled(BRANCHES)
    jac = jacobian.for_compiled(c)
    m = c.modes_literal(0.0, y, [0.0] * len(c.watched), [])
    exact = jac.dense(0.0, y, m, [])
    diff = jacobian.finite_difference(lambda t, v: c.rhs(t, list(v), m, []), 0.0,
                                      np.array(y))
    assert np.abs(exact - diff).max() <= 1e-7 * np.abs(diff).max()
    x, v, k = y[0], y[1], 0.7
    w, dw = (k * x * x + v, x * x) if x > 0.3 else (math.sin(x) * k, math.sin(x))
    dk = jacobian.for_parameters(c, "rhs").dense(0.0, y, m, [])
    assert dk[:, 0] == pytest.approx([-w - k * dw, 0.0], abs=1e-15)


def test_jacobian_code_is_closed_and_linear():
    """The generated Jacobian reads only the compiler's names, and its size grows
    linearly with the model (the chain: entries and characters per mass constant)."""
    sys.path.insert(0, os.path.join(HERE, "benchmarks"))
    from scale import chain_listing

    sizes = []
    for n in (20, 40, 80):
        jac = jacobian.for_compiled(_compiled(chain_listing(n)))
        sizes.append((jac.nnz / n, len(jac.source) / n))
    assert sizes[0][0] == pytest.approx(sizes[2][0], rel=0.1)
    assert sizes[2][1] <= 1.1 * sizes[0][1]


def test_large_chain_rolls_and_matches_the_scalar_code():
    """A 200-mass chain's 599 statements roll into a handful of NumPy groups whose
    result is the scalar code's, bit for bit (the same operations, correctly
    rounded); a small model is left to the scalar code."""
    sys.path.insert(0, os.path.join(HERE, "benchmarks"))
    from scale import chain_listing

    c = _compiled(chain_listing(200))
    before = ast.dump(c.module)
    f = rolled.for_compiled(c)
    assert f is not None
    # the module's own tree is left as it was: METHOD COMPILED translates it (a
    # 150-mass chain ran as DOP853, "P0 has no compiled form", when rolling it
    # wrote the groups' names into it)
    assert ast.dump(c.module) == before
    y = np.random.default_rng(3).normal(size=400) * 1e-2
    assert np.array_equal(np.asarray(f(0.37, y, [], [])),
                          np.asarray(c.rhs(0.37, y.tolist(), [], [])))
    assert rolled.for_compiled(_compiled(os.path.join(HERE, "models",
                                                      "hoist_backlash.amil"))) is None


def test_rolled_fault_is_the_scalar_codes():
    """Where a rolled group meets a value the language defines as NaN (SQRT of a
    negative argument) the result is the scalar code's; where the scalar code faults
    (a division by zero in one of 500 alike equations) the same fault is raised, so
    the run names the statement as it always did."""
    def listing(rate: str) -> str:
        lines = [f"X{i} = INTGRL(1.0, {rate.format(i=i)})" for i in range(1, 501)]
        return "DYNAMIC\n" + "\n".join("   " + s for s in lines) + \
            "\nTIMER FINTIM = 1.0\nEND\n"

    y = np.ones(500)
    y[137] = -1.0
    c = _compiled(listing("-SQRT(X{i}) - 0.1*X{i}"))
    f = rolled.for_compiled(c)
    assert f is not None
    got, want = np.asarray(f(0.0, y, [], [])), np.asarray(c.rhs(0.0, y.tolist(), [], []))
    assert math.isnan(got[137]) and np.array_equal(got[:137], want[:137])
    c = _compiled(listing("-1.0/(X{i} + 1.0)"))
    f = rolled.for_compiled(c)
    with pytest.raises(ZeroDivisionError):
        f(0.0, y, [], [])


@pytest.mark.slow  # (about 13 s on this machine)
def test_chain_of_1000_runs_in_seconds():
    """The 1000-mass chain (3000 equations) on AUTO: the banded Jacobian (reverse
    Cuthill-McKee renumbering) and the rolled right side take it from half a minute
    to well under ten seconds, first run and compilation included (about 4 s here
    on a loaded machine), and its result matches a tight DOP853 reference."""
    pytest.importorskip("scipy")
    sys.path.insert(0, os.path.join(HERE, "benchmarks"))
    from scale import FINTIM, chain_listing, numpy_rhs
    from scipy.integrate import solve_ivp

    n = 1000
    model = amilpy.loads(chain_listing(n))
    order = [name for i in range(1, n + 1) for name in (f"X{i}", f"V{i}")]
    run, = model.run(rtol=1e-6, atol=1e-12, advice=False, outputs=order)
    assert run.ok
    ref = solve_ivp(numpy_rhs(n), (0.0, FINTIM), np.zeros(2 * n), method="DOP853",
                    rtol=1e-10, atol=1e-14, t_eval=[FINTIM]).y[:, -1]
    got = np.array([run[name][-1] for name in order])
    assert np.abs(got - ref).max() <= 1e-4 * np.abs(ref).max()
    assert run.stats["nfev"] < 5000


def test_flow_jacobian_for_the_analyses():
    """`Flow.jacobian(state, t)` (what the modes analysis linearises with) is the
    Jacobian of `Flow.field` in the state's branches: differences of that field
    agree, in the slipping branch of the clutch model after engagement."""
    model = amilpy.load(os.path.join(HERE, "models", "ex4_clutch.amil"))
    flow = model.flow(method="RADAU", rtol=1e-10, atol=1e-14)
    s0 = flow.initial_state()
    s1, _ = flow.advance(s0, 0.0, 0.05)
    exact = flow.jacobian(s1, s1.t)
    diff = jacobian.finite_difference(flow.field(s1, s1.t), s1.t, np.asarray(s1.y))
    assert np.abs(exact - diff).max() <= 1e-7 * np.abs(diff).max()
