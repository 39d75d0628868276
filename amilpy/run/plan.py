"""The run plan: everything a run decides before its first step, as plain data.

`make_plan` reads the run spec, the options and the generated functions once and
gives a `RunPlan`: the route, the TIMER values, per-state tolerances
(`Tolerances`), the output grid, the watched surfaces with their bookkeeping,
and the breakpoints (roots of surfaces affine in TIME, IMPULS instants). The
loop reads the plan and never the spec or the options' raw values.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .. import ir
from ..codegen import ModelCode
from ..diagnostics import AmilError, Diagnostic
from ..language import START_KEY
from ..library.surfaces import linear_gradient, sign, slides
from ..result import Event, EventKind
from ..routes import DEFAULT, Route, StepPointError, route_for, step_point_mode

# RELERR and ABSERR when a listing sets none (RELERR/ABSERR, ACSL's MERROR/XERROR):
# tight enough that every digit of the printout (7 significant) is right. Measured
# (benchmarks/tolerances.py, results/tolerances.md): AUTO's global error runs 10 to 300
# times RELERR; at 1e-10 it is at most 2.7e-8 on the shipped models, models/examples
# and the published listings (the goal: 5e-7). The ACSL form a decade tighter, as
# Magnolia itself (MERROR 1e-11, with CVODE): its authors' published numbers are that
# exact, and an impact located on LSODA's trajectory (SCHEDULE .XN.) is then right to
# 2e-10 s. ABSERR a thousandth of RELERR: at RELERR x 1 (Magnolia's XERROR is of that
# kind) states smaller than 1e-3 are 3 to 50 times less exact.
TOLERANCES = {"csmp": (1e-10, 1e-13), "acsl": (1e-11, 1e-14)}
# A route whose own tolerance is tighter than RELERR (BDF's: a decade) gets a default
# that keeps it at this or above: SciPy's BDF gives up ("required step size is less
# than spacing between numbers") at 1e-10 and tighter on the Exercise 4 clutch, so its
# default RELERR is 1e-8
LOCAL_FLOOR = 1e-9

DEFAULTS = {
    "max_steps": 5_000_000,
    "max_events": 200_000,
    "max_rows": 2_000_000,
    # OUTDEL rows of a run that writes them to its CSV as it goes (output.stream): it
    # holds up to 2 bytes an instant of its grid (the masks: `GridTimes`), 40 MB at this
    "max_streamed_rows": 20_000_000,
    # values all the runs of one call keep (rows x variables, summed over the runs):
    # 2E8 float64 are 1.6 GB, what a laptop can spare for a printout
    "max_values": 200_000_000,
}

# The mode of a sliding surface: not a sign (-1, 0, 1) nor a level (a whole number).
# A sign surface slides in mode SLIDE; a level surface (QNTZR, NINT, AINT, AMOD) on the
# edge between its levels k and k + 1 slides in mode k + 1/2, the edge itself, which
# its generated surface reads (`library.surfaces.level_edge`): a mode half a whole
# number is a slide, whatever the surface.
SLIDE = 0.5
LOOKAHEAD = 1e-8  # a look-ahead's step, of the run's length (`RunPlan.lookahead_h`)


# (`slides`' rule over a list of modes, written out: these run at every step)
def sliding_in(m) -> bool:
    """Whether any surface in the modes m slides."""
    return 0.5 in map(_FRACTION, m)


def sliding(m) -> list[int]:
    """The surfaces that slide in the modes m."""
    return [k for k, v in enumerate(m) if v % 1.0 == 0.5]


_FRACTION = (1.0).__rmod__  # v -> v % 1.0


@dataclass
class Options:
    """How to run, from outside the listing (command line, API); None: the listing's."""

    method: str | None = None
    rtol: float | None = None  # replaces the listing's RELERR, per-state values included
    atol: float | None = None  # likewise ABSERR
    events: bool = True
    outputs: list[str] | None = None
    max_steps: int = DEFAULTS["max_steps"]
    max_events: int = DEFAULTS["max_events"]
    max_rows: int = DEFAULTS["max_rows"]
    max_time: float | None = None  # wall-clock seconds
    start: dict | None = None  # continue from a previous run's final_state
    fintim: float | None = None  # run length instead of the listing's FINTIM
    progress: Callable | None = None  # `progress.Progress`: given a Report now and then
    # variables whose minimum and maximum are located like RANGE's (a sweep's measure)
    extrema: tuple[str, ...] = ()
    settle: float = 0.0  # RANGE and `extrema` count the rows from t0 + settle on
    # step-point mode (routes.step_point_mode): True puts any fixed-step method in it,
    # False takes EULER/RECT out of it; None: the listing's, else the method's default
    step_point: bool | None = None
    seed: float | None = None  # the random streams' seed, instead of the listing's
    # folders where FST's weather files are looked for after the listing's own (§13)
    weather_dirs: tuple[str, ...] = ()
    # instants that must be rows, beside the OUTDEL and PRDEL grids (observations:
    # `amilpy.observed`); in neither grid's table
    extra_times: tuple[float, ...] = ()
    # where the rows go as the run makes them (output/stream.py's CsvStream: a long
    # run's CSV), keeping in memory only what it says; None: every row kept
    row_sink: object | None = None


# (the IR's: what a surface is for and how it selects a branch, one definition)
SurfaceKind, Purpose = ir.SurfaceKind, ir.Purpose


@dataclass(frozen=True)
class Watched:
    """A surface the run watches, with what the loop needs to know about it."""

    surface: int  # index in ir.Model.surfaces
    kind: SurfaceKind
    purpose: Purpose
    description: str  # the switch for a reader ("FSW for MFR (line 57)")
    text: str  # the surface as the listing writes it ("W1", "TIME - T1")
    gradient: np.ndarray | None  # d e/d y when the surface is linear in the states
    breakpoint_only: bool  # affine in TIME: handled as breakpoints
    direction: int = 0  # SCHEDULE: +1 .XP., -1 .XN., 0 .XZ. (either way)
    guarded: bool = False  # read by the program on some branches only (`ir.Surface.guard`)
    # a TERMT whose condition holds at zero too (T >= TSTOP: `ir.Model.closed`)
    closed: bool = False

    def stops(self, old: float, new: float) -> bool:
        """Whether entering `new` from `old` ends the run: a TERMT's condition holds
        (at zero too where it is closed), a FINISH is reached or passed."""
        if self.purpose is Purpose.TERMT:
            return new > 0 or (new == 0 and self.closed)
        if self.purpose is Purpose.FINISH:
            return new != old and (new == 0 or new * old < 0)
        return False

    def fires(self, old: float, new: float) -> bool:
        """Whether entering `new` from `old` is a crossing this SCHEDULE runs on:
        from < 0 to >= 0 (XP), from > 0 to <= 0 (XN), or either (XZ)."""
        up = old < 0 and new >= 0 and not slides(new)
        down = old > 0 and new <= 0
        return up if self.direction > 0 else down if self.direction < 0 else up or down

    def event(self, t: float, old: float, new: float, kind: EventKind | None = None) -> Event:
        """The event of entering mode `new` from `old` at t (`kind`: as `event_kind`
        says, unless given)."""
        return Event(t, self.description, self.surface, old, new,
                     self.event_kind(new) if kind is None else kind, self.text,
                     self.kind is SurfaceKind.LEVEL)

    def event_kind(self, new_mode: float) -> EventKind:
        """What entering `new_mode` on this surface is, as an event."""
        if self.purpose.stops:
            return EventKind(self.purpose.value)
        if self.breakpoint_only:
            return EventKind.BREAKPOINT
        if slides(new_mode):
            return EventKind.SLIDE
        return EventKind.LEVEL if self.kind is SurfaceKind.LEVEL else EventKind.SWITCH


# The least relative tolerance every solver takes in double precision: SciPy's
# solve_ivp raises less to 100 ulps, and LSODA refuses even that ("excess accuracy
# requested": its test wants the tolerance over 100 ulps of the state)
RTOL_FLOOR = 1000 * float(np.finfo(float).eps)


@dataclass(frozen=True)
class Tolerances:
    """RELERR and ABSERR per state, as the variable-step routes take them.

    `relerr`/`abserr` apply to every state not named; `relerr_each`/`abserr_each`
    hold the listing's per-state values that applied (states of this model only).
    An option from outside (`--rtol`, `rtol=`) replaces the listing's values,
    per-state ones included.
    """

    rtol: np.ndarray
    atol: np.ndarray
    relerr: float
    abserr: float
    relerr_each: dict[str, float] = field(default_factory=dict)
    abserr_each: dict[str, float] = field(default_factory=dict)
    # the least RELERR asked for, where it is below the floor (`floor`, used instead)
    floored: float | None = None

    @property
    def floor(self) -> float:
        return float(self.rtol.min()) if len(self.rtol) else RTOL_FLOOR

    @classmethod
    def build(cls, spec: ir.RunSpec, opts: Options, states: list[str],
              form: str = "csmp", route: Route | None = None) -> Tolerances:
        """`form`: the listing's form ("csmp" or "acsl"), whose defaults apply, as
        `route` takes them (LOCAL_FLOOR)."""
        def side(option, scalar, each, default):
            base = option or scalar or default
            named = {} if option else {n: v for n, v in each.items() if n in states}
            vector = np.array([named.get(n, base) for n in states], dtype=float)
            return base, named, vector

        rel, ab = TOLERANCES[form]
        if route is not None and route.local_tolerance < 1.0 and \
                rel * route.local_tolerance < LOCAL_FLOOR:
            scale = LOCAL_FLOOR / (rel * route.local_tolerance)
            rel, ab = rel * scale, ab * scale
        relerr, r_each, rtol = side(opts.rtol, spec.relerr, spec.relerr_each, rel)
        abserr, a_each, atol = side(opts.atol, spec.abserr, spec.abserr_each, ab)
        # (the floor is the solver's: a route that tightens RELERR for its own
        # estimator gets a floor as much higher)
        floor = RTOL_FLOOR / (route.local_tolerance if route is not None else 1.0)
        floored = float(rtol.min()) if len(rtol) and rtol.min() < floor else None
        return cls(np.maximum(rtol, floor), atol, relerr, abserr, r_each, a_each, floored)

    def describe(self) -> str:
        """For the printout header: "RELERR 1e-06 (X 0.001), ABSERR 1e-09"."""
        def one(word, base, each):
            named = ", ".join(f"{n} {v:g}" for n, v in each.items())
            return f"{word} {base:g}" + (f" ({named})" if named else "")
        return f"{one('RELERR', self.relerr, self.relerr_each)}, " \
               f"{one('ABSERR', self.abserr, self.abserr_each)}"


@dataclass(frozen=True)
class Grid:
    """The output instants (the union of the OUTDEL and PRDEL grids) and which
    grid each belongs to."""

    times: np.ndarray
    outdel: np.ndarray
    prdel: np.ndarray

    def masks(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The OUTDEL and PRDEL masks of rows at grid indices `g` (-1: a row
        between the grid's instants, an event's or the stop's, in neither), new
        arrays. (Indexed with g as it is, -1 reading the last instant's and put right
        after: no copy of g, which a run of 1E6 rows would hold twice.)"""
        if not len(g) or not len(self.times):
            return np.zeros(len(g), bool), np.zeros(len(g), bool)
        off = g < 0
        outdel, prdel = self.outdel[g], self.prdel[g]
        outdel[off] = prdel[off] = False
        return outdel, prdel


@dataclass(frozen=True)
class Reset:
    """MODINT: state `state` is held at its initial value while surface 1 is <= 0
    and surface 2 > 0 (each a watched position or a mode fixed for the run)."""

    state: int
    first: int | float  # int: a watched position; float: a constant mode
    second: int | float


@dataclass(frozen=True)
class RunPlan:
    route: Route
    method: str  # as the listing or the caller spelled it
    timer: dict[str, float]  # FINTIM, DELT, PRDEL, OUTDEL, DELMIN, DELMAX as applied
    t0: float
    fintim: float  # TIME at the end of the run
    tol: Tolerances
    grid: Grid
    watched: tuple[Watched, ...]
    watch_idx: tuple[int, ...]  # the watched positions that are not breakpoint-only
    breakpoints: tuple[float, ...]
    roots: dict[int, float]  # watched position -> its breakpoint
    resets: tuple[Reset, ...]
    chunked: bool  # AUTO drives odeint over chunks of output instants
    # a segment can stop at an instant and go on from it, its history kept (AUTO's
    # chunks, SciPy's solvers: `Stepper.stop_at`), where an ACSL instant's code or a
    # memory's update changes nothing the derivatives read
    pauses: bool
    max_step: float  # TIMER DELMAX (ACSL: MAXTERVAL), at most a hundredth of the run
    h_floor: float  # steps shorter than this make no progress
    floor_origin: str  # where h_floor comes from, for the message
    lookahead_h: float  # the step of a look-ahead (the branch the motion takes)
    events: bool  # locate events (False: comparisons only)
    step_point: bool = False  # the classic translators' loop (steppoint.py)

    @property
    def settings(self) -> str:
        """What the route ran with: tolerances or the fixed step (and its mode)."""
        if self.route.uses_tolerances:
            return self.tol.describe()
        return f"DELT {self.timer['DELT']:g}" + (", step-point mode" if self.step_point
                                                  else "")


def stored_values(spec: ir.RunSpec, columns: int, fintim: float | None = None) -> float:
    """The most values a run of `spec` keeps: its output rows (the OUTDEL and PRDEL
    grids, both ends included) times `columns`."""
    return output_rows(spec, fintim) * columns


def output_rows(spec: ir.RunSpec, fintim: float | None = None) -> float:
    """The most output rows a run of `spec` has (the OUTDEL and PRDEL grids, both
    ends included)."""
    t = timer_values(spec, fintim, max_rows=None)
    if t["OUTDEL"] == t["PRDEL"]:
        return t["FINTIM"] / t["OUTDEL"] + 1.0
    return t["FINTIM"] / t["OUTDEL"] + t["FINTIM"] / t["PRDEL"] + 2.0


def timer_values(spec: ir.RunSpec, fintim: float | None = None,
                 max_rows: int | None = DEFAULTS["max_rows"],
                 streamed: bool = False) -> dict[str, float]:
    """CSMP TIMER defaults: OUTDEL = FINTIM/100 and PRDEL = OUTDEL when neither is
    given; one given, the other takes its value; DELT divides the output interval.
    `streamed`: the OUTDEL rows go to a file as the run goes (a longer grid may be
    had then: `row_limit`); `max_rows` None: no limit (a count, not a run)."""
    t = dict(spec.timer)
    fintim_option = fintim
    if fintim is not None:
        if not fintim > 0:
            raise AmilError(f"FINTIM must be positive (got {fintim:g})")
        t["FINTIM"] = fintim
    if START_KEY in t:
        # FST: the run starts at STTIME and FINTIM is its end; from here on FINTIM is
        # the run's length, as in CSMP (the one place the two meet)
        if not t["FINTIM"] > t[START_KEY]:
            raise AmilError(f"FINTIM = {t['FINTIM']:g} must be later than STTIME = "
                            f"{t[START_KEY]:g}: with STTIME, FINTIM is the end time")
        t["FINTIM"] -= t[START_KEY]
    fintim = t["FINTIM"]
    if "OUTDEL" not in t and "PRDEL" not in t:
        t["OUTDEL"] = fintim / 100.0
        t["PRDEL"] = t["OUTDEL"]
    elif "OUTDEL" not in t:
        t["OUTDEL"] = t["PRDEL"]
    elif "PRDEL" not in t:
        t["PRDEL"] = t["OUTDEL"]
    interval = min(t["OUTDEL"], t["PRDEL"], fintim)
    for name in ("FINTIM", "OUTDEL", "PRDEL"):
        if not (math.isfinite(t[name]) and t[name] > 0.0):
            raise AmilError(f"{name} = {t[name]:g} is not a usable time (FINTIM = {fintim:g})")
    asked = fintim_option is not None
    for name in ("OUTDEL", "PRDEL"):
        if name in spec.timer and t[name] > t["FINTIM"] * (1.0 + 1e-12):
            # rows at t0 and FINTIM only: a straight line where the plot should be
            length = "as asked" if asked else "the run's length, FINTIM - STTIME" \
                if START_KEY in spec.timer else "FINTIM"
            raise AmilError([Diagnostic(
                f"{name} = {t[name]:g} is longer than the run ({length}: "
                f"{t['FINTIM']:g}): no output instant falls inside it",
                spec.timer_spans.get(name),
                f"ask for a run of at least {t[name]:g}, or write a smaller {name}" if asked
                else f"write {name} = {t['FINTIM'] / 100.0:g} (a hundredth of the run) or "
                "less, or a longer FINTIM")])
    if max_rows is not None:
        _check_rows(spec, t, max_rows, streamed)
    if "DELT" in t:
        n = max(1, math.ceil(interval / t["DELT"] - 1e-9))
        t["DELT"] = interval / n
    else:
        t["DELT"] = interval / 16.0
    t.setdefault("DELMIN", 0.0)
    t.setdefault("DELMAX", math.inf)
    return t


def _check_rows(spec: ir.RunSpec, t: dict[str, float], max_rows: int,
                streamed: bool) -> None:
    """Refuse more output rows than a run may have: `max_rows` kept in memory (the
    finer grid's; streamed, PRDEL's, whose rows are kept for the printout), and
    `row_limit` OUTDEL rows of a streamed run."""
    fintim = t["FINTIM"]
    stream_most = row_limit(max_rows, True)
    kept = "PRDEL" if streamed or t["PRDEL"] < t["OUTDEL"] else "OUTDEL"
    checks = [(kept, max_rows)] + ([("OUTDEL", stream_most)] if streamed else [])
    for name, limit in checks:
        rows = fintim / min(t[name], fintim)
        if rows <= limit:
            continue
        no_prdel = "PRDEL" not in spec.timer
        hint = f"raise {name}"
        if name == "PRDEL" and no_prdel:
            hint = "write a coarser PRDEL (the printed rows, kept in memory: without one " \
                   "it is OUTDEL)"
        elif name == "OUTDEL" and not streamed and rows <= stream_most and \
                (no_prdel or fintim / t["PRDEL"] <= max_rows):
            hint += (", or " + ("write a coarser PRDEL (the printed rows: without one it "
                                "is OUTDEL) and " if no_prdel else "") +
                     "have the OUTDEL rows written to a CSV as the run goes (amilpy run "
                     f"--csv FILE, Model.run(stream_csv=FILE): up to {stream_most:.0e})")
        raise AmilError([Diagnostic(f"FINTIM/{name} = {rows:.3g} output rows "
                                    f"(limit {limit})", spec.timer_spans.get(name), hint)])


def row_limit(max_rows: int, streamed: bool) -> int:
    """The most output rows a run may have: `max_rows`, more if they are streamed."""
    return max(max_rows, DEFAULTS["max_streamed_rows"]) if streamed else max_rows


def reserved_values(timer: dict[str, float]) -> dict[str, float]:
    """The TIMER values a listing may read (DELT, FINTIM, ...); FINTIM as the listing
    gave it (an end time after FST's STTIME)."""
    out = {k: timer[k] for k in ("FINTIM", "DELT", "PRDEL", "OUTDEL", "DELMIN", "DELMAX")}
    out[START_KEY] = timer.get(START_KEY, 0.0)
    out["FINTIM"] += out[START_KEY]
    return out


def start_time(spec: ir.RunSpec, opts: Options) -> float:
    """Where a run starts: a carried state's time, else TIMER STTIME (FST), else 0."""
    if opts.start:
        return float(opts.start["t"])
    return float(spec.timer.get(START_KEY, 0.0))


@dataclass(frozen=True)
class _Uniform:
    """The instants t0 + k*step, k = 0, 1, ..., the last of them FINTIM (appended
    when the last step does not reach it, else put in its place), by index: a grid
    of 1E7 instants is never written out whole before the run's own array is."""

    t0: float
    fintim: float
    step: float

    @cached_property
    def size(self) -> int:
        n = int(math.floor((self.fintim - self.t0) / self.step * (1 + 1e-12) + 1e-9))
        return n + 2 if self.fintim - (self.t0 + self.step * n) > 1e-9 * self.step \
            else n + 1

    def at(self, k: np.ndarray) -> np.ndarray:
        v = self.t0 + self.step * np.asarray(k, dtype=float)
        v[np.asarray(k) == self.size - 1] = self.fintim
        return v

    def _near(self, t: np.ndarray) -> np.ndarray:
        """Four indices about each t: the nearest instant and the count of those
        below t are among them (the floor is within one of the index)."""
        k = np.floor((t - self.t0) / self.step).clip(0, self.size - 1).astype(np.int64)
        return k[:, None] + np.arange(-1, 3)

    def below(self, t: np.ndarray, side: str = "left") -> np.ndarray:
        """np.searchsorted(the instants, t, side): how many are below each t (or at
        it too, side "right")."""
        near = self._near(t)
        inside = (near >= 0) & (near < self.size)
        at = self.at(near.clip(0, self.size - 1))
        under = inside & ((at < t[:, None]) if side == "left" else (at <= t[:, None]))
        return np.maximum(near[:, 0], 0) + under.sum(axis=1)

    def nearest(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`nearest_instants` on this grid."""
        near = self._near(t).clip(0, self.size - 1)
        d = np.abs(self.at(near) - t[:, None])
        pick = near[np.arange(len(t)), d.argmin(axis=1)]
        return pick, np.abs(self.at(pick) - t) <= SAME_INSTANT * np.maximum(1.0, np.abs(t))


class GridTimes:
    """The instants of a grid too long to write out (`LAZY_FROM`), made as they are
    read: OUTDEL's uniform instants (`_Uniform`) with the few put between them (PRDEL's
    own, the observations'). It answers what the run asks of its grid -- its length,
    an instant by index, a window by slice, `searchsorted` -- as the written array
    would, bit for bit; a slice of more than `BLOCK` instants is a view of the same
    kind, and anything else (`np.asarray`) writes the instants out.

    A streamed run of 1E7 rows would otherwise hold 80 MB of instants it reads once,
    in order: here it holds one block of them."""

    BLOCK = 1 << 12

    def __init__(self, rows: _Uniform, put: np.ndarray, at: np.ndarray,
                 lo: int = 0, hi: int | None = None) -> None:
        self.rows, self.put, self.at = rows, put, at  # put[j] goes before rows' at[j]
        self.landed = at + np.arange(len(put))  # where each put instant lands
        self.lo, self.hi = lo, rows.size + len(put) if hi is None else hi
        self._b0 = self._b1 = 0  # the block read last, [b0, b1) of this view
        self._block = np.empty(0)

    def window(self, i0: int, i1: int) -> np.ndarray:
        """The instants [i0, i1) of this view, a new array."""
        i0, i1 = self.lo + i0, self.lo + i1
        idx = np.arange(i0, i1)
        before = np.searchsorted(self.landed, idx)  # put instants before each
        is_put = before < len(self.landed)
        is_put[is_put] = self.landed[before[is_put]] == idx[is_put]
        out = np.empty(len(idx))
        out[~is_put] = self.rows.at(idx[~is_put] - before[~is_put])
        out[is_put] = self.put[before[is_put]]
        return out

    def __len__(self) -> int:
        return self.hi - self.lo

    @property
    def size(self) -> int:
        return self.hi - self.lo

    def __getitem__(self, key):
        n = self.hi - self.lo
        if isinstance(key, slice) and key.step in (None, 1):
            i0, i1, _ = key.indices(n)
            i1 = max(i0, i1)
            if i1 - i0 <= self.BLOCK:
                return self.window(i0, i1)
            return GridTimes(self.rows, self.put, self.at, self.lo + i0, self.lo + i1)
        if isinstance(key, (int, np.integer)):
            i = int(key) + n if key < 0 else int(key)
            if not 0 <= i < n:
                raise IndexError(f"index {key} is out of bounds for a grid of {n}")
            if not self._b0 <= i < self._b1:  # (read in order: a block at a time)
                self._b0, self._b1 = i, min(n, i + self.BLOCK)
                self._block = self.window(self._b0, self._b1)
            return self._block[i - self._b0]
        return np.asarray(self)[key]

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        out = self.window(0, len(self))
        return out if dtype is None else out.astype(dtype)

    def searchsorted(self, v, side: str = "left"):
        """As `np.ndarray.searchsorted` on this view's instants."""
        t = np.atleast_1d(np.asarray(v, dtype=float))
        count = self.rows.below(t, side) + np.searchsorted(self.put, t, side)
        out = (count - self.lo).clip(0, len(self))
        return out if np.ndim(v) else out[0]


# a grid of more instants is made as it is read (`GridTimes`): more than a run kept
# whole may print (max_rows), so only a streamed run has one
LAZY_FROM = 1 << 21


def _grid(t0: float, fintim: float, step: float) -> np.ndarray:
    g = _Uniform(t0, fintim, step)
    return g.at(np.arange(g.size))


# an instant within this of another (relative, at least absolute) is that instant:
# the grid's own arithmetic, t0 + k*step, rounds within it
SAME_INSTANT = 1e-12


def within(t: float) -> float:
    """How far from t another instant is still t (SAME_INSTANT)."""
    return SAME_INSTANT * max(abs(t), 1.0)


def same_instant(a: float, b: float) -> bool:
    """Whether a is the instant b (within SAME_INSTANT of it)."""
    return math.isfinite(b) and abs(a - b) <= within(b)


def nearest_instants(times: np.ndarray, t) -> tuple[np.ndarray, np.ndarray]:
    """For each of the instants t, the index of the nearest of the sorted `times`,
    and whether it is that instant (within SAME_INSTANT)."""
    t = np.asarray(t, dtype=float)
    if not len(times):
        return np.zeros(len(t), int), np.zeros(len(t), bool)
    j = np.searchsorted(times, t).clip(0, len(times) - 1)
    before = np.maximum(j - 1, 0)
    pick = np.where(np.abs(times[before] - t) < np.abs(times[j] - t), before, j)
    return pick, np.abs(times[pick] - t) <= SAME_INSTANT * np.maximum(1.0, np.abs(t))


def make_grid(t0: float, fintim: float, outdel: float, prdel: float,
              extra: tuple[float, ...] = ()) -> Grid:
    """The output instants; `extra`: more instants in (t0, fintim) to have rows at
    (in neither grid), each within SAME_INSTANT of a grid instant taken as that one.

    Written into the run's arrays part by part, or, over LAZY_FROM instants (a
    streamed run's), made as the run reads it (`GridTimes`): a streamed run of 1E7
    rows holds its masks (0 to 2 bytes an instant) and no more (its written-out
    instants took 8, and a union of the two grids 95)."""
    scale = max(1.0, abs(t0), abs(fintim))
    for name, step in (("OUTDEL", outdel), ("PRDEL", prdel)):
        if step <= SAME_INSTANT * scale:
            # (two instants that close are one: the grid's rows would fall together)
            raise AmilError([Diagnostic(
                f"{name} = {step:g} is below what TIME can tell apart at TIME = "
                f"{scale:g} (instants {SAME_INSTANT:g} of it apart are one)", None,
                f"write {name} = {SAME_INSTANT * scale * 1e3:g} or more, or start TIME "
                "nearer 0")])
    rows = _Uniform(t0, fintim, outdel)
    # a PRDEL instant that rounds within SAME_INSTANT of an OUTDEL one (3*0.05 and
    # 150*0.001) is that instant: one row, not two 3E-17 apart
    gp = _grid(t0, fintim, prdel) if prdel != outdel else np.empty(0)
    pick, same = rows.nearest(gp)
    own = gp[~same]
    more = np.asarray(extra, dtype=float)
    more = np.unique(more[(more > t0) & (more < fintim)])
    more = more[~rows.nearest(more)[1] & ~nearest_instants(own, more)[1]]
    # the instants put between the OUTDEL ones: PRDEL's own and the extra ones
    put = np.concatenate([own, more])
    order = np.argsort(put, kind="stable")
    put, put_prdel = put[order], (np.arange(len(put)) < len(own))[order]
    at = rows.below(put)  # put[j] goes before OUTDEL instant at[j]
    size = rows.size
    lazy = GridTimes(rows, put, at)
    times = lazy if size + len(put) > LAZY_FROM else np.empty(size + len(put))
    if len(put):
        new = lazy.landed
        outdel_mask = np.ones(len(times), bool)
        outdel_mask[new] = False
        prdel_mask = outdel_mask.copy() if prdel == outdel else np.zeros(len(times), bool)
        prdel_mask[new] = put_prdel
    else:  # (every instant an OUTDEL one: a mask that takes no memory, read-only)
        outdel_mask = np.broadcast_to(np.True_, (size,))
        prdel_mask = outdel_mask if prdel == outdel else np.zeros(size, bool)
    if times is not lazy:
        part = 1 << 14  # (a part's making takes 40 bytes an instant for a while)
        for a in range(0, len(times), part):
            times[a:a + part] = lazy.window(a, min(a + part, len(times)))
    if prdel != outdel:
        prdel_mask[pick[same] + np.searchsorted(at, pick[same], side="right")] = True
    return Grid(times, outdel_mask, prdel_mask)


def resolve_route(spec: ir.RunSpec, opts: Options) -> tuple[Route, str]:
    """The route a run takes and the METHOD name as spelled."""
    requested = opts.method or spec.method or DEFAULT
    route = route_for(requested)
    if route is None:
        raise AmilError(f"unknown integration method {requested}")
    return route, requested.upper()


def resolve_step_point(spec: ir.RunSpec, opts: Options) -> bool:
    """Whether a run is in step-point mode: the option, else the listing, else the
    method's default; an error for a variable-step method."""
    route, method = resolve_route(spec, opts)
    asked = opts.step_point if opts.step_point is not None else spec.step_point
    if opts.step_point is None and opts.method is not None and route.uses_tolerances:
        asked = None  # a variable-step method asked for outright replaces the listing's
        # step-point driver (IALG 3, DRIVER = 'EUDRIV') with located switching
    try:
        return step_point_mode(route, asked, method)
    except StepPointError as exc:
        raise AmilError([Diagnostic(str(exc), None, "write METHOD EULER (RECT) or RK4, "
                                    "or run without --step-point")]) from None


def make_plan(model: ir.Model, spec: ir.RunSpec, opts: Options, c: ModelCode,
              timer: dict[str, float], grid: Grid, step_point: bool = False,
              t0: float | None = None) -> RunPlan:
    """The plan of one run, from its generated functions (breakpoints need them).
    In step-point mode the run ends at the grid's last step point."""
    route, method = resolve_route(spec, opts)
    if t0 is None:
        t0 = start_time(spec, opts)
    fintim = float(grid.times[-1]) if step_point else t0 + timer["FINTIM"]
    state_index = {n: i for i, n in enumerate(c.state_names)}
    watched = []
    for i in c.watched:
        s = model.surfaces[i]
        kind = SurfaceKind(s.kind)
        g = linear_gradient(s.expr, state_index, c.constants) \
            if kind is SurfaceKind.SIGN else None
        crossing = model.acsl.crossings.get(i) if model.acsl is not None else None
        watched.append(Watched(i, kind, Purpose(s.purpose), s.description, s.text,
                               None if g is None else np.asarray(g),
                               # (a guarded one is read on its branch only: its
                               # root is located, not worked out from t0 and FINTIM)
                               (i in c.affine_time and s.guard is None)
                               or i in c.train_surfaces,
                               crossing[1] if crossing else 0, s.guard is not None,
                               i in model.closed))
    roots, breakpoints = time_breakpoints(c, watched, t0, fintim)
    pos = {i: k for k, i in enumerate(c.watched)}
    resets = []
    for si, s in enumerate(model.states):
        if s.reset_surfaces:
            s1, s2 = s.reset_surfaces
            resets.append(Reset(si, *(pos[x] if x in pos else c.const_modes.get(x, 0.0)
                                      for x in (s1, s2))))
    floor_given = timer.get("DELMIN", 0.0) > 0.0
    # steps this short make no progress: FINTIM*1e-12 is ~4000 ulps of FINTIM
    return RunPlan(
        route=route, method=method, timer=timer, t0=t0, fintim=fintim,
        tol=Tolerances.build(spec, opts, c.state_names,
                             "acsl" if model.acsl is not None else "csmp", route), grid=grid,
        watched=tuple(watched),
        watch_idx=tuple(k for k, w in enumerate(watched) if not w.breakpoint_only),
        breakpoints=tuple(breakpoints), roots=roots, resets=tuple(resets),
        chunked=route.stepper == "odeint" and not c.memory_every_step,
        pauses=route.stepper == "scipy" or (route.stepper == "odeint"
                                            and not c.memory_every_step),
        # the output grid does not bound the step (OUTDEL changes no printed number:
        # every step's surfaces are looked at and its rows come from its dense output),
        # a hundredth of the run does, as the default OUTDEL did: a state below its
        # ABSERR is not held by the error test, and a step past an explicit method's
        # stability boundary then grows it (X = 1E-300*EXP(-TIME) over 100 s); nor a
        # delay the derivatives read (every stage reads a past that is stored)
        max_step=min(timer["DELMAX"], (fintim - t0) / 100.0, c.step_limit),
        h_floor=timer["DELMIN"] if floor_given else 1e-12 * (fintim - t0),
        floor_origin="TIMER DELMIN" if floor_given else
        "the default floor FINTIM*1E-12; TIMER DELMIN lowers it",
        lookahead_h=LOOKAHEAD * max(fintim - t0, abs(t0) * 1e-8),
        events=opts.events, step_point=step_point,
    )


def time_breakpoints(c: ModelCode, watched: list[Watched], t0: float, t1: float
                     ) -> tuple[dict[int, float], list[float]]:
    """The breakpoints in (t0, t1): roots of the surfaces affine in TIME (by watched
    position) and the instants of IMPULS trains, sorted."""
    roots: dict[int, float] = {}
    for k, w in enumerate(watched):
        if w.breakpoint_only and w.surface in c.affine_time:
            root = _affine_root(c, k, t0, t1)
            if root is not None and t0 < root < t1:
                roots[k] = root
    # IMPULS instants, and the instants where a train's surfaces change sign (these
    # take their new sign there: no root to polish)
    points = list(roots.values()) + train_instants([*c.impulses, *c.trains], t0, t1)
    return roots, sorted(set(points))


def train_instants(trains: list[tuple[float, float]], t0: float, t1: float) -> list[float]:
    """The instants start + k*period (k >= 0; a period of 0: start alone) of each
    train in (t0, t1), a million at most per train, unsorted."""
    points = []
    for start, period in trains:
        if period > 0:
            k0 = max(0, math.ceil((t0 - start) / period))
            n = int(min((t1 - start) / period, k0 + 1_000_000))
            points.extend(start + k * period for k in range(k0, max(n, -1) + 1)
                          if t0 < start + k * period < t1)
        elif t0 < start < t1:
            points.append(start)
    return points


def _affine_root(c: ModelCode, k: int, t0: float, t1: float) -> float | None:
    """The first float at which an affine time surface reaches zero in [t0, t1]."""
    y, z, m = list(c.y0), list(c.z0), [0.0] * len(c.watched)

    def e(t: float) -> float:
        return c.surf(t, y, m, z)[k]

    e0, e1 = e(t0), e(t1)
    slope = (e1 - e0) / (t1 - t0)
    if slope == 0.0 or sign(e0) == sign(e1) and e1 != 0.0:
        return None
    r = t0 - e0 / slope
    # polish to the first float where the sign has changed (or is zero)
    before = sign(e0)
    for _ in range(64):
        if sign(e(r)) == before and before != 0:
            r = math.nextafter(r, math.inf)
        else:
            break
    for _ in range(64):
        p = math.nextafter(r, -math.inf)
        if sign(e(p)) != before and p > t0:
            r = p
        else:
            break
    return r
