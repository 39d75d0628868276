"""Fuzzing of amilpy's command line with mutated listings.

`mutate` makes hostile variants of the shipped and test listings, `target`
runs cases in a worker process under a memory limit and a per-case timeout,
`run_fuzz.py` drives a long campaign by hand (``python tests/fuzz/run_fuzz.py
--count 20000``). tests/test_hostile.py runs a bounded version in CI.
"""
