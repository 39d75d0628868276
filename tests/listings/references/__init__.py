"""Independent references for published listings in SOURCES.md (no amilpy imports).

Each module restates one listing's equations in plain NumPy/SciPy (transcription notes in
its docstring), integrates them at rtol 1e-10 with every event at its exact instant, and
returns the listing's printout as a dict of arrays keyed by upper-case names (T or TIME
first). test_listing_references.py checks each against a second, independent method.

    spring            acsl/spring.csl: closed-form damped oscillator; TERMT at 3.99
    flow_limited_fat  acsl/flow_limited_fat.csl: closed form; IF on T (breakpoint at 12)
    gefitinib         acsl/gefitinib.csl: SCHEDULE .AT. infusion on [0, 0.01]
    diazepam          acsl/diazepam.csl: DISCRETE sections scheduling each other
    lapatinib_md      acsl/lapatinib_md.csl: DISCRETE with INTERVAL and IF; superposition
    minmod4           acsl/minmod4.csl: ALGORITHM IALG=5 (RK4, DELT = MAXT = 0.005)
    btex              acsl/btex_ruiz2020.csl: PULSE exposure as pieces; DISCRETE sections
                      (arrays, FOR loops of SCHEDULEs, INTERVAL) that change nothing
    water_stress      fst/legumes_water_stress.fst, fst/maize_water_stress.fst: EUDRIV
                      step-point Euler recurrence with the synthetic CABO weather files
"""
