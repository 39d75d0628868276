"""The parse tree made as rules reduce (amilpy/parse/tree.py) against lark's own:
the same nodes, children, tokens and spans as lark's tree builder with
`propagate_positions` gives, the expressions made as they reduce equal to those the
builder makes by walking, and a syntax fault raised as lark's parse raises it."""

import glob
import os
from functools import lru_cache

import pytest

from amilpy.parse import _parser
from amilpy.parse.build import Builder
from amilpy.parse.lexical import prepare
from amilpy.parse.tree import Node, read

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# constructs whose spans lark's position rule decides in less obvious ways: filtered
# keywords and parentheses at a node's ends, a parenthesised operand, [...] left out,
# _rules inlined, one-child ?rules, strings, labels and the rest of a line
SNIPPETS = [
    "X = ((A + B)) * (C)\nY = -(-X)**2 + +Z\nW = F() + G(1, (2), H(3))\n",
    "IF (X .GT. 0.0 .AND. .NOT. Y) THEN\nZ = 1\nELSE IF ((X)) THEN\nZ = 2\nELSE\nEND IF\n",
    "DO 10 I = 1, N, 2\n10 CONTINUE\nDO J = 1, (N)\nEND DO\nFOR K = 1, 3\n",
    "PARAM A = 1.0, B = (1.0, 2.0, 3*4.0); C = -2\nCONST D = .TRUE.\nINCON E = 1E-3\n",
    "CONSTANT X = 1, 2, 3*0.0\nCONSTANT INTEGER N = 3\nPARAMETER (M = 4)\n",
    "FUNCTION F = 0.0, 1.0, 2.0, 3.0\nFUNCTION G = (0.0, 1.0), (2.0, 3.0)\n",
    "TIMER FINTIM = 1.0, DELT = 0.1\nRELERR 1E-6\nABSERR X = 1E-5, Y = 2E-5\n",
    "FINISH X = 1.0, Y > 2.0 + Z\nTERMT(X .GE. 1.0, 'done')\nMETHOD RKS\n",
    "PRINT A, B\nOUTPUT X, Y VS Z\nTITLE a title  \nLABEL label text\n",
    "PROCEDURAL (A, B = C, D)\nPROCEDURAL ( = C)\nPROCEDURAL\nEND\n",
    "SCHEDULE E .AT. T + 1.0\nINTERVAL CI = 0.1\nCINTERVAL CI = 0.1\nVARIABLE T = 0.0\n",
    "DIMENSION X(10), A[3, 4]\nREAL*8 V(5)\nCHARACTER*80 NAME\nLOGICAL L\n",
    "Y1, Y2 = OUTSW(X, V)\nA(1, 2) = 3\nB[I] = X[I + 1]\nM(1, 2)\nCALL SUB(1, X)\n",
    "EVENT\nZEROCONDITION X - 1\nNEWVALUE X = 0\nENDEVENT\nFIRSTTIME 1.0\nSET Y = 2\n",
    "MACRO A, B = M(C, D)\nENDMAC\nPROCEDURE A = P(B)\nENDPRO\nNOSORT\nSORT\n",
    "WEATHER WTRDIR = 'C:\\W\\'; CNTR = 'NLD'\nTRANSLATION_GENERAL DRIVER = 'EUDRIV'\n",
    "X = A + ...\n   B * (C ...\n   + D)  ! a comment\n'a string alone'\n$ Y = 1 $ Z = 2\n",
    "10: X = 1.0\nGO TO 10\nSTOP\n",
    "PROGRAM chain\nDERIVATIVE d1\nX = INTEG(V, 0.0)\nEND\nEND\n",
]


@lru_cache(maxsize=1)
def _lark_positions():
    """lark's own tree builder with positions: what tree.read matches."""
    from importlib import resources

    from lark import Lark

    grammar = resources.files("amilpy.grammar").joinpath("amil.lark").read_text("utf-8")
    return Lark(grammar, parser="lalr", lexer="contextual", propagate_positions=True,
                maybe_placeholders=True, cache=True)


def _same(ours, theirs, where=""):
    from lark import Token, Tree

    if isinstance(theirs, Tree):
        assert isinstance(ours, Node), where
        assert ours.data == theirs.data, where
        meta = theirs.meta
        if not meta.empty:
            assert (ours.line, ours.column, ours.end_line, ours.end_column) == \
                (meta.line, meta.column, meta.end_line, meta.end_column), (where, ours.data)
        assert len(ours.children) == len(theirs.children), (where, ours.data)
        for k, (a, b) in enumerate(zip(ours.children, theirs.children, strict=True)):
            _same(a, b, f"{where}/{ours.data}[{k}]")
    elif isinstance(theirs, Token):
        assert isinstance(ours, Token) and ours.type == theirs.type and ours == theirs, where
        assert (ours.line, ours.column, ours.end_line, ours.end_column, ours.start_pos,
                ours.end_pos) == (theirs.line, theirs.column, theirs.end_line,
                                  theirs.end_column, theirs.start_pos, theirs.end_pos), where
    else:
        assert ours is None and theirs is None, where


def _listings():
    files = []
    for folder in ("models", os.path.join("models", "examples"), os.path.join("tests", "golden")):
        for pattern in ("*.amil", "*.csl", "*.fst"):
            files += sorted(glob.glob(os.path.join(ROOT, folder, pattern)))
    return files


def _parts(text: str):
    """The statements of a listing that lark reads whole (a file with faults in it:
    its lines one by one, those that read)."""
    from lark.exceptions import UnexpectedInput

    prepared = prepare(text)
    if not prepared.endswith("\n"):
        prepared += "\n"
    try:
        _parser().parse(prepared)
        return [prepared]
    except UnexpectedInput:
        pass
    out = []
    for line in prepared.split("\n"):
        try:
            _parser().parse(line + "\n")
            out.append(line + "\n")
        except UnexpectedInput:
            continue
    return out


@pytest.mark.parametrize("text", SNIPPETS + [open(f, encoding="utf-8").read()
                                             for f in _listings()],
                         ids=[f"snippet{k}" for k in range(len(SNIPPETS))] +
                         [os.path.basename(f) for f in _listings()])
def test_the_tree_is_lark_s_with_its_positions(text):
    for part in _parts(text):
        _same(read(_parser(), part), _lark_positions().parse(part))


def _cleared(node):
    """The tree with no expression made as it reduced (the builder walks them all)."""
    if isinstance(node, Node):
        node.expr = None
        node.span = None
        for c in node.children:
            _cleared(c)
    return node


@pytest.mark.parametrize("text", SNIPPETS[:3] + [SNIPPETS[12], SNIPPETS[7]])
def test_expressions_made_as_they_reduce_are_the_builder_s(text):
    made = Builder(text, None, _parser()).statements(read(_parser(), prepare(text)))
    walked = Builder(text, None, _parser()).statements(_cleared(read(_parser(), prepare(text))))
    assert made == walked and made


@pytest.mark.parametrize("text", ["X = (A\n", "X = 1 2\n", "X = A $$ B\n", "X = \u00e9\n",
                                  "PARAM\n", "X = 'open\n", "IF (X) THEN Y\n"])
def test_a_fault_is_lark_s(text):
    from lark.exceptions import UnexpectedInput

    with pytest.raises(UnexpectedInput) as ours:
        read(_parser(), prepare(text))
    with pytest.raises(UnexpectedInput) as theirs:
        _parser().parse(prepare(text))
    a, b = ours.value, theirs.value
    assert (type(a), a.line, a.column, str(getattr(a, "token", ""))) == \
        (type(b), b.line, b.column, str(getattr(b, "token", "")))
