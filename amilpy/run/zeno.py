"""Events that accumulate (Zeno behaviour): a ball bouncing with restitution e < 1
bounces infinitely often before a finite TIME, each flight e times the one before.
No integrator can step past that instant as the model is written: sooner or later
a flight is shorter than the tolerance sees, the crossing is missed, and the ball
falls through the floor (every route did, at its own bounce). What follows the
accumulation point is then not the model's motion, and the run says so instead of
printing it.

`accumulation` finds a run's last events of one kind whose intervals shrink by a
steady ratio, and where they would add up to; `cut` ends the run there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..result import Event, EventKind, Events, Run

STREAK = 6  # successive intervals that shrink by the same ratio
RATIO = (0.05, 0.95)  # what "shrink" is
STEADY = 1.3  # the largest and smallest ratio of the streak differ by at most this factor
SAME = 1e-9  # events closer than this (relative to TIME) count as one
LOOK_BACK = 8  # events at the end a streak may stop short of


@dataclass(frozen=True)
class Accumulation:
    """Where the events of `what` would add up to, each interval `ratio` times the
    one before; `last`, the last of them the run met."""

    t: float
    what: str
    ratio: float
    last: float


def accumulation(events: list[Event], t_end: float) -> Accumulation | None:
    """The accumulation point of the events of one kind that the run went past
    (TIME reached `t_end` beyond it with none of those events after their last),
    or None. Events at one instant count once; a surface that begins to slide
    there (the motion goes on along it, as Filippov's) is no accumulation."""
    if any(e.kind is EventKind.SLIDE for e in events):
        return None
    kinds: dict[str, list[float]] = {}
    for e in events:
        times = kinds.setdefault(e.switch, [])
        if not times or e.time > times[-1] + SAME * abs(e.time):
            times.append(e.time)
    for what, times in kinds.items():
        # (the last few, resolved down to the spacing of the floats, lose the ratio:
        # the streak may end a few events before the last)
        for end in range(len(times), max(STREAK + 1, len(times) - LOOK_BACK) - 1, -1):
            d = np.diff(times[end - STREAK - 1:end])
            if not (d > 0).all():
                continue
            r = d[1:] / d[:-1]
            if not ((r > RATIO[0]) & (r < RATIO[1])).all() or r.max() > STEADY * r.min():
                continue
            ratio = float(np.mean(r[-3:]))
            limit = times[end - 1] + float(d[-1]) * ratio / (1.0 - ratio)
            if times[-1] <= limit + SAME * abs(limit) + float(d[-1]) and \
                    t_end > limit + float(d[-1]):
                return Accumulation(limit, what, ratio, times[-1])
            break
    return None


def cut(run: Run, at: float) -> None:
    """End the run at TIME `at`: its rows and events after it left out."""
    keep = run.times <= at
    if len(keep) and not keep.all():
        keep_last = np.flatnonzero(keep)
        run.times = run.times[keep]
        run.values = {n: v[keep] for n, v in run.values.items()}
        run.outdel_mask, run.prdel_mask = run.outdel_mask[keep], run.prdel_mask[keep]
        if len(keep_last):  # (the last row kept is shown, as a stop instant is)
            run.outdel_mask[-1] = run.prdel_mask[-1] = True
        run.final.update({n: float(v[-1]) for n, v in run.values.items() if len(v)})
    run.events = Events(e for e in run.events if e.time <= at)
    run.extrema = {n: x for n, x in run.extrema.items() if x[1] <= at and x[3] <= at}
    run.t_end = at
