"""Preloaded into each local Dask worker process of a campaign (`cluster._client`).

A Ctrl-C reaches every process of the terminal's group. The campaign's own process stops
the run and says what it kept; a worker that took the SIGINT as well printed a
KeyboardInterrupt traceback of its own. Workers ignore it: they end when the campaign's
process closes its cluster.

As it closes, a worker's heartbeat may still be on its way to the scheduler that has just
gone: Dask logs that as an ERROR with a traceback ("Failed to communicate with scheduler
during heartbeat"), printed after the campaign's own line (one CI run in five of
tests/test_campaign_dask.py's Ctrl-C). Workers drop that record; the campaign's process
learns of a scheduler really lost from its own connection.
"""

from __future__ import annotations

import logging
import signal
import threading

#: The start of Dask's record of a heartbeat that found the scheduler gone.
HEARTBEAT_LOST = "Failed to communicate with scheduler during heartbeat"


def _not_a_lost_heartbeat(record: logging.LogRecord) -> bool:
    return not str(record.msg).startswith(HEARTBEAT_LOST)


def dask_setup(worker) -> None:  # noqa: ARG001 - Dask's preload hook takes the worker
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("distributed.worker").addFilter(_not_a_lost_heartbeat)
