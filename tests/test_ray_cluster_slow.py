"""Bench and search on a real two-node Ray cluster started on this machine (``ray start --head`` plus a second
node joined with ``ray start --address``, each of one CPU) give the same results as ``--engine local``; the
cluster is torn down even when a test fails."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from simrig.benchmark import run_bench
from simrig.search import run_search
from simrig.search.fragments import FOLDER

pytestmark = pytest.mark.slow

SCENARIO = """
name = "tiny_highway"
frames = 12
[traffic]
env = "highway-v0"
lanes = 3
ego_lane = 1
vehicles = 3
window_radius_m = 45.0
spawn_min_distance_m = 20.0
speed_range_mps = [20.0, 30.0]
ego_speed_mps = 25.0
[rig]
preset = "surround6"
[render]
visibility = false
"""

SUITE = """
name = "tiny_cluster"
scenarios = ["tiny_highway.toml"]
seeds = [0, 1]
[[trackers]]
tracker = "saga"
[[trackers]]
tracker = "global_hungarian"
[[sweeps]]
parameter = "miss_probability"
values = [0.4]
"""

SPACE = """
name = "tiny_cluster_space"
base = "tiny_highway.toml"
tracker = "saga"
budget = 3
seeds = 2
confirm_top = 1
confirm_seeds = 2
[base_settings]
"perturbations" = [{ kind = "occlude", nearest = 1, frames = [2, 4] }]
[objective]
metric = "2d_IDF1"
direction = "minimize"
[[dimensions]]
path = "perturbations.0.frames"
start = [0, 4]
length = [1, 7]
"""

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


@pytest.fixture(scope="module")
def cluster():
    """(address, worker node's temp folder) of a two-node cluster of one CPU each; ended after the module."""
    pytest.importorskip("ray")
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


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cluster_files")
    (folder / "tiny_highway.toml").write_text(SCENARIO)
    (folder / "tiny_cluster.toml").write_text(SUITE)
    (folder / "tiny_cluster_space.toml").write_text(SPACE)
    return folder


def _ran_on(node_temp: Path, function: str) -> bool:
    """Whether a worker of the node with temp folder ``node_temp`` ran ``function`` (Ray marks each task in its
    worker's log with ``:task_name:FUNCTION``)."""
    return any(f":task_name:{function}" in log.read_text(errors="replace")
               for log in node_temp.glob("session_*/logs/worker-*.out"))


def test_bench_on_a_two_node_cluster_writes_the_local_tables(cluster, files, tmp_path, monkeypatch):
    address, second_node = cluster
    monkeypatch.chdir(tmp_path)  # a relative cache: the nodes' workers run in folders of their own
    cache = Path("shared-cache")  # one folder every node reads and writes
    ray_run = run_bench(files / "tiny_cluster.toml", engine="ray", address=address, out="ray", cache=cache)
    local_run = run_bench(files / "tiny_cluster.toml", engine="local", workers=1, out="local")
    assert ray_run.cells_run == local_run.cells_run == 4  # 2 seeds × (base, miss 0.4)
    for name in ("results.parquet", "causes.parquet"):  # timings.parquet: seconds, which differ
        assert (ray_run.out / name).read_bytes() == (local_run.out / name).read_bytes(), name
    assert pq.read_table(ray_run.results).num_rows == 8  # 4 cells × 2 trackers
    assert len(list(cache.iterdir())) >= 4  # the cluster's workers wrote the datasets into the shared cache
    assert _ran_on(second_node, "evaluate")  # the second node did part of the work


def _evaluations(out: Path) -> dict[str, dict]:
    documents = {}
    for path in sorted((out / FOLDER).glob("*/*.json")):
        document = json.loads(path.read_bytes())
        document.pop("seconds")
        documents[str(path.relative_to(out))] = document
    return documents


def test_search_on_a_two_node_cluster_makes_the_local_evaluations(cluster, files, tmp_path):
    address, second_node = cluster
    space = files / "tiny_cluster_space.toml"
    on_ray = run_search(space, engine="ray", address=address, out=tmp_path / "ray", cache=tmp_path / "shared-cache",
                        shrink_budget=0)
    assert len(list((tmp_path / "shared-cache").iterdir())) >= 2  # the cluster's workers wrote into the cache
    local = run_search(space, engine="local", workers=1, out=tmp_path / "local", shrink_budget=0)
    assert on_ray.evaluated_now == local.evaluated_now == 3 + 3 + 1  # tpe, random, one confirmation
    assert _evaluations(on_ray.out) == _evaluations(local.out) != {}
    tables = [pq.read_table(run.results).drop_columns(["seconds"]).to_pandas() for run in (on_ray, local)]
    assert tables[0].equals(tables[1]) and len(tables[0]) == 7  # NaN equals NaN here (pyarrow's equals: not)
    assert _ran_on(second_node, "run_seed")
