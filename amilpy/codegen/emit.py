"""IR expressions -> Python expressions, in one context, as the library's entries say.

Contexts: "rhs" (frozen modes, IMPULS = 0), "out" (frozen modes, IMPULS exact),
"mem" (like out), "literal" (modes from the current signs: INITIAL/TERMINAL and
initial values). Each emitted node remembers the IR node it came from
(`amil_src`), so a fault can be explained in the listing's notation.

A template argument used twice (DEADSP's X, a switch's surfaces and value in
INITIAL) is bound once (`((w1 := X), ... w1 ...)[-1]`), evaluated only where the
template itself is: nesting such functions N deep gives O(N) code, not O(2**N).
"""

from __future__ import annotations

import ast as py
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from itertools import count

from .. import ir
from ..diagnostics import Span
from ..library import Func, Kind, lookup, runtime_name
from ..library.runtime import Extending, safe_pow
from ..library.templates import ARGUMENTS, argument_uses, tree
from ..parse import syntax as syn
from ..parse.syntax import Visitor
from .pytree import const_value, local, number, parameter, user_function

_PYOPS = {"+": py.Add, "-": py.Sub, "*": py.Mult, "/": py.Div}
_PYCMP = {"<": py.Lt, "<=": py.LtE, ">": py.Gt, ">=": py.GtE, "==": py.Eq, "/=": py.NotEq}


def truth(value: py.expr) -> py.expr:
    """A number used as a condition: `value > 0`."""
    return py.Compare(value, [py.Gt()], [py.Constant(0.0)])


def as_number(test: py.expr, yes: float = 1.0, no: float = 0.0) -> py.expr:
    """A truth used as a number: 1.0 or 0.0."""
    return py.IfExp(test, py.Constant(yes), py.Constant(no))


@dataclass(frozen=True)
class Setting:
    """What generated code takes from how a run is made, not from the listing."""

    seed: float = 1.0  # the random streams' seed (--seed, the listing's RNSEED, else 1)
    hold: float = math.nan  # how long a random draw is held (an output interval, or DELT)
    # step-point mode: DELT. Every switch is read on the spot (in every function,
    # at every stage point); IMPULS is 1 at the first step point at or after an instant
    step: float | None = None


class Emitter(Visitor):
    """Emits Python expressions for IR expressions in one context."""

    complete = ir.EXPRESSIONS

    def __init__(self, model: ir.Model, constants: dict[str, float], const_modes,
                 context: str, mode_names: dict[int, str], tables: dict[str, tuple],
                 source_tables: dict, unpacked_z: bool = True, names=None,
                 setting: Setting | None = None,
                 parameters: frozenset[str] = frozenset(),
                 define_function: Callable | None = None) -> None:
        self.model = model
        # a template's START: the run's start as the listing declares it
        self.start = model.acsl.t0 if model.acsl is not None else 0.0
        # a FUNCTION the listing defines (ACSL form), compiled on first call:
        # `define_function(model, name, constants, tables)` (written.user_callable,
        # given by the builders: its body is emitted by an Emitter too)
        self.define_function = define_function
        self.constants = constants
        # constants read as names (p_NAME), not folded: a run with other values
        # binds the same code to them (see `codegen.params`)
        self.parameters = parameters
        self.const_modes = const_modes
        self.context = context
        self.mode_names = mode_names
        self.tables = tables  # the _T_ tables the emitted code reads (filled here)
        self.source_tables = source_tables  # the run's FUNCTION tables
        self.unpacked_z = unpacked_z
        self.names = names if names is not None else count(1)  # for bound arguments
        self.setting = setting or Setting()
        # switch values already computed into a local, by (switch, output)
        self.hoisted: dict[tuple[int, int], str] = {}
        self.hoisted_memory: dict[int, str] = {}  # memory values likewise, by instance

    def hoist(self, roots: list[syn.Node]) -> list[tuple[str, py.expr, ir.Switch]]:
        """(local, value, switch) for every switch value the roots read outright (not
        inside another switch's branch), innermost first: these are evaluated
        whenever the roots are, so computing each once changes nothing but the
        size of the code (nested LIMITs' surfaces read the switch inside)."""
        keys = sorted({(n.switch, n.output) for r in roots for n in syn.walk(r)
                       if isinstance(n, ir.SwitchValue)})
        out = []
        for key in keys:
            value = self.visit(ir.SwitchValue(key[0], Span(0, 0), key[1]))
            name = f"w{next(self.names)}"
            self.hoisted[key] = name
            out.append((name, value, self.model.switches[key[0]]))
        return out

    def emit(self, e: syn.Node) -> py.expr:
        out = self.visit(e)
        if not hasattr(out, "amil_src"):
            out.amil_src = e
        return out

    # modes -----------------------------------------------------------------------
    def mode(self, surface: int) -> py.expr:
        if surface in self.const_modes:
            return number(self.const_modes[surface])
        if self.context == "literal" or self.setting.step is not None or \
                surface not in self.mode_names:
            # on the spot: INITIAL/TERMINAL, step-point mode, or a surface the run does
            # not watch (comparisons without events read memory conditions so)
            s = self.model.surfaces[surface]
            return self.literal_mode(s.kind, self.emit(s.expr))
        return py.Name(self.mode_names[surface], py.Load())

    @staticmethod
    def literal_mode(kind: ir.SurfaceKind, value: py.expr) -> py.expr:
        fn = "_LEVEL" if kind == ir.SurfaceKind.LEVEL else "_SGN"
        return py.Call(py.Name(fn, py.Load()), [value], [])

    def memory_mode(self, surface: int, literal: py.expr) -> py.expr:
        """At step ends (and output instants: contexts "mem" and "out") a memory
        function reads its condition as it stands (`literal`, so IMPULS, which is 1
        only at its instants, triggers it), or the branch the step was taken in when
        that was the positive one (so a value tracked up to a located crossing is
        kept)."""
        mode = self.mode(surface)
        literal = py.Call(py.Name("_SGN", py.Load()), [literal], [])
        if const_value(mode) is not None:
            return literal if const_value(mode) <= 0 else mode
        return py.IfExp(py.Compare(mode, [py.Gt()], [py.Constant(0.0)]), mode, literal)

    # nodes -------------------------------------------------------------------------
    def visit_Num(self, e: syn.Num) -> py.expr:
        return number(e.value)

    def visit_Name(self, e: syn.Name) -> py.expr:
        if e.name == "TIME" and "TIME" not in self.constants:  # TERMINAL knows TIME
            return py.Name("t", py.Load())
        if e.name in self.parameters:
            return py.Name(parameter(e.name), py.Load())
        if e.name in self.constants:
            return number(self.constants[e.name])
        return py.Name(local(e.name), py.Load())

    def visit_Neg(self, e: syn.Neg) -> py.expr:
        return py.UnaryOp(py.USub(), self.emit(e.operand))

    def visit_Not(self, e: syn.Not) -> py.expr:
        return as_number(truth(self.emit(e.operand)), 0.0, 1.0)

    def visit_UnitValue(self, e: ir.UnitValue) -> py.expr:
        # the unit's statements ran before (Compiler.algebra emits them first)
        return py.Name(local(e.name), py.Load())

    def visit_BinOp(self, e: syn.BinOp) -> py.expr:
        left, right = self.emit(e.left), self.emit(e.right)
        if e.op in _PYCMP:  # evaluated where it stands (sorted code lowers <, > to switches)
            return as_number(py.Compare(left, [_PYCMP[e.op]()], [right]))
        if e.op in ("AND", "OR"):
            op = py.And() if e.op == "AND" else py.Or()
            return as_number(py.BoolOp(op, [truth(left), truth(right)]))
        if e.op in ("EQV", "NEQV"):
            same = py.Eq() if e.op == "EQV" else py.NotEq()
            return as_number(py.Compare(truth(left), [same], [truth(right)]))
        if e.op == "**":
            k = const_value(right)
            if k is not None and k.is_integer() and abs(k) <= 64:
                if k == 2.0 and isinstance(left, py.Name):
                    # x*x: exact and far cheaper than pow
                    return py.BinOp(left, py.Mult(), py.Name(left.id, py.Load()))
                return py.BinOp(left, py.Pow(), py.Constant(int(k)))
            a = const_value(left)
            if a is not None and k is not None:
                return number(safe_pow(a, k))
            return py.Call(py.Name("_POW", py.Load()), [left, right], [])
        return py.BinOp(left, _PYOPS[e.op](), right)

    def visit_Call(self, e: syn.Call) -> py.expr:
        func = lookup(e.func, len(e.args))
        acsl = self.model.acsl
        if func is None and acsl is not None and e.func in acsl.functions:
            # a FUNCTION the listing defines (ACSL form)
            self.tables[user_function(e.func)] = self.define_function(
                self.model, e.func, self.constants, self.source_tables)
            return py.Call(py.Name(user_function(e.func), py.Load()),
                           [self.emit(a) for a in e.args], [])
        if func is None:  # a run-time helper a library template calls (PULSE_ON)
            return py.Call(py.Name("_" + e.func, py.Load()), [self.emit(a) for a in e.args],
                           [])
        if func.kind in (Kind.SWITCH, Kind.TIME) and not func.plain:
            return self.literal_switch(func, e.args)  # literal use (INITIAL/TERMINAL)
        # a plain form: a function of its arguments (ABS, SIN), or a non-smooth switch
        # where it is evaluated once (lowering left it a call)
        args = [self.emit(a) for a in e.args]
        values = [const_value(a) for a in args]
        if all(v is not None for v in values):
            try:
                return number(float(func.scalar(*values)))
            except (ArithmeticError, ValueError, TypeError):
                pass  # left to the run, which reports it where it happens
        return py.Call(py.Name("_" + runtime_name(func), py.Load()), args, [])

    def visit_TableLookup(self, e: ir.TableLookup) -> py.expr:
        name = "_T_" + e.table
        if lookup(e.written or e.func).extends:
            # LINT's own copy notes reads outside the table (one warning per run);
            # "_T__": no table name starts with "_"
            name = "_T__" + e.table
            if name not in self.tables:
                self.tables[name] = Extending(e.table, self.source_tables[e.table])
        else:
            self.tables[name] = self.source_tables[e.table]
        return py.Call(py.Name("_" + e.func, py.Load()), [py.Name(name, py.Load()),
                                                          self.emit(e.x)], [])

    def visit_SwitchValue(self, e: ir.SwitchValue) -> py.expr:
        if (e.switch, e.output) in self.hoisted:
            return py.Name(self.hoisted[e.switch, e.output], py.Load())
        sw = self.model.switches[e.switch]
        func = lookup(sw.func, len(sw.args))
        text = func.values[e.output]
        args, bindings = self.bind([self.emit(a) for a in sw.args], [text])
        return self.bound(bindings, self.fill(text, args, [self.mode(s) for s in sw.surfaces]))

    def visit_MemoryValue(self, e: ir.MemoryValue) -> py.expr:
        if e.memory in self.hoisted_memory:
            return py.Name(self.hoisted_memory[e.memory], py.Load())
        return self.memory_value(self.model.memories[e.memory])

    def visit_Impulse(self, e: ir.Impulse) -> py.expr:
        if self.setting.step is not None:
            return py.Call(py.Name("_IMPULS_STEP", py.Load()),
                           [py.Name("t", py.Load()), self.emit(e.start), self.emit(e.period),
                            number(self.setting.step)], [])
        if self.context == "rhs":
            return py.Constant(0.0)
        return py.Call(py.Name("_IMPULS", py.Load()),
                       [py.Name("t", py.Load()), self.emit(e.start), self.emit(e.period)], [])

    # instances -------------------------------------------------------------------
    def literal_switch(self, func: Func, args) -> py.expr:
        """A switch in INITIAL/TERMINAL: its surfaces' signs taken on the spot."""
        emitted, bindings = self.bind([self.emit(a) for a in args],
                                      [func.values[0], *func.surfaces])
        modes = [self.literal_mode(func.surface_kind, self.fill(t, emitted))
                 for t in func.surfaces]
        return self.bound(bindings, self.fill(func.values[0], emitted, modes))

    def memory_value(self, mem: ir.Memory) -> py.expr:
        func = lookup(mem.func, len(mem.args))
        texts = [func.memory.value]
        if self.context in ("mem", "out"):
            texts += func.surfaces  # memory_mode reads them as they stand
        args, bindings = self.bind([self.emit(x) for x in mem.args], texts)
        modes = self.memory_modes(mem, func, args)
        return self.bound(bindings, self.fill(func.memory.value, args, modes, memory=mem))

    def memory_modes(self, mem: ir.Memory, func: Func, args: list[py.expr]) -> list[py.expr]:
        if self.context not in ("mem", "out"):
            return [self.mode(s) for s in mem.surfaces]
        return [self.memory_mode(s, self.fill(t, args))
                for s, t in zip(mem.surfaces, func.surfaces, strict=True)]

    def bind(self, args: list[py.expr], texts: list[str]
             ) -> tuple[list[py.expr], list[py.NamedExpr]]:
        """Arguments the templates read more than once, unless a name or a number,
        become names bound once."""
        uses = Counter(n for t in texts for n in argument_uses(t))
        bindings: list[py.NamedExpr] = []
        out = list(args)
        for i, arg in enumerate(args):
            if uses[ARGUMENTS[i]] > 1 and not isinstance(arg, (py.Name, py.Constant)) \
                    and const_value(arg) is None:
                name = f"w{next(self.names)}"
                bindings.append(py.NamedExpr(py.Name(name, py.Store()), arg))
                out[i] = py.Name(name, py.Load())
        return out, bindings

    @staticmethod
    def bound(bindings: list[py.NamedExpr], value: py.expr) -> py.expr:
        """`value` after the bindings: ((w1 := a), ..., value)[-1]."""
        if not bindings:
            return value
        return py.Subscript(py.Tuple([*bindings, value], py.Load()),
                            py.UnaryOp(py.USub(), py.Constant(1)), py.Load())

    def fill(self, text: str, args: list[py.expr], modes=(), new_modes=(),
             memory: ir.Memory | None = None, value: py.expr | None = None) -> py.expr:
        """A library template as Python, its placeholders replaced."""
        return _Fill(self, args, modes, new_modes, memory, value).visit(tree(text))

    def slot(self, k: int) -> py.expr:
        """Memory slot k: a local unpacked from z, or read from z where the store
        is large (DELAY's history)."""
        if self.unpacked_z:
            return py.Name(f"z{k}", py.Load())
        return py.Subscript(py.Name("z", py.Load()), py.Constant(k), py.Load())


class _Fill(py.NodeTransformer):
    """Replaces a template's placeholders (see `library`) by generated code."""

    def __init__(self, em: Emitter, args, modes, new_modes, memory, value) -> None:
        self.em = em
        self.args = args
        self.modes = modes
        self.new_modes = new_modes
        self.memory = memory
        self.value = value

    def visit_Name(self, node: py.Name) -> py.expr:
        name = node.id
        setting = self.em.setting
        fixed = {"TIME": lambda: py.Name("t", py.Load()), "INF": lambda: number(math.inf),
                 "VALUE": lambda: self.value, "Z": lambda: py.Name("z", py.Load()),
                 "OFFSET": lambda: py.Constant(self.memory.slot),
                 "SEED": lambda: number(float(setting.seed)),
                 "HOLD": lambda: number(setting.hold),
                 "SITE": lambda: py.Constant(self.memory.index),
                 "START": lambda: number(self.em.start)}
        if name in fixed:
            return fixed[name]()
        if len(name) == 1:
            i = ARGUMENTS.index(name)
            # an optional argument the call leaves out reads as 0 (DELAY's DMIN)
            return self.args[i] if i < len(self.args) else number(0.0)
        k = int(name[1:])
        if name[0] == "M":
            return self.modes[k]
        if name[0] == "N":
            return self.new_modes[k]
        return self.em.slot(self.memory.slot + k)  # Zk

    def visit_Call(self, node: py.Call) -> py.expr:
        # the callee is a function's name, not a placeholder
        node.args = [self.visit(a) for a in node.args]
        node.func = py.Name("_" + node.func.id, py.Load())
        return node


class _Needs(Visitor):
    """The algebraic variables some expressions read, transitively, through switch
    and memory instances (each entered once: nesting depth N costs O(N))."""

    def __init__(self, model: ir.Model) -> None:
        self.model = model
        self.equations = {e.target: e for e in model.dynamic}
        self.need: set[str] = set()
        self.seen: set[tuple[str, int]] = set()
        self.pending: list[syn.Node] = []

    def generic(self, node: syn.Node) -> None:
        pass

    def visit_Name(self, node: syn.Name) -> None:
        if node.name in self.equations and node.name not in self.need:
            self.need.add(node.name)
            self.pending.append(self.equations[node.name].expr)

    def visit_SwitchValue(self, node: ir.SwitchValue) -> None:
        if ("s", node.switch) not in self.seen:
            self.seen.add(("s", node.switch))
            sw = self.model.switches[node.switch]
            self.pending.extend(sw.args)
            self.pending.extend(self.model.surfaces[s].expr for s in sw.surfaces)

    def visit_MemoryValue(self, node: ir.MemoryValue) -> None:
        if ("m", node.memory) not in self.seen:
            self.seen.add(("m", node.memory))
            self.pending.extend(self.model.memories[node.memory].args)

    def visit_UnitValue(self, node: ir.UnitValue) -> None:
        if ("u", node.unit) not in self.seen:
            self.seen.add(("u", node.unit))
            unit = self.model.units[node.unit]
            self.pending.extend(syn.Name(n, unit.span) for n in unit.inputs)
            # the switches of its conditions: their surfaces read algebra too
            self.pending.extend(n for st in unit.body for n in syn.walk(st)
                                if isinstance(n, ir.SwitchValue))


def needs_memories(model: ir.Model, roots: list[syn.Node]) -> set[int]:
    """The memory instances whose values some expressions read, transitively."""
    visitor = _Needs(model)
    visitor.pending.extend(roots)
    while visitor.pending:
        for node in syn.walk(visitor.pending.pop()):
            visitor.visit(node)
    return {i for kind, i in visitor.seen if kind == "m"}


def printed_only_surfaces(model: ir.Model) -> set[int]:
    """The surfaces of Fortran arithmetic (ABS, SIGN, MIN, AMOD...) whose values only
    outputs read: no derivative, memory, stopping or scheduling surface, MODINT or
    LIMINT reads them, even through other switches. Nothing integrated changes where
    they flip, so they are not watched: an output reads them where they stand (the
    exact value at each row), and the run is not cut at every kink of a printed
    formula (a chain of ABS in outputs made 344 restarts and events). The switch
    functions (FSW, QNTZR...) stay watched: their instants are the event list's.
    Written-order code (IF blocks, ACSL sections, FST's NEWVALUEs) keeps them all."""
    if model.units or model.acsl is not None or model.terminal_code or model.events:
        return set()
    visitor = _Needs(model)
    visitor.pending.extend(s.deriv for s in model.states)
    visitor.pending.extend(a for m in model.memories for a in m.args)
    visitor.pending.extend(s.expr for s in model.surfaces if s.purpose != ir.Purpose.SWITCH)
    while visitor.pending:
        for node in syn.walk(visitor.pending.pop()):
            visitor.visit(node)
    kept = {s.index for s in model.surfaces if s.purpose != ir.Purpose.SWITCH}
    kept.update(i for m in model.memories for i in m.surfaces)
    kept.update(i for s in model.states for i in (*s.reset_surfaces, *s.modes))
    kept.update(i for kind, k in visitor.seen if kind == "s"
                for i in model.switches[k].surfaces)
    kept.update(i for sw in model.switches
                if not getattr(lookup(sw.func), "arithmetic", False) for i in sw.surfaces)
    return {s.index for s in model.surfaces if s.index not in kept}


def needs(model: ir.Model, roots: list[syn.Node]) -> list[ir.Equation]:
    """The sorted algebraic equations that the given expressions read, transitively."""
    visitor = _Needs(model)
    visitor.pending.extend(roots)
    while visitor.pending:
        for node in syn.walk(visitor.pending.pop()):
            visitor.visit(node)
    return [e for e in model.dynamic if e.target in visitor.need]
