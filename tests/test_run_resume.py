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
    draw = random.Random(23)  # one moment in each tenth of the run, so every stage is hit
    moments = [0.2 + (tenth + draw.random()) * (duration - 0.2) / 10 for tenth in range(10)]
    # and two kills aimed at the later stages: as soon as the dataset is complete, as soon as a score is written
    triggers = [None] * 10 + ["dataset/manifest.json", "scores/saga/score.json"]
    outcomes = []
    for trial, (moment, trigger) in enumerate(zip(moments + [None, None], triggers, strict=True)):
        out = tmp_path / f"killed-{trial}"
        process = subprocess.Popen(_run(out), start_new_session=True, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
        if trigger is None:
            time.sleep(moment)
        else:
            while not (out / trigger).exists() and process.poll() is None:
                time.sleep(0.01)
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        had_dataset = (out / "dataset" / "manifest.json").exists()
        rerun = subprocess.run(_run(out), capture_output=True, text=True, timeout=600)
        assert rerun.returncode == 0, (moment, trigger, rerun.stderr)
        for name in RESULTS:
            assert (out / name).read_bytes() == expected[name], (moment, trigger, name)
        assert ("reusing the complete dataset" in rerun.stdout) == had_dataset
        outcomes.append((trigger or round(moment, 2), had_dataset))
    print(f"reference run {duration:.1f} s; kills at (s, dataset complete before the kill): {outcomes}")
    assert not outcomes[0][1] and outcomes[-2][1], outcomes  # a kill before the dataset was complete, one after
