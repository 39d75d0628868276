"""The generated functions of one run, built as a Python syntax tree and compiled.

Every statement of the generated code (an algebraic equation, a state's
derivative, a surface, a memory update) gets its own line in the code object;
`ModelCode.statements` maps the line back to the IR statement, its target and its
span, so a fault is located from the code's own line table (see `faults`).
"""

from __future__ import annotations

import ast as py
import copy
import math
from collections.abc import Callable, Iterator
from itertools import count

from .. import ir
from ..diagnostics import AmilError, Diagnostic, Span
from ..library import WEATHER_HOLD, lookup, templates
from ..library.surfaces import constant_value, is_affine
from ..library.templates import instantiate
from ..parse import syntax as syn
from ..parse.syntax import deep_enough, no_collection
from . import jacobian, rolled
from .consts import evaluate_constant, initial_slots
from .emit import Emitter, Setting, needs, needs_memories, printed_only_surfaces, truth
from .faults import STATEMENTS, Statement
from .modelcode import ModelCode
from .pytree import (
    column_copy,
    fold,
    function,
    local,
    locate,
    namespace,
    on_line,
    parameter,
    place,
    vector_namespace,
    vectorised,
)
from .written import Statements, start, user_callable

# models with more memory slots than this read them from z instead of unpacking
MAX_UNPACKED_SLOTS = 32

# the code (keys of `Compiler.shared`) that a run builds from rhs's tree on first use:
# the rolled rhs of a large model (rolled.py, tried by every run), the Jacobian
# (jacobian.py, an implicit method's); the tree is kept until both are there
RHS_USERS = ("rolled", "jacobian")
# A model of this many states or more has what every run makes from rhs's tree made
# as soon as rhs is compiled -- the rolled rhs and where its Jacobian can be nonzero
# (`jacobian.structure`: odeint differences a narrow band itself) -- and the tree let
# go before the other functions are built (the 10,000-mass chain's first run peaked at
# 478 MB with the tree kept to then, 462 MB without; benchmarks/largemem.py). A run
# that needs its Jacobian after all (a wide band, METHOD STIFF, steady states) builds
# rhs's tree again.
EARLY_FROM = 1000


def _deepest(model: ir.Model) -> Span | None:
    """The span of the most deeply nested statement of a model."""
    best, where = 0, None
    statements = [(e.expr, e.span) for e in model.dynamic + model.initial]
    statements += [(s.deriv, s.span) for s in model.states]
    for expr, span in statements:
        stack = [(expr, 1)]
        while stack:
            node, depth = stack.pop()
            if depth > best:
                best, where = depth, span
            stack.extend((c, depth + 1) for c in node.children())
    return where


def _with_columns(fn: py.FunctionDef, name: str) -> list[py.FunctionDef]:
    """fn, and its copy for NumPy columns (`name`) if it needs one."""
    copy_ = column_copy(fn, name)
    return [fn] if copy_ is None else [fn, copy_]


def _columns(vector: dict[str, object]) -> dict[str, object]:
    """The functions executed among NumPy's (the vector namespace) with surf_vec and
    out_vec: surf and out themselves where no copy was needed (`_with_columns`)."""
    vector.setdefault("surf_vec", vector["surf"])
    vector.setdefault("out_vec", vector["out"])
    return vector


def memory_read(fn: py.FunctionDef, nz: int, kept: list[str]) -> frozenset[int]:
    """The slots of the memory vector z a generated function reads: its unpacked slots
    (z0, z1, ...) and kept names that it loads, or every slot when it hands z itself
    to a helper (DELAY's store)."""
    loads: set[str] = set()
    whole = False
    for st in fn.body:
        unpack = isinstance(st, py.Assign) and (
            (isinstance(st.value, py.Name) and st.value.id == "z") or
            (isinstance(st.value, py.Subscript) and isinstance(st.value.value, py.Name)
             and st.value.value.id == "z"))
        for node in py.walk(st.value if unpack else st):
            if isinstance(node, py.Name) and isinstance(node.ctx, py.Load):
                if node.id == "z" and not unpack:
                    whole = True
                loads.add(node.id)
    if whole:
        return frozenset(range(nz + len(kept)))
    return frozenset({k for k in range(nz) if f"z{k}" in loads} |
                     {nz + j for j, name in enumerate(kept) if local(name) in loads})


def by_rows(fn: Callable) -> Callable:
    """fn over NumPy columns (t an array, y a list of arrays), a row at a time."""
    import numpy as np

    def columns(t, y, m, z):
        times = np.atleast_1d(np.asarray(t, dtype=float))
        rows = np.column_stack([np.broadcast_to(c, times.shape) for c in y]) if y else \
            np.empty((times.size, 0))
        out = [fn(float(times[i]), rows[i].tolist(), m, z) for i in range(times.size)]
        width = len(out[0]) if out else 0
        return [np.array([r[j] for r in out], dtype=float) for j in range(width)]
    return columns


class Compiler:
    """Builds the `ModelCode` functions of one run from the IR and its constants."""

    def __init__(self, model: ir.Model, constants: dict[str, float], tables,
                 const_modes: dict[int, float], outputs: list[str] | None = None,
                 events: bool = True, setting: Setting | None = None,
                 kept: dict[str, float] | None = None,
                 priors: dict[str, float] | None = None,
                 parameters: frozenset[str] = frozenset()) -> None:
        self.model = model
        self.setting = setting or Setting()
        self.constants = constants
        # ACSL form: the names written-order code keeps between instants (memory
        # slots after the memory functions', in z) with their starting values, and
        # the INITIAL values of names DERIVATIVE computes again (a unit's output
        # keeps that value on a path that does not assign it)
        self.kept = dict(kept or {})
        self.priors = dict(priors or {})
        # constants the code reads as names (PARAM, INCON and what INITIAL derives
        # from them), so that other values need no new code (`bind`)
        self.parameters = frozenset(n for n in parameters if n in constants)
        self.shared: dict = {}
        self.tables = tables
        self.const_modes = const_modes
        self.outputs = outputs
        self.events = events
        printed = printed_only_surfaces(model)
        self.watched = [s.index for s in model.surfaces
                        if s.index not in const_modes and s.index not in printed]
        if not events:
            # only FINISH/TERMT stay watched: they stop the run, they switch nothing
            self.watched = [i for i in self.watched
                            if model.surfaces[i].purpose in ("finish", "termt", "schedule")]
        self.mode_names = {s: f"m{k}" for k, s in enumerate(self.watched)}
        self.mode_names_new = {s: f"n{k}" for k, s in enumerate(self.watched)}
        self.global_tables: dict[str, tuple] = {}
        self.entries = [lookup(m.func, len(m.args)) for m in model.memories]
        # a few slots are unpacked into locals; a large store (DELAY) is read from z
        self.unpacked_z = sum(m.nslots for m in model.memories) <= MAX_UNPACKED_SLOTS
        self.names = count(1)  # bound template arguments, unique over the module
        self.statements: list[Statement | None] = [None]  # line 1: scaffolding
        self.lines: dict[tuple[str, str], int] = {}

    def emitter(self, context: str, new_modes: bool = False) -> Emitter:
        names = self.mode_names_new if new_modes else self.mode_names
        return Emitter(self.model, self.constants, self.const_modes, context, names,
                       self.global_tables, self.tables, self.unpacked_z, self.names,
                       self.setting, self.parameters, define_function=user_callable)

    def line(self, kind: str, target: str, span: Span | None, expr=None) -> int:
        """The generated line of one IR statement (the same in every function)."""
        key = (kind, target, span)
        if key not in self.lines:
            self.statements.append(Statement(kind, target, span, expr))
            self.lines[key] = len(self.statements)
        return self.lines[key]

    def prologue(self, used_states: bool = True, modes: str = "m", mem: bool = True):
        body: list[py.stmt] = []
        n = len(self.model.states)
        if used_states and n:
            targets = [py.Name(local(s.name), py.Store()) for s in self.model.states]
            body.append(py.Assign([py.Tuple(targets, py.Store()) if n > 1 else targets[0]],
                                  py.Name("y", py.Load()) if n > 1 else
                                  py.Subscript(py.Name("y", py.Load()), py.Constant(0),
                                               py.Load())))
        if self.watched:
            prefix = "m" if modes == "m" else "n"
            names = [py.Name(f"{prefix}{k}", py.Store()) for k in range(len(self.watched))]
            src = py.Name(modes, py.Load())
            body.append(py.Assign([py.Tuple(names, py.Store())], src) if len(names) > 1 else
                        py.Assign([names[0]], py.Subscript(src, py.Constant(0), py.Load())))
        nz = sum(m.nslots for m in self.model.memories)
        if mem and nz and self.unpacked_z:
            names = [py.Name(f"z{k}", py.Store()) for k in range(nz)]
            source = py.Name("z", py.Load()) if not self.kept else py.Subscript(
                py.Name("z", py.Load()), py.Slice(None, py.Constant(nz)), py.Load())
            body.append(py.Assign([py.Tuple(names, py.Store())], source)
                        if nz > 1 else py.Assign([names[0]], py.Subscript(
                            py.Name("z", py.Load()), py.Constant(0), py.Load())))
        if mem and self.kept:
            for k, n in enumerate(self.kept):
                body.append(py.Assign([py.Name(local(n), py.Store())], py.Subscript(
                    py.Name("z", py.Load()), py.Constant(nz + k), py.Load())))
        return body

    def algebra(self, roots, em: Emitter) -> list[py.stmt]:
        """The algebraic equations the roots read, in sorted order, one line each; a
        sorting unit's statements where its first output is needed."""
        out: list[py.stmt] = []
        done: set[int] = set()
        for e in needs(self.model, roots):
            if isinstance(e.expr, ir.UnitValue):
                if e.expr.unit not in done:
                    done.add(e.expr.unit)
                    out.extend(self.unit(self.model.units[e.expr.unit], em))
                continue
            out.append(on_line(py.Assign([py.Name(local(e.target), py.Store())],
                                         em.emit(e.expr)),
                               self.line("equation", e.target, e.span, e.expr)))
        return out

    def unit(self, unit: ir.Unit, em: Emitter) -> list[py.stmt]:
        """An IF or PROCEDURAL unit: its outputs' values before it, then its body."""
        first = start(unit.outputs, set(self.kept), self.priors)
        for st in first:
            on_line(st, self.line("code", f"{unit.kind} at line {unit.span.line}", unit.span))
        return first + self.code_emitter(em).block(unit.body)

    def code_emitter(self, em: Emitter) -> Statements:
        return Statements(em, self.line, lambda: f"w{next(self.names)}")

    def surface_algebra(self, em: Emitter) -> list[py.stmt]:
        """What the watched surfaces read: the algebra, then the switch values they
        read outright, each computed once."""
        roots = [self.model.surfaces[i].expr for i in self.watched]
        body = self.algebra(roots, em)
        for name, value, sw in em.hoist(roots):
            line = self.line("switch", f"{sw.written or sw.func} at line {sw.span.line}",
                             sw.span)
            body.append(on_line(py.Assign([py.Name(name, py.Store())], value), line))
        return body

    def state_line(self, s: ir.State) -> int:
        target = s.name
        if s.hidden:  # "INTGRL#W2.1" is the INTGRL inside W2's statement
            kind, _, owner = s.name.partition("#")
            target = f"{kind.rstrip(chr(39))} in {owner.rsplit('.', 1)[0]}"
        return self.line("derivative", target, s.span, s.deriv)

    def surface_line(self, i: int) -> int:
        s = self.model.surfaces[i]
        return self.line("surface", s.description, s.span, s.expr)

    # the generated functions -----------------------------------------------------
    def rhs(self) -> py.FunctionDef:
        # Without events (for comparisons only) switches are read literally at
        # every evaluation, as a naive integrator would, and nothing is watched.
        em = self.emitter("rhs" if self.events else "literal")
        states = self.model.states
        body = self.prologue() + self.algebra([s.deriv for s in states], em)
        values = []
        for s in states:
            value = em.emit(s.deriv)
            if s.runs:  # MODINT holds, LIMINT stops at a bound: the derivative is 0
                value = py.IfExp(em.fill(s.runs, [], [em.mode(i) for i in s.modes]), value,
                                 py.Constant(0.0))
            values.append(on_line(value, self.state_line(s)))
        body.append(py.Return(py.List(values, py.Load())))
        return function("rhs", ("t", "y", "m", "z"), body)

    def surfaces(self) -> py.FunctionDef:
        em = self.emitter("rhs")
        model = self.model
        body = self.prologue() + self.surface_algebra(em)
        values = []
        for i in self.watched:
            s = model.surfaces[i]
            v = em.emit(s.expr)
            if s.kind == ir.SurfaceKind.LEVEL:
                # distance to the edges of the current level's band, in units of P (to
                # the edge itself while sliding on it)
                k = py.Name(self.mode_names[i], py.Load())
                v = py.Call(py.Name("_LEDGE", py.Load()), [v, k], [])
            values.append(on_line(v, self.surface_line(i)))
        # a guarded surface is read where the tests before it, read here, take its
        # branch (the program's own reading of this point: a step's end past where the
        # branch ends does not read it)
        values = self.in_order(body, values, lambda i, value: py.Call(
            py.Name("_SGN", py.Load()), [value], []))
        body.append(py.Return(py.List(values, py.Load())))
        return function("surf", ("t", "y", "m", "z"), body)

    def modes(self) -> py.FunctionDef:
        """The literal modes of the watched surfaces (the restart rule starts there).
        A guarded surface (`ir.Surface.guard`) is read where the surfaces before it
        take its branch: by their literal modes here (by the modes given where one is
        0, on its surface); where not, it keeps its mode. A restart reads them just
        after its instant (`SurfaceWatch.literal_here`)."""
        em = self.emitter("rhs")
        model = self.model
        body = self.prologue() + self.surface_algebra(em)
        values = [on_line(em.literal_mode(model.surfaces[i].kind, em.emit(model.surfaces[i].expr)),
                          self.surface_line(i)) for i in self.watched]
        values = self.in_order(body, values, lambda i, value: py.BoolOp(py.Or(), [
            value, py.Name(self.mode_names[i], py.Load())]))
        body.append(py.Return(py.List(values, py.Load())))
        return function("modes", ("t", "y", "m", "z"), body)

    def in_order(self, body: list, values: list, side: Callable) -> list:
        """`values` (one per watched surface) read as the program reads its tests: in
        order, a guarded surface's only where its guard holds by the sides of the
        surfaces before it (`side(i, value)`: surface i's side from its value here),
        else its mode. Unchanged where no surface is guarded."""
        model = self.model
        if not any(model.surfaces[i].guard is not None for i in self.watched):
            return values
        read = {j for i in self.watched if (g := model.surfaces[i].guard) is not None
                for n in syn.walk(g) if isinstance(n, ir.SwitchValue)
                for j in model.switches[n.switch].surfaces}
        guards = self.emitter("rhs")
        sides = dict(self.mode_names)
        out = []
        for i, value in zip(self.watched, values, strict=True):
            guard = model.surfaces[i].guard
            if guard is not None:
                guards.mode_names = dict(sides)
                value = py.IfExp(truth(guards.emit(guard)), value,
                                 py.Name(self.mode_names[i], py.Load()))
            local = f"w{next(self.names)}"
            body.append(on_line(py.Assign([py.Name(local, py.Store())], value),
                                self.surface_line(i)))
            out.append(py.Name(local, py.Load()))
            if i in read:
                sided = f"w{next(self.names)}"
                body.append(on_line(py.Assign([py.Name(sided, py.Store())],
                                              side(i, py.Name(local, py.Load()))),
                                    self.surface_line(i)))
                sides[i] = sided
        return out

    def outputs_function(self, out_names: list[str]) -> py.FunctionDef:
        em = self.emitter("out" if self.events else "literal")
        roots = [syn.Name(n, Span(0, 0)) for n in out_names]
        body = self.prologue() + self.algebra(roots, em)
        body.append(py.Return(py.List([em.emit(r) for r in roots], py.Load())))
        return function("out", ("t", "y", "m", "z"), body)

    def memory(self) -> py.FunctionDef:
        """Every memory slot after an accepted step (m: the modes the step was taken
        with, mn: the modes from now on)."""
        model = self.model
        em, em_new = self.emitter("mem"), self.emitter("mem", new_modes=True)
        body = self.prologue() + (self.prologue(used_states=False, modes="mn", mem=False)
                                  if self.watched else [])
        body += self.algebra([a for m in model.memories for a in m.args], em)
        # a memory whose update reads its value computes it anyway: once, into a
        # local, when memories nested around it read it too (innermost first)
        nested = {n.memory for m in model.memories for a in m.args for n in syn.walk(a)
                  if isinstance(n, ir.MemoryValue)}
        for mem, func in zip(model.memories, self.entries, strict=True):
            if mem.index in nested and any("VALUE" in templates.template_names(t)
                                           for t in func.memory.update):
                name = f"w{next(self.names)}"
                body.append(on_line(py.Assign([py.Name(name, py.Store())],
                                              em.memory_value(mem)),
                                    self.line("memory", mem.target, mem.span)))
                em.hoisted_memory[mem.index] = name
        new: list[py.expr] = []
        for mem, func in zip(model.memories, self.entries, strict=True):
            args = [em.emit(a) for a in mem.args]
            modes = em.memory_modes(mem, func, args)
            new_modes = em_new.memory_modes(mem, func, args)
            value = em.emit(ir.MemoryValue(mem.index, mem.span))
            line = self.line("memory", mem.target, mem.span)
            for text in func.memory.update:
                e = on_line(em.fill(text, args, modes, new_modes, mem, value), line)
                new.append(on_line(py.Starred(e, py.Load()), line) if templates.spread(text)
                           else e)
        if self.kept:  # the names written-order code keeps: unchanged by a step
            nz = sum(m.nslots for m in model.memories)
            new.append(py.Starred(py.Subscript(py.Name("z", py.Load()),
                                               py.Slice(py.Constant(nz), None), py.Load()),
                                  py.Load()))
        body.append(py.Return(py.List(new, py.Load())))
        return function("mem", ("t", "y", "m", "mn", "z"), body)

    def sample(self) -> py.FunctionDef:
        """The memory slots at a sampling instant inside a step (t, and the state the
        dense output gives there): the memories that sample the trajectory (DELAY's
        store) updated as after a step, every other slot as it is."""
        model = self.model
        em = self.emitter("mem")
        sampled = [(mem, func) for mem, func in zip(model.memories, self.entries, strict=True)
                   if func.memory.samples is not None]
        body = self.prologue() + self.algebra([a for mem, _ in sampled for a in mem.args], em)
        z = py.Name("z", py.Load())
        new: list[py.expr] = []
        for mem, func in zip(model.memories, self.entries, strict=True):
            if func.memory.samples is None:
                new.append(py.Starred(py.Subscript(z, py.Slice(
                    py.Constant(mem.slot), py.Constant(mem.slot + mem.nslots)), py.Load()),
                    py.Load()))
                continue
            args = [em.emit(a) for a in mem.args]
            modes = em.memory_modes(mem, func, args)
            line = self.line("memory", mem.target, mem.span)
            for text in func.memory.update:
                e = on_line(em.fill(text, args, modes, modes, mem), line)
                new.append(on_line(py.Starred(e, py.Load()), line) if templates.spread(text)
                           else e)
        if self.kept:
            nz = sum(m.nslots for m in model.memories)
            new.append(py.Starred(py.Subscript(z, py.Slice(py.Constant(nz), None), py.Load()),
                                  py.Load()))
        body.append(py.Return(py.List(new, py.Load())))
        return function("smp", ("t", "y", "m", "z"), body)

    def sampling(self) -> Callable[[list[float]], float] | None:
        """z -> the next instant at which some memory samples the trajectory (None:
        no memory does)."""
        slots = [m.slot + f.memory.samples for m, f in zip(self.model.memories, self.entries,
                                                          strict=True)
                 if f.memory.samples is not None]
        if not slots:
            return None
        if len(slots) == 1:
            slot = slots[0]
            return lambda z: z[slot]
        return lambda z: min(z[k] for k in slots)

    def horizons(self, constants: dict[str, float]) -> Iterator[tuple[object, object, float]]:
        """(memory, its entry, the delay) of each memory whose value reads a past
        (`MemorySpec.horizon`) at a delay known before the run and positive."""
        for mem, func in zip(self.model.memories, self.entries, strict=True):
            if func.memory.horizon:
                value = constant_value(instantiate(func.memory.horizon, mem.args, mem.span),
                                       constants)
                if value is not None and value > 0.0:
                    yield mem, func, value

    def step_limit(self, constants: dict[str, float]) -> float:
        """The longest step the derivatives allow: no longer than a delay they read
        that is known before the run (`horizons`), so that every stage reads a past
        the store holds; inf if none."""
        read = needs_memories(self.model, [s.deriv for s in self.model.states])
        return min((value for mem, _, value in self.horizons(constants) if mem.index in read),
                   default=math.inf)

    def read_knots(self, constants: dict[str, float]) -> Callable | None:
        """(z, ta, tb) -> the sorted instants in (ta, tb) at which a memory's value
        read a delay known before the run (`horizons`) back passes one of its stored
        points (`MemorySpec.knots`: DELAY's samples); None if no memory has them. A
        delay that changes in time has none here."""
        stores = [(func.memory.knots, mem.slot, mem.nslots, value)
                  for mem, func, value in self.horizons(constants)
                  if func.memory.knots is not None]
        if not stores:
            return None
        if len(stores) == 1:
            (knots, o, size, d), = stores
            return lambda z, ta, tb: knots(z, o, size, d, ta, tb)
        return lambda z, ta, tb: sorted(t for knots, o, size, d in stores
                                        for t in knots(z, o, size, d, ta, tb))

    def check_arguments(self) -> None:
        """Arguments that must be positive or not negative (PULSE's P and W), now that
        the run's constants are known; a fault is located at the call. One that may
        change in time (ACSL DELAY's TDL) is checked here where it is a constant, else
        by its function as the run goes."""
        model = self.model
        for inst in (*model.switches, *model.memories):
            func = lookup(inst.func, len(inst.args))
            for i in (*func.positive_args, *func.nonnegative_args):
                if i in func.constant_args:
                    value = self.constant(inst.args[i], inst.span)
                else:
                    value = constant_value(inst.args[i], self.constants)
                    if value is None:
                        continue
                fault = func.argument_fault(i, value)
                if fault:
                    raise AmilError([Diagnostic(fault, inst.span,
                                                f"{func.signature}: {func.doc}")],
                                    model.path, model.source)

    def settle(self) -> py.FunctionDef:
        """The states put on the values their functions hold them at (LIMINT at a
        bound), the others as they are."""
        em = self.emitter("rhs")
        states = self.model.states
        body = self.prologue() + self.algebra([v for s in states for v, _ in s.onto], em)
        values = []
        for s in states:
            value: py.expr = py.Name(local(s.name), py.Load())
            for target, when in reversed(s.onto):
                value = py.IfExp(em.fill(when, [], [em.mode(i) for i in s.modes]),
                                 em.emit(target), value)
            values.append(on_line(value, self.state_line(s)))
        body.append(py.Return(py.List(values, py.Load())))
        return function("settle", ("t", "y", "m", "z"), body)
    def section(self, fname: str, code: ir.Code) -> py.FunctionDef:
        """Written-order code as `fname(t, y, m, z, ev)` -> (states, z, values of the
        names it assigns); DERIVATIVE's values it reads are computed first."""
        model = self.model
        em = self.emitter("out")
        em.constants = {k: v for k, v in self.constants.items() if k not in code.assigned}
        em.parameters = em.parameters - set(code.assigned)
        known = set(self.kept) | {st.name for st in model.states}
        body = self.prologue()
        first = start(code.assigned, known, self.constants)
        for st in first:
            on_line(st, self.line("code", code.section, code.span))
        body += first
        reads = [n for st in code.body for n in syn.walk(st) if isinstance(n, syn.Name)]
        body += self.algebra(reads, em)
        body += self.code_emitter(em).block(code.body)
        nz = sum(m.nslots for m in model.memories)
        states = py.List([py.Name(local(st.name), py.Load()) for st in model.states], py.Load())
        kept = py.List([py.Starred(py.Subscript(py.Name("z", py.Load()), py.Slice(
            None, py.Constant(nz)), py.Load()), py.Load())]
            + [py.Name(local(n), py.Load()) for n in self.kept], py.Load())
        values = py.List([py.Name(local(n), py.Load()) for n in code.assigned], py.Load())
        body.append(py.Return(py.Tuple([states, kept, values], py.Load())))
        return function(fname, ("t", "y", "m", "z", "ev"), body)

    def sections(self) -> dict[str, ir.Code]:
        """Written-order code run during a run (the ACSL form's DYNAMIC, DISCRETE and
        TERMINAL; FST's EVENT NEWVALUEs; a CSMP TERMINAL with IF or DO blocks), by
        function name."""
        acsl = self.model.acsl
        out: dict[str, ir.Code] = {}
        if acsl is not None:
            out["dynamic"] = acsl.dynamic
            out.update({f"discrete_{k}": d.code for k, d in enumerate(acsl.discretes.values())})
        out.update({f"event_{k}": e.code for k, e in enumerate(self.model.events)})
        terminal = acsl.terminal if acsl is not None else self.model.terminal_code
        out.update({f"terminal_{k}": c for k, c in enumerate(terminal)})
        return out

    @deep_enough()
    @no_collection()
    def build(self) -> ModelCode:
        try:
            return self._build()
        except RecursionError:
            # the reader bounds nesting (syntax.MAX_DEPTH); a Python whose compiler
            # allows less than that still ends in a located model error
            span = _deepest(self.model)
            raise AmilError([Diagnostic(
                "expression nested too deeply to compile", span,
                "split it into several assignments")], self.model.path,
                self.model.source) from None

    def _build(self) -> ModelCode:
        model = self.model
        self.check_arguments()
        name = model.path or model.name
        # Each group of functions is compiled as it is built and its tree let go
        # before the next is built: the code objects are kept, not the trees they
        # were compiled from (a large model's tree takes twenty times the memory of
        # its code: the 1000-mass chain's 20 MB against 1), and one group's tree at
        # most is alive (the 3000-mass chain's whole module took 64 MB, and compiling
        # it 27 MB more). Only rhs's tree is kept, until the code every run may build
        # from it on first use is there (`from_rhs`); a rare user builds the whole
        # tree again (`tree`).
        self.code: list = []
        seen: set[int] = set()
        nz = sum(m.nslots for m in model.memories)
        for group in self.groups():
            self.code.append(compile(py.Module(body=group, type_ignores=[]), name, "exec"))
            if group[0].name in ("rhs", "surf"):
                # the slots of z that rhs and surf read: the same for every binding
                seen.update(memory_read(group[0], nz, list(self.kept)))
            if group[0].name == "rhs":
                self.rhs_tree: py.FunctionDef | None = group[0]
                if len(model.states) >= EARLY_FROM:
                    self._made_early()
            del group
        self.seen = frozenset(seen)
        self._source: str | None = None
        self.lines = {}  # (only the build numbers lines: `statements` is the table)
        return self.bind(self.constants)

    def _made_early(self) -> None:
        """What every run of a large model makes from rhs's tree (EARLY_FROM), made
        now, and the tree let go."""
        n = len(self.model.states)
        self.from_rhs("rolled", lambda rhs, _: rolled.build(rhs, n))
        self.shared["structure"] = jacobian.structure(self.rhs_tree)
        self.rhs_tree = None

    def groups(self) -> Iterator[list[py.FunctionDef]]:
        """The generated functions, folded, every node on its line, a group at a time
        (a function with the elementwise copy that shares its nodes), built in the
        same order every time: the lines and names a build gives are the same."""
        model = self.model
        out_names = self.outputs if self.outputs is not None else model.variables
        self.out_names = list(out_names)
        # surf and out once more for NumPy columns where they have a condition: it may
        # be an array (a memory function reading its condition), so if/else becomes a
        # where(); without one, surf and out work on columns themselves (`_columns`)
        yield self._ready([self.rhs()])
        yield self._ready(_with_columns(self.surfaces(), "surf_vec"))
        yield self._ready([self.modes()])
        yield self._ready(_with_columns(self.outputs_function(out_names), "out_vec"))
        yield self._ready([self.memory()])
        self.samples = any(f.memory.samples is not None for f in self.entries)
        if self.samples:
            yield self._ready([self.sample()])
        self.settles = any(s.onto for s in model.states)
        if self.settles:
            yield self._ready([self.settle()])
        self.code_sections = self.sections()
        for fname, c in self.code_sections.items():
            yield self._ready([self.section(fname, c)])

    @staticmethod
    def _ready(group: list[py.FunctionDef]) -> list[py.FunctionDef]:
        module = fold(py.Module(body=group, type_ignores=[]))
        place(module, closed=True)  # (and assert_closed's check, in the same walk)
        return module.body

    def module(self) -> py.Module:
        """The generated functions' tree, whole (`groups`)."""
        return py.Module(body=[fn for group in self.groups() for fn in group],
                         type_ignores=[])

    @deep_enough()
    @no_collection()
    def tree(self) -> py.Module:
        """The tree of the built code, built again from the IR for its rare users (the
        source text, a fault's explanation, METHOD COMPILED's translation): a new tree
        at each call, the caller's to change. The build is deterministic: the same
        statements on the same lines, so a line of the kept code is this tree's."""
        return Compiler(self.model, self.constants, self.tables, self.const_modes,
                        self.outputs, self.events, self.setting, self.kept, self.priors,
                        self.parameters).module()

    def from_rhs(self, key: str, make: Callable[[py.FunctionDef, bool], object]) -> object:
        """shared[key]: code made from rhs's tree on first use, for every binding of
        this build, by `make(tree, own)`: `own` says whether the tree is make's to
        change (no one else needs it: the last of RHS_USERS, or a tree built again),
        else make leaves it as it is. The kept tree is let go once each of RHS_USERS
        has made its code; a later user gets it built again."""
        if key not in self.shared:
            own = self.rhs_tree is None or all(k in self.shared for k in RHS_USERS
                                               if k != key)
            with no_collection():  # (a large model's makes a million nodes, as a build)
                self.shared[key] = make(self.rhs_function(), own)
            if all(k in self.shared for k in RHS_USERS):
                self.rhs_tree = None
        return self.shared[key]

    def rhs_function(self) -> py.FunctionDef:
        """rhs's tree: the one kept from the build (not to be changed but by its last
        user, `from_rhs`), else built again."""
        if self.rhs_tree is not None:
            return self.rhs_tree
        return next(f for f in self.tree().body if f.name == "rhs")

    @deep_enough()
    def source_text(self) -> str:
        """The generated module as Python text, written once (when asked for)."""
        if self._source is None:
            self._source = py.unparse(self.tree())
        return self._source

    def over_members(self, values: dict[str, object]) -> dict[str, Callable]:
        """The generated functions over NumPy columns whose parameters are arrays as
        well, an element per member of an ensemble integrated at once
        (`batch.stacked`), by name: "rhs_vec" (the right-hand side made elementwise,
        compiled once per build), "out_vec" and "surf_vec" (their own elementwise
        copies) and the written-order sections ("discrete_0", "terminal_0", ...: plain
        arithmetic runs on columns; a branch on a column raises ValueError), run with
        `values` (every parameter's array)."""
        rhs_vec = self.from_rhs("rhs_vec", lambda rhs, _: compile(locate(
            py.Module(body=[vectorised(rhs, "rhs_vec")], type_ignores=[])),
            self.model.path or self.model.name, "exec"))
        vector: dict[str, object] = {"__builtins__": {}, STATEMENTS: self.statements,
                                     **vector_namespace(), **self.global_tables}
        vector.update({parameter(n): v for n, v in values.items()})
        for code in self.code:
            exec(code, vector)  # noqa: S102 - compiler-built tree, closed namespace
        exec(rhs_vec, vector)  # noqa: S102 - the same, elementwise
        return _columns(vector)

    def bind(self, constants: dict[str, float]) -> ModelCode:
        """The built code for one run's constants: executed with its parameters' values
        (cheap: it defines the functions), and the values that depend on them."""
        model = self.model
        binder = copy.copy(self)
        binder.constants = constants
        values = {parameter(n): float(constants[n]) for n in self.parameters}
        scalar: dict[str, object] = {"__builtins__": {}, **namespace(), **self.global_tables,
                                     STATEMENTS: self.statements, **values}
        vector: dict[str, object] = {"__builtins__": {}, STATEMENTS: self.statements,
                                     **vector_namespace(), **self.global_tables, **values}
        for code in self.code:
            exec(code, scalar)  # noqa: S102 - compiler-built tree, closed namespace
            exec(code, vector)  # noqa: S102 - the same code, elementwise functions
        _columns(vector)
        trains, train_owners = binder.trains()
        if model.units:
            # statements (IF, loops) cannot run on columns: one row at a time
            vector["surf_vec"], vector["out_vec"] = by_rows(scalar["surf"]), \
                by_rows(scalar["out"])
        return ModelCode(
            state_names=[s.name for s in model.states],
            y0=[binder.constant(s.ic, s.span) for s in model.states],
            z0=[v for mem, func in zip(model.memories, self.entries, strict=True)
                for text in func.memory.initial
                for v in initial_slots(model, text, mem, constants, self.tables)]
            + list(self.kept.values()),
            out_names=list(self.out_names), constants=constants, rhs=scalar["rhs"],
            surf=scalar["surf"], out=scalar["out"], mem=scalar["mem"],
            watched=self.watched, const_modes=self.const_modes,
            modes_literal=scalar["modes"], affine_time=binder.affine(),
            impulses=binder.impulses(), tables=self.global_tables,
            surf_v=vector["surf_vec"], out_v=vector["out_vec"],
            memory_every_step=any(f.memory.every_step for f in self.entries),
            play_slots=[mem.slot for mem, f in zip(model.memories, self.entries, strict=True)
                        if f.memory.plays],
            wake_slots=self.wake_slots(),
            clock_slots=frozenset(mem.slot + k for mem, f in zip(model.memories, self.entries,
                                                                 strict=True)
                                  if f.memory.clock is not None
                                  for k in f.memory.clock(mem.nslots)),
            memory_times=self.memory_times(),
            memory_trains=[(0.0, 1.0)] if model.weather else [],
            statements=self.statements, model=model,
            namespace=scalar, shared=self.shared, binder=self,
            trains=trains, train_owners=train_owners,
            train_surfaces=set().union(*train_owners),
            settle=scalar["settle"] if self.settles else None, kept=list(self.kept),
            code={fname: (self.code_sections[fname], scalar[fname])
                  for fname in self.code_sections},
            seen_memory=self.seen, seen_times=any(
                self.seen.intersection(range(m.slot, m.slot + m.nslots))
                for m, f in zip(model.memories, self.entries, strict=True)
                if f.memory.wakes is not None or m.func == WEATHER_HOLD),
            sample=scalar["smp"] if self.samples else None, next_sample=self.sampling(),
            step_limit=binder.step_limit(constants), read_knots=binder.read_knots(constants),
        )

    def trains(self) -> tuple[list[tuple[float, float]], list[frozenset[int]]]:
        """The (first instant, period) of the time switches that declare their
        breakpoints (PULSE's train), and each one's watched surfaces."""
        if not self.events or self.setting.step is not None:
            return [], []
        trains, owners = [], []
        for sw in self.model.switches:
            func = lookup(sw.func, len(sw.args))
            watched = frozenset(i for i in sw.surfaces if i in self.watched)
            if func.breaks and watched:
                for pair in func.breaks:
                    trains.append(tuple(self.constant(instantiate(t, sw.args, sw.span),
                                                      sw.span) for t in pair))
                    owners.append(watched)
        return trains, owners

    def affine(self) -> set[int]:
        """Time surfaces affine in TIME: their roots are breakpoints found exactly."""
        model = self.model
        equations = {e.target: e.expr for e in model.dynamic}
        return {i for i in self.watched
                if model.surfaces[i].depends == ir.Depends.TIME and self.events
                and self.setting.step is None
                and model.surfaces[i].kind == ir.SurfaceKind.SIGN
                and is_affine(model.surfaces[i].expr, self.constants, equations)}

    def impulses(self) -> list[tuple[float, float]]:
        model = self.model
        exprs = [e.expr for e in model.dynamic] + [s.deriv for s in model.states]
        exprs += [n for u in model.units for st in u.body for n in syn.walk(st)]
        exprs += [a for sw in model.switches for a in sw.args]
        exprs += [a for m in model.memories for a in m.args]
        exprs += [s.expr for s in model.surfaces]
        return [(self.constant(node.start, node.span), self.constant(node.period, node.span))
                for e in exprs for node in syn.walk(e) if isinstance(node, ir.Impulse)]

    def wake_slots(self) -> list[int]:
        """The memory slots holding an instant at which the model switches (PULSE
        holds its output until the instant kept in its slot, a draw until the next is
        due)."""
        return [m.slot + f.memory.wakes for m, f in zip(self.model.memories, self.entries,
                                                         strict=True)
                if f.memory.wakes is not None]

    def memory_times(self) -> Callable[[list[float], float], list[float]]:
        """The next instants at which memory changes: those its slots hold (PULSE
        holds its output until the instant kept in its slot, a draw until the next is
        due), and FST's weather at every day's start (the day is floor(TIME))."""
        slots = self.wake_slots()
        daily = bool(self.model.weather)

        def times(z: list[float], t: float) -> list[float]:
            held = [z[s] for s in slots if z[s] > t]
            return held + [math.floor(t) + 1.0] if daily else held
        return times

    def constant(self, expr, span: Span) -> float:
        return evaluate_constant(self.model, expr, self.constants, self.tables, span)
