"""`amilpy sensitivity` / Model.sensitivity: local coefficients over time from the
sensitivity equations, and global Sobol and Morris indices, against closed forms."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import amilpy
from amilpy.cli import main
from amilpy.diagnostics import UsageError

EXAMPLES = Path(__file__).resolve().parents[1] / "models" / "examples"

DECAY = """TITLE DECAY
PARAM K = 0.7, X0 = 2.0
X = INTGRL(X0, -K*X)
TIMER FINTIM = 2.0, OUTDEL = 0.1, PRDEL = 0.5
PRINT X
END
"""

SUM = """TITLE SUM OF TWO RATES
PARAM K1 = 0.5, K2 = 1.0
X = INTGRL(0.0, K1 + K2)
TIMER FINTIM = 2.0, OUTDEL = 0.1
PRINT X
TERMINAL
   XEND = X
END
"""


def complex_step(f, values: dict[str, float], names: list[str]) -> list[float]:
    """d f(values) / d each of `names` by the complex step (h = 1e-30: exact to
    rounding for an f written in complex-safe arithmetic)."""
    return [f({**values, n: values[n] + 1e-30j}).imag / 1e-30 for n in names]


def assert_tangent_is(model, variable: str, values: dict[str, float], times, closed,
                      tol: float) -> None:
    """The tangent of `variable` (RELERR 1e-12) with respect to every one of `values`
    at `times`, against the complex step of `closed(t, values)`, to `tol`."""
    from amilpy.analysis.sensitivity import trajectory

    names = list(values)
    track = trajectory(model, 0, names, values, {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        exact = complex_step(lambda v, t=t: closed(t, v), values, names)
        assert track.row(variable, t) == pytest.approx(exact, abs=tol), t


@pytest.fixture
def decay(tmp_path):
    path = tmp_path / "decay.amil"
    path.write_text(DECAY)
    return path


@pytest.fixture
def rates(tmp_path):
    path = tmp_path / "sum.amil"
    path.write_text(SUM)
    return path


def test_local_coefficients_of_a_decay_are_minus_k_t_and_one(decay):
    # X = X0 exp(-K t): (K/X) dX/dK = -K t, (X0/X) dX/dX0 = 1. The sensitivity
    # equations are integrated with the run's steps (RELERR 1e-6): 1e-6.
    loc = amilpy.load(decay).sensitivity()
    assert loc.names == ["K", "X0"] and loc.how == "sensitivity equations"
    s = loc.normalised
    assert s[:, 0, 0] == pytest.approx(-0.7 * loc.times, abs=1e-6)
    assert s[:, 0, 1] == pytest.approx(np.ones(len(loc.times)), abs=1e-6)
    assert loc.raw[:, 0, 0] == pytest.approx(-loc.times * 2.0 * np.exp(-0.7 * loc.times),
                                             abs=1e-6)


SWITCHED = """TITLE A RATE THAT STARTS AT TS
PARAM A = 3.0, TS = 0.4
X = INTGRL(0.0, INSW(TIME - TS, 0.0, A))
TIMER FINTIM = 1.0, OUTDEL = 0.1
PRINT X
END
"""


def test_local_sensitivity_through_a_switching_instant(tmp_path):
    # X = A (t - TS) after TS: dX/dA = t - TS, dX/dTS = -A, differentiated through
    # the moving switch (its surface depends on TS): exact on this piecewise-linear
    # flow, 1e-9.
    path = tmp_path / "switched.amil"
    path.write_text(SWITCHED)
    # (At t = TS itself X is not differentiable in TS: the row there is left out.)
    loc = amilpy.load(path).sensitivity(["A", "TS"])
    after = loc.times > 0.4 + 1e-9
    before = loc.times < 0.4 - 1e-9
    assert loc.raw[after, 0, 0] == pytest.approx(loc.times[after] - 0.4, abs=1e-9)
    assert loc.raw[after, 0, 1] == pytest.approx(np.full(int(np.sum(after)), -3.0), abs=1e-9)
    assert loc.raw[before, 0, :] == pytest.approx(np.zeros((int(np.sum(before)), 2)),
                                                  abs=1e-12)


def test_an_output_a_memory_holds_carries_the_held_values_dependence():
    """XH = ZHOLD(0.5 - TIME, X) follows X = exp(-K t) until TIME = 0.5 and holds
    X(0.5) = exp(-0.35) from then on: d XH/d K = -t exp(-K t), then -0.5 exp(-0.35).
    The tangent carries the memory through its updates (it gave 0 until 2026-11-30,
    then differenced whole runs): to 1e-9."""
    model = amilpy.loads("TITLE HOLD\nPARAM K = 0.7\nX = INTGRL(1.0, -K*X)\n"
                         "XH = ZHOLD(0.5 - TIME, X)\nTIMER FINTIM = 1.0, OUTDEL = 0.1\n"
                         "PRINT X, XH\nEND\n")
    loc = model.sensitivity(["K"], outputs=["XH"])
    assert loc.how == "sensitivity equations"
    held = np.minimum(loc.times, 0.5)
    assert loc.raw[:, 0, 0] == pytest.approx(-held * np.exp(-0.7 * held), abs=1e-9)


def held_time_integral(t, k):
    """Y = INTGRL(0, ZHOLD(X - 0.5, TIME)), X = exp(-K t): the hold follows TIME
    until X reaches 0.5 at tc = ln 2 / K and keeps tc: Y = t^2/2, then tc^2/2 + tc
    (t - tc)."""
    tc = np.log(2.0) / k
    return (t * t / 2 if t < tc.real else tc * tc / 2 + tc * (t - tc)), tc


def test_a_hold_whose_instant_moves_takes_its_input_at_the_moved_instant():
    """ZHOLD(X - 0.5, TIME) holds where X = exp(-K t) reaches 0.5, at tc = ln 2/K,
    which K moves: the held value's dependence is dB/dt dtc/dK = -ln 2/K^2, the
    update's rate in TIME times the instant's shift; Y, its integral, reads it.
    Against the complex step of the closed form, to 1e-9."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("TITLE MOVING HOLD\nPARAM K = 0.7\nX = INTGRL(1.0, -K*X)\n"
                         "XH = ZHOLD(X - 0.5, TIME)\nY = INTGRL(0.0, XH)\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.1\nPRINT X, XH, Y\nEND\n")
    times = [0.5, 0.9, 1.2, 1.6, 2.0]
    track = trajectory(model, 0, ["K"], {"K": 0.7}, {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        y, tc = held_time_integral(t, 0.7 + 1e-30j)
        assert track.row("Y", t)[0] == pytest.approx(y.imag / 1e-30, abs=1e-9), t
        xh = tc.imag / 1e-30 if t > tc.real else 0.0
        assert track.row("XH", t)[0] == pytest.approx(xh, abs=1e-9), t


def test_a_switch_on_time_that_a_value_moves_jumps_the_tangent():
    """X' = STEP(T1) - K X, X(0) = 0: X = (1 - exp(-K (t - T1)))/K after T1. d X/d T1 =
    -exp(-K (t - T1)) there, 0 before: the tangent jumps by f- - f+ = -1 at T1 (the
    switch's instant moves by dT1), which it left out until 2026-11-30 (differenced).
    To 1e-9 (the tangent is exact on these linear stretches)."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("TITLE STEP\nPARAM K = 0.5, T1 = 0.7\n"
                         "X = INTGRL(0.0, STEP(T1) - K*X)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\n"
                         "PRINT X\nEND\n")
    times = [0.5, 0.75, 1.3, 2.0]
    track = trajectory(model, 0, ["T1", "K"], {"K": 0.5, "T1": 0.7}, {}, times)
    assert not isinstance(track, str), track
    for t in times:
        k, t1 = 0.5, 0.7
        s = max(t - t1, 0.0)
        dx_dt1 = -np.exp(-k * s) if t > t1 else 0.0
        dx_dk = (np.exp(-k * s) * (1 + k * s) - 1) / k ** 2 if t > t1 else 0.0
        assert track.row("X", t) == pytest.approx([dx_dt1, dx_dk], abs=1e-9), t


def hold_read(t, k):
    """Y' = XH - Y, Y(0) = 0, XH = ZHOLD(0.5 - TIME, X), X = exp(-K t): Y = (e^{-K t}
    - e^{-t})/(1 - K) to 0.5, then XH(0.5) + (Y(0.5) - XH(0.5)) e^{-(t - 0.5)}."""
    y = (np.exp(-k * min(t, 0.5)) - np.exp(-min(t, 0.5))) / (1 - k)
    if t <= 0.5:
        return y
    held = np.exp(-0.5 * k)
    return held + (y - held) * np.exp(-(t - 0.5))


def test_a_memory_the_derivatives_read_carries_its_dependence():
    """Y' = XH - Y with XH = ZHOLD(0.5 - TIME, X): the hold is itself a switch, and
    after it the derivatives read the held value; its tangent is carried (d Y/d K
    came out without that part, -0.062 for -0.153 at 0.8, until review 48; then the
    run was differenced). Against the complex step of the closed form, to 1e-9."""
    model = amilpy.loads("TITLE HOLD READ\nPARAM K = 0.7\nX = INTGRL(1.0, -K*X)\n"
                         "XH = ZHOLD(0.5 - TIME, X)\nY = INTGRL(0.0, XH - Y)\n"
                         "TIMER FINTIM = 1.5, OUTDEL = 0.1\nPRINT X, Y\nEND\n")
    loc = model.sensitivity(["K"], outputs=["Y"])
    assert loc.how == "sensitivity equations"
    exact = [hold_read(t, 0.7 + 1e-30j).imag / 1e-30 for t in loc.times]
    assert loc.raw[:, 0, 0] == pytest.approx(exact, abs=1e-9)


DUE = """PROGRAM dose when due
  CONSTANT KA = 1.2, DOSE = 100.0, TAU = 2.0
  CINTERVAL CINT = 0.5
  INITIAL
    TD = 0.0
  END
  DERIVATIVE
    AG = INTEG(-KA*AG, 0.0)
    TERMT(T >= 5.0)
  END
  DISCRETE CHECK
    INTERVAL DT = 1.0
    IF (T >= TD) THEN
      AG = AG + DOSE
      TD = TD + TAU
    END IF
  END
END
"""


def test_an_if_in_discrete_code_that_a_value_turns_has_no_derivative():
    """A dose given when T >= TD, TD = TD + TAU: at T = 2 the test stands at equality
    and TAU turns it (AG jumps by DOSE with TAU: no derivative), said and differenced
    (it gave -2.3e6, review 48). KA and DOSE do not move TD: at T = 0 its test is at
    equality too, but nothing of theirs goes through it, and their tangent is exact:
    AG = DOSE (e^{-KA t} + e^{-KA (t - 2)} + e^{-KA (t - 4)}) for t >= 4."""
    model = amilpy.loads(DUE, "due.csl")
    loc = model.sensitivity(["TAU"], outputs=["AG"])
    assert loc.how == "differences of whole runs (DISCRETE CHECK at TIME = 2: its code " \
        "jumps there (an IF whose test turns with the value))"
    from amilpy.analysis.sensitivity import trajectory

    track = trajectory(model, 0, ["KA", "DOSE"], {"KA": 1.2, "DOSE": 100.0, "TAU": 2.0}, {},
                       [4.5])
    ka, t = 1.2, 4.5
    e = sum(np.exp(-ka * (t - d)) for d in (0.0, 2.0, 4.0))
    de = sum(-(t - d) * np.exp(-ka * (t - d)) for d in (0.0, 2.0, 4.0))
    assert track.row("AG", t) == pytest.approx([100.0 * de, e], rel=1e-8)


def _bateman(t, dose, ka, ke, vd, tau=12.0, doses=7):
    """The oral-dosing program's closed form: one Bateman curve per dose (a dose at d
    counts from T = d on: the row of a dosing instant is after the dose, and the
    dose due at TSTOP = 72 is given before the TERMT ends the run)."""
    cp = ag = 0.0
    for k in range(doses):
        s = t - k * tau
        on = s >= -1e-9
        cp = cp + np.where(on, dose * ka / (vd * (ka - ke)) * (np.exp(-ke * s) -
                                                            np.exp(-ka * s)), 0.0)
        ag = ag + np.where(on, dose * np.exp(-ka * s), 0.0)
    return cp, ag


def test_an_acsl_program_is_differentiated_through_its_doses():
    """The DISCRETE dosing program's tangent: d CP/d p and d AG/d p for KA, KE, DOSE
    and VD on its whole CINT grid, dosing instants included (AG jumps by DOSE there:
    d AG/d DOSE jumps by 1), against the complex-step derivative of the closed form
    (exact to rounding, independent of amilpy). The run's RELERR 1e-10 leaves the
    tangent good to about 1e-9 of each column's largest; 1e-7 is the bound."""
    model = amilpy.load(EXAMPLES / "oral_dosing.csl")
    names = ["KA", "KE", "DOSE", "VD"]
    loc = model.sensitivity(names, outputs=["CP", "AG"])
    assert loc.how == "sensitivity equations"
    assert 12.0 in loc.times.tolist() and 36.0 in loc.times.tolist()
    p = {"DOSE": 500.0, "KA": 1.2, "KE": 0.173, "VD": 42.0}
    for j, name in enumerate(names):
        moved = {**p, name: p[name] + 1e-30j}
        cp, ag = _bateman(loc.times.astype(complex), moved["DOSE"], moved["KA"],
                          moved["KE"], moved["VD"])
        for k, exact in enumerate((cp.imag / 1e-30, ag.imag / 1e-30)):
            scale = max(np.max(np.abs(exact)), 1.0)  # (d AG/d KE = 0: its noise)
            assert np.max(np.abs(loc.raw[:, k, j] - exact)) <= 1e-7 * scale, (name, k)
    # (VD/CP) dCP/dVD = -1 exactly (CP = AB/VD)
    s = loc.normalised[1:, 0, 3]
    assert s == pytest.approx(np.full(len(s), -1.0), abs=1e-9)


SAMPLED = """PROGRAM sampled proportional control
! X' = U, U = -KP X held between the CINT instants where DYNAMIC samples it:
! X(k H) = X0 (1 - KP H)^k, and in between X grows linearly
  CONSTANT KP = 0.8, X0 = 2.0
  CINTERVAL CINT = 0.25
  INITIAL
    U = -KP*X0
  END
  DYNAMIC
    DERIVATIVE
      X = INTEG(U, X0)
    END
    U = -KP*X
    TERMT(T >= 3.0)
  END
END
"""


def test_a_value_the_dynamic_code_holds_carries_its_dependence():
    """U = -KP X, sampled by DYNAMIC every CINT and held (a memory value the
    derivatives read): X(t) = X0 (1 - KP H)^k (1 - KP (t - k H)), k = floor(t/H).
    d X/d KP and d X/d X0 from the closed form's derivative, at the grid and
    between (observations at 0.1, 0.6, 1.35): to 1e-9, the tangent being exact on
    this linear stretch (one exp per stretch) and the code's differences exact
    for code linear in its inputs."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads(SAMPLED, "sampled.csl")
    times = [0.1, 0.25, 0.6, 1.0, 1.35, 2.5]
    track = trajectory(model, 0, ["KP", "X0"], {"KP": 0.8, "X0": 2.0}, {}, times)
    assert not isinstance(track, str), track
    h = 0.25
    for t in times:
        k = np.floor(t / h + 1e-9)
        s = t - k * h
        for j, (kp, x0) in enumerate(((0.8 + 1e-30j, 2.0), (0.8, 2.0 + 1e-30j))):
            x = x0 * (1 - kp * h) ** k * (1 - kp * s)
            assert track.row("X", t)[j] == pytest.approx(x.imag / 1e-30, abs=1e-9), (t, j)
            assert track.row("U", t)[j] == pytest.approx(
                (-kp * x0 * (1 - kp * h) ** k).imag / 1e-30, abs=1e-9), (t, j)


PULSED = """PROGRAM pulsed input
! X' = A PULSE(0, 10, W) - K X: on for W, then off (W = 1 ends at a CINT instant,
! where DYNAMIC's own statement runs)
  CONSTANT A = 2.0, W = 1.0, K = 0.5
  CINTERVAL CINT = 0.5
  DYNAMIC
    DERIVATIVE
      X = INTEG(A*PULSE(0.0, 10.0, W) - K*X, 0.0)
      TERMT(T >= 3.0)
    END
    XS = X
  END
END
"""


def test_a_pulse_that_ends_at_a_cint_instant_is_the_flows_switch():
    """The PULSE's end at T = W = 1.0 falls on a CINT instant, where the program's
    branches are chosen again: it is still the flow's switch, and W moves it, so the
    tangent jumps there by (f- - f+) dT/dW: X(t) = (A/K)(1 - e^{-K W}) e^{-K (t - W)}
    after the pulse, d X/d W = A e^{-K (t - W)}, d X/d A = X/A."""
    model = amilpy.loads(PULSED, "pulsed.csl")
    loc = model.sensitivity(["A", "W"], outputs=["X"])
    assert loc.how == "sensitivity equations"
    from amilpy.analysis.sensitivity import trajectory

    times = [0.5, 0.99, 1.01, 2.5]
    track = trajectory(model, 0, ["A", "W"], {"A": 2.0, "W": 1.0, "K": 0.5}, {}, times)
    for t in times:
        exact = (1 - np.exp(-0.5 * min(t, 1.0))) / 0.5 * np.exp(-0.5 * max(t - 1.0, 0.0))
        by_w = 2.0 * np.exp(-0.5 * (t - 1.0)) if t > 1.0 else 0.0
        assert track.row("X", t) == pytest.approx([exact, by_w], abs=1e-9), t


def pulsed_decay(t, a, k, tz, p, w):
    """X' = A PULSE(TZ, P, W) - K X from 0: each pulse [s, s + W) adds
    (A/K)(e^{-K (t - min(t, s + W))} - e^{-K (t - s)}); complex arguments for the
    complex step (the instants compared by their real parts)."""
    x, n = 0.0, 0
    while (tz + n * p).real < t:
        s = tz + n * p
        e = s + w
        x = x + a / k * (np.exp(-k * (t - (e if e.real < t else t))) - np.exp(-k * (t - s)))
        n += 1
    return x


def test_a_pulse_train_whose_instants_move_jumps_the_tangent_at_each():
    """X' = A PULSE(TZ, P, W) - K X: every start TZ + k P and end TZ + k P + W of the
    train moves with TZ, P and W, the k-th by d/dTZ = 1, d/dP = k (and d/dW = 1 for
    an end): the tangent jumps by (f- - f+) dT/dp at each, and agrees with the
    complex step of the closed form (to 1e-9: the tangent's own tolerance) at
    instants between and just after the edges. Before, every such value was
    differenced ("a PULSE train whose instants depend on a data value")."""
    model = amilpy.loads("PARAM A = 2.0, K = 0.7, TZ = 0.3, P = 1.1, W = 0.4\n"
                         "X = INTGRL(0.0, A*PULSE(TZ, P, W) - K*X)\n"
                         "TIMER FINTIM = 5.0, OUTDEL = 0.25\nEND\n", "train.amil")
    names = ["A", "K", "TZ", "P", "W"]
    values = {"A": 2.0, "K": 0.7, "TZ": 0.3, "P": 1.1, "W": 0.4}
    from amilpy.analysis.sensitivity import trajectory

    times = [0.2, 0.5, 0.71, 1.0, 1.45, 1.81, 2.6, 3.61, 4.95]
    track = trajectory(model, 0, names, values, {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        for j, name in enumerate(names):
            moved = dict(values)
            moved[name] = moved[name] + 1e-30j
            exact = pulsed_decay(t, *(moved[n] for n in names)).imag / 1e-30
            assert track.row("X", t)[j] == pytest.approx(exact, abs=1e-9), (t, name)
    assert model.sensitivity(names, outputs=["X"]).how == "sensitivity equations"


def test_two_pulse_trains_sharing_an_instant_each_move_theirs():
    """X' = A PULSE(TZ1, P1, W1) + B PULSE(TZ2, P2, W2) - K X with both trains starting
    at 0.3 (and meeting again at 2.5 = 0.3 + 2 P1 = 0.3 + P2): a value moves one
    train's instants and not the other's, and the field is the sum of the two, so
    each jumps the tangent by its own (f- - f+) dT/dp. Differenced whole runs until
    2026-12-01 ("a PULSE train whose instants depend on a data value"); against the
    complex step of the closed form (the sum of two pulsed decays), to 1e-9."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM A = 2.0, B = 0.5, K = 0.7, TZ1 = 0.3, P1 = 1.1, W1 = 0.4\n"
                         "PARAM TZ2 = 0.3, P2 = 2.2, W2 = 0.9\n"
                         "X = INTGRL(0.0, A*PULSE(TZ1, P1, W1) + B*PULSE(TZ2, P2, W2) - K*X)\n"
                         "TIMER FINTIM = 4.0, OUTDEL = 0.25\nEND\n", "trains.amil")
    values = {"A": 2.0, "B": 0.5, "K": 0.7, "TZ1": 0.3, "P1": 1.1, "W1": 0.4, "TZ2": 0.3,
              "P2": 2.2, "W2": 0.9}
    names = ["TZ1", "P1", "TZ2", "P2", "W2", "K"]
    times = [0.2, 0.5, 1.0, 1.45, 2.6, 3.1, 4.0]
    track = trajectory(model, 0, names, values, {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track

    def x(t, v):
        return pulsed_decay(t, v["A"], v["K"], v["TZ1"], v["P1"], v["W1"]) + \
            pulsed_decay(t, v["B"], v["K"], v["TZ2"], v["P2"], v["W2"])

    for t in times:
        for j, name in enumerate(names):
            exact = x(t, {**values, name: values[name] + 1e-30j}).imag / 1e-30
            assert track.row("X", t)[j] == pytest.approx(exact, abs=1e-9), (t, name)


def test_two_pulse_trains_whose_product_turns_at_one_instant_have_no_derivative():
    """X' = PULSE(TZ1, 1, 0.4) PULSE(TZ2, 1, 0.6) - X with TZ1 = TZ2: moving TZ1 up
    delays the product's start by dTZ1, moving it down does not advance it (TZ2 still
    holds it off), so d X/d TZ1 differs from either side and the tangent says so;
    the fit then differences whole runs."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM TZ1 = 0.3, TZ2 = 0.3\n"
                         "X = INTGRL(0.0, PULSE(TZ1, 1.0, 0.4)*PULSE(TZ2, 1.0, 0.6) - X)\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.25\nEND\n", "product.amil")
    said = trajectory(model, 0, ["TZ1"], {"TZ1": 0.3, "TZ2": 0.3}, {}, [1.0, 2.0])
    assert isinstance(said, str) and "from either side" in said


def test_instants_the_code_sets_move_with_the_values():
    """A dose every TAU (INTERVAL DT = TAU) and one at TD (INITIAL's SCHEDULE .AT. TD)
    that grows with T: AG = DOSE sum over the doses k of exp(-KA (t - t_k)) + (DOSE/2 +
    2 TD) exp(-KA (t - TD)), the k-th INTERVAL instant moving by k dTAU and the .AT.
    one by dTD; the code's map applies where the instant moved it, at the moved TIME,
    J (Phi + f- dt) + (M_t - f+) dt (M_t, the code's rate in T, was left out until the
    re-read of 2026-11-30: d AG/d TD lacked 2 exp(-KA (t - TD))). Differenced whole runs until
    2026-11-30 ("an INTERVAL depends on TAU"); against the complex step of the
    closed form, to 1e-8."""

    text = """PROGRAM dosing every TAU
  CONSTANT KA = 0.3, DOSE = 100.0, TAU = 4.0, TD = 2.5
  CINTERVAL CINT = 0.5
  INITIAL
    SCHEDULE EXTRA .AT. TD
  END
  DERIVATIVE
    AG = INTEG(-KA*AG, 0.0)
    TERMT(T >= 19.0)
  END
  DISCRETE DOSING
    INTERVAL DT = TAU
    AG = AG + DOSE
  END
  DISCRETE EXTRA
    AG = AG + 0.5*DOSE + 2.0*T
  END
END
"""

    def ag(t, tau, ka, td):
        total, k = 0.0, 0
        while (k * tau).real <= t:
            total = total + 100.0 * np.exp(-ka * (t - k * tau))
            k += 1
        return total + ((50.0 + 2.0 * td) * np.exp(-ka * (t - td)) if t >= td.real else 0.0)

    assert_tangent_is(amilpy.loads(text, "dosing.csl"), "AG",
                      {"TAU": 4.0, "KA": 0.3, "TD": 2.5}, [1.0, 3.0, 5.0, 9.5, 13.0, 18.7],
                      lambda t, v: ag(t, v["TAU"], v["KA"], v["TD"]), 1e-8)


INFUSIONS = """PROGRAM infusions every TAU, each TLEN long
  CONSTANT R = 2.0, K = 0.7, TLEN = 0.4, TAU = 1.1, T0 = 0.3
  CINTERVAL CINT = 0.25
  INITIAL
    RATE = 0.0
    SCHEDULE ON .AT. T0
  END
  DYNAMIC
    DERIVATIVE
      X = INTEG(RATE - K*X, 0.0)
    END
    DISCRETE ON
      RATE = R
      SCHEDULE OFF .AT. T + TLEN
      SCHEDULE ON .AT. T + TAU
    END
    DISCRETE OFF
      RATE = 0.0
    END
    TERMT(T >= 5.0)
  END
END
"""


def test_instants_discrete_code_schedules_move_with_the_values():
    """An infusion at rate R from T0 every TAU, each stopped TLEN later by a SCHEDULE
    .AT. that the DISCRETE code computes (T + TLEN, T + TAU): the k-th start moves by
    dT0 + k dTAU, its stop by that + dTLEN, and the tangent carries each scheduled
    instant's shift to the section it runs (with d t_s/d T times the shift of the
    instant that schedules it). The same X as PULSE(T0, TAU, TLEN): against the
    complex step of that closed form, to 1e-9. Differenced whole runs before ("the
    time it schedules depends on a data value")."""
    model = amilpy.loads(INFUSIONS, "infusions.csl")
    values = {"R": 2.0, "K": 0.7, "T0": 0.3, "TAU": 1.1, "TLEN": 0.4}
    assert_tangent_is(model, "X", values, [0.2, 0.5, 0.71, 1.0, 1.45, 1.81, 2.6, 3.61, 4.95],
                      lambda t, v: pulsed_decay(t, v["R"], v["K"], v["T0"], v["TAU"],
                                                v["TLEN"]), 1e-9)
    assert model.sensitivity(list(values), outputs=["X"]).how == "sensitivity equations"


def test_an_instant_scheduled_from_a_state_moves_with_it():
    """The infusion stopped when X would reach a level: OFF at T + X/R (X at the
    start, so the stop moves with everything that moves X there). Against central
    differences of whole runs at RELERR 1e-12 (h = 1e-5: about 1e-7)."""
    text = INFUSIONS.replace("SCHEDULE OFF .AT. T + TLEN", "SCHEDULE OFF .AT. T + 0.3 + X/R")
    model = amilpy.loads(text, "infusions.csl")
    from amilpy.analysis.sensitivity import trajectory

    values = {"R": 2.0, "K": 0.7, "TAU": 1.1}
    times = [0.5, 1.5, 2.75, 4.75]  # (CINT instants: rows of the runs differenced)
    track = trajectory(model, 0, list(values), values, {"rtol": 1e-12, "atol": 1e-14},
                       times)
    assert not isinstance(track, str), track
    h = 1e-5
    for j, name in enumerate(values):
        def x_at(delta, name=name):
            run = model.run(advice=False, rtol=1e-12, atol=1e-14,
                            **{**values, name: values[name] + delta})[0]
            return np.array([run["X"][list(run.times).index(t)] for t in times])
        reference = (x_at(h) - x_at(-h)) / (2 * h)
        assert [track.row("X", t)[j] for t in times] == pytest.approx(reference, abs=1e-6)


def test_a_section_a_crossing_runs_moves_with_the_values():
    """X' = -K X from 2, SCHEDULE HIT .XN. X - 1, HIT: X = X + 1: X reaches 1 at
    ln 2/K, back to 2, and again every ln 2/K: X = 2 exp(-K (t - k ln 2/K)). The
    section's instant moves with K, and the tangent takes the code's map at the
    moved instant (J (Phi + f- dt) - f+ dt) where it differenced whole runs; the
    bouncing ball's impacts (G, E, H0) likewise. Against the complex step of the
    closed forms, to 1e-8."""
    from test_acsl_events import BALL

    from amilpy.analysis.sensitivity import trajectory

    text = """PROGRAM kicked decay
  CONSTANT K = 0.5
  CINTERVAL CINT = 0.5
  DERIVATIVE
    X = INTEG(-K*X, 2.0)
    SCHEDULE HIT .XN. X - 1.0
    TERMT(T >= 5.0)
  END
  DISCRETE HIT
    X = X + 1.0
  END
END
"""
    times = [0.5, 1.5, 2.0, 3.1, 4.9]
    track = trajectory(amilpy.loads(text, "kick.csl"), 0, ["K"], {"K": 0.5},
                       {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        k = 0.5 + 1e-30j
        period = np.log(2.0) / k
        x = 2.0 * np.exp(-k * (t - np.floor(t / period.real) * period))
        assert track.row("X", t)[0] == pytest.approx(x.imag / 1e-30, abs=1e-8), t

    def height(t, g, e, h0):
        t1 = (2 * h0 / g) ** 0.5
        if t < t1.real:
            return h0 - g * t * t / 2
        a, v = t1, g * t1
        while True:
            v = e * v
            if t < (a + 2 * v / g).real:
                return v * (t - a) - g * (t - a) ** 2 / 2
            a = a + 2 * v / g

    assert_tangent_is(amilpy.loads(BALL, "ball.csl"), "H",
                      {"G": 9.81, "E": 0.8, "H0": 10.0}, [0.5, 2.0, 3.0, 4.0, 5.5],
                      lambda t, v: height(t, v["G"], v["E"], v["H0"]), 1e-8)


def test_sobol_indices_of_a_sum_are_its_variance_shares(rates):
    # X(T) = T (K1 + K2), K1 ~ U(0, 1), K2 ~ U(0, 2): V(K1) = 1/12, V(K2) = 4/12, so
    # S1 = ST1 = 0.2, S2 = ST2 = 0.8 (additive: first order = total). N = 512 rows;
    # the estimators of an additive model are within 0.01 here, and the bootstrap
    # intervals hold the exact values.
    ind = amilpy.load(rates).sensitivity(method="sobol", dists={
        "K1": "uniform(0, 1)", "K2": "uniform(0, 2)"}, measures=["X", "XEND", "X@1"],
        runs=512, seed=3)
    assert ind.runs == 512 * 4 and not ind.failed
    for m in range(3):
        assert ind.first[m] == pytest.approx([0.2, 0.8], abs=0.01)
        assert ind.total[m] == pytest.approx([0.2, 0.8], abs=0.01)
        for j, exact in enumerate([0.2, 0.8]):
            assert ind.first_ci[m, j, 0] <= exact <= ind.first_ci[m, j, 1]
            assert ind.total_ci[m, j, 0] <= exact <= ind.total_ci[m, j, 1]
    assert ind.variance[0] == pytest.approx(4.0 * 5 / 12, rel=0.05)  # T^2 (1/12 + 4/12)


def test_morris_effects_of_a_linear_output_are_its_slopes(rates):
    # X(2) = 2 (K1 + K2): an effect is dX/du = 2 (b - a): 2 for K1, 4 for K2, with
    # no spread (sigma 0 to rounding); max(X) is the same (X grows).
    ind = amilpy.load(rates).sensitivity(method="morris", dists={
        "K1": "uniform(0, 1)", "K2": "uniform(0, 2)"}, measures=["X", "max(X)"],
        runs=12, seed=1)
    assert ind.runs == 12 * 3
    assert ind.mu_star == pytest.approx(np.array([[2.0, 4.0], [2.0, 4.0]]), rel=1e-9)
    assert ind.mu == pytest.approx(ind.mu_star, rel=1e-9)
    assert np.all(ind.sigma < 1e-9)


def test_global_indices_are_the_same_whatever_the_workers(rates):
    kw = dict(method="sobol", dists={"K1": "normal(1, 0.2)", "K2": "lognormal(0, 0.3)"},
              measures=["X"], runs=64, seed=5)
    one = amilpy.load(rates).sensitivity(jobs=1, **kw)
    two = amilpy.load(rates).sensitivity(jobs=2, **kw)
    assert np.array_equal(one.values, two.values)
    assert np.array_equal(one.first, two.first) and np.array_equal(one.total, two.total)


def test_sensitivity_commands_write_csv_and_figures(decay, rates, tmp_path, capsys):
    local_csv = tmp_path / "local.csv"
    assert main(["sensitivity", str(decay), "--local", "K", "--csv", str(local_csv),
                 "--plot", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("LOCAL SENSITIVITIES OF DECAY") and "S AT THE PRDEL" in out
    with open(local_csv, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["TIME", "X", "S_X_K", "D_X_K"]
    assert float(rows[-1][2]) == pytest.approx(-0.7 * 2.0, abs=1e-6)
    assert (tmp_path / "decay_sensitivity_X.png").exists()
    global_csv = tmp_path / "global.csv"
    assert main(["sensitivity", str(rates), "--method", "morris", "--dist",
                 "K1=uniform(0,1)", "--dist", "K2=uniform(0,2)", "--runs", "4",
                 "--csv", str(global_csv), "--plot", "--out", str(tmp_path),
                 "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("MORRIS ELEMENTARY EFFECTS OF SUM OF TWO RATES")
    with open(global_csv, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["MEASURE", "NAME", "MU_STAR", "MU", "SIGMA"]
    assert [r[1] for r in rows[1:]] == ["K1", "K2"]
    assert (tmp_path / "sum_sensitivity.png").exists()


@pytest.mark.parametrize("argv, message", [
    (["--local", "K", "--method", "sobol", "--dist", "K=uniform(0,1)", "--runs", "8"],
     "not both"),
    (["--dist", "K=uniform(0,1)"], "add --method"),
    (["--method", "sobol", "--runs", "8"], "--dist NAME=DIST"),
    (["--method", "sobol", "--dist", "K=uniform(0,1)"], "give the number of runs"),
    (["--method", "sobol", "--dist", "K=uniform(0,1)", "--runs", "8", "--measure", "X@0.55"],
     "not an output instant"),
    (["--method", "morris", "--dist", "K=uniform(0,1)", "--runs", "8", "--measure", "Q"],
     "Q is not a variable"),
    (["--local", "NOPE"], "--local NOPE: not a PARAM"),
])
def test_sensitivity_usage_errors(decay, capsys, argv, message):
    assert main(["sensitivity", str(decay), "--jobs", "1", *argv]) == 2
    assert message in capsys.readouterr().err


def test_a_table_is_no_distribution_for_global_indices(rates, tmp_path):
    table = tmp_path / "t.csv"
    table.write_text("K1\n1\n2\n")
    with pytest.raises(UsageError, match="not table"):
        amilpy.load(rates).sensitivity(method="sobol", dists={"K1": f"table({table})"},
                                       runs=4)


def test_a_fixed_step_route_is_differenced_and_says_so(decay):
    # EULER has no dense output for the sensitivity equations: central differences
    # of whole runs, said; (K/X) dX/dK of Euler's own solution is still about -K t.
    loc = amilpy.load(decay).sensitivity(["K"], method_ode="EULER")
    assert loc.how.startswith("differences of whole runs (a fixed-step route")
    assert loc.normalised[-1, 0, 0] == pytest.approx(-0.7 * 2.0, rel=2e-2)


def test_a_delay_s_store_carries_its_sensitivities():
    """X' = -K DELAY(50, P, X) + A sin t: the store's samples (taken inside the steps
    from the dense output) each keep their own d X/d p, the tangent cut where the
    run samples; X and XD against central differences of whole runs at RELERR 1e-12
    (h = 1e-4: about 3e-8 off, measured at N = 50, FINTIM 4, RELERR 1e-12).
    Differenced whole runs before ("DELAY's store samples the states inside the
    steps"). A free delay P moves the instants the store samples at, which the
    tangent says."""
    from amilpy.analysis.sensitivity import trajectory

    text = ("PARAM K = 0.8, A = 0.3, P = 1.0\nINCON X0 = 1.0\nXD = DELAY(20, P, X)\n"
            "X = INTGRL(X0, -K*XD + A*SIN(TIME))\nTIMER FINTIM = 2.5, OUTDEL = 0.25\n"
            "PRINT X, XD\nEND\n")
    model = amilpy.loads(text, "delay.amil")
    values = {"K": 0.8, "A": 0.3, "X0": 1.0, "P": 1.0}
    names, times = ["K", "A", "X0"], [0.5, 1.25, 2.0, 2.5]
    track = trajectory(model, 0, names, values, {"rtol": 1e-10, "atol": 1e-12}, times,
                       ["X", "XD"])
    assert not isinstance(track, str), track
    h = 1e-4
    for j, name in enumerate(names):
        def rows(delta, name=name):
            run = model.run(advice=False, rtol=1e-12, atol=1e-14,
                            **{**values, name: values[name] + delta})[0]
            at = [list(run.times).index(t) for t in times]
            return np.array([[run["X"][i], run["XD"][i]] for i in at])
        reference = (rows(h) - rows(-h)) / (2 * h)
        got = np.array([[track.row("X", t)[j], track.row("XD", t)[j]] for t in times])
        assert np.max(np.abs(got - reference)) <= 1e-6, name
    assert model.sensitivity(["K"], outputs=["X"], fintim=1.5).how == "sensitivity equations"


def delayed_decay(times, k, a, p, x0, n=20):
    """X' = -K XD + A SIN(TIME), XD = DELAY(N, P, X), X(0) = X0, as the store computes
    it: samples X_j = X(j H), H = P/N, XD linear between X_{j-N} and X_{j-N+1} on [j H,
    (j + 1) H] (X0 before P), so X on each piece is X(j H) - K times the integral of
    that line + A (cos(j H) - cos t): a closed form, complex arguments for the complex
    step (the pieces chosen by real parts). (X, XD) at each of `times`."""
    h = p / n
    x = [x0]

    def line(j: int, t):
        if j < n:
            return x0, x0 * (t - j * h)
        lo, hi = x[j - n], x[j - n + 1]
        u = t - j * h
        return lo + (hi - lo) * u / h, lo * u + (hi - lo) * u * u / (2 * h)

    out, j = [], 0
    for t in times:
        while ((j + 1) * h).real <= t:
            x.append(x[j] - k * line(j, (j + 1) * h)[1] + a * (np.cos(j * h) - np.cos((j + 1) * h)))
            j += 1
        xd, area = line(j, t)
        out.append((x[j] - k * area + a * (np.cos(j * h) - np.cos(t)), xd))
    return out


def test_a_free_delay_moves_the_store_s_instants_and_its_reads():
    """DELAY(20, P, X) with P free: the store samples at j P/20 and reads X at TIME -
    P, so d/dP moves every sampling instant (the k-th by k/20: each sample's d X/d P
    is S + f k/20, at its moving instant) and the read (its start at TIME = P, where it
    leaves the held X0, and its interpolation between samples that move). Against
    the complex step of the store's own closed form (`delayed_decay`), at instants
    between samples: X to 1e-8 (measured 4e-10), XD to 1e-7 (measured 9e-9: the read's
    difference across its interpolation, whose second derivative in P is large).
    Differenced whole runs until 2026-12-01 ("DELAY's sampling instants move with a
    data value (its delay)"); the differences across the held start put d X/d P 6e-7
    off."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM K = 0.8, A = 0.3, P = 1.0\nINCON X0 = 1.0\n"
                         "XD = DELAY(20, P, X)\nX = INTGRL(X0, -K*XD + A*SIN(TIME))\n"
                         "TIMER FINTIM = 2.5, OUTDEL = 0.25\nPRINT X, XD\nEND\n",
                         "delay.amil")
    values = {"K": 0.8, "A": 0.3, "X0": 1.0, "P": 1.0}
    times = [0.53, 1.03, 1.27, 2.03, 2.47]
    track = trajectory(model, 0, ["P", "K"], values, {"rtol": 1e-10, "atol": 1e-12},
                       times, ["X", "XD"])
    assert not isinstance(track, str), track
    for name, j in (("P", 0), ("K", 1)):
        moved = {**values, name: values[name] + 1e-30j}
        exact = delayed_decay(times, moved["K"], moved["A"], moved["P"], moved["X0"])
        for t, (x, xd) in zip(times, exact, strict=True):
            assert track.row("X", t)[j] == pytest.approx(np.imag(x) / 1e-30, abs=1e-8), (t, name)
            assert track.row("XD", t)[j] == pytest.approx(np.imag(xd) / 1e-30, abs=1e-7), \
                (t, name)
    assert model.sensitivity(["P"], outputs=["X"]).how == "sensitivity equations"


def test_a_small_value_is_differentiated_by_a_fraction_of_itself(tmp_path):
    # X' = -(1E-10/A) X with A = 1E-10: (A/X) dX/dA = +t exactly.
    path = tmp_path / "small.amil"
    path.write_text("PARAM A = 1.0E-10\nX = INTGRL(1.0, -1.0E-10/A*X)\n"
                    "TIMER FINTIM = 1.0, OUTDEL = 0.1\nPRINT X\nEND\n")
    loc = amilpy.load(path).sensitivity("A")  # (a bare name is one name)
    assert loc.normalised[:, 0, 0] == pytest.approx(loc.times, abs=1e-6)


FINISHING = """TITLE DECAY THAT STOPS
PARAM K = 0.7
X = INTGRL(1.0, -K*X)
FINISH X = 0.2
TIMER FINTIM = 3.0, OUTDEL = 0.1
PRINT X
END
"""


def test_a_value_at_an_instant_some_runs_never_reach(tmp_path):
    # FINISH stops the fast-decaying runs before TIME = 2.5: their X@2.5 has no value;
    # their rows are left out and said, not an error. An instant off the output grid
    # is refused before any run.
    path = tmp_path / "finish.amil"
    path.write_text(FINISHING)
    ind = amilpy.load(path).sensitivity(method="sobol", dists={"K": "uniform(0.2, 1.2)"},
                                        measures=["X@2.5"], runs=16, seed=1)
    assert ind.notes and "rows left out" in ind.notes[-1]
    with pytest.raises(UsageError, match="not an output instant"):
        amilpy.load(path).sensitivity(method="sobol", dists={"K": "uniform(0.2, 1.2)"},
                                      measures=["X@2.55"], runs=16)


def test_sobol_points_come_row_by_row():
    # A_r, B_r, AB_1,r ... AB_k,r together, so that a study stopped early has whole rows.
    from amilpy.batch.indices import _saltelli

    u = _saltelli(3, 8, seed=1).reshape(8, 5, 3)
    for i in range(3):
        others = [j for j in range(3) if j != i]
        assert np.array_equal(u[:, 2 + i, others], u[:, 0, others])
        assert np.array_equal(u[:, 2 + i, i], u[:, 1, i])


def thermostat(hi, lo, t_end=8.0):
    """X' = -X + 10 H from X = 5, H = RST(X - HI, LO - X, 0): heating off above HI,
    on below LO; each leg an exponential towards 0 or 10 from one threshold to the
    other (complex HI, LO: the instants compared by their real parts)."""
    t, y, heat = 0.0, 5.0 + 0j, 0
    while True:
        eq = 10.0 * heat
        end = t + np.log((y - eq) / ((lo if heat == 0 else hi) - eq))
        if end.real >= t_end:
            return eq + (y - eq) * np.exp(-(t_end - t))
        y, t, heat = (lo if heat == 0 else hi), end, 1 - heat


def test_a_flip_flop_carries_its_thresholds_through_each_switch():
    """RST's memory flips at each threshold's crossing, which HI and LO move: the
    tangent jumps there (the flip is the field's change) and carries the memory
    (its value's own derivative is 0). d X(8)/d HI and d X(8)/d LO against the
    complex step of the legs summed by hand, to 1e-8."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM HI = 3.0, LO = 2.0\nX = INTGRL(5.0, -X + 10.0*H)\n"
                         "H = RST(X - HI, LO - X, 0.0)\nTIMER FINTIM = 8.0, OUTDEL = 0.1\n"
                         "END\n", "thermostat.amil")
    track = trajectory(model, 0, ["HI", "LO"], {"HI": 3.0, "LO": 2.0},
                       {"rtol": 1e-12, "atol": 1e-14}, [8.0])
    assert not isinstance(track, str), track
    exact = [thermostat(3.0 + 1e-30j, 2.0).imag / 1e-30,
             thermostat(3.0, 2.0 + 1e-30j).imag / 1e-30]
    assert track.row("X", 8.0) == pytest.approx(exact, abs=1e-8)


def test_a_hold_that_starts_following_where_its_trigger_crosses():
    """XH = ZHOLD(X - T1, SIN(TIME)), X = TIME: 0 until T1, then SIN(TIME) (its
    trigger crossed upwards, where the update reads the trigger's sign at zero);
    Y = INTGRL(0, XH) = COS(T1) - COS(TIME) after T1: d Y/d T1 = -SIN(T1) (the
    field's jump at a crossing T1 moves), d XH/d T1 = 0. To 1e-9."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM T1 = 0.7\nX = INTGRL(0.0, 1.0)\n"
                         "XH = ZHOLD(X - T1, SIN(TIME))\nY = INTGRL(0.0, XH)\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n", "follow.amil")
    times = [0.5, 0.9, 1.4, 2.0]
    track = trajectory(model, 0, ["T1"], {"T1": 0.7}, {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        assert track.row("Y", t)[0] == pytest.approx(-np.sin(0.7) if t > 0.7 else 0.0,
                                                     abs=1e-9), t
        assert track.row("XH", t)[0] == pytest.approx(0.0, abs=1e-9), t


def test_a_numerical_derivative_carries_its_points():
    """DV = DERIV(0, X), X = exp(-K t): DERIV is the difference over the last step's
    points, kept in memory; the tangent carries them, so d DV/d K is the difference
    of d X/d K, (K t - 1) exp(-K t) to DERIV's own accuracy (its value is 3e-6 off
    here at the default tolerances: 1e-4 relative)."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM K = 0.7\nX = INTGRL(1.0, -K*X)\nDV = DERIV(0.0, X)\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n", "deriv.amil")
    times = [0.5, 1.0, 2.0]
    track = trajectory(model, 0, ["K"], {"K": 0.7}, {}, times)
    assert not isinstance(track, str), track
    for t in times:
        assert track.row("DV", t)[0] == pytest.approx((0.7 * t - 1) * np.exp(-0.7 * t),
                                                      rel=1e-4), t


def test_a_state_reset_where_a_value_moves_the_instant():
    """Y = MODINT(YIC, TR - X, X - TR, K), X = TIME: Y = YIC + K t until TR, then
    reset to YIC and held; Z = INTGRL(0, Y) = YIC t + K min(t, TR)^2/2 - ... :
    after TR, Z = YIC t + K TR^2/2. The reset is y+ = IC at an instant TR moves:
    d Z/d TR = K TR, d Z/d K = TR^2/2, d Z/d YIC = t, d Y/d YIC = 1 (the IC), d Y/d
    TR = d Y/d K = 0. Differenced whole runs until 2026-11-30; to 1e-9."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM YIC = 0.5, TR = 0.8, K = 2.0\nX = INTGRL(0.0, 1.0)\n"
                         "Y = MODINT(YIC, TR - X, X - TR, K)\nZ = INTGRL(0.0, Y)\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n", "reset.amil")
    names, values = ["YIC", "TR", "K"], {"YIC": 0.5, "TR": 0.8, "K": 2.0}
    times = [0.5, 1.0, 2.0]
    track = trajectory(model, 0, names, values, {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        if t < 0.8:
            z, y = [t, 0.0, t * t / 2], [1.0, 0.0, t]
        else:
            z, y = [t, 2.0 * 0.8, 0.8 ** 2 / 2], [1.0, 0.0, 0.0]
        assert track.row("Z", t) == pytest.approx(z, abs=1e-9), t
        assert track.row("Y", t) == pytest.approx(y, abs=1e-9), t


def test_a_reset_carries_a_switch_on_the_state_across_at_its_instant():
    """Y = MODINT(YIC, TR - X, X - TR, K) climbs from YIC at K to TR, where it is reset
    to YIC: S = FSW(Y - A, 0, 0, 1) turns on at t_c = (A - YIC)/K and off at TR, where
    the reset carries Y back below A (its surface apart from zero either side: no
    crossing of its own). Z = INTEGRAL(S) = TR - t_c after TR: d Z/d (YIC, TR, K, A) =
    (1/K, 1, (A - YIC)/K^2, -1/K), and before TR (t - t_c) the same but 0 for TR.
    Differenced whole runs until 2026-12-01 ("a state is reset with other changes at
    the instant"); to 1e-9."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM YIC = 0.5, TR = 0.8, K = 2.0, A = 1.2\nX = INTGRL(0.0, 1.0)\n"
                         "Y = MODINT(YIC, TR - X, X - TR, K)\nS = FSW(Y - A, 0.0, 0.0, 1.0)\n"
                         "Z = INTGRL(0.0, S)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n",
                         "carried.amil")
    values = {"YIC": 0.5, "TR": 0.8, "K": 2.0, "A": 1.2}
    times = [0.5, 1.0, 2.0]
    track = trajectory(model, 0, list(values), values, {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        expect = [0.5, 1.0 if t > 0.8 else 0.0, 0.7 / 4.0, -0.5]
        assert track.row("Z", t) == pytest.approx(expect, abs=1e-9), t
    # a switch that crosses at the reset's instant by itself, which TR moves apart from
    # it (T1 = TR by the data): the order of the two, and so the derivative, differs
    # from either side
    other = amilpy.loads("PARAM YIC = 0.5, TR = 0.8, K = 2.0, T1 = 0.8\nX = INTGRL(0.0, 1.0)\n"
                         "Y = MODINT(YIC, TR - X, X - TR, K)\nS = FSW(TIME - T1, 0.0, 0.0, Y)\n"
                         "Z = INTGRL(0.0, S)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n",
                         "apart.amil")
    said = trajectory(other, 0, ["TR"], {"YIC": 0.5, "TR": 0.8, "K": 2.0, "T1": 0.8}, {},
                      times)
    assert said == "a state is reset where two switches cross that a data value moves apart"


def test_a_reset_with_a_memory_update_at_its_instant():
    """H = ZHOLD(TR - X, Y) follows Y = MODINT(YIC, TR - X, X - TR, K) = YIC + K t to
    TR and holds it there, where Y is reset to YIC: the memory is updated at the
    reset's instant, before the reset (as the run does it), so H holds YIC + K TR,
    and Z = INTEGRAL(H) = YIC t + K t^2/2 to TR, then + (YIC + K TR)(t - TR). After
    TR: d H/d (YIC, TR, K) = (1, K, TR), d Z/d (YIC, TR, K) = (t, K (t - TR), TR^2/2 +
    TR (t - TR)), d Y/d (YIC, TR, K) = (1, 0, 0). Differenced whole runs until
    2026-12-01 ("a state is reset with other changes at the instant"); to 1e-9."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM YIC = 0.5, TR = 0.8, K = 2.0\nX = INTGRL(0.0, 1.0)\n"
                         "Y = MODINT(YIC, TR - X, X - TR, K)\nH = ZHOLD(TR - X, Y)\n"
                         "Z = INTGRL(0.0, H)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n",
                         "held.amil")
    values = {"YIC": 0.5, "TR": 0.8, "K": 2.0}
    times = [0.5, 1.0, 2.0]
    track = trajectory(model, 0, list(values), values, {"rtol": 1e-12, "atol": 1e-14}, times,
                       ["Z", "H", "Y"])
    assert not isinstance(track, str), track
    tr, k = 0.8, 2.0
    for t in times:
        if t < tr:
            z, h, y = [t, 0.0, t * t / 2], [1.0, 0.0, t], [1.0, 0.0, t]
        else:
            z = [t, k * (t - tr), tr * tr / 2 + tr * (t - tr)]
            h, y = [1.0, k, tr], [1.0, 0.0, 0.0]
        assert track.row("Z", t) == pytest.approx(z, abs=1e-9), t
        assert track.row("H", t) == pytest.approx(h, abs=1e-9), t
        assert track.row("Y", t) == pytest.approx(y, abs=1e-9), t


@pytest.mark.parametrize("method", ["EULER", "RK4"])
def test_a_fixed_step_route_is_differenced_at_the_rounding_step(decay, method):
    """A fixed-step route's run is a discrete map of the values, with no error
    control's noise: its differences take the rounding step cbrt(eps) |K| and are
    exact to about 1e-10. EULER with DELT = h: X_k = X0 (1 - K h)^k, d X_k/d K =
    -X0 k h (1 - K h)^(k-1); RK4: its stage polynomial, complex-stepped."""
    model = amilpy.load(decay)
    loc = model.sensitivity(["K", "X0"], method_ode=method)
    h = model.flow(method).plan.timer["DELT"]  # (taken from OUTDEL: none is given)
    k = np.rint(loc.times / h)

    def growth(kk):  # one step's factor
        a = -kk * h
        return 1 + a if method == "EULER" else 1 + a + a * a / 2 + a ** 3 / 6 + a ** 4 / 24

    by_k = (2.0 * growth(0.7 + 1e-30j) ** k).imag / 1e-30
    assert loc.raw[:, 0, 0] == pytest.approx(by_k, abs=1e-9)
    assert loc.raw[:, 0, 1] == pytest.approx(growth(0.7) ** k, abs=1e-9)


def monostable(t, w, rate=1.0):
    """X' = RATE - 3 P, P = PULSE(W, X - 1) from X = 0: X rises to 1 (t = 1/RATE), the
    pulse holds 1 for W (X' = RATE - 3), then X rises again to 1, and so on; complex
    W and RATE for the complex step (the instants compared by their real parts)."""
    t0, x0, on = 0.0, 0.0, False
    while True:
        if on:
            end = t0 + w
            if t < end.real:
                return x0 + (rate - 3.0) * (t - t0)
            x0, t0, on = x0 + (rate - 3.0) * w, end, False
        else:
            hit = t0 + (1.0 - x0) / rate
            if t < hit.real:
                return x0 + rate * (t - t0)
            x0, t0, on = 1.0 + 0.0 * x0, hit, True


def test_a_pulse_whose_end_a_value_moves_jumps_the_tangent_there():
    """CSMP's PULSE(W, X - 1) holds 1 for W from where X reaches 1, which RATE moves:
    its end, the trigger's instant + W, is kept in the memory, whose tangent gives
    the end's shift; the field drops there (X' from RATE - 3 to RATE), and the tangent
    jumps by (f- - f+) dt/dp. Differenced whole runs until 2026-11-30; against the
    complex step of the closed form, to 1e-9."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM W = 0.5, RATE = 1.0\nX = INTGRL(0.0, RATE - 3.0*P)\n"
                         "P = PULSE(W, X - 1.0)\nTIMER FINTIM = 4.0, OUTDEL = 0.1\nEND\n",
                         "mono.amil")
    times = [0.5, 1.2, 1.7, 2.2, 2.7, 3.3, 3.9]
    track = trajectory(model, 0, ["W", "RATE"], {"W": 0.5, "RATE": 1.0},
                       {"rtol": 1e-12, "atol": 1e-14}, times)
    assert not isinstance(track, str), track
    for t in times:
        exact = [monostable(t, 0.5 + 1e-30j).imag / 1e-30,
                 monostable(t, 0.5, 1.0 + 1e-30j).imag / 1e-30]
        assert track.row("X", t) == pytest.approx(exact, abs=1e-9), t


def test_sensitivities_on_long_steps_are_the_integrations_accuracy():
    """A Hopf oscillator (r' = r (1 - r^2), theta' = 2 + B r^2) on DOP853's long steps:
    d X/d B and d X/d X0 from its polar closed form, complex-stepped. The tangent's
    Magnus steps were 2e-5 off there while X was right to 1e-10 (hunt 49b); each is
    now checked against its halves: to 1e-8."""
    model = amilpy.loads("PARAM B = 0.5, X0 = 0.5\nR2 = X*X + Y*Y\n"
                         "X = INTGRL(X0, X - (2.0 + B*R2)*Y - X*R2)\n"
                         "Y = INTGRL(0.0, (2.0 + B*R2)*X + Y - Y*R2)\n"
                         "TIMER FINTIM = 10.0, OUTDEL = 0.5\nEND\n", "hopf.amil")
    loc = model.sensitivity(["B", "X0"], outputs=["X"], method_ode="DOP853")
    assert loc.how == "sensitivity equations"

    def x(t, x0, b):
        c = 1 / x0 ** 2 - 1
        r = np.sqrt(1 / (1 + c * np.exp(-2 * t)))
        return r * np.cos(2 * t + b * (t + 0.5 * np.log((1 + c * np.exp(-2 * t)) / (1 + c))))

    t = loc.times
    by_b, by_x0 = x(t, 0.5, 0.5 + 1e-30j).imag / 1e-30, x(t, 0.5 + 1e-30j, 0.5).imag / 1e-30
    assert loc.raw[:, 0, 0] == pytest.approx(by_b, abs=1e-8 * np.max(np.abs(by_b)))
    assert loc.raw[:, 0, 1] == pytest.approx(by_x0, abs=1e-8 * np.max(np.abs(by_x0)))


def test_the_field_s_derivative_in_a_value_comes_from_its_equations():
    """F_p = d f/d p is the generated field's derivative in the constants it reads,
    times INITIAL's derivatives (KK = K^2 + A): exact to rounding, where the central
    differences it replaced carried eps |f| / h, about 1e-11 of the field. f = -KK X
    + 3 SIN(A TIME) + FSW(X - 1, 0, 0, A) at X = 1.7, TIME = 0.3 (above the switch):
    d f/d K = -2 K X, d f/d A = -X + 3 TIME COS(A TIME) + 1, d f/d X0 = 0; the start
    d X(0)/d (K, A, X0) = (0, 0, 1). To 4 ulps of the terms."""
    from amilpy.analysis.sensitivity import exact_slopes
    from amilpy.codegen.jacobian import for_parameters

    model = amilpy.loads("TITLE DERIVED RATE\nPARAM K = 0.5, X0 = 2.0, A = 1.5\n"
                         "INITIAL\nKK = K*K + A\nDYNAMIC\n"
                         "X = INTGRL(X0, -KK*X + 3.0*SIN(A*TIME) + FSW(X - 1.0, 0.0, 0.0, A))\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.1\nPRINT X\nEND\n")
    c = model.flow().code
    by_name, start = exact_slopes(c, ["K", "A", "X0"])
    f_p = for_parameters(c, "rhs").dense(0.3, [1.7], [1.0], []) @ by_name
    k, a, x, t = 0.5, 1.5, 1.7, 0.3
    assert f_p[0] == pytest.approx([-2 * k * x, -x + 3 * t * np.cos(a * t) + 1, 0.0],
                                   rel=0, abs=4 * 2.2e-16 * (x + 3 * t + 1))
    assert start.tolist() == [[0.0, 0.0, 1.0]]


def test_a_small_term_beside_a_large_one_keeps_its_sensitivity():
    """X' = -K X from 1e-9, Y' = 1 - K X: d Y/d K = -X0 t exp(-K t) (d/dt of t
    e^{-Kt} is e^{-Kt}(1 - K t)), about 1e-9. Central differences of the field in K
    carried the rounding of Y's 1, eps/h = 2e-11 an evaluation, and put d Y/d K 6e-4
    off (until 2026-12-01); from the equations it is the integration's: 1e-7
    relative at RELERR 1e-10 (measured 2e-9)."""
    model = amilpy.loads("TITLE SMALL BESIDE LARGE\nPARAM K = 0.5, X0 = 1.0E-9\n"
                         "X = INTGRL(X0, -K*X)\nY = INTGRL(0.0, 1.0 - K*X)\nMETHOD RKS\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.5\nPRINT X, Y\nEND\n")
    loc = model.sensitivity(["K", "X0"], outputs=["Y"], rtol=1e-10, atol=1e-20)
    assert loc.how == "sensitivity equations"
    t = np.arange(0.0, 2.01, 0.5)
    assert loc.raw[:, 0, 0] == pytest.approx(-1e-9 * t * np.exp(-0.5 * t), rel=1e-7,
                                             abs=1e-25)
    assert loc.raw[:, 0, 1] == pytest.approx(np.exp(-0.5 * t) - 1.0, rel=1e-7, abs=1e-12)


def test_acsl_initial_assignments_are_differentiated_from_their_equations():
    """A Magnolia INITIAL block of assignments (KEV = KE*VD) is followed statement by
    statement: d KEV/d (KE, VD) = (VD, KE) exactly, and d AG(0)/d DOSE = 1 from the
    INTEG's initial value, where the bind's central differences carried eps |KEV| / h
    (1e-11 of it); an IF in INITIAL sends it back to those differences."""
    from amilpy.analysis.program import bind_slopes
    from amilpy.run import Options
    from amilpy.run.acsl import prepare_acsl

    text = ("PROGRAM derived\n  CONSTANT DOSE = 500.0, KA = 1.2, KE = 0.173, VD = 42.0\n"
            "  INITIAL\n    KEV = KE*VD\n  END\n  DERIVATIVE\n"
            "    AG = INTEG(-KA*AG, DOSE)\n    AB = INTEG(KA*AG - KEV/VD*AB, 0.0)\n"
            "    TERMT(T >= 10.0)\n  END\n  CINTERVAL CINT = 0.5\nEND\n")
    for initial, exact in (("    KEV = KE*VD\n", True),
                           ("    KEV = KE*VD\n    IF (KEV > 100.0) KEV = 100.0\n", False)):
        model = amilpy.loads(text.replace("    KEV = KE*VD\n", initial), "derived.csl")
        spec = model._specs({})[0]
        code = prepare_acsl(model.ir, spec, Options(), model.cache).code
        rows, start = bind_slopes(model.ir, spec, code, ["KE", "VD", "DOSE"], [])
        if not exact:
            assert start is None
            continue
        params = sorted(code.binder.parameters)
        assert rows[params.index("KEV")].tolist() == [42.0, 0.173, 0.0]
        assert start[code.state_names.index("AG")].tolist() == [0.0, 0.0, 1.0]


def test_a_value_initial_code_assigns_again_is_initial_s():
    """Magnolia lets INITIAL give a CONSTANT a new value: KE = 2 KE, A' = -KE A, A(0)
    = 1, so d A/d KE = -2 t exp(-2 KE t), twice what the value itself would give.
    To 1e-8 (the tangent is exact on this linear field; the bind's derivative is
    INITIAL code's central difference, exact for a linear one)."""
    model = amilpy.loads("PROGRAM reassigned\n  CONSTANT KE = 0.2\n  INITIAL\n"
                         "    KE = 2.0*KE\n  END\n  DERIVATIVE\n    A = INTEG(-KE*A, 1.0)\n"
                         "    TERMT(T >= 2.0)\n  END\n  CINTERVAL CINT = 0.5\nEND\n",
                         "reassigned.csl")
    loc = model.sensitivity(["KE"], outputs=["A"])
    assert loc.how == "sensitivity equations"
    t = np.arange(0.0, 2.01, 0.5)
    assert loc.raw[:, 0, 0] == pytest.approx(-2 * t * np.exp(-0.4 * t), abs=1e-8)


def test_an_initial_value_a_template_reads_twice_is_differentiated():
    """LIMIT(0, 1, A*2) in INITIAL: the template binds its argument once ((w1 :=
    ...)) and reads it twice; its derivative reads that name too, so the expression
    runs first (a NameError until 2026-12-01, hunt 51 F1). G = 1 + 0.1 * 2 A = 1.08
    inside the limits: X = exp(-G t), d X/d A = -0.2 t exp(-G t), to 1e-8."""
    model = amilpy.loads("TITLE LIM\nPARAM A = 0.4\nINITIAL\nG = 1.0 + 0.1*LIMIT(0.0, 1.0, A*2.0)\n"
                         "DYNAMIC\nX = INTGRL(1.0, -G*X)\nTIMER FINTIM = 1.0, OUTDEL = 0.25\nEND\n",
                         "lim.amil")
    loc = model.sensitivity(["A"], outputs=["X"], rtol=1e-10, atol=1e-12)
    assert loc.how == "sensitivity equations"
    assert loc.raw[:, 0, 0] == pytest.approx(-0.2 * loc.times * np.exp(-1.08 * loc.times),
                                             abs=1e-8)


def test_a_sawtooth_reset_that_turns_straight_back_jumps_the_tangent():
    """Y = MODINT(YIC, YMAX - Y, 1, K Y): reset to YIC where it reaches YMAX and
    integrating again at once, so the modes before and after are the same; the
    tangent left the reset out (dY/dYMAX 0 throughout, hunt 51 F2). Y = YIC exp(K
    s), s = t mod ln(YMAX/YIC)/K: against the complex step of that closed form, to
    1e-8."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads("PARAM YIC = 0.5, YMAX = 1.5, K = 2.0\n"
                         "Y = MODINT(YIC, YMAX - Y, 1.0, K*Y)\nZ = INTGRL(0.0, Y)\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n", "saw.amil")
    values = {"YIC": 0.5, "YMAX": 1.5, "K": 2.0}
    times = [0.3, 0.7, 1.3, 1.9]
    track = trajectory(model, 0, list(values), values, {"rtol": 1e-12, "atol": 1e-14}, times,
                       ["Y", "Z"])
    assert not isinstance(track, str), track

    def closed(t, v):
        period = np.log(v["YMAX"] / v["YIC"]) / v["K"]
        n = int(np.floor(t / period.real))
        s = t - n * period
        return v["YIC"] * np.exp(v["K"] * s), \
            n * (v["YMAX"] - v["YIC"]) / v["K"] + v["YIC"] * (np.exp(v["K"] * s) - 1) / v["K"]

    for t in times:
        exact = np.array([[np.imag(closed(t, {**values, n: values[n] + 1e-30j})[o]) / 1e-30
                           for n in values] for o in (0, 1)])
        assert track.row("Y", t) == pytest.approx(exact[0], abs=1e-8), t
        assert track.row("Z", t) == pytest.approx(exact[1], abs=1e-8), t


@pytest.mark.parametrize("inner, edges", [("AINT(QNTZR(0.5, X))", (0.75, 1.75)),
                                          ("NINT(QNTZR(0.5, X))", (0.25, 1.25))])
def test_a_level_function_of_a_level_function_jumps_the_tangent_at_its_edges(inner, edges):
    """X' = 1 - G L(X), L = AINT(QNTZR(0.5, X)): L is 0 below 0.75, 1 on [0.75, 1.75),
    2 above (NINT rounds QNTZR's 0.5 up: 0.25 and 1.25). The outer level jumps with
    the inner one's crossing, its own surface flat in X: its change is the
    crossing's, whose saltation now takes the field after both (it had none: d X/d G
    0.12 off at t = 2, hunt 51 F6). Closed form: X = e1 + (1 - G)(t - e1), then e2 +
    (1 - 2G)(t - t2), t2 = e1 + (e2 - e1)/(1 - G); complex-stepped, to 1e-8."""
    from amilpy.analysis.sensitivity import trajectory

    model = amilpy.loads(f"PARAM G = 0.1\nX = INTGRL(0.0, 1.0 - G*{inner})\n"
                         "TIMER FINTIM = 2.5, OUTDEL = 0.5\nEND\n", "nested.amil")
    times = [0.5, 1.0, 2.0, 2.5]  # (below the next level's edge, 2.25 for NINT)
    track = trajectory(model, 0, ["G"], {"G": 0.1}, {"rtol": 1e-12, "atol": 1e-14}, times,
                       ["X"])
    assert not isinstance(track, str), track

    def closed(t, g):
        e1, e2 = edges
        t2 = e1 + (e2 - e1) / (1 - g)
        if t < e1:
            return t + 0 * g
        return e1 + (1 - g) * (t - e1) if t < t2.real else e2 + (1 - 2 * g) * (t - t2)

    for t in times:
        assert track.row("X", t)[0] == pytest.approx(np.imag(closed(t, 0.1 + 1e-30j)) / 1e-30,
                                                     abs=1e-8), t


def test_a_procedural_if_in_the_derivatives_is_differenced_not_dropped():
    """A PROCEDURAL whose IF sets the rate (-K X above 0.5, -2 K X below): the
    generated Jacobian passed the IF through and its derivatives were 0 (d X/d X0 = 1
    throughout, d X/d K = 0, found by the review of 2026-12-01); then such a function
    was differenced; now each branch is differentiated as it runs, for d f/d y and
    d f/d p alike (and the stiff routes' Jacobian). X = X0 exp(-K t) to t1 =
    ln(2 X0)/K, then 0.5 exp(-2K (t - t1)): complex step, to 1e-7."""
    text = ("PROGRAM procedural branch\n  CONSTANT K = 0.5, X0 = 1.0\n  DERIVATIVE\n"
            "    PROCEDURAL (XD = X)\n      IF (X > 0.5) THEN\n        XD = -K*X\n"
            "      ELSE\n        XD = -2.0*K*X\n      END IF\n    END\n"
            "    X = INTEG(XD, X0)\n    TERMT(T >= 3.0)\n  END\n  CINTERVAL CINT = 0.5\nEND\n")
    model = amilpy.loads(text, "procedural.csl")
    loc = model.sensitivity(["K", "X0"], outputs=["X"], rtol=1e-10, atol=1e-12)
    assert loc.how == "sensitivity equations"

    def x(t, k, x0):
        t1 = np.log(2 * x0) / k
        return x0 * np.exp(-k * t) if t < t1.real else 0.5 * np.exp(-2 * k * (t - t1))

    for i, t in enumerate(loc.times):
        exact = [np.imag(x(t, 0.5 + 1e-30j, 1.0)) / 1e-30, np.imag(x(t, 0.5, 1.0 + 1e-30j)) / 1e-30]
        assert loc.raw[i, 0, :] == pytest.approx(exact, abs=1e-7), t
    for method in ("BDF", "RADAU"):  # (their Jacobian: every entry differenced)
        run, = model.run(method=method, advice=False)
        assert run["X"][-1] == pytest.approx(x(3.0, 0.5, 1.0), rel=1e-6)


def test_a_derivative_rule_with_no_value_at_the_point_takes_that_call_by_differences():
    """SQRT(A*B) at B = 0: the rule 0.5/SQRT(A B) divides by zero (a crash of the
    exact d f/d p path, review of 2026-12-01); that call is differenced: d X/d A = 0."""
    model = amilpy.loads("PARAM A = 1.0, B = 0.0\nX = INTGRL(1.0, -SQRT(A*B) - X)\n"
                         "TIMER FINTIM = 1.0, OUTDEL = 0.5\nEND\n", "sqrt.amil")
    loc = model.sensitivity(["A"], outputs=["X"])
    assert loc.how == "sensitivity equations"
    assert loc.raw[:, 0, 0] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)


def test_acsl_initial_reading_t_keeps_the_bind_s_differences():
    """KEV = KE*VD*(1 + T) in INITIAL reads T, which has no value among the constants:
    the assignments are not followed one by one (a NameError until the review of
    2026-12-01), the bind is differenced; T = 0 there, so d AB/d KE is the plain
    model's. Against whole-run differences, to 1e-6."""
    text = ("PROGRAM derived\n  CONSTANT DOSE = 500.0, KA = 1.2, KE = 0.173, VD = 42.0\n"
            "  INITIAL\n    KEV = KE*VD*(1.0 + T)\n  END\n  DERIVATIVE\n"
            "    AG = INTEG(-KA*AG, DOSE)\n    AB = INTEG(KA*AG - KEV/VD*AB, 0.0)\n"
            "    TERMT(T >= 4.0)\n  END\n  CINTERVAL CINT = 1.0\nEND\n")
    model = amilpy.loads(text, "derived.csl")
    loc = model.sensitivity(["KE"], outputs=["AB"], rtol=1e-10, atol=1e-12)
    assert loc.how == "sensitivity equations"
    h = 1e-5
    up = np.asarray(model.run(advice=False, rtol=1e-12, atol=1e-14, KE=0.173 + h)[0]["AB"])
    down = np.asarray(model.run(advice=False, rtol=1e-12, atol=1e-14, KE=0.173 - h)[0]["AB"])
    assert loc.raw[:, 0, 0] == pytest.approx((up - down) / (2 * h), rel=1e-6, abs=1e-6)


def test_a_program_stopped_by_termt_on_its_last_communication_instant_is_followed():
    """TERMT(T >= 1.2) with CINT 0.1: the run stops at T = 1.2, and prints its last
    row at the 12th CINT, 1.2000000000000002; the tangent had no row there and the
    whole sensitivity went to differences ("the run's steps did not reach TIME =
    1.2"). That row is the end state's. d X/d K = -t exp(-K t), to 1e-8."""
    model = amilpy.loads("PROGRAM decay\n  CONSTANT K = 0.8\n  DERIVATIVE\n"
                         "    X = INTEG(-K*X, 1.0)\n    TERMT(T >= 1.2)\n  END\n"
                         "  CINTERVAL CINT = 0.1\nEND\n", "decay.csl")
    loc = model.sensitivity(["K"], outputs=["X"], rtol=1e-10, atol=1e-12)
    assert loc.how == "sensitivity equations"
    assert loc.times[-1] == 12 * 0.1  # (not 1.2)
    assert loc.raw[:, 0, 0] == pytest.approx(-loc.times * np.exp(-0.8 * loc.times), abs=1e-8)


def _run_slope(model, name: str, value: float, h: float) -> np.ndarray:
    """d X/d name on the run's grid: central differences of whole runs at RELERR
    1e-13, step h."""
    up, down = (np.asarray(model.run(advice=False, rtol=1e-13, atol=1e-15,
                                     **{name: value + s})[0]["X"]) for s in (h, -h))
    return (up - down) / (2 * h)


def _delayed_decay(spacing, ic=0.5, k=0.8, force=0.0):
    """X' = FORCE - K XD + 0.3 SIN(T), X(0) = 1, XD = ACSL's DELAY(X, IC, TDL, N[,
    DMIN]) as the run computes it, for t < 2 TDL: IC before TDL, then the store's
    straight lines between X's samples every `spacing(TDL)` from 0 (X explicit
    there), read at t - TDL; X integrates them exactly. (X, XD) at t,
    complex-steppable in TDL."""
    def x0(s):
        return 1.0 + (force - k * ic) * s + 0.3 * (1.0 - np.cos(s))

    def closed(t, tdl):
        if t < tdl.real:
            return x0(t), ic + 0.0 * tdl
        h, s = spacing(tdl), t - tdl
        j = int(np.floor((s / h).real))
        knots = [x0(i * h) for i in range(j + 2)]
        xd = knots[j] + (knots[j + 1] - knots[j]) * (s - j * h) / h
        area = sum(0.5 * (knots[i] + knots[i + 1]) * h for i in range(j)) + \
            0.5 * (knots[j] + xd) * (s - j * h)
        return x0(tdl) + force * s - k * area + 0.3 * (np.cos(tdl) - np.cos(t)), xd

    return closed


@pytest.mark.parametrize("dmin, spacing", [("", lambda tdl: tdl / 20),
                                           (", 0.05", lambda tdl: 0.05 + 0 * tdl)])
def test_a_free_acsl_delay_follows_its_turn_from_ic_to_the_history(dmin, spacing):
    """ACSL's DELAY(X, IC, TDL, NMX[, DMIN]) reads IC until TDL, then the store's
    history, which it samples every TDL/NMX (or DMIN, when longer): a free TDL moves
    the turn (XD jumps from IC = 0.5 to X(0) = 1 there) and, without DMIN, every
    sampling instant with it -- the 20th one onto the turn itself, at one instant that
    moves with TDL as the turn does: one map. It was differenced (the store's clock
    started from rows the first update left out -- d TDL/NMX/d TDL 0 at t0, and
    8e3 in its anchor: hunt 51 F3/F4). Against the complex step of the store's own
    closed form (`_delayed_decay`), to 1e-8 (measured 5e-11 at RELERR 1e-11); the
    run ends with TERMT at T = 1.2, its last row at 12 CINTs (1.2000000000000002)."""
    model = amilpy.loads("PROGRAM delayed\n  CONSTANT K = 0.8, TDL = 0.63\n  DERIVATIVE\n"
                         f"    XD = DELAY(X, 0.5, TDL, 20{dmin})\n"
                         "    X = INTEG(-K*XD + 0.3*SIN(T), 1.0)\n"
                         "    TERMT(T >= 1.2)\n  END\n  CINTERVAL CINT = 0.1\nEND\n",
                         "delay.csl")
    loc = model.sensitivity(["TDL"], outputs=["X", "XD"], rtol=1e-11, atol=1e-13)
    assert loc.how == "sensitivity equations"
    closed = _delayed_decay(spacing)
    for i, t in enumerate(loc.times):
        exact = [np.imag(v) / 1e-30 for v in closed(t, 0.63 + 1e-30j)]
        assert loc.raw[i, :, 0] == pytest.approx(exact, abs=1e-8), t


def test_a_delay_that_reads_a_state_turns_from_ic_with_its_state_s_share():
    """DELAY(X, IC, TD0 + 0.1*X, 20): the turn from IC to the history is where TIME
    = TD0 + 0.1 X, a surface in the state. Its read just before the store's start,
    where a difference of the delay in X steps, gave IC (a jump inside the history
    branch): d XD/d X had a spike across it that put d X/d (TD0, K, IC) 1e-2 off
    after the turn (hunt 52). The first segment goes on there now. Against central
    differences of whole runs at RELERR 1e-13 that agree with themselves at h and
    h/2: to 2e-6 (measured 5.6e-7 for TD0, whose tangent steps cross the read's
    knots, which move with X; 2e-8 for K and IC)."""
    model = amilpy.loads("PROGRAM d\n  CONSTANT K = 0.8, TD0 = 0.53, IC = 0.5\n  DERIVATIVE\n"
                         "    XD = DELAY(X, IC, TD0 + 0.1*X, 20)\n"
                         "    X = INTEG(-K*XD + 0.3*SIN(T), 1.0)\n"
                         "    TERMT(T >= 0.8)\n  END\n  CINTERVAL CINT = 0.02\nEND\n", "d.csl")
    names, values = ["TD0", "K", "IC"], {"TD0": 0.53, "K": 0.8, "IC": 0.5}
    loc = model.sensitivity(names, outputs=["X"], rtol=1e-11, atol=1e-13)
    assert loc.how == "sensitivity equations"
    for j, name in enumerate(names):
        ref = _run_slope(model, name, values[name], 1e-4)
        # (no kink within h)
        assert ref == pytest.approx(_run_slope(model, name, values[name], 5e-5), abs=2e-7)
        assert loc.raw[:, 0, j] == pytest.approx(ref, abs=2e-6), name


def test_a_sample_at_dmin_s_fixed_spacing_where_a_free_tdl_turns_the_delay_says_so():
    """TDL = 0.65 = 13 DMIN: the sample due at 0.65 stays there as TDL moves, the turn
    from IC to the history does not: the sample is taken before the turn on one side
    and after it on the other (it was followed as if it moved with the turn: d XD/d
    TDL 57 off, hunt 51 F4). Differenced, and says why."""
    model = amilpy.loads("PROGRAM delayed\n  CONSTANT K = 0.8, TDL = 0.65\n  DERIVATIVE\n"
                         "    XD = DELAY(X, 0.5, TDL, 20, 0.05)\n"
                         "    X = INTEG(-K*XD + 0.3*SIN(T), 1.0)\n"
                         "    TERMT(T >= 1.5)\n  END\n  CINTERVAL CINT = 0.1\nEND\n",
                         "delay.csl")
    loc = model.sensitivity(["TDL"], outputs=["X"])
    assert loc.how.startswith("differences of whole runs (a DELAY samples where a switch "
                              "turns")


def test_a_sample_where_a_turn_leaves_the_field_as_it_was_is_followed():
    """Two delays of X, TDL = TDL2 = 0.5, each with IC = X(0) = 1: at 0.5 both turn
    from IC to the history, which starts at X(0), and the field does not change. The
    16th sample of each is at that instant, and TDL moves only its own. Such a
    sample was refused for any switch that turned there (the review of
    2026-12-01); only a turn that changes the field bends X where the sample is
    taken. Against central differences of whole runs at RELERR 1e-13, step 1e-5:
    to 3e-6 (X is C1 but not C2 in TDL at 0.5: the differences are 2.2e-6 off
    there, 2e-5 with a step of 1e-4; elsewhere they agree to 2.3e-7)."""
    model = amilpy.loads("PROGRAM d\n  CONSTANT K = 0.8, TDL = 0.5, TDL2 = 0.5\n  DERIVATIVE\n"
                         "    XD = DELAY(X, 1.0, TDL, 16)\n    XE = DELAY(X, 1.0, TDL2, 16)\n"
                         "    X = INTEG(-K*XD - 0.3*XE + 0.3*SIN(T), 1.0)\n"
                         "    TERMT(T >= 1.0)\n  END\n  CINTERVAL CINT = 0.125\nEND\n", "d.csl")
    loc = model.sensitivity(["TDL"], outputs=["X"], rtol=1e-11, atol=1e-13)
    assert loc.how == "sensitivity equations"
    assert loc.raw[:, 0, 0] == pytest.approx(_run_slope(model, "TDL", 0.5, 1e-5), abs=3e-6)


@pytest.mark.parametrize("free", [["TDL"], ["TS"], ["TDL", "TS"]])
def test_a_step_where_the_nmx_th_sample_turns_the_delay_says_so(free):
    """STEP(TS) at TS = TDL: the store's 20th sample moves with TDL onto X's kink
    there, the STEP does not -- two switches and a sample at one instant. The sample
    was checked against the first switch alone, and one side came back silently
    (d X/d TDL 0.2317 or 0.2569 at t = 1.3 by the side, hunt 52). Every switch turning
    there counts now: differenced, and says why."""
    model = amilpy.loads("PROGRAM delayed\n  CONSTANT K = 0.8, TDL = 0.63, TS = 0.63\n"
                         "  DERIVATIVE\n    XD = DELAY(X, 0.5, TDL, 20)\n"
                         "    X = INTEG(-K*XD + 0.3*SIN(T) + STEP(TS), 1.0)\n"
                         "    TERMT(T >= 1.5)\n  END\n  CINTERVAL CINT = 0.1\nEND\n",
                         "delay.csl")
    assert model.sensitivity(free, outputs=["X"]).how.startswith(
        "differences of whole runs (a DELAY samples where a switch turns")


def test_two_stores_that_sample_together_on_delays_moved_apart_are_taken_one_by_one():
    """DELAY(X, 0.5, TDL, 16) and DELAY(X, 0.2, TDL2, 16), TDL = 1.5, TDL2 = 0.5:
    every sample of the first (every 3/32) is one of the second's (every 1/32), at
    instants TDL and TDL2 move apart (by k/16 and 3k/16). It was refused ("two
    DELAY stores sample at one instant that a data value moves apart"); each store's
    sample reads X and its own slots alone, so they are taken one by one, each at
    its own moving instant. XD is IC until 1.5: d X/d TDL is 0 exactly, and d X/d
    TDL2 the complex step of the second store's closed form (`_delayed_decay`, X'
    = -0.4 - 0.3 XE + 0.3 SIN(T)), to 1e-8."""
    model = amilpy.loads("PROGRAM d\n  CONSTANT K = 0.8, TDL = 1.5, TDL2 = 0.5\n  DERIVATIVE\n"
                         "    XD = DELAY(X, 0.5, TDL, 16)\n    XE = DELAY(X, 0.2, TDL2, 16)\n"
                         "    X = INTEG(-K*XD - 0.3*XE + 0.3*SIN(T), 1.0)\n"
                         "    TERMT(T >= 0.95)\n  END\n  CINTERVAL CINT = 0.125\nEND\n", "d.csl")
    loc = model.sensitivity(["TDL", "TDL2"], outputs=["X"], rtol=1e-11, atol=1e-13)
    assert loc.how == "sensitivity equations"
    assert not np.any(loc.raw[:, 0, 0])
    closed = _delayed_decay(lambda tdl: tdl / 16, ic=0.2, k=0.3, force=-0.4)
    for i, t in enumerate(loc.times):
        # (at TDL2 itself the row is the run's, after the turn: X's kink, the side
        # after it, 0.3 (1 - 0.2) = 0.24 -- the closed form's step straddles it)
        exact = 0.24 if t == 0.5 else np.imag(closed(t, 0.5 + 1e-30j)[0]) / 1e-30
        assert loc.raw[i, 0, 1] == pytest.approx(exact, abs=1e-8), t


def test_switches_moved_together_keep_together_in_the_order_they_turn():
    """STEP(T1) STEP(T2) (1 - STEP(T3)) at T1 = T2 = T3 = 0.5, T2 free: T1 and T3
    turn together whatever T2, so the product is 0 and d X/d T2 = 0. The orders T2
    first and T2 last agree (0), but the jumps were then taken in the listing's
    order, T1, T2, T3: T2's with STEP(T1) on and STEP(T3) still off, -1 from 0.5
    on (the review of 2026-12-01). Each column now takes the order it checked. And
    the factors in the other order gave 0 already."""
    for product in ("STEP(T1)*STEP(T2)*(1.0 - STEP(T3))", "STEP(T2)*STEP(T1)*(1.0 - STEP(T3))"):
        model = amilpy.loads("PROGRAM d\n  CONSTANT T1 = 0.5, T2 = 0.5, T3 = 0.5\n"
                             f"  DERIVATIVE\n    XD = {product}\n    X = INTEG(XD - 0.5*X, 1.0)\n"
                             "    TERMT(T >= 1.0)\n  END\n  CINTERVAL CINT = 0.25\nEND\n",
                             "three.csl")
        loc = model.sensitivity(["T2"], outputs=["X"], rtol=1e-11, atol=1e-13)
        assert loc.how == "sensitivity equations"
        assert loc.raw[:, 0, 0] == pytest.approx(np.zeros(len(loc.times)), abs=1e-12), product


def test_discrete_code_that_holds_a_delayed_value_is_followed():
    """A DISCRETE section every 0.1 holds XD = DELAY(X, 0.5, TDL, 20), which the
    derivatives read back. The section's Jacobian stepped every memory slot, the
    store's count too: a count an entry off read the ring where it had been
    overwritten ("older than the 20 points of its store keep"), and whole runs were
    differenced for any free value (found with hunt 52); and the store's start at t0
    went after the section's code there. Against central differences of whole runs
    at RELERR 1e-13, for TDL and K, to 1e-6 (measured 6.5e-8)."""
    model = amilpy.loads("PROGRAM d\n  CONSTANT K = 0.8, TDL = 0.63, G = 0.5\n"
                         "  CINTERVAL CINT = 0.1\n  INITIAL\n    XH = 0.0\n  END\n"
                         "  DERIVATIVE\n    XD = DELAY(X, 0.5, TDL, 20)\n"
                         "    X = INTEG(-K*XD + 0.3*SIN(T) - G*XH, 1.0)\n"
                         "    TERMT(T >= 2.5)\n  END\n  DISCRETE SAMP\n    INTERVAL TSAMP = 0.1\n"
                         "    XH = XD\n  END\nEND\n", "d.csl")
    loc = model.sensitivity(["TDL", "K"], outputs=["X"], rtol=1e-11, atol=1e-13)
    assert loc.how == "sensitivity equations"
    for j, (name, value) in enumerate((("TDL", 0.63), ("K", 0.8))):
        assert loc.raw[:, 0, j] == pytest.approx(_run_slope(model, name, value, 1e-4),
                                                 abs=1e-6), name


def test_two_stores_sampling_together_on_one_free_delay_are_followed():
    """DELAY(X, 0.5, TDL, 20) and DELAY(X, 0.2, TDL, 10): every second sample of the
    first is one of the second's, both moving with TDL alike. Moved, the second's
    next instant (its own row, equal but for rounding) fell an ulp to one side of
    the instant: the sample skipped or taken twice, and its store reported a lost
    history -- the run "failed", whole runs differenced (hunt 52). Against those
    differences at RELERR 1e-13, to 1e-6 (measured 2e-8)."""
    model = amilpy.loads("PROGRAM d\n  CONSTANT K = 0.8, TDL = 0.63\n  DERIVATIVE\n"
                         "    XD = DELAY(X, 0.5, TDL, 20)\n    XE = DELAY(X, 0.2, TDL, 10)\n"
                         "    X = INTEG(-K*XD - 0.3*XE + 0.3*SIN(T), 1.0)\n"
                         "    TERMT(T >= 2.5)\n  END\n  CINTERVAL CINT = 0.1\nEND\n", "d.csl")
    loc = model.sensitivity(["TDL"], outputs=["X"], rtol=1e-11, atol=1e-13)
    assert loc.how == "sensitivity equations"
    assert loc.raw[:, 0, 0] == pytest.approx(_run_slope(model, "TDL", 0.63, 1e-4), abs=1e-6)


def test_switches_crossing_together_that_a_value_moves_apart():
    """X' = -X + F, T1 = T2 = 0.5, T1 free. F = STEP(T1) + STEP(T2): each jump is its
    own, in either order: d X/d T1 = -exp(-(t - T1)) after, to 1e-9. F =
    STEP(T1) STEP(T2): the forcing starts at T1 on one side of T1's move and at T2
    on the other -- no derivative; the tangent gave 0, silently (found with hunt
    52). It says so now."""
    def model(forcing):
        return amilpy.loads(f"PARAM T1 = 0.5, T2 = 0.5\nX = INTGRL(0.0, -X + {forcing})\n"
                            "TIMER FINTIM = 1.0, OUTDEL = 0.25\nEND\n", "two.amil")

    loc = model("STEP(T1) + STEP(T2)").sensitivity(["T1"], outputs=["X"])
    assert loc.how == "sensitivity equations"
    after = loc.times > 0.5
    assert loc.raw[after, 0, 0] == pytest.approx(-np.exp(-(loc.times[after] - 0.5)),
                                                 abs=1e-9)
    assert model("STEP(T1)*STEP(T2)").sensitivity(["T1"], outputs=["X"]).how == (
        "differences of whole runs (two switches turn at one instant that a data value "
        "moves apart, and the order they turn in changes the jump: its derivative differs "
        "from either side)")


def test_pulse_instants_a_value_moves_apart_without_a_derivative_say_so():
    """Two places where one side of a value's move differs from the other (hunt 51 F7,
    F8), which the tangent answered with one side or neither, silently:
    - a MODINT reset at TR = 0.8 where a PULSE ends (TZ + W = 0.8): moving TR or W
      puts the end before or after the reset;
    - PULSE(TZ, P, W) with W = P, each pulse ending where the next starts: moving W
      or P opens a gap or an overlap on one side only.
    Each is differenced, and says why; a value that moves both instants together (TZ)
    is still followed."""
    reset = amilpy.loads("PARAM YIC = 0.5, TR = 0.8, K = 2.0, TZ = 0.3, W = 0.5\n"
                         "X = INTGRL(0.0, 1.0)\nY = MODINT(YIC, TR - X, X - TR, K)\n"
                         "Z = INTGRL(0.0, Y*PULSE(TZ, 2.0, W))\n"
                         "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n", "reset.amil")
    for name in ("TR", "W"):
        assert reset.sensitivity([name], outputs=["Z"]).how.endswith(
            "(a state is reset where two switches cross that a data value moves apart)")
    touching = amilpy.loads("PARAM TZ = 0.3, P = 0.5, W = 0.5\n"
                            "X = INTGRL(0.0, PULSE(TZ, P, W) - X)\n"
                            "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n", "touching.amil")
    for name in ("W", "P"):
        assert "a PULSE ends where the next starts" in \
            touching.sensitivity([name], outputs=["X"]).how
    assert touching.sensitivity(["TZ"], outputs=["X"]).how == "sensitivity equations"


def test_a_moving_delay_sample_where_a_switch_turns_has_no_derivative():
    """DELAY(20, P, X) samples at k P/20; a STEP at 0.3 falls on the 6th sample. As P
    moves, that sample takes X before or after the step's kink -- one side or the
    other, no derivative (the tangent took one side silently, the review of
    2026-12-01); it says so. At 0.31, apart from every sample, it is followed and
    agrees with whole-run differences to 1e-6."""
    from amilpy.analysis.sensitivity import trajectory

    def case(t1):
        text = (f"PARAM K = 0.8, A = 0.3, P = 1.0, T1 = {t1}\nINCON X0 = 1.0\n"
                "XD = DELAY(20, P, X)\nX = INTGRL(X0, -K*XD + A*STEP(T1))\n"
                "TIMER FINTIM = 2.5, OUTDEL = 0.01\nPRINT X, XD\nEND\n")
        values = {"K": 0.8, "A": 0.3, "X0": 1.0, "P": 1.0, "T1": t1}
        model = amilpy.loads(text, "step.amil")
        return model, values, trajectory(model, 0, ["P"], values,
                                         {"rtol": 1e-10, "atol": 1e-12}, [1.27, 2.47], ["X"])

    assert case(0.3)[2] == ("a DELAY samples where a switch turns, at an instant a data "
                            "value moves apart from it: its derivative differs from either "
                            "side")
    model, values, track = case(0.31)
    assert not isinstance(track, str), track
    h = 1e-5

    def rows(d):
        run = model.run(advice=False, rtol=1e-12, atol=1e-14, **{**values, "P": 1.0 + d})[0]
        t = np.asarray(run.times)
        return np.array([run["X"][int(np.argmin(abs(t - s)))] for s in (1.27, 2.47)])

    reference = (rows(h) - rows(-h)) / (2 * h)
    assert [track.row("X", s)[0] for s in (1.27, 2.47)] == pytest.approx(reference, abs=1e-6)
