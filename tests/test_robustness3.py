"""Robustness round 3 (issue 30): one test per defect found again by a probe of the
campaign's classes on this code (tracebacks, hangs, lost results, misleading
messages). Each listing is the smallest that showed it; each test says what was
wrong and checks what a user gets now against an independent value where there
is one."""

from __future__ import annotations

import math
import signal

import numpy as np
import pytest
from conftest import run1

import amilpy
from amilpy import interrupts
from amilpy.cli import main
from amilpy.diagnostics import AmilError


def _run(tmp_path, text: str, *args: str, name: str = "m.amil") -> int:
    path = tmp_path / name
    path.write_text(text)
    return main(["run", str(path), "--quiet", *args])


# ------------------------------------------------------------------ tracebacks

VDP_RELAY = """TITLE stiff Van der Pol with a relay on X
PARAM MU = 1000.0
X = INTGRL(2.0, V)
V = INTGRL(0.0, MU*(1.0 - X*X)*V - X + R)
R = FSW(X, -0.5, 0.0, 0.5)
TIMER FINTIM = 3000.0, OUTDEL = 100.0
PRINT X, V, R
END
"""


def test_a_crossing_in_the_lsoda_fallback_is_located():
    """AUTO's odeint gave up on this stiff relay and SciPy's LSODA class took over;
    locating the next crossing asked that solver's dense output for nodes it does
    not have (AttributeError: 'LsodaDenseOutput' object has no attribute 'insert').
    The crossings agree with RADAU at 1e-10 to 1e-6 s (the default tolerance is
    1e-6 relative on states of size 2 over a slow relaxation)."""
    auto = run1(VDP_RELAY)
    reference = run1(VDP_RELAY, method="RADAU", rtol=1e-10, atol=1e-12)
    assert auto.ok and [e.new for e in auto.events] == [e.new for e in reference.events]
    assert len(auto.events) == 2
    for a, b in zip(auto.events, reference.events, strict=True):
        assert abs(a.time - b.time) < 1e-6 * b.time


def test_termt_in_an_acsl_function_is_refused_where_it_stands(tmp_path, capsys):
    """A TERMT in a FUNCTION's body reached generated code with no run to end
    (NameError); it is refused at its line, saying where it belongs."""
    code = _run(tmp_path, "PROGRAM P\n  FUNCTION S = F(X)\n    S = 2.0*X\n"
                "    TERMT(X .GT. 1.0)\n  END\n  DERIVATIVE\n    X = INTEG(1.0, 0.0)\n"
                "    Y = F(X)\n    TERMT(T .GE. 3.0)\n  END\nEND\n")
    err = capsys.readouterr().err
    assert code == 1 and "4:5: error: TERMT cannot stand in FUNCTION F" in err
    assert "where the FUNCTION is called" in err and "Traceback" not in err


def test_a_literal_division_by_zero_names_its_line():
    """`Y = 1/0` ended the checker with ZeroDivisionError (while writing its note on
    whole-number division); now the run says which line divides by zero."""
    run = run1("X = INTGRL(0.0, 1.0)\nY = 1/0\nTIMER FINTIM = 1.0, OUTDEL = 0.5\n"
               "PRINT X, Y\nEND\n")
    assert run.ok and any("Y (line 2): division by zero: 1/0 at TIME = 0" in w
                          for w in run.warnings)


@pytest.mark.parametrize("method", ["AUTO", "COMPILED", "RKS", "RK4"])
def test_a_fault_in_a_variable_the_derivatives_do_not_read_keeps_the_states(method):
    """Q = 1/Z with Z = 0, read by nothing the integration needs: RKS showed Q as NaN
    and said nothing, AUTO and COMPILED (outputs over many rows at once) failed the
    run at TIME = 0 with Python's bare words and kept no state. On every route now
    the run goes on, X is exp(-t) (to 1e-8, the default tolerances), Q is NaN, and
    one note names the statement."""
    run = run1("PARAM Z = 0.0\nX = INTGRL(1.0, -X)\nQ = 1.0/Z\n"
               "TIMER FINTIM = 1.0, OUTDEL = 0.5\nPRINT X, Q\nEND\n", method=method)
    assert run.ok and list(run.t) == [0.0, 0.5, 1.0]
    assert np.allclose(run["X"], np.exp(-run.t), rtol=1e-8 if method != "RK4" else 1e-5)
    assert np.isnan(run["Q"]).all()
    assert [w for w in run.warnings if "Q (line 3): division by zero: Z = 0" in w]


@pytest.mark.parametrize("method", ["AUTO", "RKS"])
def test_a_fault_in_one_output_leaves_the_others(method):
    """DN = DELAY(10, -1.0, X) cannot be computed (a negative delay): X = SIN(TIME),
    which DN reads and nothing reads from DN, was NaN in every row with it, and the
    run said nothing. Now only DN is NaN, and a note names its statement."""
    run = run1("X = SIN(TIME)\nY = INTGRL(0.0, 1.0)\nDN = DELAY(10, -1.0, X)\n"
               "TIMER FINTIM = 2.0, OUTDEL = 0.5\nPRINT X, Y, DN\nEND\n", method=method)
    assert run.ok and np.allclose(run["X"], np.sin(run.t), rtol=0, atol=1e-15)
    assert np.allclose(run["Y"], run.t) and np.isnan(run["DN"]).all()
    assert [w for w in run.warnings if w.startswith(
        "DN (line 3): the delay must not be negative (got -1 at TIME = 0)")]


def test_a_function_of_one_argument_says_argument(tmp_path, capsys):
    code = _run(tmp_path, "PROGRAM P\n  FUNCTION S = F(X)\n    S = 2.0*X\n  END\n"
                "  DERIVATIVE\n    X = INTEG(1.0, 0.0)\n    Y = F(X, X)\n"
                "    TERMT(T .GE. 1.0)\n  END\nEND\n")
    err = capsys.readouterr().err
    assert code == 1 and "FUNCTION F takes 1 argument, got 2" in err


FAR_WEATHER = """TITLE WEATHER FAR FROM THE FILE'S DAYS
WEATHER CNTR = 'NLD'; ISTN = 1; IYEAR = {year}
TIMER STTIME = {start}; FINTIM = 10.; DELT = 1.; PRDEL = 5.
TRANSLATION_GENERAL DRIVER = 'EUDRIV'
W = INTGRL(0., RDD*1.E-6)
PRINT W, RDD
END
STOP
"""


def test_an_infinite_weather_year_is_an_error_not_a_traceback(tmp_path, capsys):
    """IYEAR = 1.0E400 (infinite) ended the checker with OverflowError."""
    code = _run(tmp_path, FAR_WEATHER.format(year="1.0E400", start="1."), name="w.fst")
    err = capsys.readouterr().err
    assert code == 1 and "IYEAR must be a whole number from 1 to 9999" in err


def test_weather_days_far_from_the_file_are_found_at_once():
    """STTIME = 1E15 days walked the calendar one year at a time (3E12 turns: a
    hang). The day and year now come from whole 400-year cycles first; they are
    those of the year-by-year walk (done here for days up to 1E6)."""
    from amilpy.library.weather import Weather, WeatherSpec, days_in

    weather = Weather(WeatherSpec("NLD", 1, 1990), ".")

    def walk(t: float) -> tuple[int, int]:
        year, day = 1990, math.floor(t)
        while day > days_in(year):
            day -= days_in(year)
            year += 1
        while day < 1:
            year -= 1
            day += days_in(year)
        return year, day

    for t in (1.0, 365.5, 366.0, 146_097.0, 146_098.0, 999_999.9, 0.5, -146_097.0, -5.0):
        assert weather.locate(t) == walk(t), t
    year, day = weather.locate(1e15)
    assert 1 <= day <= days_in(year) and year > 2.7e12


def test_an_analysis_over_an_absurd_time_says_so(tmp_path, capsys):
    """--settle 1e300 asked NumPy for an array of 1E301 check instants (ValueError:
    Maximum allowed size exceeded); now a message says what to change."""
    path = tmp_path / "osc.amil"
    path.write_text("PARAM W = 1.0\nX = INTGRL(0.0, V)\nV = INTGRL(0.0, COS(W*TIME) - 0.1*V - X)\n"
                    "TIMER FINTIM = 10.0, OUTDEL = 0.1\nOUTPUT X\nEND\n")
    for args in (["periodic", "--period", "6.283185307", "--settle", "1e300"],
                 ["modes", "--at", "1e300"]):
        code = main([args[0], str(path), *args[1:]])
        err = capsys.readouterr().err
        assert code == 1 and "more than the 1e+08 an analysis looks at" in err, args


def test_a_plot_of_the_largest_floats_is_drawn_in_units_of_a_power_of_ten(tmp_path):
    """Values of +-1.7E308 made matplotlib's tick arithmetic overflow (ValueError:
    arange: cannot compute length); the axis is now drawn in units of 1E308."""
    from amilpy.output.plot import draw, figure_specs

    run = run1("X = INTGRL(1.7E308, 0.0)\nY = INTGRL(-1.7E308, 0.0)\n"
               "TIMER FINTIM = 1.0, OUTDEL = 0.1\nOUTPUT X, Y\nEND\n")
    fig = draw([run], figure_specs(run)[0])
    ax = fig.axes[0]
    assert ax.get_ylabel().endswith("(x 1E308)")
    lo, hi = ax.get_ylim()
    assert lo < -1.69 and hi > 1.69 and hi < 2.0
    assert _run(tmp_path, "X = INTGRL(1.7E308, 0.0)\nY = INTGRL(-1.7E308, 0.0)\n"
                "TIMER FINTIM = 1.0, OUTDEL = 0.1\nOUTPUT X, Y\nEND\n", "--plot",
                "--out", str(tmp_path)) == 0
    assert (tmp_path / "m.png").read_bytes().startswith(b"\x89PNG")


# -------------------------------------------------------------- messages

def test_the_row_limit_message_knows_the_listing_has_a_termt(tmp_path, capsys):
    """A TERMT at TIME 1E12 with CINT 1E-3 reaches the row limit first: the message
    said to add a TERMT, which the listing has."""
    code = _run(tmp_path, "PROGRAM P\n  CONSTANT TSTP = 1.0E12\n  CINTERVAL CINT = 1.0E-3\n"
                "  DERIVATIVE\n    X = INTEG(1.0, 0.0)\n    TERMT(T .GE. TSTP)\n  END\n"
                "  PRINT X\nEND\n")
    err = capsys.readouterr().err
    assert code == 3 and "make CINT longer, or its TERMT come sooner" in err
    assert "add TERMT" not in err


# -------------------------------------------------------- interrupted analyses

SWEEP = """PARAM W = 1.0
X = INTGRL(0.0, V)
V = INTGRL(0.0, COS(W*TIME) - 0.1*V - X)
TIMER FINTIM = 5.0, OUTDEL = 0.05
OUTPUT X
END
"""


@pytest.fixture
def _clear_interrupt():
    yield
    interrupts.handled()


def test_an_interrupted_sweep_stops_and_keeps_its_points(_clear_interrupt):
    """Ctrl-C during a sweep ended the point under way and the sweep went on to its
    last point. Now the points before are kept, the one under way is partial, and
    the rest are said to be not run (a swallowed interrupt stands in for the
    signal: it ends the first point at its first look)."""
    model = amilpy.loads(SWEEP)
    interrupts.arrived(signal.SIGINT)
    result = model.sweep("W", [0.5, 1.0, 1.5, 2.0], measure="X")
    assert len(result.points) == 1 and result.points[0].status == "failed"
    assert result.errors == ["interrupted: W = 1 to W = 2 (3 points) not run"]
    assert [p.value for p in model.sweep("W", [0.5, 1.0], measure="X").points] == [0.5, 1.0]


def test_an_interrupted_response_keeps_the_curve_so_far():
    """Ctrl-C during `response` lost every orbit found; now the curve so far is the
    result, marked interrupted (here the interrupt comes from the progress line
    after the third point)."""
    model = amilpy.loads(SWEEP.replace("FINTIM = 5.0", "FINTIM = 30.0"))
    seen = []

    def progress(report):
        seen.append(report.facts["value"])
        if report.done >= 3:
            raise KeyboardInterrupt

    resp = model.response("W", 0.5, 1.5, period="2*PI/W", progress=progress)
    assert resp.interrupted and not resp.complete
    assert len(resp.points) == 3 and resp.points[-1].value == pytest.approx(seen[-1])
    assert np.all(np.diff([p.value for p in resp.points]) > 0)


def test_a_response_past_its_time_limit_keeps_the_curve_so_far():
    """`response` had no time limit: a slow curve could only be killed, and its
    points were lost (the fuzzing's "hangs"). `max_time` ends it like Ctrl-C: the
    points so far are the result, marked as stopped by the limit. (The limit's
    signal stands in here as the progress line after the third point raising what
    the alarm raises: when it rings is the clock's business.)"""
    model = amilpy.loads(SWEEP.replace("FINTIM = 5.0", "FINTIM = 30.0"))

    def progress(report):
        if report.done >= 3:
            raise interrupts.TimeLimit

    resp = model.response("W", 0.5, 1.5, period="2*PI/W", progress=progress, max_time=3600)
    assert resp.timed_out and not resp.interrupted and not resp.complete
    assert len(resp.points) == 3


@pytest.mark.parametrize("command", [
    ["modes", "--at", "30"], ["periodic", "--period", "2*PI/W"],
    ["response", "W=0.5:1.5", "--period", "2*PI/W"]])
def test_an_analysis_stops_at_its_time_limit_with_exit_3(tmp_path, capsys, command):
    """modes, periodic and response take --max-time for the whole analysis. A limit
    far shorter than the settling run (30 s of a forced oscillator: thousands of
    steps, never done within 1 ms) ends it with exit 3 and says so."""
    path = tmp_path / "forced.amil"
    path.write_text(SWEEP.replace("FINTIM = 5.0", "FINTIM = 30.0"))
    code = main([command[0], str(path), *command[1:], "--max-time", "0.001", "--quiet"])
    err = capsys.readouterr().err
    assert code == 3, err
    assert "time limit of 0.001 s ran out" in err and "Traceback" not in err


# ------------------------------------------------------------ wall-clock limit

def test_a_time_limit_keeps_the_rows_of_auto():
    """--max-time ended AUTO inside one odeint call of 4,096 output instants, and all
    of them were lost (the printout held the row at TIME 0 only). Under a limit a
    chunk now takes at most 2 % of it: the rows up to near the end are kept, and
    they are right (X = cos(100 t))."""
    run = run1("X = INTGRL(1.0, V)\nV = INTGRL(0.0, -1.0E4*X)\n"
               "TIMER FINTIM = 20000.0, OUTDEL = 1.0\nPRINT X\nEND\n", max_time=2.0)
    assert not run.ok and "wall-clock limit of 2 s reached" in run.message
    assert len(run.t) >= 2 and run.t[-1] <= run.t_end
    assert np.max(np.abs(run["X"] - np.cos(100.0 * run.t))) < 1e-3


def test_a_time_limit_ends_a_procedural_loop_that_never_looks_at_the_clock():
    """A PROCEDURAL block of 1E12 iterations ran on past --max-time (the loop looks
    at its deadline between steps, and the first evaluation never ended). A SIGALRM
    a little after the limit (`simulate.backstop`) ends it; the run says so."""
    run = run1("PROGRAM P\n  CONSTANT N = 1.0E6\n  CINTERVAL CINT = 0.5\n  DERIVATIVE\n"
               "    X = INTEG(1.0, 0.0)\n    PROCEDURAL (S = X)\n      S = 0.0\n"
               "      DO I = 1, N\n        DO J = 1, N\n          S = S + SIN(S + X)\n"
               "        END DO\n      END DO\n    END\n    TERMT(T .GE. 2.0)\n  END\nEND\n",
               max_time=0.5)
    assert not run.ok and run.message == ("integration failed at TIME = 0: wall-clock "
                                          "limit of 0.5 s reached")


# ------------------------------------------------------------ library warnings

TOO_TIGHT = ("RELERR 1.0E-17\nABSERR 1.0E-30\nX = INTGRL(1.0, -X)\n"
             "F = FSW(X - 0.5, -1.0, 0.0, 1.0)\nY = INTGRL(1.0, F)\n"
             "TIMER FINTIM = 1.5, OUTDEL = 0.25\nPRINT X, Y\nEND\n")


@pytest.mark.parametrize("method", ["AUTO", "LSODA", "RKS", "BDF"])
def test_a_relerr_below_double_precision_is_raised_and_said(method):
    """RELERR 1E-17 made LSODA fail at its first step ("excess accuracy requested",
    then "Unexpected istate in LSODA") after SciPy's own warnings. The tolerance is
    raised to what the solver takes, one note says so, and the run is right:
    X = exp(-t), the switch at ln 2."""
    run = run1(TOO_TIGHT, method=method)
    assert run.ok, run.message
    assert np.allclose(run["X"], np.exp(-run.t), rtol=1e-9, atol=0)
    assert abs(run.events[0].time - math.log(2.0)) < 1e-9
    assert [w for w in run.warnings if w.startswith("RELERR 1e-17 is below what double "
                                                    "precision can hold")]


def test_the_command_line_shows_no_library_warning(tmp_path, capsys):
    """SciPy's, NumPy's and matplotlib's warnings point into code the user did not
    write; the command line leaves them out (and restores the warning filters)."""
    import warnings

    before = list(warnings.filters)
    path = tmp_path / "far.amil"
    # (a first step towards an output instant 1E299 away: SciPy's LSODA warns of
    # repeated convergence failures, then fails, which the run says)
    path.write_text("X = INTGRL(0.0, V)\nV = INTGRL(0.0, SIN(TIME) - 0.1*V - X)\n"
                    "TIMER FINTIM = 1.0E300, OUTDEL = 1.0E299\nPRINT X, V\nEND\n")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        amilpy.load(str(path)).run(advice=False)
    assert any("lsoda" in str(w.message) for w in seen)  # (the API passes them on)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        assert main(["run", str(path), "--quiet"]) == 3
    err = capsys.readouterr().err
    assert "Warning" not in err and "integration failed at TIME = 0" in err, err
    assert warnings.filters == before


def test_a_period_shorter_than_the_output_interval_is_no_orbit(tmp_path, capsys):
    """`periodic --period 1e-6` on a motion looked at every 0.1 s "converged" in one
    Newton step to an orbit of half peak-to-peak 1E-16, called neutral: over a time
    that short every state comes back to itself. It is refused, saying why."""
    path = tmp_path / "osc.amil"
    path.write_text("PARAM W = 1.0\nX = INTGRL(0.0, V)\nV = INTGRL(0.0, COS(W*TIME) - 0.1*V - X)\n"
                    "TIMER FINTIM = 10.0, OUTDEL = 0.1\nOUTPUT X\nEND\n")
    assert main(["periodic", str(path), "--period", "1e-6"]) == 1
    err = capsys.readouterr().err
    assert "shorter than the output interval (0.1 s)" in err
    assert main(["periodic", str(path), "--period", "2*PI/W"]) == 0


# ------------------------------------------------------------------- Zeno

ZENO_BALL = """PROGRAM a ball bouncing with restitution 0.5
  CONSTANT G = 9.81, E = 0.5
  CINTERVAL CINT = 0.25
  DERIVATIVE
    H = INTEG(V, 1.0)
    V = INTEG(-G, 0.0)
    SCHEDULE BOUNCE .XN. H
    TERMT(T .GE. 3.0)
  END
  DISCRETE BOUNCE
    V = -E*V
    H = 0.0
  END
  PRINT H, V
END
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU"])
def test_a_ball_driven_to_zeno_does_not_fall_through_the_floor(method):
    """Its bounces accumulate at 3*sqrt(2/g) (a fall, then flights of 2*sqrt(2/g)
    times 1/2, 1/4, ...). Every route missed a bounce at some point and printed the
    ball falling through the floor to H = -13 at TIME 3, with no message. Now the
    run ends at the accumulation point (to 1e-6 s) with the rows before it, none
    below the floor, and says why."""
    run = run1(ZENO_BALL, method=method)
    limit = 3.0 * math.sqrt(2.0 / 9.81)
    assert not run.ok and "accumulate at TIME = " in run.message and "(Zeno)" in run.message
    assert abs(run.t_end - limit) < 1e-6
    assert run.t[-1] <= limit and (run["H"] >= -1e-9).all()


def test_events_that_keep_their_pace_are_no_accumulation():
    """A relay that switches at a steady pace (an undamped oscillator on FSW) and a
    damped one whose reversals do not shrink geometrically run to FINTIM."""
    relay = run1("X = INTGRL(1.0, V)\nV = INTGRL(0.0, -FSW(X, -1.0, 0.0, 1.0))\n"
                 "TIMER FINTIM = 60.0, OUTDEL = 0.1\nPRINT X\nEND\n")
    assert relay.ok and len(relay.events) > 10
    damped = run1("X = INTGRL(1.0, V)\nV = INTGRL(0.0, -X - 0.3*V + FSW(V, 0.1, 0.0, -0.1))\n"
                  "TIMER FINTIM = 30.0, OUTDEL = 0.1\nPRINT X\nEND\n")
    assert damped.ok


@pytest.mark.parametrize("cint", ["1.0E-300", "5.0E-324"])
def test_a_tiny_cint_is_refused_saying_so(cint):
    """CINT = 1E-300 ended the run with "X is no longer finite after TIME = 0" (it
    was), 5E-324 with "cannot be evaluated before the run: division by zero" and a
    hint to check a line it did not give."""
    from amilpy.diagnostics import AmilError

    with pytest.raises(AmilError, match=r"the output interval CINT = .* is too small "
                                        r"\(the least is 1e-100 s"):
        amilpy.loads(f"PROGRAM P\n  CINTERVAL CINT = {cint}\n  DERIVATIVE\n"
                     "    X = INTEG(1.0, 1.0)\n    TERMT(T .GE. 1.0)\n  END\nEND\n",
                     "t.csl").run(advice=False)


# ---- found by the fuzzing over every command (stop 36) ----------------------------

def test_a_bad_call_in_a_macro_called_twice_is_an_error_not_a_traceback(tmp_path):
    # the second expansion's error repeats the first's (same MACRO line): said once,
    # but its statement must not be lowered (an IndexError in the template)
    from amilpy.cli import main

    path = tmp_path / "m.amil"
    path.write_text("MACRO Y = F2(T, X)\n   Y1 = REALPL(0., T)\n   Y = REALPL(0., T, Y1)\n"
                    "ENDMAC\nX = INTGRL(0.0, 1.0)\nA = F2(0.1, X)\nB = F2(0.2, X)\n"
                    "TIMER FINTIM = 1.0\nPRINT A, B\nEND\n")
    assert main(["check", str(path)]) == 1


def test_the_free_states_of_a_listing_with_an_impl_loop():
    # periodic/response's look at which states are free ignored IMPL units' inputs
    # (an IndexError on the shipped diode filter); V and the filters' states are read
    import os

    from conftest import ROOT

    import amilpy
    from amilpy.analysis.problem import free_states

    model = amilpy.load(os.path.join(ROOT, "models", "examples", "csmp_diode_filter.amil"))
    assert free_states(model.ir) == set()


def test_analyses_of_an_acsl_program_are_refused_plainly(tmp_path, capsys):
    import os

    from conftest import ROOT

    from amilpy.cli import main

    path = os.path.join(ROOT, "tests", "golden", "acsl_dosing.csl")
    for argv in (["periodic", path, "--period", "1"],
                 ["response", path, "KE=0.1:0.2", "--period", "1"]):
        assert main(argv) == 1
        assert "a flow map is not available for a program in ACSL form" in \
            capsys.readouterr().err


def test_an_analysis_of_a_listing_without_variables(tmp_path, capsys):
    from amilpy.cli import main

    path = tmp_path / "empty.amil"
    path.write_text("PARAM K = 1.0\nTIMER FINTIM = 1.0\nEND\n")
    assert main(["periodic", str(path), "--period", "1"]) == 2
    assert "no variable to measure" in capsys.readouterr().err


def test_a_sweep_bounds_each_point_by_the_run_limits(tmp_path, capsys):
    """`sweep` took no --max-time/--max-steps/--max-events: a point that would not end
    could only be killed. Each point's run now has them; a point over its limit is a
    failed point with its rows so far (here 50 steps cannot reach TIME 5)."""
    path = tmp_path / "forced.amil"
    path.write_text(SWEEP)
    code = main(["sweep", str(path), "W=0.5:1.5:0.5", "--max-steps", "50", "--jobs", "1",
                 "--csv", str(tmp_path / "s.csv")])
    out, err = capsys.readouterr()
    assert code == 3 and "3 point(s) failed" in err
    assert out.count("FAILED") == 3
    result = amilpy.loads(SWEEP).sweep("W", [0.5], measure="X", max_steps=50)
    assert result.points[0].status == "failed"


# a mutation of the shipped diode filter (fuzzing): the diode drop is VT*ALOG(I/IS),
# -inf while I = 0, so the period map's variation is NaN
NAN_JACOBIAN = """TITLE A DIODE FILTER WITH A DROP OF LOG(0)
MACRO Y = FILT2(TAU, X)
   Y1 = REALPL(0., TAU, X)
   Y  = REALPL(0., TAU, Y1)
ENDMAC
PARAM C = 1.E-3, R = 100., VT = 0.02585, IS = 1.E-12, V0 = 5.
V   = INTGRL(V0, -I/C)
I   = IMPL(0., 1.E-10, FI)
VD  = VT*ALOG(""" + "DEADSP(-0.5, 0.5, " * 8 + "1." + ")" * 8 + """ + I/IS)
FI  = AMAX1(0., (V - VD)/R)
IF2 = FILT2(0.01, I)
VF2 = FILT2(0.05, V)
TIMER FINTIM = 0.5, PRDEL = 0.05, OUTDEL = 0.002
PRINT V, I, VD, IF2, VF2
END
"""


def test_a_non_finite_jacobian_ends_an_analysis_with_a_message(tmp_path, capfd):
    """A NaN in the period map's Jacobian reached LAPACK, which printed its complaint
    on stdout (into the user's printout) and then gave a LinAlgError traceback. Now
    a non-finite Jacobian is said, exit 3, and nothing reaches stdout; `modes` of a
    non-finite Jacobian likewise."""
    from amilpy.analysis.linear import mode_list
    from amilpy.run import FlowFailed

    path = tmp_path / "filter.amil"
    path.write_text(NAN_JACOBIAN)
    code = main(["periodic", str(path), "--period", "1.0", "--settle", "0.5", "--quiet"])
    out, err = capfd.readouterr()
    assert code == 3 and out == "", out
    assert "Jacobian is not finite" in err and "Traceback" not in err
    with pytest.raises(FlowFailed, match="not finite"):
        mode_list(np.array([[0.0, 1.0], [np.nan, 0.0]]))


def test_an_acsl_run_of_many_variables_keeps_no_more_values_than_any_run():
    """The ACSL form's rows are known only as it runs, so the CSMP form's check of
    rows x variables before the run never applied: a program of 400 variables and a
    million communication intervals would take 3.2 GB. Its run is capped at the same
    2e8 values (500,000 intervals here) and refused before it starts, saying so."""
    lines = [f"    Y{k} = {k}.0*X" for k in range(1, 400)]
    text = ("PROGRAM MANY\n  CINTERVAL CINT = 1.0E-3\n  DERIVATIVE\n    X = INTEG(1.0, 0.0)\n"
            + "\n".join(lines) + "\n  END\n  TIMER FINTIM = 1000.0\nEND\n")
    with pytest.raises(AmilError, match=r"more than the 500,000 a run of 4\d\d variables"):
        amilpy.loads(text, "many.csl").run(advice=False)
