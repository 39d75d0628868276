"""Sliders in a notebook: `amilpy.interact("model.amil")`.

A slider per PARAM value (or per data value named), its range from the value's
`!` comment (`! [rad/s] forcing frequency, 60 to 80`) or else half the value
either way; moving one runs the listing again with the new values and redraws
its figures (the ones `--plot` draws, one per OUTPUT statement). A PARAM value is
an argument of the compiled code, so a new value costs one run, no compilation.
"Freeze" keeps the curves drawn so far beside the live ones, a colour each and
named by the values that differ from the listing's, to compare; "Clear" drops
them.

The figures are drawn by `plot.draw` without pyplot and shown as PNG images, so
the widget works with any matplotlib backend and in a notebook saved with its
outputs. ipywidgets is an optional extra: `pip install 'amilpy[widgets]'`.
"""

from __future__ import annotations

import io
import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from html import escape

from ..diagnostics import AmilError, UsageError
from ..result import Run
from . import words as W
from .plot import draw, figure_specs

STEPS = 200  # slider positions across its range
SPREAD = 0.5  # with no range in the comment: the value +- half of it
DPI = 90  # the figures' resolution on screen

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?"
# "60 to 80", "60..80", "60 do 80" (Polish), "60 – 80" (an en dash; a hyphen would
# read as a minus sign)
_RANGE = re.compile(rf"(?<![\w.])({_NUMBER})\s*(?:\.\.|…|–|\bto\b|\bdo\b)\s*({_NUMBER})")


@dataclass(frozen=True)
class SliderSpec:
    name: str
    value: float
    low: float
    high: float
    unit: str
    text: str  # the comment's description


def comment_range(text: str) -> tuple[float, float] | None:
    """The range a value's comment gives ("60 to 80", "60..80"), else None."""
    m = _RANGE.search(text)
    if not m:
        return None
    low, high = (float(g.replace("d", "e").replace("D", "e")) for g in m.groups())
    return (low, high) if low < high else None


def slider_specs(model, names: Sequence[str] | None = None) -> list[SliderSpec]:
    """A slider per PARAM value of `model` (an api.Model), or per data value named."""
    ir = model.ir
    data = ir.runs[0].data
    if names is None:
        names = [n for n in ir.data_names if ir.data_kinds.get(n) == "PARAM"]
        if not names:
            raise UsageError("the listing has no PARAM value to give a slider; name the "
                             "data values: amilpy.interact(model, names=['K', ...])")
    else:
        names = model.known_names(names, data=True)
        missing = [n for n in names if n not in data]
        if missing:
            raise UsageError(f"{missing[0]} is a variable, not a data value: a slider "
                             "sets a PARAM, CONST or INCON value")
    notes = W.name_notes(ir)
    out = []
    for name in names:
        value = float(data[name])
        unit, text = notes.get(name, ("", ""))
        span = comment_range(text)
        if span is None or not span[0] <= value <= span[1]:
            span = _around(value)
        out.append(SliderSpec(name, value, span[0], span[1], unit, text))
    return out


def _around(value: float) -> tuple[float, float]:
    if value == 0.0 or not math.isfinite(value):
        return (0.0, 1.0)
    a, b = value * (1 - SPREAD), value * (1 + SPREAD)
    return (min(a, b), max(a, b))


class Sliders:
    """The widget `interact` returns: display it (the last line of a cell does).

    `sliders` (name -> ipywidgets.FloatSlider), `images` (one per figure),
    `status` (what the last run did), `runs` (the live runs) and `frozen`
    ((label, runs) kept by `freeze`) are there to read; `update(**values)` sets
    values and runs once, as moving the sliders does."""

    def __init__(self, model, names: Sequence[str] | None = None, method: str | None = None,
                 fintim: float | None = None, **fixed: float) -> None:
        try:
            import ipywidgets as widgets
        except ImportError:
            raise UsageError("the sliders need ipywidgets: pip install 'amilpy[widgets]' "
                             "(or pip install ipywidgets)") from None
        self.model = model
        self.method = method
        self.fintim = fintim
        self.fixed = {k.upper(): float(v) for k, v in fixed.items()}
        self.specs = slider_specs(model, names)
        self.notes = W.name_notes(model.ir)
        self.runs: list[Run] = []
        self.frozen: list[tuple[str, list[Run]]] = []
        self.runs_done = 0
        self._holding = False
        self.sliders = {}
        rows = []
        for s in self.specs:
            slider = widgets.FloatSlider(
                value=s.value, min=s.low, max=s.high, step=(s.high - s.low) / STEPS,
                description=s.name, readout_format=".4g", continuous_update=False,
                style={"description_width": "initial"},
                layout=widgets.Layout(width="480px"))
            slider.observe(self._moved, names="value")
            self.sliders[s.name] = slider
            rows.append(widgets.HBox([slider, widgets.Label(
                " ".join(x for x in (f"[{s.unit}]" if s.unit else "", s.text) if x))]))
        freeze = widgets.Button(description="Freeze", tooltip="keep these curves to compare")
        clear = widgets.Button(description="Clear", tooltip="drop the frozen curves")
        freeze.on_click(lambda _: self.freeze())
        clear.on_click(lambda _: self.clear())
        self.status = widgets.HTML()
        self.images: list = []  # (made by the first drawing: one per figure)
        self._controls = [*rows, widgets.HBox([freeze, clear]), self.status]
        self.widget = widgets.VBox(self._controls)
        self._run(first=True)

    # -------------------------------------------------------------- actions

    def values(self) -> dict[str, float]:
        """The data values the sliders stand at."""
        return {name: float(s.value) for name, s in self.sliders.items()}

    def update(self, **values: float) -> list[Run]:
        """Move the named sliders to `values` and run once."""
        unknown = [k for k in values if k.upper() not in self.sliders]
        if unknown:
            raise UsageError(f"no slider for {unknown[0]}; the sliders are "
                             f"{', '.join(self.sliders)}")
        self._holding = True
        try:
            for k, v in values.items():
                self.sliders[k.upper()].value = float(v)
        finally:
            self._holding = False
        return self._run()

    def freeze(self) -> None:
        """Keep the live curves drawn, labelled by the values they were run with."""
        if self.runs:
            self.frozen.append((self._described(), self.runs))
            self._draw()

    def clear(self) -> None:
        self.frozen.clear()
        self._draw()

    def _described(self) -> str:
        """The slider values that differ from the listing's ("W = 75"), or "as
        written"."""
        moved = [f"{s.name} = {self.sliders[s.name].value:.4g}" for s in self.specs
                 if self.sliders[s.name].value != s.value]
        return ", ".join(moved) or "as written"

    def _moved(self, _change) -> None:
        if not self._holding:
            self._run()

    # ---------------------------------------------------------- run and draw

    def _run(self, first: bool = False) -> list[Run]:
        start = time.perf_counter()
        try:
            runs = self.model.run(method=self.method, fintim=self.fintim, advice=False,
                                  **{**self.fixed, **self.values()})
        except AmilError as exc:  # (a value the listing refuses: say so, keep the figures)
            if first:  # (the call's own arguments: its caller hears of it)
                raise
            self.status.value = f"<span style='color:red'>{escape(exc.text())}</span>"
            return self.runs
        self.runs_done += 1
        self.runs = runs
        took = time.perf_counter() - start
        failed = [r for r in runs if not r.ok]
        note = "; ".join(f"{r.label}: {r.message}" for r in failed)
        self.status.value = (f"{len(runs)} run(s) in {took:.2g} s" if not failed else
                             f"<span style='color:red'>{escape(note)}</span> (drawn up to "
                             "where it stopped)")
        self._draw()
        return runs

    def _draw(self) -> None:
        if not self.runs:
            return
        specs = figure_specs(self.runs[0])
        if len(self.images) != len(specs):
            import ipywidgets as widgets

            self.images = [widgets.Image(format="png") for _ in specs]
            self.widget.children = (*self._controls, *self.images)
        runs, labels = list(self.runs), _labels(f"now: {self._described()}", self.runs)
        for label, frozen in self.frozen:
            runs += frozen
            labels += _labels(label, frozen)
        for image, spec in zip(self.images, specs, strict=True):
            fig = draw(runs, spec, labels, self.notes)
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=DPI)
            image.value = buf.getvalue()

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)


def _labels(prefix: str, runs: Sequence[Run]) -> list[str]:
    if len(runs) == 1:
        return [prefix]
    return [f"{prefix}; {label}" for label in W.run_labels(runs)]


def interact(model, names: Sequence[str] | None = None, method: str | None = None,
             fintim: float | None = None, **fixed: float) -> Sliders:
    """Sliders for a listing in a Jupyter notebook: `amilpy.interact("model.amil")`.

    `model`: a path or an `amilpy.Model`; `names`: the data values that get a
    slider (default: every PARAM value); `method` and `fintim`: as in `Model.run`;
    other keywords set data values for every run, as `Model.run` takes them."""
    from ..api import Model, load

    if not isinstance(model, Model):
        model = load(model)
    return Sliders(model, names, method, fintim, **fixed)
