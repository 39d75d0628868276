"""Finite-time blow-up X = INTGRL(1, X*X): stop near TIME = 1, keep the rows."""

import numpy as np
import pytest

import amilpy
from amilpy.cli import main
from stress import cases as C


@pytest.fixture(scope="module")
def model():
    return amilpy.loads(C.BLOW_UP, name="blow_up.amil")


@pytest.mark.parametrize("method", C.METHODS)
def test_blow_up_stops_with_rows(model, method):
    r, = model.run(method=method)
    assert r.status == "failed"
    assert r.message.startswith("integration failed at TIME = ")
    assert any(s in r.message for s in ("step size", "no longer finite")), r.message
    assert 0.99 <= r.t_end <= 1.02
    x = r.values["X"]
    assert np.all(np.isfinite(x)) and len(r.times) >= 100  # everything up to TIME ~ 1
    assert x[-1] > 1e2
    early = r.t <= 0.9
    exact = 1.0 / (1.0 - r.t[early])
    tol = {"EULER": 5e-2}.get(method, 1e-2 if method in C.FIXED else 1e-4)
    assert np.allclose(r["X"][early], exact, rtol=tol)


def test_blow_up_cli_exit_code_and_partial_csv(tmp_path, capsys):
    path = tmp_path / "blow.amil"
    path.write_text(C.BLOW_UP)
    csv = tmp_path / "blow.csv"
    code = main(["run", str(path), "--quiet", "--csv", str(csv)])
    assert code == 3
    err = capsys.readouterr().err
    assert "TIME = " in err and "Traceback" not in err
    rows = csv.read_text().strip().splitlines()
    assert len(rows) > 100
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blow.amil", "blow.csv"]


@pytest.mark.parametrize("method", C.FIXED)
def test_blow_up_names_variable_fixed_step(model, method):
    r, = model.run(method=method)
    assert "X" in r.message.replace("TIME", "").replace("DELT", "")
