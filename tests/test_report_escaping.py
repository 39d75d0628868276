"""Text from a listing is shown, never obeyed, in every medium it reaches
(issue 30, class "injection"): a LaTeX report cannot make the user's TeX run
`\\input` or `\\write18`, a Markdown report carries no live HTML, a figure does
not read `$...$` as mathtext, and no control character (a terminal's escape
sequences) reaches any of them.

The hostile listing below is an ordinary listing that runs: its TITLE, LABEL,
comments and a comment line carry the payloads."""

from __future__ import annotations

import re

import pytest

from amilpy.cli import main
from amilpy.output import highlight
from amilpy.output.report import markdown

PAYLOAD = "\\end{Verbatim}\\immediate\\write18{touch pwned}\\input{/etc/passwd}"
HOSTILE = f"""TITLE TORQUE $\\sqrt{{x$ {PAYLOAD} <script>alert(1)</script> \x1b]0;owned\x07
* {PAYLOAD}
* ````
* <img src=x onerror=alert(1)>
PARAM K = 1.0  ! [1/s] $\\sqrt{{
X = INTGRL(1.0, -K*X)  ! [$m^2$ \x1b[2J] {PAYLOAD}
TIMER FINTIM = 1.0, OUTDEL = 0.1
LABEL $\\frac{{a}}{{$ {PAYLOAD}
PRINT X
OUTPUT X
END
"""
CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f]")


@pytest.fixture
def hostile(tmp_path):
    path = tmp_path / "hostile.amil"
    path.write_text(HOSTILE, encoding="utf-8")
    return path


def _verbatim_balanced(text: str) -> bool:
    """Every Verbatim the body opens is closed by its own closing line, and nothing
    in between closes it early."""
    opened = 0
    for line in text.splitlines():
        if line.startswith("\\begin{Verbatim}"):
            opened += 1
            if opened > 1:
                return False
        elif "\\end{Verbatim}" in line:
            if line != "\\end{Verbatim}" or opened != 1:
                return False
            opened = 0
    return opened == 0


@pytest.mark.parametrize("pygments", [True, False], ids=["pygments", "no-pygments"])
def test_latex_report_runs_no_command_from_the_listing(hostile, tmp_path, monkeypatch,
                                                       pygments):
    """With Pygments (the listing highlighted) and without it (plain Verbatim): the
    payload's commands appear only escaped, every Verbatim ends where amilpy ends
    it, and no control character is written."""
    if not pygments:
        monkeypatch.setattr(highlight, "AmilLexer", None)
    out = tmp_path / "out"
    assert main(["report", str(hostile), "--format", "tex", "--out", str(out)]) == 0
    for name in ("hostile_report_body.tex", "hostile_report.tex"):
        text = (out / name).read_text(encoding="utf-8")
        for command in ("\\input{/etc", "\\write18", "\\immediate", "\\end{Verbatim}\\"):
            assert command not in text, (name, command)
        assert _verbatim_balanced(text), name
        assert not CONTROL.search(text), name
    body = (out / "hostile_report_body.tex").read_text(encoding="utf-8")
    assert body.count("\\begin{Verbatim}") >= 2  # the listing and the equations


def test_verbatim_escapes_what_fancyvrb_would_read():
    """The one Verbatim writer: backslash and braces by character number (its
    commandchars), so a line can neither close the environment nor call a macro."""
    import io

    out = io.StringIO()
    highlight.verbatim(["\\end{Verbatim}", "{\\bf x}", "plain % text # & $ ^ _ ~"], out)
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("\\begin{Verbatim}[commandchars=\\\\\\{\\}")
    assert lines[1] == "\\char92{}end\\char123{}Verbatim\\char125{}"
    assert lines[2] == "\\char123{}\\char92{}bf x\\char125{}"
    assert lines[3] == "plain % text # & $ ^ _ ~"  # (other characters in a Verbatim)
    assert lines[4] == "\\end{Verbatim}"


def test_markdown_report_carries_no_live_html(hostile, tmp_path):
    """The listing's lines stay inside a fence longer than any backtick run in them
    (a line of four backticks cannot close it); text outside code has its tags and
    markup escaped; no control character."""
    out = tmp_path / "out"
    assert main(["report", str(hostile), "--format", "md", "--out", str(out)]) == 0
    text = (out / "hostile_report.md").read_text(encoding="utf-8")
    assert not CONTROL.search(text)
    inside, mark, live = False, "", []
    for line in text.splitlines():
        if not inside and line.startswith("```"):
            inside, mark = True, re.match("`+", line).group(0)
        elif inside and line.startswith("`") and line.strip() == mark:
            inside = False
        elif not inside:
            live.append(line)
        else:
            assert not line.startswith(mark)  # (a closing fence inside the code)
    assert not inside
    outside = "\n".join(live)
    assert not re.search(r"(?<!\\)<(script|img)", outside)
    assert "\\<script>" in outside  # the TITLE, shown as text


def test_markdown_fence_outgrows_the_backticks_in_its_lines():
    assert markdown.fence(["x = 1"]) == "```"
    assert markdown.fence(["* ````", "``"]) == "`````"


@pytest.mark.parametrize("command", [["run", "--plot", "--quiet"],
                                     ["report", "--format", "pdf,md"],
                                     ["sweep", "K=1.0:2.0:0.5", "--measure", "X", "--plot"]])
def test_figures_draw_dollars_as_written(hostile, tmp_path, capsys, command):
    """A TITLE and a LABEL with unbalanced `$\\sqrt{` (mathtext's ValueError ended
    the command with a traceback) and a comment unit with `$m^2$`: the figures are
    drawn, with the text as written, and matplotlib warns of no missing glyph
    (the control characters are shown as "?")."""
    import warnings

    verb, *rest = command
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        code = main([verb, str(hostile), *rest, "--out", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "Traceback" not in captured.err
    pngs = sorted(tmp_path.glob("*.png"))
    assert pngs and all(p.read_bytes().startswith(b"\x89PNG") for p in pngs)


def test_figure_title_is_the_listing_text(hostile):
    """The title drawn is the TITLE's text, dollars and backslashes included (not a
    formula), and math parsing is off for it."""
    import amilpy
    from amilpy.output.plot import draw, figure_specs

    run = amilpy.load(str(hostile)).run(advice=False)[0]
    fig = draw([run], figure_specs(run)[0])
    title = fig.axes[0].title
    assert title.get_text().startswith("TORQUE $\\sqrt{x$")
    assert title.get_parse_math() is False
    assert "\x1b" not in title.get_text()


def test_latex_refuses_a_file_name_it_would_have_to_give_raw(tmp_path, capsys):
    """\\input and \\includegraphics take the report's file names as they are: a
    listing named with TeX's special characters is refused for LaTeX (exit 4,
    saying what to do) and still written as Markdown."""
    path = tmp_path / "a}\\input{x}%.amil"
    path.write_text("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, OUTDEL = 0.5\nPRINT X\nEND\n")
    code = main(["report", str(path), "--format", "tex,md", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 4
    assert "LaTeX would read as commands" in err and "copy the listing to a name" in err
    assert not list((tmp_path / "o").glob("*.tex"))
    md = (tmp_path / "o" / "a}\\input{x}%_report.md").read_text(encoding="utf-8")
    assert "(a%7D%5Cinput%7Bx%7D%25.png)" in md  # the image link, percent-encoded
