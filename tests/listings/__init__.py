"""Published CSSL-family listings (ACSL/Magnolia, FST) and independent references for them.

SOURCES.md names every listing (repository, path, commit, licence, constructs, published
numbers); REFUSALS.md lists the dialect keywords amilpy must refuse; references/ holds
plain NumPy/SciPy restatements of six listings' equations; weather/ holds the synthetic
CABO weather files the FST listings read.
"""


def published_copy(folder, name: str, sha256: str):
    """The local copy of a published listing (never committed), checked byte for byte
    against the one SOURCES.md describes; the test is skipped where it is absent."""
    import hashlib

    import pytest

    path = folder / name
    if not path.exists():
        pytest.skip(f"{name} is not in tests/listings/{folder.name}/: copy it as "
                    "tests/listings/SOURCES.md says (never committed)")
    assert hashlib.sha256(path.read_bytes()).hexdigest() == sha256, \
        f"{name} differs from the copy SOURCES.md describes"
    return path
