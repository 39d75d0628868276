"""Runs and events of the ACSL form (contract section 11): SCHEDULE .AT. and
.XP./.XN./.XZ., DISCRETE sections that reset states, INTERVAL, TERMT located, the run's
length, and ALGORITHM ... XERROR mapped onto amilpy's routes. Each against a closed
form or an independent NumPy/SciPy computation."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import amilpy
from amilpy.diagnostics import AmilError

G, E, H0 = 9.81, 0.8, 10.0

BALL = f"""PROGRAM bouncing ball
  CONSTANT G = {G}, E = {E}, H0 = {H0}, TSTOP = 6.0
  CINTERVAL CINT = 0.25
  DERIVATIVE
    V = INTEG(-G, 0.0)
    H = INTEG(V, H0)
    SCHEDULE BOUNCE .XN. H       ! H goes from > 0 to <= 0: an impact
    TERMT(T >= TSTOP, 'time limit')
  END
  DISCRETE BOUNCE
    V = -E*V                     ! a reset of a state
    N = N + 1.0
  END
END
"""


def ball(t: np.ndarray) -> tuple[list[float], np.ndarray]:
    """Impact instants and the height at t, from the flight parabolas."""
    t1 = math.sqrt(2 * H0 / G)
    impacts, v = [t1], G * t1
    while impacts[-1] < t.max():
        v *= E
        impacts.append(impacts[-1] + 2 * v / G)
    h = np.where(t < t1, H0 - G * t**2 / 2, 0.0)
    v = G * t1
    for a, b in zip(impacts, impacts[1:], strict=False):
        v *= E
        s = t - a
        h = np.where((t >= a) & (t < b), v * s - G * s**2 / 2, h)
    return impacts, h


def test_bouncing_ball_by_schedule_xn_impact_times_and_heights():
    run, = amilpy.loads(BALL, "ball.csl").run(rtol=1e-10, atol=1e-12)
    impacts, h = ball(run.t)
    ran = [e.time for e in run.events if e.kind == "discrete"]
    # each impact located to the solver's tolerance (rtol 1e-10: ~1e-9 s over 6 s)
    assert len(ran) == 3
    assert np.max(np.abs(np.array(ran) - impacts[:3])) < 1e-8
    assert np.max(np.abs(run["H"] - h)) < 1e-8
    assert run["N"][-1] == 3.0  # a name only the DISCRETE assigns, kept between events


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU"])
@pytest.mark.parametrize("cint", [0.05, 1.5])
def test_a_crossing_either_way_does_not_run_again_as_the_code_sends_it_back(method, cint):
    """.XZ. runs its section where H goes from > 0 to <= 0 or from < 0 to >= 0. At an
    impact the section reverses V and H leaves zero upwards: from 0, which is no
    crossing. It was taken as one (the motion crossing as the code ran), the
    section ran again on the spot, 3,109 times, and the ball fell through the floor
    (H(6) = -102.5): now the .XN. ball's impacts and events, on every route and grid."""
    text = BALL.replace(".XN. H ", ".XZ. H ").replace("CINT = 0.25", f"CINT = {cint}")
    run, = amilpy.loads(text, "ball.csl").run(method=method, advice=False)
    impacts, h = ball(run.t)
    ran = [e.time for e in run.events if e.kind == "discrete"]
    assert ran == pytest.approx(impacts[:3], abs=1e-8)
    assert run["H"] == pytest.approx(h, abs=1e-7)
    assert run["N"][-1] == 3.0
    xn, = amilpy.loads(BALL.replace("CINT = 0.25", f"CINT = {cint}"), "ball.csl").run(
        method=method, advice=False)
    assert [(e.kind, e.old, e.new) for e in run.events] == \
        [(e.kind, e.old, e.new) for e in xn.events]


def test_a_toggle_on_a_crossing_either_way_flips_once():
    """X' = -X + 10 H, H = 1 - H when X - 2.5 crosses either way (.XZ.): from X = 0 with
    H = 1, X reaches 2.5 at ln(4/3), H = 0, and X decays from there, leaving the
    surface downwards -- from zero, no crossing. The run used to flip H back and
    forth at that instant until its event limit (it never returned by default)."""
    text = """PROGRAM toggle
  CONSTANT TSTOP = 3.0
  CINTERVAL CINT = 0.1
  INITIAL
    H = 1.0
  END
  DERIVATIVE
    X = INTEG(-X + 10.0*H, 0.0)
    SCHEDULE FLIP .XZ. X - 2.5
    TERMT(T >= TSTOP)
  END
  DISCRETE FLIP
    H = 1.0 - H
    N = N + 1.0
  END
END
"""
    for method in ("AUTO", "RKS", "RADAU"):
        run, = amilpy.loads(text, "toggle.csl").run(method=method, advice=False)
        assert run["N"][-1] == 1.0
        t1 = math.log(4 / 3)
        assert run["X"][-1] == pytest.approx(2.5 * math.exp(-(3.0 - t1)), abs=1e-8)


def test_bouncing_ball_as_written_to_the_integration_tolerance():
    run, = amilpy.loads(BALL, "ball.csl").run()
    _, h = ball(run.t)
    assert np.max(np.abs(run["H"] - h)) < 1e-4 * H0  # RELERR 1e-6 per step


DOSING = """PROGRAM repeated dosing
  CONSTANT KA = 1.2, KE = 0.25, DOSE = 100.0, TAU = 12.0, TSTOP = 60.0
  CINTERVAL CINT = 0.5
  DERIVATIVE
    AG = INTEG(-KA*AG, 0.0)           ! gut
    AC = INTEG(KA*AG - KE*AC, 0.0)    ! central
    TERMT(T >= TSTOP, 'end of study')
  END
  DISCRETE DOSING
    INTERVAL EVERY = 12.0
    IF (T < 48.0) THEN
      AG = AG + DOSE
    END IF
  END
END
"""


def test_repeated_dosing_by_interval_is_the_superposition_of_single_doses():
    run, = amilpy.loads(DOSING, "dosing.csl").run(rtol=1e-10, atol=1e-12)
    t = run.t
    ka, ke, dose = 1.2, 0.25, 100.0
    ac = np.zeros_like(t)
    for td in (0.0, 12.0, 24.0, 36.0):  # INTERVAL runs at t0 and every 12 h; none at 48
        s = np.clip(t - td, 0.0, None)
        ac += dose * ka / (ka - ke) * (np.exp(-ke * s) - np.exp(-ka * s))
    assert np.max(np.abs(run["AC"] - ac)) < 1e-8 * np.max(ac)
    # the row at a dose instant shows the dose given (events before the row)
    i = int(np.flatnonzero(t == 12.0)[0])
    assert run["AG"][i] - run["AG"][i - 1] > 0.9 * dose
    assert [e.time for e in run.events if e.kind == "discrete"] == [0, 12, 24, 36, 48, 60]


def test_an_interval_of_zero_stops_the_section():
    run, = amilpy.loads("""PROGRAM p
  DERIVATIVE
    X = INTEG(0.0, 0.0)
    TERMT(T >= 10.0)
  END
  DISCRETE TICK
    INTERVAL GAP = 1.0
    X = X + 1.0
    IF (X >= 3.0) GAP = 0.0
  END
END
""", "p.csl").run()
    assert run["X"][-1] == 3.0


def test_schedule_at_and_sections_that_schedule_each_other():
    # A8 (diazepam): on for 1, off for 2, repeated
    run, = amilpy.loads("""PROGRAM pulses
  INITIAL
    RATE = 0.0
    SCHEDULE ON .AT. 0.0
  END
  DERIVATIVE
    X = INTEG(RATE, 0.0)
    TERMT(T >= 7.5)
  END
  DISCRETE ON
    RATE = 1.0
    SCHEDULE OFF AT T + 1.0
  END
  DISCRETE OFF
    RATE = 0.0
    SCHEDULE ON .AT. T + 2.0
  END
END
""", "p.csl").run()
    # on during [0,1], [3,4], [6,7]
    assert run["X"][-1] == pytest.approx(3.0, rel=1e-9)
    assert [e.time for e in run.events if e.kind == "discrete"] == [0, 1, 3, 4, 6, 7]


def test_schedule_xp_and_xz():
    text = """PROGRAM p
  CINTERVAL CINT = 0.5
  DERIVATIVE
    S = INTEG(C, 0.0)
    C = INTEG(-S, 1.0)          ! S = sin t, C = cos t
    SCHEDULE UP .XP. S
    SCHEDULE ANY .XZ. C
    TERMT(T >= 7.0)
  END
  DISCRETE UP
    NUP = NUP + 1.0
    TUP = T
  END
  DISCRETE ANY
    NANY = NANY + 1.0
  END
END
"""
    run, = amilpy.loads(text, "p.csl").run(rtol=1e-10, atol=1e-12)
    # S crosses upward at 2 pi only (never at t0); C crosses at pi/2 and 3 pi/2
    assert run["NUP"][-1] == 1.0 and run["TUP"][-1] == pytest.approx(2 * math.pi, abs=1e-8)
    assert run["NANY"][-1] == 2.0


def test_schedule_in_the_past_is_an_error():
    run, = amilpy.loads("""PROGRAM p
  INITIAL
    SCHEDULE LATE .AT. 1.0
  END
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    TERMT(T >= 3.0)
  END
  DISCRETE LATE
    SCHEDULE LATE .AT. T - 0.5
  END
END
""", "p.csl").run()
    assert run.status == "failed" and "before the present time" in run.message


def test_termt_on_a_state_is_located_to_1e_9():
    run, = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.1
  DERIVATIVE
    X = INTEG(X, 1.0)            ! X = exp(t)
    TERMT(X >= 3.0, 'X reached 3')
  END
END
""", "p.csl").run(rtol=1e-11, atol=1e-14)
    assert abs(run.t_end - math.log(3.0)) < 1e-9
    assert run["X"][-1] == pytest.approx(3.0, abs=1e-9)
    assert run.message.startswith("stopped at TIME = 1.09861229: X reached 3")


def test_termt_in_dynamic_is_tested_at_the_cint_instants_and_in_discrete_when_it_runs():
    text = """PROGRAM p
  CINTERVAL CINT = 0.5
  DYNAMIC
    DERIVATIVE
      X = INTEG(1.0, 0.0)
    END
    TERMT(X >= 1.2, 'from DYNAMIC')
  END
END
"""
    run, = amilpy.loads(text, "p.csl").run()
    assert run.t_end == 1.5 and "from DYNAMIC (TERMT(X >= 1.2) at line 7)" in run.message
    run, = amilpy.loads(text.replace("    TERMT(X >= 1.2, 'from DYNAMIC')\n", "").replace(
        "  END\nEND\n", "  END\n  DISCRETE D\n    INTERVAL DT = 0.7\n"
        "    TERMT(X > 1.0, 'from DISCRETE')\n  END\nEND\n"), "p.csl").run()
    assert run.t_end == pytest.approx(1.4) and "from DISCRETE" in run.message


def test_termt_true_at_t0_stops_at_t0():
    run, = amilpy.loads("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 5.0)\nTERMT(X > 1.0)\n"
                        "END\nEND\n", "p.csl").run()
    assert run.status == "stopped" and run.t_end == 0.0 and len(run.t) == 1


def test_a_run_that_nothing_ends_stops_with_an_error(monkeypatch):
    import amilpy.run.acsl as acsl

    monkeypatch.setattr(acsl, "MAX_INTERVALS", 40)  # 10**6 in earnest
    run, = amilpy.loads("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nTERMT(X < -1.0)\n"
                        "END\nEND\n", "p.csl").run()
    assert run.status == "failed" and "no TERMT ended the run within 40 output" in run.message


def exact_rk4(f, y0, h, n):
    y = np.array(y0, float)
    for k in range(n):
        t = k * h
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y


def test_algorithm_nsteps_maxterval_give_the_fixed_step():
    # IALG 5 is RK4; DELT = min(MAXT, CINT/NSTP) = 0.1 (A11 uses the same three)
    text = """PROGRAM p
  ALGORITHM IALG = 5
  NSTEPS NSTP = 4
  MAXTERVAL MAXT = 0.2
  CINTERVAL CINT = 0.4
  DERIVATIVE
    X = INTEG(-X*X + SIN(T), 1.0)
    TERMT(T >= 2.0)
  END
END
"""
    run, = amilpy.loads(text, "p.csl").run()
    assert run.method == "RK4" and run.settings == "DELT 0.1"
    want = exact_rk4(lambda t, y: np.array([-y[0] ** 2 + math.sin(t)]), [1.0], 0.1, 20)
    assert run["X"][-1] == pytest.approx(want[0], abs=1e-13)
    assert run.constants["IALG"] == 5.0  # the names are constants the listing may read


@pytest.mark.parametrize("ialg, method", [(1, "LSODA"), (2, "BDF"), (3, "RECT"),
                                          (4, "TRAPZ"), (8, "RKS"), (10, "BDF")])
def test_each_algorithm_number_maps_to_a_route(ialg, method):
    run, = amilpy.loads(f"PROGRAM p\nALGORITHM IALG = {ialg}\nDERIVATIVE\n"
                        "X = INTEG(-X, 1.0)\nTERMT(T >= 1.0)\nEND\nEND\n", "p.csl").run()
    assert run.method == method


def test_an_unknown_algorithm_is_an_error():
    with pytest.raises(AmilError) as err:
        amilpy.loads("PROGRAM p\nALGORITHM IALG = 6\nDERIVATIVE\nX = INTEG(-X, 1.0)\n"
                     "TERMT(T >= 1.0)\nEND\nEND\n", "p.csl").run()
    d = err.value.diagnostics[0]
    assert "ALGORITHM IALG = 6" in d.message and d.span.line == 2 and "5 (RK4)" in d.hint


def test_merror_xerror_are_tolerances_per_state_or_for_all():
    run, = amilpy.loads("""PROGRAM p
  MERROR X = 1.0E-9
  XERROR ALL = 1.0E-12
  MINTERVAL MINT = 1.0E-9
  MAXTERVAL MAXT = 0.05
  DERIVATIVE
    X = INTEG(-X, 1.0)
    Y = INTEG(X, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run()
    # (RELERR: the ACSL form's default for the states not named)
    assert "RELERR 1e-11 (X 1e-09), ABSERR 1e-12" == run.settings
    assert run["X"][-1] == pytest.approx(math.exp(-1.0), rel=1e-8)


def test_dense_pbpk_like_run_matches_a_tight_scipy_solve():
    # DISCRETE infusion on [0, 0.5] into a two-compartment model, rows every 0.1
    run, = amilpy.loads("""MODEL infusion
  INITIAL
    CONSTANT K10 = 0.8, K12 = 1.5, K21 = 0.4, R0 = 10.0, TSTOP = 5.0
    CINTERVAL CINT = 0.1
    R = 0.0
    SCHEDULE START .AT. 0.0
  END
  DERIVATIVE
    C1 = INTEG(R - (K10 + K12)*C1 + K21*C2, 0.0)
    C2 = INTEG(K12*C1 - K21*C2, 0.0)
    TERMT(T >= TSTOP)
  END
  DISCRETE START
    R = R0
    SCHEDULE STOP .AT. T + 0.5
  END
  DISCRETE STOP
    R = 0.0
  END
END
""", "inf.csl").run(rtol=1e-10, atol=1e-12)

    def f(t, y, r):
        return [r - 2.3 * y[0] + 0.4 * y[1], 1.5 * y[0] - 0.4 * y[1]]

    a = solve_ivp(f, (0, 0.5), [0, 0], args=(10.0,), rtol=1e-12, atol=1e-14, method="DOP853",
                  t_eval=run.t[run.t <= 0.5], max_step=0.1)
    b = solve_ivp(f, (0.5, 5.0), a.y[:, -1], args=(0.0,), rtol=1e-12, atol=1e-14,
                  method="DOP853", t_eval=run.t[run.t > 0.5], max_step=0.1)
    want = np.hstack([a.y, b.y])
    assert np.max(np.abs(want[0] - run["C1"])) < 1e-9


def test_same_time_entries_run_in_the_order_they_were_scheduled():
    # LOG records the order: B was scheduled before A, both for t = 1; A schedules C
    # at its own instant (e = T runs at once, after the current code)
    run, = amilpy.loads("""PROGRAM p
  INITIAL
    LOG = 0.0
    SCHEDULE B .AT. 1.0
    SCHEDULE A .AT. 1.0
  END
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    TERMT(T >= 2.0)
  END
  DISCRETE A
    LOG = 10.0*LOG + 1.0
    SCHEDULE C .AT. T
  END
  DISCRETE B
    LOG = 10.0*LOG + 2.0
  END
  DISCRETE C
    LOG = 10.0*LOG + 3.0
  END
END
""", "p.csl").run()
    assert run["LOG"][-1] == 213.0


JUMP = """PROGRAM a schedule on a condition that jumps to zero
  CONSTANT TSTOP = 3.0, X1 = 1.3
  CINTERVAL CINT = 0.25
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    F = RSW(X > X1, 1.0, 0.0)
    Y = INTEG(K, 0.0)
    SCHEDULE ON .XN. 1.0 - F
    SCHEDULE UP .XP. F - 1.0
    Z = INTEG(K2, 0.0)
    TERMT(T >= TSTOP)
  END
  DISCRETE ON
    K = 1.0
  END
  DISCRETE UP
    K2 = 2.0
  END
END
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853"])
def test_a_schedule_whose_condition_jumps_to_zero_runs_its_section(method):
    """1 - RSW(X > X1, 1, 0) is 1, then 0 from where X = t crosses X1: it reaches zero
    by a jump, at the restart of the RSW's own crossing. It was listed as crossed but
    its DISCRETE never ran (Y stayed 0); now K = 1 from t = X1, and Y = t - X1."""
    run, = amilpy.loads(JUMP, "jump.csl").run(method=method, advice=False)
    assert [e.time for e in run.events if e.kind == "discrete"] == pytest.approx(
        [1.3, 1.3], abs=1e-12)  # (both sections: only one of two ran when they coincided)
    assert run["Y"] == pytest.approx(np.maximum(run.t - 1.3, 0.0), abs=1e-10)
    assert run["Z"] == pytest.approx(2.0 * np.maximum(run.t - 1.3, 0.0), abs=1e-10)


def test_in_step_point_mode_a_schedule_crossing_runs_its_section_at_the_point():
    """ALGORITHM IALG = 3 reads the SCHEDULE's condition at the step points (h = 0.25):
    1 - X reaches zero at the point t = 1 (X = t exactly there), where DISCRETE ON
    runs before the row; the Euler step from it takes K = 1: Y(t) = t - 1 from there.
    Before, the crossing was listed and the section never ran."""
    text = JUMP.replace("1.0 - F", "1.0 - X").replace(
        "CINTERVAL CINT = 0.25", "CINTERVAL CINT = 0.25\n  ALGORITHM IALG = 3\n"
        "  NSTEPS NSTP = 1")
    run, = amilpy.loads(text, "jump.csl").run(advice=False)
    assert run.method == "RECT"  # (UP: where F - 1 reaches zero, the point X > 1.3)
    assert [e.time for e in run.events if e.kind == "discrete"] == [1.0, 1.5]
    assert run["Y"] == pytest.approx(np.maximum(run.t - 1.0, 0.0), abs=1e-14)


@pytest.mark.parametrize("ialg", ["", "  ALGORITHM IALG = 3\n"])
def test_a_termt_a_discrete_section_makes_true_stops_the_run_there(ialg):
    """TERMT(N >= 2.0) with N counted by a DISCRETE every second: the section that
    makes N 2 (at t = 2) ends the run there (it went on to t = 3: N - 2 = 0 was not
    taken as holding, though >= holds at zero)."""
    text = ("PROGRAM P\n  CONSTANT TSTOP = 5.0\n  CINTERVAL CINT = 0.5\n" + ialg +
            "  DERIVATIVE\n    X = INTEG(1.0, 0.0)\n    TERMT(N >= 2.0)\n"
            "    SCHEDULE TICK .XP. X - 1.0\n    TERMT(T >= TSTOP)\n  END\n"
            "  DISCRETE TICK\n    N = N + 1.0\n    X = 0.0\n  END\nEND\n")
    run, = amilpy.loads(text, "termt.csl").run(advice=False)
    assert run.t_end == pytest.approx(2.0, abs=1e-9) and "N >= 2.0" in run.message


def test_a_set_point_the_code_moves_ends_the_slide_on_it():
    """X slides on X = XSET (X' = 3 - 0.6 X below it, -1.5 - 0.6 X above); a DISCRETE
    section moves XSET to 1 + 0.3 sin(X) at 0.7 s: X leaves the old set point, rises
    (about 0.1 s) and slides on the new one. Until 2026-11-30 the run kept sliding
    at X = 1.0, off the surface, for the rest of the run."""
    text = """PROGRAM set point moved by code
  CONSTANT K = 0.6, Q = 3.0, XS0 = 1.0, A = 0.3
  CINTERVAL CINT = 0.5
  INITIAL
    XSET = XS0
  END
  DERIVATIVE
    X = INTEG(Q*FSW(X - XSET, 1.0, 0.0, -0.5) - K*X, 0.0)
    TERMT(T >= 1.5)
  END
  DISCRETE SAMPLE
    INTERVAL DT = 0.7
    XSET = XS0 + A*SIN(X)
  END
END
"""
    run, = amilpy.loads(text, "p.csl").run(advice=False)
    at = {round(t, 9): x for t, x in zip(run.t, run.values["X"], strict=True)}
    assert at[0.5] == pytest.approx(1.0, abs=1e-9)
    assert at[1.0] == pytest.approx(1.0 + 0.3 * math.sin(1.0), abs=1e-9)


def test_a_crossing_at_a_discrete_instant_runs_its_section():
    """The ball (G = 2, H0 = 1) lands exactly at T = 1, where an unrelated INTERVAL
    section is due: BOUNCE still runs there (bounces at 1, 2, 2.5, ...). Until
    review 48 the restart after COUNT's code read H = 0 as already crossed, and the
    ball fell through the floor (H(1.9) = -2.61 for 0.09)."""
    text = """PROGRAM ball
  CONSTANT G = 2.0, E = 0.5
  CINTERVAL CINT = 0.1
  DERIVATIVE
    V = INTEG(-G, 0.0)
    H = INTEG(V, 1.0)
    SCHEDULE BOUNCE .XN. H
    TERMT(T >= 1.9)
  END
  DISCRETE BOUNCE
    V = -E*V
  END
  DISCRETE COUNT
    INTERVAL DK = 1.0
    N = N + 1.0
  END
END
"""
    for method in ("AUTO", "RKS"):
        run, = amilpy.loads(text, "ball.csl").run(advice=False, method=method)
        assert run.values["H"][-1] == pytest.approx(0.09, abs=1e-9), method
        bounces = [e.time for e in run.events if e.switch == "DISCRETE BOUNCE"]
        assert bounces[:1] == pytest.approx([1.0], abs=1e-12), method


def test_a_zeno_point_at_an_interval_instant_fails_there_in_words():
    """The bouncing ball's bounces accumulate at T = 3, where an INTERVAL section is
    due too: the run ends there, saying so in words (it said "cannot reshape array of
    size 0 into shape (0,newaxis)", numpy's words for an empty evaluation log)."""
    text = """PROGRAM ball
  CONSTANT G = 2.0, E = 0.5, TSTOP = 4.0
  CINTERVAL CINT = 0.25
  DERIVATIVE
    V = INTEG(-G, 0.0)
    H = INTEG(V, 1.0)
    SCHEDULE BOUNCE .XN. H
    TERMT(T >= TSTOP)
  END
  DISCRETE BOUNCE
    V = -E*V
  END
  DISCRETE KICK
    INTERVAL DK = 1.0
    N = N + 1.0
  END
END
"""
    run, = amilpy.loads(text, "ball.csl").run(advice=False)
    assert run.status == "failed" and "TIME = 3" in run.message
    assert "reshape" not in run.message and "array" not in run.message


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU"])
def test_cint_a_section_changes_gives_rows_on_the_new_grid_from_the_integration(method):
    """CINT = 0.2 assigned at T = 1 (from 0.5): rows at 1.2, 1.4, ... of X = INTEG(COS(T))
    = sin t. On AUTO the chunk integrated to the old 0.5 grid was resumed, and the new
    rows read off its interpolant across an old interval: 1.5e-4 off at 1.8 (hunt 49).
    Now every row to the tolerance."""
    text = """PROGRAM cint change
  CONSTANT TSTOP = 3.0
  CINTERVAL CINT = 0.5
  INITIAL
    SCHEDULE FINE .AT. 1.0
  END
  DERIVATIVE
    X = INTEG(COS(T), 0.0)
    TERMT(T >= TSTOP)
  END
  DISCRETE FINE
    CINT = 0.2
  END
END
"""
    run, = amilpy.loads(text, "cint.csl").run(method=method, advice=False)
    assert run.t == pytest.approx([0.0, 0.5, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0, 2.2, 2.4, 2.6,
                                   2.8, 3.0], abs=1e-12)
    assert run["X"] == pytest.approx(np.sin(run.t), abs=1e-9)


@pytest.mark.parametrize("method", ["AUTO", "LSODA", "RKS", "BDF", "DOP853"])
def test_a_row_at_an_impact_shows_the_values_after_it(method):
    """H = 4.905 - 9.81 t^2/2 lands at t = 1, then (E = 0.5) at 2: both CINT instants.
    Located a few ulps past the instant, the impact's row had been taken before its
    code on AUTO (V = -9.81 and -4.905, hunt 53) and at 2 on LSODA; a row at an
    instant shows the values after the instant's code: V = 4.905 and 2.4525."""
    run, = amilpy.loads("""PROGRAM ball
  CONSTANT G = 9.81, E = 0.5, H0 = 4.905
  CINTERVAL CINT = 0.5
  DERIVATIVE
    V = INTEG(-G, 0.0)
    H = INTEG(V, H0)
    SCHEDULE BOUNCE .XN. H
    TERMT(T >= 2.1)
  END
  DISCRETE BOUNCE
    V = -E*V
  END
END
""", "ball.csl").run(method=method, advice=False)
    t, v = np.asarray(run.t), np.asarray(run["V"])
    assert v[np.isclose(t, 1.0)] == pytest.approx([4.905], abs=1e-7)
    assert v[np.isclose(t, 2.0)] == pytest.approx([2.4525], abs=1e-7)
