"""Reference for fst/legumes_water_stress.fst and fst/maize_water_stress.fst
(model-library-pps/WaterStress--PureStand-Intercrops_archive, EUPL-1.2), and the
synthetic CABO weather files they read from tests/listings/weather/.

Both listings are FST form with TRANSLATION_GENERAL DRIVER='EUDRIV': step-point mode
(contract section 14), time t_k = STTIME + k*DELT, DELT = 1 d, states advanced by Euler,
every quantity evaluated at the step points only. Transcribed (legumes / maize):

    Fabs = AFGEN(FabsTB, TIME);  OBSWT = AFGEN(OBSWTB, TIME)   (end values outside)
    AVRAD = RDD*1E-6;  Iabs = (1 - RHO)*0.5*AVRAD*Fabs         (MJ PAR m-2 d-1)
    GROWTHpot = RUE*Iabs*10;  GROWTH = RATIOActPot*GROWTHpot    (kg DM ha-1 d-1)
    SOILvolroot = 10*10*Rdepth;  WSOILmin = SOILvolroot*WiltingP; WSOILmax = ...*FieldCap
    Wcritical = WSOILmin + (1 - P)*(WSOILmax - WSOILmin)
    RATIOActPot = INSW(WSOIL - Wcritical, (WSOIL - WSOILmin)/(Wcritical - WSOILmin), 1)
    RTRANSPpot = GROWTHpot/10*TRANSPC;  RTRANSPact = RATIOActPot*RTRANSPpot
    WSOILexp = WSOIL + (RAIN - RTRANSPact)*DELT;  Rperc = MAX(0, WSOILexp - WSOILmax)
    WTOT' = GROWTH;  WSOIL' = RAIN - RTRANSPact - Rperc
    Wrain' = RAIN;  Wtransp' = RTRANSPact;  Wperc' = Rperc  (maize also IABStot' = Iabs)
    BALANCE = (WSOIL - WSOILI) - (Wrain - Wtransp - Wperc)     (zero to round-off)

The legumes listing runs TIMER STTIME=1, FINTIM=275 with WEATHER CNTR='TZ', ISTN=2,
IYEAR=2018 (file TZ2.018); the maize listing STTIME=1, FINTIM=177 with IYEAR=2019
(TZ2.019; its TIMER line is the one commented "Maize 2018" while its tables and weather
year are 2019's: the listing is run as written). The weather day is floor(TIME).

The weather files are not real data: cabo_text() writes them from a formula (smooth
seasonal radiation and temperatures, rain pulses early and late in the year) so that the
run exercises both branches of the INSW (stress) and of the MAX (percolation). The files
in tests/listings/weather/ are exactly cabo_text(2018) and cabo_text(2019).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

WEATHER_DIR = Path(__file__).resolve().parent.parent / "weather"
STATION = ("TZ", 2)
LONG, LAT, ELEV, ANG_A, ANG_B = 35.75, -6.17, 1120.0, 0.25, 0.50

LISTINGS = {
    "legumes": dict(
        RUE=0.543, RHO=0.07, TRANSPC=0.3, P=0.65, RDEPTH=20.0, FIELDCAP=0.21,
        WILTINGP=0.13, WTOTI=0.1, WSOILI=420.0, STTIME=1.0, FINTIM=275.0, DELT=1.0,
        YEAR=2018,
        FABSTB=(1., 0.001, 30., 0.073, 64., 0.242, 85., 0.480, 114., 0.768, 142., 0.783,
                177., 0.680, 205., 0.518, 240., 0.331, 275., 0.092),
        OBSWTB=(1., 0., 30., 295., 64., 656., 85., 1599., 114., 1903., 142., 2294.,
                177., 4203., 205., 4364., 240., 3606., 275., 3135.)),
    "maize": dict(
        RUE=1.435, RHO=0.07, TRANSPC=0.2, P=0.8, RDEPTH=6.0, FIELDCAP=0.21,
        WILTINGP=0.13, WTOTI=0.1, WSOILI=126.0, STTIME=1.0, FINTIM=177.0, DELT=1.0,
        YEAR=2019,
        FABSTB=(1., 0.001, 27., 0.106, 55., 0.349, 83., 0.623, 120., 0.490, 153., 0.388),
        OBSWTB=(1., 0., 27., 368., 55., 906., 83., 2896., 120., 5378., 153., 5671.),
        LAITB=(1., 0.1, 27., 1.198, 55., 2.349, 83., 1.993, 120., 1.183, 135., 0.,
               153., 0.),
        KATB=(0., 0.031, 27., 0.139, 55., 0.247, 83., 0.467, 153., 0.467)),
}


def _weather_row(year: int, day: int) -> tuple[float, ...]:
    """One synthetic day: radiation kJ m-2 d-1, tmin, tmax (C), vp kPa, wind m/s, rain mm."""
    phase = 2.0 * math.pi * (day - 30 - (year - 2018) * 11) / 365.0
    rad = round(17000.0 + 5000.0 * math.sin(phase))
    tmin = round(16.0 + 3.0 * math.sin(phase), 1)
    tmax = round(tmin + 11.0 + 2.0 * math.cos(phase), 1)
    vp = round(1.5 + 0.3 * math.sin(phase), 2)
    wind = round(2.0 + 0.5 * math.cos(phase), 1)
    period = 5 if year == 2018 else 4
    wet = day <= 70 or day >= 300
    rain = round(12.0 + (day % 7), 1) if wet and day % period == 1 else 0.0
    return (rad, tmin, tmax, vp, wind, rain)


def cabo_text(year: int) -> str:
    """The CABO-format weather file TZ2.<yyy> for a year (synthetic; see the docstring)."""
    days = 366 if year % 4 == 0 and (year % 100 != 0 or year % 400 == 0) else 365
    lines = [
        "*-----------------------------------------------------------",
        f"* Station: {STATION[0]} {STATION[1]}, year {year}. SYNTHETIC weather written by",
        "* tests/listings/references/water_stress.py (cabo_text); not observations.",
        "* Columns: station year day  radiation (kJ m-2 d-1)  min temp (C)",
        "*          max temp (C)  vapour pressure (kPa)  wind (m s-1)  rain (mm d-1)",
        "*-----------------------------------------------------------",
        f"{LONG:8.2f} {LAT:8.2f} {ELEV:8.1f} {ANG_A:6.2f} {ANG_B:6.2f}",
    ]
    for day in range(1, days + 1):
        rad, tmin, tmax, vp, wind, rain = _weather_row(year, day)
        lines.append(f"{STATION[1]:3d} {year:5d} {day:4d} {rad:8.0f} {tmin:6.1f} "
                     f"{tmax:6.1f} {vp:6.2f} {wind:5.1f} {rain:6.1f}")
    return "\n".join(lines) + "\n"


def weather_path(year: int) -> Path:
    return WEATHER_DIR / f"{STATION[0]}{STATION[1]}.{year % 1000:03d}"


def read_cabo(path: Path) -> dict[int, dict[str, float]]:
    """Rows of a CABO file by day: RDD (J, = kJ*1000), TMMN, TMMX, VP, WN, RAIN."""
    rows: dict[int, dict[str, float]] = {}
    header_seen = False
    for line in path.read_text().splitlines():
        if not line.strip() or line.lstrip().startswith("*"):
            continue
        if not header_seen:
            header_seen = True
            continue
        f = line.split()
        rows[int(f[2])] = {"RDD": float(f[3]) * 1000.0, "TMMN": float(f[4]),
                           "TMMX": float(f[5]), "VP": float(f[6]), "WN": float(f[7]),
                           "RAIN": float(f[8])}
    return rows


def afgen(table: tuple[float, ...], x: float) -> float:
    """CSMP AFGEN: linear interpolation, end values outside the table."""
    xs, ys = table[0::2], table[1::2]
    return float(np.interp(x, xs, ys))


def run(name: str) -> dict[str, NDArray[np.float64]]:
    """The Euler step-point recurrence of one listing; one row per day (PRDEL = DELT = 1)."""
    c = LISTINGS[name]
    weather = read_cabo(weather_path(c["YEAR"]))
    delt = c["DELT"]
    n = int(round((c["FINTIM"] - c["STTIME"]) / delt))
    if (c["FINTIM"] - c["STTIME"]) - n * delt > 0.01 * delt:
        n += 1
    soilvol = 10.0 * 10.0 * c["RDEPTH"]
    wmin, wmax = soilvol * c["WILTINGP"], soilvol * c["FIELDCAP"]
    wcrit = wmin + (1.0 - c["P"]) * (wmax - wmin)
    s = {"WTOT": c["WTOTI"], "WSOIL": c["WSOILI"], "WRAIN": 0.0, "WTRANSP": 0.0,
         "WPERC": 0.0, "IABSTOT": 0.0}
    rows: dict[str, list[float]] = {}
    for k in range(n + 1):
        t = c["STTIME"] + k * delt
        w = weather[int(math.floor(t))]
        avrad = w["RDD"] * 1e-6
        fabs = afgen(c["FABSTB"], t)
        iabs = (1.0 - c["RHO"]) * 0.5 * avrad * fabs
        gpot = c["RUE"] * iabs * 10.0
        ratio = ((s["WSOIL"] - wmin) / (wcrit - wmin)) if s["WSOIL"] - wcrit < 0 else 1.0
        growth = ratio * gpot
        tr_act = ratio * (gpot / 10.0) * c["TRANSPC"]
        perc = max(0.0, s["WSOIL"] + (w["RAIN"] - tr_act) * delt - wmax)
        rates = {"WTOT": growth, "WSOIL": w["RAIN"] - tr_act - perc, "WRAIN": w["RAIN"],
                 "WTRANSP": tr_act, "WPERC": perc, "IABSTOT": iabs}
        row = dict(s) | {
            "TIME": t, "FABS": fabs, "AVRAD": avrad, "IABS": iabs, "IABS0": 0.5 * avrad * fabs,
            "GROWTH": growth, "RATIOACTPOT": ratio, "RTRANSPACT": tr_act, "RPERC": perc,
            "WSOILMIN": wmin, "WSOILMAX": wmax, "RAIN": w["RAIN"],
            "OBSWT": afgen(c["OBSWTB"], t),
            "BALANCE": (s["WSOIL"] - c["WSOILI"]) - (s["WRAIN"] - s["WTRANSP"] - s["WPERC"]),
        }
        if "LAITB" in c:
            row["LAI"] = afgen(c["LAITB"], t)
            row["KA"] = afgen(c["KATB"], t)
        for key, v in row.items():
            rows.setdefault(key, []).append(v)
        if k == n:
            break
        s = {key: s[key] + delt * rates[key] for key in s}
    return {key: np.array(v) for key, v in rows.items()}
