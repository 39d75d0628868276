"""Fortran's non-smooth arithmetic as switches: SIGN, ABS, AMAX1/AMIN1 (any number of
arguments), DIM, AINT, NINT and AMOD.

In sorted code (DYNAMIC, DERIVATIVE and the blocks in them) each call is a switch like
FSW: the integrator sees one smooth branch at a time, every kink and jump is located
and listed, and where both sides push the argument back the run slides (Filippov).
Where code runs once (INITIAL, TERMINAL, written-order code, a test made where it
stands) each keeps its plain Fortran value. Every listing below is checked against a
closed form, or against the same model written with FSW, solved separately.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import METHODS, ROOT, run1
from scipy.integrate import quad
from scipy.optimize import brentq

import amilpy
from amilpy import library
from amilpy.library import runtime
from amilpy.library.surfaces import amod_at, level, sign

EPS = sys.float_info.epsilon
ROOT_DOCS = Path(ROOT) / "docs"
LOCATED = {"step_point": False, "advice": False}  # EULER too locates its crossings
NONSMOOTH = ("ABS", "SIGN", "AMAX1", "AMIN1", "DIM", "AINT", "NINT", "AMOD")


def ulps(t: float, n: int = 8) -> float:
    """n units in the last place of TIME = t (how close a located instant is)."""
    return n * EPS * max(abs(t), 1.0)


# ------------------------------------------------------------ the library entries
def _template(text: str, args: tuple[float, ...], modes=()) -> float:
    """A library template evaluated on floats: A, B, ... the arguments, M0, ... modes."""
    names = {"ABS": abs, "SGN": sign, "AMODAT": amod_at,
             **dict(zip("ABCDEFGH", args, strict=False))}
    names.update({f"M{k}": m for k, m in enumerate(modes)})
    return float(eval(text, {"__builtins__": {}}, names))  # noqa: S307 - library text


def _on_the_spot(func, args: tuple[float, ...]) -> float:
    """A switch's value with its surfaces' modes taken where it stands."""
    mode = level if func.surface_kind is library.SurfaceKind.LEVEL else sign
    modes = [mode(_template(s, args)) for s in func.surfaces]
    return _template(func.values[0], args, modes)


EDGES = (0.0, -0.0, 0.25, -0.25, 0.5, -0.5, 1.0, -1.0, 1.5, -1.5, 2.0, -2.0, 2.5, -2.5,
         3.0, -7.0, 6.5, 1e-300, -1e-300, 0.49999999999999994, 2.4999999999999996,
         1.0000000000000002, 0.9999999999999999, 2.0**50 + 0.5, -(2.0**50) - 0.5)


@pytest.mark.parametrize("name", NONSMOOTH)
def test_each_switch_on_the_spot_is_its_plain_fortran_value(name):
    # the templates (what the integrator sees between crossings) with their modes
    # taken where they stand are the plain form exactly, at the kinks and band edges
    # too (whole and half numbers, zeros of either sign, the float next to an edge;
    # the level surfaces' arithmetic is exact below 2**51). AMOD's second argument is
    # a power of 2 here, so that A/B is exact as fmod is (elsewhere A/B rounds).
    func = library.lookup(name)
    assert func.kind is library.Kind.SWITCH and func.plain
    pairs = [(x,) for x in EDGES] if func.nargs[0] == 1 else \
        [(x, y) for x in EDGES for y in (0.5, -2.0, 4.0, 1.0, -0.0, 0.0, 2.5)
         if not (name == "AMOD" and (y == 0.0 or y == 2.5))]
    for args in pairs:
        assert _on_the_spot(func, args) == func.scalar(*args), (name, args)


def test_the_fortran_meanings_at_the_kinks():
    # SIGN(A, B) = |A| if B >= 0 else -|A|; DIM(X, Y) = X - Y if X > Y else 0; AINT
    # truncates toward 0; NINT rounds halves away from 0; AMOD has the sign of A
    assert [runtime.fortran_sign(3.0, b) for b in (2.0, 0.0, -2.0)] == [3.0, 3.0, -3.0]
    assert [runtime.fortran_dim(x, 1.0) for x in (3.0, 1.0, -1.0)] == [2.0, 0.0, 0.0]
    assert [runtime.fortran_aint(x) for x in (2.7, -2.7, 2.0, -0.5)] == [2.0, -2.0, 2.0, 0.0]
    assert [runtime.fortran_nint(x) for x in (2.5, -2.5, 2.4999999999999996, 0.5, -0.5)] \
        == [3.0, -3.0, 2.0, 1.0, -1.0]
    assert [runtime.fortran_amod(a, 3.0) for a in (7.0, -7.0)] == [1.0, -1.0]
    assert runtime.fortran_amod(7.0, -3.0) == 1.0


@pytest.mark.parametrize("name", NONSMOOTH)
def test_the_vector_forms_are_the_plain_forms_on_columns(name):
    # the chunked paths evaluate the generated code over NumPy columns
    func = library.lookup(name)
    scalar = library.math_functions()[name]
    vector = library.vector_functions()[name]
    xs = np.array([x for x in EDGES if abs(x) < 1e10] * 2)
    ys = np.resize(np.array([0.5, -2.0, 4.0, 1.0, 3.0]), xs.size)
    args = [xs] if func.nargs[0] == 1 else [xs, ys] if func.nargs[1] else [xs, ys, -ys]
    got = np.asarray(vector(*args), dtype=float)
    want = np.array([scalar(*a) for a in zip(*args, strict=True)])
    assert np.array_equal(got, want), name


def test_the_generated_code_on_columns_is_the_code_on_rows():
    # AUTO records whole chunks of rows at once: the surfaces and outputs are the same
    # generated code run on NumPy columns (templates with their modes frozen, and the
    # plain forms inside AINT's and TERMT's surfaces); row by row it gives the same
    from amilpy.run.prepare import prepare

    model = amilpy.loads("""X = INTGRL(-1.3, 1.0)
Y = INTGRL(0.4, X)
A = ABS(X) + SIGN(2.0, Y) + AMAX1(X, Y, 0.1) + AMIN1(X, -Y) + DIM(X, Y)
B = AINT(3.0*X) + NINT(3.0*Y) + AMOD(5.0*X, 1.5)
TERMT(X > 2.0 .AND. ABS(Y) > 3.0)
TIMER FINTIM = 2.0, OUTDEL = 0.1
END
""", name="v.amil")
    c = prepare(model.ir, model.ir.runs[0]).code
    t = np.linspace(0.0, 2.0, 41)
    cols = [-1.3 + 1.0 * t, 0.4 - 1.3 * t + 0.5 * t * t]
    m = c.modes_literal(0.7, [col[14] for col in cols], [0.0] * len(c.watched), [])
    surf = np.column_stack([np.broadcast_to(v, t.shape) for v in c.surf_v(t, cols, m, [])])
    out = np.column_stack([np.broadcast_to(v, t.shape) for v in c.out_v(t, cols, m, [])])
    for i in range(t.size):
        row = [col[i] for col in cols]
        assert list(surf[i]) == c.surf(t[i], row, m, []), i
        assert list(out[i]) == c.out(t[i], row, m, []), i


def test_the_references_show_every_one():
    text = (ROOT_DOCS / "functions.md").read_text("utf-8")
    language = (ROOT_DOCS / "language.md").read_text("utf-8")
    for name in NONSMOOTH:
        func = library.lookup(name)
        assert f"`{func.signature}`" in text and f"`{func.signature}`" in language, name


# ------------------------------------------------------------- dry friction
FRICTION = """PARAM J = 1.0, MT = 1.0, A = 1.5
TD = A*SIN(TIME)
FR = MT*{}
W = INTGRL(0.0, (TD - FR)/J)
X = INTGRL(0.0, W)
TIMER FINTIM = 10.0, OUTDEL = 0.1
END
"""
SIGN_FORM, FSW_FORM = "SIGN(1.0, W)", "FSW(W, -1.0, 0.0, 1.0)"
J, MT, A = 1.0, 1.0, 1.5


def friction_reference(t_end: float):
    """The mass driven by A sin t against Coulomb friction MT, from rest, piece by
    piece in closed form: stuck (W = 0) while |A sin t| <= MT, else slipping with
    W' = (A sin t - s MT)/J, s the sign of W. Each piece's end is found by brentq on
    the closed form. Returns the pieces (t0, t1, s) and t -> (W, X)."""
    def w(s, t0, t):
        return (A * (math.cos(t0) - math.cos(t)) - s * MT * (t - t0)) / J

    def x(s, t0, x0, t):
        return x0 + (A * (math.cos(t0) * (t - t0) - (math.sin(t) - math.sin(t0)))
                     - s * MT * (t - t0) ** 2 / 2) / J

    def first_root(g, t0, h=1e-3):
        t = t0 + h
        while t < t_end:
            if g(t) * g(t + h) <= 0 and g(t + h) != 0:
                return brentq(g, t, t + h, xtol=1e-15, rtol=4 * EPS)
            t += h
        return None

    pieces, t0, x0, s = [], 0.0, 0.0, 0
    while True:
        if s == 0:  # stuck until the drive reaches the friction
            t1 = first_root(lambda t: abs(A * math.sin(t)) - MT, t0)
        else:  # slipping until W is back at 0
            t1 = first_root(lambda t, s=s, t0=t0: w(s, t0, t), t0)
        pieces.append((t0, t_end if t1 is None else t1, s, x0))
        if t1 is None:
            break
        if s:
            x0 = x(s, t0, x0, t1)
        drive = A * math.sin(t1)
        s = 0 if s and abs(drive) < MT else (1 if drive > 0 else -1)
        t0 = t1

    def at(t):
        for t0, t1, s, x0 in pieces:
            if t0 <= t <= t1:
                return (w(s, t0, t), x(s, t0, x0, t)) if s else (0.0, x0)
        raise ValueError(t)
    return [(a, b, s) for a, b, s, _ in pieces], at


# how far from the closed form each method ends at RELERR 1e-10: the variable-step
# methods within 100 RELERR units over the run's seven events; the fixed-step ones at
# DELT = OUTDEL/16 by their order (EULER first, TRAPZ and ADAMS second, RK4 fourth)
FRICTION_TOL = {"EULER": 2e-2, "RECT": 2e-2, "TRAPZ": 1e-4, "ADAMS": 1e-3, "RK4": 1e-9}


@pytest.mark.parametrize("method", METHODS)
def test_dry_friction_in_the_sign_form_is_the_fsw_form(method):
    # MT*SIGN(1.0, W), as classic listings write Coulomb friction, is a switch on W
    # (the surface FSW's argument has: one surface for both): at rest with the drive
    # below MT both branches push W back to 0, so the mass sticks there, a slide, and
    # slips when the drive exceeds MT. The SIGN form takes the FSW form's steps, events
    # and values (as plain arithmetic it chattered on the kink: the step limit of
    # 5,000,000 by TIME = 0.0004 on AUTO); both follow the closed form.
    kw = dict(method=method, rtol=1e-10, atol=1e-12, **LOCATED)
    s = run1(FRICTION.format(SIGN_FORM), **kw)
    f = run1(FRICTION.format(FSW_FORM), **kw)
    assert s.status == f.status == "finished", s.message
    assert s.stats["nsteps"] <= 1.25 * f.stats["nsteps"]  # equal, measured
    assert [(e.kind, e.old, e.new) for e in s.events] == [(e.kind, e.old, e.new)
                                                            for e in f.events]
    assert [e.time for e in s.events] == pytest.approx([e.time for e in f.events], abs=1e-12)
    for name in ("W", "X"):
        assert s[name] == pytest.approx(f[name], abs=1e-12), name
    pieces, at = friction_reference(10.0)
    ref = np.array([at(t) for t in s.t])
    tol = FRICTION_TOL.get(method, 1e-8)
    assert np.max(np.abs(s["W"] - ref[:, 0])) <= tol
    assert np.max(np.abs(s["X"] - ref[:, 1])) <= tol
    # stuck four times (from rest, then after each slip): each a slide of W at 0, where
    # the friction holds the drive exactly (Filippov's weights: FR = TD)
    sticks = [(t0, t1) for t0, t1, sgn in pieces if sgn == 0]
    assert len(sticks) == 4 and sticks[0][0] == 0.0
    slides = [e.time for e in s.events if e.kind == "slide"]
    assert slides == pytest.approx([t0 for t0, _ in sticks], abs=max(tol, 1e-9))
    for t0, t1 in sticks:
        inside = (s.t > t0 + 1e-3) & (s.t < t1 - 1e-3)
        assert inside.any()
        # (W stays where the slip's end was located: to the method's accuracy)
        assert np.max(np.abs(s["W"][inside])) <= (1e-9 if tol <= 1e-8 else tol)
        assert s["FR"][inside] == pytest.approx(s["TD"][inside], abs=1e-12)


def test_dry_friction_costs_what_fsw_costs_at_the_default_tolerance():
    # the measurement, on AUTO with the listing's default RELERR/ABSERR: the
    # SIGN form was 888,760 steps for 0.1 s of a clutch; here it is the FSW form's
    s = run1(FRICTION.format(SIGN_FORM), advice=False)
    f = run1(FRICTION.format(FSW_FORM), advice=False)
    assert s.ok and f.ok
    assert s.stats["nsteps"] == f.stats["nsteps"] and len(s.events) == len(f.events) == 7


def test_the_clutch_with_its_friction_written_with_sign():
    # Exercise 4's rotor friction as classic listings write it, MF*SIGN(1.0, W1),
    # instead of FSW(W1, -MF, LIMIT(-MF, MF, MNET), MF): at rest the slide's weights
    # give the friction that holds the rotor (MNET, the LIMIT branch), so both runs
    # take the same 1375 steps over 0.1 s, with the same events and rows (as plain
    # arithmetic: a step-size underflow at TIME = 5E-12, after 1,000,100 steps)
    text = open(f"{ROOT}/models/ex4_clutch.amil", encoding="utf-8").read()
    text = text.replace("FINTIM = 0.5", "FINTIM = 0.1")
    fsw = amilpy.loads(text, name="c.amil").run(advice=False)[0]
    sgn = amilpy.loads(text.replace("FSW(W1, -MF, LIMIT(-MF, MF, MNET), MF)",
                                    "MF*SIGN(1.0, W1)"), name="c.amil").run(advice=False)[0]
    assert sgn.ok and sgn.stats["nsteps"] == fsw.stats["nsteps"]
    assert [(e.time, e.kind, e.old, e.new) for e in sgn.events] == \
        [(e.time, e.kind, e.old, e.new) for e in fsw.events]
    for name in ("W1", "W2", "IA", "MC"):
        assert sgn[name] == pytest.approx(fsw[name], rel=1e-12, abs=1e-15), name


# ------------------------------------------------------------ kinks, located
def test_abs_of_a_sine_is_located_at_each_zero():
    # |sin 3t| has a kink at k*pi/3: each is located to a few ulps of TIME (Brent's
    # method on the surface SIN(3.0*TIME), which reads TIME alone), and the integral
    # X = 2k/3 + (1 - |cos 3t|)/3 is followed to the tolerance across them
    r = run1("Y = ABS(SIN(3.0*TIME))\nX = INTGRL(0.0, Y)\nTIMER FINTIM = 3.0, OUTDEL = 0.1\n"
             "END\n", rtol=1e-10, atol=1e-12, advice=False)
    kinks = [k * math.pi / 3 for k in (1, 2)]
    assert [e.text for e in r.events] == ["SIN(3.0*TIME)"] * 2
    for e, t in zip(r.events, kinks, strict=True):
        assert abs(e.time - t) <= ulps(t)
    k = np.floor(3 * r.t / math.pi)
    exact = 2 * k / 3 + (1 - np.cos(3 * r.t - k * math.pi)) / 3
    assert np.max(np.abs(r["X"] - exact)) <= 1e-9  # ten RELERR units
    assert r["Y"] == pytest.approx(np.abs(np.sin(3 * r.t)), abs=1e-15)


def test_max_and_min_of_two_and_of_three_arguments():
    # AMAX1(TIME - 1, 2 - TIME) has its kink at 1.5, a breakpoint (the surface
    # (TIME - 1) - (2 - TIME) is affine in TIME: its root is exact), which MAX's with a
    # third argument shares. MAX(..., 0.6) is MAX(MAX(...), 0.6): its kinks at 1.4 and
    # 1.6 are on the running maximum. AMIN1(X, 1 - X, 0.3) of a state X = TIME has
    # kinks at 0.3 and 0.7, on the running minimum, located to a few ulps; its inner
    # kink at 0.5, inside the 0.3 branch, changes no derivative: no event. The
    # integrals against quad on the plain functions, with the kinks given.
    r = run1("""X = INTGRL(0.0, 1.0)
M2 = AMAX1(TIME - 1.0, 2.0 - TIME)
M3 = MAX(TIME - 1.0, 2.0 - TIME, 0.6)
N3 = AMIN1(X, 1.0 - X, 0.3)
I2 = INTGRL(0.0, M2)
I3 = INTGRL(0.0, M3)
J3 = INTGRL(0.0, N3)
TIMER FINTIM = 3.0, OUTDEL = 0.1
END
""", rtol=1e-10, atol=1e-12, advice=False)
    by = {}
    for e in r.events:
        by.setdefault(e.switch.split("(")[0] + ":" + e.text, []).append(e.time)
    assert by == {"AMAX1:TIME - 1.0 - (2.0 - TIME)": [1.5],  # exactly: a breakpoint
                  "MAX:MAX(TIME - 1.0, 2.0 - TIME) - 0.6": pytest.approx([1.4, 1.6],
                                                                      abs=ulps(2)),
                  "AMIN1:AMIN1(X, 1.0 - X) - 0.3": pytest.approx([0.3, 0.7], abs=ulps(1))}
    assert [e.switch for e in r.events if e.switch.startswith("AMIN1")] == \
        ["AMIN1(X, ...) at line 4"] * 2  # the call as written
    t = r.t

    def integral(f):
        return np.array([quad(f, 0.0, s, points=[0.3, 0.7, 1.4, 1.5, 1.6], limit=200)[0]
                         for s in t])
    m3 = lambda s: max(s - 1.0, 2.0 - s, 0.6)  # noqa: E731
    assert r["M3"] == pytest.approx([m3(s) for s in t], abs=1e-15)
    assert r["I2"] == pytest.approx(integral(lambda s: max(s - 1.0, 2.0 - s)), abs=1e-9)
    assert r["I3"] == pytest.approx(integral(m3), abs=1e-9)
    assert r["J3"] == pytest.approx(integral(lambda s: min(s, 1.0 - s, 0.3)), abs=1e-9)


def test_dim_is_the_positive_difference_located():
    # DIM(X, 0.5) of X = TIME: 0 until 0.5, X - 0.5 after; the integral (t - 0.5)**2/2
    r = run1("X = INTGRL(0.0, 1.0)\nD = DIM(X, 0.5)\nI = INTGRL(0.0, D)\n"
             "TIMER FINTIM = 1.0, OUTDEL = 0.1\nEND\n", rtol=1e-10, atol=1e-12, advice=False)
    assert [e.time for e in r.events] == pytest.approx([0.5], abs=ulps(0.5))
    assert r["D"] == pytest.approx(np.maximum(r.t - 0.5, 0.0), abs=1e-15)
    # (I to its tolerance: ABSERR 1e-12 + RELERR 1e-10 of I, LSODA restarting at the
    # kink with its first-order steps)
    assert r["I"] == pytest.approx(np.maximum(r.t - 0.5, 0.0) ** 2 / 2, abs=2e-12)


# ------------------------------------------------------------ jumps, located
JUMPS = """R = 2.5*TIME - 3.2
TA = AINT(R)
TN = NINT(R)
TM = AMOD(R, 1.5)
IA = INTGRL(0.0, TA)
IN = INTGRL(0.0, TN)
IM = INTGRL(0.0, TM)
TIMER FINTIM = 4.0, OUTDEL = 0.1
END
"""


def test_aint_nint_and_amod_of_a_ramp_jump_where_fortran_does():
    # R = 2.5t - 3.2 runs from -3.2 to 6.8. AINT(R) jumps where R crosses a whole
    # number other than 0 (it is 0 on (-1, 1)), NINT(R) where it crosses k + 1/2, AMOD
    # (R, 1.5) where R/1.5 crosses a whole number other than 0: each instant is located
    # to a few ulps of TIME, the values between are the plain functions', and the
    # integrals are the integrals of the plain functions (quad, with the jumps given).
    r = run1(JUMPS, rtol=1e-10, atol=1e-12, advice=False)
    at = {"AINT": [k for k in range(-3, 7) if k != 0],
          "NINT": [k + 0.5 for k in range(-3, 7)],
          "AMOD": [1.5 * k for k in range(-2, 5) if k != 0]}
    for name, values in at.items():
        times = [e.time for e in r.events if e.switch.startswith(name)]
        want = [(v + 3.2) / 2.5 for v in values]
        assert len(times) == len(want), name
        for got, t in zip(times, want, strict=True):
            assert abs(got - t) <= ulps(t), (name, got, t)
        assert all(e.kind == "level" for e in r.events)
    rr = 2.5 * r.t - 3.2
    for col, f in (("TA", runtime.fortran_aint), ("TN", runtime.fortran_nint),
                   ("TM", lambda x: runtime.fortran_amod(x, 1.5))):
        assert list(r[col]) == [f(x) for x in rr], col  # (no row is at a jump)
        jumps = [(v + 3.2) / 2.5 for vs in at.values() for v in vs]
        ref = [quad(lambda s, f=f: f(2.5 * s - 3.2), 0.0, t, points=jumps, limit=400)[0]
               for t in r.t]
        assert r["I" + col[1]] == pytest.approx(ref, abs=1e-8), col  # 100 RELERR units


def test_a_jump_of_a_state_is_located_on_the_dense_output():
    # AINT of a state that crosses 0: Q = AINT(3 sin t) jumps at 3 sin t = +-1, +-2 and
    # not at 0 (AINT is 0 on both sides: no event there)
    r = run1("S = INTGRL(0.0, C)\nC = INTGRL(1.0, -S)\nQ = AINT(3.0*S)\nI = INTGRL(0.0, Q)\n"
             "TIMER FINTIM = 6.0, OUTDEL = 0.1\nEND\n", rtol=1e-11, atol=1e-13, advice=False)
    a1, a2 = math.asin(1 / 3), math.asin(2 / 3)
    want = [a1, a2, math.pi - a2, math.pi - a1, math.pi + a1, math.pi + a2,
            2 * math.pi - a2, 2 * math.pi - a1]
    # located on the state's dense output: to the integration's accuracy
    assert [e.time for e in r.events] == pytest.approx(want, abs=1e-9)
    ref = [quad(lambda s: runtime.fortran_aint(3.0 * math.sin(s)), 0.0, t, points=want,
                limit=200)[0] for t in r.t]
    assert r["I"] == pytest.approx(ref, abs=1e-8)


# ------------------------------------------------- the plain value, where run once
def test_initial_and_terminal_keep_the_plain_values():
    # evaluated once: no switch is made, and each value is Fortran's at its kink
    model = amilpy.loads("""PARAM P = 2.5
INITIAL
   A0 = AINT(-P)
   N1 = NINT(P)
   N2 = NINT(-P)
   S0 = SIGN(3.0, 0.0)
   D0 = DIM(1.0, 2.0)
   M0 = AMOD(-7.0, 3.0)
   MX = AMAX1(1.0, 3.0, P)
   AB = ABS(-P)
DYNAMIC
   X = INTGRL(0.0, 1.0)
TERMINAL
   T1 = AINT(TIME)
   T2 = NINT(TIME - 0.5)
   T3 = SIGN(1.0, TIME - 2.0)
TIMER FINTIM = 2.0, OUTDEL = 0.5
END
""", name="once.amil")
    assert model.ir.switches == [] and model.ir.surfaces == []
    run, = model.run(advice=False)
    c = run.constants
    assert (c["A0"], c["N1"], c["N2"], c["S0"], c["D0"], c["M0"], c["MX"], c["AB"]) == \
        (-2.0, 3.0, -3.0, 3.0, 0.0, -1.0, 3.0, 2.5)
    assert run.terminal == {"T1": 2.0, "T2": 2.0, "T3": 1.0}


def test_written_order_code_of_the_acsl_form_keeps_the_plain_values():
    # ACSL's INITIAL, DYNAMIC and DISCRETE run in written order at their instants:
    # N counts the quarter hours with AINT (exact at 0.25, 0.5, ...), not a switch
    run, = amilpy.loads("""PROGRAM quarters
  CINTERVAL CINT = 0.25
  INITIAL
    K = NINT(2.5)
  END
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    TERMT(T >= 1.0)
  END
  DYNAMIC
    N = AINT(4.0*T) + K
  END
END
""", "q.csl").run(advice=False)
    assert list(run["N"]) == [3.0, 4.0, 5.0, 6.0, 7.0]
    assert [e.kind for e in run.events] == ["termt"]


def test_step_point_mode_reads_each_switch_on_the_spot():
    # METHOD EULER in step-point mode reads every switch at the step points: AINT and
    # NINT there are the plain values, band edges included (TIME = 1.0: AINT is 1;
    # TIME - 0.5 = 0.5: NINT is 1)
    r = run1("X = INTGRL(0.0, AINT(TIME) + NINT(TIME - 0.5))\nA = AINT(TIME)\n"
             "N = NINT(TIME - 0.5)\nTIMER FINTIM = 2.0, DELT = 0.25, OUTDEL = 0.25\n"
             "METHOD EULER\nEND\n")
    assert list(r["A"]) == [runtime.fortran_aint(t) for t in r.t]
    assert list(r["N"]) == [runtime.fortran_nint(t - 0.5) for t in r.t]
    # Euler's sum of the values at the step points, exactly
    values = [runtime.fortran_aint(t) + runtime.fortran_nint(t - 0.5) for t in r.t]
    assert list(r["X"]) == pytest.approx(np.concatenate(([0.0], 0.25 * np.cumsum(values[:-1]))),
                                         abs=1e-15)


def test_a_call_that_reads_a_value_a_loop_assigned_is_made_where_it_stands():
    # W is the sum a DO loop makes: no expression of what the block reads gives it,
    # so AINT(W) cannot be a surface; it is the plain value, with the warning a test
    # there gets (a value an IF assigns on every path is what the IF selects: below)
    model = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.1
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    PROCEDURAL (E, W = X)
      W = 0.0
      DO K = 1, 4
        W = W + X
      ENDDO
      E = AINT(W)
    END
    TERMT(T >= 1.0)
  END
END
""", "p.csl")
    assert any("AINT here reads a value assigned inside an IF or a loop before it: it is "
               "made where it stands, never located" in w.message for w in model.ir.warnings)
    assert model.ir.switches == []
    run, = model.run(rtol=1e-10, atol=1e-12, advice=False)
    assert list(run["E"]) == [runtime.fortran_aint(4.0 * x) for x in run["X"]]


def test_a_call_on_a_value_an_if_selects_is_located():
    # W = 4X where X > 0.5, else 0, on every path: after the IF, W is RSW(X > 0.5, 4X,
    # 0.) of what the block reads, so AINT(W) is a switch: its jumps at 4X = 3 and 4
    # (X = 0.75, 1) are located; at X = 0.5 W jumps from 0 to 2 with the IF's choice,
    # and AINT(W) with it (an event each)
    model = amilpy.loads("""X = INTGRL(0.0, 1.0)
PROCEDURE E, W = P(X)
   W = 0.0
   IF (X > 0.5) THEN
      W = 4.0*X
   ENDIF
   E = AINT(W)
ENDPRO
I = INTGRL(0.0, E)
TIMER FINTIM = 1.2, OUTDEL = 0.1
END
""", name="p.amil")
    assert not model.ir.warnings
    run, = model.run(rtol=1e-10, atol=1e-12, advice=False)
    assert [e.switch for e in run.events] == ["RSW(X > 0.5, ...) at line 4"] + \
        ["AINT(W) at line 7"] * 3
    assert [e.time for e in run.events] == pytest.approx([0.5, 0.5, 0.75, 1.0],
                                                         abs=ulps(1.0))
    # I = 2(t - .5) to .75, then 0.5 + 3(t - .75) to 1, then 1.25 + 4(t - 1)
    t = run.t
    want = np.where(t < 0.5, 0.0, np.where(t < 0.75, 2 * (t - 0.5),
                    np.where(t < 1.0, 0.5 + 3 * (t - 0.75), 1.25 + 4 * (t - 1.0))))
    assert run["I"] == pytest.approx(want, abs=1e-9)


def test_interval_expressions_may_use_the_plain_forms():
    # where only plain functions of constants may stand (CINTERVAL), AMAX1 may
    run, = amilpy.loads("""PROGRAM p
  CONSTANT H = 0.1
  CINTERVAL CINT = AMAX1(H, 0.2)
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run(advice=False)
    assert list(run.t) == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0])


def test_termt_conditions_keep_their_own_arithmetic_plain():
    # TERMT(A .AND. B) stops where the smaller of its two surfaces turns positive: the
    # AMIN1 the compiler puts there is the surface's arithmetic, no switch of its own
    model = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.1
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    Y = INTEG(2.0, 0.0)
    TERMT(X > 0.5 .AND. Y > 1.5)
  END
END
""", "p.csl")
    assert model.ir.switches == []
    run, = model.run(rtol=1e-10, atol=1e-12, advice=False)
    assert run.t_end == pytest.approx(0.75, abs=1e-12)


def test_bad_calls_are_located_errors():
    with pytest.raises(amilpy.AmilError) as err:
        amilpy.loads("X = INTGRL(0.0, DIM(X))\nTIMER FINTIM = 1.0\nEND\n", name="d.amil")
    text = err.value.render()
    assert "DIM takes 2 arguments, got 1" in text and "d.amil:1:" in text
    with pytest.raises(amilpy.AmilError) as err:
        amilpy.loads("X = INTGRL(0.0, AMAX1(X))\nTIMER FINTIM = 1.0\nEND\n", name="m.amil")
    assert "AMAX1 takes at least 2 arguments, got 1" in err.value.render()
    # AMOD(A, 0) divides by zero where it is evaluated (for the derivative of Z): the
    # run says where
    r = run1("X = INTGRL(1.0, 1.0)\nY = AMOD(X, 0.0)\nZ = INTGRL(0.0, Y)\n"
             "TIMER FINTIM = 1.0\nEND\n")
    assert r.status == "failed" and "AMOD(X, ...) at line 2" in r.message \
        and "division by zero" in r.message


# ------------------------------------------------------------ shipped models
def test_the_shipped_models_list_no_event_of_their_arithmetic():
    # the hoist's INSW(ABS(Y) - DH, ...), the diode's AMAX1 in its IMPL loop and the
    # wheat's AMAX1 of the day's temperatures are switches now, and none is ever an
    # event: ABS(Y) changes no derivative (it is followed through the gap's middle),
    # the diode current never reaches 0, the days are never below TBASE. Their values
    # are checked against references in test_models.py and test_examples.py.
    for path, count in (("models/hoist_backlash.amil", 222),
                        ("models/examples/csmp_diode_filter.amil", 0),
                        ("models/examples/fst_wheat.fst", 2)):
        model = amilpy.load(f"{ROOT}/{path}")
        assert any(sw.func in ("ABS", "AMAX1") for sw in model.ir.switches), path
        run, = model.run(advice=False)
        assert run.ok and len(run.events) == count, path
        assert not any(e.switch.startswith(("ABS", "AMAX1")) for e in run.events), path


def test_arithmetic_only_printed_is_not_an_event():
    """ABS in a printed formula changes nothing integrated: it is evaluated where it
    stands at each row (exact), makes no event and no restart, while the same ABS
    read by a derivative is located at each of its zeros (X = cos(2 pi t): 0.25, 0.75
    and 1.25). Neither form changes the states."""
    base = ("PARAM W = 6.283185307179586\nX = INTGRL(1.0, V)\nV = INTGRL(0.0, -W**2*X)\n"
            "A = ABS(X) + DIM(X, 0.5)\n{}TIMER FINTIM = 1.5, OUTDEL = 0.01\n"
            "PRINT X, A\nEND\n")
    printed = run1(base.format(""))
    t = printed["TIME"]
    x = np.cos(2 * np.pi * t)
    assert printed.events == []
    # the states to the default tolerance's global error (a few 1e-9 here)
    assert printed["X"] == pytest.approx(x, abs=1e-8)
    assert printed["A"] == pytest.approx(np.abs(x) + np.maximum(x - 0.5, 0.0), abs=1e-8)
    read = run1(base.format("Z = INTGRL(0.0, A)\n"))
    abs_times = [e.time for e in read.events if e.switch.startswith("ABS")]
    assert abs_times == pytest.approx([0.25, 0.75, 1.25], abs=1e-9)
    assert read["A"] == pytest.approx(printed["A"], abs=1e-8)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "COMPILED"])
def test_amod_of_a_large_dividend_is_the_exact_remainder(method):
    """AMOD(1E20, 7) printed 0: the switched form A - B*AINT(A/B) held at its branch
    rounds A - k*B to nothing when A is large. In the branch A/B is in it is fmod's
    exact remainder now (1E20 = 14285714285714285714*7 + 2: both exact in binary)
    on every route, the compiled one too (its numba form of the same function;
    without numba it runs as DOP853, which is then what is checked)."""
    run = run1("X = INTGRL(0.0, 1.0)\nY = AMOD(1.0E20, 7.0)\nZ = AMOD(X + 1.0E20, 7.0)\n"
               "W = AMOD(-1.0E20 - X, -7.0)\nTIMER FINTIM = 1.0, OUTDEL = 0.5\n"
               "PRINT Y, Z, W\nEND\n", method=method)
    assert run.ok
    assert list(run["Y"]) == list(run["Z"]) == [2.0] * 3
    assert list(run["W"]) == [-2.0] * 3 and math.fmod(1e20, 7.0) == 2.0


def test_amod_on_a_multiple_is_the_start_of_its_branch():
    """AMOD(Y, 0.1) where Y is a multiple of 0.1: Y/0.1 rounds onto the whole number
    (5.0 at Y = 0.5) the exact quotient is just below, and the switch has crossed to
    that branch, which starts at 0 -- fmod's exact 0.0999... belongs to the branch
    before. So the row shows 0, as A - B*AINT(A/B) does (and a large dividend keeps
    its exact remainder: the test above)."""
    run = run1("Y = INTGRL(0.0, 1.0)\nX = AMOD(Y, 0.1)\nTIMER FINTIM = 1.0, OUTDEL = 0.05\n"
               "PRINT X\nEND\n")
    x = dict(zip(np.round(run.t, 9).tolist(), run["X"].tolist(), strict=True))
    for t in (0.1, 0.2, 0.5, 0.9, 1.0):
        assert abs(x[t]) < 1e-15, (t, x[t])
    for t in (0.05, 0.45, 0.95):
        assert x[t] == pytest.approx(0.05, abs=1e-15)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "LSODA", "RADAU", "BDF",
                                    "COMPILED"])
@pytest.mark.parametrize("form", ["ACSL", "CSMP"])
def test_rsw_of_a_sliding_test_takes_filippovs_combination(method, form):
    """X' = 1 - 2 (X > 0.5) slides on X = 0.5 from t = 0.5 (the relay chatters; its
    Filippov value is 1/2). RSW(X > 0.5, 1, 0) is that test's value read through a
    switch of its own: it kept the side it had when the slide began and took 1 all
    along (Y2(3) = 2.5, hunt 53), where (X > 0.5)*1.0 gives Filippov's 1/2: Y = 1.25
    at 3. RSW's condition now takes its side in each branch of the slide. With a
    second RSW of another value of the test, Z' = RSW(X >= 0.5, -1, 1) + SIN(t)/2:
    1 before the slide, 0 on it: 0.5 + (1 - cos 3)/2 at 3. To 1e-9 (BDF, whose default
    RELERR is 1e-8: 1e-8; measured 3.7e-9)."""
    if form == "ACSL":
        text = ("PROGRAM r\n  CINTERVAL CINT = 0.5\n  DERIVATIVE\n"
                "    X = INTEG(1.0 - 2.0*(X > 0.5), 0.0)\n"
                "    Y1 = INTEG((X > 0.5)*1.0, 0.0)\n"
                "    Y2 = INTEG(RSW(X > 0.5, 1.0, 0.0), 0.0)\n"
                "    Z = INTEG(RSW(X >= 0.5, -1.0, 1.0) + 0.5*SIN(T), 0.0)\n"
                "    TERMT(T >= 3.0)\n  END\nEND\n")
        name = "r.csl"
    else:
        text = ("TITLE R\nDYNAMIC\n   X = INTGRL(0.0, 1.0 - 2.0*COMPAR(X, 0.5))\n"
                "   Y1 = INTGRL(0.0, COMPAR(X, 0.5))\n"
                "   Y2 = INTGRL(0.0, RSW(X > 0.5, 1.0, 0.0))\n"
                "   Z = INTGRL(0.0, RSW(X >= 0.5, -1.0, 1.0) + 0.5*SIN(TIME))\n"
                "TIMER FINTIM = 3.0, OUTDEL = 0.5\nEND\nSTOP\n")
        name = "r.amil"
    run, = amilpy.loads(text, name).run(method=method, advice=False)
    tol = 1e-8 if method == "BDF" else 1e-9
    assert run.final["X"] == pytest.approx(0.5, abs=tol)
    assert run.final["Y1"] == pytest.approx(1.25, abs=tol)
    assert run.final["Y2"] == pytest.approx(1.25, abs=tol)
    assert run.final["Z"] == pytest.approx(0.5 + (1.0 - math.cos(3.0)) / 2, abs=tol)
