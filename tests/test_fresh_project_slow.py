"""A user's project that has its own ``tracker/``, ``tracker.py`` and ``scenarios.py``, with simrig installed as
a wheel in a fresh virtual environment: simrig's pytest plugin and strategies work there, and the user's
``import tracker`` / ``import scenarios`` get the user's modules (simrig installs ``simrig.*`` only)."""

from __future__ import annotations

import os
import subprocess
import textwrap
from pathlib import Path

import pytest

USER_FILES = {
    "tracker.py": 'WHO = "the user\'s tracker.py"\n',
    "tracker/__init__.py": 'WHO = "the user\'s tracker package"\n',
    "scenarios.py": 'WHO = "the user\'s scenarios.py"\n',
    "test_user.py": '''
        import scenarios
        import tracker
        from hypothesis import given, settings

        import simrig
        from simrig.testing import run_tracker
        from simrig.testing.strategies import scenarios as drawn_scenarios


        def test_the_users_modules_are_the_users():
            assert tracker.WHO == "the user's tracker package"
            assert scenarios.WHO == "the user's scenarios.py"
            import simrig.scenarios
            import simrig.trackers

            assert "site-packages" in simrig.trackers.__file__ and "saga" in simrig.trackers.available()
            assert "highway_surround6" in simrig.scenarios.catalog()


        @settings(max_examples=3, deadline=None, derandomize=True)
        @given(drawn_scenarios(max_frames=6, max_vehicles=3))
        def test_saga_scores_every_drawn_scenario(scenario):
            report = run_tracker("saga", scenario)
            assert report.metrics2d["overall"]["CLR_FP"] >= 0


        def test_the_plugin_fixture(simrig_dataset):
            assert simrig_dataset.frame_count == 12
            run = simrig.track(simrig_dataset, "sort")
            assert simrig.score(simrig_dataset, run).metrics2d is not None
    ''',
}


@pytest.mark.slow
def test_a_user_project_with_its_own_tracker_and_scenarios_modules(tmp_path: Path, venv_with_release) -> None:
    python = venv_with_release
    project = tmp_path / "project"
    for name, text in USER_FILES.items():
        (project / name).parent.mkdir(parents=True, exist_ok=True)
        (project / name).write_text(textwrap.dedent(text))
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "VIRTUAL_ENV")}
    run = subprocess.run([python, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_user.py"], cwd=project,
                         env=env, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0 and "3 passed" in run.stdout, (run.stdout + run.stderr)[-3000:]
    user = subprocess.run([python, "-c", "import tracker, scenarios; print(tracker.WHO); print(scenarios.WHO)"],
                          cwd=project, env=env, capture_output=True, text=True, check=True)
    assert user.stdout.splitlines() == ["the user's tracker package", "the user's scenarios.py"]
    installed = subprocess.run([python, "-c", "import importlib.util as u; print(u.find_spec('tracker'), "
                                "u.find_spec('scenarios'))"], cwd=tmp_path, env=env, capture_output=True,
                               text=True, check=True)
    assert installed.stdout.strip() == "None None"  # outside the project, simrig installed neither name
