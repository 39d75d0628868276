"""Default tolerances: how far each route's printout is from a tight reference at a
ladder of RELERR, on every listing amilpy ships or runs, and what a tighter default costs.

    OPENBLAS_NUM_THREADS=1 python benchmarks/tolerances.py            # everything
    python benchmarks/tolerances.py --quick                           # a smoke run
    python benchmarks/tolerances.py --listings spring dcm --routes AUTO RKS

Listings (`--listings` picks by name):

* CSMP form: the six shipped models (`models/*.amil`) and `models/examples/
  csmp_diode_filter.amil`;
* ACSL form: `models/examples/oral_dosing.csl` and the published ACSL listings of
  `tests/listings/SOURCES.md` present in `tests/listings/acsl/` (a missing copy is
  listed and skipped); `minmod4` runs RK4 as written (IALG 5), so its equations are
  also measured with METHOD AUTO forced (`minmod4@auto`);
* FST form: `models/examples/fst_wheat.fst` and the two published water-stress
  listings run FST's Euler driver (EUDRIV, fixed step): their rows do not depend on
  RELERR, which is checked (two tolerances, rows equal bit for bit). No FST listing found
  uses the Runge-Kutta driver, so two are measured with `DRIVER = 'RKDRIV'` written in
  (`fst_wheat@rkdriv`, `legumes@rkdriv`: amilpy's RKS, the daily weather a step
  function of TIME).

Error (the metric of every table):

    max over the OUTDEL rows and over the variables of |y - y_ref| / max|y_ref|

the variables being the states and the PRINT variables (every state when there is no
PRINT), less a printed non-state variable that stays below 1e-8 of the largest state (a
balance check at round-off, e.g. the water-stress listings' BALANCE: its digits are
noise); a variable whose reference is 0 throughout is left out. References:

* the shipped models: the states against `cases.py`'s exact references (matrix
  exponentials between located switches; the two nonlinear ones DOP853 at rtol 1e-13,
  checked against Radau);
* `csmp_diode_filter`: the SciPy restatement of `tests/test_examples.py` (the diode
  current by brentq to round-off, DOP853 at 1e-13): amilpy's IMPL stops at the
  listing's own P = 1E-10, so amilpy cannot be its own reference there;
* `lapatinib_md`: the exact superposition of single-dose responses
  (`tests/listings/references/lapatinib_md.py`), amilpy's DOP853 at 1e-13 as its check;
* every other listing: amilpy itself at its tightest, RADAU at RELERR 1e-13 (DOP853 when
  Radau does not finish in a minute), checked against the other of the two and, for the
  published listings, against the independent restatement of
  `tests/listings/references` (rtol 1e-10, 1e-11 or exact).

Both agreements are printed: an error below them is not resolved.

Routes AUTO, RKS, DOP853, STIFF (Radau), BDF (its own tolerance a decade tighter, as
`routes.py` sets it), LSODA. AUTO at RELERR 1e-6, 1e-7, ... 1e-12; the other routes at
1e-6, 1e-8, 1e-10, 1e-12 (a coarser ladder: CPU time); ABSERR = RELERR x 1e-3 (the
ratio of today's defaults; `--atol-ratio`); the ratio's effect on AUTO is a table of its
own (ABSERR = RELERR x 1, x 1e-3, x 1e-6 at RELERR 1e-8 and 1e-10). Wall time: the
median of `--repeats` runs (one when a run takes over 0.3 s), the model compiled
beforehand; a route whose run takes over `--slow` seconds (2) is not tightened further
on that listing, and no measured run may take over 10 s (amilpy's max_time).

The bouncing ball: an ACSL program (SCHEDULE .XN. on the height, a DISCRETE that
reverses the velocity with restitution E), impact instants against the closed form of
its flight parabolas, every route, every RELERR. The flights are polynomials of degree
2, which every Runge-Kutta route integrates exactly: their impact-time error is the
event location's alone; LSODA/BDF/AUTO start each flight at order 1 and carry a
trajectory error too.

Output: tables on stdout and in `--out` (default `benchmarks/results/tolerances.md`).
Nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
for p in (str(HERE), str(ROOT), str(ROOT / "tests")):
    if p not in sys.path:
        sys.path.insert(0, p)

ROUTES = ["AUTO", "RKS", "DOP853", "STIFF", "BDF", "LSODA"]
TOLS = [10.0**-k for k in range(6, 13)]  # AUTO's ladder
OTHER_TOLS = [1e-6, 1e-8, 1e-10, 1e-12]  # the other routes' (coarse: CPU time)
ATOL_RATIO = 1e-3  # ABSERR = RELERR x this (today's 1e-6 / 1e-9)
GOAL = 5e-7  # every digit of %.6E: half a unit in the 7th significant digit
REF_RTOL = 1e-13
SLOW = 2.0  # seconds: a route's run taking longer is not tightened further
MAX_TIME = 10.0  # wall-clock cap of one measured run (amilpy's max_time)
REF_MAX_TIME = 30.0  # and of a reference run
ROUNDOFF = 1e-8  # a printed non-state variable below this x the largest state: round-off
LISTINGS = ROOT / "tests" / "listings"


# ------------------------------------------------------------------ the listings

@dataclass
class Listing:
    name: str
    form: str  # CSMP, ACSL, FST
    text: str
    source: str  # where it is (for the tables)
    case: str | None = None  # cases.py reference (shipped models)
    independent: Callable[[], dict] | None = None  # restatement, keyed "T"/"TIME" + names
    reference_is_independent: bool = False  # the restatement is the reference itself
    check: str | None = "DOP853"  # amilpy's tight run checked against the reference
    method: str | None = None  # forced method for the ladder (variants)
    fixed: bool = False  # runs a fixed-step method as written: RELERR does not apply
    weather: tuple[str, ...] = ()
    note: str = ""
    state_events: bool = False  # crossings of states located (event-location dependent)


def _read(path: Path) -> str:
    return path.read_text(encoding="utf-8", errors="replace")


def _spring_ref() -> dict:
    from listings.references import spring

    ref = spring.run()
    ref["TIME_"] = ref.pop("TIME")  # the listing's own `time` state (time is T)
    return ref


def _lapatinib_ref() -> dict:
    from listings.references import lapatinib_md

    t = lapatinib_md.output_times()
    exact = lapatinib_md.superposition(t)
    return {"T": t} | {n: exact[:, i] for i, n in enumerate(lapatinib_md.STATES)}


def _oral_dosing_ref() -> dict:
    """models/examples/oral_dosing.csl: one Bateman curve per dose (doses 0, 12, ... 72)."""
    dose, ka, ke, vd = 500.0, 1.2, 0.173, 42.0
    t = 0.5 * np.arange(145)
    ag = np.zeros_like(t)
    ab = np.zeros_like(t)
    for k in range(7):
        s = t - 12.0 * k
        on = s >= -1e-12
        s = np.clip(s, 0.0, None)
        ag += np.where(on, dose * np.exp(-ka * s), 0.0)
        ab += np.where(on, dose * ka / (ka - ke) * (np.exp(-ke * s) - np.exp(-ka * s)), 0.0)
    return {"T": t, "AG": ag, "CP": ab / vd}


def _diode_ref() -> dict:
    """models/examples/csmp_diode_filter.amil written for SciPy (tests/test_examples.py):
    V' = -I/C with I the root of R I + VT ln(1 + I/IS) = V by brentq to round-off, the
    two FILT2 macros' four lags; DOP853 at rtol 1e-13. amilpy's IMPL stops at
    |FI - I| <= P = 1E-10 (the listing's), so amilpy cannot be its own reference here."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    c, r, vt, i_s = 1e-3, 100.0, 0.02585, 1e-12

    def current(v: float) -> float:
        if v <= 0.0:
            return 0.0
        return brentq(lambda i: r * i + vt * math.log1p(i / i_s) - v, 0.0, v / r,
                      xtol=1e-18, rtol=8.9e-16)

    def rhs(t, y):
        v, a1, a2, b1, b2 = y
        i = current(v)
        return [-i / c, (i - a1) / 0.01, (a1 - a2) / 0.01, (v - b1) / 0.05, (b1 - b2) / 0.05]

    t = 0.002 * np.arange(251)
    sol = solve_ivp(rhs, (0.0, 0.5), [5.0, 0, 0, 0, 0], t_eval=t, rtol=1e-13, atol=1e-16,
                    method="DOP853")
    v, _, if2, _, vf2 = sol.y
    i = np.array([current(x) for x in v])
    return {"TIME": t, "V": v, "I": i, "VD": vt * np.log1p(i / i_s), "IF2": if2, "VF2": vf2}


def _module_ref(module: str, attr: str = "run") -> Callable[[], dict]:
    def ref():
        import importlib

        return getattr(importlib.import_module(f"listings.references.{module}"), attr)()
    return ref


PUBLISHED_ACSL = [
    # file, independent reference, note
    ("isolated_liver.csl", _module_ref("isolated_liver"), "A1 Magnolia PBPK"),
    ("flow_limited_fat.csl", _module_ref("flow_limited_fat"), "A2 Magnolia PBPK"),
    ("gefitinib.csl", _module_ref("gefitinib"), "A3 Magnolia PBPK"),
    ("dcm.csl", _module_ref("dcm"), "A4 Magnolia PBPK"),
    ("perc.csl", _module_ref("perc"), "A5 Magnolia PBPK"),
    ("perc_cc.csl", _module_ref("perc_cc"), "A6 Magnolia PBPK"),
    ("lapatinib_md.csl", _lapatinib_ref, "A7 Magnolia PBPK"),
    ("diazepam.csl", _module_ref("diazepam"), "A8 Magnolia PBPK"),
    ("warfarin.csl", _module_ref("warfarin"), "A9 Magnolia PBPK"),
    ("spring.csl", _spring_ref, "A10 ACSL manual's spring"),
]


def all_listings() -> tuple[list[Listing], list[str]]:
    """Every listing measured, and the published copies that are absent."""
    out: list[Listing] = []
    absent: list[str] = []
    for name in ("ex4_elastic", "ex4_clutch", "ex4_torque_meter", "hoist_backlash",
                 "crank_slider_startup", "machine_unit"):
        path = ROOT / "models" / f"{name}.amil"
        out.append(Listing(name, "CSMP", _read(path), f"models/{name}.amil", case=name,
                           state_events=True, note="shipped"))
    ex = ROOT / "models" / "examples"
    out.append(Listing("csmp_diode_filter", "CSMP", _read(ex / "csmp_diode_filter.amil"),
                       "models/examples/csmp_diode_filter.amil", independent=_diode_ref,
                       reference_is_independent=True, check=None,
                       note="example (IMPL with P = 1E-10, MACRO)"))
    out.append(Listing("oral_dosing", "ACSL", _read(ex / "oral_dosing.csl"),
                       "models/examples/oral_dosing.csl", independent=_oral_dosing_ref,
                       note="example (INTERVAL doses)"))
    for file, ref, note in PUBLISHED_ACSL:
        path = LISTINGS / "acsl" / file
        if not path.exists():
            absent.append(f"acsl/{file}")
            continue
        out.append(Listing(file[:-4], "ACSL", _read(path), f"tests/listings/acsl/{file}",
                           independent=ref, note=note,
                           # the exact superposition: DOP853 and Radau at 1e-13 are 4e-9
                           # and slow on this stiff system
                           reference_is_independent=file == "lapatinib_md.csl"))
    path = LISTINGS / "acsl" / "minmod4.csl"
    if path.exists():
        text = _read(path)
        out.append(Listing("minmod4", "ACSL", text, "tests/listings/acsl/minmod4.csl",
                           fixed=True, note="A11, IALG 5 (RK4) as written"))
        out.append(Listing("minmod4@auto", "ACSL", text, "tests/listings/acsl/minmod4.csl",
                           independent=_module_ref("minmod4"), method="AUTO",
                           note="A11's equations, METHOD AUTO forced (MAXT 0.005 kept)"))
    else:
        absent.append("acsl/minmod4.csl")
    wheat = _read(ex / "fst_wheat.fst")
    weather_ex = (str(ex / "weather"),)
    out.append(Listing("fst_wheat", "FST", wheat, "models/examples/fst_wheat.fst",
                       fixed=True, weather=weather_ex, note="example, EUDRIV"))
    out.append(Listing("fst_wheat@rkdriv", "FST", wheat.replace("'EUDRIV'", "'RKDRIV'"),
                       "models/examples/fst_wheat.fst", weather=weather_ex,
                       note="DRIVER = 'RKDRIV' written in"))
    weather_pub = (str(LISTINGS / "weather"),)
    for file, short in (("legumes_water_stress.fst", "legumes"),
                        ("maize_water_stress.fst", "maize")):
        path = LISTINGS / "fst" / file
        if not path.exists():
            absent.append(f"fst/{file}")
            continue
        text = _read(path)
        out.append(Listing(short, "FST", text, f"tests/listings/fst/{file}", fixed=True,
                           weather=weather_pub, note="F1/F2, EUDRIV"))
        if short == "legumes":
            out.append(Listing("legumes@rkdriv", "FST", text.replace("'EUDRIV'", "'RKDRIV'"),
                               f"tests/listings/fst/{file}", weather=weather_pub,
                               note="DRIVER = 'RKDRIV' written in"))
    for file in ("sucros1.fst", "lintul2.fst", "molly3.csl"):
        form = "fst" if file.endswith(".fst") else "acsl"
        if not (LISTINGS / form / file).exists():
            absent.append(f"{form}/{file}")
    return out, absent


# ------------------------------------------------------------------ running

@dataclass
class Result:
    route: str
    rtol: float
    atol: float
    error: float
    worst: str
    seconds: float
    nfev: int
    status: str
    events: int


@dataclass
class Measured:
    listing: Listing
    reference: str = ""
    agreement: float = math.nan  # reference against its check (same metric)
    independent: float = math.nan  # reference against the restatement
    variables: list[str] = field(default_factory=list)
    event_kinds: dict[str, int] = field(default_factory=dict)
    results: list[Result] = field(default_factory=list)
    ratio: list[Result] = field(default_factory=list)  # ABSERR ratio, AUTO
    fixed_equal: bool | None = None
    fixed_note: str = ""
    scales: dict[str, float] = field(default_factory=dict)
    dropped: list[str] = field(default_factory=list)  # printed values at round-off
    check: str = ""


def _model(listing: Listing):
    import amilpy

    return amilpy.loads(listing.text, f"{listing.name}.{listing.form.lower()}")


def _run(model, listing: Listing, method, rtol, atol, max_time=MAX_TIME):
    kw = {"advice": False, "max_time": max_time}
    if listing.weather:
        kw["weather_dir"] = list(listing.weather)
    runs = model.run(method=method, rtol=rtol, atol=atol, **kw)
    return runs[0]


def _timed(model, listing, method, rtol, atol, repeats):
    times, run = [], None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        run = _run(model, listing, method, rtol, atol)
        times.append(time.perf_counter() - t0)
        if times[-1] > 0.3:
            break
    return run, statistics.median(times)


def _matched(t_run: np.ndarray, t_ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices (i_run, i_ref) of the instants both have (to 1e-9 of the span)."""
    span = max(float(t_ref[-1] - t_ref[0]), 1e-300)
    j = np.clip(np.searchsorted(t_run, t_ref - 1e-9 * span), 0, len(t_run) - 1)
    ok = np.abs(t_run[j] - t_ref) <= 1e-9 * span
    return j[ok], np.flatnonzero(ok)


def global_error(t, values: Callable[[str], np.ndarray], t_ref, ref: dict,
                 names: list[str], partial: bool = False) -> tuple[float, str]:
    """max over the common rows and the variables of |y - y_ref| / max|y_ref|
    (`partial`: over the rows both have, however few, else inf below 90 %)."""
    t = np.asarray(t, float)
    t_ref = np.asarray(t_ref, float)
    i, k = _matched(t, t_ref)
    if not partial and len(k) < 0.9 * len(t_ref) or len(k) == 0:
        return math.inf, "stopped early"
    worst, where = 0.0, ""
    for n in names:
        r = np.asarray(ref[n], float)[k]
        scale = float(np.max(np.abs(r))) if r.size else 0.0
        if not scale > 0.0 or not np.isfinite(scale):
            continue
        y = np.asarray(values(n), float)[i]
        e = float(np.max(np.abs(y - r))) / scale
        if not np.isfinite(e):
            return math.inf, n
        if e > worst:
            worst, where = e, n
    return worst, where


def _names(model, run) -> list[str]:
    states = [s.name for s in model.ir.states if not s.hidden]
    printed = [n for rep in getattr(model.ir.runs[0], "reports", ()) if rep.kind == "PRINT"
               for n in rep.names]
    names = list(dict.fromkeys(states + printed))
    return [n for n in names if n in run.values]


def measure(listing: Listing, routes, tols, other_tols, repeats: int, slow: float,
            atol_ratio: float, ratio_tols, log) -> Measured:
    m = Measured(listing)
    model = _model(listing)
    warm = _run(model, listing, listing.method, None, None)  # compile; the default run
    if listing.fixed:
        a = _run(model, listing, None, 1e-3, 1e-6)
        b = _run(model, listing, None, 1e-12, 1e-15)
        m.fixed_equal = all(np.array_equal(a.values[n], b.values[n], equal_nan=True)
                            for n in a.values) and np.array_equal(a.times, b.times)
        m.fixed_note = f"{warm.method} ({warm.settings or 'DELT'}): rows at RELERR 1e-3 and " \
                       f"1e-12 {'equal bit for bit' if m.fixed_equal else 'DIFFER'}"
        log(f"  {listing.name}: {m.fixed_note}")
        return m
    for ev in warm.events:
        m.event_kinds[str(ev.kind)] = m.event_kinds.get(str(ev.kind), 0) + 1
    if listing.case:
        from cases import all_cases

        case = all_cases()[listing.case]
        grid, ref = case.ref()
        t_ref, names = grid, list(case.states)
        agreement, _ = case.agreement()
        m.reference = case.reference_method
        m.check = case.check_method or "-"
        m.agreement = agreement
        m.scales = {n: float(np.max(np.abs(ref[n]))) for n in names}
    elif listing.reference_is_independent:
        ref = {k.upper(): v for k, v in listing.independent().items()}
        tkey = "T" if "T" in ref else "TIME"
        t_ref = ref[tkey]
        names = [n for n in ref if n != tkey]
        m.reference = "the independent restatement"
        if listing.check:
            m.check = f"amilpy {listing.check} {REF_RTOL:g}"
            chk = _run(model, listing, listing.check, REF_RTOL, REF_RTOL * 1e-3,
                       REF_MAX_TIME)
            m.agreement, _ = global_error(chk.t, chk.__getitem__, t_ref, ref, names)
        m.scales = {n: float(np.max(np.abs(ref[n]))) for n in names}
    else:
        # DOP853 at 1e-13 (RADAU when it does not finish in REF_MAX_TIME), checked
        # against the independent restatement where there is one, else against the other
        first, second = "DOP853", "RADAU"
        rref = _run(model, listing, first, REF_RTOL, REF_RTOL * 1e-3, REF_MAX_TIME)
        if str(rref.status) == "failed":
            log(f"  {listing.name}: {first} at {REF_RTOL:g} failed ({rref.message})")
            first, second = second, first
            rref = _run(model, listing, first, REF_RTOL, REF_RTOL * 1e-3, REF_MAX_TIME)
        names = _names(model, rref)
        states = {s.name for s in model.ir.states}
        top = max((float(np.max(np.abs(rref[n]))) for n in names if n in states),
                  default=0.0)
        m.dropped = [n for n in names if n not in states
                     and float(np.max(np.abs(rref[n]))) < ROUNDOFF * top]
        names = [n for n in names if n not in m.dropped]
        t_ref = rref.t
        ref = {n: rref[n] for n in names}
        m.reference = f"amilpy {first}, RELERR {REF_RTOL:g}"
        if listing.independent is not None:
            ind = {k.upper(): v for k, v in listing.independent().items()}
            tkey = "T" if "T" in ind else "TIME"
            common = [n for n in ind if n not in ("T", "TIME") and n in rref.values]
            m.independent, _ = global_error(rref.t, rref.__getitem__, ind[tkey], ind, common)
        else:
            chk = _run(model, listing, second, REF_RTOL, REF_RTOL * 1e-3, REF_MAX_TIME)
            m.check = f"{second} {REF_RTOL:g}"
            partial = str(chk.status) == "failed"
            if partial:
                m.check += f" (to TIME {chk.t[-1]:.4g} in {REF_MAX_TIME:g} s)"
            m.agreement, _ = global_error(chk.t, chk.__getitem__, t_ref, ref, names,
                                          partial=partial)
        m.scales = {n: float(np.max(np.abs(ref[n]))) for n in names}
    m.variables = names
    log(f"  {listing.name}: reference {m.reference}; agreement {m.agreement:.1e}, "
        f"independent {m.independent:.1e}; {len(names)} variables; events {m.event_kinds}")

    def point(route, rtol, atol):
        method = listing.method if route == "AUTO" and listing.method else route
        try:
            run, sec = _timed(model, listing, method, rtol, atol, repeats)
        except Exception as exc:  # noqa: BLE001
            return Result(route, rtol, atol, math.inf, f"raised {type(exc).__name__}",
                          math.nan, 0, "raised", 0)
        err, where = global_error(run.t, run.__getitem__, t_ref, ref, names)
        if str(run.status) == "failed":
            err = math.inf
        return Result(route, rtol, atol, err, where, sec, int(run.stats.get("nfev", 0)),
                      str(run.status), len(run.events))

    for route in routes:
        for rtol in (tols if route == "AUTO" else other_tols):
            res = point(route, rtol, rtol * atol_ratio)
            m.results.append(res)
            log(f"    {route:7s} {rtol:.0e}: {res.error:.2e} ({res.worst}) "
                f"{res.seconds * 1e3:.1f} ms nfev {res.nfev} {res.status}")
            if not res.seconds <= slow:  # slow or failed: no tighter rung
                break
    if "AUTO" in routes:
        for rtol in ratio_tols:
            for ratio in (1.0, 1e-6):
                m.ratio.append(point("AUTO", rtol, rtol * ratio))
    return m


# ------------------------------------------------------------------ bouncing ball

BALL_G, BALL_E, BALL_H0, BALL_TSTOP = 9.81, 0.8, 10.0, 10.0
BALL = f"""PROGRAM bouncing ball
  CONSTANT G = {BALL_G}, E = {BALL_E}, H0 = {BALL_H0}, TSTOP = {BALL_TSTOP}
  CINTERVAL CINT = 0.05
  DERIVATIVE
    V = INTEG(-G, 0.0)
    H = INTEG(V, H0)
    SCHEDULE BOUNCE .XN. H        ! H from > 0 to <= 0: an impact, located
    TERMT(T >= TSTOP, 'time limit')
  END
  DISCRETE BOUNCE
    V = -E*V                      ! restitution: the state is reset, the run restarts
  END
END
"""


def ball_exact(t: np.ndarray) -> tuple[list[float], np.ndarray, np.ndarray]:
    """Impact instants up to TSTOP and H, V at t, from the flight parabolas (rows at an
    impact show the values after it)."""
    g, e, h0 = BALL_G, BALL_E, BALL_H0
    t1 = math.sqrt(2 * h0 / g)
    impacts, v = [t1], g * t1
    while True:
        v *= e
        nxt = impacts[-1] + 2 * v / g
        if nxt > BALL_TSTOP:
            break
        impacts.append(nxt)
    h = h0 - g * t**2 / 2
    vel = -g * t
    v = g * t1
    edges = impacts + [math.inf]
    for a, b in zip(edges, edges[1:], strict=False):
        v *= e
        s = t - a
        inside = (t >= a) & (t < b)
        h = np.where(inside, v * s - g * s**2 / 2, h)
        vel = np.where(inside, v - g * s, vel)
    return impacts, h, vel


def measure_ball(routes, tols, atol_ratio, log) -> list[dict]:
    import amilpy

    model = amilpy.loads(BALL, "ball.csl")
    model.run(advice=False)
    rows = []
    for route in routes:
        for rtol in tols:
            t0 = time.perf_counter()
            try:
                run, = model.run(method=route, rtol=rtol, atol=rtol * atol_ratio,
                                 advice=False, max_time=MAX_TIME)
            except Exception as exc:  # noqa: BLE001
                rows.append({"route": route, "rtol": rtol, "status": f"raised {exc}"})
                continue
            sec = time.perf_counter() - t0
            impacts, h, v = ball_exact(run.t)
            got = [e.time for e in run.events if str(e.kind) == "discrete"]
            n = min(len(got), len(impacts))
            dt = [abs(a - b) for a, b in zip(got[:n], impacts[:n], strict=True)]
            ulps = [d / np.spacing(b) for d, b in zip(dt, impacts[:n], strict=True)]
            # rows closer to an impact than the route's impact error are not compared
            near = np.zeros(run.t.shape, bool)
            for a in impacts:
                near |= np.abs(run.t - a) <= max(max(dt, default=0.0), 1e-12)
            eh = float(np.max(np.abs(run["H"][~near] - h[~near]))) / BALL_H0
            # the first impact's error that the trajectory alone implies: the height's
            # error at the last row before it over the speed there
            before = np.flatnonzero(run.t < impacts[0])
            k = int(before[-1]) if before.size else 0
            implied = abs(float(run["H"][k] - h[k])) / (BALL_G * impacts[0])
            ev = float(np.max(np.abs(run["V"][~near] - v[~near]))) / \
                float(np.max(np.abs(v)))
            rows.append({"route": route, "rtol": rtol, "impacts": len(got),
                         "expected": len(impacts), "first": dt[0] if dt else math.nan,
                         "implied": implied,
                         "max": max(dt, default=math.nan), "ulps": max(ulps, default=math.nan),
                         "h_err": eh, "v_err": ev, "seconds": sec, "status": str(run.status),
                         "nfev": int(run.stats.get("nfev", 0))})
            r = rows[-1]
            log(f"    ball {route:7s} {rtol:.0e}: {r['impacts']}/{r['expected']} impacts, "
                f"max |dt| {r['max']:.2e} s ({r['ulps']:.3g} ulp), first {r['first']:.2e} "
                f"(trajectory implies {implied:.2e}), H {eh:.1e} {r['status']}")
    return rows


# ------------------------------------------------------------------ tables

def _fmt(x: float) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if math.isinf(x):
        return "fail"
    return f"{x:.1e}"


def loosest(m: Measured, route: str, goal: float) -> float | None:
    """The loosest RELERR from which every tighter rung run also reaches the goal."""
    res = sorted((r for r in m.results if r.route == route), key=lambda r: -r.rtol)
    ok = None
    for r in reversed(res):  # from the tightest up
        if r.error <= goal:
            ok = r.rtol
        else:
            break
    return ok


def _auto(m: Measured, rtol: float) -> Result | None:
    for r in m.results:
        if r.route == "AUTO" and math.isclose(r.rtol, rtol):
            return r
    return None


def tables(measured: list[Measured], ball: list[dict], routes, tols, absent, goal,
           atol_ratio, header: str) -> str:
    out = [header]
    var = [m for m in measured if not m.listing.fixed]
    fixed = [m for m in measured if m.listing.fixed]

    out.append("\n## References\n")
    out.append("| listing | form | source | reference | check: its error | independent "
               "restatement: the reference's error | variables | events (kinds, default "
               "run) |")
    out.append("|---|---|---|---|---|---|---|---|")
    for m in var:
        ev = ", ".join(f"{k} {v}" for k, v in sorted(m.event_kinds.items())) or "none"
        drop = f" (left out, round-off: {', '.join(m.dropped)})" if m.dropped else ""
        out.append(f"| {m.listing.name} | {m.listing.form} | {m.listing.source} | "
                   f"{m.reference} | {m.check or '-'}: {_fmt(m.agreement)} | "
                   f"{_fmt(m.independent)} | {len(m.variables)}{drop} | {ev} |")

    out.append(f"\n## AUTO: error at each RELERR (ABSERR = RELERR x {atol_ratio:g}), "
               "time per run [ms]\n")
    out.append("| listing | form | " + " | ".join(f"{t:.0e}" for t in tols) +
               f" | loosest <= {goal:g} | time there / at 1e-6 |")
    out.append("|---|---|" + "---|" * len(tols) + "---|---|")
    for m in var:
        cells = []
        for t in tols:
            r = _auto(m, t)
            cells.append("-" if r is None else f"{_fmt(r.error)} ({r.seconds * 1e3:.3g})")
        lo = loosest(m, "AUTO", goal)
        base, there = _auto(m, 1e-6), _auto(m, lo) if lo else None
        cost = (f"{there.seconds * 1e3:.3g} / {base.seconds * 1e3:.3g} ms"
                if there and base else "-")
        out.append(f"| {m.listing.name} | {m.listing.form} | " + " | ".join(cells) +
                   f" | {'not reached' if lo is None else f'{lo:.0e}'} | {cost} |")

    out.append("\n## Every route: error at each RELERR (worst variable at the loosest), "
               "time per run [ms]\n")
    for m in var:
        checked = m.agreement if not math.isnan(m.agreement) else m.independent
        out.append(f"\n### {m.listing.name} ({m.listing.form}; {m.listing.note}; "
                   f"reference checked to {_fmt(checked)})\n")
        out.append("| route | " + " | ".join(f"{t:.0e}" for t in tols) + " | worst at 1e-6 |")
        out.append("|---|" + "---|" * len(tols) + "---|")
        for route in routes:
            rs = {round(math.log10(r.rtol)): r for r in m.results if r.route == route}
            cells = []
            for t in tols:
                r = rs.get(round(math.log10(t)))
                if r is None:
                    cells.append("-")
                else:
                    st = "" if r.status in ("finished", "stopped") else f" {r.status}"
                    cells.append(f"{_fmt(r.error)} ({r.seconds * 1e3:.3g}){st}")
            first = rs.get(-6)
            out.append(f"| {route} | " + " | ".join(cells) +
                       f" | {first.worst if first else '-'} |")

    out.append(f"\n## Per form: the loosest AUTO RELERR reaching {goal:g} on every listing\n")
    out.append("| form | listings | loosest per listing | loosest for all | "
               "AUTO time at it / at 1e-6 (sum) |")
    out.append("|---|---|---|---|---|")
    for form in ("CSMP", "ACSL", "FST"):
        ms = [m for m in var if m.listing.form == form]
        if not ms:
            continue
        lows = {m.listing.name: loosest(m, "AUTO", goal) for m in ms}
        known = [v for v in lows.values() if v is not None]
        allv = None if len(known) < len(lows) else min(known)
        t_at = t_base = 0.0
        if allv:
            for m in ms:
                a, b = _auto(m, allv), _auto(m, 1e-6)
                t_at += a.seconds if a else math.nan
                t_base += b.seconds if b else math.nan
        per = ", ".join(f"{k} {'-' if v is None else f'{v:.0e}'}" for k, v in lows.items())
        cost = f"{t_at * 1e3:.3g} / {t_base * 1e3:.3g} ms ({t_at / t_base:.2f}x)" \
            if allv and t_base else "-"
        out.append(f"| {form} | {len(ms)} | {per} | "
                   f"{'not reached' if allv is None else f'{allv:.0e}'} | {cost} |")

    ratios = [m for m in var if m.ratio]
    if ratios:
        rt = sorted({r.rtol for m in ratios for r in m.ratio}, reverse=True)
        out.append("\n## AUTO: the ABSERR ratio (ABSERR = RELERR x ratio)\n")
        out.append("| listing | smallest state scale | " +
                   " | ".join(f"{t:.0e} x {q:g}" for t in rt for q in (1.0, atol_ratio, 1e-6))
                   + " |")
        out.append("|---|---|" + "---|" * (3 * len(rt)))
        for m in ratios:
            cells = []
            for t in rt:
                for q in (1.0, atol_ratio, 1e-6):
                    if q == atol_ratio:
                        r = _auto(m, t)
                    else:
                        r = next((x for x in m.ratio if math.isclose(x.rtol, t)
                                  and math.isclose(x.atol, t * q)), None)
                    cells.append("-" if r is None else f"{_fmt(r.error)} "
                                 f"({r.seconds * 1e3:.3g})")
            small = min(m.scales.values()) if m.scales else math.nan
            out.append(f"| {m.listing.name} | {small:.2g} | " + " | ".join(cells) + " |")

    if fixed:
        out.append("\n## Fixed-step listings (RELERR does not apply)\n")
        for m in fixed:
            out.append(f"* {m.listing.name} ({m.listing.form}, {m.listing.source}): "
                       f"{m.fixed_note}")
    if absent:
        out.append("\n## Not measured\n")
        out.append("Absent published copies (see tests/listings/SOURCES.md): " +
                   ", ".join(absent) + ".")
    out.append("\nRefused as written (tests/listings/SOURCES.md): molly3.csl (arrays, GO "
               "TO), sucros1.fst and lintul2.fst (CALL of Fortran subroutines).")

    if ball:
        out.append(f"\n## Bouncing ball: impact instants against the closed form "
                   f"(ABSERR = RELERR x {atol_ratio:g})\n")
        out.append("H0 = 10, G = 9.81, E = 0.8, TSTOP = 10: 7 impacts (1.43 ... 9.86 s). "
                   "Cell: max |t_impact - exact| over the impacts [s] (in ulps of the "
                   "impact instant) / max height error over the rows, relative to H0.\n")
        tl = sorted({r["rtol"] for r in ball}, reverse=True)
        out.append("| route | " + " | ".join(f"{t:.0e}" for t in tl) + " |")
        out.append("|---|" + "---|" * len(tl))
        for route in dict.fromkeys(r["route"] for r in ball):
            cells = []
            for t in tl:
                r = next((x for x in ball if x["route"] == route and x["rtol"] == t), None)
                if r is None or "max" not in r:
                    cells.append(r["status"] if r else "-")
                    continue
                miss = "" if r["impacts"] == r["expected"] else \
                    f" {r['impacts']}/{r['expected']} impacts"
                st = "" if r["status"] in ("stopped", "finished") else f" {r['status']}"
                cells.append(f"{r['max']:.1e} ({r['ulps']:.3g}) / {r['h_err']:.0e}{miss}{st}")
            out.append(f"| {route} | " + " | ".join(cells) + " |")
        out.append("\nThe first impact: its error / the error the trajectory alone implies "
                   "(the height's error at the last row before it over the speed there) [s]."
                   " Equal: the impact is located on the route's own trajectory to round-off,"
                   " and what is left is the trajectory's error.\n")
        out.append("| route | " + " | ".join(f"{t:.0e}" for t in tl) + " |")
        out.append("|---|" + "---|" * len(tl))
        for route in dict.fromkeys(r["route"] for r in ball):
            cells = []
            for t in tl:
                r = next((x for x in ball if x["route"] == route and x["rtol"] == t), None)
                cells.append("-" if r is None or "first" not in r else
                             f"{r['first']:.1e} / {r['implied']:.1e}")
            out.append(f"| {route} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


# ------------------------------------------------------------------ main

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--listings", nargs="*", help="names (default: every listing)")
    ap.add_argument("--routes", nargs="*", default=ROUTES)
    ap.add_argument("--tols", nargs="*", type=float, default=TOLS, help="AUTO's ladder")
    ap.add_argument("--other-tols", nargs="*", type=float, default=OTHER_TOLS,
                    help="the other routes' ladder")
    ap.add_argument("--ratio-tols", nargs="*", type=float, default=[1e-8, 1e-10],
                    help="RELERR at which AUTO runs with ABSERR ratios 1 and 1e-6 too")
    ap.add_argument("--atol-ratio", type=float, default=ATOL_RATIO)
    ap.add_argument("--goal", type=float, default=GOAL)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--slow", type=float, default=SLOW)
    ap.add_argument("--no-ball", action="store_true")
    ap.add_argument("--quick", action="store_true",
                    help="two listings, AUTO and RKS, RELERR 1e-6 and 1e-9, one repeat")
    ap.add_argument("--out", default=str(HERE / "results" / "tolerances.md"))
    a = ap.parse_args(argv)
    if a.quick:
        a.listings = a.listings or ["spring", "oral_dosing", "fst_wheat"]
        a.routes, a.tols, a.ratio_tols, a.repeats = ["AUTO", "RKS"], [1e-6, 1e-9], [1e-9], 1
        a.other_tols = a.tols
    warnings.simplefilter("ignore")

    def log(s):
        print(s, flush=True)

    listings, absent = all_listings()
    if a.listings:
        listings = [x for x in listings if x.name in a.listings]
    t_start = time.perf_counter()
    cpu_start = time.process_time()
    measured = []
    for lst in listings:
        log(f"{lst.name} ({lst.form}, {lst.source})")
        measured.append(measure(lst, a.routes, a.tols, a.other_tols, a.repeats, a.slow,
                                a.atol_ratio, a.ratio_tols, log))
    ball = [] if a.no_ball else measure_ball(a.routes, a.tols, a.atol_ratio, log)
    import scipy

    import amilpy

    header = (f"# Default tolerances: error against tight references, per route and "
              f"RELERR\n\n`python benchmarks/tolerances.py {' '.join(argv or sys.argv[1:])}`"
              f" — amilpy {getattr(amilpy, '__version__', '?')}, SciPy {scipy.__version__}, "
              f"NumPy {np.__version__}, Python {platform.python_version()}; "
              f"load average at the start {os.getloadavg()[0]:.2f}; "
              f"{time.perf_counter() - t_start:.0f} s wall, "
              f"{time.process_time() - cpu_start:.0f} s CPU.\n\n"
              f"Error: max over the OUTDEL rows and the variables (states and PRINT "
              f"variables; the shipped models: states) of |y - y_ref| / max|y_ref|. "
              f"Goal: {a.goal:g} (every digit of the %.6E printout). A cell is "
              f"`error (ms per run)`; `fail`: the run failed or stopped early; `-`: not "
              f"run (a looser rung took over {a.slow:g} s, or not on the ladder).")
    text = tables(measured, ball, a.routes, a.tols, absent, a.goal, a.atol_ratio, header)
    print(text)
    if a.out:
        Path(a.out).parent.mkdir(parents=True, exist_ok=True)
        Path(a.out).write_text(text, encoding="utf-8")
        log(f"written {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
