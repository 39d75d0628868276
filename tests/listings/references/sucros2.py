"""(Written by a session that read only the listing and its weather file, never
amilpy.) Independent numerical reference for SUCROS2 (SUCROS97 V1.0, s97-2.fst).

Spring wheat, water-limited production with a four-layer soil water
balance (Goudriaan & van Laar).  Plain Python (math only), double precision.

FSE semantics (DRIVER='EUDRIV'): Euler integration with DELT = 1 d,
time points t = STTIME, STTIME+DELT, ... up to FINTIM.  At each time point
all variables are computed from the states at t and the weather of day
int(t); the row is written; the FINISH conditions are tested in the order
written in the listing (ERRSH > 1E-6, then DVS > 2); then the Euler step
state(t+DELT) = state(t) + DELT*rate(t) is taken.
"""
import math
import os

from .cabo import read_cabo
from .sucros_routines import GLA, SUBEAI, TOTASS, FortranStop
from .ttutil import AFGEN, INSW, LIMIT, NOTNUL

# ---------------------------------------------------------------------------
# Parameters, INCONs and FUNCTION tables (as in the listing)
# ---------------------------------------------------------------------------
STTIME, FINTIM, DELT, PRDEL = 80.0, 300.0, 1.0, 5.0

ZERO = 0.0
DOYEM = 90.0
WLVI, WSTI, WRTI = 0.5, 0.3, 0.8
WLVDI, WSOI, ILAI = 0.0, 0.0, 0.012
IDVS, IEAI = 0.0, 0.0
ZRTI = 5.0
WCLI1 = WCLI2 = WCLI3 = WCLI4 = 0.2
TKL1, TKL2, TKL3, TKL4 = 200.0, 400.0, 600.0, 800.0
IDSLR = 1.0
MDRATE = 50.0
ZRTMS = 1200.0
ZRTMC = 1200.0

AMX = 1.11E-3
EFF = 12.5E-6
KDF = 0.60
SCP = 0.20
Q10, TREF = 2.0, 25.0
MAINLV, MAINST = 0.03, 0.015
MAINRT, MAINSO = 0.015, 0.01
ASRQRT, ASRQLV = 1.444, 1.463
ASRQST, ASRQSO = 1.513, 1.415
FRTRL, CONVL = 0.20, 0.947
RGRL = 0.009
SLA = 0.022
EAR = 0.63E-3
LAICR, FRDR = 4.0, 1.0
TBASE = 0.0
LHVAP = 2.4E6
PSYCH = 0.067
BOLTZM = 5.668E-8
A, B = 0.25, 0.45          # PARAMETER A, B of the listing (CLEAR)
INTC = 0.25
WCFC1 = WCFC2 = WCFC3 = WCFC4 = 0.23
WCST1 = WCST2 = WCST3 = WCST4 = 0.40
EZRTC = 12.0
WCAD1 = WCAD2 = WCAD3 = WCAD4 = 0.025
EES = 0.002
TRANSC = 9.0
WCWET1 = WCWET2 = WCWET3 = WCWET4 = 0.35
WCWP1 = WCWP2 = WCWP3 = WCWP4 = 0.075
CFLV, CFST, CFRT, CFSO = 0.459, 0.494, 0.467, 0.471

DVRVT = (-10., 0., 0., 0., 30., 0.027)
DVRRT = (-10., 0., 0., 0., 30., 0.031)
AMDVST = (0.0, 1.0, 1.0, 1.0, 2.0, 0.5, 2.5, 0.0)
AMTMPT = (-10., 0., 0., 0., 10., 1., 25., 1., 35., 0., 50., 0.)
FSHTB = (0.00, 0.50, 0.10, 0.50, 0.20, 0.60, 0.35, 0.78,
         0.40, 0.83, 0.50, 0.87, 0.60, 0.90, 0.70, 0.93,
         0.80, 0.95, 0.90, 0.97, 1.00, 0.98, 1.10, 0.99,
         1.20, 1.00, 2.50, 1.00)
FLVTB = (0.00, 0.65, 0.10, 0.65, 0.25, 0.70, 0.50, 0.50,
         0.70, 0.15, 0.95, 0.00, 2.50, 0.00)
FSTTB = (0.00, 0.35, 0.10, 0.35, 0.25, 0.30, 0.50, 0.50,
         0.70, 0.85, 0.95, 1.00, 1.05, 0.00, 2.50, 0.00)
FSOTB = (0.00, 0.00, 0.95, 0.00, 1.05, 1.00, 2.50, 1.00)
EDPTFT = (-.50, 0., -.05, 0., 0., .15, .15, .6,
          .3, .8, .5, 1., 2., 1.)

# INITIAL section
WL1I = WCLI1 * TKL1
WL2I = WCLI2 * TKL2
WL3I = WCLI3 * TKL3
WL4I = WCLI4 * TKL4
TKLT = TKL1 + TKL2 + TKL3 + TKL4
WCUMI = WL1I + WL2I + WL3I + WL4I
ZRTM = min(ZRTMC, ZRTMS, TKLT)
TNASSI = (WLVI * CFLV + WSTI * CFST + WRTI * CFRT) * 44. / 12.

# ---------------------------------------------------------------------------
# Fortran subroutines (translated)
# ---------------------------------------------------------------------------


def SUBGRT(ZRT, ZRTM, DVS, TKL1, TKL2, TKL3, TKL4, WCL1, WCL2,
           WCL3, WCL4, WCWP1, WCWP2, WCWP3, WCWP4):
    WSERT = 1.
    if ZRT < TKL1 and WCL1 < WCWP1:
        WSERT = 0.
    if ZRT > TKL1 and ZRT < (TKL1 + TKL2) and WCL2 < WCWP2:
        WSERT = 0.
    if ZRT > (TKL1 + TKL2) and ZRT < (TKL1 + TKL2 + TKL3) and WCL3 < WCWP3:
        WSERT = 0.
    if (ZRT > (TKL1 + TKL2 + TKL3) and ZRT < (TKL1 + TKL2 + TKL3 + TKL4)
            and WCL4 < WCWP4):
        WSERT = 0.
    if DVS >= 1.:
        WSERT = 0.
    if ZRT > ZRTM:
        WSERT = 0.
    return WSERT


def SUBFR(WCL, WCFC, P, WCWP, WCWET, WCST):
    WCCR = WCWP + (1. - P) * (WCFC - WCWP)
    if WCL > WCWET:
        FR = (WCST - WCL) / (WCST - WCWET)
    elif WCL <= WCWET and WCL > WCCR:
        FR = 1.
    elif WCL <= WCCR and WCL > WCWP:
        FR = (WCL - WCWP) / (WCCR - WCWP)
    else:
        FR = 0.
    return min(1., max(0., FR))


# ---------------------------------------------------------------------------
# Weather (CABO format)
# ---------------------------------------------------------------------------
ISTN = 1
IYEAR = 1990


def read_weather(folder):
    header, days = read_cabo(os.path.join(folder, f'NLD{ISTN}.{str(IYEAR)[1:]}'))
    return dict(LONG=header[0], LAT=header[1], ELEV=header[2], days=days)


# ---------------------------------------------------------------------------
# Model
# ---------------------------------------------------------------------------
STATE_NAMES = ['DVS', 'LAI', 'EAI', 'WRT', 'WLVG', 'WLVD', 'WST', 'WSO',
               'TRAIN', 'TPENM', 'TEVAPR', 'TEVAPD',
               'WL1', 'WL2', 'WL3', 'WL4', 'TDRAIN', 'TAINTC', 'TRNOFF',
               'ZRT', 'TPTRAN', 'TATRAN', 'DSLR', 'TPEVAP', 'TAEVAP',
               'TDTGA', 'TNASS']

# state -> its rate variable
RATE_OF = {'DVS': 'DVR', 'LAI': 'RLAI', 'EAI': 'REAI', 'WRT': 'GRT',
           'WLVG': 'RWLVG', 'WLVD': 'DLV', 'WST': 'GST', 'WSO': 'GSO',
           'TRAIN': 'RRAIN', 'TPENM': 'PENMAN', 'TEVAPR': 'EVAPR',
           'TEVAPD': 'EVAPD', 'WL1': 'RWL1', 'WL2': 'RWL2', 'WL3': 'RWL3',
           'WL4': 'RWL4', 'TDRAIN': 'DRAIN', 'TAINTC': 'AINTC',
           'TRNOFF': 'RNOFF', 'ZRT': 'EZRT', 'TPTRAN': 'PTRANS',
           'TATRAN': 'ATRANS', 'DSLR': 'RDSLR', 'TPEVAP': 'PEVAP',
           'TAEVAP': 'AEVAP', 'TDTGA': 'DTGA', 'TNASS': 'RTNASS'}

PRINT_NAMES = ['DOY', 'DVS', 'DAYL', 'TDRW', 'TADRW', 'WLVG', 'WLVD', 'WLV',
               'WST', 'WSO', 'WRT', 'LAI', 'EAI', 'HI', 'WL1', 'WL2', 'WL3',
               'WL4', 'TPENM', 'TEVAPR', 'TEVAPD', 'TRAIN', 'TAINTC',
               'TRNOFF', 'TDRAIN', 'TPTRAN', 'TATRAN', 'TPEVAP', 'TAEVAP',
               'CHECK', 'TAR', 'EVAPR', 'EVAPD', 'CROPF', 'WSE1', 'WSE2',
               'WSE3', 'WSE4', 'PCEW', 'CPEW', 'ZRT', 'ERLB', 'WCUM',
               'RWCL1', 'RWCL2', 'RWCL3', 'RWCL4', 'CHKDIF', 'P']


def initial_states():
    return {'DVS': IDVS, 'LAI': ILAI, 'EAI': IEAI, 'WRT': WRTI,
            'WLVG': WLVI, 'WLVD': WLVDI, 'WST': WSTI, 'WSO': WSOI,
            'TRAIN': ZERO, 'TPENM': ZERO, 'TEVAPR': ZERO, 'TEVAPD': ZERO,
            'WL1': WL1I, 'WL2': WL2I, 'WL3': WL3I, 'WL4': WL4I,
            'TDRAIN': ZERO, 'TAINTC': ZERO, 'TRNOFF': ZERO,
            'ZRT': ZRTI, 'TPTRAN': ZERO, 'TATRAN': ZERO, 'DSLR': IDSLR,
            'TPEVAP': ZERO, 'TAEVAP': ZERO, 'TDTGA': ZERO, 'TNASS': TNASSI}


def div(a, b):
    """Plain division; IEEE result instead of an exception on b == 0."""
    if b == 0.0:
        return math.nan if a == 0.0 else math.copysign(math.inf, a)
    return a / b


def compute(TIME, s, wth):
    """All auxiliary variables and rates from the states s at time TIME,
    in dependency order.  Returns a dict of every variable."""
    v = dict(s)
    DVS, LAI, EAI = s['DVS'], s['LAI'], s['EAI']
    WRT, WLVG, WLVD, WST, WSO = s['WRT'], s['WLVG'], s['WLVD'], s['WST'], s['WSO']
    WL1, WL2, WL3, WL4 = s['WL1'], s['WL2'], s['WL3'], s['WL4']
    ZRT, DSLR, TNASS = s['ZRT'], s['DSLR'], s['TNASS']

    # 2.12 weather
    DOY = float(int(TIME))
    w = wth['days'][int(DOY)]
    LAT = wth['LAT']
    RDD, TMMN, TMMX, VP, WN, RAIN = (w['RDD'], w['TMMN'], w['TMMX'],
                                     w['VP'], w['WN'], w['RAIN'])
    DTR = RDD
    DAVTMP = 0.5 * (TMMX + TMMN)
    DDTMP = TMMX - 0.25 * (TMMX - TMMN)
    DTEFF = max(0., DAVTMP - TBASE)
    AVP = VP
    WDS = WN
    RRAIN = RAIN

    # 2.3 development
    EMERG = INSW(TIME - DOYEM, 0., 1.)
    DVR = INSW(DVS - 1., AFGEN(DVRVT, DAVTMP), AFGEN(DVRRT, DAVTMP)) * EMERG

    # 2.4 leaf CO2 assimilation
    AMDVS = AFGEN(AMDVST, DVS)
    AMTMP = AFGEN(AMTMPT, DDTMP)
    AMAX = AMX * AMDVS * AMTMP * EMERG

    # 2.11 totals from states
    WLV = WLVG + WLVD
    TADRW = WLV + WST + WSO
    TDRW = TADRW + WRT
    HI = WSO / NOTNUL(TADRW)

    # 2.10 / 2.5 daily gross assimilation
    TAI = 0.5 * EAI + LAI
    DAYL, DTGA, DS0 = TOTASS(DOY, LAT, DTR, SCP, AMAX, EFF, KDF, TAI)

    # soil water contents (from states)
    WCL1 = WL1 / TKL1
    WCL2 = WL2 / TKL2
    WCL3 = WL3 / TKL3
    WCL4 = WL4 / TKL4
    RWCL1 = (WCL1 - WCWP1) / (WCFC1 - WCWP1)
    RWCL2 = (WCL2 - WCWP2) / (WCFC2 - WCWP2)
    RWCL3 = (WCL3 - WCWP3) / (WCFC3 - WCWP3)
    RWCL4 = (WCL4 - WCWP4) / (WCFC4 - WCWP4)

    # 2.13 Penman-Monteith
    SVP = 0.611 * math.exp(17.4 * DAVTMP / (DAVTMP + 239.))
    SLOPE = 4158.6 * SVP / (DAVTMP + 239.) ** 2
    ALBS = 0.25 * (1. - 0.5 * WCL1 / WCST1)
    ALB = ALBS * math.exp(-0.5 * LAI) + 0.25 * (1. - math.exp(-0.5 * LAI))
    BBRAD = BOLTZM * (DAVTMP + 273.) ** 4
    FVAP = 0.56 - 0.079 * math.sqrt(AVP * 10.)
    CLEAR = LIMIT(0., 1., ((DTR / DS0) - A) / B)
    FCLEAR = 0.1 + 0.9 * CLEAR
    RLWN = BBRAD * FVAP * FCLEAR * 86400.
    NRAD = (1. - ALB) * DTR - RLWN
    EVAPR = (1. / LHVAP) * (SLOPE / (SLOPE + PSYCH)) * NRAD
    WDF = 2.63 * (1.0 + 0.54 * WDS) * PSYCH
    DRYP = (SVP - AVP) * WDF
    EVAPD = DRYP / (SLOPE + PSYCH)
    PENMAN = EVAPR + EVAPD

    # 2.14 soil water balance: fluxes
    AINTC = min(RRAIN, INTC * LAI)
    RNOFF = max(0., 0.15 * (RRAIN - AINTC - 10.),
                RRAIN - AINTC - (WCST1 * TKL1 - WL1) / (2. * DELT))
    WLFL1 = RRAIN - AINTC - RNOFF
    WLFL2 = max(0., min(WL1 - WCFC1 * TKL1, WCST2 * TKL2 - WL2) / (2. * DELT))
    WLFL3 = max(0., min(WL2 - WCFC2 * TKL2, WCST3 * TKL3 - WL3) / (2. * DELT))
    WLFL4 = max(0., min(WL3 - WCFC3 * TKL3, WCST4 * TKL4 - WL4) / (2. * DELT))
    WLFL5 = max(0., min((WL4 - WCFC4 * TKL4) / (2. * DELT), MDRATE))
    DRAIN = WLFL5

    # 2.16 transpiration
    ZRT1 = LIMIT(0., TKL1, ZRT)
    ZRT2 = LIMIT(0., TKL2, ZRT - TKL1)
    ZRT3 = LIMIT(0., TKL3, ZRT - TKL1 - TKL2)
    ZRT4 = LIMIT(0., TKL4, ZRT - TKL1 - TKL2 - TKL3)
    PTRANS = ((1. - math.exp(-0.5 * LAI)) * EVAPR + EVAPD * min(2.0, LAI)
              - 0.5 * AINTC)
    ED1 = AFGEN(EDPTFT, RWCL1)
    ED2 = AFGEN(EDPTFT, RWCL2)
    ED3 = AFGEN(EDPTFT, RWCL3)
    ED4 = AFGEN(EDPTFT, RWCL4)
    ERLB = ZRT1 * ED1 + ZRT2 * ED2 + ZRT3 * ED3 + ZRT4 * ED4
    TRRM = PTRANS / NOTNUL(ERLB)

    # 2.18 water stress factors
    P = div(TRANSC, TRANSC + PTRANS)
    WSE1 = SUBFR(WCL1, WCFC1, P, WCWP1, WCWET1, WCST1)
    WSE2 = SUBFR(WCL2, WCFC2, P, WCWP2, WCWET2, WCST2)
    WSE3 = SUBFR(WCL3, WCFC3, P, WCWP3, WCWET3, WCST3)
    WSE4 = SUBFR(WCL4, WCFC4, P, WCWP4, WCWET4, WCST4)

    TRWL1 = TRRM * WSE1 * ZRT1 * ED1
    TRWL2 = TRRM * WSE2 * ZRT2 * ED2
    TRWL3 = TRRM * WSE3 * ZRT3 * ED3
    TRWL4 = TRRM * WSE4 * ZRT4 * ED4
    ATRANS = TRWL1 + TRWL2 + TRWL3 + TRWL4

    PCEW = ATRANS / NOTNUL(PTRANS)
    CPEW = min(1., 0.5 + ATRANS / NOTNUL(PTRANS))

    # 2.17 evaporation
    PEVAP = math.exp(-0.5 * LAI) * (EVAPR + EVAPD)
    RDSLR = INSW(RRAIN - 0.5, 1., -(DSLR - 1.) / DELT)
    EVSH = min(PEVAP, (WL1 - WCAD1 * TKL1) / DELT + WLFL1)
    EVSD = min(PEVAP, 0.6 * PEVAP * (math.sqrt(DSLR + 1.) - math.sqrt(DSLR))
               + WLFL1)
    AEVAP = INSW(RRAIN - 0.5, EVSD, EVSH)
    FEVL1 = max(WL1 - WCAD1 * TKL1, 0.1) * math.exp(-EES * (0.5 * TKL1))
    FEVL2 = max(WL2 - WCAD2 * TKL2, 0.1) * math.exp(-EES * (TKL1 + (0.5 * TKL2)))
    FEVL3 = max(WL3 - WCAD3 * TKL3, 0.1) * math.exp(
        -EES * (TKL1 + TKL2 + (0.5 * TKL3)))
    FEVL4 = max(WL4 - WCAD4 * TKL4, 0.1) * math.exp(
        -EES * (TKL1 + TKL2 + TKL3 + (0.5 * TKL4)))
    FEVLT = FEVL1 + FEVL2 + FEVL3 + FEVL4
    EVSW1 = AEVAP * (FEVL1 / FEVLT)
    EVSW2 = AEVAP * (FEVL2 / FEVLT)
    EVSW3 = AEVAP * (FEVL3 / FEVLT)
    EVSW4 = AEVAP * (FEVL4 / FEVLT)

    # 2.14 soil water balance: rates
    RWL1 = WLFL1 - WLFL2 - EVSW1 - TRWL1
    RWL2 = WLFL2 - WLFL3 - EVSW2 - TRWL2
    RWL3 = WLFL3 - WLFL4 - EVSW3 - TRWL3
    RWL4 = WLFL4 - WLFL5 - EVSW4 - TRWL4

    # 2.15 rooted depth
    WSERT = SUBGRT(ZRT, ZRTM, DVS, TKL1, TKL2, TKL3, TKL4, WCL1, WCL2,
                   WCL3, WCL4, WCWP1, WCWP2, WCWP3, WCWP4)
    EZRT = EZRTC * WSERT * AMTMP

    # 2.6 carbohydrate production
    GPHOT = DTGA * PCEW * 30. / 44.

    # 2.7 maintenance respiration
    MNDVS = WLVG / NOTNUL(WLV)
    TEFF = Q10 ** ((DAVTMP - TREF) / 10.)
    MAINTS = MAINLV * WLVG + MAINST * WST + MAINRT * WRT + MAINSO * WSO
    MAINT = MAINTS * TEFF * MNDVS * EMERG

    # 2.8 partitioning
    FSHP = AFGEN(FSHTB, DVS)
    FSH = (FSHP * CPEW) / (1. + (CPEW - 1.) * FSHP)
    FRT = 1. - FSH
    FLV = AFGEN(FLVTB, DVS)
    FST = AFGEN(FSTTB, DVS)
    FSO = AFGEN(FSOTB, DVS)
    ERRSH = abs(FLV + FST + FSO - 1.)

    # 2.9 growth of organs, translocation
    ASRQ = FSH * (ASRQLV * FLV + ASRQST * FST + ASRQSO * FSO) + ASRQRT * FRT
    TRANSL = INSW(DVS - 1., 0., WST * DVR * FRTRL)
    GTW = (GPHOT - MAINT + CONVL * TRANSL * CFST * 30. / 12.) / ASRQ
    GRT = FRT * GTW
    GLV = FLV * FSH * GTW
    GST = FST * FSH * GTW - TRANSL
    GSO = FSO * FSH * GTW

    # 2.10 leaf and ear area
    GLAI = GLA(TIME, DOYEM, DTEFF, DVS, RGRL, DELT, SLA, LAI, GLV)
    RDRDV = INSW(DVS - 1.0, 0., DVR / (max(0.1, 2. - DVS)) * FRDR)
    RDRSH = LIMIT(0., 0.03, 0.03 * (LAI - LAICR) / LAICR)
    RDR = max(RDRDV, RDRSH)
    DLAI = LAI * RDR
    RLAI = GLAI - DLAI
    REAI = SUBEAI(DELT, DVS, EAR, TADRW, RDRDV, EAI)
    DLV = WLVG * DLAI / NOTNUL(LAI)
    RWLVG = GLV - DLV

    # 2.20 carbon balance check
    CO2RT = 44. / 12. * (ASRQRT * 12. / 30. - CFRT)
    CO2LV = 44. / 12. * (ASRQLV * 12. / 30. - CFLV)
    CO2ST = 44. / 12. * (ASRQST * 12. / 30. - CFST)
    CO2SO = 44. / 12. * (ASRQSO * 12. / 30. - CFSO)
    RTNASS = (((GPHOT - MAINT) * 44. / 30.)
              - (GRT * CO2RT + GLV * CO2LV + (GST + TRANSL) * CO2ST
                 + GSO * CO2SO + (1. - CONVL) * TRANSL * CFST * 44. / 12.))
    CHKIN = WLV * CFLV + WST * CFST + WRT * CFRT + WSO * CFSO
    CHKFL = TNASS * (12. / 44.)
    CHKDIF = (CHKIN - CHKFL) / NOTNUL(CHKIN)

    # water balance check, water use efficiency
    WCUM = WL1 + WL2 + WL3 + WL4
    CHECK = (s['TRAIN'] + WCUMI - s['TAINTC'] - s['TRNOFF'] - s['TDRAIN']
             - WCUM - s['TATRAN'] - s['TAEVAP'])
    TAR = s['TATRAN'] * 1.E3 / NOTNUL(s['TDTGA'])
    CROPF = div(PTRANS + PEVAP, PENMAN)

    loc = dict(locals())
    for k in ('s', 'v', 'w', 'wth', 'loc'):
        loc.pop(k, None)
    v.update(loc)
    return v


def run(folder):
    """Run SUCROS2; folder holds the weather file NLD1.990.
    Returns (rows, names); one row per time point."""
    wth = read_weather(folder)
    unprinted = [n for n in STATE_NAMES if n not in PRINT_NAMES]
    names = ['TIME'] + PRINT_NAMES + unprinted
    rows = []
    s = initial_states()
    TIME = STTIME
    n = 0
    finish = None
    while True:
        try:
            v = compute(TIME, s, wth)
        except FortranStop as e:               # program ends, no row written
            finish = f'Fortran STOP: {e}'
            break
        rows.append([TIME] + [v[k] for k in names[1:]])

        # --- self-checks -------------------------------------------------
        tol = 1e-9
        assert abs(v['TDRW'] - (v['WLVG'] + v['WLVD'] + v['WST'] + v['WSO']
                                + v['WRT'])) <= tol * max(1., v['TDRW'])
        # growth of all organs adds up to the gross growth (translocation
        # moves stem matter into the gross pool)
        assert abs(v['GRT'] + v['GLV'] + v['GST'] + v['TRANSL'] + v['GSO']
                   - v['GTW']) <= tol * max(1., abs(v['GTW']))
        # soil water: the cumulative balance closes
        assert abs(v['CHECK']) <= 1e-9 * max(1., WCUMI + v['TRAIN'])
        # soil water: evaporation and uptake distributed exactly over layers
        assert abs(v['EVSW1'] + v['EVSW2'] + v['EVSW3'] + v['EVSW4']
                   - v['AEVAP']) <= 1e-12 * max(1., abs(v['AEVAP']))
        # carbon balance
        assert abs(v['CHKDIF']) <= 1e-9, v['CHKDIF']

        # --- FINISH conditions in the order written ----------------------
        if v['ERRSH'] > 1.E-6:
            finish = 'ERRSH > 1.E-6'
        elif v['DVS'] > 2.:
            finish = 'DVS > 2.'
        if finish:
            break
        if TIME >= FINTIM * (1. - 1e-12):
            finish = 'FINTIM'
            break

        # --- Euler step --------------------------------------------------
        new = {k: s[k] + DELT * v[RATE_OF[k]] for k in STATE_NAMES}
        # change of soil water = inflows - outflows over the step
        dW = (new['WL1'] + new['WL2'] + new['WL3'] + new['WL4']) - v['WCUM']
        flows = DELT * (v['RRAIN'] - v['AINTC'] - v['RNOFF'] - v['DRAIN']
                        - v['ATRANS'] - v['AEVAP'])
        assert abs(dW - flows) <= 1e-9 * max(1., v['WCUM']), (TIME, dW, flows)
        # change of total dry weight = growth of the organs
        dT = sum(new[k] - s[k] for k in ('WLVG', 'WLVD', 'WST', 'WSO', 'WRT'))
        assert abs(dT - DELT * (v['GRT'] + v['GLV'] + v['GST'] + v['GSO'])) \
            <= 1e-9 * max(1., v['TDRW'])
        s = new
        n += 1
        TIME = STTIME + n * DELT
    run.finish = finish
    return rows, names
