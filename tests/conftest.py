"""Fixtures shared by several test files."""

from __future__ import annotations

import signal
import time
from pathlib import Path

import numpy as np
import pytest

#: pytest.approx compares within an absolute 1e-12 unless told otherwise, whatever ``rel``
#: says: a removed volume of 3.65e-14 m^3 passed against 3.60e-14 (a test helper's retract
#: ran the groove on 63 um, tests/test_cutting_batch.py), and 40 comparisons of volumes and
#: lengths in SI could not fail so. Below this magnitude an expected value must give its
#: absolute tolerance (``abs=0.0`` to compare by ``rel`` alone).
APPROX_SMALL = 1e-10
_approx = pytest.approx


def _approx_with_abs(expected, rel=None, abs=None, nan_ok=False):
    if abs is None:
        try:
            values = np.abs(np.asarray(expected, dtype=np.float64))
        except (TypeError, ValueError):  # a mapping or mixed values: as pytest compares them
            values = np.zeros(0)
        small = values[(values > 0.0) & (values < APPROX_SMALL)]
        if small.size:
            raise AssertionError(
                f"pytest.approx of {small.min():.3g} without abs: its default abs of 1e-12 "
                f"would decide, not rel={rel}; give abs= (abs=0.0: rel alone)")
    return _approx(expected, rel=rel, abs=abs, nan_ok=nan_ok)


pytest.approx = _approx_with_abs


@pytest.fixture
def degree_like_planer(tmp_path) -> str:
    """The path of planer_4axis with its A limits written as degrees (+-45): it loads with
    the `MachineSimWarning` of rotary limits that read as degrees (tests of campaigns)."""
    from machinesim.machines import models_dir

    text = (models_dir() / "planer_4axis.urdf").read_text()
    rad = 'lower="-0.7853981633974483" upper="0.7853981633974483"'
    assert text.count(rad) == 1
    path = tmp_path / "planer_4axis.urdf"
    path.write_text(text.replace(rad, 'lower="-45" upper="45"'))
    return str(path)


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)  # as a terminal's job has it (not nohup's)


@pytest.fixture
def as_in_a_terminal() -> dict:
    """`subprocess.Popen` keywords that give the child the SIGINT a terminal's Ctrl-C meets
    (and the SIGHUP its closing sends): the default disposition, whatever the test runner
    inherited. A shell's background job
    starts with SIGINT ignored, and a Python started so installs no KeyboardInterrupt
    handler: a test of Ctrl-C would then see the child go on."""
    return {"preexec_fn": _default_sigint}


def _interrupted(process, ready, sig=signal.SIGINT) -> tuple[str, str]:
    """Ctrl-C (or ``sig``) to ``process`` (a `subprocess.Popen` with text pipes) once
    ``ready(process)`` returns (a str: once it maps a library whose path holds it,
    `_mapping`); its stdout and stderr to the end. Fails if it ended before; killed if a
    check fails."""
    try:
        (_mapping(ready) if isinstance(ready, str) else ready)(process)
        assert process.poll() is None, "the process ended before it could be interrupted"
        process.send_signal(sig)
        return process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()


@pytest.fixture
def interrupted():
    """``interrupted(process, ready, sig=SIGINT)``: Ctrl-C (or ``sig``) once
    ``ready(process)`` returns, or once the process maps a library whose path holds
    ``ready`` (a str); then its stdout and stderr."""
    return _interrupted


def _mapping(library: str, timeout: float = 60.0):
    """A ``ready`` for `interrupted`: until the process maps a file whose path holds
    ``library`` (/proc/PID/maps), the process ends, or ``timeout`` s pass."""
    def ready(process) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and process.poll() is None:
            try:
                if library in Path(f"/proc/{process.pid}/maps").read_text():
                    return
            except OSError:
                pass
            time.sleep(0.001)
    return ready


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


#: The trials of `campaign`: paper 000's calibration alone (``identify_only``: ~1.5 s each).
ARM = dict(identify_only=True)


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """Paper 000's calibration campaign of 3 trials, two parameters varied (tests of
    campaigns' results and of resuming them): its folder, its ``vary`` and its Dataset."""
    from machinesim.campaign import run

    out = tmp_path_factory.mktemp("arm")
    vary = ["tool.y=normal:-178um,20um", "microscope.sigma=uniform:5nm,60nm"]
    ds = run("tool_rotation_arm", 3, vary=vary, seed=11, out=out, workers=0,
             progress=False, **ARM)
    return out, vary, ds


#: The test files holding the suite's slowest tests, each with the seconds of its slowest
#: test on CI's 2 cores (`make test`'s ``--durations``). `pytest_collection_modifyitems` runs
#: these files first, the slowest first. pytest-xdist's worksteal hands each worker a
#: contiguous half of the collection and lets an idle worker steal the tail of the other's
#: queue; collected alphabetically, the 138 s and 77 s scenario runs of test_workpiece_setting_*
#: were the last files, so they started near the end of the run while the other worker
#: went idle. Run first, the tail is made of short tests and the workers end together.
#: Only the order changes (whole files move, their module fixtures made once as before).
SLOWEST_FILES_S = {
    "test_workpiece_setting_fidelity.py": 137.6,
    "test_workpiece_setting_procedure.py": 76.9,
    "test_scenarios.py": 56.9,
    "test_scenario_budget_jobs.py": 24.3,
    "test_nc_corpus_cut.py": 21.2,
    "test_lab_turning.py": 21.2,
    "test_workpiece_setting_crown.py": 19.7,
    "test_budget_jobs.py": 17.3,
}


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The files of `SLOWEST_FILES_S` first, the slowest first; within a file, and among the
    other files, the collected order (a stable sort)."""
    items.sort(key=lambda item: -SLOWEST_FILES_S.get(item.path.name, 0.0))
