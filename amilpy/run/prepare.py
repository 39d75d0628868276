"""From a checked model and a run spec to what a run needs: the run's constants
(data, TIMER and INITIAL values), its generated functions and its plan.

`prepare` is the documented way in for anything that wants a run's generated
functions without running it (`--show-python`, benchmarks, tests). A `Cache`
keeps generated functions, INITIAL values and grids between the runs of one model;
`api.Model` owns one, so the IR holds no caches.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TypeVar

from .. import ir
from ..codegen import (
    Compiler,
    ModelCode,
    Setting,
    evaluate_constant,
    fault_line,
    initial_values,
    parameter_names,
)
from ..diagnostics import AmilError, Diagnostic, Span, in_file
from ..language import SEED_NAME
from ..library.surfaces import level, sign
from ..parse.syntax import no_collection
from . import steppoint
from .plan import (
    Options,
    RunPlan,
    make_grid,
    make_plan,
    reserved_values,
    resolve_route,
    resolve_step_point,
    row_limit,
    start_time,
    timer_values,
)

T = TypeVar("T")


class Cache:
    """Values a model's runs share, by the data that determines them: INITIAL
    values per set of data, generated functions per set of constants (bound to the
    code built for its true constants: runs that differ in PARAM values compile
    once, see `codegen.parameter_names`), output grids per timer. Each table is
    cleared when it grows past its limit (a long sweep)."""

    LIMITS = {"initial": 256, "bound": 64, "code": 64, "grid": 64, "parameters": 4,
              "weather": 16}

    def __init__(self) -> None:
        self._tables: dict[str, dict] = {name: {} for name in self.LIMITS}

    def get(self, table: str, key, make: Callable[[], T]) -> T:
        entries = self._tables[table]
        if key not in entries:
            if len(entries) > self.LIMITS[table]:
                entries.clear()
            entries[key] = make()
        return entries[key]


@dataclass(frozen=True)
class Prepared:
    """One run, ready to integrate."""

    constants: dict[str, float]  # data, TIMER and INITIAL values
    code: ModelCode
    plan: RunPlan


def prepare(model: ir.Model, spec: ir.RunSpec, opts: Options | None = None,
            cache: Cache | None = None, code_only: bool = False) -> Prepared:
    """Constants, generated functions and plan of one run. A fault while evaluating
    the constant parts (INITIAL, fixed branches, breakpoint instants) is an
    AmilError at the listing's line. `code_only`: for the code alone (what the run
    would refuse on its route is said when it runs)."""
    opts = opts or Options()
    cache = cache or Cache()
    return before_run(model, lambda: _prepare(model, spec, opts, cache, code_only))


def before_run(model: ir.Model, make: Callable[[], T], what=str) -> T:
    """`make()`, with an arithmetic fault in it (in the constant parts of a run) an
    AmilError at the listing's line; `what` words the fault."""
    try:
        return make()
    except (ArithmeticError, ValueError) as exc:
        line = fault_line(exc)
        raise AmilError([Diagnostic(f"cannot be evaluated before the run: {what(exc)}",
                                    Span(line, 1) if line else None,
                                    "check the constant expressions on that line")],
                        model.path, model.source) from None


def constant_modes(model: ir.Model, constants: dict[str, float], tables,
                   step_point: bool = False) -> dict[int, float]:
    """The branches of the surfaces fixed for the whole run (IMPULS's: 0, except in
    step-point mode, which reads it at each point)."""
    const_modes = {}
    for s in model.surfaces:
        if s.depends == "impulse" and not step_point:
            const_modes[s.index] = 0.0
        if s.depends == "const" and s.purpose not in (ir.Purpose.TERMT, ir.Purpose.FINISH):
            # (a TERMT or FINISH stays watched: one true from the start, a routine's
            # STOP, stops the run there)
            value = evaluate_constant(model, s.expr, constants, tables, s.span)
            const_modes[s.index] = level(value) if s.kind == "level" else sign(value)
    return const_modes


def with_weather(model: ir.Model, spec: ir.RunSpec, timer: dict[str, float], opts: Options,
                 cache: Cache) -> ir.RunSpec:
    """The run's spec with a day table per weather name the model reads, over the
    run's days, from the CABO files (FST's WEATHER; `library/weather.py` finds and reads them,
    and says where it looked when a file is not there)."""
    from ..library import WEATHER_TABLE
    from ..library.weather import Weather

    t0 = start_time(spec, opts)
    t1 = t0 + timer["FINTIM"] + timer["DELT"]  # a step-point run may pass FINTIM
    folder = os.path.dirname(os.path.abspath(model.path)) if model.path else os.getcwd()
    key = (spec.weather, math.floor(t0), math.floor(t1), tuple(opts.weather_dirs),
           tuple(model.weather), folder)

    def read() -> dict[str, object]:
        weather = Weather(spec.weather, folder, list(opts.weather_dirs), model.weather_lines)
        with in_file(model.path, model.source):
            days = weather.tables(model.weather, t0, t1, t0 + timer["FINTIM"])
        return {WEATHER_TABLE + name: table for name, table in days.items()}

    return replace(spec, tables={**spec.tables, **cache.get("weather", key, read)})


def _kept_needs_step_points(model: ir.Model, method: str) -> None:
    """A routine after STOP that changes a variable it is given (library's KEPT) changes
    it once per step point, as FSE's Euler loop does; a variable-step route has no
    such instants of the model (its steps are its own): refused there, by the CALL."""
    from ..library import BEFORE, KEPT

    mem = next((m for m in model.memories if m.func in (KEPT, BEFORE)), None)
    if mem is not None:
        name = getattr(mem.args[-1], "name", mem.target)
        raise AmilError([Diagnostic(
            f"a routine after STOP changes {name} from the value it left "
            f"before (a count, or a value kept where no branch sets it): that happens once "
            f"per step point, and METHOD {method} has none", mem.span,
            "run it in step-point mode: TRANSLATION_GENERAL DRIVER = 'EUDRIV', or "
            "--method RECT")], model.path, model.source)


@no_collection()
def _prepare(model: ir.Model, spec: ir.RunSpec, opts: Options, cache: Cache,
             code_only: bool = False) -> Prepared:
    with in_file(model.path, model.source):
        timer = timer_values(spec, opts.fintim, opts.max_rows, opts.row_sink is not None)
    route, method = resolve_route(spec, opts)
    step_point = resolve_step_point(spec, opts)
    if step_point:
        timer = steppoint.timer(model, spec, timer, method)
    elif not code_only:
        _kept_needs_step_points(model, method)
    if model.weather and spec.weather is not None:
        spec = with_weather(model, spec, timer, opts, cache)
    reserved = reserved_values(timer)
    tables = repr(sorted(spec.tables.items()))
    ikey = (tuple(sorted(spec.data.items())), tuple(sorted(reserved.items())), tables)
    constants = dict(cache.get("initial", ikey, lambda: initial_values(
        model, spec.data, spec.tables, reserved)))
    # FST's SET variables start from their INITIAL values and change at EVENTs
    kept = {n: float(constants.pop(n)) for n in model.sets}
    const_modes = constant_modes(model, constants, spec.tables, step_point)
    setting = Setting(seed=random_seed(opts, constants),
                      # a random draw is held for an output interval, DELT with a fixed step
                      hold=timer["DELT"] if route.fixed else min(timer["OUTDEL"],
                                                                 timer["PRDEL"]),
                      step=timer["DELT"] if step_point else None)
    outputs = tuple(opts.outputs) if opts.outputs is not None else None
    ckey = (tuple(sorted(constants.items())), tuple(kept.items()), tables, outputs,
            opts.events, setting)
    # a run whose parameters alone differ binds the code built for another (no compile)
    params = cache.get("parameters", id(model), lambda: parameter_names(model))
    skey = (tuple(sorted((k, v) for k, v in constants.items() if k not in params)),
            tuple(sorted(const_modes.items())), tuple(kept.items()), tables, outputs,
            opts.events, setting)
    code = cache.get("bound", ckey, lambda: cache.get("code", skey, lambda: Compiler(
        model, constants, spec.tables, const_modes, opts.outputs, opts.events, setting,
        kept=kept, parameters=params).build()).rebound(constants))
    t0 = start_time(spec, opts)
    fintim = t0 + timer["FINTIM"]
    gkey = (t0, fintim, timer["OUTDEL"], timer["PRDEL"], step_point and timer["DELT"],
            opts.extra_times)
    with in_file(model.path, model.source):
        grid = cache.get("grid", gkey, lambda: steppoint.grid(t0, timer) if step_point else
                         make_grid(t0, fintim, timer["OUTDEL"], timer["PRDEL"],
                                   opts.extra_times))
    limit = row_limit(opts.max_rows, opts.row_sink is not None)
    if len(grid.times) > limit:
        raise AmilError([Diagnostic(
            f"the run would print {len(grid.times)} rows (limit {limit})",
            None, "raise OUTDEL/PRDEL")], model.path, model.source)
    return Prepared(constants, code, make_plan(model, spec, opts, code, timer, grid,
                                                   step_point))


def random_seed(opts: Options, constants: dict[str, float]) -> float:
    """The seed of a run's random streams: the option (--seed, seed=), else the
    listing's RNSEED, else 1."""
    if opts.seed is not None:
        return float(opts.seed)
    return float(constants.get(SEED_NAME, 1.0))
