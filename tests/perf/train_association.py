"""Train the packaged learned association (``tracker/models/association.json``) and report what it learned.

    python tests/perf/train_association.py [--collection DIR] [--count 300] [--held-out 60]

Makes (or reuses) the ``traffic_mix`` collection of ``--count`` sequences (collection seed 0: sequence seeds are
≥ 1,000,000, so no bench seed is trained on), records the (track, detection) pairs of the reference tracker on
each (:mod:`simrig.collection.pairs`), fits the logistic model on all but the last ``--held-out`` sequences, and
reports its ROC AUC on those, against the hand-set Mahalanobis distance alone (the gate it replaces), and the
permutation importance of each feature. Writes the model and ``reports/learned/training.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from published import command_line, machine, publish
from simrig.trackers.association_features import TRACK_FEATURES
from simrig.trackers.learned import DEFAULT_MODEL
from sklearn.metrics import roc_auc_score

from simrig.collection import generate_collection
from simrig.collection.loader import CollectionPairs
from simrig.collection.train import fit_association, permutation_importances, roc_auc

ROOT = Path(__file__).resolve().parents[2]
REPORT = ROOT / "reports" / "learned" / "training.md"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--collection", type=Path, default=Path("runs/collections/traffic_mix"))
    parser.add_argument("--count", type=int, default=300)
    parser.add_argument("--held-out", type=int, default=60)
    args = parser.parse_args()
    run = generate_collection("traffic_mix", count=args.count, out=args.collection, seed=0, progress=True)
    features, same, sequence = CollectionPairs(run.out).track_pairs()
    train = sequence < args.count - args.held_out
    model = fit_association(features[train], same[train], trained_on={
        "collection": f"simrig generate --space traffic_mix --count {args.count} --seed 0",
        "sequences": f"0-{args.count - args.held_out - 1}", "pairs": int(train.sum()),
        "teacher": "global_hungarian (its Kalman filter, life rule, Mahalanobis gate, Hungarian assignment)"})
    DEFAULT_MODEL.parent.mkdir(parents=True, exist_ok=True)
    DEFAULT_MODEL.write_text(model.to_json())
    test = ~train
    auc = roc_auc(model, features[test], same[test])
    mahalanobis = roc_auc_score(same[test], -features[test, TRACK_FEATURES.index("mahalanobis")])
    importances = permutation_importances(model, features[test], same[test], repeats=5)
    lines = ["# The learned association: training", "",
             f"Produced by `{command_line()}` ({machine()}). Collection `traffic_mix`, {args.count} sequences of "
             f"2 s (collection seed 0; sequence seeds ≥ 1,000,000); the (track, detection) pairs the reference "
             f"tracker weighed; trained on sequences 0–{args.count - args.held_out - 1} ({int(train.sum()):,} "
             f"pairs, {same[train].mean():.1%} the same object), held out {args.count - args.held_out}–"
             f"{args.count - 1} ({int(test.sum()):,} pairs).", "",
             "| on the held-out pairs | ROC AUC |", "|---|---|",
             f"| learned model (`{DEFAULT_MODEL.relative_to(ROOT)}`) | {auc:.4f} |",
             f"| Mahalanobis distance alone (the hand-set gate's quantity) | {mahalanobis:.4f} |", "",
             "What it learned: permutation importance, the drop in held-out ROC AUC when one feature is shuffled "
             "across pairs (mean of 5 shuffles; the feature and its square together).", "",
             "| feature | AUC drop |", "|---|---|"]
    for name, drop in sorted(importances.items(), key=lambda item: -item[1]):
        lines.append(f"| `{name}` | {drop:+.4f} |")
    publish([*lines, ""], REPORT)
    print(f"model     {DEFAULT_MODEL}")
    return 0 if np.isfinite(auc) else 1


if __name__ == "__main__":
    sys.exit(main())
