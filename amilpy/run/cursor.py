"""What the run loop hands between its parts: where the integration stands
(`Cursor`), a stop with its outcome (`Stop`), a paused segment, and what the watch
found in one step."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..outcome import Failure
from ..steppers import Stepper

# (ta, tb, dense output, modes, memory) of every accepted step, for analyses
Observer = Callable[[float, float, Callable, list, list], None]


class Stop(Exception):
    """The run ends here, for `kind`, with the data its message needs."""

    def __init__(self, kind: Failure, t: float, **fields: object) -> None:
        super().__init__(kind.value)
        self.kind = kind
        self.t = t
        self.fields = fields


@dataclass
class Cursor:
    """Where the integration stands. `m` is shared with the segment's vector field
    (a silent switch changes it in place)."""

    t: float
    y: np.ndarray
    m: list[float]
    z: list[float]


@dataclass
class Paused:
    """A chunked segment stopped at an instant that may change nothing it reads (an
    ACSL CINT instant or event): what is needed to go on with it (`_resume`)."""

    stepper: Stepper
    f: Callable
    seg_end: float
    seg_start: float
    cur: Cursor
    t: float
    y: np.ndarray
    modes: tuple
    read: tuple  # the memory slots the derivatives read, as they were
    rec: object


@dataclass
class WatchedStep:
    """What the watch found in one accepted step."""

    tb: float
    yb: np.ndarray
    triggered: set[int]  # located at zero at tb
    departed: set[int]  # left a zero it sat on
    exits: dict[int, float]  # sliding surfaces leaving, to which branch (`slide_exits`)
    truncated: bool
    e_b: list[float]  # the watched surfaces at tb
    # hits whose branch changes no derivative (cut only for a surface that reads them)
    quiet: set[int] = field(default_factory=set)
    # surfaces that crossed silently in the step (their mode follows the sign, no
    # event): the rows inside the step take each one's sign where the row is
    silent: list[int] = field(default_factory=list)
