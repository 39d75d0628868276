"""`amilpy.interact`: a slider per PARAM value; moving one runs the listing
again (no compilation) and redraws its figures; Freeze keeps curves to compare.

The widgets are built and driven here as a notebook's front end would drive them
(setting a slider's value, clicking a button); no notebook server is needed."""

import math
import sys

import pytest

import amilpy
from amilpy.output.sliders import comment_range, slider_specs

pytest.importorskip("ipywidgets")

# X = X0 exp(-K t): the closed form each slider position is checked against
DECAY = """TITLE DECAY
PARAM K = 1.0       ! [1/s] rate constant, 0.5 to 4
PARAM X0 = 2.0      ! [m] start
PARAM Z = 0.0
X = INTGRL(X0, -K*X + Z)
TIMER FINTIM = 2.0, OUTDEL = 0.1
OUTPUT X
LABEL DECAY [M]
END
"""


def _final(sliders):
    run = sliders.runs[0]
    return float(run.t[-1]), float(run["X"][-1])


def test_slider_ranges_come_from_the_comment_or_half_the_value():
    specs = {s.name: s for s in slider_specs(amilpy.loads(DECAY))}
    assert list(specs) == ["K", "X0", "Z"]
    assert (specs["K"].low, specs["K"].high, specs["K"].unit) == (0.5, 4.0, "1/s")
    assert (specs["X0"].low, specs["X0"].high) == (1.0, 3.0)  # 2 +- 50 %
    assert (specs["Z"].low, specs["Z"].high) == (0.0, 1.0)  # a zero: 0 to 1
    # the forms a comment may give a range in; a hyphen is a minus sign, not "to"
    assert comment_range("rate, 60..80") == (60.0, 80.0)
    assert comment_range("od 1.5E-3 do 2E-2") == (1.5e-3, 2e-2)
    assert comment_range("from -3 to -1") == (-3.0, -1.0)
    assert comment_range("60 – 80") == (60.0, 80.0)
    assert comment_range("stage 2-4") is None and comment_range("80 to 60") is None


def test_moving_a_slider_reruns_without_compiling():
    model = amilpy.loads(DECAY)
    sliders = amilpy.interact(model)
    t, x = _final(sliders)
    # default tolerances: far below a plotted pixel, and below the printout's digits
    assert x == pytest.approx(2.0 * math.exp(-2.0), rel=1e-7)
    before = sliders.images[0].value
    sliders.sliders["K"].value = 3.0  # what dragging the slider does
    t, x = _final(sliders)
    assert x == pytest.approx(2.0 * math.exp(-6.0), rel=1e-7)
    assert sliders.images[0].value != before  # redrawn
    sliders.update(K=0.5, X0=1.0)  # two sliders, one run
    assert _final(sliders)[1] == pytest.approx(math.exp(-1.0), rel=1e-7)
    assert sliders.runs_done == 3
    # PARAM values are arguments of the code built once: one compilation in all
    assert len(model.cache._tables["code"]) == 1


def test_freeze_keeps_the_curves_and_clear_drops_them():
    sliders = amilpy.interact(amilpy.loads(DECAY))
    freeze, clear = sliders.widget.children[len(sliders.sliders)].children
    sliders.update(K=2.0)
    freeze.click()
    assert [label for label, _ in sliders.frozen] == ["K = 2"]
    sliders.update(K=3.0)
    assert sliders._described() == "K = 3"
    frozen_run = sliders.frozen[0][1][0]
    assert float(frozen_run["X"][-1]) == pytest.approx(2.0 * math.exp(-4.0), rel=1e-7)
    clear.click()
    assert sliders.frozen == []


def test_a_run_that_fails_says_so_and_keeps_the_figures():
    listing = DECAY.replace("-K*X + Z", "-K*X/(1.0 - Z)")
    sliders = amilpy.interact(amilpy.loads(listing))
    sliders.update(Z=0.5)
    assert "run(s) in" in sliders.status.value
    sliders.update(Z=1.0)  # (the slider's end: a division by zero at TIME 0)
    assert "color:red" in sliders.status.value and "division by zero" in \
        sliders.status.value
    assert sliders.images and sliders.images[0].value


def test_named_sliders_and_bad_names():
    sliders = amilpy.interact(amilpy.loads(DECAY), names=["x0"], K=2.0)
    assert list(sliders.sliders) == ["X0"]
    assert _final(sliders)[1] == pytest.approx(2.0 * math.exp(-4.0), rel=1e-7)
    with pytest.raises(amilpy.UsageError, match="KK is not a variable or data value"):
        amilpy.interact(amilpy.loads(DECAY), names=["KK"])
    for names in (["X"], ["K", "X"]):  # (never dropped quietly beside a good name)
        with pytest.raises(amilpy.UsageError, match="X is a variable, not a data value"):
            amilpy.interact(amilpy.loads(DECAY), names=names)
    with pytest.raises(amilpy.UsageError, match="no slider for W"):
        sliders.update(W=1.0)


def test_without_ipywidgets_the_message_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)
    with pytest.raises(amilpy.UsageError, match=r"pip install 'amilpy\[widgets\]'"):
        amilpy.interact(amilpy.loads(DECAY))


def test_the_tutorials_sliders_for_the_clutch():
    # docs/tutorial.md: `amilpy.interact("models/ex4_clutch.amil")` gives C and B,
    # and its two OUTPUT statements as two figures
    import os

    from conftest import ROOT

    sliders = amilpy.interact(os.path.join(ROOT, "models", "ex4_clutch.amil"), fintim=0.05)
    assert list(sliders.sliders) == ["C", "B"]
    assert len(sliders.images) == 2 and all(i.value[:4] == b"\x89PNG" for i in sliders.images)
    assert sliders.runs[0].ok
