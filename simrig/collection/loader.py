"""A finished collection's decisions for training (:mod:`simrig.collection.pairs`), per frame or per window, as
numpy arrays; a PyTorch ``Dataset`` when torch is installed.

>>> # pairs = CollectionPairs("mix"); X, y, sequence = pairs.track_pairs()   # every (track, detection) pair
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from simrig.trackers.association_features import DETECTION_PAIR_FEATURES, TRACK_FEATURES

from ..dataset import Dataset
from ..errors import DatasetError
from ..reading import read_capped
from .pairs import PREFILTER_M, FramePairs, sequence_pairs
from .run import COLLECTION_FILE, INDEX_FILE

DETECTION_FIELDS = ("boxes3d", "labels", "scores", "cameras", "embeddings", "actor_ids")
TRACK_PAIR_FIELDS = ("track_features", "track_same", "track_ids", "track_detections")
CAMERA_PAIR_FIELDS = ("camera_features", "camera_same", "camera_first", "camera_second")


class CollectionPairs:
    """The pairs of a finished collection's sequences (all, or those numbered in ``sequences``)."""

    def __init__(self, folder: str | Path, *, sequences: Iterable[int] | None = None,
                 prefilter_m: float = PREFILTER_M):
        self.folder = Path(folder)
        if self.folder.is_file():
            within = (f"; the collection is its folder, {self.folder.parent}"
                      if (self.folder.parent / COLLECTION_FILE).is_file() else "")
            raise DatasetError(f"{str(self.folder)!r} is a file, not a collection folder{within}")
        description = self.folder / COLLECTION_FILE
        try:
            complete = json.loads(read_capped(description, "collection file", DatasetError)).get("complete")
        except (FileNotFoundError, NotADirectoryError):
            raise DatasetError(f"{str(self.folder)!r}: not a collection (no {COLLECTION_FILE})") from None
        except (ValueError, AttributeError) as error:
            raise DatasetError(f"{description}: not a collection file ({error})") from None
        if complete is not True or not (self.folder / INDEX_FILE).is_file():
            raise DatasetError(f"{str(self.folder)!r}: the collection is not finished; run its simrig generate "
                               "--space command again to finish it")
        index = pq.read_table(self.folder / INDEX_FILE, columns=["sequence", "folder"]).to_pydict()
        folders = dict(zip(index["sequence"], index["folder"], strict=True))
        chosen = sorted(folders) if sequences is None else list(sequences)
        unknown = [number for number in chosen if number not in folders]
        if unknown:
            raise DatasetError(f"{str(self.folder)!r}: no sequence {unknown[0]} (it holds 0 … {len(folders) - 1})")
        self.sequences = chosen
        self._folders = {number: folders[number] for number in chosen}
        self.prefilter_m = prefilter_m

    def __len__(self) -> int:
        return len(self.sequences)

    def frames(self) -> Iterator[FramePairs]:
        """Every stepped frame of every chosen sequence, in sequence order."""
        for number in self.sequences:
            dataset = Dataset.open(self.folder / self._folders[number])
            yield from sequence_pairs(dataset, sequence=number, prefilter_m=self.prefilter_m)

    def windows(self, length: int) -> Iterator[dict[str, np.ndarray]]:
        """Runs of ``length`` consecutive stepped frames of one sequence (the last run of a sequence may be
        shorter), each one dict of arrays (:func:`concatenated`)."""
        if length < 1:
            raise ValueError(f"length: at least 1 frame, got {length}")
        run: list[FramePairs] = []
        for frame in self.frames():
            if run and (frame.sequence != run[0].sequence or len(run) == length):
                yield concatenated(run)
                run = []
            run.append(frame)
        if run:
            yield concatenated(run)

    def track_pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(features (P, F), same object (P,), sequence (P,)) of every (track, detection) pair."""
        return _stacked(self.frames(), "track_features", "track_same", len(TRACK_FEATURES))

    def camera_pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(features (Q, G), same object (Q,), sequence (Q,)) of every cross-camera pair of detections."""
        return _stacked(self.frames(), "camera_features", "camera_same", len(DETECTION_PAIR_FEATURES))


def _stacked(frames: Iterable[FramePairs], features: str, same: str, width: int):
    parts = [(getattr(f, features), getattr(f, same), np.full(len(getattr(f, same)), f.sequence)) for f in frames]
    if not parts:
        return np.zeros((0, width)), np.zeros(0, bool), np.zeros(0, np.int64)
    return tuple(np.concatenate(column) for column in zip(*parts, strict=True))


def concatenated(frames: list[FramePairs]) -> dict[str, np.ndarray]:
    """Consecutive frames of one sequence as one dict of arrays: the detection fields with ``frame`` (M,) per
    detection, and the pair fields with their detection rows offset into the window's detections."""
    offsets = np.cumsum([0] + [len(f.scores) for f in frames[:-1]])
    window = {"sequence": np.array(frames[0].sequence),
              "frame": np.concatenate([np.full(len(f.scores), f.frame) for f in frames])}
    for name in DETECTION_FIELDS + TRACK_PAIR_FIELDS + CAMERA_PAIR_FIELDS:
        shift = name in ("track_detections", "camera_first", "camera_second")
        window[name] = np.concatenate([getattr(f, name) + (offset if shift else 0)
                                       for f, offset in zip(frames, offsets, strict=True)])
    window["pair_frame"] = np.concatenate([np.full(len(f.track_same), f.frame) for f in frames])
    return window


def torch_dataset(pairs: CollectionPairs, *, window: int = 1):
    """A ``torch.utils.data.Dataset`` of ``pairs``' windows of ``window`` frames, each a dict of tensors
    (:func:`concatenated`), read once into memory. Needs torch (the ``torch`` extra, or any torch you have)."""
    try:
        import torch
        from torch.utils.data import Dataset as TorchDataset
    except ImportError:
        raise ImportError("torch_dataset needs PyTorch: pip install 'simrig-mot[torch]'") from None

    items = [{name: torch.as_tensor(value) for name, value in part.items()} for part in pairs.windows(window)]

    class CollectionWindows(TorchDataset):
        """Windows of a simrig collection, each a dict of tensors."""

        def __len__(self) -> int:
            return len(items)

        def __getitem__(self, index: int) -> dict:
            return items[index]

    return CollectionWindows()
