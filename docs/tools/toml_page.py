"""Write docs/reference/toml.md, the reference of every key of a TOML scene, from the live definitions.

    python docs/tools/toml_page.py            # rewrite docs/reference/toml.md
    python docs/tools/toml_page.py --check    # exit 1 if docs/reference/toml.md is not what it would write

What the page lists comes from the code: the sections and their keys from the dataclasses
(``cracklab.model.scene_io.section_classes``, each key's kind of value from the decoder's
``section_schema``, its default from the dataclass), the unit kind, accepted range and
meaning of a key outside [law] from ``cracklab.model.keys``, and the laws from
``cracklab.laws.LAWS``: each law's parameters with the unit, kind, range and meaning they
declare (``laws.base.parameter``), its components, state variables and the first paragraph
of its docstring, and the small example scene each law gives (``Law.example``, in the
law's file); a law without one stops the script. tests/docs/test_toml_page.py fails
when the committed page differs from what this script writes, runs every example through
``Scene.from_toml``, and checks that the values the definitions call refused are refused.
"""
from __future__ import annotations

import argparse
import dataclasses
import inspect
import math
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "reference" / "toml.md"
try:
    import cracklab  # noqa: F401
except ImportError:  # run from a checkout without an install
    sys.path.insert(0, str(ROOT))

VALUE = {
    "number": "number", "integer": "integer", "boolean": "boolean", "string": "string",
    "numbers": "list of numbers", "strings": "list of strings", "field": "field", "mask": "mask",
    "region": "table", "stations": "table", "any": "any",
}

HEADER = """\
# TOML scene reference

Every key of a scene file (`cracklab run SCENE.toml`, `Scene.from_toml`, a study's
`study.scene`): the kind of value it takes, its unit, the range it must lie in and its
default. How scenes are written, read and checked is on [Scenes](scenes.md); the Python
names are on the [API reference](api.md).

This page is written from the code by `docs/tools/toml_page.py` (`python
docs/tools/toml_page.py`): the sections and keys from the scene's dataclasses, the
ranges and meanings from `cracklab.model.keys` and from each law's parameter
declarations (`cracklab.laws.base.parameter`). `tests/docs/test_toml_page.py` fails when
the page is not what the script writes, parses every example below into a Scene, and
checks that values outside each range are refused.

## Values

| value | in TOML |
| --- | --- |
| number | `1.5`, `2`, `3.2038e10`, `inf` where a range allows it |
| integer | `64` (`64.0` is refused) |
| boolean | `true`, `false` |
| string | `"ramp"` |
| list of numbers, list of strings | `[0.0, 0.1]`, `["delta_2", "v_2"]` |
| table | an inline table `{ x1 = [0.2, 0.8] }` or a sub-table `[record.region]` |
| field | a number (the same at every node), a nested list of n1 rows of n3 numbers, or a file reference (below) |
| mask | a nested list of n1 rows of n3 booleans, or a file reference (below); absent: no node |

A field's range holds at every node. Units are those of the scene's `[units]` table:
"stress", "length" and "time" are its `stress`, `length` and `time` units, "velocity" is
length / time, "1" a pure number, and "-" marks what is not a quantity (a name, a
count, a switch). A key marked *required* has no default; *absent* means the key is left
out (the default behaviour is then the one described). A key that is not on this page is
refused, with the accepted keys in the message.

## File references

A field or mask can be read from a file instead of written out:

```toml
[law]
tau_c = { file = "toughness.nc", var = "tau_c" }     # netCDF
delta_c = { file = "toughness.zarr", var = "delta_c" } # Zarr
initial_crack = { file = "crack.npy" }                 # numpy, one array: no var
```

| key | accepted | meaning |
| --- | --- | --- |
"""

REFERENCE_RULES = """\

- A relative path is taken from the directory of the scene file (for TOML text given to
  `Scene.from_toml`, from its `base` argument, by default the current directory).
- A file is read only from the scene file's folder or a folder below it, after symbolic
  links are followed (an absolute path is fine if it lies there). A scene received from
  someone else thus reads only what came with it: it cannot copy other data of yours into
  its output (the store keeps every input field), which you may then share. To read from
  another folder, allow it: `cracklab run --allow-files DIR` (repeatable),
  `Scene.from_toml(path, allow=[DIR])`, or the environment variable
  `CRACKLAB_ALLOW_FILES` (folders separated by `:`).
- Only a regular file is read (a Zarr field: a directory of them): a FIFO, a device or a
  socket is refused at once rather than read (a FIFO would block the run for ever).
- Where each field came from is kept: the input variable of the output (e.g.
  `input_law_tau_c`) carries a `source` attribute with the reference as the scene wrote it
  and the SHA-256 of the bytes read.
- The array has the grid's shape: (n1, n3), or (n1, n3 + 1) with `grid.free_surface`;
  in the plane problem (n3 = 1) an array of shape (n1,) is taken as (n1, 1).
- A netCDF or Zarr variable lies on the dims `x1` and `x3` (in either order), and each
  carries its coordinate, equal to the grid's nodes x1_i = i L1 / n1, x3_k = k L3 / n3
  to a millionth of a cell. A field written for another grid or cell is refused, not
  interpolated.
- A mask is booleans, or integers 0 and 1 (netCDF has no boolean type). A field is
  numbers; NaN (a missing value, a `_FillValue`) is refused. A float32 field stays
  float32.
- A netCDF or Zarr variable with a `units` attr (a UDUNITS string, as CF files write
  them) is converted to the field's unit in the scene's `[units]`: a `tau_c` in "MPa" read
  into a scene whose stress unit is "Pa" is multiplied by 1e6. A unit UDUNITS does not
  know is refused, and so is one of another dimension: a stress in "m", or any dimensional
  unit for a quantity the scene keeps dimensionless ("1"). A variable without a `units`
  attr, and a .npy array, are taken as in the scene's units.
- Each failure is one `InputError` that names the field and says what was expected: no
  such file, an unknown format, no `var` (netCDF, Zarr) or a `var` (.npy), no such
  variable (the message lists the file's variables), the wrong dims, shape or
  coordinates, a mask that is not boolean.

`Scene.to_toml(path)` writes a scene this way: its scalars in the TOML file `path` and
every array-valued parameter into one netCDF file next to it, `<stem>.fields.nc`
(variables `<section>_<key>` on (x1, x3) with the grid's coordinates), referenced from
the TOML. A 128 x 64 random-toughness scene (`scenes.random_toughness(n1=128, n3=64)`)
is {saved} lines of TOML and the sidecar, against {inline:,} lines with its fields inline
(`Scene.to_toml()` without a path, which stays as it was). The sidecar is netCDF because
it is one file (a Zarr store is a directory of many), compressed, and read by every tool
of the field (xarray, `ncdump`, MATLAB, ParaView); it keeps float64 bits, float32 and
boolean masks exactly; and the fields of one scene are small, so Zarr's chunked, parallel
access buys nothing.
"""


def _markdown(text: str) -> str:
    text = re.sub(r":[\w.]+:`~?([^`]+)`", r"`\1`", text)
    return text.replace("``", "`")


def first_paragraph(doc: str | None) -> str:
    if not doc:
        return ""
    para = inspect.cleandoc(doc).split("\n\n")[0]
    return _markdown(" ".join(line.strip() for line in para.splitlines()))


def default(f: dataclasses.Field) -> str:
    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
        return "*required*"
    value = f.default if f.default is not dataclasses.MISSING else f.default_factory()
    return literal(value)


def literal(value) -> str:
    if value is None:
        return "*absent*"
    if isinstance(value, bool):
        return "`true`" if value else "`false`"
    if isinstance(value, float) and math.isinf(value):
        return "`inf`"
    if isinstance(value, str):
        return f'`"{value}"`'
    if isinstance(value, (tuple, list)):
        return "`[" + ", ".join(literal(v).strip("`") for v in value) + "]`"
    if isinstance(value, dict):
        return "`{" + ", ".join(f"{k} = {literal(v).strip('`')}" for k, v in value.items()) + "}`"
    return f"`{value!r}`"


def row(*cells) -> str:
    return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"


def key_table(rows) -> list[str]:
    out = [row("key", "value", "unit", "accepted", "default", "meaning"), row(*["---"] * 6)]
    out += [row(*r) for r in rows]
    return out


def section_rows(section: str, cls) -> list:
    from cracklab.model.keys import SECTION_KEYS
    from cracklab.model.scene_io import section_schema

    schema = section_schema(section, cls)
    keys = SECTION_KEYS[section]
    missing = [f.name for f in dataclasses.fields(cls) if f.name not in keys]
    if missing:
        raise SystemExit(f"cracklab.model.keys.SECTION_KEYS[{section!r}] has no entry for {missing}")
    rows = []
    for f in dataclasses.fields(cls):
        k = keys[f.name]
        rows.append((f"`{f.name}`", VALUE[schema[f.name][0]], k.unit, k.accepted, default(f), k.doc))
    return rows


def components(cls) -> str:
    comps = inspect.getattr_static(cls, "components")
    if isinstance(comps, property):  # a friction law: shear, or all three without sigma_n
        return "shear (1, 3); all (1, 2, 3) without `sigma_n`"
    names = {(2,): "normal (2)", (1, 3): "shear (1, 3)", (1, 2, 3): "all (1, 2, 3)"}
    return names.get(tuple(comps), str(tuple(comps)))


def law_section(kind: str, cls) -> list[str]:
    from cracklab.laws.base import parameter_docs
    from cracklab.model.scene_io import section_schema

    if not cls.example:
        raise SystemExit(f"the law {kind!r} has no example: give {cls.__name__} an `example`, a small TOML scene")
    schema = section_schema("law", cls)
    docs = parameter_docs(cls)
    lines = [f"### `kind = \"{kind}\"`", "", f"`{cls.__name__}`, acting on {components(cls)}. "
             + first_paragraph(cls.__doc__), ""]
    rows = []
    for f in dataclasses.fields(cls):
        unit, pkind, accepted, doc = docs[f.name]
        if accepted is None:
            accepted = "true or false at each node" if pkind == "mask" else "-"
        value = VALUE[schema[f.name][0]]
        if pkind == "mask" or (pkind == "option" and value in ("string", "boolean")):
            unit = "-"
        if pkind == "scalar":
            value = "number"
        rows.append((f"`{f.name}`", value, unit, accepted, default(f), doc))
    lines += key_table(rows)
    state = cls.state_variables
    lines += ["", "State variables (`record.fields`): " + (", ".join(
        f"`{n}` ({long}, {unit})" for n, (long, unit) in state.items()) or "none") + ".", ""]
    lines += ["```toml", cls.example.rstrip("\n"), "```", ""]
    return lines


def saved_lines() -> tuple[int, int]:
    """Lines of the TOML file ``Scene.to_toml(path)`` writes for a 128 x 64 random-toughness
    scene, and of its TOML text with the fields inline."""
    import tempfile

    from cracklab import scenes

    scene = scenes.random_toughness(n1=128, n3=64)
    with tempfile.TemporaryDirectory() as tmp:
        saved = len(scene.to_toml(Path(tmp) / "scene.toml").read_text().splitlines())
    return saved, len(scene.to_toml().splitlines())


def render() -> str:
    from cracklab.laws import LAWS
    from cracklab.model.keys import FILE_KEYS, TOP_KEYS, UNIT_KEYS
    from cracklab.model.scene import Scene
    from cracklab.model.scene_io import section_classes

    lines = [HEADER.rstrip("\n")]
    lines += [row(f"`{k}`", key.accepted, key.doc) for k, key in FILE_KEYS.items()]
    saved, inline = saved_lines()
    lines.append(REFERENCE_RULES.rstrip("\n").format(saved=saved, inline=inline))
    lines += ["", "## Top level", ""]
    fields = {f.name: f for f in dataclasses.fields(Scene)}
    rows = [(f"`{k}`", {"name": "string"}.get(k, "number"), key.unit, key.accepted, default(fields[k]), key.doc)
            for k, key in TOP_KEYS.items()]
    rows.append(("`[units]`", "table", "-", "the three keys below, or none", "all `\"1\"`",
                 "the units of the scene's quantities"))
    for section in ("material", "grid", "law", "loading", "record", "numerics", "sequence"):
        rows.append((f"`[{section}]`", "table", "-", "below", "*required*" if section in ("material", "grid", "law")
                     else "*absent*" if section == "sequence" else "every key at its default",
                     "a sequence of earthquakes (docs/guide/sequences.md)" if section == "sequence" else ""))
    rows.append(("`[materials.top]`, `[materials.bottom]`", "tables", "-", "the keys of `[material]`", "*absent*",
                 "the half spaces x2 > 0 and x2 < 0, instead of `[material]`; two different materials make a "
                 "bimaterial interface"))
    lines += key_table(rows)
    lines += ["", "## `[units]`", "", "All three or none; default `\"1\"` each (a dimensionless scene). Each is a "
              "UDUNITS-2 unit string, the units the CF conventions write (parsed by cf-units), that is a positive "
              "multiple of its quantity's SI unit (m, s, Pa): `\"km\"`, `\"ms\"`, `\"MPa\"`, `\"bar\"`; or "
              "`\"1\"`, that quantity dimensionless. Anything else is refused with the key named: a string UDUNITS "
              "does not know (`\"banana\"`), a unit of another quantity (a stress in `\"m\"`), an offset or "
              "negative unit, a date (`\"s since 2000-01-01\"`). The strings are written to the output's `units` "
              "attrs as given.", ""]
    lines += key_table([(f"`{k}`", "string", key.unit, key.accepted, '`"1"`', key.doc)
                        for k, key in UNIT_KEYS.items()])
    classes = section_classes()
    titles = {
        "material": "The half spaces' material (both sides).",
        "grid": "The periodic grid on the fracture plane (docs/reference/scenes.md, \"The grid\").",
        "loading": "tau0_j(x1, x3) times a function of time (docs/reference/equations.md, \"Loading\"); the nucleation keys "
                   "go together: all of `nucleation_radius`, `nucleation_time`, `nucleation_x1`, `nucleation_x3` and "
                   "one or both of `nucleation_dtau_1`, `nucleation_dtau_3`, or none.",
        "record": "What the run records: grid fields at a cadence, station series (`[record.stations]`), "
                  "optionally on a sub-region (`[record.region]`).",
        "numerics": "Scheme options.",
        "sequence": "A sequence of earthquakes and aseismic slip (docs/guide/sequences.md): the plate's loading, the "
                    "adaptive time step and the recording cadences. Absent: one rupture at the fixed step `beta`. "
                    "With it, `beta` and `[record]`'s `every` and `times` do not apply.",
    }
    for section in ("material", "grid"):
        lines += ["", f"## `[{section}]`", "", titles[section], ""]
        lines += key_table(section_rows(section, classes[section]))
    lines += ["", "## `[law]`", "", f"`kind` picks the law, one of {', '.join(f'`{k}`' for k in sorted(LAWS))}; the "
              "other keys are its parameters. Every law has `bonded`. A \"number\" parameter is one number, not a "
              "field.", ""]
    for kind in sorted(LAWS):
        lines += law_section(kind, LAWS[kind])
    for section in ("loading", "record", "numerics", "sequence"):
        lines += [f"## `[{section}]`", "", titles[section], ""]
        lines += key_table(section_rows(section, classes[section]))
        lines.append("")
    return "\n".join(lines)


def examples_of(text: str) -> list[str]:
    """The bodies of the ```toml blocks of the page that are whole scenes (they have t_end)."""
    blocks = re.findall(r"^```toml[ \t]*\n(.*?)^```[ \t]*$", text, re.S | re.M)
    return [b for b in blocks if re.search(r"^t_end\s*=", b, re.M)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if docs/reference/toml.md is out of date")
    args = ap.parse_args(argv)
    text = render()
    if args.check:
        ok = PAGE.exists() and PAGE.read_text() == text
        print("docs/reference/toml.md is up to date" if ok else "docs/reference/toml.md is out of date: run python docs/tools/toml_page.py")
        return 0 if ok else 1
    PAGE.write_text(text)
    print(f"wrote {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
