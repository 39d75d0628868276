"""Golden files: each `golden/NAME.amil` (CSMP form) or `golden/NAME.csl` (ACSL form)
with its expected printout (`NAME.out`) or diagnostics (`NAME.err`), exactly as
`amilpy run` shows them.

Regenerate after a deliberate change with `AMILPY_GOLDEN=update pytest tests/test_golden.py`
and read the diff before committing it.
"""

import glob
import os

import pytest

from amilpy.cli import main

HERE = os.path.join(os.path.dirname(__file__), "golden")
CASES = sorted(os.path.basename(p) for ext in ("amil", "csl")
               for p in glob.glob(os.path.join(HERE, f"*.{ext}")))


@pytest.mark.parametrize("name", CASES)
def test_golden(name, capsys, monkeypatch):
    monkeypatch.chdir(HERE)
    code = main(["run", name])
    captured = capsys.readouterr()
    kind = "err" if code == 1 else "out"
    got = captured.err if code == 1 else captured.out
    path = os.path.join(HERE, f"{os.path.splitext(name)[0]}.{kind}")
    if os.environ.get("AMILPY_GOLDEN") == "update":
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(got)
    with open(path, encoding="utf-8") as fh:
        expected = fh.read()
    assert got == expected
