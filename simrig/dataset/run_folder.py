"""The layout of a ``simrig run`` folder: one place that names its parts, for the pipeline that writes it and the
commands that read it (``explain``, ``view``)::

    dataset/                      the generated dataset, shared by every tracker run into this folder
    tracks/LABEL/                 a tracker's tracks (LABEL: the tracker's name, plus a key of its parameters
                                  and scored camera when it has any)
    tracks/LABEL/tracker.json     how to build that tracker again: name, parameters, scored camera
    scores/LABEL/score.json       every metric of that run: no wall-clock time, no absolute path, no timestamp
    scores/LABEL/errors.parquet   every FN/IDS/FRAG with its causes (and a miss's consequence for the ego's plan)
    scores/LABEL/plan.parquet     the ego's plan per frame on the ground truth and on the tracks (3D trackers)
    scores/LABEL/report.md        the score table and the command that reproduces it
    scores/LABEL/timings.json     how long generation and the tracker's step() took (machine-dependent)
    explain/LABEL/                what each cause cost that tracker (``simrig explain``)
    report.md                     every tracker run in this folder, one section each (sorted by label)
"""

from pathlib import Path

from .manifest import MANIFEST_NAME

DATASET_DIR = "dataset"
TRACKS_DIR = "tracks"
SCORES_DIR = "scores"
EXPLAIN_DIR = "explain"
REPORT = "report.md"
TRACKER_RECORD = "tracker.json"


def what_folder_holds(out: Path) -> str:
    """``"; it is …"`` for a folder that holds a simrig dataset or is a run folder (for a refusal of it as another
    command's output), ``""`` otherwise."""
    if (out / MANIFEST_NAME).is_file():
        return ("; it is a simrig dataset folder, which simrig reads and does not write into (simrig track DATASET "
                "--tracker NAME runs a tracker on it)")
    if (out / DATASET_DIR / MANIFEST_NAME).is_file():
        return f"; it looks like a 'simrig run' folder: its dataset is {str(out / DATASET_DIR)!r}"
    return ""
