"""Independent reference implementation of LINTUL2-Cassava (Ezui & Leffelaar 2016),
translated by hand from LINTUL2_Cassava_V0_October2016.fst (tests/listings/SOURCES.md)
by a session that read only the listing and its weather files, never amilpy.

FSE Euler driver semantics (DELT = 1): at each time point all algebraic variables
and rates are computed from the states (hand-ordered below), then the state EVENT
(emergence) is checked; if it fires, the NEWVALUEs are applied and everything is
recomputed. The row is written, FINISH is checked, then the Euler step is taken.

`run(irrigf, folder)`: the rows of one run (IRRIGF = 0 is the listing's first run,
1 its second), the weather read from the CABO files SVK6.013 and SVK6.014 in `folder`.
"""
import math
import os

from .cabo import read_cabo
from .ttutil import AFGEN, INSW, LIMIT, NOTNUL, REAAND, REANOR

# ----------------------------------------------------------------------------
# Parameters and tables (PARAM / FUNCTION lines)
# ----------------------------------------------------------------------------
BASE_PARAMS = dict(
    WCI=0.41,
    SLAI=0.017, SLA_MAX=0.03, NCUTTINGS=1.5625, WCUTTINGUNIT=14.0,
    TBASE=15.0,
    DOYPL=113.0,
    OPTEMERGTSUM=180.0, LAIEXPOEND=0.75, TSUMLA_MIN=180.0, RGRL=0.003,
    TSUMSOBULKINIT=540.0, RDRSHM=0.09, RDRB=0.09,
    TSUMSBR=780.0, RDRWCUTTING=0.017, LAICR=3.5, LAI_MIN=0.09, TSUMLLIFE=1200.0,
    FRACTLLFENHSH=0.85, DELREDIST=12.0,
    WSOREDISTFRACMAX=0.05, WLVGNEWN=10.0, SO2LV=0.8, RRREDISTSO=0.01,
    FASTRANSLSO=0.45, TSUMRROOTEND=720.0,
    TSUMREDISTMAX=144.0, WCUTTINGMINPRO=0.15, RECOV=0.7, FST_CUTT=0.03,
    FRT_CUTT=0.03, FLV_CUTT=0.07, FSO_CUTT=0.0,
    LUE_OPT=1.5, K_ext=0.67,
    ROOTDM=0.7, RRDMAX=0.012,
    WCAD=0.01, WCWP=0.12, WCFC=0.41, WCWET=0.46, WCST=0.52, TWCSD=1.05,
    FRACRNINTC=0.25,
    TRANCO=8.0, DRATE=50.0, IRRIGF=0.0,
)

FRACSLATB = [0., 0.57, 1440., 0.57, 2880., 0.65, 3864., 1., 4320., 1.]
RDRT = [-10., 0.02, 10., 0.02, 15., 0.03, 30., 0.06, 50., 0.06]
TTB = [-10., 0.0, 15., 0.0, 25., 1., 29., 1., 40., 0., 50., 0.0]
FRTTB = [0., 0.11, 540., 0.100, 720., 0.094, 900., 0.01, 1488., 0.01,
         1980., 0.01, 2676., 0.01, 3864., 0.010, 4320., 0.010]
FLVTB = [0., 0.71, 540., 0.515, 720., 0.393, 900., 0.24, 1488., 0.21,
         1980., 0.18, 2676., 0.13, 3864., 0.210, 4320., 0.210]
FSTTB = [0., 0.18, 540., 0.385, 720., 0.393, 900., 0.26, 1488., 0.26,
         1980., 0.19, 2676., 0.29, 3864., 0.290, 4320., 0.290]
FSOTB = [0., 0.00, 540., 0.000, 720., 0.120, 900., 0.49, 1488., 0.52,
         1980., 0.62, 2676., 0.57, 3864., 0.490, 4320., 0.490]

STTIME, FINTIM, DELT = 113.0, 435.0, 1.0
ROOTDI = 0.1
ZERO = 0.0


# ----------------------------------------------------------------------------
# Weather (CABO format)
# ----------------------------------------------------------------------------
YEARS: dict[str, tuple[dict, dict]] = {}  # folder -> (2013, 2014) days


def read_years(folder):
    if folder not in YEARS:
        YEARS[folder] = (read_cabo(os.path.join(folder, "SVK6.013"))[1],
                         read_cabo(os.path.join(folder, "SVK6.014"))[1])
    return YEARS[folder]


def weather(time, folder):
    w2013, w2014 = read_years(folder)
    day = int(round(time))
    if day <= 365:
        return w2013[day]
    return w2014[day - 365]


# ----------------------------------------------------------------------------
# Subroutines (translated from the Fortran after STOP)
# ----------------------------------------------------------------------------
def GLA(DTEFF, TSUMCROP, LAII, RGRL, DELT, SLA, LAI, GLV, TSUMLA_MIN, TRANRF,
        WC, WCWP, RWCUTTING, FLV, LAIEXPOEND, DORMANCY):
    # Growth during maturation stage
    GLAI = SLA * GLV * (1. - DORMANCY)
    # Growth during juvenile stage
    if (TSUMCROP < TSUMLA_MIN) and (LAI < LAIEXPOEND):
        GLAI = ((LAI * (math.exp(RGRL * DTEFF * DELT) - 1.) / DELT)
                + abs(RWCUTTING) * FLV * SLA) * TRANRF
    # Growth at day of seedling emergence
    if (TSUMCROP > 0.) and (LAI == 0.) and (WC > WCWP):
        GLAI = LAII / DELT
    # Growth before seedling emergence
    if TSUMCROP == 0.:
        GLAI = 0.
    return GLAI


def PENMAN(DAVTMP, VP, DTR, LAI, WN, RNINTC):
    DTRJM2 = DTR * 1.E6
    BOLTZM = 5.668E-8
    LHVAP = 2.4E6
    PSYCH = 0.067
    BBRAD = BOLTZM * (DAVTMP + 273.) ** 4 * 86400.
    SVP = 0.611 * math.exp(17.4 * DAVTMP / (DAVTMP + 239.))
    SLOPE = 4158.6 * SVP / (DAVTMP + 239.) ** 2
    RLWN = BBRAD * max(0., 0.55 * (1. - VP / SVP))
    NRADS = DTRJM2 * (1. - 0.15) - RLWN
    NRADC = DTRJM2 * (1. - 0.25) - RLWN
    PENMRS = NRADS * SLOPE / (SLOPE + PSYCH)
    PENMRC = NRADC * SLOPE / (SLOPE + PSYCH)
    WDF = 2.63 * (1.0 + 0.54 * WN)
    PENMD = LHVAP * WDF * (SVP - VP) * PSYCH / (SLOPE + PSYCH)
    PEVAP = math.exp(-0.5 * LAI) * (PENMRS + PENMD) / LHVAP
    PTRAN = (1. - math.exp(-0.5 * LAI)) * (PENMRC + PENMD) / LHVAP
    PTRAN = max(0., PTRAN - 0.5 * RNINTC)
    return PEVAP, PTRAN


def EVAPTR(PEVAP, PTRAN, ROOTD, WA, WCAD, WCWP, WCFC, WCWET, WCST, TRANCO,
           DELT, WCSD):
    WC = 0.001 * WA / ROOTD
    WAAD = 1000. * WCAD * ROOTD
    # WAFC = 1000. * WCFC * ROOTD   (computed but unused in the Fortran)
    EVAP = PEVAP * LIMIT(0., 1., (WC - WCAD) / (WCFC - WCAD))
    WCCR = WCWP + max(WCSD - WCWP, PTRAN / (PTRAN + TRANCO) * (WCFC - WCWP))
    if WC > WCCR:
        FR = LIMIT(0., 1., (WCST - WC) / (WCST - WCWET))
    else:
        FR = LIMIT(0., 1., (WC - WCWP) / (WCCR - WCWP))
    TRAN = PTRAN * FR
    AVAILF = min(1., ((WA - WAAD) / DELT) / NOTNUL(EVAP + TRAN))
    EVAP = EVAP * AVAILF
    TRAN = TRAN * AVAILF
    return WCCR, EVAP, TRAN


def DRUNIR(RAIN, RNINTC, EVAP, TRAN, IRRIGF, DRATE, DELT, WA, ROOTD, WCFC,
           WCST):
    WAFC = 1000. * WCFC * ROOTD
    WAST = 1000. * WCST * ROOTD
    DRAIN = LIMIT(0., DRATE, (WA - WAFC) / DELT + (RAIN - RNINTC - EVAP - TRAN))
    RUNOFF = max(0., (WA - WAST) / DELT
                 + (RAIN - RNINTC - EVAP - TRAN - DRAIN))
    IRRIG = IRRIGF * max(0., (WAFC - WA) / DELT
                         - (RAIN - RNINTC - EVAP - TRAN - DRAIN - RUNOFF))
    return DRAIN, RUNOFF, IRRIG


# ----------------------------------------------------------------------------
# State variables: name -> (initial value, name of its rate)
# ----------------------------------------------------------------------------
STATE_RATE = [
    ("CUMEVP", "TOTEVP"), ("CUMEVA", "TOTEVA"), ("CUMUL_EVAP", "EVAP"),
    ("CUMUL_TRAN", "TRAN"), ("TRAIN", "RAIN"), ("TDTR", "DTR"),
    ("TSUM", "RTSUM"), ("TSUMCROP", "RTSUMCROP"), ("EMERGTSUM", "REMERGTSUM"),
    ("WCUTTING", "RWCUTTING"), ("TSUMCROPLEAFAGE", "RTSUMCROPLEAFAGE"),
    ("LAI", "RLAI"), ("CUMUL_PARINT", "PARINT"),
    ("WLVG", "RWLVG"), ("WLVD", "DLV"), ("WST", "RWST"), ("WSO", "RWSO"),
    ("WSOFASTRANSLSO", "RWSOFASTRANSLSO"), ("WRT", "RWRT"),
    ("ROOTD", "RROOTD"), ("WA", "RWA"),
    ("DORMTSUM", "RDORMTSUM"), ("DURDORM", "RDORMTIME"),
    ("PUSHDORMRECTSUM", "RPUSHDORMRECTSUM"),
    ("PUSHREDISTSUM", "RPUSHREDISTSUM"),
    ("PUSHREDISTENDTSUM", "RPUSHREDISTENDTSUM"),
    ("WSOREDISTCUMUL", "RREDISTSO"), ("WLVGREDISTCUMUL", "RREDISTLVG"),
    ("REDISTMAINTLOSSCUMUL", "RREDISTMAINTLOSS"),
]


def initial(p):
    """INITIAL section / INCON: initial values of the states."""
    WCUTTINGIP = p["WCUTTINGUNIT"] * p["NCUTTINGS"]
    WLVI = WCUTTINGIP * p["FLV_CUTT"]
    LAII = WLVI * p["SLAI"]
    WAI = 1000. * ROOTDI * p["WCI"]
    s = {name: ZERO for name, _ in STATE_RATE}
    s["WCUTTING"] = WCUTTINGIP
    s["ROOTD"] = ROOTDI
    s["WA"] = WAI
    const = dict(WCUTTINGIP=WCUTTINGIP, WLVI=WLVI, LAII=LAII, WAI=WAI)
    return s, const


# ----------------------------------------------------------------------------
# All algebraic variables and rates, in dependency order
# ----------------------------------------------------------------------------
def compute(TIME, s, EMERG, p, c, folder):
    v = dict(s)           # states
    v["TIME"] = TIME
    v["EMERG"] = EMERG
    P = p
    # states as locals
    TSUM = s["TSUM"]
    TSUMCROP = s["TSUMCROP"]
    WCUTTING = s["WCUTTING"]
    TSUMCROPLEAFAGE = s["TSUMCROPLEAFAGE"]
    LAI = s["LAI"]
    WLVG = s["WLVG"]
    WLVD = s["WLVD"]
    WST = s["WST"]
    WSO = s["WSO"]
    WRT = s["WRT"]
    ROOTD = s["ROOTD"]
    WA = s["WA"]
    DORMTSUM = s["DORMTSUM"]
    PUSHDORMRECTSUM = s["PUSHDORMRECTSUM"]
    PUSHREDISTSUM = s["PUSHREDISTSUM"]
    PUSHREDISTENDTSUM = s["PUSHREDISTENDTSUM"]
    WSOREDISTCUMUL = s["WSOREDISTCUMUL"]
    WLVGREDISTCUMUL = s["WLVGREDISTCUMUL"]
    CUMEVA = s["CUMEVA"]

    # --- weather and temperature sums
    w = weather(TIME, folder)
    RDD, TMMN, TMMX, VP, WN, RAIN = (w["RDD"], w["TMMN"], w["TMMX"], w["VP"],
                                     w["WN"], w["RAIN"])
    DTR = RDD / 1.E+6
    DAVTMP = 0.5 * (TMMN + TMMX)
    DTEFF = max(0., DAVTMP - P["TBASE"])
    RTSUM = DTEFF * INSW(TIME - P["DOYPL"], 0., 1.)
    RTSUMCROP = DTEFF * EMERG
    REMERGTSUM = DTEFF * INSW(EMERG - 1., 1., 0.) * INSW(TIME - P["DOYPL"], 0., 1.)
    DAP = TIME - P["DOYPL"]

    # --- soil water content
    WC = 0.001 * WA / ROOTD
    WCSD = P["WCWP"] * P["TWCSD"]

    # --- biomass aggregates
    WLV = WLVG + WLVD
    WTOPS = WLV + WST + WCUTTING
    WTOPSGREEN = WLVG + WST + WCUTTING
    WGTOTALHARV = WTOPSGREEN + WSO
    WGTOTAL = WTOPS + WSO + WRT
    HI = WSO / NOTNUL(WGTOTALHARV)
    WP = WSO / NOTNUL(CUMEVA)

    # --- cutting, SLA
    WCUTTINGMIN = P["WCUTTINGMINPRO"] * c["WCUTTINGIP"]
    FRACSLACROPAGE = AFGEN(FRACSLATB, TSUMCROP)
    SLA = P["SLA_MAX"] * FRACSLACROPAGE

    # --- water balance: interception, Penman, evap/transp, drainage
    RNINTC = min(RAIN, P["FRACRNINTC"] * LAI)
    PEVAP, PTRAN = PENMAN(DAVTMP, VP, DTR, LAI, WN, RNINTC)
    WCCR, EVAP, TRAN = EVAPTR(PEVAP, PTRAN, ROOTD, WA, P["WCAD"], P["WCWP"],
                              P["WCFC"], P["WCWET"], P["WCST"], P["TRANCO"],
                              DELT, WCSD)
    TRANRF = TRAN / NOTNUL(PTRAN)
    DRAIN, RUNOFF, IRRIG = DRUNIR(RAIN, RNINTC, EVAP, TRAN, P["IRRIGF"],
                                  P["DRATE"], DELT, WA, ROOTD, P["WCFC"],
                                  P["WCST"])

    # --- dormancy / redistribution switches
    WSOREDISTFRAC = WSOREDISTCUMUL / NOTNUL(WSO)
    PUSHREDISTEND = (max(INSW(WSOREDISTFRAC - P["WSOREDISTFRACMAX"], 0., 1.),
                         INSW(WLVGREDISTCUMUL - P["WLVGNEWN"], 0., 1.),
                         INSW(PUSHREDISTSUM - P["TSUMREDISTMAX"], 0., 1.))
                     * INSW(-PUSHREDISTSUM, 1., 0.))
    PUSHREDIST = INSW(PUSHDORMRECTSUM - P["DELREDIST"], 0., 1.) * (1. - PUSHREDISTEND)
    PUSHDORMREC = (REAAND(WC - P["RECOV"] * WCCR, WC - P["WCWP"])
                   * INSW(-DORMTSUM, 1., 0.) * (1. - PUSHREDIST)
                   * INSW(TSUMCROP - P["TSUMSBR"], 0., 1.))
    DORMANCY = (max(REANOR(WC - WCSD, LAI - P["LAI_MIN"]), PUSHDORMREC)
                * (1. - PUSHREDIST) * INSW(TSUMCROP - P["TSUMSBR"], 0., 1.))

    # --- stem cutting decline
    RWCUTTING = (-P["RDRWCUTTING"] * WCUTTING
                 * INSW(WCUTTING - WCUTTINGMIN, 0., 1.) * TRANRF * EMERG
                 * (1. - DORMANCY))

    # --- leaf death
    ENHSHED = (max(INSW(WC - WCSD, 1., 0.), INSW(WC - P["WCWET"], 0., 1.))
               * INSW(TSUMCROPLEAFAGE - P["FRACTLLFENHSH"] * P["TSUMLLIFE"], 0., 1.))
    RDRSD = P["RDRB"] * ENHSHED
    RDRDV = INSW(TSUMCROPLEAFAGE - P["TSUMLLIFE"], 0., AFGEN(RDRT, DAVTMP))
    RDRSH = LIMIT(0., P["RDRSHM"], P["RDRSHM"] * (LAI - P["LAICR"]) / P["LAICR"])
    RDR = max(RDRDV, RDRSH, RDRSD) * INSW(TSUMCROPLEAFAGE - P["TSUMLLIFE"], 0., 1.)
    RWSOFASTRANSLSO = WLVG * RDR * P["FASTRANSLSO"] * (1. - DORMANCY)
    DLV = (WLVG * RDR - RWSOFASTRANSLSO) * (1. - DORMANCY)
    DLAI = LAI * RDR * (1. - P["FASTRANSLSO"]) * (1. - DORMANCY)
    RTSUMCROPLEAFAGE = DTEFF * EMERG - (TSUMCROPLEAFAGE / DELT) * PUSHREDIST

    # --- light interception and growth
    PARINT = 0.5 * DTR * (1. - math.exp(-P["K_ext"] * LAI))
    LUE = P["LUE_OPT"] * AFGEN(TTB, DAVTMP)
    GTOTAL = LUE * PARINT * TRANRF * (1. - DORMANCY)

    # --- partitioning
    FRTWET = AFGEN(FRTTB, TSUMCROP)
    FRTMOD = max(1., 1. / (TRANRF + 0.5))
    FRT = FRTWET * FRTMOD
    FSHMOD = (1. - FRT) / (1. - FRT / FRTMOD)
    FLV = AFGEN(FLVTB, TSUMCROP) * FSHMOD
    FST = AFGEN(FSTTB, TSUMCROP) * FSHMOD
    FSO = AFGEN(FSOTB, TSUMCROP) * FSHMOD
    FTOT = FRT + FLV + FST + FSO

    # --- redistribution from storage roots
    RREDISTSO = (P["RRREDISTSO"] * WSO * PUSHREDIST
                 - WSOREDISTCUMUL / DELT * INSW(-DORMTSUM, 1., 0.))
    RREDISTLVG = P["SO2LV"] * RREDISTSO * (1. - DORMANCY)
    RREDISTMAINTLOSS = (1. - P["SO2LV"]) * RREDISTSO

    # --- leaf area
    GLV = FLV * (GTOTAL + abs(RWCUTTING)) + RREDISTLVG * PUSHREDIST
    GLAI = GLA(DTEFF, TSUMCROP, c["LAII"], P["RGRL"], DELT, SLA, LAI, GLV,
               P["TSUMLA_MIN"], TRANRF, WC, P["WCWP"], RWCUTTING, FLV,
               P["LAIEXPOEND"], DORMANCY)
    RLAI = GLAI - DLAI

    # --- organ growth rates
    GSUP = GTOTAL + abs(RWCUTTING)
    RWST = GSUP * FST
    RWLVG = GSUP * FLV - DLV + RREDISTLVG * PUSHREDIST
    RWRT = GSUP * FRT
    RWSO = GSUP * FSO + RWSOFASTRANSLSO - RREDISTSO

    # --- roots and soil water
    RROOTD = (P["RRDMAX"] * INSW(WC - P["WCWP"], 0., 1.)
              * INSW(ROOTD - P["ROOTDM"], 1., 0.) * EMERG)
    EXPLOR = 1000. * RROOTD * P["WCFC"]
    RWA = (RAIN + EXPLOR + IRRIG) - (RNINTC + RUNOFF + TRAN + EVAP + DRAIN)

    # --- dormancy bookkeeping rates
    RDORMTSUM = DTEFF * DORMANCY - (DORMTSUM / DELT) * PUSHREDIST
    RDORMTIME = DORMANCY
    RPUSHDORMRECTSUM = (DTEFF * PUSHDORMREC - (PUSHDORMRECTSUM / DELT)
                        * (1. - PUSHDORMREC) * (1. - PUSHREDIST))
    RPUSHREDISTSUM = DTEFF * PUSHREDIST - (PUSHREDISTSUM / DELT) * PUSHREDISTEND
    RPUSHREDISTENDTSUM = (DTEFF * PUSHREDIST - (PUSHREDISTENDTSUM / DELT)
                          * (1. - PUSHREDISTEND))

    # --- cumulative evapotranspiration rates
    TOTEVP = PEVAP + PTRAN
    TOTEVA = EVAP + TRAN

    # --- emergence condition (ZEROCONDITION of the EVENT)
    EMERGFAVOURABLE = (REAAND(TSUM - P["OPTEMERGTSUM"], WC - P["WCWP"])
                       * INSW(-WST, 0., 1.))
    ZCOND = 1. - EMERGFAVOURABLE

    loc = dict(locals())
    for k in ("v", "s", "P", "p", "c", "w", "loc"):
        loc.pop(k, None)
    v.update(loc)
    return v


# ----------------------------------------------------------------------------
# Driver
# ----------------------------------------------------------------------------
OUTCOLS = ["TIME", "DAP", "TSUM", "TSUMCROP", "EMERG", "LAI", "WLVG", "WLVD",
           "WST", "WSO", "WRT", "WCUTTING", "WGTOTAL", "TRANRF", "DORMANCY",
           "PTRAN", "TRAIN", "DAVTMP", "WA", "WC", "ROOTD", "PUSHREDIST",
           "PUSHDORMREC", "CUMEVA"]


def run(irrigf, folder):
    p = dict(BASE_PARAMS)
    p["IRRIGF"] = irrigf
    s, c = initial(p)
    EMERG = 0.0                         # SET EMERG = 0.
    rows = []
    event_times = []
    zprev = None
    # integrals for a mass balance check
    cum_src = 0.0   # GTOTAL + RWSOFASTRANSLSO + RREDISTLVG*PUSHREDIST - RREDISTSO
    nsteps = int(round((FINTIM - STTIME) / DELT))
    for i in range(nsteps + 1):
        TIME = STTIME + i * DELT
        v = compute(TIME, s, EMERG, p, c, folder)
        if zprev is not None:
            z = v["ZCOND"]
            if (zprev > 0. and z <= 0.) or (zprev < 0. and z >= 0.):
                # EVENT: NEWVALUEs in written order
                EMERG = 1.
                s["WCUTTING"] = s["WCUTTING"] * (1. - p["FST_CUTT"] - p["FRT_CUTT"]
                                                 - p["FLV_CUTT"] - p["FSO_CUTT"])
                s["WST"] = s["WST"] + c["WCUTTINGIP"] * p["FST_CUTT"]
                s["WRT"] = s["WRT"] + c["WCUTTINGIP"] * p["FRT_CUTT"]
                s["WLVG"] = s["WLVG"] + c["WCUTTINGIP"] * p["FLV_CUTT"]
                s["WSO"] = s["WSO"] + c["WCUTTINGIP"] * p["FSO_CUTT"]
                event_times.append((TIME, v["TSUM"], v["WC"]))
                v = compute(TIME, s, EMERG, p, c, folder)
        zprev = v["ZCOND"]

        # --- self checks
        tot = v["WLV"] + v["WST"] + v["WCUTTING"] + v["WSO"] + v["WRT"]
        assert abs(v["WGTOTAL"] - tot) <= 1e-12 * max(1., abs(tot))
        assert abs(v["FTOT"] - 1.) < 1e-12, v["FTOT"]
        expected = c["WCUTTINGIP"] + cum_src
        assert abs(v["WGTOTAL"] - expected) <= 1e-9 * max(1., expected), \
            (TIME, v["WGTOTAL"], expected)

        rows.append([v[k] for k in OUTCOLS])
        if v["TSUM"] > 4320.:           # FINISH TSUM > 4320.
            break
        # --- Euler step
        cum_src += DELT * (v["GTOTAL"] + v["RWSOFASTRANSLSO"]
                           + v["RREDISTLVG"] * v["PUSHREDIST"] - v["RREDISTSO"])
        for name, rate in STATE_RATE:
            s[name] = s[name] + DELT * v[rate]
    return rows, event_times


def emergence_check(rows, ev):
    """Emergence should be at the first time point where TSUM > OPTEMERGTSUM and
    WC > WCWP (EMERG is 0 before and 1 from then on)."""
    idx = {k: i for i, k in enumerate(OUTCOLS)}
    first = None
    for r in rows:
        if r[idx["TSUM"]] > BASE_PARAMS["OPTEMERGTSUM"] and r[idx["WC"]] > BASE_PARAMS["WCWP"]:
            first = r[idx["TIME"]]
            break
    assert len(ev) == 1 and ev[0][0] == first, (ev, first)
    for r in rows:
        assert r[idx["EMERG"]] == (1. if r[idx["TIME"]] >= first else 0.)
    # the row before: was TSUM <= 180 or WC <= WCWP
    return first
