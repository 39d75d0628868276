"""docs/language.md is the reference a user looks things up in: it must say what
amilpy does. Its tables are generated from the registries (docs/make_language.py);
these tests fail when the file was not regenerated after a registry changed, and
run the listings it shows."""

from __future__ import annotations

import importlib.util
import math
import re
from pathlib import Path

import pytest

import amilpy

DOCS = Path(__file__).resolve().parent.parent / "docs"


def _generator():
    spec = importlib.util.spec_from_file_location("make_language", DOCS / "make_language.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _listings() -> list[str]:
    text = (DOCS / "language.md").read_text("utf-8")
    return re.findall(r"```\n(.*?)```", text, re.S)


def test_language_md_is_what_the_registries_say():
    assert (DOCS / "language.md").read_text("utf-8") == _generator().render(), \
        "docs/language.md is out of date: run python docs/make_language.py"


def test_every_function_and_refusal_is_listed():
    from amilpy import language
    from amilpy.library import FUNCTIONS

    text = (DOCS / "language.md").read_text("utf-8")
    for f in FUNCTIONS.values():
        if not f.name.startswith("."):
            assert f"`{f.signature}`" in text
    for keyword in (*language.REFUSED, *language.REFUSED_FUNCTIONS):
        assert f"`{keyword}" in text


def test_the_csmp_form_example_runs_and_oscillates_at_sqrt_k_over_m(tmp_path):
    # x'' = -K/M x from x = 1: x(t) = cos(2t); the default tolerances give 1e-5
    path = tmp_path / "spring.amil"
    path.write_text(_listings()[0], "utf-8")
    run, = amilpy.load(str(path)).run(advice=False)
    assert run.ok
    for t, x in zip(run.times, run.values["X"], strict=True):
        assert x == pytest.approx(math.cos(2.0 * t), abs=1e-4)


def test_the_acsl_form_example_doses_by_superposition(tmp_path):
    # doses of 100 at 0, 8, 16, ... decaying at KE = 0.2: A(t) is the sum of
    # 100 exp(-0.2 (t - 8k)) over the doses given by t (the dose at t itself included,
    # DISCRETE runs before the row). 1e-5 relative: ten times the default RELERR,
    # which bounds each step's error, not the error carried over 48 h.
    path = tmp_path / "dosing.csl"
    path.write_text(_listings()[1], "utf-8")
    run, = amilpy.load(str(path)).run(advice=False)
    assert run.t_end == pytest.approx(48.0)
    for t, a in zip(run.times, run.values["A"], strict=True):
        exact = sum(100.0 * math.exp(-0.2 * (t - 8.0 * k)) for k in range(7)
                    if 8.0 * k <= t + 1e-9)
        assert a == pytest.approx(exact, rel=1e-5)


def test_the_acsl_macro_example_is_two_lags_in_series(tmp_path):
    # Z = 1 - e^(-t/2), W (a lag of Z) = 1 - e^(-t/2)(1 + t/2); 1e-8 at the ACSL form's
    # default RELERR 1e-11
    text = next(t for t in _listings() if t.startswith("MACRO LAG"))
    path = tmp_path / "lags.csl"
    path.write_text(text, "utf-8")
    run, = amilpy.load(str(path)).run(advice=False)
    for t, z, w in zip(run.times, run.values["Z"], run.values["W"], strict=True):
        assert z == pytest.approx(1 - math.exp(-t / 2), abs=1e-8)
        assert w == pytest.approx(1 - math.exp(-t / 2) * (1 + t / 2), abs=1e-8)
    assert {"LAG#1.RATE", "LAG#2.RATE"} <= set(run.values)
