"""The distributions a Monte Carlo draws data values from, written as the command
line takes them, and the sampling: one place for both.

    normal(m, s)            mean m, standard deviation s
    lognormal(m, s)         exp of normal(m, s): m and s of the logarithm
    uniform(a, b)
    triangular(a, c, b)     lower a, mode c, upper b
    truncnormal(m, s, a, b) normal(m, s) kept within [a, b]
    table(FILE)             the rows of a CSV file, in order: its column of the
                            name (or its only column); names read from the same
                            file keep their rows together

Sampling (`sample`): one generator, NumPy's PCG64 seeded with the seed, draws a
standard normal score per run and per drawn name, in the order the names were
given; each name's value is its distribution's inverse CDF at Phi(score). So
the values depend on the seed alone, not on how the runs are spread over
processes or machines. Correlation between names is that of their normal
scores (a Gaussian copula): the scores are multiplied by the Cholesky factor of
the correlation matrix; the rank (Spearman) correlation of the values is then
6/pi asin(r/2), within 0.018 of r.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

import numpy as np

from ..diagnostics import UsageError
from ..language import fortran_float

# name -> (parameters, what they are)
KINDS: dict[str, tuple[tuple[str, ...], str]] = {
    "normal": (("m", "s"), "mean m, standard deviation s > 0"),
    "lognormal": (("m", "s"), "exp of normal(m, s): m, s > 0 of the logarithm"),
    "uniform": (("a", "b"), "a < b"),
    "triangular": (("a", "c", "b"), "lower a <= mode c <= upper b, a < b"),
    "truncnormal": (("m", "s", "a", "b"), "normal(m, s > 0) kept within a < b"),
    "table": (("FILE",), "the rows of a CSV file (its column of the name)"),
}
FORMS = "; ".join(f"{k}({', '.join(p)})" for k, (p, _) in KINDS.items())


@dataclass(frozen=True)
class Dist:
    kind: str
    args: tuple[float, ...] = ()
    file: str | None = None  # table(FILE)

    def text(self) -> str:
        if self.kind == "table":
            return f"table({self.file})"
        return f"{self.kind}({', '.join(f'{a:g}' for a in self.args)})"

    def quantile(self, u: np.ndarray) -> np.ndarray:
        """The inverse CDF at u in (0, 1)."""
        from scipy import stats

        a = self.args
        if self.kind == "normal":
            return stats.norm.ppf(u, a[0], a[1])
        if self.kind == "lognormal":
            return np.exp(stats.norm.ppf(u, a[0], a[1]))
        if self.kind == "uniform":
            return a[0] + (a[1] - a[0]) * u
        if self.kind == "triangular":
            lo, mode, hi = a
            return stats.triang.ppf(u, (mode - lo) / (hi - lo), loc=lo, scale=hi - lo)
        if self.kind == "truncnormal":
            m, s, lo, hi = a
            return stats.truncnorm.ppf(u, (lo - m) / s, (hi - m) / s, loc=m, scale=s)
        raise ValueError(self.kind)


def parse_dist(name: str, text: str, base: str | None = None) -> Dist:
    """`text` ("normal(1, 0.1)") as a Dist, checked; UsageError saying what to write.
    `base`: the folder a table's relative path is read from (default: here)."""
    where = f"--dist {name}={text}"
    body = text.strip()
    if "(" not in body or not body.endswith(")"):
        raise UsageError(f"{where}: write a distribution, one of {FORMS}")
    kind, inner = body[:-1].split("(", 1)
    kind = kind.strip().lower()
    if kind not in KINDS:
        from ..diagnostics import did_you_mean

        hint = did_you_mean(kind, list(KINDS))
        raise UsageError(f"{where}: {kind!r} is no distribution here" +
                         (f"; {hint}" if hint else f"; the forms are {FORMS}"))
    params, what = KINDS[kind]
    if kind == "table":
        path = inner.strip().strip("'\"")
        if not path:
            raise UsageError(f"{where}: table(FILE) needs the file")
        if base and not os.path.isabs(path):
            path = os.path.join(base, path)
        return Dist("table", file=path)
    parts = [p.strip() for p in inner.split(",")]
    if len(parts) != len(params):
        raise UsageError(f"{where}: {kind} takes {len(params)} numbers "
                         f"({kind}({', '.join(params)}): {what})")
    try:
        args = tuple(fortran_float(p) for p in parts)
    except ValueError:
        raise UsageError(f"{where}: the parameters must be numbers "
                         f"({kind}({', '.join(params)}))") from None
    if not all(math.isfinite(v) for v in args):
        raise UsageError(f"{where}: the parameters must be finite")
    ok = {"normal": lambda m, s: s > 0, "lognormal": lambda m, s: s > 0,
          "uniform": lambda a, b: a < b, "triangular": lambda a, c, b: a <= c <= b and a < b,
          "truncnormal": lambda m, s, a, b: s > 0 and a < b}[kind](*args)
    if not ok:
        raise UsageError(f"{where}: {kind}({', '.join(params)}) needs {what}")
    return Dist(kind, args)


def _table(path: str, name: str, cache: dict[str, tuple[list[str], np.ndarray]]
           ) -> np.ndarray:
    """Column `name` of a table file (or its only column)."""
    if path not in cache:
        try:
            with open(path, newline="", encoding="utf-8-sig") as fh:
                rows = [r for r in csv.reader(line for line in fh
                                              if line.strip() and not line.startswith("#"))]
        except OSError as exc:
            raise UsageError(f"table({path}): cannot read it: {exc.strerror}") from None
        except UnicodeDecodeError:
            raise UsageError(f"table({path}): not a text file (CSV, UTF-8)") from None
        if len(rows) < 2:
            raise UsageError(f"table({path}): needs a header row of names and a row of "
                             "values at least")
        header = [h.strip().upper() for h in rows[0]]
        values = np.full((len(rows) - 1, len(header)), np.nan)
        for i, row in enumerate(rows[1:], 2):
            if len(row) != len(header):
                raise UsageError(f"table({path}), line {i}: {len(row)} fields, the header "
                                 f"has {len(header)}")
            for j, field in enumerate(row):
                try:
                    values[i - 2, j] = fortran_float(field)
                except ValueError:
                    raise UsageError(f"table({path}), line {i}, column {header[j]}: not a "
                                     "number") from None
        if not np.all(np.isfinite(values)):
            raise UsageError(f"table({path}): every value must be finite")
        cache[path] = (header, values)
    header, values = cache[path]
    if name in header:
        return values[:, header.index(name)]
    if len(header) == 1:
        return values[:, 0]
    raise UsageError(f"table({path}) has no column {name} (its columns: "
                     f"{', '.join(header)})")


def sample(dists: dict[str, Dist], runs: int, seed: int,
           correlation: dict[tuple[str, str], float] | None = None
           ) -> dict[str, np.ndarray]:
    """`runs` values of each name (see the module)."""
    from scipy.special import ndtr

    drawn = [n for n, d in dists.items() if d.kind != "table"]
    correlation = correlation or {}
    for (a, b), r in correlation.items():
        for n in (a, b):
            if n not in dists:
                raise UsageError(f"--correlate {a},{b}: {n} has no --dist")
            if dists[n].kind == "table":
                raise UsageError(f"--correlate {a},{b}: {n} comes from a table, whose rows "
                                 "carry their own correlation")
        if a == b or not -1 < r < 1:
            raise UsageError(f"--correlate {a},{b}={r:g}: two different names and a "
                             "correlation strictly between -1 and 1")
    matrix = np.eye(len(drawn))
    for (a, b), r in correlation.items():
        i, j = drawn.index(a), drawn.index(b)
        matrix[i, j] = matrix[j, i] = r
    try:
        factor = np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError:
        raise UsageError("the --correlate values are not consistent with each other (the "
                         "correlation matrix is not positive definite)") from None
    rng = np.random.Generator(np.random.PCG64(seed))
    scores = rng.standard_normal((runs, len(drawn))) @ factor.T
    out: dict[str, np.ndarray] = {}
    tables: dict[str, tuple[list[str], np.ndarray]] = {}
    for name, dist in dists.items():
        if dist.kind == "table":
            column = _table(dist.file, name, tables)
            if len(column) < runs:
                raise UsageError(f"table({dist.file}) has {len(column)} rows: give --runs "
                                 f"{len(column)} or fewer")
            out[name] = column[:runs].copy()
            continue
        # (u strictly inside (0, 1): a score beyond 38 would round Phi to 1)
        u = np.clip(ndtr(scores[:, drawn.index(name)]), 1e-300, 1 - 2 ** -53)
        out[name] = np.asarray(dist.quantile(u), dtype=float)
    return out


def table_rows(dists: dict[str, Dist]) -> int | None:
    """The rows of the shortest table the names read (None: no table): the default
    number of runs when the distributions are all tables."""
    rows = [len(_table(d.file, n, {})) for n, d in dists.items() if d.kind == "table"]
    return min(rows) if rows else None
