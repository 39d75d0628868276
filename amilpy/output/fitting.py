"""A fit (`analysis.fit.Fit`) as text and as CSV rows."""

from __future__ import annotations

from collections.abc import Iterator

from . import tables as T


def fit_text(fit, model=None) -> str:
    lines = [f"FIT  ({fit.weights} weights, {fit.n} observations, {len(fit.names)} value(s), "
             f"{fit.runs} evaluations of the runs)", ""]
    head = ("NAME", "START", "ESTIMATE", "SE", "LOWER 95%", "UPPER 95%")
    table = T.Table("fit", [T.Column(head[0], fit.names, "s", left=True)] + [
        T.Column(h, v) for h, v in zip(head[1:], (fit.start, fit.estimates, fit.se,
                                                    fit.lower, fit.upper), strict=True)])
    for header, rows in T.text_blocks(table):
        lines += [header, *rows]
    lines.append(f"(95 % intervals: estimate +- {fit.quantile:.4g} SE, {fit.quantile_of})")
    if fit.log:
        lines.append(f"(on a log scale: {', '.join(fit.log)}: the interval is exp(log "
                     "estimate +- q x the SE of the log); the SE shown is the value's, by "
                     "the delta method)")
    if len(fit.names) > 1:
        lines += ["", "CORRELATION", " " * 12 + "".join(n[:10].rjust(11) for n in fit.names)]
        for name, row in zip(fit.names, fit.correlation, strict=True):
            lines.append(name[:12].ljust(12) + "".join(f"{x:11.4f}" for x in row))
    lines += ["", "RESIDUALS AT THE ESTIMATES"]
    summary = ("VARIABLE", "N", "RMS RESIDUAL", "MAX |RESIDUAL|")
    for k, run in enumerate(fit.fitted, start=1):
        table = T.residual_table(run, summary)
        if table is None:
            continue
        if len(fit.fitted) > 1:
            lines.append(f"run {k}")
        for header, rows in T.text_blocks(table):
            lines += [header, *rows]
    lines += ["", f"weighted sum of squares {2 * fit.cost:.6g}; stopped: {fit.message}",
              f"Jacobian: {fit.gradients}" + (f", {fit.jacobians} of them" if fit.jacobians
                                               else "")]
    lines += [f"NOTE: {n}" for n in fit.notes]
    return "\n".join(lines) + "\n"


def fit_csv(fit) -> tuple[list[str], Iterator[list]]:
    header = ["NAME", "START", "ESTIMATE", "SE", "LOWER95", "UPPER95"]
    return header, iter([[n, s, e, se, lo, hi] for n, s, e, se, lo, hi in zip(
        fit.names, fit.start, fit.estimates, fit.se, fit.lower, fit.upper, strict=True)])
