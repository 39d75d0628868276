"""The printout and CSV: TERMINAL values after the table, switching events in the
listing's own terms, every cell formatted once, rows streamed (bounded memory)."""

import io
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import run1

import amilpy.output.tables as T
from amilpy.output import sheets
from amilpy.output.printout import format_run, write_runs
from amilpy.result import Event, EventKind, Run, Status

SLIDE = 0.5  # the mode of a sliding surface (neither sign)


def test_terminal_values_come_after_the_table_never_as_a_column():
    # TERMINAL's values are Run.terminal (filled by the run); a PRINTed TERMINAL
    # name is shown there, not as a column of NaN
    run = run1("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, PRDEL = 0.5\nPRINT X, Y\n"
               "TERMINAL\nY = 2.0*X\nEND\n")
    run.terminal = {"Y": 2.0 * math.exp(-1.0), "Z": -1.5}
    text = format_run(run)
    head = next(line for line in text.splitlines() if line.strip().startswith("TIME"))
    assert head.split() == ["TIME", "X"]
    assert "NaN" not in text
    block = text[text.index("\nTERMINAL\n"):].splitlines()
    assert block[2:4] == ["   Y = 7.357589E-01", "   Z = -1.500000E+00"]


def _event(kind, old, new, text="W1"):
    return Event(0.0354576566, "FSW for MFR (line 57)", 3, old, new, kind, text)


def test_events_in_the_listings_terms():
    assert str(_event(EventKind.SWITCH, 1.0, -1.0)) == \
        "TIME = 0.0354576566: FSW for MFR (line 57): W1 > 0 -> W1 < 0"
    assert str(_event(EventKind.SLIDE, 1.0, SLIDE)) == \
        "TIME = 0.0354576566: FSW for MFR (line 57): W1 stays at 0: both sides push it back"
    assert str(_event(EventKind.SWITCH, SLIDE, 1.0)) == \
        "TIME = 0.0354576566: FSW for MFR (line 57): W1 held at 0 -> W1 > 0"
    assert str(_event(EventKind.LEVEL, 2.0, 3.0, "X/0.5")).endswith("level 2 -> level 3")
    assert str(_event(EventKind.FINISH, 1.0, -1.0, "V + 12")).endswith(": reached")
    # str(event), for the Python user, says the same
    assert str(_event(EventKind.SWITCH, -1.0, 1.0)).endswith("W1 < 0 -> W1 > 0")


def test_event_text_of_a_real_run():
    run = run1("PARAM T1 = 0.5\nSW = FSW(TIME - T1, 0.0, 1.0, 1.0)\nX = INTGRL(0.0, SW)\n"
               "TIMER FINTIM = 1.0, PRDEL = 0.25\nMETHOD RKS\nEND\n")
    e, = run.events
    # "argument" until the front end fills Surface.text ("TIME - T1")
    words = (e.text or "argument")
    assert f"{words} < 0 -> {words} > 0" in format_run(run)
    assert "X<0" not in format_run(run)


def test_header_shows_the_settings_of_every_route():
    assert "(METHOD RK4, DELT " in format_run(run1(
        "X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, PRDEL = 0.5\nMETHOD RK4\nEND\n"))
    assert "(METHOD AUTO, RELERR 1e-10, ABSERR 1e-13)" in format_run(run1(
        "X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, PRDEL = 0.5\nEND\n"))


def synthetic_run(rows: int, names: int) -> Run:
    """A Run built directly (no integration): TIME 0..1, variable k = k + TIME."""
    t = np.linspace(0.0, 1.0, rows)
    values = {f"V{k}": t + k for k in range(names)}
    mask = np.ones(rows, bool)
    return Run("RUN 1", {}, {}, t, values, mask, mask, [], Status.FINISHED, "", {}, {},
               "AUTO", 1e-6, 1e-9)


def test_every_cell_is_formatted_once(monkeypatch):
    """10^4 PRINT names took 33 s: the table was rebuilt for every name. Now each
    cell is formatted once, and the printout holds all 10^4 columns in order."""
    run = synthetic_run(5, 10_000)
    formatted = []
    real = T.cells

    def counting(fmt, chunk, width=0):
        out = real(fmt, chunk, width)
        formatted.append(len(out))
        return out

    monkeypatch.setattr(T, "cells", counting)
    text = format_run(run)
    blocks = -(-10_000 // T.COLUMNS_PER_BLOCK)
    assert sum(formatted) == 5 * (10_000 + blocks)  # TIME is repeated in each block
    lines = text.splitlines()
    assert lines[-1].split()[-1] == f"{9999 + 1.0:.6E}"


STREAMED = """
import resource, sys
import numpy as np
sys.path.insert(0, {tests!r})
from test_printout import synthetic_run
from amilpy.output.printout import write_runs
from amilpy.output import sheets

run = synthetic_run(100_000, 20)
size = [int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmSize")][0]
limit = size * 1024 + 64 * 2**20  # what the arrays take now, and 64 MB for writing
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
with open("/dev/null", "w") as sink:
    write_runs(sink, [run])
sheets.write_csv(sys.argv[1], [run])
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and RLIMIT_AS")
@pytest.mark.slow  # (10^5 rows written: 7 s; CI runs it in its slow step)
def test_printout_and_csv_are_streamed(tmp_path):
    """One run of 10^6 rows x 30 variables peaked at 1.9 GB: the printout and CSV
    were built as whole strings. Streamed, 10^5 rows x 20 variables (58 MB of
    printout text, 40 MB of CSV) are written within 64 MB of address space more
    than the run's arrays take."""
    path = tmp_path / "big.csv"
    code = STREAMED.format(tests=os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    done = subprocess.run([sys.executable, "-c", code, str(path)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    with open(path) as fh:
        assert fh.readline().startswith("TIME,V0,V1")
        assert fh.readline() == ",".join(["0.0"] + [repr(float(k)) for k in range(20)]) + "\n"
        assert sum(1 for _ in fh) == 100_000 - 1


def test_csv_dialect_excel_pl(tmp_path):
    run = run1("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, OUTDEL = 0.5\nEND\n")
    path = tmp_path / "x.csv"
    sheets.write_csv(str(path), [run], ["X"], dialect="excel-pl")
    raw = path.read_bytes()
    assert raw.startswith(b"\xef\xbb\xbf")  # the BOM: a spreadsheet reads it as UTF-8
    rows = raw.decode("utf-8-sig").split("\r\n")
    assert rows[0] == "TIME;X" and rows[1] == "0,0;1,0"
    t, x = rows[3].split(";")
    assert t == "1,0" and float(x.replace(",", ".")) == pytest.approx(math.exp(-1), rel=1e-5)


def test_xlsx_writer(tmp_path):
    openpyxl_or_zip = pytest.importorskip("xlsxwriter")
    assert openpyxl_or_zip
    import zipfile

    runs = amilpy_runs("PARAM K = (1.0, 2.0)\nX = INTGRL(1.0, -K*X)\n"
                       "TIMER FINTIM = 1.0, OUTDEL = 0.5\nEND\n")
    path = tmp_path / "x.xlsx"
    sheets.write_xlsx(str(path), runs, ["X"])
    with zipfile.ZipFile(path) as z:
        book = z.read("xl/workbook.xml").decode()
        assert 'name="K = 1"' in book and 'name="K = 2"' in book
        sheet2 = z.read("xl/worksheets/sheet2.xml").decode()
    # the last row of run 2: TIME 1 and exp(-2), as numbers
    assert '<c r="A4"' in sheet2 and f"{math.exp(-2.0):.6f}"[:7] in sheet2


def amilpy_runs(text):
    import amilpy

    return amilpy.loads(text).run()


def test_printout_to_a_string_and_a_stream_agree():
    run = run1("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, PRDEL = 0.5\nRANGE X\nEND\n")
    out = io.StringIO()
    write_runs(out, [run])
    assert out.getvalue() == format_run(run, 1, 1)


def test_printer_plot_of_values_spanning_every_float():
    # Y from -1E308 to 1E308: max - min overflows to inf, and the symbol's column was
    # inf/inf (a ValueError from the printout); now each row has its symbol, from the
    # left edge at -1E308 through the zero line to the right edge at 1E308
    from amilpy.output.printout import printer_plot

    run = run1("PARAM A = 1.0E300\nX = INTGRL(0.0, 1.0)\nY = A*(2.0*X - 1.0)*1.0E8\n"
               "TIMER FINTIM = 1.0, OUTDEL = 0.1\nPRTPLT Y\nEND\n")
    from amilpy.output.printout import PLOT_WIDTH

    lines = printer_plot(run, ["Y"]).splitlines()
    fields = [ln[-PLOT_WIDTH:] for ln in lines[-11:]]
    assert all(f.count("*") == 1 for f in fields), fields
    assert fields[0].index("*") == 0 and fields[-1].index("*") == PLOT_WIDTH - 1
    assert fields[5].index("*") == PLOT_WIDTH // 2  # Y = 0 on the zero line
