"""Mutations of AMIL listings: characters, lines, bytes, hostile tokens.

Everything is driven by a `random.Random` so a case is reproducible from
(corpus file, seed). Mutations work on bytes, so invalid UTF-8 is reachable.
"""

from __future__ import annotations

import glob
import os
import random
import re

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# tokens a student (or an attacker) might put in a listing
TOKENS = [
    b"**", b"^", b"(", b")", b",", b"=", b";", b"$", b"...", b"&", b"!", b"*", b"'", b'"',
    b"\\", b".", b"..", b"1,5", b"1.5D-3", b"1E999", b"1E-999", b"-1E308", b"0.0", b"/0.0",
    b"NAN", b"INF", b"-INF", b"1.0/0.0", b"END\n", b"STOP\n", b"INITIAL\n", b"DYNAMIC\n",
    b"TERMINAL\n", b"TIMER FINTIM = 1.0E9\n", b"TIMER FINTIM = 1.0E-300\n", b"METHOD RK4\n",
    b"METHOD STIFF\n", b"FSW(", b"INTGRL(", b"QNTZR(0.0, ", b"IMPULS(0.0, 1.0E-12)",
    b"PARAM K = (1000*1.0)\n", b"__import__", b"__class__", b"os.system", b"eval(", b"exec(",
    b"lambda", b"TIME", b"t", b"y", b"m", b"z", b"rhs", b"X.Y", b"\x00", b"\t", b"\r",
    b"\xff", b"\xc3\x28", b"\xe2\x82", b"\xed\xa0\x80", b"\xef\xbb\xbf", "é".encode(),
    b"2**2**2**2**2**2", b"EXP(EXP(EXP(EXP(X))))", b"ALOG(-1.0)", b"SQRT(-1.0)",
]

# characters that look like ASCII code but are not (issue 15: a Bengali four read as
# 4, a long s folded to S); each must be named, never read as its look-alike
LOOKALIKES = {
    "0": ["\u09e6", "\uff10", "\u0660", "O"], "4": ["\u09ea", "\u0664", "\uff14"],
    "1": ["\u0661", "\uff11", "l"], "8": ["\u09ee"], "A": ["\u0410", "\u0391", "\uff21"],
    "E": ["\u0415", "\u0395"], "I": ["\u0130", "\u0406", "\u2160"], "O": ["\u041e", "0"],
    "S": ["\u017f", "\u0405"], "T": ["\u0422", "\u03a4"], "-": ["\u2212", "\u2013"],
    " ": ["\u00a0", "\u2007", "\u3000"], "=": ["\uff1d"], "(": ["\uff08"], ",": ["\u201a"],
    "\n": ["\u2028", "\u0085", "\x0c", "\x0b", "\r"], "*": ["\u2217", "\u00d7"],
}

OPERATORS = ["del_char", "dup_char", "swap_chars", "del_line", "dup_line", "swap_lines",
             "random_bytes", "invalid_utf8", "token", "replace_number", "truncate",
             "case_flip", "join_lines", "lookalike", "nest_switches", "long_sum"]

# switches whose arguments nest: each level is a surface the checker classifies and the
# code generator writes (16 nested LIMITs took 100 s before both were made linear)
NESTS = [b"LIMIT(-1.0, 1.0, ", b"DEADSP(-0.5, 0.5, ", b"FSW(X, -1.0, 0.0, ",
         b"ZHOLD(X, ", b"INSW(X - 0.5, 0.0, ", b"AMAX1(0.0, "]


def corpus_files() -> list[str]:
    """Every shipped model and example and every test listing, of every form."""
    files = []
    for folder in ("models", os.path.join("models", "examples"), os.path.join("tests", "golden")):
        for pattern in ("*.amil", "*.csl", "*.fst"):
            files += sorted(glob.glob(os.path.join(ROOT, folder, pattern)))
    return files


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


def mutate_once(data: bytes, rng: random.Random, op: str | None = None) -> tuple[bytes, str]:
    op = op or rng.choice(OPERATORS)
    n = len(data)
    if n == 0:
        return rng.choice(TOKENS), "token"
    i = rng.randrange(n)
    if op == "del_char":
        k = rng.choice([1, 1, 1, 2, 5])
        return data[:i] + data[i + k:], op
    if op == "dup_char":
        return data[:i + 1] + data[i:], op
    if op == "swap_chars":
        j = min(n - 1, i + rng.choice([1, 1, 2, 7]))
        b = bytearray(data)
        b[i], b[j] = b[j], b[i]
        return bytes(b), op
    lines = _lines(data)
    li = rng.randrange(len(lines))
    if op == "del_line":
        del lines[li]
        return b"\n".join(lines), op
    if op == "dup_line":
        lines.insert(li, lines[li])
        return b"\n".join(lines), op
    if op == "swap_lines":
        lj = rng.randrange(len(lines))
        lines[li], lines[lj] = lines[lj], lines[li]
        return b"\n".join(lines), op
    if op == "random_bytes":
        k = rng.choice([1, 2, 4, 16])
        return data[:i] + bytes(rng.randrange(256) for _ in range(k)) + data[i:], op
    if op == "invalid_utf8":
        bad = rng.choice([b"\xff", b"\xc3\x28", b"\xa0\xa1", b"\xe2\x28\xa1", b"\xf0\x28\x8c\xbc",
                          b"\xed\xa0\x80", b"\xc0\xaf"])
        return data[:i] + bad + data[i:], op
    if op == "token":
        return data[:i] + rng.choice(TOKENS) + data[i:], op
    if op == "replace_number":
        # the first digit run after i becomes an extreme value
        j = i
        while j < n and not data[j:j + 1].isdigit():
            j += 1
        if j == n:
            return data + b"\n", op
        k = j
        while k < n and (data[k:k + 1].isdigit() or data[k:k + 1] in b".E+-"):
            k += 1
        new = rng.choice([b"0", b"0.0", b"-1.0", b"1E308", b"1E-308", b"1E999", b"5E-324",
                          b"1.0E9", b"1.0E-9", b"1,5", b"NAN", b"INF", b"9" * 400])
        return data[:j] + new + data[k:], op
    if op == "truncate":
        return data[:i], op
    if op == "case_flip":
        return data[:i] + data[i:i + 40].swapcase() + data[i + 40:], op
    if op == "join_lines":
        return data[:i] + data[i:].replace(b"\n", b" ", 1), op
    if op == "lookalike":
        text = data.decode("utf-8", "replace")
        spots = [k for k, ch in enumerate(text) if ch in LOOKALIKES]
        if not spots:
            return data, op
        k = rng.choice(spots)
        return (text[:k] + rng.choice(LOOKALIKES[text[k]]) + text[k + 1:]).encode(), op
    if op in ("nest_switches", "long_sum"):
        # around (or instead of) the first number after i
        j = i
        while j < n and not data[j:j + 1].isdigit():
            j += 1
        if j == n:
            return data, op
        k = j
        while k < n and (data[k:k + 1].isdigit() or data[k:k + 1] in b".E+-"):
            k += 1
        number = data[j:k]
        if op == "nest_switches":
            depth = rng.choice([2, 8, 16, 40, 200])
            wrap = rng.choice(NESTS)
            new = wrap * depth + number + b")" * depth
        else:
            new = b" + ".join([number] * rng.choice([10, 500, 999, 1500, 3000]))
        return data[:j] + new + data[k:], op
    raise ValueError(op)


def mutate(data: bytes, rng: random.Random, rounds: int | None = None) -> tuple[bytes, list[str]]:
    """Apply 1-4 random mutations; return the bytes and the operators used."""
    rounds = rounds or rng.choice([1, 1, 1, 2, 3, 4])
    ops = []
    for _ in range(rounds):
        data, op = mutate_once(data, rng)
        ops.append(op)
    return data, ops


def generate(count: int, seed: int = 0, files: list[str] | None = None):
    """Yield (case_id, bytes, description) for `count` mutations spread over the corpus."""
    files = files or corpus_files()
    originals = {f: open(f, "rb").read() for f in files}
    for k in range(count):
        f = files[k % len(files)]
        rng = random.Random(f"{seed}:{k}")
        data, ops = mutate(originals[f], rng)
        name = os.path.splitext(os.path.basename(f))[0]
        yield f"{name}-s{seed}-{k}", data, f"{os.path.relpath(f, ROOT)} seed={seed} k={k} " \
                                          f"ops={'+'.join(ops)}"


# ----------------------------------------------------------------- extremes
def extreme_cases(quick: bool = False) -> dict[str, bytes]:
    """Hand-made hostile listings of the issue (big ones are built lazily by size).

    `quick`: the two cases whose cost is only the parser's rate (a sum of 250 000
    terms, a table of 100 000 points: lark reads some 20 000-50 000 tokens a second,
    so each takes 10-30 s) at a tenth of their size, still far beyond any limit they
    probe; the test suite runs these, the fuzz campaign the whole ones."""
    t = b"TIMER FINTIM = 1.0\nPRINT X\nEND\n"
    terms, points = (25_000, 10_000) if quick else (250_000, 100_000)
    return {
        "nested_parens_10000": b"X = INTGRL(0.0, " + b"(" * 10000 + b"1.0" + b")" * 10000
                               + b")\n" + t,
        "unbalanced_parens_10000": b"X = INTGRL(0.0, " + b"(" * 10000 + b"1.0)\n" + t,
        "unary_minus_10000": b"X = INTGRL(0.0, " + b"-" * 10000 + b"1.0)\n" + t,
        "power_tower_constant": b"X = INTGRL(1.0, " + b"**".join([b"2.0"] * 60) + b")\n" + t,
        "power_tower_state": b"X = INTGRL(1.0, X" + b"**X" * 40 + b")\n" + t,
        "power_tower_caret": b"X = INTGRL(1.0, " + b"^".join([b"1.0001"] * 500) + b")\n" + t,
        "line_1MB_sum": b"X = INTGRL(0.0, " + b"+".join([b"1.0"] * terms) + b")\n" + t,
        "line_1MB_comment": b"* " + b"A" * 1_000_000 + b"\nX = INTGRL(0.0, 1.0)\n" + t,
        "line_1MB_name": b"X" + b"A" * 1_000_000 + b" = 1.0\nX = INTGRL(0.0, 1.0)\n" + t,
        "line_1MB_title": b"TITLE " + b"T" * 1_000_000 + b"\nX = INTGRL(0.0, 1.0)\n" + t,
        "line_1MB_number": b"X = INTGRL(0.0, 1." + b"1" * 1_000_000 + b")\n" + t,
        "div_zero_initial": b"INITIAL\n A = 1.0/0.0\nDYNAMIC\n X = INTGRL(0.0, A)\n" + t,
        "div_zero_initial_param": b"PARAM Z = 0.0\nINITIAL\n A = 1.0/Z\nDYNAMIC\n"
                                  b" X = INTGRL(0.0, A)\n" + t,
        "log_zero_initial": b"PARAM Z = 0.0\nINITIAL\n A = ALOG(Z)\nDYNAMIC\n"
                            b" X = INTGRL(0.0, A)\n" + t,
        "div_zero_dynamic": b"X = INTGRL(1.0, 1.0/(X - X))\n" + t,
        "sqrt_negative_dynamic": b"X = INTGRL(1.0, SQRT(-X))\n" + t,
        "nan_param": b"PARAM A = NAN\nX = INTGRL(0.0, A)\n" + t,
        "inf_param": b"PARAM A = INF\nX = INTGRL(0.0, A)\n" + t,
        "nan_name": b"X = INTGRL(0.0, NAN)\n" + t,
        "overflow_literal": b"PARAM A = 1.0E999\nX = INTGRL(0.0, A)\n" + t,
        "underflow_literal": b"PARAM A = 1.0E-999\nX = INTGRL(0.0, A)\n" + t,
        "overflow_ic": b"X = INTGRL(1.0E999, -X)\n" + t,
        "fintim_overflow": b"X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0E999\nEND\n",
        "fintim_tiny": b"X = INTGRL(1.0, -X)\nTIMER FINTIM = 5.0E-324\nEND\n",
        "outdel_tiny": b"X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0, OUTDEL = 1.0E-300\nEND\n",
        "delt_tiny": b"X = INTGRL(1.0, -X)\nMETHOD RK4\nTIMER FINTIM = 1.0, DELT = 1.0E-300\n"
                     b"END\n",
        "qntzr_zero_step": b"X = INTGRL(1.0, QNTZR(0.0, X))\n" + t,
        "impulse_period_tiny": b"X = INTGRL(1.0, IMPULS(0.0, 1.0E-12))\n" + t,
        "impulse_period_zero": b"X = INTGRL(1.0, IMPULS(0.0, 0.0))\n" + t,
        "value_list_huge": b"PARAM K = (100000000*1.0)\nX = INTGRL(1.0, -K*X)\n" + t,
        "many_end_groups": b"X = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\n" + b"END\n" * 3000,
        "many_continuations": b"X = INTGRL(1.0, -X ...\n" + b"...\n" * 10000 + b")\n" + t,
        "table_100k_points": b"FUNCTION F = " + b", ".join(b"%d,%d" % (i, i)
                                                            for i in range(points))
                             + b"\nX = INTGRL(1.0, AFGEN(F, X))\n" + t,
        "invalid_utf8": b"X = INTGRL(1.0, -X) ! \xff\xfe\n" + t,
        "nul_byte": b"X = INTGRL(1.0, -X)\x00\n" + t,
        "bom_crlf": b"\xef\xbb\xbfX = INTGRL(1.0, -X)\r\n" + t.replace(b"\n", b"\r\n"),
        "empty": b"",
        "random_bytes_4k": bytes(random.Random(1).randrange(256) for _ in range(4096)),
    }


# ----------------------------------------------------------------- command lines
CLI_LISTING = (b"PARAM K = 1.0\nX = INTGRL(1.0, -K*X)\nY = FSW(X - 0.5, 0.0, 1.0, 1.0)\n"
               b"TIMER FINTIM = 1.0, OUTDEL = 0.1\nPRINT X, Y\nOUTPUT X\nRANGE X\nEND\n")
CLI_VALUES = ["nan", "NaN", "-nan", "inf", "-inf", "+inf", "Infinity", "1e999", "-1e999", "0",
              "-0", "-1", "1e-320", "5e-324", "1e308", "", "abc", "1,5", "0x10", "1_000",
              " 2", "3.0.0", "1e-9", "0.5", "2", "100000000000000000000"]
CLI_OPTIONS = {
    "run": ["--max-time", "--max-steps", "--max-events", "--rtol", "--atol", "--fintim",
            "--from", "--to", "--runs"],
    "report": ["--max-time", "--max-steps", "--max-events", "--rtol", "--atol", "--fintim",
               "--from", "--to", "--runs"],
    "sweep": ["--settle", "--rtol", "--atol", "--fintim"],
}


def cli_cases(count: int, seed: int = 0):
    """Yield (case_id, bytes, description, argv): a small listing run with 1-3 numeric
    options (or a --set, or a sweep range) given a hostile value; '{path}' in argv
    stands for the listing. Accepted outcomes include exit 2, a usage error."""
    for k in range(count):
        rng = random.Random(f"cli:{seed}:{k}")
        command = rng.choice(["run", "run", "report", "sweep"])
        argv = [command, "{path}"]
        if command == "sweep":
            argv.append("K=" + ":".join(rng.choice(CLI_VALUES + ["1", "2", "0.5"])
                                        for _ in range(3)))
        for _ in range(rng.choice([1, 1, 2, 3])):
            option = rng.choice(CLI_OPTIONS[command] + ["--set"])
            value = rng.choice(CLI_VALUES)
            argv += [option, f"K={value}" if option == "--set" else value]
        argv += ["--quiet"]
        yield f"cli-s{seed}-{k}", CLI_LISTING, "amilpy " + " ".join(argv), argv


# What each command is run with on a mutated listing: small budgets, so that a case
# answers within the harness's time unless something is wrong; NAME is a PARAM of
# the listing where it has one (else a name it lacks: a usage error, also a case).
COMMAND_ARGS = {
    "check": [],
    "report": ["--format", "md,tex,pdf", "--no-accuracy-check", "--max-time", "3"],
    "sweep": ["{name}=0.5:1.5:0.5", "--fintim", "0.5", "--jobs", "1", "--max-time", "3"],
    "modes": ["--at", "0", "--max-time", "10"],
    "periodic": ["--period", "1.0", "--settle", "0.5", "--max-time", "10"],
    "response": ["{name}=1.0:1.05", "--period", "1.0", "--settle", "0.5", "--max-time", "10"],
    "montecarlo": ["--dist", "{name}=uniform(0.5,1.5)", "--runs", "6", "--fintim", "0.5",
                   "--jobs", "1", "--max-time", "5"],
    "sensitivity": ["--local", "{name}", "--fintim", "0.5", "--max-time", "5"],
    "steady": ["--max-time", "10"],
}


def command_cases(count: int, seed: int = 0):
    """Yield (case_id, bytes, description, argv): mutations of the corpus (as
    `generate`) through every command but `run` in turn (which `generate` drives),
    with the options of `COMMAND_ARGS`."""
    commands = sorted(COMMAND_ARGS)
    for k, (case_id, data, desc) in enumerate(generate(count, seed)):
        command = commands[k % len(commands)]
        found = re.search(rb"^\s*PARAM\s+([A-Za-z]\w*)", data, re.M | re.I)
        name = found.group(1).decode("ascii", "replace") if found else "NOPARAM"
        argv = [command, "{path}",
                *(a.replace("{name}", name) for a in COMMAND_ARGS[command]), "--quiet"] \
            if command != "check" else [command, "{path}"]
        yield f"{command}-{case_id}", data, f"amilpy {command}: {desc}", argv


def big_file(path: str, megabytes: int = 50) -> None:
    """A listing of `megabytes` MB: a valid model buried in comment and data lines."""
    block = (b"* a comment line of a long listing, padded out to a realistic width ....\n"
             b"PARAM P%d = 1.0\n")
    with open(path, "wb") as fh:
        fh.write(b"TITLE A VERY LONG LISTING\nX = INTGRL(1.0, -X)\n")
        size, k = 0, 0
        while size < megabytes * 1_000_000:
            chunk = b"".join(block % (k * 1000 + j) for j in range(1000))
            fh.write(chunk)
            size += len(chunk)
            k += 1
        fh.write(b"TIMER FINTIM = 1.0\nPRINT X\nEND\n")
