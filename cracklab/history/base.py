"""The history-engine protocol (docs/developer/developer.md, "Layers"): an engine is a class
registered with :func:`register` under its ``name`` (a value of ``Numerics.engine``); every
module of this package is imported (``history.ENGINES``), so that a new engine is one file.

The class says, before any is built:

* ``windowed``: whether it keeps a truncated history (``Numerics.window``);
* ``flat_cost``: whether its cost per step stays flat as the run goes ("auto" picks the
  first such engine that takes the scene's window);
* ``memory(scene, kernel, scheme, material, shared=False)``: (bytes held, extra bytes
  while it is built or grows) of one engine of a half space of ``material`` serving the
  channel of ``kernel`` under ``scheme``, ``shared`` when an engine of the same kernel and
  material was built before it in the run (what it may take from that one: memoised
  tables, the start-up weight E_0 of the bimaterial face's coupling channels)
  (solver/budget.py sums them);
* ``extra_at_build``: whether that extra comes while the engine is built (beside the
  engines built before it) rather than while its history grows (beside every engine).

An instance, built with ``(kernel=, gamma=, nu=, rule=, formulation=, lag=, window=,
chunk=, threads=, nsteps=)``, answers ``push(x, out=None, scale=None)`` with S_n,
``weight(j)``, ``start_weight(n)`` (the product rule's E_0(n)), ``launch()`` and ``wait()``
(work on a thread of its own, if any), ``get_state()`` and ``set_state(state)``.
"""
from __future__ import annotations

#: steps the compiled loop of the exponential engine advances its states at once, and the
#: direct taps every mode keeps at least (exponential.py, blocked.py)
BLOCK = 8

#: {name: engine class}, in the order the classes registered (history.ENGINES sorts them)
REGISTRY: dict = {}


def register(cls):
    """Class decorator: register the engine class ``cls`` under its ``name``."""
    if not cls.name:
        raise ValueError(f"{cls.__name__} has no name")
    if REGISTRY.get(cls.name, cls) is not cls:
        raise ValueError(f"two history engines are named {cls.name!r}: {REGISTRY[cls.name].__name__}, {cls.__name__}")
    REGISTRY[cls.name] = cls
    return cls
