"""The command line: exit codes, printout, files, overrides."""

import os

import pytest

import amilpy
from amilpy.cli import main

DECAY = """TITLE DECAY
PARAM K = 2.0
X = INTGRL(1.0, -K*X)
TIMER FINTIM = 1.0, PRDEL = 0.5, OUTDEL = 0.1
PRINT X
OUTPUT X
LABEL X AGAINST TIME
RANGE X
PREPARE X
END
STOP
"""


@pytest.fixture
def model(tmp_path):
    path = tmp_path / "decay.amil"
    path.write_text(DECAY)
    return path


def test_run_prints_the_lab_table(model, capsys):
    assert main(["run", str(model)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("DECAY\nRUN   (METHOD AUTO")
    lines = out.splitlines()
    head = lines.index("          TIME             X")
    assert lines[head + 1].split() == ["0.000000E+00", "1.000000E+00"]
    assert lines[head + 3].split()[0] == "1.000000E+00"
    assert "RANGE" in out and "MINIMUM" in out
    assert os.path.exists(model.parent / "decay.csv")  # PREPARE


def test_set_overrides_and_csv(model, tmp_path, capsys):
    csv = tmp_path / "out" / "x.csv"
    assert main(["run", str(model), "--set", "K=1.0", "--csv", str(csv), "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    rows = csv.read_text().splitlines()
    assert rows[0] == "TIME,X"
    assert len(rows) == 12
    t, x = map(float, rows[-1].split(","))
    assert t == 1.0 and x == pytest.approx(0.36787944, rel=1e-5)


def test_plot_writes_png(model, tmp_path):
    out = tmp_path / "figs"
    assert main(["run", str(model), "--plot", "--out", str(out), "--quiet"]) == 0
    png = out / "decay.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_written_files_get_the_usual_mode(model, tmp_path):
    """Files are written to a private temporary file and renamed: the CSV and PNG must
    still come out as a plain open() would make them (they were 0600), and an
    existing file keeps its mode."""
    umask = os.umask(0o022)
    try:
        out = tmp_path / "figs"
        assert main(["run", str(model), "--plot", "--out", str(out), "--quiet"]) == 0
        assert (out / "decay.png").stat().st_mode & 0o777 == 0o644
        assert (out / "decay.csv").stat().st_mode & 0o777 == 0o644
        os.chmod(out / "decay.png", 0o640)
        assert main(["run", str(model), "--plot", "--out", str(out), "--quiet"]) == 0
        assert (out / "decay.png").stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(umask)


def test_show_python(model, capsys):
    assert main(["run", str(model), "--show-python", "--quiet"]) == 0
    out = capsys.readouterr().out
    # K is a PARAM: read by name, so another value binds the same code
    assert "def rhs(t, y, m, z):" in out and "-p_K * v_X" in out


def test_check_ok_and_model_error_exit_codes(tmp_path, capsys):
    good = tmp_path / "g.amil"
    good.write_text(DECAY)
    assert main(["check", str(good)]) == 0
    bad = tmp_path / "b.amil"
    bad.write_text("X = INTGRL(1.0, -KK*X)\nTIMER FINTIM = 1.0\n")
    assert main(["check", str(bad)]) == 1
    err = capsys.readouterr().err
    assert f"{bad}:1:18: error: KK is used but never defined" in err
    assert "Traceback" not in err


@pytest.mark.parametrize("argv", [
    ["run"], ["frobnicate", "x.amil"], ["run", "x.amil", "--rtol", "abc"],
])
def test_usage_errors_exit_2(argv, capsys):
    assert main(argv) == 2


def test_bad_set_is_a_usage_error(model, capsys):
    assert main(["run", str(model), "--set", "K"]) == 2
    assert main(["run", str(model), "--set", "K=abc"]) == 2


def test_unknown_set_name_is_a_usage_error(model, capsys):
    # a name on the command line that the listing does not have is the command
    # line's mistake, not the listing's: exit 2, with the file and a hint
    assert main(["run", str(model), "--set", "KK=1"]) == 2
    err = capsys.readouterr().err
    assert f"amilpy: {model}: KK is not a PARAM/CONST/INCON value" in err and \
        "did you mean K?" in err


def test_missing_file(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.amil")]) == 1
    assert "cannot read" in capsys.readouterr().err


def test_failed_integration_exits_3_and_keeps_rows(tmp_path, capsys):
    path = tmp_path / "blow.amil"
    path.write_text("X = INTGRL(1.0, X*X)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\nPRINT X\n"
                    "PREPARE X\nEND\n")
    assert main(["run", str(path)]) == 3
    captured = capsys.readouterr()
    assert "PARTIAL RESULTS" in captured.out and "integration failed at TIME = " in captured.err
    # the exact solution 1/(1 - t) blows up at t = 1: rows up to 0.9 are kept
    rows = (tmp_path / "blow.csv").read_text().splitlines()
    assert rows[0].startswith("# PARTIAL (run 1): integration failed at TIME = ")
    assert rows[1] == "TIME,X"
    assert rows[11].startswith("0.9,")
    t_stop = float(rows[-1].split(",")[0])
    assert 0.99 < t_stop <= 1.0


def test_invalid_utf8(tmp_path, capsys):
    """Bytes that are not UTF-8 are read as Windows-1250 (then ISO-8859-2), with a
    note where they start; in code they are then characters the language refuses,
    at their place."""
    path = tmp_path / "bin.amil"
    path.write_bytes(b"X = 1.0\nY = \xff\xfe\n")
    assert main(["check", str(path)]) == 1
    err = capsys.readouterr().err
    assert ":2:5: error: character '\u02d9' is not allowed here" in err
    assert ":2:5: warning: the file is not UTF-8 (from here on): it was read as Windows-1250" \
        in err


def test_a_windows_1250_listing_is_read(tmp_path, capsys):
    """The lab's Windows machines save listings in Windows-1250: a Polish TITLE and
    comment are read as written, the run is the UTF-8 file's, and a note says how
    the file was read (issue 28 point 6)."""
    text = ("TITLE SPRZ\u0118G\u0141O CIERNE \u2013 \u0106WICZENIE 4\n"
            "X = INTGRL(1.0, -X)  ! [rad/s] pr\u0119dko\u015b\u0107 wa\u0142u\n"
            "TIMER FINTIM = 1.0, OUTDEL = 0.5\nPRINT X\nEND\n")
    legacy, utf8 = tmp_path / "cp.amil", tmp_path / "u8.amil"
    legacy.write_bytes(text.encode("cp1250"))
    utf8.write_text(text, encoding="utf-8")
    assert main(["run", str(legacy)]) == 0
    out = capsys.readouterr().out
    assert "SPRZ\u0118G\u0141O CIERNE \u2013 \u0106WICZENIE 4" in out
    assert "NOTE: line 1: the file is not UTF-8 (from here on): it was read as Windows-1250" \
        in out
    assert main(["run", str(utf8)]) == 0
    rows = [line for line in out.splitlines() if line.startswith("  ")]
    assert rows and rows == [line for line in capsys.readouterr().out.splitlines()
                             if line.startswith("  ")]


def test_ctrl_c_keeps_the_rows_and_exits_3(tmp_path, capsys, monkeypatch):
    # Ctrl-C in the middle of a run: the rows so far are printed and written,
    # marked partial, and no further run starts
    import amilpy.cli as cli

    path = tmp_path / "long.amil"
    path.write_text("PARAM K = (1.0, 2.0)\nX = INTGRL(0.0, COS(K*TIME))\n"
                    "TIMER FINTIM = 100.0, OUTDEL = 0.01\nPRINT X\nPREPARE X\nEND\n")

    class Interrupt:
        def __init__(self, enabled):
            pass

        def __call__(self, report):
            if report.task == "run" and report.done > 10.0:
                raise KeyboardInterrupt

        def done(self):
            pass

    monkeypatch.setattr(cli, "Progress", Interrupt)
    # one process: the progress callback that interrupts runs in this one
    assert main(["run", str(path), "--method", "RKS", "--jobs", "1"]) == 3
    out = capsys.readouterr()
    assert "interrupted at TIME = " in out.err and "PARTIAL RESULTS" in out.out
    rows = (tmp_path / "long.csv").read_text().splitlines()
    assert rows[0].startswith("# PARTIAL (run 1): interrupted at TIME = ")
    assert rows[1] == "TIME,X" and len(rows) > 500  # one run only, cut after TIME 10


# ------------------------------------------------------- usage, files, exit codes


def test_version(capsys):
    import amilpy

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"amilpy {amilpy.__version__}"


def test_every_option_is_described(capsys):
    # every option and argument of every command has a help text
    from amilpy.cli import _parser

    parser = _parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name, command in sub.choices.items():
        for action in command._actions:
            if action.dest != "help":
                assert action.help, f"{name} {action.option_strings or action.dest}"


@pytest.mark.parametrize("argv, option", [
    (["--method", "RUNGE"], "--method"),
    (["--max-time", "0"], "--max-time"), (["--max-time", "nan"], "--max-time"),
    (["--max-time", "-1"], "--max-time"), (["--max-steps", "0"], "--max-steps"),
    (["--max-steps", "1.5"], "--max-steps"), (["--max-events", "-3"], "--max-events"),
    (["--rtol", "inf"], "--rtol"), (["--atol", "0"], "--atol"), (["--fintim", "-1"], "--fintim"),
    (["--from", "nan"], "--from"), (["--runs", "0,2"], "--runs"),
])
def test_bad_values_are_usage_errors_naming_the_option(model, argv, option, capsys):
    assert main(["run", str(model), *argv]) == 2
    assert f"argument {option}:" in capsys.readouterr().err


def test_bad_method_lists_the_methods(model, capsys):
    from amilpy.routes import method_names

    assert main(["run", str(model), "--method", "RUNGE"]) == 2
    err = capsys.readouterr().err
    assert all(name in err for name in method_names())


@pytest.mark.parametrize("spec", ["K=nan:1:0.1", "K=0:inf:1", "K=0:1", "K=1:0:0.5", "K=0:1:0",
                                  "K=0:1e9:1e-3"])
def test_bad_sweep_ranges_are_usage_errors_with_the_file(model, spec, capsys):
    assert main(["sweep", str(model), spec]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"amilpy: {model}: the sweep range {spec}:") and "<listing>" not in err


def test_sweep_of_an_unknown_name_is_a_usage_error(model, capsys):
    assert main(["sweep", str(model), "KK=0:1:0.5"]) == 2
    assert "did you mean K?" in capsys.readouterr().err


def test_several_files_for_check_and_run(tmp_path, capsys):
    good = tmp_path / "g.amil"
    good.write_text(DECAY)
    bad = tmp_path / "b.amil"
    bad.write_text("X = INTGRL(1.0, -KK*X)\nTIMER FINTIM = 1.0\n")
    assert main(["check", str(good), str(bad), str(good)]) == 1  # the worst of the three
    captured = capsys.readouterr()
    assert captured.out.count(f"{good}: ok") == 2 and f"{bad}:1:18: error" in captured.err
    assert main(["run", str(good), str(good), "--quiet"]) == 0
    assert main(["run", str(good), str(good), "--csv", str(tmp_path / "x.csv")]) == 2


def test_report_of_a_failed_run_is_written_partial_and_exits_3(tmp_path, capsys):
    path = tmp_path / "blow.amil"
    path.write_text("TITLE BLOW-UP\nX = INTGRL(1.0, X*X)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\n"
                    "PRINT X\nEND\n")
    assert main(["report", str(path), "--out", str(tmp_path / "r"), "--format", "md"]) == 3
    md = (tmp_path / "r" / "blow_report.md").read_text()
    assert md.startswith("# BLOW-UP\n\n**PARTIAL REPORT")
    assert "**Partial results: integration failed at TIME = " in md
    assert "the report is marked partial" in capsys.readouterr().err


def test_csv_dialect_on_the_command_line(model, tmp_path):
    csv = tmp_path / "x.csv"
    assert main(["run", str(model), "--csv", str(csv), "--csv-dialect", "excel-pl",
                 "--quiet"]) == 0
    assert csv.read_bytes().decode("utf-8-sig").split("\r\n")[:2] == ["TIME;X", "0,0;1,0"]


# ------------------------------------------------------------ output faults


def test_out_that_is_a_file_exits_4_and_writes_the_rest(model, tmp_path, capsys):
    blocker = tmp_path / "afile"
    blocker.write_text("")
    csv = tmp_path / "ok.csv"
    code = main(["run", str(model), "--out", str(blocker), "--plot", "--csv", str(csv)])
    assert code == 4
    captured = capsys.readouterr()
    assert f"amilpy: cannot write {blocker}: it is not a directory" in captured.err
    assert csv.read_text().startswith("TIME,X")  # the other output is written ...
    assert "1.000000E+00" in captured.out  # ... and the rows are printed
    assert blocker.read_text() == ""


def test_out_dev_null_and_csv_directory_exit_4(model, tmp_path, capsys):
    assert main(["run", str(model), "--out", "/dev/null", "--plot", "--quiet"]) == 4
    assert "cannot write /dev/null: it is not a directory" in capsys.readouterr().err
    folder = tmp_path / "adir"
    folder.mkdir()
    assert main(["run", str(model), "--csv", str(folder), "--quiet"]) == 4
    assert f"cannot write {folder}: it is a directory" in capsys.readouterr().err
    assert folder.is_dir() and not any(folder.iterdir())


def test_a_fifo_at_the_output_path_is_never_replaced(model, tmp_path, capsys):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    assert main(["run", str(model), "--csv", str(fifo), "--quiet"]) == 4
    assert "it is a FIFO, not a regular file" in capsys.readouterr().err
    import stat

    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_a_symbolic_link_is_written_through(model, tmp_path):
    target = tmp_path / "data" / "x.csv"
    target.parent.mkdir()
    target.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    assert main(["run", str(model), "--csv", str(link), "--quiet"]) == 0
    assert link.is_symlink() and target.read_text().startswith("TIME,X")


def test_a_read_only_folder_exits_4(model, tmp_path, capsys):
    import subprocess
    import sys

    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    argv = ["run", str(model), "--csv", str(folder / "x.csv"), "--quiet"]
    if os.geteuid() != 0:
        assert main(argv) == 4
        err = capsys.readouterr().err
    else:  # root writes anywhere: run as nobody, in a folder nobody can read
        import shutil

        if shutil.which("setpriv") is None:
            pytest.skip("running as root without setpriv to drop privileges")
        import tempfile

        # every folder from the system's temporary one down (pytest-xdist adds a
        # level per worker)
        top = os.path.realpath(tempfile.gettempdir())
        for p in (tmp_path, *tmp_path.parents):
            if os.path.realpath(p) == top or p == p.parent:
                break
            p.chmod(p.stat().st_mode | 0o755)
        model.chmod(0o644)
        nobody = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups",
                  sys.executable]
        probe = subprocess.run([*nobody, "-c", "import lark, numpy, scipy, amilpy"],
                               capture_output=True, text=True, timeout=120)
        if probe.returncode != 0:
            # e.g. Python installed under /root (mode 0700): nobody cannot import it
            pytest.skip("an unprivileged user cannot import this Python's packages")
        done = subprocess.run([*nobody, "-m", "amilpy.cli", *argv],
                              capture_output=True, text=True, timeout=120,
                              env=dict(os.environ, MPLBACKEND="Agg"))
        assert done.returncode == 4, done.stderr
        err = done.stderr
    assert f"cannot write {folder / 'x.csv'}: Permission denied" in err


def test_max_time_bounds_reading_checking_and_compiling(tmp_path, capsys):
    # 1400 nested LIMITs: each level is a switch whose surfaces and code are built
    # in order, a few seconds of front end; --max-time 0.1 stops it there (exit 3,
    # like a run stopped by a limit) instead of only once a run has started
    text = "X = INTGRL(0.0, " + "LIMIT(-1.0, 1.0, " * 1400 + "TIME" + ")" * 1400 + ")\n"
    listing = tmp_path / "nested.amil"
    listing.write_text(text + "TIMER FINTIM = 1.0\nEND\n")
    assert main(["run", str(listing), "--max-time", "0.1", "--quiet"]) == 3
    err = capsys.readouterr().err
    assert "reading, checking and compiling the listing took longer than --max-time 0.1 s" \
        in err


def test_a_max_time_past_any_timer_is_no_limit(model, capsys):
    # --max-time 1E308 once overflowed setitimer's time_t (found by the fuzzer)
    assert main(["run", str(model), "--max-time", "1e308", "--quiet"]) == 0


def test_step_point_and_seed_options(model, tmp_path, capsys):
    """--step-point puts a fixed-step method in step-point mode (the header says so),
    is refused with a variable-step one, and --seed makes the random streams a
    function of it alone."""
    assert main(["run", str(model), "--method", "RK4", "--step-point", "--quiet",
                 "--csv", str(tmp_path / "a.csv")]) == 0
    assert main(["run", str(model), "--method", "RK4", "--step-point"]) == 0
    assert "(METHOD RK4, DELT 0.00625, step-point mode)" in capsys.readouterr().out
    assert main(["run", str(model), "--method", "RKS", "--step-point"]) == 2  # usage
    assert "--step-point needs a fixed-step method; --method RKS" in capsys.readouterr().err
    # the listing's own variable-step METHOD: a fault in the listing's run
    auto = tmp_path / "auto.amil"
    auto.write_text(DECAY.replace("PRINT X", "METHOD RKS\nPRINT X"))
    assert main(["run", str(auto), "--step-point"]) == 1
    err = capsys.readouterr().err
    assert "step-point mode needs a fixed-step method" in err and "METHOD RKS" in err
    noisy = tmp_path / "noise.amil"
    noisy.write_text("G = GAUSS(0.0, 1.0)\nTIMER FINTIM = 1.0, OUTDEL = 0.1\nEND\n")
    out = {}
    for seed in ("3", "3", "4"):
        path = tmp_path / f"g{len(out)}.csv"
        assert main(["run", str(noisy), "--seed", seed, "--quiet", "--csv", str(path)]) == 0
        out[len(out)] = path.read_text()
    assert out[0] == out[1] != out[2]


def test_an_interrupt_inside_a_module_import_is_an_interruption(capsys):
    """Ctrl-C while SciPy's compiled modules initialize (imported when a run first
    needs them) comes out of the import as "ImportError: initialization failed" (seen
    in CI, 1.2 s into a farmed run): the command says it was interrupted and exits 3,
    with no traceback; an ImportError with no interrupt behind it is not hidden."""
    import signal

    from amilpy.cli import EXIT_FAILED, _one
    from amilpy.cli.console import Signals

    def interrupted_import(args, path, signals):
        signals.received = signal.SIGINT
        raise ImportError("initialization failed")

    assert _one(interrupted_import, None, "m.amil", Signals()) == EXIT_FAILED
    assert capsys.readouterr().err == "amilpy: m.amil: interrupted\n"

    def broken_import(args, path, signals):
        raise ImportError("initialization failed")

    with pytest.raises(ImportError):
        _one(broken_import, None, "m.amil", Signals())


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_a_device_given_as_the_listing_is_refused(capsys):
    # /dev/zero never ends: it was read until the machine ran out of memory
    assert main(["check", "/dev/zero"]) == 1
    assert capsys.readouterr().err.startswith(
        "/dev/zero: error: longer than 64 MB, which no listing is (a device?)")


def test_control_characters_from_a_listing_are_not_sent_to_the_terminal(tmp_path, capsys):
    # a TITLE carrying ESC sequences (clear the screen, retitle the window) was
    # printed raw; they are shown as "?" in the printout and in messages
    path = tmp_path / "esc.amil"
    path.write_text("TITLE EVIL \x1b[2J\x1b]0;pwned\x07 TITLE\nX = INTGRL(1.0, -X)\n"
                    "TIMER FINTIM = 1.0, OUTDEL = 0.5\nPRINT X\nEND\n")
    assert main(["run", str(path)]) == 0
    out = capsys.readouterr().out
    assert "EVIL ?[2J?]0;pwned? TITLE" in out
    assert not any(c in out for c in "\x1b\x07")
    bad = tmp_path / "bad.amil"
    bad.write_text("X = INTGRL(1.0, -X) \x1b[31m+\nEND\n")
    assert main(["check", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "\x1b" not in err and "?[31m" in err


def test_termt_in_a_macro_body_is_an_error_not_a_traceback(tmp_path, capsys):
    path = tmp_path / "mac.amil"
    path.write_text("MACRO Y = M(X)\nY = X\nTERMT(X .GT. 1.0)\nENDMAC\nA = INTGRL(0.0, 1.0)\n"
                    "B = M(A)\nTIMER FINTIM = 2.0, OUTDEL = 0.5\nPRINT A\nEND\n")
    assert main(["run", str(path)]) == 1
    err = capsys.readouterr().err
    assert "3:1: error: a MACRO body holds assignments only" in err and "Traceback" not in err


# one validating API: the API raises UsageError for a call that cannot be right, the
# command line checks none of it again and maps it to exit 2 (what argparse itself
# reads, a number or one of the methods' names, it refuses as argparse does: exit 2)
USAGE = [
    (lambda m: m.run(KK=1.0), ["run", "--set", "KK=1"], "KK is not a PARAM", None),
    (lambda m: m.run(method="RK9"), ["run", "--method", "RK9"], "unknown integration method",
     "--method: unknown method 'RK9'"),
    (lambda m: m.run(rtol=-1.0), ["run", "--rtol", "-1"], "rtol must be positive",
     "--rtol: must be a positive number"),
    (lambda m: m.sweep("KK", [1.0]), ["sweep", "KK=1:2:1"], "KK is not a PARAM", None),
    (lambda m: m.sweep("K", [1.0], measure="XX"), ["sweep", "K=1:2:1", "--measure", "XX"],
     "XX is not a variable", None),
    (lambda m: m.sweep("K", [1.0], carry_state=True, grid=("K", [1.0])),
     ["sweep", "K=1:2:1", "K=1:2:1", "--carry-state"], "cannot carry the state", None),
    (lambda m: m.periodic(period="1.0", measure="XX"), ["periodic", "--period", "1.0",
                                                        "--measure", "XX"],
     "XX is not a variable", None),
    (lambda m: m.response("KK", 1.0, 2.0, period="1.0"), ["response", "KK=1:2",
                                                          "--period", "1.0"],
     "KK is not a PARAM", None),
]


@pytest.mark.parametrize("call, argv, says, argparse_says", USAGE,
                         ids=[" ".join(u[1][:2]) + " " + u[2][:12] for u in USAGE])
def test_the_api_says_usage_errors_and_the_command_line_maps_them(
        call, argv, says, argparse_says, model, capsys):
    with pytest.raises(amilpy.UsageError, match=says):
        call(amilpy.load(model))
    command, *options = argv
    code = main([command, str(model), *options])
    err = capsys.readouterr().err
    assert code == 2, err
    assert (argparse_says in err) if argparse_says else \
        (f"amilpy: {model}: " in err and says in err), err


def test_every_help_text_prints(capsys):
    """`amilpy --help` and each command's: argparse formats help texts with %, so a
    bare "95 % intervals" in one took the whole --help down with a TypeError."""
    from amilpy.cli import _parser

    parser = _parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    for argv in (["--help"], *([c, "--help"] for c in commands)):
        assert main(argv) == 0, argv
    assert "95 % intervals" in capsys.readouterr().out
