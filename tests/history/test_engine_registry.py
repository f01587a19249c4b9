"""History engines register themselves and carry their own facts (history/base.py)."""
import pytest

from cracklab import Grid, InputError, Loading, Material, Numerics, Scene, TractionFree
from cracklab.history import ENGINES, DirectEngine, ExponentialEngine, register, resolve_engine
from cracklab.solver.budget import run_memory
from cracklab.solver.schemes import SCHEMES


def test_every_engine_file_registers_its_engine():
    assert ENGINES == {"direct": DirectEngine, "exponential": ExponentialEngine}
    assert (DirectEngine.windowed, ExponentialEngine.windowed) == (True, False)

    class Again:
        name = "direct"

    with pytest.raises(ValueError, match="two history engines are named 'direct'"):
        register(Again)
    assert ENGINES["direct"] is DirectEngine


def test_auto_takes_the_flat_cost_engine_unless_a_window_needs_the_other():
    assert resolve_engine("auto") == "exponential" and resolve_engine("auto", window=5.0) == "direct"
    assert resolve_engine("direct") == "direct"
    with pytest.raises(InputError, match="numerics.window: a truncated history needs engine 'direct' "
                                         r"\(engine 'exponential' keeps the whole history\)"):
        Numerics(engine="exponential", window=5.0)


@pytest.mark.parametrize("engine", ["direct", "exponential"])
def test_the_memory_estimate_is_the_engines_own_per_channel(engine):
    """run_memory's history is the sum of the engine's own estimate over the channels (II and
    III of 3D shear): the engine of each name is asked, not a table outside it."""
    sc = Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=Grid(n1=16, n3=16, L1=1.0, L3=1.0),
               law=TractionFree(), loading=Loading(tau0_1=1.0), t_end=0.3,
               numerics=Numerics(formulation="product", engine=engine))
    held = [ENGINES[engine].memory(sc, k, SCHEMES["product"], sc.material)[0] for k in ("II", "III")]
    assert run_memory(sc).history == sum(held) > 0
    other = {"direct": "exponential", "exponential": "direct"}[engine]
    assert ENGINES[other].memory(sc, "II", SCHEMES["product"], sc.material)[0] != held[0]
