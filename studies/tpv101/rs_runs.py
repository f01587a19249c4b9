"""Runs of the TPV101/TPV103 study (studies/tpv101/run.py): the scenes, their Zarr stores
and the wall-time records next to them. A store that holds a finished run of the same
scene is reused; a killed run resumes from its last checkpoint."""
from __future__ import annotations

from studies.benchmarks import harness as H

DEFAULT_DOMAIN = (72000.0, 36000.0)


def build_scene(problem, dx, t_end=None, domain=None):
    """``scenes.<problem>`` (tpv101 or tpv103) at ``dx`` with its stations, the rupture
    time of the whole plane and the slip field at the end."""
    from cracklab import scenes

    return H.build(getattr(scenes, problem), float(dx), t_end=t_end, domain=domain)


def tag(problem, dx, domain=None):
    d = "" if domain is None or tuple(domain) == DEFAULT_DOMAIN else \
        f"_{domain[0] / 1e3:g}x{domain[1] / 1e3:g}km"
    return f"{problem}_dx{dx:g}{d}"


def store_path(out, problem, dx, domain=None):
    return H.store_path(out, tag(problem, dx, domain))


def run_one(problem, dx, out, *, t_end=None, domain=None, force=False, log=print):
    """Run (or reuse, or resume) one grid spacing; return its metadata dict."""
    scene = build_scene(problem, dx, t_end, domain)
    return H.run_scene(scene, store_path(out, problem, dx, domain), label=f"{problem} {dx:g} m",
                       meta={"problem": problem, "dx": float(dx)}, force=force, log=log, resume=True)


def load_run(out, problem, dx, domain=None):
    """(Dataset, scene, station Dataset, metadata) of a finished run."""
    store = store_path(out, problem, dx, domain)
    return (*H.load_run(store), H.read_meta(store))
