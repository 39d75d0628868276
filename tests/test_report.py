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
    # the text pages, then one per figure
    from amilpy.api import load

    model = load(path)
    figures = [(str(tmp_path / i), "") for i in images]
    doc = build(model, model.run(), figures, path, "en")
    assert pdf_pages(written["pdf"]) == len(pages(doc)) + len(images)
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
    assert pdf_pages(str(out / "napęd_report.pdf")) == 2  # one text page, one figure


def test_report_format_is_checked(tmp_path, capsys):
    assert main(["report", MODELS[0], "--format", "docx"]) == 2
