"""The society's router (:mod:`cfgplan.runtime.router`): two robots that are
its clients hear each other through it, and only through it; a client that
goes is seen lost by the other; the router's options are checked before it
opens. Loopback, free ports, scouting off, bounded waits."""

from __future__ import annotations

import threading
import time

import pytest

from cfgplan.runtime import RunError
from cfgplan.runtime.router import RouterOptions, router_config, serve
from cfgplan.runtime.zenoh_transport import ZenohOptions, zenoh_config
from tests.runtime.netutil import endpoint, free_port, wait_for


def test_a_router_is_zenohs_router_mode_with_the_lease_and_no_scouting() -> None:
    config = router_config(RouterOptions(listen=("tcp/127.0.0.1:7447",), lease=0.5))
    assert config.get_json("mode") == '"router"'
    assert config.get_json("listen/endpoints") == '["tcp/127.0.0.1:7447"]'
    assert config.get_json("scouting/multicast/enabled") == "false"
    assert config.get_json("transport/link/tx/lease") == "500"
    wait = "transport/link/tx/queue/congestion_control/block/wait_before_close"
    assert config.get_json(wait) == "25000"  # a full client's link closed after lease / 20
    with pytest.raises(RunError, match="--listen 'here'"):
        RouterOptions(listen=("here",))
    with pytest.raises(RunError, match="must listen somewhere"):
        RouterOptions(listen=())
    with pytest.raises(RunError, match="the lease must be a positive"):
        RouterOptions(lease=0)


def test_two_clients_of_a_router_hear_each_other_and_see_each_other_go() -> None:
    import zenoh

    port = free_port()
    stop, said = threading.Event(), list[str]()
    options = RouterOptions(listen=(endpoint(port),), lease=1.0)
    runs = threading.Thread(target=serve, args=(options, said.append, stop), daemon=True)
    runs.start()
    try:
        wait_for("the router listens", lambda: said or None, 10.0)
        assert said[0].endswith(f"listening on {endpoint(port)}"), said
        client = ZenohOptions(router=(endpoint(port),), lease=1.0)
        emil, pippi = (zenoh.open(zenoh_config(client, name)) for name in ("Emil", "Pippi"))
        try:
            heard: list[str] = []
            alive: list[tuple[str, str]] = []
            pippi.declare_subscriber("t/data", lambda s: heard.append(s.payload.to_string()))
            pippi.liveliness().declare_subscriber(
                "t/alive/*", lambda s: alive.append((str(s.kind), str(s.key_expr))), history=True
            )
            token = emil.liveliness().declare_token("t/alive/Emil")
            wait_for("Emil seen", lambda: alive or None, 10.0)

            def put_and_hear() -> bool | None:
                emil.put("t/data", "hello")
                time.sleep(0.05)
                return bool(heard) or None

            wait_for("data through the router", put_and_hear, 10.0)
            assert heard[0] == "hello"
            assert [str(z) for z in emil.info.peers_zid()] == []  # no link between the two
            assert len(list(emil.info.routers_zid())) == 1
            token.undeclare()
            emil.close()
            wait_for("Emil lost", lambda: "SampleKind.DELETE" in alive[-1][0] or None, 10.0)
        finally:
            pippi.close()
    finally:
        stop.set()
        runs.join(timeout=10.0)
    assert said[-1] == "router stopped" and not runs.is_alive()
