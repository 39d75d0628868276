import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import amilpy  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from amilpy.routes import ROUTES  # noqa: E402

# one METHOD spelling per route, from the registry
METHODS = [r.aliases[0] for r in ROUTES]


def run1(text: str, **kw):
    """Run a one-run listing and return its Run."""
    runs = amilpy.loads(text, name="t.amil").run(**kw)
    assert len(runs) == 1
    return runs[0]


@pytest.fixture
def root() -> str:
    return ROOT
