"""`amilpy report` for every shipped model: Markdown with each table and image,
LaTeX with booktabs tables, a PDF that opens with the right number of pages;
Polish TITLE text survives every format."""

import glob
import os
import re

import pytest
from conftest import ROOT

from amilpy.cli import main
from amilpy.output.report import make_report
from amilpy.output.report.document import build
from amilpy.output.report.pdf import pages

MODELS = sorted(glob.glob(os.path.join(ROOT, "models", "*.amil")))


def pdf_pages(path: str) -> int:
    data = open(path, "rb").read()
    assert data.startswith(b"%PDF-") and data.rstrip().endswith(b"%%EOF")
    return len(re.findall(rb"/Type\s*/Page(?![s\w])", data))


@pytest.mark.parametrize("path", MODELS, ids=os.path.basename)
def test_report_of_every_shipped_model(path, tmp_path):
    written = make_report(path, str(tmp_path), ("md", "tex", "pdf"))
    stem = os.path.splitext(os.path.basename(path))[0]
    md = open(written["md"], encoding="utf-8").read()
    for heading in ("## Listing", "## Data and initial values", "## Equations as evaluated",
                    "## Run 1", "## Plots"):
        assert heading in md, heading
    images = re.findall(r"!\[[^]]*\]\(([^)]+)\)", md)
    assert images and all(os.path.exists(tmp_path / i) for i in images)
    assert "| TIME |" in md
    tex = open(written["tex"], encoding="utf-8").read()
    assert "\\begin{document}" in tex and tex.endswith("\\end{document}\n")
    body = (tmp_path / f"{stem}_report_body.tex").read_text(encoding="utf-8")
    assert "\\toprule" in body and "\\documentclass" not in body
    # the figures as vector PDFs for LaTeX, beside the PNGs
    for image in images:
        vector = (tmp_path / image).with_suffix(".pdf")
        assert vector.read_bytes().startswith(b"%PDF") and vector.name in body
    assert pdf_pages(written["pdf"]) >= 1
    assert stem in written["md"]


def test_polish_title_in_every_format(tmp_path):
    listing = tmp_path / "napęd.amil"
    listing.write_text("TITLE Napęd z mikrosilnikiem — prędkość kątowa ω\nX = INTGRL(1.0, -X)\n"
                       "TIMER FINTIM = 1.0, PRDEL = 0.25\nPRINT X\nRANGE X\nEND\n",
                       encoding="utf-8")
    assert main(["report", str(listing), "--out", str(tmp_path / "r"),
                 "--format", "md,tex,pdf"]) == 0
    out = tmp_path / "r"
    title = "Napęd z mikrosilnikiem — prędkość kątowa ω"
    assert f"# {title}" in (out / "napęd_report.md").read_text(encoding="utf-8")
    assert "Napęd z mikrosilnikiem — prędkość kątowa \\ensuremath{\\omega}" in (
        out / "napęd_report_body.tex").read_text(encoding="utf-8")
    assert pdf_pages(str(out / "napęd_report.pdf")) == 1  # text and figure on one page


def test_report_format_is_checked(tmp_path, capsys):
    assert main(["report", MODELS[0], "--format", "docx"]) == 2


# ------------------------------------------------------------- contents

WIDE = """TITLE SEVEN LONG NAMES, A LINE-PRINTER FIGURE AND TWO RUNS
PARAM B = 6.0E-5                ! [N*m*s/rad] coupling damping
CONST U = 12.0, R = 13.7        ! [V] supply voltage; [ohm] winding resistance
INITIAL
   TAU = 0.5                    ! s: time constant
   K2  = 2.0*B                  ! a value with a description only
DYNAMIC
   ALPHA1 = INTGRL(1.0, -ALPHA1/TAU)
   ALPHA2 = 2.0*ALPHA1 - 1.0E5*B
   ALPHA3 = 3.0*ALPHA1
   ALPHA4 = 4.0*ALPHA1
   ALPHA5 = 5.0*ALPHA1
   ALPHA6 = 6.0*ALPHA1
   ALPHA7 = -7.0E-12*ALPHA1
TIMER FINTIM = 1.0, PRDEL = 0.1, OUTDEL = 0.01
PRINT ALPHA1, ALPHA2, ALPHA3, ALPHA4, ALPHA5, ALPHA6, ALPHA7
PRTPLT ALPHA1, ALPHA3
LABEL ANGLES [RAD]
END
PARAM B = 2.0E-4
END
STOP
"""


@pytest.fixture
def wide(tmp_path):
    path = tmp_path / "wide.amil"
    path.write_text(WIDE)
    written = make_report(str(path), str(tmp_path / "r"), ("md", "tex", "pdf"), lang="en")
    return tmp_path / "r", written


def test_data_table_has_units_and_descriptions_from_comments(wide):
    out, written = wide
    md = open(written["md"], encoding="utf-8").read()
    assert "| name | value | unit | description | defined |" in md
    assert "| B | 6e-05 | N\\*m\\*s/rad | coupling damping | PARAM, line 2 |" in md
    assert "| U | 12 | V | supply voltage | CONST, line 3 |" in md
    assert "| R | 13.7 | ohm | winding resistance | CONST, line 3 |" in md
    assert "| TAU | 0.5 | s | time constant | INITIAL, line 5 |" in md
    assert "| K2 | 0.00012 |  | a value with a description only | INITIAL, line 6 |" in md


def test_runs_are_headed_by_their_values_and_plots_captioned(wide):
    out, written = wide
    md = open(written["md"], encoding="utf-8").read()
    assert "## Run 1: B = 6e-05" in md and "## Run 2: B = 0.0002" in md
    assert "*Figure 1: ANGLES \\[RAD\\]: ALPHA1, ALPHA3 against TIME; B = 6e-05; " \
           "B = 0.0002*" in md
    body = (out / "wide_report_body.tex").read_text(encoding="utf-8")
    assert "\\caption{ANGLES [RAD]: ALPHA1, ALPHA3 against TIME; B = 6e-05; B = 0.0002}" \
        in body
    assert "\\subsection*{\\raggedright Run 2: B = 0.0002}" in body


def test_printer_plots_in_every_format(wide):
    out, written = wide
    md = open(written["md"], encoding="utf-8").read()
    assert md.count("PRINTER PLOT   * ALPHA1   + ALPHA3") == 2  # one per run
    body = (out / "wide_report_body.tex").read_text(encoding="utf-8")
    assert body.count("PRINTER PLOT   * ALPHA1   + ALPHA3") == 2
    # (a printer plot 100 characters wide fits the text in \\small, as the listing)
    assert "\\begin{Verbatim}[commandchars=\\\\\\{\\},fontsize=\\small]\nANGLES [RAD]" in body
    text = pdf_text(written["pdf"])
    assert text is None or text.count("PRINTER PLOT") == 2


def pdf_text(path):
    """The PDF's text with its layout (pdftotext from poppler-utils), or None."""
    import shutil
    import subprocess

    if shutil.which("pdftotext") is None:
        return None
    return subprocess.run(["pdftotext", "-layout", path, "-"], capture_output=True,
                          text=True, check=True).stdout


def test_pdf_lines_are_never_cut(wide, tmp_path):
    """The PDF cut every line at 110 characters: with 7 PRINT variables the last
    column lost its name and exponents. Now tables split by columns and text wraps;
    every header and every exponent of the last column is in the PDF's text."""
    out, written = wide
    from amilpy.api import load

    runs = load(str(tmp_path / "wide.amil")).run()
    text = pdf_text(written["pdf"])
    if text is None:
        pytest.skip("pdftotext (poppler-utils) is not installed: page text not checked")
    for name in ("ALPHA1", "ALPHA6", "ALPHA7"):
        assert f" {name}" in text
    last = runs[0].printout["ALPHA7"]
    for v in last:
        assert f"{v:.6E}" in text  # e.g. -7.000000E-12, whole


def test_tables_split_across_pages_repeat_their_header(tmp_path):
    path = tmp_path / "long.amil"
    path.write_text("X = INTGRL(1.0, -X)\nTIMER FINTIM = 3.0, PRDEL = 0.01\nPRINT X\nEND\n")
    written = make_report(str(path), str(tmp_path), ("pdf",))
    if pdf_text(written["pdf"]) is None:
        pytest.skip("pdftotext (poppler-utils) is not installed: page text not checked")
    from amilpy.api import load

    model = load(str(path))
    split = pages(build(model, model.run(), [], str(path), "en"))
    assert len(split) >= 3
    import subprocess

    rows = 0
    for k in range(2, pdf_pages(written["pdf"]) + 1):  # the printout's 301 rows go on
        page = subprocess.run(["pdftotext", "-layout", "-f", str(k), "-l", str(k),
                               written["pdf"], "-"], capture_output=True, text=True,
                              check=True).stdout.split("\n")
        numbers = [i for i, line in enumerate(page) if re.match(r"\s*\d\.\d{6}E", line)]
        if numbers:  # its first row under the header, as on page 1
            header = page[numbers[0] - 1].split()
            assert header == ["TIME", "X"], page[:numbers[0]]
            rows += len(numbers)
    assert rows > 100


def test_headings_in_polish(tmp_path):
    listing = tmp_path / "naped.amil"
    listing.write_text("TITLE NAPED Z SILNIKIEM\nX = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\n"
                       "PRINT X\nEND\n")
    written = make_report(str(listing), str(tmp_path), ("md",))  # Polish words, no letters
    md = open(written["md"], encoding="utf-8").read()
    assert "## Listing programu" in md and "## Dane i wartości początkowe" in md
    assert "## Przebieg 1" in md and "## Wykresy" in md and "*Rys. 1:" in md
    written = make_report(str(listing), str(tmp_path), ("md",), lang="en")
    assert "## Listing\n" in open(written["md"], encoding="utf-8").read()


def test_language_from_text_then_locale():
    from amilpy.output.words import detect_language

    assert detect_language(["Napęd"], {}) == "pl"
    assert detect_language(["CWICZENIE 4"], {}) == "pl"
    assert detect_language(["CLUTCH"], {"LANG": "pl_PL.UTF-8"}) == "pl"
    assert detect_language(["CLUTCH"], {"LANG": "de_DE.UTF-8"}) == "en"
    assert detect_language(["CLUTCH"], {"LC_ALL": "C", "LANG": "pl_PL.UTF-8"}) == "en"


def test_latex_body_compiles_inside_a_wrapper(wide, tmp_path):
    """The body is `\\input` into a student's own document (here a minimal one that
    loads the packages the body's first lines name) and compiled with pdflatex."""
    import shutil
    import subprocess

    if shutil.which("pdflatex") is None:
        pytest.skip("no LaTeX installed (pdflatex): the body was not compiled")
    out, written = wide
    body = (out / "wide_report_body.tex").read_text(encoding="utf-8")
    packages = body.splitlines()[1].split("usepackage{")[1].rstrip("}")
    wrapper = out / "student.tex"
    wrapper.write_text("\\documentclass{article}\n\\usepackage[T1]{fontenc}\n"
                       f"\\usepackage{{{packages}}}\n\\begin{{document}}\n"
                       "\\section{My lab report}\n\\input{wide_report_body}\n"
                       "\\section{Conclusions}\n\\end{document}\n")
    for _ in range(2):  # longtable settles its columns on the second pass
        done = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error",
                               "student.tex"], cwd=out, capture_output=True, text=True,
                              timeout=180)
        assert done.returncode == 0, done.stdout[-3000:]
    assert (out / "student.pdf").read_bytes().startswith(b"%PDF")
    # the document beside it compiles too
    done = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error",
                           "wide_report.tex"], cwd=out, capture_output=True, text=True,
                          timeout=180)
    assert done.returncode == 0, done.stdout[-3000:]


def test_golden_report(tmp_path, monkeypatch):
    """The Markdown report of golden/clutch_breakpoint.amil, exactly (regenerate with
    AMILPY_GOLDEN=update and read the diff, as for the golden printouts)."""
    golden = os.path.join(ROOT, "tests", "golden")
    monkeypatch.chdir(golden)
    written = make_report("clutch_breakpoint.amil", str(tmp_path), ("md",), lang="en")
    got = open(written["md"], encoding="utf-8").read()
    path = os.path.join(golden, "clutch_breakpoint_report.md")
    if os.environ.get("AMILPY_GOLDEN") == "update":
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(got)
    with open(path, encoding="utf-8") as fh:
        assert got == fh.read()
