"""The output grid: the OUTDEL and PRDEL instants, one row per instant, and how many
rows a run may have.

The reference is exact arithmetic: the instants k*OUTDEL and j*PRDEL as fractions,
merged as a set. The grid's own instants are the floats t0 + k*step, which round
within 1e-12 (SAME_INSTANT) of the exact ones; an instant of both grids is one row.
"""

from __future__ import annotations

import tracemalloc
from fractions import Fraction

import numpy as np
import pytest

from amilpy import cli
from amilpy.diagnostics import AmilError
from amilpy.run.plan import make_grid, timer_values


def exact_grid(t0: str, fintim: str, outdel: str, prdel: str, extra=()):
    """(instant, on OUTDEL, on PRDEL) in order, from exact fractions: each grid's
    instants t0 + k*step up to FINTIM, and FINTIM itself on both."""
    a, b = Fraction(t0), Fraction(fintim)

    def grid(step: str) -> set[Fraction]:
        d = Fraction(step)
        return {a + k * d for k in range(int((b - a) / d) + 1)} | {b}

    o, p = grid(outdel), grid(prdel)
    e = {Fraction(x) for x in extra if a < Fraction(x) < b}
    return [(float(t), t in o, t in p) for t in sorted(o | p | e)]


@pytest.mark.parametrize("t0, fintim, outdel, prdel, extra", [
    ("0", "5", "0.001", "0.05", ()),           # the hoist's: PRDEL on every 50th row
    ("0", "1", "0.03", "0.1", ()),             # PRDEL instants between OUTDEL ones
    ("0", "1", "0.1", "0.03", ()),             # and the other way round
    ("0.3", "10", "0.07", "0.07", ("0.5", "3.333", "9.99", "42")),  # one grid, extras
    ("0", "0.5", "0.125", "0.1", ("0.25", "0.2", "0.3")),  # extras on grid instants
    ("2", "7.5", "0.25", "1", ()),             # FINTIM - t0 not a multiple of PRDEL
])
def test_the_grid_is_the_union_of_the_two_grids_one_row_an_instant(t0, fintim, outdel,
                                                                    prdel, extra):
    grid = make_grid(float(t0), float(fintim), float(outdel), float(prdel),
                     tuple(float(x) for x in extra))
    want = exact_grid(t0, fintim, outdel, prdel, extra)
    assert len(grid.times) == len(want)
    # (t0 + k*step rounds within a few ulps of the exact instant)
    np.testing.assert_allclose(grid.times, [w[0] for w in want], rtol=1e-13, atol=1e-13)
    assert grid.outdel.tolist() == [w[1] for w in want]
    assert grid.prdel.tolist() == [w[2] for w in want]
    assert np.all(np.diff(grid.times) > 0)


def test_the_grid_of_a_long_run_takes_its_own_ten_bytes_an_instant():
    """A million OUTDEL instants and 18,000 PRDEL ones between them: the grid holds
    8 bytes an instant and two 1-byte masks; making it took 95 bytes an instant at
    its peak (the union and membership tests of two written-out grids), which is what
    a streamed run of 1E7 rows would have needed (950 MB) before its first step."""
    tracemalloc.start()
    try:
        grid = make_grid(0.0, 1000.0, 1e-3, 0.05 + 1e-4)  # (PRDEL's own instants)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    rows = len(grid.times)
    # PRDEL = 0.0501: j*PRDEL is an OUTDEL instant where j is a multiple of 10
    assert rows == 1_000_001 + sum(1 for j in range(1, int(1000 / 0.0501) + 1) if j % 10)
    assert peak / rows < 13.0  # 10 held; a part of 65,536 being written out, 2 MB


GRIDS = [(0.0, 10.0, 1e-3, 0.05, ()),  # the hoist's
         (0.0, 10.0, 1e-3, 0.0037, (0.5, 1.23456, 3.0001)),  # PRDEL's own, extras
         (-2.0, 3.0, 0.1, 0.1, (0.05,)),
         (0.3, 9.9, 0.07, 0.07, ())]  # FINTIM no instant of OUTDEL's


@pytest.mark.parametrize("t0, fintim, outdel, prdel, extra", GRIDS)
def test_a_grid_made_as_it_is_read_is_the_written_one_bit_for_bit(monkeypatch, t0, fintim,
                                                                 outdel, prdel, extra):
    """A grid over LAZY_FROM instants (a streamed run's) is made as the run reads it:
    by index, window and searchsorted it answers what the written-out array does,
    exactly (the rows' instants are these numbers)."""
    from amilpy.run import plan

    written = make_grid(t0, fintim, outdel, prdel, extra)
    monkeypatch.setattr(plan, "LAZY_FROM", 0)
    grid = make_grid(t0, fintim, outdel, prdel, extra)
    lazy, want = grid.times, written.times
    assert isinstance(lazy, plan.GridTimes) and len(lazy) == len(want)
    assert np.array_equal(np.asarray(lazy), want)
    assert np.array_equal(grid.outdel, written.outdel)
    assert np.array_equal(grid.prdel, written.prdel)
    n = len(want)
    assert [lazy[i] for i in range(n)] == want.tolist()  # (in order, a block at a time)
    assert lazy[-1] == want[-1] and lazy[n // 3] == want[n // 3]
    probes = np.concatenate([want, np.nextafter(want, np.inf), np.nextafter(want, -np.inf),
                             [t0 - 1.0, fintim + 1.0],
                             np.random.default_rng(0).uniform(t0 - 1, fintim + 1, 200)])
    for lo, hi in [(0, n), (7, n - 3), (n // 2, n), (5, 5 + plan.GridTimes.BLOCK + 10),
                   (3, 40)]:
        view = lazy[lo:hi]
        assert np.array_equal(np.asarray(view), want[lo:hi])
        for side in ("left", "right"):
            assert np.array_equal(view.searchsorted(probes, side),
                                  want[lo:hi].searchsorted(probes, side))
            assert view.searchsorted(float(probes[5]), side) == \
                want[lo:hi].searchsorted(probes[5], side)
    with pytest.raises(IndexError):
        lazy[n]


def test_a_streamed_runs_grid_holds_no_instants():
    """1E7 OUTDEL instants and PRDEL's on every 50th: made, the grid holds its PRDEL
    mask (a byte an instant) and nothing of its instants; written out they took 80 MB."""
    tracemalloc.start()
    try:
        grid = make_grid(0.0, 10_000.0, 1e-3, 0.05)
        held, peak = tracemalloc.get_traced_memory()
        assert grid.times[9_999_999] == 9999.999 and grid.times[-1] == 10_000.0
        assert grid.times.searchsorted(5000.0) == 5_000_000
    finally:
        tracemalloc.stop()
    assert len(grid.times) == 10_000_001
    # (held: the mask, 10 MB; at the peak also PRDEL's 200,001 instants matched to
    # OUTDEL's, four candidates each: 21 MB measured)
    assert held < 12e6 and peak < 30e6


def model_with(fintim: float, outdel: float, prdel: float | None = None):
    import amilpy

    timer = f"FINTIM = {fintim!r}, OUTDEL = {outdel!r}" + \
        (f", PRDEL = {prdel!r}" if prdel is not None else "")
    return amilpy.loads(f"X = INTGRL(0.0, 1.0)\nTIMER {timer}\nPRINT X\nEND\n")


def spec_with(fintim: float, outdel: float, prdel: float | None = None):
    return model_with(fintim, outdel, prdel).ir.runs[0]


def test_rows_past_the_limit_are_refused_with_the_way_to_have_them():
    """2E6 rows a run keeps in memory; a run writing its OUTDEL rows to its CSV as it
    goes holds only their instants and may have 2E7; PRDEL's rows are kept either
    way (the printout), so their limit stays."""
    spec = spec_with(10_000.0, 1e-3, 1.0)  # 1E7 OUTDEL rows
    with pytest.raises(AmilError) as exc:
        timer_values(spec)
    text = exc.value.render()
    assert "FINTIM/OUTDEL = 1e+07 output rows (limit 2000000)" in text
    assert "--csv FILE" in text and "stream_csv" in text
    assert timer_values(spec, streamed=True)["OUTDEL"] == 1e-3
    with pytest.raises(AmilError, match="FINTIM/OUTDEL = 3e.07 output rows .limit 20000000"):
        timer_values(spec_with(30_000.0, 1e-3, 1.0), streamed=True)
    with pytest.raises(AmilError, match="FINTIM/PRDEL = 1e.07 output rows .limit 2000000"):
        timer_values(spec_with(10_000.0, 1e-3, 1e-3), streamed=True)


def test_a_run_kept_whole_is_refused_at_the_rows_memory_may_keep_whatever_its_length():
    """3E7 rows without --csv: the limit said is 2E6 (not the streamed one), from
    Model.run as from timer_values."""
    with pytest.raises(AmilError) as exc:
        model_with(30.0, 1e-6, 0.5).run()
    assert "(limit 2000000)" in exc.value.render()


def test_a_listing_without_prdel_is_told_to_write_one_to_stream():
    """PRDEL defaults to OUTDEL, and PRDEL's rows are kept for the printout: such a
    run is refused in OUTDEL's name, told to write a coarser PRDEL and stream; streamed
    as it is, told to write a PRDEL."""
    spec = spec_with(3.0, 1e-6)
    with pytest.raises(AmilError) as exc:
        timer_values(spec)
    text = exc.value.render()
    assert "FINTIM/OUTDEL = 3e+06 output rows (limit 2000000)" in text
    assert "write a coarser PRDEL" in text and "--csv FILE" in text
    with pytest.raises(AmilError) as exc:
        timer_values(spec, streamed=True)
    text = exc.value.render()
    assert "FINTIM/PRDEL = 3e+06 output rows (limit 2000000)" in text
    assert "write a coarser PRDEL" in text and "--csv" not in text


def test_one_grid_counts_its_rows_once():
    """OUTDEL = PRDEL (or PRDEL not written): one grid, FINTIM/OUTDEL + 1 rows, so
    a run of 1.2E6 rows is kept whole, not streamed."""
    assert model_with(1.2, 1e-6).most_rows() == pytest.approx(1_200_001)
    assert model_with(1.2, 1e-6, 1e-6).most_rows() == pytest.approx(1_200_001)
    assert model_with(1.0, 1e-6, 0.5).most_rows() == pytest.approx(1_000_001 + 3)


def test_the_command_streams_a_run_of_more_rows_than_memory_may_keep(tmp_path, capsys):
    """`amilpy run --csv` with 3E7 rows: refused before the run, saying the limit
    (nothing written); 1E7 rows without --csv: refused, saying --csv has them."""
    path = tmp_path / "ramp.amil"
    path.write_text("X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0, OUTDEL = 1.0E-4, PRDEL = 0.5\n"
                    "PRINT X\nEND\n")
    code = cli.main(["run", str(path), "--fintim", "3000", "--csv", str(tmp_path / "x.csv"),
                     "--quiet"])
    err = capsys.readouterr().err
    assert code == 1 and "3e+07 output rows (limit 20000000)" in err
    assert not (tmp_path / "x.csv").exists() and list(tmp_path.iterdir()) == [path]
    code = cli.main(["run", str(path), "--fintim", "1000", "--quiet"])
    err = capsys.readouterr().err
    assert code == 1 and "1e+07 output rows (limit 2000000)" in err and "--csv FILE" in err


def test_events_share_their_branch_values_and_keep_minus_zero():
    """Events hold one float object per branch value (a long run keeps 10^5 of them);
    -0.0 stays -0.0 after a 0.0 (a QNTZR level), other kinds of number as given."""
    import math

    from amilpy.result import Event, EventKind

    a = Event(1.0, "FSW", 0, float("-1"), float("1"))
    b = Event(2.0, "FSW", 0, float("1"), float("-1"))
    assert a.new is b.old and a.old is b.new
    zero = Event(3.0, "QNTZR", 1, 0.0, 1.0, EventKind.LEVEL)
    minus = Event(4.0, "QNTZR", 1, -0.0, 1.0, EventKind.LEVEL)
    assert math.copysign(1.0, zero.old) == 1.0 and math.copysign(1.0, minus.old) == -1.0
    assert Event(5.0, "FSW", 0, 1, -1).old == 1 and type(Event(5.0, "FSW", 0, 1, -1).old) is int


def test_a_grid_finer_than_time_can_tell_apart_is_refused():
    """Instants within 1E-12 of TIME of each other are one instant (the grid's own
    rounding): OUTDEL 1E-3 from TIME = 1E9 (a late STTIME, a run continued) would give
    rows that fall together, which the union of the grids merged silently, taking
    some for others. Refused, with what to write."""
    with pytest.raises(AmilError) as exc:
        make_grid(1e9, 1e9 + 1.5, 1e-3, 1.5e-3)
    text = exc.value.render()
    assert "OUTDEL = 0.001 is below what TIME can tell apart at TIME = 1e+09" in text
    assert "write OUTDEL = 1 or more, or start TIME nearer 0" in text
    with pytest.raises(AmilError, match="PRDEL = 1e-07 is below"):
        make_grid(1e5, 1e5 + 1.0, 0.5, 1e-7)
    assert len(make_grid(1e6, 1e6 + 1.0, 1e-3, 0.5).times) == 1001  # (1E-9 of TIME apart)
