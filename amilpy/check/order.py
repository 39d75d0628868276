"""Ordering: each equation after what it reads (a depth-first sort, iterative), and
every algebraic loop reported with all its variables and lines."""

from __future__ import annotations

from .. import ir
from ..diagnostics import Reporter
from ..library import lookup
from ..parse import syntax as ast
from ..parse.syntax import Visitor


class _Reads(Visitor):
    """The variable names IR expressions read, through switch and memory arguments
    (each instance entered once)."""

    def __init__(self, switches: list[ir.Switch], memories: list[ir.Memory]) -> None:
        self.switches = switches
        self.memories = memories
        self.names: list[str] = []
        self.pending: list[ast.Node] = []
        self.seen: set[tuple[str, int]] = set()

    def generic(self, node: ast.Node) -> None:
        pass

    def visit_Name(self, node: ast.Name) -> None:
        self.names.append(node.name)

    def visit_SwitchValue(self, node: ir.SwitchValue) -> None:
        if ("s", node.switch) not in self.seen:
            self.seen.add(("s", node.switch))
            self.pending.extend(self.switches[node.switch].args)

    def visit_MemoryValue(self, node: ir.MemoryValue) -> None:
        if ("m", node.memory) not in self.seen:
            self.seen.add(("m", node.memory))
            mem = self.memories[node.memory]
            if not lookup(mem.func, len(mem.args)).memory.delayed:
                self.pending.extend(mem.args)

    def visit_UnitValue(self, node: ir.UnitValue) -> None:
        if ("u", node.unit) not in self.seen:
            self.seen.add(("u", node.unit))
            self.names.extend(self.units[node.unit].inputs)


def reads(expr: ast.Node, switches: list[ir.Switch], memories: list[ir.Memory],
          units: list[ir.Unit] = ()) -> list[str]:
    """Variable names an IR expression reads, including through switch/memory args
    and the inputs of sorting units."""
    visitor = _Reads(switches, memories)
    visitor.units = units
    visitor.pending.append(expr)
    while visitor.pending:
        for node in ast.walk(visitor.pending.pop()):
            visitor.visit(node)
    return visitor.names


def sort(equations: list[ir.Equation], section: str, rep: Reporter,
         switches: list[ir.Switch], memories: list[ir.Memory],
         units: list[ir.Unit] = ()) -> list[ir.Equation]:
    """Order equations so each follows what it reads; report algebraic loops."""
    by_target = {e.target: e for e in equations}
    deps: dict[str, list[str]] = {}
    for e in equations:
        seen: list[str] = []
        for n in reads(e.expr, switches, memories, units):
            if n in by_target and n not in seen:
                seen.append(n)
        deps[e.target] = seen
    order: list[ir.Equation] = []
    state = dict.fromkeys(by_target, 0)  # 0 new, 1 on the path, 2 done
    reported: set[frozenset[str]] = set()
    for root in by_target:
        if state[root]:
            continue
        # iterative DFS, keeping the path to report cycles
        stack = [(root, iter(deps[root]))]
        path = [root]
        state[root] = 1
        while stack:
            node, it = stack[-1]
            nxt = next(it, None)
            if nxt is None:
                stack.pop()
                path.pop()
                state[node] = 2
                order.append(by_target[node])
                continue
            if state[nxt] == 1:
                cycle = path[path.index(nxt):]
                if frozenset(cycle) not in reported:
                    reported.add(frozenset(cycle))
                    loop_error(cycle, by_target, section, rep)
            elif state[nxt] == 0:
                state[nxt] = 1
                path.append(nxt)
                stack.append((nxt, iter(deps[nxt])))
    return order


def loop_error(cycle: list[str], by_target: dict[str, ir.Equation], section: str,
               rep: Reporter) -> None:
    first = by_target[cycle[0]]
    chain = " -> ".join(cycle + [cycle[0]])
    related = tuple((by_target[n].span, f"{n} is computed here") for n in cycle[1:])
    rep.error(
        f"algebraic loop in {section}: {chain}",
        first.span,
        "every variable of the loop needs the others at the same instant; break it with "
        "a state (INTGRL), e.g. a fast first-order lag REALPL",
        related=related,
    )
