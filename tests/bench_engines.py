"""Test helper: a suite run on the local pool and on Ray must write the same tables, byte for byte."""

from pathlib import Path

import pytest


def assert_same_bench_bytes(suite_text: str, tmp_path: Path) -> None:
    """Run the suite ``suite_text`` (TOML) on both engines with 2 workers and compare ``results.parquet`` and
    ``causes.parquet`` byte for byte (skipped without the ``ray`` extra)."""
    from simrig.benchmark import run_bench

    pytest.importorskip("ray")
    suite = tmp_path / "suite.toml"
    suite.write_text(suite_text)
    local = run_bench(suite, out=tmp_path / "local", workers=2)
    ray_run = run_bench(suite, out=tmp_path / "ray", engine="ray", workers=2)
    for name in ("results.parquet", "causes.parquet"):
        assert (local.out / name).read_bytes() == (ray_run.out / name).read_bytes(), name
