"""The Python front door: load a listing, run it, get `Run` objects back.

    >>> import amilpy
    >>> model = amilpy.loads("X = INTGRL(1.0, -X)\\nTIMER FINTIM = 1.0\\nEND\\n")
    >>> run, = model.run()
    >>> round(float(run["X"][-1]), 6)
    0.367879
"""

from __future__ import annotations

import os
from contextlib import contextmanager
from dataclasses import replace
from typing import TYPE_CHECKING

from . import interrupts, ir
from .check import check
from .diagnostics import AmilError, Diagnostic, UsageError, did_you_mean, in_file, with_hint
from .outcome import was_interrupted
from .parse import parse
from .progress import report
from .routes import METHODS, route_for

if TYPE_CHECKING:
    from .result import Run
    from .run import Cache, Flow


class Model:
    """A checked listing, ready to run any number of times. It keeps what its runs
    share (generated functions, INITIAL values, output grids) in `cache`."""

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

    def python_source(self, weather_dir: str | list[str] | None = None,
                      **params: float) -> str:
        """The generated Python of the first run (what `--show-python` prints)."""
        from .run import Options, prepare

        spec = self._specs(params)[0]
        if self.ir.acsl is not None:
            from .run.acsl import prepare_acsl

            return prepare_acsl(self.ir, spec, cache=self.cache).code.source
        from .run.plan import DEFAULTS

        # (the code is the same however many rows a run then keeps or streams)
        opts = Options(weather_dirs=_folders(weather_dir), max_rows=DEFAULTS["max_streamed_rows"])
        return prepare(self.ir, spec, opts, cache=self.cache, code_only=True).code.source

    def flow(self, method: str | None = None, rtol: float | None = None,
             atol: float | None = None, run: int = 0, **params: float) -> Flow:
        """The flow map of run `run` (its data, with `params` overriding): see
        `amilpy.run.flow` for `advance`, its events and its sensitivity."""
        from .run import Flow, Options

        _check_method(method)
        self._flow_map()
        spec = self._specs(params)[run]
        return Flow(self.ir, spec, Options(method=method, rtol=rtol, atol=atol), self.cache)

    def _flow_map(self) -> None:
        """Refuse what needs the model's flow map (`flow`, the analyses) in ACSL form."""
        if self.ir.acsl is not None:
            raise AmilError("a flow map is not available for a program in ACSL form: its "
                            "DISCRETE sections and DYNAMIC statements run between the "
                            "integrator's steps", self.ir.path)

    def _specs(self, params: dict[str, float]) -> list[ir.RunSpec]:
        from .parse.fortran import PARAMETER_OF

        known = set(self.ir.data_names)
        overrides = {}
        for key, value in params.items():
            name = key.upper()
            if name not in known and PARAMETER_OF(name) in known:
                name = PARAMETER_OF(name)  # (a PARAM a routine changes: its first value)
            if name not in known:
                raise UsageError([Diagnostic(
                    f"{name} is not a PARAM/CONST/INCON value of this model",
                    None, did_you_mean(name, known) or
                    "only data values can be set from outside")], self.ir.path)
            try:
                overrides[name] = float(value)
            except (TypeError, ValueError):
                raise UsageError(f"{name} must be a number, got {value!r}") from None
        return [spec.overridden(overrides) for spec in self.ir.runs]

    def run(self, method: str | None = None, rtol: float | None = None,
            atol: float | None = None, *, events: bool = True,
            outputs: list[str] | None = None, max_steps: int | None = None,
            max_events: int | None = None, max_time: float | None = None,
            fintim: float | None = None, progress=None, advice: bool = True,
            step_point: bool | None = None, seed: float | None = None,
            weather_dir: str | list[str] | None = None,
            jobs: int = 1, scheduler: str | None = None, data=None,
            stream_csv=None, csv_names: list[str] | None = None,
            csv_dialect: str = "plain", **params: float) -> list[Run]:
        """Run every run of the listing (value lists, END groups); data values
        given as keywords override the listing's for all of them.

        `data`: a CSV of observations (a path, or `amilpy.observed.read`'s result):
        each run gets rows at their instants and `Run.observed`, its comparison
        with them (see `amilpy.observed`).

        `stream_csv`: a path (or an `output.stream.CsvStream`, which the caller
        then closes): write the runs' CSV (`csv_names` its columns, default every
        PRINT/OUTPUT/PREPARE variable; `csv_dialect`) as the runs go, keeping in
        memory only the PRDEL rows, observed instants and a sample of the OUTDEL
        rows for the figures (see `amilpy.output.stream`): for runs whose rows would
        not fit in memory. The runs are then made here, one after the other.

        `step_point=True` runs a fixed-step method in step-point mode (the classic
        translators' loop: switches read at the step points, nothing located), False
        takes METHOD EULER/RECT out of it; None: the listing's choice. `seed` seeds
        the random streams (GAUSS, UNIF, OU...) instead of the listing's RNSEED.
        `weather_dir`: folder(s) of CABO weather files for an FST listing's WEATHER,
        looked in after the listing's own (see `amilpy.library.weather`).

        `jobs`: worker processes for the runs, which are independent (the command
        line uses every core); `scheduler`: the address of a Dask scheduler to run
        them on instead (`amilpy[cluster]`). Either way the runs come back in their
        order, the same as run one after the other, and a run whose data cannot be
        evaluated comes back FAILED with its message (it does not stop the others).
        `progress` (`amilpy.progress`): given a Report of each run's TIME now and
        then (runs here only), and one as each run finishes (task "runs")."""
        from .output.views import install

        install()  # (how the runs show themselves: Run.plot, a notebook's table)
        _check_method(method)
        _check_tolerances(rtol, atol)
        specs = self._specs(params)
        obs = self._observations(data, len(specs))
        if outputs is not None:
            outputs = self.known_names(outputs)
            if obs is not None:  # (the observed variables are recorded too)
                outputs += [n for n in dict.fromkeys(s.name for s in obs.series)
                            if n not in outputs]
        opts = _run_options(method, rtol, atol, max_steps, max_events, events=events,
                            outputs=outputs, max_time=max_time, progress=progress,
                            fintim=fintim, step_point=step_point, seed=_seed(seed),
                            weather_dirs=_folders(weather_dir),
                            extra_times=tuple(obs.times().tolist()) if obs is not None
                            else ())
        if stream_csv is None:
            self._check_memory(specs, outputs, fintim)
            return self._runs(specs, opts, obs, advice, jobs, scheduler, progress)
        from .output.sheets import partial_notes
        from .output.stream import CsvStream

        if csv_names is not None:
            csv_names = self.known_names([n for n in csv_names if n.upper() != "TIME"],
                                         data=True)
        own = not isinstance(stream_csv, CsvStream)  # (else the caller closes it)
        sink = CsvStream(stream_csv, csv_names, csv_dialect, [s.data for s in specs]) \
            if own else stream_csv
        opts.row_sink = sink
        try:
            runs = self._runs(specs, opts, obs, advice, 1, None, progress, sink)
            if own:
                sink.close(partial_notes(runs), [r.params for r in runs])
        except BaseException:
            sink.discard()
            raise
        if sink.rows > sink.kept:
            for run in runs:
                run.warnings.append(f"the OUTDEL rows ({sink.rows} in all) went to "
                                    f"{sink.path} as the runs went; {sink.kept} of them, "
                                    "evenly spaced, are kept for the figures")
        return runs

    def _runs(self, specs, opts, obs, advice: bool, jobs: int, scheduler, progress,
              sink=None) -> list[Run]:
        runs = []
        advised = False
        farmed = self._farm(specs, opts, jobs, scheduler, progress)
        for k, spec in enumerate(specs):
            if sink is not None:
                sink.next_run(k + 1)
            run = farmed[k] if farmed else self._one(spec, opts, len(specs) > 1)
            if advice and not advised:
                from .run.advice import stiffness_advice

                run.advice = stiffness_advice(self.ir, spec, run, replace(opts, row_sink=None),
                                              self.cache)
                advised = run.advice is not None  # say it once
            if obs is not None:
                from .observed import compare

                run.observed = compare(run, obs, k + 1, self._why_no_row())
            runs.append(run)
            if was_interrupted(run.message):
                break  # Ctrl-C: keep what was computed, start nothing new
            if self._ends_job(run) and k + 1 < len(specs):
                left = len(specs) - k - 1
                run.warnings.append(
                    f"a routine's STOP ended the program here, as Fortran's does: the "
                    f"{left} later run{'s are' if left > 1 else ' is'} not made")
                break
            if not farmed:
                report(progress, "runs", k + 1, len(specs), index=k)
        return runs

    def _ends_job(self, run: Run) -> bool:
        """Whether a routine's STOP or FATALERR stopped the run (`ir.Model.ending`)."""
        from .result import EventKind, Status

        return run.status == Status.STOPPED and bool(run.events) and \
            run.events[-1].kind == EventKind.TERMT and run.events[-1].surface in self.ir.ending

    def _observations(self, data, runs: int):
        """`data` read and checked (None: none)."""
        if data is None:
            return None
        from .observed import Observations, read

        if isinstance(data, Observations):
            return data
        return read(os.fspath(data), self.ir.variables, runs)

    def _why_no_row(self) -> str:
        """What to change when a run cannot have a row at an observed instant."""
        if self.ir.acsl is not None:
            return (f"step-point mode (IALG 3, Euler) has rows at its steps only: make "
                    f"{self.ir.acsl.cint_name} divide the observations' instants, or run "
                    "without step-point mode")
        return ("step-point mode has rows at its steps only: make DELT divide the "
                "observations' instants, or run without step-point mode")

    def stored_values(self, fintim: float | None = None, outputs: list[str] | None = None,
                      **params: float) -> float:
        """How many values the runs would keep (rows x columns; 0 for the ACSL form,
        whose rows are known only as it runs)."""
        if self.ir.acsl is not None:
            return 0.0
        return self._stored(self._specs(params), self._columns(outputs), fintim)

    def most_rows(self, fintim: float | None = None, **params: float) -> float:
        """The most output rows any run would have (0 for the ACSL form)."""
        from .run.plan import output_rows

        if self.ir.acsl is not None:
            return 0.0
        return max(self._per_run(self._specs(params), lambda s: output_rows(s, fintim)))

    def _columns(self, outputs: list[str] | None) -> int:
        """The columns a run keeps: the outputs asked for, else every variable."""
        return len(outputs) if outputs is not None else len(self.ir.variables)

    def _stored(self, specs, columns: int, fintim) -> float:
        from .run.plan import stored_values

        return sum(self._per_run(specs, lambda s: stored_values(s, columns, fintim)))

    def _per_run(self, specs, count) -> list[float]:
        """`count` of each run's spec; a fault in its TIMER located in the listing."""
        with in_file(self.ir.path, self.ir.source):
            return [count(spec) for spec in specs]

    def _check_memory(self, specs: list[ir.RunSpec], outputs: list[str] | None,
                      fintim: float | None) -> None:
        """Refuse, before the first run, runs whose rows together would not fit. (In
        ACSL form the rows follow CINT and TERMT, known only after INITIAL: a run is
        capped at language.MAX_INTERVALS rows instead.)"""
        from .run.plan import DEFAULTS

        if self.ir.acsl is not None:
            return
        columns = self._columns(outputs)
        total = self._stored(specs, columns, fintim)
        limit = DEFAULTS["max_values"]
        if total > limit:
            raise AmilError(
                f"the {len(specs)} run(s) would keep {total:.3g} values ({columns} variables "
                f"on every output row; limit {limit:.0e}, about {8 * limit / 1e9:.1f} GB): "
                "raise OUTDEL/PRDEL, shorten FINTIM, or run fewer values at a time")

    def _one(self, spec: ir.RunSpec, opts, among_others: bool) -> Run:
        """One run here. Among other runs, one whose data cannot be evaluated comes
        back FAILED with its message, as from a worker (`_farm`), and the others
        are kept; alone, its fault is the listing's (exit 1, located)."""
        from .run import simulate

        if not among_others:
            return simulate(self.ir, spec, opts, self.cache)
        from .batch.farm import failed_run
        from .run.plan import resolve_route

        try:
            return simulate(self.ir, spec, opts, self.cache)
        except AmilError as exc:
            if exc.path is None:
                exc.path = self.ir.path
            return failed_run(spec, resolve_route(spec, opts)[1], exc.render())

    def _farm(self, specs: list[ir.RunSpec], opts, jobs: int, scheduler: str | None,
              progress) -> list[Run] | None:
        """The runs, farmed out (see `amilpy.batch.farm`); None to run them here, one by one."""
        if not scheduler and (jobs <= 1 or len(specs) <= 1):
            return None
        from .batch.farm import failed_run, run_tasks
        from .run.plan import resolve_route

        finished = [0]

        def done(i: int, _outcome) -> None:  # (in the order they finish)
            finished[0] += 1
            report(progress, "runs", finished[0], len(specs), index=i)

        outcomes = run_tasks(self.ir, specs, opts, jobs, scheduler, cache=self.cache,
                             done=done)
        return [o.run if o.run is not None else failed_run(
            spec, resolve_route(spec, opts)[1],
            "interrupted before it finished" if o.interrupted else o.error or "not run")
            for o, spec in zip(outcomes, specs, strict=True)]

    def check_accuracy(self, runs: list[Run], *, fintim: float | None = None,
                       step_point: bool | None = None, seed: float | None = None,
                       weather_dir: str | list[str] | None = None,
                       **params: float) -> list:
        """Each of `runs` (this model's, as `run` gave them, with the same keyword
        values and options) repeated with a 100 times smaller RELERR and ABSERR (a
        fixed-step method: DELT / 4) and compared on the output grid:
        `run.accuracy.AccuracyCheck` per run; `output.words.accuracy_lines` says in
        words which printed digits stand and which variation is numerical."""
        from .run import Options
        from .run.accuracy import AccuracyCheck, compare, printed_names, tightened

        out = []
        for spec, run in zip(self._specs(params), runs, strict=False):
            if not run.ok:
                out.append(AccuracyCheck(run.label, "", (), 0, 0, None, "the run failed"))
                continue
            try:
                tight_spec, tols, how = tightened(spec, run, route_for(run.method).fixed)
            except ValueError as exc:
                out.append(AccuracyCheck(run.label, "", (), 0, 0, None, str(exc)))
                continue
            opts = Options(method=run.method, rtol=tols.get("rtol"), atol=tols.get("atol"),
                           fintim=fintim, step_point=step_point, seed=_seed(seed),
                           weather_dirs=_folders(weather_dir))
            tight = self._one(tight_spec, opts, True)
            if not tight.ok:
                out.append(AccuracyCheck(run.label, how, (), 0, 0, None,
                                         f"the tighter run failed: {tight.message}"))
                continue
            out.append(compare(run, tight, how, printed_names(run)))
        return out

    def sweep(self, name: str, values, *, both_ways: bool = False, carry_state: bool = False,
              settle: float = 0.0, measure: str | None = None, method: str | None = None,
              rtol: float | None = None, atol: float | None = None,
              fintim: float | None = None, keep_runs: bool = False, progress=None,
              step_point: bool | None = None, seed: float | None = None,
              weather_dir: str | list[str] | None = None,
              jobs: int = 1, scheduler: str | None = None, max_time: float | None = None,
              max_steps: int | None = None, max_events: int | None = None,
              **params: float):
        """One run per value of data value `name` (see `amilpy.batch.sweep.sweep`; `jobs`,
        `scheduler` as for `run`, for a sweep that does not carry its state; the
        limits are each point's run's)."""
        from .batch.sweep import sweep
        from .output.views import install

        install()  # (the runs it keeps plot and show themselves)
        _check_method(method)
        return sweep(self, name, [float(v) for v in values], both_ways=both_ways,
                     carry_state=carry_state, settle=settle, measure=measure, method=method,
                     rtol=rtol, atol=atol, fintim=fintim, keep_runs=keep_runs,
                     progress=progress, step_point=step_point, seed=_seed(seed),
                     weather_dirs=_folders(weather_dir), jobs=jobs, scheduler=scheduler,
                     max_time=max_time, max_steps=max_steps, max_events=max_events,
                     **params)

    def montecarlo(self, dists: dict, runs: int | None = None, seed: int | None = 1, *,
                   quantiles=(5.0, 50.0, 95.0), correlation: dict | None = None,
                   outputs: list[str] | None = None, method: str | None = None,
                   rtol: float | None = None, atol: float | None = None,
                   fintim: float | None = None, jobs: int = 1, scheduler: str | None = None,
                   progress=None, max_time: float | None = None,
                   max_steps: int | None = None, max_events: int | None = None,
                   weather_dir: str | list[str] | None = None, stacked: bool = True,
                   step_point: bool | None = None, **params: float):
        """A Monte Carlo (`amilpy.batch.montecarlo`): `runs` runs of the listing's
        first run with each data value in `dists` drawn from its distribution (a
        `batch.distributions.Dist` or its text, "lognormal(0, 0.2)"; `runs` may be
        left out when every one is a table), `seed` the draws' seed;
        `correlation` {(A, B): r} between drawn names (a Gaussian copula). Returns
        a `MonteCarlo`: quantile bands of `outputs` (default every PRINT/OUTPUT
        variable), quantiles of final and TERMINAL values, failed runs with their
        values. The same for a seed whatever `jobs`/`scheduler`. `max_time`:
        wall-clock seconds for the whole study (the runs done by then are kept;
        each run is bounded by it too). `stacked`: where the runs share their
        switching instants (none switches on its own), integrate them all at once
        (`batch.stacked`); False runs them one by one."""
        from .batch.distributions import table_rows
        from .batch.montecarlo import montecarlo, parse_quantiles
        from .output.views import install

        install()
        _check_method(method)
        parsed = _draws(dists)
        if runs is None:
            runs = table_rows(parsed)
            if runs is None:
                raise UsageError("give the number of runs (--runs N)")
        runs, seed = _whole(runs, "runs", 1), _draw_seed(seed)
        pairs = _pairs(correlation)
        variables = self.known_names(outputs) if outputs else None
        opts = _batch_options(method, rtol, atol, fintim, max_time, weather_dir, max_steps,
                              max_events, step_point)
        self._specs(params)  # (unknown names are errors here)
        return montecarlo(self, parsed, runs, seed, quantiles=parse_quantiles(quantiles),
                          correlation=pairs, names=variables, options=opts, jobs=jobs,
                          scheduler=scheduler, progress=progress, max_time=max_time,
                          params={k.upper(): float(v) for k, v in params.items()},
                          stacked=stacked)

    def sensitivity(self, names=None, *, method: str = "local", dists: dict | None = None,
                    measures=(), runs: int | None = None, seed: int | None = 1,
                    outputs: list[str] | None = None, method_ode: str | None = None,
                    rtol: float | None = None, atol: float | None = None,
                    fintim: float | None = None, jobs: int = 1,
                    scheduler: str | None = None, progress=None,
                    max_time: float | None = None, max_steps: int | None = None,
                    max_events: int | None = None, step_point: bool | None = None,
                    weather_dir: str | list[str] | None = None, **params: float):
        """Sensitivities. `method="local"`: (P/Y) dY/dP over the first run of `outputs`
        (default every PRINT/OUTPUT variable) to the data values `names` (default the
        PARAM values), from the variational equations (`analysis.sensitivity.Local`).
        `method="morris"` or `"sobol"`: global indices of `measures` ("X", "X@T",
        "max(X)", "min(X)", a TERMINAL name) over `dists` (name -> distribution, as
        `montecarlo`), `runs` trajectories (Morris) or rows (Sobol), `seed`
        (`batch.indices.Indices`). `method_ode`: the integration method. `max_time`:
        wall-clock seconds for the whole analysis."""
        from .run.flow import FlowFailed

        _check_method(method_ode)
        opts = _batch_options(method_ode, rtol, atol, fintim, max_time, weather_dir,
                              max_steps, max_events, step_point)
        if method == "local":
            from .analysis.sensitivity import local

            if dists:
                raise UsageError("a local sensitivity takes no distributions: give "
                                 "method='morris' or 'sobol' for global indices")
            with _analysis_time(max_time, FlowFailed):
                return local(self, _names(names) or None, _names(outputs) or None,
                             opts, params)
        from .batch.indices import indices

        self._specs(params)
        if runs is None:
            raise UsageError("give the number of runs (--runs N: Sobol's rows, Morris's "
                             "trajectories)")
        return indices(self, method, _draws(dists or {}), _names(measures),
                       _whole(runs, "runs", 1), _draw_seed(seed), options=opts,
                       jobs=jobs, scheduler=scheduler, progress=progress, max_time=max_time,
                       params={k.upper(): float(v) for k, v in params.items()})

    def modes(self, at: float = 0.0, method: str | None = None, rtol: float | None = None,
              atol: float | None = None, progress=None, max_time: float | None = None,
              **params: float):
        """The linear modes about the state at TIME `at` (`amilpy.analysis.linear`):
        eigenvalues, natural frequencies, damping ratios, shapes, the Jacobian.
        `max_time`: wall-clock seconds for the whole analysis (FlowFailed past it)."""
        from .analysis.linear import modes
        from .run.flow import FlowFailed

        _check_method(method)
        with _analysis_time(max_time, FlowFailed):
            return modes(self, at, method=method, rtol=rtol, atol=atol, progress=progress,
                         **params)

    def steady(self, at: float | None = None, guess: dict[str, float] | None = None, *,
               inputs=(), outputs=(), method: str | None = None, rtol: float | None = None,
               atol: float | None = None, progress=None, max_time: float | None = None,
               **params: float):
        """The equilibrium (every derivative zero, in the switch branches that hold
        there) near the initial state or `guess` (state -> value), the field frozen
        at TIME `at` (default the start): `amilpy.analysis.steady.Equilibrium`, with
        its eigenvalues and, given `inputs` (data values) and `outputs` (variables),
        the linear model A, B, C, D about it. Raises `analysis.steady.NoEquilibrium`
        (a FlowFailed) when none is found, or past `max_time` seconds."""
        from .analysis.steady import NoEquilibrium, equilibrium

        self._flow_map()
        _check_method(method)
        _check_tolerances(rtol, atol)
        with _analysis_time(max_time, NoEquilibrium):
            return equilibrium(self, at, guess, method=method, rtol=rtol, atol=atol,
                               inputs=inputs, outputs=outputs, progress=progress, **params)

    def periodic(self, period=None, angle=None, measure=(), settle: float | None = None,
                 method: str | None = None, rtol: float | None = None,
                 atol: float | None = None, progress=None, max_time: float | None = None,
                 **params: float):
        """The periodic steady state by shooting (`amilpy.analysis.periodic`): after
        `period` (a number or an expression of constants, "2*PI/W"), or when state
        NAME has advanced by VALUE (`angle="PHI=2*PI"`); raises NotConverged (also
        when `max_time`, wall-clock seconds for the whole analysis, runs out)."""
        from .analysis import Closure
        from .analysis.periodic import NotConverged, periodic

        self._flow_map()

        _check_method(method)
        with _analysis_time(max_time, lambda text: NotConverged(text, [])):
            return periodic(self, Closure.of(period, angle), self._measures(measure),
                            settle_time=settle, method=method, rtol=rtol, atol=atol,
                            progress=progress, **params)

    def response(self, name: str, start: float, stop: float, period=None, angle=None,
                 measure=(), settle: float | None = None, method: str | None = None,
                 rtol: float | None = None, atol: float | None = None, progress=None,
                 max_time: float | None = None, **params: float):
        """The response curve in data value `name` over [start, stop] by continuation
        of the periodic orbit (`amilpy.analysis.response`): stable and unstable
        points, folds located. `max_time`: wall-clock seconds for the whole curve;
        the points found by then are kept (`Response.timed_out`); NotConverged if
        it runs out before the first point."""
        from .analysis import Closure
        from .analysis.periodic import NotConverged
        from .analysis.response import response

        self._flow_map()

        _check_method(method)
        self._specs({**params, name: start})  # an unknown name is an error here
        with _analysis_time(max_time, lambda text: NotConverged(text, [])):
            return response(self, name.upper(), float(start), float(stop),
                            Closure.of(period, angle), self._measures(measure),
                            settle_time=settle, method=method, rtol=rtol, atol=atol,
                            progress=progress, **params)

    def fit(self, data, free, *, log=(), weights: str = "sd", method: str | None = None,
            rtol: float | None = None, atol: float | None = None, progress=None,
            max_evaluations: int = 200, gradients: str = "differences", **params: float):
        """Fit data values to measurements (`amilpy.analysis.fit`): `data` a CSV of
        observations (see `run`), `free` the values fitted ("B", "B=0:1E-3", or a
        dict name -> (lo, hi)), `log` those fitted on a log scale, `weights` "sd",
        "relative" or "none", `gradients` "differences" (of whole runs) or
        "sensitivities" (the variational equations). Returns an `analysis.fit.Fit`."""
        from .analysis.fit import fit

        _check_method(method)
        return fit(self, data, free, log=log, weights=weights, method=method, rtol=rtol,
                   atol=atol, progress=progress, max_evaluations=max_evaluations,
                   gradients=gradients, **params)

    def _measures(self, names) -> list[str]:
        from .batch.sweep import default_measure

        names = [names] if isinstance(names, str) else list(names)
        return self.known_names(names) or [default_measure(self.ir)]

    def known_names(self, names, data: bool = False) -> list[str]:
        """`names` (a name or several) upper-cased, each a variable of the model or,
        with `data`, one of its data values; a UsageError naming the nearest name
        otherwise."""
        names = [names] if isinstance(names, str) else list(names)
        known = list(self.ir.variables) + (list(self.ir.runs[0].data) if data else [])
        out = [n.strip().upper() for n in names]
        for n in out:
            if n not in known:
                what = "a variable or data value" if data else "a variable"
                raise UsageError(with_hint(f"{n} is not {what} of the model", n, known))
        return out


    def __repr__(self) -> str:
        return f"<amilpy.Model {self.name!r}: {len(self.ir.states)} states, " \
               f"{len(self.ir.runs)} runs>"


def _names(value) -> list[str]:
    """One name or several (a bare string is one name, not its letters)."""
    if value is None:
        return []
    return [value] if isinstance(value, str) else list(value)


def _whole(value, what: str, least: int) -> int:
    """A count or a seed: a whole number, at least `least`."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = float("nan")
    if not (number == number and number == int(number) and number >= least):
        raise UsageError(f"{what} must be a whole number, {least} or more, got {value!r}")
    return int(number)


def _draw_seed(seed) -> int:
    """The seed of an ensemble's draws: a whole number, 0 or more (None: 1)."""
    return _whole(1 if seed is None else seed, "seed", 0)


def _draws(dists) -> dict:
    """name -> Dist from name -> Dist or its text; a name given twice is an error."""
    from .batch.distributions import Dist, parse_dist

    items = dists.items() if hasattr(dists, "items") else dists
    out: dict = {}
    for key, dist in items:  # (a table's path: relative to the working folder)
        name = str(key).strip().upper()
        if name in out:
            raise UsageError(f"{name} has two distributions: give one")
        out[name] = dist if isinstance(dist, Dist) else parse_dist(name, str(dist))
    return out


def _pairs(correlation) -> dict[tuple[str, str], float]:
    """{(A, B): r} from {(A, B): r}, {"A,B": r} or such pairs in a list; a pair given
    twice is an error."""
    out: dict[tuple[str, str], float] = {}
    items = correlation.items() if hasattr(correlation, "items") else (correlation or ())
    for key, r in items:
        parts = key.split(",") if isinstance(key, str) else list(key)
        if len(parts) != 2:
            raise UsageError(f"a correlation is between two names (A, B): got {key!r}")
        a, b = (str(p).strip().upper() for p in parts)
        if (a, b) in out or (b, a) in out:
            raise UsageError(f"the correlation of {a} and {b} is given twice")
        try:
            out[(a, b)] = float(r)
        except (TypeError, ValueError):
            raise UsageError(f"the correlation of {a} and {b} must be a number, got "
                             f"{r!r}") from None
    return out


def _batch_options(method, rtol, atol, fintim, max_time, weather_dir, max_steps, max_events,
                   step_point):
    """The run options every run of an ensemble shares."""
    _check_tolerances(rtol, atol)
    return _run_options(method, rtol, atol, max_steps, max_events, fintim=fintim,
                        max_time=max_time, weather_dirs=_folders(weather_dir),
                        step_point=step_point)


def _check_tolerances(rtol: float | None, atol: float | None) -> None:
    for label, tol in (("rtol", rtol), ("atol", atol)):
        if tol is not None and not tol > 0:
            raise UsageError(f"{label} must be positive, got {tol}")


def _run_options(method, rtol, atol, max_steps: int | None, max_events: int | None,
                 **fields):
    """run.Options from the API's keywords (a limit left out: the default)."""
    from .run import Options

    opts = Options(method=method, rtol=rtol, atol=atol, **fields)
    if max_steps:
        opts.max_steps = max_steps
    if max_events:
        opts.max_events = max_events
    return opts


def _folders(value) -> tuple[str, ...]:
    """One folder or several (weather_dir=)."""
    if value is None:
        return ()
    return (str(value),) if isinstance(value, (str, os.PathLike)) else tuple(map(str, value))


def _seed(seed) -> float | None:
    """A seed as given (a whole number is usual; any finite number is a seed)."""
    if seed is None:
        return None
    try:
        value = float(seed)
    except (TypeError, ValueError):
        raise AmilError(f"seed must be a number, got {seed!r}") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise AmilError(f"seed must be a finite number, got {seed!r}")
    return value


def loads(text: str, name: str = "<listing>") -> Model:
    """Parse and check a listing given as text."""
    program = parse(text, name)
    return Model(check(program, name))


# what a listing that is not UTF-8 is read as: the lab's Windows machines write it
LEGACY_ENCODING = ("cp1250", "Windows-1250 (Central European)")
# a 10,000-mass chain's listing is 2 MB
MAX_LISTING_BYTES = 64 * 2**20


def load(path: str | os.PathLike) -> Model:
    """Parse and check a listing file: UTF-8, else read as Windows-1250 (the lab's
    Windows machines save Polish comments and titles so), with a note."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            # (a device such as /dev/zero never ends: read what a listing can be)
            raw = fh.read(MAX_LISTING_BYTES + 1)
    except OSError as exc:
        raise AmilError(f"cannot read {path}: {exc.strerror}", path) from None
    if len(raw) > MAX_LISTING_BYTES:
        raise AmilError(f"longer than {MAX_LISTING_BYTES // 2**20} MB, which no listing is "
                        "(a device?): give the listing's file", path)
    try:
        return loads(raw.decode("utf-8"), path)
    except UnicodeDecodeError as exc:
        from .diagnostics import Span

        line = raw[: exc.start].count(b"\n") + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        encoding, name = LEGACY_ENCODING
        try:
            text = raw.decode(encoding)
        except UnicodeDecodeError:  # (bytes Windows-1250 leaves undefined: ISO-8859-2)
            encoding, name = "iso-8859-2", "ISO-8859-2"
            text = raw.decode(encoding)
        note = Diagnostic(f"the file is not UTF-8 (from here on): it was read as {name}",
                          Span(line, col), "save the listing as UTF-8 to be sure of its "
                          "characters", severity="warning")
    try:
        model = loads(text, path)
    except AmilError as err:
        err.diagnostics.append(note)
        raise
    model.ir.warnings.append(note)
    return model


@contextmanager
def _analysis_time(max_time: float | None, error):
    """An analysis within `max_time` seconds of wall clock (None: unbounded): past
    it, `error(text)` is raised, unless the analysis kept what it found itself (a
    response curve's points)."""
    if max_time is not None and not max_time > 0:
        raise UsageError(f"max_time must be positive, got {max_time!r}")
    try:
        with interrupts.time_limit(max_time):
            yield
    except interrupts.TimeLimit:
        interrupts.silence_alarm()
        raise error(f"the time limit of {max_time:g} s ran out") from None


def _check_method(method: str | None) -> None:
    """The API's METHOD names are the listing's (routes.ROUTES)."""
    if method is not None and route_for(method) is None:
        raise UsageError(with_hint(f"unknown integration method {method}", method.upper(),
                                   METHODS))

