"""A Python example of docs/reference/scenes.md that begins with its imports runs on its own, in a
fresh namespace (a reader copies one block, not the page)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FENCE = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def standalone_blocks(page: str) -> list[tuple[int, str]]:
    text = (ROOT / page).read_text()
    out = []
    for m in FENCE.finditer(text):
        body = m.group(1)
        first = next((line for line in body.splitlines() if line.strip() and not line.startswith("#")), "")
        if first.startswith(("import ", "from ")):
            out.append((text[:m.start()].count("\n") + 1, body))
    return out


BLOCKS = standalone_blocks("docs/reference/scenes.md")


def test_the_front_analysis_example_is_among_them():
    assert any("front_position" in body for _, body in BLOCKS)


@pytest.mark.parametrize("line,body", BLOCKS, ids=[f"line{line}" for line, _ in BLOCKS])
def test_block_runs_alone(line, body, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    exec(compile(body, f"docs/reference/scenes.md, python block at line {line}", "exec"), {"__name__": "__docs__"})
