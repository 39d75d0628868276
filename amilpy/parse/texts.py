"""CHARACTER names and their texts (ACSL form): read and set aside.

Published listings declare text variables for messages (`CHARACTER bufferslp*80`,
`CONSTANT bufferslp = 'RumPartSizeSlp is positive ...'`) that only routines amilpy
does not run would print. A run computes with numbers only, so a CHARACTER name's
declaration and its CONSTANT text leave the program here; a text given to a name not
declared CHARACTER, and a CHARACTER name read or assigned anywhere, is a located
error saying so (it would otherwise read as "used but never defined").
"""

from __future__ import annotations

from dataclasses import replace

from ..diagnostics import Diagnostic
from . import syntax as ast


def set_aside(statements: list, errors: list[Diagnostic]) -> list:
    """The statements without CHARACTER declarations and the texts of those names;
    faults go to `errors`."""
    everything = ast.every_statement(statements)
    texts = {name for st in everything if isinstance(st, ast.Declare)
             and st.type == "CHARACTER" for name in st.names}
    if not texts and not any(isinstance(st, ast.Data) and any(it.text is not None
                                                              for it in st.items)
                             for st in everything):
        return statements
    return _keep(statements, texts, errors)


def _keep(statements, texts: set[str], errors: list[Diagnostic]) -> list:
    out = []
    for st in statements:
        if isinstance(st, ast.Declare) and st.type == "CHARACTER":
            continue
        if isinstance(st, ast.Data):
            items = []
            for it in st.items:
                if it.text is not None and it.name in texts:
                    continue
                if it.text is not None:
                    errors.append(Diagnostic(
                        f"the string '{it.text}' cannot be a value of {it.name}", it.span,
                        f"a text is kept in a CHARACTER name (CHARACTER {it.name}*80); "
                        "a run computes with numbers: text is for TERMT messages and "
                        "comments"))
                elif it.name in texts:
                    errors.append(Diagnostic(
                        f"{it.name} is CHARACTER: it takes a text in quotes", it.span,
                        f"write CONSTANT {it.name} = 'text', or declare it a number"))
                else:
                    items.append(it)
            if items:
                out.append(replace(st, items=tuple(items)))
            continue
        _said(st, texts, errors)
        out.append(ast.with_bodies(st, lambda body: _keep(body, texts, errors)))
    return out


def _said(st, texts: set[str], errors: list[Diagnostic]) -> None:
    """A CHARACTER name read or assigned by st itself (not its blocks' statements)."""
    if not texts:
        return
    if isinstance(st, ast.Assign):
        named = [(n, s) for n, s in zip(st.targets, st.target_spans, strict=False)
                 if n in texts]
        roots = [st.expr]
    else:
        named = []
        roots = [getattr(b, "cond", None) for b in st.branches] if isinstance(st, ast.If) \
            else [getattr(st, f, None) for f in ("expr", "start", "stop", "step")]
    named += [(n.name, n.span) for r in roots if r is not None for n in ast.walk(r)
              if isinstance(n, ast.Name) and n.name in texts]
    for name, span in named[:1]:
        errors.append(Diagnostic(
            f"{name} is CHARACTER text: a run computes with numbers only", span,
            "text is kept only for what amilpy does not run (a message routine); "
            "compute with a number, or leave the statement out"))
