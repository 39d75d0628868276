"""An ensemble integrated at once: every member's states stacked into one system,
the generated right-hand side evaluated over a member axis (NumPy), one LSODA
integration (odeint) for all of them, as a competent user would write it by hand
when the members share their switching instants.

Which ensembles (`why_not`): a listing in CSMP form on a variable-step route,
with nothing that makes a member's run its own -- no watched switching surface
(a member would switch at its own instants), no memory function, delay, random
draw or weather, no breakpoints, resets or settled states, no TERMINAL section,
no FINISH -- and members whose true constants (CONST, TIMER and what INITIAL
works out from them) are the same, so that one build serves them all. Anything
else runs member by member (`montecarlo.run_sets`), as before.

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


def why_not(model, code, plan, opts) -> str | None:
    """Why this ensemble cannot be integrated at once (None: it can)."""
    ir = model.ir
    if ir.acsl is not None:
        return "an ACSL program runs its own code between the steps"
    if plan.step_point or not plan.route.uses_tolerances:
        return "a fixed-step route"
    if code.watched:
        return "the members switch at their own instants"
    if ir.units:
        return "statements (IF blocks, loops) run one row at a time"
    if code.z0 or ir.memories or ir.weather or code.sample is not None or \
            code.memory_trains or code.seen_times:
        return "memory functions, delays, random draws or weather"
    if plan.breakpoints or plan.resets or code.settle is not None or code.impulses or \
            code.trains:
        return "breakpoints, resets or settled states"
    if ir.terminal or ir.terminal_code:
        return "a TERMINAL section (it runs per member)"
    if opts.extrema:
        return "extremes located between the rows (per member)"
    if code.binder is None:
        return "no build to share"
    return None


def run_stacked(model, base, sets: dict[str, np.ndarray], runs: int, variables: list[str],
                opts) -> Batch | None:
    """The ensemble at once (see the module): `runs` runs of spec `base` with `sets`'
    values, `opts` their options; None when it cannot be (`why_not`) or LSODA fails on
    the stacked system (the members then run one by one)."""
    from scipy.integrate import odeint

    from ..codegen.consts import evaluate_constant, initial_values
    from ..run import prepare
    from ..run.plan import reserved_values

    if runs < 2 or model.ir.acsl is not None:
        return None
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
    values = {n: np.array([c[n] for c in per_member]) for n in binder.parameters}
    rhs, out = binder.over_members(values)
    states = model.ir.states
    y0 = np.array([[evaluate_constant(model.ir, s.ic, c, base.tables, s.span)
                    for c in per_member] for s in states])  # (states, members)
    n = len(states)
    shape = (n, runs)

    def f(y, t):
        d = rhs(t, list(y.reshape(shape)), [], [])
        return np.concatenate([np.broadcast_to(np.asarray(v, dtype=float), (runs,))
                               for v in d])

    def per_state(x) -> np.ndarray:
        return np.repeat(np.broadcast_to(np.asarray(x, dtype=float), (n,)), runs)

    times = plan.grid.times
    try:
        with np.errstate(all="ignore"):
            sol, info = odeint(f, y0.reshape(-1), times, rtol=per_state(plan.tol.rtol),
                               atol=per_state(plan.tol.atol), mxstep=MXSTEP,
                               hmax=plan.max_step if math.isfinite(plan.max_step) else 0.0,
                               full_output=True)
            ys = sol.reshape(len(times), n, runs)  # (times, states, members)
            outs = out(times[:, None], [ys[:, i, :] for i in range(n)], [], [])
    except (ArithmeticError, ValueError, TypeError):
        # (a function with no elementwise form, a fault: the members one by one, where
        # a fault is located and said)
        return None
    if info.get("message") != "Integration successful." or not np.all(np.isfinite(sol)):
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
