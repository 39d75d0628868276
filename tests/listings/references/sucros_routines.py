"""SUCROS97's routines after STOP, as SUCROS1 (s97-1.fst) and SUCROS2 (s97-2.fst) both
write them (the same Fortran in both files): GLA, SUBEAI, ASTRO, ASSIM and TOTASS,
translated by hand by a session that read only the listings, never amilpy."""
import math


class FortranStop(Exception):
    """A Fortran STOP 'text' inside a routine: ends the program."""


# Gauss points and weights exactly as in the DATA statements of TOTASS and ASSIM
XGAUSS3 = (0.112702, 0.500000, 0.887298)
WGAUSS3 = (0.277778, 0.444444, 0.277778)
XGAUSS5 = (0.0469101, 0.2307534, 0.5, 0.7692465, 0.9530899)
WGAUSS5 = (0.1184635, 0.2393144, 0.2844444, 0.2393144, 0.1184635)


def GLA(TIME, DOYEM, DTEFF, DVS, RGRL, DELT, SLA, LAI, GLV):
    GLAI = SLA * GLV                                    # maturation stage
    if (DVS < 0.3) and (LAI < 0.75):                    # juvenile stage
        GLAI = (LAI * (math.exp(RGRL * DTEFF * DELT) - 1.)) / DELT
    if TIME <= DOYEM:                                   # before emergence
        GLAI = 0.
    return GLAI


def SUBEAI(DELT, DVS, EAR, TADRW, RDRDV, EAI):
    if DVS < 0.8:
        REAI = 0.
    if DVS >= 0.8 and EAI == 0.:
        REAI = (EAR * TADRW) / DELT
    else:
        REAI = 0.
    if DVS >= 1.3:
        REAI = -RDRDV * EAI
    return REAI


def ASTRO(DOY, LAT):
    PI = 3.141592654
    RAD = PI / 180.
    if LAT > 67.:
        raise FortranStop('ERROR IN ASTRO: LAT> 67')
    if LAT < -67.:
        raise FortranStop('ERROR IN ASTRO: LAT>-67')
    DEC = -math.asin(math.sin(23.45 * RAD) * math.cos(2. * PI * (DOY + 10.) / 365.))
    SINLD = math.sin(RAD * LAT) * math.sin(DEC)
    COSLD = math.cos(RAD * LAT) * math.cos(DEC)
    AOB = SINLD / COSLD
    DAYL = 12.0 * (1. + 2. * math.asin(AOB) / PI)
    DSINB = 3600. * (DAYL * SINLD + 24. * COSLD * math.sqrt(1. - AOB * AOB) / PI)
    DSINBE = 3600. * (DAYL * (SINLD + 0.4 * (SINLD * SINLD + COSLD * COSLD * 0.5))
                      + 12.0 * COSLD * (2.0 + 3.0 * 0.4 * SINLD)
                      * math.sqrt(1. - AOB * AOB) / PI)
    SC = 1370. * (1. + 0.033 * math.cos(2. * PI * DOY / 365.))
    DS0 = SC * DSINB
    return SC, DS0, SINLD, COSLD, DAYL, DSINB, DSINBE


def ASSIM(SCP, AMAX, EFF, KDF, LAI, SINB, PARDR, PARDF):
    SQV = math.sqrt(1. - SCP)
    REFH = (1. - SQV) / (1. + SQV)
    REFS = REFH * 2. / (1. + 2. * SINB)
    CLUSTF = KDF / (0.8 * SQV)
    KBL = (0.5 / SINB) * CLUSTF
    KDRT = KBL * SQV
    FGROS = 0.
    for I1 in range(5):
        LAIC = LAI * XGAUSS5[I1]
        VISDF = (1. - REFH) * PARDF * KDF * math.exp(-KDF * LAIC)
        VIST = (1. - REFS) * PARDR * KDRT * math.exp(-KDRT * LAIC)
        VISD = (1. - SCP) * PARDR * KBL * math.exp(-KBL * LAIC)
        VISSHD = VISDF + VIST - VISD
        if AMAX > 0.:
            FGRSH = AMAX * (1. - math.exp(-VISSHD * EFF / AMAX))
        else:
            FGRSH = 0.
        VISPP = (1. - SCP) * PARDR / SINB
        FGRSUN = 0.
        for I2 in range(5):
            VISSUN = VISSHD + VISPP * XGAUSS5[I2]
            if AMAX > 0.:
                FGRS = AMAX * (1. - math.exp(-VISSUN * EFF / AMAX))
            else:
                FGRS = 0.
            FGRSUN = FGRSUN + FGRS * WGAUSS5[I2]
        FSLLA = CLUSTF * math.exp(-KBL * LAIC)
        FGL = FSLLA * FGRSUN + (1. - FSLLA) * FGRSH
        FGROS = FGROS + FGL * WGAUSS5[I1]
    FGROS = FGROS * LAI
    return FGROS


def TOTASS(DOY, LAT, DTR, SCP, AMAX, EFF, KDF, LAI):
    PI = 3.141592654
    SC, DS0, SINLD, COSLD, DAYL, DSINB, DSINBE = ASTRO(DOY, LAT)
    DTGAS = 0.
    for I1 in range(3):
        HOUR = 12.0 + DAYL * 0.5 * XGAUSS3[I1]
        SINB = max(0., SINLD + COSLD * math.cos(2. * PI * (HOUR + 12.) / 24.))
        PAR = 0.5 * DTR * SINB * (1. + 0.4 * SINB) / DSINBE
        ATMTR = PAR / (0.5 * SC * SINB)
        if ATMTR <= 0.22:
            FRDF = 1.
        elif ATMTR > 0.22 and ATMTR <= 0.35:
            FRDF = 1. - 6.4 * (ATMTR - 0.22) ** 2
        else:
            FRDF = 1.47 - 1.66 * ATMTR
        FRDF = max(FRDF, 0.15 + 0.85 * (1. - math.exp(-0.1 / SINB)))
        PARDF = PAR * FRDF
        PARDR = PAR - PARDF
        FGROS = ASSIM(SCP, AMAX, EFF, KDF, LAI, SINB, PARDR, PARDF)
        DTGAS = DTGAS + FGROS * WGAUSS3[I1]
    DTGA = DTGAS * DAYL * 3600.
    return DAYL, DTGA, DS0
