"""Independent references for the shipped models in ``models/``.

Each module restates one model's equations in plain NumPy/SciPy, integrates them at
rtol 1e-12 with every switching instant located by ``solve_ivp`` events and the
integration restarted in the new branch, and supplies the closed-form quantities the
validation compares against. Nothing here imports amilpy: a reference that shared code
with the interpreter could not catch the interpreter's mistakes.

Modules:
    ex4           Exercise 4 (lab sheet, seed 004): micromotor, elastic coupling, clutch,
                  torque-meter stand; Coulomb friction with stiction.
    hoist         Seed 002: three-mass hoist with backlash; eigenproblem, eq. (17),
                  harmonic linearisation (eqs. 11-14), harmonic balance (eq. 21).
    crank_slider  Seed 000: start-up of the crank-slider; the paper's Table 1 and its
                  stepwise energy method.
    machine_unit  Seed 003: machine unit, start-up to steady motion; energy balance.
    pencil        Matrix-pencil fit of a sampled sum of exponentials.
"""
