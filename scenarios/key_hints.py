"""Hints for a misspelt key or kind in a scenario, suite, space or replay file: the known name nearest to it.

A validation error names the key that is wrong (``traffic.vehicels: unknown key``); these functions find what the
file's author most likely meant — the keys the table at that place accepts, or the kinds a tagged table accepts —
with :func:`difflib.get_close_matches` (no hint when nothing is close).
"""

from __future__ import annotations

import difflib
import typing

from pydantic import BaseModel

from .base import Strict

CUTOFF = 0.75
"""Similarity (difflib's ratio, 0–1) a known name needs to be offered: 'vehicels' → 'vehicles' is 0.875."""


def nearest(word: str, known: typing.Iterable[str]) -> str:
    """`` (did you mean 'NAME'?)`` for the known name nearest to ``word``, or ``""``.

    >>> nearest("vehicels", ["vehicles", "window_radius_m"])
    " (did you mean 'vehicles'?)"
    >>> nearest("zzz", ["vehicles"])
    ''
    """
    close = difflib.get_close_matches(word, list(known), n=1, cutoff=CUTOFF)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _strict_models() -> dict[str, type[BaseModel]]:
    """Every strict model by class name (a name two models share is left out: it would be ambiguous)."""
    found: dict[str, type[BaseModel] | None] = {}
    pending = list(Strict.__subclasses__())
    while pending:
        model = pending.pop()
        found[model.__name__] = None if model.__name__ in found else model
        pending.extend(model.__subclasses__())
    return {name: model for name, model in found.items() if model is not None}


def _models_in(annotation) -> list[type[BaseModel]]:
    """The models an annotation can hold: itself, or inside Optional/Union/list/tuple/dict/Annotated."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [model for argument in typing.get_args(annotation) for model in _models_in(argument)]


def _keys(model: type[BaseModel]) -> set[str]:
    return {field.alias or name for name, field in model.model_fields.items()}


def known_keys(title: str, place: tuple) -> set[str]:
    """The keys the table at ``place`` (a validation error's location without its last part) accepts, in the
    file whose top-level model is named ``title``; empty when that cannot be told."""
    root = _strict_models().get(title)
    if root is None:
        return set()
    models = [root]
    for part in place:
        if isinstance(part, int):  # an item of a list: the models of the list are already the candidates
            continue
        holding = [model for model in models if part in model.model_fields]
        if not holding:  # a tagged union's tag in the location: the candidates whose tag it is stay
            models = [model for model in models if part in _tags(model)] or models
            continue
        models = [inner for model in holding for inner in _models_in(model.model_fields[part].annotation)]
        if not models:
            return set()
    return set().union(*(_keys(model) for model in models))


def _tags(model: type[BaseModel]) -> set[str]:
    """The literal values of a model's ``kind`` field (its tag in a tagged union), if it has one."""
    field = model.model_fields.get("kind")
    return set(typing.get_args(field.annotation)) if field is not None else set()
