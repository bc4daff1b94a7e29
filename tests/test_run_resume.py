"""``simrig run`` is resumable and reproducible: killed with SIGKILL at random moments and rerun without
``--overwrite``, every rerun finishes and writes a score.json (and report.md) byte-identical to an uninterrupted
run's, in another folder."""

import os
import random
import signal
import subprocess
import sys
import time

import pytest

SCENARIO = ["highway_stereo", "--frames", "20", "--seed", "3", "--tracker", "saga", "--quiet"]
RESULTS = ("scores/saga/score.json", "scores/saga/errors.parquet", "scores/saga/report.md", "report.md")


def _run(out):
    return [sys.executable, "-m", "simrig.cli", "run", *SCENARIO, "--out", str(out)]


@pytest.mark.slow
def test_run_killed_at_ten_random_moments_resumes_to_the_same_bytes(tmp_path):
    started = time.monotonic()
    reference = subprocess.run(_run(tmp_path / "reference"), capture_output=True, text=True, timeout=600)
    duration = time.monotonic() - started
    assert reference.returncode == 0, reference.stderr
    expected = {name: (tmp_path / "reference" / name).read_bytes() for name in RESULTS}
    draw = random.Random(23)
    moments = sorted(draw.uniform(0.2, duration) for _ in range(10))
    assert len(set(moments)) == 10
    outcomes = []
    for trial, moment in enumerate(moments):
        out = tmp_path / f"killed-{trial}"
        process = subprocess.Popen(_run(out), start_new_session=True, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
        time.sleep(moment)
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        had_dataset = (out / "dataset" / "manifest.json").exists()
        rerun = subprocess.run(_run(out), capture_output=True, text=True, timeout=600)
        assert rerun.returncode == 0, (moment, rerun.stderr)
        for name in RESULTS:
            assert (out / name).read_bytes() == expected[name], (moment, name)
        assert ("reusing the complete dataset" in rerun.stdout) == had_dataset
        outcomes.append((round(moment, 2), had_dataset))
    print(f"reference run {duration:.1f} s; kills at (s, dataset complete before the kill): {outcomes}")
    # the moments covered both a kill before the dataset was complete and one after
    assert {had for _, had in outcomes} == {True, False}, outcomes
