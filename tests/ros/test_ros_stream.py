"""psgsl live --foxglove: the live channels reach a Foxglove WebSocket client (a minimal client written here, speaking
the foxglove.sdk.v1 subprotocol: advertise, subscribe, binary message data)."""

from __future__ import annotations

import base64
import json
import socket
import struct
import time

import numpy as np
import pytest

pytest.importorskip("foxglove", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from psgsl_pgm.experiment import VARIANTS
from psgsl_pgm.ros._stream import FoxgloveStream
from psgsl_pgm.sim import default_house


def _recv(sock, n):
    out = b""
    while len(out) < n:
        chunk = sock.recv(n - len(out))
        if not chunk:
            raise ConnectionError("closed")
        out += chunk
    return out


def _frame(sock):
    b0, b1 = _recv(sock, 2)
    n = b1 & 0x7F
    if n == 126:
        n = struct.unpack(">H", _recv(sock, 2))[0]
    elif n == 127:
        n = struct.unpack(">Q", _recv(sock, 8))[0]
    return b0 & 0x0F, _recv(sock, n)


def _send_text(sock, text):
    data, mask = text.encode(), b"\x01\x02\x03\x04"
    head = bytes([0x81]) + (bytes([0x80 | len(data)]) if len(data) < 126 else bytes([0x80 | 126]) +
                            struct.pack(">H", len(data)))
    sock.sendall(head + mask + bytes(c ^ mask[i % 4] for i, c in enumerate(data)))


def _connect(port):
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    key = base64.b64encode(b"psgsl-live-test!").decode()
    sock.sendall((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                  f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
                  "Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n").encode())
    head = b""
    while b"\r\n\r\n" not in head:
        head += _recv(sock, 1)
    assert b" 101 " in head.split(b"\r\n")[0]
    return sock


def test_a_client_receives_the_posteriors_and_the_goal():
    grid = default_house(0).grid
    stream = FoxgloveStream(grid, VARIANTS, port=0)
    try:
        sock = _connect(stream.port)
        channels, end = {}, time.monotonic() + 5
        while len(channels) < 6 and time.monotonic() < end:
            op, payload = _frame(sock)
            if op == 1:
                msg = json.loads(payload)
                if msg.get("op") == "advertise":
                    channels.update({c["topic"]: c for c in msg["channels"]})
        assert {f"/posterior/{v}" for v in VARIANTS} | {"/map", "/robot/pose", "/robot/path", "/robot/next"} \
            <= set(channels)
        assert channels["/posterior/semantics"]["schemaName"] == "foxglove.Grid"
        assert channels["/robot/next"]["schemaName"] == "foxglove.PoseInFrame"
        _send_text(sock, json.dumps({"op": "subscribe", "subscriptions": [
            {"id": 7, "channelId": channels["/posterior/semantics"]["id"]},
            {"id": 8, "channelId": channels["/robot/next"]["id"]}]}))
        time.sleep(0.3)  # the server takes the subscription before the first log
        rng = np.random.default_rng(3)
        posts = rng.random((2, len(VARIANTS), *grid.shape))
        posts /= posts.sum(axis=(2, 3), keepdims=True)
        goals = [(1.25, 6.25, 0.5), (2.75, 5.75, -1.0)]
        t0 = 1_700_000_000_000_000_000
        for k in range(2):
            stream.step(t0 + k * 10**9, (1.0 + k, 6.0), 0.0, posts[k], goals[k])
        got = {}
        while len(got) < 4:
            op, payload = _frame(sock)
            if op == 2 and payload[0] == 1:
                sub, t = struct.unpack("<IQ", payload[1:13])
                got[(sub, t)] = payload[13:]
        for k in range(2):
            cells = np.asarray(posts[k][VARIANTS.index("semantics")], dtype=np.float32).tobytes()
            assert cells in got[(7, t0 + k * 10**9)]
            goal = got[(8, t0 + k * 10**9)]
            assert struct.pack("<d", goals[k][0]) in goal and struct.pack("<d", goals[k][1]) in goal
        with pytest.raises(ValueError, match="posteriors must have shape"):
            stream.step(t0, (1.0, 6.0), 0.0, posts[0][:2], goals[0])
        sock.close()
    finally:
        stream.close()


def test_a_taken_port_and_a_bad_port_are_refused():
    grid = default_house(0).grid
    first = FoxgloveStream(grid, VARIANTS, port=0)
    try:
        with pytest.raises(RuntimeError, match="already in use"):
            FoxgloveStream(grid, VARIANTS, port=first.port)
    finally:
        first.close()
    with pytest.raises(ValueError, match="port must be"):
        FoxgloveStream(grid, VARIANTS, port=70000)
