"""The tutorial's Python snippet, run as written from the clone's folder, prints
what the tutorial shows (issue 28: it had gone stale, and failed when saved as a
script elsewhere without saying where to run it)."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

from conftest import ROOT


def test_the_tutorials_python_prints_what_it_shows(monkeypatch):
    text = (Path(ROOT) / "docs" / "tutorial.md").read_text(encoding="utf-8")
    section = text[text.index("## 6. The same from Python"):]
    code, shown = re.search(r"```python\n(.*?)```\n```\n(.*?)```", section, re.S).groups()
    monkeypatch.chdir(ROOT)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "tutorial.md", "exec"), {})  # noqa: S102 - the docs' own code
    assert out.getvalue() == shown
