"""A scheduler address that answers, but not as a Dask scheduler (issue 29, item 19): an SSH banner was read as
a 3 EiB frame ("out of memory"), an HTTP server hung for minutes. Both are named as not answering as a Dask
scheduler, within the stated time. The servers are the test's own, on 127.0.0.1, closed at the end."""

from __future__ import annotations

import http.server
import socket
import threading
import time

import numpy as np
import pytest

pytest.importorskip("dask")
pytest.importorskip("distributed")

from satchain import load_preset  # noqa: E402
from satchain.engine import distributed as dist  # noqa: E402
from satchain.errors import SatchainIOError  # noqa: E402

LIMIT_S = 2.0  # the stated time, made short for the test


class _BannerServer:
    """Accepts connections on 127.0.0.1, writes an SSH banner and holds each until the peer closes (<= 10 s)."""

    def __init__(self):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self):
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            with conn:
                conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
                conn.settimeout(0.2)
                t0 = time.monotonic()
                while not self.stop.is_set() and time.monotonic() - t0 < 10:
                    try:
                        if not conn.recv(4096):
                            break
                    except TimeoutError:
                        continue
                    except OSError:
                        break

    def close(self):
        self.stop.set()
        self.thread.join(5)
        self.sock.close()


@pytest.fixture
def banner():
    s = _BannerServer()
    yield f"tcp://127.0.0.1:{s.port}"
    s.close()


@pytest.fixture
def http_server():
    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    srv.daemon_threads = True
    t = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.1}, daemon=True)
    t.start()
    yield f"tcp://127.0.0.1:{srv.server_address[1]}"
    srv.shutdown()
    srv.server_close()
    t.join(5)


@pytest.fixture
def short_limit(monkeypatch):
    monkeypatch.setattr(dist, "CONNECT_TIMEOUT_S", LIMIT_S)


@pytest.mark.parametrize("server", ["banner", "http_server"])
def test_an_address_that_answers_but_not_as_a_dask_scheduler_is_named_in_time(request, server, short_limit):
    address = request.getfixturevalue(server)
    t0 = time.monotonic()
    with pytest.raises(SatchainIOError, match=r"does not answer as a Dask scheduler") as e:
        dist.simulate_distributed(np.full((140, 140), 0.2), load_preset("ankarasat3"), pixel_m=0.098,
                                  scheduler=address)  # fmt: skip
    elapsed = time.monotonic() - t0
    assert elapsed < LIMIT_S + 1.5, elapsed
    assert address in str(e.value) and "memory" not in str(e.value)


def test_a_closed_port_is_still_called_unreachable(short_limit):
    with socket.create_server(("127.0.0.1", 0)) as s:
        port = s.getsockname()[1]  # bound then closed: nothing listens there
    with pytest.raises(SatchainIOError, match=r"cannot reach a Dask scheduler"):
        dist.simulate_distributed(np.full((140, 140), 0.2), load_preset("ankarasat3"), pixel_m=0.098,
                                  scheduler=f"tcp://127.0.0.1:{port}")  # fmt: skip
