"""What a command hands its writers and renderers: the CSV dialects, the plot
options, the outputs of a run or an analysis. Plain data, standard library only
(the command line builds its options from them before it knows whether it will
need numpy), so every renderer reads them here and none imports another's module
for them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..result import Run


@dataclass(frozen=True)
class Dialect:
    delimiter: str
    decimal: str
    newline: str
    encoding: str
    help: str


# `excel-pl`: what a spreadsheet set to a Polish (or German, French...) locale
# reads as columns: `;` between fields and a decimal comma; the BOM tells it UTF-8.
DIALECTS: dict[str, Dialect] = {
    "plain": Dialect(",", ".", "\n", "utf-8", "comma-separated, decimal point (default)"),
    "excel-pl": Dialect(";", ",", "\r\n", "utf-8-sig",
                        "semicolons and a decimal comma, for a spreadsheet in a Polish locale"),
}


@dataclass(frozen=True)
class PlotOptions:
    """How figures are drawn (the command line's plot options)."""

    start: float | None = None  # --from: the window's first TIME
    stop: float | None = None  # --to
    zoom_events: bool = False  # a figure around the first switching event too
    subplots: bool = False  # one axis per variable whatever the scales
    runs: tuple[int, ...] | None = None  # run numbers (1-based) to draw; None: all
    show: bool = False  # open windows after saving
    formats: tuple[str, ...] = ("png",)  # --format: the files each figure is saved as
    height: float = 4.8  # inches, a figure with one axis (8 wide)


@dataclass
class Outputs:
    """What a command hands its writers."""

    command: str  # "run", "sweep", "modes", "periodic" or "response"
    stem: str  # the listing's file name without .amil
    out_dir: str  # --out, else the listing's folder
    runs: list[Run] = field(default_factory=list)
    sweep: object = None  # a sweep.Sweep
    analysis: object = None  # analysis.Modes, Orbit or Response
    model: object = None  # the api.Model (units, labels)
    dialect: str = "plain"  # --csv-dialect
    plot: PlotOptions = field(default_factory=PlotOptions)
    # the --csv the runs wrote as they went (output.stream.CsvStream), to be closed
    streamed: object | None = None
    names: list[str] | None = None  # --vars: the columns of --csv/--xlsx (None: the default)
