"""The checker: faults it reports with their place, and the shape of the IR it builds."""

import pytest

import amilpy
from amilpy.diagnostics import AmilError


def fault(text: str) -> AmilError:
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, name="m.amil")
    return err.value


@pytest.mark.parametrize("section", ["INITIAL", "TERMINAL"])
def test_termt_outside_dynamic_is_a_located_error(section):
    # it used to end in "'Termt' object has no attribute 'targets'"
    text = f"{section}\n TERMT(TIME - 1.0)\nDYNAMIC\n X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 2\nEND\n"
    err = fault(text)
    assert (err.line, err.column) == (2, 2)
    assert f"TERMT cannot stand in {section}" in err.render()
    assert "put it in DYNAMIC" in err.render()


def test_fintim_missing_points_at_the_timer_statement():
    err = fault("X = INTGRL(0.0, 1.0)\nTIMER PRDEL = 0.1\nEND\n")
    assert err.diagnostics[0].message == "FINTIM is not given"
    assert err.line == 2
    assert "add FINTIM to this TIMER statement" in err.render()


def test_fintim_missing_without_timer_has_no_place():
    err = fault("X = INTGRL(0.0, 1.0)\nEND\n")
    assert err.diagnostics[0].span is None and "add a TIMER statement" in err.render()


@pytest.mark.parametrize("kind", ["RELERR", "ABSERR"])
def test_a_tolerance_for_an_unknown_name_is_an_error(kind):
    # it used to be ignored (ABSERR) or to tighten every state (RELERR)
    err = fault(f"POS = INTGRL(1.0, VEL)\nVEL = INTGRL(0.0, -POS)\n"
                f"{kind} POS = 1E-3, VELO = 1E-9\nTIMER FINTIM = 1\nEND\n")
    assert (err.line, err.column) == (3, 20)
    assert f"{kind} names VELO, which is not a variable of the model" in err.render()
    assert "did you mean VEL?" in err.render()


def test_a_tolerance_for_an_algebraic_variable_names_the_states():
    err = fault("X = INTGRL(1.0, -X)\nW = 2*X\nRELERR W = 1E-3\nTIMER FINTIM = 1\nEND\n")
    assert "RELERR names W, which is not a state" in err.render()
    assert "applies to a state (an INTGRL output): X" in err.render()


def test_tolerances_for_states_are_kept_per_state():
    m = amilpy.loads("X = INTGRL(1.0, -X)\nY = INTGRL(1.0, -Y)\nRELERR X = 1E-3\n"
                     "ABSERR Y = 1E-12\nTIMER FINTIM = 1\nEND\n")
    spec = m.ir.runs[0]
    assert spec.relerr_each == {"X": 1e-3} and spec.abserr_each == {"Y": 1e-12}


def test_switches_on_one_surface_share_it():
    # issue 15: X' = -FSW(X, ...) and Y' = FSW(X, ...) must slide on one surface
    m = amilpy.loads("X = INTGRL(1.0, -FSW(X, -1.0, 0.0, 1.0))\n"
                     "Y = INTGRL(0.0, FSW(X, -1.0, 0.0, 1.0))\n"
                     "Z = INTGRL(0.0, FSW( x , -1.0, 0.0, 1.0) + INSW(X, 0.0, 1.0))\n"
                     "TIMER FINTIM = 3\nEND\n").ir
    assert len(m.switches) == 4
    assert {sw.surfaces for sw in m.switches} == {(0,)}
    assert len(m.surfaces) == 1


def test_different_surfaces_stay_apart():
    m = amilpy.loads("X = INTGRL(1.0, -FSW(X, -1.0, 0.0, 1.0))\n"
                     "Y = INTGRL(0.0, FSW(X - 0.5, -1.0, 0.0, 1.0) + QNTZR(1.0, X))\n"
                     "FINISH X = 0.0\nTIMER FINTIM = 3\nEND\n").ir
    # X, X - 0.5, QNTZR's X/1.0 (a level surface) and FINISH's X - 0.0
    assert len(m.surfaces) == 4
    assert [str(s.purpose) for s in m.surfaces] == ["switch", "switch", "switch", "finish"]


def test_limit_shares_its_surfaces_with_a_dead_zone_on_the_same_input():
    m = amilpy.loads("X = INTGRL(1.0, -X)\nA = LIMIT(-0.5, 0.5, X)\nB = DEADSP(-0.5, 0.5, X)\n"
                     "TIMER FINTIM = 1\nEND\n").ir
    assert m.switches[0].surfaces == m.switches[1].surfaces
    assert len(m.surfaces) == 2


def _work(listing: str) -> tuple[int, int]:
    """(visits of syntax/IR nodes, characters of generated code) for check + compile."""
    from amilpy.codegen import Compiler
    from amilpy.parse.syntax import Visitor

    calls = [0]
    visit = Visitor.visit

    def counting(self, node, *args):
        calls[0] += 1
        return visit(self, node, *args)

    Visitor.visit = counting
    try:
        model = amilpy.loads(listing).ir
        c = Compiler(model, {}, {}, {}).build()
    finally:
        Visitor.visit = visit
    return calls[0], len(c.source)


@pytest.mark.parametrize("func", ["LIMIT(-1.0, 1.0, ", "DEADSP(-0.1, 0.1, ", "ZHOLD(X, ",
                                  "FSW(X - 0.5, 0.0, 1.0, "])
def test_nesting_depth_n_costs_order_n(func):
    """Issue 15: 16 nested LIMITs took 100 s (each level tripled the work). Doubling
    the depth must at most double the work of checking and compiling (counted in
    node visits and generated characters, not seconds), also in INITIAL."""
    def listing(n):
        e = func * n + "X" + ")" * n
        initial = e.replace("X", "0.3") if "ZHOLD" not in func else "0.3"
        return (f"X = INTGRL(1.0, -X)\nY = {e}\nINITIAL\nA = {initial}\nDYNAMIC\n"
                "TIMER FINTIM = 1\nEND\n")

    (v1, s1), (v2, s2), (v4, s4) = (_work(listing(n)) for n in (32, 64, 128))
    assert v2 / v1 < 2.3 and v4 / v2 < 2.3
    assert s2 / s1 < 2.3 and s4 / s2 < 2.3


def test_surfaces_carry_their_text_and_a_readable_description():
    m = amilpy.loads("PARAM T1 = 0.5, P1 = -1.0, P2 = 1.0\nW1 = INTGRL(1.0, -W1)\n"
                     "S = FSW(W1, 0.0, 1.0, 2.0) + fcnsw(time - t1, 0.0, 1.0, 1.0)\n"
                     "L = BOUND(P1, P2, X)\nX = W1*2.0\nZ = ZHOLD(W1 - 0.5, W1)\n"
                     "FINISH W1 = 0.1\nTERMT(W1 - 2.0)\nTIMER FINTIM = 1\nEND\n").ir
    assert [(s.text, s.description) for s in m.surfaces] == [
        ("W1", "FSW(W1, ...) at line 3"),
        ("TIME - T1", "FCNSW(TIME - T1, ...) at line 3"),
        ("X - P1", "BOUND(P1, ...) at line 4"),
        ("X - P2", "BOUND(P1, ...) at line 4"),
        ("W1 - 0.5", "ZHOLD(W1 - 0.5, ...) at line 6"),
        ("W1 - 0.1", "FINISH W1=0.1"),
        ("W1 - 2.0", "TERMT(W1 - 2.0) at line 8"),
    ]
    # the written name is kept (FSW stays FSW, BOUND stays BOUND)
    assert [sw.written for sw in m.switches] == ["FSW", "FCNSW", "BOUND"]


def test_a_long_surface_text_is_shortened():
    long = " + ".join(f"W{k}" for k in range(40))
    m = amilpy.loads(f"W0 = INTGRL(1.0, -W0)\nY = FSW({long}, 0.0, 1.0, 2.0)\n"
                     + "".join(f"W{k} = {k}*W0\n" for k in range(1, 40))
                     + "TIMER FINTIM = 1\nEND\n").ir
    s = m.surfaces[0]
    assert s.text.startswith("W0 + W1 + W2") and s.text.endswith("...")
    assert len(s.text) <= 60 and len(s.description) < 90


@pytest.mark.parametrize("listing", ["ok", "bad"])
def test_check_imports_neither_scipy_nor_matplotlib(tmp_path, listing):
    """`amilpy check` parses and checks: it needs neither the integrators nor the
    plots, and importing them costs more than the check itself (SciPy's integrate
    alone about 0.3 s). Guards every path: a clean listing and one with an error."""
    import subprocess
    import sys

    path = tmp_path / "m.amil"
    path.write_text("X = INTGRL(1.0, -K*X)\nPARAM K = 2.0\nTIMER FINTIM = 1.0\nEND\n"
                    if listing == "ok" else "X = INTGRL(1.0, -K*X\nTIMER FINTIM = 1.0\nEND\n")
    code = ("import sys\nfrom amilpy.cli import main\n"
            f"rc = main(['check', {str(path)!r}])\n"
            "heavy = sorted({m.split('.')[0] for m in sys.modules} & {'scipy', 'matplotlib'})\n"
            "print(rc, ','.join(heavy) or '-')\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    rc, heavy = done.stdout.split()[-2:]
    assert heavy == "-", done.stdout
    assert rc == ("0" if listing == "ok" else "1"), done.stdout + done.stderr
