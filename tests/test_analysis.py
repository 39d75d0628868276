"""Linear modes and periodic orbits (amilpy.analysis) against closed forms: a
damped oscillator's eigenvalues, a nonlinear field's Jacobian, a forced linear
oscillator's orbit and Floquet multipliers, a dead-zone oscillator's orbit
through two switches against a finite-difference monodromy of a SciPy
integration written here, and the failures that must be said, not hidden."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

import amilpy
from amilpy.analysis import NotConverged
from amilpy.analysis.linear import linearise
from amilpy.run.jacobian import DIFFERENCES, MODEL, field_jacobian

W0, Z = 3.0, 0.2  # X'' + 2 Z W0 X' + W0^2 X = 0
DAMPED = f"""PARAM W0 = {W0}, Z = {Z}
X = INTGRL(1.0, V)
V = INTGRL(0.0, -2.0*Z*W0*V - W0*W0*X)
TIMER FINTIM = 1.0
END
"""


def test_damped_oscillator_modes_exactly():
    # lambda = -Z W0 +- i W0 sqrt(1 - Z^2): the field is linear, so the difference
    # Jacobian is exact to rounding; w_n and zeta to 1e-12
    result = amilpy.loads(DAMPED).modes()
    mode, = result.modes
    assert mode.wn == pytest.approx(W0, rel=1e-12)
    assert mode.zeta == pytest.approx(Z, rel=1e-12)
    assert mode.eigenvalue.imag == pytest.approx(W0 * math.sqrt(1 - Z * Z), rel=1e-12)
    assert mode.fhz == pytest.approx(W0 / (2 * math.pi), rel=1e-12)
    # the shape: V = lambda X, largest component 1
    x, v = (mode.shape[result.names.index(n)] for n in ("X", "V"))
    assert v / x == pytest.approx(mode.eigenvalue, rel=1e-10)
    assert max(abs(x), abs(v)) == pytest.approx(1.0)
    assert result.error < 1e-12


def test_jacobian_of_a_nonlinear_field_and_its_stated_accuracy():
    # d/dX of -G*SIN(X) - B*X**3 at X = 1.2 is -G cos(1.2) - 3 B 1.44. The model's
    # own Jacobian (codegen.jacobian) is exact to rounding: 1e-14. The central
    # differences the analyses fall back on (a sliding field, a construct without a
    # symbolic derivative) promise 1e-9 relative with the step chosen per column,
    # and their error estimate must not understate the true error
    model = amilpy.loads("PARAM G = 9.81, B = 0.7\nX = INTGRL(1.2, V)\n"
                         "V = INTGRL(-0.4, -G*SIN(X) - B*X**3)\nTIMER FINTIM = 1.0\nEND\n")
    flow = model.flow()
    state = flow.initial_state()
    jac, names = linearise(flow, state, 0.0)
    exact = -9.81 * math.cos(1.2) - 3 * 0.7 * 1.44
    vx, xv = names.index("V"), names.index("X")
    assert jac[vx, xv] == pytest.approx(exact, rel=1e-14)
    assert jac[xv, vx] == 1.0
    lin = model.modes()
    assert lin.how == MODEL and lin.error == 0.0
    field = flow.field(state, 0.0)
    diff, error = field_jacobian(lambda v: field(0.0, np.asarray(v)), state.y, 1e-3,
                                 with_error=True)
    assert diff[vx, xv] == pytest.approx(exact, rel=1e-9)
    assert abs(diff[vx, xv] - exact) <= max(10 * error[xv], 1e-12 * abs(exact))


def test_modes_while_a_surface_slides_use_differences_of_the_combined_field():
    # X' = -S + 0.3 Y, Y' = -2 Y + S with S a relay on X: X reaches 0 and slides
    # there with S = 0.3 Y (X' = 0), so Y' = -1.7 Y. The combined field has no
    # symbolic Jacobian; its central differences are exact to rounding on a field
    # linear in the states: eigenvalues -1.7 (to 1e-10) and 0 (X held on the surface)
    result = amilpy.loads("S = FSW(X, -1.0, 0.0, 1.0)\nX = INTGRL(1.0, -S + 0.3*Y)\n"
                          "Y = INTGRL(0.0, -2.0*Y + S)\nTIMER FINTIM = 4.0\nEND\n"
                          ).modes(at=3.0)
    assert result.how == DIFFERENCES and result.error < 1e-10
    zero, moving = result.modes
    assert zero.zero and moving.eigenvalue == pytest.approx(-1.7, rel=1e-10)


def test_modes_flag_rigid_body_and_follow_the_switch_branch():
    # two masses on a spring, free to drift: a zero mode (rigid body) and one at
    # sqrt(2K/M); with the contact branch of a dead zone in force
    text = """PARAM K = 8.0, M = 2.0, D = 0.1
X1 = INTGRL(0.5, V1)
X2 = INTGRL(0.0, V2)
V1 = INTGRL(0.0, -K*DEADSP(-D, D, X1 - X2)/M)
V2 = INTGRL(0.0, K*DEADSP(-D, D, X1 - X2)/M)
TIMER FINTIM = 1.0
END
"""
    result = amilpy.loads(text).modes()
    zero = [m for m in result.modes if m.zero]
    moving = [m for m in result.modes if not m.zero]
    assert len(zero) == 2 and len(moving) == 1  # rigid drift: a double zero
    assert moving[0].wn == pytest.approx(math.sqrt(2 * 8.0 / 2.0), rel=1e-12)
    # in the gap (|X1 - X2| <= D) there is no spring: every mode is zero
    gap = amilpy.loads(text.replace("X1 = INTGRL(0.5", "X1 = INTGRL(0.05")).modes()
    assert all(m.zero for m in gap.modes)


W, F = 1.5, 1.0  # forcing of a damped linear oscillator X'' + 2 Z W0 X' + W0^2 X
FORCED = f"""TITLE FORCED LINEAR OSCILLATOR
PARAM W = {W}, W0 = {W0}, Z = 0.05, F = {F}
X = INTGRL(0.0, V)
V = INTGRL(0.0, F*SIN(W*TIME) - 2.0*Z*W0*V - W0*W0*X)
TIMER FINTIM = 60.0, OUTDEL = 0.1
END
"""


def amplitude(w: float, w0: float = W0, z: float = 0.05, f: float = F) -> float:
    return f / math.sqrt((w0 * w0 - w * w) ** 2 + (2 * z * w0 * w) ** 2)


def test_forced_linear_oscillator_orbit():
    # X = a sin(W t - phi): half peak-to-peak a, mean 0, period 2 pi/W; both
    # multipliers exp(-Z W0 T) in modulus (e^{A T}). Newton from the settled state
    # must end at the noise of the integration (RELERR 1e-9): 1e-8 relative.
    orbit = amilpy.loads(FORCED).periodic(period="2*PI/W", measure=["X", "V"])
    t = 2 * math.pi / W
    assert orbit.period == t
    assert orbit.measures["X"].half_pp == pytest.approx(amplitude(W), rel=1e-8)
    assert orbit.measures["V"].half_pp == pytest.approx(W * amplitude(W), rel=1e-8)
    assert abs(orbit.measures["X"].mean) <= 1e-9 * amplitude(W)
    assert np.abs(orbit.multipliers) == pytest.approx([math.exp(-0.05 * W0 * t)] * 2,
                                                      rel=1e-9)
    assert orbit.stable and orbit.residuals[-1] <= 1e-8
    # the orbit starts on the forcing's phase 0 (whole periods after TIME 0)
    phase = math.atan2(2 * 0.05 * W0 * W, W0 * W0 - W * W)
    assert orbit.value("X") == pytest.approx(-amplitude(W) * math.sin(phase), abs=1e-9)


D, KD, P = 0.5, 4.0, 3.0  # the spring acts outside |X| <= D; a bias P keeps X > -D
DEAD_ZONE = f"""TITLE DEAD-ZONE OSCILLATOR, BIASED: CONTACT ON ONE SIDE ONLY
PARAM D = {D}, K = {KD}, C = 0.4, P = {P}, F = 1.0, W = 1.7
PH = INTGRL(0.0, W)
X = INTGRL(0.0, V)
V = INTGRL(0.0, P + F*SIN(PH) - C*V - K*DEADSP(-D, D, X))
TIMER FINTIM = 40.0, OUTDEL = 0.05
END
"""


def _scipy_dead_zone(start: np.ndarray, w: float = 1.7) -> np.ndarray:
    """The stroboscopic map of the dead-zone oscillator, (X, V) over one forcing
    period from phase 0, by solve_ivp with the contact edges X = D located as
    events and the integration restarted in the new branch."""
    def f(t, s, contact):
        spring = KD * (s[0] - D) if contact else 0.0
        return [s[1], P + 1.0 * math.sin(w * t) - 0.4 * s[1] - spring]

    def edge(t, s, contact):
        return s[0] - D
    edge.terminal = True
    t, s, end = 0.0, np.array(start, dtype=float), 2 * math.pi / w
    while t < end:
        contact = s[0] > D
        sol = solve_ivp(f, (t, end), s, args=(contact,), events=edge, method="DOP853",
                        rtol=1e-12, atol=1e-14)
        t, s = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status == 1:  # on the edge: step off it the way the motion goes
            s[0] = D + 1e-15 * np.sign(s[1])
    return s


def test_dead_zone_orbit_through_two_switches_against_finite_differences():
    # The orbit enters the contact (X = D) and leaves it once a period (X stays
    # above -D). The multipliers are real here (0.85, 0.27); their product is
    # exp(-C T), the trace of either branch's field being -C. The period
    # is found as the time the phase takes to advance 2 pi (--angle): 2 pi/W to the
    # integration's accuracy. The Floquet multipliers against the eigenvalues of a
    # central-difference Jacobian of the SciPy map above at the orbit (h = 1e-5:
    # truncation h^2 ~ 1e-10, noise 1e-12/h ~ 1e-7): 1e-6.
    orbit = amilpy.loads(DEAD_ZONE).periodic(angle="PH=2*PI", measure=["X"])
    assert orbit.period == pytest.approx(2 * math.pi / 1.7, rel=1e-12)
    assert len(orbit.events) == 2
    assert orbit.measures["X"].minimum > -D and orbit.measures["X"].maximum > D
    start = np.array([orbit.value("X"), orbit.value("V")])
    assert _scipy_dead_zone(start) == pytest.approx(start, abs=1e-8)  # a fixed point
    h = 1e-5
    jac = np.column_stack([(_scipy_dead_zone(start + h * e) - _scipy_dead_zone(start - h * e))
                           / (2 * h) for e in np.eye(2)])
    want = np.sort_complex(np.linalg.eigvals(jac))
    assert np.sort_complex(orbit.multipliers) == pytest.approx(want, abs=1e-6)
    assert np.prod(orbit.multipliers).real == pytest.approx(math.exp(-0.4 * orbit.period),
                                                            rel=1e-9)
    assert orbit.stable


def test_running_integral_is_left_out_and_the_angle_closes_the_period():
    # AW = INTGRL(W*W) feeds nothing: free, and its increase over the orbit is
    # the integral of W dPHI
    text = """PARAM A = 10.0, B = 2.0, C1 = 3.0
PHI = INTGRL(0.0, W)
W = INTGRL(1.0, A - B*W - C1*SIN(PHI))
AW = INTGRL(0.0, W*W)
TIMER FINTIM = 20.0
END
"""
    orbit = amilpy.loads(text).periodic(angle="PHI=2*PI", measure="W")
    assert orbit.free == ["AW"] and orbit.cyclic == ["W"] and orbit.angle == "PHI"
    gain = orbit.end.y[orbit.names.index("AW")] - orbit.value("AW")
    assert gain / (2 * math.pi) == pytest.approx(10.0 / 2.0, rel=1e-8)  # energy balance


def test_a_phase_given_a_period_does_not_converge_and_says_so():
    # PH grows by 2 pi each period: it cannot repeat. Newton must fail with its
    # residual history, never report an orbit, and name the way out (--angle).
    with pytest.raises(NotConverged) as err:
        amilpy.loads(DEAD_ZONE).periodic(period="2*PI/W", settle=5.0)
    assert err.value.history and "PH" in str(err.value) and "angle" in str(err.value)


def test_period_and_angle_expressions_are_checked():
    model = amilpy.loads(FORCED)
    with pytest.raises(amilpy.AmilError, match="Q is not a constant"):
        model.periodic(period="2*PI/Q")
    with pytest.raises(amilpy.AmilError, match="INTGRL is not a plain function"):
        model.periodic(period="INTGRL(0, 1)")
    with pytest.raises(amilpy.AmilError, match="either a period"):
        model.periodic()
    with pytest.raises(amilpy.AmilError, match="not a state"):
        model.periodic(angle="W=2*PI")
    with pytest.raises(amilpy.AmilError, match="not a variable"):
        model.periodic(period="2*PI/W", measure="XX")


def test_monodromy_by_variational_equations_matches_the_closed_form():
    # the flow map's sensitivity on the linear oscillator, by the variational
    # equations (default) and by differences of whole flows: e^{AT} both, the
    # variational one to the integration's accuracy
    flow = amilpy.loads(DAMPED).flow(method="DOP853", rtol=1e-11, atol=1e-13)
    a = np.array([[0.0, 1.0], [-W0 * W0, -2 * Z * W0]])
    idx = [flow.state_names.index("X"), flow.state_names.index("V")]
    for variational, tol in ((True, 1e-10), (False, 1e-6)):
        flow.variational = variational
        _, _, m = flow.advance(flow.initial_state(), 0.0, 2.3, sensitivity=True)
        assert np.max(np.abs(m[np.ix_(idx, idx)] - expm(2.3 * a))) <= tol
        assert flow.last_sensitivity.startswith("variational" if variational else "diff")


HOPF = """TITLE HOPF CYCLE
PARAM B = 0.5
DYNAMIC
   R2 = X*X + Y*Y
   X = INTGRL(1.0, X - (2.0 + B*R2)*Y - X*R2)
   Y = INTGRL(0.0, (2.0 + B*R2)*X + Y - Y*R2)
TIMER FINTIM = 10.0, OUTDEL = 0.05
END
"""


@pytest.mark.parametrize("method", [None, "RADAU"])
def test_floquet_multipliers_of_a_limit_cycle_on_long_steps(method):
    # r' = r (1 - r^2), theta' = 2 + B r^2: the cycle r = 1 has period 2 pi/2.5 and
    # multipliers 1 and exp(-2 T) (the radial rate -2 there). DOP853's long steps
    # left the monodromy 1e-4 off (0.999931, 0.00656187 for 0.00656142; hunt 49b):
    # each step of the variational equations is now checked against its halves.
    orbit = amilpy.loads(HOPF).periodic(period="2*PI/2.5", method=method)
    mu = np.sort(np.abs(orbit.multipliers))[::-1]
    assert mu == pytest.approx([1.0, math.exp(-4 * math.pi / 2.5)], rel=1e-7)
