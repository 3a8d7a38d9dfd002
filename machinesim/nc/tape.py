"""Where a FANUC control stops reading an NC file: at the % that ends the program.

FANUC Series 16i/18i Operator's Manual (B-63524EN/01, 8. "Data input/output", "File
format", http://cncmanuals.com/fanuc/150/series-16i-18i-160i-180i-tb-operators-manual/page/675):
"A file starts with % or LF, followed by the actual data. A file always ends with %." So
the % that opens a file is the start mark and the next one ends it; in a file that does not
open with one, the first % ends it. What follows is not read (another program a DNC sender
appended, an editor's leftovers), and had been read here as more of the program.
"""

from __future__ import annotations

__all__ = ["end_of_program"]


def end_of_program(data: bytes) -> tuple[bytes, int | None]:
    """``data`` up to the end of its line with the % that ends the program (with its line
    end), and the first
    line (1-based) after it that holds anything but white space (None when none does, or
    when no % ends the program)."""
    lines = data.split(b"\n")
    marks = [i for i, line in enumerate(lines) if line.strip().startswith(b"%")]
    if not marks:
        return data, None
    first_text = next((i for i, line in enumerate(lines) if line.strip()), None)
    end = marks[0] if marks[0] != first_text else (marks[1] if len(marks) > 1 else None)
    if end is None:
        return data, None
    after = next((i + 1 for i in range(end + 1, len(lines)) if lines[i].strip()), None)
    return data[:sum(len(line) + 1 for line in lines[:end + 1])], after
