"""A lossy link for the fault benchmark, without a kernel module.

Two ways, chosen by what the machine allows:

* :class:`NetnsLink` — two network namespaces, each with a TUN device
  (``10.77.0.1/24`` and ``10.77.0.2/24``). A tiny opener started inside each
  namespace (``ip netns exec NS python -m benchmarks.lossy_link open ...``)
  creates the device, gives it its address and hands its file descriptor back
  over an inherited unix socket; this process then forwards every IP packet
  between the two devices, dropping a seeded share of them and delaying the
  rest. TCP sees real packet loss and retransmits. A cut is a loss of 100 %.
  Needs root (or CAP_NET_ADMIN) and ``/dev/net/tun``.
* :class:`ProxyLink` — a TCP proxy on loopback between the helper and the
  coordinator that can delay bytes, stall (hold them) and cut (close every
  connection and refuse new ones). It cannot lose packets: TCP would hide it.

Robots on a :class:`NetnsLink` run under :meth:`NetnsLink.wrap` and listen on
its addresses; on a :class:`ProxyLink` the helper connects to
:attr:`ProxyLink.port` instead of the coordinator's.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import fcntl
import heapq
import itertools
import os
import random
import selectors
import shutil
import socket
import struct
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Protocol

PREFIX = "cfgfault-"
"""Names of the namespaces this module makes: ``cfgfault-<pid>-<n>a`` and ``...b``."""
_LINKS = itertools.count(1)

TUNSETIFF = 0x400454CA
IFF_TUN = 0x0001
IFF_NO_PI = 0x1000
COMMAND_LIMIT = 30.0  # seconds for one `ip` command or one opener


@dataclass
class Impairment:
    """What the link does to traffic now: ``loss`` a share of packets dropped
    (1.0: cut), ``delay`` seconds added to each packet, one way."""

    loss: float = 0.0
    delay: float = 0.0


@dataclass
class Counts:
    """Packets the link saw and dropped, both ways together."""

    seen: int = 0
    dropped: int = 0


class Link(Protocol):
    """What the benchmark needs of a link."""

    kind: str
    can_lose: bool

    def set(self, loss: float = 0.0, delay: float = 0.0) -> None: ...

    def close(self) -> None: ...


class LinkUnavailable(RuntimeError):
    """This machine cannot make this kind of link (not root, no TUN, ...)."""


def _ip(*args: str, netns: str | None = None) -> None:
    prefix = ["ip", "netns", "exec", netns] if netns else []
    out = subprocess.run(
        [*prefix, "ip", *args], capture_output=True, text=True, timeout=COMMAND_LIMIT
    )
    if out.returncode != 0:
        raise LinkUnavailable(f"ip {' '.join(args)}: {out.stderr.strip()}")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_leftovers() -> list[str]:
    """Delete namespaces of this module whose making process is gone (a run
    that crashed); returns their names."""
    out = subprocess.run(
        ["ip", "netns", "list"], capture_output=True, text=True, timeout=COMMAND_LIMIT
    )
    removed = []
    for line in out.stdout.splitlines():
        name = line.split()[0] if line.split() else ""
        if not name.startswith(PREFIX):
            continue
        pid = name[len(PREFIX) :].split("-")[0]
        if pid.isdigit() and _alive(int(pid)):
            continue
        subprocess.run(["ip", "netns", "del", name], capture_output=True, timeout=COMMAND_LIMIT)
        removed.append(name)
    return removed


def open_tun(name: str, address: str) -> int:
    """A TUN device ``name`` in this process's namespace, with ``address``
    (CIDR) and up, and loopback up; returns its file descriptor."""
    fd = os.open("/dev/net/tun", os.O_RDWR)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", name.encode(), IFF_TUN | IFF_NO_PI))
    _ip("addr", "add", address, "dev", name)
    _ip("link", "set", name, "up")
    _ip("link", "set", "lo", "up")
    return fd


@dataclass
class NetnsLink:
    """Two namespaces joined by a forwarder in this process (see the module's
    docstring); ``seed`` makes the dropped packets the same in every run."""

    seed: int = 0
    addresses: tuple[str, str] = ("10.77.0.1", "10.77.0.2")
    kind: str = "netns + TUN forwarder"
    can_lose: bool = True
    counts: Counts = field(default_factory=Counts)
    impairment: Impairment = field(default_factory=Impairment)

    def __post_init__(self) -> None:
        if os.geteuid() != 0 or not os.path.exists("/dev/net/tun") or not shutil.which("ip"):
            raise LinkUnavailable("needs root, /dev/net/tun and ip (iproute2)")
        remove_leftovers()
        made = next(_LINKS)
        self.names = (f"{PREFIX}{os.getpid()}-{made}a", f"{PREFIX}{os.getpid()}-{made}b")
        self._fds: list[int] = []
        self._made: list[str] = []
        self._stop = threading.Event()
        self._random = random.Random(self.seed)
        try:
            for name, address in zip(self.names, self.addresses, strict=True):
                _ip("netns", "add", name)
                self._made.append(name)
                self._fds.append(self._open_in(name, f"{address}/24"))
        except (LinkUnavailable, OSError, subprocess.SubprocessError) as error:
            self.close()
            raise LinkUnavailable(str(error)) from error
        for fd in self._fds:
            os.set_blocking(fd, False)
        self._thread = threading.Thread(target=self._forward, name="lossy-link", daemon=True)
        self._thread.start()

    def _open_in(self, netns: str, address: str) -> int:
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        with ours, theirs:
            command = ["ip", "netns", "exec", netns, sys.executable, "-m", "benchmarks.lossy_link"]
            command += ["open", "--name", "tun0", "--address", address]
            command += ["--fd", str(theirs.fileno())]
            opener = subprocess.run(
                command,
                pass_fds=[theirs.fileno()],
                capture_output=True,
                text=True,
                timeout=COMMAND_LIMIT,
                cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
            )
            if opener.returncode != 0:
                raise LinkUnavailable(f"TUN in {netns}: {opener.stderr.strip()[-300:]}")
            ours.settimeout(COMMAND_LIMIT)
            _, fds, _, _ = socket.recv_fds(ours, 16, 1)
        if not fds:
            raise LinkUnavailable(f"TUN in {netns}: no descriptor came back")
        return fds[0]

    def wrap(self, side: int, command: list[str]) -> list[str]:
        """``command`` run inside namespace ``side`` (0 or 1)."""
        return ["ip", "netns", "exec", self.names[side], *command]

    def set(self, loss: float = 0.0, delay: float = 0.0) -> None:
        self.impairment = Impairment(loss, delay)

    def _forward(self) -> None:
        """Move packets between the two TUN devices until closed."""
        a, b = self._fds
        other = {a: b, b: a}
        waiting: list[tuple[float, int, int, bytes]] = []  # due, order, to, packet
        order = 0
        with selectors.DefaultSelector() as selector:
            selector.register(a, selectors.EVENT_READ)
            selector.register(b, selectors.EVENT_READ)
            while not self._stop.is_set():
                timeout = 0.05 if not waiting else max(0.0, waiting[0][0] - time.monotonic())
                for key, _ in selector.select(min(timeout, 0.05)):
                    fd = int(key.fd)
                    with contextlib.suppress(BlockingIOError, OSError):
                        while True:
                            packet = os.read(fd, 65536)
                            now = self.impairment
                            self.counts.seen += 1
                            if now.loss > 0 and self._random.random() < now.loss:
                                self.counts.dropped += 1
                                continue
                            order += 1
                            due = time.monotonic() + now.delay
                            heapq.heappush(waiting, (due, order, other[fd], packet))
                now_t = time.monotonic()
                while waiting and waiting[0][0] <= now_t:
                    _, _, to, packet = heapq.heappop(waiting)
                    with contextlib.suppress(OSError):
                        os.write(to, packet)

    def close(self) -> None:
        """Stop forwarding, close the devices, delete the namespaces."""
        self._stop.set()
        thread = getattr(self, "_thread", None)
        if thread is not None:
            thread.join(5.0)
        for fd in self._fds:
            with contextlib.suppress(OSError):
                os.close(fd)
        self._fds = []
        for name in self._made:
            subprocess.run(["ip", "netns", "del", name], capture_output=True, timeout=COMMAND_LIMIT)
        self._made = []


@dataclass
class ProxyLink:
    """A TCP proxy on 127.0.0.1 to ``target`` (a port): delays bytes, stalls,
    cuts. ``set(loss=1.0)`` is a cut: every connection closed, new ones
    refused (closed at once) until the loss is set below 1 again; a loss
    between 0 and 1 cannot be made here and is refused."""

    target: int
    kind: str = "TCP proxy on loopback"
    can_lose: bool = False
    impairment: Impairment = field(default_factory=Impairment)
    stalled: bool = False

    def __post_init__(self) -> None:
        self._loop = asyncio.new_event_loop()
        self._writers: set[asyncio.StreamWriter] = set()
        self._thread = threading.Thread(target=self._run, name="tcp-proxy", daemon=True)
        self._thread.start()
        started = asyncio.run_coroutine_threadsafe(
            asyncio.start_server(self._client, "127.0.0.1", 0), self._loop
        )
        try:
            self._server = started.result(COMMAND_LIMIT)
        except (OSError, TimeoutError) as error:
            self.close()
            raise LinkUnavailable(f"the TCP proxy did not start: {error}") from error
        self.port = int(self._server.sockets[0].getsockname()[1])

    def _run(self) -> None:
        """The proxy's event loop, until :meth:`close`; then every task ends."""
        asyncio.set_event_loop(self._loop)
        self._loop.run_forever()
        tasks = asyncio.all_tasks(self._loop)
        for task in tasks:
            task.cancel()
        self._loop.run_until_complete(asyncio.gather(*tasks, return_exceptions=True))
        self._loop.close()

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if self.impairment.loss >= 1.0:
            writer.close()
            return
        try:
            up_reader, up_writer = await asyncio.open_connection("127.0.0.1", self.target)
        except OSError:
            writer.close()
            return
        self._writers |= {writer, up_writer}
        await asyncio.gather(
            self._pipe(reader, up_writer), self._pipe(up_reader, writer), return_exceptions=True
        )

    async def _pipe(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        with contextlib.suppress(OSError, asyncio.IncompleteReadError):
            while data := await reader.read(65536):
                while self.stalled:
                    await asyncio.sleep(0.01)
                if self.impairment.delay:
                    await asyncio.sleep(self.impairment.delay)
                writer.write(data)
                await writer.drain()
        self._writers.discard(writer)
        writer.close()

    def set(self, loss: float = 0.0, delay: float = 0.0) -> None:
        if 0.0 < loss < 1.0:
            raise LinkUnavailable("a TCP proxy cannot lose packets")
        self.impairment = Impairment(loss, delay)
        if loss >= 1.0:
            self._loop.call_soon_threadsafe(self._cut)

    def _cut(self) -> None:
        for writer in list(self._writers):
            writer.close()
        self._writers.clear()

    def close(self) -> None:
        def stop() -> None:
            server = getattr(self, "_server", None)
            if server is not None:
                server.close()
            self._cut()
            self._loop.stop()

        if self._thread.is_alive():
            self._loop.call_soon_threadsafe(stop)
            self._thread.join(5.0)


def main(argv: list[str] | None = None) -> int:
    """``open``: inside a namespace, make a TUN device and pass it back."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.lossy_link")
    commands = parser.add_subparsers(dest="command", required=True)
    opener = commands.add_parser("open", help="make a TUN device, send its fd over --fd")
    opener.add_argument("--name", required=True)
    opener.add_argument("--address", required=True, help="CIDR, e.g. 10.77.0.1/24")
    opener.add_argument("--fd", type=int, required=True, help="a unix socket inherited")
    args = parser.parse_args(argv)
    try:
        fd = open_tun(args.name, args.address)
        with socket.socket(fileno=args.fd) as back:
            socket.send_fds(back, [b"tun"], [fd])
    except (OSError, LinkUnavailable) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
