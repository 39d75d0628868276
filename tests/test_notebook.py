"""The notebook side of a Run: HTML summary, DataFrame, plotting helper."""

import pytest
from conftest import run1

import amilpy

LISTING = ("TITLE DECAY\nPARAM K = 2.0\nX = INTGRL(1.0, -K*X)\nY = 2.0*X\n"
           "TIMER FINTIM = 1.0, OUTDEL = 0.1, PRDEL = 0.05\nEND\n")


def test_run_html_summary_shows_status_and_rows():
    html = run1(LISTING)._repr_html_()
    assert "DECAY" in html and "finished" in html and "<th>TIME</th><th>X</th>" in html
    assert "&hellip;" in html  # 21 printout rows, the middle left out


def test_error_renders_as_html():
    with pytest.raises(amilpy.AmilError) as info:
        amilpy.loads("X = INTGRL(1.0, -KK*X)\nTIMER FINTIM = 1.0\n", name="m.amil")
    assert "m.amil:1:18: error: KK is used but never defined" in info.value._repr_html_()


def test_plot_returns_axes():
    ax = run1(LISTING).plot("x", "Y")
    assert [line.get_label() for line in ax.get_lines()] == ["X", "Y"]
    assert ax.get_xlabel() == "TIME [s]"


def test_to_pandas():
    pd = pytest.importorskip("pandas")
    frame = run1(LISTING).to_pandas()
    assert list(frame.columns) == ["X", "Y"] and frame.index.name == "TIME"
    assert isinstance(frame, pd.DataFrame) and len(frame) == 11
