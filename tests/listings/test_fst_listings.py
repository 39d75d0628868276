"""Published FST listings, run as written (tests/listings/SOURCES.md, F1 and F2: the
Wageningen water-stress models, EUPL-1.2). The copies are not in the repository (the
tools' terms): a test whose copy is absent from tests/listings/fst/ is skipped. Their
WEATHER names station TZ 2 and a WTRDIR on the authors' disk; the run finds the
synthetic CABO files of tests/listings/weather/ in the listing's ../weather/ (contract
section 13's search order), which the reference writes and reads independently.

Each is FST's Euler loop (DRIVER = 'EUDRIV', DELT = 1 d): the rows must equal the
plain recurrence (references/water_stress.py) to round-off."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import amilpy
from listings import published_copy
from listings.references import water_stress

HERE = Path(__file__).resolve().parent / "fst"
SHA256 = {
    "legumes_water_stress.fst": "3d31d3c98a81d0fbee46478b7b7fdde9985a73297f9741306b22a84111c5143a",
    "maize_water_stress.fst": "8811eb799b3c9ec2dccb6866741fc54acf6854720f684de588bd9d13ff26852f",
}


def listing(name: str) -> Path:
    return published_copy(HERE, name, SHA256[name])


@pytest.mark.parametrize("name, key", [("legumes_water_stress.fst", "legumes"),
                                       ("maize_water_stress.fst", "maize")])
def test_water_stress_listing_is_the_euler_recurrence(name, key):
    run, = amilpy.load(listing(name)).run(advice=False)
    ref = water_stress.run(key)
    assert run.ok and run.method == "RECT"
    assert np.array_equal(run.times, ref["TIME"])
    worst = 0.0
    for column in ("WTOT", "WSOIL", "WRAIN", "WTRANSP", "WPERC", "RATIOACTPOT", "GROWTH",
                   "IABS", "OBSWT", "FABS"):
        scale = np.max(np.abs(ref[column])) or 1.0
        worst = max(worst, float(np.max(np.abs(run.values[column] - ref[column])) / scale))
    assert worst < 1e-12, worst
    # the listing's own water balance closes (its BALANCE column)
    assert np.max(np.abs(run.values["BALANCE"])) < 1e-9
    # both branches of the stress switch and of the percolation are exercised
    assert run.values["RATIOACTPOT"].min() < 1.0 and run.values["WPERC"][-1] > 0.0
