"""Preloaded into each local Dask worker process of a campaign (`runner._client`).

A Ctrl-C reaches every process of the terminal's group. The campaign's own process stops
the run and says what it kept; a worker that took the SIGINT as well printed a
KeyboardInterrupt traceback of its own. Workers ignore it: they end when the campaign's
process closes its cluster.
"""

from __future__ import annotations

import signal
import threading


def dask_setup(worker) -> None:  # noqa: ARG001 - Dask's preload hook takes the worker
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
