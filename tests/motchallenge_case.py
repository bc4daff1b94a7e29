"""A MOTChallenge benchmark folder written as another tool would (not by simrig): ground truth and one tracker's
results for several sequences, in TrackEval's ``MotChallenge2DBox`` layout, with the conventions that matter —
1-based frames, the ``consider`` flag (read as an integer), the class column (pedestrians, distractor classes,
other classes, a tracker box on an other-class box and a distractor at once) and the visibility column."""

from __future__ import annotations

from pathlib import Path

import numpy as np

BENCHMARK, SPLIT, TRACKER = "MOT17", "train", "mytracker"


def write_case(root: Path, seed: int = 0, sequences=(("MOT17-02", 40, 6), ("MOT17-04", 30, 4), ("MOT17-09", 25, 5))
               ) -> tuple[Path, Path]:
    """Write ``root/gt/mot_challenge/MOT17-train/SEQ/...`` and ``root/trackers/mot_challenge/MOT17-train/
    mytracker/data/SEQ.txt``; returns (gt folder of the benchmark, the tracker's data folder)."""
    rng = np.random.default_rng(seed)
    gt_root = root / "gt" / "mot_challenge"
    bench = gt_root / f"{BENCHMARK}-{SPLIT}"
    data = root / "trackers" / "mot_challenge" / f"{BENCHMARK}-{SPLIT}" / TRACKER / "data"
    data.mkdir(parents=True)
    (gt_root / "seqmaps").mkdir(parents=True)
    (gt_root / "seqmaps" / f"{BENCHMARK}-{SPLIT}.txt").write_text("name\n" + "".join(f"{s}\n" for s, _, _ in sequences))
    for name, length, people in sequences:
        folder = bench / name
        (folder / "gt").mkdir(parents=True)
        (folder / "seqinfo.ini").write_text(f"[Sequence]\nname={name}\nimDir=img1\nframeRate=30\nseqLength={length}\n"
                                            "imWidth=1920\nimHeight=1080\nimExt=.jpg\n")
        gt_lines, tracker_lines = [], []
        start = rng.uniform([50, 100], [1500, 700], size=(people, 2))
        speed = rng.normal(0, 6, size=(people, 2))
        size = rng.uniform([40, 100], [90, 250], size=(people, 2))
        life = np.sort(rng.integers(1, length + 1, size=(people, 2)), axis=1)
        next_id = 1
        swap_at = int(rng.integers(length // 3, 2 * length // 3))
        for p in range(people):
            for f in range(life[p, 0], life[p, 1] + 1):
                x, y = start[p] + speed[p] * f
                w, h = size[p]
                visibility = round(float(rng.uniform(0, 1)), 2)  # 0 happens: TrackEval still scores it
                gt_lines.append(f"{f},{p + 1},{x:.2f},{y:.2f},{w:.2f},{h:.2f},1,1,{visibility}")
                if rng.random() < 0.12:
                    continue  # the tracker misses it
                track = p + 1 if f < swap_at or p % 2 else p + 101  # an id switch for half the people
                jitter = rng.normal(0, 4, size=4)
                tracker_lines.append(f"{f},{track},{x + jitter[0]:.3f},{y + jitter[1]:.3f},{w + jitter[2]:.3f},"
                                     f"{h + jitter[3]:.3f},{rng.uniform(0.3, 1):.3f},-1,-1,-1")
            next_id = p + 2
        for f in range(1, length + 1, 3):
            # a static person (distractor class 7, consider 0) with a tracker box on it: removed by both
            gt_lines.append(f"{f},{next_id},1700,50,40,90,0,7,1")
            tracker_lines.append(f"{f},900,1702,52,40,90,0.9,-1,-1,-1")
            # a car (class 3, consider 0) with a tracker box on it: not ground truth, the box a false positive
            gt_lines.append(f"{f},{next_id + 1},20,900,200,120,0,3,1")
            tracker_lines.append(f"{f},901,22,902,200,120,0.8,-1,-1,-1")
            # a reflection (class 12) nobody tracks: no miss
            gt_lines.append(f"{f},{next_id + 2},1500,900,60,150,0,12,0.5")
        for f in range(2, length + 1, 5):
            # a tracker box on a car and a static person at once: TrackEval's match gives it to the car (higher
            # IoU), so it is not removed but stays a false positive
            gt_lines.append(f"{f},{next_id + 3},600,50,100,100,0,3,1")
            gt_lines.append(f"{f},{next_id + 4},610,50,100,100,0,7,1")
            tracker_lines.append(f"{f},902,602,50,100,100,0.7,-1,-1,-1")
            # a pedestrian not to be considered (consider 0.4, read as the integer 0) with a tracker box on it
            gt_lines.append(f"{f},{next_id + 5},300,600,50,140,0.4,1,1")
            tracker_lines.append(f"{f},903,301,601,50,140,0.6,-1,-1,-1")
        # false positives
        for f in rng.integers(1, length + 1, size=5):
            tracker_lines.append(f"{f},{700 + int(f)},{rng.uniform(0, 1800):.1f},{rng.uniform(0, 900):.1f},50,120,"
                                 "0.4,-1,-1,-1")
        rng.shuffle(gt_lines)
        (folder / "gt" / "gt.txt").write_text("\n".join(gt_lines) + "\n")
        (data / f"{name}.txt").write_text("\n".join(sorted(tracker_lines, key=lambda s: int(s.split(",")[0])))
                                          + "\n")
    return bench, data


def trackeval_scores(root: Path) -> dict[str, float]:
    """TrackEval's combined HOTA, DetA, AssA, MOTA, IDSW, IDF1 on the folder ``write_case`` wrote."""
    import trackeval

    config = {**trackeval.Evaluator.get_default_eval_config(), "PRINT_RESULTS": False, "PRINT_CONFIG": False,
              "OUTPUT_SUMMARY": False, "OUTPUT_DETAILED": False, "PLOT_CURVES": False, "PRINT_ONLY_COMBINED": True,
              "TIME_PROGRESS": False, "DISPLAY_LESS_PROGRESS": True, "USE_PARALLEL": False, "LOG_ON_ERROR": None}
    dataset_config = {**trackeval.datasets.MotChallenge2DBox.get_default_dataset_config(),
                      "GT_FOLDER": str(root / "gt" / "mot_challenge"),
                      "TRACKERS_FOLDER": str(root / "trackers" / "mot_challenge"), "BENCHMARK": BENCHMARK,
                      "SPLIT_TO_EVAL": SPLIT, "TRACKERS_TO_EVAL": [TRACKER], "PRINT_CONFIG": False,
                      "OUTPUT_FOLDER": str(root / "trackeval-out")}
    evaluator = trackeval.Evaluator(config)
    metrics = [trackeval.metrics.HOTA(), trackeval.metrics.CLEAR({"PRINT_CONFIG": False}),
               trackeval.metrics.Identity({"PRINT_CONFIG": False})]
    results, _ = evaluator.evaluate([trackeval.datasets.MotChallenge2DBox(dataset_config)], metrics)
    combined = results["MotChallenge2DBox"][TRACKER]["COMBINED_SEQ"]["pedestrian"]
    return {"HOTA": float(np.mean(combined["HOTA"]["HOTA"])), "DetA": float(np.mean(combined["HOTA"]["DetA"])),
            "AssA": float(np.mean(combined["HOTA"]["AssA"])), "MOTA": float(combined["CLEAR"]["MOTA"]),
            "IDSW": float(combined["CLEAR"]["IDSW"]), "IDF1": float(combined["Identity"]["IDF1"])}
