"""The checked visitor over syntax and IR nodes (pylox's NodeVisitor, checked at import)."""

import pytest

import amilpy
from amilpy import ir
from amilpy.diagnostics import Span
from amilpy.parse import syntax
from amilpy.parse.syntax import NODES, Visitor

SP = Span(1, 1)


def test_a_visitor_naming_no_node_fails_when_defined():
    with pytest.raises(TypeError, match="visit_Nmu names no node class"):
        class Typo(Visitor):  # noqa: F841 - defining it is the test
            def visit_Nmu(self, node):
                return node


def test_a_complete_visitor_missing_a_node_fails_when_defined():
    with pytest.raises(TypeError, match="declared complete but does not visit Impulse"):
        class Partial(Visitor):  # noqa: F841
            complete = ir.EXPRESSIONS

            def visit_Num(self, e): ...
            def visit_Name(self, e): ...
            def visit_Call(self, e): ...
            def visit_BinOp(self, e): ...
            def visit_Neg(self, e): ...
            def visit_Not(self, e): ...
            def visit_SwitchValue(self, e): ...
            def visit_MemoryValue(self, e): ...
            def visit_TableLookup(self, e): ...
            def visit_UnitValue(self, e): ...


def test_the_complete_visitors_of_amilpy_are_checked_complete():
    # every module with a complete visitor imports cleanly (else the import fails)
    from amilpy.parse import unparse  # noqa: F401

    complete = [v for v in _all_subclasses(Visitor)
                if v.complete and v.__module__.startswith("amilpy")]
    assert len(complete) >= 5
    for v in complete:
        for node in v.complete:
            assert hasattr(v, "visit_" + node.__name__), (v, node)


def _all_subclasses(cls):
    out = []
    for sub in cls.__subclasses__():
        out.append(sub)
        out.extend(_all_subclasses(sub))
    return out


def test_families_hold_every_expression_node():
    # a node added to syntax or ir must join a family, or no complete visitor sees it
    families = set(ir.EXPRESSIONS) | set(syntax.STATEMENTS) | set(ir.CODE) \
        | set(syntax.RESOLVED_BY_READER)
    # pieces of statements, not visited alone
    parts = {syntax.DataItem, syntax.Setting, syntax.Branch, syntax.Item}
    assert set(NODES.values()) == families | parts
    assert set(syntax.EXPRESSIONS) < set(ir.EXPRESSIONS)


def test_an_unhandled_node_in_a_partial_visitor_says_so():
    class OnlyNums(Visitor):
        def visit_Num(self, e):
            return e.value

    assert OnlyNums().visit(syntax.Num(2.0, SP)) == 2.0
    with pytest.raises(TypeError, match="cannot visit Name"):
        OnlyNums().visit(syntax.Name("X", SP))


def test_walk_is_iterative_and_in_source_order():
    e = syntax.Num(1.0, SP)
    for k in range(50_000):  # far deeper than Python's recursion limit
        e = syntax.BinOp("+", e, syntax.Name(f"X{k}", SP), SP)
    nodes = list(syntax.walk(e))
    assert len(nodes) == 100_001
    call = syntax.Call("F", (syntax.Name("A", SP), syntax.Name("B", SP)), SP)
    assert [n.name for n in syntax.walk(call) if isinstance(n, syntax.Name)] == ["A", "B"]


def _walk_by_children(node):
    """walk as it is defined: every node, then its `children()` in order."""
    out, stack = [], [node]
    while stack:
        n = stack.pop()
        out.append(n)
        stack.extend(reversed(n.children()))
    return out


@pytest.mark.parametrize("path", ["models/ex4_clutch.amil", "models/hoist_backlash.amil",
                                  "models/examples/oral_dosing.csl",
                                  "models/examples/fst_wheat.fst",
                                  "models/examples/csmp_diode_filter.amil"])
def test_walk_visits_what_children_says(path):
    """`walk` reads the child fields itself (it is the front end's busiest loop);
    it must visit exactly the nodes, in the order, that `children()` gives, also
    for the classes that define `children()` themselves (IF branches, IR nodes)."""
    from pathlib import Path

    from amilpy.parse import parse

    file = Path(__file__).resolve().parents[1] / path
    model = amilpy.load(file).ir
    roots = list(parse(file.read_text(), str(file)).statements)
    roots += [e.expr for e in model.dynamic] + [s.deriv for s in model.states]
    roots += [a for sw in model.switches for a in sw.args]
    if_block = syntax.If((syntax.Branch(syntax.Name("C", SP), (), SP),
                          syntax.Branch(None, (), SP)), SP)
    for root in [*roots, if_block]:
        assert list(syntax.walk(root)) == _walk_by_children(root)


def test_children_of_ir_nodes_do_not_enter_instances():
    # a switch's arguments live on the instance: its value node has no children
    assert ir.SwitchValue(0, SP).children() == ()
    look = ir.TableLookup("F", syntax.Name("X", SP), "AFGEN", SP)
    assert look.children() == (syntax.Name("X", SP),)


def test_equations_print_in_the_listing_notation():
    from amilpy.output.report.document import equation_lines

    m = amilpy.loads("Y = INTGRL(0.0, -X**2/(A - B) - (C - D))\n"
                     "X = FSW(Y, 1.0, 2.0, BOUND(0.0, 1.0, Y))\n"
                     "PARAM A = 1, B = 2, C = 3, D = 4\nTIMER FINTIM = 1\nEND\n")
    text = dict((line.split(" = ")[0], line) for _, line in equation_lines(m.ir))
    assert text["X"] == "X = FSW(Y, 1.0, 2.0, BOUND(0.0, 1.0, Y))"
    assert text["dY/dt"].startswith("dY/dt = -X**2/(A - B) - (C - D)")


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


def _exprs():
    leaf = st.sampled_from(["X", "K", "TIME", "1.0", "2.", ".5", "1.5D-3", "3"])
    return st.recursive(leaf, lambda sub: st.one_of(
        st.tuples(sub, st.sampled_from(["+", "-", "*", "/", "**"]), sub).map(
            lambda t: f"({t[0]}){t[1]}({t[2]})"),
        sub.map(lambda s: f"-({s})"),
        st.tuples(st.sampled_from(["SIN", "AMAX1", "FSW"]), st.lists(sub, min_size=1,
                                                                      max_size=3)).map(
            lambda t: f"{t[0]}({', '.join(t[1])})")), max_leaves=12)


def _shape(e):
    """The structure of an expression, spans aside."""
    if isinstance(e, syntax.Num):
        return e.value
    if isinstance(e, syntax.Name):
        return e.name
    return (type(e).__name__, getattr(e, "op", getattr(e, "func", "")),
            *map(_shape, e.children()))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(_exprs())
def test_text_reads_back_as_the_same_expression(text):
    """unparse(parse(e)) parses to the same tree: the text is the listing's notation,
    with no parenthesis missing (and its precedence rules are Fortran's)."""
    from amilpy.parse import parse
    from amilpy.parse.unparse import expr_text

    first = parse(f"Y = {text}\n").statements[0].expr
    again = parse(f"Y = {expr_text(None, first)}\n").statements[0].expr
    assert _shape(again) == _shape(first)
