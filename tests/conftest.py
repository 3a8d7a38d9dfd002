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


@pytest.fixture(scope="module")
def a0ib():
    """The 5-axis robonano_a0ib (its probe_tip 40 mm along +Y and 1 mm above the edge)."""
    import machinesim

    return machinesim.load_machine("robonano_a0ib")


@pytest.fixture(scope="module")
def flat():
    """5 x 3 x 1 mm block: x in [0, 5] mm, y in [0, 3] mm, top face at z = 0."""
    from machinesim.workpiece import block

    return block(5e-3, 3e-3, 1e-3)
