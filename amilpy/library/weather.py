"""Daily weather from CABO-format files, for FST listings' WEATHER statement (§13).

    WEATHER WTRDIR = 'C:\\SYS\\WEATHER\\'; CNTR = 'NLD'; ISTN = 1; IYEAR = 1990

makes the day's RDD (J m-2 d-1: the file's kJ times 1000), TMMN, TMMX, VP, WN,
RAIN, the station's LONG, LAT, ELEV, and DOY and YEAR available as names. The
day is floor(TIME); after day 365 (366 in a leap year) the run goes on in the
next year's file. The file of a year is CNTR + ISTN + '.' + the year's last three
digits (NLD1.990), in any case, looked for in WTRDIR (backslashes read as
folder separators, a drive letter dropped), the listing's folder, its weather/
and ../weather/ folders, and any folders given (`--weather-dir`).

A CABO file: lines starting with `*` are comments; the first other line is the
station's LONG LAT ELEV A B (the Angstrom coefficients A and B are read and not
used); then one row a day, `station year day radiation tmin tmax vp wind rain`.
-99 marks a missing value: one that a run uses is an error naming the file, the
day and the variable. Files are read when a value of their year is first asked
for, so a listing that names no weather variable reads nothing.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

from ..diagnostics import AmilError, Diagnostic, Span
from ..language import plain_float

# the daily columns of a CABO row after station, year and day, as the listing names them
DAILY = ("RDD", "TMMN", "TMMX", "VP", "WN", "RAIN")
STATION = ("LONG", "LAT", "ELEV")
CALENDAR = ("DOY", "YEAR")
NAMES = DAILY + STATION + CALENDAR  # every name a WEATHER statement defines
MISSING = -99.0
SCALE = {"RDD": 1000.0}  # kJ in the file, J in the model


@dataclass(frozen=True)
class WeatherSpec:
    """What a WEATHER statement (or several, FST splits them) asks for."""

    country: str
    station: int
    year: int
    wtrdir: str | None = None
    span: Span | None = None  # the statement, for errors

    @property
    def what(self) -> str:
        """The station and year as a run's label says them."""
        return f"WEATHER {self.country} {self.station} {self.year}"


@dataclass
class WeatherYear:
    """One CABO file: the station's position and the daily rows by day of year."""

    path: str
    long: float
    lat: float
    elev: float
    days: dict[int, tuple[float, ...]] = field(default_factory=dict)  # day -> DAILY values
    lines: dict[int, int] = field(default_factory=dict)  # day -> line in the file


CYCLE_DAYS = 146_097  # the days of 400 years of the Gregorian calendar


def days_in(year: int) -> int:
    return 366 if year % 4 == 0 and (year % 100 != 0 or year % 400 == 0) else 365


def file_name(country: str, station: int, year: int) -> str:
    """NLD1.990: country, station, '.', the last three digits of the year."""
    return f"{country}{station}.{year % 1000:03d}"


def search_dirs(spec: WeatherSpec, listing_dir: str, extra: list[str] | None = None
                ) -> list[str]:
    """Where the files are looked for, in order (§13)."""
    dirs = []
    if spec.wtrdir and spec.wtrdir.strip():  # (Rlintul's LINTUL1 gives WTRDIR = ' ')
        d = spec.wtrdir.strip().replace("\\", "/")
        if len(d) >= 2 and d[1] == ":":  # a Windows drive letter means nothing here
            d = d[2:]
        dirs.append(d)
    dirs += [listing_dir, os.path.join(listing_dir, "weather"),
             os.path.join(listing_dir, os.pardir, "weather")]
    dirs += list(extra or [])
    return dirs


def find_file(name: str, dirs: list[str]) -> str | None:
    """The file `name` in the first folder that has it, matched in any case."""
    want = name.lower()
    for d in dirs:
        try:
            entries = os.listdir(d or ".")
        except OSError:
            continue
        for entry in sorted(entries):
            if entry.lower() == want and os.path.isfile(os.path.join(d, entry)):
                return os.path.join(d, entry)
    return None


def read_cabo(path: str) -> WeatherYear:
    """Parse one CABO file; a malformed line is an error naming the file and line."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            text = fh.read()
    except OSError as exc:
        raise AmilError(f"cannot read the weather file {path}: {exc.strerror or exc}") from None
    year: WeatherYear | None = None
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields or fields[0].startswith("*"):
            continue
        try:
            values = [float(f) for f in fields]
        except ValueError:
            # (the field's place, never its text: a "weather file" may be a link to
            # something that is no business of an error message, /proc/self/environ)
            k = next(k for k, f in enumerate(fields, start=1) if plain_float(f) is None)
            raise AmilError(f"{path}:{number}: not a CABO weather line: field {k} is not "
                            "a number (a line holds the station, the year, the day and "
                            "the day's values)") from None
        bad = next((f for f, v in zip(fields, values, strict=True) if not math.isfinite(v)),
                   None)
        if bad is not None:  # (Python reads "nan" and "inf" as numbers; a CABO file has none)
            k = fields.index(bad) + 1
            raise AmilError(f"{path}:{number}: field {k} is not a finite number, which a "
                            "CABO weather file holds: write -99 for a missing value")
        if year is None:
            if len(values) < 3:
                raise AmilError(f"{path}:{number}: the station line needs LONG LAT ELEV "
                                f"(A B), found {len(values)} numbers")
            year = WeatherYear(path, values[0], values[1], values[2])
            continue
        if values[0] == -999.0:
            # (a line of codes, station -999: how each value of the day was obtained,
            # measured or estimated; NL1.989 has one before its day 43 and others)
            continue
        if len(values) < 3 + len(DAILY):
            raise AmilError(f"{path}:{number}: a day needs station, year, day and "
                            f"{len(DAILY)} values, found {len(values)} numbers")
        day = int(values[2])
        year.days[day] = tuple(values[3:3 + len(DAILY)])
        year.lines[day] = number
    if year is None:
        raise AmilError(f"the weather file {path} has no station line and no days")
    return year


class Weather:
    """The weather of one run: values by name and TIME, files read as needed."""

    def __init__(self, spec: WeatherSpec, listing_dir: str, extra_dirs: list[str] | None = None,
                 used_at: list[Span] | None = None) -> None:
        self.spec = spec
        self.dirs = search_dirs(spec, listing_dir, extra_dirs)
        self.used_at = used_at or []  # the lines that use weather, for a missing file
        self.years: dict[int, WeatherYear] = {}

    def _year(self, year: int) -> WeatherYear:
        if year not in self.years:
            name = file_name(self.spec.country, self.spec.station, year)
            path = find_file(name, self.dirs)
            if path is None:
                where = ", ".join(d or "." for d in dict.fromkeys(self.dirs))
                uses = ", ".join(str(n) for n in sorted({s.line for s in self.used_at})[:8])
                raise AmilError([Diagnostic(
                    f"the weather file {name} (station {self.spec.country} "
                    f"{self.spec.station}, {year}) is not in {where}",
                    self.spec.span,
                    "put the file in one of those folders or give --weather-dir"
                    + (f"; weather is used on line(s) {uses}" if uses else ""))])
            self.years[year] = read_cabo(path)
        return self.years[year]

    def locate(self, t: float) -> tuple[int, int]:
        """(year, day of year) of TIME t: day floor(t) of IYEAR, running on into the
        following years."""
        if not math.isfinite(t):
            raise AmilError(f"no weather at TIME = {t}")
        year, day = self.spec.year, int(math.floor(t))
        # whole 400-year cycles of the calendar at once (a TIME of 1E15 days would
        # take 3E12 turns of the loops below)
        cycles = (day - 1) // CYCLE_DAYS
        year, day = year + 400 * cycles, day - CYCLE_DAYS * cycles
        while day > days_in(year):
            day -= days_in(year)
            year += 1
        while day < 1:
            year -= 1
            day += days_in(year)
        return year, day

    def value(self, name: str, t: float) -> float:
        """The weather variable `name` at TIME t."""
        value, missing = self.lookup(name, t)
        if missing:
            raise AmilError(missing)
        return value

    def lookup(self, name: str, t: float) -> tuple[float, str | None]:
        """(value, None), or (NaN, what is missing: the file, day and variable) where
        the file has no value; a file that is not there is an error at once."""
        year, day = self.locate(t)
        if name == "DOY":
            return float(day), None
        if name == "YEAR":
            return float(year), None
        data = self._year(year)
        if name in STATION:
            return (data.long, data.lat, data.elev)[STATION.index(name)], None
        row = data.days.get(day)
        k = DAILY.index(name)
        if row is None or row[k] == MISSING:
            what = "has no line for" if row is None else "has -99 (missing) for"
            return math.nan, (f"the weather file {data.path} {what} {name} on day {day} "
                              f"of {year} (TIME = {t:g})")
        return row[k] * SCALE.get(name, 1.0), None

    def tables(self, names: list[str], t0: float, t1: float, sure: float | None = None
               ) -> dict[str, object]:
        """A `runtime.DayTable` per name over the days of [t0, t1], and one more. The
        days after `sure` may not be read (a step-point run's last step may pass
        FINTIM, or not): a file missing for them is said only if one is read (LINGRA
        runs to day 365 of 1989 and has no file for 1990)."""
        from .runtime import DayTable

        first, last = math.floor(t0), math.floor(t1) + 1
        out = {}
        for name in names:
            values, missing = [], {}
            for day in range(first, last + 1):
                try:
                    value, problem = self.lookup(name, float(day))
                except AmilError as exc:
                    if sure is None or day <= math.floor(sure):
                        raise
                    value, problem = math.nan, exc.diagnostics[0].message
                values.append(value)
                if problem:
                    missing[day] = problem
            out[name] = DayTable(first, tuple(values), missing)
        return out

    def values(self, name: str, ts):
        """`value` at every instant of ts (a NumPy array)."""
        import numpy as np

        return np.array([self.value(name, float(t)) for t in np.asarray(ts, float)])
