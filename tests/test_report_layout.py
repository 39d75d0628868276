"""The report's pages, looked at as rendered (issue 28): a 31-line listing with two
runs fits in four A4 pages in both PDFs; no text leaves the text block; long
listing lines wrap, marked, instead of running off the page; the figures are
vector graphics; the LaTeX document compiles in one pdflatex run with nothing
overfull and no package beyond latex-base/recommended.

pdftotext/pdfimages (poppler-utils) and pdflatex are looked for; a test that
needs one that is missing skips and says so."""

import os
import re
import shutil
import subprocess

import pytest
from conftest import ROOT

from amilpy.output.report import make_report

# A lab listing of the size the issue names: 31 lines, a PARAM value list (two
# runs), a 51-row printout each, two OUTPUT figures, RANGE, events.
MOTOR = """TITLE DC MOTOR START-UP WITH A FLEXIBLE COUPLING (EXERCISE 4, TWO DAMPINGS)
* A separately excited motor drives a load through a shaft of stiffness C and
* damping B. The load torque acts from the start; the supply is switched on at 0.
*   L dIA/dt = U - R*IA - KE*W1                 armature circuit
*   J1 dW1/dt = KT*IA - C*TH - B*(W1 - W2)       rotor
*   J2 dW2/dt = C*TH + B*(W1 - W2) - MOBC        load
*   dTH/dt = W1 - W2                             shaft twist
CONST  U = 12.0, R = 13.7, L = 2.9E-3     ! [V] supply; [ohm] winding; [H] inductance
CONST  KT = 3.03E-2, KE = 3.03E-2         ! [N*m/A] torque constant; [V*s/rad] back-EMF
CONST  J1 = 1.1E-6, J2 = 2.2E-6           ! [kg*m2] rotor; [kg*m2] load
CONST  MOBC = 2.0E-3                      ! [N*m] load torque
PARAM  C = 2.0                            ! [N*m/rad] shaft stiffness
PARAM  B = (2.0E-5, 2.0E-4)               ! [N*m*s/rad] shaft damping
DYNAMIC
   IA   = INTGRL(0.0, (U - R*IA - KE*W1)/L)
   MC   = C*TH + B*(W1 - W2)
   W1   = INTGRL(0.0, (KT*IA - MC)/J1)
   ML   = FSW(W2, 0.0, AMIN1(MC, MOBC), MOBC)
   W2   = INTGRL(0.0, (MC - ML)/J2)
   TH   = INTGRL(0.0, W1 - W2)
   P    = U*IA                            ! [W] power drawn
TIMER  FINTIM = 0.1, PRDEL = 2.0E-3, OUTDEL = 1.0E-4
METHOD AUTO
PRINT  IA, W1, W2, TH, MC, P
OUTPUT W1, W2
LABEL  ANGULAR VELOCITIES W1, W2 [RAD/S]
OUTPUT MC
LABEL  COUPLING TORQUE MC [N*M]
RANGE  W1, W2, MC, IA
END
STOP
"""

# eleven PRINT variables: the printout table is wider than any page
ELEVEN = """TITLE ELEVEN PRINTED VARIABLES
X = INTGRL(1.0, -X)
""" + "".join(f"Y{k} = {k}.0*X - 1.0E-{k}\n" for k in range(1, 11)) + """\
TIMER FINTIM = 1.0, PRDEL = 0.05
PRINT X, """ + ", ".join(f"Y{k}" for k in range(1, 11)) + """
END
"""

A4_WIDTH = 595.28  # points
MARGIN = 56.69  # 2 cm: both PDFs' left and right margins


def _need(tool):
    if shutil.which(tool) is None:
        pytest.skip(f"{tool} is not installed: the rendered pages were not checked")


def _pdflatex(folder, name):
    """One pdflatex run: (return code, log)."""
    done = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error", name],
                          cwd=folder, capture_output=True, text=True, timeout=300)
    log = (folder / name.replace(".tex", ".log")).read_text(errors="replace")
    return done.returncode, log


def _pages(pdf):
    out = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True, check=True)
    return int(re.search(r"Pages:\s+(\d+)", out.stdout).group(1))


def _boxes(pdf):
    """(page, x_min, y_min, x_max, y_max, word) of every word pdftotext finds."""
    html = subprocess.run(["pdftotext", "-bbox", str(pdf), "-"], capture_output=True,
                          text=True, check=True).stdout
    out, page = [], 0
    for line in html.splitlines():
        if "<page " in line:
            page += 1
        m = re.search(r'<word xMin="([\d.]+)" yMin="([\d.]+)" xMax="([\d.]+)" '
                      r'yMax="([\d.]+)">(.*?)</word>', line)
        if m:
            out.append((page, *(float(g) for g in m.groups()[:4]), m.group(5)))
    return out


def _words(pdf):
    """(page, x_min, x_max, word) of every word."""
    return [(p, x0, x1, w) for p, x0, _, x1, _, w in _boxes(pdf)]


def _report(tmp_path, name, text, formats=("pdf", "tex")):
    listing = tmp_path / f"{name}.amil"
    listing.write_text(text)
    out = tmp_path / "r"
    make_report(str(listing), str(out), formats, lang="en")
    return out


@pytest.fixture(scope="module")
def motor(tmp_path_factory):
    """The motor listing's report in both PDFs, the LaTeX one made by one run."""
    tmp_path = tmp_path_factory.mktemp("motor")
    out = _report(tmp_path, "motor", MOTOR)
    latex = None
    if shutil.which("pdflatex"):
        code, log = _pdflatex(out, "motor_report.tex")
        assert code == 0, log[-3000:]
        latex = (out / "motor_report.pdf").read_bytes(), log
    make_report(str(tmp_path / "motor.amil"), str(out), ("pdf",), lang="en")  # (over it)
    return out, latex


def test_a_31_line_listing_with_two_runs_fits_four_pages(motor, tmp_path):
    _need("pdfinfo")
    out, latex = motor
    assert MOTOR.count("\n") == 31
    assert _pages(out / "motor_report.pdf") <= 4  # matplotlib's
    if latex is None:
        pytest.skip("no pdflatex: the LaTeX report's pages were not counted")
    (tmp_path / "latex.pdf").write_bytes(latex[0])
    assert _pages(tmp_path / "latex.pdf") <= 4


def test_latex_compiles_in_one_run_with_nothing_overfull(motor):
    _need("pdflatex")
    out, (_, log) = motor
    # longtable's columns have fixed widths and nothing refers forward: no rerun
    assert "Rerun" not in log and "Overfull" not in log
    wrapper = (out / "motor_report.tex").read_text()
    # lmodern only where installed (Debian's latex-recommended lacks it)
    assert "\\IfFileExists{lmodern.sty}{\\usepackage{lmodern}}{}" in wrapper
    for package in re.findall(r"\\usepackage(?:\[[^]]*\])?\{([^}]*)\}", wrapper):
        # every package the document loads is in latex-base or latex-recommended
        assert package in {"inputenc", "fontenc", "lmodern", "booktabs", "longtable", "array",
                           "graphicx", "fancyvrb", "color", "geometry"}, package


@pytest.mark.parametrize("name, text", [("motor", MOTOR), ("eleven", ELEVEN)])
def test_no_text_outside_the_text_block(name, text, tmp_path):
    _need("pdftotext")
    out = _report(tmp_path, name, text)
    pdfs = {"matplotlib": out / f"{name}_report.pdf"}
    if shutil.which("pdflatex"):
        code, log = _pdflatex(out, f"{name}_report.tex")
        assert code == 0 and "Overfull" not in log, log[-3000:]
        (out / "latex.pdf").write_bytes((out / f"{name}_report.pdf").read_bytes())
        make_report(str(tmp_path / f"{name}.amil"), str(out), ("pdf",), lang="en")
        pdfs["latex"] = out / "latex.pdf"
    for kind, pdf in pdfs.items():
        words = _words(pdf)
        assert words
        # (1 pt of slack for the rounding of glyph boxes)
        outside = [w for w in words if w[1] < MARGIN - 1 or w[2] > A4_WIDTH - MARGIN + 1]
        assert not outside, (kind, outside[:5])
    # every printed variable's name is on a page: the wide table was split, not cut
    if name == "eleven":
        for pdf in pdfs.values():
            names = {w[3] for w in _words(pdf)}
            assert {"X", "Y1", "Y9", "Y10"} <= names


def test_a_long_listing_line_wraps_marked(tmp_path):
    """models/ex4_clutch.amil line 41 ran off the LaTeX page at "[ohm] termi"."""
    _need("pdftotext")
    source = os.path.join(ROOT, "models", "ex4_clutch.amil")
    line41 = open(source).read().splitlines()[40]
    assert len(line41) > 100
    out = tmp_path / "r"
    make_report(source, str(out), ("pdf", "tex"), lang="en")
    pdfs = [out / "ex4_clutch_report.pdf"]
    if shutil.which("pdflatex"):
        code, log = _pdflatex(out, "ex4_clutch_report.tex")
        assert code == 0, log[-3000:]
        (out / "latex.pdf").write_bytes((out / "ex4_clutch_report.pdf").read_bytes())
        make_report(source, str(out), ("pdf",), lang="en")
        pdfs.append(out / "latex.pdf")
    tail = line41.split("!", 1)[1].split()  # the comment: where the line overflowed
    for pdf in pdfs:
        text = subprocess.run(["pdftotext", "-f", "1", "-l", "2", str(pdf), "-"],
                              capture_output=True, text=True, check=True).stdout
        words = text.split()
        start = words.index("[V]")  # the comment's first word, then all of it in order
        assert words[start:start + 30] != tail[:30]  # (a mark interrupts it...)
        kept = [w for w in words[start:start + len(tail) + 6] if w in tail]
        assert kept == tail  # ...and nothing of it is lost


def test_figures_are_vector_graphics(motor, tmp_path):
    _need("pdfimages")
    out, latex = motor
    pdfs = [out / "motor_report.pdf"]
    if latex is not None:
        (tmp_path / "latex.pdf").write_bytes(latex[0])
        pdfs.append(tmp_path / "latex.pdf")
    for pdf in pdfs:
        listed = subprocess.run(["pdfimages", "-list", str(pdf)], capture_output=True,
                                text=True, check=True).stdout.splitlines()
        assert len(listed) == 2, listed  # the header only: no raster image anywhere
        # and the figures are there: their axis labels are text on the page
        words = {w[3] for w in _words(pdf)} if shutil.which("pdftotext") else {"[s]"}
        assert "[s]" in words


def _word_boxes(pdf):
    """(page, y_min, y_max, word) of every word."""
    return [(p, y0, y1, w) for p, _, y0, _, y1, w in _boxes(pdf)]


def test_a_figure_taller_than_a_page_is_drawn_smaller_not_cut(tmp_path):
    """Seven stacked axes (--subplots) are taller than the text's width allows: the
    figure is narrowed to fit its page with its caption (a review found it run off
    the page's foot, the caption lost)."""
    _need("pdftotext")
    names = [f"Y{k}" for k in range(1, 8)]
    listing = ("TITLE SEVEN AXES\nX = INTGRL(1.0, -X)\n"
               + "".join(f"{n} = {10 ** k}.0*X\n" for k, n in enumerate(names))
               + "TIMER FINTIM = 1.0, PRDEL = 0.5, OUTDEL = 0.01\n"
               + f"OUTPUT {', '.join(names)}\nEND\n")
    path = tmp_path / "seven.amil"
    path.write_text(listing)
    from amilpy.output.options import PlotOptions

    make_report(str(path), str(tmp_path / "r"), ("pdf",), lang="en",
                plot_options=PlotOptions(subplots=True))
    words = _word_boxes(tmp_path / "r" / "seven_report.pdf")
    caption = [w for w in words if w[3] == "Figure"]
    assert caption, "the caption is on a page"
    page = caption[0][0]
    # everything on the figure's page but its footer stays above the bottom margin
    foot = 841.89 - 0.95 * 72  # (the text block's foot; the footer sits below it)
    body = [w for w in words if w[0] == page and w[1] < 841.89 - 50]
    assert body and max(w[2] for w in body) <= foot + 1
    # and the page before does not end with the heading alone
    before = [w for w in words if w[0] == page - 1 and w[1] < 841.89 - 50]
    assert not before or before[-1][3] != "Plots"
