"""The functions of the contract's section 12 (ACSL and CSMP III), each against a
closed form: the PULSE train and HARM (breakpoints exact), RSW, BCKLSH, LIMINT (bounds
located), ACSL's DELAY, DERIVT, NOTNUL, REAAND/REANOR and LINT. The random functions
are in test_random.py."""

import math

import numpy as np
import pytest
from conftest import run1
from scipy import integrate

import amilpy
from amilpy.diagnostics import AmilError
from amilpy.library import lookup

TIGHT = {"rtol": 1e-10, "atol": 1e-12}


def probe(body: str, fintim=1.0, outdel=0.25, **kw):
    return run1(f"{body}\nTIMER FINTIM = {fintim}, OUTDEL = {outdel}\nEND\n", **kw)


# ---------------------------------------------------------------- PULSE(TZ, P, W)
def pulse_integral(t, tz, p, w):
    """The integral from 0 of ACSL's pulse train: W per whole period, plus the part
    of the current pulse."""
    u = np.maximum(t - tz, 0.0)
    return np.where(t >= tz, np.floor(u / p) * w + np.minimum(np.mod(u, p), w), 0.0)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU", "RK4", "TRAPZ"])
def test_pulse_train_breakpoints_are_exact(method):
    """1 on [TZ + k*P, TZ + k*P + W). The rate is piecewise constant and every switch
    is a breakpoint known before the run, so every method integrates it exactly (to
    rounding); a pulse far shorter than the output interval is not missed. The
    events are at the instants themselves, as floats computed once (TZ + k*P)."""
    tz, p, w = 0.3711, 0.7, 0.013
    r = probe(f"X = INTGRL(0.0, PULSE({tz}, {p}, {w}))", fintim=5.0, outdel=0.5,
              method=method)
    assert np.max(np.abs(r["X"] - pulse_integral(r.t, tz, p, w))) <= 1e-12
    starts = [tz + k * p for k in range(7)]
    ends = [(tz + w) + k * p for k in range(7)]
    assert [e.time for e in r.events] == sorted(starts + ends)
    assert all(e.kind == "breakpoint" for e in r.events)


def test_pulse_train_values_and_the_csmp_form_beside_it():
    r = probe("A = PULSE(0.5, 2.0, 1.0)\nB = PULSE(0.0, 1.0, 1.0)\n"
              "C = PULSE(0.25, 1.0, 0.0)\nD = PULSE(0.1, TIME - 0.3)", fintim=4.0,
              outdel=0.25)
    t = r.t
    on = (t >= 0.5) & (np.mod(t - 0.5, 2.0) < 1.0)
    assert list(r["A"]) == list(on.astype(float))
    assert set(r["B"]) == {1.0}  # W = P: always on
    assert set(r["C"]) == {0.0}  # W = 0: never on
    assert list(r["D"][t > 0.3]) == [1.0] * int(np.sum(t > 0.3))  # CSMP's PULSE(P, X)


@pytest.mark.parametrize("call, message", [
    ("PULSE(0.0, 0.0, 0.5)", "P of PULSE must be positive (got 0)"),
    ("PULSE(0.0, -1.0, 0.5)", "P of PULSE must be positive (got -1)"),
    ("PULSE(0.0, 1.0, -0.5)", "W of PULSE must not be negative (got -0.5)"),
    ("PULSE(0.0, PP, 0.5)", "P of PULSE must be positive (got 0)"),
    ("PULSE(0.0, X, 0.5)", "P of PULSE uses X, which changes in time"),
])
def test_pulse_arguments_are_checked_with_the_listing(call, message):
    with pytest.raises(AmilError) as err:
        amilpy.loads(f"PARAM PP = 0.0\nX = INTGRL(0.0, {call})\nTIMER FINTIM = 1\nEND\n")
    assert message in err.value.render() and err.value.line == 2


def test_a_pulse_period_known_only_at_the_run_is_checked_there():
    model = amilpy.loads("PARAM A = 1.0\nINITIAL\nP = A - 1.0\nDYNAMIC\n"
                         "X = INTGRL(0.0, PULSE(0.0, P, 0.5))\nTIMER FINTIM = 1\nEND\n")
    with pytest.raises(AmilError) as err:
        model.run()
    assert "P of PULSE must be positive (got 0)" in err.value.render()
    assert err.value.line == 5
    assert model.run(A=2.0)[0].ok


def test_pulse_train_in_step_point_mode():
    """Read at the step points: with DELT = 1, PULSE(0.5, 2, 1) is on at 1, 3, 5."""
    r = run1("X = PULSE(0.5, 2.0, 1.0)\nTIMER FINTIM = 6, DELT = 1, PRDEL = 1\n"
             "METHOD EULER\nEND\n")
    assert list(r["X"]) == [0, 1, 0, 1, 0, 1, 0]


# ------------------------------------------------------------------------- HARM
def test_harm_is_sine_with_acsl_arguments():
    """HARM(TZ, W, P): 0 before TZ, sin(W*(t - TZ) + P) after; its start is a
    breakpoint found exactly, so the integral is exact to the tolerance."""
    tz, w, p = 0.3711, 3.0, 0.2
    r = probe(f"H = HARM({tz}, {w}, {p})\nX = INTGRL(0.0, H)", fintim=2.0, outdel=0.1,
              **TIGHT)
    t = r.t
    assert np.max(np.abs(r["H"] - np.where(t >= tz, np.sin(w * (t - tz) + p), 0.0))) < 1e-15
    exact = np.where(t >= tz, (math.cos(p) - np.cos(w * (t - tz) + p)) / w, 0.0)
    assert np.max(np.abs(r["X"] - exact)) <= 1e-9
    assert [e.time for e in r.events] == [tz] and r.events[0].kind == "breakpoint"
    assert lookup("HARM") is lookup("SINE")


# -------------------------------------------------------------------------- RSW
def test_rsw_on_a_number_and_on_a_state():
    """RSW(C, A, B): A if C > 0, else B (0 is false). On a state the condition is
    located like FSW's: X' = -1 while X - 0.5 > 0, then 0: X stops at 0.5 at t = 0.5."""
    r = probe("A = RSW(TIME - 0.5, 2.0, 1.0)\nX = INTGRL(1.0, RSW(X - 0.5, -1.0, 0.0))",
              **TIGHT)
    assert list(r["A"]) == [1.0, 1.0, 1.0, 2.0, 2.0]  # at t = 0.5, C = 0: false
    assert r["X"] == pytest.approx(np.maximum(1.0 - r.t, 0.5), abs=1e-9)
    assert [round(e.time, 9) for e in r.events if "RSW(X" in e.switch] == [0.5]


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "COMPILED"])
def test_rsw_on_a_relation_takes_its_branch_where_the_relation_turns(method):
    """RSW(X > 0, 1, 2) of X = 1 - t: the relation is a switch on X whose 1 or 0 is
    RSW's condition. The relation changes no derivative itself, so it was followed at
    the end of its step, where RSW's condition became 0 unseen: 1 to the end, Y(2) =
    2. Its crossing is cut and RSW decides again there: Y = t, then 1 + 2(t - 1)."""
    r = probe("X = INTGRL(1.0, -1.0)\nY = INTGRL(0.0, RSW(X > 0.0, 1.0, 2.0))", fintim=2.0,
              method=method, advice=False)
    assert r["Y"] == pytest.approx(np.where(r.t <= 1.0, r.t, 2.0 * r.t - 1.0), abs=1e-12)
    assert [(e.time, e.text) for e in r.events] == [(pytest.approx(1.0, abs=1e-15),
                                                     "X > 0.0")]


# ----------------------------------------------------------------------- BCKLSH
def test_backlash_is_hstrss_with_symmetric_play():
    """BCKLSH(IC, DL, X) = HSTRSS(IC, -DL, DL, X): the output follows X - DL rising
    and X + DL falling, and holds in between."""
    r = probe("X = SIN(6.283185307179586*TIME)\nB = BCKLSH(0.0, 0.1, X)\n"
              "H = HSTRSS(0.0, -0.1, 0.1, X)", outdel=0.05, method="RK4")
    assert np.array_equal(r["B"], r["H"])
    x = r["X"]
    assert r["B"][5] == pytest.approx(x[5] - 0.1, abs=1e-12)  # t = .25, the top
    assert r["B"][6] == pytest.approx(0.9, abs=1e-12)  # held
    assert r["B"][15] == pytest.approx(x[15] + 0.1, abs=1e-12)  # t = .75, the bottom


def backlash_of_2sin(t):
    """BCKLSH(0, 0.5, 2 sin t): 0 until X - 0.5 reaches it at asin(1/4), X - 0.5 up
    to the top (1.5 at pi/2), held until X + 0.5 comes down to it (5 pi/6), X + 0.5
    down to -1.5 at 3 pi/2, held until X - 0.5 comes up to it (11 pi/6), and so on."""
    x = 2 * np.sin(t)
    return np.select([t < math.asin(0.25), t < np.pi / 2, t < 5 * np.pi / 6,
                      t < 1.5 * np.pi, t < 11 * np.pi / 6, t < 2.5 * np.pi],
                     [0.0, x - 0.5, 1.5, x + 0.5, -1.5, x - 0.5], 1.5)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU"])
@pytest.mark.parametrize("outdel", [0.05, 1.5])
def test_backlash_holds_the_extreme_its_input_turns_at(method, outdel):
    """A play holds what its input reached where the input turns: the turn inside a
    step is located (the step cut there), not taken at the step's end, where the
    value would have followed X back (-1.49988 for -1.5 before). Y to rounding, its
    integral to 5e-8 (Y's kinks where the play engages are not located: they cost
    RKS's fifth order a little there), whatever the output grid."""
    r = probe("X = 2.0*SIN(TIME)\nY = BCKLSH(0.0, 0.5, X)\nZ = INTGRL(0.0, Y)\nRANGE Y",
              fintim=7.5, outdel=outdel, method=method)
    assert np.max(np.abs(r["Y"] - backlash_of_2sin(r.t))) <= 1e-9
    edges = [math.asin(0.25), np.pi / 2, 5 * np.pi / 6, 1.5 * np.pi, 11 * np.pi / 6]
    for t, z in zip(r.t, r["Z"], strict=True):
        exact = integrate.quad(backlash_of_2sin, 0.0, t, points=[e for e in edges if e < t],
                               epsabs=1e-13, epsrel=1e-13, limit=200)[0]
        assert z == pytest.approx(exact, abs=5e-8)
    low, _, high, _ = r.range["Y"]  # (RANGE: the extremes between the rows too)
    assert (low, high) == pytest.approx((-1.5, 1.5), abs=1e-12)


def backlash_spring(x0: float, dl: float, fintim: float):
    """X'' = -Y, Y = BCKLSH(0, DL, X): a mass on a spring through a play, solved
    here by branches -- held (Y constant), pushed up (Y = X - DL) or down (Y = X + DL)
    -- with the turns where V = X' = 0 and the engagements where X - DL or X + DL
    reaches the held value located by solve_ivp at rtol 1e-12 (the play's own rule,
    written with X's rate, which amilpy does not have)."""
    t, y, held, mode = 0.0, np.array([x0, 0.0]), 0.0, 0
    if x0 - dl > 0:
        mode = 1
    elif x0 + dl < 0:
        mode = -1
    pieces = []
    while t < fintim:
        def rhs(_, s, mode=mode, held=held):
            out = held if mode == 0 else s[0] - mode * dl
            return [s[1], -out]

        if mode == 0:
            up = lambda _, s, held=held: s[0] - dl - held  # noqa: E731
            down = lambda _, s, held=held: s[0] + dl - held  # noqa: E731
            up.terminal = down.terminal = True
            up.direction, down.direction = 1, -1
            events = [up, down]
        else:
            turn = lambda _, s: s[1]  # noqa: E731
            turn.terminal, turn.direction = True, -mode
            events = [turn]
        sol = integrate.solve_ivp(rhs, (t, fintim), y, method="DOP853", rtol=1e-12,
                                  atol=1e-14, events=events, dense_output=True)
        pieces.append((t, sol.t[-1], mode, held, sol.sol))
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 1:
            hit = next(i for i, e in enumerate(sol.t_events) if len(e))
            if mode == 0:
                mode = 1 if hit == 0 else -1
            else:
                held, mode = y[0] - mode * dl, 0

    def at(times):
        out = []
        for u in times:
            t0, t1, mode, held, sol = next(p for p in pieces if p[0] <= u <= p[1])
            x = sol(u)[0]
            out.append((x, held if mode == 0 else x - mode * dl))
        return np.array(out)
    return at


def test_backlash_in_a_loop_against_a_solve_by_branches():
    """The play's output drives the motion (a mass on a spring through the play):
    the turns located in the steps make X and Y agree with an independent solve by
    branches to the tolerance's order, on the default route and on RKS."""
    ref = backlash_spring(1.0, 0.2, 12.0)
    for method in ("AUTO", "RKS"):
        r = probe("X = INTGRL(1.0, V)\nV = INTGRL(0.0, -Y)\nY = BCKLSH(0.0, 0.2, X)",
                  fintim=12.0, outdel=0.1, method=method)
        exact = ref(r.t)
        assert np.max(np.abs(r["X"] - exact[:, 0])) <= 5e-8, method
        assert np.max(np.abs(r["Y"] - exact[:, 1])) <= 5e-8, method


@pytest.mark.parametrize("method", ["AUTO", "RKS"])
def test_sensitivities_through_a_play_agree_with_the_solve_by_branches(method):
    """d X/d p and d Y/d p of the spring through the play, for its width DL and the
    start X0, from the sensitivity equations: the play's memory carried through its
    updates on the branch the motion takes -- following its input, or holding where
    it turned -- and its engagements inside the steps found. Against central
    differences (h = 1e-5) of the solve by branches at rtol 1e-12 (error about 1e-7);
    the instants avoid the engagements, where dY/dp jumps. Before, the play sent the
    gradient to differences of whole runs; read through the clamp's kink the
    tangent was 5e-3 off in d X/d DL."""
    text = ("PARAM DL = 0.2, X0 = 1.0\nX = INTGRL(X0, V)\nV = INTGRL(0.0, -Y)\n"
            "Y = BCKLSH(0.0, DL, X)\nTIMER FINTIM = 12.0, OUTDEL = 0.37\nPRINT X, Y\nEND\n")
    loc = amilpy.loads(text, "play.amil").sensitivity(["DL", "X0"], outputs=["X", "Y"],
                                                       method_ode=method)
    assert loc.how == "sensitivity equations"
    h = 1e-5
    for j, (dl, x0) in enumerate([((0.2 + h, 0.2 - h), (1.0, 1.0)),
                                  ((0.2, 0.2), (1.0 + h, 1.0 - h))]):
        up = backlash_spring(x0[0], dl[0], 12.0)(loc.times)
        down = backlash_spring(x0[1], dl[1], 12.0)(loc.times)
        reference = (up - down) / (2 * h)
        assert np.max(np.abs(loc.raw[:, :, j] - reference)) <= 1e-6, (method, j)


# ----------------------------------------------------------------------- LIMINT
def limint_cosine(t):
    """The integral of cos t from 0, held within [-0.5, 0.5]: sin t up to 0.5 at pi/6,
    held there until cos turns negative at pi/2, then 0.5 + (sin t - 1) down to -0.5
    at pi, held until 3pi/2, -0.5 + (sin t + 1) up to 0.5 at 2pi, and so on."""
    u = np.mod(t, 2 * np.pi)
    cycle = np.select([u < np.pi / 2, u < np.pi, u < 1.5 * np.pi],
                      [0.5, np.sin(u) - 0.5, -0.5], np.sin(u) + 0.5)
    return np.where(t < np.pi / 6, np.sin(t), cycle)


def test_limint_against_the_clipped_integral():
    """The bounds are located like a switch on a state (to 1e-9 here), and the
    turns of YD too: the output is the clipped integral to the tolerance."""
    r = probe("Y = LIMINT(COS(TIME), 0.0, -0.5, 0.5)", fintim=10.0, outdel=0.05, **TIGHT)
    assert np.max(np.abs(r["Y"] - limint_cosine(r.t))) <= 1e-8
    hits = [e.time for e in r.events if e.text.startswith("Y - ")]
    expected = [np.pi / 6, np.pi, 2 * np.pi, 3 * np.pi]
    assert hits == pytest.approx(expected, abs=1e-9)
    turns = [e.time for e in r.events if e.text == "COS(TIME)"]
    assert turns == pytest.approx([np.pi / 2, 1.5 * np.pi, 2.5 * np.pi], abs=1e-9)
    assert max(r["Y"]) <= 0.5 + 1e-12 and min(r["Y"]) >= -0.5 - 1e-12


def test_limint_starting_beyond_a_bound_is_put_on_it_until_yd_turns():
    """IC = 2 above TB = 1 while YD > 0: the state is held within [BB, TB], on TB;
    from t = 0.5 (YD turns) it falls by (t - 0.5)**2/2, until BB = 0 at 0.5 + sqrt 2."""
    r = probe("Y = LIMINT(0.5 - TIME, 2.0, 0.0, 1.0)", fintim=2.0, outdel=0.25, **TIGHT)
    fall = np.maximum(1.0 - (r.t - 0.5) ** 2 / 2, 0.0)
    assert r["Y"] == pytest.approx(np.where(r.t < 0.5, 1.0, fall), abs=1e-9)


def test_a_held_limint_sits_exactly_on_its_bound_through_other_restarts():
    """Other switches restart the run while LIMINT is held (a PULSE train here): the
    state stays exactly on the bound, and no restart lets it go (each bound is
    reached once, each turn of YD once)."""
    r = probe("Y = LIMINT(COS(3.0*TIME), 0.0, -0.2, 0.2)\nP = PULSE(0.0, 0.01, 0.005)\n"
              "X = INTGRL(0.0, P)", fintim=3.0, outdel=0.01)
    held = (r.t > 0.22) & (r.t < 0.52)
    assert np.all(r["Y"][held] == 0.2)
    limint = [e for e in r.events if "LIMINT" in e.switch]
    assert [e.text for e in limint] == ["Y - 0.2", "COS(3.0*TIME)", "Y - -0.2",
                                        "COS(3.0*TIME)", "Y - 0.2", "COS(3.0*TIME)"]


def test_limint_in_step_point_mode_is_held_on_the_bound():
    """Euler: the state is put on the bound at the first step point past it (no
    overshoot), and stays while YD pushes out: the recurrence clipped."""
    r = run1("Y = LIMINT(1.0 - TIME, 0.0, -1.0, 0.35)\nTIMER FINTIM = 3.0, DELT = 0.1, "
             "PRDEL = 0.1\nMETHOD EULER\nEND\n")
    y, ys = 0.0, []
    for k in range(31):
        t = k * 0.1
        yd = 1.0 - t
        if (y <= -1.0 and yd < 0) or (y >= 0.35 and yd > 0):
            y = -1.0 if y <= -1.0 else 0.35
        ys.append(y)
        held = (y <= -1.0 and yd < 0) or (y >= 0.35 and yd > 0)
        y = y if held else y + 0.1 * yd
    assert np.max(np.abs(r["Y"] - np.array(ys))) <= 1e-14


# ------------------------------------------------------------- DELAY (ACSL form)
@pytest.mark.parametrize("method", ["AUTO", "RKS", "RK4", "RADAU"])
def test_acsl_delay_against_the_delayed_sine(method):
    """DELAY(X, IC, TDL, NMX): IC before t0 + TDL, X(t - TDL) after (NMX = 1000 points
    over TDL, taken from the dense output: the rows read stored instants, the
    derivative reads between them, off by (5e-4)**2/8 = 3.1e-8; DMIN = 1e-4 is closer
    than TDL/NMX and changes nothing). The integral of a delayed cosine with IC = 1
    (a jump at TDL, where the run restarts): t before TDL, then TDL + sin(t - TDL)."""
    tdl = 0.5
    r = probe(f"D = DELAY(SIN(TIME), 0.0, {tdl}, 1000)\n"
              f"Y = INTGRL(0.0, DELAY(COS(TIME), 1.0, {tdl}, 1000, 1.0E-4))",
              fintim=3.0, outdel=0.01, method=method)
    t = r.t
    assert np.max(np.abs(r["D"] - np.where(t < tdl, 0.0, np.sin(t - tdl)))) < 1e-12
    assert np.max(np.abs(r["Y"] - np.where(t < tdl, t, tdl + np.sin(t - tdl)))) < 1e-7


def test_acsl_and_csmp_delay_are_told_apart_by_their_arguments():
    entry = lookup("DELAY")
    assert lookup("DELAY", 3).signature == "DELAY(N, P, X)"
    assert lookup("DELAY", 4).signature == lookup("DELAY", 5).signature == \
        "DELAY(X, IC, TDL, NMX[, DMIN])"
    assert entry.signatures() == "DELAY(N, P, X) or DELAY(X, IC, TDL, NMX[, DMIN])"
    with pytest.raises(AmilError) as err:
        amilpy.loads("X = INTGRL(1.0, -X)\nD = DELAY(X, 0.0, 0.5, NM)\nPARAM NM = 9\n"
                     "TIMER FINTIM = 1\nEND\n")
    assert "NMX of DELAY must be a whole number written out" in err.value.render()
    with pytest.raises(AmilError) as err:
        amilpy.loads("X = INTGRL(1.0, -X)\nD = DELAY(X, 0.0, 0.0, 10)\nTIMER FINTIM = 1\n"
                     "END\n")
    assert "TDL of DELAY must be positive (got 0)" in err.value.render()
    with pytest.raises(AmilError) as err:
        amilpy.loads("X = INTGRL(1.0, -X)\nD = DELAY(X, 0.0, 0.5, 10, 1, 2)\n"
                     "TIMER FINTIM = 1\nEND\n")
    assert "DELAY takes 3, 4 or 5 arguments, got 6" in err.value.render()


def test_acsl_delay_in_step_point_mode_is_the_stored_value():
    """Euler, DELT = 0.1: the delayed X at t_k is X at t_k - TDL, from the store (TDL a
    multiple of DELT): the recurrence written out, to round-off."""
    r = run1("X = INTGRL(1.0, -X + D)\nD = DELAY(X, 0.0, 0.3, 30)\n"
             "TIMER FINTIM = 2.0, DELT = 0.1, PRDEL = 0.1\nMETHOD EULER\nEND\n")
    xs = [1.0]
    for k in range(20):
        d = xs[k - 3] if k >= 3 else 0.0
        xs.append(xs[k] + 0.1 * (-xs[k] + d))
    assert np.max(np.abs(r["X"] - np.array(xs))) <= 1e-14


# ---------------------------------------------------------------------- DERIVT
def test_derivt_is_deriv():
    r = probe("X = INTGRL(0.0, COS(TIME))\nA = DERIVT(1.0, X)\nB = DERIV(1.0, X)",
              fintim=3.0, outdel=0.5, method="RK4")
    assert np.array_equal(r["A"], r["B"]) and r["A"][0] == 1.0
    assert r["A"] == pytest.approx(np.cos(r.t), abs=2e-3)


# ---------------------------------------------------------------------- NOTNUL
def test_a_division_by_notnul_never_faults():
    """NOTNUL(X) is 1 for X = 0 (either sign), else X: Y/NOTNUL(X) never divides by 0,
    at an output instant, in a derivative, or in INITIAL."""
    r = probe("INITIAL\nQ = 2.0/NOTNUL(-0.0)\nDYNAMIC\nZ = TIME/NOTNUL(TIME - 0.5)\n"
              "N = NOTNUL(TIME - 0.5)\nX = INTGRL(0.0, 1.0/NOTNUL(STEP(0.5) - 1.0))")
    assert list(r["N"]) == [-0.5, -0.25, 1.0, 0.25, 0.5]
    assert r["Z"][2] == 0.5 and r.final["Q"] == 2.0
    assert r["X"] == pytest.approx(np.where(r.t < 0.5, -r.t, -0.5 + (r.t - 0.5)), abs=1e-9)


# --------------------------------------------------------------- REAAND, REANOR
def test_reaand_and_reanor_truth_tables():
    r = probe("P = TIME - 0.5\nA = REAAND(P, 1.0)\nB = REAAND(P, -1.0)\n"
              "C = REANOR(P, -1.0)\nD = REANOR(P, 0.0)")
    before, at, after = 1, 2, 3  # rows at t = .25, .5 (P = 0: not > 0), .75
    assert [r["A"][i] for i in (before, at, after)] == [0, 0, 1]
    assert set(r["B"]) == {0.0}
    assert [r["C"][i] for i in (before, at, after)] == [1, 1, 0]
    assert [r["D"][i] for i in (before, at, after)] == [1, 1, 0]
    assert lookup("REAAND") is lookup("AND") and lookup("REANOR") is lookup("NOR")


# ------------------------------------------------------------------------ LINT
def test_lint_extends_the_end_segments_with_one_warning():
    """Inside the table LINT is AFGEN; outside it the end segments go on (AFGEN holds
    the end values), and the run warns once per table, with how far out it read."""
    r = probe("FUNCTION F = 0.0, 1.0, 1.0, 3.0, 2.0, 2.0\nY = LINT(F, 4.0*TIME - 1.0)\n"
              "W = LINT(F, 3.0*TIME)\nA = AFGEN(F, 4.0*TIME - 1.0)", outdel=0.125)
    x = 4.0 * r.t - 1.0
    exact = np.where(x < 1.0, 1.0 + 2.0 * x, 3.0 - (x - 1.0))
    assert np.max(np.abs(r["Y"] - exact)) <= 1e-14
    inside = (x >= 0.0) & (x <= 2.0)
    assert np.array_equal(r["Y"][inside], r["A"][inside])
    assert r.warnings == ["LINT read table F outside its x range [0, 2] (down to -1 and up "
                          "to 3): the end segments were extended"]


def test_lint_inside_the_table_warns_nothing_and_runs_start_afresh():
    model = amilpy.loads("FUNCTION F = 0.0, 0.0, 1.0, 2.0\nPARAM S = 1.0\n"
                         "Y = LINT(F, S*TIME)\nTIMER FINTIM = 1.0\nEND\n")
    assert model.run(S=2.0)[0].warnings and not model.run(S=1.0)[0].warnings


SECTION_12 = ("PULSE", "HARM", "RSW", "BCKLSH", "LIMINT", "DELAY", "DERIVT", "GAUSS", "UNIF",
              "RNDGEN", "OU", "NOTNUL", "REAAND", "REANOR", "LINT")


def test_the_functions_reference_shows_each_signature_as_the_library_has_it():
    from pathlib import Path

    text = (Path(__file__).resolve().parent.parent / "docs" / "functions.md").read_text("utf-8")
    for name in SECTION_12:
        entry = lookup(name)
        if name != entry.name:  # an ACSL name for a function of section 5
            assert f"`{name}(" in text, name
            continue
        for f in (entry, *entry.variants):
            assert f"`{f.signature}" in text, f.signature
