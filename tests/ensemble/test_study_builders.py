"""Study files run only registered builders: cracklab's own (scenes.BUILDERS), those
registered in Python (cracklab.register_builder) and entry points of the group
"cracklab.builders". Any other name is one InputError before any work starts (no store,
no module imported, nothing run), naming the registered builders."""
import importlib.metadata
import inspect
import sys
import textwrap

import pytest
from click.testing import CliRunner

import cracklab
from cracklab import ensemble as E
from cracklab import scenes
from cracklab.cli import main
from cracklab.errors import InputError
from cracklab.scenes import registry as builders

# names a study file might try: shell and process functions, eval, numpy reached through
# cracklab.scenes, dotted paths into cracklab, a private helper, public non-builders
REFUSED = [
    "os:system", "subprocess:run", "subprocess:Popen", "builtins:eval", "builtins:exec", "os.system",
    "np.save", "np:save", "scenes.np", "np", "numpy:save", "cracklab.scenes:np.save",
    "cracklab.scenes:_crack_setup", "_crack_setup", "cracklab.scenes:lamb", "cracklab.ensemble:run",
    "tpv3_station_name", "ellipse_mask", "random_field", "UNIT", "Material", "Scene", "beta_max",
    "check_positive", "__builtins__", "lamb.__globals__", "lamb ", "",
]

TINY = dict(n=16, t_end=0.05)


def tiny_lamb(*, n=16, t_end=0.05, p=1.0):
    """A registered test builder: Lamb's problem on a small grid, loaded with p."""
    scene = scenes.lamb(n=n, t_end=t_end)
    return scene.replace(loading=scene.loading.__class__(tau0_2=p), name="tiny_lamb")


@pytest.fixture
def canary(tmp_path, monkeypatch):
    """A module that, if a study could import it, would write a file on import."""
    flag = tmp_path / "imported.flag"
    (tmp_path / "canary_builders.py").write_text(textwrap.dedent(f"""
        import pathlib
        pathlib.Path({str(flag)!r}).write_text("imported")
        def build(**kw):
            pathlib.Path({str(flag)!r}).write_text("called")
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    sys.modules.pop("canary_builders", None)
    yield flag
    sys.modules.pop("canary_builders", None)


@pytest.fixture
def registry():
    """Restore the registrations after the test."""
    saved = dict(builders.REGISTERED)
    yield
    builders.REGISTERED.clear()
    builders.REGISTERED.update(saved)
    builders.ENTRY_POINT_CACHE.clear()


def _check_refused(err, field, name=None):
    assert err.field == field, str(err)
    text = str(err)
    assert "is not a scene builder registered with cracklab" in text or "must be the name" in text, text
    assert "registered: " in text or "must be the name" in text
    if "registered: " in text:
        for own in scenes.BUILDERS:
            assert own in text
        assert "cracklab.register_builder" in text and "cracklab.builders" in text
    assert err.__cause__ is None and (err.__context__ is None or err.__suppress_context__)


@pytest.mark.parametrize("name", REFUSED + ["canary_builders:build"])
def test_a_study_naming_an_unregistered_builder_is_refused_before_any_work(tmp_path, canary, name):
    marker = tmp_path / "shell.flag"
    study = tmp_path / "study.toml"
    study.write_text(f'[study]\nbuilder = "{name}"\n[base]\ncommand = "touch {marker}"\n'
                     f'args = ["touch", "{marker}"]\n')
    with pytest.raises(InputError) as err:
        E.load_study(study)
    _check_refused(err.value, "study.builder")
    # the command line: one error line, no store, nothing run, nothing imported
    store = tmp_path / "ens.zarr"
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(store), "--scheduler", "synchronous"])
    assert res.exit_code == 1 and isinstance(res.exception, SystemExit), res.output
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("Error: study.builder: "), res.output
    assert not store.exists() and not marker.exists()
    assert not canary.exists() and "canary_builders" not in sys.modules


@pytest.mark.parametrize("name", ["os:system", "np.save", "scenes.np", "builtins:eval", "cracklab.scenes:_crack_setup"])
def test_a_member_or_an_axis_naming_an_unregistered_builder_is_refused_before_the_store(tmp_path, name):
    marker = tmp_path / "shell.flag"
    store = tmp_path / "ens.zarr"
    cases = [
        (f'[study]\nbuilder = "lamb"\n[base]\nn = 16\nt_end = 0.05\n[[members]]\nbuilder = "{name}"\n'
         f'command = "touch {marker}"\n', "members[0].builder"),
        (f'[study]\nbuilder = "lamb"\n[base]\nn = 16\nt_end = 0.05\n[sweep]\nbuilder = ["lamb", "{name}"]\n',
         "sweep.builder"),
        (f'[study]\nbuilder = "lamb"\n[base]\nbuilder = "{name}"\ncommand = "touch {marker}"\n', "base.builder"),
    ]
    for text, field in cases:
        study = tmp_path / "study.toml"
        study.write_text(text)
        s = E.load_study(study)
        with pytest.raises(InputError) as err:
            E.plan(s.base, s.sweep)
        assert err.value.field == field, str(err.value)
        with pytest.raises(InputError) as err:
            E.run_study(study, store, scheduler="synchronous", progress=False)
        assert err.value.field == field
        res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(store), "--scheduler", "synchronous"])
        assert res.exit_code == 1 and res.output.startswith(f"Error: {field}: "), res.output
        assert not store.exists() and not marker.exists()
    # the same from Python
    for bad in (lambda: E.Builder(name), lambda: E.plan(E.Builder("lamb", **TINY), [{"builder": name}]),
                lambda: E.run(name, {"n": [16]}, store, scheduler="synchronous")):
        with pytest.raises(InputError) as err:
            bad()
        assert err.value.field.endswith("builder") and "registered" in str(err.value)
    assert not store.exists() and not marker.exists()


def test_cracklab_builders_are_a_fixed_named_set():
    """scenes.BUILDERS lists exactly the public scene builders of cracklab.scenes (the
    functions of its modules taking t_end, or years for a sequence); its other names are
    not builders."""
    public = {n for n, f in vars(scenes).items() if inspect.isfunction(f)
              and f.__module__.startswith(f"{scenes.__name__}.") and not n.startswith("_")
              and {"t_end", "years"} & set(inspect.signature(f).parameters)}
    assert set(scenes.BUILDERS) == public and len(scenes.BUILDERS) == len(public)
    assert {n: w for n, w in E.registered_builders().items() if w == "cracklab"} == dict.fromkeys(
        scenes.BUILDERS, "cracklab")
    for name in scenes.BUILDERS:
        assert E.resolve_builder(name) is getattr(scenes, name)


def test_a_registered_builder_runs_from_a_study_file(tmp_path, registry):
    study = tmp_path / "study.toml"
    study.write_text('[study]\nbuilder = "tiny_lamb"\n[base]\nn = 16\n[sweep]\np = [1.0, 2.0]\n')
    with pytest.raises(InputError, match="'tiny_lamb' is not a scene builder registered"):
        E.load_study(study)
    assert cracklab.register_builder("tiny_lamb", tiny_lamb) is tiny_lamb
    assert E.registered_builders()["tiny_lamb"] == "registered"
    res = E.run_study(study, tmp_path / "ens.zarr", scheduler="synchronous", progress=False)
    assert res.ok and len(res.members) == 2, res.summary()
    ens = E.open_ensemble(tmp_path / "ens.zarr")
    assert list(ens.p.values) == [1.0, 2.0] and set(ens.scene_name.values) == {"tiny_lamb"}
    # a member may name it too, and the workers' mapping is used when given
    members = E.plan(E.Builder("lamb", **TINY), [{"builder": "tiny_lamb", "p": 3.0}])
    assert members[0].params["builder"] == "tiny_lamb"
    E.unregister_builder("tiny_lamb")
    scene = E.build_scene(None, members[0].params, builders={"tiny_lamb": tiny_lamb})
    assert scene.name == "tiny_lamb" and float(scene.loading.tau0_2) == 3.0
    with pytest.raises(InputError, match="not a scene builder registered"):
        E.build_scene(None, members[0].params)


def test_register_builder_rules(registry):
    with pytest.raises(InputError, match="one of cracklab's own builders"):
        cracklab.register_builder("lamb", tiny_lamb)
    for name in ("", "  ", None, 3):
        with pytest.raises(InputError, match="non-empty string"):
            cracklab.register_builder(name, tiny_lamb)
    with pytest.raises(InputError, match="must be a function"):
        cracklab.register_builder("x", 42)

    @cracklab.register_builder("decorated")
    def decorated(*, n=16, t_end=0.05):
        return scenes.lamb(n=n, t_end=t_end)

    assert E.resolve_builder("decorated") is decorated
    cracklab.register_builder("decorated", decorated)              # the same function again: fine
    with pytest.raises(InputError, match="already registered to .*replace=True"):
        cracklab.register_builder("decorated", tiny_lamb)
    cracklab.register_builder("decorated", tiny_lamb, replace=True)
    assert E.resolve_builder("decorated") is tiny_lamb


def test_a_function_given_in_python_is_registered_under_its_name(registry):
    E.unregister_builder("test_study_builders:tiny_lamb")
    b = E.Builder(tiny_lamb, n=16)
    assert b.name == "test_study_builders:tiny_lamb" and b.func is tiny_lamb
    assert E.resolve_builder(b.name) is tiny_lamb
    assert E.Builder(scenes.lamb).name == "lamb"           # cracklab's own: by its name
    members = E.plan(b, {"p": [1.0, 2.0]})
    assert [m.params["builder"] for m in members] == [b.name] * 2
    with pytest.raises(InputError, match="module-level function"):
        E.Builder(lambda **kw: None)


def _entry_points(*eps):
    def entry_points(**kw):
        found = importlib.metadata.EntryPoints(eps)
        return found.select(**kw) if kw else found
    return entry_points


def test_entry_point_builders(tmp_path, monkeypatch, registry):
    eps = [importlib.metadata.EntryPoint("ep_lamb", "test_study_builders:tiny_lamb", E.ENTRY_POINT_GROUP),
           importlib.metadata.EntryPoint("lamb", "os:system", E.ENTRY_POINT_GROUP),     # cannot shadow
           importlib.metadata.EntryPoint("broken", "no_such_module_xyz:f", E.ENTRY_POINT_GROUP),
           importlib.metadata.EntryPoint("other_group", "os:system", "console_scripts")]
    monkeypatch.setattr(importlib.metadata, "entry_points", _entry_points(*eps))
    names = E.registered_builders()
    assert names["ep_lamb"] == "entry point test_study_builders:tiny_lamb"
    assert names["lamb"] == "cracklab" and "other_group" not in names
    assert E.resolve_builder("ep_lamb") is tiny_lamb and E.resolve_builder("lamb") is scenes.lamb
    study = tmp_path / "study.toml"
    study.write_text('[study]\nbuilder = "ep_lamb"\n[base]\nn = 16\n[sweep]\np = [1.0, 2.0]\n')
    s = E.load_study(study)
    assert [m.params["p"] for m in E.plan(s.base, s.sweep)] == [1.0, 2.0]
    res = E.run_study(study, tmp_path / "ens.zarr", scheduler="synchronous", progress=False)
    assert res.ok, res.summary()
    with pytest.raises(InputError, match="'broken': the entry point 'no_such_module_xyz:f'.*cannot be loaded") as err:
        E.resolve_builder("broken", "study.builder")
    assert err.value.field == "study.builder"
    with pytest.raises(InputError) as err:
        E.resolve_builder("other_group")
    assert "ep_lamb" in str(err.value) and "broken" in str(err.value)


def test_cli_sweep_import_registers_the_builders_of_a_module(tmp_path, monkeypatch, registry):
    (tmp_path / "my_builders.py").write_text(textwrap.dedent("""
        import cracklab

        @cracklab.register_builder("my_builders:lamb16")
        def lamb16(*, t_end=0.05, p=1.0):
            s = cracklab.scenes.lamb(n=16, t_end=t_end)
            return s.replace(loading=s.loading.__class__(tau0_2=p))
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    sys.modules.pop("my_builders", None)
    study = tmp_path / "study.toml"
    study.write_text('[study]\nbuilder = "my_builders:lamb16"\n[sweep]\np = [1.0]\n')
    store = tmp_path / "ens.zarr"
    args = ["sweep", str(study), "-o", str(store), "--scheduler", "synchronous"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1 and res.output.startswith("Error: study.builder: 'my_builders:lamb16' is not"), \
        res.output
    assert "my_builders" not in sys.modules and not store.exists()
    res = CliRunner().invoke(main, args + ["--import", "no_such_module_xyz"])
    assert res.exit_code == 1 and res.output.startswith("Error: --import: cannot import 'no_such_module_xyz'")
    res = CliRunner().invoke(main, args + ["--import", "my_builders"])
    assert res.exit_code == 0, res.output
    assert "1 member: 1 ran" in res.output
    sys.modules.pop("my_builders", None)


def test_docs_ensembles_own_builders_example_runs(tmp_path, monkeypatch, registry):
    """The example of docs/guide/ensembles.md, "Your own builders", prints what the page shows,
    and the refusal shown there is the message of that name."""
    import contextlib
    import io
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "ensembles.md").read_text()
    section = text.split("### Your own builders", 1)[1].split("\n### ", 1)[0]
    fence = re.compile(r"^```([\w-]*)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
    found = fence.findall(section)
    (code,) = [b for tag, b in found if tag == "python"]
    shown = [b for tag, b in found if tag == "text"]
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "docs/guide/ensembles.md", "exec"), {"__name__": "__docs__"})
    assert out.getvalue().strip() == shown[1].strip()
    with pytest.raises(InputError) as err:
        E.resolve_builder("os:system", "study.builder")
    shown_error = shown[0].strip().removeprefix("Error: ")
    names = ", ".join(sorted(E.registered_builders()))
    assert str(err.value) == shown_error.replace(
        "asperity_row, bp1, bp5, elliptical_crack, kostrov, lamb, periodic_cracks, random_toughness, tpv101, tpv102, "
        "tpv103, tpv104, tpv3, tpv5, tpv6", names)
