"""Run the nuScenes devkit's tracking evaluation and print its summary as JSON (run by the tests in an
environment that has ``nuscenes-devkit``, which pins numpy < 2 and so cannot live in simrig's)::

    python nuscenes_devkit_eval.py DATAROOT VERSION SPLIT RESULTS.json OUTPUT_DIR

Writes nothing but the devkit's own output folder; prints ``metrics_summary.json``.
"""

import json
import sys


def main(dataroot: str, version: str, split: str, results: str, output: str) -> None:
    from nuscenes.eval.common.config import config_factory
    from nuscenes.eval.tracking.evaluate import TrackingEval

    evaluation = TrackingEval(config_factory("tracking_nips_2019"), results, split, output, version, dataroot,
                              verbose=False)
    evaluation.main(render_curves=False)
    with open(f"{output}/metrics_summary.json") as handle:
        print(json.dumps(json.load(handle)))


if __name__ == "__main__":
    main(*sys.argv[1:6])
