"""FST's form (contract section 13): TIMER STTIME, relational FINISH, the translator's
driver, WEATHER read from CABO files, and IALG 3 / EUDRIV in step-point mode. The
numbers are checked against the plain Euler recurrence written here, reading the
weather files with their own few lines of parsing (not amilpy.library.weather)."""

from __future__ import annotations

import math
import os
import shutil
from pathlib import Path

import pytest
from references import cabo

import amilpy
from amilpy.diagnostics import AmilError

HERE = Path(__file__).resolve().parent
WEATHER = HERE / "listings" / "weather"  # synthetic CABO files (TZ 2, 2018 and 2019)

LOGISTIC = """TITLE FST LOGISTIC GROWTH
PARAM RGR = 0.1; WMAX = 100.
INCON WI = 1.
W = INTGRL(WI, RGR*W*(1. - W/WMAX))
FINISH W > 90.
TIMER STTIME = 80.; FINTIM = 300.; DELT = 1.; PRDEL = 20.
TRANSLATION_GENERAL DRIVER = 'EUDRIV'
PRINT W
END
STOP
"""

CROP = """TITLE FST CROP: TEMPERATURE SUM AND RADIATION
WEATHER WTRDIR = 'C:\\DATA\\NOWHERE\\'; CNTR = 'TZ'; ISTN = 2
WEATHER IYEAR = 2018
TIMER STTIME = 100.; FINTIM = 300.; DELT = 1.; PRDEL = 10.
TRANSLATION_GENERAL DRIVER = 'EUDRIV'; TRACE = 0
PARAM TBASE = 10.
INCON TSUMI = 0.
TSUM = INTGRL(TSUMI, AMAX1(0., (TMMN+TMMX)/2. - TBASE))
RADSUM = INTGRL(0., RDD*1.E-6)
FINISH TSUM > 800.
PRINT TSUM, RADSUM, DOY
END
STOP
"""




def _listing(tmp_path: Path, text: str, name: str = "model.fst") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_fst_euler_loop_from_sttime_is_the_plain_recurrence():
    # FST's EUDRIV: W(k+1) = W(k) + DELT*rate(W(k)) from STTIME = 80, rows every PRDEL
    # from STTIME, and FINISH W > 90 tested at each step point: exact to round-off
    run, = amilpy.loads(LOGISTIC).run(advice=False)
    assert run.method == "RECT" and run.times[0] == 80.0
    w, t, rows = 1.0, 80, {}
    while True:
        rows[t] = w
        if w > 90.0:
            break
        w, t = w + 0.1 * w * (1.0 - w / 100.0), t + 1
    assert run.t_end == t == 150
    for time, value in zip(run.times, run.values["W"], strict=True):
        assert value == pytest.approx(rows[round(time)], rel=1e-14)
    assert "FINISH W > 90. at line 5" in run.message


def test_a_variable_step_method_locates_the_relational_finish():
    # dW/dt = RGR W (1 - W/WMAX) from W(80) = 1: W = WMAX / (1 + 99 exp(-RGR (t - 80))),
    # W = 90 at t = 80 + ln(99*9)/RGR; located to the tolerance (1e-6 relative)
    run, = amilpy.loads(LOGISTIC).run(method="RKS", rtol=1e-9, atol=1e-12, advice=False)
    assert run.t_end == pytest.approx(80.0 + math.log(99.0 * 9.0) / 0.1, rel=1e-8)


def test_drivers_methods_and_the_timer_are_checked(tmp_path):
    cases = [
        (LOGISTIC.replace("EUDRIV", "XXDRIV"), "unknown DRIVER 'XXDRIV'", "'EUDRIV' or"),
        (LOGISTIC.replace("PRINT W", "METHOD RKS\nPRINT W"),
         "METHOD RKS contradicts DRIVER = 'EUDRIV'", "remove one"),
        (LOGISTIC.replace("FINTIM = 300.", "FINTIM = 50."),
         "FINTIM = 50 is not after STTIME = 80", "end time"),
        (LOGISTIC.replace("DRIVER = 'EUDRIV'", "DRIVER = 'EUDRIV'; FOO = 1"),
         "TRANSLATION_GENERAL has no setting FOO", "DRIVER, EPS"),
    ]
    for text, message, hint in cases:
        with pytest.raises(AmilError) as err:
            amilpy.loads(text)
        rendered = err.value.render()
        assert message in rendered and hint in rendered, rendered


def test_rkdriv_is_rks_with_eps_as_relerr_and_fse_is_euler():
    rks, = amilpy.loads(LOGISTIC.replace("DRIVER = 'EUDRIV'",
                                         "DRIVER = 'RKDRIV'; EPS = 1E-8")).run(advice=False)
    assert rks.method == "RKS" and rks.rtol == 1e-8
    fse, = amilpy.loads(LOGISTIC.replace("TRANSLATION_GENERAL DRIVER = 'EUDRIV'",
                                         "TRANSLATION_FSE")).run(advice=False)
    euler, = amilpy.loads(LOGISTIC).run(advice=False)
    assert fse.method == "RECT" and list(fse.values["W"]) == list(euler.values["W"])


def _crop_reference(rows: dict[int, list[float]]):
    """The crop listing by hand: Euler with DELT = 1 from day 100, each day's weather."""
    tsum, rad, t, out = 0.0, 0.0, 100, {}
    while True:
        out[t] = (tsum, rad)
        if tsum > 800.0:
            return t, out
        r = rows[t]
        tsum += max(0.0, (r[1] + r[2]) / 2.0 - 10.0)
        rad += r[0] * 1000.0 * 1e-6  # kJ in the file, J in the model
        t += 1


def test_weather_from_a_cabo_file_in_step_point_mode(tmp_path):
    # the file is found through weather_dir= (WTRDIR and the listing's folders lack it)
    path = _listing(tmp_path, CROP)
    run, = amilpy.load(path).run(weather_dir=str(WEATHER), advice=False)
    end, ref = _crop_reference(cabo.days(WEATHER / "TZ2.018"))
    assert run.t_end == end
    for t, tsum, rad, doy in zip(run.times, run.values["TSUM"], run.values["RADSUM"],
                                 run.values["DOY"], strict=True):
        assert (tsum, rad) == pytest.approx(ref[round(t)], rel=1e-13)
        assert doy == round(t)  # day of 2018 = floor(TIME)


@pytest.mark.parametrize("rate", ["AMAX1(0., (TMMN+TMMX)/2. - TBASE)",
                                  "INSW((TMMN+TMMX)/2. - TBASE, 0., (TMMN+TMMX)/2. - TBASE)"])
def test_weather_with_located_finish_is_exact_between_day_starts(tmp_path, rate):
    # the daily values are constant over each day and every day's start is a
    # breakpoint: the integral is exact, and the crossing of 800 lies inside day
    # 156 at 156 + (800 - TSUM(156)) / rate(156), located to 1e-9 by AUTO and RKS.
    # Both spellings of the rate are switches on the day's weather: a new day's
    # value decides the branch from the day's start (the branch chosen with the day
    # before's value integrated a day at the wrong rate: 157.16)
    os.makedirs(tmp_path / "weather")
    shutil.copy(WEATHER / "TZ2.018", tmp_path / "weather" / "tz2.018")  # any case
    path = _listing(tmp_path, CROP.replace("AMAX1(0., (TMMN+TMMX)/2. - TBASE)", rate))
    rows = cabo.days(WEATHER / "TZ2.018")
    end, ref = _crop_reference(rows)
    tsum = ref[end - 1][0]
    rate = max(0.0, (rows[end - 1][1] + rows[end - 1][2]) / 2.0 - 10.0)
    crossing = end - 1 + (800.0 - tsum) / rate
    for method in ("AUTO", "RKS"):
        run, = amilpy.load(path).run(method=method, advice=False)
        assert run.t_end == pytest.approx(crossing, abs=1e-6), method


def test_a_weather_statement_after_end_is_that_runs_weather(tmp_path):
    """FST's reruns: LINTUL2 gives a WEATHER ... IYEAR after each END, one run a year.
    Each run reads its own year's file (every run read the last year's before, and
    failed when that one file was missing); its label says the year."""
    path = _listing(tmp_path, CROP.replace("END\nSTOP", "END\nWEATHER IYEAR = 2019\nEND\n"
                                           "STOP"))
    runs = amilpy.load(path).run(weather_dir=str(WEATHER), advice=False)
    assert [r.label for r in runs] == ["RUN 1", "WEATHER TZ 2 2019"]
    for run, year in zip(runs, ("018", "019"), strict=True):
        end, ref = _crop_reference(cabo.days(WEATHER / f"TZ2.{year}"))
        assert run.t_end == end
        for t, tsum in zip(run.times, run.values["TSUM"], strict=True):
            assert tsum == pytest.approx(ref[round(t)][0], rel=1e-13)
    assert runs[0].t_end != runs[1].t_end


def test_a_routine_loop_reads_the_days_weather(tmp_path):
    """A statement of a routine's DO loop that reads what the loop assigns is
    evaluated where it stands; the weather names in it are still the day's (SUCROS's
    TOTASS reads LAT so: it stopped with a Python NameError). S = (1 + 2 + 3)*LAT +
    3*TMMX, LAT from the file's station line, TMMX the day's."""
    text = ("TITLE T\nWEATHER CNTR = 'TZ'; ISTN = 2; IYEAR = 2018\nCALL G(LAT, TMMX, S)\n"
            "X = INTGRL(0., 1.)\nTIMER STTIME = 100.; FINTIM = 103.; DELT = 1.; PRDEL = 1.\n"
            "TRANSLATION_GENERAL DRIVER = 'EUDRIV'\nPRINT S\nEND\nSTOP\n"
            "      SUBROUTINE G(A, T, S)\n      IMPLICIT REAL (A-Z)\n      INTEGER I\n"
            "      S = 0.\n      DO 10 I = 1, 3\n         S = S + A*I + T\n"
            "   10 CONTINUE\n      RETURN\n      END\n")
    run, = amilpy.load(_listing(tmp_path, text)).run(weather_dir=str(WEATHER), advice=False)
    lat = cabo.station(WEATHER / "TZ2.018")[1]
    days = cabo.days(WEATHER / "TZ2.018")
    assert list(run["S"]) == pytest.approx([6.0 * lat + 3.0 * days[round(t)][2]
                                            for t in run.t], rel=1e-14)


def test_a_missing_weather_file_names_where_it_looked_and_the_lines(tmp_path):
    path = _listing(tmp_path, CROP)
    with pytest.raises(AmilError) as err:
        amilpy.load(path).run(advice=False)
    text = err.value.render()
    assert "the weather file TZ2.018 (station TZ 2, 2018) is not in /DATA/NOWHERE/" in text
    assert str(tmp_path / "weather") in text and "line(s) 8, 9" in text
    assert "--weather-dir" in text
    # a blank WTRDIR (Rlintul's LINTUL1 writes WTRDIR = ' ') is no folder to name
    blank = _listing(tmp_path, CROP.replace("'C:\\DATA\\NOWHERE\\'", "' '"), "b.fst")
    with pytest.raises(AmilError) as err:
        amilpy.load(blank).run(advice=False)
    assert f"is not in {tmp_path}," in err.value.render()


def test_a_missing_value_that_is_read_stops_the_run_naming_file_day_and_variable(tmp_path):
    os.makedirs(tmp_path / "weather")
    lines = (WEATHER / "TZ2.018").read_text().splitlines()
    out = []
    for line in lines:
        f = line.split()
        if len(f) >= 9 and not f[0].startswith("*") and f[2] == "105":
            f[5] = "-99"
            line = "  ".join(f)
        out.append(line)
    (tmp_path / "weather" / "TZ2.018").write_text("\n".join(out) + "\n")
    run, = amilpy.load(_listing(tmp_path, CROP)).run(advice=False)
    assert not run.ok and run.times[-1] <= 105.0
    assert "has -99 (missing) for TMMX on day 105 of 2018" in run.message


def test_weather_names_are_checked(tmp_path):
    no_weather = "TITLE T\nX = INTGRL(0., RDD)\nTIMER FINTIM = 10.\nPRINT X\nEND\n"
    with pytest.raises(AmilError) as err:
        amilpy.loads(no_weather)
    assert "RDD is an FST weather variable: add a WEATHER statement" in err.value.render()
    in_initial = CROP.replace("PARAM TBASE = 10.", "PARAM TBASE = 10.\nINITIAL\nR0 = RDD\n"
                              "DYNAMIC")
    with pytest.raises(AmilError) as err:
        amilpy.loads(in_initial)
    assert "RDD is the day's weather, which changes in time" in err.value.render()
    # a name the listing defines itself is its own, not the weather's
    own = CROP.replace("RADSUM = INTGRL(0., RDD*1.E-6)", "RDD = 2.E7\n"
                       "RADSUM = INTGRL(0., RDD*1.E-6)")
    path = _listing(tmp_path, own)
    run, = amilpy.load(path).run(weather_dir=str(WEATHER), advice=False)
    assert run.values["RADSUM"][1] == pytest.approx(200.0, rel=1e-12)


ACSL_EULER = """PROGRAM euler decay with doses
  CONSTANT K = 0.3, DOSE = 5.0, TSTOP = 10.0
  ALGORITHM IALG = 3
  NSTEPS NSTP = 4
  CINTERVAL CINT = 1.0
  DERIVATIVE
    X = INTEG(-K*X + STEP(2.5), 1.0)
    TERMT(T >= TSTOP, 'end')
  END
  DISCRETE DOSING
    INTERVAL DT = 4.0
    X = X + DOSE
  END
  PRINT X
END
"""


def test_acsl_ialg_3_is_the_classic_euler_loop_with_its_events():
    # IALG = 3 is Euler in step-point mode: h = CINT/NSTP = 0.25, the STEP read at
    # the step points (on from 2.5), a dose at t = 0, 4, 8 before that instant's row,
    # and TERMT(T >= TSTOP) holding at the step point T = 10 exactly
    run, = amilpy.loads(ACSL_EULER).run(advice=False)
    x, t, rows = 6.0, 0.0, {0: 6.0}
    for _ in range(40):
        x, t = x + 0.25 * (-0.3 * x + (1.0 if t >= 2.5 else 0.0)), t + 0.25
        if abs(t - 4.0) < 1e-9 or abs(t - 8.0) < 1e-9:
            x += 5.0
        if abs(t - round(t)) < 1e-9:
            rows[round(t)] = x
    assert run.method == "RECT" and run.t_end == 10.0
    assert len(run.times) == 11
    for time, value in zip(run.times, run.values["X"], strict=True):
        assert value == pytest.approx(rows[round(time)], rel=1e-13)


def test_the_report_writes_weather_and_impl_as_the_listing_does():
    # "Equations as evaluated" speaks the listing's language: a weather name, not the
    # memory and table that hold it; an IMPL loop's outputs by the loop's line
    from amilpy.parse.unparse import expr_text

    model = amilpy.loads(CROP)
    tsum = next(s for s in model.ir.states if s.name == "TSUM")
    assert expr_text(model.ir, tsum.deriv) == "AMAX1(0., (TMMN + TMMX)/2. - TBASE)"
    impl = amilpy.loads("TITLE T\nY = IMPL(1., 1.E-8, F)\nF = COS(Y)\nX = INTGRL(0., Y)\n"
                        "TIMER FINTIM = 1.\nPRINT X\nEND\n").ir
    y = next(e for e in impl.dynamic if e.target == "Y")
    assert expr_text(impl, y.expr) == "(the IMPL loop at line 2)"


SAWTOOTH = """TITLE FST STATE EVENT: X GROWS AT R; WHERE IT REACHES XMAX IT STARTS AGAIN
INITIAL
INCON ZERO = 0.
SET K = 0.
DYNAMIC
PARAM R = 0.7; XMAX = 2.5
X = INTGRL(ZERO, R)
N = INTGRL(ZERO, K)
EVENT
   ZEROCONDITION X - XMAX
   NEWVALUE X = 0.
   NEWVALUE K = K + 1.
ENDEVENT
TIMER STTIME = 0.; FINTIM = 10.; DELT = 0.5; PRDEL = 0.5
PRINT X, K, N
END
STOP
"""


def test_an_event_resets_a_state_where_its_zero_condition_is_located():
    """EVENT / ZEROCONDITION X - XMAX / NEWVALUE X = 0 / NEWVALUE K = K + 1: X = R*t
    reaches XMAX at t_k = k*XMAX/R, where X starts again and the SET variable K counts
    (N = INTGRL(0, K) integrates the count). Closed forms: X = R t mod XMAX, K =
    floor(R t / XMAX), N = sum of (t - t_k). The instants are located on every
    variable-step route, to 1e-12 (the crossing of a state linear in time)."""
    period = 2.5 / 0.7
    for method in ("AUTO", "RKS", "DOP853", "STIFF"):
        run, = amilpy.loads(SAWTOOTH, "saw.fst").run(method=method, advice=False)
        ran = [e.time for e in run.events if e.kind == "discrete"]
        assert ran == pytest.approx([period, 2 * period], abs=1e-12), method
        for t, x, k, n in zip(run.t, run["X"], run["K"], run["N"], strict=True):
            kk = math.floor(t / period + 1e-12)
            assert k == kk, (method, t)
            assert x == pytest.approx(0.7 * (t - kk * period), abs=1e-10), (method, t)
            assert n == pytest.approx(sum(t - j * period for j in range(1, kk + 1)),
                                      abs=1e-10), (method, t)
        assert "EVENT at line 9 (NEWVALUE X, K): ran" in [str(e).split(": ", 1)[1]
                                                          for e in run.events]


def test_in_step_point_mode_an_event_runs_at_the_step_point_it_is_seen():
    """FSE's Euler driver: the zero condition is read at the step points; at the first
    where it has reached zero (from either side) the NEWVALUEs run, before that
    point's row, and the step from it takes the rates of the new values. The plain
    recurrence: X(k+1) = X(k) + DELT*R, reset where X - XMAX <= 0 turns false."""
    text = SAWTOOTH.replace("TIMER", "TRANSLATION_GENERAL DRIVER = 'EUDRIV'\nTIMER")
    run, = amilpy.loads(text, "saw.fst").run(advice=False)
    assert run.method == "RECT"
    x, k, n, z_prev, rows, fired = 0.0, 0.0, 0.0, None, [], []
    for i in range(21):
        t = 0.5 * i
        z = x - 2.5
        if z_prev is not None and ((z_prev > 0 >= z) or (z_prev < 0 <= z)):
            x, k = 0.0, k + 1.0
            fired.append(t)
            z = x - 2.5
        rows.append((t, x, k, n))
        z_prev = z
        x, n = x + 0.5 * 0.7, n + 0.5 * k
    assert [e.time for e in run.events if e.kind == "discrete"] == fired == [4.0, 8.0]
    for row, t, x_, k_, n_ in zip(rows, run.t, run["X"], run["K"], run["N"], strict=True):
        assert (t, x_, k_) == pytest.approx(row[:3], abs=1e-13)
        assert n_ == pytest.approx(row[3], abs=1e-13)


EMERGENCE = """TITLE EMERGENCE AS LINTUL2-CASSAVA WRITES IT: A FLAG SET ONCE BY AN EVENT
INITIAL
SET EMERG = 0.
DYNAMIC
PARAM RT = 1.3; TSE = 5.; W0 = 2.; RGR = 0.5
TSUM = INTGRL(0., RT)
W = INTGRL(0., RGR*W*EMERG)
FAVOURABLE = INSW(TSUM - TSE, 0., 1.)*INSW(-W, 0., 1.)
EVENT
   ZEROCONDITION 1. - FAVOURABLE
   NEWVALUE EMERG = 1.
   NEWVALUE W = W + W0
ENDEVENT
TIMER STTIME = 0.; FINTIM = 8.; DELT = 0.25; PRDEL = 0.25
PRINT W, EMERG, TSUM
END
STOP
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RECT"])
def test_a_zero_condition_that_jumps_to_zero_fires_once(method):
    """The condition 1 - FAVOURABLE is 1 or 0: it reaches zero by a jump, where the
    switch INSW(TSUM - TSE) changes branch (TSUM = RT t reaches TSE at t_e = TSE/RT),
    and is 1 again as soon as W > 0: the EVENT runs once. Then W = W0 exp(RGR (t -
    t_e)). Located routes: t_e to 1e-12 and W to their tolerance; RECT (step-point):
    the first step point with TSUM >= TSE, 4.0, and W the Euler recurrence from it."""
    run, = amilpy.loads(EMERGENCE, "em.fst").run(method=method, advice=False)
    ran = [e.time for e in run.events if e.kind == "discrete"]
    if method == "RECT":
        assert ran == [4.0]
        w, rows = 0.0, {}
        for i in range(33):
            t = 0.25 * i
            if t == 4.0:
                w += 2.0
            rows[t] = w
            w += 0.25 * 0.5 * w * (1.0 if t >= 4.0 else 0.0)
        assert list(run["W"]) == pytest.approx([rows[t] for t in run.t], rel=1e-14)
    else:
        t_e = 5.0 / 1.3
        assert ran == pytest.approx([t_e], abs=1e-12)
        exact = [2.0 * math.exp(0.5 * (t - t_e)) if t > t_e else 0.0 for t in run.t]
        assert list(run["W"]) == pytest.approx(exact, rel=1e-7, abs=1e-12)
    assert list(run["EMERG"]) == [1.0 if t >= ran[0] else 0.0 for t in run.t]


@pytest.mark.parametrize("text, line, message, hint", [
    (EMERGENCE.replace("NEWVALUE W = W + W0", "NEWVALUE FAVOURABLE = 0."), 12,
     "NEWVALUE FAVOURABLE: FAVOURABLE is neither a state nor a SET variable",
     "FAVOURABLE is computed at line 8; an EVENT changes states"),
    (EMERGENCE.replace("SET EMERG = 0.\nDYNAMIC", "DYNAMIC\nSET EMERG = 0."), 4,
     "SET cannot stand in DYNAMIC", "write it in INITIAL"),
    (EMERGENCE.replace("   ZEROCONDITION 1. - FAVOURABLE\n", ""), 9,
     "this EVENT has no ZEROCONDITION", "where e reaches zero"),
    (EMERGENCE.replace("ENDEVENT\n", ""), 9, "EVENT opened at line 9 is never closed",
     "ENDEVENT"),
    (EMERGENCE.replace("   NEWVALUE W = W + W0\n", "   NEWVALUE EMERG = 2.\n"), 12,
     "NEWVALUE EMERG twice in one EVENT", "line 11"),
    (EMERGENCE.replace("   NEWVALUE W = W + W0\n", "   NEWVALUE W = W + W0\n   W0 = 3.\n"),
     13, "W0 is the EVENT's own value and a variable of the model", "another name"),
    (EMERGENCE.replace("   NEWVALUE W = W + W0\n", "   NEWVALUE W = W + W0\n   PRINT W\n"),
     13, "an EVENT holds ZEROCONDITION (or FIRSTTIME and NEXTTIME), NEWVALUE statements, "
     "assignments and PARAMETERs only", "NEWVALUE X = value"),
    (EMERGENCE.replace("   ZEROCONDITION 1. - FAVOURABLE\n", "   NEXTTIME TIME + 1.\n"), 10,
     "NEXTTIME without FIRSTTIME", "FIRSTTIME t"),
    (EMERGENCE.replace("   ZEROCONDITION 1. - FAVOURABLE\n",
                       "   ZEROCONDITION 1. - FAVOURABLE\n   FIRSTTIME 2.\n"), 11,
     "an EVENT has a ZEROCONDITION or a FIRSTTIME, not both", "another EVENT"),
    (EMERGENCE.replace("ENDEVENT\n", "ENDEVENT\nNEWVALUE W = 0.\n"), 14,
     "NEWVALUE stands inside an EVENT", "EVENT / NEWVALUE ... / ENDEVENT"),
    (EMERGENCE.replace("   ZEROCONDITION 1. - FAVOURABLE\n", "   FIRSTTIME W\n"), 10,
     "FIRSTTIME uses W, which changes in time", "a number, a data value"),
    ("PROGRAM P\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nEVENT\nZEROCONDITION X - 1.\n"
     "NEWVALUE X = 0.\nENDEVENT\nTERMT(T >= 2.)\nEND\nEND\n", 4,
     "FST's EVENT ... ENDEVENT belongs to the CSMP (FST) form", "SCHEDULE name .XZ."),
    ("PROGRAM P\nINITIAL\nSET K = 1.0\nEND\nDERIVATIVE\nX = INTEG(K, 0.0)\n"
     "TERMT(T >= 2.)\nEND\nEND\n", 3, "FST's SET belongs to the FST (CSMP) form",
     "assign it in INITIAL (K = ...)"),
])
def test_event_and_set_faults_are_located_and_say_what_to_write(text, line, message, hint):
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "e.fst")
    d = err.value.diagnostics[0]
    assert (d.span.line, d.message) == (line, message), err.value.render()
    assert hint in d.hint


PRUNING = """TITLE TIME EVENTS: X GROWS AT 1 A DAY, HALVED AT DAY 10 AND EVERY 7 DAYS ON
INITIAL
SET N = 0.
DYNAMIC
X = INTGRL(0., 1.)
EVENT
   FIRSTTIME STTIME + 10.
   NEXTTIME TIME + GAP
   PARAMETER GAP = 7.
   HALF = X/2.
   NEWVALUE X = HALF
   NEWVALUE N = N + 1.
ENDEVENT
TIMER STTIME = 2.; FINTIM = 32.; DELT = 0.5; PRDEL = 0.5
PRINT X, N
END
STOP
"""


def test_a_time_event_at_firsttime_and_then_at_each_nexttime():
    """FIRSTTIME STTIME + 10 and NEXTTIME TIME + GAP (a PARAMETER inside the EVENT, the
    listing's like any other), with a value of the event's own (HALF): X = t - 2
    halved at t = 12, 19, 26. Located (AUTO, RKS): the integration stops at each
    instant; step-point (EUDRIV, DELT 0.5): the same instants are step points. Both
    are the recurrence x -> x/2 at the instants, to round-off; the rows at an instant
    show the values after the event."""
    def exact(t):
        x, last = 0.0, 2.0
        for at in (12.0, 19.0, 26.0):
            if t < at:
                break
            x, last = (x + at - last) / 2.0, at
        return x + t - last

    for text, method in ((PRUNING, "AUTO"), (PRUNING, "RKS"), (PRUNING.replace(
            "TIMER", "TRANSLATION_GENERAL DRIVER = 'EUDRIV'\nTIMER"), None)):
        run, = amilpy.loads(text, "prune.fst").run(method=method, advice=False)
        assert [e.time for e in run.events if e.kind == "discrete"] == [12.0, 19.0, 26.0]
        assert list(run["X"]) == pytest.approx([exact(t) for t in run.t], abs=1e-9)
        assert list(run["N"]) == [float(sum(t >= a for a in (12, 19, 26))) for t in run.t]


def test_in_step_point_mode_a_time_event_runs_at_the_first_step_point_at_or_after_it():
    """DELT 0.3: day 12 is no step point; the event runs at the first after it, 12.2
    (2 + 34*0.3), and NEXTTIME TIME + 7 counts from there: 19.2 is none either, so
    19.4, then 26.6 (FSE's Euler driver does not shorten its step to an event)."""
    text = PRUNING.replace("DELT = 0.5; PRDEL = 0.5", "DELT = 0.3; PRDEL = 0.3").replace(
        "TIMER", "TRANSLATION_GENERAL DRIVER = 'EUDRIV'\nTIMER")
    run, = amilpy.loads(text, "prune.fst").run(advice=False)
    ran = [e.time for e in run.events if e.kind == "discrete"]
    assert ran == pytest.approx([12.2, 19.4, 26.6], abs=1e-9)
    x, t, rows, k, due = 0.0, 2.0, [], 0, 12.0
    while t <= 32.0 + 1e-9:
        if t >= due - 1e-9:
            x, due = x / 2.0, t + 7.0
        rows.append(x)
        x, k = x + 0.3, k + 1
        t = 2.0 + 0.3 * k
    assert list(run["X"]) == pytest.approx(rows, abs=1e-12)


def test_newvalues_are_given_at_once_from_the_values_before_the_event():
    """FST's statements have no order, so neither may an EVENT's: NEWVALUE A = B and
    NEWVALUE B = A swap them (in written order both would end as B)."""
    text = ("TITLE SWAP\nA = INTGRL(1., 0.)\nB = INTGRL(2., 0.)\nEVENT\nFIRSTTIME 1.\n"
            "NEWVALUE A = B\nNEWVALUE B = A\nENDEVENT\nTIMER FINTIM = 2.; DELT = 1.; "
            "PRDEL = 1.\nPRINT A, B\nEND\nSTOP\n")
    for method in ("AUTO", "RECT"):
        run, = amilpy.loads(text, "swap.fst").run(method=method, advice=False)
        assert (list(run["A"]), list(run["B"])) == ([1.0, 2.0, 2.0], [2.0, 1.0, 1.0])


def test_a_nexttime_that_is_not_later_stops_the_run_saying_so():
    text = PRUNING.replace("NEXTTIME TIME + GAP", "NEXTTIME TIME")
    run, = amilpy.loads(text, "prune.fst").run(advice=False)
    assert run.status == "failed" and "NEXTTIME = 12 is not after TIME = 12" in run.message


COINCIDENT = """TITLE EVENTS AT ONE INSTANT, AND ONE AT FINTIM
INITIAL
SET KA = 0.
SET KB = 0.
SET KC = 0.
DYNAMIC
X = INTGRL(0., 1.)
Y = INTGRL(0., 1.)
EVENT
   ZEROCONDITION X - 1.5
   NEWVALUE KA = KA + 1.
ENDEVENT
EVENT
   ZEROCONDITION X - 1.5
   NEWVALUE KB = KB + 1.
ENDEVENT
EVENT
   ZEROCONDITION TIME - 1.5
   NEWVALUE KC = KC + 1.
ENDEVENT
EVENT
   ZEROCONDITION Y - 1.
   NEWVALUE Y = 0.
ENDEVENT
TIMER STTIME = 0.; FINTIM = 4.; DELT = 0.25; PRDEL = 0.5
PRINT KA, KB, KC, Y
END
STOP
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "STIFF", "RECT"])
def test_events_at_one_instant_all_run_and_one_at_fintim_runs_before_the_last_row(method):
    """Two EVENTs on one condition and a third on TIME reach zero at t = 1.5: all three
    run (only one did on the located routes, the others listed as crossed). Y = TIME
    reaches 1 at t = 1, 2, 3 and 4 = FINTIM, each a float from an output instant: each
    row there shows Y after its reset (Y = 0), the last one too (FINTIM's event ran on
    some routes and not others, by the last bit of Y)."""
    run, = amilpy.loads(COINCIDENT, "coincident.fst").run(method=method, advice=False)
    ran = sorted(e.time for e in run.events if e.kind == "discrete")
    assert ran == pytest.approx([1.0, 1.5, 1.5, 1.5, 2.0, 3.0, 4.0], abs=1e-12)
    assert (run["KA"][-1], run["KB"][-1], run["KC"][-1]) == (1.0, 1.0, 1.0)
    assert list(run["Y"]) == pytest.approx([t % 1.0 for t in run.t], abs=1e-12)


@pytest.mark.parametrize("method, end", [("AUTO", 3 * 2.5 / 0.7), ("RKS", 3 * 2.5 / 0.7),
                                         ("RECT", 12.0)])
def test_a_finish_the_new_values_reach_stops_the_run_there(method, end):
    """FINISH K = 2.5 on the SET variable the sawtooth's EVENT counts: the third event
    reaches it, and the run stops at that instant (it was listed as reached and the
    run went on to FINTIM), its last row the values after the event."""
    text = SAWTOOTH.replace("TIMER", "FINISH K = 2.5\nTIMER").replace("FINTIM = 10.",
                                                                       "FINTIM = 20.")
    run, = amilpy.loads(text, "saw.fst").run(method=method, advice=False)
    assert run.status == "stopped" and "FINISH K=2.5" in run.message
    assert run.t_end == pytest.approx(end, abs=1e-9)
    assert run["K"][-1] == 3.0 and run["X"][-1] == pytest.approx(0.0, abs=1e-9)
