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


def test_the_tutorials_printout_and_csv_are_what_the_run_prints(tmp_path, monkeypatch,
                                                                capsys):
    """Sections 3 and 4 show the printout and the CSV of the shipped clutch: every
    line shown is a line the run prints (they had gone stale when the default
    tolerances tightened, issue 21)."""
    import shutil

    from amilpy.cli import main

    text = (Path(ROOT) / "docs" / "tutorial.md").read_text(encoding="utf-8")
    section3 = text[text.index("## 3."):text.index("## 4.")]
    section4 = text[text.index("## 4."):text.index("## 5.")]
    shutil.copytree(Path(ROOT) / "models", tmp_path / "models")
    monkeypatch.chdir(tmp_path)
    assert main(["run", "models/ex4_clutch.amil", "--plot", "--zoom-events"]) == 0
    printed = capsys.readouterr().out.splitlines()
    shown = [line for block in _output_blocks(section3) for line in block]
    assert len(shown) > 25
    for line in shown:
        if line == "..." or line.startswith("written: "):
            continue
        assert line in printed, line
    written = next(line for line in shown if line.startswith("written: "))
    for path in written[len("written: "):].split(", "):
        assert (tmp_path / "models" / Path(path).name).exists(), path
    assert main(["run", "models/ex4_clutch.amil", "--set", "B=2.0E-5", "--quiet", "--csv",
                 "b2e-5.csv"]) == 0
    csv_shown = next(b for b in _output_blocks(section4) if b and b[0].startswith("TIME,"))
    assert (tmp_path / "b2e-5.csv").read_text().splitlines()[:len(csv_shown)] == csv_shown


def _output_blocks(text: str) -> list[list[str]]:
    """The fenced blocks without a language (what a command printed), as lines."""
    blocks, current, info = [], None, ""
    for line in text.splitlines():
        if line.startswith("```"):
            if current is None:
                current, info = [], line[3:].strip()
            else:
                if not info:
                    blocks.append(current)
                current = None
        elif current is not None:
            current.append(line)
    return blocks
