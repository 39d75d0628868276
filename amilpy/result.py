"""What a run produces: sampled variables, events, RANGE, status.

A `Run` is plain data (numpy arrays and lists); printing and plotting read it
(amilpy.output), nothing here computes dynamics or draws: `Run.plot`, the
notebook view and `str(event)` hand over to the output package.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Callable, Iterable, Iterator, MutableSequence
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from .library.surfaces import slides


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
    SCHEDULE = "schedule"  # a SCHEDULE .XP./.XN./.XZ. crossing (ACSL form)
    DISCRETE = "discrete"  # a DISCRETE section ran (ACSL form)

    def __str__(self) -> str:
        return self.value


_BRANCHES: dict[tuple[float, float], float] = {}  # every branch value events have had


def _shared(value):
    """One float object for each branch value (-0.0 apart from 0.0; others as given)."""
    if type(value) is not float or value != value or len(_BRANCHES) >= 4096:
        return value
    return _BRANCHES.setdefault((value, math.copysign(1.0, value)), value)


@dataclass(frozen=True, slots=True)  # (a long run keeps 10^5 of them: 120 bytes each)
class Event:
    """A switching instant: `old` -> `new` branch of one surface at `time`.

    `switch` describes the switch for a reader (function, where it stands);
    `text` is the surface's expression as the listing writes it (e.g. "W1",
    "TIME - T1"), so a printout can say "W1 > 0 -> W1 < 0"; `level`: the surface is
    a level surface (QNTZR, NINT, AINT, AMOD), its branches levels k and a slide on it
    the edge k + 1/2 between two.
    """

    time: float
    switch: str
    surface: int
    old: float
    new: float
    kind: EventKind = EventKind.SWITCH
    text: str = ""
    level: bool = False

    def __post_init__(self) -> None:
        # (the branches are a few values: one float object each, not two an event)
        object.__setattr__(self, "old", _shared(self.old))
        object.__setattr__(self, "new", _shared(self.new))

    def describe_branch(self, mode: float) -> str:
        """A branch in the listing's own terms: "W1 > 0", "W1 held at 0", "level 3"."""
        if self.level or self.kind == EventKind.LEVEL:
            if slides(mode):
                return f"on the edge between levels {mode - 0.5:g} and {mode + 0.5:g}"
            return f"level {mode:g}"
        x = self.text or "argument"
        if mode in (-1.0, 0.0, 1.0):
            return f"{x} {'<=>'[int(mode) + 1]} 0"
        return f"{x} held at 0"  # sliding: neither sign, the surface is kept at zero

    def change(self) -> str:
        """What changed, for a reader: "W1 > 0 -> W1 < 0", "reached", "ran"."""
        if self.kind == EventKind.SLIDE:
            if self.level:
                return f"{self.text or 'its argument'} stays at {self.new:g}, " \
                    f"{self.describe_branch(self.new)}: both push it back"
            return f"{self.text or 'its argument'} stays at 0: both sides push it back"
        if self.kind in (EventKind.FINISH, EventKind.TERMT):  # the condition that stops it
            return "reached"
        if self.kind == EventKind.SCHEDULE:  # a crossing that runs a DISCRETE section
            return f"{self.text or 'its expression'} crossed zero"
        if self.kind == EventKind.DISCRETE:
            return "ran"
        return f"{self.describe_branch(self.old)} -> {self.describe_branch(self.new)}"

    def __str__(self) -> str:
        """The instant, the switch as written and what changed."""
        return f"TIME = {self.time:.9g}: {self.switch}: {self.change()}"


class Events(MutableSequence):
    """A run's events in order, as a list of `Event`s reads; held as two columns,
    the instant (8 bytes) and which change it is (4 bytes: a long run's hundreds of
    thousands of events are a few kinds of change, each switch of each surface), an
    `Event` made each time one is read. (As Event objects a long run's 445,634 took
    53 MB.)"""

    __slots__ = ("_t", "_k", "_kinds", "_index")

    def __init__(self, events: Iterable[Event] = ()) -> None:
        self._t, self._k = array("d"), array("i")
        self._kinds: list[tuple] = []  # (switch, surface, old, new, kind, text, level)
        self._index: dict[tuple, int] = {}
        for e in events:
            self.append(e)

    def _kind(self, e: Event) -> int:
        kind = (e.switch, e.surface, e.old, e.new, e.kind, e.text, e.level)
        # (-0.0 and 0.0 are two branches: the sign is part of the key)
        key = kind + (math.copysign(1.0, e.old), math.copysign(1.0, e.new))
        k = self._index.get(key)
        if k is None:
            k = self._index[key] = len(self._kinds)
            self._kinds.append(kind)
        return k

    def _event(self, i: int) -> Event:
        return Event(self._t[i], *self._kinds[self._k[i]])

    def __len__(self) -> int:
        return len(self._t)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self._event(j) for j in range(*i.indices(len(self._t)))]
        n = len(self._t)
        if not -n <= i < n:
            raise IndexError("event index out of range")
        return self._event(i if i >= 0 else i + n)

    def __setitem__(self, i, e) -> None:
        if isinstance(i, slice):  # (as a list does: the events in the slice replaced)
            events = list(self)
            events[i] = e
            self._t, self._k = array("d"), array("i")
            self.extend(events)
            return
        self._t[i], self._k[i] = e.time, self._kind(e)

    def __delitem__(self, i) -> None:
        del self._t[i], self._k[i]

    def insert(self, i: int, e: Event) -> None:
        self._t.insert(i, e.time)
        self._k.insert(i, self._kind(e))

    def append(self, e: Event) -> None:
        self._t.append(e.time)
        self._k.append(self._kind(e))

    def remove(self, e: Event) -> None:
        """The last event equal to e goes (the one removed is a recent one)."""
        for i in range(len(self._t) - 1, -1, -1):
            if self._t[i] == e.time and self._event(i) == e:
                del self[i]
                return
        raise ValueError("Events.remove(e): e is not among them")

    def clear(self) -> None:
        del self._t[:], self._k[:]

    def __iter__(self) -> Iterator[Event]:
        kinds = self._kinds
        for t, k in zip(self._t, self._k, strict=True):
            yield Event(t, *kinds[k])

    def __reversed__(self) -> Iterator[Event]:
        for i in range(len(self._t) - 1, -1, -1):
            yield self._event(i)

    def __eq__(self, other) -> bool:
        if isinstance(other, (Events, list)):  # (as a list: never equal to a tuple)
            return len(self) == len(other) and \
                all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    # what a list of events did before: + and * give lists, copy() and sort() as a list's
    def __add__(self, other) -> list[Event]:
        return list(self) + list(other)

    def __radd__(self, other) -> list[Event]:
        return list(other) + list(self)

    def __mul__(self, n: int) -> list[Event]:
        return list(self) * n

    __rmul__ = __mul__

    def copy(self) -> Events:
        return Events(self)

    def sort(self, *, key=None, reverse: bool = False) -> None:
        self[:] = sorted(self, key=key, reverse=reverse)

    def __repr__(self) -> str:
        return f"Events({list(self)!r})"

    def __reduce__(self):
        return Events, (list(self),)


@dataclass
class Table:
    """Values of some variables on a time grid (the printout, or PREPARE)."""

    t: np.ndarray
    columns: dict[str, np.ndarray]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name.upper()]


@dataclass
class Compared:
    """One variable's observations (`--data`) against a run's values at their
    instants; residual = observed - simulated."""

    name: str
    t: np.ndarray
    observed: np.ndarray
    simulated: np.ndarray
    sd: np.ndarray | None  # the file's SD_<NAME>, if given
    source: str  # the data file
    unreached: int = 0  # observations past a failed run's end, left out

    @property
    def residual(self) -> np.ndarray:
        return self.observed - self.simulated

    @property
    def rms(self) -> float:
        r = self.residual
        return float(np.sqrt(np.mean(r * r))) if r.size else math.nan

    @property
    def largest(self) -> float:
        """The largest |residual|."""
        return float(np.max(np.abs(self.residual))) if self.residual.size else math.nan


@dataclass
class Run:
    label: str
    params: dict[str, float]
    constants: dict[str, float]
    times: np.ndarray  # every recorded instant (union of output grids)
    values: dict[str, np.ndarray]  # name -> values at `times`
    outdel_mask: np.ndarray
    prdel_mask: np.ndarray
    events: MutableSequence[Event]  # `Events` as a run makes them
    status: Status
    message: str
    final: dict[str, float]
    stats: dict[str, float]
    method: str
    rtol: float  # RELERR for every state not named in a per-state RELERR
    atol: float  # likewise ABSERR
    titles: list[str] = field(default_factory=list)
    reports: list = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    t_end: float = 0.0
    final_state: dict = field(default_factory=dict)  # for continuing a run (sweeps)
    advice: str | None = None  # a note on the method (see run/advice.py)
    # what the route ran with, for the printout header: "RELERR 1e-06, ABSERR 1e-09"
    # for a variable-step route, "DELT 0.000625" for a fixed-step one
    settings: str = ""
    terminal: dict[str, float] = field(default_factory=dict)  # TERMINAL values, written order
    # name -> (min, time of min, max, time of max) located on the integrator's dense
    # output (the RANGE variables; see run.record.Extrema)
    extrema: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    observed: list[Compared] = field(default_factory=list)  # --data, per variable

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
        """name -> (min, time of min, max, time of max): located between the output
        instants for the RANGE variables, over the recorded instants for the others."""
        out = {}
        for name, v in self.values.items():
            if name in self.extrema:
                out[name] = self.extrema[name]
            elif v.size == 0 or not np.any(np.isfinite(v)):
                out[name] = (np.nan, np.nan, np.nan, np.nan)
            else:
                i, j = int(np.nanargmin(v)), int(np.nanargmax(v))
                out[name] = (float(v[i]), float(self.times[i]), float(v[j]),
                             float(self.times[j]))
        return out

    @property
    def ok(self) -> bool:
        return self.status != Status.FAILED

    def sample(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Every recorded instant and one variable's values there: the OUTDEL grid and
        the rows between (a crossing's instant, a PRDEL row, an observation's), as a
        figure draws them."""
        key = name.upper()
        if key == "TIME":
            return self.times, self.times
        if key in self.values:
            return self.times, self.values[key]
        if key in self.constants:
            return self.times, np.full(self.times.shape, self.constants[key])
        raise KeyError(f"{name} is not a variable of this run")

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

    def plot(self, *names: str, ax=None, label: str | None = None):
        """Plot variables against TIME (all recorded ones if none are named) on `ax`;
        returns the matplotlib axes. For several runs on one axes, use
        `amilpy.output.plot.draw_runs(runs, *names)`, which labels each run by the
        values that tell it from the others."""
        return _view("plot")(self, names, ax, label)

    def _repr_html_(self) -> str | None:
        view = VIEWS.get("html")
        return view(self) if view is not None else None  # (None: the plain repr)


# How a Run shows itself -- a figure, a table in a notebook -- is the output stage's
# business: `amilpy.output.views` puts its functions here (the API does, before its
# first run), so this module imports nothing of the stages after it.
VIEWS: dict[str, Callable] = {}


def _view(name: str) -> Callable:
    if name not in VIEWS:
        raise RuntimeError(f"Run.{name} is drawn by amilpy.output: call "
                           "amilpy.output.views.install() first (amilpy.Model.run does)")
    return VIEWS[name]
