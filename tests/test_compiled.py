"""METHOD COMPILED: DOP853, the output rows and the plain crossings compiled by numba.

Its reference is first SciPy's DOP853 (the same method: the kernel must take the same
steps), then closed forms and the hoist's independent event-located reference. Without
numba the route runs as DOP853 in Python and says so (the last tests run either way).
"""

from __future__ import annotations

import math
import os
import sys

import numpy as np
import pytest

import amilpy
from amilpy import compiled

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from conftest import ROOT, run1  # noqa: E402

needs_numba = pytest.mark.skipif(not compiled.available(), reason="numba not installed "
                                 "(pip install 'amilpy[fast]')")

# X grows at rate 1 until X = 0.5 (t = 0.5); from there X' = 1 - X:
#   X = 1 - 0.5*exp(-(t - 0.5)) for t >= 0.5
KNEE = """TITLE KNEE
X = INTGRL(0.0, 1.0 - X*S)
S = INSW(X - 0.5, 0.0, 1.0)
TIMER FINTIM = 3.0, OUTDEL = 0.01
METHOD COMPILED
END
"""


def knee(t: np.ndarray) -> np.ndarray:
    return np.where(t < 0.5, t, 1.0 - 0.5 * np.exp(-(t - 0.5)))


@needs_numba
def test_knee_closed_form_and_its_crossing():
    # one crossing, located by the kernel (no Python between steps): at t = 0.5 to
    # a few ulps, the rows within the tolerance's reach of the closed form
    r = run1(KNEE, rtol=1e-10, atol=1e-12)
    assert r.status == "finished" and not r.warnings
    assert len(r.events) == 1 and r.events[0].time == pytest.approx(0.5, abs=1e-12)
    assert np.max(np.abs(r["X"] - knee(r.t))) < 1e-9
    assert r["S"][r.t > 0.5].min() == 1.0 and r["S"][r.t < 0.5].max() == 0.0


@needs_numba
def test_an_argument_bound_once_compiles():
    # DEADSP reads X twice: the compiler binds X - 0.3 once, inside the expression
    # (w1 := X - 0.3), which numba cannot type; the translation makes it a statement.
    # X = exp(-t) leaves the dead zone [-0.2, 0.2] of X - 0.3 at t = ln 2, and
    # Y = integral of X - 0.5 until then
    text = ("X = INTGRL(1.0, -X)\nD = DEADSP(-0.2, 0.2, X - 0.3)\nY = INTGRL(0.0, D)\n"
            "TIMER FINTIM = 1.0, OUTDEL = 0.1\nEND\n")
    r = run1(text, method="COMPILED", rtol=1e-10, atol=1e-12)
    assert r.status == "finished" and not r.warnings, r.warnings
    assert [e.time for e in r.events] == pytest.approx([math.log(2.0)], abs=1e-12)
    t = min(r.t[-1], math.log(2.0))
    assert r["Y"][-1] == pytest.approx(1.0 - math.exp(-t) - 0.5 * t, abs=1e-9)


@needs_numba
@pytest.mark.parametrize("model", ["machine_unit", "crank_slider_startup"])
def test_same_steps_as_scipy_dop853(model):
    # the kernel is SciPy's DOP853 (coefficients, error norm, step control, first
    # step): on a model with no crossing inside its steps, the same steps (but for
    # one where rounding tips a step-size choice: the first step's norms are summed
    # in another order) and the same rows within the method's own error (RELERR
    # 1E-8: 1.7e-8 of the largest W measured, where one step went differently).
    # (The crank-slider's FINISH is a crossing the loop decides: the kernel holds
    # that step for it, as a Python stepper's step.)
    m = amilpy.load(os.path.join(ROOT, "models", f"{model}.amil"))
    a, = m.run(method="COMPILED", rtol=1e-8, atol=1e-10)
    b, = m.run(method="DOP853", rtol=1e-8, atol=1e-10)
    assert not a.warnings
    assert abs(a.stats["nsteps"] - b.stats["nsteps"]) <= 2
    assert len(a.t) == len(b.t) and a.t == pytest.approx(b.t, rel=1e-12)
    for name in a.values:
        scale = max(np.max(np.abs(b[name])), 1e-300)
        assert np.max(np.abs(a[name] - b[name])) <= 1e-7 * scale, name
    assert [e.time for e in a.events] == pytest.approx([e.time for e in b.events], rel=1e-12)


@needs_numba
def test_hoist_against_its_event_located_reference():
    # 222 contact edges in 5 s, every one located in the kernel. Reference: the
    # hoist's own SciPy integration with the edges as events (tests/references),
    # at rtol 1e-12. RELERR 1E-9 gives 4e-8 of the largest value (DOP853's own
    # error there, the same as the Python route's), so 1e-6 leaves room.
    from references import hoist as ref

    m = amilpy.load(os.path.join(ROOT, "models", "hoist_backlash.amil"))
    r, = m.run(method="COMPILED", rtol=1e-9, atol=1e-12)
    p, = m.run(method="DOP853", rtol=1e-9, atol=1e-12)
    assert r.status == "finished" and not r.warnings
    sim = ref.simulate(ref.Hoist(), 70.0, (0.0, 5.0), t_eval=r.t)
    y_ref = sim.y[1]
    assert np.max(np.abs(r["Y"] - y_ref)) <= 1e-6 * np.max(np.abs(y_ref))
    assert len(r.events) == 2 * len(sim.edges)  # |Y| = DELTA/2: two surfaces each
    assert len(r.events) == len(p.events) == 222
    assert [e.time for e in r.events] == pytest.approx([e.time for e in p.events], abs=1e-9)
    assert [e.surface for e in r.events] == [e.surface for e in p.events]


@needs_numba
@pytest.mark.parametrize("model", ["ex4_elastic", "ex4_clutch", "ex4_torque_meter"])
def test_exercise4_events_and_rows_as_the_python_route(model):
    # friction that sticks (a sliding surface: those segments run on SciPy's
    # DOP853), a clutch with memory (its crossings go back to the loop), branches
    # nothing uses that cross at every stability-bound step (followed in the kernel)
    m = amilpy.load(os.path.join(ROOT, "models", f"{model}.amil"))
    a, = m.run(method="COMPILED", rtol=1e-9, atol=1e-12)
    b, = m.run(method="DOP853", rtol=1e-9, atol=1e-12)
    assert a.status == b.status == "finished"
    assert [(e.surface, e.old, e.new) for e in a.events] == \
        [(e.surface, e.old, e.new) for e in b.events]
    assert [e.time for e in a.events] == pytest.approx([e.time for e in b.events], abs=1e-9)
    for name in b.values:
        scale = max(np.max(np.abs(b[name])), 1e-300)
        # two DOP853 runs at RELERR 1E-9 on stability-bound steps: their rows differ
        # by their own errors (measured against the exact references: 3e-7 on the
        # clutch, 2.3e-6 and 2.6e-6 on the torque meter; where the stiffness test
        # confirms, and the rows turn cubic, rounding decides: 1.35e-5 of MNET there)
        assert np.max(np.abs(a[name] - b[name])) <= 3e-5 * scale, name


@needs_numba
def test_parameters_are_arguments_not_code():
    # a new PARAM value (a sweep point) reads the same compiled functions with new
    # arguments: no new module, and the values are those of the Python route
    text = KNEE.replace("X = INTGRL(0.0, 1.0 - X*S)", "PARAM K = 1.0\nX = INTGRL(0.0, K - X*S)")
    model = amilpy.loads(text, name="k.amil")
    before = set(compiled._LOADED)
    model.run(K=1.0)
    new = set(compiled._LOADED) - before
    second, = model.run(K=2.0)
    assert len(new) == 1 and set(compiled._LOADED) - before == new
    kernel = compiled._LOADED[new.pop()]
    assert kernel.parameters == ("p_K",)
    # X reaches 0.5 at t = 0.25 with K = 2; then X' = 2 - X
    assert second.events[0].time == pytest.approx(0.25, abs=1e-12)
    t = second.t[second.t > 0.25]
    assert np.max(np.abs(second["X"][second.t > 0.25] - (2.0 - 1.5 * np.exp(-(t - 0.25))))) \
        < 1e-5
    with open(kernel.module.__file__) as fh:
        assert "p[0]" in fh.read()


@needs_numba
def test_finish_and_termt_are_the_loops():
    # a FINISH condition is a stop: the kernel hands its step back, the run ends at
    # the located instant as on every route
    r = run1(KNEE.replace("END", "FINISH X = 0.8\nEND"))
    stop = 0.5 + math.log(0.5 / 0.2)  # 1 - 0.5 exp(-(t - 0.5)) = 0.8
    assert r.t[-1] == pytest.approx(stop, abs=1e-9)


@needs_numba
def test_a_fault_gets_the_python_routes_message():
    # the kernel's step size collapses where 1/(1 - TIME) blows up; SciPy's DOP853
    # takes over there and the run fails with the message METHOD DOP853 gives
    text = "X = INTGRL(1.0, 1.0/(1.0 - TIME))\nTIMER FINTIM = 2.0, OUTDEL = 0.01\nEND\n"
    a = run1(text, method="COMPILED")
    b = run1(text, method="DOP853")
    assert a.status == b.status == "failed"
    assert a.t[-1] == pytest.approx(b.t[-1], rel=1e-6)
    assert a.message.split(":")[0] == b.message.split(":")[0]


def test_no_compiled_form_runs_as_dop853_and_says_why():
    # AFGEN's table has no compiled form (nor has anything without numba): the run
    # is DOP853's, with one warning saying why
    text = ("FUNCTION TAB = 0.0, 0.0, 1.0, 2.0, 2.0, 2.0\nX = INTGRL(0.0, AFGEN(TAB, TIME))\n"
            "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n")
    a = run1(text, method="COMPILED")
    b = run1(text, method="DOP853")
    assert len(a.warnings) == 1 and "ran as DOP853" in a.warnings[0]
    assert ("AFGEN" in a.warnings[0]) or ("numba" in a.warnings[0])
    assert np.array_equal(a["X"], b["X"])


@needs_numba
def test_a_large_model_says_why_it_is_not_compiled():
    # numba's compile time grows faster than the function: 15 s for 400 equations,
    # 315 s for the 1000-mass chain's 2,999 (measured); past 400 the run is DOP853's
    # at once, and says so once, with the count
    sys.path.insert(0, os.path.join(ROOT, "benchmarks"))
    from scale import chain_listing

    r, = amilpy.loads(chain_listing(200)).run(method="COMPILED", advice=False)
    assert r.status == "finished"
    assert r.warnings == ["METHOD COMPILED: this model has no compiled form: its right "
                          "side has 599 equations, more than the 400 numba compiles in "
                          "15 s (3,000 take it 5 min); it ran as DOP853"]


def test_without_numba_the_route_is_dop853(monkeypatch):
    monkeypatch.setattr(compiled, "available", lambda: False)
    monkeypatch.setattr(compiled, "_BY_SOURCE", {})  # (this process may have built it)
    text = KNEE
    a = run1(text)
    b = run1(text, method="DOP853")
    assert any("numba is not installed" in w for w in a.warnings)
    assert np.array_equal(a["X"], b["X"])
    assert np.max(np.abs(a["X"] - knee(a.t))) < 1e-5


# Found in review: each runs as METHOD DOP853 does (the Python route through the same
# loop), with the same rows, events, warnings and message.
SAME_AS_DOP853 = {
    # a step below TIMER DELMIN is the loop's to count (step-size underflow)
    "delmin": "Y = INTGRL(1.0, -1000.0*Y)\nTIMER FINTIM = 2.0, OUTDEL = 0.1, DELMIN = 0.01\n",
    # a state that overflows is the loop's to report, with no infinite rows
    "overflow": "Y = INTGRL(1.0E308, 1.0E307)\nTIMER FINTIM = 10.0, OUTDEL = 1.0\n",
    # a branch nothing uses flips inside a step: the row at its end shows the new one
    "silent_row": "X = INTGRL(1.0, V)\nV = INTGRL(0.0, -X)\nR = FSW(V, -1.0, 0.0, 1.0)\n"
                  "PRINT X, R\nTIMER FINTIM = 5.0, OUTDEL = 0.1\n",
    # ZHOLD's trigger flips where nothing else sees it: the held value is sampled
    "zhold": "X = INTGRL(1.0, V)\nV = INTGRL(0.0, -X)\nH = ZHOLD(X, V)\nPRINT X, H\n"
             "TIMER FINTIM = 10.0, OUTDEL = 0.5\n",
    # restarts in the kernel start the stiffness test again, as a new stepper does
    "stiff_restarts": "Z = INTGRL(1.0, W)\nW = INTGRL(0.0, -3600.0*Z)\n"
                      "X = INTGRL(0.0, -3000.0*(X - U))\nU = FSW(Z, -1.0, 0.0, 1.0)\n"
                      "TIMER FINTIM = 1.0, OUTDEL = 0.01\n",
    # switching ever faster (Zeno): the same stop, at the same instant
    "zeno": "X = INTGRL(1.0, V)\nV = INTGRL(0.0, -FSW(X, -1.0, 0.0, 1.0) - "
            "0.5*FSW(V, -1.0, 0.0, 1.0))\nTIMER FINTIM = 10.0, OUTDEL = 0.1\n",
}


@needs_numba
@pytest.mark.parametrize("name", list(SAME_AS_DOP853))
def test_found_in_review_runs_as_dop853(name):
    # (RELERR 1E-6, as these were found: two implementations of one method agree to
    # a few tolerances, and the stops below come where the step size collapses)
    text = "RELERR 1.0E-6\nABSERR 1.0E-9\n" + SAME_AS_DOP853[name] + "END\n"
    a = run1(text, method="COMPILED")
    b = run1(text, method="DOP853")
    assert (a.status, a.message.split(":")[0]) == (b.status, b.message.split(":")[0])
    assert a.t_end == pytest.approx(b.t_end, rel=1e-6, abs=1e-9)
    assert [w.split(":")[0] for w in a.warnings] == [w.split(":")[0] for w in b.warnings]
    assert [(e.surface, e.old, e.new) for e in a.events] == \
        [(e.surface, e.old, e.new) for e in b.events]
    assert len(a.t) == len(b.t) and np.all(np.isfinite(a["Y" if "Y" in a.values else "X"]))
    for var in b.values:
        scale = max(np.max(np.abs(b[var])), 1e-300)
        # RELERR 1E-6: two implementations of one method, rows within a few tolerances
        assert np.max(np.abs(a[var] - b[var])) <= 2e-5 * scale, var


@needs_numba
def test_memory_kept_step_by_step_says_it_ran_as_dop853():
    text = ("X = INTGRL(1.0, V)\nV = INTGRL(0.0, -X)\nY = INTGRL(0.0, HSTRSS(0.0, -0.2, 0.2, X))"
            "\nTIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n")
    a = run1(text, method="COMPILED")
    b = run1(text, method="DOP853")
    assert len(a.warnings) == 1 and "HSTRSS" in a.warnings[0] and "ran as DOP853" in a.warnings[0]
    assert np.array_equal(a["Y"], b["Y"])


@needs_numba
def test_every_math_function_with_a_compiled_form_compiles():
    # every helper the translation spells is used, so the run is the kernel's (no
    # warning that it ran as DOP853) and gives DOP853's rows: each function means
    # in numba what it means in `amilpy.library.runtime`. In sorted code AINT ... DIM are
    # switches (their templates, an argument bound once: ABS(X - 0.3)); inside the
    # PROCEDURE they read W, assigned in its IF, so they are their plain forms there
    text = """X = INTGRL(0.5, -X)
A = SQRT(X) + EXP(X) + ALOG(X) + ALOG10(X) + SIN(X) + COS(X) + TAN(X)
B = ASIN(X) + ACOS(X) + ATAN(X) + TANH(X) + ATAN2(X, 1.0) + SINH(X) + COSH(X)
C = AINT(10.0*X) + FLOAT(2) + AMOD(10.0*X, 0.3) + SIGN(2.0, X - 0.3) + NOTNUL(X - X)
D = AMAX1(X, 0.2) + AMIN1(X, 0.2, 0.3) + X**1.5 + ABS(X - 0.3) + NINT(10.0*X) + DIM(X, 0.3)
PROCEDURE E, W = PLAIN(X)
   W = 0.0
   IF (X > 0.0) THEN
      W = 10.0*X
   ENDIF
   E = AINT(W) + AMOD(W, 0.3) + SIGN(2.0, W - 3.0) + NINT(W) + DIM(W, 3.0) + ABS(W - 3.0)
   E = E + AMAX1(W, 3.0, 2.0) + AMIN1(W, 3.0)
ENDPRO
Y = INTGRL(0.0, A + B + C + D + E)
TIMER FINTIM = 2.0, OUTDEL = 0.1
END
"""
    a = run1(text, method="COMPILED", rtol=1e-9, atol=1e-12, advice=False)
    b = run1(text, method="DOP853", rtol=1e-9, atol=1e-12, advice=False)
    assert a.status == "finished" and not [w for w in a.warnings if "DOP853" in w], a.warnings
    # the switches' crossings are located by both routes (the same events, to the
    # solver's tolerance); the plain forms in the PROCEDURE jump where W crosses
    # their edges, stepped over: the rows agree to the tolerance
    assert [e.text for e in a.events] == [e.text for e in b.events]
    assert [e.time for e in a.events] == pytest.approx([e.time for e in b.events], abs=1e-9)
    assert np.max(np.abs(a["Y"] - b["Y"])) <= 1e-6 * np.max(np.abs(b["Y"]))


def test_the_cache_folder_is_made_private_and_a_shared_one_refused(tmp_path):
    """The compiled models' folder holds Python files that are imported and numba
    index files that are unpickled: it is made 0700, and one that other users can
    write (AMILPY_CACHE pointed at a shared folder) is refused, with why."""
    fresh = tmp_path / "mine" / "compiled"
    assert compiled.private_folder(fresh) is None
    assert (fresh.stat().st_mode & 0o777) == 0o700
    assert (fresh.parent.stat().st_mode & 0o777) == 0o700
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    why = compiled.private_folder(shared / "compiled")
    assert why == f"{shared} can be written by other users (mode 777)"


@needs_numba
def test_a_shared_cache_folder_runs_as_dop853_and_says_why(tmp_path, monkeypatch):
    """Nothing is written to or loaded from a folder others can write: the run is
    DOP853's, with the rows DOP853 gives, and one warning naming the folder."""
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv(compiled.ENV_CACHE, str(shared))
    monkeypatch.setattr(compiled, "_BY_SOURCE", {})
    monkeypatch.setattr(compiled, "_LOADED", {})
    a = run1(KNEE, method="COMPILED")
    b = run1(KNEE, method="DOP853")
    assert len(a.warnings) == 1 and "not private" in a.warnings[0]
    assert f"{shared} can be written by other users" in a.warnings[0]
    assert "ran as DOP853" in a.warnings[0]
    assert np.array_equal(a["X"], b["X"])
    assert not any((shared / "compiled").glob("*.py"))


DAMAGED_CACHE_RUN = """
import sys, amilpy
run, = amilpy.loads(sys.argv[1]).run(method="COMPILED", advice=False)
print(run.status, run.warnings, float(run["X"][-1]))
"""


@pytest.mark.slow  # (50 s: CI runs it in the [fast] step, -m slow)
@needs_numba
def test_a_damaged_numba_cache_is_compiled_again(tmp_path):
    """numba reads its cache with pickle and lets a damaged file raise: every METHOD
    COMPILED run then failed at TIME = 0 ("unregistered extension code"). With the
    kernel's and the model's cache files overwritten with noise, the run is compiled
    again and is the same run. (In a process of its own, with numba's and amilpy's
    caches in this test's folder: the kernel is compiled twice, about 20 s.)"""
    import subprocess

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               AMILPY_CACHE=str(tmp_path / "amilpy"), PYTHONPATH=ROOT)

    def run() -> str:
        done = subprocess.run([sys.executable, "-c", DAMAGED_CACHE_RUN, KNEE], env=env,
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        return done.stdout

    first = run()
    assert first.startswith("finished [] ")
    files = [*(tmp_path / "numba").rglob("*.nb[ic]"), *(tmp_path / "amilpy").rglob("*.nb[ic]")]
    assert any("kernel" in f.name for f in files) and any("amilpy_model" in f.name
                                                          for f in files)
    for f in files:
        f.write_bytes(os.urandom(40))
    assert run() == first


@needs_numba
def test_the_compiled_truncations_do_not_wrap_for_large_values():
    """numba compiles AINT and QNTZR's level as written; with integers there, AINT(1E20)
    wrapped to -9.2E18 (past 2**63). In floats they are Python's exactly, at the
    band edges, at zeros of either sign, and far past 2**63; NaN and infinities are
    faults as in Python."""
    import math

    import numba

    from amilpy.library.runtime import fortran_aint
    from amilpy.library.surfaces import level

    aint, lev = numba.njit(fortran_aint), numba.njit(level)
    for x in (0.0, -0.0, 0.5, -0.5, 0.49999999999999994, 1.5, -1.5, 2.5, -2.5,
              2.0**50 + 0.5, 1e20, -1e20, 3.7e300, -3.7, 5e-324):
        k = math.ceil(x - 0.5)
        k = k - 1 if x <= k - 0.5 else k + 1 if x > k + 0.5 else k
        assert aint(x) == fortran_aint(x) == float(math.trunc(x)), x
        assert lev(x) == level(x) == float(k), x
    for bad in (math.nan, math.inf):
        with pytest.raises((ValueError, OverflowError)):
            fortran_aint(bad)
        with pytest.raises((ValueError, OverflowError)):
            level(bad)


@needs_numba
def test_an_ensemble_of_a_listing_that_names_no_method_runs_compiled():
    # With numba installed, the hoist's members (each meets the gap's edges at its own
    # instants, so they cannot be stacked) run on METHOD COMPILED, the kernel compiled
    # once; said in the result, and the members end where plain AUTO runs end (both
    # at RELERR 1e-8: 1e-6 of the twist's range).
    model = amilpy.load(os.path.join(ROOT, "models", "hoist_backlash.amil"))
    mc = model.montecarlo({"ZETA": "uniform(0.004, 0.006)"}, runs=3, seed=2, outputs=["Y"],
                          fintim=0.5, rtol=1e-8)
    assert "METHOD COMPILED" in mc.how
    for k in range(3):
        run, = model.run(method="AUTO", rtol=1e-8, fintim=0.5, outputs=["Y"], advice=False,
                         ZETA=float(mc.samples["ZETA"][k]))
        assert mc.final[k, 0] == pytest.approx(run["Y"][-1], abs=1e-6 * np.ptp(run["Y"]))
    named = model.montecarlo({"ZETA": "uniform(0.004, 0.006)"}, runs=2, seed=2,
                             outputs=["Y"], fintim=0.1, method="AUTO")
    assert named.how == ""  # (a method named: the caller's)


@needs_numba
def test_two_listings_with_the_same_code_and_other_parameters_each_get_theirs():
    # X' = -X in both; the first binds K (read only by INITIAL), the second nothing.
    # The kernel reads parameters by position: one built for the first, reused for the
    # second, asked it for K (a KeyError).
    first = amilpy.loads("PARAM K = 2.0\nINITIAL\n   R = SQRT(K)\nDYNAMIC\n"
                         "X = INTGRL(R, -X)\nMETHOD COMPILED\nTIMER FINTIM = 1.0\nEND\n")
    second = amilpy.loads("X = INTGRL(1.0, -X)\nMETHOD COMPILED\nTIMER FINTIM = 1.0\nEND\n")
    a, = first.run(advice=False)
    b, = second.run(advice=False)
    assert a["X"][-1] == pytest.approx(math.sqrt(2.0) * math.exp(-1.0), rel=1e-6)
    assert b["X"][-1] == pytest.approx(math.exp(-1.0), rel=1e-6)
