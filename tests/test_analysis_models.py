"""The analyses on the shipped models against their references (tests/references,
SciPy and closed forms only): the hoist's linear eigenfrequencies at the loaded
equilibrium (the seed's eq. 16), the Exercise 4 coupling mode after
engagement, the machine unit's steady motion against its energy balance, the
hoist's periodic orbits against a SciPy integration of the same equations, and
(slow) the hoist's whole response curve with its folds."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from references import ex4, hoist, machine_unit

import amilpy

MODELS = Path(__file__).resolve().parents[1] / "models"
LOADED = dict(X10=1.91892e-3, Y0=0.024350)  # the hoist at its loaded equilibrium


def test_hoist_eigenfrequencies_are_the_seed_eq16():
    # At the loaded equilibrium the teeth touch: the chain is linear with q = c2.
    # The dashpots are stiffness-proportional (D = BETA*C), so each mode's natural
    # frequency |lambda| is exactly eq. 16's root (to 1e-12; the Jacobian is exact
    # on a linear branch) and its damping ratio BETA*lambda/2: ZETA for lambda2.
    # Two zero modes: the rigid-body drift of the chain and the forcing phase PH.
    # Against the paper's eq. 17 (rounded coefficients) to the 0.5 % it prints.
    result = amilpy.load(MODELS / "hoist_backlash.amil").modes(**LOADED)
    h = hoist.Hoist()
    lam2, lam3 = hoist.linear_frequencies(h, h.c2)
    zero = [m for m in result.modes if m.zero]
    oscillating = [m for m in result.modes if not m.zero]
    assert len(zero) == 2 and len(oscillating) == 2
    assert [m.wn for m in oscillating] == pytest.approx([lam2, lam3], rel=1e-12)
    assert [m.zeta for m in oscillating] == pytest.approx(
        [h.zeta, h.zeta * lam3 / lam2], rel=1e-8)
    assert [m.wn for m in oscillating] == pytest.approx(list(hoist.eq17(1.0)), rel=5e-3)
    rigid = zero[0].shape  # the drift: V1 = V2 = V3, twists unchanged
    v = [rigid[result.names.index(n)] for n in ("V1", "V2", "V3", "X1", "Y")]
    assert v == pytest.approx([1, 1, 1, 0, 0], abs=1e-9)


def test_exercise4_coupling_mode_after_engagement():
    # After T1 and the last rotor reversal the rotor slips forwards (friction
    # constant): the engaged drive is linear and its eigenvalues are those of the
    # reference's state matrix (eig of A assembled from its right-hand side): the
    # coupling mode -719.641 +- 6659.68j (1066 Hz natural, zeta 0.1074) to 1e-9.
    result = amilpy.load(MODELS / "ex4_clutch.amil").modes(at=0.2)
    want = np.linalg.eigvals(ex4.engaged_matrix(ex4.clutch_chain()))
    got = np.array([m.eigenvalue for m in result.modes])
    got = np.concatenate([got, np.conj(got[got.imag > 0])])
    assert np.sort_complex(got) == pytest.approx(np.sort_complex(want), rel=1e-9)
    coupling = next(m for m in result.modes if m.eigenvalue.imag > 0)
    _, zeta, lam = ex4.coupling_mode(ex4.clutch_chain())
    assert coupling.eigenvalue == pytest.approx(lam, rel=1e-9)
    assert coupling.zeta == pytest.approx(zeta, rel=1e-9)


def test_machine_unit_steady_motion_against_its_energy_balance():
    # Over one steady revolution the kinetic energy repeats, so the work of
    # MD - MC vanishes: the mean of W over PHI is (A - C0)/(B + K) = 520/41 exactly;
    # AW = integral of W*W dt (left out of the periodicity: nothing reads it) gains
    # 2 pi times that over the orbit. The period and W's extremes against the
    # reference's revolutions after 10 s (rtol 1e-12; its extremes on a 2001-point
    # grid, so to 1e-6).
    orbit = amilpy.load(MODELS / "machine_unit.amil").periodic(angle="PHI=2*PI",
                                                                measure=["W", "EK"])
    assert orbit.free == ["AW"] and orbit.angle == "PHI" and orbit.cyclic == ["W"]
    gain = orbit.end.y[orbit.names.index("AW")] - orbit.value("AW")
    assert gain / (2 * math.pi) == pytest.approx(machine_unit.PHI_MEAN_SPEED, rel=1e-8)
    revs, _ = machine_unit.simulate(10.0)
    last = revs[-1]
    assert orbit.period == pytest.approx(last.t1 - last.t0, rel=1e-8)
    assert orbit.measures["W"].mean == pytest.approx(last.time_mean, rel=1e-8)
    assert orbit.measures["W"].minimum == pytest.approx(last.w_min, rel=1e-6)
    assert orbit.measures["W"].maximum == pytest.approx(last.w_max, rel=1e-6)
    assert orbit.stable and len(orbit.multipliers) == 1


@pytest.mark.parametrize("w, events", [(70.0, 0), (72.0, 4)])
def test_hoist_periodic_orbit_is_a_fixed_point_of_the_reference(w, events):
    # From the loaded equilibrium the hoist settles on the small orbit at 70 rad/s
    # (teeth always in contact) and on the large one at 72 rad/s (they separate
    # twice a period: four contact edges). amilpy's orbit, integrated one period by
    # the reference (DOP853, rtol 1e-12, every contact edge located), comes back
    # to its start to 1e-7 of each state's size, and the reference's half
    # peak-to-peak of Y on a fine grid agrees to 1e-6.
    orbit = amilpy.load(MODELS / "hoist_backlash.amil").periodic(
        angle="PH=2*PI", measure=["Y"], settle=20.0, W=w, **LOADED)
    assert len(orbit.events) == events and orbit.stable
    assert orbit.period == pytest.approx(2 * math.pi / w, rel=1e-12)
    order = ["X1", "Y", "V1", "V2", "V3", "PH"]
    start = np.array([orbit.value(n) for n in order])
    h = hoist.Hoist()
    t = np.linspace(0.0, orbit.period, 20001)
    ref = hoist.simulate(h, w, (0.0, orbit.period), start, t_eval=t)
    size = np.max(np.abs(ref.y), axis=1)
    back = ref.final - start
    back[5] -= 2 * math.pi
    assert np.max(np.abs(back) / size) <= 1e-7
    assert 0.5 * (ref.y[1].max() - ref.y[1].min()) == pytest.approx(
        orbit.measures["Y"].half_pp, rel=1e-6)


@pytest.mark.slow  # about 20-30 s on this machine (2 cores shared)
def test_hoist_response_curve_with_both_folds():
    # The whole amplitude-frequency curve of the seed's Fig. 11 over the stepped
    # sweep's range: a fold where the small orbit ends (the teeth begin to
    # separate) and one where the large one does, each inside the bracket of the
    # stepped sweep's jumps (docs/models.md: 72.00-72.05 up, 67.80-67.85 down) and
    # within 0.05 rad/s of the damped harmonic balance (72.045, 67.82); unstable
    # orbits between them and none outside.
    resp = amilpy.load(MODELS / "hoist_backlash.amil").response(
        "W", 67.5, 73.0, angle="PH=2*PI", measure="Y", settle=20.0, **LOADED)
    assert resp.complete
    folds = sorted(p.value for p in resp.folds)
    assert len(folds) == 2
    assert 67.80 < folds[0] < 67.85 and 72.00 < folds[1] < 72.05
    hb = hoist.damped_hb_folds(hoist.Hoist())
    assert folds == pytest.approx([hb["w_down"], hb["w_up"]], abs=0.05)
    unstable = [p for p in resp.points if not p.kind and p.mu_max > 1.01]
    assert unstable and all(folds[0] < p.value < folds[1] for p in unstable)
