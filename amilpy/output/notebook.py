"""A Run in a notebook: its status and the head and tail of its printout table."""

from __future__ import annotations

from html import escape

from ..result import Run
from . import tables as T

HEAD, TAIL, COLUMNS = 6, 5, 8


def run_html(run: Run) -> str:
    names = [n for n in run.values if "#" not in n][:COLUMNS]
    table = T.printout_table(run, names)
    n = len(table)
    rows = list(range(n)) if n <= HEAD + TAIL + 1 else [*range(HEAD), -1,
                                                        *range(n - TAIL, n)]
    head = "".join(f"<th>{escape(c.name)}</th>" for c in table.columns)
    body = []
    for i in rows:
        if i == -1:
            body.append(f"<tr><td colspan='{len(table.columns)}'>&hellip;</td></tr>")
            continue
        cells = [T.cell("g", c.values[i:i + 1][0]) for c in table.columns]
        body.append("<tr>" + "".join(f"<td>{v}</td>" for v in cells) + "</tr>")
    colour = {"finished": "green", "stopped": "teal", "failed": "red"}[str(run.status)]
    title = escape(run.titles[0]) + "<br>" if run.titles else ""
    events = f", {len(run.events)} events" if run.events else ""
    note = f"<br><i>{escape(run.message)}</i>" if run.message else ""
    return (f"<div><b>{title}{escape(run.label)}</b> &mdash; "
            f"<span style='color:{colour}'>{run.status}</span>, METHOD {run.method}, "
            f"{run.stats.get('nsteps', 0)} steps{events}{note}"
            f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody>"
            f"</table></div>")
