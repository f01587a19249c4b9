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
