"""CABO weather files read in a few lines, apart from amilpy.library.weather: the tests'
recurrences take the day's values from here."""

from __future__ import annotations

from pathlib import Path


def days(path: Path) -> dict[int, list[float]]:
    """day -> [radiation kJ m-2 d-1, tmin, tmax, vapour pressure, wind, rain]."""
    rows = {}
    for line in Path(path).read_text().splitlines():
        f = line.split()
        if len(f) >= 9 and not f[0].startswith("*"):
            rows[int(f[2])] = [float(x) for x in f[3:9]]
    return rows


def station(path: Path) -> list[float]:
    """The station line: [longitude, latitude, elevation, A, B]."""
    for line in Path(path).read_text().splitlines():
        if line.strip() and not line.startswith("*"):
            return [float(x) for x in line.split()]
    raise ValueError(f"{path}: no station line")
