TITLE FST EXAMPLE: SPRING WHEAT, RADIATION-LIMITED GROWTH
* An FST-form listing (contract section 13): `;` between items, TIMER STTIME with
* FINTIM as the end day, the Euler driver, FINISH on a relation, and the day's
* weather read from the CABO file weather/NLD1.020 (synthetic, written for this
* example). Development stage DVS rises with the daily mean temperature above
* TBASE: 1 at anthesis after TSUMA degree-days, 2 at maturity after TSUMM more.
* Growth is the light use efficiency RUE [g/MJ] times the intercepted
* photosynthetically active radiation, half of RDD [J/m2/d]; leaves take FLV of
* it until anthesis. tests/test_examples.py checks the run day by day against
* the same Euler recurrence written with NumPy.
WEATHER WTRDIR = 'C:\FST\WEATHER\'; CNTR = 'NLD'; ISTN = 1; IYEAR = 2020
TIMER STTIME = 90.; FINTIM = 300.; DELT = 1.; PRDEL = 10.
TRANSLATION_GENERAL DRIVER = 'EUDRIV'
PARAM TBASE = 0.; TSUMA = 1000.; TSUMM = 800.
PARAM RUE = 2.8; K = 0.6; SLA = 0.018; FLV = 0.35
INCON WLVI = 2.; WTI = 4.

DTEFF = AMAX1(0., 0.5*(TMMN + TMMX) - TBASE)
DVR   = INSW(DVS - 1., DTEFF/TSUMA, DTEFF/TSUMM)
DVS   = INTGRL(0., DVR)
LAI   = SLA*WLV
PARI  = 0.5*RDD*1.E-6*(1. - EXP(-K*LAI))
GTW   = RUE*PARI
WLV   = INTGRL(WLVI, FLV*GTW*INSW(DVS - 1., 1., 0.))
WT    = INTGRL(WTI, GTW)

FINISH DVS > 2.
PRINT DVS, LAI, WT, RDD
OUTPUT WT, LAI
END
STOP
