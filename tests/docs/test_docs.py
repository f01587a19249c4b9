"""The documentation stays true: its examples run, and the verification table in
docs/studies/verification.md matches the registry in tests/verification.py."""
from __future__ import annotations

import contextlib
import io
import math
import re
import tomllib
from pathlib import Path

import pytest
import verification
import xarray as xr
from click.testing import CliRunner

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
EXAMPLE_PAGES = ("README.md", "docs/guide/getting_started.md")
FENCE = re.compile(r"^```([\w-]*)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def blocks(page: str, lang: str) -> list[str]:
    text = (ROOT / page).read_text()
    return [body for tag, body in FENCE.findall(text) if tag == lang]


def run_blocks(page: str) -> str:
    """Execute the ```python blocks of a page in order, in one namespace; return stdout."""
    code = blocks(page, "python")
    assert code, f"{page} has no python examples"
    namespace = {"__name__": "__docs__"}
    out = io.StringIO()
    for i, body in enumerate(code):
        with contextlib.redirect_stdout(out):
            try:
                exec(compile(body, f"{page} [python block {i + 1}]", "exec"), namespace)
            except Exception as exc:
                raise AssertionError(f"{page}: python block {i + 1} failed: {exc!r}\n{body}") from exc
    return out.getvalue()


@pytest.mark.parametrize("page", EXAMPLE_PAGES)
def test_python_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    run_blocks(page)


def test_readme_output_is_what_the_example_prints(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    printed = run_blocks("README.md")
    shown = blocks("README.md", "text")
    assert shown and printed.strip() == shown[0].strip(), printed


def test_bad_input_output_is_what_the_example_prints(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = [b for b in blocks("docs/guide/getting_started.md", "python") if "except InputError" in b]
    assert len(code) == 1
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code[0], "bad-input example", "exec"), {"__name__": "__docs__"})
    shown = [b for b in blocks("docs/guide/getting_started.md", "text") if "grid.n3" in b]
    assert shown and [line.rstrip() for line in out.getvalue().strip().splitlines()] == \
        [line.rstrip() for line in shown[0].strip().splitlines()]


def test_readme_quick_start_is_two_commands():
    text = (ROOT / "README.md").read_text()
    quick = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = [body.strip() for tag, body in FENCE.findall(quick)]
    assert commands == ["python3 bootstrap.py demo", "python3 bootstrap.py test"]


def test_toml_scene_runs_from_the_command_line(tmp_path, monkeypatch):
    """The TOML scene of getting_started.md, with the two `cracklab run` commands shown there."""
    from cracklab.cli import main

    (toml,) = blocks("docs/guide/getting_started.md", "toml")
    tomllib.loads(toml)
    (sh,) = [b for b in blocks("docs/guide/getting_started.md", "sh") if "cracklab run" in b]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scene.toml").write_text(toml)
    for line in sh.strip().splitlines():
        args = line.split()
        assert args[0].endswith("cracklab") and args[1] == "run", line
        res = CliRunner().invoke(main, args[1:])
        assert res.exit_code == 0, (line, res.output)
    a = xr.open_zarr(tmp_path / "scene.zarr", consolidated=False)
    b = xr.open_zarr(tmp_path / "again.zarr", consolidated=False)
    assert float(a.delta_3.isel(t=-1).max()) > 0
    xr.testing.assert_allclose(a.delta_3, b.delta_3)


def anchors(page: Path) -> set[str]:
    """GitHub-style anchors of the headings of a Markdown page."""
    out = set()
    for line in FENCE.sub("", page.read_text()).splitlines():
        if line.startswith("#"):
            title = line.lstrip("#").strip().lower()
            out.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return out


def doc_pages() -> list[Path]:
    """The Markdown pages of docs/ (in its folders; not the site's build or gallery)."""
    return sorted(p for p in DOCS.rglob("*.md") if not {"_build", "gallery"} & set(p.relative_to(DOCS).parts))


def test_docs_links_resolve():
    pages = [ROOT / "README.md", *doc_pages()]
    for page in pages:
        text = "\n".join(line for line in FENCE.sub("", page.read_text()).splitlines()
                         if not line.startswith("    "))  # indented code
        prose = re.sub(r"`[^`\n]*`", "", text)
        for target, anchor in re.findall(r"\]\(([^)#\s]+)(?:#([^)]*))?\)", prose):
            if "://" in target:
                continue
            assert (page.parent / target).exists(), f"{page.name}: broken link {target}"
            assert (page.parent / target).resolve().is_relative_to(ROOT), f"{page.name}: links outside the repository: {target}"
            if anchor:
                assert anchor in anchors(page.parent / target), f"{page.name}: broken anchor {target}#{anchor}"
    index = (DOCS / "index.md").read_text()
    for page in doc_pages():
        rel = page.relative_to(DOCS).as_posix()
        if rel not in ("index.md", "site/readme.md"):
            assert f"]({rel})" in index, f"docs/index.md does not link {rel}"


# ----------------------------------------------------------------------------- verification
def table() -> dict:
    return verification.parse_table((DOCS / "studies" / "verification.md").read_text())


def test_registry_rows_are_well_formed():
    assert len({r[0] for r in verification.ROWS}) == len(verification.ROWS)
    assert verification.OUTCOME_ROWS <= set(verification.BY_ID)
    for rid, nodeid, reference, quantity, tol in verification.ROWS:
        for text in (rid, nodeid, reference, quantity):
            assert "|" not in text and "`" not in text and "\n" not in text, (rid, text)
        assert isinstance(tol, (int, float)) and tol >= 0, rid
        # the node id names an existing test module (and test function)
        path, _, func = nodeid.partition("::")
        source = (ROOT / path).read_text()
        if func:
            assert f"def {func.split('[')[0]}(" in source, (rid, nodeid)
        if rid not in verification.OUTCOME_ROWS:
            assert "check(" in source, f"{path} never calls verification.check ({rid})"


def test_every_row_is_in_the_docs_with_its_tolerance():
    rows = table()
    assert list(rows) == [r[0] for r in verification.ROWS], \
        "docs/studies/verification.md rows differ from tests/verification.py ROWS; rerun with " \
        "CRACKLAB_WRITE_VERIFICATION=1 (see docs/studies/verification.md)"
    for rid, nodeid, reference, quantity, tol in verification.ROWS:
        cells = rows[rid]
        assert cells["test"] == verification.first_cell((rid, nodeid)), rid
        assert cells["reference"] == reference and cells["quantity"] == quantity, rid
        assert float(cells["tolerance"]) == tol, f"{rid}: tolerance {cells['tolerance']} in the docs, {tol} in the tests"


def test_every_achieved_value_is_within_tolerance():
    for rid, cells in table().items():
        tol = verification.tolerance(rid)
        try:
            achieved = float(cells["achieved"])
        except ValueError:
            pytest.fail(f"{rid}: achieved is {cells['achieved']!r}, not a number")
        assert not math.isnan(achieved) and achieved <= tol, f"{rid}: achieved {achieved} > tolerance {tol}"


def test_check_records_and_asserts():
    rid = "penny"
    before = dict(verification.ACHIEVED)
    try:
        verification.check(rid, 0.0)
        with pytest.raises(AssertionError, match="penny.*exceeds the tolerance 0.02"):
            verification.check(rid, 0.5)
        assert verification.ACHIEVED[rid] == 0.5
        with pytest.raises(AssertionError):
            verification.check(rid, float("nan"))
        with pytest.raises(KeyError, match="unknown verification row"):
            verification.check("no-such-row", 0.0)
    finally:
        verification.drain()  # not a real measurement: keep it out of the table
        verification.ACHIEVED.clear()
        verification.ACHIEVED.update(before)


def test_table_round_trip():
    achieved = {r[0]: (0 if r[0] in verification.OUTCOME_ROWS else r[4] / 2) for r in verification.ROWS}
    text = f"intro\n{verification.START}\nold\n{verification.END}\noutro\n"
    new = verification.replace_table(text, verification.render_table(achieved))
    assert new.startswith("intro\n") and new.endswith("\noutro\n")
    rows = verification.parse_table(new)
    assert list(rows) == [r[0] for r in verification.ROWS]
    for rid, cells in rows.items():
        assert float(cells["achieved"]) == pytest.approx(float(verification.format_value(achieved[rid])))


# ----------------------------------------------------------------------------- measured tables
def markdown_tables(text: str) -> list[list[str]]:
    """The Markdown tables of a page, each as its list of lines."""
    tables, current = [], []
    for line in text.splitlines():
        if line.startswith("|"):
            current.append(line.strip())
        elif current:
            tables.append(current)
            current = []
    if current:
        tables.append(current)
    return tables


def test_stability_table_matches_cracklab_stability():
    from cracklab.solver.stability import gamma_max

    text = (DOCS / "reference" / "equations.md").read_text()
    (tab,) = [t for t in markdown_tables(text) if t[0].startswith("| scheme | mode I")]
    shown = {}
    for line in tab[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        shown[cells[0].split(",")[0]] = dict(zip(("I", "II", "III"), map(float, cells[1:])))
    assert shown == {f: {m: round(gamma_max(f, m, 0.25, measured=True), 3) for m in ("I", "II", "III")}
                     for f in ("displacement", "velocity", "product")}


def test_stability_nu_table_matches_cracklab_stability():
    """The table of limits against nu in stability.md is cracklab.solver.stability.LIMITS."""
    from cracklab.solver.stability import LIMITS, NU_NODES

    text = (DOCS / "reference" / "stability.md").read_text()
    (tab,) = [t for t in markdown_tables(text) if t[0].startswith("| nu |")]
    cols = [c.strip().split() for c in tab[0].strip("|").split("|")[1:]]
    rows = [[float(c) for c in line.strip("|").split("|")] for line in tab[2:]]
    assert [r[0] for r in rows] == list(NU_NODES)
    for k, (scheme, mode) in enumerate(cols, start=1):
        # the page shows 3 decimals of the measured limit, the code keeps 4
        assert [r[k] for r in rows] == pytest.approx(list(LIMITS[scheme][mode]), abs=6e-4), (scheme, mode)


def test_every_law_has_its_row_in_the_toml_reference():
    """docs/reference/scenes.md lists every registered law with exactly its parameters and state."""
    from cracklab.laws import LAWS

    text = (DOCS / "reference" / "scenes.md").read_text()
    (tab,) = [t for t in markdown_tables(text) if t[0].startswith("| kind | class | acts on")]
    rows = {}
    for line in tab[2:]:
        kind, cls, _, params, state = [c.strip() for c in line.strip("|").split("|")]
        rows[kind.strip("`")] = (cls.strip("`"), params, state)
    assert set(rows) == set(LAWS)
    for kind, law in LAWS.items():
        cls, params, state = rows[kind]
        assert cls == law.__name__
        assert params == ", ".join(f"`{n}` ({u}, {k})" for n, (u, k) in law.parameters().items())
        assert state == (", ".join(f"`{n}` ({u})" for n, (_, u) in law.state_variables.items()) or "-")


def test_modal_scheme_tables_match_the_study():
    """The two tables of the 12-scheme study in verification.md are what
    studies/modal_schemes.py prints (the figure is not redrawn here)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("modal_schemes", ROOT / "studies" / "modal_schemes.py")
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    pfs = {(s, g): study.pf(s, g) for s in study.SCHEMES for g in study.GAMMAS}
    rates = {(s, g): study.growth(s, g) for s in study.SCHEMES for g in study.GAMMAS}
    tables = ["\n".join(t) for t in markdown_tables((DOCS / "studies" / "verification.md").read_text())]
    assert study.markdown(pfs, study.fmt_pf) in tables
    assert study.markdown(rates, study.fmt_growth) in tables


# ----------------------------------------------------------------------------- pages against the code
def test_periodic_crack_example_prints_what_the_page_says(tmp_path, monkeypatch):
    """getting_started's plane periodic-crack example, run alone: the slip it prints is the
    one the paragraph above it quotes (0.5773 against 0.5722), within 1 % of exact."""
    monkeypatch.chdir(tmp_path)
    (code,) = [b for b in blocks("docs/guide/getting_started.md", "python") if "periodic_row_opening" in b]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "periodic-crack example", "exec"), {"__name__": "__docs__"})
    m = re.fullmatch(r"1 centre slip (\d\.\d{4}), exact (\d\.\d{4})", out.getvalue().strip())
    assert m, out.getvalue()
    slip, exact = m.groups()
    text = (ROOT / "docs" / "guide" / "getting_started.md").read_text()
    assert f"({slip} against {exact})" in text, (slip, exact)
    assert abs(float(slip) / float(exact) - 1) < 0.01


def test_ensembles_quick_start_runs_alone(tmp_path, monkeypatch):
    """docs/guide/ensembles.md's quick start: its study is the demo's study file, and its Python
    block runs on its own in a fresh namespace (its imports suffice) on that study with
    smaller grids, printing the table of diameter, contrast and final crack length."""
    import functools

    from cracklab import ensemble

    text = (DOCS / "guide" / "ensembles.md").read_text()
    quick = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    study = [body for tag, body in FENCE.findall(quick) if tag == "toml"][0]
    assert tomllib.loads(study) == tomllib.loads((ROOT / "studies" / "asperity_ensemble" / "study.toml").read_text())
    code = [body for tag, body in FENCE.findall(quick) if tag == "python"][0]
    small = study.replace("n1 = 128", "n1 = 32").replace("n3 = 64", "n3 = 16").replace("t_end = 4.0", "t_end = 0.5")
    small = small.replace("record.every = 16", "record.every = 8")
    assert small.count("= 32") == 1 and "t_end = 0.5" in small
    (tmp_path / "studies" / "asperity_ensemble").mkdir(parents=True)
    (tmp_path / "studies" / "asperity_ensemble" / "study.toml").write_text(small)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(ensemble, "run_study", functools.partial(ensemble.run_study, scheduler="synchronous",
                                                                 progress=False))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "docs/guide/ensembles.md, quick start", "exec"), {"__name__": "__docs__"})
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("9 members: 9 ran"), lines[0]
    header = next(line for line in lines if "crack_length" in line).split()
    assert header[:3] == ["diameter", "contrast", "crack_length"], header


def test_readme_says_how_to_build_and_open_the_site_and_ci_builds_it():
    """The README's site command is bootstrap.py's, with the page bootstrap.py names; CI
    (.ci/run) runs the suite through bootstrap.py, whose lock pins the site's tools, so the
    site's test (tests/docs/test_site.py: -W -n) runs there, unskipped."""
    import importlib.util

    readme = (ROOT / "README.md").read_text()
    assert "```sh\npython3 bootstrap.py docs\n```" in readme and "docs/_build/html/index.html" in readme
    spec = importlib.util.spec_from_file_location("bootstrap", ROOT / "bootstrap.py")
    boot = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(boot)
    assert boot.SITE == ROOT / "docs" / "_build" / "html" and "docs" in boot.USAGE
    ci = (ROOT / ".ci" / "run").read_text()
    assert "bootstrap.py test" in ci
    lock = (ROOT / "environment.lock").read_text()
    for package in ("sphinx", "myst-parser", "sphinx-gallery"):
        assert re.search(rf"^{package}==[\d.]+ \\", lock, flags=re.M), package
    site_test = (ROOT / "tests" / "docs" / "test_site.py").read_text()
    assert 'if not os.environ.get("CI"):' in site_test and '"-W"' in site_test and '"-n"' in site_test


def test_the_demo_times_agree_between_readme_and_getting_started():
    """The demo's run time is a measurement on a quiet host, which no test can repeat; the
    two pages that quote it quote the same figures."""
    readme = (ROOT / "README.md").read_text().split("## Quick start", 1)[1].split("\n## ", 1)[0]
    first = (ROOT / "docs" / "guide" / "getting_started.md").read_text().split("## First run", 1)[1].split("\n## ", 1)[0]

    def times(text):
        return re.findall(r"about (\d+) s[^(]*\((\d+) s the first time", " ".join(text.split()))
    assert times(readme) and times(readme) == times(first), (times(readme), times(first))


# ----------------------------------------------------------------------------- lists the code holds
def section(text: str, heading: str) -> str:
    """The body of the section under a Markdown heading (up to the next heading of any level)."""
    body = text.split(heading + "\n", 1)[1]
    return re.split(r"^#{1,6} ", body, maxsplit=1, flags=re.M)[0]


def test_getting_started_builder_table_lists_every_builder():
    from cracklab.scenes import BUILDERS

    text = (DOCS / "guide" / "getting_started.md").read_text()
    (tab,) = [t for t in markdown_tables(text) if t[0].startswith("| builder | problem")]
    names = [re.match(r"\| `(\w+)\(", line).group(1) for line in tab[2:]]
    assert names == list(BUILDERS), names
    # the arguments shown are the builder's: `k=` a required one, `k=v` its default
    import ast
    import inspect

    from cracklab import scenes

    for line in tab[2:]:
        name, args = re.match(r"\| `(\w+)\((.*?)\)` \|", line).groups()
        params = inspect.signature(getattr(scenes, name)).parameters
        for arg in (a.strip() for a in re.split(r",\s*(?![^()]*\))", args) if a.strip() not in ("", "...")):
            key, _, value = arg.partition("=")
            assert key in params, (name, key)
            if value:
                assert ast.literal_eval(value) == params[key].default, (name, key, value)
            else:
                assert params[key].default is inspect.Parameter.empty, (name, key)


def test_ensembles_lists_every_builder_and_the_refusal_names_them():
    from cracklab.scenes import BUILDERS

    text = (DOCS / "guide" / "ensembles.md").read_text()
    own = " ".join(section(text, "### Your own builders").split("2. builders registered")[0].split())
    listed = re.findall(r"`(\w+)`", own.split("`cracklab.scenes.BUILDERS`:", 1)[1])
    assert listed == list(BUILDERS), listed
    (error,) = [b for tag, b in FENCE.findall(text) if tag == "text" and "is not a scene builder" in b]
    registered = error.split("registered: ", 1)[1].split(". Register", 1)[0].split(", ")
    assert registered == sorted(BUILDERS), registered


def test_getting_started_command_table_lists_every_command():
    from cracklab.cli import main

    text = (DOCS / "guide" / "getting_started.md").read_text()
    (tab,) = [t for t in markdown_tables(text) if t[0].startswith("| command | what it does")]
    commands = {re.match(r"\| `cracklab (\w+)", line).group(1) for line in tab[2:]}
    assert commands == set(main.commands), commands ^ set(main.commands)


def test_builder_signatures_on_the_scenes_page_are_the_code_s():
    """Every `scenes.NAME(*, ...)` block of scenes.md has the builder's parameters and
    defaults, in order."""
    import ast
    import inspect

    from cracklab import scenes

    text = (DOCS / "reference" / "scenes.md").read_text()
    calls = re.findall(r"^scenes\.(\w+)(\(\*,.*?\))\s*$", "\n".join(b for tag, b in FENCE.findall(text)
                                                                     if tag == "python"), flags=re.M | re.S)
    assert {"asperity_row", "random_toughness", "tpv5", "tpv6", "tpv101", "tpv103"} <= {n for n, _ in calls}
    for name, args in calls:
        tree = ast.parse(f"def f{args}: pass").body[0].args
        shown = {a.arg: ast.literal_eval(d) for a, d in zip(tree.kwonlyargs, tree.kw_defaults)}
        params = inspect.signature(getattr(scenes, name)).parameters
        assert list(shown) == list(params), name
        for p, value in shown.items():
            default = params[p].default
            if default is inspect.Parameter.empty:
                continue
            assert value == default, (name, p, value, default)


def test_no_page_names_a_file_outside_the_repository():
    for page in [ROOT / "README.md", *doc_pages()]:
        text = page.read_text()
        assert not re.search(r"shared/(reference|API\.md)", text), f"{page.name} names a file outside the repository"


def test_the_demo_time_on_the_ensembles_page_is_the_readme_s():
    readme = (ROOT / "README.md").read_text().split("## Quick start", 1)[1].split("\n## ", 1)[0]
    demo = section((DOCS / "guide" / "ensembles.md").read_text(), "## The demo")

    def times(text):
        return re.findall(r"about (\d+) s[^(]*\((\d+) s the first time", " ".join(text.split()))
    assert times(readme) and times(readme) == times(demo), (times(readme), times(demo))
