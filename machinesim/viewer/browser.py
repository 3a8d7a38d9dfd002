"""Headless Chromium, driven over the DevTools protocol: open a page, wait, take a screenshot.

Used to render a scene to PNG (`machinesim view ... --screenshot`), by the browser tests and by
the benchmark. It needs the Debian package ``chromium`` and nothing else: the DevTools
protocol is spoken over tornado's WebSocket client (tornado comes with meshcat).

Chromium is started with a fresh profile and with every name lookup failing and every
non-loopback request sent to a dead loopback proxy, so that a page, and the browser itself,
cannot reach any other host; pages on 127.0.0.1 (the live viewer) still load.
"""

from __future__ import annotations

import asyncio
import base64
import itertools
import json
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from tornado.websocket import websocket_connect

from machinesim.exceptions import MachineSimError

#: Executable names tried, in order.
CHROMIUM_NAMES = ("chromium", "chromium-browser")
#: What to run when Chromium is missing.
INSTALL_HINT = "apt-get update && apt-get install -y chromium"
#: The flags of every run. --headless, --no-sandbox (root in a container), --disable-gpu and
#: SwiftShader (WebGL on the CPU: there is no GPU), no first-run, update or background
#: traffic; name lookups fail (~NOTFOUND) and any other request goes to a dead loopback
#: proxy (port 9, discard), which Chromium bypasses for loopback addresses.
FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader", "--disable-background-networking",
    "--disable-component-update", "--no-first-run", "--no-default-browser-check",
    "--disable-sync", "--disable-extensions", "--disable-default-apps",
    "--disable-domain-reliability", "--disable-client-side-phishing-detection",
    "--disable-breakpad", "--no-pings", "--mute-audio",
    "--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1",
    "--proxy-server=127.0.0.1:9",
)
#: Seconds to wait for Chromium to start, for a page to load, and for a condition.
START_TIMEOUT_S = 30.0
LOAD_TIMEOUT_S = 60.0
#: Attempts at removing the temporary profile, 0.1 s apart (`Browser.close`).
PROFILE_CLEANUP_TRIES = 30
#: Largest DevTools message (a screenshot of a large window is a few MB of base64).
MAX_MESSAGE_BYTES = 256 << 20
#: A page has drawn once two animation frames have passed after its scripts ran.
_TWO_FRAMES = ("new Promise(done => requestAnimationFrame(() => "
               "requestAnimationFrame(() => done(true))))")


def find_chromium() -> str:
    """Path of the Chromium executable; MachineSimError with the install hint if missing."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    raise MachineSimError(f"headless Chromium is needed and was not found (looked for "
                          f"{', '.join(CHROMIUM_NAMES)}); install it: {INSTALL_HINT}")


class Browser:
    """One headless Chromium with one page, driven over the DevTools protocol.

    Parameters
    ----------
    width, height : int
        Viewport size, CSS px (device scale factor 1).

    Attributes
    ----------
    requests : list of str
        URLs the page requested (main document, scripts, fetches, WebSockets), in order.
    """

    def __init__(self, width: int = 1200, height: int = 800) -> None:
        executable = find_chromium()
        self.width, self.height = width, height
        self.requests: list[str] = []
        self._ids = itertools.count(1)
        self._loop = asyncio.new_event_loop()
        self._profile = tempfile.TemporaryDirectory(prefix="machinesim-chromium-")
        self._process = subprocess.Popen(
            [executable, *FLAGS, f"--window-size={width},{height}",
             f"--user-data-dir={self._profile.name}", "--remote-debugging-port=0",
             "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            self._connect()
        except BaseException:
            self.close()
            raise

    def _connect(self) -> None:
        port_file = Path(self._profile.name) / "DevToolsActivePort"
        deadline = time.monotonic() + START_TIMEOUT_S
        while not (port_file.is_file() and len(port_file.read_text().split()) == 2):
            if self._process.poll() is not None or time.monotonic() > deadline:
                raise MachineSimError("headless Chromium did not start (no DevTools port)")
            time.sleep(0.05)
        port, path = port_file.read_text().split()
        self._socket = self._run(lambda: websocket_connect(
            f"ws://127.0.0.1:{port}{path}", max_message_size=MAX_MESSAGE_BYTES))
        target = self._call("Target.createTarget", url="about:blank")["targetId"]
        self._session = self._call("Target.attachToTarget", targetId=target,
                                   flatten=True)["sessionId"]
        for domain in ("Page", "Network", "Runtime"):
            self._call(f"{domain}.enable", session=True)
        self._call("Emulation.setDeviceMetricsOverride", session=True, width=self.width,
                   height=self.height, deviceScaleFactor=1, mobile=False)

    def _run(self, start, timeout: float = LOAD_TIMEOUT_S):
        """Run ``start()`` (which makes an awaitable) on this browser's event loop."""
        async def run():
            return await asyncio.wait_for(start(), timeout)

        return self._loop.run_until_complete(run())

    def _call(self, method: str, session: bool = False, timeout: float = LOAD_TIMEOUT_S,
              **params):
        """Send one DevTools command and return its result, keeping events seen meanwhile."""
        ident = next(self._ids)
        message = {"id": ident, "method": method, "params": params}
        if session:
            message["sessionId"] = self._session
        self._socket.write_message(json.dumps(message))
        deadline = time.monotonic() + timeout
        while True:
            reply = self._next(deadline - time.monotonic())
            if reply.get("id") == ident:
                if "error" in reply:
                    raise MachineSimError(f"Chromium refused {method}: {reply['error']}")
                return reply.get("result", {})

    def _next(self, timeout: float) -> dict:
        if timeout <= 0.0:
            raise MachineSimError("headless Chromium did not answer in time")
        text = self._run(self._socket.read_message, timeout)
        if text is None:
            raise MachineSimError("headless Chromium closed the DevTools connection")
        message = json.loads(text)
        method = message.get("method", "")
        if method == "Network.requestWillBeSent":
            self.requests.append(message["params"]["request"]["url"])
        elif method == "Network.webSocketCreated":
            self.requests.append(message["params"]["url"])
        elif method == "Page.loadEventFired":
            self._loaded = True
        return message

    def open(self, url: str, timeout: float = LOAD_TIMEOUT_S) -> None:
        """Load ``url`` and wait for its load event."""
        self._loaded = False
        self._call("Page.navigate", session=True, url=url)
        deadline = time.monotonic() + timeout
        while not self._loaded:
            self._next(deadline - time.monotonic())

    def evaluate(self, expression: str, timeout: float = LOAD_TIMEOUT_S):
        """The value of a JavaScript expression in the page (promises are awaited)."""
        result = self._call("Runtime.evaluate", session=True, timeout=timeout,
                            expression=expression, awaitPromise=True, returnByValue=True)
        if "exceptionDetails" in result:
            raise MachineSimError(f"the page raised: {result['exceptionDetails'].get('text')}")
        return result["result"].get("value")

    def wait_for(self, expression: str, timeout: float = LOAD_TIMEOUT_S) -> None:
        """Poll a JavaScript expression until it is true."""
        deadline = time.monotonic() + timeout
        while not self.evaluate(expression):
            if time.monotonic() > deadline:
                raise MachineSimError(f"the page never satisfied {expression!r}")
            time.sleep(0.1)

    def wheel(self, x: float, y: float, delta_y: float) -> None:
        """Turn the mouse wheel over the point (x, y) of the viewport (CSS px) by
        ``delta_y`` px (positive: down), as a user's hand would."""
        self._call("Input.dispatchMouseEvent", session=True, type="mouseWheel", x=x, y=y,
                   deltaX=0, deltaY=delta_y)

    def screenshot(self) -> bytes:
        """PNG of the viewport, after the page has drawn two more frames."""
        self.evaluate(_TWO_FRAMES)
        return base64.b64decode(self._call("Page.captureScreenshot", session=True,
                                           format="png")["data"])

    def close(self) -> None:
        """End Chromium and remove its profile."""
        socket = getattr(self, "_socket", None)
        if socket is not None:
            socket.close()
        if self._process.poll() is None:
            self._process.terminate()
            try:
                self._process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        self._loop.close()
        # Chromium's helper processes can outlive the browser process by a moment and still
        # write into the profile (seen as "Directory not empty: 'Default'" under load): retry,
        # then leave what they still hold to the system's temporary-file cleaning.
        for _ in range(PROFILE_CLEANUP_TRIES):
            try:
                self._profile.cleanup()
                return
            except OSError:
                time.sleep(0.1)
        shutil.rmtree(self._profile.name, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def screenshot(url: str, ready: str = "true", width: int = 1200, height: int = 800) -> bytes:
    """PNG of ``url`` in headless Chromium, once the JavaScript ``ready`` is true."""
    with Browser(width, height) as browser:
        browser.open(url)
        browser.wait_for(ready)
        return browser.screenshot()


__all__ = ["FLAGS", "INSTALL_HINT", "Browser", "find_chromium", "screenshot"]
