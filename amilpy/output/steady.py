"""An equilibrium for a reader (`amilpy.analysis.steady` computes it): the
printout, its CSV rows, the linear model's matrices (CSV and .npz) and the Bode
diagram."""

from __future__ import annotations

import io
from collections.abc import Iterator, Sequence

import numpy as np

from ..analysis.steady import FREE, HELD
from ..run.jacobian import DIFFERENCES
from . import words as W
from .analysis import _num, _title, eigen_table, units
from .plot import save_figure

ROLE_WORDS = {HELD: "held: its rate reads no state (a clock, a forcing phase), so it is "
                    "frozen like TIME",
              FREE: "free: nothing reads it (a running integral), so it is left as it is"}


def _branch(mode: float) -> str:
    if mode == 0.5:
        return "sliding on it"
    if mode in (-1.0, 0.0, 1.0):
        return {-1.0: "negative side", 0.0: "on it", 1.0: "positive side"}[mode]
    return f"level {mode:g}"


def stability_text(eq) -> str:
    if eq.stability == "none":
        return "NO STATE TO SOLVE FOR: every state is held or free, so nothing here comes " \
               "to rest by itself"
    zero = eq.zero_modes
    also = f", apart from {zero} zero mode{'s' * (zero != 1)} (a direction the field " \
        "does not change along: a drift, a free position)" if zero else ""
    if eq.stability == "unstable":
        grow = max(m.eigenvalue.real for m in eq.modes if not m.zero)
        return f"UNSTABLE: a mode grows (largest real part {grow:.6g} 1/s)"
    if eq.stability == "stable":
        return "STABLE: every mode decays" + also
    return "MARGINAL: no mode grows, but one neither grows nor decays" + also


def steady_text(eq, model=None) -> str:
    lines = [f"EQUILIBRIUM OF {_title(model)}".rstrip(),
             f"the field frozen at TIME = {eq.time:.9g}; found by {eq.how} in "
             f"{eq.iterations} iterations; largest residual {eq.residual:.1E} of its "
             "equation's rate scale",
             "", f"{'STATE':<12}{'VALUE':>16}{'D/DT':>16}"]
    for name, value, rate in zip(eq.names, eq.state.y, eq.rates, strict=True):
        role = eq.roles[name]
        note = f"  {ROLE_WORDS[role]}" if role in ROLE_WORDS else ""
        lines.append(f"{name:<12}{value:16.8E}{rate:16.8E}{note}")
    moving = [n for n, r in zip(eq.names, eq.rates, strict=True)
              if eq.roles[n] in ROLE_WORDS and r != 0]
    if moving:
        lines += ["", f"note: {', '.join(moving)} keep{'s' * (len(moving) == 1)} changing; "
                      "this is the equilibrium with "
                      + ("it" if len(moving) == 1 else "them") + " frozen"]
    if eq.surfaces:
        lines += ["", "SWITCHING SURFACES AT THE EQUILIBRIUM"]
        lines += [f"  {text}: {_branch(mode)}" for text, mode in eq.surfaces]
    lines += ["", stability_text(eq)]
    if eq.modes:
        lines += ["", f"EIGENVALUES OF THE SOLVED STATES' JACOBIAN (from {eq_how(eq)})",
                  *eigen_table(eq.modes)]
    if eq.linear is not None:
        lines += ["", "LINEAR MODEL ABOUT THE EQUILIBRIUM (deviations): x' = A x + B u, "
                      "y = C x + D u"]
        lin = eq.linear
        for label, mat, rows, cols in (("A", lin.a, lin.states, lin.states),
                                       ("B", lin.b, lin.states, lin.inputs),
                                       ("C", lin.c, lin.outputs, lin.states),
                                       ("D", lin.d, lin.outputs, lin.inputs)):
            if not mat.size:
                continue
            lines += ["", f"{label} {'':<10}" + "".join(f"{c:>14}" for c in cols)]
            lines += [f"  {r:<10}" + "".join(_num(v) for v in row)
                      for r, row in zip(rows, mat, strict=True)]
    return "\n".join(lines) + "\n"


def eq_how(eq) -> str:
    return "the model's equations" if not eq.error else \
        f"{DIFFERENCES}, estimated error {eq.error:.1E} of its largest entry"


def steady_csv(eq) -> tuple[list[str], Iterator[list]]:
    """One row per state: NAME, VALUE, RATE (its derivative there), ROLE."""
    header = ["NAME", "VALUE", "RATE", "ROLE"]
    return header, ([n, float(v), float(r), eq.roles[n]]
                    for n, v, r in zip(eq.names, eq.state.y, eq.rates, strict=True))


def matrices_csv(eq) -> tuple[list[str], Iterator[list]]:
    """The linear model in long form: MATRIX (A, B, C or D), ROW, COLUMN, VALUE."""
    lin = eq.linear
    blocks = (("A", lin.a, lin.states, lin.states), ("B", lin.b, lin.states, lin.inputs),
              ("C", lin.c, lin.outputs, lin.states), ("D", lin.d, lin.outputs, lin.inputs))
    return ["MATRIX", "ROW", "COLUMN", "VALUE"], (
        [label, r, c, float(mat[i, j])] for label, mat, rows, cols in blocks
        for i, r in enumerate(rows) for j, c in enumerate(cols))


def npz_bytes(eq) -> bytes:
    """Everything as NumPy arrays (np.load reads them back): the equilibrium, the
    eigenvalues and, with a linear model, A, B, C, D and their names."""
    arrays = {"time": np.array(eq.time), "names": np.array(eq.names),
              "values": np.asarray(eq.state.y, dtype=float), "rates": eq.rates,
              "roles": np.array([eq.roles[n] for n in eq.names]),
              "jacobian": eq.jacobian, "solved": np.array(eq.solved, dtype=str),
              "eigenvalues": np.array([m.eigenvalue for m in eq.modes], dtype=complex)}
    if eq.linear is not None:
        lin = eq.linear
        arrays.update(A=lin.a, B=lin.b, C=lin.c, D=lin.d, states=np.array(lin.states),
                      inputs=np.array(lin.inputs, dtype=str),
                      outputs=np.array(lin.outputs, dtype=str))
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def plot_bode(eq, path: str, model=None, formats: Sequence[str] = ()) -> list[str]:
    """The frequency response of every output to every input: magnitude and phase
    against frequency, one figure per input (path_<INPUT>); the paths written."""
    from matplotlib.figure import Figure

    lin = eq.linear
    w = lin.frequencies()
    g = lin.transfer(w)
    out = []
    for j, name in enumerate(lin.inputs):
        fig = Figure(figsize=(8, 6.5))
        mag, phase = fig.subplots(2, 1, sharex=True)
        in_unit = units(model, name, None)[0]
        for i, y in enumerate(lin.outputs):
            h = g[:, i, j]
            amp = np.abs(h)
            unit = units(model, None, y)[1]
            label = y + (f" [{unit}]" if unit else "") + \
                (f" per {in_unit}" if in_unit else "")
            mag.loglog(w, np.where(amp > 0, amp, np.nan), label=label, linewidth=1.3)
            phase.semilogx(w, np.degrees(np.unwrap(np.angle(h))), linewidth=1.3)
        for m in eq.modes:
            if not m.zero and w[0] <= m.wn <= w[-1]:
                for ax in (mag, phase):
                    ax.axvline(m.wn, color="0.7", linewidth=0.8, linestyle=":")
        mag.set_ylabel(f"|output / {name}|")
        phase.set_ylabel("phase [deg]")
        phase.set_xlabel("frequency [rad/s]")
        for ax in (mag, phase):
            ax.grid(True, which="both", alpha=0.3)
        mag.legend(fontsize=8)
        mag.set_title(f"{W.shorten(_title(model), 90)}\nBode diagram about the equilibrium, "
                      f"input {name} (dotted: natural frequencies)", fontsize=10)
        fig.tight_layout()
        out += save_figure(fig, f"{path}_{name}", formats or ("png",))
    return out
