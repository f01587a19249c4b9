"""The FFTW wisdom cache is data: a file planted in the cache runs nothing and is not read
as a pickle (cracklab/solver/spectral.py)."""
import os
import pickle
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("pyfftw")


class _Payload:
    """Unpickling this runs ``touch MARKER``: what an attacker would plant."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


def _transform_in_child(cache, tmp_path):
    """Plan and run one transform with pyfftw in a fresh process whose cache is ``cache``."""
    code = textwrap.dedent("""
        import numpy as np
        from cracklab import Grid
        from cracklab.solver.spectral import Transforms
        g = Grid(n1=16, n3=8, L1=1.0, L3=1.0)
        x = np.random.default_rng(0).standard_normal(g.shape)
        t = Transforms(g, backend="pyfftw")
        assert np.allclose(t.inverse(t.forward(x)), x)
        print("ok")
    """)
    env = dict(os.environ, CRACKLAB_CACHE=str(cache), CRACKLAB_FFT="pyfftw")
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp_path, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_a_planted_pickle_runs_nothing(tmp_path):
    """A pickle under the old wisdom name and under the current one: the run plans, transforms
    and finishes, and the pickle's payload never ran."""
    import socket

    cache = tmp_path / "cache"
    cache.mkdir()
    marker = tmp_path / "pwned"
    blob = pickle.dumps(_Payload(marker))
    host = socket.gethostname()
    for name in (f"fftw-wisdom-{host}.pickle", f"fftw-wisdom-{host}.json"):
        (cache / name).write_bytes(blob)
    _transform_in_child(cache, tmp_path)
    assert not marker.exists()
    # the current file was replaced by wisdom as data, which a later run reads back
    from cracklab.solver.spectral import wisdom_from_json

    wisdom = wisdom_from_json((cache / f"fftw-wisdom-{host}.json").read_text())
    assert len(wisdom) == 3 and b"fftw" in wisdom[0]
    _transform_in_child(cache, tmp_path)
    assert not marker.exists()


def test_the_wisdom_file_is_json_of_fftw_text(tmp_path):
    """What is written is FFTW's exported text in a tagged JSON document, and only such a
    document is accepted back."""
    from cracklab.solver.spectral import WISDOM_FORMAT, wisdom_from_json, wisdom_to_json

    wisdom = (b"(fftw-3.3.10 fftw_wisdom #x1\n)\n", b"(fftw-3.3.10 fftwf_wisdom #x2\n)\n", b"")
    doc = wisdom_to_json(wisdom)
    assert f'"format": "{WISDOM_FORMAT}"' in doc
    assert wisdom_from_json(doc) == wisdom
    for bad in ('{"format": "other"}', "[1, 2]", '{"format": "%s", "double": 3}' % WISDOM_FORMAT):
        with pytest.raises(ValueError):
            wisdom_from_json(bad)


def test_a_fifo_in_place_of_the_wisdom_file_does_not_hang(tmp_path):
    """A FIFO planted under the wisdom's name (the current one, and the older pickle's) is not
    opened: opening it would block the run for ever."""
    import socket

    cache = tmp_path / "cache"
    cache.mkdir()
    for suffix in ("json", "pickle"):
        os.mkfifo(cache / f"fftw-wisdom-{socket.gethostname()}.{suffix}")
    _transform_in_child(cache, tmp_path)


def test_the_sequence_window_plans_from_and_into_the_host_wisdom(tmp_path):
    """A quasi-dynamic sequence's window (solver/sequence/window.py) plans its padded box with
    the host's wisdom: after one process planned it, another can plan that box from the file
    alone (FFTW_WISDOM_ONLY fails without wisdom of the size), so a resumed run transforms
    with the plan of the run it resumes."""
    cache = tmp_path / "cache"
    env = dict(os.environ, CRACKLAB_CACHE=str(cache), CRACKLAB_FFT="pyfftw")
    plan = textwrap.dedent("""
        import sys
        import numpy as np
        from cracklab.scenes import bp1
        from cracklab.solver.sequence.run import system_of
        s = system_of(bp1(dz=400.0, years=1.0))
        w = s.window
        assert w is not None and w.fftw
        w.traction({3: np.zeros(s.n)})
        print(w.size[0])
    """)
    size = int(subprocess.run([sys.executable, "-c", plan], env=env, cwd=tmp_path, capture_output=True, text=True,
                              timeout=120, check=True).stdout.split()[-1])
    only = textwrap.dedent(f"""
        import pyfftw
        from cracklab.solver import spectral
        spectral._load_wisdom()
        a = pyfftw.empty_aligned(({size}, 1), dtype="float64")
        b = pyfftw.empty_aligned(({size} // 2 + 1, 1), dtype="complex128")
        pyfftw.FFTW(a, b, axes=(0,), flags=("FFTW_MEASURE", "FFTW_WISDOM_ONLY"))
        pyfftw.FFTW(b.copy(), a.copy(), axes=(0,), direction="FFTW_BACKWARD", flags=("FFTW_MEASURE", "FFTW_WISDOM_ONLY"))
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", only], env=env, cwd=tmp_path, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]
