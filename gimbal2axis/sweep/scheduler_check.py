"""Whether the service at a --scheduler address speaks Dask's protocol, asked before distributed connects.

distributed's TCP comm reads the first 8 bytes a peer sends as the length of its first message and
allocates that much: a web server's answer "HTTP/1.1" reads as 3 EiB, and the client dies with a
MemoryError or, where the number fits, waits with the memory taken. A Dask scheduler greets every new
connection with its handshake (distributed/comm/core.py, Listener.on_connection), a message of a few
dozen bytes: the check reads those 8 bytes itself and refuses a service whose first message is
absent or implausibly long."""
from __future__ import annotations

import socket
import struct
import time

from .spec import SweepError

# A scheduler's handshake is under a hundred bytes (58 with distributed 2024); its prefix announcing
# more than this is not a scheduler's.
MAX_HANDSHAKE_BYTES = 1 << 16
PREFIX = struct.Struct("<Q")   # distributed/comm/tcp.py: the frames' length, "Q" on a little-endian host


def check_scheduler(address: str, timeout_s: float) -> None:
    """Refuses (SweepError, one line) a tcp:// address whose service does not greet as a Dask scheduler
    within `timeout_s`. Other schemes (tls://, ucx://, inproc://) are left to distributed; so is an
    address nothing listens at (distributed says that in its own words)."""
    host_port = _tcp_host_port(address)
    if host_port is None:
        return
    try:
        connection = socket.create_connection(host_port, timeout=timeout_s)
    except (OSError, ValueError):
        return
    with connection:
        prefix = _first_bytes(connection, PREFIX.size, timeout_s)
    not_dask = f"--scheduler {address}: the service there is not a Dask scheduler"
    if prefix is None or len(prefix) < PREFIX.size:
        said = f"sent nothing within {timeout_s:g} s" if prefix is None else \
            f"sent {prefix!r} and no more" if prefix else "closed the connection"
        raise SweepError(f"{not_dask}: it {said} (a scheduler greets every connection with its handshake)")
    announced, = PREFIX.unpack(prefix)
    if not 0 < announced <= MAX_HANDSHAKE_BYTES:
        raise SweepError(f"{not_dask}: its first message announces {announced:,} bytes (a scheduler's handshake "
                         f"is under {MAX_HANDSHAKE_BYTES:,}; its first bytes are {prefix!r})")


def _tcp_host_port(address: str) -> tuple[str, int] | None:
    scheme, separator, location = address.partition("://")
    if not separator:
        scheme, location = "tcp", address
    if scheme != "tcp":
        return None
    host, _, port = location.rpartition(":")
    host = host.strip("[]")   # [::1]:8786
    try:
        return (host or "127.0.0.1", int(port.split("/")[0]))
    except ValueError:
        return None


def _first_bytes(connection: socket.socket, count: int, timeout_s: float) -> bytes | None:
    """Up to `count` bytes the peer sends first: fewer when it closes, None when it sends none in time."""
    received = b""
    deadline = time.monotonic() + timeout_s
    while len(received) < count:
        left = deadline - time.monotonic()
        if left <= 0:
            return received or None
        connection.settimeout(left)
        try:
            chunk = connection.recv(count - len(received))
        except (socket.timeout, TimeoutError):
            return received or None
        except OSError:
            return received
        if not chunk:
            return received
        received += chunk
    return received
