"""docs/reference/toml.md is what docs/tools/toml_page.py writes from the law and scene definitions;
its examples are valid scenes, it lists every key, and the ranges it states are the ones
the validation enforces."""
from __future__ import annotations

import copy
import dataclasses
import importlib.util
import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from cracklab import InputError, Scene
from cracklab.laws import LAWS
from cracklab.laws.base import RANGES, parameter_docs
from cracklab.model.keys import SECTION_KEYS, TOP_KEYS, UNIT_KEYS
from cracklab.model.scene_io import scene_from_data, section_classes

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "reference" / "toml.md"
INF, NAN = math.inf, math.nan


def generator():
    spec = importlib.util.spec_from_file_location("toml_page", ROOT / "docs" / "tools" / "toml_page.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


GEN = generator()
TEXT = PAGE.read_text()
EXAMPLES = {tomllib.loads(body)["law"]["kind"]: body for body in GEN.examples_of(TEXT)}


def test_toml_page_is_up_to_date():
    assert TEXT == GEN.render(), "docs/reference/toml.md is out of date: run python docs/tools/toml_page.py"


def test_every_example_on_the_page_is_a_valid_scene_one_per_law():
    bodies = GEN.examples_of(TEXT)
    assert len(bodies) == len(LAWS) and set(EXAMPLES) == set(LAWS)
    for body in bodies:
        scene = Scene.from_toml(body)
        assert scene.law.kind in LAWS and scene.nsteps >= 1


def table_keys(block: str) -> list[str]:
    """The first column of the first key table of a page section."""
    table = block.split("| key |", 1)[1].split("\n\n", 1)[0]
    return [re.match(r"\| `([^`]+)`", line).group(1) for line in table.splitlines() if line.startswith("| `")]


def section_block(title: str) -> str:
    return TEXT.split(f"\n{title}\n", 1)[1].split("\n## ", 1)[0].split("\n### ", 1)[0]


def test_the_page_lists_every_section_and_key():
    classes = section_classes()
    for section, cls in classes.items():
        assert table_keys(section_block(f"## `[{section}]`")) == [f.name for f in dataclasses.fields(cls)], section
    for kind, cls in LAWS.items():
        assert table_keys(section_block(f"### `kind = \"{kind}\"`")) == [f.name for f in dataclasses.fields(cls)]
    top = table_keys(section_block("## Top level"))
    assert top[:len(TOP_KEYS)] == list(TOP_KEYS)
    assert table_keys(section_block("## `[units]`")) == list(UNIT_KEYS)
    for section in ("units", "material", "grid", "law", "loading", "record", "numerics"):
        assert f"| `[{section}]` |" in TEXT
    assert "| `file` |" in TEXT and "| `var` |" in TEXT


def test_every_key_has_a_unit_kind_and_range():
    units = {"stress", "length", "velocity", "time", "stiffness", "1", "-"}
    for section, keys in SECTION_KEYS.items():
        assert set(keys) == {f.name for f in dataclasses.fields(section_classes()[section])}, section
        for key, k in keys.items():
            assert k.unit in units and k.accepted and k.doc, (section, key)
    for kind, cls in LAWS.items():
        for name, (unit, pkind, accepted, doc) in parameter_docs(cls).items():
            assert doc, (kind, name)
            if pkind in ("field", "scalar"):
                assert accepted.split(";")[0] in RANGES, (kind, name, accepted)


def expect_refused(data, field):
    with pytest.raises(InputError) as err:
        scene_from_data(data)
    assert err.value.field == field or err.value.field.startswith(field + "."), str(err.value)


def expect_not_refused_for(data, field):
    try:
        scene_from_data(data)
    except InputError as exc:
        assert exc.field != field, str(exc)


#: values each declared range refuses, and values it accepts
PROBES = {"> 0": ((0.0, -1.0, INF), (1e-3,)), ">= 0": ((-1.0, INF), (0.0,)),
          ">= 0 or inf": ((-1.0,), (0.0, INF)), "finite": ((INF, NAN), (-0.5,))}
#: what a probe of an optional law parameter needs besides the example
#: (None: without that key)
CONTEXT = {("rate_state", "f_w"): {"evolution": "slip", "V_w": 0.1},
           ("rate_state", "V_w"): {"evolution": "slip", "f_w": 0.2},
           ("rate_state", "psi_ini"): {"V_ini": None},
           # the regularised normal stress goes without sigma_n
           **{(kind, name): {"sigma_n": None} for kind in ("slip_weakening", "rate_state", "constant_friction")
              for name in ("normal_slip_scale", "normal_time")}}


@pytest.mark.parametrize("kind", sorted(LAWS))
def test_law_ranges_on_the_page_are_the_checks(kind):
    """Each law parameter's declared range: values outside it are refused with an InputError
    naming the parameter, as one number and as one node of a field; values inside it are not
    refused for that parameter."""
    base = tomllib.loads(EXAMPLES[kind])
    shape = (base["grid"]["n1"], base["grid"]["n3"])
    for name, (unit, pkind, accepted, doc) in parameter_docs(LAWS[kind]).items():
        field = f"law.{name}"
        if pkind == "mask":
            for bad in ("yes", 2.0):
                data = copy.deepcopy(base)
                data["law"][name] = bad
                expect_refused(data, field)
            continue
        if pkind not in ("field", "scalar"):
            continue
        refused, allowed = PROBES[accepted.split(";")[0]]
        for value, check in [(v, expect_refused) for v in refused] + [(v, expect_not_refused_for) for v in allowed]:
            data = copy.deepcopy(base)
            for key, extra in CONTEXT.get((kind, name), {}).items():
                if extra is None:
                    data["law"].pop(key, None)
                else:
                    data["law"][key] = extra
            data["law"][name] = value
            check(data, field)
            if pkind == "field":      # the range holds at every node
                arr = np.full(shape, 1.0)
                arr[0, 0] = value
                data["law"][name] = arr
                if check is expect_refused:
                    check(data, field)


#: the law example each section's probes start from (nucleation needs the keys that go with it)
BASE_OF = {"loading": "slip_weakening", "record": "prescribed_rupture"}


@pytest.mark.parametrize("section", sorted(SECTION_KEYS) + ["top", "units"])
def test_section_ranges_on_the_page_are_the_checks(section):
    keys = {"top": TOP_KEYS, "units": UNIT_KEYS}.get(section) or SECTION_KEYS[section]
    base = tomllib.loads(EXAMPLES[BASE_OF.get(section, "linear_cohesive")])
    base.setdefault("units", {"length": "1", "time": "1", "stress": "1"})
    for key, k in keys.items():
        assert k.refused or section == "top", (section, key)
        for value in k.refused:
            data = copy.deepcopy(base)
            if section == "top":
                data[key] = value
                field = key
            else:
                data.setdefault(section, {})[key] = value
                field = f"{section}.{key}"
            expect_refused(data, field)


def test_toml_page_is_linked():
    assert "](reference/toml.md)" in (ROOT / "docs" / "index.md").read_text()
    assert "](toml.md)" in (ROOT / "docs" / "reference" / "scenes.md").read_text()
