"""IR -> Python syntax tree -> code object, once per run.

The model's data and INITIAL values are folded into the code as constants, so
the hot functions are straight-line float arithmetic. Generated code is built as
a `ast` tree (model text is never pasted into source), compiled with the
listing's path as file name and each statement on its listing line, so a fault
inside points at the `.amil` line. Its globals are only the names this module
puts there (`NAMESPACE`), with empty builtins: no imports, no attributes.

Functions made for one run (all take plain lists of floats):
  rhs(t, y, m, z)              state derivatives under frozen modes m
  surf(t, y, m, z)             the watched switching surfaces
  out(t, y, m, z)              every recorded variable, only at output instants
  mem(t, y, m, mn, z)          memory values after an accepted step (m: the modes
                               the step was taken with, mn: the modes from now on)
"""

from __future__ import annotations

import ast as py
import math
from dataclasses import dataclass, field

from . import ir, templates
from . import syntax as syn
from .diagnostics import AmilError, Diagnostic, Span
from .library import Func, lookup, math_functions, runtime_name, vector_functions
from .runtime import HELPERS, safe_pow
from .surfaces import is_affine
from .syntax import Visitor
from .templates import ARGUMENTS


def namespace() -> dict[str, object]:
    """Every callable generated code can reach: the language's math functions and
    the run-time helpers, each as _NAME (read from the library at each build, so an
    entry registered later is there too)."""
    out: dict[str, object] = {f"_{k}": v for k, v in math_functions().items()}
    out.update({f"_{k}": v for k, v in HELPERS.items()})
    return out


NAMESPACE = namespace()  # as the library stands at import (benchmarks read it)

# models with more memory slots than this read them from z instead of unpacking
MAX_UNPACKED_SLOTS = 32

# Names the generated code reads, and which a model name can never produce
# (model names become v_NAME, hidden states h_N): the compiler's own vocabulary.
_ARGS = ("t", "y", "m", "mn", "z")


@dataclass
class Compiled:
    """The callables and constants of one run of one model."""

    state_names: list[str]
    y0: list[float]
    z0: list[float]
    out_names: list[str]
    constants: dict[str, float]
    rhs: object
    surf: object
    out: object
    mem: object
    watched: list[int]  # surface indices surf() returns, in order
    const_modes: dict[int, float]  # surfaces fixed for the whole run
    modes_literal: object  # (t, y, z) -> list of literal modes of watched surfaces
    affine_time: set[int]  # surfaces affine in TIME: their roots are breakpoints
    impulses: list[tuple[float, float]]
    source: str
    tables: dict[str, tuple] = field(default_factory=dict)
    # surf and out over NumPy columns: y is a list of arrays, t an array
    surf_v: object = None
    out_v: object = None
    # some memory must be updated after every accepted step (HSTRSS, RST, DERIV);
    # when False, memory changes only where a run restarts anyway (ZHOLD, PULSE)
    memory_every_step: bool = False
    # (z, t) -> instants after t at which memory makes the model switch (PULSE ends)
    memory_times: object = None

    def fault_line(self, exc: BaseException) -> int | None:
        """The listing line of the generated statement that raised `exc`."""
        return fault_line(exc)


# the functions build() generates
_GENERATED = ("rhs", "out", "surf", "mem", "modes", "surf_vec", "out_vec")


def fault_line(exc: BaseException) -> int | None:
    """The listing line of the generated statement that raised `exc`, if the fault
    happened inside generated code."""
    tb = exc.__traceback__
    line = None
    while tb is not None:
        if tb.tb_frame.f_code.co_name in _GENERATED:
            line = tb.tb_lineno
        tb = tb.tb_next
    return line


def _num(v: float) -> py.expr:
    if v != v:
        return py.Call(py.Name("_FLOAT", py.Load()), [py.Constant("nan")], [])
    if math.isinf(v):
        return py.Call(py.Name("_FLOAT", py.Load()), [py.Constant("inf" if v > 0 else "-inf")],
                       [])
    if v < 0 or (v == 0 and math.copysign(1.0, v) < 0):
        return py.UnaryOp(py.USub(), py.Constant(-float(v)))
    return py.Constant(float(v))


def _const_value(node: py.expr) -> float | None:
    if isinstance(node, py.Constant) and isinstance(node.value, float):
        return node.value
    if (isinstance(node, py.UnaryOp) and isinstance(node.op, py.USub)
            and isinstance(node.operand, py.Constant) and isinstance(node.operand.value, float)):
        return -node.operand.value
    return None


_PYOPS = {"+": py.Add, "-": py.Sub, "*": py.Mult, "/": py.Div}


class _Folder(py.NodeTransformer):
    """Constant folding on the generated tree (keeps float semantics)."""

    def visit_BinOp(self, node):
        self.generic_visit(node)
        a, b = _const_value(node.left), _const_value(node.right)
        if isinstance(node.op, py.Pow) and a is not None and isinstance(node.right, py.Constant):
            v = safe_pow(a, float(node.right.value))
            return py.copy_location(_num(v), node) if math.isfinite(v) else node
        if a is not None and b is not None and not isinstance(node.op, py.Pow):
            try:
                if isinstance(node.op, py.Add):
                    v = a + b
                elif isinstance(node.op, py.Sub):
                    v = a - b
                elif isinstance(node.op, py.Mult):
                    v = a * b
                elif isinstance(node.op, py.Div):
                    v = a / b
                else:
                    return node
            except (ArithmeticError, ValueError):
                return node
            return py.copy_location(_num(v), node)
        return node

    def visit_UnaryOp(self, node):
        self.generic_visit(node)
        if isinstance(node.op, py.USub):
            inner = node.operand
            if isinstance(inner, py.UnaryOp) and isinstance(inner.op, py.USub):
                return inner.operand
        return node

    def visit_IfExp(self, node):
        self.generic_visit(node)
        test = _truth(node.test)
        if test is None:
            return node
        return node.body if test else node.orelse


def _truth(node) -> bool | None:
    if isinstance(node, py.Constant) and isinstance(node.value, bool):
        return node.value
    if isinstance(node, py.Compare) and len(node.ops) == 1:
        a, b = _const_value(node.left), _const_value(node.comparators[0])
        if a is None or b is None:
            return None
        op = node.ops[0]
        return {py.Lt: a < b, py.Gt: a > b, py.LtE: a <= b, py.GtE: a >= b, py.Eq: a == b,
                py.NotEq: a != b}[type(op)]
    if isinstance(node, py.BoolOp):
        vals = [_truth(v) for v in node.values]
        if isinstance(node.op, py.And):
            if any(v is False for v in vals):
                return False
            return True if all(v is True for v in vals) else None
        if any(v is True for v in vals):
            return True
        return False if all(v is False for v in vals) else None
    return None


def _local(name: str) -> str:
    """Python identifier for a model variable (hidden ones have '#')."""
    if "#" in name:
        # hidden names hold '#', '.' and "'": spell every non-alphanumeric
        # character as _XX so that no two names meet
        return "h_" + "".join(c if c.isalnum() else f"_{ord(c):02X}" for c in name)
    return "v_" + name


class _Emitter(Visitor):
    """Emits Python expressions for IR expressions in one context.

    context: "rhs" (frozen modes, IMPULS = 0), "out" (frozen modes, IMPULS exact),
    "mem" (like out), "literal" (modes from the current signs: INITIAL/TERMINAL).
    """

    complete = ir.EXPRESSIONS

    def __init__(self, model: ir.Model, constants: dict[str, float], const_modes,
                 context: str, mode_names: dict[int, str], tables,
                 unpacked_z: bool = True) -> None:
        self.unpacked_z = unpacked_z
        self.model = model
        self.constants = constants
        self.const_modes = const_modes
        self.context = context
        self.mode_names = mode_names
        self.tables = tables

    def mode(self, surface: int) -> py.expr:
        if surface in self.const_modes:
            return _num(self.const_modes[surface])
        if self.context == "literal":
            s = self.model.surfaces[surface]
            fn = "_LEVEL" if s.kind == "level" else "_SGN"
            return py.Call(py.Name(fn, py.Load()), [self.emit(s.expr)], [])
        return py.Name(self.mode_names[surface], py.Load())

    def memory_mode(self, surface: int) -> py.expr:
        """At step ends (and output instants) a memory function reads its condition
        as it stands (so IMPULS, which is 1 only at its instants, triggers it), or
        the branch the step was taken in when that was the positive one (so a value
        tracked up to a located crossing is kept)."""
        mode = self.mode(surface)
        if self.context not in ("mem", "out"):
            return mode
        literal = py.Call(py.Name("_SGN", py.Load()),
                          [self.emit(self.model.surfaces[surface].expr)], [])
        if _const_value(mode) is not None:
            return literal if _const_value(mode) <= 0 else mode
        return py.IfExp(py.Compare(mode, [py.Gt()], [py.Constant(0.0)]), mode, literal)

    def emit(self, e) -> py.expr:
        return self.visit(e)

    def visit_Num(self, e: syn.Num) -> py.expr:
        return _num(e.value)

    def visit_Name(self, e: syn.Name) -> py.expr:
        if e.name == "TIME":
            return py.Name("t", py.Load())
        if e.name in self.constants:
            return _num(self.constants[e.name])
        return py.Name(_local(e.name), py.Load())

    def visit_Neg(self, e: syn.Neg) -> py.expr:
        return py.UnaryOp(py.USub(), self.emit(e.operand))

    def visit_BinOp(self, e: syn.BinOp) -> py.expr:
        left, right = self.emit(e.left), self.emit(e.right)
        if e.op == "**":
            k = _const_value(right)
            if k is not None and k.is_integer() and abs(k) <= 64:
                if k == 2.0:
                    # x*x: exact and far cheaper than pow
                    if isinstance(left, py.Name):
                        return py.BinOp(left, py.Mult(), py.Name(left.id, py.Load()))
                return py.BinOp(left, py.Pow(), py.Constant(int(k)))
            a = _const_value(left)
            if a is not None and k is not None:
                return _num(safe_pow(a, k))
            return py.Call(py.Name("_POW", py.Load()), [left, right], [])
        return py.BinOp(left, _PYOPS[e.op](), right)

    def visit_Call(self, e: syn.Call) -> py.expr:
        func = lookup(e.func, len(e.args))
        if func.kind in ("switch", "time"):  # literal use (INITIAL/TERMINAL)
            return self.literal_switch(func, e.args)
        args = [self.emit(a) for a in e.args]
        values = [_const_value(a) for a in args]
        if all(v is not None for v in values):
            try:
                return _num(float(func.scalar(*values)))
            except (ArithmeticError, ValueError, TypeError):
                pass  # left to the run, which reports it where it happens
        return py.Call(py.Name("_" + runtime_name(func), py.Load()), args, [])

    def visit_TableLookup(self, e: ir.TableLookup) -> py.expr:
        name = "_T_" + e.table
        self.tables[name] = self.table_value(e.table)
        return py.Call(py.Name("_" + e.func, py.Load()), [py.Name(name, py.Load()),
                                                          self.emit(e.x)], [])

    def visit_SwitchValue(self, e: ir.SwitchValue) -> py.expr:
        sw = self.model.switches[e.switch]
        func = lookup(sw.func, len(sw.args))
        return self.fill(func.values[e.output], [self.emit(a) for a in sw.args],
                         [self.mode(s) for s in sw.surfaces])

    def visit_MemoryValue(self, e: ir.MemoryValue) -> py.expr:
        return self.memory_value(self.model.memories[e.memory])

    def visit_Impulse(self, e: ir.Impulse) -> py.expr:
        if self.context == "rhs":
            return py.Constant(0.0)
        return py.Call(py.Name("_IMPULS", py.Load()),
                       [py.Name("t", py.Load()), self.emit(e.start), self.emit(e.period)], [])

    def table_value(self, name: str):
        return self.tables_source[name]

    def literal_switch(self, func: Func, args) -> py.expr:
        """A switch in INITIAL/TERMINAL: evaluate its surfaces' signs on the spot."""
        fn = "_LEVEL" if func.surface_kind == ir.SurfaceKind.LEVEL else "_SGN"
        modes = [py.Call(py.Name(fn, py.Load()),
                         [self.emit(templates.instantiate(t, tuple(args), Span(0, 0)))], [])
                 for t in func.surfaces]
        return self.fill(func.values[0], [self.emit(a) for a in args], modes)

    def fill(self, text: str, args: list[py.expr], modes=(), new_modes=(),
             memory: ir.Memory | None = None, value: py.expr | None = None) -> py.expr:
        """A library template as Python, its placeholders replaced."""
        return _Fill(self, args, modes, new_modes, memory, value).visit(templates.tree(text))

    def slot(self, k: int) -> py.expr:
        """Memory slot k: a local unpacked from z, or read from z where the store
        is large (DELAY's history)."""
        if self.unpacked_z:
            return py.Name(f"z{k}", py.Load())
        return py.Subscript(py.Name("z", py.Load()), py.Constant(k), py.Load())

    def memory_value(self, mem: ir.Memory) -> py.expr:
        func = lookup(mem.func, len(mem.args))
        return self.fill(func.memory.value, [self.emit(x) for x in mem.args],
                         [self.memory_mode(s) for s in mem.surfaces], memory=mem)


class _Fill(py.NodeTransformer):
    """Replaces a template's placeholders (see `library`) by generated code."""

    def __init__(self, em: _Emitter, args, modes, new_modes, memory, value) -> None:
        self.em = em
        self.args = args
        self.modes = modes
        self.new_modes = new_modes
        self.memory = memory
        self.value = value

    def visit_Name(self, node: py.Name) -> py.expr:
        name = node.id
        if name == "TIME":
            return py.Name("t", py.Load())
        if name == "INF":
            return _num(math.inf)
        if name == "VALUE":
            return self.value
        if name == "Z":
            return py.Name("z", py.Load())
        if name == "OFFSET":
            return py.Constant(self.memory.slot)
        if len(name) == 1:
            return self.args[ARGUMENTS.index(name)]
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
        self.pending: list = []

    def generic(self, node) -> None:
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


def _needs(model: ir.Model, roots: list) -> list[ir.Equation]:
    """The sorted algebraic equations that the given expressions read, transitively."""
    needs = _Needs(model)
    needs.pending.extend(roots)
    while needs.pending:
        for node in syn.walk(needs.pending.pop()):
            needs.visit(node)
    return [e for e in model.dynamic if e.target in needs.need]


def _assign(name: str, value: py.expr, line: int) -> py.stmt:
    stmt = py.Assign([py.Name(name, py.Store())], value)
    stmt.lineno = line
    return stmt


def _place(module: py.Module) -> None:
    """Give every node the listing line of its statement, so a fault inside
    generated code reports the `.amil` line (other statements take line 1)."""
    for fn in module.body:
        last = 1
        for stmt in fn.body:
            line = getattr(stmt, "lineno", None) or 1
            last = max(last, line)
            for node in py.walk(stmt):
                if isinstance(node, (py.expr, py.stmt, py.excepthandler, py.arg)):
                    node.lineno = node.end_lineno = line
                    node.col_offset = node.end_col_offset = 0
        fn.lineno, fn.end_lineno = 1, last
        fn.col_offset = fn.end_col_offset = 0
        for node in py.walk(fn.args):
            node.lineno = node.end_lineno = 1
            node.col_offset = node.end_col_offset = 0


def _function(name: str, args: tuple[str, ...], body: list[py.stmt]) -> py.FunctionDef:
    fn = py.FunctionDef(
        name=name,
        args=py.arguments(posonlyargs=[], args=[py.arg(a) for a in args], vararg=None,
                          kwonlyargs=[], kw_defaults=[], kwarg=None, defaults=[]),
        body=body or [py.Pass()],
        decorator_list=[],
        returns=None,
        type_params=[],
    )
    return fn


class Compiler:
    """Builds the `Compiled` functions of one run from the IR and its constants."""

    def __init__(self, model: ir.Model, constants: dict[str, float], tables,
                 const_modes: dict[int, float], outputs: list[str] | None = None,
                 events: bool = True) -> None:
        self.model = model
        self.constants = constants
        self.tables = tables
        self.const_modes = const_modes
        self.outputs = outputs
        self.events = events
        self.watched = [s.index for s in model.surfaces if s.index not in const_modes]
        if not events:
            # only FINISH/TERMT stay watched: they stop the run, they switch nothing
            self.watched = [i for i in self.watched
                            if model.surfaces[i].purpose in ("finish", "termt")]
        self.mode_names = {s: f"m{k}" for k, s in enumerate(self.watched)}
        self.mode_names_new = {s: f"n{k}" for k, s in enumerate(self.watched)}
        self.global_tables: dict[str, tuple] = {}
        self.entries = [lookup(m.func, len(m.args)) for m in model.memories]
        # a few slots are unpacked into locals; a large store (DELAY) is read from z
        self.unpacked_z = sum(m.nslots for m in model.memories) <= MAX_UNPACKED_SLOTS

    def emitter(self, context: str, new_modes: bool = False) -> _Emitter:
        names = self.mode_names_new if new_modes else self.mode_names
        em = _Emitter(self.model, self.constants, self.const_modes, context, names,
                      self.global_tables, self.unpacked_z)
        em.tables_source = self.tables
        return em

    def prologue(self, used_states: bool = True, modes: str = "m", mem: bool = True):
        body: list[py.stmt] = []
        n = len(self.model.states)
        if used_states and n:
            targets = [py.Name(_local(s.name), py.Store()) for s in self.model.states]
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
            body.append(py.Assign([py.Tuple(names, py.Store())], py.Name("z", py.Load()))
                        if nz > 1 else py.Assign([names[0]], py.Subscript(
                            py.Name("z", py.Load()), py.Constant(0), py.Load())))
        return body

    def algebra(self, roots, em: _Emitter) -> list[py.stmt]:
        return [_assign(_local(e.target), em.emit(e.expr), e.span.line)
                for e in _needs(self.model, roots)]

    def build(self) -> Compiled:
        model = self.model
        # Without events (for comparisons only) switches are read literally at
        # every evaluation, as a naive integrator would, and nothing is watched.
        em_rhs = self.emitter("rhs" if self.events else "literal")
        derivs = []
        for s in model.states:
            d = s.deriv
            derivs.append(d)
        # rhs --------------------------------------------------------------
        body = self.prologue()
        body += self.algebra(derivs, em_rhs)
        ret = []
        for s in model.states:
            value = em_rhs.emit(s.deriv)
            if s.reset_surfaces:
                value = py.IfExp(py.Compare(em_rhs.mode(s.reset_surfaces[0]), [py.Gt()],
                                            [py.Constant(0.0)]), value, py.Constant(0.0))
            ret.append(value)
        body.append(py.Return(py.List(ret, py.Load())))
        fns = [_function("rhs", ("t", "y", "m", "z"), body)]
        # surfaces -------------------------------------------------------------
        em_s = self.emitter("rhs")
        roots = [model.surfaces[i].expr for i in self.watched]
        body = self.prologue() + self.algebra(roots, em_s)
        vals = []
        for i in self.watched:
            s = model.surfaces[i]
            v = em_s.emit(s.expr)
            if s.kind == "level":
                # distance to the edges of the current level's band, in units of P
                k = py.Name(self.mode_names[i], py.Load())
                v = py.BinOp(py.Constant(0.5), py.Sub(),
                             py.Call(py.Name("_ABS", py.Load()),
                                     [py.BinOp(v, py.Sub(), k)], []))
            vals.append(v)
        body.append(py.Return(py.List(vals, py.Load())))
        fns.append(_function("surf", ("t", "y", "m", "z"), body))
        # literal modes of the watched surfaces (restart rule starts from these)
        em_l = self.emitter("rhs")
        body = self.prologue() + self.algebra(roots, em_l)
        vals = []
        for i in self.watched:
            s = model.surfaces[i]
            fn = "_LEVEL" if s.kind == "level" else "_SGN"
            vals.append(py.Call(py.Name(fn, py.Load()), [em_l.emit(s.expr)], []))
        body.append(py.Return(py.List(vals, py.Load())))
        fns.append(_function("modes", ("t", "y", "m", "z"), body))
        # outputs ----------------------------------------------------------------
        em_o = self.emitter("out" if self.events else "literal")
        out_names = self.outputs if self.outputs is not None else model.variables
        roots = [syn.Name(n, Span(0, 0)) for n in out_names]
        body = self.prologue() + self.algebra(roots, em_o)
        body.append(py.Return(py.List([em_o.emit(r) for r in roots], py.Load())))
        fns.append(_function("out", ("t", "y", "m", "z"), body))
        # memory -------------------------------------------------------------------
        em_m = self.emitter("mem")
        em_new = self.emitter("mem", new_modes=True)
        mem_roots = [a for m in model.memories for a in m.args]
        body = self.prologue() + (self.prologue(used_states=False, modes="mn", mem=False)
                                  if self.watched else [])
        body += self.algebra(mem_roots, em_m)
        new: list[py.expr] = []
        for mem, func in zip(model.memories, self.entries, strict=True):
            args = [em_m.emit(a) for a in mem.args]
            modes = [em_m.memory_mode(s) for s in mem.surfaces]
            new_modes = [em_new.memory_mode(s) for s in mem.surfaces]
            value = em_m.memory_value(mem)
            for text in func.memory.update:
                e = em_m.fill(text, args, modes, new_modes, mem, value)
                new.append(py.Starred(e, py.Load()) if templates.spread(text) else e)
        body.append(py.Return(py.List(new, py.Load())))
        fns.append(_function("mem", ("t", "y", "m", "mn", "z"), body))

        # surf and out once more for NumPy columns: a condition there may be an array
        # (a memory function reading its condition), so if/else becomes a where()
        fns.append(_vectorised(fns[1], "surf_vec"))
        fns.append(_vectorised(fns[3], "out_vec"))
        module = py.Module(body=fns, type_ignores=[])
        module = _Folder().visit(module)
        _place(module)
        py.fix_missing_locations(module)
        _assert_closed(module)
        source = py.unparse(module)
        code = compile(module, model.path or model.name, "exec")
        scalar: dict[str, object] = {"__builtins__": {}}
        scalar.update(namespace())
        scalar.update(self.global_tables)
        exec(code, scalar)  # noqa: S102 - compiler-built tree, closed namespace
        vector: dict[str, object] = {"__builtins__": {}}
        vector.update({f"_{k}": v for k, v in vector_functions().items()})
        vector.update(self.global_tables)
        exec(code, vector)  # noqa: S102 - the same code, elementwise functions

        # initial values -------------------------------------------------------------
        y0 = [self.constant(s.ic, s.span) for s in model.states]
        z0 = [v for mem, func in zip(model.memories, self.entries, strict=True)
              for text in func.memory.initial for v in self.initial_slots(text, mem)]
        equations = {e.target: e.expr for e in model.dynamic}
        affine = {i for i in self.watched
                  if model.surfaces[i].depends == "time" and self.events
                  and model.surfaces[i].kind == "sign"
                  and is_affine(model.surfaces[i].expr, self.constants, equations)}
        impulses = [(self.constant(node.start, node.span), self.constant(node.period, node.span))
                    for e in _all_exprs(model) for node in syn.walk(e)
                    if isinstance(node, ir.Impulse)]
        return Compiled(
            state_names=[s.name for s in model.states], y0=y0, z0=z0,
            out_names=list(out_names), constants=self.constants, rhs=scalar["rhs"],
            surf=scalar["surf"], out=scalar["out"], mem=scalar["mem"],
            watched=self.watched, const_modes=self.const_modes,
            modes_literal=scalar["modes"], affine_time=affine, impulses=impulses,
            source=source, tables=self.global_tables,
            surf_v=vector["surf_vec"], out_v=vector["out_vec"],
            memory_every_step=any(f.memory.every_step for f in self.entries),
            memory_times=self.memory_times(),
        )

    def initial_slots(self, text: str, mem: ir.Memory) -> list[float]:
        """The initial values a memory template gives (one, or several with `*`)."""
        em = _Emitter(self.model, self.constants, {}, "literal", {}, {})
        em.tables_source = self.tables
        args = [em.emit(a) for a in mem.args]
        value = _evaluate(self.model, em.fill(text, args, memory=mem), em.tables, mem.span)
        return [float(v) for v in value] if templates.spread(text) else [float(value)]

    def memory_times(self):
        """Memory that holds a future instant at which the model switches (PULSE
        holds its output until the instant kept in its slot)."""
        slots = [m.slot + f.memory.wakes for m, f in zip(self.model.memories, self.entries,
                                                        strict=True)
                 if f.memory.wakes is not None]

        def times(z: list[float], t: float) -> list[float]:
            return [z[s] for s in slots if z[s] > t]
        return times

    def constant(self, expr, span: Span) -> float:
        return evaluate_constant(self.model, expr, self.constants, self.tables, span)


def _vectorised(fn: py.FunctionDef, name: str) -> py.FunctionDef:
    """A copy of a generated function whose conditionals work elementwise."""
    import copy

    class Where(py.NodeTransformer):
        def visit_IfExp(self, node):
            self.generic_visit(node)
            return py.Call(py.Name("_WHERE", py.Load()), [node.test, node.body, node.orelse], [])

        def visit_BoolOp(self, node):
            self.generic_visit(node)
            fn = "_ALL" if isinstance(node.op, py.And) else "_ANY"
            return py.Call(py.Name(fn, py.Load()), node.values, [])

    new = Where().visit(copy.deepcopy(fn))
    new.name = name
    return new


def _all_exprs(model: ir.Model):
    for e in model.dynamic:
        yield e.expr
    for s in model.states:
        yield s.deriv
    for sw in model.switches:
        yield from sw.args
    for m in model.memories:
        yield from m.args
    for s in model.surfaces:
        yield s.expr


def _assert_closed(module: py.Module) -> None:
    """Generated code reads only the compiler's names: no attributes, no builtins."""
    allowed = set(namespace()) | set(_ARGS)
    for node in py.walk(module):
        if isinstance(node, (py.Attribute, py.Import, py.ImportFrom, py.Global, py.Lambda)):
            raise AssertionError(f"generated code contains {type(node).__name__}")
        if isinstance(node, py.Name) and isinstance(node.ctx, py.Load):
            ok = (node.id in allowed or node.id.startswith(("v_", "h_", "_T_"))
                  or (node.id[0] in "mnz" and node.id[1:].isdigit()))
            if not ok:
                raise AssertionError(f"generated code reads unknown name {node.id}")


# ------------------------------------------------------------ constant evaluation

def evaluate_constant(model: ir.Model, expr, constants: dict[str, float], tables,
                      span: Span) -> float:
    """Evaluate an expression of constants (INITIAL, initial conditions)."""
    comp_tables: dict[str, tuple] = {}
    em = _Emitter(model, constants, {}, "literal", {}, comp_tables)
    em.tables_source = tables
    try:
        tree = em.emit(expr)
    except KeyError as exc:  # a name that is not a constant
        raise AmilError([Diagnostic(f"{exc.args[0]} is not known before the run starts",
                                    span)], model.path, model.source) from None
    return float(_evaluate(model, tree, comp_tables, span))


def _evaluate(model: ir.Model, body: py.expr, tables: dict[str, tuple], span: Span):
    """The value of a generated expression of constants; a fault is an AmilError at span."""
    tree = py.Expression(body)
    py.fix_missing_locations(tree)
    _assert_closed(py.Module(body=[py.Expr(tree.body)], type_ignores=[]))
    scope: dict[str, object] = {"__builtins__": {}}
    scope.update(namespace())
    scope.update(tables)
    try:
        return eval(compile(tree, model.path or model.name, "eval"), scope)  # noqa: S307
    except ZeroDivisionError:
        raise AmilError([Diagnostic("division by zero", span,
                                    "check the data values this expression uses")],
                        model.path, model.source) from None
    except OverflowError:
        raise AmilError([Diagnostic("value too large (overflow)", span)], model.path,
                        model.source) from None
    except (ValueError, TypeError) as exc:
        raise AmilError([Diagnostic(f"cannot be evaluated: {exc}", span,
                                    "check the arguments' ranges (ASIN, ACOS, SQRT, ALOG)")],
                        model.path, model.source) from None
    except NameError as exc:
        name = str(exc).split("'")[1] if "'" in str(exc) else str(exc)
        raise AmilError([Diagnostic(
            f"{name.removeprefix('v_')} is not known before the run starts", span,
            "an initial value or INITIAL statement can use numbers, data values and INITIAL "
            "values only")], model.path, model.source) from None


def initial_values(model: ir.Model, data: dict[str, float], tables,
                   reserved: dict[str, float]) -> dict[str, float]:
    """Data values, TIMER values and the INITIAL section, evaluated in sorted order."""
    constants = dict(reserved)
    constants.update(data)
    constants["PI"] = math.pi
    for eq in model.initial:
        constants[eq.target] = evaluate_constant(model, eq.expr, constants, tables, eq.span)
    return constants
