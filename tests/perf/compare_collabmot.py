"""Report: CollabMOT against its per-camera baseline on the ego camera of the stereo occlusion scenarios.

Run explicitly (not part of the test suite)::

    python tests/perf/compare_collabmot.py [--scenarios stereo_occluder stereo_occluder_narrow stereo_one_sided
        stereo_one_sided_narrow] [--seeds 100 101 … 109]
        [--frames 200] [--data runs/collabmot] [--out reports/trackers/collabmot.md]

Each (scenario, seed) dataset is generated once into ``--data``. On the same detections: each per-camera tracker
alone (``sort``, ``deepsort``, and ``bytetrack`` for reference), and ``collabmot`` with every (ego, remote)
pair of the first two, online (the default) and semi-online (its own rows); everything scored on the ego
camera ``left`` only (``simrig score --camera left``). HOTA, AssA, DetA and IDF1 are averaged over the seeds,
IDSW summed. The gains table shows ΔAssA and ΔIDF1 of every (scenario, combination) cell against the
per-camera tracker CollabMOT runs on the ego camera, whatever their sign, paired per seed with a 95 % BCa
bootstrap interval over the seeds (``simrig.report.paired``), and pooled over every scenario and seed; the
verdict counts the online cells whose interval shows both improved. Default seeds 100–109: no tracker was tuned
on seeds ≥ 100.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from published import cached_dataset, command_line, machine, publish  # tests/perf helpers
from simrig.scenarios import load_scenario
from simrig.trackers import create

from simrig.pipeline.track import run_tracker
from simrig.report.paired import paired_difference
from simrig.scoring import score

SCENARIOS = ("stereo_occluder", "stereo_occluder_narrow", "stereo_one_sided", "stereo_one_sided_narrow")
SINGLE = ("sort", "deepsort")
ALONE = ("bytetrack",)
"""Per-camera trackers shown alone for reference (CollabMOT does not run on them)."""
METRICS = ("HOTA", "AssA", "DetA", "IDF1")
EGO = "left"


def systems() -> list[tuple[str, str, dict]]:
    """(label, tracker, params): the baselines, then CollabMOT for every (ego, remote) pair online (the
    default, the paper's per-time-step output), then the same pairs semi-online (hindsight: interpolated gap
    boxes and past frames relabelled) in their own rows."""
    out = [(name, name, {}) for name in SINGLE + ALONE]
    for semi_online in (False, True):
        for ego in SINGLE:
            for remote in SINGLE:
                label = f"collabmot {ego}+{remote}" + (" (semi-online)" if semi_online else "")
                out.append((label, "collabmot", {"ego_tracker": ego, "remote_tracker": remote,
                                                 "semi_online": semi_online}))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=list(SCENARIOS))
    parser.add_argument("--seeds", nargs="+", type=int, default=list(range(100, 110)))
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--data", type=Path, default=Path("runs/collabmot"))
    parser.add_argument("--out", type=Path, default=Path("reports/trackers/collabmot.md"))
    args = parser.parse_args()

    results: dict[tuple[str, str], list[dict]] = {}
    baselines = {}
    for scenario in args.scenarios:
        baselines[scenario] = load_scenario(scenario).rig.baseline_m
        for seed in args.seeds:
            dataset = cached_dataset(scenario, seed, args.frames, args.data)
            for label, name, params in systems():
                folder = args.data / "tracks" / f"{scenario}-seed{seed}" / label.replace(" ", "_").replace("+", "-")
                built = create(name, **params)
                run = run_tracker(dataset, built, folder)
                metrics = score(dataset, run.out, camera=EGO).metrics2d["per_camera"][EGO]
                if params:
                    metrics = {**metrics, **built.mechanism(), "frames": args.frames}
                results.setdefault((scenario, label), []).append(metrics)
                print(f"{scenario} seed {seed} {label:40s} AssA {metrics['AssA']:.3f} IDF1 {metrics['IDF1']:.3f} "
                      f"IDSW {metrics['IDSW']:.0f}", flush=True)

    def mean(scenario: str, label: str, key: str) -> float:
        return float(np.mean([m[key] for m in results[(scenario, label)]]))

    def idsw(scenario: str, label: str) -> int:
        return int(sum(m["IDSW"] for m in results[(scenario, label)]))

    lines = [
        "# CollabMOT against its per-camera baseline, ego camera",
        "",
        f"Produced by `{command_line()}` ({machine()}). Scenarios: "
        + ", ".join(f"`{s}` (stereo pair, {baselines[s]:g} m baseline)" for s in args.scenarios)
        + f"; seeds {', '.join(map(str, args.seeds))}; {args.frames} frames at 10 Hz. Every tracker with its "
        "default parameters (CollabMOT: the paper's) on the same detections, scored on the ego camera `left` "
        "only (`simrig score DIR TRACKS --camera left`). HOTA, AssA, DetA, IDF1 are means over the seeds "
        "(Δ: against the per-camera tracker that runs on the ego camera, alone); IDSW is summed.",
        "",
    ]
    verdicts = []
    for scenario in args.scenarios:
        lines += [f"## {scenario} ({baselines[scenario]:g} m baseline)", "",
                  "| tracker on `left` | " + " | ".join(METRICS) + " | IDSW | AssA better in seeds |",
                  "|---|" + "---:|" * (len(METRICS) + 2)]
        for label, _, params in systems():
            ego = params.get("ego_tracker", label)
            cells = []
            for key in METRICS:
                value = mean(scenario, label, key)
                delta = value - mean(scenario, ego, key)
                cells.append(f"{value:.3f}" + (f" ({delta:+.3f})" if params else ""))
            better = ""
            if params:
                per_seed = [m["AssA"] - b["AssA"] for m, b in zip(results[(scenario, label)], results[(scenario, ego)],
                                                                 strict=True)]
                better = f"{sum(d > 0 for d in per_seed)}/{len(per_seed)}"
            lines.append(f"| `{label}` | " + " | ".join(cells) + f" | {idsw(scenario, label)} | {better} |")
        lines.append("")

    def paired(scenarios: list[str], label: str, ego: str, key: str):
        return paired_difference([m[key] for s in scenarios for m in results[(s, label)]],
                                 [m[key] for s in scenarios for m in results[(s, ego)]])

    columns = [*args.scenarios, "all"]
    lines += ["## Gains per cell, paired", "",
              "ΔAssA and ΔIDF1 against the per-camera tracker on the ego camera, in points (×100): the mean "
              "per-seed difference with its 95 % BCa bootstrap interval over the seeds (`all`: over every scenario "
              "and seed); `n.s.`: the interval contains 0. Online rows first, semi-online rows (hindsight, not the "
              "paper's per-time-step output) after. The paper (CollabMOT, Ninh and Kim, 2024) reports +0.3 to +2.2 "
              "AssA points over its single-camera trackers on KITTI.", "",
              "| combination | " + " | ".join(f"{s} ΔAssA | {s} ΔIDF1" for s in columns) + " |",
              "|---|" + "---:|" * (2 * len(columns))]
    for label, _, params in systems():
        if not params:
            continue
        ego = params["ego_tracker"]
        cells = []
        for column in columns:
            scenarios = args.scenarios if column == "all" else [column]
            assa, idf1 = (paired(scenarios, label, ego, key) for key in ("AssA", "IDF1"))
            cells += [assa.text(100, 1), idf1.text(100, 1)]
            if column != "all" and not params["semi_online"]:
                verdicts.append(assa.significant and assa.mean > 0 and idf1.significant and idf1.mean > 0)
        lines.append(f"| `{label}` | " + " | ".join(cells) + " |")
    lines += ["", f"Online: AssA and IDF1 both improved, with intervals above 0, in {sum(verdicts)} of "
              f"{len(verdicts)} (scenario, combination) cells.", ""]
    lines += mechanism_lines(results, args.scenarios)
    publish(lines, args.out)


MECHANISM = ("linked", "reconnected", "relabelled", "interpolated")


def mechanism_lines(results: dict, scenarios: list[str]) -> list[str]:
    """What CollabMOT's mechanism did per sequence (means over seeds) and which of it goes with its AssA gain:
    Spearman's ρ across every (scenario, seed) sequence between each count and ΔAssA against the ego's tracker."""
    from scipy.stats import spearmanr

    lines = ["## What the collaboration did, per sequence", "",
             "Means over the seeds of each scenario: (ego, remote) pairs linked per frame, lost ego tracklets "
             "reconnected through a global id, ego tracklets reported under an id an earlier ego tracklet had "
             "(what changes the ego camera's identities), gap boxes interpolated (semi-online only). Last "
             "columns: Spearman's ρ between each count and ΔAssA over all sequences (n.s. where its p > 0.05).", "",
             "| combination | " + " | ".join(f"{s} linked/frame · reconnected · relabelled · interpolated"
                                           for s in scenarios) + " | " + " | ".join(f"ρ({m}, ΔAssA)"
                                                                                  for m in MECHANISM) + " |",
             "|---|" + "---:|" * (len(scenarios) + len(MECHANISM))]
    for label, _, params in systems():
        if not params:
            continue
        ego = params["ego_tracker"]
        cells = []
        for scenario in scenarios:
            rows = results[(scenario, label)]
            cells.append(f"{np.mean([r['linked'] / r['frames'] for r in rows]):.2f} · "
                         + " · ".join(f"{np.mean([r[m] for r in rows]):.1f}" for m in MECHANISM[1:]))
        gains = [m["AssA"] - b["AssA"] for s in scenarios
                 for m, b in zip(results[(s, label)], results[(s, ego)], strict=True)]
        for name in MECHANISM:
            counts = [r[name] for s in scenarios for r in results[(s, label)]]
            if np.ptp(counts) == 0 or np.ptp(gains) == 0:
                cells.append("–")
                continue
            rho, p = spearmanr(counts, gains)
            cells.append(f"{rho:+.2f}" + ("" if p <= 0.05 else " n.s."))
        lines.append(f"| `{label}` | " + " | ".join(cells) + " |")
    return lines + [""]


if __name__ == "__main__":
    main()
