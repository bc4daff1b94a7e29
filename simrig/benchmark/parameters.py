"""Swept parameters: a scenario setting by its dotted path, or a named alias that reads better on a plot.

An alias maps the value a suite sweeps (and a plot shows) to a scenario setting:
``miss_probability`` m sets ``sensor.detection.probability`` to 1 − m.

>>> from simrig.scenarios import load_scenario
>>> s = load_scenario("highway_surround6")
>>> round(parameter_value(s, "miss_probability"), 6)
0.1
>>> apply_parameter(s, "miss_probability", 0.3).sensor.detection.probability
0.7
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from simrig.scenarios import Scenario
from simrig.scenarios.overrides import get_setting, with_setting


@dataclass(frozen=True)
class Alias:
    """A swept value v stands for the setting ``path`` = ``to_setting(v)``; ``from_setting`` is the inverse."""

    path: str
    to_setting: Callable[[float], float]
    from_setting: Callable[[float], float]
    description: str


ALIASES = {
    "miss_probability": Alias("sensor.detection.probability", lambda v: 1.0 - v, lambda p: 1.0 - p,
                              "1 − the detection probability p_max of a fully visible object in range"),
}
DIGITS = 12
"""Swept values are rounded to this many decimals, so that 1 − (1 − 0.3) is 0.3 again."""


def parameter_value(scenario: Scenario, parameter: str) -> float:
    """The scenario's own value of ``parameter`` (a dotted setting path or an alias), as a number."""
    alias = ALIASES.get(parameter)
    value = get_setting(scenario, alias.path if alias else parameter)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{parameter}: {scenario.name} has {value!r} there, not a number a sweep can vary")
    return round(float(alias.from_setting(value) if alias else value), DIGITS)


def apply_parameter(scenario: Scenario, parameter: str, value: float) -> Scenario:
    """``scenario`` with ``parameter`` set to ``value`` (validated; a :class:`~simrig.scenarios.ScenarioError` if the
    value or the setting does not fit the scenario). An integer setting keeps integer values."""
    alias = ALIASES.get(parameter)
    path = alias.path if alias else parameter
    current = get_setting(scenario, path)
    setting = round(alias.to_setting(value), DIGITS) if alias else value
    if isinstance(current, int) and not isinstance(current, bool) and float(setting).is_integer():
        setting = int(setting)
    return with_setting(scenario, path, setting)
