"""Serve an emulated segment on a network interface, so that a real master (SOEM) can drive it.

`st ethercat serve --iface ecs0 --config segment.toml` opens a raw packet socket bound to EtherType
0x88A4 on the interface, answers every EtherCAT frame through the `Segment` (time = seconds
since start on CLOCK_MONOTONIC) and sends it back out of the same interface. Run it in its own
process: pysoem holds the interpreter lock in several calls, so a segment served by a thread of
the master's process would starve. Readiness is announced (a line on stdout, or a file) only
once the socket is bound, so a master that starts after it finds every slave.
"""

from __future__ import annotations

import os
import select
import signal
import socket
import time

ETH_P_ECAT = 0x88A4


class RawSocket:
    """A bound AF_PACKET socket for one interface (needs root or CAP_NET_RAW)."""

    def __init__(self, iface: str):
        self.sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ECAT))
        self.sock.bind((iface, ETH_P_ECAT))
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)

    def recv(self, timeout: float):
        r, _, _ = select.select([self.sock], [], [], timeout)
        if not r:
            return None
        return self.sock.recv(2048)

    def send(self, frame: bytes) -> None:
        if len(frame) < 60:
            frame = frame + bytes(60 - len(frame))
        self.sock.send(frame)

    def close(self) -> None:
        self.sock.close()


def serve(iface: str, segment, ready_file: str | None = None, announce=print, duration: float = 0.0) -> int:
    """Answer frames until SIGTERM/SIGINT (or `duration` seconds); returns the number of frames."""
    sock = RawSocket(iface)
    stop = []
    signal.signal(signal.SIGTERM, lambda *a: stop.append(1))
    signal.signal(signal.SIGINT, lambda *a: stop.append(1))
    t0 = time.monotonic()
    if ready_file:
        with open(ready_file + ".tmp", "w") as f:
            f.write(f"{os.getpid()}\n")
        os.replace(ready_file + ".tmp", ready_file)
    announce(f"serving {len(segment.slaves)} slave(s) on {iface}")
    n = 0
    try:
        while not stop:
            if duration and time.monotonic() - t0 > duration:
                break
            frame = sock.recv(0.2)
            if frame is None:
                continue
            if len(frame) >= 12 and frame[6] & 0x02:  # our own answer echoed back: not a request
                continue
            out = segment.exchange(frame, time.monotonic() - t0)
            if out is not None:
                sock.send(out)
                n += 1
    finally:
        sock.close()
        segment.close()
    return n


def create_veth(master_if: str = "ecm0", slave_if: str = "ecs0") -> None:
    """A veth pair for a master and a served segment (root)."""
    import subprocess

    subprocess.run(
        ["ip", "link", "add", master_if, "type", "veth", "peer", "name", slave_if], check=True, capture_output=True
    )
    for i in (master_if, slave_if):
        subprocess.run(["ip", "link", "set", i, "up"], check=True, capture_output=True)
