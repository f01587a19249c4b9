"""Planning a sweep (its members, their parameters and ids) and building one member's
scene (the builder called, then the scene paths applied)."""
from __future__ import annotations

import dataclasses
import hashlib
import itertools

import numpy as np

from ..errors import InputError
from ..scenes.registry import accepts, builder_name, resolve_builder
from .identity import canonical, canonical_json, decode, member_id, scene_digest
from .spec import Builder, Member, Sweep

SECTIONS = ("material", "grid", "law", "loading", "record", "numerics", "sequence")
TOP_LEVEL = ("t_end", "beta", "name")
SEED_BITS = 53          # seeds fit exactly in float64, int64 and JSON numbers


def _is_path(key: str) -> bool:
    return "." in key


def _check_path(key: str, where: str):
    section, _, rest = key.partition(".")
    if section not in SECTIONS or not rest or "." in rest:
        raise InputError(f"{where}.{key}", f"a dotted name must be a scene path <section>.<key> with section "
                                           f"one of {', '.join(SECTIONS)}")


def as_sweep(sweep) -> Sweep:
    """A ``Sweep`` from a Sweep, a dict of product axes or a list of member dicts."""
    if isinstance(sweep, Sweep):
        return sweep
    if isinstance(sweep, dict):
        return Sweep(product=dict(sweep))
    if isinstance(sweep, (list, tuple)):
        return Sweep(members=list(sweep))
    raise InputError("sweep", f"must be a Sweep, a dict of axes or a list of members, got {type(sweep).__name__}")


def _base_of(base_scene):
    """(builder name or None, base args, base key, Scene or None)."""
    from ..model.scene import Scene

    if isinstance(base_scene, Scene):
        return None, {}, f"scene:{scene_digest(base_scene)}", base_scene
    if isinstance(base_scene, Builder):
        return base_scene.name, dict(base_scene.args), "builder", None
    if isinstance(base_scene, str) or callable(base_scene):
        b = Builder(base_scene)
        return b.name, {}, "builder", None
    raise InputError("base_scene", f"must be a Scene, a Builder, or a builder name, got {type(base_scene).__name__}")


def _classify(key, accepted, varkw, where, builder):
    """'builder', 'arg' or 'path' for a parameter name (raises on unknown names)."""
    if key == "builder":
        return "builder"
    if _is_path(key):
        _check_path(key, where)
        return "path"
    if builder is not None and (key in accepted or varkw):
        return "arg"
    if key in TOP_LEVEL:
        return "path"
    if builder is None:
        raise InputError(f"{where}.{key}", f"is not a scene path: give <section>.<key> "
                                           f"({', '.join(SECTIONS)}) or one of {', '.join(TOP_LEVEL)}")
    raise InputError(f"{where}.{key}", f"is neither an argument of the builder {builder!r} (accepted: "
                                       f"{', '.join(sorted(accepted))}) nor a scene path <section>.<key>")


def _numeric_text(value) -> bool:
    """True for a string that reads as a number ("0.1", "2", "1e3"): a value typed in quotes."""
    if not isinstance(value, str):
        return False
    try:
        float(value)
    except ValueError:
        return False
    return True


def _check_type(key, value, kind, default, where):
    """A parameter value of the wrong type, refused before any member runs: a number in
    quotes ("0.1"), or text or a boolean for a builder argument whose default is a number."""
    text_ok = isinstance(default, str) or key == "name"
    values = value if isinstance(value, (list, tuple)) else [value]
    for v in values:
        if _numeric_text(v) and not text_ok:
            raise InputError(f"{where}.{key}", f"must be a number, got the text {v!r} (a string in quotes): "
                                               f"write {v} without quotes")
    if kind == "arg" and isinstance(default, (int, float)) and not isinstance(default, bool) \
            and isinstance(value, (str, bool)):
        raise InputError(f"{where}.{key}", f"must be a number (the builder's default is {default!r}), got "
                                           f"{value!r} ({type(value).__name__})")


def _defaults(func) -> dict:
    import inspect

    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return {}
    return {p.name: p.default for p in sig.parameters.values() if p.default is not inspect.Parameter.empty}


def plan(base_scene, sweep) -> list[Member]:
    """The members of a sweep, in order (product first, then explicit members), with
    resolved parameters and ids. Unknown parameter names fail here, before any work;
    parameter values are checked when each member's scene is built (on the worker)."""
    sweep = as_sweep(sweep)
    default_builder, base_args, base_key, _ = _base_of(base_scene)
    base_args = {**base_args, **(sweep.base or {})}
    if not isinstance(sweep.replicates, int) or isinstance(sweep.replicates, bool) or sweep.replicates < 1:
        raise InputError("study.replicates", f"must be an integer >= 1, got {sweep.replicates!r}")
    if sweep.entropy is not None and (not isinstance(sweep.entropy, (int, np.integer)) or sweep.entropy < 0):
        raise InputError("study.entropy", f"must be an integer >= 0, got {sweep.entropy!r}")
    for name, values in sweep.product.items():
        if not isinstance(values, (list, tuple, np.ndarray)) or len(values) == 0:
            raise InputError(f"sweep.{name}", f"must be a non-empty list of values, got {values!r}")
    combos = []
    axes = list(sweep.product)
    if axes:
        for values in itertools.product(*(list(sweep.product[a]) for a in axes)):
            combos.append(("sweep", dict(zip(axes, values))))
    for i, m in enumerate(sweep.members):
        if not isinstance(m, dict):
            raise InputError(f"members[{i}]", f"must be a table of parameters, got {m!r}")
        combos.append((f"members[{i}]", dict(m)))
    if not combos:
        combos.append(("base", {}))

    if "builder" in base_args:
        raise InputError("base.builder", "the builder is named by the study ([study] builder, or Builder(...)) "
                                         "or by a member, not among the base parameters")
    members, seen = [], {}
    for where, given in combos:
        builder = given.get("builder", default_builder)
        if builder is not None and not isinstance(builder, str):
            builder = builder_name(builder)
            given["builder"] = builder
        if default_builder is None and "builder" in given:
            raise InputError(f"{where}.builder", "a member of a sweep over a base Scene cannot name a builder")
        if builder is not None:
            func = resolve_builder(builder, f"{where}.builder" if "builder" in given else "builder")
            accepted, varkw = accepts(func)
            defaults = _defaults(func)
        else:
            accepted, varkw, defaults = set(), False, {}
        params = {}
        if builder is not None:
            params["builder"] = builder
        for key, value in base_args.items():
            try:
                kind = _classify(key, accepted, varkw, "base", builder)
            except InputError:
                if builder != default_builder:
                    continue        # base arguments of the study's builder another builder lacks
                raise
            _check_type(key, value, kind, defaults.get(key), "base")
            params[key] = canonical(value, f"base.{key}")
        for key, value in given.items():
            if key == "builder":
                continue
            kind = _classify(key, accepted, varkw, where, builder)
            _check_type(key, value, kind, defaults.get(key), where)
            params[key] = canonical(value, f"{where}.{key}")
        swept = [k for k in given if k != "builder" or given["builder"] != default_builder]
        seeded = builder is not None and sweep.seed_arg in accepted and sweep.seed_arg not in params \
            and sweep.entropy is not None
        if sweep.replicates > 1 and not seeded:
            raise InputError("study.replicates", f"replicates > 1 need study.entropy and a builder taking "
                                                 f"{sweep.seed_arg!r} ({builder!r} in {where})")
        for r in range(sweep.replicates):
            p = dict(params)
            s = list(swept)
            if seeded:
                own = {"builder": builder, **{k: params[k] for k in given if k != "builder"}}
                h = hashlib.sha256(canonical_json(own).encode()).digest()
                key = (int.from_bytes(h[:4], "little"), int.from_bytes(h[4:8], "little"), r)
                state = np.random.SeedSequence(int(sweep.entropy), spawn_key=key).generate_state(1, np.uint64)
                p[sweep.seed_arg] = int(state[0] >> np.uint64(64 - SEED_BITS))
                s.append(sweep.seed_arg)
            mid = member_id(base_key, p)
            if mid in seen:
                raise InputError(where, f"member {len(members)} has the same parameters as member {seen[mid]} "
                                        f"(id {mid}): {p}")
            seen[mid] = len(members)
            members.append(Member(len(members), mid, p, tuple(dict.fromkeys(s))))
    return members


# ---------------------------------------------------------------------------- building one member
def _field_value(section, value):
    if isinstance(value, list) and section in ("law", "loading"):
        arr = np.asarray(value)
        return arr.astype(float) if arr.dtype.kind in "iu" else arr
    if isinstance(value, list):
        return tuple(value)
    return value


def check_paths(scene, paths: dict, where: str | None = None):
    """Refuse a scene path that names no key of ``scene`` (with the nearest key as a
    suggestion: law.tauc -> law.tau_c) or gives text where the scene holds a number;
    ``where``: the study table the paths come from (sweep, members[2], ...), for the message."""
    import difflib

    for key, value in paths.items():
        if not _is_path(key):
            continue
        section, _, name = key.partition(".")
        obj = getattr(scene, section, None)
        if obj is None or not dataclasses.is_dataclass(obj):
            continue
        known = [f.name for f in dataclasses.fields(obj)]
        field = f"{where}.{key}" if where else key
        if name not in known:
            close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
            hint = f"did you mean {section}.{close[0]}? " if close else ""
            raise InputError(field, f"unknown key for {type(obj).__name__}; {hint}accepted: "
                                    f"{', '.join(sorted(known))}")
        current = getattr(obj, name)
        if isinstance(decode(value), str) and (isinstance(current, (int, float, np.ndarray))
                                               and not isinstance(current, bool)):
            raise InputError(field, f"must be a number (the scene has {type(current).__name__} "
                                    f"{current if np.ndim(current) == 0 else 'a field'}), got the text {value!r}")


def _section_classes(section):
    """The classes a scene's ``section`` may be (every law's for "law")."""
    from ..model.grid import Grid
    from ..model.loading import Loading
    from ..model.material import Material
    from ..model.record import Record
    from ..model.scene import Numerics

    if section == "law":
        from ..laws import LAWS

        return list(LAWS.values())
    return [{"material": Material, "grid": Grid, "loading": Loading, "record": Record,
             "numerics": Numerics}[section]]


def check_section_keys(key: str, value, where: str | None = None):
    """``check_paths`` without a scene: the key must name a field of its section's class
    (of some law for law.*), with the nearest one suggested."""
    import difflib

    if not _is_path(key):
        return
    section, _, name = key.partition(".")
    classes = _section_classes(section)
    known = sorted({f.name for c in classes for f in dataclasses.fields(c)})
    if name not in known:
        close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
        hint = f"did you mean {section}.{close[0]}? " if close else ""
        what = "any law" if section == "law" else classes[0].__name__
        raise InputError(f"{where}.{key}" if where else key, f"unknown key for {what}; {hint}accepted: "
                                                              f"{', '.join(known)}")


def apply_paths(scene, paths: dict):
    """``scene`` with the scene paths ``{"law.tau_c": 2.0, "beta": 0.4, ...}`` set; every
    changed part is rebuilt with ``dataclasses.replace`` and so validated again."""
    sections, top = {}, {}
    for key, value in paths.items():
        value = decode(value)
        if _is_path(key):
            section, _, name = key.partition(".")
            sections.setdefault(section, {})[name] = _field_value(section, value)
        elif key in TOP_LEVEL:
            top[key] = value
        else:
            raise InputError(key, "is not a scene path")
    check_paths(scene, paths)
    changes = dict(top)
    for section, values in sections.items():
        changes[section] = dataclasses.replace(getattr(scene, section), **values)
    return scene.replace(**changes) if changes else scene


def split_params(func, params: dict) -> tuple[dict, dict]:
    """(builder arguments, scene paths) of a member's parameters (without "builder")."""
    accepted, varkw = accepts(func)
    args = {k: decode(v) for k, v in params.items() if k != "builder" and not _is_path(k)
            and (k in accepted or varkw)}
    return args, {k: v for k, v in params.items() if k != "builder" and k not in args}


def build_scene(base_scene, params: dict, *, fft_threads: int | None = 1, builders: dict | None = None):
    """The Scene of one member: the builder called with its arguments (or the base Scene),
    then the scene paths applied. ``fft_threads`` sets numerics.fft_threads unless the
    member sets it (None: leave it). ``builders``: {name: function} to use for these
    names (what a worker is sent); other names are resolved with ``resolve_builder``."""
    from ..model.scene import Scene

    params = dict(params)
    if isinstance(base_scene, Scene):
        scene, paths = base_scene, params
    else:
        name = params.pop("builder")
        func = (builders or {}).get(name) if isinstance(name, str) else None
        func = func or resolve_builder(name)
        args, paths = split_params(func, params)
        scene = func(**args)
        if not isinstance(scene, Scene):
            raise InputError("builder", f"must return a cracklab.Scene, got {type(scene).__name__}")
    scene = apply_paths(scene, paths)
    if fft_threads is not None and "numerics.fft_threads" not in params \
            and scene.numerics.fft_threads != fft_threads:
        scene = scene.replace(numerics=dataclasses.replace(scene.numerics, fft_threads=int(fft_threads)))
    return scene
