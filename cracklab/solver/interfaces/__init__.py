"""Interfaces between two half spaces, one type per file (protocol: base.py). Every module
of this package is imported and each type it registers (``base.register``) is in ``TYPES``:
``interface_type`` picks the one a pair of materials needs, ``interface`` builds it, so that
adding a type is one file."""
from __future__ import annotations

import importlib
import pkgutil

from ..schemes import scheme_of
from .base import TYPES, Interface, register  # noqa: F401


def _discover() -> None:
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name != "base":
            module = importlib.import_module(f"{__name__}.{info.name}")
            for obj in vars(module).values():
                if obj in TYPES and obj.__module__ == module.__name__:
                    globals()[obj.__name__] = obj


_discover()


def pair(materials) -> tuple:
    """(top, bottom) of ``materials`` = (top, bottom), or of one Material for both."""
    return tuple(materials) if isinstance(materials, (tuple, list)) else (materials, materials)


def interface_type(materials) -> type:
    """The interface type between ``materials`` = (top, bottom), or one Material for both:
    the registered type that accepts the pair."""
    top, bottom = pair(materials)
    found = [cls for cls in TYPES if cls.accepts(top, bottom)]
    if len(found) != 1:
        raise LookupError(f"{len(found)} interface types accept the materials {top!r}, {bottom!r}: "
                          f"{[cls.__name__ for cls in found]}")
    return found[0]


def interface(materials, grid, dt, components, **options) -> Interface:
    """The interface between ``materials`` = (top, bottom), or one Material for both
    (options: cracklab.solver.halfspace.HalfSpace's)."""
    top, bottom = pair(materials)
    return interface_type((top, bottom)).build(top, bottom, grid, dt, components, **options)


def for_scene(scene, transforms=None, nsteps=None, scheme=None) -> Interface:
    """The interface a run of ``scene`` uses (its materials, scheme, engine, window and
    length; ``nsteps``: the length the kernels' fits must cover instead, if longer;
    ``scheme``: the scene's scheme, when the caller has it already)."""
    return interface(scene.materials, scene.grid, scene.dt, scene.components,
                     formulation=scheme_of(scheme or scene.formulation), engine=scene.numerics.engine,
                     window=scene.numerics.window, transforms=transforms,
                     nsteps=max(scene.nsteps, nsteps or 0), threads=scene.numerics.history_threads)


__all__ = ["Bimaterial", "Identical", "Interface", "TYPES", "for_scene", "interface", "interface_type", "register"]
