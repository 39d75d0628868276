"""The optional compiled route (`pip install amilpy[fast]`, METHOD COMPILED).

The DOP853 step loop, the output rows and the location of plain crossings run as
one numba-compiled function (`kernel.advance`, compiled once per machine), calling
the model's right-hand side and surfaces, compiled per model text (`translate`) and
kept on disk (`cache_dir`); the run loop keeps every other rule. Parameters are
arguments, so a new PARAM value or a sweep point compiles nothing. Without numba,
or for a model with a construct that has no compiled form, the route runs as
DOP853 in Python and says why once (`kernel_for`).

Nothing here is imported by a plain run: numba is imported on the first
METHOD COMPILED run.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

from ..codegen import Compiled

ENV_CACHE = "AMILPY_CACHE"  # where the compiled models are kept (default ~/.cache/amilpy)


def available() -> bool:
    """numba can be imported (the [fast] extra is installed)."""
    return importlib.util.find_spec("numba") is not None


def cache_dir() -> Path:
    base = os.environ.get(ENV_CACHE) or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache"), "amilpy")
    return Path(base) / "compiled"


@dataclass(frozen=True)
class Kernel:
    """One model's compiled functions, the loop that runs them, and the order of the
    model's parameters."""

    module: ModuleType  # model_rhs, model_surf
    loop: ModuleType  # amilpy.compiled.kernel
    parameters: tuple[str, ...]

    def parameter_values(self, c: Compiled) -> np.ndarray:
        """The run's parameter values, in the order the compiled code reads them."""
        return np.array([c.namespace[n] for n in self.parameters], dtype=float)


_LOADED: dict[str, Kernel] = {}  # by module key, for this process
# by the generated Python source: a run whose constants differ (FINTIM, say) builds
# new scalar functions of the same text, and needs no new translation
_BY_SOURCE: dict[str, Kernel | str] = {}


def kernel_for(c: Compiled) -> Kernel | str:
    """The compiled module for `c`'s code (built, or read from the disk cache, once
    per process), or why there is none."""
    kernel = _BY_SOURCE.get(c.source)
    if kernel is None:
        kernel = _BY_SOURCE[c.source] = _build(c)
    return kernel


def _build(c: Compiled) -> Kernel | str:
    if not available():
        return "numba is not installed (pip install 'amilpy[fast]')"
    from . import kernel as loop
    from .translate import Unsupported, translate

    try:
        tr = translate(c)
    except Unsupported as exc:
        return f"this model has no compiled form: {exc}"
    if tr.key in _LOADED:
        return _LOADED[tr.key]
    folder = cache_dir()
    path = folder / f"amilpy_model_{tr.key}.py"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.read_text() != tr.text:
            # written whole, then renamed: a concurrent run never imports half a file
            fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
            with os.fdopen(fd, "w") as fh:
                fh.write(tr.text)
            os.replace(tmp, path)
    except OSError as exc:
        return f"cannot write the compiled model to {folder}: {exc.strerror or exc}"
    name = f"amilpy_model_{tr.key}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # numba's typing and lowering errors have no common base
        del sys.modules[name]
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return f"numba could not compile this model ({first})"
    kernel = _LOADED[tr.key] = Kernel(module, loop, tr.parameters)
    return kernel
