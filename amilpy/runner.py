"""One run: segments between breakpoints, events located on the dense output,
restarts in the new branch, memory updates on accepted steps, output sampling.

A run is a pure function of (model, run spec, options): `simulate` builds the
compiled functions for the run's constants and integrates; nothing global is
touched, so runs can be farmed out.

Discontinuities. Each switching surface has a mode (its branch) that is frozen
while a segment is integrated, so the stepper always sees a smooth right-hand
side. Surfaces on TIME alone whose root is known in advance are breakpoints:
segments end exactly there. The other surfaces are watched: after every
accepted step their sign is checked; a crossing is located by Brent's method
on the stepper's dense output, the step is cut there, and the run restarts.
The new mode comes from the direction the dynamics take in each branch (a
look-ahead of the surface's rate): if both branches push the surface back to
zero, the run slides along it (Filippov: the convex combination of the two
vector fields that keeps the surface at zero) until one side lets go.
"""

from __future__ import annotations

import math
import time as _clock
from bisect import bisect_left, bisect_right
from dataclasses import dataclass

import numpy as np

from . import ir
from .codegen import Compiled, Compiler, evaluate_constant, fault_line, initial_values
from .diagnostics import AmilError, Diagnostic, Span
from .language import RESERVED
from .result import Event, EventKind, Run, Status
from .routes import DEFAULT, route_for
from .steppers import Hermite, OdeintStepper, make_stepper
from .surfaces import level, linear_gradient, sign
from .switching import SLIDE, Switching, _Surfaces

DEFAULTS = {
    "rtol": 1e-6,
    "atol": 1e-9,
    "max_steps": 5_000_000,
    "max_events": 200_000,
    "max_rows": 2_000_000,
}


@dataclass
class Options:
    method: str | None = None
    rtol: float | None = None
    atol: float | None = None
    events: bool = True
    outputs: list[str] | None = None
    max_steps: int = DEFAULTS["max_steps"]
    max_events: int = DEFAULTS["max_events"]
    max_rows: int = DEFAULTS["max_rows"]
    max_time: float | None = None  # wall-clock seconds
    start: dict | None = None  # continue from a previous run's final_state
    fintim: float | None = None  # run length instead of the listing's FINTIM
    progress: object = None  # callable(t, fintim, events, steps) or None


@dataclass
class _Grid:
    times: np.ndarray
    outdel: np.ndarray
    prdel: np.ndarray


def timer_values(spec: ir.RunSpec, route: str, fintim: float | None = None
                 ) -> dict[str, float]:
    """CSMP TIMER defaults: OUTDEL = FINTIM/100 and PRDEL = OUTDEL when neither is
    given; one given, the other takes its value; DELT divides the output interval."""
    t = dict(spec.timer)
    if fintim is not None:
        if not fintim > 0:
            raise AmilError(f"FINTIM must be positive (got {fintim:g})")
        t["FINTIM"] = fintim
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
    rows = fintim / interval
    if not rows <= DEFAULTS["max_rows"]:
        raise AmilError(f"FINTIM/{'OUTDEL' if t['OUTDEL'] <= t['PRDEL'] else 'PRDEL'} = "
                        f"{rows:.3g} output rows (limit {DEFAULTS['max_rows']}): raise "
                        "OUTDEL/PRDEL")
    if "DELT" in t:
        n = max(1, math.ceil(interval / t["DELT"] - 1e-9))
        t["DELT"] = interval / n
    else:
        t["DELT"] = interval / 16.0
    t.setdefault("DELMIN", 0.0)
    t.setdefault("DELMAX", math.inf)
    return t


def _grid(t0: float, fintim: float, step: float) -> np.ndarray:
    n = int(math.floor((fintim - t0) / step * (1 + 1e-12) + 1e-9))
    g = t0 + step * np.arange(n + 1)
    if fintim - g[-1] > 1e-9 * step:
        g = np.append(g, fintim)
    else:
        g[-1] = fintim
    return g


def _make_grid(t0: float, fintim: float, outdel: float, prdel: float) -> _Grid:
    go = _grid(t0, fintim, outdel)
    gp = _grid(t0, fintim, prdel)
    times = np.union1d(go, gp)
    return _Grid(times, np.isin(times, go), np.isin(times, gp))


class _Simulation(Switching):
    def __init__(self, model: ir.Model, spec: ir.RunSpec, opts: Options) -> None:
        self.model = model
        self.spec = spec
        self.opts = opts
        requested = opts.method or spec.method or DEFAULT
        route = route_for(requested)
        if route is None:
            raise AmilError(f"unknown integration method {requested}")
        self.route = route.name
        self.method = requested.upper()
        self.timer = timer_values(spec, route, opts.fintim)
        reserved = {k: self.timer[k] for k in ("FINTIM", "DELT", "PRDEL", "OUTDEL", "DELMIN",
                                               "DELMAX")}
        # INITIAL is compiled and evaluated once per set of data (sweeps and repeated
        # runs come back to the same values)
        ckey = ("initial", tuple(sorted(spec.data.items())), tuple(sorted(reserved.items())),
                repr(sorted(spec.tables.items())))
        if ckey not in model.memo:
            if len(model.memo) > 256:
                model.memo.clear()
            model.memo[ckey] = initial_values(model, spec.data, spec.tables, reserved)
        self.constants = dict(model.memo[ckey])
        const_modes = {}
        for s in model.surfaces:
            if s.depends == "impulse":
                const_modes[s.index] = 0.0
            if s.depends == "const":
                value = evaluate_constant(model, s.expr, self.constants, spec.tables, s.span)
                const_modes[s.index] = level(value) if s.kind == "level" else sign(value)
        if not opts.events:
            # event location off (for comparisons): every surface is still
            # evaluated, but crossings are only noticed at step ends
            pass
        key = (tuple(sorted(self.constants.items())), repr(sorted(spec.tables.items())),
               tuple(opts.outputs) if opts.outputs is not None else None, opts.events)
        if key not in model.compiled:
            if len(model.compiled) > 64:  # a long sweep: keep the cache small
                model.compiled.clear()
            model.compiled[key] = Compiler(model, self.constants, spec.tables, const_modes,
                                           opts.outputs, opts.events).build()
        self.c: Compiled = model.compiled[key]
        self.rtol = opts.rtol or spec.relerr or DEFAULTS["rtol"]
        atol = opts.atol or spec.abserr or DEFAULTS["atol"]
        names = self.c.state_names
        if spec.abserr_each or spec.relerr_each:
            vec = np.full(len(names), atol)
            for i, n in enumerate(names):
                vec[i] = spec.abserr_each.get(n, atol)
            self.atol = vec
            if spec.relerr_each:
                self.rtol = min([self.rtol] + list(spec.relerr_each.values()))
        else:
            self.atol = atol
        self.atol_scalar = float(np.min(self.atol))
        # AUTO drives Fortran LSODA over chunks of output instants. Memory functions
        # must see every accepted step, so a model with them takes the LSODA class.
        # ZHOLD and PULSE change their memory only where the run restarts anyway (an
        # event or a breakpoint), so they may too; the others need every step.
        self.fast = self.route == "AUTO" and not self.c.memory_every_step
        # a continued run (a sweep with carried state) goes on from its start TIME
        self.t0 = float(opts.start["t"]) if opts.start else 0.0
        self.fintim = self.t0 + self.timer["FINTIM"]
        self.delt = self.timer["DELT"]
        self._setup_surfaces()

    # ------------------------------------------------------------- surfaces
    def _setup_surfaces(self) -> None:
        c, model = self.c, self.model
        kinds, purposes, descs, grads, bp = [], [], [], [], []
        state_index = {n: i for i, n in enumerate(c.state_names)}
        for i in c.watched:
            s = model.surfaces[i]
            kinds.append(s.kind)
            purposes.append(s.purpose)
            descs.append(s.description)
            g = linear_gradient(s.expr, state_index, self.constants) \
                if s.kind == "sign" else None
            grads.append(None if g is None else np.asarray(g))
            bp.append(i in c.affine_time)
        self.sf = _Surfaces(kinds, purposes, descs, grads, bp)
        # breakpoints known before the run: roots of surfaces affine in TIME
        self.breakpoints: list[float] = []
        self.roots: dict[int, float] = {}
        y_dummy = list(c.y0)
        z0 = list(c.z0)
        m0 = [0.0] * len(c.watched)
        for k in range(len(c.watched)):
            if not bp[k]:
                continue
            root = self._affine_root(k, y_dummy, m0, z0)
            if root is not None and self.t0 < root < self.fintim:
                self.breakpoints.append(root)
                self.roots[k] = root
        t0 = self.t0
        for start, period in c.impulses:
            if period > 0:
                k0 = max(0, math.ceil((t0 - start) / period))
                n = int(min((self.fintim - start) / period, k0 + 1_000_000))
                self.breakpoints.extend(start + k * period for k in range(k0, max(n, -1) + 1)
                                        if t0 < start + k * period < self.fintim)
            elif t0 < start < self.fintim:
                self.breakpoints.append(start)
        self.breakpoints = sorted(set(self.breakpoints))

    def _affine_root(self, k: int, y, m, z) -> float | None:
        """The first float at which an affine time surface reaches zero."""
        def e(t: float) -> float:
            return self.c.surf(t, y, m, z)[k]

        t0 = self.t0
        e0, e1 = e(t0), e(self.fintim)
        slope = (e1 - e0) / (self.fintim - t0)
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

    # ---------------------------------------------------------------- rhs
    def rhs_for(self, m: list[float], z: list[float]):
        rhs = self.c.rhs
        slides = [k for k, v in enumerate(m) if v == SLIDE]
        bad: list = self.arith_faults

        if not slides:
            def f(t, y):
                try:
                    return rhs(t, y.tolist(), m, z)
                except (ArithmeticError, ValueError) as exc:
                    bad.append((t, exc))
                    return [math.nan] * len(y)
            return f

        k = slides[0]

        def f_slide(t, y):
            try:
                fp, fm, alpha = self.filippov(k, t, y, m, z)
            except (ArithmeticError, ValueError) as exc:
                bad.append((t, exc))
                return [math.nan] * len(y)
            return alpha * fp + (1.0 - alpha) * fm
        return f_slide

    def run(self) -> Run:
        c, opts = self.c, self.opts
        started = _clock.perf_counter()
        self.arith_faults: list = []
        start = opts.start
        t0 = self.t0
        y = np.array(start["y"] if start else c.y0, dtype=float)
        z = list(start["z"]) if start else list(c.z0)
        gkey = ("grid", t0, self.fintim, self.timer["OUTDEL"], self.timer["PRDEL"])
        if gkey not in self.model.memo:
            self.model.memo[gkey] = _make_grid(t0, self.fintim, self.timer["OUTDEL"],
                                               self.timer["PRDEL"])
        grid = self.model.memo[gkey]
        if len(grid.times) > opts.max_rows:
            raise AmilError([Diagnostic(
                f"the run would print {len(grid.times)} rows (limit {opts.max_rows})",
                None, "raise OUTDEL/PRDEL")], self.model.path, self.model.source)
        self.lookahead_h = 1e-8 * max(self.fintim - t0, abs(t0) * 1e-8)
        n_watch = len(c.watched)
        m = [0.0] * n_watch
        events: list[Event] = []
        nsteps = 0
        nfev = 0
        status, message = Status.FINISHED, ""
        rows = _Rows(len(c.out_names))
        warnings: list[str] = []
        stiff_noted = False
        slide_noted: set[int] = set()
        watch_idx = [k for k in range(n_watch) if not self.sf.breakpoint_only[k]]
        try:
            if start and "m" in start and len(start["m"]) == n_watch:
                m = list(start["m"])
            else:
                m = self.choose_modes(t0, y, z, m, set(), first=True)
            y = self.apply_resets(y, m)
            if c.z0:
                z[:] = c.mem(t0, y.tolist(), m, m, z)
            for k in range(n_watch):
                if m[k] == SLIDE:
                    self.note_slide(k, t0, warnings, slide_noted)
            out_i = 0
            times = grid.times


            def record(t: float, yv: np.ndarray, mv, g: int = -1) -> None:
                if g >= 0 and abs(t - times[g]) <= 1e-12 * max(abs(t), 1e-300):
                    t = float(times[g])  # print the grid instant, not a float next to it
                rows.add(t, g, self.outputs(t, yv, mv, z))

            # t0 row: a surface exactly at zero shows its X=0 branch (FSW's B)
            lit0 = c.modes_literal(t0, y.tolist(), m, z)
            record(t0, y, [0.0 if (lit0[k] == 0.0 and self.sf.kinds[k] == "sign"
                                   and m[k] != SLIDE) else m[k] for k in range(n_watch)], 0)
        except (ArithmeticError, ValueError) as exc:
            # a fault in the switching surfaces at the start (QNTZR with P = 0, say)
            line = self.c.fault_line(exc)
            where = f" (line {line})" if line else ""
            return self.result(_Rows(len(c.out_names)), grid, [], Status.FAILED,
                               f"cannot start at TIME = {t0:.9g}: {exc}{where}", [],
                               dict(nsteps=0, nfev=0, nevents=0, seconds=0.0), t0, y, z, m)
        out_i = 1
        t = t0
        stop_reason = None
        last_step = None
        recent_events: list[float] = []
        stepper = None
        # steps this short make no progress: FINTIM*1e-12 is ~4000 ulps of FINTIM
        h_floor = max(self.timer["DELMIN"], 1e-12 * (self.fintim - t0))
        tiny_steps = 0
        last_good = None
        try:
            if not np.all(np.isfinite(y)):
                bad = int(np.flatnonzero(~np.isfinite(y))[0])
                raise _Failure(t0, f"the initial value of {c.state_names[bad]} is not finite "
                                   f"({y[bad]:g})")
            while t < self.fintim and stop_reason is None:
                k_bp = bisect_right(self.breakpoints, t * (1 + 1e-15) + 1e-300)
                seg_end = self.fintim
                if k_bp < len(self.breakpoints):
                    seg_end = min(seg_end, self.breakpoints[k_bp])
                for end_time in self.pulse_ends(z, t):
                    seg_end = min(seg_end, end_time)
                f = self.rhs_for(m, z)
                if len(y):
                    # a derivative that is not finite where a segment starts can never
                    # give an accepted step: say so instead of shrinking the step forever
                    f0 = np.asarray(f(t, y), dtype=float)
                    if not np.all(np.isfinite(f0)):
                        bad = int(np.flatnonzero(~np.isfinite(f0))[0])
                        raise _Failure(t, f"the derivative of {c.state_names[bad]} is "
                                          f"{f0[bad]:g} at TIME = {t:.9g}" + self.fault_note())
                # never step over more than an output interval: a switch that goes
                # and comes back inside one step would be missed
                max_step = min(self.timer["DELMAX"], max(self.timer["OUTDEL"],
                                                         self.timer["PRDEL"]))
                checks = None
                # while a surface slides, step by step (LSODA's class): its exit is
                # seen at the step it happens, with no chunk integrated past it
                if self.fast and SLIDE not in m:
                    # the AUTO route steps from output instant to output instant
                    lo = bisect_right(times, t, out_i)
                    checks = times[lo:bisect_left(times, seg_end, lo)]
                # with nothing to watch nothing is thrown away after a chunk: one odeint
                # call per segment (a FINISH would throw away the rest of the run)
                chunk = 16 if watch_idx else 1 << 30
                stepper = make_stepper(self.route, f, t, y, seg_end, rtol=self.rtol,
                                       atol=self.atol, delt=self.delt, max_step=max_step,
                                       first_step=last_step, checks=checks, chunk=chunk)
                e_prev = c.surf(t, y.tolist(), m, z) if watch_idx else []
                self.segment_start = t
                bulk = isinstance(stepper, OdeintStepper) and SLIDE not in m
                restart = False
                while not restart:
                    if bulk:
                        # AUTO: take the clean part of an odeint chunk at once
                        taken, e_bulk = self.take_clean(stepper, m, z, seg_end, times, out_i,
                                                        watch_idx, rows)
                        if taken:
                            out_i += taken
                            nsteps += taken
                            t, y = stepper.t, stepper.y
                            if e_bulk is not None:
                                e_prev = e_bulk
                            if opts.max_time and _clock.perf_counter() - started > \
                                    opts.max_time:
                                raise _Failure(t, f"wall-clock limit of {opts.max_time:g} s "
                                                  "reached")
                            if opts.progress is not None:
                                opts.progress(t, self.fintim, len(events), nsteps)
                    err = stepper.step()
                    nsteps += 1
                    if err is not None:
                        bad = getattr(stepper, "bad_index", None)
                        unstable = getattr(stepper, "unstable", None)
                        if unstable is not None:
                            since, safe = unstable
                            err = f"{c.state_names[bad]} grows without bound from TIME = " \
                                  f"{since:.9g}: METHOD {self.method} is unstable with DELT " \
                                  f"= {self.delt:g} ({err}); take DELT below {safe:.2g} or " \
                                  "a variable-step method (METHOD AUTO)"
                        elif bad is not None:
                            err = f"{c.state_names[bad]} is no longer finite after TIME = " \
                                  f"{stepper.t:.9g}: {err}"
                        raise _Failure(stepper.t, err + self.fault_note())
                    ta, tb = stepper.t_old, stepper.t
                    yb = stepper.y
                    last_good = (tb, yb, m)
                    if stepper.stiff_at is not None and not stiff_noted:
                        stiff_noted = True
                        warnings.append(
                            f"stiff from TIME = {stepper.stiff_at:.6g}: the steps of METHOD "
                            f"{self.method} are limited by stability, not accuracy (h*|lambda| "
                            f"= {stepper.h_lambda:.3g}): METHOD AUTO or STIFF needs far fewer "
                            "steps")
                    if tb - ta < h_floor:
                        tiny_steps += 1
                        if tiny_steps >= 100:
                            big = int(np.argmax(np.abs(yb)))
                            raise _Failure(tb, "step size underflow: 100 steps shorter than "
                                               f"{h_floor:.3g} s; {c.state_names[big]} = "
                                               f"{yb[big]:.6g} (a finite-time singularity?)")
                    else:
                        tiny_steps = 0
                    if not np.all(np.isfinite(yb)):
                        bad = int(np.flatnonzero(~np.isfinite(yb))[0])
                        raise _Failure(ta, f"{c.state_names[bad]} is no longer finite "
                                           f"after TIME = {ta:.9g}" + self.fault_note())
                    triggered: set[int] = set()  # located at zero here
                    departed: set[int] = set()  # left a zero it sat on
                    truncated = False
                    exits: dict[int, float] = {}
                    stop_here = None
                    if watch_idx:
                        e_b = c.surf(tb, yb.tolist(), m, z)
                        hits = []
                        silent: list[int] = []
                        for k in watch_idx:
                            if m[k] == SLIDE:
                                continue
                            if self.crossed(k, m[k], e_prev[k], e_b[k]):
                                if self.silent(k, tb, yb, m, z):
                                    # its branch feeds nothing the states see now
                                    # (a switch inside an unused branch): follow
                                    # its sign, no need to stop and restart
                                    silent.append(k)
                                    continue
                                hits.append(k)
                        slide_exit = self.slide_exits(m, tb, yb, z)
                        if hits or slide_exit:
                            interp = stepper.interpolant()
                            roots = {}
                            for k in hits:
                                tk = self.locate(k, m, z, interp, ta, tb, e_prev[k], e_b[k])
                                if tk is None:
                                    departed.add(k)  # no crossing to bracket: sign at tb
                                else:
                                    roots[k] = tk
                            for k, sign in slide_exit:
                                roots[k] = self.locate_slide_exit(k, sign, m, z, interp, ta, tb)
                            t_star = min(roots.values(), default=tb)
                            if t_star < tb:
                                # the solver has moved past t_star: it must restart
                                stepper.truncate(t_star)
                                tb, yb = stepper.t, stepper.y
                                truncated = True
                            e_b = c.surf(tb, yb.tolist(), m, z)
                            close = 8 * np.finfo(float).eps * max(abs(tb), 1e-300)
                            triggered = {k for k, tk in roots.items() if tk - t_star <= close}
                            # leaving a sliding motion: the side it leaves to is known
                            exits = {k: sign for k, sign in slide_exit if k in triggered}
                        if silent and not truncated:
                            lit = self.c.modes_literal(tb, yb.tolist(), m, z)
                            for k in silent:
                                m[k] = lit[k]
                            e_b = c.surf(tb, yb.tolist(), m, z)
                        # a surface sitting at zero (mode 0) that has moved off it
                        for k in watch_idx:
                            if m[k] == 0.0 and self.sf.kinds[k] == "sign" and \
                                    abs(e_b[k]) > 1e-12 * (1 + abs(e_prev[k])) and e_b[k] != 0:
                                departed.add(k)
                        e_prev = e_b
                    # outputs inside (ta, tb); the one at tb waits for the new modes
                    while out_i < len(times) and times[out_i] < tb * (1 - 4e-16):
                        to = float(times[out_i])
                        yo = np.asarray(stepper.interpolant()(to), dtype=float)
                        if not np.all(np.isfinite(yo)) and np.all(np.isfinite(yb)):
                            # the dense output overflowed inside (DOP853's does near
                            # 1E300) while both ends are finite: a cubic through them
                            yo = Hermite(ta, y, np.asarray(f(ta, y), float), tb, yb,
                                         np.asarray(f(tb, yb), float))(to)
                        if not np.all(np.isfinite(yo)):
                            bad = int(np.flatnonzero(~np.isfinite(yo))[0])
                            raise _Failure(ta, f"{c.state_names[bad]} is no longer finite "
                                               f"after TIME = {ta:.9g}")
                        record(to, yo, m, out_i)
                        out_i += 1
                    at_output = out_i < len(times) and times[out_i] <= tb * (1 + 4e-16)
                    at_boundary = tb >= seg_end
                    if at_boundary and tb < self.fintim:
                        # a breakpoint: the surfaces on TIME that reach zero here decide anew
                        for k, root in self.roots.items():
                            if root == tb:
                                triggered.add(k)
                    if triggered or departed or (at_boundary and tb < self.fintim):
                        finish = [k for k in triggered if self.sf.purposes[k] in
                                  ("finish", "termt")]
                        new_m = self.choose_modes(tb, yb, z, m, triggered, forced=exits)
                        for k in finish:
                            fired = (self.sf.purposes[k] == "termt" and new_m[k] > 0) or \
                                    (self.sf.purposes[k] == "finish" and new_m[k] != m[k])
                            if fired:
                                stop_here = k
                        for k in range(n_watch):
                            if new_m[k] != m[k]:
                                if k not in triggered and self.silent(k, tb, yb, new_m, z):
                                    continue  # a branch nothing uses now: not an event
                                kind = EventKind.SLIDE if new_m[k] == SLIDE else \
                                    EventKind(self.sf.kinds[k].replace("sign", "switch"))
                                if self.sf.purposes[k] in ("finish", "termt"):
                                    kind = EventKind(self.sf.purposes[k])
                                if self.sf.breakpoint_only[k]:
                                    kind = EventKind.BREAKPOINT
                                last = next((e for e in reversed(events)
                                             if e.surface == c.watched[k]), None)
                                if last is not None and last.old == new_m[k] and \
                                        abs(last.time - tb) <= 1e-12 * max(abs(tb), 1e-300):
                                    # switched and switched back at one instant (noise
                                    # at a tangential crossing): nothing happened
                                    events.remove(last)
                                    continue
                                events.append(Event(tb, self.sf.descriptions[k],
                                                    c.watched[k], m[k], new_m[k], kind,
                                                    self.model.surfaces[c.watched[k]].text))
                                if new_m[k] == SLIDE:
                                    self.note_slide(k, tb, warnings, slide_noted)
                        if c.z0:
                            z[:] = c.mem(tb, yb.tolist(), m, new_m, z)
                        changed = new_m != m
                        m[:] = new_m
                        y = self.apply_resets(yb, m)
                        t = tb
                        if at_output:
                            # at a switching instant the printout shows the branch in
                            # force from then on; a surface exactly at zero shows its
                            # X=0 branch (FSW's B), as the function is defined
                            lit = c.modes_literal(tb, y.tolist(), m, z)
                            shown = [0.0 if (lit[k] == 0.0 and self.sf.kinds[k] == "sign"
                                             and m[k] != SLIDE) else m[k]
                                     for k in range(n_watch)]
                            record(tb, y, shown, out_i)
                            out_i += 1
                            at_output = False
                        if stop_here is not None:
                            stop_reason = stop_here
                            if rows.last_t != tb:
                                record(tb, y, m, -1)
                            break
                        if changed or at_boundary or truncated or not np.array_equal(y, yb):
                            recent_events.append(tb)
                            if len(events) > opts.max_events:
                                raise _Failure(tb, f"more than {opts.max_events} switching "
                                                   "events (raise --max-events)")
                            self.check_chatter(recent_events, events)
                            restart = True
                            last_step = max(tb - ta, 1e-12 * max(abs(tb), 1.0))
                            nfev += stepper.nfev
                            stepper = None
                            break
                    elif c.z0:
                        z[:] = c.mem(tb, yb.tolist(), m, m, z)
                    if at_output:
                        record(tb, yb, m, out_i)
                        out_i += 1
                    t = tb
                    y = yb
                    if at_boundary:
                        restart = True
                        nfev += stepper.nfev
                        stepper = None
                        break
                    if nsteps >= opts.max_steps:
                        raise _Failure(t, f"more than {opts.max_steps} steps (raise "
                                          "--max-steps, or check the model for stiffness)")
                    if opts.max_time and _clock.perf_counter() - started > opts.max_time:
                        raise _Failure(t, f"wall-clock limit of {opts.max_time:g} s reached")
                    if opts.progress is not None and nsteps % 200 == 0:
                        opts.progress(t, self.fintim, len(events), nsteps)
                    if self.z_changes_breakpoints(z, t, seg_end):
                        restart = True
                        nfev += stepper.nfev
                        stepper = None
                        break
            if stop_reason is not None:
                status = Status.STOPPED
                message = f"stopped at TIME = {t:.9g}: {self.sf.descriptions[stop_reason]}"
        except _Failure as fail:
            status = Status.FAILED
            message = f"integration failed at TIME = {fail.t:.9g}: {fail.reason}"
            t = fail.t
            # keep the last accepted state as the final row (everything computed)
            if last_good is not None and (rows.last_t is None or last_good[0] > rows.last_t) \
                    and \
                    np.all(np.isfinite(last_good[1])):
                record(last_good[0], np.asarray(last_good[1], float), last_good[2], -1)
                t, y = last_good[0], np.asarray(last_good[1], float)
        except KeyboardInterrupt:
            status = Status.FAILED
            message = f"interrupted at TIME = {t:.9g}"
        except (ArithmeticError, ValueError) as exc:
            # arithmetic in generated code (surfaces, outputs) or SciPy refusing
            # non-finite values: the run ends here, with what it computed so far
            status = Status.FAILED
            line = self.c.fault_line(exc)
            where = f" (line {line})" if line else ""
            message = f"integration failed at TIME = {t:.9g}: {exc}{where}"
        if stepper is not None:
            nfev += stepper.nfev
        if status == Status.FINISHED and out_i < len(times):
            record(self.fintim, y, m, len(times) - 1)
        return self.result(rows, grid, events, status, message, warnings,
                           dict(nsteps=nsteps, nfev=nfev, nevents=len(events),
                                seconds=_clock.perf_counter() - started),
                           t, y, z, m)

    # ---------------------------------------------------------------- helpers
    def note_slide(self, k, t, warnings, noted) -> None:
        if k in noted:
            return
        noted.add(k)
        warnings.append(f"sliding on {self.sf.descriptions[k]} from TIME = {t:.6g}: both "
                        "branches push it back to zero, so the run follows the motion that "
                        "keeps it there (Filippov)")

    def check_chatter(self, recent: list[float], events) -> None:
        if len(recent) < 200:
            return
        window = recent[-200:]
        span = window[-1] - window[0]
        if span <= 1e-9 * max(self.fintim, abs(window[-1])):
            what = f"{events[-1].switch} chatters" if events else "the run makes no progress"
            raise _Failure(window[-1], f"{what}: 200 restarts within {span:.3g} s "
                                       f"at TIME = {window[-1]:.9g}")
        del recent[:-200]

    def take_clean(self, stepper, m, z, seg_end, times, out_i, watch_idx, rows
                   ) -> tuple[int, list | None]:
        """Record at once the pending odeint instants before the first one that needs
        a look (a surface crossed, a non-finite state, the segment's end), using
        the surface and output functions over NumPy columns. Returns how many were
        taken and the surfaces at the last of them."""
        T, Y = stepper.pending()
        n = len(T)
        if n and T[-1] >= seg_end:
            n -= 1  # the segment's end is a breakpoint: the step-by-step path ends it
        if n == 0 or out_i + n > len(times) or T[0] != times[out_i]:
            return 0, None
        T, Y = T[:n], Y[:n]
        finite = np.isfinite(Y).all(axis=1)
        if not finite.all():
            n = int(np.argmin(finite))
        cols = list(Y[:n].T)
        e_last = None
        if n and watch_idx:
            with np.errstate(all="ignore"):
                E = [_column(v, n) for v in self.c.surf_v(T[:n], cols, m, z)]
            bad = np.zeros(n, bool)
            for k in watch_idx:
                mode = m[k]
                if self.sf.kinds[k] == "level" or mode > 0:
                    bad |= E[k] < 0.0
                elif mode < 0:
                    bad |= E[k] > 0.0
                else:
                    bad |= E[k] != 0.0
            if bad.any():
                n = int(np.argmax(bad))
                cols = [c[:n] for c in cols]
            e_last = [float(e[n - 1]) for e in E] if n else None
        if n == 0:
            return 0, None
        with np.errstate(all="ignore"):
            outs = self.c.out_v(T[:n], cols, m, z)
        table = np.column_stack([_column(v, n) for v in outs]) if outs else np.empty((n, 0))
        rows.add_block(T[:n], np.arange(out_i, out_i + n), table)
        stepper.consume(n)
        return n, e_last

    def pulse_ends(self, z, t) -> list[float]:
        return [e for e in self.c.memory_times(z, t) if e < self.fintim]

    def z_changes_breakpoints(self, z, t, seg_end) -> bool:
        return any(t < e < seg_end for e in self.pulse_ends(z, t))

    def outputs(self, t, y, m, z) -> list[float]:
        slides = [k for k, v in enumerate(m) if v == SLIDE]
        try:
            if not slides:
                return self.c.out(t, y.tolist(), m, z)
            k = slides[0]
            _, _, alpha = self.filippov(k, t, y, m, z)
            mp, mm = list(m), list(m)
            mp[k], mm[k] = 1.0, -1.0
            op = self.c.out(t, y.tolist(), mp, z)
            om = self.c.out(t, y.tolist(), mm, z)
            return [alpha * a + (1 - alpha) * b for a, b in zip(op, om, strict=True)]
        except (ArithmeticError, ValueError):
            return [math.nan] * len(self.c.out_names)

    def fault_note(self) -> str:
        if not self.arith_faults:
            return ""
        t, exc = self.arith_faults[-1]
        line = self.c.fault_line(exc)
        where = f" (line {line})" if line else ""
        return f"; last arithmetic fault at TIME = {t:.9g}{where}: {exc}"

    def result(self, rows, grid, events, status, message, warnings, stats,
               t, y, z, m) -> Run:
        names = self.c.out_names
        times, g, table = rows.arrays()
        values = {n: table[:, i].copy() for i, n in enumerate(names)}
        last = np.zeros(len(g), bool)
        if len(g):
            last[-1] = True  # the stop instant (FINISH, TERMT, failure) is always shown
        on_grid = g >= 0
        outdel_mask = last.copy()
        prdel_mask = last.copy()
        outdel_mask[on_grid] |= grid.outdel[g[on_grid]]
        prdel_mask[on_grid] |= grid.prdel[g[on_grid]]
        final = {k: float(v) for k, v in self.constants.items() if k not in RESERVED}
        final.update({n: float(v[-1]) for n, v in values.items()} if len(times) else {})
        for i, n in enumerate(self.c.state_names):
            if "#" not in n:
                final[n] = float(y[i])
        params = {k: v for k, v in self.constants.items()}
        return Run(
            label=self.spec.label, params=dict(self.spec.data), constants=params,
            times=times, values=values, outdel_mask=outdel_mask, prdel_mask=prdel_mask,
            events=events, status=status, message=message, final=final, stats=stats,
            method=self.method, rtol=self.rtol, atol=self.atol_scalar,
            settings=(f"RELERR {self.rtol:g}, ABSERR {self.atol_scalar:g}"
                      if route_for(self.method).uses_tolerances else f"DELT {self.delt:g}"),
            titles=list(self.spec.titles), reports=list(self.spec.reports),
            warnings=warnings, t_end=float(t),
            final_state={"t": float(t), "y": y.tolist(), "z": list(z), "m": list(m)},
        )


class _Rows:
    """The recorded output rows, in order: single rows from the step-by-step path,
    whole blocks from an odeint chunk (kept as arrays, never split into lists)."""

    def __init__(self, width: int) -> None:
        self.width = width
        self.blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.t: list[float] = []
        self.g: list[int] = []
        self.v: list[list[float]] = []
        self.last_t: float | None = None

    def add(self, t: float, g: int, values: list[float]) -> None:
        self.t.append(t)
        self.g.append(g)
        self.v.append(values)
        self.last_t = t

    def _flush(self) -> None:
        if self.t:
            self.blocks.append((np.asarray(self.t, float), np.asarray(self.g, int),
                                np.asarray(self.v, float).reshape(len(self.t), self.width)))
            self.t, self.g, self.v = [], [], []

    def add_block(self, t: np.ndarray, g: np.ndarray, values: np.ndarray) -> None:
        self._flush()
        self.blocks.append((t, g, values))
        self.last_t = float(t[-1])

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        self._flush()
        if not self.blocks:
            return np.empty(0), np.empty(0, int), np.empty((0, self.width))
        return tuple(np.concatenate(parts) for parts in zip(*self.blocks, strict=True))


class _Failure(Exception):
    def __init__(self, t: float, reason: str) -> None:
        super().__init__(reason)
        self.t = t
        self.reason = reason


def _column(v, n: int) -> np.ndarray:
    """A vector function's result as n values (a constant comes back as a float)."""
    if isinstance(v, np.ndarray) and v.shape == (n,):
        return v
    return np.full(n, float(v))


def simulate(model: ir.Model, spec: ir.RunSpec, options: Options | None = None) -> Run:
    """Integrate one run of a checked model. Faults in the data raise AmilError;
    a failing integration returns a Run with status FAILED and the rows so far."""
    try:
        sim = _Simulation(model, spec, options or Options())
    except (ArithmeticError, ValueError) as exc:
        # set-up evaluates constant parts (breakpoint instants, fixed branches):
        # a fault there is in the listing's data, shown at its line
        line = fault_line(exc)
        raise AmilError([Diagnostic(f"cannot be evaluated before the run: {exc}",
                                    Span(line, 1) if line else None,
                                    "check the constant expressions on that line")],
                        model.path, model.source) from None
    return sim.run()

