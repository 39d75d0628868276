"""Sensitivities of a program in ACSL form to data values: d (states, memory)(t)/d p
along one run, through its DISCRETE sections and DYNAMIC statements.

Between the program's instants the run is a flow whose derivatives also read the
memory values z the code keeps (a dose count, a rate the code sets): the tangent
`ProgramTangent` carries (y, z, p) with z' = 0 through the steps and the located
switches, as `ParameterTangent` does for a model. At an instant the code is a map
(y, z) -> (y', z') at a fixed TIME; the tangent takes its Jacobian, by central
differences of the generated section at that TIME (d/dy, d/dz) and of the same
section bound to p +- h (d/dp: no integration, the code only). A DOSE of AG = AG +
DOSE then gives d AG/d DOSE a jump of 1, exactly as the run does. A section that a
SCHEDULE crossing runs (.XN./.XP./.XZ.: a ball's impact) is at an instant the values
move, dt/dp = -(n . Phi)/rate: the code's map applies to the states as the instant
moves them, at the moved TIME (its code may read T: M_t, its rate in T), and the
field after it runs the shift back, J (Phi + f- dt) + (M_t - f+) dt.

An instant the code sets that the values move -- an INTERVAL computed from them,
INITIAL's SCHEDULE .AT. time, a SCHEDULE .AT. that DISCRETE code computes from the
values, the states or the memory (an infusion stopped at T + TLEN) -- is followed the
same way, its shift carried from one instant to the next (the k-th dose every TAU
moves by k dTAU): d t_s/d (y, z, p) along the tangent, and d t_s/d T times the
shift of the instant that schedules it.

What it does not follow it says, and the caller differences whole runs instead: the
sections code schedules changing with the values, a section due twice at instants
that move differently, a crossing the flow is tangent to, besides what
`ParameterTangent` does not follow."""

from __future__ import annotations

import time as _clock

import numpy as np

from ..run import Options
from ..run.acsl import AcslRun, prepare_acsl
from ..run.code import Calls
from ..run.flow import State
from ..run.jacobian import STEP
from ..run.plan import SAME_INSTANT, same_instant
from ..run.variational import ProgramTangent
from .tangents import Sampler, output_row, outputs_asked, start_slope, step_for


def bind_slopes(model, spec, c, names: list[str], constants: list[tuple[dict, dict, float]]
                ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(d P/d names for the constants P the generated functions read by name
    (`ParameterTangent.exact`), d y0/d names or None): from INITIAL's assignments
    where its code is only those (`codegen.consts.written_slopes`); where it is more
    (IFs, loops), 1 for a value itself and what INITIAL's code computes from the
    values by the central differences of the runs bound to each value moved
    (`constants`: their values, h), the start differenced. (None, None) where a
    value is folded into the code."""
    from ..codegen.consts import written_slopes
    from ..codegen.jacobian import by_parameter, parameter_names
    from ..run.acsl import initial_start

    if c.binder is None or any(name not in c.binder.parameters for name in names):
        return None, None
    found = written_slopes(model, names, initial_start(spec), c.constants, c.binder.tables)
    if found is not None:
        rows, ics = found
        return by_parameter(c, rows, len(names)), ics
    params = parameter_names(c)
    # (a value INITIAL assigns again -- Magnolia allows it -- is INITIAL's)
    again = {n for code in model.acsl.initial for n in code.assigned}
    out = np.zeros((len(params), len(names)))
    for i, p in enumerate(params):
        for j, (plus, minus, h) in enumerate(constants):
            out[i, j] = 1.0 if p == names[j] and p not in again else \
                (plus[p] - minus[p]) / (2.0 * h)
    return out, None


class _Jumped(Exception):
    """The tangent cannot follow an instant's code (why)."""


def program_trajectory(model, k: int, names: list[str], data: dict[str, float],
                       options: dict, times, variables: list[str] | None = None):
    """Run `k`'s tangent with respect to `names` at `times` (sorted), or why the
    tangent cannot follow it: a `ProgramTrajectory` or a str. `variables`: the outputs
    it will be asked for (default every one)."""
    from ..diagnostics import AmilError

    def prepared_at(**changed):
        spec = model._specs({**data, **changed})[k]
        opts = Options(method=options.get("method"), rtol=options.get("rtol"),
                       atol=options.get("atol"))
        return spec, opts, prepare_acsl(model.ir, spec, opts, model.cache)

    spec, opts, base = prepared_at()
    plan, c = base.plan, base.code
    if plan.step_point or not plan.route.uses_tolerances:
        return "a fixed-step route has no dense output for the sensitivity equations"
    n, r = len(c.y0), len(c.z0)
    variants, start = [], np.zeros((n + r, len(names)))
    # the instants INITIAL schedules (.AT.) and the INTERVALs, as the values move them
    moved_at = np.zeros((len(base.schedules), len(names)))
    constants: list[tuple[dict, dict, float]] = []
    for j, name in enumerate(names):
        h = step_for(data[name], STEP)
        try:
            plus, minus = prepared_at(**{name: data[name] + h})[2], \
                prepared_at(**{name: data[name] - h})[2]
        except AmilError as exc:
            return f"{name} moved by {h:.3g}: {exc}"
        if any((v.code.watched, v.code.state_names, v.code.out_names, v.code.kept,
                len(v.code.z0)) != (c.watched, c.state_names, c.out_names, c.kept, r)
               for v in (plus, minus)):
            return f"{name} changes which switches the run watches"
        if [s for _, s in plus.schedules] != [s for _, s in base.schedules] or \
                [s for _, s in minus.schedules] != [s for _, s in base.schedules]:
            return f"INITIAL schedules other sections as {name} moves"
        moved_at[:, j] = [(a - b) / (2.0 * h) for (a, _), (b, _) in
                          zip(plus.schedules, minus.schedules, strict=True)]
        constants.append((plus.constants, minus.constants, h))
        variants.append((plus.code, minus.code, h))
        start[:, j] = start_slope(np.concatenate([plus.code.y0, plus.code.z0]),
                                  np.concatenate([minus.code.y0, minus.code.z0]), h)
    floor = np.broadcast_to(np.asarray(plan.tol.atol / plan.tol.rtol, dtype=float), (n,))
    exact, ics = bind_slopes(model.ir, spec, c, names, constants)
    if ics is not None:  # (the states' start from its equations; the memory's differenced)
        start[:n] = ics
    tangent = ProgramTangent(c, None, floor, start, variants, r, outputs_asked(c, variables),
                             exact)
    if c.clock_slots:  # (a store whose instants a free delay may move: `along_clock`)
        tangent.make_halves = lambda: [(prepared_at(**{name: data[name] + 0.5 * h})[2].code,
                                        prepared_at(**{name: data[name] - 0.5 * h})[2].code)
                                       for name, (_, _, h) in zip(names, variants, strict=True)]
    times = np.asarray(times, dtype=float)
    sampler = Sampler(tangent, times, n + r)
    run = _TangentRun(model.ir, spec, opts, base, _clock.perf_counter(), sampler, variants,
                      constants, moved_at)
    tangent.watch = run.watch
    result = run.run()
    if run.why is not None:
        return run.why
    if tangent.failed is not None:
        return tangent.failed
    if not result.ok:
        return f"the run failed: {result.message}"
    end = tangent.prev
    for t in times.tolist():
        # (a row the run prints at the instant it stops, TERMT located at T = 1.2, on
        # a grid whose 12th CINT is 1.2000000000000002: its state is the end's)
        if t not in sampler.at and end is not None and same_instant(t, end[0]):
            sampler.at[t] = (State(end[1].copy(), tuple(end[2]), tuple(end[3]), t),
                             tangent.phi[:n + r].copy())
    missing = [t for t in times.tolist() if t not in sampler.at]
    if missing:
        return f"the run's steps did not reach TIME = {missing[0]:.9g}"
    return ProgramTrajectory(c, variants, floor, sampler.at, run.watch,
                             lambda: tangent.halves)


class _TangentRun(AcslRun):
    """An ACSL run whose accepted steps the tangent follows (`observer`), and whose
    instants' code it takes the Jacobian of before the code runs."""

    def __init__(self, model, spec, opts, prepared, started, sampler, variants,
                 constants, moved_at) -> None:
        super().__init__(model, spec, opts, prepared, started)
        self.observer, self.sampler, self.variants = sampler, sampler, variants
        self.keys = {id(fn): key for key, (_, fn) in self.c.code.items()}
        self.why: str | None = None
        # d/dp of the instant each section is due at next, where the values move it
        # (an INTERVAL computed from them, INITIAL's .AT. time), and the constants of
        # the moved runs (an INTERVAL's value)
        self.moved_constants = constants
        self.due_moved: dict[str, np.ndarray] = {
            section: moved_at[i] for i, (_, section) in enumerate(prepared.schedules)
            if np.any(moved_at[i])}

    @property
    def tangent(self) -> ProgramTangent:
        return self.sampler.tangent

    def run_code(self, cur, fn, what: str) -> Calls:
        matrix, moving, rate, scheduled = None, None, None, None
        section = what.removeprefix("DISCRETE ")
        shift = self.due_moved.pop(section, None)
        if self.why is None and self.tangent.failed is None:
            try:
                matrix, scheduled = self._code_jacobian(cur, fn)
                moving = self._crossing_shift(cur, what)
                if moving is None and shift is not None:
                    moving = shift, self.tangent.field_rows(cur.t, cur.y, list(cur.m),
                                                            list(cur.z))
                schedule_rate = None
                if moving is not None:  # (the code may read T: AG = AG + 20 T)
                    rate, schedule_rate = self._code_rate(cur, fn)
                self._schedules_moved(scheduled, moving, schedule_rate)
            except _Jumped as exc:
                self.why = f"{what} at TIME = {cur.t:.9g}: {exc}"
        calls = super().run_code(cur, fn, what)
        d = self.acsl.discretes.get(section) if what.startswith("DISCRETE ") else None
        if d is not None and d.interval is not None and matrix is not None:
            # (its next instant: this one's shift and the INTERVAL's own dependence)
            gap = self._interval_moved(d.interval)
            after = (moving[0] if moving is not None else 0.0) + gap
            if np.any(after):
                self.due_moved[section] = after
        if matrix is not None:
            # (where the section ran at an instant the values move: the code's map at
            # the moved instant, `ParameterTangent.map_at`)
            t = self.tangent
            moved = None if moving is None else \
                (*moving, t.field_rows(cur.t, cur.y, list(cur.m), list(cur.z)), rate)
            t.jump(matrix, cur.t, cur.y, cur.m, cur.z, moved)
        return calls

    def _schedules_moved(self, scheduled, moving, schedule_rate) -> None:
        """The instants the code schedules (SCHEDULE OFF .AT. T + TLEN), as the values
        move them: d t_s/d (y, z, p) (`_code_jacobian`) along the tangent before the
        code (the states' total derivative where this instant moves), and d t_s/d T
        (`schedule_rate`) times this instant's own shift. Kept for when that section
        runs (`due_moved`); two pending instants of one section that move differently
        the tangent cannot tell apart."""
        if not scheduled:
            return
        t = self.tangent
        rows, sections = scheduled
        size = t.n + t.r
        # (where this instant moves, the states the code reads are the ones there, and
        # its T too: Phi + f- dt, and d t_s/d T dt)
        total = t.phi[:size] if moving is None else \
            t.phi[:size] + np.outer(moving[1][:size], moving[0])
        shifts = rows[:, :size] @ total + rows[:, size:]
        if moving is not None:
            shifts = shifts + np.outer(schedule_rate, moving[0])
        for section, moved in zip(sections, shifts, strict=True):
            if not np.any(moved):
                continue
            pending = self.due_moved.get(section)
            if pending is not None and not np.allclose(pending, moved, rtol=1e-9,
                                                       atol=1e-12):
                raise _Jumped(f"DISCRETE {section} is due twice at instants that move "
                              "differently")
            self.due_moved[section] = moved

    def _interval_moved(self, name: str) -> np.ndarray:
        """d/dp of an INTERVAL's value: its tangent row where the code keeps it, else
        the moved runs' constants."""
        t, kept = self.tangent, self.c.kept
        if name in kept:
            return t.phi[t.n + t.r - len(kept) + kept.index(name)].copy()
        return np.array([(plus.get(name, 0.0) - minus.get(name, 0.0)) / (2.0 * h)
                         for plus, minus, h in self.moved_constants])

    def _crossing_shift(self, cur, what: str) -> tuple[np.ndarray, np.ndarray] | None:
        """(d t/d p of this instant, the field before the code in the tangent's rows)
        where the section runs because a SCHEDULE crossing fired here (.XN. H: a
        ball's impact, which G and H0 move), else None."""
        at, fired = self.fired_at
        if not fired or not same_instant(at, cur.t):
            return None
        plan, t = self.plan, self.tangent
        section = what.removeprefix("DISCRETE ")
        ks = [k for k in fired if self.acsl.crossings[plan.watched[k].surface][0] == section]
        if not ks:
            return None
        k = ks[0]
        y, m, z = np.asarray(cur.y, dtype=float), list(cur.m), list(cur.z)
        # (the crossing's rate as a switch's jump takes it: no field change here)
        jump = t._jump(k, cur.t, y, m, m, z, z)
        if jump is None or jump[2] is None:
            raise _Jumped(t.failed or "the crossing that runs it has no rate")
        g, _, rate = jump
        return t.shift_of(g, t._by_data("surf", cur.t, y, m, z)[k], rate), \
            t.field_rows(cur.t, y, m, z)

    def _start(self, y: np.ndarray, z: list[float]):
        self._unstarted = list(z)
        return super()._start(y, z)

    def first_row(self, cur) -> None:
        # (the memory's update at t0 -- a DELAY store starting, its first sampling
        # instant t0 + TDL/NMX -- follows the start the values moved, as the flow's
        # `initial_state` has it in the tangent's start: the store's clock rows from
        # there, not from the update at the first step's end; before the code at t0,
        # as the run has it)
        t = self.tangent
        if self.c.clock_slots and list(cur.z) != self._unstarted and t.failed is None:
            t._update_memory(cur.t, np.asarray(cur.y, dtype=float), list(cur.m), list(cur.m),
                             self._unstarted, list(cur.z))
        super().first_row(cur)

    def instant(self, cur) -> None:
        t = self.tangent
        if t.prev is not None and t.failed is None:
            # a switch of the flow at this very instant (a breakpoint: a PULSE ends
            # at a CINT instant) jumps the tangent before the code runs
            t._join(cur.t, np.asarray(cur.y, dtype=float), list(cur.m), list(cur.z))
        t.prev = (cur.t, cur.y.copy(), list(cur.m), list(cur.z))
        modes = list(cur.m)
        super().instant(cur)
        self._branches_chosen_again(cur, modes)
        # the instant's row is after its code, and so is the tangent read there
        t.prev = (cur.t, cur.y.copy(), list(cur.m), list(cur.z))
        times = self.sampler.times
        i = int(np.searchsorted(times, cur.t - SAME_INSTANT * max(1.0, abs(cur.t))))
        if i < len(times) and same_instant(cur.t, float(times[i])):
            self.sampler.at[float(times[i])] = (
                State(cur.y.copy(), tuple(cur.m), tuple(cur.z), cur.t),
                t.phi[:t.n + t.r].copy())

    def _branches_chosen_again(self, cur, modes: list) -> None:
        """The branches the run chose again after the instant's code: a switch on
        TIME due now (a breakpoint, whose sign is already the new one: a PULSE that
        ends at a CINT instant) is the flow's, with its jump (none, unless a data
        value moves its instant: then the tangent says so); one on the states is
        the code's doing, at an instant fixed in time: none."""
        t = self.tangent
        y, z = np.asarray(cur.y, dtype=float), list(cur.z)
        for k in range(len(modes)):
            if t.failed is not None or cur.m[k] == modes[k] or \
                    np.any(t._gradient(k, cur.t, y, modes, z)):  # (a switch on the states)
                continue
            after = list(modes)
            after[k] = cur.m[k]
            jump = t._saltation(k, cur.t, y, modes, after, z, z)
            if jump is None:
                return
            t._phi = jump @ t.phi
            modes = after

    def _code_rate(self, cur, fn) -> tuple[np.ndarray, np.ndarray]:
        """d/d TIME of the section `fn` at the cursor: of (y', z'), in the tangent's rows
        (what it gives at an instant the values move beyond the states it is given),
        and of each instant it schedules."""
        t = self.tangent
        h = STEP * max(abs(cur.t), 1.0)
        out = np.zeros(len(t.phi))
        sides, times = [], []
        for at in (cur.t + h, cur.t - h):
            calls = Calls()
            try:
                y1, z1, _ = fn(at, cur.y.tolist(), list(cur.m), list(cur.z), calls)
            except (ArithmeticError, ValueError) as exc:
                raise _Jumped(f"its code has no value near the run's ({exc})") from None
            sides.append(np.concatenate([np.asarray(y1, dtype=float),
                                         np.asarray(z1, dtype=float)]))
            times.append(np.array([when for when, _ in calls.schedules], dtype=float))
        if times[0].shape != times[1].shape:
            raise _Jumped("the sections it schedules change with TIME")
        out[:t.n + t.r] = (sides[0] - sides[1]) / (2.0 * h)
        return out, (times[0] - times[1]) / (2.0 * h)

    def _code_jacobian(self, cur, fn) -> tuple[np.ndarray, tuple | None]:
        """d (y', z') / d (y, z, p) of the section `fn` at the cursor, and of the times
        it schedules: (their rows d t_s / d (y, z, p), their sections), None if it
        schedules none."""
        tangent = self.tangent
        n, r, q = tangent.n, tangent.r, len(self.variants)
        t, m, y, z = cur.t, list(cur.m), np.asarray(cur.y, dtype=float), list(cur.z)

        def run(f, yv, zv):
            calls = Calls()
            try:
                y1, z1, _ = f(t, list(yv), m, list(zv), calls)
            except (ArithmeticError, ValueError) as exc:
                raise _Jumped(f"its code has no value near the run's ({exc})") from None
            return np.concatenate([np.asarray(y1, dtype=float),
                                   np.asarray(z1, dtype=float)]), calls.schedules

        center, schedules = run(fn, y.tolist(), z)
        sections = [what for _, what in schedules]
        timing = np.zeros((len(schedules), n + r + q))

        def times_of(got, what: str) -> np.ndarray:
            # the same sections in the same order, at times the move may change
            if [w for _, w in got] != sections:
                raise _Jumped(f"the sections it schedules depend on {what}")
            return np.array([t_s for t_s, _ in got], dtype=float)

        moving = np.any(tangent.phi[:n + r] != 0.0, axis=1)  # (what the values move)

        def column(hi, lo, width: float, moved: bool) -> np.ndarray:
            # an IF whose test turns between the two: the code jumps, no derivative --
            # which matters only along a variable the data values move (a counter
            # T >= TD at TD = T as the run starts does not)
            ahead, behind = (hi - center) / (0.5 * width), (center - lo) / (0.5 * width)
            if moved and np.any(np.abs(ahead - behind) >
                                1e-3 * (np.abs(ahead) + np.abs(behind)) +
                                1e-7 * (np.abs(center) + 1.0) / width):
                raise _Jumped("its code jumps there (an IF whose test turns with the value)")
            return (hi - lo) / width

        v = np.concatenate([y, np.asarray(z, dtype=float)])
        scale = np.concatenate([np.maximum(np.abs(y), tangent.floor),
                                np.maximum(np.abs(v[n:]), 1.0)])
        out = np.eye(n + r + q)
        for j in range(n + r):
            if j >= n and not moving[j]:
                # (a memory value no data value moves: its column meets a zero row of
                # the tangent, and the fields it is moved along have none past the
                # states. A DELAY store's count, moved by a difference's step, read
                # its ring an entry off: "older than the store keeps")
                continue
            h = STEP * scale[j]
            up, down = v.copy(), v.copy()
            up[j] += h
            down[j] -= h
            hi, s_hi = run(fn, up[:n].tolist(), up[n:].tolist())
            lo, s_lo = run(fn, down[:n].tolist(), down[n:].tolist())
            timing[:, j] = (times_of(s_hi, "the states or memory") -
                            times_of(s_lo, "the states or memory")) / (up[j] - down[j])
            out[:n + r, j] = column(hi, lo, up[j] - down[j], bool(moving[j]))
        key = self.keys[id(fn)]
        for j, (plus, minus, h) in enumerate(self.variants):
            hi, s_hi = run(plus.code[key][1], y.tolist(), z)
            lo, s_lo = run(minus.code[key][1], y.tolist(), z)
            timing[:, n + r + j] = (times_of(s_hi, "a data value") -
                                    times_of(s_lo, "a data value")) / (2.0 * h)
            out[:n + r, n + r + j] = column(hi, lo, 2.0 * h, True)
        return out, ((timing, sections) if sections else None)


class ProgramTrajectory:
    """d (state or output)(t)/d p at the instants asked for (`program_trajectory`)."""

    def __init__(self, code, variants, floor: np.ndarray, at: dict[float, tuple],
                 watch, halves=None) -> None:
        self.code, self.variants, self.floor, self.at = code, variants, floor, at
        self.watch, self.halves = watch, halves
        self.states = {name: i for i, name in enumerate(code.state_names)}
        self.outputs = {name: i for i, name in enumerate(code.out_names)}

    def row(self, name: str, t: float) -> np.ndarray:
        """d name(t) / d p, a value per data value."""
        state, sens = self.at[t]
        if name in self.states:
            return sens[self.states[name]]
        return output_row(self.code, self.variants, self.outputs[name], t, state, sens,
                          self.floor, self.watch, self.halves)
