"""The live viewer's server does not outlive the process that started it (`live.serve`):
a script stopped by SIGTERM or SIGKILL, or one that simply ends, takes its server along,
where the server had lived on as an orphan holding its port."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import pytest

#: A user's script: a live viewer on ``port``; it prints the server's process id and URL,
#: then waits to be stopped, or ends at once ('ends').
SCRIPT = ("import sys, time\n"
          "from machinesim.viewer import serve\n"
          "from machinesim.viewer.scene import Scene\n"
          "live = serve(Scene('parent test'), int(sys.argv[1]))\n"
          "print(live.process.pid, live.url, flush=True)\n"
          "if sys.argv[2] != 'ends':\n"
          "    time.sleep(120)\n")

#: Seconds the server is given to end after the script has.
GRACE_S = 10.0

needs_proc = pytest.mark.skipif(not Path("/proc/self/stat").exists(),
                                reason="tells a process's state from /proc (Linux)")


def _unused_port() -> int:
    """A port the system has just given out and taken back (beyond the ports from 7000 that
    other live viewers take first)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _running(pid: int) -> bool:
    """Whether process ``pid`` runs: not gone, and not a zombie (an orphan's end is reaped
    by whoever adopted it, which in a container may be never)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] not in "ZX"


def _port_free(port: int) -> bool:
    with socket.socket() as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return False
        return True


@needs_proc
@pytest.mark.parametrize("stop", ["SIGTERM", "SIGKILL", "ends"])
def test_a_scripts_live_server_ends_with_the_script(stop):
    """``kill`` (SIGTERM's default action: no finally, no atexit) and ``kill -9`` of a script
    that called serve(), and a script that ended without closing its session: the server
    ends within a few seconds and its port is free. It had lived on with parent 1, its port
    taken (observed: port 7000 held after the script was gone)."""
    port = _unused_port()
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    script = subprocess.Popen([sys.executable, "-c", SCRIPT, str(port), stop],
                              stdout=subprocess.PIPE, text=True, env=env)
    watchdog = threading.Timer(60, script.kill)  # a script that hangs before its line
    watchdog.start()
    server = None
    try:
        line = script.stdout.readline()
        watchdog.cancel()
        pid, url = line.split()
        server = int(pid)
        assert url == f"http://127.0.0.1:{port}/static/"
        assert _running(server) and not _port_free(port)
        if stop != "ends":
            script.send_signal(getattr(signal, stop))
        status = script.wait(timeout=60)
        assert status == (0 if stop == "ends" else -getattr(signal, stop))
        # the main thread shows 'Z' as the process exits, while its other threads (ZeroMQ's)
        # still hold its sockets for a moment: both are waited for
        end = time.monotonic() + GRACE_S
        while (_running(server) or not _port_free(port)) and time.monotonic() < end:
            time.sleep(0.05)
        assert not _running(server), f"the server outlived its script by {GRACE_S:g} s"
        assert _port_free(port), f"port {port} still taken {GRACE_S:g} s after the script"
        with pytest.raises(OSError):
            urllib.request.urlopen(url, timeout=5)
    finally:
        watchdog.cancel()
        if script.poll() is None:
            script.kill()
            script.wait()
        if server is not None and _running(server):
            os.kill(server, signal.SIGKILL)  # the orphan this test found, not left behind
        script.stdout.close()
