"""Validation never crashes: scene TOML files of every builder, mutated by hypothesis.

Loading and validating a mutated file either gives a valid Scene (one that serialises
again, with a finite time step, at least one step and finite derived quantities) or
raises one cracklab InputError naming the field, with no chained exception; never
another exception (OverflowError, ZeroDivisionError, UnicodeDecodeError, RecursionError,
TypeError, ...). The mutations replace, scale, delete and add values anywhere in the
file (nested list elements and table entries included) with extreme floats and integers,
booleans, strings, dates, nested lists and tables, and corrupt the bytes of the file.
Deterministic in CI (derandomize, no example database); CRACKLAB_FUZZ_EXAMPLES=5000
CRACKLAB_HYPOTHESIS_RANDOM=1 for a longer random search. See docs/guide/reliability.md,
"Input validation never crashes"."""
import copy
import datetime
import math
import os
import tomllib

import numpy as np
import pytest
import tomli_w
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import cracklab
from cracklab import InputError, Scene, scenes
from cracklab import ensemble as E
from cracklab.model.scene_io import scene_from_toml, scenes_equal

EXAMPLES = int(os.environ.get("CRACKLAB_FUZZ_EXAMPLES", "400"))
RANDOM = os.environ.get("CRACKLAB_HYPOTHESIS_RANDOM") == "1"
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=not RANDOM, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
SECTIONS = ("material", "grid", "law", "loading", "record", "numerics")
FIELD_HEADS = SECTIONS + ("t_end", "beta", "name", "units", "scene", "toml")


def _bases():
    """Valid scenes of every builder (small grids), plus a windowed cohesive scene with
    region, stations and times, and one in SI units."""
    out = [scenes.lamb(n=8, t_end=0.2),
           scenes.elliptical_crack(n=8, a=0.25, b=0.25, t_end=0.1),
           scenes.periodic_cracks(n=8, c=0.25, mode="II", t_end=0.1),
           scenes.kostrov(n=16, speed=0.5, t_end=0.2),
           scenes.tpv3(dx=3000.0, t_end=0.5),
           scenes.asperity_row(n1=16, n3=8, t_end=0.3),
           scenes.random_toughness(n1=16, n3=8, t_end=0.3)]
    crack = out[1]
    out.append(crack.replace(
        name="windowed", record=cracklab.Record(fields=("delta_2", "v_2"), times=(0.0, 0.05),
                                                region={"x1": (0.0, 0.5), "x3": (0.25, 1.0)},
                                                stations={"a": (0.5, 0.5)}),
        numerics=cracklab.Numerics(engine="direct", window=5.0, rupture_threshold=1e-3)))
    out.append(out[4].replace(name="tpv3_si", units={"length": "m", "time": "s", "stress": "Pa"}))
    return out


BASES = _bases()
TEXTS = [s.to_toml() for s in BASES]
DATA = [tomllib.loads(t) for t in TEXTS]

EXTREME_FLOATS = [1.7e308, -1.7e308, 1e300, -1e300, 1e-300, 5e-324, -5e-324, 2.2250738585072014e-308,
                  math.inf, -math.inf, math.nan, 0.0, -0.0, 1e100, 1e-100, 1.0000000000000002e100,
                  9.99e-101, 1e150, 1e-150, 1e30, 1e-30, -1.0, 0.5, 1.0]
EXTREME_INTS = [0, 1, -1, 2, 3, 17, 2**16, 2**16 + 2, 2**26, 2**31, 2**53 + 1, 2**62, 2**63 - 1, -2**63]
scalars = st.one_of(
    st.sampled_from(EXTREME_FLOATS), st.sampled_from(EXTREME_INTS), st.floats(), st.integers(-2**63, 2**63 - 1),
    st.booleans(), st.text(max_size=6), st.sampled_from(["", "1.0", "inf", "nan", "lamb", "\x00", "é\u202e"]),
    st.dates(), st.datetimes(), st.times())
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=4), inner, max_size=3)), max_leaves=8)


def _nested(depth, leaf=1.0):
    v = leaf
    for _ in range(depth):
        v = [v]
    return v


odd_values = st.one_of(values, st.integers(2, 80).map(_nested),
                       st.lists(st.lists(st.sampled_from(EXTREME_FLOATS), min_size=1, max_size=16), min_size=1,
                                max_size=16))


def _paths(data):
    """Every path to a value in the nested data (tables, lists, leaves)."""
    out = []
    stack = [((), data)]
    while stack:
        path, value = stack.pop()
        if path:
            out.append(path)
        if isinstance(value, dict):
            stack.extend((path + (k,), v) for k, v in value.items())
        elif isinstance(value, list) and len(path) < 4:
            # a field's rows and elements: a few of them
            idx = sorted({0, len(value) - 1, len(value) // 2}) if value else []
            stack.extend((path + (i,), value[i]) for i in idx)
    return sorted(out, key=repr)


def _get(data, path):
    for p in path:
        data = data[p]
    return data


def _set(data, path, value):
    _get(data, path[:-1])[path[-1]] = value


def _delete(data, path):
    parent = _get(data, path[:-1])
    del parent[path[-1]]


@st.composite
def mutated(draw):
    """(index of the base, mutated data, list of mutations)."""
    i = draw(st.integers(0, len(DATA) - 1))
    data = copy.deepcopy(DATA[i])
    done = []
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        how = draw(st.sampled_from(["replace", "replace", "number", "number", "scale", "scale", "delete", "add"]))
        if not paths:
            how = "add"
        if how == "add":
            tables = [()] + [p for p in paths if isinstance(_get(data, p), dict)]
            where = draw(st.sampled_from(tables))
            key = draw(st.sampled_from(["colour", "kind", "n1", "L1", "every", "times", "window", "x1", "a"]))
            _get(data, where)[key] = draw(odd_values)
            done.append(("add", where + (key,)))
            continue
        path = draw(st.sampled_from(paths))
        old = _get(data, path)
        numeric = isinstance(old, (int, float)) and not isinstance(old, bool)
        if how == "delete":
            _delete(data, path)
        elif how == "number":         # another number where a number is: extreme but often valid
            if not numeric:
                continue
            _set(data, path, draw(st.one_of(st.sampled_from(EXTREME_FLOATS), st.floats(),
                                            st.sampled_from(EXTREME_INTS))))
        elif how == "scale":
            if not numeric:
                continue
            factor = draw(st.sampled_from([1e300, 1e-300, 1e200, 1e-200, 1e150, 1e-150, 1e100, 1e-100, 1e50,
                                           1e-50, -1.0, 0.0, 2.0 ** 1023, 2.0 ** -1074]))
            _set(data, path, old * factor)
        else:
            _set(data, path, draw(odd_values))
        done.append((how, path))
    return i, data, done


def _check_error(exc, data=None):
    assert isinstance(exc, InputError), repr(exc)
    assert exc.__cause__ is None and (exc.__context__ is None or exc.__suppress_context__), repr(exc)
    text = str(exc)
    assert text.startswith(f"{exc.field}: ") and len(text) > len(exc.field) + 2, text
    head = exc.field.split(".")[0]
    # a section field, the file, or an unknown key given at the top level
    assert head in FIELD_HEADS or head in (data or {}) or "unknown key; accepted:" in text, text


def _check_scene(scene):
    """What a valid scene guarantees: finite derived quantities, at least one step, a
    lossless round trip through TOML."""
    assert isinstance(scene, Scene)
    m, g = scene.material, scene.grid
    for x in (m.rho, m.cd, m.cR, m.eta(1), m.eta(2), g.dx1, g.dx3, g.q_max(), scene.dt):
        assert math.isfinite(x) and x > 0 and x >= np.finfo(float).tiny, (x, scene)
    assert 1 <= scene.nsteps <= cracklab.model.scene.MAX_STEPS
    again = Scene.from_toml(scene.to_toml())
    assert scenes_equal(again, scene)


OUTCOMES = {}       # outcome -> count, reported by test_report_outcomes (run with -s)


def load(source, kind="scene"):
    """scene_from_toml of ``source``: a Scene, or the InputError (anything else escapes)."""
    try:
        out = scene_from_toml(source)
    except InputError as exc:
        out = exc
    key = (kind, "scene" if isinstance(out, Scene) else f"InputError {out.field.split('.')[0]}")
    OUTCOMES[key] = OUTCOMES.get(key, 0) + 1
    return out


@FUZZ
@given(mutated())
def test_mutated_scene_toml_gives_a_valid_scene_or_one_input_error(case):
    i, data, done = case
    try:
        text = tomli_w.dumps(data)
    except (TypeError, ValueError, RecursionError):
        assume(False)                 # not representable in TOML (e.g. a list of mixed tables)
    out = load(text)
    if isinstance(out, InputError):
        _check_error(out, data)
    else:
        _check_scene(out)


@FUZZ
@given(st.integers(0, len(TEXTS) - 1), st.data())
def test_corrupted_bytes_give_a_valid_scene_or_one_input_error(i, draw):
    """The file's bytes with bytes replaced, inserted or cut (invalid UTF-8, NUL bytes,
    brackets nested thousands deep, pure binary)."""
    raw = bytearray(TEXTS[i].encode())
    how = draw.draw(st.sampled_from(["replace", "insert", "truncate", "binary", "deep"]))
    at = draw.draw(st.integers(0, len(raw)))
    if how == "replace" and raw:
        at = min(at, len(raw) - 1)
        chunk = draw.draw(st.binary(min_size=1, max_size=4))
        raw[at:at + len(chunk)] = chunk
    elif how == "insert":
        raw[at:at] = draw.draw(st.one_of(st.binary(min_size=1, max_size=8),
                                         st.sampled_from([b"\xff", b"\xc3", b"\x00", b"\xed\xa0\x80", b"[[", b"{"])))
    elif how == "truncate":
        del raw[at:]
    elif how == "binary":
        raw = bytearray(draw.draw(st.one_of(st.binary(max_size=64),
                                            st.just(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR"))))
    else:
        depth = draw.draw(st.sampled_from([33, 100, 500, 1000, 5000]))
        text = TEXTS[i].replace("t_end = ", "t_end = " + "[" * depth, 1)
        text = text.replace("\nbeta", "]" * depth + "\nbeta", 1) if draw.draw(st.booleans()) else text
        raw = bytearray(text.encode())
    out = load(bytes(raw), "bytes")
    if isinstance(out, InputError):
        _check_error(out)
    else:
        _check_scene(out)


# ---------------------------------------------------------------------------- study files
STUDY_BUILDERS = list(scenes.BUILDERS) + ["os:system", "subprocess:run", "np.save", "scenes.np", "builtins:eval",
                                          "cracklab.scenes:_crack_setup", "_require", "", "no_such"]


@settings(max_examples=max(EXAMPLES // 4, 50), deadline=None, derandomize=not RANDOM, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.sampled_from(STUDY_BUILDERS), st.dictionaries(st.sampled_from(
    ["n", "n1", "t_end", "beta", "law.tau_c", "record.every", "numerics.window", "command", "builder"]),
    odd_values, max_size=3), st.dictionaries(st.sampled_from(["n", "diameter", "p", "loading.tau0_2", "builder"]),
                                             st.lists(odd_values, max_size=3), max_size=2),
    st.lists(st.dictionaries(st.sampled_from(["builder", "n", "p", "seed"]),
                             st.one_of(st.sampled_from(STUDY_BUILDERS), odd_values), max_size=2), max_size=2),
    st.dictionaries(st.sampled_from(["entropy", "replicates", "name", "seed_arg", "colour"]), odd_values, max_size=2))
def test_mutated_study_files_plan_or_give_one_input_error(tmp_path_factory, builder, base, sweep, members, study):
    """load_study + plan of a STUDY.toml with any values: members, or one InputError
    (never an unregistered builder's members, never another exception)."""
    data = {"study": {"builder": builder, **study}, "base": base, "sweep": sweep, "members": members}
    try:
        text = tomli_w.dumps(data)
    except (TypeError, ValueError, RecursionError):
        assume(False)
    path = tmp_path_factory.mktemp("study") / "study.toml"
    path.write_text(text)
    try:
        s = E.load_study(path)
        planned = E.plan(s.base, s.sweep)
    except InputError as exc:
        _check_error_study(exc)
        return
    own = set(scenes.BUILDERS)
    assert planned and all(m.params["builder"] in own for m in planned), planned


def _check_error_study(exc):
    assert isinstance(exc, InputError), repr(exc)
    assert exc.__cause__ is None and (exc.__context__ is None or exc.__suppress_context__), repr(exc)
    assert str(exc).startswith(f"{exc.field}: ")


def test_the_fuzzers_reach_every_outcome():
    """The strategies are not vacuous: a few fixed mutations give a valid scene, an error
    naming a section field, and an error of the file itself."""
    data = copy.deepcopy(DATA[1])
    assert isinstance(load(tomli_w.dumps(data)), Scene)
    data["grid"]["L1"] = 1e300
    err = load(tomli_w.dumps(data))
    assert isinstance(err, InputError) and err.field == "grid.L1"
    err = load(b"\x89PNG\r\n\x1a\n")
    assert isinstance(err, InputError) and err.field == "toml"


def test_report_outcomes():
    """Runs after the fuzzers (in the same process): how the inputs ended (printed with -s);
    both valid scenes and errors must be reached, or the mutations are vacuous."""
    print("\nfuzz outcomes: " + ", ".join(f"{k[0]} -> {k[1]}: {v}" for k, v in sorted(OUTCOMES.items())))
    scenes_ = sum(v for (kind, out), v in OUTCOMES.items() if kind == "scene" and out == "scene")
    errors = sum(v for (kind, out), v in OUTCOMES.items() if kind == "scene" and out != "scene")
    if scenes_ + errors:
        assert scenes_ >= 0.05 * (scenes_ + errors) and errors >= 0.3 * (scenes_ + errors), OUTCOMES


if __name__ == "__main__":      # a longer search by hand
    pytest.main([__file__, "-q"])
