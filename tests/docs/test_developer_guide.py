"""docs/developer/developer.md's recipes against the code they describe."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_add_a_law_recipe_shows_constant_friction_py_as_it_is():
    text = (ROOT / "docs" / "developer" / "developer.md").read_text()
    recipe = text[text.index("### Add a law"):text.index("### Add a scene builder")]
    blocks = re.findall(r"```python\n(.*?)```", recipe, re.S)
    assert len(blocks) == 1
    assert blocks[0] == (ROOT / "cracklab" / "laws" / "constant_friction.py").read_text()


GUIDE = ROOT / "docs" / "developer" / "developer.md"


def _section(start, end):
    text = GUIDE.read_text()
    return text[text.index(start):text.index(end)]


def _named(section):
    """The code names a recipe gives in backticks: `name` or `name(args)`."""
    return sorted(set(re.findall(r"`([a-z_]+)(?:\([^`]*\))?`", section)))


def test_every_file_the_guide_names_exists():
    """A path such as `solver/halfspace.py` or cracklab/laws/base.py names a file of the
    repository (a module that moved leaves no stale path behind)."""
    text = GUIDE.read_text()
    paths = set(re.findall(r"(?<![\w./])((?:cracklab/)?(?:elastic|solver|history|laws|model|output|ensemble|analysis|"
                           r"plots|scenes|cli)/[\w/]+\.py)", text))
    paths |= set(re.findall(r"(?<![\w./])((?:tests|studies|docs/tools)/[\w/]+\.py)", text))
    missing = sorted(p for p in paths
                     if not (ROOT / p).is_file() and not (ROOT / "cracklab" / p).is_file())
    assert paths and not missing, missing


def test_the_scheme_recipe_names_what_a_scheme_has():
    import dataclasses
    import inspect

    import cracklab
    from cracklab.solver.halfspace import HalfSpace
    from cracklab.solver.schemes import SCHEMES
    from cracklab.solver.schemes.base import Run

    schemes = list(SCHEMES.values())
    channel_args = set().union(*(inspect.signature(getattr(s, m)).parameters for s in schemes
                                 for m in ("channel", "estimate", "finish")))
    others = {f.name for f in dataclasses.fields(Run)} | set(dir(HalfSpace)) | set(dir(cracklab)) | channel_args
    names = _named(_section("### Add a time scheme", "### Add a half-space type"))
    missing = [n for n in names if not (all(hasattr(s, n) for s in schemes) or n in others)]
    assert len(names) > 10 and not missing, missing


def test_the_interface_recipe_names_what_an_interface_type_has():
    import dataclasses

    from cracklab.model.scene import Scene
    from cracklab.solver.interfaces.base import TYPES
    from cracklab.solver.schemes.base import Run

    types = list(TYPES.values()) if isinstance(TYPES, dict) else list(TYPES)
    protocol = [n for n in ("accepts", "build", "accepts_scheme", "scheme_error", "margin", "engine_channels",
                            "mode_arrays", "energy_refusal", "holds_faces")]
    names = _named(_section("### Add a half-space type", "### Add a history engine"))
    assert set(protocol) <= set(names), set(protocol) - set(names)
    for n in protocol:
        assert all(hasattr(t, n) for t in types), n
    others = {f.name for f in dataclasses.fields(Run)} | {f.name for f in dataclasses.fields(Scene)}
    missing = [n for n in names if not (any(hasattr(t, n) for t in types) or n in others)]
    assert not missing, missing


def test_the_engine_recipe_names_what_an_engine_has():
    from cracklab.history import ENGINES

    engines = list(ENGINES.values()) if isinstance(ENGINES, dict) else list(ENGINES)
    names = _named(_section("### Add a history engine", "### Add a benchmark study"))
    missing = [n for n in names if not all(hasattr(e, n) for e in engines)]
    assert len(names) > 8 and not missing, missing
