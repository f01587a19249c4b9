"""The small TOML scene the tests of field files share: the 2 x 1 plane on 16 x 8 nodes
(``GRID``) under a uniform opening load, and a linear cohesive law whose other keys (a
field read from a file, most often) the test gives."""
from cracklab import Grid

GRID = Grid(n1=16, n3=8, L1=2.0, L3=1.0)

HEAD = """\
t_end = 0.05

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = 16
n3 = 8
L1 = 2.0
L3 = 1.0

[loading]
tau0_2 = 0.5
"""


def toml(law: str, head: str = HEAD) -> str:
    """The scene's TOML: ``head``, then ``[law]`` (linear cohesive, delta_c = 0.01) with ``law``."""
    return head + "\n[law]\nkind = \"linear_cohesive\"\ndelta_c = 0.01\n" + law + "\n"
