"""The exponential engine's sums do not depend on which compiled loops a process built
first. numba compiles the complex-arithmetic helpers of a loop once per process and
reuses them, with the fast-math flags of whichever loop needed them first; the engine's
fast-math loops therefore write their complex arithmetic on the real and imaginary
parts (history/blocked.py). Each case runs in a fresh process with an empty numba cache."""
import hashlib
import os
import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import hashlib, sys
    import numpy as np
    from cracklab import scenes
    from cracklab.solver import loops
    from cracklab.solver.interfaces import for_scene
    if sys.argv[1] == "loops-first":   # the 3D shear rotation compiled before the engine
        r = np.random.default_rng(3)
        c, s = r.standard_normal((2, 40, 21))
        a = r.standard_normal((40, 21)) + 1j * r.standard_normal((40, 21))
        loops.rotate(c, s, a, a.copy())
    from cracklab.history import make_engine
    gamma = np.abs(np.random.default_rng(5).standard_normal((32, 17))) + 0.05
    engines = {"I": for_scene(scenes.lamb(n=32, t_end=0.3)).channels["I"].engine,   # displacement
               "II": make_engine("exponential", kernel="II", gamma=gamma, nu=0.25, rule="product",
                                 formulation="velocity", lag=1, nsteps=2000)}      # taps ahead
    for name, eng in engines.items():
        r = np.random.default_rng(0)
        h = hashlib.sha256()
        for n in range(40):
            x = r.standard_normal(eng.shape) + 1j * r.standard_normal(eng.shape)
            h.update(np.ascontiguousarray(eng.push(x)).tobytes())
            eng.wait()
        print(name, h.hexdigest())
    # and the solver's complex loops, compiled after the engine here or before it
    r = np.random.default_rng(7)
    c, s = r.standard_normal((2, 40, 21))
    a, b, k = (r.standard_normal((40, 21)) + 1j * r.standard_normal((40, 21)) for _ in range(3))
    h = hashlib.sha256()
    for arr in loops.rotate(c, s, a, b) + (loops.plus_product(a, c, b),):
        h.update(np.ascontiguousarray(arr).tobytes())
    print("loops", h.hexdigest())
""")


def _run(order, tmp_path):
    cache = tmp_path / order
    cache.mkdir()
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    out = subprocess.run([sys.executable, "-c", SCRIPT, order], env=env, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout.split()


def test_engine_sums_do_not_depend_on_the_compile_order(tmp_path):
    first = _run("engine-first", tmp_path)
    second = _run("loops-first", tmp_path)
    assert len(first) == 6 and first == second
