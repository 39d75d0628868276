"""Two-mass drive, coupling stiffness 1E0..1E8, every method (issue 5, stiffness)."""

import numpy as np
import pytest

import amilpy
from stress import cases as C

KS = [1e0, 1e1, 1e2, 3e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8]  # every decade, and the worst K
MAX_STEPS = 5000  # CI size: explicit methods on K = 1E8 need millions of steps

@pytest.fixture(scope="module")
def model():
    return amilpy.loads(C.TWO_MASS.format(fintim="1.0", outdel="0.01"), name="two_mass.amil")


def _params():
    for k in KS:
        for method in C.METHODS:
            yield pytest.param(k, method, id=f"K{k:.0e}-{method}")


@pytest.mark.parametrize("k,method", list(_params()))
def test_stiff_drive(model, k, method):
    # at RELERR 1E-6 (the error bound below, in tolerance units, is this one's: a
    # global error grows with the steps, and at the default 1E-10 it is 20-30 units)
    r, = model.run(method=method, K=k, max_steps=MAX_STEPS, rtol=1e-6, atol=1e-9)
    assert len(r.times) >= 1 and np.all(np.isfinite(r.values["W1"])), "no NaN tables"
    if method in C.FIXED:
        if not r.ok:
            assert "TIME =" in r.message, r.message
            assert "grows without bound" in r.message or "no longer finite" in r.message
            assert r.t_end < 1.0
        else:
            ref = C.two_mass_reference(k, r.t)
            assert np.allclose(r["W1"], ref["W1"], atol=1e-2), "a finished fixed-step run"
        return
    if not r.ok:
        # only the explicit methods may give up, and then with the step limit named
        assert method in C.EXPLICIT_VARIABLE and k >= 1e6, r.message
        assert "TIME =" in r.message and f"more than {MAX_STEPS} steps" in r.message
        assert "stiff" in r.message
        return
    ref = C.two_mass_reference(k, r.t)
    err = C.scaled_error(r, ref, r.rtol, r.atol)
    assert err <= 10.0, f"error {err:.3g} tolerance units"


@pytest.mark.parametrize("method", C.IMPLICIT)
def test_stiff_methods_are_cheap_at_1e8(model, method):
    """The stiff routes must not notice the 4E8 stiffness ratio."""
    r, = model.run(method=method, K=1e8)
    assert r.ok and r.stats["nsteps"] < 2000


@pytest.mark.parametrize("method", C.FIXED)
def test_fixed_step_instability_names_the_variable(model, method):
    r, = model.run(method=method, K=1e8)
    assert not r.ok and "TIME =" in r.message
    assert any(v in r.message for v in ("PHI", "W1", "W2")), r.message


def test_stiffness_ratio_reaches_1e8():
    assert C.stiffness_ratio(1e0) < 10 and C.stiffness_ratio(1e8) > 1e8


def test_explicit_method_says_when_it_is_stiff(model):
    """At K = 1E6 DOP853's step is bound by stability (h*|lambda| ~ 6): the run says
    so once, with the TIME, and its rows between step ends are still within the
    tolerance (SciPy's own interpolant was 20 units off there)."""
    r, = model.run(method="DOP853", K=1e6)
    stiff = [w for w in r.warnings if w.startswith("stiff from TIME = ")]
    assert r.ok and len(stiff) == 1, r.warnings
    assert "METHOD DOP853" in stiff[0] and "METHOD AUTO or STIFF" in stiff[0]
    ref = C.two_mass_reference(1e6, r.t)
    assert C.scaled_error(r, ref, r.rtol, r.atol) <= 3.0


@pytest.mark.parametrize("method", C.EXPLICIT_VARIABLE)
def test_no_stiffness_warning_when_accuracy_sets_the_step(model, method):
    r, = model.run(method=method, K=1e2)
    assert r.ok and not [w for w in r.warnings if w.startswith("stiff")], r.warnings


@pytest.mark.parametrize("rtol", [1e-3, 1e-9])
def test_stiff_dop853_within_tolerance_across_tolerances(model, rtol):
    """K = 1E5: stability-bound at every tolerance (the step count hardly changes), so
    the error in tolerance units must not grow as the tolerance is tightened."""
    r, = model.run(method="DOP853", K=1e5, rtol=rtol, atol=rtol * 1e-3)
    ref = C.two_mass_reference(1e5, r.t)
    assert r.ok and C.scaled_error(r, ref, r.rtol, r.atol) <= 10.0


@pytest.mark.parametrize("rtol", [1e-3, 1e-6, 1e-8])
def test_bdf_on_a_lightly_damped_mode(model, rtol):
    """K = 1E2: a shaft mode with damping ratio 0.07 that BDF's errors per step add up
    on (25 units at 1E-6 with SciPy's tolerance as given): amilpy's BDF keeps to 10."""
    r, = model.run(method="BDF", K=1e2, rtol=rtol, atol=rtol * 1e-3)
    ref = C.two_mass_reference(1e2, r.t)
    assert r.ok and C.scaled_error(r, ref, r.rtol, r.atol) <= 10.0


@pytest.mark.parametrize("method", C.FIXED)
def test_fixed_step_instability_is_stopped_before_it_overflows(model, method):
    """K = 1E6, DELT = 6.25E-4: h*|lambda| ~ 12 on the shaft mode, past every fixed-step
    method's stability limit. The run stops within a few steps of the growth with
    the variable, the TIME it began, and a DELT that would be stable; no row holds
    an overflowing value."""
    r, = model.run(method=method, K=1e6)
    assert not r.ok and "grows without bound from TIME = " in r.message, r.message
    assert f"METHOD {method} is unstable with DELT = 0.000625" in r.message
    safe = float(r.message.split("take DELT below ")[1].split()[0])
    assert 2e-5 < safe < 2.5e-4  # the limit over h*|lambda| = 2E4 1/s
    assert r.t_end < 0.01 and np.all(np.abs(r["W1"]) < 1e20)


def test_slow_instability_is_caught_too(model):
    """K = 1E5 with ADAMS: h*|lambda| ~ 1.2 against AB2's limit of 1, a growth of 1.34
    a step that used to finish the run with W1 = 5.7E149 in the last row."""
    r, = model.run(method="ADAMS", K=1e5)
    assert not r.ok and "grows without bound" in r.message and "W1" in r.message
    assert np.all(np.abs(r["W1"]) < 1.0)


@pytest.mark.parametrize("method", C.FIXED)
def test_stable_fixed_step_runs_are_not_stopped(model, method):
    """K = 1E4: h*|lambda| ~ 0.09 is stable for all four methods."""
    r, = model.run(method=method, K=1e4)
    assert r.ok, r.message
