"""Each language function is one library entry: the checker and the compiler read it,
and a new function (CSMP's DELAY) is one entry plus its tests and its editor line."""

import re
from pathlib import Path

import numpy as np
import pytest
from conftest import run1

import amilpy
from amilpy import library
from amilpy.diagnostics import AmilError
from amilpy.library import Func, Kind, MemorySpec, lookup

ROOT = Path(__file__).resolve().parent.parent

P = 0.5
DELAYED = f"""
PARAM P = {P}
X = SIN(TIME)
D = DELAY(100, P, X)
Y = INTGRL(0.0, DELAY(100, P, COS(TIME)))
TIMER FINTIM = 3.0, OUTDEL = 0.01
END
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU", "RK4", "BDF", "DOP853", "TRAPZ"])
def test_delay_against_the_delayed_sine(method):
    """DELAY(N, P, X) is X(t0) before t0 + P and X(t - P) after.

    The store keeps X every P/N = 0.005, taken from the dense output, and is read
    linearly: the rows' t - P are stored instants (exact), the derivative reads between
    them, off by at most 0.005**2/8 * max|X''| = 3.1e-6, which integrates over the
    2.5 s after P to at most 3.1e-6 * 1.6 = 5e-6 (tests/test_delay.py has the rest)."""
    r = run1(DELAYED, method=method)
    assert r.ok
    t = r.t
    assert np.max(np.abs(r["D"] - np.where(t < P, 0.0, np.sin(t - P)))) < 1e-12
    # Y' = 1 before P (X(t0) = cos 0), then cos(t - P): Y = P + sin(t - P)
    assert np.max(np.abs(r["Y"] - np.where(t < P, t, P + np.sin(t - P)))) < 5e-6


def test_delay_error_falls_with_the_square_of_the_points():
    """N sizes the store: the interpolation error is (P/N)**2/8 * max|X''|."""
    errors = []
    for n in (5, 10):
        r = run1(DELAYED.replace("DELAY(100, P, X)", f"DELAY({n}, P, X)"), method="RK4")
        t = r.t
        errors.append(np.max(np.abs(r["D"] - np.where(t < P, 0.0, np.sin(t - P)))))
    assert errors[0] <= (P / 5) ** 2 / 8 * 1.0001
    assert 3.5 < errors[0] / errors[1] < 4.5


def test_delay_of_a_state_starts_from_its_initial_value():
    # X(t0) = 2 is held for P; after that the delayed decay 2*exp(-(t - P)), read at
    # stored instants (X from the dense output there: the integrator's own error)
    r = run1("X = INTGRL(2.0, -X)\nD = DELAY(400, 1.0, X)\nTIMER FINTIM = 2.0, OUTDEL = 0.01\n"
             "END\n", method="RKS")
    t = r.t
    expect = np.where(t < 1.0, 2.0, 2.0 * np.exp(-(t - 1.0)))
    assert np.max(np.abs(r["D"] - expect)) < 1e-11


@pytest.mark.parametrize("call, message", [
    ("DELAY(N, 0.5, X)", "N of DELAY must be a whole number written out"),
    ("DELAY(2.5, 0.5, X)", "N of DELAY must be a whole number written out"),
    ("DELAY(0, 0.5, X)", "N of DELAY must be a whole number written out"),
    ("DELAY(10, X, X)", "P of DELAY uses X, which changes in time"),
    # CSMP's form takes 3, ACSL's (section 12) 4 or 5: the message counts both
    ("DELAY(10, 0.5)", "DELAY takes 3, 4 or 5 arguments, got 2"),
])
def test_delay_arguments_are_checked(call, message):
    with pytest.raises(AmilError) as err:
        amilpy.loads(f"PARAM N = 3\nX = INTGRL(1.0, -X)\nD = {call}\nTIMER FINTIM = 1\nEND\n")
    assert message in str(err.value.render())
    assert err.value.line == 3


def test_delay_is_one_entry_and_in_the_editor_grammar():
    entry = lookup("DELAY")
    assert entry.kind == Kind.MEMORY and entry.memory.every_step
    grammar = (ROOT / "editors/vscode/syntaxes/amil.tmLanguage.json").read_text("utf-8")
    assert re.search(r"\|DELAY\|", grammar)


def test_memory_entries_decide_what_the_runner_reads():
    def compiled(body):
        from amilpy.codegen import Compiler

        m = amilpy.loads(body + "\nTIMER FINTIM = 1\nEND\n").ir
        return Compiler(m, {}, {}, {}).build()

    # ZHOLD and PULSE change only at events; HSTRSS needs every step
    assert not compiled("X = INTGRL(0.0, 1.0)\nH = ZHOLD(X - 0.5, X)").memory_every_step
    assert compiled("X = INTGRL(0.0, 1.0)\nH = HSTRSS(0.0, -0.1, 0.1, X)").memory_every_step
    c = compiled("X = INTGRL(0.0, 1.0)\nH = PULSE(0.3, X - 0.5)")
    assert c.memory_times([2.5], 1.0) == [2.5] and c.memory_times([0.5], 1.0) == []


def test_a_variant_is_chosen_by_its_number_of_arguments():
    one = Func("TWOFORMS", Kind.MATH, "TWOFORMS(X)", scalar=abs, vector="abs",
               variants=(Func("TWOFORMS", Kind.MATH, "TWOFORMS(X, Y)", scalar=min,
                              vector="minimum"),))
    library.register(one)
    try:
        assert lookup("TWOFORMS", 1).signature == "TWOFORMS(X)"
        assert lookup("TWOFORMS", 2).signature == "TWOFORMS(X, Y)"
        assert lookup("TWOFORMS").signatures() == "TWOFORMS(X) or TWOFORMS(X, Y)"
        r = run1("A = TWOFORMS(-3.0)\nB = TWOFORMS(-3.0, TIME)\nTIMER FINTIM = 1\nEND\n")
        assert r["A"][0] == 3.0 and r["B"][-1] == -3.0
    finally:
        del library.FUNCTIONS["TWOFORMS"]


@pytest.mark.parametrize("memory, message", [
    (MemorySpec("1", ("0.0",), "(B if M0 > 0 else Z0)", ("VALUE",)), "M0 means nothing"),
    (MemorySpec("1", ("0.0",), "Z0", ("OPEN(A)",)), "calls name a math function"),
    (MemorySpec("1", ("0.0",), "Z0.real", ("VALUE",)), "Attribute is not allowed"),
])
def test_a_wrong_template_fails_when_registered(memory, message):
    with pytest.raises(ValueError, match=message):
        library.register(Func("BROKEN", Kind.MEMORY, "BROKEN(X, Y)", memory=memory))
    assert "BROKEN" not in library.FUNCTIONS


def test_no_function_is_known_by_name_outside_the_library():
    """check and codegen read entries: no `func.name == "X"` / `func == "X"` chains."""
    names = set(library.FUNCTIONS) | set(library.ALIASES)
    pattern = re.compile(r"""(func|\.name|\.func)\s*(==|in)\s*\(?["']([A-Z0-9]+)["']""")
    for path in [*ROOT.glob("amilpy/check/*.py"), *ROOT.glob("amilpy/codegen/*.py"),
                 ROOT / "amilpy/check.py", ROOT / "amilpy/codegen.py"]:
        if path.exists():
            for m in pattern.finditer(path.read_text("utf-8")):
                assert m.group(3) not in names, f"{path.name}: {m.group(0)}"


def test_every_entry_documents_itself():
    for name, func in library.FUNCTIONS.items():
        assert func.signature.startswith(name + "("), name
        if func.kind != Kind.MATH:
            assert func.doc, name


@pytest.mark.parametrize("func", ["AFGEN", "NLFGEN"])
def test_a_table_lookup_of_nan_is_nan(func):
    # issue 15: an IndexError off the end of the table
    from amilpy.library import runtime

    table = ((0.0, 1.0, 2.0), (0.0, 1.0, 4.0))
    assert np.isnan(getattr(runtime, func.lower())(table, float("nan")))
    r = run1(f"FUNCTION F = 0.0, 0.0, 1.0, 1.0, 2.0, 4.0\nPARAM Z = 0.0\n"
             f"Y = {func}(F, SQRT(TIME - 0.5) + Z)\nTIMER FINTIM = 1.0, OUTDEL = 0.25\nEND\n",
             method="RK4")
    # the table is y = x*x at its points: linear between them, exact quadratically
    x = np.sqrt(0.5)
    assert np.isnan(r["Y"][0]) and r["Y"][-1] == pytest.approx(
        x if func == "AFGEN" else x * x, rel=1e-12)


def test_a_memory_condition_is_read_on_the_spot_when_nothing_is_watched():
    """events=False (comparisons) watches only FINISH/TERMT: ZHOLD's condition is then
    read where it is evaluated (it was a KeyError in the compiler)."""
    r = run1("X = INTGRL(0.0, 1.0)\nH = ZHOLD(X - 0.5, X)\nTIMER FINTIM = 1, OUTDEL = 0.1\n"
             "END\n", events=False)
    assert r.ok and r["H"][-1] == pytest.approx(1.0) and r["H"][3] == 0.0


def test_a_level_is_exact_at_its_band_edges():
    # QNTZR's level k holds (k - 1/2, k + 1/2]; v - 1/2 rounds (-0.49999999999999994
    # - 0.5 is -1.0, which made the level -1), so the band is checked: scalar and
    # elementwise alike
    from amilpy.library.runtime import vector_helpers
    from amilpy.library.surfaces import level

    v = [-0.49999999999999994, -0.5, 0.5, 0.49999999999999994, 1.5, -1.5, 2.5000000000000004]
    want = [0.0, -1.0, 0.0, 0.0, 1.0, -2.0, 3.0]
    assert [level(x) for x in v] == want
    assert list(vector_helpers()["LEVEL"](np.array(v))) == want
