"""A finished bench folder, read for reporting: its results and causes as data frames and its description."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from ..benchmark.api import BENCH_FILE
from ..benchmark.results import CAMERAS, CAUSES, RESULTS
from ..benchmark.suite import TrackerEntry
from ..errors import SimrigError
from ..reading import check_regular, open_regular


class ReportError(SimrigError):
    """A bench folder cannot be reported on; the message names the folder and what is missing."""


@dataclass(frozen=True)
class BenchResults:
    """``results``: one row per point × tracker; ``causes``: errors by cause; ``description``: bench.json;
    ``cameras``: 2D metrics per point × tracker × camera (empty for a bench folder written before it existed)."""

    folder: Path
    results: pd.DataFrame
    causes: pd.DataFrame
    description: dict
    cameras: pd.DataFrame | None = None

    @property
    def suite(self) -> str:
        return self.description["suite"]

    @property
    def trackers(self) -> list[dict]:
        """The suite's tracker entries in suite order, each with its ``name`` (label) added."""
        return [entry | {"name": TrackerEntry.model_validate(entry).name}
                for entry in self.description["suite_settings"]["trackers"]]

    def unique_cells(self, frame: pd.DataFrame) -> pd.DataFrame:
        """``frame`` with one row per (cell, tracker): a cell shared by two points counts once."""
        return frame.drop_duplicates(["cell", "tracker"] + (["dimension", "cause", "kind"]
                                                            if "cause" in frame.columns else []))


REQUIRED_COLUMNS = ("scenario", "tracker", "cell", "seed", "sweep", "value", "scored")
"""Columns of ``results.parquet`` the report reads for every tracker (the metrics vary with the suite)."""


def load_bench(path: Path | str) -> BenchResults:
    """The bench folder ``path`` (or the folder of ``path`` = its results.parquet), which must be complete."""
    folder = Path(path)
    if folder.is_file():
        folder = folder.parent
    description_path = folder / BENCH_FILE
    try:
        with open_regular(description_path, BENCH_FILE, ReportError) as handle:
            description = json.loads(handle.read())
    except FileNotFoundError:
        raise ReportError(f"{str(folder)!r} is not a bench folder: it has no {BENCH_FILE}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise ReportError(f"{str(description_path)!r} is not valid JSON ({error})") from None
    if not isinstance(description, dict):
        raise ReportError(f"{str(description_path)!r} is not a bench description (a JSON object)")
    if not description.get("complete") or not (folder / RESULTS).is_file():
        raise ReportError(f"bench in {str(folder)!r} did not finish; run '{description.get('command')}' again "
                          "to complete it")
    tables = {}
    for name in (RESULTS, CAUSES, CAMERAS):
        if name == CAMERAS and not (folder / name).is_file():
            continue
        try:
            check_regular(folder / name, name, ReportError)
            tables[name] = pq.read_table(folder / name).to_pandas()
        except (pa.ArrowInvalid, OSError) as error:
            raise ReportError(f"{str(folder / name)!r}: not a readable Parquet table ({error})") from None
    missing = [column for column in REQUIRED_COLUMNS if column not in tables[RESULTS].columns]
    if missing or not len(tables[RESULTS]):
        raise ReportError(f"{str(folder / RESULTS)!r}: not a bench's results table ("
                          + (f"no column {', '.join(missing)})" if missing else "no row)"))
    return BenchResults(folder, tables[RESULTS], tables[CAUSES], description, tables.get(CAMERAS))
