"""Sensitivities of the observed values to data values: d(simulated)/d p at every
observation of a `--data` file, from the variational equations of the flow
(`run.variational.ParameterTangent`): the states' tangent carried along each step
(the model's own Jacobian d f/d y, exact to rounding), the data values' part F_p =
d f/d p, and at every located switch the jump of the tangent, the surface's own
dependence on p included -- so a value that moves a switching instant is
differentiated through it. The memory functions' values (ZHOLD, RST, DERIV, CSMP's
PULSE, the random draws) are carried too, through their updates (`ProgramTangent`:
the update's Jacobian, and its rate in TIME where a switch that moves holds it). An
observed output that is no state is d out/d y . S + d out/d z . S_z + d out/d p at
its instant.

F_p and ds/dp are the generated functions' own derivatives in the constants they
read by name (`codegen.jacobian.for_parameters`, each switch in its branch) times
d P/d p, the derivatives of those constants in the free values: INITIAL's and the
initial values' equations differentiated in their sorted order
(`codegen.consts.slopes`), exact to rounding; a program in ACSL form runs INITIAL
as written-order code, followed assignment by assignment
(`codegen.consts.written_slopes`), its values differenced where it has IFs or
loops (`analysis.program.bind_slopes`). While surfaces slide (the weights move with p
too), on a PULSE train's surfaces, for a CONST (folded into the code) and for d
out/dp and the memory's start, central differences of the generated functions at
one TIME and state (the run's code bound to p +- h, no integration); h = cbrt(eps)
|p| (1e-8 for p = 0: `step_for`). Where the
variational equations do not follow the flow (a state reset where two switches
cross that p moves apart, a flow tangent to a surface; in a program of the ACSL
form, an
instant its code runs at that moves with p: `analysis.program`) the caller
differences whole runs instead, and is told why."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from ..observed import Observations
from ..run.flow import FlowFailed
from ..run.jacobian import STEP  # (cbrt(machine epsilon): the one differencing step)
from ..run.plan import SAME_INSTANT, sliding_in
from ..run.variational import ParameterTangent, ProgramTangent
from .tangents import Sampler, output_row, outputs_asked, start_slope, step_for

if TYPE_CHECKING:
    from .program import ProgramTrajectory


def observed_jacobian(model, obs: Observations, names: list[str], values: dict[str, float],
                      params: dict[str, float], options: dict
                      ) -> tuple[np.ndarray | None, str]:
    """(d simulated / d p, a row per observation in the order of the fit's residuals
    -- run by run, then `Run.observed`'s order -- a column per name; "") or (None,
    why not)."""
    from ..diagnostics import AmilError

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
    track = trajectory(model, k, names, {**params, **values}, options, obs.times(k + 1),
                       sorted({s.name for s in obs.for_run(k + 1)}))
    if isinstance(track, str):
        return None, track
    series = [s for s in obs.for_run(k + 1) if s.name in track.code.out_names]
    rows = [track.row(s.name, tk) for s in series for tk in s.t.tolist()]
    return (np.array(rows).reshape(len(rows), len(names))), ""


class Trajectory:
    """d y(t)/d p along one run at given instants (`trajectory`), and of any output."""

    def __init__(self, flow, variants, floor, at: dict[float, tuple], halves=None) -> None:
        self.flow, self.code = flow, flow.code
        self.variants, self.floor, self.at = variants, floor, at
        self.halves = halves  # () -> the variants at half the step (`along_clock`)
        self.states = {name: i for i, name in enumerate(self.code.state_names)}
        self.outputs = {name: i for i, name in enumerate(self.code.out_names)}
        self._rows: dict[float, object] = {}

    def row(self, name: str, t: float) -> np.ndarray:
        """d name(t) / d p, a value per data value."""
        state, sens = self.at[t]
        if name in self.states:
            return sens[self.states[name]]
        if t not in self._rows:
            # the branches at t chosen afresh, as the run's row there has them: a switch
            # on TIME due exactly at t is taken (the step that ends at t has the old one);
            # a surface sliding stays so (its state, a rounding off it, would pick a side)
            # (with the memory the tangent was read with: the start's would update it
            # here, putting a play's value on its own kink)
            self._rows[t] = state if sliding_in(state.modes) else \
                replace(self.flow.state(state.y, None, state.memory, t), memory=state.memory)
        return output_row(self.code, self.variants, self.outputs[name], t, self._rows[t],
                          sens, self.floor, self.flow.watch, self.halves)


def moved_flows(flow_at, code, name: str, value: float):
    """(flow with data value `name` at value + h, at value - h, h), h = `step_for`, for
    central differences of the generated functions; None where moving it changes
    which switches the run watches (`code`'s: the variants must be the same model).
    `flow_at(**values)`: the flow with those data values."""
    h = step_for(value, STEP)
    plus, minus = flow_at(**{name: value + h}), flow_at(**{name: value - h})
    if any((v.code.watched, v.code.state_names, v.code.out_names) !=
           (code.watched, code.state_names, code.out_names) for v in (plus, minus)):
        return None
    return plus, minus, h


def exact_slopes(c, names: list[str]) -> tuple[np.ndarray, np.ndarray] | None:
    """(d P/d names for the constants P `c`'s functions read by name, in
    `ParameterJacobian.names`' order; d y0/d names), from the listing's INITIAL and
    initial-value equations (`codegen.consts.slopes`), or None where they cannot be
    had so (a CONST among `names`: folded into the code)."""
    from ..codegen.consts import slopes
    from ..codegen.jacobian import by_parameter

    if c.binder is None or c.model is None:
        return None
    found = slopes(c.model, names, c.constants, c.binder.parameters, c.binder.tables)
    if found is None:
        return None
    rows, start = found
    return by_parameter(c, rows, len(names)), start


def trajectory(model, k: int, names: list[str], data: dict[str, float], options: dict,
               times, variables: list[str] | None = None
               ) -> Trajectory | ProgramTrajectory | str:
    """Run `k`'s tangent with respect to the data values `names` at `times` (sorted;
    `data` the values), or why the variational equations cannot follow it; `variables`:
    the outputs it will be asked for (default every one). A program in ACSL form:
    through its instants' code (`analysis.program`)."""
    if model.ir.acsl is not None:
        from .program import program_trajectory

        return program_trajectory(model, k, names, data, options, times, variables)

    def flow_at(**changed):
        return model.flow(options.get("method"), options.get("rtol"), options.get("atol"),
                          run=k, **{**data, **changed})

    flow = flow_at()
    if flow.plan.step_point or not flow.plan.route.uses_tolerances:
        return "a fixed-step route has no dense output for the sensitivity equations"
    c = flow.code
    start = flow.initial_state()
    n = len(start.y)
    # the memory functions' values are carried too (their rows after the states's)
    r = len(start.memory)
    variants, dy0 = [], np.zeros((n + r, len(names)))
    for j, name in enumerate(names):
        moved = moved_flows(flow_at, c, name, data[name])
        if moved is None:
            return f"{name} changes which switches the run watches"
        plus, minus, h = moved
        variants.append((plus.code, minus.code, h))
        up, down = plus.initial_state(), minus.initial_state()
        dy0[:, j] = start_slope(np.concatenate([up.y, up.memory[:r]]),
                                np.concatenate([down.y, down.memory[:r]]), h)
    exact = exact_slopes(c, names)
    if exact is not None:  # (the states' start from its equations; the memory's differenced)
        dy0[:n] = exact[1]
    floor = np.broadcast_to(np.asarray(flow.plan.tol.atol / flow.plan.tol.rtol, dtype=float),
                            (n,))
    asked = outputs_asked(c, variables)
    by_name = None if exact is None else exact[0]
    tangent = ProgramTangent(c, flow.watch, floor, dy0, variants, r, asked, by_name) if r \
        else ParameterTangent(c, flow.watch, floor, dy0, variants, asked, by_name)
    if r and c.clock_slots:  # (a store whose instants a free delay may move: `along_clock`)
        tangent.make_halves = lambda: [(flow_at(**{name: data[name] + 0.5 * h}).code,
                                        flow_at(**{name: data[name] - 0.5 * h}).code)
                                       for name, (_, _, h) in zip(names, variants, strict=True)]
    times = np.asarray(times, dtype=float)
    sampler = Sampler(tangent, times, n + r)
    at: dict[float, tuple] = sampler.at
    if len(times) and times[0] <= start.t + SAME_INSTANT * max(1.0, abs(start.t)):
        at[float(times[0])] = (start, tangent.phi[:n + r].copy())
    if len(times) and times[-1] > start.t:
        # one integration over the whole span, as the run's: the tangent is read inside
        # the steps at the instants asked for (no restart at each of them)
        end, _ = flow.advance(start, start.t, float(times[-1]), observer=sampler)
        sampler.finish(end)
        if tangent.failed is not None:
            return tangent.failed
        if end.t < times[-1] * (1 - 1e-12) - 1e-300:
            return f"the run stops at TIME = {end.t:.9g}"
    missing = [t for t in times.tolist() if t not in at]
    if missing:
        return f"the flow's steps did not reach TIME = {missing[0]:.9g}"
    return Trajectory(flow, variants, floor, at,
                      (lambda: tangent.halves) if isinstance(tangent, ProgramTangent) else None)



@dataclass
class Local:
    """Local sensitivities of the first run's variables to data values over time."""

    names: list[str]  # the data values
    values: dict[str, float]  # their values in the run
    variables: list[str]
    times: np.ndarray  # the output grid (OUTDEL and PRDEL instants)
    prdel: np.ndarray  # which of `times` are PRDEL instants
    y: np.ndarray  # (times, variables)
    raw: np.ndarray  # (times, variables, names): d y / d p
    how: str  # "sensitivity equations", or "differences of whole runs (why)"

    @property
    def normalised(self) -> np.ndarray:
        """p / y * d y / d p: the percent change of y per percent of p (NaN where
        y = 0)."""
        p = np.array([self.values[n] for n in self.names])
        with np.errstate(all="ignore"):
            out = self.raw * p[None, None, :] / self.y[:, :, None]
        out[~np.isfinite(out)] = np.nan
        return out

    def largest(self) -> np.ndarray:
        """(variables, names): the largest |P dY/dP| over the run relative to the
        largest |Y| (a coefficient over Y's scale: near a zero of Y the pointwise
        one grows without bound)."""
        p = np.array([self.values[n] for n in self.names])
        with np.errstate(all="ignore"):
            top = np.nanmax(np.abs(self.y), axis=0) if len(self.y) else \
                np.full(len(self.variables), np.nan)
            effect = np.nanmax(np.abs(self.raw * p[None, None, :]), axis=0) \
                if len(self.raw) else np.full((len(self.variables), len(p)), np.nan)
            out = effect / top[:, None]
        out[~np.isfinite(out)] = np.nan
        return out


def local(model, names: list[str] | None = None, variables: list[str] | None = None,
          options=None, params: dict[str, float] | None = None) -> Local:
    """d y/d p of `variables` (default every PRINT/OUTPUT variable) to the data values
    `names` (default the PARAM values) on the first run's output grid: the
    variational equations (`trajectory`), else central differences of whole runs
    (`difference_step`), and why. `options`: a run.Options for the run."""
    from dataclasses import replace

    from ..batch.members import member_of
    from ..batch.montecarlo import reported
    from ..diagnostics import UsageError
    from ..run import Options

    options = replace(options or Options(), outputs=None, progress=None)
    params = {k.upper(): float(v) for k, v in (params or {}).items()}
    data = {**model.ir.runs[0].data, **params}
    if not names:
        kinds = model.ir.data_kinds
        names = [n for n in model.ir.data_names if kinds.get(n) == "PARAM"] or \
            list(model.ir.data_names)
    names = [n.upper() for n in names]
    for n in names:
        if n not in data:
            from ..diagnostics import with_hint

            raise UsageError(with_hint(f"--local {n}: not a PARAM/CONST/INCON value of this "
                                       "model", n, list(data)))
    if not names:
        raise UsageError("the model has no data value to differentiate by")
    variables = model.known_names(variables) if variables else reported(model)
    run = _one_run(model, options, variables, params)
    base = member_of(tuple(variables), run)
    flow_options = {"method": options.method, "rtol": options.rtol, "atol": options.atol}
    track = trajectory(model, 0, names, data, flow_options, base.times, variables)
    if not isinstance(track, str):
        raw = np.array([[track.row(v, t) for v in variables] for t in base.times.tolist()])
        how = "sensitivity equations"
    else:
        raw = _differences(model, names, data, variables, options, params, base)
        how = f"differences of whole runs ({track})"
    return Local(names, {n: data[n] for n in names}, variables, base.times, base.prdel,
                 base.values, raw.reshape(len(base.times), len(variables), len(names)), how)


def _one_run(model, options, variables, params):
    """The first run with `options` (its Options: limits, weather, step-point mode),
    or FlowFailed saying why it failed."""
    from dataclasses import replace

    from ..run import simulate

    spec = model._specs(params)[0]
    run = simulate(model.ir, spec, replace(options, outputs=list(variables)), model.cache)
    if not run.ok:
        raise FlowFailed(f"the run failed: {run.message}")
    return run


def difference_step(model, method: str | None, rtol: float | None) -> float:
    """The relative step of central differences of whole runs: cbrt(RELERR) on a
    route with error control, whose runs carry its noise (the truncation error h^2
    and the noise RELERR/h balance there; at least 1e-6); cbrt(eps) on a fixed-step
    route (step-point mode, EULER, RK4...), whose runs are a discrete map of the
    values, smooth in them to rounding: differenced so, it is exact to about 1e-10,
    as the tangent's own differences of the generated functions are."""
    if model.ir.acsl is not None:
        from ..run import Options
        from ..run.acsl import prepare_acsl

        plan = prepare_acsl(model.ir, model._specs({})[0], Options(method=method, rtol=rtol),
                            model.cache).plan
    else:
        plan = model.flow(method, rtol, None).plan
    if plan.step_point or not plan.route.uses_tolerances:
        return STEP
    return max(float(np.cbrt(plan.tol.relerr)), 1e-6)


def _differences(model, names, data, variables, options, params, base) -> np.ndarray:
    """Central differences of whole runs, h = `difference_step` |p|."""
    from ..batch.members import member_of
    from ..run.plan import nearest_instants

    rel = difference_step(model, options.method, options.rtol)
    out = np.full((len(base.times), len(variables), len(names)), np.nan)
    for j, name in enumerate(names):
        h = step_for(data[name], rel)
        rows = []
        for value in (data[name] + h, data[name] - h):
            try:
                run = _one_run(model, options, variables, {**params, name: value})
            except FlowFailed as exc:
                raise FlowFailed(f"the run with {name} = {value:.9g}: {exc}") from None
            m = member_of(tuple(variables), run)
            pick, same = nearest_instants(m.times, base.times)
            rows.append(np.where(same[:, None], m.values[pick], np.nan))
        out[:, :, j] = (rows[0] - rows[1]) / (2 * h)
    return out
