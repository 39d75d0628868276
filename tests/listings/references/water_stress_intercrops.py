"""Independent reference for Water-Stress_Intercrops.fst (SOURCES.md F8: the 2018
maize-ldP intercrop as written, TIMER 1..275, DELT 1, EUDRIV), translated by hand from
the listing's active equations by a session that never read amilpy. FSE's Euler loop:
at each day all rates from the states, the row, then state += rate*DELT; the weather
(RDD, RAIN) read from the CABO file TZ2.018 (tests/listings/weather, synthetic).

`run(folder)`: one dict per day with the PRINT columns the test compares."""
import math
import os

from .cabo import read_cabo
from .ttutil import AFGEN as afgen
from .ttutil import INSW as insw
from .ttutil import NOTNUL as notnul

# ---- parameters (active, uncommented lines of the listing) ----
RUEM = 1.435
KAMTB = (0.,0.234, 85.,0.467, 177.,0.467, 275.,0.467)
LAIMTB = (1., 0.01, 30., 0.981, 64., 2.197, 85., 3.139, 114., 2.074, 142., 2.074, 165., 0.,
          177., 0., 275., 0.)
HGHMTB = (1.,0.1, 30.,44., 64.,100., 85.,147., 114.,178., 142.,186., 177.,189., 178.,0., 275.,0.)
OBSWMTB = (1.,0., 30.,484., 64.,3148., 85.,4176., 114.,6986., 142.,8700., 177.,9000., 275.,9000.)
RUEL = 0.543
KALTB = (1., 0.275, 30., 0.275, 64., 0.649, 85., 0.460, 114., 0.499, 142., 0.367, 177., 0.409,
         205., 0.396, 240., 0.336, 275., 0.336)
LAILTB = (1., 0.001, 30., 0.069, 64., 0.332, 85., 1.180, 114., 3.232, 142., 3.141, 177., 2.354,
          205., 2.051, 240., 1.659, 255., 0., 275., 0.)
HGHLTB = (1., 0.1, 30., 34., 64., 54., 85., 87., 114., 147., 142., 153., 177., 178., 205., 202.,
          240., 216., 275., 216.)
OBSWLTB = (1., 0., 30., 296., 64., 520., 85., 731., 114., 1071., 142., 1762., 177., 3164.,
           205., 3572., 240., 3267., 275., 3164.)
FabsTB = (1., 0., 30., 0.210, 64., 0.531, 85., 0.679, 114., 0.754, 142., 0.629, 177., 0.601,
          205., 0.536, 240., 0.390, 255., 0., 275., 0.)
RHO = 0.07
TRANSPCM, PM = 0.2, 0.8
TRANSPCL, PL = 0.3, 0.65
RdepthM, RdepthL = 6., 20.
FieldCap, WiltingP = 0.21, 0.13
STTIME, FINTIM, DELT = 1., 275., 1.
WTOTMI = WTOTLI = 0.1
WSOILL1I, WSOILL2I = 126., 294.


def run(folder):
    W = read_cabo(os.path.join(folder, "TZ2.018"))[1]
    SOILvolrootL1 = 10. * 10. * RdepthM
    WSOILminL1, WSOILmaxL1 = SOILvolrootL1 * WiltingP, SOILvolrootL1 * FieldCap
    SOILvolrootL2 = 10. * 10. * (RdepthL - RdepthM)
    WSOILminL2, WSOILmaxL2 = SOILvolrootL2 * WiltingP, SOILvolrootL2 * FieldCap

    s = dict(WTOTM=WTOTMI, WTOTL=WTOTLI, WSOILL1=WSOILL1I, WSOILL2=WSOILL2I,
             IABSACCM=0., IABSACCL=0., WRAIN=0., WTRANSP=0., WPERC=0.)
    rows = []
    nsteps = int(round((FINTIM - STTIME) / DELT))
    for k in range(nsteps + 1):
        TIME = STTIME + k * DELT
        wd = W[int(math.floor(TIME))]
        AVRAD, RAIN = wd["RDD"] * 1e-6, wd["RAIN"]
        LAIM, KAM, HEIGHTM = afgen(LAIMTB, TIME), afgen(KAMTB, TIME), afgen(HGHMTB, TIME)
        LAIL, KAL, HEIGHTL = afgen(LAILTB, TIME), afgen(KALTB, TIME), afgen(HGHLTB, TIME)
        OBSWL, FabsOBS = afgen(OBSWLTB, TIME), afgen(FabsTB, TIME)
        LAITM = max(((HEIGHTM - HEIGHTL) / notnul(HEIGHTM)) * LAIM, 0.)
        LAIBM = LAIM - LAITM
        LAITL = max(((HEIGHTL - HEIGHTM) / notnul(HEIGHTL)) * LAIL, 0.)
        IabsTM = (1. - RHO) * 0.5 * AVRAD * (1. - math.exp(-KAM * LAITM))
        IabsTL = (1. - RHO) * 0.5 * AVRAD * (1. - math.exp(-KAL * LAITL))
        IMID = (1. - RHO) * 0.5 * AVRAD * math.exp(-KAM * LAITM - KAL * LAITL)
        KLAILeg = 0.692 * 1E-7 * OBSWL**2 + 0.0005061 * OBSWL
        IabsBTOT = IMID * (1. - math.exp(-KAM * LAIBM - KLAILeg))
        IabsBM = ((KAM * LAIBM) / notnul(KAM * LAIBM + KLAILeg)) * IabsBTOT
        IabsBL = (KLAILeg / notnul(KAM * LAIBM + KLAILeg)) * IabsBTOT
        IabsM = IabsTM + IabsBM
        IabsL = insw(LAIM - 0.001, FabsOBS * 0.5 * AVRAD, IabsTL + IabsBL)
        FabsTOT = (IabsM + IabsL) / (0.5 * AVRAD)
        GROWTHMpot = RUEM * IabsM * 10.
        GROWTHLpot = RUEL * IabsL * 10.
        L1, L2 = s["WSOILL1"], s["WSOILL2"]
        WcML1 = WSOILminL1 + (1. - PM) * (WSOILmaxL1 - WSOILminL1)
        WcLL1 = WSOILminL1 + (1. - PL) * (WSOILmaxL1 - WSOILminL1)
        WcLL2 = WSOILminL2 + (1. - PL) * (WSOILmaxL2 - WSOILminL2)
        RATIOActPotM = insw(L1 - WcML1, (L1 - WSOILminL1) / (WcML1 - WSOILminL1), 1.)
        RATIOActPotLL1 = insw(L1 - WcLL1, (L1 - WSOILminL1) / (WcLL1 - WSOILminL1), 1.)
        RATIOActPotLL2 = insw(L2 - WcLL2, (L2 - WSOILminL2) / (WcLL2 - WSOILminL2), 1.)
        RTRANSPMpot = (GROWTHMpot / 10.) * TRANSPCM
        RTRANSPMact = RATIOActPotM * RTRANSPMpot
        RTRANSPLpot = (GROWTHLpot / 10.) * TRANSPCL
        RTRANSPLL1pot = RTRANSPLpot * (RdepthM / RdepthL)
        RTRANSPLL1act = RATIOActPotLL1 * RTRANSPLL1pot
        RTRANSPL1act = RTRANSPMact + RTRANSPLL1act
        RTRANSPLL2pot = RTRANSPLpot * ((RdepthL - RdepthM) / RdepthL) + \
            (RTRANSPLL1pot - RTRANSPLL1act)
        RTRANSPLL2act = RATIOActPotLL2 * RTRANSPLL2pot
        RTRANSPLact = RTRANSPLL1act + RTRANSPLL2act
        RATIOActPotL = RTRANSPLact / notnul(RTRANSPLpot)
        RTRANSPTOTact = RTRANSPL1act + RTRANSPLL2act
        GROWTHM = RATIOActPotM * GROWTHMpot
        GROWTHL = RATIOActPotL * GROWTHLpot
        WSOILexpL1 = L1 + (RAIN - RTRANSPL1act) * DELT
        RpercL1 = max(0., WSOILexpL1 - WSOILmaxL1)
        RWSOILL1 = RAIN - RTRANSPL1act - RpercL1
        WSOILexpL2 = L2 + (RpercL1 - RTRANSPLL2act) * DELT
        RpercL2 = max(0., WSOILexpL2 - WSOILmaxL2)
        RWSOILL2 = RpercL1 - RTRANSPLL2act - RpercL2
        BALANCE = ((L1 + L2) - (WSOILL1I + WSOILL2I)) - (s["WRAIN"] - s["WTRANSP"] - s["WPERC"])
        rows.append(dict(TIME=TIME, LAIM=LAIM, LAIL=LAIL, AVRAD=AVRAD, IABSM=IabsM, IABSL=IabsL,
                         FABSTOT=FabsTOT, RATIOACTPOTM=RATIOActPotM, RATIOACTPOTL=RATIOActPotL,
                         RTRANSPTOTACT=RTRANSPTOTact, BALANCE=BALANCE, **s))
        rates = dict(WTOTM=GROWTHM, WTOTL=GROWTHL, WSOILL1=RWSOILL1, WSOILL2=RWSOILL2,
                     IABSACCM=IabsM, IABSACCL=IabsL, WRAIN=RAIN, WTRANSP=RTRANSPTOTact,
                     WPERC=RpercL2)
        for key in s:
            s[key] += rates[key] * DELT
    return rows
