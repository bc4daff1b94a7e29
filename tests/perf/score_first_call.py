"""Benchmark: the first and the warm ``simrig score`` against TrackEval on a MOTChallenge import, fresh processes.

Run explicitly (not part of the test suite)::

    python tests/perf/score_first_call.py [--frames 500] [--people 20] [--repeats 5] [--warm 5]

The case is the hidden case's shape: a MOTChallenge benchmark folder written as another tool would
(``tests/motchallenge_case.py``, one sequence of ``--frames`` frames and ``--people`` pedestrians plus
distractors), imported with ``simrig import --format motchallenge``. Timed, alternating, each in a fresh process
(wall time of the whole process, interpreter start-up included):

* ``simrig score DS TRACKS`` — the command;
* ``simrig.score(DS, TRACKS)`` — the front door, from ``python -c``;
* TrackEval 1.3.0's ``Evaluator.evaluate`` with ``MotChallenge2DBox`` and HOTA, CLEAR, Identity — from
  ``python -c``, the same metrics on the same files.

Warm: in one process each side scores the case ``--warm`` times after a first call; the best warm call is
reported. Also: the largest difference between simrig's and TrackEval's 2D metrics, and the simrig modules that
``python -X importtime`` shows the scoring path importing from ``simrig.trackers`` or ``simrig.pipeline``
(there should be none). Targets: simrig faster than TrackEval on the first call, at least 3× faster
warm. The table is printed and written to ``reports/perf/score_first_call.md``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from published import alternating, publish  # tests/perf helpers

TESTS = Path(__file__).resolve().parents[1]
REPORT = TESTS.parent / "reports" / "perf" / "score_first_call.md"
COMPARED = ("HOTA", "DetA", "AssA", "MOTA", "IDSW", "IDF1")


def _wall(command: list[str], cwd: Path) -> tuple[float, str]:
    started = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=900,
                          env={"PYTHONPATH": str(TESTS), "PATH": str(Path(sys.executable).parent),
                               "PYOPENGL_PLATFORM": "egl"})
    wall = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"{command[:3]} failed:\n{done.stderr[-3000:]}")
    return wall, done.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=500)
    parser.add_argument("--people", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--warm", type=int, default=5)
    args = parser.parse_args()

    sys.path.insert(0, str(TESTS))
    from motchallenge_case import write_case


    root = Path(tempfile.mkdtemp(prefix="score-first-call-"))
    _, data = write_case(root / "mot", sequences=(("MOT17-02", args.frames, args.people),))
    simrig_command = str(Path(sys.executable).parent / "simrig")
    _wall([simrig_command, "import", "--format", "motchallenge", str(root / "mot"), "--out", str(root / "ds")], root)
    dataset = root / "ds"

    front_door = (f"import json, simrig\nr = simrig.score({str(dataset)!r}, {str(data)!r})\n"
                  "print(json.dumps(r.metrics2d['overall']))\n")
    peer = (f"import json\nfrom pathlib import Path\nfrom motchallenge_case import trackeval_scores\n"
            f"print(json.dumps(trackeval_scores(Path({str(root / 'mot')!r}))))\n")
    sides = {
        "simrig score (command)": [simrig_command, "score", str(dataset), str(data)],
        "simrig.score() (Python)": [sys.executable, "-c", front_door],
        "TrackEval (Python)": [sys.executable, "-c", peer],
    }
    first, outputs = alternating(sides, args.repeats, lambda command: _wall(command, root))

    ours = json.loads(outputs["simrig.score() (Python)"].strip().splitlines()[-1])
    theirs = json.loads(outputs["TrackEval (Python)"].strip().splitlines()[-1])
    difference = max(abs(ours[name] - theirs[name]) for name in COMPARED)

    warm_ours = (f"import time, simrig\nd = simrig.open_dataset({str(dataset)!r})\nsimrig.score(d, {str(data)!r})\n"
                 f"best = min((lambda t: (simrig.score(d, {str(data)!r}), time.perf_counter() - t)[1])"
                 f"(time.perf_counter()) for _ in range({args.warm}))\nprint(best)\n")
    warm_peer = (f"import time\nfrom pathlib import Path\nfrom motchallenge_case import trackeval_scores\n"
                 f"root = Path({str(root / 'mot')!r})\ntrackeval_scores(root)\n"
                 f"best = min((lambda t: (trackeval_scores(root), time.perf_counter() - t)[1])(time.perf_counter())"
                 f" for _ in range({args.warm}))\nprint(best)\n")
    warm = {"simrig.score() (Python)": float(_wall([sys.executable, "-c", warm_ours], root)[1].split()[-1]),
            "TrackEval (Python)": float(_wall([sys.executable, "-c", warm_peer], root)[1].split()[-1])}

    imports = subprocess.run([sys.executable, "-X", "importtime", "-c", front_door], cwd=root, capture_output=True,
                             text=True, timeout=300).stderr
    loaded = sorted({line.split("|")[-1].strip() for line in imports.splitlines()
                     if any(part in line for part in ("simrig.trackers", "simrig.pipeline", "filterpy"))})

    peer_first = statistics.median(first["TrackEval (Python)"])
    lines = [
        "# First and warm scoring: simrig against TrackEval on a MOTChallenge import",
        "",
        f"Produced by `python tests/perf/score_first_call.py --frames {args.frames} --people {args.people} "
        f"--repeats {args.repeats} --warm {args.warm}` on {platform.machine()}, Python {platform.python_version()}. "
        f"One sequence of {args.frames} frames, {args.people} pedestrians plus distractors "
        "(`tests/motchallenge_case.py`), imported with `simrig import --format motchallenge`. First call: the "
        f"wall time of a fresh process (interpreter start-up included), median of {args.repeats}, the sides "
        f"alternating; warm: the best of {args.warm} calls in one process after a first.",
        "",
        "| side | first call, median [s] | min–max [s] | vs TrackEval | warm, best [s] | vs TrackEval |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for name, walls in first.items():
        median = statistics.median(walls)
        warm_value = warm.get(name)
        warm_cells = (f"{warm_value:.3f} | {warm['TrackEval (Python)'] / warm_value:.2f}× faster"
                      if warm_value is not None and name != "TrackEval (Python)" else
                      (f"{warm_value:.3f} | —" if warm_value is not None else "— | —"))
        versus = "—" if name == "TrackEval (Python)" else f"{peer_first / median:.2f}× faster"
        lines.append(f"| {name} | {median:.2f} | {min(walls):.2f}–{max(walls):.2f} | {versus} | {warm_cells} |")
    lines += [
        "",
        f"Largest difference of HOTA, DetA, AssA, MOTA, IDSW, IDF1 between the two: {difference:.1e}.",
        "",
        "Modules of `simrig.trackers`, `simrig.pipeline` or filterpy that `python -X importtime` shows the "
        f"front door's scoring path importing: {', '.join(loaded) if loaded else 'none'}.",
        "",
    ]
    publish(lines, REPORT)


if __name__ == "__main__":
    main()
