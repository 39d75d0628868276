"""A model file is data, not code: nothing in it reaches Python's builtins,
imports or attributes, and names that Python knows are ordinary variables."""

import ast
import os
import sys

import pytest
from conftest import run1

import amilpy
from amilpy.cli import main

BUILTIN_NAMES = ["OPEN", "EXEC", "EVAL", "LEN", "SUM", "ID", "IMPORT", "GLOBALS", "LOCALS",
                 "COMPILE", "T", "Y", "M", "Z", "MN", "RHS", "SURF", "OUT", "MEM", "LAMBDA",
                 "NONE", "TRUE", "CLASS", "DEF", "RETURN", "M0", "Z0", "V_X", "H_1"]


def test_python_names_are_ordinary_variables():
    eqs = "\n".join(f" {n} = {k + 1}.0 + 0.0*S" for k, n in enumerate(BUILTIN_NAMES))
    total = " + ".join(BUILTIN_NAMES)
    r = run1(f"DYNAMIC\n S = INTGRL(0.0, 1.0)\n{eqs}\n TOTAL = {total}\n"
             "TIMER FINTIM = 1.0\nEND\n")
    n = len(BUILTIN_NAMES)
    assert r["TOTAL"][-1] == n * (n + 1) / 2
    assert r["OPEN"][0] == 1.0 and r["EVAL"][0] == 3.0


def test_generated_code_is_closed():
    m = amilpy.loads("PARAM K = 1.0\nX = INTGRL(1.0, -K*X*ABS(X))\nY = FSW(X - 0.5, 0, 1, 2)\n"
                     "TIMER FINTIM = 1.0\nEND\n")
    tree = ast.parse(m.python_source())
    kinds = {type(node).__name__ for node in ast.walk(tree)}
    assert not kinds & {"Attribute", "Import", "ImportFrom", "Global", "Lambda", "Subscript"
                        } - {"Subscript"}
    names = {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}
    assert all(n.startswith(("v_", "h_", "p_", "_", "m", "n", "z")) or n in ("t", "y")
               for n in names)


@pytest.mark.parametrize("bad", ["open", "__import__", "os.system"])
def test_the_build_checks_closedness_in_its_placing_walk(bad, monkeypatch):
    """The build checks that generated code reads only the compiler's names in the
    same walk that gives every node its line (`place(..., closed=True)`): a name or
    an attribute the compiler did not put there stops the build, as assert_closed
    would."""
    from amilpy.codegen import build as codegen_build
    from amilpy.codegen.pytree import assert_closed, place
    from amilpy.run import prepare

    injected = ast.parse(bad, mode="eval").body
    emit = codegen_build.Compiler.outputs_function

    def with_injection(self, names):
        fn = emit(self, names)
        fn.body.insert(0, ast.Expr(injected))  # as if an emitter had let text through
        return fn

    monkeypatch.setattr(codegen_build.Compiler, "outputs_function", with_injection)
    m = amilpy.loads("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nEND\n")
    with pytest.raises(AssertionError, match="unknown name|contains Attribute"):
        prepare(m.ir, m.ir.runs[0])
    module = ast.Module(body=[ast.FunctionDef("f", ast.arguments([], [], None, [], [], None,
                                                                 []), [ast.Expr(injected)],
                                              [], None)], type_ignores=[])
    for check in (assert_closed, lambda mod: place(mod, closed=True)):
        with pytest.raises(AssertionError):
            check(module)


def test_generated_functions_have_no_builtins():
    from amilpy.run import prepare

    m = amilpy.loads("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nEND\n")
    compiled = prepare(m.ir, m.ir.runs[0]).code
    assert compiled.rhs.__globals__["__builtins__"] == {}


@pytest.mark.parametrize("text", [
    "X = __import__('os')\n",
    "X = OS.SYSTEM(1)\n",
    "X = A.B\n",
    "X = 'rm -rf'\n",
    'X = "abc"\n',
    "X = A \\ B\n",
    "X = EVAL(1)\n",
    "X = EXEC(1)\n",
    "X = OPEN(1)\n",
    "X = GETATTR(A, B)\n",
    "X = 1; import os\n",
    "X = [1]\n",
    "X = {1}\n",
    "X = lambda: 1\n",
    "TITLE ok'); import os; os.system('touch pwned') #\nX = 1.0\n",
    "FUNCTION __CLASS__ = 0,0, 1,1\n",
    "X = 1e999999\n",
])
def test_injection_attempts_do_nothing(text, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "evil.amil"
    path.write_text(text + "TIMER FINTIM = 1.0\nEND\n")
    before_modules = set(sys.modules)
    code = main(["run", str(path), "--quiet"])
    assert code in (0, 1)
    assert sorted(os.listdir(tmp_path)) == ["evil.amil"]  # nothing created
    new = set(sys.modules) - before_modules
    assert not any(m.split(".")[0] in ("os", "subprocess", "shutil", "socket") for m in new)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if code == 1:
        assert "evil.amil:" in err
