"""The package's layout keeps its stages apart (issue 27): no import cycle between
modules, lazy imports inside functions included (a cycle through 33 modules ran
from result.py into output/ and back), and the result imports nothing of the
stages after it."""

import ast
import os

from conftest import ROOT

PACKAGE = os.path.join(ROOT, "amilpy")


def _modules() -> dict[str, tuple[str, bool]]:
    out = {}
    for folder, _, files in os.walk(PACKAGE):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                name = os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".")
                package = name.endswith(".__init__")
                out[name[:-9] if package else name] = (path, package)
    return out


def _imports(modules) -> dict[str, set[str]]:
    """module -> the amilpy modules it imports anywhere in its text."""
    edges = {m: set() for m in modules}
    for m, (path, package) in modules.items():
        for node in ast.walk(ast.parse(open(path, encoding="utf-8").read())):
            targets = []
            if isinstance(node, ast.ImportFrom):
                base = m.split(".") if package else m.split(".")[:-1]
                if node.level:
                    base = base[:len(base) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                targets = [f"{target}.{a.name}" if f"{target}.{a.name}" in modules else target
                           for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            edges[m].update(t for t in targets if t in modules and t != m)
    return edges


def _cycles(edges) -> list[list[str]]:
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in edges:
        if v not in index:
            visit(v)
    return found


def test_no_import_cycles():
    modules = _modules()
    assert len(modules) > 100
    assert _cycles(_imports(modules)) == []


def test_the_result_imports_nothing_of_the_stages_after_it():
    edges = _imports(_modules())
    later = ("amilpy.output", "amilpy.cli", "amilpy.api", "amilpy.batch", "amilpy.analysis")
    assert not [m for m in edges["amilpy.result"] if m.startswith(later)]


def test_a_run_still_plots_and_shows_itself():
    # (the output stage registers how: Run.plot, a notebook's table)
    import amilpy

    run, = amilpy.loads("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, PRDEL = 0.5\n"
                        "PRINT X\nEND\n").run()
    assert "<table>" in run._repr_html_()
    ax = run.plot("X")
    assert ax.get_lines()[0].get_label() == "X"


def test_the_runs_a_sweep_keeps_plot_themselves():
    import amilpy

    model = amilpy.loads("PARAM K = 1.0\nX = INTGRL(1.0, -K*X)\n"
                         "TIMER FINTIM = 1.0, PRDEL = 0.5\nPRINT X\nEND\n")
    kept = model.sweep("K", [1.0, 2.0], keep_runs=True).runs
    assert kept[0].plot("X").get_lines()


def test_every_package_is_in_the_wheel():
    # pyproject lists the packages; one left out is missing from a normal (not
    # editable) install, which the test suite's editable install would never show
    import re

    text = open(os.path.join(ROOT, "pyproject.toml"), encoding="utf-8").read()
    listed = set(re.findall(r'"(amilpy[\w.]*)"', text.split("packages = [", 1)[1]
                            .split("]", 1)[0]))
    found = {m for m, (_, package) in _modules().items() if package}
    assert found <= listed, sorted(found - listed)
