"""``cracklab new``: a scene TOML from a registered scene builder and key=value arguments."""
from __future__ import annotations

import inspect
import re
import tomllib
from pathlib import Path

import click

from .common import CONTEXT, fail, main


def parse_value(text: str):
    """A command-line value read as a TOML value (``400``, ``1e-3``, ``true``, ``"x"``,
    ``[64000.0, 32000.0]``); text that is not one is taken as a plain string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def builder_lines() -> list[str]:
    """"name  first sentence of its docstring" of every registered builder, sorted by name."""
    from ..scenes.registry import registered_builders, resolve_builder

    out = []
    names = sorted(registered_builders())
    width = max(map(len, names), default=0)
    for name in names:
        try:
            doc = inspect.getdoc(resolve_builder(name)) or ""
        except Exception:  # noqa: BLE001 - a broken entry point is still listed
            doc = "(cannot be loaded)"
        out.append(f"{name:<{width}}  {_first_sentence(doc)}".rstrip())
    return out


def _first_sentence(doc: str, width: int = 100) -> str:
    """The first sentence of a docstring's first paragraph, cut at ``width`` characters."""
    para = " ".join(doc.split("\n\n")[0].split())
    end = re.search(r"\.\s+(?=[A-Z])", para)      # not "Figs. 12"
    text = para if end is None else para[:end.start() + 1]
    return text if len(text) <= width else text[:width - 3].rstrip() + "..."


def _arguments(func) -> list[str]:
    try:
        params = inspect.signature(func).parameters.values()
    except (TypeError, ValueError):
        return []
    return [p.name for p in params if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)]


def build(name: str, assignments) -> object:
    """The scene of the builder ``name`` called with the ``key=value`` ``assignments``
    (builder arguments, or scene paths such as ``record.every=16``, set afterwards)."""
    from ..ensemble.planning import TOP_LEVEL, apply_paths
    from ..errors import InputError
    from ..model.scene import Scene
    from ..scenes.registry import accepts, resolve_builder

    func = resolve_builder(name, "BUILDER")
    accepted, varkw = accepts(func)
    listed = ", ".join(_arguments(func)) or "none"
    args, paths, texts = {}, {}, []
    for item in assignments:
        key, eq, text = item.partition("=")
        key = key.strip()
        if not eq or not key:
            raise InputError("ARGUMENT", f"{item!r} is not key=value (e.g. dx=400); {name} takes {listed}")
        value = parse_value(text.strip())
        if isinstance(value, str) and not text.strip().startswith(("'", '"')):
            texts.append(key)
        if "." in key or (key in TOP_LEVEL and key not in accepted):
            paths[key] = value
        elif key in accepted or varkw:
            args[key] = value
        else:
            raise InputError(key, f"{name} takes no argument {key!r}; its arguments: {listed} (or a scene path "
                                  f"such as record.every=16)")
    try:
        scene = func(**args)
    except InputError as exc:
        if not texts:
            raise
        text = str(exc)
        rest = text[len(exc.field) + 2:] if text.startswith(exc.field + ": ") else text
        raise InputError(exc.field, f"{rest} ({', '.join(texts)}: not a TOML value, taken as text)") from None
    except (TypeError, ValueError) as exc:
        typed = " ".join(assignments)
        note = f" ({', '.join(texts)}: not a TOML value, taken as text)" if texts else ""
        raise InputError(name, f"cannot build the scene from {typed or 'no arguments'}{note}: "
                               f"{type(exc).__name__}: {exc}") from None
    if not isinstance(scene, Scene):
        raise InputError(name, f"the builder must return a cracklab.Scene, got {type(scene).__name__}")
    return apply_paths(scene, paths)


@main.command(context_settings=CONTEXT)
@click.argument("builder", required=False)
@click.argument("assignments", nargs=-1, metavar="[KEY=VALUE]...")
@click.option("-o", "--output", default=None, type=click.Path(dir_okay=False),
              help="Scene TOML file to write; its fields go into OUTPUT's sidecar <stem>.fields.nc.")
@click.option("--overwrite", is_flag=True, help="Replace OUTPUT (and its sidecar) when it exists.")
@click.option("--list", "list_", is_flag=True, help="List the registered builders, each with the first sentence "
                                                    "of its docstring.")
def new(builder, assignments, output, overwrite, list_) -> None:
    """Write the scene of BUILDER (a registered scene builder, see --list) to OUTPUT.

    Each KEY=VALUE is an argument of the builder, or a scene path set afterwards
    (record.every=16, law.tau_c=2.0, t_end=5); VALUE is read as a TOML value (400,
    1e-3, true, "text", [64000.0, 32000.0]), else taken as a string. Example:
    cracklab new tpv3 dx=400 -o tpv3.toml, then cracklab run tpv3.toml -o tpv3.zarr."""
    from ..errors import InputError

    if list_:
        for line in builder_lines():
            click.echo(line)
        return
    if builder is None:
        raise click.UsageError("Missing argument 'BUILDER' (cracklab new --list lists them).")
    if output is None:
        raise click.UsageError("Missing option '-o' / '--output' (the scene TOML file to write).")
    target = Path(output)
    if target.exists() and not overwrite:
        raise click.ClickException(f"-o: {output} exists; refusing to replace it: choose another -o, or --overwrite")
    try:
        scene = build(builder, assignments)
        scene.to_toml(target)
    except InputError as exc:
        raise fail(exc) from None
    except OSError as exc:
        raise click.ClickException(f"-o: cannot write {output}: {exc.strerror or exc}") from None
    click.echo(f"cracklab: wrote {output} (scene {scene.name!r}, grid {scene.grid.n1} x {scene.grid.n3}, "
               f"{scene.nsteps} steps to t_end = {scene.t_end:g})")
