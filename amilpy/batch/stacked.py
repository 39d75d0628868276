"""An ensemble integrated at once: every member's states side by side in one
system, the generated right-hand side evaluated over a member axis (NumPy), one
LSODA integration (odeint) for all of them, as a competent user would write it by
hand when the members share their switching instants. The system's Jacobian is
banded (each member's block on its diagonal, the states numbered to narrow the
block), its blocks from the model's generated Jacobian over the same columns
(`lsoda`).

Which ensembles (`why_not`): a listing on a variable-step route with nothing that
makes a member's run its own -- no watched switching surface (a member would
switch at its own instants), no memory function, delay, random draw or weather,
no breakpoints, resets or settled states, no FINISH -- and members whose true
constants (CONST, TIMER and what INITIAL works out from them) are the same, so
that one build serves them all. In CSMP form, no TERMINAL section either. In ACSL
form (`run_acsl`) the members share their instants when their DISCRETE sections
run every INTERVAL or where SCHEDULE puts them (the same for every member), their
TERMTs are on TIME alone (the same instant for every member) and there are no
SCHEDULEs at crossings: the stacked system is integrated from one such instant
(and, with DYNAMIC statements, one CINT instant) to the next, and the DISCRETE,
DYNAMIC and TERMINAL code runs there on the members' columns (plain arithmetic
runs elementwise; code that branches on a member's value runs member by member,
each with its own functions). Anything else runs member by member
(`montecarlo.run_sets`), as before.

Accuracy. LSODA's error test takes the weighted max-norm over every component
(ODEPACK's DVMNRM), so each member's local error is held to the tolerances it
would be held to alone; the step size is the one the hardest member needs. The
values at the output instants are LSODA's own (it steps past and interpolates, as
the AUTO route's odeint chunks do). `tests/test_montecarlo.py` compares the two
routes' quantiles member by member.
"""

from __future__ import annotations

import math

import numpy as np

from ..diagnostics import AmilError
from ..result import Status
from .members import Batch, Member

MXSTEP = 500_000  # odeint's steps per output interval (its default 500 is too few here)
# states in one stacked integration: LSODA's work array holds 3n + 10 values a state
# for n states a member (its banded Jacobian), allocated by every call
MAX_EQUATIONS = 16_384


def why_not(model, code, plan, opts) -> str | None:
    """Why this ensemble cannot be integrated at once (None: it can)."""
    ir = model.ir
    acsl = ir.acsl
    if plan.step_point or not plan.route.uses_tolerances:
        return "a fixed-step route"
    if any(not _termt_on_time(code, w) for w in plan.watched) or \
            (acsl is None and code.watched):
        return "the members switch at their own instants"
    if ir.units:
        return "statements (IF blocks, loops) run one row at a time"
    if code.z0[:len(code.z0) - len(code.kept)] or ir.memories or ir.weather or \
            code.sample is not None or code.memory_trains or code.seen_times:
        return "memory functions, delays, random draws or weather"
    if set(plan.breakpoints) - set(plan.roots.values()) or plan.resets or \
            code.settle is not None or code.impulses or code.trains:
        return "breakpoints, resets or settled states"
    if acsl is None and (ir.terminal or ir.terminal_code):
        return "a TERMINAL section (it runs per member)"
    if acsl is not None:
        if acsl.crossings:
            return "a SCHEDULE at a crossing (each member crosses at its own instant)"
        if acsl.cint_name in code.kept or any(
                d.interval in code.kept for d in acsl.discretes.values()):
            return "CINT or an INTERVAL assigned during the run"
    if opts.extrema:
        return "extremes located between the rows (per member)"
    if not ir.states:
        return "no states to integrate"
    if opts.max_time:
        return "a time limit for each run"
    if code.binder is None:
        return "no build to share"
    return None


def _termt_on_time(code, w) -> bool:
    """A TERMT on TIME alone (an ACSL program's end): every member that shares its
    root stops at the same instant."""
    from ..run.plan import Purpose

    return w.purpose is Purpose.TERMT and w.surface in code.affine_time


def run_stacked(model, base, sets: dict[str, np.ndarray], runs: int, variables: list[str],
                opts) -> Batch | None:
    """The ensemble at once (see the module): `runs` runs of spec `base` with `sets`'
    values, `opts` their options; None when it cannot be (`why_not`) or LSODA fails on
    the stacked system (the members then run one by one). At most MAX_EQUATIONS
    states in one integration: larger ensembles go in parts of that size."""
    if runs < 2:
        return None
    route = run_acsl if model.ir.acsl is not None else _run_csmp
    part = max(1, MAX_EQUATIONS // max(len(model.ir.states), 1))
    members: list = []
    for lo in range(0, runs, part):
        got = route(model, base, {n: v[lo:lo + part] for n, v in sets.items()},
                    min(part, runs - lo), variables, opts)
        if got is None:
            return None
        members += got.members
    between = " from one DISCRETE instant to the next" if model.ir.acsl is not None else ""
    parts = f", in {math.ceil(runs / part)} parts of {part}" if runs > part else ""
    return Batch(members, {}, how=f"the {runs} runs integrated at once (none switches on "
                 f"its own): LSODA over every member's states{between}{parts}")


def _run_csmp(model, base, sets: dict[str, np.ndarray], runs: int, variables: list[str],
              opts) -> Batch | None:
    """`run_stacked` for a listing in CSMP form: one LSODA integration over the
    output grid."""
    from ..codegen.consts import evaluate_constant, initial_values
    from ..run import prepare
    from ..run.plan import reserved_values

    first = base.overridden({n: float(v[0]) for n, v in sets.items()})
    try:
        prepared = prepare(model.ir, first, opts, model.cache)
    except AmilError:
        return None  # (the first member's fault: one by one, with its message)
    code, plan = prepared.code, prepared.plan
    if why_not(model, code, plan, opts) is not None:
        return None
    binder = code.binder
    fixed = {k: v for k, v in code.constants.items() if k not in binder.parameters}
    reserved = reserved_values(plan.timer)
    per_member: list[dict[str, float]] = []
    for k in range(runs):
        data = {**base.data, **{n: float(v[k]) for n, v in sets.items()}}
        try:
            constants = initial_values(model.ir, data, base.tables, reserved)
        except (ArithmeticError, ValueError):
            return None  # (a member whose INITIAL faults: one by one, with its message)
        if any(constants.get(n) != v for n, v in fixed.items()
               if not (isinstance(v, float) and math.isnan(v))):
            return None  # (a drawn value changes a true constant: another build)
        per_member.append(constants)
    values = {n: shared_or_columns([c[n] for c in per_member]) for n in binder.parameters}
    functions = binder.over_members(values)
    rhs, out = functions["rhs_vec"], functions["out_vec"]
    states = model.ir.states
    y0 = np.array([[evaluate_constant(model.ir, s.ic, c, base.tables, s.span)
                    for c in per_member] for s in states])  # (states, members)
    n = len(states)
    times = plan.grid.times
    try:
        with np.errstate(all="ignore"):
            ys, steps = lsoda(lambda t, cols: rhs(t, cols, [], []), y0, times, plan,
                              with_branches(members_jacobian(code, values), [], []))
            if ys is None or steps > opts.max_steps:
                return None
            outs = out(times[:, None], [ys[:, i, :] for i in range(n)], [], [])
    except (ArithmeticError, ValueError, TypeError):
        # (a function with no elementwise form, a fault: the members one by one, where
        # a fault is located and said)
        return None
    index = {name: i for i, name in enumerate(code.out_names)}
    members = []
    for k in range(runs):
        cols = []
        for name in variables:
            if name in index:
                cols.append(np.broadcast_to(np.asarray(outs[index[name]], dtype=float),
                                            (len(times), runs))[:, k])
            else:
                cols.append(np.full(len(times), per_member[k].get(name, math.nan)))
        values_k = np.column_stack(cols) if cols else np.empty((len(times), 0))
        members.append(Member(times, plan.grid.prdel, values_k, tuple(values_k[-1].tolist()),
                              {}, str(Status.FINISHED), ""))
    return Batch(members, {})


def run_acsl(model, base, sets: dict[str, np.ndarray], runs: int, variables: list[str],
             opts) -> Batch | None:
    """`run_stacked` for a program in ACSL form (see the module), in the order one run
    of it takes (`run.acsl.AcslRun`): at each instant the DISCRETE sections due, in
    queue order, then the TERMT test, then the row; between instants one LSODA
    integration of every member's states. None when it cannot be."""
    import heapq

    from ..codegen.consts import evaluate_constant
    from ..outcome import message
    from ..run.acsl import (
        initial_reads,
        initial_start,
        prepare_acsl,
        run_initial,
        run_values,
        termination,
    )
    from ..run.code import Calls
    from ..run.plan import same_instant, within
    from ..run.prepare import Cache
    from ..run.record import close_to
    from ..run.watch import literal_modes

    ir = model.ir
    acsl = ir.acsl
    first = base.overridden({n: float(v[0]) for n, v in sets.items()})
    try:
        prepared = prepare_acsl(ir, first, opts, model.cache)
    except AmilError:
        return None  # (the first member's fault: one by one, with its message)
    code, plan = prepared.code, prepared.plan
    if why_not(model, code, plan, opts) is not None or prepared.stop is not None or \
            prepared.unbounded:
        return None
    binder = code.binder
    fixed = {k: v for k, v in code.constants.items() if k not in binder.parameters}
    # what sets the instants: the same for every member, or one by one
    shared = [acsl.cint_name] + [d.interval for d in acsl.discretes.values() if d.interval]
    scratch = Cache()  # (INITIAL per member: kept out of the model's own cache)
    # INITIAL once, where it neither reads nor assigns a drawn value (its values are
    # every member's then)
    once = None if set(sets) & initial_reads(ir) else run_initial(ir, first, scratch)
    members: list[tuple[dict[str, float], dict[str, float]]] = []
    priors0 = None
    with np.errstate(all="ignore"):
        for k in range(runs):
            spec = base.overridden({n: float(v[k]) for n, v in sets.items()})
            try:
                start, values, schedules, stop = run_initial(ir, spec, scratch) \
                    if once is None else (initial_start(spec), *once[1:])
            except (ArithmeticError, ValueError):
                return None  # (a member whose INITIAL faults: one by one, with its message)
            constants, kept, priors = run_values(ir, start, values)
            priors0 = priors if priors0 is None else priors0
            if schedules != prepared.schedules or stop is not None or priors != priors0 or any(
                    constants.get(n) != v for n, v in fixed.items()
                    if not (isinstance(v, float) and math.isnan(v))) or any(
                    constants.get(n) != code.constants.get(n) for n in shared):
                return None  # (another build, or instants of its own)
            members.append((constants, kept))
    values = {n: shared_or_columns([c[n] for c, _ in members]) for n in binder.parameters}
    functions = binder.over_members(values)
    rhs, out, surf = functions["rhs_vec"], functions["out_vec"], functions["surf_vec"]
    jacobian = members_jacobian(code, values)
    states = ir.states
    n = len(states)
    try:
        y = np.array([[evaluate_constant(ir, s.ic, {**c, **kept}, base.tables, s.span)
                       for c, kept in members] for s in states], dtype=float).reshape(n, runs)
    except (ArithmeticError, ValueError, KeyError):
        return None
    z = [np.array([kept[name] for _, kept in members]) for name in code.kept]
    m = literal_modes(code, plan, plan.t0, list(code.y0), [0.0] * len(plan.watched),
                      list(code.z0))

    def columns(x) -> np.ndarray:
        return np.broadcast_to(np.asarray(x, dtype=float), (runs,)).copy()

    # the TERMTs on TIME: every member's root on the same float as the first's
    stop_at, stop_what = math.inf, ""
    for k, w in enumerate(plan.watched):
        root = plan.roots.get(k)
        probes = (math.nextafter(root, -math.inf), root) if root is not None else \
            (plan.t0, plan.fintim)
        with np.errstate(all="ignore"):
            signs = [np.sign(columns(surf(t, list(y), m, z)[k])) for t in probes]
        if any(not np.all(sg == sg[0]) for sg in signs):
            return None  # (a drawn value moves the TERMT's instant)
        if root is not None and root < stop_at:
            stop_at, stop_what = root, w.description
    nw = len(code.kept)
    fns = {d.name: f"discrete_{k}" for k, d in enumerate(acsl.discretes.values())}
    bound: dict[int, dict] = {}

    def section(name: str, t: float, y: np.ndarray, z: list[np.ndarray]):
        """Written-order code `name` on every member: (states, kept, values, calls).
        On the columns where it runs there (plain arithmetic), else member by member
        with each member's own functions; members whose code SCHEDULEs or TERMTs
        differently have instants of their own."""
        calls = Calls()
        try:
            # (a fault on any member's column raises, as it does in a run of its own:
            # the members then run one by one, where the fault is located and said)
            with np.errstate(divide="raise", over="raise", invalid="raise"):
                ys, zs, vals = functions[name](t, list(y), m, list(z), calls)
            return (np.array([columns(v) for v in ys]).reshape(n, runs),
                    [columns(v) for v in zs[len(zs) - nw:]], [columns(v) for v in vals], calls)
        except (ValueError, TypeError):
            pass  # (a branch on a member's own value: member by member)
        outs = []
        for k in range(runs):
            if k not in bound:
                bound[k] = binder.bind(members[k][0]).code
            ck = Calls()
            outs.append((*bound[k][name][1](t, y[:, k].tolist(), m, [float(v[k]) for v in z],
                                            ck), ck))
        calls = outs[0][3]
        if any(o[3].schedules != calls.schedules or o[3].termts != calls.termts for o in outs):
            raise _OwnInstants
        return (np.array([[o[0][s] for o in outs] for s in range(n)], dtype=float).reshape(
                    n, runs),
                [np.array([o[1][len(o[1]) - nw + j] for o in outs], dtype=float)
                 for j in range(nw)],
                [np.array([o[2][j] for o in outs], dtype=float) for j in range(len(outs[0][2]))],
                calls)

    gaps = {d.name: float(code.constants.get(d.interval, 0.0))
            for d in acsl.discretes.values() if d.interval}
    queue: list[tuple[float, int, str]] = []
    order = 0
    for name in fns:
        if name in gaps:
            queue.append((plan.t0, order, name))
            order += 1
    for when, name in prepared.schedules:  # (INITIAL's, the same for every member)
        queue.append((when, order, name))
        order += 1
    heapq.heapify(queue)
    times = plan.grid.times
    segments: list[tuple[np.ndarray, np.ndarray, list[np.ndarray]]] = []
    t, i, events, steps, stopped = plan.t0, 0, 0, 0, None

    dynamic = bool(acsl.dynamic.body)  # (its statements run at every CINT instant)

    def reported(calls) -> bool:
        """What written-order code SCHEDULEd and TERMTed (at times every member shares),
        taken; False for a SCHEDULE into the past (the runs one by one say so)."""
        nonlocal order, stopped
        for when, name in calls.schedules:
            if when < t - within(t):
                return False
            heapq.heappush(queue, (max(when, t), order, name))
            order += 1
        if calls.termts and stopped is None:
            stopped = termination(acsl.termts[calls.termts[0]])
        return True

    try:
        with np.errstate(all="ignore"):
            while True:
                at_end = t >= plan.fintim
                if t >= stop_at and not (queue and queue[0][0] <= t) and not (
                        dynamic and i < len(times) and times[i] <= t):
                    # (the TERMT's crossing ends the run before an instant just after it;
                    # one at the very instant acts first, as in a run of its own)
                    stopped = stop_what
                while queue and not at_end and stopped is None and \
                        queue[0][0] <= t + within(t):
                    _, _, due = heapq.heappop(queue)
                    y, z, _, calls = section(fns[due], t, y, z)
                    if not reported(calls):
                        return None  # (one by one: the run says it is in the past)
                    events += 1
                    if events > opts.max_events:
                        return None  # (one by one: each run says so)
                    if gaps.get(due, 0.0) > 0:
                        heapq.heappush(queue, (t + gaps[due], order, due))
                        order += 1
                on_grid = i < len(times) and same_instant(t, times[i])
                if dynamic and on_grid and not at_end and stopped is None:
                    y, z, _, calls = section("dynamic", t, y, z)
                    if not reported(calls):
                        return None
                if stopped is None and t >= stop_at:
                    stopped = stop_what
                last = segments[-1][0][-1] if segments else -math.inf
                if on_grid or (stopped is not None and not same_instant(t, last)):
                    # (a row on the grid is the grid's instant, whatever rounding the
                    # events' times gathered; a stop a float from the last row is it)
                    segments.append((np.array([times[i] if on_grid else t]), y[None].copy(),
                                     z))
                    i += on_grid
                if stopped is not None or at_end:
                    break
                t_next = min(queue[0][0] if queue else math.inf, stop_at, plan.fintim,
                             times[i] if dynamic and i < len(times) else math.inf)
                # (the rows before the next instant; one a float from an instant where
                # code runs is that instant's row, after the code, as a run of its own
                # holds it)
                acts = bool(queue) and queue[0][0] <= t_next or \
                    dynamic and i < len(times) and times[i] <= t_next
                j = i + int(np.searchsorted(times[i:], t_next, side="left"))
                while acts and j > i and close_to(times[j - 1], t_next):
                    j -= 1
                if j == i and t_next - t <= within(t):
                    t = max(t, float(t_next))  # (as a run of its own: nothing to integrate)
                    continue
                ts = np.concatenate([[t], times[i:j], [t_next]])
                ys, taken = lsoda(lambda tt, cols, zz=z: rhs(tt, cols, m, zz), y, ts, plan,
                                  with_branches(jacobian, m, z))
                steps += taken
                if ys is None or steps > opts.max_steps:
                    return None  # (one by one: each run says why)
                if j > i:
                    segments.append((ts[1:-1], ys[1:-1], z))
                i, t, y = j, float(t_next), ys[-1].copy()
            terminal: dict[str, np.ndarray] = {}
            yt, zt = y, z
            for k, c in enumerate(acsl.terminal):
                yt, zt, assigned, _ = section(f"terminal_{k}", t, yt, zt)
                terminal.update(zip(c.assigned, assigned, strict=True))
            outputs = []
            for ts, ys, zs in segments:
                outs = out(ts[:, None], [ys[:, s, :] for s in range(n)], m, zs)
                outputs.append([np.broadcast_to(np.asarray(v, dtype=float), (len(ts), runs))
                                for v in outs])
    except (ArithmeticError, ValueError, TypeError, IndexError, _OwnInstants):
        # (a function with no elementwise form, a fault, instants of a member's own: the
        # members one by one, where a fault is located and said)
        return None
    rows = np.concatenate([ts for ts, _, _ in segments])
    index = {name: j for j, name in enumerate(code.out_names)}
    columns_of = {name: np.concatenate([o[index[name]] for o in outputs])
                  for name in variables if name in index}
    if any(not np.all(np.isfinite(v)) for v in [*columns_of.values(), *terminal.values(),
                                                 *z]):
        return None  # (a fault: one by one, where it is said)
    every = np.ones(rows.size, bool)
    status = Status.STOPPED if stopped is not None else Status.FINISHED
    said = message(Status.STOPPED, t=t, what=stopped) if stopped is not None else ""
    out_members = []
    for k, (constants, _) in enumerate(members):
        cols = [columns_of[name][:, k] if name in columns_of else
                np.full(rows.size, constants.get(name, math.nan)) for name in variables]
        values_k = np.column_stack(cols) if cols else np.empty((rows.size, 0))
        ends = {name: float(v[k]) for name, v in terminal.items()}
        final = tuple(ends.get(name, float(values_k[-1, j]) if rows.size else math.nan)
                      for j, name in enumerate(variables))
        out_members.append(Member(rows, every & _prdel(plan, rows), values_k, final, ends,
                                  str(status), said))
    return Batch(out_members, {})


def lsoda(rhs_columns, y0: np.ndarray, ts: np.ndarray, plan, jacobian=None
          ) -> tuple[np.ndarray | None, int]:
    """The members' states (n, members) from ts[0] to every instant of `ts`: one
    odeint over them, each member's states side by side, so that the Jacobian is
    banded (a member's block on the diagonal) and LSODA's stiff method keeps no
    square matrix of every state. `rhs_columns(t, columns)` gives the derivatives
    of n columns (a float where all members share one); `jacobian`, a
    `codegen.jacobian.ModelJacobian` over columns with its branches and memory bound
    (`jacobian.variable(t, columns)`), gives the blocks from the model's equations,
    each member's states in the order that narrows its block's band (else LSODA
    differences 2n - 1 evaluations a Jacobian of n - 1 bands either side).
    ((len(ts), n, members), or None where LSODA gives up or a state is not finite;
    the steps LSODA took)."""
    import warnings

    from scipy.integrate import ODEintWarning, odeint

    from ..steppers.jacobian import narrowest

    n, runs = y0.shape
    if jacobian is not None:
        order, lower, upper = narrowest(n, jacobian.rows, jacobian.cols, always=True)
    else:
        order, lower, upper = np.arange(n), n - 1, n - 1
    position = np.argsort(order)  # (old state i at new position[i])

    def f(flat: np.ndarray, t: float) -> np.ndarray:
        d = np.empty((runs, n))
        columns = list(flat.reshape(runs, n)[:, position].T)
        for s, v in enumerate(rhs_columns(t, columns)):
            d[:, position[s]] = v
        return d.reshape(-1)

    def per_state(x) -> np.ndarray:
        return np.tile(np.broadcast_to(np.asarray(x, dtype=float), (n,))[order], runs)

    options = {}
    width = lower + upper + 1
    if jacobian is not None:
        band = (upper + position[jacobian.rows] - position[jacobian.cols])[:, None]
        members, cols = np.arange(runs)[None, :], position[jacobian.cols][:, None]
        varying = np.flatnonzero(np.isnan(jacobian.constant))

        def dfun(flat: np.ndarray, t: float) -> np.ndarray:
            entries = np.empty((len(jacobian.constant), runs))
            entries[:] = jacobian.constant[:, None]
            if varying.size:
                columns = list(flat.reshape(runs, n)[:, position].T)
                entries[varying] = [np.broadcast_to(v, (runs,)) for v in
                                    jacobian.variable(t, columns)]
            if not np.all(np.isfinite(entries)):
                return by_differences(flat, t)
            out = np.zeros((width, runs, n))
            out[band, members, cols] = entries
            return out.reshape(width, runs * n)

        def by_differences(flat: np.ndarray, t: float) -> np.ndarray:
            # (state j of every member moved at once: one evaluation gives column j of
            # every member's block, the members being independent)
            y = flat.reshape(runs, n)
            f0 = f(flat, t).reshape(runs, n)
            out = np.zeros((width, runs, n))
            for j in range(n):
                moved = y.copy()
                h = 1.5e-8 * np.maximum(np.abs(y[:, j]), 1.0)
                moved[:, j] += h
                column = (f(moved.reshape(-1), t).reshape(runs, n) - f0) / h[:, None]
                rows = np.arange(max(j - upper, 0), min(j + lower, n - 1) + 1)
                out[upper + rows - j, :, j] = column[:, rows].T
            return out.reshape(width, runs * n)

        options["Dfun"] = dfun
    hmax = plan.max_step if math.isfinite(plan.max_step) else 0.0
    with warnings.catch_warnings():
        # (LSODA giving up is said by the members run one by one, not by its warning)
        warnings.simplefilter("ignore", ODEintWarning)
        sol, info = odeint(f, y0.T[:, order].reshape(-1), ts, rtol=per_state(plan.tol.rtol),
                           atol=per_state(plan.tol.atol), ml=lower, mu=upper, mxstep=MXSTEP,
                           hmax=hmax, full_output=True, **options)
    steps = int(np.max(info["nst"], initial=0))
    if info.get("message") != "Integration successful." or not np.all(np.isfinite(sol)):
        return None, steps
    return sol.reshape(len(ts), runs, n)[:, :, position].transpose(0, 2, 1), steps


def members_jacobian(code, values: dict[str, object]):
    """The model's Jacobian over the members' columns (see `lsoda`); None where the
    model has none."""
    from ..codegen.jacobian import over_members

    try:
        return over_members(code, values)
    except (NotImplementedError, ArithmeticError, ValueError, TypeError, RecursionError):
        return None


def with_branches(jacobian, m, z):
    """`members_jacobian`'s with the branches m and memory z it is taken in."""
    from dataclasses import replace

    if jacobian is None:
        return None
    variable = jacobian.variable
    return replace(jacobian, variable=lambda t, cols: variable(t, cols, m, z))


class _OwnInstants(Exception):
    """Members whose written-order code schedules or stops at instants of their own."""


def shared_or_columns(values: list[float]) -> float | np.ndarray:
    """A parameter's values over the members: one float where every member has the
    same (code that branches on it then runs on the columns), else the column."""
    column = np.array(values, dtype=float)
    return float(column[0]) if column.size and np.all(column == column[0]) else column


def _prdel(plan, rows: np.ndarray) -> np.ndarray:
    """Which rows are the PRDEL rows of the run's grid (an ACSL run's are every CINT)."""
    grid = plan.grid
    keep = np.isin(rows, grid.times[grid.prdel]) if grid.times.size else \
        np.zeros(rows.size, bool)
    keep[-1:] = True
    return keep
