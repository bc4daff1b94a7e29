"""The bench under faults: a driver killed with SIGKILL leaves no worker behind; Ctrl-C stops at once, keeps
every finished cell, says truthfully what was lost, and the rerun computes no finished cell twice."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from terminal import ctrl_c_delivered
from test_bench import TINY_SCENARIO, TINY_SUITE

CELLS = 12
TRACKERS = 2


def _suite(folder: Path) -> Path:
    """test_bench's tiny suite: 12 cells (3 seeds × 4 miss probabilities of one scenario), 2 trackers."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "tiny_scenario.toml").write_text(TINY_SCENARIO)
    (folder / "tiny.toml").write_text(TINY_SUITE)
    return folder / "tiny.toml"


def _group(pgid: int) -> dict[int, str]:
    """Live (non-zombie) processes of process group ``pgid``: pid → command line, read from /proc."""
    members = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            command = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        state, group = fields[0], int(fields[2])
        if group == pgid and state != "Z":
            members[int(entry.name)] = command
    return members


def _fragments(out: Path) -> dict[str, int]:
    return {str(path.relative_to(out)): path.stat().st_mtime_ns for path in (out / "fragments").glob("*/*.json")}


def _start(suite: Path, out: Path, workers: int) -> subprocess.Popen:
    command = [sys.executable, "-m", "simrig.cli", "bench", str(suite), "--out", str(out), "--workers",
               str(workers), "--quiet"]
    return subprocess.Popen(command, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=ctrl_c_delivered)


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_sigkill_of_the_driver_leaves_no_simrig_process(tmp_path):
    process = _start(_suite(tmp_path / "suite"), tmp_path / "out", workers=2)
    deadline = time.monotonic() + 120
    try:
        while len(_group(process.pid)) < 3:  # the driver and its two pool workers
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "the pool never started"
            time.sleep(0.05)
        time.sleep(2.0)  # the workers are generating now
        workers = set(_group(process.pid)) - {process.pid}
        os.kill(process.pid, signal.SIGKILL)  # the driver only, not its group
        process.wait()
        time.sleep(5.0)
        left = _group(process.pid)
        print(f"SIGKILL of the driver: processes of its group before {sorted(workers)}, 5 s after {sorted(left)}")
        assert not left, f"still running 5 s after the driver was killed: {left} (workers were {workers})"
        assert len(workers) >= 3  # two pool workers and multiprocessing's resource tracker were there
    finally:
        if _group(process.pid):
            os.killpg(process.pid, signal.SIGKILL)


def _complete_cells(fragments: dict[str, int]) -> set[str]:
    cells = [Path(path).parent.name for path in fragments]
    return {cell for cell in cells if cells.count(cell) == TRACKERS}


@pytest.mark.slow  # the default run stays under 10 minutes on 2 cores; CI runs it in the slow pass
def test_ctrl_c_keeps_finished_cells_says_what_was_lost_and_the_rerun_redoes_none(tmp_path):
    suite = _suite(tmp_path / "suite")
    out = tmp_path / "out"
    process = _start(suite, out, workers=1)
    deadline = time.monotonic() + 180
    try:
        while len(_complete_cells(_fragments(out) if out.exists() else {})) < 2:
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "no two cells finished within 3 minutes"
            time.sleep(0.05)
        os.killpg(process.pid, signal.SIGINT)  # what Ctrl-C in a terminal does: the whole foreground group
        interrupted = time.monotonic()
        _, stderr = process.communicate(timeout=60)
        stopped_in = time.monotonic() - interrupted
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 130, stderr
    assert stopped_in < 10, f"took {stopped_in:.1f} s to stop: it waited for the running cell"
    assert "Traceback" not in stderr, stderr
    kept = _fragments(out)
    complete = _complete_cells(kept)
    match = re.search(r"interrupted: (\d+) finished cells are kept in .* \((\d+) of them this run\); "
                      r"(\d+) running cells were stopped and their work is lost, (\d+) had not started", stderr)
    assert match, stderr
    said_kept, said_now, said_running, said_pending = map(int, match.groups())
    print(f"Ctrl-C: stopped in {stopped_in:.1f} s; {stderr.strip()}")
    assert said_kept == said_now == len(complete) and said_running == 1
    assert said_kept + said_running + said_pending == CELLS
    gone = time.monotonic() + 5  # the stopped worker is gone too (multiprocessing's tracker exits just after)
    while _group(process.pid) and time.monotonic() < gone:
        time.sleep(0.1)
    assert not _group(process.pid), _group(process.pid)
    assert not (out / "results.parquet").exists()

    rerun = subprocess.run([sys.executable, "-m", "simrig.cli", "bench", str(suite), "--out", str(out), "--workers",
                            "2", "--quiet"], capture_output=True, text=True, timeout=600)
    assert rerun.returncode == 0, rerun.stderr
    assert f"({len(complete)} finished earlier, {CELLS - len(complete)} run now)" in rerun.stdout
    after = _fragments(out)
    assert {path: after[path] for path in kept} == kept  # not one finished fragment computed again
    assert len(after) == CELLS * TRACKERS


def test_a_tracker_that_hangs_on_frame_3_is_stopped_and_its_rows_say_it_timed_out(tmp_path, monkeypatch):
    import pyarrow.parquet as pq

    from simrig.benchmark import run_bench

    folder = tmp_path / "suite"
    _suite(folder)
    (folder / "hang.toml").write_text(
        'name = "hang"\nscenarios = ["tiny_scenario.toml"]\nseeds = [0, 1]\nframes = 8\nframe_time_limit_s = 2\n'
        '[[trackers]]\ntracker = "saga"\n[[trackers]]\ntracker = "bench_trackers:HangsOnFrame3"\n')
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    monkeypatch.setenv("PYTHONPATH", str(Path(__file__).parent))  # for the spawned pool workers
    started = time.monotonic()
    run = run_bench(folder / "hang.toml", out=tmp_path / "out", workers=2, trust_file=True)
    took = time.monotonic() - started
    print(f"hanging tracker: the bench (2 cells, limit 2 s) finished in {took:.1f} s")
    assert took < 120
    rows = pq.read_table(run.results).to_pandas()
    hung = rows[rows["tracker"] == "bench_trackers:HangsOnFrame3"]
    fine = rows[rows["tracker"] == "saga"]
    assert len(hung) == len(fine) == 2
    assert all(text.startswith("timeout: tracker 'bench_trackers:HangsOnFrame3': frame 3: step() did not return "
                               "within 2 s") for text in hung["failure"])
    assert hung["3d_AMOTA"].isna().all() and hung["2d_HOTA"].isna().all()
    assert fine["failure"].isna().all() and fine["2d_HOTA"].notna().all()
