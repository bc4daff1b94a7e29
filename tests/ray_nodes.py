"""Test helper: a two-node Ray cluster on this machine (``ray start --head`` plus a second node joined with
``ray start --address``, each of one CPU), torn down by process group even when the caller fails. Used by
``tests/test_ray_cluster_slow.py`` and ``tests/perf/collection.py``."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

STARTUP_S = 90.0
"""How long a node may take to come up on a busy machine."""


def _ray_start(arguments: list[str], temp: Path, env: dict) -> subprocess.Popen:
    """``ray start ARGUMENTS --block`` in a session of its own (so that the whole node can be ended by its
    process group, never by name: ``ray stop`` would end every Ray on the machine)."""
    ray = Path(sys.executable).with_name("ray")
    log = (temp / "start.log").open("w")
    return subprocess.Popen([str(ray), "start", *arguments, "--block", "--num-cpus", "1", "--disable-usage-stats",
                             "--temp-dir", str(temp)], stdout=log, stderr=subprocess.STDOUT, env=env,
                            cwd=temp, start_new_session=True)  # the node's workers run in their own folder


def _end(nodes: list[subprocess.Popen]) -> None:
    """SIGTERM to every node's process group, SIGKILL to what is left of them after 5 s."""
    for sig, wait_s in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 5.0)):
        for node in nodes:
            try:
                os.killpg(node.pid, sig)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + wait_s
        while time.monotonic() < deadline:
            if all(subprocess.run(["pgrep", "-g", str(node.pid)], capture_output=True).returncode != 0
                   for node in nodes):
                break
            time.sleep(0.2)
    for node in nodes:
        node.wait(timeout=5)


def _wait_for_address(temp: Path, head: subprocess.Popen) -> str:
    marker = temp / "ray_current_cluster"
    deadline = time.monotonic() + STARTUP_S
    while time.monotonic() < deadline:
        if marker.is_file() and marker.read_text().strip():
            return marker.read_text().strip()
        if head.poll() is not None:
            break
        time.sleep(0.2)
    raise RuntimeError(f"the Ray head did not start: {(temp / 'start.log').read_text()[-2000:]}")


def _wait_for_nodes(address: str, count: int) -> list[dict]:
    import ray

    ray.init(address=address, log_to_driver=False)
    try:
        deadline = time.monotonic() + STARTUP_S
        while time.monotonic() < deadline:
            alive = [node for node in ray.nodes() if node["Alive"]]
            if len(alive) == count:
                return alive
            time.sleep(0.5)
        raise RuntimeError(f"{len(alive)} of {count} Ray nodes came up")
    finally:
        ray.shutdown()


@contextmanager
def two_node_cluster() -> Iterator[tuple[str, Path]]:
    """(address, the second node's temp folder) of a two-node cluster of one CPU each, ended on exit. The caller
    must have Ray installed."""
    temps = [Path(tempfile.mkdtemp(prefix="sr", dir="/tmp")) for _ in range(2)]  # short: Ray's socket paths
    # a cluster of our own on loopback: no token to share (Ray's token authentication is for real networks)
    env = os.environ | {"RAY_AUTH_MODE": "disabled", "PYOPENGL_PLATFORM": "egl"}
    previous = os.environ.get("RAY_AUTH_MODE")
    os.environ["RAY_AUTH_MODE"] = "disabled"  # this process is the driver
    nodes: list[subprocess.Popen] = []
    try:
        nodes.append(_ray_start(["--head", "--port", "0", "--include-dashboard", "false"], temps[0], env))
        address = _wait_for_address(temps[0], nodes[0])
        nodes.append(_ray_start(["--address", address, "--dashboard-agent-listen-port", "0"], temps[1], env))
        alive = _wait_for_nodes(address, 2)
        assert [node["Resources"].get("CPU") for node in alive] == [1.0, 1.0]
        yield address, temps[1]
    finally:
        _end(nodes)
        if previous is None:
            os.environ.pop("RAY_AUTH_MODE", None)
        else:
            os.environ["RAY_AUTH_MODE"] = previous
        for temp in temps:
            shutil.rmtree(temp, ignore_errors=True)


def ran_on(node_temp: Path, function: str, wait_s: float = 20.0) -> bool:
    """Whether a worker of the node with temp folder ``node_temp`` ran ``function`` (Ray marks each task in its
    worker's log with ``:task_name:FUNCTION``). A worker writes its log on its own time, after the task's result
    has reached the driver: the logs are read again for up to ``wait_s`` seconds before the answer is no."""
    import time

    deadline = time.monotonic() + wait_s
    while True:
        if any(f":task_name:{function}" in log.read_text(errors="replace")
               for log in node_temp.glob("session_*/logs/worker-*.out")):
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.25)
