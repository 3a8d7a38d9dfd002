"""Live mode: start the loopback meshcat server (`machinesim.viewer.server`), replay a scene.

`serve` starts the server in its own process, sends it the scene's page overlay and its
meshcat commands over ZeroMQ, and returns a `LiveSession` with the URL to open.
"""

from __future__ import annotations

import re
import subprocess
import sys
import threading
from collections import deque
from dataclasses import dataclass, field

import zmq
from meshcat.servers.tree import SceneTree, find_node, walk

from machinesim._interrupts import Terminated
from machinesim.exceptions import MachineSimError
from machinesim.viewer.scene import Scene, overlay_html

#: The only address the live server listens on.
LOOPBACK = "127.0.0.1"
#: Seconds to wait for the server process to report its URLs.
START_TIMEOUT_S = 30.0
#: Seconds to wait for the server to take one command (a large mesh is a few MB).
REPLY_TIMEOUT_S = 60.0

#: `LiveSession.wait` waits on the server in steps of this many seconds, so that a Ctrl-C
#: the kernel delivered to another thread of the process is read between two steps.
WAIT_STEP_S = 0.2
#: ZeroMQ command that sets the page's title and overlay (ours, beside meshcat's commands).
PAGE_COMMAND = b"machinesim_page"
#: Lines of the server's stderr kept from its start, and from the start of its first Python
#: traceback (where 'Traceback (most recent call last):' and the outer frames are, or a
#: chained exception's root cause): a long traceback kept its end alone.
STDERR_FIRST_LINES = 50
#: Lines of the server's stderr kept at its end (a traceback's end, tornado's warnings).
#: Lines between the first and the last are dropped, so a chatty server costs no more memory.
STDERR_LAST_LINES = 200
#: Characters of one stderr line a message quotes.
STDERR_LINE_SHOWN = 300
#: The line a traceback starts with.
TRACEBACK_START = "Traceback (most recent call last)"
#: meshcat's line for a ZeroMQ port it passed over as it started: chatter of a server that
#: started, never what it said last before it ended.
_PORT_SEARCH = re.compile(r"Port: \d+ in use, trying another\.\.\.")


class StderrTail:
    """What ``process`` writes to its stderr (a text pipe): its first `STDERR_FIRST_LINES`
    lines, the first as many of its first Python traceback, and its last `STDERR_LAST_LINES`
    lines, read by a daemon thread as they come: the pipe never fills, so a chatty server is
    not stalled, and a server that crashed leaves its traceback here, where stderr had gone
    to /dev/null (a crash was told as 'exit status 1' alone)."""

    def __init__(self, process: subprocess.Popen) -> None:
        self._process = process
        # (number of the line in the stream, line); the three overlap when it is short
        self._first: list[tuple[int, str]] = []
        self._traceback: list[tuple[int, str]] = []
        self._last: deque[tuple[int, str]] = deque(maxlen=STDERR_LAST_LINES)
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._drain, args=(process.stderr,),
                                        daemon=True, name="machinesim-viewer-stderr")
        self._thread.start()

    def _drain(self, stream) -> None:
        with stream:
            for number, line in enumerate(stream):
                self._keep(number, line.rstrip("\r\n"))

    def _keep(self, number: int, line: str) -> None:
        with self._lock:
            if len(self._first) < STDERR_FIRST_LINES:
                self._first.append((number, line))
            if self._traceback:
                if len(self._traceback) < STDERR_FIRST_LINES:
                    self._traceback.append((number, line))
            elif line.startswith(TRACEBACK_START):
                self._traceback.append((number, line))
            self._last.append((number, line))

    def _wait(self, timeout: float) -> None:
        if self._process.poll() is not None:
            self._thread.join(timeout)

    def lines(self, timeout: float = 5.0) -> list[str]:
        """The lines kept so far, oldest first, with ``... K lines left out ...`` where lines
        were dropped between them; once the process has ended, all it wrote (its first
        lines, its first traceback's and its last), waiting up to ``timeout`` s for the
        pipe's rest to be read."""
        self._wait(timeout)
        with self._lock:
            kept = dict(self._first)
            kept.update(self._traceback)
            kept.update(self._last)
        lines, after = [], 0  # after: the number of the line that follows those told
        for number in sorted(kept):
            if number > after:
                lines.append(f"... {number - after} line{'s' * (number - after > 1)} "
                             "left out ...")
            lines.append(kept[number])
            after = number + 1
        return lines

    def last(self, timeout: float = 5.0, *, any_line: bool = False) -> str:
        """The last line that is not blank, stripped and cut to `STDERR_LINE_SHOWN`
        characters, when the process wrote a Python traceback (its exception, the cause of a
        crash); "" otherwise. Without a traceback the last line is no cause (a process that
        ended by itself had its chance to say why), unless ``any_line``: a process killed by
        a signal leaves no traceback, and what it said last is all there is. meshcat's
        "Port: 6002 in use, trying another..." of its start is never quoted."""
        self._wait(timeout)
        with self._lock:
            if not (self._traceback or any_line):
                return ""
            last = [line for _, line in self._last]
        for line in reversed(last):
            line = line.strip()
            if line and not _PORT_SEARCH.fullmatch(line):
                return (line if len(line) <= STDERR_LINE_SHOWN
                        else line[:STDERR_LINE_SHOWN] + "...")
        return ""


@dataclass
class LiveSession:
    """A running live server showing a scene.

    Attributes
    ----------
    url : str
        The page to open, ``http://127.0.0.1:PORT/static/``.
    zmq_url : str
        Where the server takes meshcat commands.
    process : subprocess.Popen
        The server process; `close` ends it.
    messages : int
        Messages a browser that connects now receives (meshcat's viewer counts them in
        ``viewer.num_messages_received``): the scene is complete when it has them all.
    stderr : StderrTail, optional
        What the server wrote to stderr (`StderrTail.last` after it ended: a crash's
        exception, or a killed server's last words); None for a process whose stderr is not piped.
    """

    url: str
    zmq_url: str
    process: subprocess.Popen
    messages: int = 0
    stderr: StderrTail | None = field(default=None, repr=False)

    def send(self, scene: Scene) -> None:
        """Send ``scene`` (page overlay and commands) to the server, which has shown nothing
        yet (`serve` does this once)."""
        socket = zmq.Context.instance().socket(zmq.REQ)
        socket.setsockopt(zmq.RCVTIMEO, int(REPLY_TIMEOUT_S * 1000))
        socket.connect(self.zmq_url)
        try:
            socket.send_multipart([PAGE_COMMAND, scene.title.encode("utf-8"),
                                   overlay_html(scene).encode("utf-8")])
            socket.recv()
            for kind, path, data in scene.frames:
                socket.send_multipart([kind.encode("utf-8"), path.encode("utf-8"), data])
                reply = socket.recv()
                if reply != b"ok":
                    raise MachineSimError(f"the live viewer refused a {kind} command at "
                                          f"{path!r}: {reply.decode('utf-8', 'replace')}")
        except zmq.Again:
            raise MachineSimError(f"the live viewer server did not answer within "
                                  f"{REPLY_TIMEOUT_S:g} s") from None
        finally:
            socket.close(linger=0)
        self.messages = replay_count(scene.frames)

    def wait(self) -> int | None:
        """Block until the server process ends, or until Ctrl-C: its exit code, or None
        after Ctrl-C, which ends the server (a script's ``live.wait()`` is stopped so, as
        the command line's viewer is, without a KeyboardInterrupt traceback). SIGTERM
        (`machinesim._interrupts.Terminated`) ends the server too and is raised on."""
        try:
            while True:  # in steps: a Ctrl-C the kernel hands to another of this process's
                # threads (the server's stderr reader) only sets Python's flag, which a main
                # thread blocked in waitpid never reads; between steps it does
                try:
                    return self.process.wait(timeout=WAIT_STEP_S)
                except subprocess.TimeoutExpired:
                    continue
        except KeyboardInterrupt as stop:
            self.close()
            if isinstance(stop, Terminated):
                raise  # SIGTERM: the caller is stopped, not left to go on as after Ctrl-C
            return None

    def close(self) -> None:
        """End the server process."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self.process.stdin is not None:
            self.process.stdin.close()  # the pipe that told the server this process lives

    def __enter__(self) -> LiveSession:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def replay_count(frames) -> int:
    """How many messages meshcat's server sends a new browser after ``frames``.

    The server keeps, per scene node, the last object, the properties set since it, the
    last transform and the last animation, and replays those (meshcat.servers.zmqserver).
    """
    tree = SceneTree()
    for kind, path, _ in frames:
        names = [p for p in path.split("/") if p]
        if kind == "delete":
            parent = find_node(tree, names[:-1]) if names else None
            if parent is None:
                tree = SceneTree()
            else:
                parent.pop(names[-1], None)
            continue
        node = find_node(tree, names)
        if kind == "set_object":
            node.object, node.properties = True, []
        elif kind == "set_property":
            node.properties.append(True)
        elif kind == "set_transform":
            node.transform = True
        elif kind == "set_animation":
            node.animation = True
    return sum((n.object is not None) + len(n.properties) + (n.transform is not None)
               + (n.animation is not None) for n in walk(tree))


def server_command(port: int | None = None) -> list[str]:
    """The command that runs the loopback server (`machinesim.viewer.server`), which ends
    when its stdin does (`start_server` keeps the pipe's write end)."""
    command = [sys.executable, "-u", "-m", "machinesim.viewer.server", "--until-stdin-ends"]
    return command if port is None else [*command, "--port", str(port)]


def start_server(port: int | None = None) -> LiveSession:
    """Start the loopback server in a new process (nothing shown yet).

    The server has `START_TIMEOUT_S` to print its two URLs: past it, it is ended (which
    ends the wait for its next line too) and a MachineSimError says so, where a server that
    printed nothing hung the command; one that could not start says why (``error=...``).

    The server's stdin is a pipe whose write end only this process holds (the session's
    ``process.stdin``; Python's descriptors are not inherited, PEP 446): when this process
    ends, by SIGTERM or SIGKILL too, the server reads end of file and ends
    (`machinesim.viewer.server.end_with_stdin`), where it had lived on, holding its port.
    """
    process = subprocess.Popen(server_command(port), stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               errors="replace")
    stderr = StderrTail(process)  # drained from now on: stderr never stalls the server
    late = threading.Event()

    def give_up() -> None:
        late.set()
        process.kill()

    timer = threading.Timer(START_TIMEOUT_S, give_up)
    timer.start()
    urls, cause = {}, ""
    try:
        while len(urls) < 2 and not cause:
            line = process.stdout.readline()
            if not line:
                break
            key, _, value = line.strip().partition("=")
            if key in ("zmq_url", "web_url"):
                urls[key] = value
            elif key == "error":
                cause = f": {value}"
    finally:
        timer.cancel()
    if len(urls) < 2:
        process.kill()
        process.wait()
        process.stdin.close()
        why = (f"gave no address within {START_TIMEOUT_S:g} s" if late.is_set()
               else "ended before giving its address")
        last = "" if cause else stderr.last()  # a crash before main's 'error=' (an import)
        cause = cause or (f": {last}" if last else "")
        if port is None:
            raise MachineSimError(f"the live viewer server did not start (it {why}{cause}; "
                                  "is the port free? try --port, or --html FILE to export "
                                  "instead)")
        # the port asked for: name it, not 'try --port' to a user who gave one
        raise MachineSimError(f"--port {port}: the live viewer server did not start on it (it "
                              f"{why}{cause}); expected a free port: try another, or --html "
                              "FILE to export instead")
    return LiveSession(urls["web_url"], urls["zmq_url"], process, stderr=stderr)


def serve(scene: Scene, port: int | None = None) -> LiveSession:
    """Show ``scene`` live: start the loopback server and replay the scene into it.

    Parameters
    ----------
    scene : Scene
    port : int, optional
        Web port; default: the first free one from 7000 (meshcat's rule).

    Returns
    -------
    LiveSession
        Open `LiveSession.url` in a browser; `LiveSession.close` ends the server.
    """
    session = start_server(port)
    try:
        session.send(scene)
    except BaseException:
        session.close()
        raise
    return session


__all__ = ["LOOPBACK", "LiveSession", "StderrTail", "replay_count", "serve",
           "server_command", "start_server"]
