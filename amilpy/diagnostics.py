"""One error family for everything wrong with a listing, rendered once at the edge.

Each stage (parse, check, compile, run set-up) collects every fault it finds into a
`Reporter` and raises a single `AmilError` carrying all of them, so a student sees
every mistake of a stage in one go, each as ``model.amil:12:5: error: ...`` with
the source line, a caret under the offending text and a hint.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from .language import split_lines


@dataclass(frozen=True)
class Span:
    """A stretch of source text: 1-based line and column, end exclusive."""

    line: int
    column: int
    end_line: int | None = None
    end_column: int | None = None

    def __str__(self) -> str:
        return f"{self.line}:{self.column}"


@dataclass(frozen=True)
class Diagnostic:
    message: str
    span: Span | None = None
    hint: str | None = None
    severity: str = "error"
    # Further places that belong to the same fault (e.g. every equation of an
    # algebraic loop), each with a short note.
    related: tuple[tuple[Span, str], ...] = ()


class AmilError(Exception):
    """A fault in a listing (or in how it was asked to run).

    `.diagnostics` holds every fault the stage found; `.path`, `.line` and
    `.column` point at the first one.
    """

    def __init__(
        self,
        diagnostics: list[Diagnostic] | str,
        path: str | None = None,
        source: str | None = None,
    ) -> None:
        if isinstance(diagnostics, str):
            diagnostics = [Diagnostic(diagnostics)]
        self.diagnostics = list(diagnostics)
        self.path = path
        self.source = source
        first = self.diagnostics[0].span if self.diagnostics else None
        self.line = first.line if first else None
        self.column = first.column if first else None
        super().__init__(self.diagnostics[0].message if self.diagnostics else "error")

    def render(self) -> str:
        return render(self.diagnostics, self.path, self.source)

    def _repr_html_(self) -> str:
        from html import escape

        return f"<pre style='color:#b00'>{escape(self.render())}</pre>"


@contextmanager
def in_file(path: str | None, source: str | None) -> Iterator[None]:
    """A fault raised inside that names no file is a fault of this one."""
    try:
        yield
    except AmilError as exc:
        if exc.path is None:
            exc.path, exc.source = path, source
        raise


class UsageError(AmilError):
    """A call that cannot be right whatever the listing says: a data value or
    variable it does not have, an unknown method, a tolerance that is not positive,
    options that exclude each other. Raised by the API where it checks its
    arguments; the command line, which checks nothing the API checks, exits 2."""

    def text(self) -> str:
        """The message with its hint, on one line."""
        d = self.diagnostics[0]
        return f"{d.message}; {d.hint}" if d.hint else d.message


def _source_excerpt(source: str | None, span: Span) -> list[str]:
    if source is None:
        return []
    lines = split_lines(source)  # as the reader counts them (no U+2028, \f, ...)
    if not 1 <= span.line <= len(lines):
        return []
    text = lines[span.line - 1].expandtabs(1)
    # A 1 MB line would bury the message: show a window around the caret.
    start = 0
    if len(text) > 200:
        start = max(0, span.column - 80)
        text = ("…" if start else "") + text[start : start + 160] + "…"
    col = max(span.column - start - (0 if start == 0 else -1), 1)
    width = 1
    if span.end_line == span.line and span.end_column and span.end_column > span.column:
        width = min(span.end_column - span.column, max(1, len(text) - col + 1))
    gutter = f"{span.line:>5} | "
    return [gutter + text, " " * (len(gutter) - 2) + "| " + " " * (col - 1) + "^" * width]


def render(diagnostics: list[Diagnostic], path: str | None, source: str | None) -> str:
    """Format diagnostics the way compilers do: location, message, line, caret, hint."""
    where = path or "<listing>"
    out: list[str] = []
    for d in diagnostics:
        loc = f"{where}:{d.span.line}:{d.span.column}" if d.span else where
        out.append(f"{loc}: {d.severity}: {d.message}")
        if d.span:
            out.extend(_source_excerpt(source, d.span))
        for span, note in d.related:
            out.append(f"{where}:{span.line}:{span.column}: note: {note}")
            out.extend(_source_excerpt(source, span))
        if d.hint:
            out.append(f"      = hint: {d.hint}")
    n = sum(1 for d in diagnostics if d.severity == "error")
    if n > 1:
        out.append(f"{n} errors")
    return "\n".join(out)


@dataclass
class Reporter:
    """Collects the faults of one stage; `raise_if_any` ends the stage."""

    path: str | None
    source: str | None
    diagnostics: list[Diagnostic] = field(default_factory=list)
    # every error reported, a repeat included: what a check compares to see whether it
    # found a fault (the list says a repeated one once: a MACRO line called twice)
    errors: int = 0

    def error(
        self,
        message: str,
        span: Span | None = None,
        hint: str | None = None,
        related: tuple[tuple[Span, str], ...] = (),
    ) -> None:
        self.errors += 1
        d = Diagnostic(message, span, hint, "error", related)
        if d not in self.diagnostics:  # (two checks meeting one fault say it once)
            self.diagnostics.append(d)

    def raise_if_any(self) -> None:
        if self.diagnostics:
            ordered = sorted(
                self.diagnostics,
                key=lambda d: (d.span.line, d.span.column) if d.span else (10**9, 0),
            )
            raise AmilError(ordered, self.path, self.source)


def nearest(name: str, candidates: Iterable[str]) -> str | None:
    """The known name closest to a misspelt one, if any is close enough to suggest."""
    import difflib

    hits = difflib.get_close_matches(name.upper(), sorted(candidates), n=1, cutoff=0.6)
    return hits[0] if hits else None


def did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """"did you mean X?" for the known name closest to a misspelt one, or ""."""
    hint = nearest(name, candidates)
    return f"did you mean {hint}?" if hint else ""


def with_hint(message: str, name: str, candidates: Iterable[str]) -> str:
    """`message`, and "; did you mean X?" when a known name is close to `name`."""
    hint = did_you_mean(name, candidates)
    return f"{message}; {hint}" if hint else message
