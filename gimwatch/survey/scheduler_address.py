"""A Dask scheduler address checked before Dask is given it: its form, then its first bytes.

Dask's client trusts what answers at an address: an HTTP server's first eight bytes
("HTTP/1.1") read as a frame length asked for a 3 EiB allocation, and a port that accepts and
never answers kept the command waiting. So, before ``distributed.Client`` connects:

1. `check_address` refuses what is not ``[scheme://]host:port`` (or ``inproc://...``) without
   a traceback, malformed URLs included;
2. `probe_scheduler` opens one TCP connection to a ``tcp://`` address with a timeout of
   `HANDSHAKE_SECONDS` and reads the first frame header a Dask scheduler sends unasked (its
   handshake: an 8-byte little-endian length, then that many bytes). Silence, a refused
   connection, or a length beyond `MAX_HANDSHAKE_BYTES` is refused with one line.
"""

from __future__ import annotations

import socket
import struct
import time
from urllib.parse import urlsplit

from gimwatch.errors import InputError

__all__ = ["HANDSHAKE_SECONDS", "MAX_HANDSHAKE_BYTES", "check_address", "probe_scheduler"]

#: The longest gimwatch waits for a scheduler to connect and send its handshake (s).
HANDSHAKE_SECONDS = 10.0
#: The largest first frame taken for a Dask handshake (a real one is under 1 KiB).
MAX_HANDSHAKE_BYTES = 1 << 20
_RULE = "'local' or a Dask scheduler address tcp://host:port"
_NAME = "scheduler"  # the CLI shows it as --scheduler


def check_address(scheduler: str) -> None:
    """Refuse what is not ``[scheme://]host:port`` (port 1..65535) or ``inproc://...``.

    Raises:
        InputError: The address is malformed (a bad port, an unclosed IPv6 bracket, a path).
    """
    try:
        parts = urlsplit(scheduler if "://" in scheduler else f"tcp://{scheduler}")
        port = parts.port
        host = parts.hostname
    except ValueError:  # a port out of range or not a number, an unclosed '['
        raise InputError(_NAME, _RULE, scheduler) from None
    if parts.scheme == "inproc":  # inproc://host/pid/n, a scheduler in this process
        well_formed = bool(host)
    else:
        well_formed = (
            parts.scheme in ("tcp", "tls", "ws", "wss", "ucx")
            and bool(host)
            and bool(port)
            and parts.path in ("", "/")
            and not parts.query
            and not parts.fragment
        )
    if not well_formed:
        raise InputError(_NAME, _RULE, scheduler)


def probe_scheduler(scheduler: str, *, seconds: float | None = None) -> None:
    """Check that a ``tcp://`` address answers as a Dask scheduler does, in time.

    ``seconds`` bounds the connection and the handshake (default `HANDSHAKE_SECONDS`).
    Other schemes (tls, ws, ucx) get only the connection check: their first bytes are the
    transport's own handshake.

    Raises:
        InputError: Nothing listens, the connection or the handshake takes longer than
            ``seconds``, or what answers is not a Dask scheduler.
    """
    check_address(scheduler)
    seconds = HANDSHAKE_SECONDS if seconds is None else seconds
    parts = urlsplit(scheduler if "://" in scheduler else f"tcp://{scheduler}")
    if parts.scheme == "inproc":
        return
    deadline = time.monotonic() + seconds
    try:
        with socket.create_connection((parts.hostname, parts.port), timeout=seconds) as conn:
            if parts.scheme != "tcp":
                return
            header = b""
            while len(header) < 8:
                conn.settimeout(max(deadline - time.monotonic(), 1e-3))
                chunk = conn.recv(8 - len(header))
                if not chunk:
                    raise InputError(
                        _NAME, _RULE, scheduler, hint="it closed the connection unanswered"
                    )
                header += chunk
    except TimeoutError:
        raise InputError(
            _NAME, _RULE, scheduler, hint=f"no Dask handshake within {seconds:g} s"
        ) from None
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise InputError(_NAME, _RULE, scheduler, hint=reason.lower()) from None
    (length,) = struct.unpack("<Q", header)
    if not 0 < length <= MAX_HANDSHAKE_BYTES:
        raise InputError(_NAME, _RULE, scheduler, hint="what answers there is not a Dask scheduler")
