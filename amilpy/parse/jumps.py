"""GO TO in written-order code, written out as IF blocks (issues 22, 23).

    IF (FORSET .EQ. 1.0) GO TO 10          GO1#10 = 0.0 ... (each label's flag, first)
    IF (MIXSET .EQ. 1.0) GO TO 11          IF (FORSET .EQ. 1.0) GO1#10 = 1.0
    10: X = 1.0                            IF (GO1#10 < 0.5) THEN
        GO TO 13                              IF (MIXSET .EQ. 1.0) GO1#11 = 1.0
    11: X = 2.0                            END IF
    13: CONTINUE                           GO1#10 = 0.0   (label 10: every path here)
                                           ...

A jump goes forward, to a label later in its own statement list or in one around it
(out of an IF or a DO loop, never into one): each label a GO TO names gets a flag, set
where the GO TO stands and cleared at the label; a statement between runs only where
no flag of a label still ahead of it is set. The flags are variables of the section
or PROCEDURAL (`GOk#label`, k counting the places GO TO is used), 0 at its start. A
jump out of a DO loop leaves the loop's remaining passes doing nothing. The same
numbers as the jumps: the conditions are evaluated where they stand, nothing is
evaluated that the jump skips. Refused at the GO TO: a jump backwards (a loop), into
a block, to a label the section does not have, and a label written twice.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import count

from ..diagnostics import Diagnostic
from . import syntax as ast

# the statement lists no jump leaves: a section, a PROCEDURAL, a FUNCTION, a MACRO
_SCOPES = (ast.Block, ast.Procedural, ast.FunctionDef, ast.Macro)


def lower_jumps(statements: list, errors: list[Diagnostic], sorted_top: bool = False
                ) -> list:
    """The statements with every GO TO and its label written out as IF blocks (the
    statements as they are where there is none). `sorted_top`: the statements outside
    any section are sorted code (an ACSL program's DERIVATIVE without its keyword),
    where no GO TO can stand."""
    if not any(isinstance(n, (ast.GoTo, ast.Target)) for st in statements
               for n in ast.walk_statements(st)):
        return statements
    places = count(1)

    def scopes(body) -> list:
        out = []
        for st in body:
            if isinstance(st, _SCOPES):
                st = replace(st, body=tuple(scopes(st.body)))
                st = _Scope(st.body, next(places), errors).written(st)
            elif isinstance(st, (ast.If, ast.Loop)):
                st = ast.with_bodies(st, scopes)
            out.append(st)
        return out

    top = _Scope(tuple(scopes(statements)), next(places), errors)
    if sorted_top and top.used:
        top.refuse_sorted()
        return statements
    return top.lowered_top()


def _jumps_in(st) -> bool:
    """Whether an IF or a loop holds a GO TO or a label (not inside a scope of its own,
    whose jumps are written out already or refused)."""
    stack = [st]
    while stack:
        n = stack.pop()
        if isinstance(n, (ast.GoTo, ast.Target)):
            return True
        if n is st or not isinstance(n, _SCOPES):
            stack.extend(n.children())
    return False


class _Scope:
    """One statement list no jump leaves, and the jumps in it (nested IFs and loops
    included, nested PROCEDURALs not)."""

    def __init__(self, body: tuple, place: int, errors: list[Diagnostic]) -> None:
        self.body, self.place, self.errors = body, place, errors
        self.used: dict[str, object] = {}  # label -> the first GO TO naming it
        self.labels: dict[str, object] = {}
        self.order: dict[int, int] = {}  # id of a GO TO or a label -> its place in the text
        self.kept_vars: set[str] = set()  # loop variables a jump out of a loop keeps
        self._collect(body)

    def _collect(self, body) -> None:
        for st in body:
            if isinstance(st, (ast.Target, ast.GoTo)):
                self.order[id(st)] = len(self.order)
            if isinstance(st, ast.Target):
                if st.label in self.labels:
                    self.errors.append(Diagnostic(
                        f"the label {st.label} is written twice", st.span,
                        f"the first is at line {self.labels[st.label].span.line}: give "
                        "each place its own label"))
                self.labels.setdefault(st.label, st)
            elif isinstance(st, ast.GoTo):
                self.used.setdefault(st.label, st)
            elif isinstance(st, (ast.If, ast.Loop)):
                for b in (st.branches if isinstance(st, ast.If) else (st,)):
                    self._collect(b.body)

    def flag(self, label: str) -> str:
        return f"GO{self.place}#{label}"

    def written(self, st):
        """A section, PROCEDURAL, FUNCTION or MACRO with its jumps written out."""
        if not self.used and not self.labels:
            return st
        if isinstance(st, ast.Block) and st.kind == "DERIVATIVE" and self.used:
            self.refuse_sorted()
            return st
        body = self.lowered_top()
        if isinstance(st, ast.Procedural) and (st.outputs or st.inputs):
            # (its flags are its own outputs: not a name left out of its list)
            flags = tuple(self.flag(x) for x in sorted(self.used))
            st = replace(st, outputs=st.outputs + flags)
        return replace(st, body=tuple(body))

    def refuse_sorted(self) -> None:
        first = next(iter(self.used.values()))
        self.errors.append(Diagnostic(
            "GO TO in DERIVATIVE's sorted code, whose order is not the written one",
            first.span, "put the GO TO and its label inside a PROCEDURAL block"))

    def lowered_top(self) -> list:
        start = self.body[0].span if self.body else None
        body, _ = self.lower(self.body, frozenset(), frozenset())
        # (each flag and each kept loop variable has a value from the start: written-
        # order code reads no name before it has one)
        first = [self._set(label, 0.0, start) for label in sorted(self.used)]
        first += [ast.Assign((self.kept(v),), (start,), ast.Num(0.0, start, "0"), start)
                  for v in sorted(self.kept_vars)]
        return first + body

    def _set(self, label: str, value: float, span) -> ast.Assign:
        return ast.Assign((self.flag(label),), (span,), ast.Num(value, span, f"{value:g}"),
                          span)

    def _guard(self, pending: frozenset, statements: list, span) -> list:
        """statements, run only where no flag of `pending` is set."""
        if not pending or not statements:
            return statements
        cond = ast.BinOp("<", self._total(pending, span), ast.Num(0.5, span, "0.5"), span)
        return [ast.If((ast.Branch(cond, tuple(statements), span),), span)]

    def kept(self, var: str) -> str:
        """Where a loop's variable is kept when a GO TO leaves the loop (its name first:
        Fortran's implicit type is the variable's)."""
        return f"{var}#GO{self.place}"

    def lower(self, body, ahead: frozenset, pending: frozenset, loops: tuple = ()
              ) -> tuple[list, frozenset]:
        """body written out, where the labels `ahead` follow it in the lists around it,
        the flags `pending` may be set where it starts, and `loops` are the DO loops
        around it (their variable, the labels inside them): (its statements, the flags
        that may be set where it ends)."""
        out: list = []
        run: list = []
        run_pending = pending

        def flush() -> None:
            out.extend(self._guard(run_pending, list(run), run[0].span if run else None))
            run.clear()

        # the labels after each statement, in its list and the lists around it (one
        # pass from the end: a long section with one jump stays linear)
        after, seen = [], ahead
        for st in reversed(body):
            after.append(seen)
            if isinstance(st, ast.Target):
                seen = seen | {st.label}
        after.reverse()
        for st, later in zip(body, after, strict=True):
            if isinstance(st, ast.Target):
                flush()
                if st.label in self.used:
                    out.append(self._set(st.label, 0.0, st.span))  # (every path here)
                pending = pending - {st.label}
            elif isinstance(st, ast.GoTo):
                flush()
                if self._check(st, later):
                    # (and the variable of each loop it leaves keeps its value there)
                    left = [var for var, inside in loops if st.label not in inside]
                    self.kept_vars.update(left)
                    kept = [ast.Assign((self.kept(var),), (st.span,), ast.Name(var, st.span),
                                       st.span) for var in left]
                    out += self._guard(pending, [self._set(st.label, 1.0, st.span), *kept],
                                       st.span)
                    pending = pending | {st.label}
            elif isinstance(st, (ast.If, ast.Loop)) and _jumps_in(st):
                flush()
                inner, after = self._nested(st, later, loops)
                out += self._guard(pending, inner, st.span)
                pending = pending | after
            else:
                if run and run_pending != pending:
                    flush()
                if not run:
                    run_pending = pending
                run.append(st)
        flush()
        return out, pending

    def _nested(self, st, later: frozenset, loops: tuple):
        """An IF or DO loop holding jumps: its statements, each list written out; the
        flags that may be set after it (its jumps to labels after it)."""
        if isinstance(st, ast.If):
            branches, after = [], frozenset()
            for b in st.branches:
                body, left = self.lower(b.body, later, frozenset(), loops)
                branches.append(replace(b, body=tuple(body)))
                after |= left
            return [replace(st, branches=tuple(branches))], after
        # a loop: a jump out of it leaves its flag set for the passes that remain, so
        # each pass runs only where none of the flags it may set is; after it, the loop
        # variable is the one the jump left it with, not the count's end
        inside = frozenset(n.label for n in ast.walk(st) if isinstance(n, ast.Target))
        exits = frozenset(n.label for n in ast.walk(st) if isinstance(n, ast.GoTo)) - inside
        body, after = self.lower(st.body, later, exits, loops + ((st.var, inside),))
        out = [replace(st, body=tuple(body))]
        if exits:
            span = st.span
            out += self._guard_set(exits, [ast.Assign((st.var,), (span,),
                                                      ast.Name(self.kept(st.var), span),
                                                      span)], span)
        return out, after

    def _guard_set(self, flags: frozenset, statements: list, span) -> list:
        """statements, run only where a flag of `flags` is set."""
        total = self._total(flags, span)
        cond = ast.BinOp(">", total, ast.Num(0.5, span, "0.5"), span)
        return [ast.If((ast.Branch(cond, tuple(statements), span),), span)]

    def _total(self, flags: frozenset, span):
        names = [ast.Name(self.flag(x), span) for x in sorted(flags)]
        total = names[0]
        for f in names[1:]:
            total = ast.BinOp("+", total, f, span)
        return total

    def _check(self, st: ast.GoTo, later: frozenset) -> bool:
        if st.label in later:
            return True
        target = self.labels.get(st.label)
        if target is None:
            what, hint = f"GO TO {st.label}: no label {st.label} where it can jump (its " \
                "section, PROCEDURAL or routine)", \
                f"write {st.label}: (a routine's {st.label} in columns 1-5) before the " \
                "statement to go to"
        elif self.order[id(target)] < self.order[id(st)]:
            what, hint = f"GO TO {st.label} jumps back (to line {target.span.line}): a " \
                "loop, which is not supported", "write DO i = a, b ... END DO, or the " \
                "passes one after another"
        else:
            what, hint = f"GO TO {st.label} jumps into an IF or DO block (to line " \
                f"{target.span.line}), which is not supported", \
                "jump to a label outside the block, or put the GO TO inside it"
        self.errors.append(Diagnostic(what, st.span, hint))
        return False
