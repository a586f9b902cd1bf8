"""Headless Chromium driven over its DevTools protocol (a websocket): enough to test the web page.

No driver, no selenium: Debian's ``chromium`` started with ``--remote-debugging-port=0`` writes the
port it chose to ``DevToolsActivePort`` in its profile folder; the page target's websocket takes
the protocol's JSON commands (Page.navigate, Runtime.evaluate, Page.captureScreenshot) and sends
its events (Network.requestWillBeSent: every request the page makes, for the offline check).

:func:`start_browser` fails the test in CI (``CI`` or ``RIGID_ROT_SIM_CI`` set: ``.ci/run`` installs
chromium) when no browser starts, and skips it elsewhere, saying why.
"""

from __future__ import annotations

import base64
import itertools
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import numpy as np
import pytest
from websockets.sync.client import connect

CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
START_TIMEOUT = 30.0  # s: a cold start on a loaded 2-core machine
#: Software WebGL (SwiftShader): the machines have no GPU; root needs --no-sandbox.
FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-dev-shm-usage",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--window-size=1280,900",
)


def in_ci() -> bool:
    return bool(os.environ.get("CI") or os.environ.get("RIGID_ROT_SIM_CI"))


def _unavailable(reason: str) -> None:
    if in_ci():
        pytest.fail(f"browser test in CI: {reason} (.ci/run installs Debian's chromium as root)")
    pytest.skip(f"no browser: {reason} (Debian/Ubuntu: apt install chromium; in CI this test fails)")


class Browser:
    """One headless Chromium with one page; the page's network requests are logged in :attr:`requests`."""

    def __init__(self, executable: str) -> None:
        self.profile = Path(tempfile.mkdtemp(prefix="rigid_rot_chromium_"))
        self.log = self.profile / "chromium.log"
        with open(self.log, "wb") as log:
            self.process = subprocess.Popen(
                [executable, *FLAGS, "--remote-debugging-port=0", f"--user-data-dir={self.profile}", "about:blank"],
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
            )
        self.requests: list[str] = []
        self.events: list[dict[str, Any]] = []
        self._ids = itertools.count(1)
        port = self._devtools_port()
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10))
        page = next(t for t in targets if t.get("type") == "page")
        self.ws = connect(page["webSocketDebuggerUrl"], max_size=64 * 1024 * 1024, open_timeout=10)
        self.call("Network.enable")
        self.call("Page.enable")

    def _devtools_port(self) -> int:
        active = self.profile / "DevToolsActivePort"
        deadline = time.monotonic() + START_TIMEOUT
        while not (active.exists() and active.read_text().strip()):
            if self.process.poll() is not None:
                raise RuntimeError(f"chromium exited with {self.process.returncode}: {self.log.read_text()[-2000:]}")
            if time.monotonic() > deadline:
                raise RuntimeError(f"chromium wrote no DevToolsActivePort in {START_TIMEOUT:g} s")
            time.sleep(0.05)
        return int(active.read_text().split()[0])

    def _record(self, message: dict[str, Any]) -> None:
        method = message.get("method", "")
        params = message.get("params", {})
        if method == "Network.requestWillBeSent":
            self.requests.append(params["request"]["url"])
        elif method == "Network.webSocketCreated":
            self.requests.append(params["url"])
        self.events.append(message)

    def call(self, method: str, timeout: float = 60.0, **params: Any) -> dict[str, Any]:
        """Send one command; its result (events that arrive meanwhile are recorded)."""
        ident = next(self._ids)
        self.ws.send(json.dumps({"id": ident, "method": method, "params": params}))
        deadline = time.monotonic() + timeout
        while True:
            message = json.loads(self.ws.recv(timeout=max(0.01, deadline - time.monotonic())))
            if message.get("id") == ident:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})
            self._record(message)

    def pump(self, seconds: float) -> None:
        """Record the events that arrive within ``seconds``."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            try:
                self._record(json.loads(self.ws.recv(timeout=left)))
            except TimeoutError:
                return

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page."""
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def goto(self, url: str) -> None:
        self.call("Page.navigate", url=url)

    def until(self, expression: str, timeout: float, what: str) -> Any:
        """Evaluate until truthy; its value. AssertionError naming ``what`` after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while not (value := self.evaluate(expression)):
            assert time.monotonic() < deadline, f"the page never showed {what} in {timeout:g} s"
            self.pump(0.1)
        return value

    def text(self) -> str:
        return self.evaluate("document.body ? document.body.innerText : ''") or ""

    def click_button(self, label: str) -> None:
        clicked = self.evaluate(
            "(() => { const b = [...document.querySelectorAll('button')]"
            f".find(e => e.innerText.trim() === {json.dumps(label)}); if (b) b.click(); return !!b; }})()"
        )
        assert clicked, f"no button {label!r} on the page:\n{self.text()}"

    def canvas_box(self) -> dict[str, float]:
        """The largest canvas's rectangle (CSS px): the 3D view."""
        box = self.evaluate(
            "(() => { const c = [...document.querySelectorAll('canvas')]"
            ".map(e => e.getBoundingClientRect()).sort((a, b) => b.width * b.height - a.width * a.height)[0];"
            " return c ? {x: c.x, y: c.y, width: c.width, height: c.height} : null; })()"
        )
        assert box and box["width"] > 100 and box["height"] > 100, f"no 3D canvas on the page: {box}"
        return box

    def screenshot(self, path: Path, clip: dict[str, float] | None = None) -> np.ndarray:
        """A PNG of the page (or ``clip``) saved to ``path``; its pixels (rows, columns, RGB(A), 0..1)."""
        params: dict[str, Any] = {"format": "png"}
        if clip is not None:
            params["clip"] = {**clip, "scale": 1}
        data = base64.b64decode(self.call("Page.captureScreenshot", **params)["data"])
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        import matplotlib.image

        return np.asarray(matplotlib.image.imread(path))

    def foreign_requests(self, host: str) -> list[str]:
        """Requests the page made to anywhere but ``host`` (HOST:PORT); data: and blob: URLs are local."""
        return [
            url
            for url in self.requests
            if urlsplit(url).scheme not in ("data", "blob") and urlsplit(url).netloc != host
        ]

    def close(self) -> None:
        try:
            self.ws.close()
        except Exception:
            pass
        self.process.terminate()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(timeout=10)
        shutil.rmtree(self.profile, ignore_errors=True)


def start_browser() -> Browser:
    """A headless Chromium, or the test fails (CI) / skips (elsewhere) saying why."""
    executable = next((shutil.which(name) for name in CANDIDATES if shutil.which(name)), None)
    if executable is None:
        _unavailable(f"none of {', '.join(CANDIDATES)} on PATH")
    try:
        return Browser(str(executable))
    except Exception as exc:
        _unavailable(f"{executable} did not start: {exc}")
        raise  # unreachable: _unavailable fails or skips
