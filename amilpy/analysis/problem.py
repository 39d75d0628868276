"""The shooting problem at one set of data values: what closes a period, which
states the closing condition holds for, and the residual and its Jacobian.

A period closes either after a known time (`--period EXPR`, forced motion) or
when a state, the angle, has advanced by a known amount (`--angle PHI=2*PI`, a
crank or a forcing phase; the period is then an unknown). The unknowns are the
start values of the *cyclic* states (those that must repeat) and, with an
angle, the period; the angle itself starts on a fixed value, the section. A
state no derivative, surface or memory depends on (a running integral such as
the work done) is *free*: it is carried along and left out of the condition.

    residual = y_c(t0 + T) - y_c(t0)                    (cyclic states)
             [ angle(t0 + T) - angle(t0) - VALUE ]      (with an angle)
    Jacobian = M_cc - I  [ f_c(T) ]                     (M: the flow's monodromy)
               [ M_ac      f_a(T) ]

The Floquet multipliers are the eigenvalues of the Poincare map's Jacobian:
M_cc with a period, M_cc - f_c M_ac / f_a with an angle (the section's normal
is the angle: a start moved off the orbit arrives at the section earlier or
later).

Symmetries. A drive chain written with absolute speeds (the hoist's V1, V2, V3
appear only as differences) has a direction v along which the field does not
change: f(y + c v) = f(y). Every orbit shifted along v is an orbit too, so the
period map has the multiplier 1 exactly and its Jacobian is singular there. Such
directions are found as the common null space of the field's Jacobian (scaled
by the state sizes) at states spread over the first period; Newton then moves
only in the complement (least squares, minimum norm), and the multipliers are
those of the map on the quotient (the trivial 1 per direction is reported
apart).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .. import ir
from ..check.order import reads
from ..diagnostics import AmilError, with_hint
from ..library import lookup
from ..parse import syntax as ast
from ..run import Flow, FlowFailed, State

# tolerances of the analyses when the caller gives none (the listing's RELERR is
# for a transient to be drawn; a Newton iteration needs its residuals to 1E-8)
RTOL, ATOL = 1e-9, 1e-12
# the route when neither the caller nor the listing names one: eighth order from
# the first step after every switch (LSODA starts again at first order there and
# takes several times the steps over a period with four contacts). A settling
# run it finds stiff goes back to AUTO (`stiff_fallback`).
METHOD = "DOP853"


@dataclass(frozen=True)
class Closure:
    """How one period closes: after `period` (an expression of the listing's
    constants), or when state `angle` has advanced by `advance`."""

    period: str | None = None
    angle: str | None = None
    advance: str | None = None

    @classmethod
    def of(cls, period=None, angle=None) -> Closure:
        """From the API's arguments: period a number or an expression; angle
        "NAME=VALUE" or (NAME, VALUE)."""
        if (period is None) == (angle is None):
            raise AmilError("give either a period (forced motion) or an angle NAME=VALUE "
                            "(a state that advances by VALUE per period)")
        if angle is None:
            return cls(period=str(period))
        if isinstance(angle, str):
            if "=" not in angle:
                raise AmilError(f"the angle takes NAME=VALUE (e.g. PHI=2*PI), got {angle!r}")
            name, value = angle.split("=", 1)
        else:
            name, value = angle
        return cls(angle=name.strip().upper(), advance=str(value))

    def describe(self) -> str:
        if self.angle:
            return f"{self.angle} advances by {self.advance}"
        return f"period {self.period}"


def constant(text: str, flow: Flow, what: str, extra: dict[str, float] | None = None
             ) -> float:
    """The value of an expression of the run's constants (data, TIMER and INITIAL
    values, PI, and `extra`): "2*PI/W". `what` names the option in messages."""
    from ..codegen import evaluate_constant
    from ..parse import parse

    try:
        statement = parse(f"ZZ = {text}\n", what).statements[0]
    except AmilError as exc:
        raise AmilError(f"{what} {text!r}: {exc.diagnostics[0].message}") from None
    expr = getattr(statement, "expr", None)
    if expr is None:
        raise AmilError(f"{what} {text!r} is not an expression")
    known = {**flow.code.constants, **(extra or {})}
    for node in ast.walk(expr):
        if isinstance(node, ast.Name) and node.name not in known:
            raise AmilError(with_hint(f"{what} {text!r}: {node.name} is not a constant of "
                                      "this listing (the data, TIMER and INITIAL values "
                                      "and PI are)", node.name, known))
        if isinstance(node, ast.Call):
            func = lookup(node.func)
            if func is None or not func.plain:
                raise AmilError(f"{what} {text!r}: {node.func} is not a plain function of "
                                "constants")
    value = evaluate_constant(flow.model, expr, known, {}, statement.span)
    if not np.isfinite(value) or value <= 0:
        raise AmilError(f"{what} {text!r} is {value:g}; it must be positive")
    return value


def free_states(model: ir.Model) -> set[str]:
    """States that no derivative, switching surface or memory reads, directly or
    through DYNAMIC variables: running integrals, left out of the periodicity."""
    roots: list[ast.Node] = [s.deriv for s in model.states]
    roots += [s.expr for s in model.surfaces if s.purpose in (ir.Purpose.SWITCH,
                                                              ir.Purpose.MEMORY)]
    roots += [a for m in model.memories for a in m.args]
    seen = read_closure(model, roots)
    return {s.name for s in model.states if s.name not in seen}


def read_closure(model: ir.Model, roots: list[ast.Node]) -> set[str]:
    """The names `roots` read, directly or through DYNAMIC variables (and the
    switches' and memory functions' arguments)."""
    by_target = {eq.target: eq.expr for eq in model.dynamic}
    seen: set[str] = set()
    pending = [n for r in roots for n in reads(r, model.switches, model.memories, model.units)]
    while pending:
        name = pending.pop()
        if name in seen:
            continue
        seen.add(name)
        if name in by_target:
            pending.extend(reads(by_target[name], model.switches, model.memories, model.units))
    return seen


SYMMETRY = 1e-8  # a singular value below this fraction of the largest: a symmetry


@dataclass(frozen=True)
class Symmetries:
    """Directions the field does not change along, and bases of their complements
    (orthonormal in coordinates scaled by the state sizes)."""

    vectors: np.ndarray  # cyclic states x k, largest component 1
    basis_c: np.ndarray  # cyclic states x (n_c - k)
    basis_x: np.ndarray  # unknowns x (n_x - k)


def parameter_model(model: ir.Model, spec: ir.RunSpec, name: str
                    ) -> tuple[ir.Model, ir.RunSpec] | None:
    """The model with data value `name` made a state whose derivative is 0, so that a
    flow can change it without being compiled again; None where something worked
    out before the run reads it (INITIAL, an initial value, a memory function's
    arguments, a switching surface that is not watched)."""
    if name not in spec.data:
        return None
    reading = {name}
    grew = True
    while grew:  # the DYNAMIC variables that read it, through each other
        grew = False
        for eq in model.dynamic:
            if eq.target not in reading and \
                    set(reads(eq.expr, model.switches, model.memories, model.units)) & reading:
                reading.add(eq.target)
                grew = True

    def touches(expr) -> bool:
        return bool(set(reads(expr, model.switches, model.memories, model.units)) & reading)

    fixed = (ir.Depends.CONST, ir.Depends.TIME, ir.Depends.IMPULSE)
    if any(touches(eq.expr) for eq in model.initial) or \
            any(touches(s.ic) for s in model.states) or \
            any(touches(a) for m in model.memories for a in m.args) or \
            any(s.depends in fixed and touches(s.expr) for s in model.surfaces):
        return None
    span = model.spans.get(name) or next(iter(model.spans.values()), None)
    state = ir.State(name, ast.Num(spec.data[name], span), ast.Num(0.0, span), span)
    data = {k: v for k, v in spec.data.items() if k != name}
    runs = [replace(r, data={k: v for k, v in r.data.items() if k != name}) for r in model.runs]
    moved = replace(model, states=[*model.states, state],
                    data_names=[n for n in model.data_names if n != name], runs=runs,
                    compiled={}, memo={})
    return moved, replace(spec, data=data)


@dataclass
class Evaluation:
    """The residual at a start, the end of the period, and (when asked) the
    Jacobian and the Poincare map's Jacobian."""

    x: np.ndarray
    residual: np.ndarray
    start: State
    end: State
    events: list
    jacobian: np.ndarray | None = None
    poincare: np.ndarray | None = None
    glam: np.ndarray | None = None  # d(residual)/d(parameter), where known at once


def _unseen(ta: float, tb: float, interp, m, z) -> None:
    """An observer that looks at nothing (see `Problem.evaluate`)."""


class Problem:
    """The shooting problem of one run of a model with given data values."""

    def __init__(self, model, closure: Closure, params: dict[str, float],
                 method: str | None = None, rtol: float | None = None,
                 atol: float | None = None, parameter: str | None = None) -> None:
        """`parameter`: a data value the caller will change (`set`) without a new
        flow, where the listing allows (`parameter_model`); `self.parameter` says
        whether it does."""
        from ..run import Cache, Options

        self.closure = closure
        self.params = dict(params)
        spec = model._specs(params)[0]
        source, cache = model.ir, model.cache
        self.parameter = None
        if parameter is not None:
            moved = parameter_model(model.ir, spec, parameter)
            if moved is not None:
                (source, spec), cache = moved, Cache()
                self.parameter = parameter
        self.chosen = method is None and spec.method is None  # the route is ours
        options = Options(method=METHOD if self.chosen else method,
                          rtol=RTOL if rtol is None else rtol,
                          atol=ATOL if atol is None else atol)
        self.options = dict(method=method, rtol=rtol, atol=atol)
        self.flow = Flow(source, spec, options, cache)
        self.flow.grazing = True  # a dip across a surface inside a step is a crossing
        names = self.flow.state_names
        self.names = names
        self.p_index = names.index(parameter) if self.parameter else None
        self.lam = float(model._specs(params)[0].data[parameter]) if self.parameter else None
        skip = {self.p_index}
        self.free = [i for i, n in enumerate(names) if n in free_states(source) and i not in skip]
        self.angle: int | None = None
        if closure.angle is not None:
            if closure.angle not in names or names.index(closure.angle) in skip:
                raise AmilError(with_hint(f"--angle {closure.angle}: not a state of this "
                                          "listing", closure.angle, names))
            self.angle = names.index(closure.angle)
            if self.angle in self.free:
                raise AmilError(f"--angle {closure.angle}: no derivative depends on it, so "
                                "it cannot mark the period")
        self.cyclic = [i for i in range(len(names))
                       if i not in self.free and i != self.angle and i not in skip]
        self._lengths: dict[float | None, tuple] = {}
        self.set(self.lam)
        self.scale = np.ones(len(names))  # each state's size along the orbit (settle sets it)
        self.period_scale = 1.0
        self.symmetries = self._no_symmetry()

    def on_auto(self, model) -> Problem:
        """The same problem on the AUTO route."""
        opts = dict(self.options, method="AUTO")
        return Problem(model, self.closure, self.params, parameter=self.parameter, **opts)

    def set(self, lam: float | None) -> None:
        """The parameter's value for the evaluations to come (with `parameter`)."""
        self.lam = lam
        if lam not in self._lengths:
            extra = {self.parameter: lam} if self.parameter else None
            c = self.closure
            if c.angle is not None:
                self._lengths[lam] = (None, constant(c.advance, self.flow,
                                                     f"--angle {c.angle}=", extra))
            else:
                period = constant(c.period, self.flow, "--period", extra)
                timer = self.flow.plan.timer
                step = min(timer["OUTDEL"], timer["PRDEL"])
                if period < step:
                    # (the motion is looked at, its switches found and its extremes
                    # taken, at the output instants: over less than one of them any
                    # state comes back to itself within the tolerance, orbit or not)
                    at = f" at {self.parameter} = {lam:g}" if self.parameter else ""
                    raise AmilError(
                        f"--period {c.period!r} is {period:g} s{at}, shorter than the "
                        f"output interval ({step:g} s) at which the motion is looked at: "
                        "give the period of the forcing, or make OUTDEL in the listing's "
                        "TIMER a small part of the period")
                self._lengths[lam] = (period, None)
        self.fixed_period, self.advance = self._lengths[lam]

    # ------------------------------------------------------------ unknowns
    @property
    def size(self) -> int:
        return len(self.cyclic) + (self.angle is not None)

    def unknowns(self, state: State, period: float) -> np.ndarray:
        x = np.asarray(state.y, dtype=float)[self.cyclic]
        return np.append(x, period) if self.angle is not None else x

    @property
    def weights(self) -> tuple[np.ndarray, np.ndarray]:
        """The scales of the unknowns and of the residual."""
        w = self.scale[self.cyclic]
        if self.angle is None:
            return w, w
        return np.append(w, self.period_scale), np.append(w, abs(self.advance))

    def _no_symmetry(self) -> Symmetries:
        nc = len(self.cyclic)
        return Symmetries(np.zeros((nc, 0)), np.eye(nc), np.eye(self.size))

    def find_symmetries(self, states: list[State]) -> None:
        """The directions of cyclic states along which the field's Jacobian (rows:
        the cyclic states and the angle) vanishes at every one of `states`."""
        rows = self.cyclic + ([self.angle] if self.angle is not None else [])
        w = self.scale
        blocks = []
        for s in states:
            jac = self.flow.jacobian(s, s.t, floor=w)
            blocks.append(jac[np.ix_(rows, self.cyclic)] * w[self.cyclic][None, :] /
                          w[rows][:, None])
        stacked = np.vstack(blocks) if blocks else np.zeros((0, len(self.cyclic)))
        if not stacked.size:
            return
        _, sv, vt = np.linalg.svd(stacked)
        null = np.flatnonzero(np.append(sv, np.zeros(len(self.cyclic) - len(sv)))
                              <= SYMMETRY * sv[0])
        if not len(null):
            self.symmetries = self._no_symmetry()
            return
        v_scaled = vt[null].T  # orthonormal, scaled coordinates
        complement = vt[np.setdiff1d(np.arange(len(self.cyclic)), null)].T
        vectors = v_scaled * w[self.cyclic][:, None]
        vectors = vectors / vectors[np.argmax(np.abs(vectors), axis=0),
                                    np.arange(vectors.shape[1])]
        basis_x = complement
        if self.angle is not None:  # the period is not part of any symmetry
            basis_x = np.block([[complement, np.zeros((len(self.cyclic), 1))],
                                [np.zeros((1, complement.shape[1])), np.ones((1, 1))]])
        self.symmetries = Symmetries(vectors, complement, basis_x)

    def quotient(self, poincare: np.ndarray) -> np.ndarray:
        """The Poincare map's Jacobian on the complement of the symmetries."""
        w = self.scale[self.cyclic]
        u = self.symmetries.basis_c
        return u.T @ (poincare * w[None, :] / w[:, None]) @ u

    def period_of(self, x: np.ndarray) -> float:
        return float(x[-1]) if self.angle is not None else self.fixed_period

    def start(self, x: np.ndarray, base: State, t0: float) -> State:
        """The state at t0 with the cyclic states from x, the rest from `base`;
        branches chosen as at a start, memory from `base`."""
        y = np.array(base.y, dtype=float)
        y[self.cyclic] = x[:len(self.cyclic)]
        if self.p_index is not None:
            y[self.p_index] = self.lam
        return self.flow.state(y, None, base.memory, t0)

    # ----------------------------------------------------------- residual
    def evaluate(self, x: np.ndarray, base: State, t0: float, jacobian: bool = False,
                 observer=None) -> Evaluation:
        period = self.period_of(x)
        if not period > 0:
            raise AmilError(f"the period became {period:g}")
        start = self.start(x, base, t0)
        c = self.cyclic
        # with the parameter a state, its column is d(residual)/d(parameter) at once
        # (an angle's period is an unknown, so nothing else moves with it)
        with_p = self.p_index is not None and self.angle is not None
        if jacobian:
            columns = c + [self.p_index] if with_p else c
            end, events, m = self.flow.advance(start, t0, t0 + period, sensitivity=True,
                                               columns=columns, scale=self.scale,
                                               observer=observer)
        else:
            # the route the sensitivity takes (its dense output, step by step), so
            # that every residual of a Newton iteration is made alike
            end, events = self.flow.advance(start, t0, t0 + period,
                                            observer=observer or _unseen)
        if end.t < t0 + period * (1 - 1e-12):
            raise AmilError(f"the run stops at TIME = {end.t:.9g}, inside the period")
        r = end.y[c] - start.y[c]
        if self.angle is not None:
            a = self.angle
            r = np.append(r, end.y[a] - start.y[a] - self.advance)
        ev = Evaluation(x, r, start, end, events)
        if jacobian:
            if not np.all(np.isfinite(m)):
                # (LAPACK would print its complaint on stdout and give up)
                bad = int(np.argmax(~np.isfinite(m).all(axis=1)))
                raise FlowFailed(f"the period map's Jacobian is not finite (the variation "
                                 f"of {self.names[bad]} at TIME = {end.t:.9g}): the "
                                 "motion cannot be linearised there")
            if with_p:
                ev.glam = np.append(m[c, -1], m[self.angle, -1])
                m = m[:, :-1]
            mc = m[c, :]
            if self.angle is None:
                ev.jacobian = mc - np.eye(len(c))
                ev.poincare = mc
            else:
                f = np.asarray(self.flow.field(end, end.t)(end.t, end.y), dtype=float)
                fc, fa = f[c], f[self.angle]
                ma = m[self.angle, :]
                top = np.hstack([mc - np.eye(len(c)), fc[:, None]])
                ev.jacobian = np.vstack([top, np.append(ma, fa)[None, :]])
                if fa == 0:
                    raise AmilError(f"{self.names[self.angle]} does not advance at the end "
                                    "of the period: it cannot mark the period")
                ev.poincare = mc - np.outer(fc, ma) / fa
        return ev
