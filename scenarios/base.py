"""Shared pieces of the scenario schema: the strict base model and constrained number types."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

from simrig.names import name_problem

MAX_SETTING = 1e6
"""The largest magnitude of any real-valued setting, in its own unit (metres, seconds, degrees, m/s, ...): no
scenario means a million of any of them, and a value like 1e200 was accepted and simulated into overflow. Settings
with a natural limit of their own have a tighter one."""
PositiveFloat = Annotated[float, Field(gt=0, le=MAX_SETTING, allow_inf_nan=False)]
NonNegativeFloat = Annotated[float, Field(ge=0, le=MAX_SETTING, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(ge=-MAX_SETTING, le=MAX_SETTING, allow_inf_nan=False)]


def _path_name(name: str) -> str:
    problem = name_problem(name)
    if problem is not None:
        raise ValueError(f"{name!r} {problem} (the name becomes a file or folder name)")
    return name


PathName = Annotated[str, AfterValidator(_path_name)]
"""A name that becomes a file or folder name (scenario, camera, search space): :mod:`simrig.names`'s rule."""


class Strict(BaseModel):
    """Base model: unknown keys are errors, values are immutable once validated."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=False)


def set_keys(model: BaseModel) -> set[str]:
    """The keys the scenario file actually set (not defaults)."""
    return set(model.model_fields_set)
