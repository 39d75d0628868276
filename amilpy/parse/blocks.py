"""Statements read one by one -> nested blocks (contract sections 9 and 10).

The grammar reads block openers (`IF (c) THEN`, `DISCRETE name`, `DO i = 1, N`, the
sections of the ACSL form ...) and closers (`END`, `END IF`, `END DO`) as statements
of their own, so a fault in one is located like any other; `nest` builds the
blocks. In ACSL form (the first statement is PROGRAM or MODEL) `END` closes the
innermost open block; `END IF`/`ENDIF` closes only an IF and `END DO`/`ENDDO` only
a DO. In CSMP form the sections stay markers and `END` ends a run group; IF and DO
blocks nest the same way, closed by `END IF` and `END DO`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..diagnostics import Diagnostic, Span
from . import syntax as ast

# what opens a block, as a reader calls it
_NAMES = {"IF": "IF", "FOR": "FOR loop", "DO": "DO loop", "PROCEDURAL": "PROCEDURAL",
          "FUNCTION": "FUNCTION", "DISCRETE": "DISCRETE", "PROGRAM": "PROGRAM",
          "INITIAL": "INITIAL", "DYNAMIC": "DYNAMIC", "DERIVATIVE": "DERIVATIVE",
          "TERMINAL": "TERMINAL", "MACRO": "MACRO", "PROCEDURE": "PROCEDURE",
          "EVENT": "EVENT"}
# CSMP III's and FST's blocks and the closer each needs (END ends a run group in CSMP
# form)
CLOSERS = {"MACRO": "ENDMAC", "PROCEDURE": "ENDPRO", "EVENT": "ENDEVENT"}
OPENERS = {closer: kind for kind, closer in CLOSERS.items()}
ACSL_ONLY = ("FOR", "PROCEDURAL", "FUNCTION", "DISCRETE", "INCLUDED")


@dataclass
class Head:
    """A block opener: IF (data: the condition), PROCEDURAL ((outputs, inputs)),
    FOR/DO ((var, start, stop, step)), FUNCTION ((result, params)), DISCRETE and
    the ACSL sections (name), PROGRAM (its name)."""

    kind: str
    span: Span
    name: str | None = None
    data: object = None
    label: str | None = None  # DO 10 I = ...: closed by `10 CONTINUE`


@dataclass
class ElseHead:
    cond: ast.Expr | None  # ELSE IF (c); None: ELSE
    span: Span


@dataclass
class Close:
    kind: str  # END, ENDIF, ENDDO
    span: Span
    label: str | None = None  # `10 CONTINUE`: the end of the DO loops labelled 10


@dataclass
class _Open:
    head: Head
    branches: list[tuple[ast.Expr | None, Span, list]] = field(default_factory=list)

    @property
    def body(self) -> list:
        return self.branches[-1][2]


def _acsl_macro(item) -> bool:
    """ACSL's MACRO NAME(A1, ...) head (not CSMP III's MACRO O = NAME(P))."""
    return isinstance(item, Head) and item.kind == "MACRO" and bool(item.data[2])


def _describe(kind: str) -> str:
    return _NAMES.get(kind, kind)


def _a(kind: str) -> str:
    """'a MACRO', 'an EVENT'."""
    return f"{'an' if kind[:1] in 'AEIOU' else 'a'} {kind}"


class Nester:
    """Builds the nested statements; faults go to `errors`."""

    def __init__(self, errors: list[Diagnostic]) -> None:
        self.errors = errors
        self.notes: list[Diagnostic] = []  # warnings the checked program carries

    def error(self, message: str, span: Span | None, hint: str | None = None) -> None:
        self.errors.append(Diagnostic(message, span, hint))

    def nest(self, items: list) -> tuple[str, str, list]:
        """(form, program name, top-level statements)."""
        first = next((s for s in items if not isinstance(s, ast.Title)), None)
        # (ACSL MACROs may be defined before the PROGRAM they serve)
        acsl = isinstance(first, Head) and (first.kind == "PROGRAM" or _acsl_macro(first) and any(
            isinstance(s, Head) and s.kind == "PROGRAM" for s in items))
        form = "ACSL" if acsl else "CSMP"
        # the labels a GO TO names (a `13 CONTINUE` no DO ends is its place)
        jumped_to = {n.label for s in items if isinstance(s, ast.Node)
                     for n in ast.walk_statements(s) if isinstance(n, ast.GoTo)}
        stack: list[_Open] = []
        top: list = []
        name, closed = "", None
        for item in items:
            if acsl and isinstance(item, ast.Section):
                item = Head(item.written or item.name, item.span)
            if acsl and isinstance(item, ast.End):
                item = Close("END", item.span)
            if closed is not None:
                # (ACSL's translator reads the program up to its END: what follows is
                # not read, as published listings that leave code there expect)
                if not isinstance(item, ast.Title) and not self.notes:
                    self.notes.append(Diagnostic(
                        f"the text after the program's END (line {closed.line}) is not "
                        "read", item.span, "remove it, or move it inside the program",
                        "warning"))
                continue
            target = stack[-1].body if stack else top
            if isinstance(item, Head):
                if item.kind == "PROGRAM":
                    if not acsl or stack or not all(isinstance(s, ast.Macro) for s in top):
                        self.error("PROGRAM or MODEL must be the first statement", item.span,
                                   "a file in ACSL form starts with PROGRAM or MODEL")
                        continue
                    name = item.name or ""
                elif item.kind == "MACRO" and _acsl_macro(item) and not acsl:
                    self.error("ACSL's MACRO NAME(A1, A2) ... MACRO END belongs to the ACSL "
                               "form", item.span, "start the file with PROGRAM, or write "
                               "CSMP III's MACRO O1 = NAME(P1, P2) ... ENDMAC")
                    continue
                elif item.kind == "MACRO" and not _acsl_macro(item) and (acsl or stack):
                    self.error("MACRO ... ENDMAC stands at the top level of a CSMP-form "
                               "listing" if not acsl else "CSMP III's MACRO O = NAME(P) ... "
                               "ENDMAC in the ACSL form", item.span,
                               "define it before the statements that call it" if not acsl
                               else "write ACSL's MACRO NAME(O, P) ... MACRO END")
                    continue
                elif acsl and item.kind == "EVENT":
                    # (opened all the same, so that its ENDEVENT closes it: one fault)
                    self.error("FST's EVENT ... ENDEVENT belongs to the CSMP (FST) form",
                               item.span, "in ACSL form write SCHEDULE name .XZ. condition "
                               "and DISCRETE name ... END")
                    item.data = "refused"
                elif stack and item.kind == "EVENT":
                    self.error(f"an EVENT cannot stand inside the {_describe(stack[-1].head.kind)} "
                               f"of line {stack[-1].head.span.line}", item.span,
                               "write EVENT ... ENDEVENT among the listing's statements")
                    item.data = "refused"
                elif not acsl and item.kind in ACSL_ONLY:
                    self.error(f"{_describe(item.kind)} belongs to the ACSL form", item.span,
                               "start the file with PROGRAM or MODEL (ACSL form)"
                               + ("; in CSMP form write DO i = a, b ... END DO"
                                  if item.kind == "FOR" else ""))
                    continue
                opened = _Open(item)
                opened.branches.append((item.data if item.kind == "IF" else None, item.span, []))
                stack.append(opened)
            elif isinstance(item, ElseHead):
                if not stack or stack[-1].head.kind != "IF":
                    self.error("ELSE without an open IF", item.span)
                    continue
                open_if = stack[-1]
                if open_if.branches[-1][0] is None and len(open_if.branches) > 1:
                    self.error("ELSE IF or ELSE after the ELSE of this IF", item.span,
                               f"the IF opened at line {open_if.head.span.line} has its ELSE")
                    continue
                open_if.branches.append((item.cond, item.span, []))
            elif isinstance(item, Close) and item.label in jumped_to and \
                    not any(o.head.label == item.label for o in stack):
                # `13 CONTINUE` that a GO TO names and no DO ends: the place it jumps to
                target.append(ast.Target(item.label, item.span))
            elif isinstance(item, Close):
                if item.label in jumped_to and stack and stack[-1].head.label == item.label:
                    # GO TO the loop's own CONTINUE: the rest of the pass skipped
                    stack[-1].body.append(ast.Target(item.label, item.span))
                done = self.close(stack, item, acsl)
                if done is None:
                    continue
                # (DO 10 I ... DO 10 J ... 10 CONTINUE: one label may end several loops)
                while item.label is not None and stack and stack[-1].head.label == item.label:
                    inner = self.block(done)
                    stack[-1].body.append(inner)
                    done = stack.pop()
                if done.head.kind == "PROGRAM":
                    top = top + list(self.block(done))  # (after the MACROs before it)
                    closed = item.span
                    continue
                built = self.block(done)
                into = stack[-1].body if stack else top
                if done.head.kind == "INCLUDED":  # its statements stand where it stands
                    into.extend(built)
                elif built is not None:  # (None: an EVENT whose fault is said)
                    into.append(built)
                    if isinstance(built, ast.Event):  # (its PARAMETERs are the listing's)
                        into.extend(built.data)
            elif isinstance(item, (ast.ZeroCondition, ast.NewValue)) and \
                    not (stack and stack[-1].head.kind == "EVENT"):
                word = item.kind if isinstance(item, ast.ZeroCondition) else "NEWVALUE"
                self.error(f"{word} stands inside an EVENT", item.span,
                           f"write EVENT / {word} ... / ENDEVENT")
            else:
                target.append(item)
        for opened in reversed(stack):
            self.error(f"{_describe(opened.head.kind)} opened at line "
                       f"{opened.head.span.line} is never closed", opened.head.span,
                       "close it with " + self.closer(opened.head.kind, acsl))
        return form, name, top

    @staticmethod
    def closer(kind: str, acsl: bool) -> str:
        if kind == "MACRO" and acsl:
            return "MACRO END"
        if kind == "IF":
            return "END IF" + (" (or END)" if acsl else "")
        if kind == "DO":
            return "END DO" + (" (or END)" if acsl else "")
        return CLOSERS.get(kind, "END")

    def close(self, stack: list[_Open], item: Close, acsl: bool) -> _Open | None:
        said = "MACRO END" if acsl and item.kind == "ENDMAC" else item.kind
        if not stack:
            opens = OPENERS.get(item.kind)
            self.error(f"{said} with no open block", item.span,
                       f"{said} closes {_a(opens)}: write {opens} ... {said}" if opens
                       else "every END closes a block opened before it")
            return None
        kind = stack[-1].head.kind
        line = stack[-1].head.span.line
        if item.kind in OPENERS and kind != OPENERS[item.kind]:
            self.error(f"{said} closes {_a(OPENERS[item.kind])}, but the innermost open "
                       f"block is the {_describe(kind)} of line {line}", item.span,
                       f"close that {_describe(kind)} first with {self.closer(kind, acsl)}")
            return None
        if kind in CLOSERS and item.kind != CLOSERS[kind]:
            self.error(f"{'END' if item.kind == 'END' else item.kind} inside the {kind} of "
                       f"line {line}", item.span, f"{_a(kind)} ends with "
                       f"{self.closer(kind, acsl)}")
            return None
        if item.label is not None and stack[-1].head.label != item.label:
            self.error(f"{item.label} CONTINUE ends no DO loop labelled {item.label}"
                       + (f": the innermost open block is the {_describe(kind)} of line "
                          f"{line}" if kind != "DO" or stack[-1].head.label is None else
                          f": the innermost is DO {stack[-1].head.label} of line {line}"),
                       item.span, f"a loop DO {item.label} I = a, b ends at {item.label} "
                       "CONTINUE")
            return None
        want = {"ENDIF": "IF", "ENDDO": "DO"}.get(item.kind)
        if want is not None and kind != want:
            self.error(f"{'END IF' if want == 'IF' else 'END DO'} closes "
                       f"{'an IF' if want == 'IF' else 'a DO loop'}, but the "
                       f"innermost open block is the {_describe(kind)} of line "
                       f"{stack[-1].head.span.line}", item.span,
                       f"close that {_describe(kind)} first with "
                       f"{self.closer(kind, acsl)}")
            return None
        return stack.pop()

    def block(self, opened: _Open):
        head = opened.head
        body = tuple(opened.body)
        if head.kind in ("PROGRAM", "INCLUDED"):
            return body
        if head.kind == "IF":
            return ast.If(tuple(ast.Branch(cond, tuple(b), span)
                                for cond, span, b in opened.branches), head.span)
        if head.kind in ("PROCEDURAL", "PROCEDURE"):
            outputs, inputs = head.data
            return ast.Procedural(outputs, inputs, body, head.span)
        if head.kind in ("FOR", "DO"):
            var, start, stop, step = head.data
            if isinstance(step, ast.Num) and step.value == 0.0:
                self.error(f"a {head.kind} loop with step 0 never ends", step.span,
                           "write a step other than 0 (or none: 1)")
            return ast.Loop(var, start, stop, step, body, head.span, head.kind)
        if head.kind == "MACRO":
            outputs, params, acsl = head.data
            if not acsl:
                return ast.Macro(head.name or "", outputs, params, body, head.span)
            directives = [st for st in body if isinstance(st, ast.MacroDirective)]
            return ast.Macro(
                head.name or "", (), params,
                tuple(st for st in body if not isinstance(st, ast.MacroDirective)),
                head.span, True,
                tuple(pair for d in directives if d.kind == "STANDVAL"
                      for pair in zip(d.names, d.values, strict=True)),
                tuple(n for d in directives if d.kind == "REDEFINE" for n in d.names))
        if head.kind == "FUNCTION":
            result, params = head.data
            return ast.FunctionDef(head.name or "", result, params, body, head.span)
        if head.kind == "EVENT":
            return self.event(head, body)
        return ast.Block(head.kind, head.name, body, head.span)

    def event(self, head: Head, body: tuple) -> ast.Event | None:
        """EVENT ... ENDEVENT: its condition (ZEROCONDITION, or FIRSTTIME and maybe
        NEXTTIME), NEWVALUEs, assignments of its own and PARAMETERs."""
        if head.data == "refused":  # (where it stands is said)
            return None
        conditions: dict[str, ast.ZeroCondition] = {}
        for st in body:
            if isinstance(st, ast.ZeroCondition):
                if st.kind in conditions:
                    self.error(f"a second {st.kind} in one EVENT", st.span,
                               f"the EVENT of line {head.span.line} has its {st.kind} at "
                               f"line {conditions[st.kind].span.line}: write another EVENT")
                conditions.setdefault(st.kind, st)
            elif not isinstance(st, (ast.NewValue, ast.Assign, ast.Data)):
                self.error("an EVENT holds ZEROCONDITION (or FIRSTTIME and NEXTTIME), "
                           "NEWVALUE statements, assignments and PARAMETERs only",
                           getattr(st, "span", head.span), "compute other values among the "
                           "listing's statements and give them in NEWVALUE X = value")
        values = tuple(st for st in body if isinstance(st, ast.NewValue))
        zero, first, nxt = (conditions.get(k) for k in ("ZEROCONDITION", "FIRSTTIME",
                                                        "NEXTTIME"))
        if zero is None and first is None and nxt is None:
            self.error("this EVENT has no ZEROCONDITION", head.span,
                       "write ZEROCONDITION e (the NEWVALUEs run where e reaches zero), or "
                       "FIRSTTIME t (at t) for a time event")
        if zero is not None and (first or nxt) is not None:
            self.error("an EVENT has a ZEROCONDITION or a FIRSTTIME, not both",
                       (first or nxt).span, "write a time event as another EVENT")
        elif nxt is not None and first is None:
            self.error("NEXTTIME without FIRSTTIME", nxt.span,
                       "a time event starts at FIRSTTIME t; NEXTTIME gives each next time")
        if not values:
            self.error("this EVENT has no NEWVALUE", head.span,
                       "write NEWVALUE X = value for each state or SET variable it changes")
        seen: dict[str, ast.NewValue] = {}
        for st in values:
            if st.target in seen:
                self.error(f"NEWVALUE {st.target} twice in one EVENT", st.target_span,
                           f"line {seen[st.target].span.line} gives its new value already")
            seen.setdefault(st.target, st)
        # (one of ZEROCONDITION and FIRSTTIME, NEXTTIME only with FIRSTTIME, a NEWVALUE)
        if (zero is None) == (first is None) or (nxt and not first) or not values:
            return None
        return ast.Event(zero, first, nxt, tuple(st for st in body if isinstance(st, ast.Assign)),
                         values, head.span,
                         tuple(st for st in body if isinstance(st, ast.Data)))
