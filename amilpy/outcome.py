"""How a run ends, other than by reaching FINTIM: one kind per reason, one message
template per kind (SciPy's `MESSAGES`, diffrax's outcome enumeration).

The run loop and the steppers name a `Failure` and give the data its template
needs; `message` writes the sentence a user reads. Every failure message of a
run is in this table, so their wording is reviewed in one place.

"""

from __future__ import annotations

from enum import Enum

from .result import Status


class Failure(Enum):
    """Why a run ended early (or did not start)."""

    INITIAL_NOT_FINITE = "an initial value is not finite"
    DERIVATIVE_NOT_FINITE = "a derivative is not finite where a segment starts"
    NOT_FINITE = "a state stopped being finite"
    UNSTABLE = "a fixed-step method made a decaying mode grow"
    SOLVER = "the solver gave up"
    STEP_UNDERFLOW = "the step size fell below its floor"
    STEP_SPACING = "the solver's step fell to the spacing of floats"
    SLIDES = "too many surfaces slide at once"
    FAULT = "an arithmetic fault in the model's statements"
    CANNOT_START = "an arithmetic fault before the first step"
    TERMINAL = "an arithmetic fault in TERMINAL"
    STEPS = "the step limit"
    EVENTS = "the event limit"
    TIME_LIMIT = "the wall-clock limit"
    CHATTER = "a switch chatters"
    INTERRUPTED = "interrupted (Ctrl-C)"
    ZENO = "events accumulate before a finite TIME"


_FAILED = "integration failed at TIME = {t:.9g}: "

# The sentence for each outcome. Fields: t (TIME where the run ended), name (a state),
# value, detail (the solver's or the fault's own words), and the kind's own below.
MESSAGES: dict[Failure | Status, str] = {
    Status.STOPPED: "stopped at TIME = {t:.9g}: {what}",
    Failure.INITIAL_NOT_FINITE: _FAILED + "the initial value of {name} is not finite "
                                          "({value:g})",
    Failure.DERIVATIVE_NOT_FINITE: _FAILED + "the derivative of {name} is {value:g} at "
                                             "TIME = {t:.9g}",
    Failure.NOT_FINITE: _FAILED + "{name} is no longer finite after TIME = {t:.9g}{detail}",
    Failure.UNSTABLE: _FAILED + "{name} grows without bound from TIME = {since:.9g}: METHOD "
                                "{method} is unstable with DELT = {delt:g} ({detail}); take "
                                "DELT below {safe:.2g} or a variable-step method (METHOD AUTO)",
    Failure.SOLVER: _FAILED + "{detail}",
    Failure.STEP_UNDERFLOW: _FAILED + "step size underflow: 100 steps shorter than {floor:.3g} "
                                      "s ({origin}); {name} = {value:.6g} (a finite-time "
                                      "singularity?)",
    Failure.STEP_SPACING: _FAILED + "step size underflow: the step fell to the spacing of "
                                    "the floats at this TIME; {name} = {value:.6g} (a "
                                    "finite-time singularity?)",
    Failure.SLIDES: _FAILED + "{count} switching surfaces slide at once (at most {limit})",
    Failure.FAULT: _FAILED + "{detail}",
    Failure.CANNOT_START: "cannot start at TIME = {t:.9g}: {detail}",
    Failure.TERMINAL: "TERMINAL failed after TIME = {t:.9g}: {detail}",
    Failure.STEPS: _FAILED + "more than {limit} steps (raise --max-steps, or check the model "
                             "for stiffness)",
    Failure.EVENTS: _FAILED + "more than {limit} switching events (raise --max-events)",
    Failure.TIME_LIMIT: _FAILED + "wall-clock limit of {limit:g} s reached",
    Failure.CHATTER: _FAILED + "{what}: 200 restarts within {span:.3g} s at TIME = {t:.9g}",
    Failure.INTERRUPTED: "interrupted at TIME = {t:.9g}",
    Failure.ZENO: "the events of {what} accumulate at TIME = {t:.9g}, each interval "
                  "{ratio:.3g} times the one before (Zeno): no run goes past that instant "
                  "as the listing is written, so the rows after it are left out; say in the "
                  "listing what happens there (the ball comes to rest, say)",
}


def was_interrupted(text: str) -> bool:
    """A run's message says it was interrupted (Ctrl-C, SIGTERM, SIGHUP): what
    runs after it should not start."""
    return text.startswith(MESSAGES[Failure.INTERRUPTED].split()[0])  # ("interrupted ...")


def message(kind: Failure | Status, **fields: object) -> str:
    """The sentence a user reads for an outcome, from its template and data."""
    return MESSAGES[kind].format(**fields)
