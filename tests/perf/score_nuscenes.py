"""Benchmark: scoring a nuScenes tracking result, simrig against the nuScenes devkit, first call and warm.

Run explicitly (not part of the test suite)::

    python tests/perf/score_nuscenes.py [--devkit-python .cache/nuscenes-venv/bin/python] [--repeats 5] [--warm 5]

The case is the tests' nuScenes case (``tests/nuscenes_case.py``: the devkit's database tables for two scenes and a
tracking-results JSON written as another tool would), imported once with ``simrig import --format nuscenes``. Each
side scores the same results file against the same ground truth, the AMOTA family over every class:

* the nuScenes devkit 1.2.0, ``TrackingEval(...).main()`` (``tests/nuscenes_devkit_eval.py``; it pins numpy < 2,
  so it runs in its own environment, ``--devkit-python``), which also loads the database tables;
* ``simrig.score(DS, RESULTS)`` on the imported dataset.

First call: CPU time (user + system) of a fresh process, interpreter start-up included, median of ``--repeats``,
the sides alternating. Warm: the best of ``--warm`` calls in one process after a first (the devkit's evaluation
object made again each call, as a new evaluation makes it). Writes ``reports/perf/score_nuscenes.md``.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from published import alternating, command_line, machine, publish  # tests/perf helpers

TESTS = Path(__file__).resolve().parents[1]
REPORT = TESTS.parent / "reports" / "perf" / "score_nuscenes.md"
COMPARED = ("AMOTA", "AMOTP", "MOTA", "IDS", "FRAG", "TP", "FP", "FN")


def _cpu(command: list[str], cwd: Path) -> tuple[float, str]:
    """(CPU seconds of the child, user + system; its stdout)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=900,
                          env={"PYTHONPATH": str(TESTS), "PATH": str(Path(sys.executable).parent),
                               "PYOPENGL_PLATFORM": "egl"})
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{command[:3]} failed:\n{done.stderr[-3000:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), done.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--devkit-python", type=Path,
                        default=TESTS.parent / ".cache" / "nuscenes-venv" / "bin" / "python")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--warm", type=int, default=5)
    args = parser.parse_args()
    if not args.devkit_python.exists():
        raise SystemExit(f"no Python with nuscenes-devkit at {args.devkit_python} (see tests/test_import.py)")

    sys.path.insert(0, str(TESTS))
    from nuscenes_case import SPLIT, VERSION, write_case

    root = Path(tempfile.mkdtemp(prefix="score-nuscenes-"))
    results = write_case(root / "nu")
    _cpu([str(Path(sys.executable).parent / "simrig"), "import", "--format", "nuscenes", str(root / "nu"),
          "--out", str(root / "ds")], root)
    devkit_script = str(TESTS / "nuscenes_devkit_eval.py")
    ours = (f"import json, simrig\nr = simrig.score({str(root / 'ds')!r}, {str(results)!r})\n"
            "print(json.dumps(r.metrics3d['overall']))\n")
    sides = {
        "nuScenes devkit 1.2.0": [str(args.devkit_python), devkit_script, str(root / "nu"), VERSION, SPLIT,
                                  str(results), str(root / "devkit")],
        "simrig.score()": [sys.executable, "-c", ours],
    }
    first, outputs = alternating(sides, args.repeats, lambda command: _cpu(command, root))
    devkit = json.loads(outputs["nuScenes devkit 1.2.0"].strip().splitlines()[-1])
    simrig_metrics = json.loads(outputs["simrig.score()"].strip().splitlines()[-1])
    difference = max(abs(float(simrig_metrics[name]) - float(devkit[name.lower()])) for name in COMPARED)

    timer = "import time\nbest = float('inf')\n"
    warm_devkit = (f"import sys\nsys.argv = ['x', {str(root / 'nu')!r}, {VERSION!r}, {SPLIT!r}, {str(results)!r}, "
                   f"{str(root / 'devkit')!r}]\nimport io, contextlib\nfrom nuscenes_devkit_eval import main\n"
                   + timer + f"for _ in range({args.warm} + 1):\n    t = time.process_time()\n"
                   "    with contextlib.redirect_stdout(io.StringIO()):\n        main(*sys.argv[1:6])\n"
                   "    best = min(best, time.process_time() - t) if _ else best\nprint(best)\n")
    warm_ours = (f"import simrig\nd = simrig.open_dataset({str(root / 'ds')!r})\n" + timer
                 + f"for _ in range({args.warm} + 1):\n    t = time.process_time()\n"
                 f"    simrig.score(d, {str(results)!r})\n"
                 "    best = min(best, time.process_time() - t) if _ else best\nprint(best)\n")
    warm = {"nuScenes devkit 1.2.0": float(_cpu([str(args.devkit_python), "-c", warm_devkit], root)[1].split()[-1]),
            "simrig.score()": float(_cpu([sys.executable, "-c", warm_ours], root)[1].split()[-1])}

    peer = "nuScenes devkit 1.2.0"
    lines = ["# Scoring a nuScenes tracking result: simrig against the nuScenes devkit, first call and warm", "",
             f"Produced by `{command_line()}` on {machine()}. The tests' nuScenes case (`tests/nuscenes_case.py`: "
             "two scenes, four classes), imported with `simrig import --format nuscenes`; both sides score the same "
             "results file, the AMOTA family over every class. First call: CPU time (user + system) of a fresh "
             f"process, start-up included, median of {args.repeats}, the sides alternating; warm: the best of "
             f"{args.warm} calls in one process after a first.", "",
             "| side | first call, median [CPU s] | min–max | vs devkit | warm, best [CPU s] | vs devkit |",
             "|---|---:|---:|---:|---:|---:|"]
    for name in sides:
        median = float(np.median(first[name]))
        ratio = "—" if name == peer else f"{np.median(first[peer]) / median:.1f}× faster"
        warm_ratio = "—" if name == peer else f"{warm[peer] / warm[name]:.0f}× faster"
        lines.append(f"| {name} | {median:.2f} | {min(first[name]):.2f}–{max(first[name]):.2f} | {ratio} | "
                     f"{warm[name]:.3f} | {warm_ratio} |")
    lines += ["", f"Largest difference of {', '.join(COMPARED)} between the two: {difference:.1e}.", ""]
    publish(lines, REPORT)


if __name__ == "__main__":
    main()
