"""Interfaces between two half spaces, one type per file (protocol: base.py).
``interface`` builds the one a pair of materials needs."""
from __future__ import annotations

from .base import Interface
from .bimaterial import Bimaterial
from .identical import Identical


def interface(materials, grid, dt, components, **options) -> Interface:
    """The interface between ``materials`` = (top, bottom), or one Material for both
    (options: cracklab.solver.halfspace.HalfSpace's)."""
    top, bottom = materials if isinstance(materials, (tuple, list)) else (materials, materials)
    if top != bottom:
        return Bimaterial(top, bottom, grid, dt, components, **options)
    return Identical(top, grid, dt, components, **options)


def for_scene(scene, transforms=None, nsteps=None) -> Interface:
    """The interface a run of ``scene`` uses (its materials, scheme, engine, window and
    length; ``nsteps``: the length the kernels' fits must cover instead, if longer)."""
    return interface(scene.materials, scene.grid, scene.dt, scene.components, formulation=scene.formulation,
                     engine=scene.numerics.engine, window=scene.numerics.window, transforms=transforms,
                     nsteps=max(scene.nsteps, nsteps or 0), threads=scene.numerics.history_threads)


__all__ = ["Bimaterial", "Identical", "Interface", "for_scene", "interface"]
