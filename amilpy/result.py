"""What a run produces: sampled variables, events, RANGE, status.

A `Run` is plain data (numpy arrays and lists); printing and plotting read it,
nothing here computes dynamics.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np


class Status(str, Enum):
    """How a run ended; the value is what a user reads."""

    FINISHED = "finished"  # reached FINTIM
    STOPPED = "stopped"  # a FINISH condition or TERMT halted it
    FAILED = "failed"  # integration failed; what was computed is kept

    def __str__(self) -> str:
        return self.value


class EventKind(str, Enum):
    """What happened at an event; the value is the word a printout may use."""

    SWITCH = "switch"  # a sign surface changed branch
    LEVEL = "level"  # QNTZR moved to another level
    SLIDE = "slide"  # a surface began to slide (both branches push it to zero)
    FINISH = "finish"  # a FINISH condition was met
    TERMT = "termt"  # a TERMT condition turned true
    BREAKPOINT = "breakpoint"  # a switch on TIME alone, at an instant known in advance

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class Event:
    """A switching instant: `old` -> `new` branch of one surface at `time`.

    `switch` describes the switch for a reader (function, where it stands);
    `text` is the surface's expression as the listing writes it (e.g. "W1",
    "TIME - T1"), so a printout can say "W1 > 0 -> W1 < 0".
    """

    time: float
    switch: str
    surface: int
    old: float
    new: float
    kind: EventKind = EventKind.SWITCH
    text: str = ""

    def describe_branch(self, mode: float) -> str:
        if self.kind == EventKind.LEVEL:
            return f"level {mode:g}"
        return {-1.0: "X<0", 0.0: "X=0", 1.0: "X>0", 0.5: "sliding"}.get(mode, f"{mode:g}")

    def __str__(self) -> str:
        return (f"TIME = {self.time:.9g}: {self.switch}: {self.describe_branch(self.old)} -> "
                f"{self.describe_branch(self.new)}")


@dataclass
class Table:
    """Values of some variables on a time grid (the printout, or PREPARE)."""

    t: np.ndarray
    columns: dict[str, np.ndarray]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name.upper()]


@dataclass
class Run:
    label: str
    params: dict[str, float]
    constants: dict[str, float]
    times: np.ndarray  # every recorded instant (union of output grids)
    values: dict[str, np.ndarray]  # name -> values at `times`
    outdel_mask: np.ndarray
    prdel_mask: np.ndarray
    events: list[Event]
    status: Status
    message: str
    final: dict[str, float]
    stats: dict[str, float]
    method: str
    rtol: float
    atol: float
    titles: list[str] = field(default_factory=list)
    reports: list = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    t_end: float = 0.0
    final_state: dict = field(default_factory=dict)  # for continuing a run (sweeps)
    advice: str | None = None  # a note on the method (see advice.py)
    # what the route ran with, for the printout header: "RELERR 1e-06, ABSERR 1e-09"
    # for a variable-step route, "DELT 0.000625" for a fixed-step one
    settings: str = ""
    terminal: dict[str, float] = field(default_factory=dict)  # TERMINAL values, written order

    @property
    def t(self) -> np.ndarray:
        """The OUTDEL grid (with 0, FINTIM and the stop instant)."""
        return self.times[self.outdel_mask]

    def __getitem__(self, name: str) -> np.ndarray:
        key = name.upper()
        if key == "TIME":
            return self.t
        if key in self.values:
            return self.values[key][self.outdel_mask]
        if key in self.constants:
            return np.full(self.t.shape, self.constants[key])
        raise KeyError(f"{name} is not a variable of this run")

    def __contains__(self, name: str) -> bool:
        key = name.upper()
        return key in self.values or key in self.constants or key == "TIME"

    @property
    def printout(self) -> Table:
        """The PRDEL-grid table of every recorded variable."""
        mask = self.prdel_mask
        return Table(self.times[mask], {k: v[mask] for k, v in self.values.items()})

    @property
    def range(self) -> dict[str, tuple[float, float, float, float]]:
        """name -> (min, time of min, max, time of max) over the recorded instants."""
        out = {}
        for name, v in self.values.items():
            if v.size == 0 or not np.any(np.isfinite(v)):
                out[name] = (np.nan, np.nan, np.nan, np.nan)
                continue
            i, j = int(np.nanargmin(v)), int(np.nanargmax(v))
            out[name] = (float(v[i]), float(self.times[i]), float(v[j]), float(self.times[j]))
        return out

    @property
    def ok(self) -> bool:
        return self.status != Status.FAILED

    def sample(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """All recorded instants and values of one variable."""
        return self.times, self.values[name.upper()]

    def __repr__(self) -> str:
        return (f"<Run {self.label!r}: {self.status}, {len(self.times)} rows, "
                f"{len(self.events)} events>")

    # ------------------------------------------------------------- notebooks
    def to_pandas(self):
        """The OUTDEL-grid values as a pandas DataFrame indexed by TIME (pandas is
        optional: `pip install pandas`)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Run.to_pandas needs pandas: pip install pandas") from None
        frame = pd.DataFrame({n: self[n] for n in self.values if "#" not in n},
                             index=pd.Index(self.t, name="TIME"))
        frame.attrs.update(label=self.label, status=str(self.status), message=self.message)
        return frame

    def plot(self, *names: str, ax=None):
        """Plot variables against TIME (all recorded ones if none are named);
        returns the matplotlib axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 4))
        for name in names or [n for n in self.values if "#" not in n]:
            ax.plot(self.t, self[name], label=name.upper())
        ax.set_xlabel("TIME")
        ax.set_title(self.titles[0] if self.titles else self.label)
        ax.grid(True, alpha=0.3)
        ax.legend()
        return ax

    def _repr_html_(self) -> str:
        from html import escape

        names = [n for n in self.values if "#" not in n][:8]
        table = self.printout
        rows = list(range(len(table.t)))
        if len(rows) > 12:
            rows = rows[:6] + [-1] + rows[-5:]
        head = "".join(f"<th>{escape(n)}</th>" for n in ["TIME", *names])
        body = []
        for i in rows:
            if i == -1:
                body.append(f"<tr><td colspan='{len(names) + 1}'>&hellip;</td></tr>")
                continue
            cells = [table.t[i]] + [table.columns[n][i] for n in names]
            body.append("<tr>" + "".join(f"<td>{v:.6g}</td>" for v in cells) + "</tr>")
        colour = {"finished": "green", "stopped": "teal", "failed": "red"}[str(self.status)]
        title = escape(self.titles[0]) + "<br>" if self.titles else ""
        events = f", {len(self.events)} events" if self.events else ""
        note = f"<br><i>{escape(self.message)}</i>" if self.message else ""
        return (f"<div><b>{title}{escape(self.label)}</b> &mdash; "
                f"<span style='color:{colour}'>{self.status}</span>, METHOD {self.method}, "
                f"{self.stats.get('nsteps', 0)} steps{events}{note}"
                f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody>"
                f"</table></div>")
