"""Split one line of NC text into words; the rules are in `machinesim.nc`."""

from __future__ import annotations

import re
import string
from dataclasses import dataclass

from machinesim.exceptions import NCProgramError, brief

#: A number: blanks may stand between its sign and its digits (``Z - 0.1``), as between a
#: letter and its number, since blanks in a block are not read; not inside the digits.
_NUMBER = re.compile(r"(?:[+-][ \t]*)?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)")
#: What float() would read as NaN or infinity, where a number belongs (refused by name).
_NOT_FINITE = re.compile(r"[+-]?[ \t]*(?:nan|inf(?:inity)?)(?![a-z])", re.IGNORECASE)
#: Blanks inside a line. A carriage return is a blank only as the CR of a CRLF line end: the
#: line's text then ends in it (the text stops before the LF), and `tokenize` drops it; any
#: other CR is refused (a lone CR, as old Mac files end lines, would join several blocks).
_BLANK = " \t"
_LETTERS = frozenset(string.ascii_letters)
#: What starts like a word after ';': a letter the reader knows, blanks, a number (as
#: `_NUMBER`). Such text after ';' would be a block lost in a comment.
_WORD_START = re.compile(r"([NOGMSFPXYZABCIJKRQLHTD])[ \t]*(" + _NUMBER.pattern + ")",
                         re.IGNORECASE)
#: The most words and problems one line is read for. A block holds one word per address
#: letter, one G code per modal group and a few M codes (FANUC: at most 3), so a line with
#: more is blocks whose line ends were lost, or no program; reading on had cost about 60 us
#: a word (one million 'X1. ' on a line: 65 s for a refusal that keeps 10,000 problems).
MAX_LINE_ITEMS = 10_000


@dataclass(frozen=True)
class Word:
    """One word: an address letter and its number, as written."""

    letter: str  # upper case
    text: str  # the number as written, without blanks after its sign
    column: int  # 1-based column of the letter

    @property
    def key(self) -> str:
        return self.letter + self.text


def tokenize(raw: str, source: str, line: int, *,
             line_feed: bool = True) -> tuple[list[Word], list[NCProgramError]]:
    """Words of one line and the problems found in it (comments, blanks, '%' give no words).

    ``raw`` is the line without its LF; ``line_feed`` says whether an LF followed it (False
    for the last line of a text that does not end in one). A CR at the end of ``raw`` is
    then the CR of a CRLF line end; every other CR is a lone CR and refused, and the line is
    read only up to it (what follows belongs to other lines the CR was meant to end).

    A problem does not stop the line: the reader skips to the next blank, letter or comment
    and goes on, so that one pass lists every malformed word of the line.
    """
    words: list[Word] = []
    problems: list[NCProgramError] = []
    percent = False

    def fail(message: str, column: int, key: str) -> None:
        problems.append(NCProgramError(message, source=source, line=line, column=column,
                                       key=key))

    if line_feed and raw.endswith("\r"):
        raw = raw[:-1]  # the CR of CRLF
    lone = raw.find("\r")
    if lone >= 0:
        count = raw.count("\r")
        more = f" (this line holds {count} of them)" if count > 1 else ""
        fail("carriage return (CR) not followed by a line feed (LF): line ends must be LF "
             "or CRLF; a lone CR, as old Mac files end lines, would join several blocks "
             f"into one line{more}; convert the file's line ends to LF or CRLF",
             lone + 1, "\\r")
        raw = raw[:lone]
    i, n = 0, len(raw)

    while i < n:
        c = raw[i]
        if c in _BLANK:
            i += 1
        elif c == "(":
            close = raw.find(")", i + 1)
            if close < 0:
                fail("comment '(' is not closed on its line", i + 1, "(")
                break
            inner = raw.find("(", i + 1, close)
            if inner >= 0:  # one problem, not one per word of the comment's rest
                fail("comments do not nest: this '(' is inside the comment opened at "
                     f"column {i + 1}, which ends at the first ')'", inner + 1, "(")
                close = max(close, raw.rfind(")"))
            i = close + 1
        elif c == ";":
            _after_end_of_block(raw, i, fail)
            break
        # after the comments, which add no word: a line of MAX_LINE_ITEMS words and its
        # comment is read whole, and only a word or problem beyond them stops the reading
        elif len(words) + len(problems) >= MAX_LINE_ITEMS:
            fail(f"more than {MAX_LINE_ITEMS} words and problems on one line, so reading of "
                 "the line stopped here: a block holds one word per address letter, one G "
                 "code per group and a few M codes; was it many blocks whose line ends were "
                 f"lost? ({len(raw) - i} characters not read)", i + 1, brief(raw[i:i + 20]))
            break
        elif c == ")":
            fail("')' without an opening '('", i + 1, ")")
            i += 1
        elif c == "%" or percent:
            if words or percent:
                # one problem for the line's text, not one for each of its letters
                stop = raw.find("(", i + 1)
                rest = raw[i:stop if stop > i else n].rstrip(_BLANK)
                found = f"{brief(rest)!r} after it" if percent else "it after words"
                fail(f"'%' must stand alone on its line (comments aside), found {found}: "
                     "past the opening one, a '%' ends the "
                     "program, and a FANUC control reads nothing after it; make the text a "
                     "comment '(...)' or remove the '%'", i + 1, rest)
                break
            percent = True
            i += 1
        elif c in _LETTERS or c == ":":
            # ':' is the ISO-code address of a program number, as O is: FANUC controls read
            # ':1234' as O1234 (https://en.cncforum.net/t/cnc-program-name-and-number-
            # identification/382; docs/nc.md)
            letter = "O" if c == ":" else c.upper()
            start = i
            i += 1
            while i < n and raw[i] in _BLANK:
                i += 1
            if c == ":" and i < n and raw[i] in _LETTERS:
                # ':O1001' had been "malformed number '' after 'O'" at the ':' (never written)
                _colon_before_letter(raw, start, i, fail)
                continue
            match = _NUMBER.match(raw, i)
            end = match.end() if match else i
            special = _NOT_FINITE.match(raw, i) if match is None else None
            if special is not None:  # Xnan, X-inf: one problem, not one per letter of it
                fail(f"{letter}{special.group()} is not a finite number (NaN and infinity "
                     f"are no lengths, angles or codes); expected digits with an optional "
                     f"sign and decimal point, e.g. {_example(letter)}", start + 1,
                     letter + special.group())
                i = special.end()
                continue
            if letter == "O" and c != ":" and (raw[i:i + 1] == "<" or (
                    match is not None and _o_word_keyword(raw, end) is not None)):
                i = _linuxcnc_o_word(raw, start, fail)
                continue
            sign = i
            if match is None and sign < n and raw[sign] in "+-":
                sign += 1
                while sign < n and raw[sign] in _BLANK:
                    sign += 1
            if match is None and sign < n and raw[sign] in "#[":
                stop = _end_of_expression(raw, sign)
                if raw.startswith("#<", sign):  # X#<x_max>, X-#<x_max>
                    fail(f"{letter}{brief(raw[i:stop])} takes its value from a "
                         f"{_NAMED_PARAMETER}; expected a number, e.g. {_example(letter)}",
                         start + 1, letter + raw[i:stop])
                else:
                    fail(f"{letter}{brief(raw[i:stop])} is a macro expression: {_MACROS}; "
                         f"expected a number, e.g. {_example(letter)}", start + 1,
                         letter + raw[i:stop])
                i = stop
                continue
            if match is None and c != ":" and _starts_text(raw, start + 1, i):
                i = _text_outside_comment(raw, start, fail)
                continue
            if match is None or (end < n and raw[end] in "0123456789.+-"):
                stop = _end_of_garbage(raw, i)
                tail = raw[i:stop]
                fail(
                    f"malformed number {brief(tail)!r} after {c!r}; expected digits "
                    f"with an optional sign and decimal point, e.g. {_example(letter)}",
                    start + 1,
                    (c if c == ":" else letter) + tail,
                )
                i = max(stop, i)
                continue
            number = match.group()
            if number[0] in "+-":
                number = number[0] + number[1:].lstrip(_BLANK)
            words.append(Word(letter, number, start + 1))
            i = end
        elif c in "0123456789+-.":
            stop = _end_of_garbage(raw, i)
            fail(f"number {brief(raw[i:stop])!r} without an address letter", i + 1,
                 raw[i:stop])
            i = stop
        elif c == "/":  # block delete (optional block skip), '/' or '/1'..'/9'
            stop = max(_end_of_garbage(raw, i + 1), i + 1)
            fail(f"block delete {raw[i:stop]!r} is not read: a FANUC control skips the block "
                 "from it on when its block-delete switch is on and runs it when off, and "
                 "the switch is not simulated; remove the '/' to run the block, or the block "
                 "to skip it", i + 1, raw[i:stop])
            i = stop
        elif c == "," and 0 < i < n - 1 and raw[i - 1].isdigit() and raw[i + 1].isdigit():
            stop = _end_of_garbage(raw, i + 1)
            start = words[-1].column - 1 if words else i - 1  # the word the comma ends
            fail(f"decimal comma in {raw[start:stop]!r}: NC numbers take a decimal point "
                 "(X1.5, not X1,5); the comma would split the number in two", i + 1, ",")
            i = stop
        elif c == "#" and raw.startswith("#<", i):  # LinuxCNC's '#<x_max> = 30'
            text = raw[i:_end_of_line_text(raw, i)].rstrip(_BLANK)
            fail(f"{brief(text)!r} sets a {_NAMED_PARAMETER}", i + 1, text)
            break
        elif c == "#":  # a macro variable: '#1=2.', '#101=[#1*2]'
            fail(f"macro variable {brief(raw[i:].rstrip())!r}: {_MACROS}", i + 1, c)
            break
        elif c == "\ufffd":  # what the reader decodes a byte that is not UTF-8 to
            fail("a byte that is not UTF-8 (a Latin-1 or Windows-1252 character, such as a "
                 "no-break space, saved by an editor in that encoding); expected ASCII "
                 "outside comments: save the file as UTF-8 or remove the character",
                 i + 1, c)
            i = max(_end_of_garbage(raw, i + 1), i + 1)
        else:
            fail(
                f"unexpected character {c!r}; expected words (a letter and a number), "
                "'(comment)', ';comment' or a lone '%'",
                i + 1,
                c,
            )
            i = max(_end_of_garbage(raw, i + 1), i + 1)
    return words, problems


def _after_end_of_block(raw: str, semicolon: int, fail) -> None:
    """Refuse a word after the ';' at index ``semicolon``: the rest of the line is read as a
    comment, so in FANUC text with several ';'-ended blocks on one line they would be lost.
    Blanks and further ';' are skipped; text that does not start like a word stays a
    comment."""
    i, n = semicolon + 1, len(raw)
    while i < n and (raw[i] in _BLANK or raw[i] == ";"):
        i += 1
    match = _WORD_START.match(raw, i)
    if match is None:
        return
    key = match.group(1).upper() + match.group(2)
    if raw[:semicolon].strip(_BLANK):
        fail(f"word {key!r} after the ';' at column {semicolon + 1} would be lost: words "
             "after ';' on the same line are read as a comment, but ';' ends a block in "
             "FANUC text; put each block on its own line (or write the comment in "
             "parentheses, e.g. '(T1 tool)')", i + 1, key)
        return
    # the line starts with ';': a whole-line comment in LinuxCNC, grbl and Mach3 (a drill
    # post's '; T3 Diameter: 0.70mm'), where no block comes before it to be lost; on a FANUC
    # control ';' ends an empty block and the text after it runs as the next one
    text = raw[i:].rstrip(_BLANK + "\r\n")
    shown = (f"'({brief(text)})'" if "(" not in text and ")" not in text
             else "e.g. '(T1 tool)'")
    fail(f"word {key!r} after the ';' that starts the line: a line starting with ';' is a "
         "comment in LinuxCNC and grbl, but ';' ends a block in FANUC text, where "
         f"{key!r} starts the next block; write the comment in parentheses ({shown}), or "
         "remove the ';' to run it as a block", i + 1, key)


def _colon_before_letter(raw: str, colon: int, letter: int, fail) -> None:
    """Refuse the ':' at ``raw[colon]`` followed (past blanks) by the letter at
    ``raw[letter]``: ':' is the program number's address in ISO code and takes digits, so
    ':O1001' gives the address twice. Reading goes on at the letter."""
    digits = letter + 1
    while digits < len(raw) and raw[digits] in _BLANK:
        digits += 1
    number = _NUMBER.match(raw, digits)
    stop = number.end() if number else _end_of_garbage(raw, letter + 1)
    found = raw[colon:stop]
    fix = (f"write ':{number.group()}' or 'O{number.group()}', not both"
           if number and raw[letter] in "oO" else "write the program number's digits after it")
    fail(f"':' is the ISO-code address of a program number, as O is, and takes its digits "
         f"(':1001' reads as O1001); found {brief(found)!r}: {fix}", colon + 1, found)


def _starts_text(raw: str, after: int, i: int) -> bool:
    """Whether the letter before ``raw[after]``, which no number follows (the number would
    start at ``raw[i]``, past blanks), starts text rather than a word: another letter right
    after it (``ROUGH``, ``FEED``), or blanks and a run of two letters (``A POCKET``).
    No word of the dialect has a letter after its letter; a lone letter before a word
    (``X Y1.``) stays a missing number."""
    if after < len(raw) and raw[after] in _LETTERS:
        return True
    return i > after and raw[i:i + 1] in _LETTERS and raw[i + 1:i + 2] in _LETTERS


#: Custom macro B's statements (IF [..] GOTO n, WHILE [..] DO1 .. END1, DPRNT[..]), by the
#: run of letters they start with and what follows it (blanks skipped): a bracket, a '#'
#: or a digit (``END OF PROGRAM`` is text).
_MACRO_STATEMENTS = frozenset({"IF", "WHILE", "GOTO", "DO", "END", "THEN", "DPRNT", "BPRNT",
                               "POPEN", "PCLOS"})
#: The macro statements that stand alone (open and close the output device).
_FILE_COMMANDS = frozenset({"POPEN", "PCLOS"})


def _text_outside_comment(raw: str, start: int, fail) -> int:
    """Refuse, as one problem, the text from the letter at ``raw[start]`` to the end of the
    line (or a comment or ';' after it): prose written outside parentheses (``ROUGH THE
    POCKET``, ``G01 X1. FEED SLOWLY``) or a macro statement (``IF [#1 GT 2] GOTO 10``).
    It had been one 'malformed number' problem for each of its letters. Returns the index
    where reading goes on."""
    stop = len(raw)
    for mark in "(;":
        found = raw.find(mark, start)
        if 0 <= found < stop:
            stop = found
    text = raw[start:stop].rstrip(_BLANK)
    letters = start
    while letters < stop and raw[letters] in _LETTERS:
        letters += 1
    word = raw[start:letters].upper()
    after = raw[letters:stop].lstrip(_BLANK)[:1]
    if word in _MACRO_STATEMENTS and (
            (after != "" and (after in "#[" or after.isdigit())) or word in _FILE_COMMANDS):
        fail(f"macro statement {brief(text)!r} (custom macro B: IF, GOTO, WHILE/DO/END, "
             "DPRNT) is not read: machinesim reads no branches, loops or macro output; post "
             "the program with them resolved into plain blocks", start + 1, text)
    else:
        fail(f"text {brief(text)!r} outside a comment: a word is one letter and a number "
             "(X1., M98 P1000); expected a comment in parentheses, e.g. "
             f"{brief('(' + text + ')')!r}", start + 1, text)
    return stop


#: Why '#' and '[' are refused where they stand: a program with them computes its numbers
#: when it runs (FANUC custom macro B; LinuxCNC's expressions), and a reader that does not
#: evaluate them cannot read them ('I[300 + [100 * sqrt[2]]]' had been ten problems, one for
#: each letter of 'sqrt', each asking for digits).
_MACROS = ("macro variables and expressions (#1, [#1 * 2], custom macro B or LinuxCNC's "
           "expressions) are not read: post the program with their values")


#: LinuxCNC's named parameters (``#<x_max> = 30``, ``G01 X#<x_max>``): one problem for each,
#: naming it (``X#<x_max>`` had been three: the '#', a "malformed number '<'" and stray text).
_NAMED_PARAMETER = ("LinuxCNC named parameter (#<name>), which this reader of FANUC text does "
                    "not read (no parameters or expressions): expand the program with their "
                    "values before reading it (docs/nc.md, 'LinuxCNC programs')")

#: LinuxCNC's O-word statements by their keyword: what each kind is called in the refusal.
_O_WORD_KINDS = {
    **dict.fromkeys(("sub", "endsub", "call", "return"), "subroutine"),
    **dict.fromkeys(("if", "elseif", "else", "endif", "while", "endwhile", "do", "repeat",
                     "endrepeat", "break", "continue"), "flow control"),
}


def _o_word_keyword(raw: str, i: int) -> str | None:
    """The LinuxCNC O-word keyword (``sub``, ``call``, ``while`` ...) that starts at
    ``raw[i]`` past blanks, as a whole run of letters, or None."""
    while i < len(raw) and raw[i] in _BLANK:
        i += 1
    stop = i
    while stop < len(raw) and raw[stop] in _LETTERS:
        stop += 1
    word = raw[i:stop].lower()
    return word if word in _O_WORD_KINDS else None


def _end_of_line_text(raw: str, i: int) -> int:
    """Where the text from ``raw[i]`` ends: the line's end, or a comment after it."""
    stop = len(raw)
    for mark in "(;":
        found = raw.find(mark, i)
        if 0 <= found < stop:
            stop = found
    return stop


def _linuxcnc_o_word(raw: str, start: int, fail) -> int:
    """Refuse, as one problem, LinuxCNC's O-word statement from the 'o' at ``raw[start]``
    to the line's end or its comment (``o<probe> sub``, ``o100 call [1] [2]``,
    ``o<loop> while [#1 lt 3]``): each had been a "malformed number '<'" and stray text.
    Returns the index where reading goes on."""
    i = start + 1
    while i < len(raw) and raw[i] in _BLANK:
        i += 1
    if raw.startswith("<", i):
        close = raw.find(">", i)
        i = close + 1 if close >= 0 else len(raw)
    else:
        number = _NUMBER.match(raw, i)
        i = number.end() if number else i
    keyword = _o_word_keyword(raw, i)
    stop = _end_of_line_text(raw, start)
    text = raw[start:stop].rstrip(_BLANK)
    kind = _O_WORD_KINDS.get(keyword, "statement") if keyword else "statement"
    fail(f"LinuxCNC O-word {kind} {brief(text)!r}, which this reader of FANUC text does not "
         "read (its subroutines, branches and loops are LinuxCNC's, not FANUC's O1234 ... "
         "M99 called by M98): expand the program into plain blocks before reading it "
         "(docs/nc.md, 'LinuxCNC programs')", start + 1, text)
    return stop


def _end_of_expression(raw: str, i: int) -> int:
    """The end of the macro expression starting at ``raw[i]`` ('#' or '['): its brackets
    closed (or the line's end), then what is not a blank, letter or comment. A LinuxCNC
    named parameter's name, ``#<x_max>``, is part of it."""
    depth = 0
    while i < len(raw):
        if raw.startswith("#<", i):
            close = raw.find(">", i)
            i = close + 1 if close >= 0 else len(raw)
            continue
        if raw[i] == "[":
            depth += 1
        elif raw[i] == "]":
            depth -= 1
        elif raw[i] in "(;" and depth == 0:
            break
        if depth == 0 and raw[i] not in "#[]0123456789.+-*/":
            break
        i += 1
    return i


def _end_of_garbage(raw: str, i: int) -> int:
    while i < len(raw) and raw[i] not in _BLANK and raw[i] not in _LETTERS and raw[i] not in "(;":
        i += 1
    return i


#: Address letters that take a negative value (coordinates, arc centres and radius, a
#: cycle's R plane); and those that take a whole number (codes, numbers, counts).
_SIGNED = frozenset("ABCIJKRUVWXYZ")
_WHOLE = frozenset("DGHLMNOPT")


def _example(letter: str) -> str:
    """A well-formed word for ``letter``: negative only where the letter takes it (F-12.5
    had been offered for a feed, which is refused), whole where it is a code or count."""
    letter = letter.upper()
    if letter in _WHOLE:
        return f"{letter}12"
    return f"{letter}-12.5" if letter in _SIGNED else f"{letter}12.5"
