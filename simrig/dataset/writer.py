"""Writing a dataset folder atomically.

Everything is written into a hidden sibling folder ``.<name>.partial-<pid>``; the manifest (with
``complete: true`` as its last key) is written last, and only then is the folder renamed to its final
name. An exception or Ctrl-C removes the partial folder; a hard kill leaves it behind under its hidden
name, where no reader looks, and the next run into the same place removes it.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import DatasetError, DatasetExistsError, SimrigError
from ..reading import read_capped
from .manifest import (
    FORMAT_NAME,
    FORMAT_VERSION,
    IMAGES_FOLDER,
    MANIFEST_NAME,
    file_sha256,
    folder_digest,
    manifest_digest,
    read_manifest,
    write_json_atomic,
    written_by_simrig,
)
from .outputs import PARTIAL_MARKER, check_output_path, make_partial, partial_sibling, publish, remove_stale_partials
from .run_folder import what_folder_holds
from .tables import ALL_SCHEMAS, SCHEMAS

FRAMES_PER_ROW_GROUP = 100
"""Frames buffered in memory before a Parquet row group is written (bounds memory on long runs)."""


def check_output_folder(out: Path, *, overwrite: bool) -> None:
    """Refuse to write into ``out`` if it is no place for output (:func:`check_output_path`), holds a complete
    dataset (without ``overwrite``) or holds anything else: ``overwrite`` replaces only a simrig dataset."""
    check_output_path(out, what="output folder")
    if not out.exists():
        return
    try:
        manifest = read_manifest(out)
    except DatasetError as error:  # ours, but damaged or from an older simrig: replaceable with overwrite
        if not written_by_simrig(out):
            raise
        if overwrite:
            return
        raise DatasetExistsError(f"output folder {str(out)!r} holds a simrig dataset that cannot be read ({error}); "
                                 "pass --overwrite to replace it") from None
    if manifest is not None and not overwrite:
        raise DatasetExistsError(
            f"output folder {str(out)!r} already holds a complete dataset "
            f"({manifest['scenario']['name']}, seed {manifest['seed']}); pass --overwrite to replace it"
        )
    if manifest is None and any(out.iterdir()):
        raise DatasetError(
            f"output folder {str(out)!r} is not empty and holds no simrig dataset{what_folder_holds(out)}; simrig "
            "replaces only a folder it wrote (--overwrite included): choose another folder"
        )


def _dataset_file_names(folder: Path):
    """Whether a relative path in the dataset ``folder`` is one simrig writes: a table, ``rig.json``, the
    manifest, an image, or a file the folder's manifest lists (read even when the manifest is damaged)."""
    names = {f"{name}.parquet" for name in ALL_SCHEMAS} | {"rig.json", MANIFEST_NAME}
    try:
        listed = json.loads(read_capped(folder / MANIFEST_NAME, "manifest")).get("files", {})
        names |= {entry["file"] for entry in listed.values() if isinstance(entry, dict)
                  and isinstance(entry.get("file"), str)}
    except (OSError, ValueError, AttributeError, SimrigError):
        pass

    def ours(relative: Path) -> bool:
        return relative.parts[0] == IMAGES_FOLDER or (len(relative.parts) == 1 and relative.name in names)

    return ours


def _concatenate(chunks: list, arrow_type: pa.DataType) -> pa.Array:
    """One Arrow column from per-frame chunks (numpy arrays, or Arrow arrays for list columns)."""
    if isinstance(chunks[0], pa.Array):
        return pa.concat_arrays([chunk.cast(arrow_type) for chunk in chunks])
    return pa.array(np.concatenate(chunks), type=arrow_type)


def arrow_table(name: str, chunks: list[dict]) -> pa.Table:
    """Table ``name`` (:data:`~simrig.dataset.tables.ALL_SCHEMAS`) of per-frame column chunks, as it is written."""
    schema = ALL_SCHEMAS[name]
    return pa.Table.from_arrays([_concatenate([chunk[field.name] for chunk in chunks], field.type)
                                 for field in schema], schema=schema)


class DatasetWriter:
    """Streams frames into Parquet tables in a partial folder and publishes it on :meth:`commit`.

    Use as a context manager; leaving the block without :meth:`commit` (an exception, Ctrl-C) deletes the
    partial folder.
    """

    def __init__(self, out: Path | str, *, overwrite: bool = False):
        self.out = Path(out)
        self.overwrite = overwrite
        self.partial = partial_sibling(self.out)
        self._writers: dict[str, pq.ParquetWriter] = {}
        self._buffers: dict[str, list[dict]] = {name: [] for name in ALL_SCHEMAS}
        self._rows: dict[str, int] = dict.fromkeys(ALL_SCHEMAS, 0)
        self._buffered_frames = 0
        self._committed = False
        self.kept: list[Path] = []
        """Files a user had added to the dataset this one replaced, moved into it (relative paths)."""

    def __enter__(self) -> DatasetWriter:
        check_output_folder(self.out, overwrite=self.overwrite)
        self.out.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_partials(self.out)
        make_partial(self.partial)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        for writer in self._writers.values():
            writer.close()
        self._writers.clear()
        if not self._committed:
            shutil.rmtree(self.partial, ignore_errors=True)

    # ------------------------------------------------------------------ content
    def write_frame(self, columns: dict[str, dict[str, np.ndarray]]) -> None:
        """Buffer one frame's columns per table (see :func:`simrig.pipeline.frame_columns.frame_columns`)."""
        for name, table_columns in columns.items():
            self._buffers[name].append(table_columns)
        self._buffered_frames += 1
        if self._buffered_frames >= FRAMES_PER_ROW_GROUP:
            self._flush()

    def write_json(self, filename: str, data: dict) -> None:
        """A JSON side file (e.g. ``rig.json``) in the dataset folder."""
        write_json_atomic(self.partial / filename, data)

    def write_image(self, relative: str, image: np.ndarray) -> None:
        """An RGB ``(H, W, 3)`` uint8 image as PNG at ``relative`` (e.g. ``images/CAM_FRONT/000012.png``)."""
        from PIL import Image

        path = self.partial / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(image).save(path, format="PNG")

    def _flush(self) -> None:
        for name, chunks in self._buffers.items():
            schema = ALL_SCHEMAS[name]
            if not chunks:
                continue
            table = arrow_table(name, chunks)
            if name not in self._writers:
                self._writers[name] = pq.ParquetWriter(self.partial / f"{name}.parquet", schema)
            self._writers[name].write_table(table)
            self._rows[name] += table.num_rows
            chunks.clear()
        self._buffered_frames = 0

    # ------------------------------------------------------------------ publishing
    def commit(self, manifest: dict) -> dict:
        """Close the tables, hash every file, write the manifest last and publish the folder.

        ``manifest`` holds the run's description (scenario, seed, frames, versions, events); this adds the
        format, the tables' row counts and SHA-256 hashes, and ``complete: true`` as the last key. Returns
        the manifest written.
        """
        self._flush()
        for name, schema in SCHEMAS.items():
            if name not in self._writers:  # a table with no rows still gets a file with its schema
                self._writers[name] = pq.ParquetWriter(self.partial / f"{name}.parquet", schema)
        for writer in self._writers.values():
            writer.close()
        self._writers.clear()
        files = {}
        for path in sorted(self.partial.iterdir()):
            if path.is_dir() or path.name == PARTIAL_MARKER:
                continue
            entry = {"file": path.name, "sha256": file_sha256(path)}
            if path.stem in self._rows:
                entry["rows"] = self._rows[path.stem]
            files[path.stem] = entry
        full = {"format": FORMAT_NAME, "format_version": FORMAT_VERSION, **manifest, "files": files}
        images = self.partial / IMAGES_FOLDER
        if images.is_dir():
            full["images"] = folder_digest(images)
        full.pop("complete", None)
        full.pop("manifest_sha256", None)
        full["manifest_sha256"] = manifest_digest(full)
        full["complete"] = True
        write_json_atomic(self.partial / MANIFEST_NAME, full)
        self._publish()
        self._committed = True
        return full

    def _publish(self) -> None:
        if self.out.exists():
            check_output_folder(self.out, overwrite=self.overwrite)  # it may have changed since we started
        self.kept = publish(self.partial, self.out, _dataset_file_names(self.out))
