"""The lexical pass before the grammar: what a context-free lexer cannot decide.

`prepare` rewrites the text without moving any line or column, so every
diagnostic still points into the listing as written:

- a line whose first non-blank character is `*` is a comment (blanked), unless it
  continues the line before (`...` or `&` at its end);
- in the item lists of `PARAM PARAMETER CONST CONSTANT INCON TIMER FINISH WEATHER
  TRANSLATION_*`, a `;` separates items like `,` (it becomes `,`); a `;` that ends
  the line still ends the statement. Everywhere else `;` separates statements;
- `!=` inside parentheses is not-equal (it becomes `/=`); elsewhere `!` starts a
  comment, so banner comments such as `!======` stay comments;
- text after a `STOP` (or `ENDJOB`) statement is not read (FST files keep Fortran there);
- Magnolia's `IF T < TCHNG THEN` (and `ELSE IF`, and an IF alone on its line) has
  its condition put in parentheses: the blank after IF becomes `(`, the blank before
  THEN (or a comment), or the line's end, `)`.

Strings (`'text'`, `''` a quote) and `!` comments are skipped as units: a `!` or
`;` inside a string and a `'` inside a comment are plain characters.
"""

from __future__ import annotations

import re

from ..language import ITEM_KEYWORDS

_WORD = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_MARK = re.compile(r"['!()$;]")  # what `_Scanner.line` acts on inside a statement
# (CSMP III's and FST's ENDJOB, the job's last statement, ends the reading as STOP does)
_STOP = re.compile(r"^[ \t]*(?:STOP|ENDJOB)[ \t]*(?:[;$][ \t]*)?(?:!.*)?$", re.IGNORECASE)


def code_end(line: str) -> int:
    """Where the code of a line ends: at its `!` comment (outside strings), or its end."""
    bang = line.find("!")
    if bang < 0:
        return len(line)
    if "'" not in line:
        return bang
    quoted = False
    for i, ch in enumerate(line):
        if ch == "'":
            quoted = not quoted  # '' inside a string toggles twice: still inside
        elif ch == "!" and not quoted:
            return i
    return len(line)


def continues(line: str) -> bool:
    """A line whose code ends in a continuation mark (`...` or `&`)."""
    code = line[:code_end(line)].rstrip()
    return code.endswith("...") or (code.endswith("&") and not code.endswith("&&"))


def blank_comment_lines(text: str) -> str:
    """Blank every `*` comment line, keeping line and column numbers intact.

    A line that follows a continuation mark is part of an expression even when
    it starts with `*`, so it is kept.
    """
    out = []
    continued = False
    for line in text.split("\n"):
        if not continued and line.strip().startswith("*"):
            out.append("")
            continue
        out.append(line)
        continued = continues(line)
    return "\n".join(out)


_BARE_IF = re.compile(r"^([ \t]*(?:ELSE[ \t]*IF|IF))([ \t])(?![ \t]*\()(.*?)"
                      r"(?:([ \t])(THEN)[ \t]*)?$", re.IGNORECASE)
_ASSIGNS = re.compile(r"(?<![<>=/!~])=(?!=)")  # an `=` that is no comparison's


def _bare_code_end(line: str) -> int:
    """`code_end`, but a `!=` is not-equal (a bare condition has no parentheses
    around it for the scanner to know)."""
    end = code_end(line)
    while end < len(line) and line[end + 1:end + 2] == "=":
        end = end + 2 + code_end(line[end + 2:])
    return min(end, len(line))


def _bare_if(line: str) -> str:
    """IF cond [THEN] with the condition in parentheses, columns kept (see the
    module); any other line as it is (a line that continues too)."""
    if continues(line):
        return line
    end = _bare_code_end(line)
    code = line[:end].rstrip(" \t")
    m = _BARE_IF.match(code)
    if m is None or not m.group(3).strip() or _ASSIGNS.search(m.group(3)) or \
            "'" in m.group(3):
        return line
    head, cond = m.group(1) + "(" + m.group(3), ")"
    if m.group(5):  # (the blank before THEN)
        return head + cond + m.group(5) + line[len(code):]
    rest = line[len(code):]
    if rest[:1] in (" ", "\t"):  # (the blank before a comment)
        return head + cond + rest[1:]
    return head + cond + rest


def stop_line(lines: list[str]) -> int | None:
    """The index of the STOP (or ENDJOB) statement line, None if there is none."""
    continued = False
    for k, line in enumerate(lines):
        if not continued and _STOP.match(line):
            return k
        continued = continues(line)
    return None


def _after_stop(lines: list[str]) -> list[str]:
    """Lines after the first STOP (or ENDJOB) statement line are blanked (not read)."""
    k = stop_line(lines)
    return lines if k is None else lines[:k + 1] + [""] * (len(lines) - k - 1)


class _Scanner:
    """Walks the statements of the text, keeping strings and comments whole."""

    def __init__(self) -> None:
        self.items = False  # inside an item-list statement
        self.start = True  # at the start of a statement
        self.depth = 0  # parentheses open in this statement
        self.quoted = False  # a string goes on from the line before

    def end_statement(self) -> None:
        self.items, self.start, self.depth = False, True, 0

    def line(self, line: str, continued: bool) -> str:
        chars = list(line)
        i, n = 0, len(chars)
        quoted, self.quoted = self.quoted, False
        while i < n:
            ch = chars[i]
            if ch == "'" or quoted:
                # (a string the line before continued with `...` goes on here: FST's
                # WTRDIR = 'D:\MODELS\...' / 'LINGRA\')
                j = i if quoted else i + 1
                quoted = False
                while j < n:
                    if chars[j] == "'":
                        if j + 1 < n and chars[j + 1] == "'":
                            j += 2
                            continue
                        break
                    j += 1
                if j >= n and continued:
                    self.quoted = True
                i, self.start = j + 1, False
                continue
            if ch == "!":
                if self.depth > 0 and i + 1 < n and chars[i + 1] == "=":
                    chars[i] = "/"
                    i += 2
                    continue
                break  # a comment: the rest of the line
            if ch in " \t\r":
                i += 1
                continue
            if self.start:
                self.start = False
                word = _WORD.match(line, i)
                if word is not None:
                    rest = line[word.end():].lstrip(" \t")
                    keyword = word.group().upper()
                    self.items = (keyword in ITEM_KEYWORDS
                                  or keyword.startswith("TRANSLATION_")) \
                        and not (rest.startswith("=") and not rest.startswith("=="))
                    i = word.end()
                    continue
            if ch == "(":
                self.depth += 1
            elif ch == ")":
                self.depth = max(0, self.depth - 1)
            elif ch == "$":
                self.end_statement()
            elif ch == ";":
                if self.items and line[i + 1:code_end(line)].strip():
                    chars[i] = ","
                else:
                    self.end_statement()
            i += 1
            if not self.start:  # (on to the next character that matters)
                mark = _MARK.search(line, i)
                i = n if mark is None else mark.start()
        if not continued:
            self.end_statement()
        return "".join(chars)


def prepare(text: str) -> str:
    """The text the grammar reads (see the module's docstring); same lines, same columns."""
    lines = _after_stop(blank_comment_lines(text).split("\n"))
    scanner = _Scanner()
    out = []
    continued = False
    for line in lines:
        if not continued:
            line = _bare_if(line)
        continued = continues(line)
        out.append(scanner.line(line, continued))
    return "\n".join(out)
