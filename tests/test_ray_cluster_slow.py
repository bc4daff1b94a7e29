"""Bench and search on a real two-node Ray cluster started on this machine (``ray start --head`` plus a second
node joined with ``ray start --address``, each of one CPU) give the same results as ``--engine local``; the
cluster is torn down even when a test fails."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from ray_nodes import ran_on, two_node_cluster

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

@pytest.fixture(scope="module")
def cluster():
    """(address, worker node's temp folder) of a two-node cluster of one CPU each; ended after the module."""
    pytest.importorskip("ray")
    with two_node_cluster() as (address, second_node):
        yield address, second_node


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cluster_files")
    (folder / "tiny_highway.toml").write_text(SCENARIO)
    (folder / "tiny_cluster.toml").write_text(SUITE)
    (folder / "tiny_cluster_space.toml").write_text(SPACE)
    return folder


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
    assert ran_on(second_node, "evaluate")  # the second node did part of the work


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
    assert ran_on(second_node, "run_seed")


def test_a_collection_on_a_two_node_cluster_is_the_local_one(cluster, files, tmp_path):
    from simrig.collection import generate_collection

    address, second_node = cluster
    space = files / "tiny_collection.toml"
    space.write_text('name = "tiny_collection"\nbase = "tiny_highway.toml"\nframes = 4\n[[dimensions]]\n'
                     'path = "traffic.vehicles"\nlow = 1\nhigh = 5\n')
    on_ray = generate_collection(space, count=6, out=tmp_path / "ray", engine="ray", address=address)
    local = generate_collection(space, count=6, out=tmp_path / "local", workers=1)
    assert on_ray.made == local.made == 6
    files_of = [{str(p.relative_to(run.out)): p.read_bytes() for p in sorted(run.out.rglob("*"))
                 if p.is_file() and p.name != ".lock"} for run in (on_ray, local)]
    assert files_of[0] == files_of[1]
    assert ran_on(second_node, "make_sequence")
