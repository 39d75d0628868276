"""Independent reference implementation of LINGRA-new-JRC (perennial ryegrass, Wolf 2006),
translated by hand from LINGRATW-new-JRC.fst, its Fortran subroutines after STOP (PENMAN,
EVAPTR, DRUNIR, SOSUB, TILSUB, MOWING) and its weather file NL1.989, by a session that read
only the listing, the weather file and the FST-generated Fortran (model.f90), never amilpy.

Plain Python, math module only, double precision throughout. FSE computes in REAL*4,
so its printout (5 or 6 significant digits) differs from this in the last digit here and
there, and more where float32 rounding is amplified: NEWBIO (a difference of sums near
244 kg/ha that is itself near 0 early in the season) and WRE (integral of GTWSO1 - GTWSI,
two fluxes of some 200 kg/ha/d).

FSE semantics (DRIVER='EUDRIV', DELT = 1, STTIME = 1, FINTIM = 365, PRDEL = 1):
  time points TIME = 1, 2, ..., 365; at each one the weather of day int(TIME) of 1989 is
  read, all variables and rates are computed from the states (in the order of model.f90's
  rate section, which is a valid order of the sorted listing), the row is written, then the
  Euler step state += DELT * rate.
  The generated MODEL routine SAVEs every variable, and the subroutines change some of
  their arguments in place:
    - PENMAN does VP = MIN(VP, SVP) on the weather variable VP, so the printed VP is the
      clipped one (the weather system sets VP afresh at every call);
    - MOWING does INCUT = INCUT + 1. on the PARAM INCUT, which therefore counts the cuts
      for the rest of the run (it is read again as 0 at the start of each run). Its four
      branches always set HARV and RDAHA, but they are carried over between days anyway
      (each run starts them at 0 here; FSE would keep the previous run's values, which
      MOWING overwrites before any use).
Two runs: run 0 with the listing's PARAMs (RUN = 0, IRRIGF = 1), run 1 the rerun
(RUN = 1, IRRIGF = 0); each starts again from the initial values.

Weather: WEATHER CNTR='Nl'; ISTN=1; IYEAR=1989 -> NL1.989 (CABO format). RDD =
irradiation (kJ m-2 d-1) * 1000 -> J m-2 d-1. LAT is the second number of the header
line (longitude, latitude, elevation, A, B). Rows whose station number is -999 (the
file's quality-code rows before some days) are skipped.

`run(run_number, folder)`: one dict per day (TIME 1..365) with every variable of the
model, the printed ones among them (and TIME, HARV, DAHA, INCUT).
"""
import math
import os

from .cabo import read_cabo
from .ttutil import AFGEN, FCNSW, INSW, LIMIT, NOTNUL, REAAND

# ----------------------------------------------------------------------------
# Parameters, initial conditions, function tables, timer (from the listing)
# ----------------------------------------------------------------------------
# INCON
ZERO = 0.0
ROOTDI = 0.4
LAII = 0.1
SOITMI = 5.0
TILLI = 7000.0
WREI = 200.0
WRTI = 4.0

BASE_PARAMS = dict(
    RUN=0.0,
    CO2A=360.0, KDIF=0.60, LAICR=4.0, TBASE=0.0,
    LUEMAX=3.0, IMOPT=2.0, INCUT=0.0,
    SLA=0.0025, CLAI=0.8, NITMAX=3.34, NITR=3.34, RDRD=0.01,
    TMBAS1=3.0, CWGHT=1800.0,
    DRATE=50.0, IRRIGF=1.0, ROOTDM=0.4, RRDMAX=0.012,
    WCAD=0.005, WCWP=0.12, WCFC=0.29,
    WCI=0.29, WCWET=0.37, WCST=0.41,
)
# The rerun between the two END lines
RERUN_PARAMS = dict(RUN=1.0, IRRIGF=0.0)

# Harvest dates: ARRAY_SIZE NH=10; MNDAT(6:NH) = 999.
NH = 10
MNDAT = [135.0, 165.0, 200.0, 240.0, 280.0] + [999.0] * (NH - 5)

LUERD1 = [-20., 0., 3., 0., 8., 1., 40., 1.]
LUERD2 = [0., 1., 10., 1., 40., 0.33]
FRRTTB = [-10., 0.263, 0., 0.263, 1., 0.165]

STTIME, FINTIM, DELT = 1.0, 365.0, 1.0
IYEAR = 1989

# ----------------------------------------------------------------------------
# Weather (CABO format)
# ----------------------------------------------------------------------------


def read_weather(folder):
    """Returns the header (lon, lat, elev, A, B) and {day: (RDD, TMMN, TMMX, VP, WN, RAIN)}."""
    header, days = read_cabo(os.path.join(folder, 'NL1.989'))
    return header, {d: tuple(v[k] for k in ('RDD', 'TMMN', 'TMMX', 'VP', 'WN', 'RAIN'))
                    for d, v in days.items()}


# ----------------------------------------------------------------------------
# Subroutines (translated from the Fortran after STOP)
# ----------------------------------------------------------------------------


def PENMAN(DAVTMP, VP, DTR, LAI, WN, RNINTC):
    """Returns (VP, PEVAP, PTRAN): VP is an argument the routine clips in place."""
    DTRJM2 = DTR * 1.E6
    BOLTZM = 5.668E-8
    LHVAP = 2.4E6
    PSYCH = 0.067
    BBRAD = BOLTZM * (DAVTMP + 273.) ** 4 * 86400.
    SVP = 0.611 * math.exp(17.4 * DAVTMP / (DAVTMP + 239.))
    VP = min(VP, SVP)
    SLOPE = 4158.6 * SVP / (DAVTMP + 239.) ** 2
    RLWN = BBRAD * max(0., 0.55 * (1. - VP / SVP))
    NRADS = DTRJM2 * (1. - 0.15) - RLWN
    NRADC = DTRJM2 * (1. - 0.25) - RLWN
    PENMRS = NRADS * SLOPE / (SLOPE + PSYCH)
    PENMRC = NRADC * SLOPE / (SLOPE + PSYCH)
    WDF = 2.63 * (1.0 + 0.54 * WN)
    PENMD = LHVAP * WDF * (SVP - VP) * PSYCH / (SLOPE + PSYCH)
    PEVAP = max(0.0, math.exp(-0.5 * LAI) * (PENMRS + PENMD) / LHVAP)
    PTRAN = (1. - math.exp(-0.5 * LAI)) * (PENMRC + PENMD) / LHVAP
    PTRAN = max(0.0, PTRAN - 0.5 * RNINTC)
    return VP, PEVAP, PTRAN


def EVAPTR(PEVAP, PTRAN, ROOTD, WA, WCAD, WCWP, WCFC, WCWET, WCST, DELT):
    """Returns (EVAP, TRAN)."""
    WC = 0.001 * WA / ROOTD
    WAAD = 1000. * WCAD * ROOTD
    # WAFC = 1000. * WCFC * ROOTD is computed in the Fortran but not used
    EVAP1 = PEVAP * LIMIT(0., 1., (WC - WCAD) / (WCFC - WCAD))
    WCCR = WCWP + 0.5 * (WCFC - WCWP)
    if WC > WCCR:
        FR = LIMIT(0., 1., (WCST - WC) / (WCST - WCWET))
    else:
        FR = LIMIT(0., 1., (WC - WCWP) / (WCCR - WCWP))
    TRAN = PTRAN * FR
    AVAILF = min(1., ((WA - WAAD) / DELT) / NOTNUL(EVAP1 + TRAN))
    EVAP2 = EVAP1 * AVAILF
    TRAN = TRAN * AVAILF
    return EVAP2, TRAN


def DRUNIR(RAIN, RNINTC, EVAP, TRAN, IRRIGF, DRATE, DELT, WA, ROOTD, WCFC, WCST):
    """Returns (DRAIN, RUNOFF, IRRIG); note IRRIG is not clipped at 0 here."""
    WAFC = 1000. * WCFC * ROOTD
    WAST = 1000. * WCST * ROOTD
    DRAIN = LIMIT(0., DRATE, (WA - WAFC) / DELT + (RAIN - RNINTC - EVAP - TRAN))
    RUNOFF = max(0., (WA - WAST) / DELT + (RAIN - RNINTC - EVAP - TRAN - DRAIN))
    IRRIG = IRRIGF * ((WAFC - WA) / DELT
                      - (RAIN - RNINTC - EVAP - TRAN - DRAIN - RUNOFF))
    return DRAIN, RUNOFF, IRRIG


def SOSUB(PARINT, LUE, CO2A, NITR, NITMAX, TRANRF, HARV):
    """Returns (LUED, GTWSO): source-limited growth, 0 on a harvest day."""
    LUED = min(LUE * (0.336 + 0.224 * NITR) / (0.336 + 0.224 * NITMAX), LUE * TRANRF)
    GTWSO = 0.
    if HARV == 0.:
        # 10: conversion from g m-2 d-1 to kg ha-1 d-1
        GTWSO = LUED * PARINT * (1. + 0.8 * math.log(CO2A / 360.)) * 10.
    return LUED, GTWSO


def TILSUB(TILLER, FSMAX, LAI, LAICR, DAHA, LEAFN, TSUM, RED):
    """Returns DTIL, the rate of tiller emergence."""
    if DAHA < 8.:
        REFTIL = max(0., 0.335 - 0.067 * LAI) * RED
    else:
        REFTIL = LIMIT(0., FSMAX, 0.867 - 0.183 * LAI) * RED
    DTILD = max(0.01 * (1. + TSUM / 600.), 0.05 * (LAI - LAICR) / LAICR)
    if TILLER <= 14000.:
        DTIL = (REFTIL - DTILD) * LEAFN * TILLER
    else:
        DTIL = -DTILD * LEAFN * TILLER
    return DTIL


def MOWING(IMOPT, INCUT, MNDAT, NH, TIME, WLVG, CWGHT, CWLVG, DAHA, RDAHA, HARV):
    """Returns (INCUT, RDAHA, HARV): INCUT, RDAHA and HARV are in-out arguments in the
    Fortran (a branch that does not fire leaves RDAHA and HARV as they were)."""
    MOWDAY = False
    for i1 in range(NH):
        if TIME == MNDAT[i1]:
            MOWDAY = True
    if IMOPT == 1. and WLVG >= CWGHT:
        HARV = WLVG - CWLVG
        RDAHA = -DAHA
        INCUT = INCUT + 1.
    elif IMOPT == 2. and MOWDAY and WLVG > CWLVG:
        HARV = WLVG - CWLVG
        RDAHA = -DAHA
        INCUT = INCUT + 1.
    elif INCUT == 0.:
        HARV = 0.
        RDAHA = 0.
    elif INCUT != 0.:
        HARV = 0.
        RDAHA = 1.
    return INCUT, RDAHA, HARV


# ----------------------------------------------------------------------------
# States: name -> name of its rate (INTGRL statements)
# ----------------------------------------------------------------------------
STATE_RATE = [
    ('SOITMP', 'RSOITM'), ('PARCU', 'PARINT'), ('TRACU', 'TRAN'), ('TRAMCU', 'PTRAN'),
    ('EVACU', 'EVAP'), ('EVAMCU', 'PEVAP'), ('IRRCU', 'IRRIG'), ('TSUM', 'TMEFF'),
    ('LAI', 'RLAI'), ('DAHA', 'RDAHA'), ('TILLER', 'DTIL'), ('WLVG', 'RLV'),
    ('WLVD', 'DLV'), ('GRASS', 'HARV'), ('WRE', 'RRE'), ('WRT', 'GRT'),
    ('LENGTH', 'LERA2'), ('ROOTD', 'RROOTD'), ('WA', 'RWA'), ('RAINCU', 'RAIN'),
]


def initial(p):
    """INITIAL section: computed initial values and constants, and the states."""
    c = dict(
        WAI=1000. * ROOTDI * p['WCI'],
        WLVGI=LAII / p['SLA'],       # initial leaf weight from initial leaf area
        CWLVG=p['CLAI'] / p['SLA'],  # leaf weight left after cutting
        FSMAX=p['NITR'] / p['NITMAX'] * 0.693,
    )
    s = {name: ZERO for name, _ in STATE_RATE}
    s.update(SOITMP=SOITMI, LAI=LAII, TILLER=TILLI, WLVG=c['WLVGI'], WRE=WREI, WRT=WRTI,
             ROOTD=ROOTDI, WA=c['WAI'])
    return s, c


# ----------------------------------------------------------------------------
# All variables and rates at one time point (model.f90's order of the rate section)
# ----------------------------------------------------------------------------


def model(TIME, s, P, c, saved, LAT, wdays):
    """Every variable at TIME from the states s. `saved` holds the values that survive
    from the previous call (INCUT, RDAHA, HARV) and is updated in place."""
    SOITMP, PARCU, TSUM, LAI = s['SOITMP'], s['PARCU'], s['TSUM'], s['LAI']
    DAHA, TILLER, WLVG, WLVD = s['DAHA'], s['TILLER'], s['WLVG'], s['WLVD']
    GRASS, WRE, WRT, LENGTH = s['GRASS'], s['WRE'], s['WRT'], s['LENGTH']
    ROOTD, WA = s['ROOTD'], s['WA']
    SLA, CWLVG, WLVGI, FSMAX = P['SLA'], c['CWLVG'], c['WLVGI'], c['FSMAX']

    # --- weather and calendar of day int(TIME)
    RDD, TMMN, TMMX, VP, WN, RAIN = wdays[int(TIME)]
    DOY = float(int(TIME))
    YEAR = float(IYEAR)

    DAVTMP = 0.5 * (TMMN + TMMX)
    PHOTMP = (TMMN + 3. * TMMX) / 4.
    PI = 3.1416  # the listing's own PI, not math.pi
    DTR = RDD / 1.E+6  # J/m2/d -> MJ/m2/d
    DVS = TSUM / 600.
    WLVD1 = WLVD - GRASS
    HRVBL = WLVG - CWLVG
    TADRW = GRASS + WLVG
    SLAINT = LAI / NOTNUL(WLVG)

    REDTMP = AFGEN(LUERD1, SOITMP)
    REDRDD = AFGEN(LUERD2, RDD / 1.E6)
    PAR = RDD / 1.0E6 * 0.50
    FINT = (1. - math.exp(-P['KDIF'] * LAI))

    # MOWING before anything that uses HARV or RDAHA; it also counts the cuts in INCUT
    saved['INCUT'], saved['RDAHA'], saved['HARV'] = MOWING(
        P['IMOPT'], saved['INCUT'], MNDAT, NH, TIME, WLVG, P['CWGHT'], CWLVG, DAHA,
        saved['RDAHA'], saved['HARV'])
    INCUT, RDAHA, HARV = saved['INCUT'], saved['RDAHA'], saved['HARV']

    DRE = WRE / DELT
    RDRSH = LIMIT(0., 0.03, 0.03 * (LAI - P['LAICR']) / P['LAICR'])
    RNINTC = min(RAIN, 0.25 * LAI)
    WC = 0.001 * WA / ROOTD

    NEWBIO = WLVG + WRT + WRE - (WLVGI + WRTI + WREI) + GRASS
    WRTMIN = -WRT
    RUNNR = P['RUN']
    LUE1 = P['LUEMAX'] * REDTMP * REDRDD
    PARINT = FINT * PAR
    # leaf appearance rate driven by the running-average soil temperature
    LEAFN = FCNSW(REDTMP, 0., 0., SOITMP * 0.01)
    # leaf elongation rate, cm d-1 tiller-1
    LERA = FCNSW(DAVTMP - P['TMBAS1'], 0., 0., 0.83 * math.log(max(DAVTMP, 2.)) - 0.8924)
    RAD = PI / 180.
    YIELD = GRASS + max(0., HRVBL)

    # PENMAN clips the weather variable VP in place: the printed VP is the clipped one
    VP, PEVAP, PTRAN = PENMAN(DAVTMP, VP, DTR, LAI, WN, RNINTC)

    RROOTD = P['RRDMAX'] * REAAND(P['ROOTDM'] - ROOTD, WC - P['WCWP'])
    RSOITM = (DAVTMP - SOITMP) / 10.
    EFFTMP = max(DAVTMP, P['TBASE'])
    RRATIO = LIMIT(0., 1., (WRT - WRTI) / NOTNUL(NEWBIO))
    TMEFF = max(DAVTMP - P['TMBAS1'], 0.)
    EVAP, TRAN = EVAPTR(PEVAP, PTRAN, ROOTD, WA, P['WCAD'], P['WCWP'], P['WCFC'],
                        P['WCWET'], P['WCST'], DELT)
    EXPLOR = 1000. * RROOTD * P['WCFC']
    # on a harvest day the leaf length is reset to 0
    LERA2 = INSW(HARV - 0.1, LERA, -LENGTH)
    DTIL = TILSUB(TILLER, FSMAX, LAI, P['LAICR'], DAHA, LEAFN, TSUM, REDTMP)
    # sink-limited leaf area growth; TILLER in m-2, 1.0E-8 from cm2 to ha
    DLAIS = (TILLER * 1.0E4 * (LERA * 0.3)) * 1.0E-8
    LUEYCU = YIELD / NOTNUL(PARCU)
    DEC = -math.asin(math.sin(23.45 * RAD) * math.cos(2. * PI * (DOY + 10.) / 365.))
    DECC = LIMIT(math.atan(-1. / math.tan(RAD * LAT)), math.atan(1. / math.tan(RAD * LAT)),
                 DEC)
    DRAIN, RUNOFF, IRRIG = DRUNIR(RAIN, RNINTC, EVAP, TRAN, P['IRRIGF'], P['DRATE'], DELT,
                                  WA, ROOTD, P['WCFC'], P['WCST'])
    TRANRF = INSW(-PTRAN, TRAN / NOTNUL(PTRAN), 1.)
    RDRSM = LIMIT(0., 0.05, 0.05 * (1. - TRANRF))
    FRT = AFGEN(FRRTTB, TRANRF)
    RWA = (RAIN + EXPLOR + IRRIG) - (RNINTC + RUNOFF + TRAN + EVAP + DRAIN)
    LUE2, GTWSO1 = SOSUB(PARINT, LUE1, P['CO2A'], P['NITR'], P['NITMAX'], TRANRF, HARV)
    DAYL = 0.5 * (1. + 2. * math.asin(math.tan(RAD * LAT) * math.tan(DECC)) / PI)
    # source: new assimilates plus all reserves
    GTWSO2 = GTWSO1 + WRE / DELT
    RDRS = max(RDRSH, RDRSM)
    FLV = 1. - FRT
    PARAV = 0.5 * DTR / DAYL
    RDR = P['RDRD'] + RDRS
    # sink: leaf demand converted to total dry matter; none on a harvest day
    GTWSI = FCNSW(HARV, DLAIS * (1. / SLA) * (1. / FLV), DLAIS * (1. / SLA) * (1. / FLV), 0.)
    # leaf area loss: senescence, or the harvested leaf area on a harvest day
    DLAI = FCNSW(HARV, LAI * (1. - math.exp(-RDR * DELT)), LAI * (1. - math.exp(-RDR * DELT)),
                 HARV * SLAINT)
    # growth is the smaller of source and sink; the surplus goes back to the reserves
    GRE = FCNSW(GTWSO2 - GTWSI, 0., 0., GTWSO2 - GTWSI)
    GTW = FCNSW(GTWSO2 - GTWSI, GTWSO2, GTWSO2, GTWSI)
    GRT = GTW * FRT
    GLAI = GTW * FLV * SLA
    GLV = FCNSW(HARV, GTW * FLV, GTW * FLV, 0.)
    RRE = GRE - DRE
    DLV = DLAI / NOTNUL(SLAINT)
    RLAI = GLAI - DLAI
    RLV = GLV - DLV

    v = dict(locals())
    for k in ('P', 'c', 's', 'saved', 'wdays'):
        v.pop(k)
    v.update(s)
    return v


# ----------------------------------------------------------------------------
# Driver
# ----------------------------------------------------------------------------
PRINT_NAMES = ['YEAR', 'DAVTMP', 'DTR', 'DAYL', 'LAI', 'TILLER', 'YIELD',
               'WLVG', 'WLVD1', 'WRE', 'WRT', 'WRTMIN',
               'RRATIO', 'SLA', 'SLAINT', 'PARCU', 'LUEYCU', 'RUNNR', 'GRASS', 'TADRW',
               'VP', 'NEWBIO', 'TRANRF', 'TRAN', 'PTRAN', 'EVAP', 'PEVAP', 'WC', 'WA', 'RAIN',
               'RAINCU', 'WN', 'TRAMCU', 'TRACU', 'EVAMCU', 'EVACU', 'IRRCU', 'GTW', 'GTWSI',
               'LENGTH']


def run(run_number, folder):
    """The rows of run `run_number` (0: the listing's PARAMs, 1: the rerun)."""
    p = dict(BASE_PARAMS)
    if run_number == 1:
        p.update(RERUN_PARAMS)
    elif run_number != 0:
        raise ValueError('run_number is 0 or 1')
    header, wdays = read_weather(folder)
    LAT = header[1]
    s, c = initial(p)
    # INCUT is read again as a PARAM at the start of each run; HARV and RDAHA start at 0
    saved = dict(INCUT=p['INCUT'], RDAHA=0.0, HARV=0.0)

    rows = []
    cum_growth = 0.0  # integral of GTWSO1, the only source of new dry matter
    cum_water = 0.0   # integral of RWA's terms that have no cumulative state
    nsteps = int(round((FINTIM - STTIME) / DELT))
    for i in range(nsteps + 1):
        TIME = STTIME + i * DELT
        v = model(TIME, s, p, c, saved, LAT, wdays)

        # self-checks: the dry matter balance (harvested leaves go to WLVD, so the
        # plant's total only grows by GTWSO1), and the water balance of the rooted zone
        total = v['WLVG'] + v['WLVD'] + v['WRE'] + v['WRT']
        expected = c['WLVGI'] + WREI + WRTI + cum_growth
        assert abs(total - expected) <= 1e-9 * expected, (TIME, total, expected)
        water = (c['WAI'] + v['RAINCU'] + v['IRRCU'] - v['TRACU'] - v['EVACU'] + cum_water)
        assert abs(v['WA'] - water) <= 1e-9 * max(1.0, v['RAINCU']), (TIME, v['WA'], water)

        rows.append(v)
        # Euler step
        cum_growth += DELT * v['GTWSO1']
        cum_water += DELT * (v['EXPLOR'] - v['RNINTC'] - v['RUNOFF'] - v['DRAIN'])
        for name, rate in STATE_RATE:
            s[name] = s[name] + DELT * v[rate]
    return rows
