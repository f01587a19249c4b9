"""STUDY.toml: ``load_study`` reads a study file into a ``Study``, ``run_study`` runs it."""
from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..scenes.registry import resolve_builder
from .identity import canonical
from .planning import SECTIONS
from .running import run
from .spec import Builder, Study, Sweep, SweepResult


def _flatten(table: dict, where: str) -> dict:
    """TOML nests dotted keys (law.tau_c = ...); bring section tables back to paths."""
    out = {}
    for key, value in table.items():
        if key in SECTIONS and isinstance(value, dict):
            for k2, v2 in value.items():
                out[f"{key}.{k2}"] = v2
        else:
            out[key] = value
    return out


STUDY_KEYS = ("name", "builder", "scene", "entropy", "replicates", "seed_arg", "description")


def load_study(path, allow=()) -> Study:
    """Read a STUDY.toml (see docs/guide/ensembles.md); the field files of its base scene
    (``study.scene``) are read from that file's folder and below, or the ``allow``
    folders (cracklab.model.field_files)::

        [study]
        name = "asperity_ensemble"
        builder = "asperity_row"        # a registered builder (ensemble.registered_builders())
        # scene = "base.toml"           # or: a base scene file (then only scene paths)
        entropy = 2024                  # SeedSequence root for builders taking `seed`
        [base]                          # base builder arguments and scene paths
        n1 = 128
        record.every = 16
        [sweep]                         # product axes
        diameter = [0.125, 0.25]
        law.tau_c = [1.0, 2.0]
        [[members]]                     # explicit members (merged over [base])
        builder = "random_toughness"
    """
    from ..model.scene_io import read_toml_file, scene_from_toml_file

    path = Path(path)
    if not path.exists():
        raise InputError(str(path), "no such study file")
    data = read_toml_file(path)
    for key in data:
        if key not in ("study", "base", "sweep", "members"):
            raise InputError(key, "unknown table; accepted: study, base, sweep, members")
    for key in ("study", "base", "sweep"):
        if not isinstance(data.get(key, {}), dict):
            raise InputError(key, f"must be a table [{key}], got {data[key]!r}")
    members = data.get("members", [])
    if not isinstance(members, list) or not all(isinstance(m, dict) for m in members):
        raise InputError("members", "must be an array of tables [[members]]")
    study = data.get("study", {})
    for key in study:
        if key not in STUDY_KEYS:
            raise InputError(f"study.{key}", f"unknown key; accepted: {', '.join(STUDY_KEYS)}")
    if ("builder" in study) == ("scene" in study):
        raise InputError("study.builder", "give exactly one of study.builder and study.scene")
    base = _flatten(data.get("base", {}), "base")
    if "builder" in study:
        if not isinstance(study["builder"], str):
            raise InputError("study.builder", f"must be the name of a registered scene builder, got "
                                              f"{study['builder']!r}")
        resolve_builder(study["builder"], "study.builder")     # before anything else is done
        builder = Builder(study["builder"])
    else:
        if not isinstance(study["scene"], str):
            raise InputError("study.scene", f"must be the path of a scene TOML file, got {study['scene']!r}")
        scene_path = (path.parent / study["scene"])
        if not scene_path.is_file():
            raise InputError("study.scene", f"no such scene file {scene_path}")
        builder = scene_from_toml_file(scene_path, "study.scene", allow=allow)
    for key in ("name", "seed_arg", "description"):
        if key in study and not isinstance(study[key], str):
            raise InputError(f"study.{key}", f"must be a string, got {study[key]!r}")
    sweep = Sweep(product=_flatten(data.get("sweep", {}), "sweep"),
                  members=[_flatten(m, f"members[{i}]") for i, m in enumerate(members)],
                  entropy=study.get("entropy"), replicates=study.get("replicates", 1),
                  seed_arg=study.get("seed_arg", "seed"), base=base)
    spec = {"name": study.get("name", path.stem), "file": path.name, **canonical(data)}
    return Study(builder, sweep, study.get("name", path.stem), spec)


def run_study(study, store, **kwargs) -> SweepResult:
    """``run`` for a ``Study`` or the path of a STUDY.toml."""
    if not isinstance(study, Study):
        study = load_study(study)
    return run(study.base, study.sweep, store, study_spec=study.spec, **kwargs)
