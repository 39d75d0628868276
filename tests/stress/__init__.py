"""Numerical stress suite (issue 5): stiffness, backlash, chattering, blow-up,
long horizons and extreme scales. CI-sized; benchmarks/stress.py runs the long
versions by hand. The listings and their closed forms live in `cases`."""
