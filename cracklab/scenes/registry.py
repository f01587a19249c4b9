"""The builder registry: cracklab's own scene builders (``BUILDERS``), those registered
with ``register_builder``, and entry points of the group "cracklab.builders"."""
from __future__ import annotations

import functools
import inspect

from ..errors import InputError
from .fronts import asperity_row, random_toughness
from .paper import elliptical_crack, kostrov, lamb, periodic_cracks
from .scec import tpv3, tpv5, tpv6, tpv101, tpv102, tpv103, tpv104
from .seas import bp1, bp5

# The scene builders a study file may name (resolve_builder): exactly these functions of
# cracklab.scenes, by name. No other name of cracklab.scenes (a helper, or ``np``) is
# reachable from a study; further builders are registered explicitly (register_builder,
# or the entry-point group "cracklab.builders").
BUILDERS = ("lamb", "elliptical_crack", "periodic_cracks", "kostrov", "tpv3", "tpv5", "tpv6", "tpv101", "tpv102",
            "tpv103", "tpv104", "bp1", "bp5", "asperity_row", "random_toughness")

ENTRY_POINT_GROUP = "cracklab.builders"
REGISTERED: dict = {}          # name -> function, from register_builder
ENTRY_POINT_CACHE: dict = {}   # (name, entry point value) -> loaded function


def own_builders() -> dict:
    """cracklab's own builders: the functions of cracklab.scenes listed in BUILDERS."""
    return {name: globals()[name] for name in BUILDERS}


def _entry_points() -> dict:
    """{name: entry point} of the group "cracklab.builders" (installed packages)."""
    from importlib.metadata import entry_points

    try:
        eps = entry_points(group=ENTRY_POINT_GROUP)
    except Exception:  # noqa: BLE001 - broken package metadata: no entry-point builders
        return {}
    return {ep.name: ep for ep in eps}


def _same_function(a, b) -> bool:
    """The same function, or the same module-level name (a module reloaded, a notebook cell
    run again)."""
    if a is b:
        return True
    key = (getattr(a, "__module__", None), getattr(a, "__qualname__", None))
    return None not in key and "<" not in key[1] and \
        key == (getattr(b, "__module__", None), getattr(b, "__qualname__", None))


def register_builder(name, func=None, *, replace=False):
    """Let study files and sweeps name the scene builder ``func`` as ``name``.

    ``func(**arguments)`` must return a ``cracklab.Scene``. ``name`` is any non-empty
    string other than the names of cracklab's own builders (``scenes.BUILDERS``), e.g.
    ``"my_crack"`` or ``"mypackage.scenes:my_crack"``. Registering another function
    under a name already taken needs ``replace=True``. Without ``func`` this is a
    decorator: ``@cracklab.register_builder("my_crack")``. Returns ``func``.

    A study file can name only registered builders: cracklab's own, those registered
    here, and those of installed packages under the entry-point group
    ``"cracklab.builders"`` (see docs/guide/ensembles.md); it never imports a module itself.
    The function object goes to the workers with each task (by reference when it is
    importable there, else by value), so the workers need no registration."""
    if func is None:
        return functools.partial(register_builder, name, replace=replace)
    if not isinstance(name, str) or not name.strip():
        raise InputError("builder", f"a builder name must be a non-empty string, got {name!r}")
    if not callable(func):
        raise InputError("builder", f"{name!r}: a builder must be a function returning a Scene, got {func!r}")
    if name in own_builders():
        raise InputError("builder", f"{name!r} is one of cracklab's own builders; register yours under "
                                    f"another name")
    old = REGISTERED.get(name)
    if old is not None and not replace and not _same_function(old, func):
        raise InputError("builder", f"{name!r} is already registered to {_describe(old)}; pass replace=True "
                                    f"to register {_describe(func)} instead")
    REGISTERED[name] = func
    return func


def unregister_builder(name) -> None:
    """Forget a builder registered with ``register_builder`` (no error when there is none)."""
    REGISTERED.pop(name, None)


def registered_builders() -> dict:
    """{name: where it comes from} of every builder a study may name: "cracklab" (its own,
    ``scenes.BUILDERS``), "registered" (``register_builder``), or "entry point
    <package.module:function>" (group "cracklab.builders"; an entry point does not shadow
    the others)."""
    out = {name: "cracklab" for name in own_builders()}
    for name in REGISTERED:
        out.setdefault(name, "registered")
    for name, ep in _entry_points().items():
        out.setdefault(name, f"entry point {ep.value}")
    return out


def _describe(func) -> str:
    module, qual = getattr(func, "__module__", None), getattr(func, "__qualname__", None)
    return f"{module}:{qual}" if module and qual else repr(func)


def builder_name(builder) -> str:
    """The name of a builder: a string as given; for a function, the name it is
    registered under (cracklab's own builders by their name), else "module:qualname",
    under which it is registered now (a function given in Python is trusted)."""
    if isinstance(builder, str):
        return builder
    if callable(builder):
        for name, func in own_builders().items():
            if func is builder:
                return name
        for name, func in REGISTERED.items():
            if func is builder:
                return name
        module, qual = getattr(builder, "__module__", None), getattr(builder, "__qualname__", None)
        if not module or not qual or "<" in qual:
            raise InputError("builder", f"must be a module-level function, got {qual or builder!r}; give another "
                                        f"function a name with cracklab.register_builder(name, function)")
        name = f"{module}:{qual}"
        register_builder(name, builder)
        return name
    raise InputError("builder", f"must be a builder name or function, got {builder!r}")


def resolve_builder(name, field: str = "builder"):
    """The function registered as ``name``: one of cracklab's own builders
    (``scenes.BUILDERS``), one registered with ``register_builder``, or an entry point of
    the group "cracklab.builders". Any other name, "package.module:function" included,
    is an InputError naming ``field`` and the registered builders: a name never imports
    a module nor reaches another attribute of cracklab.scenes."""
    if not isinstance(name, str) or not name:
        raise InputError(field, f"must be the name of a registered scene builder, got {name!r}")
    own = own_builders()
    if name in own:
        return own[name]
    if name in REGISTERED:
        return REGISTERED[name]
    ep = _entry_points().get(name)
    if ep is not None:
        key = (name, ep.value)
        if key not in ENTRY_POINT_CACHE:
            try:
                func = ep.load()
            except Exception as exc:  # noqa: BLE001 - reported as one clear line
                raise InputError(field, f"{name!r}: the entry point {ep.value!r} (group {ENTRY_POINT_GROUP!r}) "
                                        f"cannot be loaded: {type(exc).__name__}: {exc}") from None
            if not callable(func):
                raise InputError(field, f"{name!r}: the entry point {ep.value!r} (group {ENTRY_POINT_GROUP!r}) "
                                        f"is not a function")
            ENTRY_POINT_CACHE[key] = func
        return ENTRY_POINT_CACHE[key]
    names = sorted(registered_builders())
    shown = repr(name) if len(name) <= 80 else repr(name[:77] + "...")
    raise InputError(field, f"{shown} is not a scene builder registered with cracklab; registered: "
                            f"{', '.join(names)}. Register your own in Python with "
                            f"cracklab.register_builder(name, function), or in an installed package "
                            f"under the entry-point group {ENTRY_POINT_GROUP!r}")


def accepts(func):
    """(names of keyword parameters, accepts **kwargs)."""
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):     # no signature to read (some built-in callables)
        return set(), True
    names = {p.name for p in sig.parameters.values()
             if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)}
    return names, any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values())
