"""What a build gives: the generated functions of one run and the means to locate a
fault in them (`Compiler` in build.py makes these)."""

from __future__ import annotations

import ast as py
import math
from collections.abc import Callable
from dataclasses import dataclass, field

from .. import ir
from .faults import FaultReport, Statement, explain, statement_of, tolerant


@dataclass
class ModelCode:
    """The callables and constants of one run of one model."""

    state_names: list[str]
    y0: list[float]
    z0: list[float]
    out_names: list[str]
    constants: dict[str, float]
    rhs: Callable
    surf: Callable
    out: Callable
    mem: Callable
    watched: list[int]  # surface indices surf() returns, in order
    const_modes: dict[int, float]  # surfaces fixed for the whole run
    modes_literal: Callable  # (t, y, m, z) -> list of literal modes of watched surfaces
    affine_time: set[int]  # surfaces affine in TIME: their roots are breakpoints
    impulses: list[tuple[float, float]]
    tables: dict[str, tuple] = field(default_factory=dict)
    # surf and out over NumPy columns: y is a list of arrays, t an array
    surf_v: Callable | None = None
    out_v: Callable | None = None
    # some memory must be updated after every accepted step (HSTRSS, RST, DERIV,
    # DELAY); when False, memory changes only where a run restarts anyway (ZHOLD, PULSE)
    memory_every_step: bool = False
    # the memory slots whose value is a play (HSTRSS, BCKLSH: `MemorySpec.plays`)
    play_slots: list[int] = field(default_factory=list)
    # the memory slots holding an instant at which the model switches (PULSE's end, a
    # draw's next instant: `MemorySpec.wakes`)
    wake_slots: list[int] = field(default_factory=list)
    # the memory slots that keep instants and counts (DELAY's store: `MemorySpec.clock`)
    clock_slots: frozenset[int] = frozenset()
    # (z, t) -> instants after t at which memory makes the model switch (PULSE ends)
    memory_times: Callable | None = None
    # memory that samples the trajectory inside each accepted step (DELAY's store):
    # sample(t, y, m, z) -> z with those slots updated at (t, y); next_sample(z) -> the
    # next instant one of them asks for (None: no memory samples)
    sample: Callable | None = None
    next_sample: Callable | None = None
    # no step longer than this: a delay the derivatives read, known before the run
    step_limit: float = math.inf
    # (z, ta, tb) -> the instants in (ta, tb) at which such a delayed value passes a
    # stored point (its slope jumps there), or None: `MemorySpec.knots`
    read_knots: Callable | None = None
    # line k of the generated code is statements[k - 1] (None: scaffolding)
    statements: list[Statement | None] = field(default_factory=list)
    # (t, y, m, z) -> the states put where their function holds them (LIMINT's
    # bounds), or None when no state is
    settle: Callable | None = None
    # time switches whose surfaces change sign only at first + k*period (PULSE's
    # train): those instants are breakpoints, and these surfaces are not located
    trains: list[tuple[float, float]] = field(default_factory=list)
    train_surfaces: set[int] = field(default_factory=set)
    # the surfaces each of `trains` turns (its switch's)
    train_owners: list[frozenset[int]] = field(default_factory=list)
    # ACSL form: the names written-order code keeps (z after the memory slots), and
    # that code by function name: (its IR, fn(t, y, m, z, ev) -> (y, z, values))
    kept: list[str] = field(default_factory=list)
    code: dict[str, tuple[ir.Code, Callable]] = field(default_factory=dict)
    # the slots of z the derivatives and the watched surfaces read: memory written
    # elsewhere (an output held by ZHOLD, a name DYNAMIC computes for the printout, a
    # draw only printed) changes nothing the integrator sees, so a run need not
    # restart for it
    seen_memory: frozenset[int] = frozenset()
    # (first instant, period) of the memory's instants known before the run (FST's
    # weather: every day's start), where a chunked integration pauses (`memory_times`)
    memory_trains: list[tuple[float, float]] = field(default_factory=list)
    # whether the integrator sees a memory that changes at its own instants (a draw
    # the derivatives read): then such an instant is most likely a restart
    seen_times: bool = False
    model: ir.Model | None = field(default=None, repr=False)
    namespace: dict = field(default_factory=dict, repr=False)
    checking: dict = field(default_factory=dict, repr=False)  # built on the first fault
    derived: dict = field(default_factory=dict, repr=False)  # built on first use (jacobian)
    # code built from the tree on first use, for every binding of it (see `rebound`)
    shared: dict = field(default_factory=dict, repr=False)
    binder: object = field(default=None, repr=False)  # the Compiler, for `rebound`

    @property
    def module(self) -> py.Module | None:
        """The generated functions' tree, built again at each call (only the code is
        kept: `Compiler.tree`), the caller's to change."""
        return None if self.binder is None else self.binder.tree()

    @property
    def parameter_values(self) -> dict[str, float]:
        """The parameters' globals the generated functions read (p_NAME -> value), for
        code made from them later (the Jacobians, the rolled rhs) to run with."""
        return {k: v for k, v in self.namespace.items() if k.startswith("p_")}

    @property
    def source(self) -> str:
        """The generated scalar functions as Python text (written on first use: most
        runs never need it, and a large model's takes long to write)."""
        return self.binder.source_text()

    def rebound(self, constants: dict[str, float]) -> ModelCode:
        """These functions for a run whose constants differ from these only in the
        parameters' values (`Compiler.parameters`): the same code, executed again
        with the new values; no compilation."""
        if constants == self.constants or self.binder is None:
            return self
        return self.binder.bind(constants)

    def fault_line(self, exc: BaseException) -> int | None:
        """The listing line of the generated statement that raised `exc`."""
        return fault_line(exc)

    def explain_fault(self, exc: BaseException, t: float, y, m, z) -> FaultReport | None:
        """What `exc`, raised by generated code evaluated at (t, y, m, z), did where:
        the statement (its target and span) and the operation with its operand values,
        e.g. "W2 (line 16): division by zero: JL = 0". None if the fault did not
        happen in this model's generated code."""
        return explain(self, exc, t, y, m, z)

    def outputs_tolerant(self, t: float, y, m, z) -> list[float]:
        """The outputs at one point, each statement that faults NaN and no other."""
        return tolerant(self, "out")(t, y, m, z)


def fault_line(exc: BaseException) -> int | None:
    """The listing line of the generated statement that raised `exc`, if the fault
    happened inside generated code."""
    found = statement_of(exc)
    if found is None or found[0] is None or found[0].span is None:
        return None
    return found[0].span.line
