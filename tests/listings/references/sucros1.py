"""Independent numerical reference for s97-1.fst (SUCROS1, spring wheat,
potential production; Goudriaan & van Laar 1994, version September 1997).

Plain Python, math module only, double precision throughout; written by a session
that read only the listing and its weather file, never amilpy.

FSE semantics (DRIVER='EUDRIV', rectangular/Euler integration):
  time points t = STTIME + i*DELT (i = 0, 1, ...) up to FINTIM;
  at each time point all variables are computed from the states at t and the
  weather of day int(t); the output row is written; the FINISH conditions are
  tested (the run stops at the first time point where one holds, that row
  being the last); then the Euler step state(t+DELT) = state(t) + DELT*rate(t).

Weather: WEATHER CNTR='NLD'; ISTN=1; IYEAR=1990  ->  file NLD1.990 (CABO
format).  RDD = irradiation (kJ m-2 d-1) * 1000 -> J m-2 d-1.  LAT is the
latitude in the header line of the weather file (the listing's
`PARAMETER LATT = 52.` is commented out and LAT is documented as read from
the weather file).

`run(folder)`: the rows and their column names, the weather read from NLD1.990 in
`folder`. The routines after STOP are `sucros_routines`, which SUCROS2's reference
shares (the two files have the same Fortran).
"""
import os

from .cabo import read_cabo
from .sucros_routines import GLA, SUBEAI, TOTASS, WGAUSS3, WGAUSS5
from .ttutil import AFGEN, INSW, LIMIT, NOTNUL

# ----------------------------------------------------------------------------
# Parameters, initial conditions, function tables, timer (from the listing)
# ----------------------------------------------------------------------------

# INITIAL
DOYEM = 90.0
WLVI = 0.5
WSTI = 0.3
WRTI = 0.8
WLVDI = 0.0
WSOI = 0.0
ILAI = 0.012
IDVS = 0.0
IEAI = 0.0

# 1.3 crop development
DVRVT = [-10.0, 0.0, 0.0, 0.0, 30.0, 0.027]
DVRRT = [-10.0, 0.0, 0.0, 0.0, 30.0, 0.031]

# 1.4 leaf CO2 assimilation
AMX = 1.11e-3
AMDVST = [0.0, 1.0, 1.0, 1.0, 2.0, 0.5, 2.5, 0.0]
AMTMPT = [-10.0, 0.0, 0.0, 0.0, 10.0, 1.0, 25.0, 1.0, 35.0, 0.0, 50.0, 0.0]

# 1.5 daily gross CO2 assimilation
EFF = 12.5e-6
KDF = 0.60
SCP = 0.20

# 1.7 maintenance respiration
Q10 = 2.0
TREF = 25.0
MAINLV = 0.03
MAINST = 0.015
MAINRT = 0.015
MAINSO = 0.01

# 1.8 dry matter partitioning
FSHTB = [0.00, 0.50, 0.10, 0.50, 0.20, 0.60, 0.35, 0.78,
         0.40, 0.83, 0.50, 0.87, 0.60, 0.90, 0.70, 0.93,
         0.80, 0.95, 0.90, 0.97, 1.00, 0.98, 1.10, 0.99,
         1.20, 1.00, 2.50, 1.00]
FLVTB = [0.00, 0.65, 0.10, 0.65, 0.25, 0.70, 0.50, 0.50,
         0.70, 0.15, 0.95, 0.00, 2.50, 0.00]
FSTTB = [0.00, 0.35, 0.10, 0.35, 0.25, 0.30, 0.50, 0.50,
         0.70, 0.85, 0.95, 1.00, 1.05, 0.00, 2.50, 0.00]
FSOTB = [0.00, 0.00, 0.95, 0.00, 1.05, 1.00, 2.50, 1.00]

# 1.9 growth of plant organs and translocation
ASRQRT = 1.444
ASRQLV = 1.463
ASRQST = 1.513
ASRQSO = 1.415
FRTRL = 0.20
CONVL = 0.947

# 1.10 leaf and ear development
RGRL = 0.009
SLA = 0.022
EAR = 0.63e-3
LAICR = 4.0
FRDR = 1.0

# 1.12 weather
TBASE = 0.0
CNTR = 'NLD'
ISTN = 1
IYEAR = 1990

# 1.13 carbon balance
CFLV = 0.459
CFST = 0.494
CFRT = 0.467
CFSO = 0.471

# 1.14 run control
STTIME = 80.0
FINTIM = 300.0
DELT = 1.0
PRDEL = 5.0  # output interval in FSE; this reference writes every time point

# ----------------------------------------------------------------------------
# Weather (CABO format)
# ----------------------------------------------------------------------------


def read_weather(folder):
    """Returns (lon, lat, elev, A, B) and {day: (RDD, TMMN, TMMX, VP, WN, RAIN)} of
    NLD1.990 (its two '-999' rows, for days 1 and 2, are codes, no days)."""
    header, days = read_cabo(os.path.join(folder, f'{CNTR}{ISTN}.{str(IYEAR)[1:]}'))
    return header, {d: tuple(v[k] for k in ('RDD', 'TMMN', 'TMMX', 'VP', 'WN', 'RAIN'))
                    for d, v in days.items()}


# ----------------------------------------------------------------------------
# Model: rates and auxiliary variables from the states at time t
# ----------------------------------------------------------------------------

STATE_NAMES = ['DVS', 'LAI', 'EAI', 'WRT', 'WLVG', 'WLVD', 'WST', 'WSO', 'TNASS']
PRINT_NAMES = ['DOY', 'DTR', 'DVS', 'TDRW', 'TADRW', 'WLVG', 'WLVD', 'WLV', 'WST',
               'WSO', 'WRT', 'LAI', 'EAI', 'HI', 'GPHOT', 'DAYL',
               'DS0', 'TRANSL', 'CHKIN', 'CHKFL', 'CHKDIF', 'ERRSH', 'MAINT']


def model(TIME, s, LAT, weather):
    """All variables at time TIME from the states s (dict); returns
    (v, rates): v a dict of every variable, rates a dict keyed by state."""
    DVS, LAI, EAI = s['DVS'], s['LAI'], s['EAI']
    WRT, WLVG, WLVD, WST, WSO, TNASS = (s['WRT'], s['WLVG'], s['WLVD'],
                                        s['WST'], s['WSO'], s['TNASS'])

    # 1.12 weather of day int(TIME)
    DOY = float(int(TIME))
    RDD, TMMN, TMMX, VP, WN, RAIN = weather[int(TIME)]
    DTR = RDD
    DAVTMP = 0.5 * (TMMX + TMMN)
    DDTMP = TMMX - 0.25 * (TMMX - TMMN)
    DTEFF = max(0.0, DAVTMP - TBASE)

    # 1.3 development
    EMERG = INSW(TIME - DOYEM, 0.0, 1.0)
    DVR = INSW(DVS - 1.0, AFGEN(DVRVT, DAVTMP), AFGEN(DVRRT, DAVTMP)) * EMERG

    # 1.11 weights derived from states
    WLV = WLVG + WLVD
    TADRW = WLV + WST + WSO
    TDRW = TADRW + WRT
    HI = WSO / NOTNUL(TADRW)

    # 1.4 leaf CO2 assimilation
    AMDVS = AFGEN(AMDVST, DVS)
    AMTMP = AFGEN(AMTMPT, DDTMP)
    AMAX = AMX * AMDVS * AMTMP * EMERG

    # 1.10 (part) photosynthetically active area
    TAI = 0.5 * EAI + LAI

    # 1.5 daily gross CO2 assimilation
    DAYL, DTGA, DS0 = TOTASS(DOY, LAT, DTR, SCP, AMAX, EFF, KDF, TAI)

    # 1.6 carbohydrate production
    GPHOT = DTGA * 30.0 / 44.0

    # 1.7 maintenance respiration
    MNDVS = WLVG / NOTNUL(WLV)
    TEFF = Q10 ** ((DAVTMP - TREF) / 10.0)
    MAINTS = MAINLV * WLVG + MAINST * WST + MAINRT * WRT + MAINSO * WSO
    MAINT = MAINTS * TEFF * MNDVS * EMERG

    # 1.8 partitioning
    FSH = AFGEN(FSHTB, DVS)
    FRT = 1.0 - FSH
    FLV = AFGEN(FLVTB, DVS)
    FST = AFGEN(FSTTB, DVS)
    FSO = AFGEN(FSOTB, DVS)
    ERRSH = abs(FLV + FST + FSO - 1.0)

    # 1.9 growth of organs and translocation
    ASRQ = FSH * (ASRQLV * FLV + ASRQST * FST + ASRQSO * FSO) + ASRQRT * FRT
    TRANSL = INSW(DVS - 1.0, 0.0, WST * DVR * FRTRL)
    GTW = (GPHOT - MAINT + CONVL * TRANSL * CFST * 30.0 / 12.0) / ASRQ
    GRT = FRT * GTW
    GLV = FLV * FSH * GTW
    GST = FST * FSH * GTW - TRANSL
    GSO = FSO * FSH * GTW

    # 1.10 leaf and ear development
    GLAI = GLA(TIME, DOYEM, DTEFF, DVS, RGRL, DELT, SLA, LAI, GLV)
    RDRDV = INSW(DVS - 1.0, 0.0, DVR / (max(0.1, 2.0 - DVS)) * FRDR)
    RDRSH = LIMIT(0.0, 0.03, 0.03 * (LAI - LAICR) / LAICR)
    RDR = max(RDRDV, RDRSH)
    DLAI = LAI * RDR
    RLAI = GLAI - DLAI
    REAI = SUBEAI(DELT, DVS, EAR, TADRW, RDRDV, EAI)
    DLV = WLVG * DLAI / NOTNUL(LAI)
    RWLVG = GLV - DLV

    # 1.13 carbon balance check
    CO2RT = 44.0 / 12.0 * (ASRQRT * 12.0 / 30.0 - CFRT)
    CO2LV = 44.0 / 12.0 * (ASRQLV * 12.0 / 30.0 - CFLV)
    CO2ST = 44.0 / 12.0 * (ASRQST * 12.0 / 30.0 - CFST)
    CO2SO = 44.0 / 12.0 * (ASRQSO * 12.0 / 30.0 - CFSO)
    RTNASS = (((GPHOT - MAINT) * 44.0 / 30.0)
              - (GRT * CO2RT + GLV * CO2LV + (GST + TRANSL) * CO2ST + GSO * CO2SO
                 + (1.0 - CONVL) * TRANSL * CFST * 44.0 / 12.0))
    CHKIN = WLV * CFLV + WST * CFST + WRT * CFRT + WSO * CFSO
    CHKFL = TNASS * (12.0 / 44.0)
    CHKDIF = (CHKIN - CHKFL) / NOTNUL(CHKIN)

    v = dict(locals())
    v.pop('s'), v.pop('weather')
    rates = {'DVS': DVR, 'LAI': RLAI, 'EAI': REAI, 'WRT': GRT, 'WLVG': RWLVG,
             'WLVD': DLV, 'WST': GST, 'WSO': GSO, 'TNASS': RTNASS}
    return v, rates


def finish_conditions(v):
    """FINISH statements of the listing, in listing order."""
    hits = []
    if v['ERRSH'] > 1.0e-6:
        hits.append('ERRSH > 1.E-6')
    if v['CHKDIF'] > 0.001:
        hits.append('CHKDIF > 0.001')
    if v['DVS'] > 2.0:
        hits.append('DVS > 2.')
    return hits


def run(folder=None):
    """Runs the model; returns (rows, column names).  Also sets
    run.finished_by (list of FINISH conditions that held at the last row, or
    ['FINTIM'])."""
    if folder is None:
        folder = os.path.dirname(os.path.abspath(__file__))
    header, weather = read_weather(folder)
    LAT = header[1]

    # self-checks: Gauss weights sum to 1 (to the 7 digits of the DATA values)
    assert abs(sum(WGAUSS3) - 1.0) < 1e-5
    assert abs(sum(WGAUSS5) - 1.0) < 1e-6

    # INITIAL
    TNASSI = (WLVI * CFLV + WSTI * CFST + WRTI * CFRT) * 44.0 / 12.0
    s = {'DVS': IDVS, 'LAI': ILAI, 'EAI': IEAI, 'WRT': WRTI, 'WLVG': WLVI,
         'WLVD': WLVDI, 'WST': WSTI, 'WSO': WSOI, 'TNASS': TNASSI}

    names = ['TIME'] + PRINT_NAMES + [n for n in STATE_NAMES if n not in PRINT_NAMES]
    rows = []
    run.finished_by = ['FINTIM']
    i = 0
    while True:
        TIME = STTIME + i * DELT
        if TIME > FINTIM + 1e-9 * DELT:
            break
        v, rates = model(TIME, s, LAT, weather)

        # self-checks: dry-matter balance and partitioning
        organs = v['WLVG'] + v['WLVD'] + v['WST'] + v['WSO'] + v['WRT']
        assert abs(organs - v['TDRW']) <= 1e-12 * max(1.0, v['TDRW'])
        assert abs(v['GRT'] + v['GLV'] + v['GST'] + v['TRANSL'] + v['GSO']
                   - v['GTW']) <= 1e-12 * max(1.0, abs(v['GTW']))

        rows.append([TIME] + [v[n] for n in names[1:]])
        hits = finish_conditions(v)
        if hits:
            run.finished_by = hits
            break
        # Euler step
        for n in STATE_NAMES:
            s[n] = s[n] + DELT * rates[n]
        i += 1
    return rows, names
