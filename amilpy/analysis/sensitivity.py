"""Sensitivities of the observed values to data values: d(simulated)/d p at every
observation of a `--data` file, from the variational equations of the flow
(`run.variational.ParameterTangent`): the states' tangent carried along each step
(the model's own Jacobian d f/d y, exact to rounding), the data values' part F_p =
d f/d p, and at every located switch the jump of the tangent, the surface's own
dependence on p included -- so a value that moves a switching instant is
differentiated through it. An observed output that is no state is d out/d y . S +
d out/d p at its instant.

F_p, ds/dp, d out/dp and the start's dependence d y(t0)/dp are central differences
of the generated functions at one TIME and state (the run's code bound to p +- h,
no integration); h = cbrt(eps) |p|, at least 1e-8. Where the variational equations do not follow
the flow (a surface that slides, a state reset, a memory value the derivatives read
changing, a flow tangent to a surface, a memory function's initial value that
depends on p, the ACSL form's written-order code) the caller differences whole runs
instead, and is told why."""

from __future__ import annotations

import numpy as np

from ..observed import Observations
from ..run.flow import FlowFailed
from ..run.variational import ParameterTangent

STEP = 6e-6  # ~ cbrt(machine epsilon): central differences of the generated functions


def observed_jacobian(model, obs: Observations, names: list[str], values: dict[str, float],
                      params: dict[str, float], options: dict
                      ) -> tuple[np.ndarray | None, str]:
    """(d simulated / d p, a row per observation in the order of the fit's residuals
    -- run by run, then `Run.observed`'s order -- a column per name; "") or (None,
    why not)."""
    from ..diagnostics import AmilError

    if model.ir.acsl is not None:
        return None, "an ACSL program has no flow map (its DYNAMIC and DISCRETE code " \
                     "runs between the integrator's steps)"
    rows = []
    for k in range(len(model.ir.runs)):
        try:
            part, why = _run_jacobian(model, obs, k, names, values, params, options)
        except (AmilError, FlowFailed, ArithmeticError, ValueError) as exc:
            return None, f"run {k + 1}: {exc}"
        if part is None:
            return None, f"run {k + 1}: {why}"
        rows.append(part)
    return (np.vstack(rows) if rows else np.empty((0, len(names)))), ""


def _run_jacobian(model, obs: Observations, k: int, names, values, params, options):
    data = {**params, **values}

    def flow_at(**changed):
        return model.flow(options.get("method"), options.get("rtol"), options.get("atol"),
                          run=k, **{**data, **changed})

    flow = flow_at()
    c = flow.code
    start = flow.initial_state()
    n = len(start.y)
    variants, dy0 = [], np.zeros((n, len(names)))
    for j, name in enumerate(names):
        # (a value of 0, or a tiny one, is moved by at least 1e-8: exact for what it
        # enters linearly, which is what a value near 0 mostly does)
        h = max(STEP * abs(data[name]), 1e-8)
        plus, minus = flow_at(**{name: data[name] + h}), flow_at(**{name: data[name] - h})
        if any((v.code.watched, v.code.state_names, v.code.out_names) !=
               (c.watched, c.state_names, c.out_names) for v in (plus, minus)):
            return None, f"{name} changes which switches the run watches"
        variants.append((plus.code, minus.code, h))
        up, down = plus.initial_state(), minus.initial_state()
        if up.memory != down.memory:  # (HSTRSS's, BCKLSH's initial value: not followed)
            return None, f"a memory function's initial value depends on {name}"
        dy0[:, j] = (np.asarray(up.y) - np.asarray(down.y)) / (2.0 * h)
    floor = np.broadcast_to(np.asarray(flow.plan.tol.atol / flow.plan.tol.rtol, dtype=float),
                            (n,))
    tangent = ParameterTangent(c, flow.watch, floor, dy0, variants)
    series = [s for s in obs.for_run(k + 1) if s.name in c.out_names]
    times = obs.times(k + 1)
    at: dict[float, tuple] = {}
    state, t = start, start.t
    for tk in times.tolist():
        if tk > t:
            state, _ = flow.advance(state, t, tk, observer=tangent)
            if tangent.failed is not None:
                return None, tangent.failed
            if state.t < tk * (1 - 1e-12) - 1e-300:
                return None, f"the run stops at TIME = {state.t:.9g}"
            t = tk
            # the branches at tk chosen afresh, as at a start: a switch on TIME due
            # exactly at tk is taken (the next advance would start on its surface and
            # keep the old branch); the tangent's jump follows from the change
            state = flow.state(state.y, None, state.memory, tk)
        at[tk] = (state, tangent.phi[:n].copy())
    states = {name: i for i, name in enumerate(c.state_names)}
    out_index = {name: i for i, name in enumerate(c.out_names)}
    rows = []
    for s in series:
        for tk in s.t.tolist():
            st, sens = at[tk]
            if s.name in states:
                rows.append(sens[states[s.name]])
                continue
            rows.append(_output_row(c, variants, out_index[s.name], tk, st, sens, floor))
    return (np.array(rows).reshape(len(rows), len(names))), ""


def _output_row(c, variants, i: int, t: float, state, sens: np.ndarray, floor: np.ndarray
                ) -> np.ndarray:
    """d out_i / d p = d out_i/d y . S + d out_i/d p at (t, state)."""
    y = np.asarray(state.y, dtype=float)
    m, z = list(state.modes), list(state.memory)
    grad = np.zeros(len(y))
    for j in range(len(y)):
        h = STEP * max(abs(y[j]), float(floor[j]))
        up, down = y.copy(), y.copy()
        up[j] += h
        down[j] -= h
        grad[j] = (c.out(t, up.tolist(), m, z)[i] - c.out(t, down.tolist(), m, z)[i]) / (2 * h)
    direct = np.array([(plus.out(t, y.tolist(), m, z)[i] - minus.out(t, y.tolist(), m, z)[i])
                       / (2.0 * h) for plus, minus, h in variants])
    return grad @ sens + direct

