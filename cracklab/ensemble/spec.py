"""What a sweep is made of: a ``Builder`` and its base arguments, the ``Sweep``, a
``Study`` (what a STUDY.toml holds), a planned ``Member``, and the ``SweepResult``."""
from __future__ import annotations

from dataclasses import dataclass, field

from ..scenes.registry import builder_name, resolve_builder


class Builder:
    """A scene builder and its base arguments: ``Builder("asperity_row", n1=128, n3=64)``.

    ``builder``: the name of a registered builder (one of cracklab's own, ``scenes.BUILDERS``,
    one registered with ``register_builder``, or an entry point of the group
    "cracklab.builders"), or a function (registered under its name, "module:qualname",
    unless it is registered already)."""

    def __init__(self, builder, **args):
        self.name = builder_name(builder)
        self.args = args
        self.func = resolve_builder(self.name)

    def __repr__(self):
        return f"Builder({self.name!r}, **{self.args!r})"


@dataclass
class Sweep:
    """Members of an ensemble: the Cartesian product of ``product`` ({name: [values]}),
    then the explicit ``members`` (each a {name: value} dict), each ``replicates`` times.

    ``entropy``: root of one ``numpy.random.SeedSequence``; every member whose builder
    accepts ``seed_arg`` and does not set it gets ``seed`` = a 53-bit integer from the
    child ``SeedSequence(entropy, spawn_key=(hash of its builder and swept parameters,
    replicate))``, i.e. independent, reproducible streams that do not depend on member
    order nor on the base parameters (a longer t_end keeps the same random field)."""

    product: dict = field(default_factory=dict)
    members: list = field(default_factory=list)
    entropy: int | None = None
    replicates: int = 1
    seed_arg: str = "seed"
    base: dict = field(default_factory=dict)   # extra base parameters (merged over the Builder's)


@dataclass
class Study:
    """What a STUDY.toml holds: a base (Builder or Scene), a Sweep and a name."""

    base: object
    sweep: Sweep
    name: str = "study"
    spec: dict = field(default_factory=dict)    # the TOML tables, kept in the store's attrs


@dataclass(frozen=True)
class Member:
    index: int
    id: str
    params: dict          # resolved parameters (canonical, JSON-able)
    swept: tuple          # names of the parameters that vary by sweep (coordinates)


@dataclass
class SweepResult:
    store: str
    members: list
    ran: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failed: dict = field(default_factory=dict)      # id -> error line
    elapsed: float = 0.0
    damaged: dict = field(default_factory=dict)     # id -> damage found in a complete member (run again)

    @property
    def ok(self) -> bool:
        return not self.failed

    def summary(self) -> str:
        n = len(self.members)
        lines = [f"{n} member{'s' if n != 1 else ''}: {len(self.ran) - len(self.failed)} ran, "
                 f"{len(self.skipped)} already complete, {len(self.failed)} failed "
                 f"({self.elapsed:.1f} s) -> {self.store}"]
        by_id = {m.id: m for m in self.members}
        for mid, err in self.failed.items():
            m = by_id.get(mid)
            shown = ", ".join(f"{k}={m.params[k]!r}" for k in m.swept) if m else ""
            lines.append(f"  FAILED {mid} ({shown}): {err}")
        for mid, problem in self.damaged.items():
            lines.append(f"  DAMAGED {mid} (was complete; run again): {problem}")
        return "\n".join(lines)
