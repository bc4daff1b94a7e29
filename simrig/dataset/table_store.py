"""A dataset's Parquet tables: each opened from the manifest's list, its file checked against the recorded
SHA-256, its columns against the table's schema and its row count against the manifest's; read whole (and kept),
by columns, or a row group at a time."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import DatasetError
from .manifest_files import ManifestFiles
from .tables import ALL_SCHEMAS, OPTIONAL_SCHEMAS


class TableStore:
    """The tables of the dataset at ``path`` with ``manifest``; ``files`` checks each before use."""

    def __init__(self, path: Path, manifest: dict, files: ManifestFiles):
        self.path = path
        self.manifest = manifest
        self.files = files
        self._tables: dict[str, pa.Table] = {}  # read whole so far (:meth:`table`)

    def table(self, name: str) -> pa.Table:
        """One of the Parquet tables (:data:`simrig.dataset.tables.SCHEMAS`: ``ego_poses``, ``ground_truth``,
        ``projections``, ``visibility``, ``detections``, ``sensor_truth``, ``frames``), whole, kept for the
        next call. Long runs: :meth:`columns` and :meth:`batches` read less and keep nothing."""
        if name not in self._tables:
            self._tables[name] = self.columns(name)
        return self._tables[name]

    def columns(self, name: str, columns: list[str] | None = None) -> pa.Table:
        """The ``columns`` (default: all) of table ``name``, read now and not kept (see :meth:`table`)."""
        return self._parquet(name).read(columns=columns)

    def batches(self, name: str, columns: list[str] | None = None) -> Iterator[pa.Table]:
        """Table ``name`` (its ``columns``, default all) in its row groups, in order: a long dataset's frames a
        group at a time (:data:`simrig.dataset.writer.FRAMES_PER_ROW_GROUP` frames each, as written)."""
        file = self._parquet(name)
        for group in range(file.num_row_groups):
            yield file.read_row_group(group, columns=columns)

    def has(self, name: str) -> bool:
        """Whether the dataset holds table ``name`` (the optional ones, ``captures`` and ``ego_estimates``, only
        when its scenario sets capture timing; ``truth_plans``, when simrig generated it since it records plans)."""
        return name in self.manifest.get("files", {})

    def num_rows(self, name: str) -> int:
        """Rows of table ``name`` (from the Parquet footer; nothing else read)."""
        return self._parquet(name).metadata.num_rows

    def _parquet(self, name: str) -> pq.ParquetFile:
        """Table ``name`` opened for reading, its file checked against the manifest's SHA-256 and its columns
        against the table's schema."""
        if name not in ALL_SCHEMAS:
            raise KeyError(f"unknown table {name!r}; tables: {', '.join(ALL_SCHEMAS)}")
        if name in OPTIONAL_SCHEMAS and not self.has(name):
            why = ("its scenario sets no capture timing" if name != "truth_plans"
                   else "it was imported, or generated before simrig recorded plans")
            raise KeyError(f"dataset {str(self.path)!r} has no {name} table ({why})")
        file = self.files.verified(name)
        try:
            parquet = pq.ParquetFile(file)
        except (pa.ArrowInvalid, OSError) as error:
            raise DatasetError(f"dataset {str(self.path)!r}: {name} is not a readable Parquet file ({error})") from None
        if not parquet.schema_arrow.equals(ALL_SCHEMAS[name], check_metadata=False):
            raise DatasetError(f"dataset {str(self.path)!r}: {name} columns {parquet.schema_arrow.names} do not "
                               "match its schema")
        stated = self.manifest["files"][name].get("rows")
        if stated is not None and stated != parquet.metadata.num_rows:  # a re-hashed manifest that lies
            raise DatasetError(f"dataset {str(self.path)!r}: manifest says {name} holds {stated!r} rows, its table "
                               f"holds {parquet.metadata.num_rows}")
        return parquet
