"""The documentation site (docs/conf.py) builds with Sphinx with warnings as errors and
every cross-reference checked (-W -n): the Markdown pages, the API reference from the
docstrings, and the gallery, whose examples/ scripts run during the build."""
from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"

if not os.environ.get("CI"):  # CI installs the docs extra from environment.lock: there, no skip
    pytest.importorskip("sphinx", reason="the docs extra is not installed (python3 bootstrap.py installs it)")
    pytest.importorskip("myst_parser")
    pytest.importorskip("sphinx_gallery")


def sphinx(src: Path, out: Path, *extra: str, conf: Path | None = None) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-b", "html", "-q",
           "-d", str(out / ".doctrees"), *extra]
    if conf is not None:
        cmd += ["-c", str(conf)]
    env = {**os.environ, "MPLBACKEND": "agg"}
    return subprocess.run([*cmd, str(src), str(out / "html")], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=600, stdin=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    res = sphinx(DOCS, out)
    assert res.returncode == 0, f"sphinx-build -W -n failed:\n{res.stderr[-6000:]}"
    return out / "html"


def test_every_page_is_on_the_site(site):
    """The glob toctree of docs/index.md takes every Markdown page, including new ones."""
    pages = sorted(p.relative_to(DOCS).with_suffix("").as_posix() for p in DOCS.rglob("*.md")
                   if not {"_build", "gallery"} & set(p.relative_to(DOCS).parts))
    assert "guide/getting_started" in pages and "reference/api" in pages
    for stem in pages:
        assert (site / f"{stem}.html").is_file(), stem
    nav = (site / "index.html").read_text()
    for stem in pages:
        if stem != "index":
            assert f'href="{stem}.html"' in nav, f"{stem} is not in the site's navigation"
    assert (site / "site" / "readme.html").is_file() and 'href="site/readme.html"' in nav


def test_api_reference_has_every_public_name(site):
    """Every name of docs/reference/api.md has its autodoc entry (an anchor) on the reference page."""
    import cracklab

    html = (site / "reference" / "docstrings.html").read_text()
    listed = (DOCS / "reference" / "api.md").read_text().split("\n## Promised", 1)[0]  # not the missing ones
    names = re.findall(r"^- `(cracklab\.[\w.]+)", listed, flags=re.M)
    assert len(names) > 50
    for name in names:
        assert f'id="{name}"' in html, f"{name} has no entry in the API reference"
    # the full docstring, not only its first sentence: the last words of its last paragraph
    text = " ".join(re.sub(r"<[^>]+>", "", html).split())
    last = " ".join(cracklab.simulate.__doc__.replace("``", "").split()[-6:])
    assert last in text, last
    from cracklab.cli import main

    for command in main.commands:
        assert f"Usage: cracklab {command}" in html, command


def test_gallery_runs_its_examples(site):
    """Each examples/plot_*.py has a gallery page with its printed output and a figure."""
    scripts = sorted((ROOT / "examples").glob("plot_*.py"))
    assert len(scripts) >= 3
    index = (site / "gallery" / "index.html").read_text()
    for script in scripts:
        page = site / "gallery" / f"{script.stem}.html"
        assert page.is_file() and f"{script.stem}.html" in index, script.name
        html = page.read_text()
        assert re.search(r'<img [^>]*src="[^"]*sphx_glr_' + script.stem + r'_\d+\.png"', html), script.name
        assert "sphx-glr-script-out" in html, f"{script.name}: no printed output"


def test_links_between_pages_resolve(site):
    """Markdown links between pages (with GitHub-style anchors) are links on the site."""
    html = (site / "guide" / "getting_started.html").read_text()
    assert 'href="environment.html"' in html
    assert 'href="../reference/stability.html#limits-for-every-poisson-ratio"' in html
    readme = (site / "index.html").read_text()
    assert 'href="site/readme.html"' in readme  # [README](../README.md)


def test_a_broken_link_or_reference_fails_the_build(tmp_path):
    """With the site's configuration, a link to a missing page, a missing anchor and a
    reference to a cracklab name that does not exist are errors; a reference to an
    internal cracklab object is not."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "index.md").write_text(textwrap.dedent("""\
        # Title

        [a page that does not exist](missing.md), [an anchor](other.md#no-such-heading),
        {py:func}`cracklab.no_such_function`, {py:func}`cracklab.laws.solve.solve_velocity`.

        ```{toctree}
        other
        gallery/index
        ```
        """))
    (src / "other.md").write_text("# Other\n\n## A heading\n")
    res = sphinx(src, tmp_path / "out", "-D", "plot_gallery=0", conf=DOCS)
    assert res.returncode != 0
    warnings = [line for line in res.stderr.splitlines() if "WARNING" in line or "ERROR" in line]
    assert any("missing" in w for w in warnings), res.stderr
    assert any("no-such-heading" in w for w in warnings), res.stderr
    assert any("cracklab.no_such_function" in w for w in warnings), res.stderr
    assert not any("solve_velocity" in w for w in warnings), res.stderr
    assert len(warnings) == 3, res.stderr


def test_the_sidebar_lists_each_page_once(site):
    """The site's navigation names each page once: one "API reference" (the docstrings),
    besides the one-line "API summary"."""
    nav = (site / "index.html").read_text().split('class="sphinxsidebar"', 1)[1]
    titles = re.findall(r'<a class="reference internal" href="[^"#]+">([^<]+)</a>', nav)
    assert titles.count("API reference") == 1 and titles.count("API summary") == 1, titles
    assert len(titles) == len(set(titles)), titles
