"""The live viewer's kept stderr (`machinesim.viewer.live.StderrTail`): what a server that
ended wrote, its first lines, its first traceback's and its last, checked against the whole
stream of the same process run again."""

from __future__ import annotations

import subprocess
import sys

import pytest

from machinesim.viewer.live import STDERR_FIRST_LINES, STDERR_LAST_LINES, StderrTail

#: A Python error chained 100 times ('raise ... from'): a traceback of about 600 lines whose
#: first line is 'Traceback (most recent call last):' and whose root cause, 'level 0', comes
#: first; ``{chat}`` lines written before it.
CHAINED = ("import sys\n"
           "for i in range({chat}):\n"
           "    print(f'chat {{i}}', file=sys.stderr)\n"
           "error = None\n"
           "for i in range(100):\n"
           "    try:\n"
           "        raise RuntimeError(f'level {{i}}') from error\n"
           "    except RuntimeError as raised:\n"
           "        error = raised\n"
           "raise error\n")


def _kept_and_whole(script: str) -> tuple[StderrTail, list[str]]:
    """A StderrTail of ``script`` run to its end, and all ``script`` writes to stderr."""
    command = [sys.executable, "-c", script]
    whole = subprocess.run(command, capture_output=True, text=True, timeout=60).stderr
    process = subprocess.Popen(command, stderr=subprocess.PIPE, text=True, errors="replace")
    tail = StderrTail(process)
    process.wait(timeout=60)
    return tail, whole.splitlines()


def _left_out(count: int) -> str:
    return f"... {count} lines left out ..."


def test_a_long_traceback_keeps_its_head():
    # the last 200 lines alone were kept: a 600-line traceback lost its 'Traceback (most
    # recent call last):', its outer frames and its root cause, and as no line then began
    # a traceback, a crash's exception was not quoted either (last() gave "")
    tail, whole = _kept_and_whole(CHAINED.format(chat=0))
    assert len(whole) > STDERR_FIRST_LINES + STDERR_LAST_LINES
    assert whole[0] == "Traceback (most recent call last):"
    assert tail.lines() == [*whole[:STDERR_FIRST_LINES],
                            _left_out(len(whole) - STDERR_FIRST_LINES - STDERR_LAST_LINES),
                            *whole[-STDERR_LAST_LINES:]]
    assert "RuntimeError: level 0" in tail.lines()[:STDERR_FIRST_LINES]
    assert tail.last() == "RuntimeError: level 99"


def test_a_traceback_after_chat_keeps_its_head_and_the_chats():
    # 1000 lines of chat, then the traceback: the stream's first lines, the traceback's
    # first lines and the last lines, each gap counted
    tail, whole = _kept_and_whole(CHAINED.format(chat=1000))
    start = whole.index("Traceback (most recent call last):")
    assert start == 1000
    first, last = STDERR_FIRST_LINES, len(whole) - STDERR_LAST_LINES
    assert tail.lines() == [*whole[:first], _left_out(start - first),
                            *whole[start:start + first], _left_out(last - start - first),
                            *whole[last:]]
    assert tail.last() == "RuntimeError: level 99"


@pytest.mark.parametrize("count", [0, 1, STDERR_FIRST_LINES + STDERR_LAST_LINES])
def test_a_short_stream_is_kept_whole(count):
    # as many lines as are kept, or fewer: all of them, in order, and no gap
    tail, whole = _kept_and_whole(f"import sys\nfor i in range({count}): "
                                  "print(f'line {i}', file=sys.stderr)\n")
    assert whole == [f"line {i}" for i in range(count)]
    assert tail.lines() == whole
    assert tail.last() == ""  # no traceback: no cause to quote


def test_one_line_left_out_is_said_in_the_singular():
    count = STDERR_FIRST_LINES + STDERR_LAST_LINES + 1
    tail, whole = _kept_and_whole(f"import sys\nfor i in range({count}): "
                                  "print(f'line {i}', file=sys.stderr)\n")
    assert tail.lines() == [*whole[:STDERR_FIRST_LINES], "... 1 line left out ...",
                            *whole[-STDERR_LAST_LINES:]]


def test_a_killed_process_has_its_last_words_quoted_but_not_meshcats_port_search():
    # a server killed by a signal (the out-of-memory killer's SIGKILL) leaves no traceback:
    # what it said last was kept and never told; quoted when asked (any_line), past
    # meshcat's 'Port: N in use, trying another...' of its start
    script = ("import os, signal, sys\n"
              "print('WARNING:tornado.access:404 GET /favicon.ico', file=sys.stderr)\n"
              "print('Port: 6000 in use, trying another...', file=sys.stderr)\n"
              "print('', file=sys.stderr)\n"
              "sys.stderr.flush()\n"
              "os.kill(os.getpid(), signal.SIGKILL)\n")
    process = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.PIPE,
                               text=True)
    tail = StderrTail(process)
    assert process.wait(timeout=60) == -9
    assert tail.last() == ""  # no traceback: no cause, as before
    assert tail.last(any_line=True) == "WARNING:tornado.access:404 GET /favicon.ico"
