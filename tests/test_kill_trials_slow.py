"""Kill trials of every long command: ``generate``, ``run``, ``search`` and ``explain`` (the bench's own are in
``test_bench_faults.py``), each killed with SIGKILL (the driver alone, as the OOM killer does) and interrupted with
SIGINT (the whole foreground group, as Ctrl-C does) once its work is under way.

After each: no process of its group is left 5 s later, nothing is marked complete that is not, and the same
command run again finishes (it resumes or starts over; it never trips over what the killed one left).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from terminal import ctrl_c_delivered
from test_bench_faults import _group
from test_search_run import TINY

from simrig.dataset import Dataset

pytestmark = pytest.mark.slow

SCENARIO = ('extends = "highway_surround6"\nframes = 200\n'
            "[traffic]\nvehicles = 12\nwindow_radius_m = 100.0\nspawn_min_distance_m = 70.0\n")


def _start(args: list, cwd: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "simrig.cli", *map(str, args)], cwd=cwd, start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=ctrl_c_delivered)


def _wait_for(process: subprocess.Popen, under_way, what: str, limit_s: float = 180) -> None:
    deadline = time.monotonic() + limit_s
    while not under_way():
        assert process.poll() is None, f"finished before {what}: {process.communicate()}"
        assert time.monotonic() < deadline, f"never {what}"
        time.sleep(0.05)


def _stop(process: subprocess.Popen, how: signal.Signals) -> str:
    """Send ``how`` (SIGKILL to the driver, SIGINT to the group); the stderr; no process of the group 5 s on."""
    assert process.poll() is None, f"finished before {how.name} could be sent: {process.communicate()}"
    try:
        if how == signal.SIGKILL:
            os.kill(process.pid, signal.SIGKILL)
        else:
            os.killpg(process.pid, signal.SIGINT)
        _, stderr = process.communicate(timeout=60)
        gone = time.monotonic() + 5
        while _group(process.pid) and time.monotonic() < gone:
            time.sleep(0.1)
        assert not _group(process.pid), f"left 5 s after {how.name}: {_group(process.pid)}"
    finally:
        if _group(process.pid):
            os.killpg(process.pid, signal.SIGKILL)
    if how == signal.SIGINT:
        assert process.returncode == 130, stderr
        assert "Traceback" not in stderr, stderr
        assert stderr.strip().splitlines()[-1].startswith("simrig: interrupted"), stderr  # above it: progress bars
    else:
        assert process.returncode == -signal.SIGKILL
    return stderr


def _rerun(args: list, cwd: Path) -> subprocess.CompletedProcess:
    done = subprocess.run([sys.executable, "-m", "simrig.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    return done


def _partials(folder: Path) -> list[Path]:
    return list(folder.glob(".*partial*")) if folder.exists() else []


@pytest.fixture(scope="module")
def scenario(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("trial") / "small.toml"
    path.write_text(SCENARIO)
    return path


SIGNALS = [signal.SIGKILL, signal.SIGINT]


@pytest.mark.parametrize("how", SIGNALS, ids=lambda s: s.name)
def test_generate(how, scenario, tmp_path):
    out = tmp_path / "dataset"
    args = ["generate", scenario, "--out", out, "--quiet"]
    process = _start(args, tmp_path)
    _wait_for(process, lambda: _partials(tmp_path), "started writing")
    time.sleep(1.0)
    _stop(process, how)
    assert not out.exists()  # nothing published: the partial folder is hidden (and removed on Ctrl-C)
    if how == signal.SIGINT:
        assert not _partials(tmp_path)
    _rerun(args, tmp_path)
    assert Dataset.open(out).verify() == [] and not _partials(tmp_path)


@pytest.mark.parametrize("how", SIGNALS, ids=lambda s: s.name)
def test_run(how, scenario, tmp_path):
    out = tmp_path / "run"
    args = ["run", scenario, "--tracker", "sort", "--out", out]
    process = _start(args, tmp_path)
    _wait_for(process, lambda: _partials(out), "started its dataset")
    time.sleep(1.0)
    _stop(process, how)
    assert not (out / "report.md").exists() and not (out / "dataset").exists()
    _rerun(args, tmp_path)
    assert (out / "report.md").is_file() and json.loads((out / "scores" / "sort" / "score.json").read_text())


@pytest.mark.parametrize("how", SIGNALS, ids=lambda s: s.name)
def test_search_with_two_workers(how, tmp_path):
    space = tmp_path / "tiny.toml"
    space.write_text(TINY)
    out = tmp_path / "search"
    args = ["search", space, "--workers", "2", "--out", out]
    process = _start(args, tmp_path)
    _wait_for(process, lambda: len(_group(process.pid)) >= 3, "started its pool")  # driver, two workers
    time.sleep(2.0)
    _stop(process, how)
    recorded = json.loads((out / "search.json").read_text())
    assert recorded["complete"] is False and not (out / "results.parquet").exists()
    _rerun(args, tmp_path)
    assert json.loads((out / "search.json").read_text())["complete"] is True


@pytest.fixture(scope="module")
def run_folder(scenario, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("explained") / "run"
    _rerun(["run", scenario, "--tracker", "sort", "--frames", "30", "--out", out], out.parent)
    return out


@pytest.mark.parametrize("how", SIGNALS, ids=lambda s: s.name)
def test_explain_with_two_workers(how, run_folder, tmp_path):
    import shutil

    folder = shutil.copytree(run_folder, tmp_path / "run")
    args = ["explain", folder, "--workers", "2", "--causes", "occlusion,random_misses,false_positives"]
    process = _start(args, tmp_path)
    _wait_for(process, lambda: len(_group(process.pid)) >= 3, "started its pool")
    time.sleep(2.0)
    _stop(process, how)
    assert not (folder / "explain" / "sort" / "explain.json").exists()
    _rerun(args, tmp_path)
    assert json.loads((folder / "explain" / "sort" / "explain.json").read_text())
