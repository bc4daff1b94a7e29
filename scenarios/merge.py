"""Merging a scenario file's tables onto its base's (``extends``, a detector preset): the loader's one rule."""

from __future__ import annotations

from typing import Any


def merge(base: dict[str, Any], override: dict[str, Any]) -> dict[str, Any]:
    """``override`` on top of ``base``: tables merge key by key, everything else is replaced.

    >>> merge({"traffic": {"lanes": 4, "vehicles": 40}, "frames": 200}, {"traffic": {"vehicles": 10}})
    {'traffic': {'lanes': 4, 'vehicles': 10}, 'frames': 200}
    """
    out = dict(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out
