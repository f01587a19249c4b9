"""The layers of cracklab, in the order docs/developer/developer.md gives them: a module imports
only from its own layer and the layers below it, at the top of a file or inside a function
alike. Read from the source (every ``import`` and ``from ... import`` statement), so an
import against the order fails here before it can hide a cycle."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "cracklab"

#: bottom to top; a name is a module of the package root or a subpackage
LAYERS = ("errors", "version", "limits", "jit", "elastic", "laws", "history", "solver", "model", "output",
          "scenes", "ensemble", "analysis", "plots", "cli")
#: the package's public faces, which import from every layer
FACES = {"cracklab", "cracklab.kernels", "cracklab.__main__"}
#: the imports against the order that stay, each with its reason
EXCEPTIONS = {
    ("cracklab.ensemble", "cracklab.analysis.table"):
        "ensemble.summary, a documented convenience name for analysis.summary, imported when called",
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in PACKAGE.rglob("*.py")}


def resolve(name: str) -> str | None:
    """The module of ``name`` (a module, or a name defined in one)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def imports(module: str, path: Path):
    """(imported module, line) of every import of cracklab in ``path``."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "cracklab":
                    yield resolve(alias.name), node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            if source.split(".")[0] != "cracklab":
                continue
            for alias in node.names:      # `from . import x` imports the module x
                yield resolve(f"{source}.{alias.name}") or resolve(source), node.lineno


def layer(module: str) -> str:
    return module.split(".")[1] if module.count(".") else module


def test_every_module_has_a_layer():
    unknown = sorted(m for m in MODULES if m not in FACES and layer(m) not in LAYERS)
    assert not unknown, f"modules outside the layers of docs/developer/developer.md: {unknown}"


def test_no_import_goes_up_the_layers():
    wrong = []
    for module, path in MODULES.items():
        if module in FACES:
            continue
        here = LAYERS.index(layer(module))
        for target, line in imports(module, path):
            if target is None or target == module or (module, target) in EXCEPTIONS:
                continue
            there = target in FACES or LAYERS.index(layer(target)) > here
            if there:
                wrong.append(f"{path.relative_to(ROOT)}:{line} imports {target} ({layer(target)} is above "
                             f"{layer(module)})" if target not in FACES else
                             f"{path.relative_to(ROOT)}:{line} imports the package face {target}")
    assert not wrong, "imports against the layer order:\n" + "\n".join(wrong)


def test_the_exceptions_are_still_there():
    """An exception whose import is gone is taken off the list."""
    for (module, target) in EXCEPTIONS:
        assert any(t == target for t, _ in imports(module, MODULES[module])), (module, target)


def test_the_bottom_layers_import_nothing_above_errors():
    for module, path in MODULES.items():
        if layer(module) in ("errors", "version", "limits", "jit", "elastic"):
            for target, line in imports(module, path):
                assert target is None or layer(target) in ("errors", layer(module)), \
                    f"{path.relative_to(ROOT)}:{line} imports {target}"


def test_the_check_sees_an_import_against_the_order(tmp_path):
    """The reader of imports finds a relative import inside a function (what a cycle hides
    behind) and resolves it to its module."""
    src = tmp_path / "x.py"
    src.write_text("def f():\n    from ..solver.stepper import Stepper\n    from .. import plots\n")
    found = list(imports("cracklab.model.x", src))
    assert found == [("cracklab.solver.stepper", 2), ("cracklab.plots", 3)]


def test_the_developer_guide_gives_this_order():
    text = (ROOT / "docs" / "developer" / "developer.md").read_text()
    block = text.split("```text", 1)[1].split("```", 1)[0]
    named = [line.split()[0].rstrip("/").removesuffix(".py") for line in block.splitlines()
             if line.strip() and not line.startswith(" " * 4) and line.split()[0] != "cracklab/"]
    assert named == list(LAYERS), named


#: cycles between two modules that stay, with their reason
PAIRS = {
    frozenset({"cracklab.model.scene", "cracklab.model.scene_io"}):
        "Scene's round trips (to_toml, from_dataset, ...) are thin wrappers over scene_io, which builds Scenes",
}


def _cycles():
    """The strongly connected sets of modules of the import graph (function-level imports
    included; a module's import of its own package face left out)."""
    graph = {m: {t for t, _ in imports(m, p) if t and t != m and t not in FACES and not m.startswith(t + ".")}
             for m, p in MODULES.items() if m not in FACES}
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = set()
            while True:
                w = stack.pop()
                on.discard(w)
                group.add(w)
                if w == v:
                    break
            if len(group) > 1:
                found.append(frozenset(group))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_no_two_modules_import_each_other():
    cycles = [sorted(c) for c in _cycles() if c not in PAIRS]
    assert not cycles, f"modules that import each other (directly or around a circle): {cycles}"
    assert all(pair in _cycles() for pair in PAIRS), "a listed cycle is gone: take it off PAIRS"


def test_no_private_name_is_imported_from_another_module():
    """A helper one module shares with another is public in it (no ``from .common import
    _helper``): a leading underscore means "of this module only"."""
    taken = []
    for module, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("cracklab")):
                taken += [f"{path.relative_to(ROOT)}:{node.lineno} {a.name}" for a in node.names
                          if a.name.startswith("_") and not a.name.startswith("__")]
    assert not taken, taken
