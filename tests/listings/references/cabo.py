"""A CABO weather file as the hand translations of the FST listings read it (TTUTIL's
format, from its documentation, never from amilpy). Comment lines start with '*'; the
first other line is the station's: longitude, latitude, elevation, A, B; then a line a
day: station, year, day, irradiation (kJ m-2 d-1), minimum and maximum temperature (C),
vapour pressure (kPa), wind (m s-1), rain (mm d-1). A line of station -999 holds codes
for how a day's values were obtained, and is no day."""

from __future__ import annotations

import os


def read_cabo(path: str | os.PathLike) -> tuple[tuple[float, ...], dict[int, dict]]:
    """(the station line's five numbers, {day: RDD (J m-2 d-1, = kJ*1000), TMMN, TMMX, VP,
    WN, RAIN})."""
    header: tuple[float, ...] | None = None
    days: dict[int, dict] = {}
    with open(path) as f:
        for line in f:
            s = line.strip()
            if not s or s.startswith("*"):
                continue
            fields = s.split()
            if header is None:
                header = tuple(float(v) for v in fields[:5])
                continue
            if int(float(fields[0])) == -999:
                continue
            irr, tmn, tmx, vp, wn, rain = (float(v) for v in fields[3:9])
            days[int(fields[2])] = dict(RDD=irr * 1000.0, TMMN=tmn, TMMX=tmx, VP=vp, WN=wn,
                                        RAIN=rain)
    assert header is not None, f"{path}: no station line"
    return header, days
