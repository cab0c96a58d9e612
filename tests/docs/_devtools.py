"""A headless Chromium driven over the DevTools protocol, with nothing but the standard library.

Why the DevTools protocol and not ``chromium --dump-dom`` with ``--enable-logging=stderr``: the protocol reports
each console call with its level (``Runtime.consoleAPICalled``), every uncaught exception
(``Runtime.exceptionThrown``), the browser's own error log (``Log.entryAdded``: a script or stylesheet that does
not load) and every failed request with its URL (``Network.loadingFailed``), as structured events; the stderr log
is free text whose format changes between Chromium versions. It also lets the test wait for the load event and
then ask the page itself whether every image decoded (``HTMLImageElement.decode()``), which ``--dump-dom`` cannot.

The websocket client is the minimum RFC 6455 needs for this: one connection, masked text frames out, unmasked
(possibly fragmented) text frames in, pings answered.
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import shutil
import socket
import struct
import subprocess
import time
import urllib.parse
from pathlib import Path

#: Flags for a headless browser that runs as root in a container, with no network and no profile of its own.
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-extensions",
                  "--disable-default-apps", "--mute-audio", "--window-size=1280,900")
_WS_GUID = "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"


def find_chromium() -> str | None:
    """The Chromium executable on PATH (Debian's ``chromium``), or None."""
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    return None


class WebSocket:
    """A client websocket on ``ws://host:port/path`` (text messages only)."""

    def __init__(self, url: str, *, timeout: float = 30.0):
        parts = urllib.parse.urlparse(url)
        self._sock = socket.create_connection((parts.hostname, parts.port), timeout=timeout)
        key = base64.b64encode(os.urandom(16)).decode()
        self._sock.sendall((f"GET {parts.path} HTTP/1.1\r\nHost: {parts.hostname}:{parts.port}\r\n"
                            "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        self._buf = b""
        while b"\r\n\r\n" not in self._buf:
            self._fill()
        head, self._buf = self._buf.split(b"\r\n\r\n", 1)
        lines = head.decode("latin-1").split("\r\n")
        accept = base64.b64encode(hashlib.sha1((key + _WS_GUID).encode()).digest()).decode()
        headers = {k.strip().lower(): v.strip() for k, _, v in (line.partition(":") for line in lines[1:])}
        if " 101 " not in lines[0] + " " or headers.get("sec-websocket-accept") != accept:
            raise ConnectionError(f"websocket handshake with {url} failed: {lines[0]!r}")

    def _fill(self) -> None:
        chunk = self._sock.recv(65536)
        if not chunk:
            raise ConnectionError("the browser closed the DevTools connection")
        self._buf += chunk

    def _read(self, n: int) -> bytes:
        while len(self._buf) < n:
            self._fill()
        out, self._buf = self._buf[:n], self._buf[n:]
        return out

    def _send_frame(self, opcode: int, payload: bytes) -> None:
        n = len(payload)
        if n < 126:
            header = struct.pack("!BB", 0x80 | opcode, 0x80 | n)
        elif n < 1 << 16:
            header = struct.pack("!BBH", 0x80 | opcode, 0x80 | 126, n)
        else:
            header = struct.pack("!BBQ", 0x80 | opcode, 0x80 | 127, n)
        mask = os.urandom(4)
        masked = (int.from_bytes(payload, "big") ^ int.from_bytes((mask * (n // 4 + 1))[:n], "big")).to_bytes(n, "big")
        self._sock.sendall(header + mask + masked)

    def send(self, text: str) -> None:
        self._send_frame(0x1, text.encode())

    def recv(self, timeout: float) -> str:
        """The next text message; ``TimeoutError`` when none arrives within ``timeout`` seconds."""
        self._sock.settimeout(timeout)
        parts = []
        while True:
            try:
                b1, b2 = self._read(2)
            except socket.timeout as err:
                raise TimeoutError(f"no DevTools message within {timeout} s") from err
            n = b2 & 0x7F
            if n == 126:
                (n,) = struct.unpack("!H", self._read(2))
            elif n == 127:
                (n,) = struct.unpack("!Q", self._read(8))
            mask = self._read(4) if b2 & 0x80 else None
            data = self._read(n)
            if mask:
                data = bytes(b ^ mask[i % 4] for i, b in enumerate(data))
            opcode = b1 & 0x0F
            if opcode == 0x9:  # ping
                self._send_frame(0xA, data)
                continue
            if opcode == 0x8:
                raise ConnectionError("the browser closed the DevTools connection")
            if opcode in (0x1, 0x0):
                parts.append(data)
                if b1 & 0x80:
                    return b"".join(parts).decode()

    def close(self) -> None:
        try:
            self._send_frame(0x8, b"")
        except OSError:
            pass
        self._sock.close()


class Browser:
    """A headless Chromium process (started here, stopped by its own id) and one page attached to it."""

    def __init__(self, executable: str, profile: Path, *, timeout: float = 60.0):
        profile.mkdir(parents=True, exist_ok=True)
        port_file = profile / "DevToolsActivePort"
        port_file.unlink(missing_ok=True)  # a reused profile's file names a port of a browser that is gone
        self._ws = None
        self._profile = profile
        self._log = open(profile / "chromium-stderr.log", "wb")  # noqa: SIM115 - closed in close()
        self._proc = subprocess.Popen([executable, *CHROMIUM_FLAGS, f"--user-data-dir={profile}",
                                       "--remote-debugging-port=0", "about:blank"],
                                      stdout=subprocess.DEVNULL, stderr=self._log)
        deadline = time.monotonic() + timeout
        while not (port_file.exists() and len(port_file.read_text().split()) >= 2):
            if self._proc.poll() is not None or time.monotonic() > deadline:
                self.close()
                raise RuntimeError(f"chromium did not open its DevTools port (log: {profile / 'chromium-stderr.log'})")
            time.sleep(0.1)
        port, path = port_file.read_text().split()[:2]
        self._next = 0
        self.events: list[dict] = []
        try:
            self._ws = WebSocket(f"ws://127.0.0.1:{port}{path}", timeout=timeout)
            target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
            self._session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
            for domain in ("Page", "Runtime", "Log", "Network"):
                self.call(f"{domain}.enable", session=True)
        except BaseException:
            self.close()
            raise

    def call(self, method: str, params: dict | None = None, *, session: bool = False, timeout: float = 60.0):
        """Send one command and return its result; events that arrive meanwhile are kept in ``events``."""
        self._next += 1
        message = {"id": self._next, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = self._session
        self._ws.send(json.dumps(message))
        deadline = time.monotonic() + timeout
        while True:
            reply = json.loads(self._ws.recv(max(0.1, deadline - time.monotonic())))
            if reply.get("id") == self._next:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
            self.events.append(reply)

    def _wait_event(self, method: str, timeout: float) -> dict:
        deadline = time.monotonic() + timeout
        while True:
            for i, event in enumerate(self.events):
                if event.get("method") == method and event.get("sessionId") == self._session:
                    return self.events.pop(i)
            self.events.append(json.loads(self._ws.recv(max(0.1, deadline - time.monotonic()))))

    def evaluate(self, expression: str, *, timeout: float = 60.0):
        """The value of a JavaScript expression in the page (a promise is awaited)."""
        result = self.call("Runtime.evaluate", {"expression": expression, "awaitPromise": True,
                                                "returnByValue": True}, session=True, timeout=timeout)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression[:80]}…: {result['exceptionDetails']}")
        return result["result"].get("value")

    def open(self, url: str, *, timeout: float = 60.0) -> None:
        """Navigate to ``url`` and wait for its load event; earlier pages' events are dropped."""
        self.events.clear()
        self.call("Page.navigate", {"url": url}, session=True)
        self._wait_event("Page.loadEventFired", timeout)

    def problems(self, *, local_prefix: str = "file://") -> tuple[list[str], list[str]]:
        """(errors, offline): what went wrong on the page since it was opened.

        ``errors`` are console errors and assertions, uncaught exceptions, the browser's error log and failed
        requests for the site's own files; ``offline`` are failed requests to other hosts (this machine has no
        network; a reader's browser fetches them).
        """
        urls = {}
        for event in self.events:
            if event.get("method") == "Network.requestWillBeSent":
                urls[event["params"]["requestId"]] = event["params"]["request"]["url"]
        errors, offline = [], []
        for event in self.events:
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.exceptionThrown":
                details = params["exceptionDetails"]
                errors.append(f"uncaught exception: {details.get('exception', {}).get('description') or details}")
            elif method == "Runtime.consoleAPICalled" and params["type"] in ("error", "assert"):
                text = " ".join(str(a.get("value", a.get("description", ""))) for a in params.get("args", []))
                errors.append(f"console.{params['type']}: {text}")
            elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
                entry = params["entry"]
                url = entry.get("url", "")
                (errors if not url or url.startswith(local_prefix) else offline).append(
                    f"log ({entry['source']}): {entry['text']} {url}")
            elif method == "Network.loadingFailed" and not params.get("canceled"):
                url = urls.get(params["requestId"], "?")
                (errors if url.startswith(local_prefix) else offline).append(
                    f"request failed: {url}: {params.get('errorText')}")
        return errors, offline

    def requests(self) -> list[str]:
        """Every URL the page requested since it was opened (documents, scripts, styles, fonts, images, XHR)."""
        return [event["params"]["request"]["url"] for event in self.events
                if event.get("method") == "Network.requestWillBeSent"]

    def close(self) -> None:
        """Stop the browser this object started (by its process id) and wait for it."""
        if self._ws is not None:
            self._ws.close()
            self._ws = None
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait(10)
        self._log.close()
        # A browser that outlived the process started here (handed over to, or forked from it) holds this profile's
        # lock, a link to "host-pid": stop that process too, by its id, when its command line names this profile.
        lock = self._profile / "SingletonLock"
        try:
            pid = int(os.readlink(lock).rsplit("-", 1)[1])
            if f"--user-data-dir={self._profile}" in Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0"):
                os.kill(pid, 15)
        except (OSError, ValueError, IndexError):
            pass  # no lock, or its process is gone: nothing left running
