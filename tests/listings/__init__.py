"""Published CSSL-family listings (ACSL/Magnolia, FST) and independent references for them.

SOURCES.md names every listing (repository, path, commit, licence, constructs, published
numbers); REFUSALS.md lists the dialect keywords amilpy must refuse; references/ holds
plain NumPy/SciPy restatements of six listings' equations; weather/ holds the synthetic
CABO weather files the FST listings read.
"""
