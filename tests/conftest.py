"""Fixtures shared by several test files."""

from __future__ import annotations

import signal

import pytest


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.fixture
def as_in_a_terminal() -> dict:
    """`subprocess.Popen` keywords that give the child the SIGINT a terminal's Ctrl-C meets:
    the default disposition, whatever the test runner inherited. A shell's background job
    starts with SIGINT ignored, and a Python started so installs no KeyboardInterrupt
    handler: a test of Ctrl-C would then see the child go on."""
    return {"preexec_fn": _default_sigint}
