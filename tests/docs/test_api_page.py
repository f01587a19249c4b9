"""docs/reference/api.md is what docs/tools/api_page.py writes from the live signatures and
docstrings, and it lists every public name of cracklab."""
from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import cracklab

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "reference" / "api.md"


def generator():
    spec = importlib.util.spec_from_file_location("api_page", ROOT / "docs" / "tools" / "api_page.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_api_page_is_up_to_date():
    text = generator().render()
    assert PAGE.read_text() == text, "docs/reference/api.md is out of date: run python docs/tools/api_page.py"


def test_api_page_is_deterministic_and_complete():
    text = generator().render()
    assert text == generator().render()
    assert not re.search(r" at 0x[0-9a-f]+", text), "an object's address in a signature"
    entries = set(re.findall(r"^- `([\w.]+)", text, flags=re.M))
    modules = {"analysis", "ensemble", "kernels", "scenes", "__version__"}
    for name in sorted(set(cracklab.__all__) - modules):
        assert f"cracklab.{name}" in entries, f"cracklab.{name} is not on docs/reference/api.md"
    for builder in cracklab.scenes.BUILDERS:
        assert f"cracklab.scenes.{builder}" in entries, builder
    from cracklab.cli import main

    for command in main.commands:
        assert f"- `cracklab {command} " in text or f"- `cracklab {command}`" in text, command


def test_every_entry_has_a_summary():
    for line in PAGE.read_text().splitlines():
        if line.startswith("- `cracklab") and "`:" in line:
            assert line.split("`:", 1)[1].split("*(no docstring)*")[0].strip(), line


def test_api_page_is_linked_from_the_index():
    assert "](reference/api.md)" in (ROOT / "docs" / "index.md").read_text()
