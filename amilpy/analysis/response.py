"""The response curve: the periodic orbit followed in one data value by
arclength continuation, through folds, stable and unstable alike.

One flow. Where the listing allows (`problem.parameter_model`: nothing worked
out before the run reads the value), the data value becomes a state whose
derivative is 0, so one compiled flow serves the whole curve and, with an
angle, d(residual)/d(value) is one more column of the variational equations;
else each value is a run of its own, compiled when first met.

Coordinates. A point is u = (x, lam): the shooting unknowns (`problem.Problem`)
and the value, scaled (x by X_WEIGHT times the state sizes of the first orbit,
lam by the length of the range) and reduced to the complement of the
symmetries. The start of an orbit on its section turns with the phase of the
response, so the states are weighted down: a state moving by its own size
counts as a fifth of the range.

Step. The predictor is the parabola through the last three points (the
tangent [G_x, G_lam] t = 0 at the first point and after a grazing). The
corrector holds the coordinate the secant moves most in (local
parametrisation, as in AUTO; lam itself away from folds) and is Newton in the
others, each iterate a whole point: residual, monodromy (variational
equations, switches and all), Floquet multipliers and measures from one
integration, so the last iterate is the point. A step is refused and halved
when the corrector fails or lands more than DRIFT steps from its prediction
(another branch); the next step grows by 1.5 (2 on a straight stretch) within
three limits: the secant may turn TURN, and the curve as drawn (lam over the
range against the first measure's half peak-to-peak over the largest so far)
may bend PLOT_TURN and run PLOT_STEP per step.

Grazings and folds (`folds.py`). Where the number of switches per period
changes the curve may turn sharply; the step goes on along the tangent there,
lam turning back if a multiplier crossed +1. Where the corrector cannot follow
the curve even at the smallest step, the reason is given and the curve is taken
up again a little further in lam by Newton in x alone, if it can be.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .. import interrupts
from ..diagnostics import AmilError
from ..progress import report
from ..result import EventKind
from . import folds
from .measure import Stats, Tracker
from .periodic import UNIT, NotConverged, floquet, newton, settled
from .problem import Closure, Evaluation, Problem

DS0, DS_MAX, DS_MIN = 0.02, 0.15, 2e-5  # arclength steps, in units of the whole range
X_WEIGHT = 0.1  # a state moving by its size counts as a tenth of the range
DRIFT = 0.5  # a corrected point this many steps from its prediction: a jump, refused
TURN = 0.25  # radians the secant may turn in one step
# the curve as drawn: lam over the range against the first measure's half
# peak-to-peak over the largest met so far; a segment at most PLOT_STEP long,
# turning at most PLOT_TURN from the one before
PLOT_STEP, PLOT_TURN = 0.08, 0.15
# the largest scaled residual of a point on the curve: an orbit's states to about
# 1E-7/(1 - |mu|) of their size, far below what a figure shows
CURVE_TOL = 1e-7
MAX_POINTS = 2000
MAX_CORRECTOR = 10


@dataclass
class Point:
    """One orbit on the curve."""

    value: float  # the data value
    period: float
    tracker: Tracker = field(repr=False)  # what was seen over the period
    multipliers: np.ndarray
    kind: str = ""  # "", "fold", "end"
    residual: float = 0.0
    start: np.ndarray | None = None  # every state at the start of the orbit
    events: int = 0  # switches per period
    _measures: dict[str, Stats] | None = field(default=None, repr=False)

    @property
    def measures(self) -> dict[str, Stats]:
        """Minimum, maximum, mean of each measured variable (located when first
        asked for: most Newton iterates on the way to a point are never asked)."""
        if self._measures is None:
            self._measures = self.tracker.stats(self.period)
        return self._measures

    @property
    def mu_max(self) -> float:
        return float(np.max(np.abs(self.multipliers))) if len(self.multipliers) else 0.0

    @property
    def stable(self) -> bool:
        return self.mu_max < 1.0 - UNIT


@dataclass
class Response:
    name: str
    closure: Closure
    measures: list[str]
    points: list[Point] = field(default_factory=list)  # along the curve, folds in place
    notes: list[str] = field(default_factory=list)  # flags, what could not be followed
    complete: bool = True  # the curve reached an end of the range
    interrupted: bool = False  # Ctrl-C (SIGTERM, SIGHUP) ended it: the points so far kept
    timed_out: bool = False  # its time limit (`max_time`) ended it: the points so far kept
    names: list[str] = field(default_factory=list)  # the states, in Point.start order

    @property
    def folds(self) -> list[Point]:
        return [p for p in self.points if p.kind == "fold"]


@dataclass
class _Node:
    """A converged point with what continuation needs of it."""

    x: np.ndarray
    lam: float
    ev: Evaluation  # with the Jacobian
    point: Point
    gx: np.ndarray  # G_x U, scaled and reduced
    glam: np.ndarray | None = None  # G_lam, scaled, when the monodromy gave it
    heading: float = 1.0  # the sign lam changed with on the way here

    @property
    def test(self) -> float:
        """det(P - I) = the product of (mu - 1) over the multipliers: its sign changes
        when a real multiplier crosses +1 (a complex pair adds |mu - 1|^2 > 0)."""
        return float(np.prod(self.point.multipliers - 1.0).real)


class Continuation:
    """Follows the orbit of `model` in data value `name` over [start, stop]."""

    def __init__(self, model, name: str, closure: Closure, start: float, stop: float,
                 measures: list[str], params: dict[str, float], method=None, rtol=None,
                 atol=None, settle_time=None, progress: Callable | None = None) -> None:
        self.model, self.name, self.closure = model, name.upper(), closure
        self.start, self.stop = float(start), float(stop)
        self.params = {k.upper(): v for k, v in params.items()}
        self.options = dict(method=method, rtol=rtol, atol=atol)
        self.measure_names = measures
        self.settle_time = settle_time
        self.progress = progress
        self.span = abs(self.stop - self.start)
        if not self.span > 0:
            raise AmilError(f"the range of {self.name} is empty")
        self._problems: dict[float, Problem] = {}
        self.first: Problem | None = None
        self.shared: Problem | None = None
        self.count = 0

    # ------------------------------------------------------------- problems
    def problem(self, lam: float) -> Problem:
        if self.shared is not None:  # the value is a state of one flow: no new compile
            self.shared.set(lam)
            return self.shared
        p = self._problems.get(lam)
        if p is None:
            if len(self._problems) > 8:
                self._problems.clear()
            p = Problem(self.model, self.closure, {**self.params, self.name: lam},
                        **self.options)
            if self.first is not None:  # one metric for the whole curve
                p.scale, p.period_scale = self.first.scale, self.first.period_scale
                p.symmetries = self.first.symmetries
            self._problems[lam] = p
        return p

    def t0(self, lam: float) -> float:
        """The orbit's start: with a period, whole periods after the run's start."""
        if self.closure.angle is not None:
            return self.t_start
        return self.t_init + self.periods * self.problem(lam).fixed_period

    def evaluate(self, x: np.ndarray, lam: float, jacobian: bool = False,
                 observer=None) -> Evaluation:
        return self.problem(lam).evaluate(x, self.base, self.t0(lam), jacobian, observer)

    # ------------------------------------------------------ reduced coordinates
    def reduce(self, dx: np.ndarray, dlam: float) -> np.ndarray:
        return np.append(self.u.T @ (dx / self.wx), dlam / self.span)

    def expand(self, d: np.ndarray) -> tuple[np.ndarray, float]:
        return self.wx * (self.u @ d[:-1]), float(d[-1] * self.span)


    def g_lam(self, x: np.ndarray, lam: float, r: np.ndarray) -> np.ndarray:
        """d(scaled residual)/d(scaled lam) by a forward difference (r: at lam)."""
        h = np.cbrt(self.first.flow.plan.tol.relerr) * max(abs(lam), self.span)
        return (self.evaluate(x, lam + h).residual / self.wr - r) / h * self.span

    def tangent(self, node: _Node, orient: np.ndarray) -> np.ndarray:
        """The unit tangent at a point (the null vector of [G_x, G_lam]), oriented
        like `orient`."""
        glam = node.glam
        if glam is None:
            glam = self.g_lam(node.x, node.lam, node.ev.residual / self.wr)
        t = np.linalg.svd(np.hstack([node.gx, glam[:, None]]))[2][-1]
        return -t if float(t @ orient) < 0 else t

    def node(self, x: np.ndarray, lam: float, residual: float | None = None,
             kind: str = "") -> _Node:
        """The point at (x, lam): its residual, monodromy, multipliers and measures,
        all from one integration."""
        problem = self.problem(lam)
        tracker = Tracker(problem.flow, self.measure_names)
        ev = self.evaluate(x, lam, jacobian=True, observer=tracker)
        period = problem.period_of(x)
        if residual is None:
            residual = float(np.max(np.abs(ev.residual / self.wr))) if ev.residual.size \
                else 0.0
        point = Point(lam, period, tracker, floquet(problem, ev), kind, residual,
                      np.array(ev.start.y), len(ev.events))
        gx = (ev.jacobian * self.wx[None, :] / self.wr[:, None]) @ self.u
        glam = None if ev.glam is None else ev.glam / self.wr * self.span
        return _Node(x, lam, ev, point, gx, glam)

    # --------------------------------------------------------------- corrector
    def correct(self, x: np.ndarray, lam: float, row: np.ndarray, value: float,
                kind: str = "") -> _Node:
        """Newton onto the curve with row . reduce(u - anchor) fixed at `value` (row:
        a unit coordinate, or a plane's normal), from (x, lam). Every iterate is a
        whole point (`node`: the residual with its Jacobian, from the variational
        equations of the same integration), so the last is the point itself; a
        step that does not lower the residual is halved (near a grazing the
        Jacobian changes fast: with the square root of the penetration).
        Raises NotConverged."""
        history: list[float] = []
        free_lam = abs(row[-1]) < 1.0 - 1e-12  # lam moves: G_lam is needed

        def plane(node: _Node) -> float:
            return float(row @ self.reduce(node.x - self.origin_x,
                                           node.lam - self.origin_lam)) - value

        def size(node: _Node) -> float:
            return max(node.point.residual, 1e-2 * abs(plane(node)))

        node = self.node(x, lam, kind=kind)
        for _ in range(MAX_CORRECTOR):
            norm = size(node)
            history.append(norm)
            if not np.isfinite(norm):
                raise NotConverged("the orbit is lost", history)
            if node.point.residual <= CURVE_TOL and abs(plane(node)) <= 1e-10:
                return node
            r = node.ev.residual / self.wr
            glam = node.glam
            if not free_lam:
                glam = np.zeros(len(r))
            elif glam is None:
                glam = self.g_lam(node.x, node.lam, r)
            # least squares: with a symmetry and its balance (the hoist's rigid-body
            # speed and momentum) the system has one more row than rank
            a = np.vstack([np.hstack([node.gx, glam[:, None]]), row[None, :]])
            if not np.all(np.isfinite(a)):  # (LAPACK would print on stdout and give up)
                raise NotConverged("the curve's Jacobian is not finite here", history)
            d = np.linalg.lstsq(a, -np.append(r, plane(node)), rcond=None)[0]
            for halving in range(4):
                dx, dlam = self.expand(d * 0.5 ** halving)
                trial = self.node(node.x + dx, node.lam + dlam, kind=kind)
                if size(trial) < norm:
                    break
            else:
                raise NotConverged("the corrector does not converge", history)
            node = trial
        raise NotConverged("the corrector does not converge", history)

    def solve_on(self, x: np.ndarray, lam: float, row: np.ndarray, value: float,
                 kind: str = "") -> _Node:
        self.origin_x, self.origin_lam = self.anchor
        return self.correct(x, lam, row, value, kind)

    def say(self, lam: float, residual: float) -> None:
        report(self.progress, "response", self.count, name=self.name, value=lam,
               residual=residual)

    # ---------------------------------------------------------------- the curve
    def run(self) -> Response:
        out = Response(self.name, self.closure, self.measure_names)
        node, tangent = self.begin()
        out.names = list(self.first.names)
        out.points.append(node.point)
        self.count = 1
        lo, hi = min(self.start, self.stop), max(self.start, self.stop)
        trail, ds = [node], DS0
        try:
            self.follow(out, node, tangent, trail, ds, lo, hi)
        except KeyboardInterrupt:  # the points found are kept, as a run's rows are
            interrupts.handled()
            out.complete, out.interrupted = False, True
        except interrupts.TimeLimit:  # (the same, at the caller's time limit)
            interrupts.silence_alarm()
            out.complete, out.timed_out = False, True
        return out

    def follow(self, out: Response, node: _Node, tangent: np.ndarray, trail: list[_Node],
               ds: float, lo: float, hi: float) -> None:
        """Along the curve from `node` until an end of [lo, hi], a point it cannot
        pass, or MAX_POINTS."""
        while len(out.points) < MAX_POINTS:
            self.jumped = False
            nxt, ds, tangent = self.step(trail, tangent, ds, out)
            if nxt is None:
                out.complete = False
                break
            nxt.heading = math.copysign(1.0, nxt.lam - node.lam) if nxt.lam != node.lam \
                else node.heading
            if not lo <= nxt.lam <= hi:
                end = self.boundary(node, nxt, hi if nxt.lam > hi else lo)
                if end is not None:
                    folds.flag(self, node, end, out)
                    end.point.kind = "end"
                    out.points.append(end.point)
                break
            folds.flag(self, node, nxt, out)
            out.points.append(nxt.point)
            self.count = len(out.points)
            self.say(nxt.lam, nxt.point.residual)
            if len(nxt.ev.events) != len(node.ev.events) or (node.test > 0) != (nxt.test > 0):
                tangent = self.turned(node, nxt, tangent)
            trail = [nxt] if self.jumped else (trail + [nxt])[-3:]
            node = nxt

    def begin(self) -> tuple[_Node, np.ndarray]:
        """The first point (settled, then Newton) and the tangent towards STOP."""
        first = Problem(self.model, self.closure, {**self.params, self.name: self.start},
                        parameter=self.name, **self.options)
        first, (self.base, self.t_start, x) = settled(first, self.model, self.settle_time)
        self.options["method"] = first.options["method"]  # AUTO if settled found it stiff
        if first.parameter is not None:
            self.shared = first
        else:
            self._problems[self.start] = first
        self.first = first
        self.t_init = first.flow.initial_state().t
        if self.closure.angle is None:
            self.periods = round((self.t_start - self.t_init) / first.fixed_period)
        wx, self.wr = first.weights
        self.wx = wx / X_WEIGHT
        self.u = first.symmetries.basis_x
        ev, history = newton(first, x, self.base, self.t_start,
                             lambda r: self.say(self.start, r.facts["residual"]))
        node = self.node(ev.x, self.start, history[-1])
        node.heading = math.copysign(1.0, self.stop - self.start)
        towards = np.zeros(self.u.shape[1] + 1)
        towards[-1] = self.stop - self.start
        self.largest, self.last_drawn, self.cruise = 0.0, None, DS0
        return node, self.tangent(node, towards)

    def turned(self, node: _Node, nxt: _Node, tangent: np.ndarray) -> np.ndarray:
        """A fold or a grazing (the number of switches per period changed) between
        node and nxt: the curve may turn sharply there. Go on along the tangent at
        nxt (not a secant or a parabola across the turn), lam turning back if a
        multiplier crossed +1 (a fold)."""
        folded = (node.test > 0) != (nxt.test > 0)
        tangent = self.tangent(nxt, tangent)
        want = -node.heading if folded else node.heading
        if tangent[-1] * want < 0:
            tangent = -tangent
        nxt.heading = want
        self.jumped = True
        return tangent

    def step(self, trail: list[_Node], tangent: np.ndarray, ds: float, out: Response):
        """The next point, ds along the curve from the last of `trail` (a parabola
        through the last three points predicts it; halved on failure); the next ds
        and the secant to go on along."""
        node = trail[-1]
        while ds >= DS_MIN:
            guess = self.predict(trail, tangent, ds)
            nxt = self.try_step(node, guess, tangent)
            if nxt is None or float(np.linalg.norm(
                    self.reduce(nxt.x - node.x, nxt.lam - node.lam) - guess)) > DRIFT * ds:
                ds *= 0.5  # no orbit there, or one on another branch
                continue
            secant = self.reduce(nxt.x - node.x, nxt.lam - node.lam)
            length = float(np.linalg.norm(secant))
            if length == 0:
                ds *= 0.5
                continue
            secant /= length
            turn = _angle(secant, tangent)
            seg = self.drawn(node, nxt)
            drawn = float(np.linalg.norm(seg))
            bend = _angle(seg, self.last_drawn) if self.last_drawn is not None else 0.0
            # at a grazing or a fold the curve may turn sharply: take it as it comes
            sharp = len(nxt.ev.events) != len(node.ev.events) or \
                (node.test > 0) != (nxt.test > 0)
            if not sharp and ds > 4 * DS_MIN and (turn > 2 * TURN or bend > 2 * PLOT_TURN
                                                  or drawn > 2 * PLOT_STEP):
                ds *= 0.5
                continue
            limits = [TURN / max(turn, 1e-12), PLOT_TURN / max(bend, 1e-12),
                      PLOT_STEP / max(drawn, 1e-12)]
            grow = min(4.0 if min(limits) > 16 else 2.0 if min(limits) > 4 else 1.5, *limits)
            if sharp:
                grow = max(grow, self.cruise / max(length, 1e-300) / 4)
            self.last_drawn = seg / drawn if drawn > 0 else self.last_drawn
            if not sharp:
                self.cruise = length
            return nxt, float(min(DS_MAX, max(DS_MIN, length * grow))), secant
        nxt = self.jump(node, tangent, out)
        self.jumped = True  # no parabola across the gap
        if nxt is None:
            return None, DS0, tangent
        secant = self.reduce(nxt.x - node.x, nxt.lam - node.lam)
        return nxt, DS0, secant / max(float(np.linalg.norm(secant)), 1e-300)

    def try_step(self, node: _Node, guess: np.ndarray, tangent: np.ndarray) -> _Node | None:
        """Correct the predicted point with the coordinate the tangent moves most in
        held; if that is lam and it fails, with the state coordinate it moves most
        in held (past a fold at a grazing, where lam ends, a state goes on)."""
        order = [int(np.argmax(np.abs(tangent)))]
        if order[0] == len(tangent) - 1 and len(tangent) > 1:
            order.append(int(np.argmax(np.abs(tangent[:-1]))))
        dx, dlam = self.expand(guess)
        for k in order:
            row = np.zeros(len(tangent))
            row[k] = 1.0
            self.anchor = (node.x, node.lam)
            try:
                return self.solve_on(node.x + dx, node.lam + dlam, row, float(guess[k]))
            except (NotConverged, AmilError):
                continue
        return None

    def predict(self, trail: list[_Node], tangent: np.ndarray, ds: float) -> np.ndarray:
        """The reduced step from the last point to the predicted one: along the
        tangent, or by the parabola through the last three points (chord lengths
        as the parameter) when there are three."""
        if len(trail) < 3:
            return ds * tangent
        last = trail[-1]
        pts = [self.reduce(n.x - last.x, n.lam - last.lam) for n in trail[-3:]]
        s1 = float(np.linalg.norm(pts[1] - pts[0]))
        s2 = s1 + float(np.linalg.norm(pts[2] - pts[1]))
        s = s2 + ds
        knots = (0.0, s1, s2)
        guess = np.zeros(len(tangent))
        for i, p in enumerate(pts):
            w = 1.0
            for j, sj in enumerate(knots):
                if j != i:
                    w *= (s - sj) / (knots[i] - sj)
            guess += w * p
        return guess

    def drawn(self, a: _Node, b: _Node) -> np.ndarray:
        """The segment from a to b as the curve is drawn (see PLOT_STEP)."""
        name = self.measure_names[0] if self.measure_names else None
        if name is None:
            return np.array([(b.lam - a.lam) / self.span, 0.0])
        pa, pb = a.point.measures[name].half_pp, b.point.measures[name].half_pp
        self.largest = top = max(self.largest, pa, pb)
        return np.array([(b.lam - a.lam) / self.span, (pb - pa) / top if top > 0 else 0.0])

    def jump(self, node: _Node, tangent: np.ndarray, out: Response) -> _Node | None:
        """The corrector cannot follow past `node`: say why, and take the curve up
        again a little further on in lam, by Newton in x alone."""
        sign = 1.0 if tangent[-1] >= 0 else -1.0
        why = self.why(node)
        for k in (1, 2, 4, 8):
            lam = node.lam + sign * k * 1e-3 * self.span
            problem = self.problem(lam)
            try:
                ev, history = newton(problem, node.x, self.base, self.t0(lam))
            except (NotConverged, AmilError):
                continue
            out.notes.append(f"{self.name} = {node.lam:.7g} ... {lam:.7g}: the orbit could not "
                             f"be followed{why}; taken up again at {lam:.7g}")
            return self.node(ev.x, lam, history[-1])
        out.notes.append(f"{self.name} = {node.lam:.7g}: the orbit could not be followed "
                         f"further{why}")
        return None

    def why(self, node: _Node) -> str:
        events = node.ev.events
        if any(e.kind is EventKind.SLIDE for e in events):
            return " (a switching surface slides on it)"
        if events:
            return f" (it crosses switching surfaces {len(events)} times a period: a " \
                   "grazing contact changes that number)"
        return ""

    def boundary(self, node: _Node, nxt: _Node, lam_end: float) -> _Node | None:
        """The point at the range's end, between `node` and `nxt`."""
        w = (lam_end - node.lam) / (nxt.lam - node.lam)
        x = node.x + w * (nxt.x - node.x)
        try:
            ev, history = newton(self.problem(lam_end), x, self.base, self.t0(lam_end))
        except (NotConverged, AmilError):
            return None
        return self.node(ev.x, lam_end, history[-1])

def _angle(a: np.ndarray, b: np.ndarray) -> float:
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if na == 0 or nb == 0:
        return 0.0
    return math.acos(max(-1.0, min(1.0, float(a @ b) / (na * nb))))


def response(model, name: str, start: float, stop: float, closure: Closure,
             measures: list[str], *, settle_time=None, method=None, rtol=None, atol=None,
             progress: Callable | None = None, **params: float) -> Response:
    """The response curve of `model` (an api.Model) in `name` over [start, stop]."""
    return Continuation(model, name, closure, start, stop, measures, params, method, rtol,
                        atol, settle_time, progress).run()
