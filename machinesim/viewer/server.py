"""The live server: meshcat's bridge with its web server bound to 127.0.0.1 only.

meshcat's own server binds its ZeroMQ socket to 127.0.0.1 but its web server (tornado's
``listen(port)``) to every interface. This one binds both to the loopback interface and
serves the scene's page (meshcat's viewer plus the overlay with notes and legends) at the
URL it prints. Run as ``python -m machinesim.viewer.server [--port PORT]`` (`live.serve`
does); it prints ``zmq_url=...`` and ``web_url=...`` and runs until interrupted, or, with
``--until-stdin-ends`` (`live.serve` passes it), until its standard input reaches its end:
the process that started it, holding the pipe's other end, has ended (see `end_with_stdin`).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading

import tornado.web
from meshcat.servers.zmqserver import (
    VIEWER_ROOT,
    StaticFileHandlerNoCache,
    WebSocketHandler,
    ZMQWebSocketBridge,
)

from machinesim.viewer.live import LOOPBACK, PAGE_COMMAND
from machinesim.viewer.scene import page


class _LoopbackApplication(tornado.web.Application):
    """A tornado application that listens on `LOOPBACK` whatever address it is given."""

    def listen(self, port, address=None, **kwargs):
        return super().listen(port, address=LOOPBACK, **kwargs)


class LoopbackBridge(ZMQWebSocketBridge):
    """meshcat's ZeroMQ-to-WebSocket bridge, listening on the loopback interface only."""

    def __init__(self, port: int | None = None) -> None:
        self.title, self.overlay = "machinesim", ""
        self._web_port = port
        super().__init__(host=LOOPBACK, port=port)

    def setup_zmq(self, url):
        # meshcat takes the first free port from 6000 for ZeroMQ before the web server
        # binds: a web port asked for in that range (--port 6001, 6000 busy) was taken
        # from under it. Passed over here, as a port in use is.
        if self._web_port is not None and url.endswith(f":{self._web_port}"):
            raise OSError(f"port {self._web_port} is kept for the web server")
        return super().setup_zmq(url)

    def make_app(self):
        bridge = self

        class PageHandler(tornado.web.RequestHandler):
            def get(self, *_):
                self.set_header("Cache-Control", "no-store")
                self.write(bridge.page())

        return _LoopbackApplication([
            (r"/static/(?:index\.html)?", PageHandler),
            (r"/static/(.*)", StaticFileHandlerNoCache,
             {"path": VIEWER_ROOT, "default_filename": "index.html"}),
            (r"/", WebSocketHandler, {"bridge": self}),
        ])

    def page(self) -> str:
        script = ('<script src="main.min.js"></script>\n<script>\n'
                  'var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));\n'
                  "viewer.connect();\n</script>")
        return page(self.title, self.overlay, script)

    def handle_zmq(self, frames):
        if frames[0] == PAGE_COMMAND:
            self.title, self.overlay = frames[1].decode("utf-8"), frames[2].decode("utf-8")
            self.zmq_socket.send(b"ok")
            return
        super().handle_zmq(frames)


def end_with_stdin(loop) -> threading.Thread:
    """Stop ``loop`` (the bridge's tornado IOLoop) once standard input reaches its end.

    `live.start_server` gives the server a pipe for stdin and keeps its write end: when the
    starting process ends, however it ends (SIGTERM's default action, SIGKILL, a crash, or
    simply returning), the system closes that end and the read here returns end of file.
    A server left running had gone on holding its port (7000) as an orphan. This is chosen
    over Linux's PR_SET_PDEATHSIG, which exists on Linux alone, fires when the *thread* that
    started the child ends (prctl(2)) and needs a ``preexec_fn`` (not safe with threads,
    per the subprocess docs); and over polling ``os.getppid()``, which waits a poll
    interval and on Windows keeps the dead parent's id. A pipe's end of file once no
    process holds its write end is POSIX read()'s documented rule and holds on Windows too.
    A process forked from the starter after the server started holds a copy of the write
    end, and the server lasts until it too has ended.
    """
    def watch() -> None:
        try:
            while os.read(0, 65536):
                pass
        except OSError:
            pass  # stdin unreadable is as good as ended
        loop.add_callback(loop.stop)  # the one IOLoop method safe from another thread

    thread = threading.Thread(target=watch, daemon=True, name="machinesim-viewer-stdin")
    thread.start()
    return thread


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="meshcat server on 127.0.0.1 only")
    parser.add_argument("--port", type=int, default=None)
    parser.add_argument("--until-stdin-ends", action="store_true",
                        help="end when standard input reaches its end (the process that "
                             "started the server, holding its other end, has ended)")
    args = parser.parse_args(argv)
    try:
        bridge = LoopbackBridge(port=args.port)
    except Exception as error:  # said to the command that started us
        # said on the pipe the command reads for the URLs (`live.start_server`), in one line
        print(f"error={type(error).__name__}: {error}", flush=True)
        sys.exit(1)
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}", flush=True)
    # nobody reads the pipe after the URLs: a full pipe would stall the server
    sys.stdout = open(os.devnull, "w")
    if args.until_stdin_ends:
        end_with_stdin(bridge.ioloop)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass


__all__ = ["LoopbackBridge", "end_with_stdin", "main"]

if __name__ == "__main__":
    main()
