"""What the compiled loop (`kernel.advance`) and its Python side share: the slots of
its scalar state `sc`, what it may do with a surface's crossing, and what it returns.
Plain integers, no numba: the run loop reads these without importing it."""

# sc, the kernel's scalar state (read and written in place by `kernel.advance`)
AT = 0  # TIME where the kernel stands
STEP = 1  # the next step to try
HELD_END = 2  # a held step's end (its state, slope and interpolant in held_*)
NFEV = 3  # evaluations so far
NSTEPS = 4  # accepted steps so far
BOUND = 5  # the segment's end
MAX_STEP = 6
LOOKAHEAD = 7  # the step of a look-ahead (the branch the motion takes)
POSITIVE = 8  # the stiffness test: positive tests,
CALM = 9  # negative ones since the last positive,
H_LAMBDA = 10  # its last estimate of h*|lambda|,
STIFF_AT = 11  # where it was confirmed (NaN: not yet),
STIFF_H_LAMBDA = 12  # and the estimate there
CUBIC = 13  # 1: the held step is interpolated from its ends (stability-bound)
LIMIT = 14  # the pair's stability limit
RESTARTED = 15  # the steps before the last restart (the test counts from there)
FLOOR = 16  # the step-size floor: a step shorter is held for the loop to count
SLOTS = 17

# handled[k]: what the kernel may do with surface k's crossing
LOOP = 0  # hand the step to the run loop
QUIET = 1  # follow it where its branch changes nothing (no restart, no event)
PLAIN = 2  # that, or locate it, change the branch and restart

# what `kernel.advance` returns as its status
BUFFER = 0  # a buffer is full or the call's step budget is spent: call again
HELD = 1  # a step is held for the run loop (sc[HELD_END] is its end)
STEPS = 2  # the run's step limit
SMALL = 3  # the step size fell below its floor (a fault, a singularity)
