"""The Dask cluster a campaign's trials run on: a local one it starts, or a scheduler's.

A local `dask.distributed.LocalCluster` of ``workers`` processes, one thread each, starts
without a dashboard (`NO_DASHBOARD`), with the nanny's environment less its
MALLOC_TRIM_THRESHOLD_, with SIGINT blocked in the workers and a Ctrl-C meanwhile held until
it stands (`_client`), and closes the same way (`_close`). A ``--scheduler`` address is
checked before the campaign folder is made (`check_scheduler`). Moved out of
`machinesim.campaign.runner`, which still exports the public names.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys

from machinesim._cores import usable_cores
from machinesim._interrupts import ctrl_c_deferred, sigint_blocked
from machinesim.exceptions import InputError

__all__ = ["GUARD", "NO_DASHBOARD", "SCHEDULER_TIMEOUT_S", "check_scheduler"]


#: How a local cluster starts (`LocalCluster`'s keywords): no dashboard, and its scheduler's
#: HTTP server (health checks, which it keeps with no dashboard) on a free port of
#: 127.0.0.1, not on 8787. With ``dashboard_address=None`` the server took 8787 first (its
#: default port), and where a second cluster had it, Dask warned "Port 8787 is already in
#: use" and moved on. The address is LocalCluster's documented form ('localhost:8787'; port 0
#: a random one); ``dashboard`` False, as None had it, keeps the dashboard off.
NO_DASHBOARD = {"dashboard_address": "127.0.0.1:0", "scheduler_kwargs": {"dashboard": False}}

#: Seconds a ``--scheduler`` has to accept the connection and answer Dask's handshake.
SCHEDULER_TIMEOUT_S = 20.0


def _scheduler_refused(scheduler: str, why: str) -> InputError:
    return InputError(f"cannot reach the Dask scheduler {scheduler!r} ({why}); expected the "
                      "address of a running one, e.g. tcp://host:8786", key="--scheduler")


def check_scheduler(scheduler: str, timeout_s: float | None = None) -> None:
    """Refuse, within ``timeout_s`` (default `SCHEDULER_TIMEOUT_S`), an address where no Dask
    scheduler answers.

    `distributed.Client`'s timeout bounds the connection but not the handshake after it: a
    service that accepts and never answers (a web server, say) held the command forever,
    and one that answers something else had its first bytes read as a message length (an
    allocation of exabytes, reported as out of memory). A TCP port where nothing listens is
    refused at once (Dask retries it until its timeout). Run on a thread of its own, so that
    a caller with an event loop of its own (a notebook) can call it too.
    """
    import asyncio
    import socket
    import threading

    if timeout_s is None:
        timeout_s = SCHEDULER_TIMEOUT_S
    from distributed.comm import connect, parse_address
    from distributed.comm.addressing import parse_host_port
    from distributed.comm.registry import get_backend

    try:
        scheme, location = parse_address(scheduler)
        get_backend(scheme)  # ValueError naming the schemes there are
        if scheme == "tcp":
            host, port = parse_host_port(location)
            if not 0 < port < 65536:
                raise ValueError(f"port {port}; expected 1 to 65535")
            socket.create_connection((host, port), timeout=timeout_s).close()
    except ConnectionRefusedError:
        raise _scheduler_refused(scheduler, "nothing listens there: connection refused") \
            from None
    except (OSError, ValueError, TypeError) as error:
        raise _scheduler_refused(scheduler, str(error) or type(error).__name__) from None
    if scheme != "tcp":  # tls://, ws:// ...: their credentials are the Client's to find
        return

    from distributed.security import Security

    failed: list[BaseException] = []
    options = Security().get_connection_args("client")  # as dask's config sets them

    async def handshake():
        comm = await asyncio.wait_for(connect(scheduler, timeout=timeout_s, **options),
                                      timeout_s)
        comm.abort()

    def probe():
        try:
            asyncio.run(handshake())
        except BaseException as error:  # reported below, on the caller's thread
            failed.append(error)

    thread = threading.Thread(target=probe, name="machinesim-scheduler-check", daemon=True)
    thread.start()
    thread.join(timeout_s + 5.0)
    if thread.is_alive():
        raise _scheduler_refused(scheduler, f"no answer within {timeout_s:g} s")
    if failed:
        error = failed[0]
        if isinstance(error, TimeoutError):
            why = f"it did not answer as a Dask scheduler within {timeout_s:g} s"
        elif isinstance(error, OSError):
            why = str(error) or type(error).__name__
        else:  # MemoryError, a decoding error: bytes that are no Dask message
            why = f"it answered, but not as a Dask scheduler: {type(error).__name__}"
        raise _scheduler_refused(scheduler, why)


def _client(workers, scheduler, client, trials: int | None = None):
    """(client, cluster to close or None); a local cluster of no more workers than
    ``trials`` (the trials to run), when given."""
    if client is not None:
        return client, None
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError, ValueError) as error:
            raise InputError(f"cannot reach the Dask scheduler {scheduler!r} ({error}); "
                             "expected the address of a running one, e.g. tcp://host:8786",
                             key="--scheduler") from None
    count = workers if workers is not None else usable_cores()
    if trials is not None:  # a worker with no trial to run only costs its start (~2 s, ~0.3 GB)
        count = max(1, min(count, trials))
    # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which makes glibc
    # hand back every freed block at once: a trial's many short-lived numpy arrays then
    # cost a fresh mmap each, and a probing trial ran 2.95 s instead of 1.64 s on one
    # core. Workers keep the nanny's single-thread BLAS settings without that one.
    import dask

    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}), \
            ctrl_c_deferred(), sigint_blocked(), _main_from_no_file_kept_here():
        # A Ctrl-C while the workers start waits until the cluster stands, and then
        # closes it (below); the workers start with SIGINT blocked, so that the
        # terminal's Ctrl-C, which reaches its whole process group, reaches none of them
        # while it imports (a traceback each), nor later (their preload ignores it too).
        try:
            cluster = LocalCluster(n_workers=count, threads_per_worker=1,
                                   processes=True, **NO_DASHBOARD,
                                   silence_logs=logging.ERROR,
                                   preload=["machinesim.campaign._worker_setup"])
        except RuntimeError as exc:  # each worker's own message is on stderr above
            main = sys.modules.get("__main__")
            script = getattr(main, "__file__", None)
            if script is None or getattr(main, "__spec__", True) is not None:
                raise  # python -m ..., an interactive session: no script's guard missing
            raise InputError(f"the local Dask workers did not start ({exc}); {GUARD}",
                             source=script, key="workers") from exc
    try:
        client = Client(cluster)
        client.run(_one_core_each)
    except BaseException:
        cluster.close()
        raise
    return client, cluster


@contextlib.contextmanager
def _main_from_no_file_kept_here():
    """Within the block, a main program read from no file (``python -`` fed on standard
    input: ``__file__`` is ``'<stdin>'``) is not handed to the workers spawned to run again.
    multiprocessing's spawn runs the parent's ``__main__.__file__`` in each new process, and
    '<stdin>' is no file: every local worker failed to start, and the call was refused as a
    script without the ``__main__`` guard, whether it had one or not. Without it the workers
    start as an interactive session's do (docs/campaigns.md: no guard needed there)."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if not (isinstance(path, str) and path.startswith("<") and path.endswith(">")):
        yield
        return
    del main.__file__
    try:
        yield
    finally:
        main.__file__ = path


def _one_core_each(dask_worker) -> None:
    """Keep a local worker to one core: pinned to core ``name mod cores`` (Linux), and the
    planner's and reader's thread pools to one thread. A trial alone spreads over ~1.3
    cores (manifold3d's TBB threads, the planner's pool); K such workers on K cores would
    fight for them, while one worker per core keeps every core busy with its own trial."""
    if hasattr(os, "sched_setaffinity"):
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cores[int(dask_worker.name) % len(cores)]})
    from machinesim.motion import chords
    from machinesim.nc import fastscan

    chords.WORKERS = fastscan.WORKERS = 1


#: What a script that runs a campaign needs, said where a worker's start met its call.
GUARD = ("a script that calls campaign.run must call it under 'if __name__ == \"__main__\":' "
         "(Dask starts each local worker as a new Python, which imports the script again "
         "as '__mp_main__'), as docs/campaigns.md shows")


def _close(client, cluster) -> None:
    """Close ``client`` and then ``cluster`` (None: none to close), the campaign's own. A
    Ctrl-C again meanwhile waits: no cluster left to Dask's atexit to close."""
    with ctrl_c_deferred():
        client.close()
        if cluster is not None:
            cluster.close()
