"""A dataset folder opened: :class:`Dataset`, a thin front over parts with one job each — its identity from the
manifest (attributes), its tables (:mod:`.table_store`), what a tracker is given frame by frame
(:mod:`.delivery`), the ground truth (:mod:`.ground_truth`) and its summary (:mod:`.summary`)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from functools import cached_property
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import DatasetError
from ..rig import rig_from_dict
from ..road import RoadMarkings
from ..types import GroundTruthFrame, Rig, SensorFrame
from .delivery import sensor_frames
from .ground_truth import GroundTruth, ground_truth_frames
from .manifest import MANIFEST_NAME, read_manifest
from .manifest_files import ManifestFiles
from .summary import summary, summary_counts
from .table_store import TableStore


class Dataset:
    """A complete dataset folder. Open with :meth:`open`; tables load on first use."""

    def __init__(self, path: Path, manifest: dict):
        self.path = path
        self.manifest = manifest
        self.seed: int = int(manifest["seed"])
        self.scenario: dict = manifest["scenario"]
        """The resolved scenario the dataset was generated from (as a plain dict)."""
        self.frame_count: int = int(manifest["frames"])
        self.source: dict | None = manifest.get("source")
        """How an imported dataset was made (``simrig import``: its ``format``, ``path``, whether it has 3D
        ground truth and a calibrated rig); ``None`` for a generated one."""
        self.has_3d: bool = self.source is None or bool(self.source.get("ground_truth_3d"))
        """Whether the dataset holds world-frame 3D ground truth (an import from 2D boxes does not)."""
        self.causes_known: bool = self.source is None
        """Whether the dataset records why the detector missed each box (generated: yes; imported: unknown)."""
        self.identity: dict = {"scenario": self.scenario["name"], "seed": self.seed,
                               "ground_truth_sha256": manifest["files"]["ground_truth"]["sha256"]}
        """What tracks made on this dataset record of it (:func:`~simrig.dataset.tracks_file.write_tracks`):
        scenario name, seed and the SHA-256 of its ground-truth table. Tracks are scored only on a dataset with
        the same ground truth."""
        self.tables = TableStore(path, manifest, ManifestFiles(path, manifest))

    @classmethod
    def open(cls, path: Path | str, *, verify: bool = False) -> Dataset:
        """Open ``path``; a :class:`DatasetError` if it holds no complete manifest (e.g. an interrupted
        generation). ``verify`` also checks every file's SHA-256 against the manifest."""
        path = Path(path)
        if path.exists() and not path.is_dir():
            raise DatasetError(f"{str(path)!r} is a file, not a dataset folder (a dataset is the folder holding "
                               f"{MANIFEST_NAME})")
        if not path.is_dir():
            raise DatasetError(f"dataset folder {str(path)!r} does not exist")
        manifest = read_manifest(path)
        if manifest is None:
            inner = path / "dataset"
            hint = (f"; it looks like a 'simrig run' folder: its dataset is {str(inner)!r}"
                    if (inner / MANIFEST_NAME).is_file() else "")
            raise DatasetError(
                f"{str(path)!r} holds no complete simrig dataset ({MANIFEST_NAME} missing or not complete; "
                f"an interrupted generation leaves none){hint}"
            )
        dataset = cls(path, manifest)
        if verify:
            dataset.verify()
        return dataset

    def verify(self) -> list[str]:
        """Check that every file listed in the manifest exists and has the recorded SHA-256 (the manifest's own
        hash is checked on :meth:`open`); returns the files in the folder that the manifest does not list
        (e.g. a mosaic written by ``simrig render``), sorted, relative to the folder."""
        return self.files.verify()

    @property
    def files(self) -> ManifestFiles:
        """The folder's files as the manifest lists them, each checked against its SHA-256 before use."""
        return self.tables.files

    @property
    def has_2d(self) -> bool:
        """Whether the dataset has cameras to score 2D boxes in (an import of 3D boxes without cameras has not)."""
        return len(self.rig.cameras) > 0

    def source_ignored_table(self) -> pa.Table | None:
        """The boxes an imported dataset's source marks as not scored (``frame, actor_id, camera, reason``), or
        ``None`` when the manifest lists no such table."""
        if "source_ignored" not in self.manifest["files"]:
            return None
        return pq.read_table(pa.BufferReader(self.files.read("source_ignored")))

    @cached_property
    def rig(self) -> Rig:
        return rig_from_dict(json.loads(self.files.read("rig")))

    def road_markings(self) -> RoadMarkings | None:
        """The painted lines of the dataset's road (world frame), or None if it recorded none."""
        if "road" not in self.manifest["files"]:
            return None
        return RoadMarkings.from_dict(json.loads(self.files.read("road")))

    def table(self, name: str) -> pa.Table:
        """One of the Parquet tables, whole, kept for the next call (:meth:`TableStore.table`)."""
        return self.tables.table(name)

    def columns(self, name: str, columns: list[str] | None = None) -> pa.Table:
        """The ``columns`` (default: all) of table ``name``, read now and not kept (:meth:`TableStore.columns`)."""
        return self.tables.columns(name, columns)

    def batches(self, name: str, columns: list[str] | None = None) -> Iterator[pa.Table]:
        """Table ``name`` a row group at a time (:meth:`TableStore.batches`)."""
        return self.tables.batches(name, columns)

    def has_table(self, name: str) -> bool:
        """Whether the dataset holds table ``name`` (:meth:`TableStore.has`)."""
        return self.tables.has(name)

    def num_rows(self, name: str) -> int:
        """Rows of table ``name`` (from the Parquet footer; nothing else read)."""
        return self.tables.num_rows(name)

    @cached_property
    def ground_truth(self) -> GroundTruth:
        """The whole ground truth as flat arrays (:class:`~simrig.dataset.ground_truth.GroundTruth`), read once
        per :class:`Dataset` object by the one ground-truth reader."""
        from .ground_truth import load_ground_truth

        return load_ground_truth(self)

    @property
    def image_folder(self) -> Path | None:
        """The dataset's ``images/`` folder (one PNG per camera and frame), or ``None`` without images."""
        folder = self.path / "images"
        return folder if folder.is_dir() else None

    def ground_truth_frames(self) -> Iterator[GroundTruthFrame]:
        """Every frame's :class:`GroundTruthFrame`, in order (:func:`.ground_truth.ground_truth_frames`)."""
        return ground_truth_frames(self)

    def sensor_frames(self) -> Iterator[SensorFrame]:
        """What a tracker sees, frame by frame (:func:`simrig.dataset.delivery.sensor_frames`): a
        :class:`SensorFrame` per frame that was not dropped, its detections as arrays. No ground truth is in it."""
        return sensor_frames(self)

    def summary_counts(self) -> dict[str, int | float]:
        """What :meth:`summary` reports, as numbers (:func:`simrig.dataset.summary.summary_counts`)."""
        return summary_counts(self)

    def summary(self) -> str:
        """A few readable lines: scenario, seed, frames, actors, rig, rows, events, capture timing."""
        return summary(self)
