"""The flow map: the run loop as a function, for analyses that build on it
(periodic orbits by shooting, Poincare maps, continuation).

    from amilpy.run import Flow, Options
    flow = Flow(model.ir, model.ir.runs[0], Options(method="RADAU", rtol=1e-11,
                                                     atol=1e-13))
    s0 = flow.initial_state()                    # y, branches and memory at t0
    s1, events = flow.advance(s0, 0.0, 2.0)
    s1, events, M = flow.advance(s0, 0.0, 2.0, sensitivity=True)
    s2, events = flow.advance(s1, s1.t, 10.0, stop_at_event=True)
    J = flow.jacobian(s0, 0.0)                   # d f/d y in the branches of s0

`advance` integrates exactly as a run does (same route, tolerances, breakpoints,
event location, sliding and restarts; on the run's own [t0, FINTIM] the AUTO
route checks its surfaces at the same output instants, so a flow from t0 to
FINTIM ends where the run ends; in step-point mode the classic loop, on the
grid t0 + k*DELT from the flow's t0) and records no rows. A failure raises
AmilError with the run's message.

Sensitivity. `sensitivity=True` also gives M = d(final state)/d(initial state),
the monodromy matrix over [t0, t1] (or up to the first event), by central
differences of the flow map: column j is (phi(y + h_j e_j) - phi(y - h_j e_j)) /
(2 h_j), each perturbed flow integrated like the base one. Every located switch
on the way is crossed by the perturbed flows too, at their own instants, so the
saltation of each switch (the jump of the derivatives it causes) is in M
without being written down. With stop_at_event, the end is the event itself
and M is the derivative of that Poincare-type map. The step is
h_j = RELERR**(1/3) * max(|y_j|, mean |y|, ABSERR_j/RELERR_j): the truncation
error, h^2 times the third derivative, and the integration noise, RELERR/h,
then have the same size, RELERR**(2/3). Measured (tests/test_flow.py, RELERR
1E-11, ABSERR 1E-13): the linear oscillator's M matches e^{AT} to 2E-8 relative
on the worst of the variable-step routes (LSODA; 1E-11 on RKS, Radau, DOP853),
and the dead-zone oscillator's, through two switches, its closed form to 1E-8
(RK4 at its default DELT: 6E-10). Variational equations integrated along the
flow, with the saltation matrices written at each event, would be exact to
the integration tolerance and cheaper for many states; they are not done yet.
Give tight tolerances for a monodromy matrix; at the default RELERR 1E-6
expect about 1E-4.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .. import ir
from ..diagnostics import AmilError
from ..outcome import message
from ..result import Event
from .dense import Observers
from .driver import start_cursor
from .grazing import Grazing, Missed
from .jacobian import jacobian_at
from .loop import Cursor, Integrator, Stop
from .plan import Options
from .prepare import Cache, prepare
from .slide import MAX_SLIDING
from .steppoint import StepPoint
from .variational import Tangent
from .watch import SurfaceWatch, TooManySlides, literal_modes

MAX_REFINES = 64  # steps taken again in pieces, per advance (see grazing.py)
GIVE_UP = 8  # dips of one surface found in one advance before it is left alone


class FlowFailed(AmilError):
    """The integration of a flow failed (the run's message says where and why):
    not a fault in the listing as written, but a run that cannot go on."""


@dataclass(frozen=True)
class State:
    """Where a flow stands: the states `y` (in `Flow.state_names` order), the branch
    of every watched surface (`modes`, in `Flow.surfaces` order: -1, 0, +1, a
    QNTZR level, or 0.5 while sliding) and the memory values of HSTRSS, ZHOLD,
    RST, PULSE and DERIV. `t` is the TIME it was taken at (set by `advance`)."""

    y: np.ndarray
    modes: tuple[float, ...]
    memory: tuple[float, ...] = ()
    t: float = field(default=float("nan"), compare=False)


class Flow:
    """The flow map of one run of a model: its data, method and tolerances fixed."""

    def __init__(self, model: ir.Model, spec: ir.RunSpec, options: Options | None = None,
                 cache: Cache | None = None) -> None:
        self.model = model
        self.opts = options or Options()
        prepared = prepare(model, spec, self.opts, cache)
        self.c, self.plan = prepared.code, prepared.plan
        self.watch = SurfaceWatch(self.c, self.plan)
        # monodromy by the variational equations where they apply (else differences)
        self.variational = True
        self.last_sensitivity = ""  # how the last monodromy was made, and why
        # look inside every step for a surface dipping across zero (grazing.py):
        # the analyses need it, a plain flow stays the run's own integration
        self.grazing = False
        self.stiff = False  # a step of an explicit route was limited by stability

    @property
    def code(self):
        """The run's generated functions (`codegen.ModelCode`)."""
        return self.c

    @property
    def state_names(self) -> list[str]:
        return list(self.c.state_names)

    def field(self, state: State, t: float):
        """The vector field a stepper integrates from `state` at `t`: f(t, y) with
        the branches frozen (sliding ones combined), as the loop builds it."""
        integ = Integrator(self.model, self.plan, self.c, self.watch, self.opts)
        return integ.vector_field(Cursor(t, np.array(state.y, dtype=float), list(state.modes),
                                         list(state.memory)))

    def jacobian(self, state: State, t: float, floor=None) -> np.ndarray:
        """d f / d y of the vector field `field` integrates from `state` at `t` (the
        branches frozen as `state.modes` says): from the model's own equations, each
        switch differentiated in its branch (`codegen.jacobian`, exact to rounding);
        while a surface slides, or where the model's own cannot be had, by refined
        central differences of the field with steps from `floor` (the states' sizes;
        default ABSERR/RELERR), as `run.jacobian.jacobian_at` says."""
        return self.linearise(state, t, floor)[0]

    def linearise(self, state: State, t: float, floor=None
                  ) -> tuple[np.ndarray, np.ndarray, str]:
        """`jacobian` with the estimated error of each column and where it came from
        (`run.jacobian.jacobian_at`)."""
        y = np.array(state.y, dtype=float)
        if floor is None:
            floor = self.plan.tol.atol / self.plan.tol.rtol
        field: list = []  # built only when differences are taken

        def f(v):
            if not field:
                field.append(self.field(state, t))
            return field[0](t, np.asarray(v))

        return jacobian_at(self.c, f, t, y, state.modes, state.memory, floor, refine=True)

    @property
    def surfaces(self) -> list[str]:
        """The watched surfaces, as the listing writes them, in `State.modes` order."""
        return [w.text or w.description for w in self.plan.watched]

    def initial_state(self) -> State:
        """The run's start: initial values, the branches the dynamics take at t0,
        memory after its first update."""
        cur = self._start(np.array(self.c.y0, dtype=float), list(self.c.z0), None)
        return State(cur.y, tuple(cur.m), tuple(cur.z), cur.t)

    def state(self, y, modes=None, memory=None, t: float | None = None) -> State:
        """A state at `t` (default the run's t0) from given values; branches chosen
        as at a start when not given, memory from the run's start when not given."""
        z = list(self.c.z0) if memory is None else list(memory)
        cur = self._start(np.array(y, dtype=float), z, None if modes is None else list(modes),
                          t)
        return State(cur.y, tuple(cur.m), tuple(cur.z), cur.t)

    def _integrator(self, plan=None) -> Integrator | StepPoint:
        cls = StepPoint if self.plan.step_point else Integrator
        return cls(self.model, plan or self.plan, self.c, self.watch, self.opts)

    def _start(self, y: np.ndarray, z: list[float], m, t: float | None = None) -> Cursor:
        try:
            if self.plan.step_point:
                # the branches as they read at t0; memory is updated at each step point,
                # the first one included, when the flow advances
                when = self.plan.t0 if t is None else t
                m = literal_modes(self.c, self.plan, when, y.tolist(),
                                  [0.0] * len(self.plan.watched), z) if m is None else m
                return Cursor(when, y, list(m), list(z))
            return start_cursor(self.c, self.plan, self.watch, self.opts, y, z, m, t)
        except (ArithmeticError, ValueError, TooManySlides) as exc:
            when = self.plan.t0 if t is None else t
            why = f"{exc.count} switching surfaces slide at once (at most {MAX_SLIDING})" \
                if isinstance(exc, TooManySlides) else exc
            raise AmilError(f"cannot start at TIME = {when:g}: {why}") from None

    def advance(self, state: State, t0: float, t1: float, *, stop_at_event: bool = False,
                sensitivity: bool = False, columns=None, scale=None, observer=None):
        """Integrate from `state` at `t0` to `t1` (or to the first event, or a
        FINISH/TERMT). Returns (state, events) or, with sensitivity, (state,
        events, M) with M = d(final y)/d(initial y) (see the module docstring).
        `columns`: the initial states M differentiates by (indices; default all,
        M then has one column each); `scale`: each state's typical size, for the
        differencing steps (default: the rule in the module docstring);
        `observer(ta, tb, interpolant, modes, memory)` sees every accepted step
        of the flow itself (not of the perturbed ones)."""
        tangent = None
        # (step-point mode has no dense output for the variational equations to follow)
        if sensitivity and self.variational and not stop_at_event and \
                not self.plan.step_point:
            n = len(state.y)
            floor = self.plan.tol.atol / self.plan.tol.rtol
            if scale is not None:
                floor = np.maximum(floor, scale)
            tangent = Tangent(self.c, self.watch, floor, n,
                              range(n) if columns is None else columns)
            observer = Observers([tangent, observer])
        end, events = self._advance(np.array(state.y, dtype=float), state, t0, t1,
                                    stop_at_event, observer)
        if not sensitivity:
            return end, events
        if tangent is not None and tangent.failed is None:
            self.last_sensitivity = "variational equations"
            return end, events, tangent.phi
        self.last_sensitivity = "differences" + (f" ({tangent.failed})" if tangent else "")
        return end, events, self._monodromy(state, t0, t1, stop_at_event, columns, scale)

    def _advance(self, y: np.ndarray, state: State, t0: float, t1: float,
                 stop_at_event: bool, observer=None) -> tuple[State, list[Event]]:
        cur = Cursor(t0, y, list(state.modes), list(state.memory))
        events: list[Event] = []
        plan, until = self.plan, None  # a step taken again in pieces, up to `until`
        misses: dict[int, int] = {}  # per surface
        for _ in range(MAX_REFINES):
            integ = self._integrator(plan)
            end = t1 if until is None else until
            integ.window(cur.t, end)
            seen = observer
            if self.grazing and not self.plan.step_point:
                guard = Grazing(self.c, self.plan, self.watch,
                                {k for k, n in misses.items() if n >= GIVE_UP})
                seen = Observers([guard, observer])  # the guard first: a missed dip
                # aborts the step
            try:
                integ.integrate(cur, end, stop_at_event=stop_at_event, observer=seen)
            except Missed as miss:
                misses[miss.surface] = misses.get(miss.surface, 0) + 1
                events += integ.events
                cur = Cursor(miss.ta, miss.y, miss.modes, miss.memory)
                plan = replace(self.plan, max_step=(miss.tb - miss.ta) / 16)
                until = miss.tb
                continue
            except Stop as stop:
                raise FlowFailed(message(stop.kind, t=stop.t, **stop.fields)) from None
            except (ArithmeticError, ValueError, TooManySlides) as exc:
                raise FlowFailed(f"integration failed at TIME = {cur.t:.9g}: {exc}") from None
            events += integ.events
            self.stiff = self.stiff or any(w.startswith("stiff") for w in integ.warnings)
            if until is None or integ.stop_reason is not None or cur.t >= t1 or \
                    (stop_at_event and events):
                break
            plan, until = self.plan, None
        else:
            raise FlowFailed(f"integration failed at TIME = {cur.t:.9g}: a switching surface "
                            f"dips across zero inside the steps more than {MAX_REFINES} times")
        return State(cur.y.copy(), tuple(cur.m), tuple(cur.z), cur.t), events

    def _monodromy(self, state: State, t0: float, t1: float, stop_at_event: bool,
                   columns=None, scale=None) -> np.ndarray:
        y = np.array(state.y, dtype=float)
        n = len(y)
        tol = self.plan.tol
        rel = np.cbrt(tol.rtol)
        if scale is None:
            scale = np.maximum(np.abs(y), np.mean(np.abs(y)) if n else 0.0)
        scale = np.maximum(np.asarray(scale, dtype=float), tol.atol / tol.rtol)
        h = rel * scale
        columns = range(n) if columns is None else list(columns)
        out = np.empty((n, len(columns)))
        for k, j in enumerate(columns):
            up, down = y.copy(), y.copy()
            up[j] += h[j]
            down[j] -= h[j]
            hi, _ = self._advance(up, state, t0, t1, stop_at_event)
            lo, _ = self._advance(down, state, t0, t1, stop_at_event)
            out[:, k] = (hi.y - lo.y) / (up[j] - down[j])
        return out
