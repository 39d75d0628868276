"""CABO weather files for FST's WEATHER statement (contract §13): file names, the
search order, the units, the year's end and the errors. Checked against the
synthetic files of tests/listings/weather, whose values the reference generator
(tests/listings/references/water_stress.py) computes independently."""

import os
from pathlib import Path

import numpy as np
import pytest

from amilpy.diagnostics import AmilError
from amilpy.library.weather import Weather, WeatherSpec, file_name, read_cabo

HERE = os.path.dirname(os.path.abspath(__file__))
WEATHER = os.path.join(HERE, "listings", "weather")

CABO = """* a comment line
*  and another
   5.18   52.0    7.0   -0.18   -0.55
  1  1990    1    2800   -2.1    4.2   0.65   3.1   0.4
  1  1990    2    -99    -1.0    5.0   0.70   2.0   1.2
  1  1990  365    3000    1.0    6.0   0.70   2.0   0.0
"""


def _spec(**kw):
    base = dict(country="TZ", station=2, year=2018)
    base.update(kw)
    return WeatherSpec(**base)


def test_file_names_take_the_last_three_digits_of_the_year():
    assert file_name("NLD", 1, 1990) == "NLD1.990"
    assert file_name("TZ", 2, 2018) == "TZ2.018"
    assert file_name("NLD", 1, 2005) == "NLD1.005"


def test_values_match_the_reference_reader_with_rdd_in_joules():
    # the reference reads the same file its own way (RDD = kJ * 1000)
    from listings.references.water_stress import read_cabo as reference

    rows = reference(Path(WEATHER, "TZ2.018"))
    w = Weather(_spec(wtrdir=WEATHER), listing_dir="/nonexistent")
    for day in (1, 57, 180, 365):
        for name in ("RDD", "TMMN", "TMMX", "VP", "WN", "RAIN"):
            # any TIME within the day gives the day's value
            assert w.value(name, day + 0.75) == rows[day][name]
    assert w.value("LAT", 3.0) == -6.17 and w.value("ELEV", 3.0) == 1120.0
    assert w.value("DOY", 57.9) == 57.0 and w.value("YEAR", 57.9) == 2018.0
    assert np.array_equal(w.values("TMMX", np.array([1.0, 1.5, 2.0])),
                          [rows[1]["TMMX"], rows[1]["TMMX"], rows[2]["TMMX"]])


def test_after_the_last_day_the_next_year_file_is_read():
    # 2018 has 365 days: TIME 366 is 1 January 2019, in TZ2.019
    from listings.references.water_stress import read_cabo as reference

    rows19 = reference(Path(WEATHER, "TZ2.019"))
    w = Weather(_spec(wtrdir=WEATHER), listing_dir="/nonexistent")
    assert w.locate(366.2) == (2019, 1)
    assert w.value("RAIN", 366.2) == rows19[1]["RAIN"]
    assert w.value("YEAR", 366.2) == 2019.0 and w.value("DOY", 366.2) == 1.0
    assert sorted(w.years) == [2019]  # 2018's file was not needed, so not read


def test_search_order_any_case_and_a_windows_wtrdir(tmp_path):
    # the listing's own weather/ folder holds the file, in lower case; WTRDIR is a
    # Windows path that does not exist here (as in the published FST listings)
    (tmp_path / "weather").mkdir()
    (tmp_path / "weather" / "nld1.990").write_text(CABO)
    w = Weather(WeatherSpec("NLD", 1, 1990, wtrdir="C:\\SYS\\WEATHER\\"), str(tmp_path))
    assert w.value("RDD", 1.0) == 2800e3 and w.value("LONG", 1.0) == 5.18
    # a file in WTRDIR comes first
    first = tmp_path / "first"
    first.mkdir()
    (first / "NLD1.990").write_text(CABO.replace("2800", "1234"))
    w = Weather(WeatherSpec("NLD", 1, 1990, wtrdir=str(first)), str(tmp_path))
    assert w.value("RDD", 1.0) == 1234e3


def test_a_missing_value_that_is_used_names_file_day_and_variable(tmp_path):
    (tmp_path / "NLD1.990").write_text(CABO)
    w = Weather(WeatherSpec("NLD", 1, 1990), str(tmp_path))
    assert w.value("TMMN", 2.5) == -1.0  # the same day's other values are fine
    with pytest.raises(AmilError, match=r"NLD1\.990 has -99 \(missing\) for RDD on day 2 "
                                        r"of 1990 \(TIME = 2\.5\)"):
        w.value("RDD", 2.5)
    with pytest.raises(AmilError, match="has no line for RAIN on day 3 of 1990"):
        w.value("RAIN", 3.0)


def test_a_missing_file_says_where_it_looked_and_which_lines_use_weather(tmp_path):
    from amilpy.diagnostics import Span

    w = Weather(WeatherSpec("NLD", 1, 1990, wtrdir="C:\\SYS\\WEATHER\\", span=Span(12, 1)),
                str(tmp_path), extra_dirs=["/opt/wx"], used_at=[Span(30, 5), Span(41, 9)])
    with pytest.raises(AmilError) as err:
        w.value("TMMX", 100.0)
    d = err.value.diagnostics[0]
    assert "the weather file NLD1.990 (station NLD 1, 1990) is not in /SYS/WEATHER/" \
        in d.message
    assert str(tmp_path) in d.message and "/opt/wx" in d.message
    assert d.span.line == 12 and "line(s) 30, 41" in d.hint and "--weather-dir" in d.hint


def test_lines_of_codes_station_minus_999_are_not_days(tmp_path):
    # (NL1.989, LINGRA's weather, has a line of how-obtained codes, station -999,
    # before some days: here one before day 1 and one after it, which must not
    # replace the day's values, and one for a day with no line of its own)
    codes = "-999  1990    {day}      1     1     1       3     1     3\n"
    text = CABO.replace("  1  1990    1 ", codes.format(day=1) + "  1  1990    1 ", 1)
    text = text.replace("  1  1990    2 ", codes.format(day=1) + "  1  1990    2 ", 1)
    (tmp_path / "NLD1.990").write_text(text + codes.format(day=3))
    w = Weather(WeatherSpec("NLD", 1, 1990), str(tmp_path))
    assert [w.value(n, 1.0) for n in ("RDD", "TMMN", "RAIN")] == [2.8e6, -2.1, 0.4]
    with pytest.raises(AmilError, match="has no line for RAIN on day 3 of 1990"):
        w.value("RAIN", 3.0)


def test_a_malformed_line_is_named(tmp_path):
    (tmp_path / "NLD1.990").write_text(CABO.replace("0.65", "O.65"))
    with pytest.raises(AmilError, match=r"NLD1\.990:4: not a CABO weather line"):
        read_cabo(str(tmp_path / "NLD1.990"))


@pytest.mark.parametrize("old, new", [("2800", "nan"), ("2800", "inf"),
                                      ("    1    2800", "  inf    2800"), ("-0.18", "NaN")])
def test_a_value_that_is_not_a_number_is_named_not_a_traceback(tmp_path, old, new):
    # Python's float() reads "nan" and "inf": a NaN day ran on as "no weather" and an
    # infinite day number was an OverflowError; -99 is how a CABO file marks a gap
    (tmp_path / "NLD1.990").write_text(CABO.replace(old, new, 1))
    with pytest.raises(AmilError, match=r"NLD1\.990:[34]: field \d+ is not a finite number, "
                                        r"which a CABO weather file holds: write -99"):
        read_cabo(str(tmp_path / "NLD1.990"))


def test_a_weather_file_that_is_no_weather_is_not_quoted(tmp_path):
    """A weather file linked to /proc/self/environ printed the start of the process's
    environment in its error (the bad line was quoted). Errors now name the line and
    the field, never the text."""
    secret = "AMILPY_SECRET_TOKEN=hunter2"
    (tmp_path / "NLD1.990").write_text(CABO.replace("2800", secret, 1))
    with pytest.raises(AmilError, match=r"NLD1\.990:\d+: not a CABO weather line: field \d+ "
                                        r"is not a number") as err:
        read_cabo(str(tmp_path / "NLD1.990"))
    assert "hunter2" not in str(err.value) and "SECRET" not in str(err.value)
    if os.path.exists("/proc/self/environ"):
        os.symlink("/proc/self/environ", tmp_path / "NLD2.990")
        with pytest.raises(AmilError) as err:
            read_cabo(str(tmp_path / "NLD2.990"))
        assert "PATH=" not in str(err.value) and "HOME=" not in str(err.value)
