"""Trackers by name. The reference trackers and a user's tracker register the same way.

A user's package can register through the ``simrig.trackers`` entry-point group (``name = "module:factory"``)
or by calling :func:`register` directly. An unknown name is an error that lists the known ones.

>>> class Still:
...     def reset(self, *, rig, seed=None): pass
...     def step(self, frame): return []
>>> register("doc-still", Still)
>>> type(create("doc-still")).__name__
'Still'
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from importlib import metadata

from .protocol import Tracker

ENTRY_POINT_GROUP = "simrig.trackers"
_FACTORIES: dict[str, Callable[..., Tracker]] = {}
_LAZY: dict[str, str] = {}
"""name → ``module:attribute`` of a factory imported when the tracker is first asked for (simrig's own trackers,
entry points): a command imports only the trackers it runs."""
_REGISTERED_HERE: dict[str, str] = {}
"""name → ``module:qualname`` of a factory a user registered with :func:`register` in this process."""


def register(name: str, factory: Callable[..., Tracker], *, replace: bool = False) -> None:
    """Make ``factory(**params)`` available as tracker ``name``; registering a name another factory holds (one of
    simrig's own, another registration, or an installed package's entry point) is an error unless ``replace``;
    registering the same factory again is not."""
    if not name or not isinstance(name, str):
        raise ValueError(f"tracker name must be a non-empty string, got {name!r}")
    _load_entry_points()  # an installed package's tracker of that name is taken too, not silently shadowed
    reference = f"{getattr(factory, '__module__', None) or ''}:{getattr(factory, '__qualname__', '')}"
    if name in _LAZY and not replace and _LAZY[name] != reference:  # the same factory again is no conflict
        raise ValueError(f"tracker {name!r} is already registered")
    if name in _FACTORIES and not replace and _FACTORIES[name] is not factory:
        raise ValueError(f"tracker {name!r} is already registered")
    _LAZY.pop(name, None)
    _FACTORIES[name] = factory
    if not reference.startswith(__name__.rpartition(".")[0] + "."):  # a user's tracker, not one of simrig's
        _REGISTERED_HERE[name] = reference


def register_lazily(name: str, reference: str) -> None:
    """Make the factory at ``reference`` (``module:attribute``) tracker ``name``, imported when first asked for."""
    if name in _FACTORIES or name in _LAZY:
        raise ValueError(f"tracker {name!r} is already registered")
    _LAZY[name] = reference


def _factory(name: str) -> Callable[..., Tracker] | None:
    """The factory of ``name``, imported now if it was registered lazily; None when unknown."""
    if name not in _FACTORIES and name in _LAZY:
        _FACTORIES[name] = imported(_LAZY.pop(name))
    return _FACTORIES.get(name)


def registered_here(name: str) -> str | None:
    """``module:qualname`` of the factory registered as ``name`` by :func:`register` in this process from a
    user's module (not simrig's own, not an entry point), or ``None``. Other processes (a bench's workers) do
    not see such a registration: they import this reference instead (:func:`register_again`)."""
    return _REGISTERED_HERE.get(name)


def register_again(name: str, reference: str) -> None:
    """In another process, register ``name`` as the factory at ``reference`` (``module:qualname``, from
    :func:`registered_here`), unless the name is already known there."""
    _load_entry_points()
    if name not in _FACTORIES and name not in _LAZY:
        _FACTORIES[name] = imported(reference)


def imported(reference: str):
    """The object ``"package.module:Attribute.path"`` names, its module imported (``ImportError``,
    ``AttributeError`` or ``ValueError`` when it cannot be)."""
    import importlib

    module, _, attribute = reference.partition(":")
    target = importlib.import_module(module)
    for part in attribute.split("."):
        target = getattr(target, part)
    return target


def _load_entry_points() -> None:
    """Know every entry point's tracker by name (imported when first asked for)."""
    for entry in metadata.entry_points(group=ENTRY_POINT_GROUP):
        if entry.name not in _FACTORIES and entry.name not in _LAZY:
            _LAZY[entry.name] = entry.value


def available() -> list[str]:
    """Names of every registered tracker, sorted (nothing is imported)."""
    _load_entry_points()
    return sorted(set(_FACTORIES) | set(_LAZY))


def create(name: str, **params) -> Tracker:
    """A new tracker ``name`` built with ``params``; ``KeyError`` naming the known trackers if unknown."""
    _load_entry_points()
    factory = _factory(name)
    if factory is None:
        known = ", ".join(available()) or "none registered"
        raise KeyError(f"unknown tracker {name!r}; known: {known} (a tracker of your own is known by name to every "
                       f"simrig command once registered by entry point, group {ENTRY_POINT_GROUP!r} in your "
                       "package's pyproject.toml; or name it as module:attribute)") from None
    _check_params(name, factory, params)
    tracker = factory(**params)
    if not isinstance(tracker, Tracker):
        raise TypeError(f"tracker {name!r}: factory returned {type(tracker).__name__}, which has no reset/step")
    return tracker


def parameters(name: str) -> dict[str, object]:
    """The keyword parameters tracker ``name`` takes, with their defaults (``inspect.Parameter.empty`` when
    required)."""
    _load_entry_points()
    factory = _factory(name)
    if factory is None:
        create(name)  # raises the KeyError naming the known trackers
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):
        return {}
    return {
        p.name: p.default
        for p in signature.parameters.values()
        if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)
    }


def _check_params(name: str, factory: Callable[..., Tracker], params: dict) -> None:
    """An unknown parameter is an error naming the tracker and its parameters (not a TypeError from inside
    the factory)."""
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):
        return
    if not any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values()):
        known = parameters(name)
        unknown = sorted(set(params) - set(known))
        if unknown:
            listed = ", ".join(known) or "none"
            raise ValueError(f"tracker {name!r} has no parameter {unknown[0]!r}; parameters: {listed}")
    check_param_types(name, signature, params)


def check_param_types(name: str, signature: inspect.Signature, params: dict) -> None:
    """A parameter whose default is a number, a flag or a string must be given one of the same kind (an int
    where the default is a float is fine; a flag is not a number): a ``ValueError`` naming the tracker, the
    parameter, the value and what it takes, before the factory sees it."""
    kinds = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}
    for key, value in params.items():
        parameter = signature.parameters.get(key)
        default = None if parameter is None else parameter.default
        expected = type(default)
        if expected not in kinds:
            continue  # no default, None, or a richer type: the factory judges it
        fits = (isinstance(value, expected) and not (expected is not bool and isinstance(value, bool))) or (
            expected is float and isinstance(value, int) and not isinstance(value, bool))
        if not fits:
            raise ValueError(f"tracker {name!r}: parameter {key}={value!r} must be {kinds[expected]} (its "
                             f"default is {default!r})")
