"""A run of a program in ACSL form (contract sections 9 and 11): its preparation and
its event queue.

One run: constants -> INITIAL (written order, `prepare_acsl`) -> the states' INTEG
initial values -> DERIVATIVE -> the events due at t0 -> DYNAMIC's own statements ->
the TERMT tests -> the first row. Then the loop integrates to the next of: a CINT
instant where DYNAMIC's own statements run, a scheduled event, a located crossing
(SCHEDULE .XP./.XN./.XZ., a TERMT). At an event the due DISCRETE sections run in
queue order, then the run restarts (branches chosen again); at a CINT instant
DYNAMIC's own statements and their TERMTs run and a row is taken (after the
events of that instant). Rows are every CINT; the loop records them (interpolated)
where nothing happens, and holds the row of an instant where something does, for
`AcslRun.instant` to take after it. At the end: the last row, then TERMINAL.
"""

from __future__ import annotations

import heapq
import math
from bisect import bisect_right
from dataclasses import dataclass, field, replace
from itertools import count

import numpy as np

from .. import ir
from ..codegen import Compiler, Setting, evaluate_constant
from ..codegen.written import compile_code
from ..diagnostics import AmilError, Diagnostic
from ..language import MAX_INTERVALS
from ..outcome import Failure
from ..parse.syntax import no_collection
from ..result import Event, EventKind
from ..routes import IALG_METHODS, route_for
from . import steppoint
from .code import Calls, code_fault
from .driver import _Run
from .loop import Cursor, Stop
from .plan import (
    DEFAULTS,
    Grid,
    Options,
    Purpose,
    make_grid,
    make_plan,
    resolve_step_point,
    same_instant,
    slides,
    within,
)
from .prepare import Cache, Prepared, before_run, constant_modes, random_seed
from .watch import left_surfaces

MIN_INTERVAL = 1e-100  # the least CINT a run takes


@dataclass(frozen=True)
class AcslPrepared(Prepared):
    """A prepared run of the ACSL form: what INITIAL scheduled and whether a TERMT of
    INITIAL already holds."""

    schedules: list[tuple[float, str]] = field(default_factory=list)
    stop: str | None = None
    unbounded: bool = False  # no TERMT on time and no FINTIM: the run is capped


def termination(t: ir.Termination) -> str:
    where = f"TERMT at line {t.span.line}" if not t.text else \
        f"TERMT({t.text}) at line {t.span.line}"
    return f"{t.message} ({where})" if t.message else where


# ----------------------------------------------------------------- preparation


def prepare_acsl(model: ir.Model, spec: ir.RunSpec, opts: Options | None = None,
                 cache: Cache | None = None) -> AcslPrepared:
    """Constants, INITIAL, generated functions and plan of one run of the ACSL form.
    A fault in INITIAL or in a value needed before the run is an AmilError there."""
    opts = opts or Options()
    cache = cache or Cache()
    return before_run(model, lambda: _prepare(model, spec, opts, cache), code_fault)


def initial_start(spec: ir.RunSpec) -> dict[str, float]:
    """The values INITIAL starts from: the data, PI and the TIMER values."""
    return {"PI": math.pi, **spec.data, **spec.timer}  # (a listing's own PI wins)


def run_initial(model: ir.Model, spec: ir.RunSpec, cache: Cache):
    """INITIAL, run once: (the data and TIMER values it started from, values of the
    names it assigns and of CINT and the INTERVALs, what it scheduled, the first TERMT
    of it that holds)."""
    acsl = model.acsl
    base = initial_start(spec)
    tables = spec.tables
    starts = {acsl.cint_name: evaluate_constant(model, acsl.cint, base, tables, None)}
    for d in acsl.discretes.values():
        if d.interval is not None:
            starts[d.interval] = evaluate_constant(model, d.interval_value, base, tables,
                                                   d.span)
    key = (tuple(sorted(base.items())), repr(sorted(tables.items())))
    init = cache.get("initial", ("acsl",) + key, lambda: compile_code(
        model, "initial", acsl.initial, base, tables, starts))
    calls = Calls()
    values = dict(zip(init.amil_names, init(acsl.t0, [], [], [], calls), strict=True))
    stop = termination(acsl.termts[calls.termts[0]]) if calls.termts else None
    return base, values, calls.schedules, stop


def initial_reads(model: ir.Model) -> frozenset[str]:
    """Every data name `run_initial`'s values may depend on: what INITIAL and the CINT
    and INTERVAL values read, and what INITIAL assigns (a constant it assigns keeps
    its own value where INITIAL's branch does not assign it): a run whose data
    differ only elsewhere gets the same values."""
    from ..parse.syntax import Name, walk

    acsl = model.acsl
    roots = [st for code in acsl.initial for st in code.body] + [acsl.cint] + [
        d.interval_value for d in acsl.discretes.values() if d.interval_value is not None]
    return frozenset(node.name for root in roots for node in walk(root)
                     if isinstance(node, Name)) | {
        n for code in acsl.initial for n in code.assigned}


def run_values(model: ir.Model, base: dict[str, float], values: dict[str, float]
               ) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
    """From INITIAL's start and its values (`run_initial`): the run's constants, the
    values written-order code keeps between instants (z slots) and INITIAL's values
    of the names DERIVATIVE assigns again."""
    acsl = model.acsl
    # what DERIVATIVE computes (its equations and states) is no constant, even where
    # INITIAL gave it a value
    derived = {e.target for e in model.dynamic} | {s.name for s in model.states}
    kept = {n: float(values.get(n, 0.0)) for n in acsl.discrete_vars}
    constants = {k: v for k, v in {**base, **values}.items()
                 if k not in kept and k not in derived}
    priors = {n: values[n] for n in acsl.priors if n in values}
    return constants, kept, priors


@no_collection()
def _prepare(model: ir.Model, spec: ir.RunSpec, opts: Options, cache: Cache) -> AcslPrepared:
    acsl = model.acsl
    base, values, schedules, stop = run_initial(model, spec, cache)
    constants, kept, priors = run_values(model, base, values)
    cint = kept.get(acsl.cint_name, constants.get(acsl.cint_name))
    if not (cint is not None and math.isfinite(cint) and cint > 0):
        raise AmilError(f"the output interval {acsl.cint_name} = {cint} must be positive",
                        model.path)
    if not (cint >= MIN_INTERVAL and acsl.t0 + cint > acsl.t0):
        # (the solvers' own step floors are far above it: below, a run failed with
        # "X is no longer finite", or a division by zero with no line)
        raise AmilError(f"the output interval {acsl.cint_name} = {cint:g} is too small "
                        f"(the least is {MIN_INTERVAL:g} s, and a step TIME can take from "
                        f"{acsl.t0:g}): make it longer", model.path)
    method = _method(model, spec, opts, constants)
    spec = replace(spec, method=method)
    timer = _timer(model, spec, opts, constants, cint)
    # IALG 3 (Euler) is METHOD RECT, in step-point mode like every classic translator's
    step_point = resolve_step_point(spec, opts)
    const_modes = constant_modes(model, constants, spec.tables, step_point)
    fixed = route_for(method or "AUTO").fixed
    # a random draw is held for one output interval (one DELT with a fixed step)
    setting = Setting(seed=random_seed(opts, constants), hold=timer["DELT"] if fixed else cint,
                      step=timer["DELT"] if step_point else None)
    ckey = ("acsl", tuple(sorted(constants.items())), tuple(kept.items()),
            tuple(sorted(priors.items())), repr(sorted(spec.tables.items())),
            tuple(opts.outputs) if opts.outputs is not None else None, opts.events, setting)
    # a run whose data values (and what INITIAL works out) alone differ binds the code
    # built for another, as in CSMP form (a Monte Carlo, a sweep: no compile per run);
    # the written-order code reads them by name, so nothing of them is folded in
    params = frozenset(model.data_names) | frozenset(
        n for code in acsl.initial for n in code.assigned)
    skey = ("acsl", tuple(sorted((k, v) for k, v in constants.items() if k not in params)),
            tuple(sorted(const_modes.items())), tuple(kept.items()),
            tuple(sorted(priors.items())), repr(sorted(spec.tables.items())),
            tuple(opts.outputs) if opts.outputs is not None else None, opts.events, setting)
    code = cache.get("bound", ckey, lambda: cache.get("code", skey, lambda: Compiler(
        model, constants, spec.tables, const_modes, opts.outputs, opts.events,
        setting=setting, kept=kept, priors=priors, parameters=params).build()
    ).rebound(constants))
    t0 = acsl.t0
    # the rows a run keeps: MAX_INTERVALS, fewer when many variables would make them
    # more values than any run keeps (a CSMP run is refused before it starts likewise)
    kept_intervals = min(MAX_INTERVALS, DEFAULTS["max_values"] // max(len(code.out_names), 1))
    # a TERMT on time alone bounds the run: find its instant from a plan reaching far
    far = dict(timer, FINTIM=MAX_INTERVALS * cint)
    first = make_plan(model, spec, opts, code, far, make_grid(t0, t0 + cint, cint, cint),
                      t0=t0)
    roots = [first.roots[k] for k, w in enumerate(first.watched)
             if w.purpose is Purpose.TERMT and k in first.roots]
    given = opts.fintim or spec.timer.get("FINTIM")
    unbounded = False
    if roots and (given is None or min(roots) - t0 <= given):
        fintim = min(roots) - t0 + cint  # the TERMT instant lies inside the run
    elif given is not None:
        fintim = given
    else:
        fintim, unbounded = kept_intervals * cint, True
    if not fintim / cint <= kept_intervals + 1:  # (+ the row past a TERMT instant)
        raise AmilError(f"{acsl.cint_name} = {cint:g} gives {fintim / cint:.3g} output "
                        f"intervals to TIME = {t0 + fintim:g}, more than the "
                        f"{kept_intervals:,} a run of {len(code.out_names)} variables keeps "
                        f"({DEFAULTS['max_values']:.0e} values at most): make "
                        f"{acsl.cint_name} longer", model.path)
    timer["FINTIM"] = fintim
    # (an observation's instant between the CINT ones is a row too, the states there
    # and what the code last left: no code runs at it)
    grid = steppoint.grid(t0, timer) if step_point else \
        make_grid(t0, t0 + fintim, cint, cint, opts.extra_times)
    plan = make_plan(model, spec, opts, code, timer, grid, step_point, t0=t0)
    if unbounded:  # (a hundredth of a run of 100 output intervals: the length is unknown)
        plan = replace(plan, max_step=min(plan.max_step, cint))
    return AcslPrepared({**constants, **values}, code, plan, schedules, stop, unbounded)


def _method(model: ir.Model, spec: ir.RunSpec, opts: Options, constants) -> str | None:
    """METHOD, or the route ALGORITHM IALG = n maps to (contract section 11)."""
    if opts.method or spec.method:
        return spec.method
    name = model.acsl.controls.get("ALGORITHM")
    if name is None:
        return None
    ialg = constants.get(name)
    if ialg is None or not float(ialg).is_integer() or int(ialg) not in IALG_METHODS:
        known = ", ".join(f"{k} ({v})" for k, v in IALG_METHODS.items())
        raise AmilError([Diagnostic(f"ALGORITHM {name} = {ialg:g} is not an algorithm amilpy "
                                    "runs", model.acsl.control_spans.get("ALGORITHM"),
                                    f"IALG takes {known}")], model.path, model.source)
    return IALG_METHODS[int(ialg)]


def _timer(model: ir.Model, spec: ir.RunSpec, opts: Options, constants, cint: float
           ) -> dict[str, float]:
    """Output interval CINT; fixed step min(MAXT, CINT/NSTP), made to divide CINT;
    variable step: DELMAX = MAXT, DELMIN = MINT."""
    controls = model.acsl.controls

    def control(keyword: str, default: float) -> float:
        name = controls.get(keyword)
        return float(constants[name]) if name in constants else default

    nstp, maxt = control("NSTEPS", 10.0), control("MAXTERVAL", 1e10)
    mint = control("MINTERVAL", 0.0)
    delt = min(maxt, cint / max(nstp, 1.0))
    delt = cint / max(1, math.ceil(cint / delt - 1e-9))
    route = route_for(opts.method or spec.method)
    timer = {"OUTDEL": cint, "PRDEL": cint, "DELT": delt, "DELMIN": mint,
             "DELMAX": maxt if "MAXTERVAL" in controls and route is not None
             and not route.fixed else math.inf}
    timer.update({k: v for k, v in spec.timer.items() if k in ("DELMIN", "DELMAX")})
    return timer


# ------------------------------------------------------------------------ run


class AcslRun(_Run):
    """simulate's run with the ACSL form's order of one run (see the module's doc)."""

    observer = None  # (of every accepted step: the program's tangent, `analysis.program`)

    def __init__(self, model, spec, opts, prepared: AcslPrepared, started) -> None:
        super().__init__(model, spec, opts, prepared, started)
        self.acsl = model.acsl
        self.prepared = prepared
        c = self.c
        self.fns = {d.name: c.code[f"discrete_{k}"][1]
                    for k, d in enumerate(self.acsl.discretes.values())}
        self.dynamic = c.code["dynamic"][1] if self.acsl.dynamic.body else None
        self.queue: list[tuple[float, int, str]] = []
        self.order = count()
        self.stopped: str | None = prepared.stop
        # the SCHEDULE surfaces whose crossing ran its section at this instant: the
        # motion leaving their zero (a ball bouncing off the floor) crosses nothing
        self.fired_at: tuple[float, set[int]] = (math.nan, set())
        for d in self.acsl.discretes.values():
            if d.interval is not None:
                self.schedule(self.plan.t0, d.name)
        for t, section in prepared.schedules:
            self.schedule(t, section)

    # ------------------------------------------------------------------- queue
    def schedule(self, t: float, section: str, now: float | None = None) -> None:
        if now is not None and t < now - within(now):
            raise Stop(Failure.FAULT, now, detail=f"SCHEDULE {section} at T = {t:.9g}, "
                       "before the present time")
        heapq.heappush(self.queue, (max(t, now) if now is not None else t, next(self.order),
                                    section))

    def due(self, t: float) -> bool:
        return bool(self.queue) and self.queue[0][0] <= t + within(t)

    def next_instant(self, t: float) -> tuple[float, bool]:
        """The next instant something happens, and whether it acts (else only ends)."""
        nxt, acts = self.plan.fintim, False
        if self.queue and self.queue[0][0] < nxt:
            nxt, acts = self.queue[0][0], True
        if self.dynamic is not None:
            times, cint = self.plan.grid.times, self.plan.grid.outdel
            k = bisect_right(times, t * (1 + 1e-15) + 1e-300)
            while k < len(times) and not cint[k]:
                k += 1  # (an observation's row: the loop takes it as it passes)
            if k < len(times) and times[k] <= nxt:
                nxt, acts = float(times[k]), True
        return nxt, acts

    # -------------------------------------------------------------------- code
    def run_code(self, cur: Cursor, fn, what: str) -> Calls:
        calls = Calls()
        try:
            y, z, _ = fn(cur.t, cur.y.tolist(), cur.m, cur.z, calls)
        except (ArithmeticError, ValueError) as exc:
            raise Stop(Failure.FAULT, cur.t, detail=f"{what}: {code_fault(exc)}") from None
        cur.y = np.asarray(y, dtype=float)
        cur.z[:] = z
        for t, section in calls.schedules:
            self.schedule(t, section, cur.t)
        if calls.termts and self.stopped is None:
            self.stopped = termination(self.acsl.termts[calls.termts[0]])
        return calls

    def run_due(self, cur: Cursor) -> bool:
        """The DISCRETE sections due now, in queue order (one scheduled now by them runs
        after them); each INTERVAL section is scheduled again."""
        ran = False
        while self.due(cur.t) and self.stopped is None:
            _, _, section = heapq.heappop(self.queue)
            self.run_code(cur, self.fns[section], f"DISCRETE {section}")
            self.integ.events.append(Event(cur.t, f"DISCRETE {section}", -1, 0.0, 0.0,
                                           EventKind.DISCRETE, section))
            if len(self.integ.events) > self.opts.max_events:
                raise Stop(Failure.EVENTS, cur.t, limit=self.opts.max_events)
            d = self.acsl.discretes[section]
            if d.interval is not None:
                gap = self.value(cur, d.interval)
                if gap > 0:
                    self.schedule(cur.t + gap, section)
            ran = True
        return ran

    def value(self, cur: Cursor, name: str) -> float:
        kept = self.c.kept
        if name in kept:
            return float(cur.z[len(cur.z) - len(kept) + kept.index(name)])
        return float(self.constants.get(name, 0.0))

    def run_crossing(self, cur: Cursor, surface: int) -> None:
        """A SCHEDULE crossing seen at a step point: its DISCRETE section runs now
        (with any others due)."""
        self.schedule(cur.t, self.acsl.crossings[surface][0], cur.t)
        self.run_due(cur)

    def termt_ahead(self, t: float) -> float | None:
        """The instant of a TERMT on TIME a few floats after t (events summed up to
        just before it), which the integration loop would take as passed."""
        plan = self.plan
        near = [root for k, root in plan.roots.items()
                if plan.watched[k].purpose is Purpose.TERMT
                and t < root <= t * (1 + 1e-15) + 1e-300]
        return min(near) if near else None

    def termt_now(self, cur: Cursor) -> None:
        """The TERMTs of DERIVATIVE, tested at an instant (t0, an event)."""
        plan = self.plan
        ks = [k for k, w in enumerate(plan.watched) if w.purpose is Purpose.TERMT]
        if not ks or self.stopped is not None:
            return
        e = self.c.surf(cur.t, cur.y.tolist(), cur.m, cur.z)
        for k in ks:
            # (TERMT(N >= 2) holds at zero: a DISCRETE that makes N 2 stops the run)
            if e[k] > 0 or (e[k] == 0 and (plan.watched[k].breakpoint_only
                                           or plan.watched[k].closed)):
                self.stopped = plan.watched[k].description
                return

    def instant(self, cur: Cursor) -> None:
        """Events due now, then (at a CINT instant) DYNAMIC's own statements, the
        TERMT tests and the row."""
        sliding = [k for k, v in enumerate(cur.m) if slides(v)]
        # (the surfaces before the code: a sliding one it moves is left; a SCHEDULE's
        # that the motion crosses right here, and the code leaves as it was, fires)
        surfaces = self.c.surf(cur.t, cur.y.tolist(), cur.m, cur.z) \
            if sliding or self.integ.scheduling else None
        before = (cur.y, list(cur.m), list(cur.z))
        changed = self.run_due(cur)
        times = self.plan.grid.times
        on_grid = self.rec.out_i < len(times) and \
            same_instant(cur.t, times[self.rec.out_i])
        # (DYNAMIC runs at the CINT instants, not at an observation's)
        if on_grid and self.plan.grid.outdel[self.rec.out_i] and self.dynamic is not None \
                and self.stopped is None:
            self.run_code(cur, self.dynamic, "DYNAMIC")
            changed = True
        if changed and sliding:
            self.off_surfaces(cur, sliding, surfaces)
        if changed:
            self.restart_firing(cur, surfaces)
        self.termt_now(cur)
        self.rec.hold = None
        if not np.array_equal(before[0], cur.y):
            # (RANGE reads both sides of the states the code set, and integrates again
            # from after it: a dose between two rows is the peak; at the start there
            # is no side before the first row's)
            if self.rec.last_t is not None:
                self.rec.sample(cur.t, *before)
            self.rec.restarted(cur.t, cur.y.copy(), list(cur.m), list(cur.z))
            self.rec.sample(cur.t, cur.y, cur.m, cur.z)
        if not on_grid and changed:
            # (the instant's row taken a float before a crossing located just after
            # it -- a ball landing on a CINT instant, to rounding: after its code)
            self.rec.retake(cur.t, cur.y, cur.m, cur.z)
        if on_grid:
            self.rec.grid_row(cur.t, cur.y, cur.m, cur.z,
                              shown=self.rec.shown_modes(cur.t, cur.y, cur.m, cur.z))
        elif self.stopped is not None and (self.rec.last_t is None or
                                           not same_instant(self.rec.last_t, cur.t)):
            # (the instant a TERMT of code ended the run is its last row, as a located
            # stop's is: its final values are those after the code that ran there; a
            # row a float before it is that row)
            self.rec.row(cur.t, cur.y, cur.m, cur.z,
                         shown=self.rec.shown_modes(cur.t, cur.y, cur.m, cur.z))
        if changed and self.acsl.cint_name in self.c.kept:
            self.regrid(cur.t, self.value(cur, self.acsl.cint_name))

    def restart_firing(self, cur: Cursor, before: list[float] | None) -> None:
        """The branches chosen again after the instant's code; a SCHEDULE surface the
        motion crosses at this very instant (a ball landing as an INTERVAL section is
        due), which the code left as it was, runs its section now: it was taken as
        already crossed, and the ball fell through the floor."""
        at, fired = self.fired_at
        if not same_instant(at, cur.t):
            fired = set()
        for _ in range(self.opts.max_events):
            # (a surface whose crossing ran its section here is at zero: the motion
            # leaving it either way, .XZ.'s ball going up again, is no crossing --
            # taken as one, the ball bounced on the spot 3,000 times and fell through)
            _, more = self.restart(cur, before, fired)
            fired.update(more)
            self.fired_at = (cur.t, fired)
            plan = self.plan
            for k in more:
                self.schedule(cur.t, self.acsl.crossings[plan.watched[k].surface][0], cur.t)
            if not more or not self.run_due(cur):
                return
            before = self.c.surf(cur.t, cur.y.tolist(), cur.m, cur.z)

    def off_surfaces(self, cur: Cursor, sliding: list[int], before: list[float]) -> None:
        """A surface the motion slid on that the code moved off zero (a set point a
        DISCRETE section changes) is slid on no longer: its branch is the side it is
        on now, and the restart goes on from there (it kept sliding, off the surface,
        until 2026-11-30)."""
        now = self.c.surf(cur.t, cur.y.tolist(), cur.m, cur.z)
        for k, side in left_surfaces(before, now, sliding).items():
            cur.m[k] = side

    def regrid(self, t: float, cint: float) -> None:
        """CINT assigned during the run: rows every new CINT from this instant on."""
        plan = self.plan
        if cint == plan.timer["OUTDEL"]:
            return
        if not (math.isfinite(cint) and cint > 0):
            raise Stop(Failure.FAULT, t, detail=f"{self.acsl.cint_name} = {cint:g}: the "
                       "output interval must be positive")
        done = plan.grid.times[:self.rec.out_i]
        later = make_grid(t, plan.fintim, cint, cint).times
        times = np.concatenate([done, later[later > (done[-1] if done.size else -math.inf)]])
        every = np.ones(times.size, bool)
        timer = dict(plan.timer, OUTDEL=cint, PRDEL=cint)
        if route_for(plan.method) is not None and route_for(plan.method).fixed:
            timer["DELT"] = cint / max(1, math.ceil(cint / plan.timer["DELT"] - 1e-9))
        self.plan = replace(plan, grid=Grid(times, every, every), timer=timer)
        self.rec.plan = self.integ.plan = self.plan
        self.rec.times = times
        self.integ.new_grid(times)

    # ---------------------------------------------------------------- _Run hooks
    def first_row(self, cur: Cursor) -> None:
        try:
            self.instant(cur)
        except Stop as stop:  # raised again where the run's faults are handled
            self.failed = stop
        if self.rec.last_t is None:
            super().first_row(cur)

    def advance(self, cur: Cursor) -> str | None:
        plan, integ, rec = self.plan, self.integ, self.rec
        if getattr(self, "failed", None) is not None:
            raise self.failed
        while self.stopped is None:
            t_next, acts = self.next_instant(cur.t)
            ahead = self.termt_ahead(cur.t)
            if ahead is not None and ahead <= t_next:
                # (the loop takes a breakpoint this close as passed: the TERMT's
                # instant is here, not at the next instant)
                cur.t = ahead
                self.instant(cur)
                continue
            rec.hold = t_next if acts else None
            if t_next - cur.t <= within(cur.t):
                # (an instant that rounding put a few floats after this one, FINTIM
                # after INTERVALs summed up to it: nothing to integrate, and LSODA
                # refuses a span that short)
                cur.t = max(cur.t, t_next)
            else:
                # (a CINT instant or an event that changes nothing the derivatives read
                # does not restart the integrator)
                integ.integrate(cur, t_next, rec, pause=acts, observer=self.observer)
            rec.hold = None
            reason, fired = integ.stop_reason, integ.fired
            integ.fired = []
            if fired:
                self.fired_at = (cur.t, set(fired))
            for k in fired:  # (their sections run now, as the next instant)
                self.schedule(cur.t, self.acsl.crossings[plan.watched[k].surface][0], cur.t)
            if reason is not None:
                w = plan.watched[reason]
                if w.purpose is not Purpose.SCHEDULE:
                    if fired:  # (the instant's sections run before the run stops)
                        self.run_due(cur)
                    return w.description
                integ.stop_reason = None
                continue
            if cur.t >= plan.fintim:
                if self.prepared.unbounded:
                    termt = any(w.purpose is Purpose.TERMT for w in plan.watched)
                    raise Stop(Failure.FAULT, cur.t, detail=(
                        f"no TERMT ended the run within "
                        f"{len(self.prepared.plan.grid.times) - 1:,} output intervals "
                        "(the most a run of its variables keeps); " + (
                            "make CINT longer, or its TERMT come sooner" if termt else
                            "add TERMT(T >= TSTOP) or TIMER FINTIM")))
                return None
            if cur.t >= t_next:
                self.instant(cur)
        return self.stopped


__all__ = ["AcslPrepared", "AcslRun", "Grid", "initial_reads", "initial_start", "prepare_acsl",
           "run_initial", "run_values"]
