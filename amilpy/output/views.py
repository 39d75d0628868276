"""How a Run shows itself: `Run.plot` draws it, a notebook shows it as a table.
The output stage registers these with the result (`result.VIEWS`), so the result
needs nothing of the output stage; `amilpy.Model.run` installs them."""

from __future__ import annotations

from .. import result


def _plot(run, names, ax, label):
    from .plot import plot_run

    return plot_run(run, names, ax, label)


def _html(run) -> str:
    from .notebook import run_html

    return run_html(run)


def install() -> None:
    """Register the views (once is enough; again changes nothing)."""
    result.VIEWS.setdefault("plot", _plot)
    result.VIEWS.setdefault("html", _html)
