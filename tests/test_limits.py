"""Limits that stop a run, and the step-size floor: DELMIN lowers it (Robertson's
problem to 4E10), the step and wall-clock limits hold inside AUTO's odeint chunks,
and the stiffness-advice probe stays within the run's limits."""

import numpy as np
import pytest
from conftest import run1
from scipy.integrate import odeint

import amilpy
from amilpy.result import Run, Status
from amilpy.run import Options, advice

ROBERTSON = """Y1 = INTGRL(1.0, -0.04*Y1 + 1.0E4*Y2*Y3)
Y2 = INTGRL(0.0, 0.04*Y1 - 1.0E4*Y2*Y3 - 3.0E7*Y2*Y2)
Y3 = INTGRL(0.0, 3.0E7*Y2*Y2)
TIMER FINTIM = 4.0E10{delmin}
RELERR 1.0E-6
ABSERR 1.0E-10
ABSERR Y2 = 1.0E-14
END
"""


@pytest.fixture(scope="module")
def robertson_reference():
    """Y(4E10), written separately: odeint's BDF with the analytic Jacobian at
    RELERR 1E-12 (Radau at 1E-10 agrees to 1E-9)."""
    def f(t, y):
        return [-0.04 * y[0] + 1e4 * y[1] * y[2],
                0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2, 3e7 * y[1] ** 2]

    def jac(t, y):
        return [[-0.04, 1e4 * y[2], 1e4 * y[1]],
                [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]], [0.0, 6e7 * y[1], 0.0]]

    return odeint(f, [1.0, 0.0, 0.0], [0.0, 4e10], Dfun=jac, tfirst=True, rtol=1e-12,
                  atol=[1e-16, 1e-22, 1e-16], mxstep=10**6)[-1]


@pytest.mark.parametrize("method", ["BDF", "RADAU", "AUTO"])
def test_robertson_to_4e10_finishes_with_delmin(method, robertson_reference):
    r = run1(ROBERTSON.format(delmin=", DELMIN = 1.0E-30"), method=method, advice=False)
    assert r.status == "finished", r.message
    y1, y2, y3 = (r[n][-1] for n in ("Y1", "Y2", "Y3"))
    ref = robertson_reference
    # Y1 and Y2 are 5E-8 and 2E-13 by then: what RELERR 1E-6 leaves after 16 decades
    # of TIME is about 1E-4 of them; Y3 (near 1) to its absolute tolerance
    assert y1 == pytest.approx(ref[0], rel=1e-3) and y2 == pytest.approx(ref[1], rel=1e-3)
    assert y3 == pytest.approx(ref[2], abs=1e-8)


def test_the_default_floor_says_which_it_is_and_how_to_lower_it():
    # without DELMIN the floor is FINTIM*1E-12 = 0.04 s, too coarse for the
    # transient BDF must resolve at the start
    r = run1(ROBERTSON.format(delmin=""), method="BDF", advice=False)
    assert r.status == "failed" and "step size underflow" in r.message
    assert "the default floor FINTIM*1E-12; TIMER DELMIN lowers it" in r.message


def test_a_delmin_floor_is_named():
    r = run1("X = INTGRL(1.0, X*X)\nTIMER FINTIM = 2.0, DELMIN = 1.0E-6\nEND\n",
             method="RKS", advice=False)
    assert r.status == "failed" and "shorter than 1e-06 s (TIMER DELMIN)" in r.message
    assert 0.99 < r.t_end < 1.001


# 160 000 periods in FINTIM: odeint needs about 3 million steps, 30 000 per output
# interval; one chunk of the output grid is far more than any limit below allows
FAST = "X = INTGRL(1.0, V)\nV = INTGRL(0.0, -1.0E12*X)\nTIMER FINTIM = 1.0, OUTDEL = 0.01\nEND\n"


def test_the_step_limit_holds_inside_an_odeint_chunk():
    # a chunk used to run to its end (the limit counted output instants, not steps)
    r = run1(FAST, max_steps=1000, advice=False)
    assert r.status == "failed" and "more than 1000 steps" in r.message
    assert r.stats["nsteps"] <= 1000 and r.stats["nfev"] < 5000


def test_the_wall_clock_limit_holds_inside_an_odeint_chunk():
    # the deadline is checked inside the right-hand side, so the first chunk (16
    # output instants, about 500 000 steps) ends at the limit: no row of it is kept
    r = run1(FAST, max_time=0.05, advice=False)
    assert r.status == "failed" and "wall-clock limit of 0.05 s reached" in r.message
    assert len(r.times) < 16


def _fake_run(**kw) -> Run:
    base = dict(label="RUN 1", params={}, constants={}, times=np.zeros(1),
                values={}, outdel_mask=np.ones(1, bool), prdel_mask=np.ones(1, bool),
                events=[], status=Status.FINISHED, message="", final={},
                stats={"nfev": 10**6, "seconds": 5.0, "stiff_from": 0.1}, method="RKS",
                rtol=1e-6, atol=1e-9)
    base.update(kw)
    return Run(**base)


def test_advice_probe_never_follows_a_failed_run_nor_exceeds_the_time_left(monkeypatch):
    calls = []

    def fake_simulate(model, spec, opts, cache=None):
        calls.append(opts)  # the explicit probe 100 times dearer than AUTO
        return _fake_run(stats={"nfev": 100 if opts.method == "AUTO" else 10**4,
                                "seconds": 1.0})

    monkeypatch.setattr(advice, "simulate", fake_simulate)
    model = amilpy.loads("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nEND\n").ir
    spec = model.runs[0]
    failed = _fake_run(status=Status.FAILED, message="integration failed at TIME = 0.5: x")
    assert advice.stiffness_advice(model, spec, failed, Options(method="RKS")) is None
    spent = _fake_run()  # took 5 s of a 4 s limit
    assert advice.stiffness_advice(model, spec, spent, Options(max_time=4.0)) is None
    assert calls == []
    # with 10 s of which the run took 5: the probes get the 5 left, and its steps
    assert advice.stiffness_advice(model, spec, spent, Options(max_time=10.0,
                                                                max_steps=1000)) is not None
    assert [o.method for o in calls] == ["RKS", "AUTO"]
    assert calls[0].max_time == pytest.approx(5.0) and calls[1].max_time == pytest.approx(4.0)
    assert all(o.max_steps == 1000 for o in calls)


def test_runs_that_together_would_not_fit_in_memory_are_refused_before_the_first():
    # 3000 runs of 1E5 rows each, X and Y on every row: 6E8 values (4.8 GB) kept
    # for the printout and the plots. One such run is fine; all of them used to run
    # until the machine was out of memory and nothing was written.
    listing = ("PARAM K = ({n}*1.0)\nX = INTGRL(0.0, K)\nY = X*2.0\n"
               "TIMER FINTIM = 1.0, OUTDEL = 1.0E-5\nEND\n")
    with pytest.raises(amilpy.AmilError, match=r"the 3000 run\(s\) would keep 6e\+08 "
                       r"values .*raise OUTDEL/PRDEL"):
        amilpy.loads(listing.format(n=3000)).run(advice=False)
    assert amilpy.loads(listing.format(n=1)).run(advice=False)[0].ok
