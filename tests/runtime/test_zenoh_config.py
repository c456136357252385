"""How a robot program's options become its Zenoh session configuration (no network)."""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path
from types import SimpleNamespace

import pytest

from cfgplan.runtime import RunError
from cfgplan.runtime.zenoh_config import RUNTIME_THREADS, spare_threads
from cfgplan.runtime.zenoh_transport import (
    DEFAULT_LEASE,
    OPEN_TIMEOUT_MS,
    ZenohOptions,
    ZenohTransport,
    zenoh_config,
)
from tests.runtime.netutil import endpoint, hermetic_config


def _get(options: ZenohOptions, key: str) -> object:
    return json.loads(zenoh_config(options).get_json(key))  # type: ignore[no-any-return]


def test_peer_mode_multicast_on_a_lan_and_a_lease_of_one_second() -> None:
    options = ZenohOptions()
    assert _get(options, "mode") == "peer"
    assert _get(options, "scouting/multicast/enabled") is None  # Zenoh's default: on
    assert _get(options, "transport/link/tx/lease") == DEFAULT_LEASE * 1000
    assert _get(options, "connect/retry")["period_max_ms"] == 500  # type: ignore[index]


def test_endpoints_turn_multicast_scouting_off() -> None:
    options = ZenohOptions(listen=("tcp/127.0.0.1:7447",), connect=("tcp/10.0.0.2:7447",))
    assert _get(options, "listen/endpoints") == ["tcp/127.0.0.1:7447"]
    assert _get(options, "connect/endpoints") == ["tcp/10.0.0.2:7447"]
    assert _get(options, "scouting/multicast/enabled") is False
    assert _get(ZenohOptions(connect=("udp/[::1]:7000",)), "scouting/multicast/enabled") is False
    assert _get(ZenohOptions(lease=0.25), "transport/link/tx/lease") == 250


def test_a_robot_that_only_connects_listens_nowhere(tmp_path: Path) -> None:
    """A robot started with only ``--connect`` listened on every
    interface (Zenoh's default ``tcp/[::]:0``). It reaches out; it listens only
    where it is told — by ``--listen`` or by a configuration file."""
    assert _get(ZenohOptions(connect=("tcp/10.0.0.2:7447",)), "listen/endpoints") == []
    assert _get(ZenohOptions(), "listen/endpoints") == {  # no endpoints: scouting, Zenoh's
        "router": ["tcp/[::]:7447"],
        "peer": ["tcp/[::]:0"],
    }
    path = tmp_path / "zenoh.json5"
    path.write_text('{ listen: { endpoints: ["tcp/127.0.0.1:7447"] } }')
    from_file = ZenohOptions(config_file=str(path), connect=("tcp/10.0.0.2:7447",))
    assert _get(from_file, "listen/endpoints") == ["tcp/127.0.0.1:7447"]


def test_a_config_file_is_the_base_and_options_go_on_top(tmp_path: Path) -> None:
    path = tmp_path / "zenoh.json5"
    path.write_text('{ mode: "client", transport: { link: { tx: { lease: 3000 } } } }')
    from_file = ZenohOptions(config_file=str(path))
    assert _get(from_file, "mode") == "client"
    assert _get(from_file, "transport/link/tx/lease") == 3000  # the file's, not ours
    assert _get(ZenohOptions(config_file=str(path), lease=2), "transport/link/tx/lease") == 2000


def test_a_config_file_keeps_cfgplans_lease_and_retry_unless_it_sets_them(tmp_path: Path) -> None:
    """A file that set only an endpoint dropped cfgplan's lease (a
    frozen robot was reported lost after 10 s, Zenoh's default) and its retry."""
    path = tmp_path / "zenoh.json5"
    path.write_text('{ listen: { endpoints: ["tcp/127.0.0.1:7447"] } }')
    options = ZenohOptions(config_file=str(path))
    assert _get(options, "listen/endpoints") == ["tcp/127.0.0.1:7447"]  # the file's
    assert _get(options, "transport/link/tx/lease") == DEFAULT_LEASE * 1000  # cfgplan's
    assert _get(options, "transport/unicast/open_timeout") == OPEN_TIMEOUT_MS
    assert _get(options, "connect/retry")["period_max_ms"] == 500  # type: ignore[index]
    assert _get(options, "mode") == "peer"
    path.write_text("{ connect: { retry: { period_init_ms: 500, period_max_ms: 4000 } } }")
    assert _get(options, "connect/retry")["period_max_ms"] == 4000  # type: ignore[index]
    assert _get(options, "transport/link/tx/lease") == DEFAULT_LEASE * 1000
    path.write_text("{ transport: { unicast: { open_timeout: 5000 } } }")
    assert _get(options, "transport/unicast/open_timeout") == 5000  # the file's


def test_what_is_refused_is_said_clearly(tmp_path: Path) -> None:
    with pytest.raises(RunError, match="an endpoint is PROTOCOL/ADDRESS"):
        ZenohOptions(listen=("7447",))
    with pytest.raises(RunError, match="the lease must be a positive number"):
        ZenohOptions(lease=0)
    with pytest.raises(RunError, match="society name is empty"):
        ZenohOptions(society="")
    with pytest.raises(RunError, match=r"cannot read the Zenoh configuration .*No such file"):
        zenoh_config(ZenohOptions(config_file=str(tmp_path / "none.json5")))
    bad = tmp_path / "bad.json5"
    bad.write_text("{ mode: ")
    with pytest.raises(RunError, match="cannot read the Zenoh configuration") as caught:
        zenoh_config(ZenohOptions(config_file=str(bad)))
    assert ".rs:" not in str(caught.value)  # no Rust source locations


def test_a_session_that_cannot_open_is_a_clear_error(tmp_path: Path) -> None:
    hermetic = str(hermetic_config(tmp_path))
    with pytest.raises(RunError, match="cannot open the Zenoh session: ") as caught:
        ZenohTransport("Emil", ZenohOptions(listen=("tcp/127.0.0.1:x",), config_file=hermetic))
    assert ".rs:" not in str(caught.value)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        busy = endpoint(taken.getsockname()[1])
        with pytest.raises(RunError, match="cannot open the Zenoh session: "):
            ZenohTransport("Emil", ZenohOptions(listen=(busy,), config_file=hermetic))


def test_a_session_whose_token_is_refused_is_closed(monkeypatch: pytest.MonkeyPatch) -> None:
    """Zenoh refusing the robot's liveliness token is a clear error, and the
    session already opened is closed (it stayed open, holding its ports)."""
    import zenoh

    closed: list[bool] = []

    class Liveliness:
        def declare_token(self, key: str) -> None:
            raise zenoh.ZError(f"refused {key}")

    class Session:
        def liveliness(self) -> Liveliness:
            return Liveliness()

        def close(self) -> None:
            closed.append(True)

    fake = SimpleNamespace(ZError=zenoh.ZError, Config=zenoh.Config, open=lambda _: Session())
    monkeypatch.setattr("cfgplan.runtime.zenoh_transport.load_zenoh", lambda: fake)
    with pytest.raises(RunError, match="cannot declare Emil alive: refused"):
        ZenohTransport("Emil", ZenohOptions(listen=("tcp/127.0.0.1:7447",)))
    assert closed == [True]


def test_a_client_of_a_router_connects_only_there_and_listens_nowhere() -> None:
    """``--router``: Zenoh's client mode, the router its only link; what
    cannot go with it is refused (a mesh's endpoints; with the society's keys,
    tests/security/test_zenoh_tls.py)."""
    options = ZenohOptions(router=("tcp/10.0.0.1:7447",))
    assert _get(options, "mode") == "client"
    assert _get(options, "connect/endpoints") == ["tcp/10.0.0.1:7447"]
    assert _get(options, "listen/endpoints") == []
    assert _get(options, "scouting/multicast/enabled") is False
    assert _get(options, "transport/link/tx/lease") == DEFAULT_LEASE * 1000
    with pytest.raises(RunError, match="--router and --listen"):
        ZenohOptions(router=("tcp/10.0.0.1:7447",), listen=("tcp/127.0.0.1:7448",))
    with pytest.raises(RunError, match="--router and --connect"):
        ZenohOptions(router=("tcp/10.0.0.1:7447",), connect=("tcp/127.0.0.1:7448",))
    with pytest.raises(RunError, match="--router 'nowhere'"):
        ZenohOptions(router=("nowhere",))


WAIT = "transport/link/tx/queue/congestion_control/block/wait_before_close"


def test_a_stuck_link_is_closed_after_a_twentieth_of_the_lease_unless_a_file_says(
    tmp_path: Path,
) -> None:
    """Zenoh waits 5 s on a full link before closing it, on the thread that
    sends (in a router, the one reading a healthy robot's link): cfgplan
    waits 100 ms with the 2 s lease, following ``--lease`` and a file's
    lease; a file's own wait is kept."""
    assert _get(ZenohOptions(), WAIT) == DEFAULT_LEASE * 1_000_000 / 20 == 100_000
    assert _get(ZenohOptions(lease=10.0), WAIT) == 500_000
    leased = tmp_path / "leased.json5"
    leased.write_text("{ transport: { link: { tx: { lease: 4000 } } } }")
    assert _get(ZenohOptions(config_file=str(leased)), WAIT) == 200_000
    own = tmp_path / "own.json5"
    own.write_text(
        "{ transport: { link: { tx: { queue: { congestion_control: "
        "{ block: { wait_before_close: 750000 } } } } } } }"
    )
    assert _get(ZenohOptions(config_file=str(own), lease=1.0), WAIT) == 750_000


def test_zenoh_gets_spare_threads_unless_the_environment_names_its_own(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("ZENOH_RUNTIME", raising=False)
    spare_threads()
    assert os.environ["ZENOH_RUNTIME"] == RUNTIME_THREADS
    assert "acc: (worker_threads: 8)" in RUNTIME_THREADS  # Zenoh's default is 1
    mine = "(rx: (worker_threads: 3))"
    monkeypatch.setenv("ZENOH_RUNTIME", mine)
    spare_threads()
    assert os.environ["ZENOH_RUNTIME"] == mine
