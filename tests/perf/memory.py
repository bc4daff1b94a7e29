"""Memory check: peak RSS of ``generate``, ``track`` and ``score`` at 5,000 frames of
``highway_surround6`` (rendering off) against 500 frames; the target is at most 1.5×.

Run explicitly (not part of the test suite)::

    python tests/perf/memory.py [--frames 500 5000] [--trackers saga global_hungarian] [--scratch /tmp/simrig-memory]
                                [--steps generate track score] [--before COMMIT] [--repeats 1]

Each command runs as the CLI a user types (``simrig generate|track|score``), in its own child process, one at a
time; its peak resident set size is the ``ru_maxrss`` that ``os.wait4`` returns for exactly that child (the
kernel's high-water mark of its RSS, not a sampled value). The scenario is ``highway_surround6`` extended with
``[render] visibility = false`` (traffic, projection and the sensor model; no pyrender), seed 0.

Datasets and tracks are kept under ``--scratch`` (``ds{N}``, ``tracks{N}_{tracker}``) and reused by later runs;
``--steps`` chooses what is measured this time (e.g. ``--steps track score`` reuses the datasets, since a
5,000-frame generation takes minutes). Measurements are merged into ``--scratch/measurements.json`` with the
commit they were made at, and the table of every (command, frames) measured so far is printed and written to
``reports/perf/memory.md``. With ``--before COMMIT`` the simrig of that commit (its sources unpacked from git into
``--scratch``, this environment's dependencies) is measured too, alternating with the working tree's, and the
report says whether both wrote the same datasets (every file's SHA-256) and the same scores.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import tomli_w
from published import command_line, machine, publish  # tests/perf helpers

REPORT = Path(__file__).resolve().parents[2] / "reports" / "perf" / "memory.md"
SCENARIO = "highway_surround6"
TARGET = 1.5
"""[-] peak RSS at the longest run may be at most this multiple of the shortest run's."""
SIMRIG = [str(Path(sys.executable).with_name("simrig"))]
"""The CLI of the environment this script runs in."""
ROOT = Path(__file__).resolve().parents[2]


def peak_rss_mb(command: list[str]) -> tuple[float, float]:
    """Run ``command`` as a child process; its peak RSS [MiB] (``ru_maxrss`` from ``os.wait4``) and wall time
    [s]. A failing command stops the benchmark with its exit status."""
    started = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode:
        raise SystemExit(f"{' '.join(command)}: exit status {child.returncode}")
    return usage.ru_maxrss / 1024, time.perf_counter() - started  # ru_maxrss is in KiB on Linux


def git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()


def commit() -> str:
    """The short commit of the working tree (with ``+`` when it has uncommitted changes)."""
    dirty = git("status", "--porcelain", "--untracked-files=no")
    return git("rev-parse", "--short", "HEAD") + ("+" if dirty else "")


def cli_at(revision: str, scratch: Path) -> list[str]:
    """A command that runs the simrig CLI of ``revision``: its sources (``simrig/``, ``tracker/``,
    ``scenarios/``) unpacked under ``scratch`` in the installed layout and put first on the path; the
    dependencies are this environment's."""
    source = scratch / f"src-{revision}"
    if not (source / "simrig").is_dir():
        shutil.rmtree(source, ignore_errors=True)
        source.mkdir(parents=True)
        archive = subprocess.run(["git", "archive", revision, "simrig", "tracker", "scenarios"], cwd=ROOT,
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(source)], input=archive, check=True)
        (source / "tracker").rename(source / "simrig" / "trackers")
        (source / "scenarios").rename(source / "simrig" / "scenarios")
    return [sys.executable, "-c", f"import sys; sys.path.insert(0, {str(source)!r}); sys.argv[0] = 'simrig'; "
                                  "from simrig.cli import console; sys.exit(console())"]


def same_dataset(a: Path, b: Path) -> bool:
    """Whether two datasets hold the same files (the SHA-256 of every file in their manifests)."""
    hashes = [{name: entry["sha256"] for name, entry in json.loads((d / "manifest.json").read_text())["files"].items()}
              for d in (a, b)]
    return hashes[0] == hashes[1]


def same_scores(a: Path, b: Path) -> bool:
    """Whether two ``score --json`` files hold the same values (the paths they name aside)."""
    values = [{k: v for k, v in json.loads(path.read_text()).items() if k not in ("dataset", "tracks")}
              for path in (a, b)]
    return values[0] == values[1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, nargs="+", default=[500, 5000])
    parser.add_argument("--trackers", nargs="+", default=["saga", "global_hungarian"])
    parser.add_argument("--scratch", type=Path, default=Path("/tmp/simrig-memory"))
    parser.add_argument("--steps", nargs="+", choices=("generate", "track", "score"),
                        default=["generate", "track", "score"])
    parser.add_argument("--before", default="", help="also measure the simrig of this commit, side by side")
    parser.add_argument("--repeats", type=int, default=1,
                        help="runs of each command: the highest peak RSS and the shortest wall time are kept")
    parser.add_argument("--report", type=Path, default=REPORT)
    args = parser.parse_args()
    scratch = args.scratch.resolve()
    scratch.mkdir(parents=True, exist_ok=True)
    scenario = scratch / f"{SCENARIO}-no-rendering.toml"
    scenario.write_text(tomli_w.dumps({"extends": SCENARIO, "render": {"visibility": False}}))
    store = scratch / "measurements.json"
    measured = json.loads(store.read_text()) if store.exists() else {}
    versions = {"now": (SIMRIG, commit())}
    if args.before:
        versions[f"at {args.before}"] = (cli_at(args.before, scratch), args.before)

    def measure(key: str, command: list[str], at: str) -> None:
        runs = [peak_rss_mb(command) for _ in range(args.repeats)]
        rss, wall = max(rss for rss, _ in runs), min(wall for _, wall in runs)
        measured[key] = {"rss_mb": rss, "wall_s": wall, "commit": at, "repeats": args.repeats}
        store.write_text(json.dumps(measured, indent=1, sort_keys=True))
        print(f"{key}: peak RSS {rss:.0f} MiB, {wall:.0f} s", flush=True)

    for frames in sorted(args.frames):
        for label, (simrig, at) in versions.items():  # the versions alternate, so load on the machine is shared
            folder = scratch / label.replace(" ", "-")
            dataset = folder / f"ds{frames}"
            if "generate" in args.steps:
                shutil.rmtree(dataset, ignore_errors=True)
                measure(f"{label}|generate|{frames}", [*simrig, "generate", str(scenario), "--seed", "0",
                                                       "--frames", str(frames), "--out", str(dataset), "--quiet"], at)
            for name in args.trackers:
                tracks = folder / f"tracks{frames}_{name}"
                if "track" in args.steps:
                    shutil.rmtree(tracks, ignore_errors=True)
                    measure(f"{label}|track {name}|{frames}", [*simrig, "track", str(dataset), "--tracker", name,
                                                               "--out", str(tracks)], at)
                if "score" in args.steps:
                    measure(f"{label}|score {name}|{frames}", [*simrig, "score", str(dataset), str(tracks), "--json",
                                                               str(folder / f"score{frames}_{name}.json")], at)

    commands = ["generate", *(f"track {name}" for name in args.trackers), *(f"score {name}" for name in args.trackers)]
    lengths = sorted({int(key.split("|")[2]) for key in measured})
    short, long = lengths[0], lengths[-1]
    rows, all_ok = [], True
    for label in versions:
        for name in commands:
            cells = [measured.get(f"{label}|{name}|{frames}") for frames in lengths]
            if cells[0] is None or cells[-1] is None:
                continue
            ratio = cells[-1]["rss_mb"] / cells[0]["rss_mb"]
            ok = ratio <= TARGET
            if label == "now":
                all_ok &= ok
            rows.append(f"| {label} | `simrig {name}` | " + " | ".join(
                "–" if cell is None else f"{cell['rss_mb']:.0f} ({cell['wall_s']:.0f} s, {cell['commit']}"
                + (f", ×{cell['repeats']}" if cell.get("repeats", 1) > 1 else "") + ")"
                for cell in cells) + f" | {ratio:.2f} ({'ok' if ok else 'FAILS'}) |")
    checks = []
    if args.before:
        before = scratch / f"at-{args.before}"
        for frames in lengths:
            if (scratch / "now" / f"ds{frames}" / "manifest.json").exists() and (before / f"ds{frames}").exists():
                checks.append(f"{frames} frames: datasets of both versions "
                              + ("identical (every file's SHA-256)" if same_dataset(scratch / "now" / f"ds{frames}",
                                                                                     before / f"ds{frames}")
                                 else "DIFFER"))
            for name in args.trackers:
                now, then = scratch / "now" / f"score{frames}_{name}.json", before / f"score{frames}_{name}.json"
                if now.exists() and then.exists():
                    checks.append(f"{frames} frames, {name}: scores of both versions "
                                  + ("identical" if same_scores(now, then) else "DIFFER"))
    lines = [
        f"# Peak memory of long runs — {SCENARIO}, rendering off, seed 0",
        "",
        f"Command: `{command_line()}`  ",
        f"Machine: {machine()}. Peak RSS [MiB] of each CLI command run alone in its own child process "
        "(`ru_maxrss` of that child from `os.wait4`), with its wall time and the commit it was measured at "
        "(`+`: with uncommitted changes); with `--repeats`, the highest peak and the shortest time of the runs "
        f"(`×n`). Target: {long} frames within {TARGET}× of {short}.",
        "",
        "| simrig | command | " + " | ".join(f"{frames} frames" for frames in lengths) + f" | {long}/{short} |",
        "|---|---|" + "---:|" * (len(lengths) + 1),
        *rows,
        "",
        *(f"- {line}" for line in checks),
        "" if checks else "",
        f"The memory check for simrig now: {'PASSES' if all_ok else 'FAILS'}.",
        "",
    ]
    publish(lines, args.report)
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
