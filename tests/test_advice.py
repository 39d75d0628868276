"""Method advice: an expensive explicit run of a stiff model says once that
METHOD AUTO would be cheaper; a cheap or non-stiff run says nothing."""

import amilpy

STIFF = """PARAM C = 1.0E6
X1 = INTGRL(0.0, V1)
V1 = INTGRL(0.0, 1.0 - C*(X1 - X2) - 1.0E4*(V1 - V2))
X2 = INTGRL(0.0, V2)
V2 = INTGRL(0.0, C*(X1 - X2) + 1.0E4*(V1 - V2) - V2)
TIMER FINTIM = 2.0
END
"""


def test_stiff_model_on_rks_gets_advice_once(monkeypatch):
    from amilpy.run import advice

    monkeypatch.setattr(advice, "SLOW", 0.0)  # this run takes well under a second
    runs = amilpy.loads(STIFF.replace("END", "METHOD RKS\nEND\nPARAM C = 2.0E6\nEND")).run()
    assert runs[0].advice.startswith("stiff: METHOD AUTO took")
    assert runs[1].advice is None  # said once


def test_a_quick_run_is_not_probed():
    """The probe costs 20-60 % of the run (benchmarks/README.md): only a run that took
    SLOW seconds or more pays it, however many evaluations it made."""
    from dataclasses import replace

    from amilpy.run import Options, advice

    model = amilpy.loads(STIFF)
    run, = model.run(method="RKS", advice=False)
    assert run.stats["nfev"] >= advice.EXPENSIVE
    quick = replace(run, stats={**run.stats, "seconds": 0.5 * advice.SLOW})
    slow = replace(run, stats={**run.stats, "seconds": 2.0 * advice.SLOW})
    spec, opts = model.ir.runs[0], Options(method="RKS")
    assert advice.stiffness_advice(model.ir, spec, quick, opts) is None
    assert advice.stiffness_advice(model.ir, spec, slow, opts).startswith("stiff:")


def test_advice_can_be_silenced_and_is_not_given_for_auto():
    model = amilpy.loads(STIFF)
    assert model.run(method="RKS", advice=False)[0].advice is None
    assert model.run()[0].advice is None  # AUTO switches by itself


def test_non_stiff_expensive_run_gets_no_advice():
    # a fast undamped oscillator: many evaluations, but Radau is no cheaper
    model = amilpy.loads("X = INTGRL(1.0, V)\nV = INTGRL(0.0, -1.0E4*X)\n"
                         "TIMER FINTIM = 10.0\nEND\n")
    run, = model.run(method="RKS")
    assert run.stats["nfev"] > 5000 and run.advice is None
