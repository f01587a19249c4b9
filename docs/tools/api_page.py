"""Write docs/reference/api.md, the reference of cracklab's public names, from the live code.

    python docs/tools/api_page.py            # rewrite docs/reference/api.md
    python docs/tools/api_page.py --check    # exit 1 if docs/reference/api.md is not what it would write

The names and their grouping by layer are listed here (``groups``); each entry's
signature comes from ``inspect.signature`` (the command line's from its click
parameters) and its summary is the first sentence of its docstring; a listed name without
a docstring of its own stops the script. tests/docs/test_api_page.py fails when the
committed page differs from what this script writes.
"""
from __future__ import annotations

import argparse
import dataclasses
import functools
import importlib
import inspect
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "reference" / "api.md"
try:
    import cracklab  # noqa: F401
except ImportError:  # run from a checkout without an install
    sys.path.insert(0, str(ROOT))

#: promised by the project's public API; listed as "not in cracklab yet" while they are missing
PROMISED = ("cracklab.scenes.tpv5", "cracklab.scenes.tpv6", "cracklab.scenes.tpv101",
            "cracklab.scenes.tpv102", "cracklab.scenes.tpv103", "cracklab.scenes.tpv104")

ABBREVIATIONS = ("e.g", "i.e", "eq", "eqs", "Eq", "Eqs", "Fig", "Figs", "cf", "etc", "vs", "approx")


def groups() -> list[tuple[str, str, list[str]]]:
    """(title, layer modules, dotted names) in the order of the page."""
    import cracklab
    from cracklab.cli import main
    from cracklab.laws import LAWS
    from cracklab.scenes import BUILDERS

    laws = [f"cracklab.{c.__name__}" if getattr(cracklab, c.__name__, None) is c else f"cracklab.laws.{c.__name__}"
            for c in sorted(LAWS.values(), key=lambda c: c.__name__)]
    return [
        ("Model", "`cracklab.model`", [
            "cracklab.Material", "cracklab.Material.cd", "cracklab.Material.rho", "cracklab.Material.cR",
            "cracklab.Material.a",
            "cracklab.Grid", "cracklab.Grid.x1", "cracklab.Grid.x3", "cracklab.Grid.dx1", "cracklab.Grid.dx3",
            "cracklab.Loading", "cracklab.point_load", "cracklab.Record", "cracklab.Numerics", "cracklab.Sequence",
            "cracklab.Scene", "cracklab.Scene.replace", "cracklab.Scene.dt", "cracklab.Scene.nsteps",
            "cracklab.Scene.beta_max", "cracklab.Scene.formulation", "cracklab.Scene.components",
            "cracklab.Scene.to_toml", "cracklab.Scene.from_toml", "cracklab.Scene.to_dataset",
            "cracklab.Scene.from_dataset", "cracklab.InputError"]),
        ("Laws", "`cracklab.laws`", laws),
        ("Solver", "`cracklab.solver`; its kernels are public as `cracklab.kernels`", [
            "cracklab.kernels.C_I", "cracklab.kernels.C_II", "cracklab.kernels.C_III", "cracklab.kernels.Z"]),
        ("Output", "`cracklab.output`", [
            "cracklab.simulate", "cracklab.stations", "cracklab.scene_of", "cracklab.SimulationError",
            "cracklab.output.seas.export_seas", "cracklab.output.stores.Store", "cracklab.output.stores.store_for",
            "cracklab.output.stores.kinds"]),
        ("Ensemble", "`cracklab.ensemble`", [
            "cracklab.open_ensemble", "cracklab.register_builder", "cracklab.ensemble.run",
            "cracklab.ensemble.load_study", "cracklab.ensemble.plan", "cracklab.ensemble.open_member",
            "cracklab.ensemble.member_status", "cracklab.ensemble.export_netcdf"]),
        ("Analysis", "`cracklab.analysis`", [
            "cracklab.modal_response",
            *[f"cracklab.analysis.{n}" for n in importlib.import_module("cracklab.analysis").__all__],
            *[f"cracklab.energy.{n}" for n in cracklab.energy.__all__]]),
        ("Plots", "`cracklab.plots`", [f"cracklab.plots.{n}" for n in importlib.import_module("cracklab.plots").__all__]),
        ("Scenes", "`cracklab.scenes`", [f"cracklab.scenes.{b}" for b in BUILDERS]),
        ("Command line", "`cracklab.cli`", [f"cracklab {name}" for name in main.commands]),
    ]


# ----------------------------------------------------------------------------- lookup
def resolve(dotted: str):
    """(owner class or None, object) for a dotted name: the longest importable module,
    then attributes (looked up statically, so that properties are found as such)."""
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        owner = None
        for name in parts[k:]:
            owner = obj if inspect.isclass(obj) else None
            obj = inspect.getattr_static(obj, name) if owner is not None else getattr(obj, name)
        return owner, obj
    raise ImportError(dotted)


def exists(dotted: str) -> bool:
    try:
        resolve(dotted)
    except (ImportError, AttributeError):
        return False
    return True


# ----------------------------------------------------------------------------- text
def markdown(text: str) -> str:
    """reST inline markup as Markdown: ``x`` and :role:`x` become `x`."""
    text = re.sub(r":[\w.]+:`~?([^`]+)`", r"`\1`", text)
    text = re.sub(r"::$", ".", text)
    return text.replace("``", "`")


def first_sentence(doc: str | None) -> str:
    """The first sentence of a docstring's first paragraph, on one line."""
    if not doc:
        return ""
    para = inspect.cleandoc(doc).split("\n\n")[0]
    text = " ".join(line.strip() for line in para.splitlines())
    for m in re.finditer(r"(?<=[^\s.])[.!?](../?=\s|$)", text):
        word = re.search(r"([\w.]*)$", text[:m.start()]).group(1)
        if word in ABBREVIATIONS or (len(word) == 1 and word.isalpha()):
            continue
        if text[:m.start()].count("(") > text[:m.start()].count(")"):
            continue  # inside parentheses
        return markdown(text[:m.end()])
    return markdown(text)


def own_doc(dotted: str, owner, obj) -> str | None:
    """The docstring written for this object (not a dataclass's generated one, not the
    base class's)."""
    if isinstance(obj, (property, functools.cached_property)):
        return (obj.fget if isinstance(obj, property) else obj.func).__doc__
    if isinstance(obj, (classmethod, staticmethod)):
        obj = obj.__func__
    doc = obj.__doc__ if inspect.isclass(obj) else inspect.getdoc(obj)
    if inspect.isclass(obj) and dataclasses.is_dataclass(obj) and doc and doc.startswith(obj.__name__ + "("):
        return None  # the signature dataclasses writes when there is no docstring
    return doc


def default(value, param_name, cls) -> str:
    if value is dataclasses.MISSING or repr(value) == "<factory>":
        field = {f.name: f for f in dataclasses.fields(cls)}[param_name]
        made = field.default_factory()
        return f"{type(made).__name__}()" if dataclasses.is_dataclass(made) else repr(made)
    return repr(value)


def parameters(sig: inspect.Signature, cls=None, drop_first=False) -> str:
    out, star = [], False
    params = list(sig.parameters.values())[1 if drop_first else 0:]
    for p in params:
        if p.kind is p.KEYWORD_ONLY and not star:
            out.append("*")
            star = True
        if p.kind is p.VAR_POSITIONAL:
            out.append(f"*{p.name}")
            star = True
        elif p.kind is p.VAR_KEYWORD:
            out.append(f"**{p.name}")
        elif p.default is p.empty:
            out.append(p.name)
        else:
            out.append(f"{p.name}={default(p.default, p.name, cls)}")
        if p.kind is p.POSITIONAL_ONLY and (p is params[-1] or params[params.index(p) + 1].kind is not p.POSITIONAL_ONLY):
            out.append("/")
    return ", ".join(out)


def returns(sig: inspect.Signature) -> str:
    ann = sig.return_annotation
    if ann is sig.empty or ann in (None, "None"):
        return ""
    text = ann if isinstance(ann, str) else getattr(ann, "__name__", repr(ann))
    return f" -> {text.strip(chr(39) + chr(34))}"


def signature(dotted: str, owner, obj) -> tuple[str, str]:
    """(the call as code, a note: "property", an exception's base class, or "")."""
    if isinstance(obj, (property, functools.cached_property)):
        return dotted, "property"
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        base = next(b for b in obj.__mro__[1:] if b.__module__ == "builtins").__name__
        if "__init__" in vars(obj):
            return f"{dotted}({parameters(inspect.signature(obj))})", f"exception, a {base}"
        return dotted, f"exception, a {base}"
    if inspect.isclass(obj):
        return f"{dotted}({parameters(inspect.signature(obj), cls=obj)})", ""
    if isinstance(obj, classmethod):
        func = obj.__func__
        return f"{dotted}({parameters(inspect.signature(func), drop_first=True)}){returns(inspect.signature(func))}", ""
    if isinstance(obj, staticmethod):
        obj = obj.__func__
    sig = inspect.signature(obj)
    drop = owner is not None and next(iter(sig.parameters), None) == "self"
    return f"{dotted}({parameters(sig, drop_first=drop)}){returns(sig)}", ""


def click_usage(cmd_name: str):
    """(usage, summary) of a `cracklab` subcommand from its click parameters."""
    import click

    from cracklab.cli import main

    cmd = main.commands[cmd_name]
    pieces = []
    for p in cmd.params:
        if isinstance(p, click.Argument):
            pieces.append(p.human_readable_name)
            continue
        if getattr(p, "hidden", False):
            continue
        name = max(p.opts, key=len) if not any(o.startswith("-") and not o.startswith("--") for o in p.opts) \
            else next(o for o in p.opts if not o.startswith("--"))
        if p.is_flag:
            text = "/".join([name, *p.secondary_opts])
        elif isinstance(p.type, click.Choice):
            text = f"{name} {{{','.join(map(str, p.type.choices))}}}"
        else:
            text = f"{name} {p.metavar or p.type.name.split()[0].upper()}"
        if p.multiple:
            text += " ..."
        pieces.append(text if p.required else f"[{text}]")
    return f"cracklab {cmd_name} " + " ".join(pieces), first_sentence(cmd.help)


def entry(dotted: str) -> str:
    if dotted.startswith("cracklab "):
        usage, summary = click_usage(dotted.split(" ", 1)[1])
        return f"- `{usage.strip()}`: {summary}"
    owner, obj = resolve(dotted)
    summary = first_sentence(own_doc(dotted, owner, obj))
    if not summary:
        raise SystemExit(f"{dotted} has no docstring of its own: write one (its first sentence is its summary here)")
    code, note = signature(dotted, owner, obj)
    return f"- `{code}`{f' ({note})' if note else ''}: {summary}"


HEADER = """# API summary

The public names of `cracklab`, by layer: each with its signature and the first sentence
of its docstring. The names and their meanings are the project's promise to its users;
the other pages ([index.md](../index.md)) explain them. This page is
written from the code by `docs/tools/api_page.py` (`python docs/tools/api_page.py`), and
`tests/docs/test_api_page.py` fails when it is not what the script writes.
"""


def render() -> str:
    lines = [HEADER]
    for title, layer, names in groups():
        lines += [f"## {title}", "", f"Layer: {layer}.", ""]
        lines += [entry(n) for n in names]
        lines.append("")
    missing = [n for n in PROMISED if not exists(n)]
    import cracklab
    if "materials" not in inspect.signature(cracklab.Scene).parameters:
        missing.append("cracklab.Scene(..., materials=(top, bottom))")
    if missing:
        lines += ["## Promised by shared/API.md, not in cracklab yet", ""]
        lines += [f"- `{n}`" for n in missing]
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if docs/reference/api.md is out of date")
    args = ap.parse_args(argv)
    text = render()
    if args.check:
        ok = PAGE.exists() and PAGE.read_text() == text
        print("docs/reference/api.md is up to date" if ok else "docs/reference/api.md is out of date: run python docs/tools/api_page.py")
        return 0 if ok else 1
    PAGE.write_text(text)
    print(f"wrote {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
