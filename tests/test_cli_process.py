"""The command line as a process: signals, a closed pipe, a full disk, a console
that cannot show every character, a display with no GUI. Each runs `amilpy` in a
real subprocess, since these are things only a process meets."""

import importlib.util
import os
import resource
import signal
import subprocess
import sys
import time

import pytest

ENV = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
AMILPY = [sys.executable, "-m", "amilpy.cli"]

LONG = """TITLE A LONG RUN
X = INTGRL(0.0, COS(TIME))
TIMER FINTIM = 5000.0, OUTDEL = 0.05, PRDEL = 0.05
METHOD RKS
PRINT X
OUTPUT X
END
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT],
                         ids=["SIGTERM", "SIGHUP", "SIGINT"])
def test_signal_keeps_the_rows_writes_the_files_and_exits_3(tmp_path, sig):
    listing = tmp_path / "long.amil"
    listing.write_text(LONG)
    csv = tmp_path / "long.csv"
    proc = subprocess.Popen([*AMILPY, "run", str(listing), "--csv", str(csv), "--show-python"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    proc.stdout.readline()  # the generated code is printed just before the run starts
    time.sleep(2.0)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    assert "interrupted at TIME = " in err and "Traceback" not in err
    assert "*** PARTIAL RESULTS: interrupted at TIME = " in out
    rows = csv.read_text().splitlines()
    assert rows[0].startswith("# PARTIAL (run 1): interrupted at TIME = ")
    t_stop = float(rows[0].rsplit("= ", 1)[1])
    assert rows[1] == "TIME,X"
    # every OUTDEL row up to the interruption is kept
    times = [float(r.split(",")[0]) for r in rows[2:]]
    # (TIME is printed to 10 digits: the last row, 872.9000000000001, was "after" 872.9)
    assert t_stop - 0.05 < times[-1] <= t_stop * (1.0 + 1e-9)
    assert times == pytest.approx([0.05 * k for k in range(len(times))])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["long.amil", "long.csv"]


def test_a_closed_pipe_still_writes_the_files(tmp_path):
    """`amilpy run m.amil --csv out.csv --plot | head` exited 0 with no CSV and no
    PNG; the files are written before the printout now, and the exit code is the
    run's (0), with no complaint about the pipe."""
    listing = tmp_path / "m.amil"
    listing.write_text("TITLE A LONG PRINTOUT\nX = INTGRL(1.0, -X)\n"
                       "TIMER FINTIM = 100.0, OUTDEL = 0.001, PRDEL = 0.001\nPRINT X\n"
                       "OUTPUT X\nEND\n")
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader has gone before the first line, as `head` may have
    try:
        done = subprocess.run([*AMILPY, "run", str(listing), "--csv",
                               str(tmp_path / "out.csv"), "--plot"], stdout=write_end,
                              stderr=subprocess.PIPE, text=True, env=ENV, cwd=tmp_path,
                              timeout=120)
    finally:
        os.close(write_end)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert (tmp_path / "out.csv").read_text().count("\n") == 100_002
    assert (tmp_path / "m.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("flag, name", [
    ("--csv", "x.csv"),
    # (XlsxWriter writes a zip through a temporary of its own: issue 30 found a
    # traceback there)
    pytest.param("--xlsx", "x.xlsx", marks=pytest.mark.skipif(
        importlib.util.find_spec("xlsxwriter") is None, reason="XlsxWriter not installed"))])
def test_a_full_disk_exits_4_names_the_file_and_leaves_no_temporary(tmp_path, flag, name):
    listing = tmp_path / "m.amil"
    listing.write_text("X = INTGRL(1.0, -X)\nTIMER FINTIM = 10.0, OUTDEL = 0.01\nPRINT X\n"
                       "END\n")
    out = tmp_path / "out"
    out.mkdir()

    def small_files():  # a disk that is full after 4 kB, for this process only
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

    done = subprocess.run([*AMILPY, "run", str(listing), flag, str(out / name)],
                          preexec_fn=small_files, capture_output=True, text=True, env=ENV,
                          timeout=120)
    assert done.returncode == 4, done.stderr
    assert (f"amilpy: cannot write {out / name}: the file is larger than this process "
            "may write") in done.stderr
    assert "Traceback" not in done.stderr
    assert list(out.iterdir()) == []  # no half file, no hidden temporary
    assert " 1.000000E+01" in done.stdout.splitlines()[-1]  # the rows computed are printed


def test_a_console_that_cannot_show_every_character(tmp_path):
    """PYTHONIOENCODING=cp1252 (a Windows console): ę and ω have no place in it.
    They print as "?" instead of ending the run with a UnicodeEncodeError, and the
    CSV is written."""
    listing = tmp_path / "napęd.amil"
    listing.write_text("TITLE Napęd — prędkość kątowa ω\nX = INTGRL(1.0, -X)\n"
                       "TIMER FINTIM = 1.0, OUTDEL = 0.5\nPRINT X\nEND\n", encoding="utf-8")
    env = dict(ENV, PYTHONIOENCODING="cp1252")
    done = subprocess.run([*AMILPY, "run", str(listing), "--csv", str(tmp_path / "x.csv")],
                          capture_output=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr.decode("cp1252")
    out = done.stdout.decode("cp1252")
    assert out.startswith("Nap?d — pr?dko?? k?towa ?\n")
    assert (tmp_path / "x.csv").read_text().startswith("TIME,X")


def test_no_matplotlib_warning_with_a_display_but_no_gui(tmp_path):
    listing = tmp_path / "m.amil"
    listing.write_text("X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nOUTPUT X\nEND\n")
    env = {k: v for k, v in ENV.items() if k != "MPLBACKEND"}
    env["DISPLAY"] = ":99"  # no X server there
    done = subprocess.run([*AMILPY, "run", str(listing), "--plot", "--quiet"],
                          capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert (tmp_path / "m.png").exists()


SMALL = "X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, OUTDEL = 0.1\nPRINT X\nEND\n"


@pytest.mark.parametrize("closed", ["stdout", "stderr"])
def test_a_closed_standard_stream_still_writes_the_files(tmp_path, closed):
    """`amilpy run m.amil --csv out.csv >&-` gave a traceback ('NoneType' object has
    no attribute 'write'), and with stderr closed nothing was written at all: the
    stream that is closed writes nowhere, the CSV is written whole, exit 0."""
    (tmp_path / "m.amil").write_text(SMALL)
    fd = 1 if closed == "stdout" else 2
    done = subprocess.run(["/bin/sh", "-c", f'"$@" {fd}>&-', "sh", *AMILPY, "run", "m.amil",
                           "--csv", "out.csv"], cwd=tmp_path, env=ENV, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stdout + done.stderr
    assert (tmp_path / "out.csv").read_text().count("\n") == 12  # header + 11 rows


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_full_standard_output_is_said_and_exits_4(tmp_path):
    (tmp_path / "m.amil").write_text(SMALL)
    with open("/dev/full", "w") as full:
        done = subprocess.run([*AMILPY, "run", "m.amil", "--csv", "out.csv"], cwd=tmp_path,
                              env=ENV, stdout=full, stderr=subprocess.PIPE, text=True,
                              timeout=120)
    assert done.returncode == 4
    assert done.stderr == ("amilpy: cannot write the printout to standard output: No space "
                           "left on device\n")
    assert (tmp_path / "out.csv").read_text().count("\n") == 12


def test_csv_to_standard_output_goes_where_the_shell_sends_it(tmp_path):
    """`amilpy run m.amil --csv /dev/stdout > all.txt` renamed a temporary onto
    all.txt, which the printout (written through the shell's descriptor) then missed:
    the CSV is written through that descriptor too, before the printout."""
    (tmp_path / "m.amil").write_text(SMALL)
    done = subprocess.run(["/bin/sh", "-c", '"$@" > all.txt', "sh", *AMILPY, "run",
                           "m.amil", "--csv", "/dev/stdout"], cwd=tmp_path, env=ENV,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    lines = (tmp_path / "all.txt").read_text().splitlines()
    assert lines[:2] == ["TIME,X", "0.0,1.0"] and len(lines) > 13
    assert any(line.startswith("RUN ") for line in lines[12:])  # the printout after it


def test_a_dangling_link_at_an_output_path_makes_no_folders(tmp_path):
    (tmp_path / "m.amil").write_text(SMALL)
    (tmp_path / "out.csv").symlink_to(tmp_path / "nowhere" / "deeper" / "x.csv")
    done = subprocess.run([*AMILPY, "run", "m.amil", "--csv", "out.csv", "--quiet"],
                          cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=120)
    assert done.returncode == 4
    assert "it is a symbolic link to" in done.stderr and "whose folder does not exist" in \
        done.stderr
    assert not (tmp_path / "nowhere").exists()
