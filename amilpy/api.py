"""The Python front door: load a listing, run it, get `Run` objects back.

    >>> import amilpy
    >>> model = amilpy.loads("X = INTGRL(1.0, -X)\\nTIMER FINTIM = 1.0\\nEND\\n")
    >>> run, = model.run()
    >>> round(float(run["X"][-1]), 6)
    0.367879
"""

from __future__ import annotations

import os
from dataclasses import replace
from typing import TYPE_CHECKING

from . import ir
from .check import check
from .diagnostics import AmilError, Diagnostic, nearest
from .parse import parse
from .routes import route_for

if TYPE_CHECKING:
    from .result import Run
    from .run import Cache, Flow


class Model:
    """A checked listing, ready to run any number of times. It keeps what its runs
    share (compiled functions, INITIAL values, output grids) in `cache`."""

    def __init__(self, model: ir.Model) -> None:
        self.ir = model
        self._cache: Cache | None = None

    @property
    def cache(self) -> Cache:
        if self._cache is None:  # the run package (NumPy) loads on the first run
            from .run import Cache

            self._cache = Cache()
        return self._cache

    @property
    def name(self) -> str:
        return self.ir.name

    @property
    def path(self) -> str | None:
        return self.ir.path

    @property
    def variables(self) -> list[str]:
        return self.ir.variables

    @property
    def parameters(self) -> dict[str, float]:
        return dict(self.ir.runs[0].data)

    def python_source(self, **params: float) -> str:
        """The generated Python of the first run (what `--show-python` prints)."""
        from .run import prepare

        return prepare(self.ir, self._specs(params)[0], cache=self.cache).compiled.source

    def flow(self, method: str | None = None, rtol: float | None = None,
             atol: float | None = None, run: int = 0, **params: float) -> Flow:
        """The flow map of run `run` (its data, with `params` overriding): see
        `amilpy.run.flow` for `advance`, its events and its sensitivity."""
        from .run import Flow, Options

        if method is not None and route_for(method) is None:
            raise AmilError(f"unknown integration method {method}")
        spec = self._specs(params)[run]
        return Flow(self.ir, spec, Options(method=method, rtol=rtol, atol=atol), self.cache)

    def _specs(self, params: dict[str, float]) -> list[ir.RunSpec]:
        known = set(self.ir.data_names)
        overrides = {}
        for key, value in params.items():
            name = key.upper()
            if name not in known:
                hint = nearest(name, known)
                raise AmilError([Diagnostic(
                    f"{name} is not a PARAM/CONST/INCON value of this model",
                    None, f"did you mean {hint}?" if hint else
                    "only data values can be set from outside")], self.ir.path)
            try:
                overrides[name] = float(value)
            except (TypeError, ValueError):
                raise AmilError(f"{name} must be a number, got {value!r}") from None
        specs = []
        for spec in self.ir.runs:
            if overrides:
                data = dict(spec.data)
                data.update(overrides)
                changed = {**spec.changed, **overrides}
                label = ", ".join(f"{n} = {v:g}" for n, v in changed.items())
                spec = replace(spec, data=data, changed=changed, label=label or spec.label)
            specs.append(spec)
        return specs

    def run(self, method: str | None = None, rtol: float | None = None,
            atol: float | None = None, *, events: bool = True,
            outputs: list[str] | None = None, max_steps: int | None = None,
            max_events: int | None = None, max_time: float | None = None,
            fintim: float | None = None, progress=None, advice: bool = True,
            **params: float) -> list[Run]:
        """Run every run of the listing (value lists, END groups); data values
        given as keywords override the listing's for all of them."""
        from .run import Options, simulate

        if method is not None and route_for(method) is None:
            raise AmilError(f"unknown integration method {method}")
        for label, tol in (("rtol", rtol), ("atol", atol)):
            if tol is not None and not tol > 0:
                raise AmilError(f"{label} must be positive, got {tol}")
        if outputs is not None:
            outputs = [o.upper() for o in outputs]
            unknown = [o for o in outputs if o not in self.ir.variables]
            if unknown:
                raise AmilError(f"{unknown[0]} is not a variable of the model")
        opts = Options(method=method, rtol=rtol, atol=atol, events=events, outputs=outputs,
                       max_time=max_time, progress=progress, fintim=fintim)
        if max_steps:
            opts.max_steps = max_steps
        if max_events:
            opts.max_events = max_events
        runs = []
        advised = False
        for spec in self._specs(params):
            run = simulate(self.ir, spec, opts, self.cache)
            if advice and not advised:
                from .advice import stiffness_advice

                run.advice = stiffness_advice(self.ir, spec, run, opts, self.cache)
                advised = run.advice is not None  # say it once
            runs.append(run)
            if run.message.startswith("interrupted"):
                break  # Ctrl-C: keep what was computed, start nothing new
        return runs

    def sweep(self, name: str, values, *, both_ways: bool = False, carry_state: bool = False,
              settle: float = 0.0, measure: str | None = None, method: str | None = None,
              rtol: float | None = None, atol: float | None = None,
              fintim: float | None = None, keep_runs: bool = False, progress=None,
              **params: float):
        """One run per value of data value `name` (see `amilpy.sweep.sweep`)."""
        from .sweep import sweep

        if method is not None and route_for(method) is None:
            raise AmilError(f"unknown integration method {method}")
        return sweep(self, name, [float(v) for v in values], both_ways=both_ways,
                     carry_state=carry_state, settle=settle, measure=measure, method=method,
                     rtol=rtol, atol=atol, fintim=fintim, keep_runs=keep_runs,
                     progress=progress, **params)

    def modes(self, at: float = 0.0, method: str | None = None, rtol: float | None = None,
              atol: float | None = None, progress=None, **params: float):
        """The linear modes about the state at TIME `at` (`amilpy.analysis.linear`):
        eigenvalues, natural frequencies, damping ratios, shapes, the Jacobian."""
        from .analysis.linear import modes

        self._check_method(method)
        return modes(self, at, method=method, rtol=rtol, atol=atol, progress=progress,
                     **params)

    def periodic(self, period=None, angle=None, measure=(), settle: float | None = None,
                 method: str | None = None, rtol: float | None = None,
                 atol: float | None = None, progress=None, **params: float):
        """The periodic steady state by shooting (`amilpy.analysis.periodic`): after
        `period` (a number or an expression of constants, "2*PI/W"), or when state
        NAME has advanced by VALUE (`angle="PHI=2*PI"`); raises NotConverged."""
        from .analysis import Closure
        from .analysis.periodic import periodic

        self._check_method(method)
        return periodic(self, Closure.of(period, angle), self._measures(measure),
                        settle_time=settle, method=method, rtol=rtol, atol=atol,
                        progress=progress, **params)

    def response(self, name: str, start: float, stop: float, period=None, angle=None,
                 measure=(), settle: float | None = None, method: str | None = None,
                 rtol: float | None = None, atol: float | None = None, progress=None,
                 **params: float):
        """The response curve in data value `name` over [start, stop] by continuation
        of the periodic orbit (`amilpy.analysis.response`): stable and unstable
        points, folds located."""
        from .analysis import Closure
        from .analysis.response import response

        self._check_method(method)
        self._specs({**params, name: start})  # an unknown name is an error here
        return response(self, name.upper(), float(start), float(stop),
                        Closure.of(period, angle), self._measures(measure),
                        settle_time=settle, method=method, rtol=rtol, atol=atol,
                        progress=progress, **params)

    def _measures(self, names) -> list[str]:
        from .sweep import default_measure

        names = [names] if isinstance(names, str) else list(names)
        out = [n.upper() for n in names] or [default_measure(self.ir)]
        for n in out:
            if n not in self.ir.variables:
                hint = nearest(n, set(self.ir.variables))
                raise AmilError(f"{n} is not a variable of the model"
                                + (f"; did you mean {hint}?" if hint else ""))
        return out

    @staticmethod
    def _check_method(method: str | None) -> None:
        if method is not None and route_for(method) is None:
            raise AmilError(f"unknown integration method {method}")

    def __repr__(self) -> str:
        return f"<amilpy.Model {self.name!r}: {len(self.ir.states)} states, " \
               f"{len(self.ir.runs)} runs>"


def loads(text: str, name: str = "<listing>") -> Model:
    """Parse and check a listing given as text."""
    program = parse(text, name)
    return Model(check(program, name))


def load(path: str | os.PathLike) -> Model:
    """Parse and check a listing file (UTF-8)."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise AmilError(f"cannot read {path}: {exc.strerror}", path) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        from .diagnostics import Span

        raise AmilError([Diagnostic("the file is not valid UTF-8", Span(line, col),
                                    "save the listing as UTF-8")], path) from None
    return loads(text, path)
