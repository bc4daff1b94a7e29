"""Benchmark: ``simrig generate --space`` at scale.

    python tests/perf/collection.py [--space traffic_mix] [--count 2000] [--workers 2] [--no-ray]

Three collections of the same space, count and seed, each made by the command a user types:

1. uninterrupted, on the local pool of ``--workers`` processes: wall time and sequences per minute;
2. killed (SIGKILL to the command and its workers, as a machine going down) at two random moments, each drawn
   uniformly in 15–45 % of run 1's wall time after the run's start, then run again to the end;
3. on a two-node Ray cluster started on this machine (``ray start --head`` and a second node, one CPU each).

Every file of runs 2 and 3 (the lock file aside) is compared with run 1's, byte for byte. Writes
``reports/perf/collection.md``.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from published import command_line, machine, publish

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the Ray cluster helper
from ray_nodes import two_node_cluster  # noqa: E402

OUT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "collection.md"
SEED = 0


def digest(folder: Path) -> tuple[str, int]:
    """SHA-256 over every file's relative path and bytes (the lock file aside), and the number of files."""
    hasher, count = hashlib.sha256(), 0
    for path in sorted(folder.rglob("*")):
        if path.is_file() and path.name != ".lock":
            hasher.update(str(path.relative_to(folder)).encode() + b"\0" + path.read_bytes())
            count += 1
    return hasher.hexdigest(), count


def command(args: argparse.Namespace, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "simrig.cli", "generate", "--space", args.space, "--count", str(args.count),
            "--seed", str(SEED), "--quiet", "--out", str(out), *extra]


def run(argv: list[str]) -> tuple[float, str]:
    started = time.perf_counter()
    done = subprocess.run(argv, check=True, capture_output=True, text=True)
    return time.perf_counter() - started, done.stdout.strip()


def finished(out: Path) -> int:
    return len(list(out.glob("shards/*/*/manifest.json")))


def killed_at(argv: list[str], out: Path, after_s: float) -> tuple[float, int]:
    """Start ``argv``, SIGKILL its process group ``after_s`` seconds later; (seconds run, datasets finished)."""
    started = time.perf_counter()
    process = subprocess.Popen(argv, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        process.wait(timeout=after_s)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
    else:
        raise RuntimeError("the run finished before it was killed; the check needs a later kill")
    return time.perf_counter() - started, finished(out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--space", default="traffic_mix")
    parser.add_argument("--count", type=int, default=2000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--no-ray", action="store_true", help="skip run 3")
    parser.add_argument("--kill-seed", type=int, default=1, help="seed of the two kill moments")
    args = parser.parse_args()
    rows, notes = [], []
    with tempfile.TemporaryDirectory(dir=os.environ.get("SIMRIG_PERF_TMP")) as tmp:
        root = Path(tmp)
        whole = root / "whole"
        seconds, output = run(command(args, whole, "--workers", str(args.workers)))
        reference, files = digest(whole)
        rows.append(("1. uninterrupted, local pool", f"{args.workers} processes", seconds, args.count, "(reference)"))
        notes.append(f"run 1: `{output.splitlines()[0]}`; {files:,} files, "
                     f"{sum(p.stat().st_size for p in whole.rglob('*') if p.is_file()) / 2**20:,.0f} MiB")
        shutil.rmtree(whole / "shards")  # the digest is kept; the disk is not needed any more

        resumed = root / "resumed"
        moments = random.Random(args.kill_seed)
        spent = 0.0
        for kill in (1, 2):
            after = moments.uniform(0.15, 0.45) * seconds
            ran, done = killed_at(command(args, resumed, "--workers", str(args.workers)), resumed, after)
            spent += ran
            notes.append(f"run 2, kill {kill}: SIGKILL after {ran:.0f} s, {done:,} of {args.count:,} sequences "
                         f"finished; index.parquet present: {(resumed / 'index.parquet').exists()}")
        last, output = run(command(args, resumed, "--workers", str(args.workers)))
        notes.append(f"run 2, resumed: `{output.splitlines()[0]}`")
        same = digest(resumed)[0] == reference
        rows.append(("2. killed twice, resumed", f"{args.workers} processes", spent + last, args.count,
                     "identical" if same else "DIFFERENT"))
        shutil.rmtree(resumed)

        if not args.no_ray:
            with two_node_cluster() as (address, _):
                on_ray = root / "ray"
                seconds_ray, output = run(command(args, on_ray, "--engine", "ray", "--address", address))
            same = digest(on_ray)[0] == reference
            rows.append(("3. two-node Ray cluster", "2 nodes × 1 CPU", seconds_ray, args.count,
                         "identical" if same else "DIFFERENT"))
            notes.append(f"run 3: `{output.splitlines()[0]}`")
    lines = ["# `simrig generate --space` at scale", "",
             f"Produced by `{command_line()}` ({machine()}); space `{args.space}`, {args.count:,} sequences, "
             f"collection seed {SEED}. Wall time of the command a user types (start-up included).", "",
             "| run | engine | wall [s] | sequences/min | every file the same as run 1's |", "|---|---|---|---|---|"]
    for name, engine, seconds, count, same in rows:
        lines.append(f"| {name} | {engine} | {seconds:,.0f} | {60 * count / seconds:,.1f} | {same} |")
    lines += ["", *[f"- {note}" for note in notes], ""]
    publish(lines, OUT)
    return 0 if all(row[4] in ("(reference)", "identical") for row in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
