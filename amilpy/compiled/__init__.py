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
import stat
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

from ..codegen import ModelCode

ENV_CACHE = "AMILPY_CACHE"  # where the compiled models are kept (default ~/.cache/amilpy)


def available() -> bool:
    """numba can be imported (the [fast] extra is installed)."""
    return importlib.util.find_spec("numba") is not None


def cache_dir() -> Path:
    base = os.environ.get(ENV_CACHE) or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache"), "amilpy")
    return Path(base) / "compiled"


def private_folder(folder: Path) -> str | None:
    """Make `folder` (mode 0700) if it is not there; why it may not hold code that
    this process runs, or None. The cache holds Python files that are imported and
    numba's index files that are unpickled: in a folder another user can write
    (AMILPY_CACHE pointed at a shared one), they could plant code that runs as
    whoever runs amilpy next."""
    try:
        folder.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        folder.mkdir(mode=0o700, exist_ok=True)
    except OSError as exc:
        return f"cannot make the folder {folder}: {exc.strerror or exc}"
    if not hasattr(os, "getuid"):  # (Windows: a user's own profile folder)
        return None
    for place in (folder.parent, folder):
        st = place.stat()  # (of what a link points to: that is where the files go)
        if st.st_uid != os.getuid():
            return f"{place} belongs to another user"
        if st.st_mode & 0o022:
            return (f"{place} can be written by other users (mode "
                    f"{stat.S_IMODE(st.st_mode):o})")
    return None


@dataclass(frozen=True)
class Kernel:
    """One model's compiled functions, the loop that runs them, and the order of the
    model's parameters."""

    module: ModuleType  # model_rhs, model_surf
    loop: ModuleType  # amilpy.compiled.kernel
    parameters: tuple[str, ...]

    def parameter_values(self, c: ModelCode) -> np.ndarray:
        """The run's parameter values, in the order the compiled code reads them."""
        return np.array([c.namespace[n] for n in self.parameters], dtype=float)


_LOADED: dict[str, Kernel] = {}  # by module key, for this process
# by the generated Python source: a run whose constants differ (FINTIM, say) builds
# new scalar functions of the same text, and needs no new translation
_BY_SOURCE: dict[tuple, Kernel | str] = {}


def kernel_for(c: ModelCode) -> Kernel | str:
    """The compiled module for `c`'s code (built, or read from the disk cache, once
    per process), or why there is none."""
    # (two listings can generate the same text and bind different parameters: one
    # whose INITIAL reads a PARAM that no derivative reads, and one with none; the
    # kernel reads its parameters by position, so they are part of the key)
    key = (c.source, tuple(sorted(k for k, v in c.namespace.items()
                                  if k.startswith("p_") and isinstance(v, float))))
    kernel = _BY_SOURCE.get(key)
    if kernel is None:
        kernel = _BY_SOURCE[key] = _build(c)
    return kernel


def _build(c: ModelCode) -> Kernel | str:
    if not available():
        return "numba is not installed (pip install 'amilpy[fast]')"
    loop = _kernel_module()
    from .translate import Unsupported, translate

    try:
        tr = translate(c)
    except Unsupported as exc:
        return f"this model has no compiled form: {exc}"
    if tr.key in _LOADED:
        return _LOADED[tr.key]
    folder = cache_dir()
    path = folder / f"amilpy_model_{tr.key}.py"
    refused = private_folder(folder)
    if refused is not None:
        return (f"the compiled models' folder is not private: {refused} (set {ENV_CACHE} "
                "to a folder of your own)")
    try:
        if not path.exists() or path.read_text() != tr.text:
            # written whole, then renamed: a concurrent run never imports half a file
            fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
            with os.fdopen(fd, "w") as fh:
                fh.write(tr.text)
            os.replace(tmp, path)
    except OSError as exc:
        return f"cannot write the compiled model to {folder}: {exc.strerror or exc}"
    name = f"amilpy_model_{tr.key}"
    try:
        module = _import(name, path)
    except Exception:  # noqa: BLE001 - (numba's errors have no common base)
        # a damaged cache of this model's compiled functions (read when the module
        # defines them) is removed, and the model compiled again, once
        _forget_cache(path)
        try:
            module = _import(name, path)
        except Exception as exc:  # noqa: BLE001 - typing and lowering errors
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            return f"numba could not compile this model ({first})"
    mend_cache(loop)
    kernel = _LOADED[tr.key] = Kernel(module, loop, tr.parameters)
    return kernel


def _kernel_module() -> ModuleType:
    """amilpy.compiled.kernel, whose entry points numba compiles (or reads from its
    cache) as the module is imported: a damaged cache file made the import fail, and
    every METHOD COMPILED run with it. Its cache is then removed and the module
    compiled again, once."""
    try:
        from . import kernel
    except Exception:  # noqa: BLE001 - whatever a damaged pickle raises
        from ..library import surfaces  # (the leaving rule, compiled with the kernel)

        for part in ("kernel.py", "dop853.py"):
            _forget_cache(Path(__file__).with_name(part))
        _forget_cache(Path(surfaces.__file__))
        from . import kernel
    return kernel


def _forget_cache(source: Path) -> None:
    """Remove numba's cache files of the functions in `source`, found where numba
    looks for them (its first cache locator that takes the file)."""
    from numba.core.caching import FunctionCache

    for locator in getattr(FunctionCache._impl_class, "_locator_classes", ()):
        try:
            found = locator.from_function(_forget_cache, str(source))
        except Exception:  # noqa: BLE001 - (numba's locators are not public API)
            continue
        if found is not None:
            for stale in Path(found.get_cache_path()).glob(f"{source.stem}.*.nb[ic]"):
                stale.unlink(missing_ok=True)
            return


def _import(name: str, path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


_MENDED: set[str] = set()


def mend_cache(module: ModuleType) -> None:
    """numba reads its on-disk cache with pickle and lets a damaged file (a disk
    full at the wrong moment, a copy cut short) raise at the function's first
    call: the run failed at TIME = 0 with "unregistered extension code". Each cached
    function of `module` has its index and entries read here once per process; one
    whose cache cannot be read has it emptied, and is compiled again. (numba's
    cache objects are not public API: where they are not found, nothing is done.)"""
    if module.__name__ in _MENDED:
        return
    _MENDED.add(module.__name__)
    for function in list(vars(module).values()):
        cache = getattr(function, "_cache", None)
        store = getattr(cache, "_cache_file", None)
        if store is None or not hasattr(store, "_load_index") or not hasattr(store, "load"):
            continue
        try:
            for key in store._load_index():
                store.load(key)
        except Exception:  # noqa: BLE001 - whatever a damaged pickle raises
            try:
                cache.flush()
            except OSError:
                pass
