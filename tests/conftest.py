import os
import tempfile

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# METHOD COMPILED's models (with numba installed): kept for the next session, not
# in the user's own cache
os.environ.setdefault("AMILPY_CACHE", os.path.join(tempfile.gettempdir(), "amilpy-test-cache"))

import amilpy  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from amilpy.routes import ROUTES  # noqa: E402

# one METHOD spelling per route, from the registry
METHODS = [r.aliases[0] for r in ROUTES]


def run1(text: str, **kw):
    """Run a one-run listing and return its Run."""
    runs = amilpy.loads(text, name="t.amil").run(**kw)
    assert len(runs) == 1
    return runs[0]


@pytest.fixture
def root() -> str:
    return ROOT


# ---------------------------------------------------------------- token names
# No message may show a parser token name (DOLLAR, DATA_KW, __ANON_3, _NL, ...):
# every Diagnostic any test creates is scanned (issue 11, contract section 14).
# Terminal names that are plain words a message may use are left out.
_WORDS = {"NAME", "NUMBER", "INT", "TEXT", "STRING", "REST", "INITIAL", "DYNAMIC",
          "DERIVATIVE", "TERMINAL", "POW", "WS", "COMMENT", "TRUTH"}


def token_names() -> list[str]:
    from amilpy.parse import _parser

    names = {t.name for t in _parser().terminals} | {"$END", "_NL"}
    return sorted(n for n in names if n not in _WORDS)


def _pattern():
    import re

    names = "|".join(re.escape(n) for n in token_names())
    return re.compile(rf"(?<![A-Za-z0-9_$])({names}|__ANON_[0-9]+)(?![A-Za-z0-9_])")


TOKEN_NAME = _pattern()


def leaked_token(text: str | None) -> str | None:
    """The first parser token name in a message, if any (a character's Unicode name,
    "U+2212 MINUS SIGN", is no token)."""
    import re

    text = re.sub(r"U\+[0-9A-F]{4,6} [A-Z0-9 -]+", "", text or "")
    found = TOKEN_NAME.search(text)
    return found.group(1) if found else None


@pytest.fixture(autouse=True)
def _no_token_names_in_diagnostics(monkeypatch):
    from amilpy.diagnostics import Diagnostic

    original = Diagnostic.__init__

    def init(self, message, span=None, hint=None, severity="error", related=()):
        original(self, message, span, hint, severity, related)
        for text in (message, hint, *(note for _, note in related)):
            leaked = leaked_token(text)
            assert leaked is None, f"a parser token name ({leaked}) in a message: {text!r}"

    monkeypatch.setattr(Diagnostic, "__init__", init)
