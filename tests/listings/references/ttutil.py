"""TTUTIL's functions as the hand translations of the FST listings read them (from
TTUTIL's documentation, never from amilpy): INSW, LIMIT, NOTNUL, AFGEN, REAAND and
REANOR."""


def INSW(x, a, b):
    """Input switch: a if x < 0 else b."""
    return a if x < 0.0 else b


def FCNSW(x, a, b, c):
    """Function switch: a if x < 0, b if x == 0, c if x > 0."""
    if x < 0.0:
        return a
    if x == 0.0:
        return b
    return c


def LIMIT(xmin, xmax, x):
    """x clamped into [xmin, xmax] (TTUTIL stops the program where MAX < MIN)."""
    if xmax < xmin:
        raise ValueError('LIMIT: MAX < MIN')
    if x < xmin:
        return xmin
    if x > xmax:
        return xmax
    return x


def NOTNUL(x):
    """1 if x == 0 else x."""
    return 1.0 if x == 0.0 else x


def AFGEN(table, x):
    """Linear interpolation in a FUNCTION table's flat (x1, y1, x2, y2, ...) list; the
    end values outside its x range."""
    xs = table[0::2]
    ys = table[1::2]
    if x <= xs[0]:
        return ys[0]
    if x >= xs[-1]:
        return ys[-1]
    for i in range(1, len(xs)):
        if x <= xs[i]:
            x0, x1 = xs[i - 1], xs[i]
            y0, y1 = ys[i - 1], ys[i]
            return y0 + (x - x0) * (y1 - y0) / (x1 - x0)
    return ys[-1]


def REAAND(x1, x2):
    """1 if both are positive, else 0."""
    return 1.0 if (x1 > 0.0 and x2 > 0.0) else 0.0


def REANOR(x1, x2):
    """1 if neither is positive, else 0."""
    return 1.0 if (x1 <= 0.0 and x2 <= 0.0) else 0.0
