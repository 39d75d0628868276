"""A run keeps its generated code objects, not the syntax trees they were compiled
from (issue 29.3: a 1000-mass chain's trees took 46 MB after its first run): the
trees are built again, the same, for their rare users; rhs's tree is kept only until
the rolled rhs and the Jacobian (or, for a large model with a narrow band, only where
its entries are) are made from it; placing leaves the end positions to compile(),
which gives the same code."""

from __future__ import annotations

import ast
import os
import sys
import types

import numpy as np
import pytest

import amilpy
from amilpy.codegen import jacobian, rolled
from amilpy.run import prepare
from amilpy.run.acsl import prepare_acsl

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(HERE, "benchmarks"))
from scale import chain_listing  # noqa: E402

TEMPLATES = """PARAM K = 2.0
X = INTGRL(1.0, -K*LIMIT(-0.5, 0.5, X) + FSW(X - 0.2, 0.0, 1.0, 2.0))
H = ZHOLD(X - 0.5, X)
D = DELAY(10, 0.1, X)
P = PULSE(0.3, X - 0.5)
Y = INTGRL(0.0, D + H + P)
IF (X > 0.0) THEN
   F = -X
ELSE
   F = -2.0*X
END IF
V = INTGRL(0.0, F)
TIMER FINTIM = 1.0, PRDEL = 0.1
END
"""


def _compiled(source: str):
    if source.endswith(".csl"):
        model = amilpy.load(source)
        return prepare_acsl(model.ir, model.ir.runs[0]).code
    model = amilpy.load(source) if source.endswith(".amil") else amilpy.loads(source)
    return prepare(model.ir, model.ir.runs[0]).code


def _same(code: types.CodeType) -> tuple:
    """What a code object does and where each instruction is, its constants' too."""
    consts = tuple(_same(k) if isinstance(k, types.CodeType) else (type(k), repr(k))
                   for k in code.co_consts)
    return (code.co_name, code.co_code, consts, code.co_names, code.co_varnames,
            code.co_linetable, tuple(code.co_positions()), code.co_filename)


def _functions(codes) -> dict[str, tuple]:
    return {k.co_name: _same(k) for code in codes for k in code.co_consts
            if isinstance(k, types.CodeType)}


SOURCES = [os.path.join(HERE, "models", "ex4_clutch.amil"),
           os.path.join(HERE, "models", "hoist_backlash.amil"),
           os.path.join(HERE, "tests", "golden", "acsl_procedural.csl"),
           os.path.join(HERE, "tests", "golden", "acsl_bounce.csl"),
           TEMPLATES, chain_listing(30)]


@pytest.mark.parametrize("source", SOURCES, ids=lambda s: os.path.basename(s)[:20])
def test_the_tree_built_again_is_the_one_the_kept_code_was_compiled_from(source):
    # every function, its code and its line table (so a fault's line is found in the
    # tree built again), and each call builds a new tree, the caller's to change
    c = _compiled(source)
    module = c.module
    assert module is not c.module
    names = [f.name for f in module.body]
    # (surf_vec and out_vec only where a condition must become elementwise: else surf
    # and out work on columns themselves)
    assert [n for n in names if not n.endswith("_vec")][:5] == \
        ["rhs", "surf", "modes", "out", "mem"]
    kept = _functions(c.binder.code)  # (a code object per group, compiled as built)
    assert _functions([compile(module, c.model.path or c.model.name, "exec")]) == kept
    assert set(kept) == set(names)
    # what the built module says is what it always said: its text
    assert c.source == ast.unparse(module)


def test_rhs_tree_is_let_go_once_the_rolled_rhs_and_the_jacobian_are_made():
    c = _compiled(chain_listing(200))
    assert c.binder.rhs_tree is not None
    assert rolled.for_compiled(c) is not None
    assert c.binder.rhs_tree is not None  # (the Jacobian still needs it)
    jac = jacobian.for_compiled(c)
    assert c.binder.rhs_tree is None
    # the Jacobian that took rhs's statements is the one made from a copy
    fresh = jacobian.build(c.module, len(c.state_names), c.tables,
                           {k: v for k, v in c.namespace.items() if k.startswith("p_")})
    assert jac.source == fresh.source
    assert np.array_equal(jac.rows, fresh.rows) and np.array_equal(jac.cols, fresh.cols)
    y = np.random.default_rng(5).normal(size=len(c.state_names)).tolist()
    assert np.array_equal(jac.values(0.3, y, [], []), fresh.values(0.3, y, [], []))
    # a user after them (an ensemble's elementwise rhs) gets rhs built again
    functions = c.binder.over_members({n: np.full(3, c.constants[n])
                                       for n in c.binder.parameters})
    rows = [np.full(3, v) for v in y]
    assert np.allclose(np.asarray(functions["rhs_vec"](0.3, rows, [], []))[:, 0],
                       c.rhs(0.3, y, [], []), rtol=1e-12, atol=0)


def test_a_rhs_the_jacobian_cannot_take_is_left_as_it_was(monkeypatch):
    c = _compiled(TEMPLATES)
    rhs = c.binder.rhs_function()
    before = ast.dump(rhs, include_attributes=True)

    def refuse(self, e, j):
        raise NotImplementedError("BinOp")

    monkeypatch.setattr(jacobian._Deriv, "d_BinOp", refuse)
    with pytest.raises(NotImplementedError):
        jacobian.tree(rhs, len(c.state_names), own=True)
    assert ast.dump(rhs, include_attributes=True) == before


def test_placing_leaves_the_ends_to_compile_which_takes_them_for_the_starts():
    # no node keeps an end (half of a placed node's positions), and the code is the
    # one with every end set to its start, byte for byte in what it does and where
    c = _compiled(TEMPLATES)
    module = c.module
    located = [n for n in ast.walk(module) if "lineno" in n._attributes]
    assert located and not any("end_lineno" in vars(n) for n in located)
    path = c.model.path or c.model.name
    bare = _functions([compile(module, path, "exec")])
    for node in located:
        node.end_lineno, node.end_col_offset = node.lineno, node.col_offset
    assert _functions([compile(module, path, "exec")]) == bare


def test_the_structure_is_where_the_jacobian_can_be_nonzero():
    # the dependency graph alone: every entry the built Jacobian has is in it (the
    # rest: a switch's branch whose derivative is zero in the branch at hand); none
    # for an rhs with a unit's IF, whose Jacobian is built
    for source in (chain_listing(30), SOURCES[0], SOURCES[1]):
        c = _compiled(source)
        rows, cols = jacobian.structure(c.binder.rhs_function())
        jac = jacobian.for_compiled(c)
        entries = set(zip(rows.tolist(), cols.tolist(), strict=True))
        assert set(zip(jac.rows.tolist(), jac.cols.tolist(), strict=True)) <= entries
        if source is not SOURCES[1]:  # (the hoist's backlash: branches of zero slope)
            assert len(entries) == jac.nnz
    assert jacobian.structure(_compiled(TEMPLATES).binder.rhs_function()) is None


def test_a_large_narrow_model_lets_odeint_difference_its_band(monkeypatch):
    # 600 masses (1,200 states, band 7 once renumbered): the rolled rhs and the
    # structure are made with the build and rhs's tree let go at once, the model's
    # Jacobian is never built, and the run is the one with the built Jacobian to
    # within its tolerance (the Jacobian steers LSODA's Newton iterations only: 4e-15
    # apart on the 3,000-mass chain, RELERR 1e-8 asked here)
    from amilpy.codegen import build

    text = chain_listing(600).replace("OUTDEL = 0.02", "OUTDEL = 0.1")
    model = amilpy.loads(text)
    r, = model.run(advice=False, rtol=1e-8, atol=1e-11)
    c = model.flow().code
    assert c.binder.rhs_tree is None and c.shared["rolled"] is not None
    assert "jacobian" not in c.shared and c.shared["structure"] is not None
    monkeypatch.setattr(build, "EARLY_FROM", 10**9)
    lazy = amilpy.loads(text)
    built, = lazy.run(advice=False, rtol=1e-8, atol=1e-11)
    assert "jacobian" in lazy.flow().code.shared
    for name in ("X1", "V1", "X300", "V300"):
        scale = float(np.max(np.abs(built[name])))
        assert np.max(np.abs(r[name] - built[name])) <= 1e-6 * scale
    # a run that needs the Jacobian after all builds rhs's tree again for it
    jac = jacobian.for_compiled(c)
    assert jac.nnz and set(zip(jac.rows.tolist(), jac.cols.tolist(), strict=True)) <= \
        set(zip(*(a.tolist() for a in c.shared["structure"]), strict=True))


def test_surf_and_out_are_copied_for_columns_only_where_a_condition_needs_it():
    # the chain has no condition: its surf and out are their own column versions (a
    # second copy of a large model's out took a quarter of its compile); the
    # templates' out has LIMIT's and FSW's conditions, made elementwise in its copy
    chain, templates = _compiled(chain_listing(30)), _compiled(TEMPLATES)
    assert not {"surf_vec", "out_vec"} & _functions(chain.binder.code).keys()
    assert "out_vec" in _functions(templates.binder.code)
    rows = np.random.default_rng(3).normal(size=(len(chain.state_names), 4))
    columns = np.array(chain.out_v(0.5, list(rows), [], []), dtype=float)
    for k in range(4):  # (NumPy's power and Python's may differ in the last bit)
        assert np.allclose(columns[:, k], chain.out(0.5, rows[:, k].tolist(), [], []),
                           rtol=1e-14, atol=0)
