"""Arrays -> one variable per element, before anything checks the program.

ACSL and Magnolia listings declare arrays (`DIMENSION X(4), A[3, 3]`, `REAL V(5)`,
`DIMENSION INTEGER N(2)`), give them values (`CONSTANT X = 1.0, 2.0, 2*0.0`, in
Fortran's order: the first subscript runs fastest) and read and write them element by
element, mostly in loops (`FOR i = 1, 4 ... END`, `DO i = 1, 4 ... END DO`). Here each
element becomes a variable of its own, named as the listing would write it, `X(1)`,
`A(2,3)`; after this pass nothing knows arrays: sorting, the compiler, the Jacobian
and every route see scalars, and a state that is an element is a state like any other.

- A subscript whose value is known when the listing is read (numbers, constants, the
  variable of a loop that is written out) names the element: `X[i + 1]` in a loop's
  third pass from 1 is `X(4)`. A loop whose bounds are known is written out pass by
  pass (in written-order code its variable then holds the value after the last pass,
  as Fortran's does); one whose bounds are not known runs as a loop.
- A subscript known only as the run goes (`DOSE[DAY]` in a DISCRETE section, DAY a
  variable) reads through ELEMENT(k, X(1), ..., X(n)) and, in written-order code,
  writes through an IF per element; a subscript outside the array is a fault there,
  which names its value.
- A statement that assigns a whole array (`X = INTEG(XD, XIC)`, `V = 2.0*W`) is one
  statement per element, every array in it read at that element (a scalar as it is).
- PRINT, OUTPUT, PREPARE, RANGE X and a PROCEDURAL's lists name its elements.
- A function table read as ACSL reads its TABLE, `F(X)`, is `AFGEN(F, X)`.
- The constants that give a size or the bounds of a written-out loop are fixed when
  the listing is read (`Program.fixed`): a run may not change them.
"""

from __future__ import annotations

import itertools
import math
import operator
from dataclasses import dataclass, fields, replace

from ..diagnostics import Diagnostic, Span
from ..language import ACSL_TIME, MAX_ELEMENTS, RESERVED
from . import syntax as ast

# the statements of written-order code (where a subscript known only at run time may
# be written, and a loop's variable keeps its value after the loop)
_WRITTEN_BLOCKS = ("INITIAL", "DYNAMIC", "TERMINAL", "DISCRETE")
_EXPRESSIONS = (*ast.EXPRESSIONS, *ast.RESOLVED_BY_READER)
# the arithmetic a size, a subscript or a loop's bound may be written with
_ARITHMETIC = {"+": operator.add, "-": operator.sub, "*": operator.mul,
               "/": operator.truediv, "**": operator.pow}


@dataclass(frozen=True)
class Array:
    name: str
    sizes: tuple[int, ...]
    span: Span

    def element(self, index: tuple[int, ...]) -> str:
        return f"{self.name}({','.join(str(i) for i in index)})"

    def indices(self) -> list[tuple[int, ...]]:
        """Every subscript, in Fortran's order (the first subscript fastest)."""
        ranges = [range(1, n + 1) for n in reversed(self.sizes)]
        return [tuple(reversed(k)) for k in itertools.product(*ranges)]

    def elements(self) -> list[str]:
        return [self.element(k) for k in self.indices()]


class _Unknown(Exception):
    """A value not known when the listing is read."""


def expand(statements: list, errors: list[Diagnostic], acsl: bool,
           notes: list[Diagnostic] | None = None,
           bracketed: bool = True) -> tuple[list, frozenset[str]]:
    """The statements with every array written out as its elements (see the module),
    and the constants fixed by it. Faults go to `errors`, warnings to `notes`.
    `bracketed`: the listing may hold an `X[i]` (False: no `[` in its text, so no
    expression holds an element, and without tables none is searched)."""
    everything = ast.every_statement(statements)
    tables = {st.name for st in everything if isinstance(st, ast.Table)}
    walk = ast.walk if bracketed or tables else ast.walk_statements
    if not any((isinstance(st, ast.Declare) and st.sizes)
               or (isinstance(st, ast.Data) and any(it.is_array or it.pieces
                                                     for it in st.items))
               or (isinstance(st, ast.Table) and st.grid) for st in everything) and not any(
            isinstance(n, ast.Index) or (isinstance(n, ast.Assign) and n.subscripts)
            or (isinstance(n, ast.Call) and n.func in tables)
            for st in statements for n in walk(st)):
        return statements, frozenset()
    pass_ = _Arrays(statements, everything, errors, acsl)
    if notes is not None:
        pass_.notes = notes
    return pass_.statements(statements, {}, written=False), frozenset(pass_.fixed)


class _Arrays:
    def __init__(self, statements: list, everything: list, errors: list[Diagnostic],
                 acsl: bool) -> None:
        """`everything`: the statements, in blocks and loops too (`syntax.every_statement`)."""
        self.errors = errors
        self.notes: list[Diagnostic] = []
        self.acsl = acsl
        self.fixed: set[str] = set()
        self.written_out = 0  # statements the loops were written out into
        # constants: a name given one value, once (or always the same)
        values: dict[str, float | None] = {}
        first: dict[str, Span] = {}
        self.twice: dict[str, tuple[Span, Span]] = {}  # names given two values
        for st in everything:
            if isinstance(st, ast.Data) and st.keyword != "INCON":
                for it in st.items:
                    v = it.values[0] if len(it.values) == 1 and not (
                        it.is_list or it.is_array) else None
                    if it.name in values and values[it.name] != v:
                        self.twice.setdefault(it.name, (first[it.name], it.span))
                    first.setdefault(it.name, it.span)
                    values[it.name] = v if values.get(it.name, v) == v else None
        self.constants = {n: v for n, v in values.items() if v is not None}
        # function tables (ACSL's TABLE F, n, ... / ... /, FUNCTION F = ...), read as
        # F(X), F(X, Y), F(X, Y, Z): their names and how many variables each reads
        self.tables = {st.name: 1 + len(st.grid) for st in everything
                       if isinstance(st, ast.Table)}
        self.table_parts: dict[str, list] = {}
        self.read_after_loops = _read_outside_loops(statements)
        self.table_statements = {st.name: self.written_out_table(st) for st in everything
                                 if isinstance(st, ast.Table) and st.grid}
        self.arrays: dict[str, Array] = {}
        self.unsized: set[str] = set()
        total = 0
        from ..library import callable_names

        taken = {n: "is a function" for n in callable_names()}
        taken.update({n: "is reserved" for n in (*RESERVED, *((ACSL_TIME,) if acsl else ()))})
        for st in everything:
            if not isinstance(st, ast.Declare) or not st.sizes:
                continue
            for name, span, sizes in zip(st.names, st.name_spans, st.sizes, strict=True):
                if not sizes:
                    continue
                if name in taken:
                    self.error(f"{name} {taken[name]}: an array cannot take its name", span,
                               "give the array another name")
                    continue
                dims = tuple(self.size(e, name) for e in sizes)
                if not all(dims):
                    self.unsized.add(name)  # (said at its size: its uses say no more)
                    continue
                if name in self.arrays and self.arrays[name].sizes != dims:
                    self.error(f"{name} is declared twice with other sizes", span,
                               f"first at line {self.arrays[name].span.line}: declare it once")
                    continue
                self.arrays[name] = Array(name, dims, span)
                total += math.prod(dims)
                if total > MAX_ELEMENTS:
                    self.error(f"the arrays hold more than {MAX_ELEMENTS:,} elements", span,
                               "each element is a variable of its own: use smaller arrays")
                    self.arrays.pop(name)

    def error(self, message: str, span: Span | None, hint: str | None = None) -> None:
        self.errors.append(Diagnostic(message, span, hint))

    # ---------------------------------------------------------------- values known
    def value(self, e: ast.Node, env: dict[str, int]) -> float:
        """The value of e when the listing is read (numbers, constants, loop
        variables); raises _Unknown. The constants it reads are fixed from then on."""
        used: list[str] = []
        v = self._value(e, env, used)
        self.fixed.update(used)
        return v

    def _value(self, e, env, used) -> float:
        if isinstance(e, ast.Num):
            return e.value
        if isinstance(e, ast.Name):
            if e.name in env:
                return float(env[e.name])
            if e.name in self.constants:
                used.append(e.name)
                return self.constants[e.name]
            raise _Unknown
        if isinstance(e, ast.Neg):
            return -self._value(e.operand, env, used)
        if isinstance(e, ast.BinOp) and e.op in _ARITHMETIC:
            a, b = self._value(e.left, env, used), self._value(e.right, env, used)
            try:
                return float(_ARITHMETIC[e.op](a, b))
            except (ArithmeticError, ValueError, TypeError):
                raise _Unknown from None
        raise _Unknown

    def whole(self, e: ast.Node, env: dict[str, int], what: str) -> int | None:
        """A whole number known when the listing is read, else None (said)."""
        try:
            v = self.value(e, env)
        except _Unknown:
            return None
        if not (math.isfinite(v) and v == int(v)):
            self.error(f"{what} is {v:g}, not a whole number", e.span,
                       "a subscript, size or loop bound is a whole number")
            return None
        return int(v)

    def size(self, e: ast.Node, name: str) -> int:
        n = self.whole(e, {}, f"a size of {name}")
        if n is None and isinstance(e, ast.Name) and e.name in self.twice:
            was, again = self.twice[e.name]
            self.error(f"{e.name}, a size of {name}, is given another value here (line "
                       f"{was.line} gave it one): a size is fixed when the listing is read",
                       again, f"give {e.name} one value (ARRAY_SIZE {e.name} = n), and no "
                       "other in a later run")
            return 0
        if n is None:
            if not any(d.span == e.span for d in self.errors):
                self.error(f"the size of {name} is not known when the listing is read", e.span,
                           "write a number, or a CONSTANT/PARAMETER given one")
            return 0
        if n < 1:
            self.error(f"a size of {name} is {n}", e.span, "an array has 1 element or more")
            return 0
        return n

    # ---------------------------------------------------------------- expressions
    def needs(self, e: ast.Node, env: dict[str, int]) -> bool:
        for n in ast.walk(e):
            if isinstance(n, ast.Index) or (isinstance(n, ast.Call) and (
                    n.func in self.arrays or n.func in self.tables)):
                return True
            if isinstance(n, ast.Name) and (n.name in env or n.name in self.arrays):
                return True
        return False

    def expr(self, e, env: dict[str, int], whole: dict[str, str] | None = None):
        """e with its subscripts resolved; `whole`: the element each array read whole
        stands for (a statement that assigns a whole array, at one of its elements)."""
        if e is None or not self.needs(e, env):
            return e
        try:
            return self._expr(e, env, whole)
        except RecursionError:
            self.error("an expression with subscripts nested too deeply", e.span,
                       "split it into several assignments")
            return e

    def _expr(self, e, env, whole):
        if isinstance(e, ast.Name):
            if e.name in env:
                return ast.Num(float(env[e.name]), e.span, str(env[e.name]))
            if e.name in self.arrays:
                if whole is not None and e.name in whole:
                    return ast.Name(whole[e.name], e.span)
                self.error(f"the array {e.name} stands here without a subscript", e.span,
                           f"write one element, {e.name}[i], or assign the whole array "
                           f"({e.name} = ... on the left)")
            return e
        if isinstance(e, ast.Index) or (isinstance(e, ast.Call) and e.func in self.arrays):
            name = e.name if isinstance(e, ast.Index) else e.func
            args = tuple(self._expr(a, env, whole) for a in e.args)
            if name not in self.arrays:
                self.error(f"{name}[...]: {name} is not an array", e.span,
                           f"declare it, e.g. DIMENSION {name}(10)")
                return ast.Num(0.0, e.span, "0")
            return self.read(self.arrays[name], args, e.span, env)
        if isinstance(e, ast.Call):
            args = tuple(self._expr(a, env, whole) for a in e.args)
            if e.func in self.tables:
                return self.lookup(e.func, args, e.span)
            return replace(e, args=args)
        if isinstance(e, ast.BinOp):
            return replace(e, left=self._expr(e.left, env, whole),
                           right=self._expr(e.right, env, whole))
        if isinstance(e, (ast.Neg, ast.Not)):
            return replace(e, operand=self._expr(e.operand, env, whole))
        return e

    def subscripts(self, a: Array, args, span: Span, env) -> list[int | None] | None:
        """Each subscript's value when known (None: known only at run time); None
        when they are wrong (said)."""
        if len(args) != len(a.sizes):
            self.error(f"{a.name} has {len(a.sizes)} subscript(s), not {len(args)}", span,
                       f"write {a.name}[{', '.join('i j k l m'.split()[:len(a.sizes)])}]")
            return None
        known: list[int | None] = []
        for d, (arg, n) in enumerate(zip(args, a.sizes, strict=True)):
            try:
                v = self.value(arg, env)
            except _Unknown:
                known.append(None)
                continue
            if not (math.isfinite(v) and v == int(v) and 1 <= v <= n):
                self.error(f"the subscript {v:g} of {a.name} is outside 1..{n}"
                           + (f" (subscript {d + 1})" if len(a.sizes) > 1 else ""), arg.span,
                           f"{a.name} is declared with {n} element(s) there (line "
                           f"{a.span.line})")
                return None
            known.append(int(v))
        return known

    def read(self, a: Array, args, span: Span, env):
        known = self.subscripts(a, args, span, env)
        if known is None:
            return ast.Num(0.0, span, "0")
        return self._pick(a, list(args), known, span, ())

    def _pick(self, a: Array, args, known, span, chosen: tuple[int, ...]):
        """The element at the subscripts: the last dimension first, ELEMENT over it
        where its subscript is known only at run time."""
        d = len(a.sizes) - 1 - len(chosen)
        if d < 0:
            return ast.Name(a.element(chosen), span)
        if known[d] is not None:
            return self._pick(a, args, known, span, (known[d], *chosen))
        options = tuple(self._pick(a, args, known, span, (k, *chosen))
                        for k in range(1, a.sizes[d] + 1))
        return ast.Call("ELEMENT", (args[d], *options), span)

    def lookup(self, name: str, args: tuple, span: Span):
        """ACSL's F(X) of a table: AFGEN(F, X). F(X, Y) of a table of two variables:
        the sum over Y's breakpoints y_j of AFGEN(F_yj, Y) * AFGEN(F_xj, X), where
        F_yj is the hat that is 1 at y_j and 0 at the other breakpoints (held past
        the ends) and F_xj the table over X at y_j: bilinear interpolation, the end
        values held, through the 1-variable tables only (`written_out_table`);
        F(X, Y, Z) likewise over Y's and Z's breakpoints."""
        n = self.tables[name]
        if len(args) != n:
            self.error(f"the table {name} takes {n} argument(s), not {len(args)}", span,
                       f"write {name}({', '.join('XYZ'[:n])})")
            return ast.Num(0.0, span, "0")

        def afgen(table: str, arg):
            return ast.Call("AFGEN", (ast.Name(table, span), arg), span)
        if n == 1:
            return afgen(name, args[0])
        total = None
        for key, hats in self.table_parts[name]:
            term = afgen(f"{name}_x{key}", args[0])
            for axis, j in hats:
                term = ast.BinOp("*", afgen(f"{name}_{axis}{j}", args["yz".index(axis) + 1]),
                                 term, span)
            total = term if total is None else ast.BinOp("+", total, term, span)
        return total

    def written_out_table(self, st: ast.Table) -> list[ast.Table]:
        """A table of 2 or 3 variables as the 1-variable tables `lookup` reads: one over
        X for each breakpoint of the others, and each other breakpoint's hat."""
        nx, out, parts = len(st.xs), [], []
        axes = list(zip("yz", st.grid, strict=False))
        for axis, points in axes:
            if len(points) > 1:
                out += [ast.Table(f"{st.name}_{axis}{j + 1}", points,
                                  tuple(float(i == j) for i in range(len(points))), st.span)
                        for j in range(len(points))]
        for flat, index in enumerate(itertools.product(*(range(len(p)) for _, p in
                                                          reversed(axes)))):
            index = tuple(reversed(index))  # (y's index faster than z's)
            key = "_".join(str(i + 1) for i in index)
            out.append(ast.Table(f"{st.name}_x{key}", st.xs,
                                 st.ys[flat * nx:(flat + 1) * nx], st.span))
            parts.append((key, [(axis, i + 1) for (axis, points), i in zip(axes, index,
                                                                           strict=True)
                                if len(points) > 1]))
        self.table_parts[st.name] = parts
        return out

    # ---------------------------------------------------------------- statements
    def statements(self, sts, env: dict[str, int], written: bool) -> list:
        out: list = []
        for st in sts:
            if isinstance(st, ast.Section):  # CSMP form: TERMINAL runs in written order
                written = st.name == "TERMINAL"
            elif isinstance(st, ast.Nosort):
                written = not st.sorted
            out.extend(self.statement(st, env, written))
        return out

    def statement(self, st, env: dict[str, int], written: bool) -> list:
        if isinstance(st, ast.Declare):
            return [self.declare(st)]
        if isinstance(st, ast.Data):
            return [self.data(st)]
        if isinstance(st, ast.Assign):
            return self.assign(st, env, written)
        if isinstance(st, ast.Loop):
            return self.loop(st, env, written)
        if isinstance(st, ast.If):
            return [replace(st, branches=tuple(
                replace(b, cond=self.expr(b.cond, env),
                        body=tuple(self.statements(b.body, env, written)))
                for b in st.branches))]
        if isinstance(st, ast.Procedural):
            return [replace(st, outputs=self.names(st.outputs), inputs=self.names(st.inputs),
                            body=tuple(self.statements(st.body, env, True)))]
        if isinstance(st, ast.Block):
            return [replace(st, body=tuple(self.statements(
                st.body, env, st.kind in _WRITTEN_BLOCKS)))]
        if isinstance(st, ast.FunctionDef):
            return [replace(st, body=tuple(self.statements(st.body, env, True)))]
        if isinstance(st, ast.Report):
            return [self.report(st)]
        if isinstance(st, ast.Table) and st.grid:
            return self.table_statements[st.name]
        if isinstance(st, ast.Finish):
            return [replace(st, relations=tuple(self.statement(r, env, written)[0]
                                                for r in st.relations))]
        changed = {f.name: self.expr(getattr(st, f.name), env) for f in fields(st)
                   if isinstance(getattr(st, f.name), _EXPRESSIONS)}
        return [replace(st, **changed) if changed else st]

    def names(self, names: tuple[str, ...]) -> tuple[str, ...]:
        return self.named(names, names)[0]

    def named(self, names: tuple[str, ...], spans: tuple) -> tuple[tuple, tuple]:
        """Names with each array's in place of it, and the span each came from."""
        out, where = [], []
        for name, span in zip(names, spans, strict=True):
            each = self.arrays[name].elements() if name in self.arrays else [name]
            out.extend(each)
            where.extend([span] * len(each))
        return tuple(out), tuple(where)

    def declare(self, st: ast.Declare) -> ast.Declare:
        return ast.Declare(st.type, *self.named(st.names, st.name_spans), st.span)

    def data(self, st: ast.Data) -> ast.Data:
        items = []
        for it in st.items:
            if it.element:
                items.extend(self.elements_given(it))
                continue
            if it.pieces:
                values = self.pieces(it)
                if values is None:
                    continue
                it = replace(it, values=values, pieces=())
            a = self.arrays.get(it.name)
            if a is None:
                if it.is_array:
                    self.error(f"{it.name} is given {len(it.values)} values, but it is no "
                               "array", it.span,
                               f"declare it, DIMENSION {it.name}({len(it.values)}); or, for "
                               "one value, the decimal separator is a point: 1.5, not 1,5")
                items.append(it)
                continue
            count = math.prod(a.sizes)
            if it.is_list:
                self.error(f"{it.name} is an array: a list in parentheses (one run per "
                           "value) cannot give it values", it.span,
                           f"write CONSTANT {it.name} = v1, v2, ... (n*v repeats v)")
                continue
            values = it.values
            if len(values) < count and self.acsl:
                # (a DATA statement of the translators' Fortran: the elements after the
                # list keep the zero of static storage, which published listings use
                # for the unused rows of a table)
                self.notes.append(Diagnostic(
                    f"{it.name} is given {len(values)} value(s) for {count} elements: "
                    f"the other {count - len(values)} are 0", it.span, severity="warning"))
                values = values + (0.0,) * (count - len(values))
            if len(values) != count:
                self.error(f"{it.name} is given {len(values)} value(s) for {count} "
                           "elements", it.span,
                           f"give one value per element, in Fortran's order; {count}*0.0 "
                           f"sets all {count}")
                continue
            items.extend(ast.DataItem(e, (v,), it.span)
                         for e, v in zip(a.elements(), values, strict=True))
        return replace(st, items=tuple(items))

    def elements_given(self, it: ast.DataItem) -> list[ast.DataItem]:
        """FST's X(k) = v and X(i:j) = v1, v2, ...: the elements' items; one value
        for a range gives every element of it that value (FST's MNDAT(6:NH) = 999.)."""
        a = self.arrays.get(it.name)
        if it.name in self.unsized:
            return []
        if a is None or len(a.sizes) != 1:
            self.error(f"{it.name}(...) = ...: {it.name} is not an array of one subscript",
                       it.span, f"declare it, e.g. ARRAY {it.name}(1:N) with ARRAY_SIZE "
                       "N = 10")
            return []
        values = self.pieces(it)
        first, last = it.element
        bounds = []
        for b in (first, first if last is None else last):
            k = self.whole(b if isinstance(b, ast.Node) else
                           ast.Name(b, it.span) if isinstance(b, str) else
                           ast.Num(b, it.span, f"{b:g}"), {}, f"a subscript of {it.name}")
            if k is None:
                if not any(d.span == it.span for d in self.errors):
                    self.error(f"a subscript of {it.name} is not known when the listing is "
                               "read", it.span, "write a number, or an ARRAY_SIZE name")
                return []
            bounds.append(k)
        lo, hi = bounds
        n = a.sizes[0]
        if not 1 <= lo <= hi <= n:
            self.error(f"{it.name}({lo}:{hi}) is not a range of {it.name}(1:{n})", it.span,
                       f"{it.name} is declared with {n} element(s) (line {a.span.line})")
            return []
        if values is None:
            return []
        count = hi - lo + 1
        if len(values) == 1:
            values = values * count
        if len(values) != count:
            self.error(f"{it.name}({lo}:{hi}) is given {len(values)} values for {count} "
                       "elements", it.span, "give one value for each, or one for all")
            return []
        return [ast.DataItem(a.element((k,)), (v,), it.span)
                for k, v in zip(range(lo, hi + 1), values, strict=True)]

    def pieces(self, it: ast.DataItem) -> tuple[float, ...] | None:
        """The values of a data item whose counts or values name constants (ACSL's
        CONSTANT X = N*0.0 after PARAMETER (N = 4)); None where a name has no value
        when the listing is read (said)."""
        values: list[float] = []
        for count, value, span in it.pieces:
            try:
                n = count if isinstance(count, int) else \
                    self.value(ast.Name(count, span), {})
                v = value if isinstance(value, float) else \
                    self.value(ast.Name(value, span), {})
            except _Unknown:
                name = value if isinstance(value, str) and value not in self.constants \
                    else count
                self.error(f"{it.name}'s values name {name}, which has no value when the "
                           "listing is read", span,
                           "write a number, or the name of a PARAMETER/CONSTANT given a "
                           "number before")
                return None
            if not (math.isfinite(n) and n == int(n) and 0 <= n <= MAX_ELEMENTS):
                self.error(f"{it.name}: the repeat count {count} is {n:g}", span,
                           f"a repeat count is a whole number from 0 to {MAX_ELEMENTS:,}")
                return None
            values.extend([v] * int(n))
        return tuple(values)

    def report(self, st: ast.Report) -> ast.Report:
        if st.x in self.arrays:
            self.error(f"VS {st.x}: an array cannot be the horizontal axis", st.x_span,
                       "plot against one variable")
        names, spans = self.named(st.names, st.name_spans)
        return replace(st, names=names, name_spans=spans)

    def assign(self, st: ast.Assign, env, written: bool) -> list:
        if st.subscripts:
            name = st.targets[0]
            a = self.arrays.get(name)
            if a is None:
                self.error(f"{name}(...) = ...: {name} is not an array", st.target_spans[0],
                           f"declare it, e.g. DIMENSION {name}(10)")
                return []
            args = tuple(self.expr(s, env) for s in st.subscripts)
            known = self.subscripts(a, args, st.span, env)
            if known is None:
                return []
            expr = self.expr(st.expr, env)
            if all(k is not None for k in known):
                return [replace(st, targets=(a.element(tuple(known)),), expr=expr,
                                subscripts=())]
            return self.write_at(st, a, args, known, expr, written)
        arrays = [t for t in st.targets if t in self.arrays]
        if not arrays:
            return [replace(st, expr=self.expr(st.expr, env))]
        if len(st.targets) > 1:
            self.error(f"the array {arrays[0]} cannot be one of two outputs", st.span,
                       "write the call once per element")
            return []
        a = self.arrays[arrays[0]]
        return [self.at_element(st, a, k, env) for k in a.indices()]

    def at_element(self, st: ast.Assign, a: Array, k: tuple[int, ...], env) -> ast.Assign:
        """The whole-array assignment st at element k: every array of a's sizes read at k."""
        whole = {}
        for n in ast.walk(st.expr):
            if isinstance(n, ast.Name) and n.name in self.arrays:
                other = self.arrays[n.name]
                if other.sizes != a.sizes:
                    self.error(f"{a.name} = ... reads the array {n.name}, whose sizes differ",
                               n.span, f"{a.name} is {a.sizes}, {n.name} {other.sizes}: "
                               "write a loop over the elements")
                    continue
                whole[n.name] = other.element(k)
        return replace(st, targets=(a.element(k),), expr=self.expr(st.expr, env, whole))

    def write_at(self, st: ast.Assign, a: Array, args, known, expr, written: bool) -> list:
        """X(k) = e with k known only at run time: an IF over the elements (written-order
        code only); a subscript outside X reaches ELEMENT, which says so."""
        if not written:
            self.error(f"{a.name}(...) = ... with a subscript known only as the run goes, in "
                       "sorted code", st.span,
                       "put it in a PROCEDURAL block, INITIAL, DISCRETE or DYNAMIC, or make "
                       "the subscript a number or a loop's variable")
            return []
        branches = []
        for k in a.indices():
            if any(c is not None and c != i for c, i in zip(known, k, strict=True)):
                continue
            tests = [ast.BinOp("==", arg, ast.Num(float(i), st.span, str(i)), st.span)
                     for arg, c, i in zip(args, known, k, strict=True) if c is None]
            cond = tests[0]
            for t in tests[1:]:
                cond = ast.BinOp("AND", cond, t, st.span)
            branches.append(ast.Branch(cond, (replace(st, targets=(a.element(k),),
                                                      expr=expr, subscripts=()),), st.span))
        first = a.element(a.indices()[0])
        fault = replace(st, targets=(first,), subscripts=(),
                        expr=self._pick(a, list(args), known, st.span, ()))
        branches.append(ast.Branch(None, (fault,), st.span))
        return [ast.If(tuple(branches), st.span)]

    def loop(self, st: ast.Loop, env, written: bool) -> list:
        body = ast.every_statement(st.body)
        if any(self.reads_arrays(s) for s in body):
            used: list[str] = []
            try:
                start, stop, step = (self._value(e, env, used) if e is not None else 1.0
                                     for e in (st.start, st.stop, st.step))
            except _Unknown:
                start = stop = step = math.nan
            if step != 0 and all(math.isfinite(b) for b in (start, stop, step)):
                return self.written_out_loop(st, env, written, (start, stop, step), used,
                                             len(body))
        # (a loop that reads no array, or whose bounds are known only as the run goes:
        # a loop, its subscripts through ELEMENT)
        return [replace(st, start=self.expr(st.start, env), stop=self.expr(st.stop, env),
                        step=self.expr(st.step, env),
                        body=tuple(self.statements(st.body, env, written)))]

    def reads_arrays(self, st) -> bool:
        if isinstance(st, ast.Assign) and (st.subscripts or set(st.targets) & self.arrays.keys()):
            return True
        return any(isinstance(n, ast.Index) or (isinstance(n, ast.Call) and n.func in self.arrays)
                   or (isinstance(n, ast.Name) and n.name in self.arrays) for n in ast.walk(st))

    def written_out_loop(self, st: ast.Loop, env, written: bool, bounds, used: list[str],
                         size: int) -> list:
        """The loop written out pass by pass (its bounds known when it is read)."""
        from ..library.runtime import loop_count  # (the library imports the IR, which
        # imports this package)

        start, stop, step = bounds
        try:
            passes = loop_count(start, stop, step)  # (Fortran's trip count, as at run time)
        except ValueError as exc:
            self.error(str(exc), st.span, "write bounds that give fewer passes")
            return []
        self.written_out += passes * size
        if self.written_out > MAX_ELEMENTS:
            self.error(f"the loops over arrays write out more than {MAX_ELEMENTS:,} "
                       "statements", st.span, "use smaller arrays")
            return []
        self.fixed.update(used)
        out: list = []
        for p in range(passes):
            out.extend(self.statements(st.body, {**env, st.var: _number(start + p * step)},
                                       written))
        # (the value after the last pass, as Fortran leaves it, where anything reads it)
        if written and st.var in self.read_after_loops:
            final = _number(start + passes * step)
            out.append(ast.Assign((st.var,), (st.span,),
                                  ast.Num(float(final), st.span, str(final)), st.span))
        return out


def _read_outside_loops(statements) -> set[str]:
    """The names read (or reported) somewhere no loop over them encloses."""
    out: set[str] = set()
    stack = [(st, frozenset()) for st in statements]
    while stack:
        st, inside = stack.pop()
        if isinstance(st, ast.Report):
            out.update(st.names)
            continue
        if isinstance(st, ast.Loop):
            for e in (st.start, st.stop, st.step):
                if e is not None:
                    out.update(n.name for n in ast.walk(e) if isinstance(n, ast.Name)
                               and n.name not in inside)
            stack.extend((b, inside | {st.var}) for b in st.body)
            continue
        body = st.body if isinstance(st, (ast.Procedural, ast.Block, ast.FunctionDef)) else \
            tuple(b for br in st.branches for b in br.body) if isinstance(st, ast.If) else ()
        if body:
            if isinstance(st, ast.If):
                out.update(n.name for br in st.branches if br.cond is not None
                           for n in ast.walk(br.cond) if isinstance(n, ast.Name)
                           and n.name not in inside)
            stack.extend((b, inside) for b in body)
            continue
        out.update(n.name for n in ast.walk(st) if isinstance(n, ast.Name)
                   and n.name not in inside)
    return out


def _number(v: float) -> int | float:
    return int(v) if v == int(v) else v
