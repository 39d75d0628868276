"""A CSV written as the runs make their rows (`Model.run(stream_csv=...)`, and
`amilpy run --csv` for a run whose rows would take much memory): a long run's
OUTDEL rows go to the file part by part (`run.record.Rows` hands each part of
32,768 rows over), and the run keeps in memory only what the printout, RANGE and
the figures need -- its PRDEL rows, the rows of observed instants, every k-th
OUTDEL row (at most KEEP of them, evenly: the figures), and the last row.

The file is the one `sheets.write_csv` writes for the same runs, byte for byte:
the same header (a RUN column and the changed values first with several runs),
the same numbers (repr, the dialect's decimal mark), the PARTIAL notes of failed
runs on top. Its body goes to a temporary file beside the path while the runs go
on; `close` writes the notes and header and the body into the path atomically
(whole or absent, as every file), `discard` removes the temporary."""

from __future__ import annotations

import csv
import math
import os
import shutil
import tempfile
from collections.abc import Sequence

import numpy as np

from ..run.plan import nearest_instants
from .files import atomic_open
from .options import DIALECTS
from .sheets import export_names_from
from .words import run_column

KEEP = 20_000  # OUTDEL rows a streamed run keeps in memory at most (for its figures)


class CsvStream:
    """The rows of a sequence of runs to `path` (see the module)."""

    def __init__(self, path: str, names: Sequence[str] | None, dialect: str,
                 params: Sequence[dict[str, float]]) -> None:
        self.path, self.dialect = path, dialect
        self.names = list(names) if names is not None else None
        d = DIALECTS[dialect]
        self._newline, self._encoding = d.newline, d.encoding
        self._decimal = d.decimal
        folder = os.path.dirname(os.path.abspath(path)) or "."
        fd, self._tmp = tempfile.mkstemp(prefix=".amilpy-", suffix=".csv.part", dir=folder)
        self._body = os.fdopen(fd, "w", encoding=self._encoding, newline="")
        self._writer = csv.writer(self._body, delimiter=d.delimiter, lineterminator=d.newline)
        several = len(params) > 1
        self.changed = [n for n in dict.fromkeys(k for p in params for k in p)
                        if several and any(p.get(n) != params[0].get(n) for p in params)]
        self._params = list(params)
        self._run = 0
        self._prefix: list = []
        self._held: tuple | None = None  # the last row of a part: it may be the last
        self.rows = 0  # OUTDEL rows written
        self.kept = 0  # of them, kept in memory

    # ------------------------------------------------------------ a run
    def next_run(self, k: int) -> None:
        """Run k (1-based) begins."""
        self._run, self._held = k, None
        self._prefix = [k, *(float(self._params[k - 1].get(n, math.nan))
                             for n in self.changed)] if len(self._params) > 1 else []

    def begin(self, out_names: Sequence[str], constants: dict[str, float], reports,
              grid_rows: int, observed: Sequence[float] = ()) -> None:
        """The run's columns (its generated outputs' names), constants, reports, how
        many rows its grid has, and the instants observations are compared at (their
        rows are kept)."""
        self._observed = np.unique(np.asarray(observed, dtype=float))
        index = {n: i for i, n in enumerate(out_names)}
        if self.names is None:
            self.names = export_names_from(reports, lambda n: n in index or n in constants) \
                or [n for n in out_names if "#" not in n]
        self._columns = [index.get(n) for n in self.names]
        self._constants = [float(constants.get(n, math.nan)) for n in self.names]
        self._stride = max(1, math.ceil(grid_rows / KEEP))
        self._held = None

    def part(self, t: np.ndarray, g: np.ndarray, columns: list[np.ndarray],
             outdel: np.ndarray, prdel: np.ndarray, final: bool) -> np.ndarray:
        """Write a part's OUTDEL rows (the last row of the run's last part is one
        whatever its instant: the stop instant); the rows to keep in memory."""
        n = len(t)
        written = outdel.copy()
        if final and n:
            written[-1] = True
        held = self._held
        self._held = None
        if not final and n:
            # (the part's last row is written with the next part, which knows
            # whether it was the run's last)
            self._held = (float(t[-1]), [c[-1] for c in columns], bool(outdel[-1]))
            written[-1] = False
        if held is not None and (held[2] or (final and n == 0)):
            self._write([held[0]], [[v] for v in held[1]])
        rows = np.flatnonzero(written)
        if rows.size:
            self._write(t[rows].tolist(), [c[rows].tolist() for c in columns])
        keep = ~outdel | prdel | (g % self._stride == 0)
        if n and self._observed.size:  # (an observation on an OUTDEL instant: its row)
            keep |= nearest_instants(self._observed, t)[1]
        if n:
            keep[-1] = True
        self.kept += int(np.count_nonzero(keep & written))
        return keep

    def _write(self, t: list[float], columns: list[list[float]]) -> None:
        num = repr if self._decimal == "." else \
            (lambda x, d=self._decimal: repr(x).replace(".", d))
        cells = []
        for j, k in enumerate(self._columns):
            if k is None:
                cells.append([self._constants[j]] * len(t))
            else:
                cells.append([float(v) for v in columns[k]])
        prefix = [num(v) if isinstance(v, float) else v for v in self._prefix]
        self._writer.writerows(prefix + [num(x) for x in row]
                               for row in zip(t, *cells, strict=True))
        self.rows += len(t)

    # ------------------------------------------------------------ the file
    def close(self, notes: Sequence[str], made: Sequence[dict[str, float]]) -> None:
        """The file: `notes` (# lines), the header, the body; whole or absent. `made`:
        the data values of the runs made (fewer than planned after a Ctrl-C: the
        RUN and changed-value columns are then those of the runs made, as the CSV
        written after them has)."""
        self._body.close()
        index = run_column([*self.changed, *(self.names or [])])
        lead = [index, *self.changed] if len(self._params) > 1 else []
        changed = [n for n in dict.fromkeys(k for p in made for k in p)
                   if len(made) > 1 and any(p.get(n) != made[0].get(n) for p in made)]
        wanted = [index, *changed] if len(made) > 1 else []
        # (a data value both changed between the runs and asked for is its lead column
        # alone, as the CSV written after the runs has it)
        columns = ["TIME", *(self.names or [])]
        keep = [k for k, name in enumerate(lead) if name in wanted] + \
            [len(lead) + k for k, name in enumerate(columns) if name not in changed]
        sep = DIALECTS[self.dialect].delimiter
        try:
            with atomic_open(self.path, text=True, encoding=self._encoding, newline="") as fh:
                for line in notes:
                    fh.write(f"# {line}{self._newline}")
                csv.writer(fh, delimiter=sep, lineterminator=self._newline).writerow(
                    wanted + [n for n in columns if n not in changed])
                with open(self._tmp, encoding=self._encoding, newline="") as body:
                    if keep == list(range(len(lead) + len(columns))):
                        shutil.copyfileobj(body, fh, 1 << 20)
                    else:  # (numbers only: no field is quoted)
                        for row in body:
                            cells = row.rstrip("\r\n").split(sep)
                            fh.write(sep.join(cells[k] for k in keep) + self._newline)
        finally:
            self.discard()

    def discard(self) -> None:
        if not self._body.closed:
            self._body.close()
        try:
            os.unlink(self._tmp)
        except FileNotFoundError:
            pass
