"""One setting of a scenario changed by its dotted path — how a bench sweep varies a scenario.

A path names nested keys with dots and list items by index: ``rig.overlap_deg``,
``sensor.detection.probability``, ``perturbations.0.frames.1``. The changed scenario is validated again, so a
value out of range, or a key that does not apply to the scenario's preset, is a :class:`ScenarioError`.

>>> from simrig.scenarios import load_scenario
>>> with_setting(load_scenario("highway_surround6"), "rig.overlap_deg", 20.0).rig.overlap_deg
20.0
>>> get_setting(load_scenario("highway_surround6"), "traffic.vehicles")
40
"""

from __future__ import annotations

import copy
from typing import Any

from pydantic import BaseModel, ValidationError

from . import ScenarioError, describe_errors
from .schema import Scenario


def _steps(path: str) -> list[str | int]:
    if not path or any(not part for part in path.split(".")):
        raise ScenarioError(f"setting path {path!r}: must be keys joined by dots, e.g. 'rig.overlap_deg'")
    return [int(part) if part.isdigit() else part for part in path.split(".")]


def get_setting(scenario: Scenario, path: str) -> Any:
    """The value at ``path`` in ``scenario`` (defaults included); a :class:`ScenarioError` naming the path
    and the first key that does not exist."""
    value: Any = scenario
    for step in _steps(path):
        if isinstance(step, int):
            if not isinstance(value, (list, tuple)) or step >= len(value):
                raise ScenarioError(f"setting {path!r}: {scenario.name} has no item {step} there")
            value = value[step]
        elif isinstance(value, BaseModel) and step in type(value).model_fields:
            value = getattr(value, step)
        elif isinstance(value, dict) and step in value:
            value = value[step]
        else:
            raise ScenarioError(f"setting {path!r}: {scenario.name} has no key {step!r} there")
    return value.model_dump(mode="json") if isinstance(value, BaseModel) else value


def with_setting(scenario: Scenario, path: str, value: Any) -> Scenario:
    """``scenario`` with the key at ``path`` set to ``value``, validated again; its name is kept. ``sensor.preset``
    replaces the whole sensor table with that preset's (set single ``sensor.*`` keys after it)."""
    get_setting(scenario, path)  # the path must exist (with defaults) before it is set
    raw = scenario.model_dump(mode="json", exclude_unset=True)
    raw["name"] = scenario.name
    steps = _steps(path)
    if steps == ["sensor", "preset"]:
        # another detector: the whole sensor table becomes that preset's (keys set after this one override it);
        # merged into the resolved table, the old preset's values would stay on top of the new one's
        raw["sensor"] = {"preset": copy.deepcopy(value)}
        try:
            return Scenario.model_validate(raw)
        except ValidationError as error:
            raise ScenarioError(f"scenario {scenario.name!r} with {path} = {value!r}: {describe_errors(error)}") \
                from None
    node: Any = raw
    for step in steps[:-1]:
        if isinstance(step, int):
            node = node[step]
        else:
            node = node.setdefault(step, {})
            if not isinstance(node, (dict, list)):
                raise ScenarioError(f"setting {path!r}: {step!r} is not a table in {scenario.name}")
    node[steps[-1]] = copy.deepcopy(value)
    try:
        return Scenario.model_validate(raw)
    except ValidationError as error:
        raise ScenarioError(f"scenario {scenario.name!r} with {path} = {value!r}: {describe_errors(error)}") from None
