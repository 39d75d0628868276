"""A fault in generated code names its statement (the listing's line, the variable it
assigns) and the operation with its operand values, found from the code object's
own line table (issue 10: faults were blamed on the wrong variable and on line 1)."""

import pytest

import amilpy
from amilpy.codegen import Compiler, FaultReport, fault_line, initial_values
from amilpy.language import TIMER_KEYS

CLUTCH = """TITLE A STUDENT'S FIRST CLUTCH
CONST  U = 12.0, R = 2.5, L = 0.3E-3, KT = 0.02, KE = 0.02, J1 = 1.0E-5
PARAM  C = 2.0, B = 1.0E-3
INITIAL
   T1   = 5.0*R*J1/(KT*KE)
   JOBC = 2.0*J1
   MOBC = 0.25*KT*U/R
DYNAMIC
   JL   = FSW(TIME - T1, 0.0, JOBC, JOBC)
   IA   = INTGRL(0.0, (U - R*IA - KE*W1)/L)
   MC   = C*FI1 + B*(W1 - W2)
   FI1  = INTGRL(0.0, W1 - W2)
   W1   = INTGRL(0.0, (KT*IA - MC)/J1)
   W2   = INTGRL(0.0, (MC - MOBC)/JL)
TIMER  FINTIM = 0.5, PRDEL = 0.01
END
"""


def compiled(text: str):
    model = amilpy.loads(text, name="m.amil").ir
    spec = model.runs[0]
    timer = {k: spec.timer.get(k, 1.0) for k in TIMER_KEYS}
    constants = initial_values(model, spec.data, spec.tables, timer)
    return Compiler(model, constants, spec.tables, {}).build()


def fault_of(c, fn, *args):
    with pytest.raises((ArithmeticError, ValueError)) as err:
        fn(*args)
    return err.value


def test_the_clutch_fault_names_w2_and_its_divisor():
    c = compiled(CLUTCH)
    m = [-1.0] * len(c.watched)  # before T1: FSW takes its first value, JL = 0
    exc = fault_of(c, c.rhs, 0.0, c.y0, m, c.z0)
    report = c.explain_fault(exc, 0.0, c.y0, m, c.z0)
    assert isinstance(report, FaultReport)
    assert report.target == "W2" and report.span.line == 14
    assert report.text == "division by zero: JL = 0"
    assert str(report) == "W2 (line 14): division by zero: JL = 0"
    assert fault_line(exc) == 14 and c.fault_line(exc) == 14  # not line 1, the TITLE


def test_a_zero_param_is_blamed_on_the_state_that_divides_by_it():
    c = compiled("PARAM K = 0.0\nX = INTGRL(0.0, 1.0)\nY = INTGRL(1.0, 1.0/K)\n"
                 "TIMER FINTIM = 1\nEND\n")
    exc = fault_of(c, c.rhs, 0.0, c.y0, [], c.z0)
    report = c.explain_fault(exc, 0.0, c.y0, [], c.z0)
    assert str(report) == "Y (line 3): division by zero: K = 0"


def test_an_algebraic_equation_in_the_outputs_is_named():
    c = compiled("X = INTGRL(0.0, 1.0)\nA = 2.0 + 1.0/(X - 1.0)\nB = 2*A\n"
                 "TIMER FINTIM = 2\nEND\n")
    exc = fault_of(c, c.out, 1.0, [1.0], [], c.z0)
    report = c.explain_fault(exc, 1.0, [1.0], [], c.z0)
    assert str(report) == "A (line 2): division by zero: X - 1.0 = 0"


def test_a_math_domain_fault_names_the_function_and_its_argument():
    c = compiled("X = INTGRL(0.0, 1.0)\nV = INTGRL(0.0, ASIN(X) + 1.0)\nTIMER FINTIM = 2\nEND\n")
    y = [2.0, 0.0] if c.state_names == ["X", "V"] else [0.0, 2.0]
    exc = fault_of(c, c.rhs, 1.0, y, [], c.z0)
    report = c.explain_fault(exc, 1.0, y, [], c.z0)
    assert str(report) == "V (line 2): math domain error: ASIN(X) with X = 2"


def test_a_fault_in_a_nested_integral_names_its_statement():
    c = compiled("PARAM K = 0.0\nY = 1.0 + INTGRL(0.0, 1.0/K)\nTIMER FINTIM = 1\nEND\n")
    exc = fault_of(c, c.rhs, 0.0, c.y0, [], c.z0)
    assert str(c.explain_fault(exc, 0.0, c.y0, [], c.z0)) == \
        "INTGRL in Y (line 2): division by zero: K = 0"


def test_a_surface_fault_names_the_switch():
    c = compiled("PARAM P = 0.0\nX = INTGRL(1.0, -X)\nQ = QNTZR(P, X)\nTIMER FINTIM = 1\nEND\n")
    exc = fault_of(c, c.surf, 0.0, c.y0, [0.0], c.z0)
    report = c.explain_fault(exc, 0.0, c.y0, [0.0], c.z0)
    assert report.span.line == 3 and "QNTZR" in report.target
    assert report.text == "division by zero: P = 0"


def test_an_exception_from_elsewhere_is_not_explained():
    c = compiled(CLUTCH)
    try:
        1 / 0  # noqa: B018 - a fault that is not the model's
    except ZeroDivisionError as exc:
        assert c.explain_fault(exc, 0.0, c.y0, [0.0], c.z0) is None
        assert fault_line(exc) is None


def test_a_compiler_that_cannot_nest_so_deep_gives_a_located_error(monkeypatch):
    # CPython 3.12+ bounds the compiler's nesting by its C stack: the error is the model's
    import builtins

    def shallow_compile(*args, **kw):
        raise RecursionError("maximum recursion depth exceeded during compilation")

    model = amilpy.loads("X = INTGRL(0.0, 1.0)\nY = ((X + 1.0)*2.0 - 3.0)/4.0\n"
                         "TIMER FINTIM = 1\nEND\n").ir
    monkeypatch.setattr(builtins, "compile", shallow_compile)
    with pytest.raises(amilpy.AmilError) as err:
        Compiler(model, {}, {}, {}).build()
    assert err.value.line == 2 and "nested too deeply to compile" in err.value.render()
