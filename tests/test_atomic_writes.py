"""Every writer goes through one atomic helper (:func:`simrig.dataset.outputs.atomic_file`): killed at any
moment, the target holds either the old file or the new one, never part of one, and no write follows a link."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pyarrow as pa  # noqa: E402
import pytest  # noqa: E402

from simrig.dataset import outputs  # noqa: E402
from simrig.dataset.manifest import write_json_atomic  # noqa: E402
from simrig.dataset.outputs import (  # noqa: E402
    save_figure,
    write_bytes_atomic,
    write_table_atomic,  # noqa: E402
    write_text_atomic,
)
from simrig.scoring.attribution import ERRORS_SCHEMA  # noqa: E402
from simrig.scoring.results import ScoreReport  # noqa: E402


def _report() -> ScoreReport:
    return ScoreReport(dataset="d", tracks="t", scenario="s", seed=0, metrics3d=None, metrics2d=None,
                       errors=ERRORS_SCHEMA.empty_table(), settings={})


def _figure():
    figure, axis = plt.subplots()
    axis.plot([0, 1], [0, 1])
    return figure


WRITERS = {
    "write_text_atomic": lambda path: write_text_atomic(path, "new"),
    "write_bytes_atomic": lambda path: write_bytes_atomic(path, b"new"),
    "write_json_atomic": lambda path: write_json_atomic(path, {"new": True}),
    "write_table_atomic": lambda path: write_table_atomic(pa.table({"a": [1, 2]}), path),
    "save_figure": lambda path: save_figure(_figure(), path),
    "ScoreReport.write_errors": lambda path: _report().write_errors(path),
    "ScoreReport.write_json": lambda path: _report().write_json(path),
}


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_a_writer_stopped_before_its_rename_leaves_the_old_file_and_no_partial(writer, tmp_path, monkeypatch):
    target = tmp_path / "out.png"
    target.write_bytes(b"old")

    def dies(*args, **kwargs):
        raise KeyboardInterrupt  # the moment just before the rename

    monkeypatch.setattr(outputs.os, "replace", dies)
    with pytest.raises(KeyboardInterrupt):
        WRITERS[writer](target)
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.png"]


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_a_writer_replaces_a_planted_link_and_never_writes_through_it(writer, tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("mine")
    target = tmp_path / "out.png"
    target.symlink_to(victim)
    WRITERS[writer](target)
    assert victim.read_text() == "mine" and not target.is_symlink() and target.stat().st_size > 0


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_killed_mid_write_the_target_is_old_or_new_never_partial(tmp_path):
    """A process writing a 64 MiB file through atomic_file, killed with SIGKILL at several moments."""
    target = tmp_path / "big.bin"
    script = textwrap.dedent(f"""
        import sys
        from pathlib import Path
        from simrig.dataset.outputs import atomic_file
        with atomic_file(Path({str(target)!r})) as temporary, open(temporary, "wb") as handle:
            for _ in range(64):
                handle.write(b"n" * 2**20)
                handle.flush()
        print("done", flush=True)
    """)
    seen = set()
    for delay in (0.0, 0.2, 0.5, 1.0, 3.0):
        target.write_bytes(b"old")
        process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
        time.sleep(delay)
        os.kill(process.pid, signal.SIGKILL)
        process.wait()
        data = target.read_bytes()
        assert data == b"old" or data == b"n" * 2**26, (delay, len(data))
        seen.add("old" if data == b"old" else "new")
    assert "old" in seen  # killed before the rename at least once: the test did test something
    print(json.dumps(sorted(seen)))


def test_a_partial_folder_of_a_killed_process_not_yet_reaped_is_stale(tmp_path):
    """A killed worker whose parent was killed too stays a zombie until an init reaps it, which in a container may
    be never; ``kill(pid, 0)`` still finds it, so its partial folder was kept as if it were being written."""
    import signal
    import subprocess
    import time

    from simrig.dataset.outputs import make_partial, remove_stale_partials

    child = subprocess.Popen(["sleep", "60"])
    try:
        out = tmp_path / "dataset"
        partial = tmp_path / f".dataset.partial-{child.pid}"
        make_partial(partial)
        remove_stale_partials(out)
        assert partial.is_dir()  # its process runs: left alone
        child.send_signal(signal.SIGKILL)
        time.sleep(0.2)  # dead, not reaped: a zombie
        remove_stale_partials(out)
        assert not partial.exists()
    finally:
        child.kill()
        child.wait()
