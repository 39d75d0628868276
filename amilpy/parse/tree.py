"""lark's LALR parse without lark's tree builder: the parse tree `build.Builder` reads,
made by callbacks of our own as each rule reduces, in a loop of our own over lark's
tables (the grammar's, from lark's cache) with lark's contextual lexer.

lark's own tree building with `propagate_positions` was half of the parsing: every
reduction, the nine precedence levels an operand climbs through included, went
through three wrappers and set a dozen attributes of a `Meta`. Here a reduction
makes one `Node` (a unit reduction, `?sum: product`, makes none), with the same
children lark's tree has (tokens filtered, `_rules` inlined, `[...]` as None) and
the same span lark's `propagate_positions` gives it:

- a node starts where its first child's *container* starts and ends where its
  last child's container ends, filtered tokens (keywords, parentheses) counted;
- a node passed up unchanged by a `?rule` with one child (`"(" expr ")"`) keeps
  its own span, and its container becomes the rule's (the parentheses).

An expression node also carries its `syntax` expression, made as it reduces
(`Node.expr`), so the builder takes it as it is. Only a clean one does: an
expression with a string in it (an error the builder reports where it reads it)
or nested deeper than `MAX_DEPTH` has none, and the builder walks it as before.

A syntax fault is raised by lark's own parse of the text (`read`), so every
message is the one lark's tree-building parser gives.
"""

from __future__ import annotations

from ..diagnostics import Span
from ..language import fortran_float
from . import syntax as ast
from .syntax import MAX_DEPTH


class Node:
    """A rule's node: `data` (the rule's name or alias) and `children` as in lark's
    tree; its span (line, column, end_line, end_column; None when it holds no
    token), its container's (`c...`, where parentheses around it end), and for an
    expression its syntax (`expr`, None when the builder makes it) and depth."""

    __slots__ = ("data", "children", "line", "column", "end_line", "end_column",
                 "cline", "ccolumn", "cend_line", "cend_column", "expr", "depth", "span")

    def __init__(self, data: str, children: list, line=None, column=None, end_line=None,
                 end_column=None) -> None:
        self.data = data
        self.children = children
        self.expr = None
        self.depth = 0
        self.span = None
        self.line = self.cline = line
        self.column = self.ccolumn = column
        self.end_line = self.cend_line = end_line
        self.end_column = self.cend_column = end_column

    def __repr__(self) -> str:
        # (as lark's Tree reads: a message that shows a node -- a data statement's
        # `NZ*0.0` in CSMP form -- reads as it did)
        return f"Tree({self.data!r}, {self.children!r})"


def _first(raw):
    """(line, column) where the first child's container starts (None: no token)."""
    for c in raw:
        if c.__class__ is Node:
            if c.cline is not None:
                return c.cline, c.ccolumn
        else:  # a token
            return c.line, c.column
    return None


def _last(raw):
    for k in range(len(raw) - 1, -1, -1):
        c = raw[k]
        if c.__class__ is Node:
            if c.cend_line is not None:
                return c.cend_line, c.cend_column
        else:
            return c.end_line, c.end_column
    return None


def _passed(node, raw) -> None:
    """A node passed up by a `?rule` of one child: its container becomes the rule's."""
    if node.__class__ is not Node:
        return  # (a token: lark gives it no container)
    first = _first(raw)
    if first is not None:
        if node.line is None:
            node.line, node.column = first
        node.cline, node.ccolumn = first
    last = _last(raw)
    if last is not None:
        if node.end_line is None:
            node.end_line, node.end_column = last
        node.cend_line, node.cend_column = last


# ----------------------------------------------------------------- expressions

_BINOPS = {"add": "+", "sub": "-", "mul": "*", "div": "/", "pow": "**"}
# relational and logical operators (the token's spelling decides: rel, land, ...)
_OPERATORS = {".EQ.": "==", "==": "==", ".NE.": "/=", "/=": "/=", "~=": "/=",
              ".LT.": "<", "<": "<", ".LE.": "<=", "<=": "<=", ".GT.": ">", ">": ">",
              ".GE.": ">=", ">=": ">=", ".AND.": "AND", "&&": "AND", ".OR.": "OR",
              "||": "OR", ".EQV.": "EQV", ".NEQV.": "NEQV"}
_LOGIC = frozenset({"rel", "land", "lor", "eqv"})


def _span(node: Node) -> Span:
    return Span(node.line, node.column, node.end_line, node.end_column)


def _expression(node: Node) -> None:
    """`node.expr` and `node.depth` of an expression node whose children are made:
    what `Builder.expr` makes of it, or None where the builder must (a string in it,
    too deep, anything unexpected)."""
    kind = node.data
    children = node.children
    if kind == "number":
        tok = children[0]
        node.depth = 1
        node.span = span = _span(node)
        node.expr = ast.Num(fortran_float(str(tok)), span, str(tok))
        return
    if kind == "name":
        node.depth = 1
        node.span = span = _span(node)
        node.expr = ast.Name(str(children[0]).upper(), span)
        return
    if kind in _BINOPS:
        a, b = children[0], children[-1]
        depth = node.depth = 1 + (a.depth if a.depth > b.depth else b.depth)
        if a.expr is None or b.expr is None or depth > MAX_DEPTH:
            return
        node.span = span = _span(node)
        node.expr = ast.BinOp(_BINOPS[kind], a.expr, b.expr, span)
        return
    if kind in _LOGIC:
        a, b = children[0], children[-1]
        depth = node.depth = 1 + (a.depth if a.depth > b.depth else b.depth)
        op = _OPERATORS.get(str(children[1]).upper())
        if a.expr is None or b.expr is None or depth > MAX_DEPTH or op is None:
            return
        node.span = span = _span(node)
        node.expr = ast.BinOp(op, a.expr, b.expr, span)
        return
    if kind == "call" or kind == "subscript":
        args = [a for a in children[1:] if a is not None]
        depth = 0
        for a in args:
            if a.depth > depth:
                depth = a.depth
            if a.expr is None:
                depth = -1
                break
        if depth < 0:
            node.depth = 1 + max(a.depth for a in args)
            return
        depth = node.depth = depth + 1
        if depth > MAX_DEPTH:
            return
        node.span = span = _span(node)
        name = str(children[0]).upper()
        if kind == "call":
            node.expr = ast.Call(name, tuple(a.expr for a in args), span,
                                 tuple(a.span for a in args))
        else:
            node.expr = ast.Index(name, tuple(a.expr for a in args), span)
        return
    if kind == "neg" or kind == "pos" or kind == "lnot":
        a = children[-1]
        depth = node.depth = 1 + a.depth
        if a.expr is None or depth > MAX_DEPTH:
            return
        if kind == "pos":
            node.span = _span(node)
            node.expr = a.expr
            return
        node.span = span = _span(node)
        node.expr = ast.Neg(a.expr, span) if kind == "neg" else ast.Not(a.expr, span)
        return
    if kind == "truth":
        node.depth = 1
        tok = children[0]
        if getattr(tok, "type", None) == "TRUTH":
            text = str(tok).upper()
            node.span = span = _span(node)
            node.expr = ast.Num(1.0 if text == ".TRUE." else 0.0, span, text)
        return
    if kind == "string":
        node.depth = 1
        return
    raise AssertionError(f"unknown expression node {kind}")


def relation(node: Node) -> Node:
    """FINISH's `sum REL_OP sum` (a finish_relation node) as a `rel` expression."""
    rel = Node("rel", node.children, node.line, node.column, node.end_line, node.end_column)
    rel.cline, rel.ccolumn, rel.cend_line, rel.cend_column = \
        node.cline, node.ccolumn, node.cend_line, node.cend_column
    _expression(rel)
    return rel


_EXPRESSIONS = frozenset({"number", "name", "call", "subscript", "neg", "pos", "lnot",
                          "truth", "string", *_BINOPS, *_LOGIC})


# ------------------------------------------------------------------ callbacks

def _plan(rule):
    """Which of a rule's symbols its node keeps, as lark's tree builder does: tokens
    lark filters out (anonymous strings, `_NAMES`) left out, `_rules` inlined, a
    None for each `[...]` not there. ((index, inline, Nones before), Nones after)"""
    expansion = rule.expansion
    keep_all = bool(getattr(rule.options, "keep_all_tokens", False))  # (a `!rule`)
    flags = getattr(rule.options, "empty_indices", ()) or ()
    if flags:
        s = "".join(str(int(b)) for b in flags)
        empty = [len(ones) for ones in s.split("0")]
    else:
        empty = [0] * (len(expansion) + 1)
    plan, nones = [], 0
    for i, sym in enumerate(expansion):
        nones += empty[i]
        if keep_all or not (sym.is_term and sym.filter_out):
            plan.append((i, not sym.is_term and sym.name.startswith("_"), nones))
            nones = 0
    return tuple(plan), nones + empty[len(expansion)]


def _unit(raw):
    return raw[0]


def _callback(rule):
    plan, tail = _plan(rule)
    options = rule.options
    expand1 = bool(getattr(options, "expand1", False)) and not rule.alias
    name = rule.alias or rule.origin.name
    expression = name in _EXPRESSIONS
    size = len(rule.expansion)
    simple = not tail and all(not inline and not nones for _, inline, nones in plan)
    indices = tuple(i for i, _, _ in plan)

    if expand1 and size == 1 and simple and len(plan) == 1:
        return _unit  # ?sum: product -- the child, passed up as it is

    if simple and len(indices) == size:
        def children(raw):
            return raw  # (a fresh list: the parser's slice of its stack)
    elif simple:
        def children(raw):
            return [raw[i] for i in indices]
    else:
        def children(raw):
            out: list = []
            for i, inline, nones in plan:
                if nones:
                    out += [None] * nones
                if inline:
                    if out:
                        out += raw[i].children
                    else:  # (left recursion: the list grows in place)
                        out = raw[i].children
                else:
                    out.append(raw[i])
            if tail:
                out += [None] * tail
            return out

    whole = simple and len(indices) == size

    def reduce(raw):
        kept = raw if whole else children(raw)
        if expand1 and len(kept) == 1:
            node = kept[0]
            _passed(node, raw)
            return node
        # a new node's span: from its first child's container to its last one's
        # (_first and _last, written out)
        line = column = end_line = end_column = None
        for c in raw:
            if c.__class__ is Node:
                if c.cline is not None:
                    line, column = c.cline, c.ccolumn
                    break
            else:  # a token
                line, column = c.line, c.column
                break
        for c in reversed(raw):
            if c.__class__ is Node:
                if c.cend_line is not None:
                    end_line, end_column = c.cend_line, c.cend_column
                    break
            else:
                end_line, end_column = c.end_line, c.end_column
                break
        node = Node(name, kept, line, column, end_line, end_column)
        if expression:
            _expression(node)
        return node
    return reduce


_TABLES: dict = {}


class _Fault(Exception):
    """No action for a token: a syntax fault, said by lark's own parse."""


def _table(parser, conf) -> tuple[dict, dict, dict]:
    """lark's LALR table, each state's actions by symbol: the next state (a shift or
    a goto), or a reduction (size, the rule's name, our callback; None: the rule
    passes its one child up unchanged); each state's lexing (`_scanning`) and where
    a run of unit reductions ends (`_chain`), filled as they are met. One per parser."""
    from lark.parsers.lalr_analysis import Shift

    key = id(parser)
    if key not in _TABLES:
        made = {rule: _callback(rule) for rule in conf.callbacks if hasattr(rule, "expansion")}
        reductions = {rule: (len(rule.expansion), rule.origin.name,
                             None if made[rule] is _unit else made[rule]) for rule in made}
        table = {state: {symbol: arg if action is Shift else reductions[arg]
                         for symbol, (action, arg) in actions.items()}
                 for state, actions in conf.states.items()}
        _TABLES[key] = (parser, table, {}, {})  # (the parser kept: its id stays its own)
    return _TABLES[key][1:]


def _chain(table: dict, below: int, top: int, kind: str) -> int:
    """The top state after the unit reductions a token sets off one after another
    (an operand climbing `?sum: product`, `?relation: sum`, ...): they leave the
    stack below as it is, so where they end depends on the state below, the top
    state and the token only."""
    while True:
        action = table[top].get(kind)
        if action.__class__ is not tuple or action[2] is not None:
            return top
        top = table[below][action[1]]


def _scanning(lexer) -> tuple:
    """What the lexing of one parser state needs from lark's lexer for it (a
    `BasicLexer` of the terminals the state accepts): its scanner's match, the types
    it ignores, those that may hold a line end, and its callbacks (a TEXT that is
    exactly `(` is the token `(`, as lark's lexer retypes it)."""
    match = lexer.scanner.match  # (built on first use; it makes `callback` too)
    return match, lexer.ignore_types, lexer.newline_types, lexer.callback


def read(parser, text: str) -> Node:
    """The tree of `text` (lark's UnexpectedInput as lark's own parse raises it).

    lark's contextual lexer and LALR loop (`ContextualLexer.lex`,
    `ParserState.feed_token`) written out as one loop over our table: the lexer of
    the top state matches with lark's scanner of that state and makes lark's
    tokens; a run of unit reductions (44 of the 59 reductions of a chain statement)
    is one look-up (`_chain`), and no rule is hashed to find its callback."""
    from lark.exceptions import UnexpectedInput
    from lark.lexer import Token

    interactive = parser.parse_interactive(text)
    state = interactive.parser_state
    conf = state.parse_conf
    table, scanners, chains = _table(parser, conf)
    lexers = state.lexer.lexer.lexers  # (the contextual lexer's, by parser state)
    source = state.lexer.state.text  # (a TextSlice from lark 1.2 on, a str before)
    end = getattr(source, "end", None)
    if end is None:
        end = len(source)
    new_token = getattr(Token, "_future_new", Token)
    end_state = conf.end_state
    states = state.state_stack
    values = state.value_stack
    pos, line, line_start = 0, 1, 0
    try:
        while True:
            if pos >= end:  # the end of the text: reduce to the start
                token, kind = None, "$END"
            else:
                top = states[-1]
                scanning = scanners.get(top)
                if scanning is None:
                    scanning = scanners[top] = _scanning(lexers[top])
                match, ignore, newline, retype = scanning
                found = match(source, pos)
                if not found:
                    raise _Fault
                value, kind = found
                start, pos = pos, pos + len(value)
                if kind in ignore:
                    if kind in newline:
                        lines = value.count("\n")
                        if lines:
                            line += lines
                            line_start = start + value.rindex("\n") + 1
                    continue
                first_line, column = line, start - line_start + 1
                if kind in newline:
                    lines = value.count("\n")
                    if lines:
                        line += lines
                        line_start = start + value.rindex("\n") + 1
                token = new_token(kind, value, start, first_line, column, line,
                                  pos - line_start + 1, pos)
                if kind in retype:
                    token = retype[kind](token)
                    kind = token.type
            while True:
                top = states[-1]
                action = table[top].get(kind)
                if action.__class__ is int and token is not None:
                    states.append(action)
                    values.append(token)
                    break
                if action is None or action.__class__ is int:
                    raise _Fault
                size, origin, callback = action
                if callback is None:  # unit reductions, as many as follow: one look-up
                    below = states[-2]
                    key = (below, top, kind)
                    after = chains.get(key)
                    if after is None:
                        after = chains[key] = _chain(table, below, top, kind)
                    states[-1] = after
                else:
                    if size:
                        raw = values[-size:]
                        del states[-size:]
                        del values[-size:]
                    else:
                        raw = []
                    values.append(callback(raw))
                    states.append(table[states[-1]][origin])
                if token is None and states[-1] == end_state:
                    return values[-1]
    except (UnexpectedInput, _Fault):
        pass
    parser.parse(text)  # (raises the same fault, as the messages have always read it)
    raise AssertionError("lark's parse read what its tables did not")  # pragma: no cover
