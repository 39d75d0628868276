"""Several runs from one listing, and how runs end (FINISH, TERMT), with the
events they record."""

import math

import numpy as np
import pytest
from conftest import run1

import amilpy
from amilpy.output.sheets import csv_text

DECAY = "PARAM K = {k}\nX = INTGRL(1.0, -K*X)\nTIMER FINTIM = 1.0, OUTDEL = 0.5\n"


def test_param_value_list_gives_one_run_per_value():
    runs = amilpy.loads(DECAY.format(k="(1.0, 2*2.0, 3.0)") + "END\n").run()
    assert [r.label for r in runs] == ["K = 1", "K = 2", "K = 2", "K = 3"]
    for r, k in zip(runs, [1.0, 2.0, 2.0, 3.0], strict=True):
        assert r["X"][-1] == pytest.approx(math.exp(-k), rel=1e-5)


def test_end_groups_inherit_and_change_data():
    text = DECAY.format(k="1.0") + "END\nPARAM K = 2.0\nEND\nTIMER FINTIM = 2.0\nEND\nSTOP\n"
    runs = amilpy.loads(text).run()
    assert [r.label for r in runs] == ["RUN 1", "K = 2", "K = 2"]
    assert runs[1]["X"][-1] == pytest.approx(math.exp(-2.0), rel=1e-5)
    assert runs[2].t[-1] == 2.0  # the third group inherits K = 2 and changes FINTIM
    assert runs[2]["X"][-1] == pytest.approx(math.exp(-4.0), rel=1e-5)


def test_equations_after_end_are_refused():
    with pytest.raises(amilpy.AmilError, match="only data and control statements"):
        amilpy.loads(DECAY.format(k="1.0") + "END\nY = 2.0\nEND\n")


def test_keyword_overrides_apply_to_every_run():
    runs = amilpy.loads(DECAY.format(k="(1.0, 2.0)") + "END\n").run(K=0.5)
    assert all(r["X"][-1] == pytest.approx(math.exp(-0.5), rel=1e-5) for r in runs)


def test_csv_has_a_run_column_with_several_runs():
    # each row says its run by number and by the value that changes (run 1's too)
    runs = amilpy.loads(DECAY.format(k="(1.0, 2.0)") + "PREPARE X\nEND\n").run()
    lines = csv_text(runs).splitlines()
    assert lines[0] == "RUN,K,TIME,X"
    assert [line.split(",")[:2] for line in lines[1:]] == [["1", "1.0"]] * 3 + [["2", "2.0"]] * 3


def test_finish_stops_at_the_located_instant():
    r = run1("PARAM G = 9.81\nY = INTGRL(10.0, V)\nV = INTGRL(0.0, -G)\n"
             "TIMER FINTIM = 5.0, OUTDEL = 0.1\nFINISH Y = 0.0\nEND\n", rtol=1e-10, atol=1e-12)
    t_hit = math.sqrt(2 * 10.0 / 9.81)
    assert r.status == "stopped" and "FINISH" in r.message
    assert r.t[-1] == pytest.approx(t_hit, rel=1e-12)
    assert r["Y"][-1] == pytest.approx(0.0, abs=1e-9)
    assert r.t[-2] == pytest.approx(1.4)  # the rows before it are the OUTDEL grid


def test_termt_halts_when_its_argument_becomes_positive():
    r = run1("X = INTGRL(0.0, 1.0)\nTERMT(X - 0.375)\nTIMER FINTIM = 1.0, OUTDEL = 0.1\nEND\n")
    assert r.status == "stopped" and r.t[-1] == pytest.approx(0.375, rel=1e-12)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "RADAU", "RK4"])
def test_state_event_recorded_with_branches(method):
    # a ball bouncing on a spring floor: contact is a DEADSP edge on the state
    r = run1("PARAM K = 1.0E4\nY = INTGRL(1.0, V)\n"
             "V = INTGRL(0.0, -9.81 - K*LIMIT(-1.0E9, 0.0, Y))\n"
             "TIMER FINTIM = 0.6, OUTDEL = 0.01\nEND\n", method=method, rtol=1e-9, atol=1e-12)
    contact = [e for e in r.events if "LIMIT" in e.switch]
    t_free = math.sqrt(2 / 9.81)
    assert contact[0].time == pytest.approx(t_free, rel=1e-6)
    assert (contact[0].old, contact[0].new) == (1.0, -1.0)


def test_coulomb_friction_sticks_by_sliding_rule():
    # A block on a belt: spring K, dry friction F*sign(V - VB). From rest the belt
    # drags it (slip is impossible at first: both branches push V - VB to zero)
    # so it sticks at belt speed until K*X reaches F, at X = F/K = 0.5 at t = 0.5.
    r = run1("PARAM K = 1.0, F = 0.5, VB = 1.0, M = 1.0\n"
             "X = INTGRL(0.0, V)\nV = INTGRL(1.0, (FSW(V - VB, F, 0.0, -F) - K*X)/M)\n"
             "TIMER FINTIM = 0.8, OUTDEL = 0.1\nEND\n", rtol=1e-10, atol=1e-12)
    # sliding from the start is an event (the printout words it), not a NOTE
    slide = [e for e in r.events if e.kind == "slide"]
    assert slide and slide[0].time == 0.0
    assert not r.warnings
    stick = r.t <= 0.5
    assert r["V"][stick] == pytest.approx(np.ones(stick.sum()), abs=1e-9)
    assert r["X"][stick] == pytest.approx(r.t[stick], abs=1e-9)
    leave = [e for e in r.events if e.old == 0.5]
    assert leave and leave[0].time == pytest.approx(0.5, rel=1e-6)
    # then a harmonic slip arc, the belt faster than the block (friction +F):
    # X'' = F - K X from X = 0.5, V = 1, so X = F/K + sin(t - 0.5)
    t = r.t[r.t > 0.5] - 0.5
    assert r["X"][r.t > 0.5] == pytest.approx(0.5 + np.sin(t), abs=1e-8)


def test_zhold_on_a_switch_that_jumps_to_zero():
    # SW jumps from 0 to 1 at T1, so 1 - SW lands exactly on zero: ZHOLD holds
    r = run1("PARAM T1 = 0.5\nSW = FSW(TIME - T1, 0.0, 1.0, 1.0)\nX = INTGRL(0.0, 1.0)\n"
             "H = ZHOLD(1.0 - SW, X)\nTIMER FINTIM = 1.0, OUTDEL = 0.25\nEND\n")
    assert r["H"] == pytest.approx([0.0, 0.25, 0.5, 0.5, 0.5], abs=1e-12)


def test_final_holds_every_variable_and_initial_value():
    r = run1("PARAM K = 2.0\nINITIAL\n T = 1.0/K\nDYNAMIC\n X = INTGRL(1.0, -X/T)\n"
             "TIMER FINTIM = 1.0\nEND\n")
    assert r.final["T"] == 0.5 and r.final["K"] == 2.0
    assert r.final["X"] == pytest.approx(math.exp(-2.0), rel=1e-5)
