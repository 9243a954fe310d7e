"""The sweep's local Dask cluster listens on the loopback interface only."""

from __future__ import annotations

import ipaddress
from urllib.parse import urlparse

import psutil
import pytest

from rvsm.sim.sweep.executors import LOCAL_HOST, local_cluster


def _listening(procs) -> list[tuple[int, str, int]]:
    out = []
    for p in procs:
        try:
            conns = p.net_connections(kind="inet")
        except psutil.NoSuchProcess:  # pragma: no cover - a worker exiting
            continue
        out += [(p.pid, c.laddr.ip, c.laddr.port) for c in conns
                if c.status == psutil.CONN_LISTEN]
    return out


@pytest.mark.parametrize("processes", [False, True])
def test_local_cluster_binds_loopback_only(processes):
    from dask.distributed import Client

    me = psutil.Process()
    before = {(pid, port) for pid, _, port in _listening([me])}
    with local_cluster(1, processes=processes) as cluster, Client(cluster) as client:
        addresses = [cluster.scheduler_address, *client.scheduler_info()["workers"]]
        for a in addresses:  # tcp:// on loopback, or in-process (threads)
            assert a.startswith("inproc://") or urlparse(a).hostname == LOCAL_HOST, a
        http = cluster.scheduler.http_server  # Dask always serves its info pages
        assert http.address == LOCAL_HOST and http.port != 8787  # random, not shared
        listening = [x for x in _listening([me, *me.children(recursive=True)])
                     if (x[0], x[2]) not in before]
        assert http.port in {port for _, _, port in listening}
        assert all(ipaddress.ip_address(ip).is_loopback for _, ip, _ in listening), listening
