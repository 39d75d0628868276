"""Switching at odeint's cost (issue 14.2): the AUTO route locates a crossing from
the rows odeint computed (a cubic or quintic Hermite through them and their
derivatives), integrates a narrow window again only where the tolerance needs it,
and sizes its chunks from the rhythm of the recent events."""

from __future__ import annotations

import math

import numpy as np
import pytest

import amilpy
from amilpy.steppers.dense import Nodes, quintic_gap, quintic_terms
from amilpy.steppers.odeint import OdeintStepper


def _poly(coefficients):
    p = np.poly1d(coefficients)
    return p, p.deriv()


def test_cubic_nodes_are_exact_on_a_cubic():
    """Two instants with values and derivatives fix a cubic: the dense output is
    that cubic (to rounding) inside and outside the interval."""
    p, dp = _poly([2.0, -1.0, 3.0, 0.5])
    n = Nodes([0.3, 1.1], [np.array([p(0.3)]), np.array([p(1.1)])],
              [np.array([dp(0.3)]), np.array([dp(1.1)])])
    for t in (0.3, 0.5, 0.9, 1.1):
        assert n(t)[0] == pytest.approx(p(t), abs=1e-14)


def test_sharpened_nodes_are_exact_on_a_quintic():
    """A third instant (values and derivatives) makes the piece a quintic: exact for
    a quintic, and `quintic_gap` is then the cubic's own error."""
    p, dp = _poly([0.3, -1.0, 2.0, -1.0, 3.0, 0.5])
    t0, t1, t2 = 0.3, 1.1, 1.6
    n = Nodes([t0, t1], [np.array([p(t0)]), np.array([p(t1)])],
              [np.array([dp(t0)]), np.array([dp(t1)])])
    cubic = n(0.7)[0]
    terms = quintic_terms(t0, n.y[0], n.f[0], t1, n.y[1], n.f[1], t2, np.array([p(t2)]),
                          np.array([dp(t2)]))
    gap = quintic_gap(terms, 0.7)
    n.sharpen(terms)
    for t in (0.3, 0.6, 0.9, 1.1):
        assert n(t)[0] == pytest.approx(p(t), abs=1e-13)
    assert gap[0] == pytest.approx(abs(p(0.7) - cubic), rel=1e-9)
    # the projection used by the root finder is the same polynomial on floats
    assert n.along(np.array([1.0]))(0.77) == pytest.approx(p(0.77), abs=1e-13)


def _oscillator_stepper(rtol):
    """y'' = -y from y = 1: cos t, crossing zero at pi/2 between two rows 0.3 apart."""
    def f(t, y):
        return [y[1], -y[0]]

    checks = np.arange(0.3, 3.0, 0.3)
    s = OdeintStepper(f, 0.0, np.array([1.0, 0.0]), 3.0, checks, rtol=rtol,
                      atol=rtol * 1e-3, max_step=math.inf, first_step=None)
    while s.t < 1.5:
        s.pending()
        s.consume(1)
    s.pending()
    s.consume(1)  # now t_old = 1.5 < pi/2 < t = 1.8
    return s


@pytest.mark.parametrize("rtol", [1e-4, 1e-10])
def test_crossing_on_the_rows_to_the_tolerance(rtol):
    """The zero of cos t located on odeint's rows (a 0.3 interval, 30 % of a
    radian): at rtol 1e-4 the quintic through a third row is within the tolerance
    and no integration is added; at 1e-10 it is not (the cubic is off by 2e-6), and
    a window of 1 % of the interval integrated once more brings the crossing within
    10 tolerances of pi/2, like the rows themselves (odeint's global error)."""
    from scipy.optimize import brentq

    s = _oscillator_stepper(rtol)
    before = s.nfev
    sharp = s.sharpen()
    dense = s.interpolant() if sharp else s.refine(1.5 + 0.3 * 0.24)
    root = brentq(lambda t: dense(t)[0], s.t_old, s.t, xtol=1e-15)
    assert sharp == (rtol > 1e-6)
    assert abs(root - math.pi / 2) < (20 if sharp else 10) * rtol
    added = s.nfev - before  # derivatives at the rows (+ the window's integration)
    assert added <= (3 if sharp else 80)


HOIST = "models/hoist_backlash.amil"


def test_hoist_chunks_follow_the_rhythm_of_the_contacts(monkeypatch):
    """The hoist's 111 contact pairs come in a steady rhythm: after a few, each chunk
    of output instants covers the time to the next contact and little more, so
    fewer than 25 % of the instants odeint integrates are thrown away (all of them
    after each of the first contacts: 42 % before)."""
    import os

    rows = []
    real = OdeintStepper._fill

    def counting(self):
        real(self)
        rows.append(len(self.T))

    monkeypatch.setattr(OdeintStepper, "_fill", counting)
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    run, = amilpy.load(os.path.join(here, HOIST)).run(advice=False)
    assert len(run.events) == 222
    kept = len(run.times)
    assert (sum(rows) - kept) / sum(rows) < 0.25


def test_range_turns_in_a_bracket_one_ulp_long():
    """A restart one ulp after an output row leaves a RANGE bracket one ulp long
    (RKS on the torque meter at rtol 1e-6 made one): its ends are its candidates,
    and no rate is divided by a zero width (was a ZeroDivisionError)."""
    from amilpy.run.peaks import turns

    ta = 2.05
    tb = math.nextafter(ta, 3.0)
    assert turns(lambda t: 3.0 * t, ta, tb) == [(ta, 3.0 * ta), (tb, 3.0 * tb)]
