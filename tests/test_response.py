"""Response curves by continuation (amilpy.analysis.response) against closed forms
and an independent reference: a forced linear oscillator's amplitude curve, and
a Duffing oscillator's curve with its two folds against a SciPy shooting of the
folds' own defining equations (tests/references/duffing.py)."""

import math

import numpy as np
import pytest
from references import duffing

import amilpy

W0, Z = 2.0, 0.05
LINEAR = f"""TITLE FORCED LINEAR OSCILLATOR
PARAM W = 1.5, W0 = {W0}, Z = {Z}, F = 1.0
X = INTGRL(0.0, V)
V = INTGRL(0.0, F*SIN(W*TIME) - 2.0*Z*W0*V - W0*W0*X)
TIMER FINTIM = 60.0, OUTDEL = 0.1
END
"""

DUFFING = f"""TITLE FORCED DUFFING OSCILLATOR
PARAM W = 1.1, C = {duffing.C}, K = {duffing.K}, A = {duffing.A}, F = {duffing.F}
X = INTGRL(0.0, V)
V = INTGRL(0.0, F*COS(W*TIME) - C*V - K*X - A*X**3)
TIMER FINTIM = 100.0, OUTDEL = 0.1
END
"""


def amplitude(w: float) -> float:
    return 1.0 / math.sqrt((W0 * W0 - w * w) ** 2 + (2 * Z * W0 * w) ** 2)


def test_linear_response_curve_is_the_analytic_amplitude():
    # Through the resonance at W0: every point's half peak-to-peak is F/|W0^2 - W^2 +
    # 2i Z W0 W| to 1e-6 (the points converge to a scaled residual of 1e-7), every
    # orbit is stable (|mu| = exp(-Z W0 T)), no fold, and the curve runs from START
    # to STOP exactly.
    resp = amilpy.loads(LINEAR).response("W", 1.6, 2.4, period="2*PI/W", measure="X")
    assert resp.complete and not resp.folds and not resp.notes
    values = [p.value for p in resp.points]
    assert values[0] == 1.6 and values[-1] == 2.4 and values == sorted(values)
    for p in resp.points:
        assert p.measures["X"].half_pp == pytest.approx(amplitude(p.value), rel=1e-6)
        assert p.mu_max == pytest.approx(math.exp(-Z * W0 * 2 * math.pi / p.value), rel=1e-7)
        assert p.stable and p.period == pytest.approx(2 * math.pi / p.value, rel=1e-14)
    peak = max(resp.points, key=lambda p: p.measures["X"].half_pp)
    assert peak.value == pytest.approx(W0 * math.sqrt(1 - 2 * Z * Z), abs=0.02)


@pytest.fixture(scope="module")
def duffing_curve():
    return amilpy.loads(DUFFING).response("W", 1.1, 1.45, period="2*PI/W", measure="X")


@pytest.fixture(scope="module")
def reference_folds():
    return [duffing.fold(w, duffing.hb_state(w, a)) for w, a in duffing.hb_folds()]


@pytest.mark.slow  # (the curve: a 9 s fixture; CI runs it in its slow step)
def test_duffing_folds_against_an_independent_shooting(duffing_curve, reference_folds):
    # Two folds, each located to 1e-6 of the reference's root of [G = 0, det(G_x)
    # = 0] (rtol 1e-12); at a fold the amplitude goes as the square root of the
    # distance, so it is compared to 1e-3; a multiplier is +1 there (to 1e-2: the
    # bracketing point nearest the fold).
    folds = duffing_curve.folds
    assert len(folds) == 2
    for point, (w_ref, start) in zip(sorted(folds, key=lambda p: -p.value),
                                     sorted(reference_folds, key=lambda f: -f[0]),
                                     strict=True):
        assert point.value == pytest.approx(w_ref, rel=1e-6)
        assert point.measures["X"].half_pp == pytest.approx(duffing.half_pp(start, w_ref),
                                                            rel=1e-3)
        assert np.min(np.abs(point.multipliers - 1)) < 1e-2


@pytest.mark.slow  # (the curve: a 9 s fixture; CI runs it in its slow step)
def test_duffing_branches_stable_unstable_stable(duffing_curve, reference_folds):
    # along the curve: the large orbit (stable) up to the upper fold, the middle
    # one (unstable) back to the lower fold, the small one (stable) on; each
    # checked against the reference orbit at that W started from amilpy's start.
    # A point is converged to a residual of 1e-7 of the states' sizes, so its
    # start is within about 1e-7/|1 - mu| of the orbit (mu: the multiplier nearest
    # 1, near 1 by a fold): 1e-6/|1 - mu| of the amplitude.
    (w_hi, _), (w_lo, _) = sorted(reference_folds, key=lambda f: -f[0])
    kinds = []
    for p in duffing_curve.points:
        if p.kind == "fold":
            continue
        kinds.append(p.stable)
    changes = [a for a, b in zip(kinds[:-1], kinds[1:], strict=True) if a != b]
    assert changes == [True, False]  # stable -> unstable -> stable
    middle = [p for p in duffing_curve.points if not p.stable and not p.kind]
    assert middle and all(w_lo < p.value < w_hi for p in middle)
    index = [duffing_curve.names.index(n) for n in ("X", "V")]
    for p in duffing_curve.points[::9]:
        start = p.start[index]
        ref = duffing.orbit(p.value, start)
        near = float(np.min(np.abs(p.multipliers - 1)))
        assert ref == pytest.approx(start, abs=1e-6 * p.measures["X"].half_pp / near)


def test_response_range_and_names_are_checked():
    model = amilpy.loads(LINEAR)
    with pytest.raises(amilpy.AmilError, match="not a PARAM"):
        model.response("WW", 1.0, 2.0, period="2*PI/W")
    with pytest.raises(amilpy.AmilError, match="empty"):
        model.response("W", 1.0, 1.0, period="2*PI/W")
