"""Bitwise regression record: a fixed set of runs, a SHA-256 of every output array.

    python studies/regression/hashes.py record OUT.json [--only NAME ...]
    python studies/regression/hashes.py check BASE.json [--only NAME ...] [--save NEW.json] [-v]
    python studies/regression/hashes.py compare A.json B.json [-v]
    python studies/regression/hashes.py list

``record`` runs every case (or the ``--only`` ones), each in a fresh process
(``hashes.py _case NAME PREFIX``), and writes OUT.json: per case the SHA-256 of every
data variable and coordinate of the output Dataset, of the station series
(``cracklab.stations``), of the scene's TOML (``Scene.to_toml``), and the run time;
plus the version and git commit of the checkout the package was imported from
(``cracklab.__file__``), the environment variables that can change results, and the
digests of the kernel-fit and FFTW-wisdom cache files. Next to it, OUT.npz holds the
arrays themselves, so that a later ``check`` or ``compare`` can say how large a
difference is (a hash alone cannot). An array's digest covers its dtype, its shape and
its bytes in C order: a change of one ulp, of dtype or of shape is a different array.

``check`` reruns the cases of BASE.json (or the ``--only`` ones) and compares;
``compare`` compares two recordings without running. Both print one row per case
(``-v``: per array) with "same" or "DIFFERENT" and, for a differing numeric array, the
max abs and max relative difference (|a - b| / |b| where b != 0) and the count of
entries whose NaN pattern differs; they exit 0 only if every array (and every scene
TOML) is bitwise identical and no array is missing or new. ``--ignore-scene`` leaves the
TOML digests out of the verdict (they are still printed).

Against an older commit (e.g. before a redesign)::

    git worktree add /tmp/before <commit>
    PYTHONPATH=/tmp/before python studies/regression/hashes.py record before.json
    PYTHONPATH=$PWD python studies/regression/hashes.py check before.json

(the script is this checkout's; only ``PYTHONPATH`` chooses the package it runs; the
recording says which one it imported, from ``cracklab.__file__``).

Same machine, same cache. The two recordings compared must come from the same machine
and the same user cache (``$CRACKLAB_CACHE``, else ``$XDG_CACHE_HOME/cracklab``, else
``~/.cache/cracklab``; ``--cache DIR`` sets it for the runs). The FFTs are planned with
FFTW_MEASURE, which picks among algorithms by timing them, from the host's wisdom file in
that directory: every process then uses the plan stored there, but a recording made with
the wisdom gone (an emptied cache, another host) can plan differently, and another plan
changes the last bits (measured: with an empty cache the plane cases kostrov_plane and
periodic_cracks_II and the 80 x 40 tpv3_600m differ by rounding, up to ~1e-14 absolute
in the dimensionless fields and ~1e-9 relative where a value is near zero, e.g. tau_3 at
a TPV3 station, while the other cases stay identical; removing only the kernel fits,
the wisdom kept, changed no array).
The exponential engine's kernel fits are stored there too and read back by every later
process, fresh ones included. A run reads an existing plan and fit, never its own, so
with the cache kept results are reproducible run to run and process to process. The
recording keeps the cache files' digests and the FFTW wisdom's entries, and ``compare``
notes a changed fit file, a wisdom entry of the base that is gone, or a different cache
directory. The environment (thread counts, CRACKLAB_FFT, OMP settings) is recorded and
compared too. A restructuring that hands FFTW arrays of another alignment or layout, or
plans with other flags, gets other plans and may change the last bits for that reason.

Compiled loops. The numba loops are compiled with ``cache=True``, and which of the
specialisations stored in the on-disk cache a call runs depends on what earlier runs of
that checkout compiled: two checkouts of the same commit, one with a cache filled by
earlier work and one fresh, differ in the last bits (measured: Lamb 64 x 64 from step
2 on, every case but the direct engine's and the modal one). ``record`` and ``check``
therefore run every case with ``NUMBA_CACHE_DIR`` set to a new empty directory (shared
by the cases of one invocation, which run in the same order each time), unless the
caller sets it.

The cases (``list`` prints them); only the public API is used (``cracklab.scenes``
builders, ``Scene``, ``Record``, ``Numerics``, the laws, ``simulate``, ``stations``,
``modal_response``), so that the same script runs before and after a restructuring:

- lamb64: Lamb's problem, 64 x 64, t_end 1 (128 steps), opening, its rate and the
  traction every 8 steps, two stations; default numerics (exponential engine).
- lamb64_overlap: the same with two engine threads (the engine's advance on a worker
  thread overlapping the FFTs, ``Numerics(engine_threads=2)``).
- lamb60: Lamb's problem on 60 x 60, t_end 1: a grid whose 1/N is not a power of two
  (on the power-of-two grids a scale by 1/N is exact wherever it is applied, so a moved
  scaling shows only here and in tpv3_600m).
- lamb32_direct: Lamb's problem, 32 x 32, t_end 0.5, the direct (reference) engine.
- elliptical: suddenly loaded elliptical crack, 64 x 64, a = 0.25, b = 0.15, t_end 0.5.
- kostrov_plane: plane (n3 = 1) Kostrov crack, n = 512, speed 0.7, t_end 0.3.
- asperity_member: the demo ensemble's member diameter = 0.25 Z, contrast = 3
  (studies/asperity_ensemble/study.toml: asperity_row, 128 x 64, t_end 4, a snapshot
  every 16 steps).
- slip_weakening_product: 3D slip-weakening rupture, 64 x 64 unit square, nucleation
  patch, ``Numerics(formulation="product")``, every field.
- random_toughness: random_toughness on the same geometry (128 x 64, tau_c lognormal,
  cov 0.2, correlation length Z/4, seed 1), t_end 4.
- periodic_cracks_II: plane periodic row of cracks in mode II (the product scheme in 2D),
  n = 512, c = 0.1, t_end 0.5 (``cracklab.scenes.periodic_cracks``, looked up with getattr).
- tpv3_600m: SCEC TPV3 at dx = 600 m (80 x 40), t_end 12 s, its stations and rupture time.
- modal: ``modal_response`` of the 12 schemes of section 3.1 (formulation x convolution
  x integration) and of product / product-cubic with predictor-corrector, modes I, II,
  III, gamma 0.25, 0.5, 1 and 2, T_end 200 (a scheme that refuses a gamma, e.g. a
  singular step, records its error message).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import platform
import re
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

FORMAT = 1
#: environment variables that can change a run's numbers or its threads
ENV_KEYS = ("CRACKLAB_CACHE", "XDG_CACHE_HOME", "CRACKLAB_FFT", "CRACKLAB_FFT_THREADS", "OMP_NUM_THREADS",
            "OMP_WAIT_POLICY", "NUMBA_NUM_THREADS", "NUMBA_THREADING_LAYER", "OPENBLAS_NUM_THREADS",
            "MKL_NUM_THREADS", "NUMBA_DISABLE_JIT", "CRACKLAB_KERNEL_CACHE_MB")
SCENE_KEY = "scene_toml"


# ---------------------------------------------------------------------------- hashing
def array_digest(a) -> str:
    """SHA-256 of an array: its dtype, its shape, then its bytes in C order (object
    arrays, e.g. strings held as Python objects, by the JSON of their str values)."""
    a = np.asarray(a)
    h = hashlib.sha256()
    h.update(f"{a.dtype.str}|{a.shape}|".encode())
    if a.dtype.kind == "O":
        h.update(json.dumps([str(x) for x in a.ravel().tolist()]).encode())
    else:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def text_digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def dataset_arrays(ds, prefix):
    """{prefix/name: numpy array} for every variable (data and coordinate) of ``ds``."""
    return {f"{prefix}/{name}": np.asarray(ds[name].values) for name in sorted(map(str, ds.variables))}


def _storable(a):
    """The array as it goes into the .npz (object arrays as strings)."""
    return a.astype(str) if a.dtype.kind == "O" else a


# ---------------------------------------------------------------------------- the cases
def _cl():
    import cracklab

    return cracklab


def case_lamb64():
    """Lamb's problem 64 x 64, t_end 1 (exponential engine)."""
    cl = _cl()
    rec = cl.Record(fields=("delta_2", "v_2", "tau_2"), every=8,
                    stations={"r16": (0.75, 0.5), "diag": (0.625, 0.625)})
    return cl.scenes.lamb(n=64, t_end=1.0, record=rec)


def case_lamb64_overlap():
    """Lamb 64 x 64 with two engine threads (the advance overlapped)."""
    cl = _cl()
    rec = cl.Record(fields=("delta_2", "v_2"), every=8, stations={"r16": (0.75, 0.5)})
    return cl.scenes.lamb(n=64, t_end=1.0, record=rec, numerics=cl.Numerics(fft_threads=1, engine_threads=2))


def case_lamb60():
    """Lamb 60 x 60 (1/N of the transforms not a power of two), t_end 1."""
    cl = _cl()
    rec = cl.Record(fields=("delta_2", "v_2", "tau_2"), every=8, stations={"r15": (0.75, 0.5)})
    return cl.scenes.lamb(n=60, t_end=1.0, record=rec)


def case_lamb32_direct():
    """Lamb 32 x 32, t_end 0.5, direct engine."""
    cl = _cl()
    rec = cl.Record(fields=("delta_2",), every=4, stations={"r8": (0.75, 0.5)})
    return cl.scenes.lamb(n=32, t_end=0.5, record=rec, numerics=cl.Numerics(engine="direct"))


def case_elliptical():
    """Elliptical crack 64 x 64, a = 0.25, b = 0.15, t_end 0.5."""
    cl = _cl()
    rec = cl.Record(fields=("delta_2", "v_2", "tau_2"), every=8,
                    stations={"centre": (0.5, 0.5), "tip_a": (0.75, 0.5), "tip_b": (0.5, 0.65)})
    return cl.scenes.elliptical_crack(n=64, a=0.25, b=0.15, p=1.0, t_end=0.5, record=rec)


def case_kostrov_plane():
    """Plane Kostrov crack, n = 512, speed 0.7, t_end 0.3."""
    cl = _cl()
    # kostrov() builds the plane (n3 = 1) problem; its default stations hold the centre
    rec = cl.Record(fields=("delta_3", "v_3", "tau_3", "strength"), every=16,
                    stations={"centre": (0.5, 0.0), "x0.6": (0.6, 0.0)})
    return cl.scenes.kostrov(n=512, speed=0.7, t_end=0.3, record=rec)


def case_asperity_member():
    """Demo ensemble member: asperity_row 128 x 64, diameter 0.25, contrast 3, t_end 4."""
    cl = _cl()
    # studies/asperity_ensemble/study.toml: builder asperity_row, base n1 = 128, n3 = 64,
    # t_end = 4, record.every = 16; member diameter = 0.25, contrast = 3.0 (fft_threads 1)
    rec = cl.Record(fields=("delta_2",), every=16)
    return cl.scenes.asperity_row(n1=128, n3=64, t_end=4.0, diameter=0.25, contrast=3.0, record=rec)


def case_slip_weakening_product():
    """3D slip weakening, 64 x 64, product scheme, t_end 0.6."""
    cl = _cl()
    n = 64
    grid = cl.Grid(n1=n, n3=n, L1=1.0, L3=1.0)
    x1, x3 = np.meshgrid(np.asarray(grid.x1), np.asarray(grid.x3), indexing="ij")
    patch = np.hypot(x1 - 0.5, x3 - 0.5) <= 0.1
    fault = (np.abs(x1 - 0.5) <= 0.4) & (np.abs(x3 - 0.5) <= 0.3)
    law = cl.SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.005, sigma_n=1.0, bonded=~fault)
    rec = cl.Record(fields=("delta_1", "delta_3", "v_1", "v_3", "tau_1", "tau_3", "strength"), every=8,
                    stations={"hypo": (0.5, 0.5), "along": (0.7, 0.5), "across": (0.5, 0.7)})
    return cl.Scene(material=cl.Material(mu=1.0, cs=1.0, nu=0.25), grid=grid, law=law,
                    loading=cl.Loading(tau0_1=np.where(patch, 0.61, 0.55)), t_end=0.6,
                    record=rec, numerics=cl.Numerics(formulation="product", rupture_threshold=1e-3),
                    name="slip_weakening_product")


def case_random_toughness():
    """random_toughness 128 x 64 (tau_c lognormal, cov 0.2, l = Z/4, seed 1), t_end 4."""
    cl = _cl()
    rec = cl.Record(fields=("delta_2",), every=16)
    return cl.scenes.random_toughness(n1=128, n3=64, t_end=4.0, cov=0.2, correlation_length=0.25, seed=1,
                                      record=rec)


def case_periodic_cracks_II():
    """Plane periodic cracks in mode II (the product scheme in 2D), n = 512, t_end 0.5."""
    cl = _cl()
    builder = getattr(cl.scenes, "periodic_cracks", None)
    if builder is None:
        raise RuntimeError("cracklab.scenes.periodic_cracks is gone: drop this case from both recordings")
    rec = cl.Record(fields=("delta_1", "v_1", "tau_1"), every=16, stations={"centre": (0.5, 0.0)})
    return builder(n=512, c=0.1, mode="II", t_end=0.5, record=rec)


def case_tpv3_600m():
    """SCEC TPV3 at dx = 600 m (80 x 40), t_end 12 s."""
    return _cl().scenes.tpv3(dx=600.0, t_end=12.0)


MODAL_GAMMAS = (0.25, 0.5, 1.0, 2.0)
MODAL_T_END = 200.0


def modal_schemes():
    """(formulation, convolution, integration) of every modal run: the 12 of section 3.1
    and the two product rules with predictor-corrector."""
    forms, convs, integs = ("displacement", "velocity"), ("discretized", "trapezoid", "simpson"), \
        ("explicit", "semi-implicit")
    schemes = [(f, c, i) for f in forms for c in convs for i in integs]
    return schemes + [("velocity", "product", "predictor-corrector"),
                      ("velocity", "product-cubic", "predictor-corrector")]


def run_modal():
    """modal_response: 14 schemes x modes I, II, III x 4 gammas, T_end 200."""
    import warnings

    cl = _cl()
    arrays = {}
    for mode in ("I", "II", "III"):
        for gamma in MODAL_GAMMAS:
            for f, c, i in modal_schemes():
                key = f"{mode}/g{gamma:g}/{f}/{c}/{i}"
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        r = cl.modal_response(mode, gamma=gamma, T_end=MODAL_T_END, formulation=f,
                                              convolution=c, integration=i)
                except Exception as exc:  # noqa: BLE001 - a refusal (e.g. a singular step) is a result too
                    arrays[f"{key}/error"] = np.array(f"{type(exc).__name__}: {exc}")
                    continue
                arrays[f"{key}/r"] = np.asarray(r.values)
                arrays[f"{key}/T"] = np.asarray(r["T"].values)
    return arrays, None


def _run_scene(builder):
    def run():
        cl = _cl()
        scene = builder()
        ds = cl.simulate(scene)
        arrays = dataset_arrays(ds, "ds")
        try:
            st = cl.stations(ds)
        except ValueError:  # no stations
            st = None
        if st is not None:
            arrays.update(dataset_arrays(st, "stations"))
        return arrays, scene.to_toml()

    run.__doc__ = builder.__doc__
    return run


CASES = {
    "lamb64": _run_scene(case_lamb64),
    "lamb64_overlap": _run_scene(case_lamb64_overlap),
    "lamb60": _run_scene(case_lamb60),
    "lamb32_direct": _run_scene(case_lamb32_direct),
    "elliptical": _run_scene(case_elliptical),
    "kostrov_plane": _run_scene(case_kostrov_plane),
    "asperity_member": _run_scene(case_asperity_member),
    "slip_weakening_product": _run_scene(case_slip_weakening_product),
    "random_toughness": _run_scene(case_random_toughness),
    "periodic_cracks_II": _run_scene(case_periodic_cracks_II),
    "tpv3_600m": _run_scene(case_tpv3_600m),
    "modal": run_modal,
}
#: tiny cases for the tests of this tool (not part of a recording unless asked with --only)
TEST_CASES = {
    "tiny_lamb": _run_scene(lambda: _cl().scenes.lamb(
        n=16, t_end=0.1, record=_cl().Record(fields=("delta_2",), every=2, stations={"s": (0.75, 0.5)}))),
    "tiny_modal": lambda: ({"I/r": np.asarray(_cl().modal_response("I", gamma=0.5, T_end=5.0).values)}, None),
}


def _lookup(name):
    if name in CASES:
        return CASES[name]
    if name in TEST_CASES:
        return TEST_CASES[name]
    raise SystemExit(f"unknown case {name!r}; cases: {', '.join(CASES)} (tests: {', '.join(TEST_CASES)})")


# ---------------------------------------------------------------------------- provenance
def _git(where, *args):
    try:
        out = subprocess.run(["git", "-C", str(where), *args], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def package_info():
    """Version, source directory and git commit of the imported package."""
    cl = _cl()
    src = Path(cl.__file__).resolve().parent
    dirty = _git(src, "status", "--porcelain", "--untracked-files=no", "--", ".")
    return {"version": getattr(cl, "__version__", None), "source": str(src),
            "commit": _git(src, "rev-parse", "HEAD"), "dirty": bool(dirty) if dirty is not None else None}


def cache_dir() -> Path:
    """The user cache of kernel fits and FFTW wisdom (the rule of cracklab's docs)."""
    env = os.environ.get("CRACKLAB_CACHE")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "cracklab"


_WISDOM_ENTRY = re.compile(rb"\(fftw_[^()]*\)")


def wisdom_entries(data: bytes):
    """Digests of the solver entries of an FFTW wisdom file (read as bytes, not unpickled)."""
    return sorted({hashlib.sha256(m.group()).hexdigest()[:16] for m in _WISDOM_ENTRY.finditer(data)})


def cache_digests():
    """The kernel-fit and FFTW-wisdom files of the cache: {"files": {name: sha256},
    "wisdom": {name: [entry digests]}}."""
    files, wisdom = {}, {}
    root = cache_dir()
    if root.is_dir():
        for p in sorted(root.iterdir()):
            fit = p.name.startswith("expfit-") and p.suffix == ".npz"
            wis = p.name.startswith("fftw-wisdom-") and p.suffix in (".json", ".pickle")
            if p.is_file() and (fit or wis):
                try:
                    data = p.read_bytes()
                except OSError:
                    continue
                files[p.name] = hashlib.sha256(data).hexdigest()
                if wis:
                    wisdom[p.name] = wisdom_entries(data)
    return {"dir": str(root), "files": files, "wisdom": wisdom}


def environment():
    import numpy

    info = {"host": socket.gethostname(), "python": platform.python_version(), "numpy": numpy.__version__,
            "platform": platform.platform(), "cpu_count": os.cpu_count(),
            "env": {k: os.environ[k] for k in ENV_KEYS if k in os.environ}, "cache_dir": str(cache_dir())}
    for mod in ("scipy", "numba", "pyfftw", "xarray"):
        try:
            info[mod] = __import__(mod).__version__
        except Exception:  # noqa: BLE001 - absent or broken: recorded as such
            info[mod] = None
    return info


# ---------------------------------------------------------------------------- one case (child)
def run_case(name, prefix):
    """Run one case in this process; write PREFIX.json (digests) and PREFIX.npz (arrays)."""
    t0 = time.perf_counter()
    arrays, toml = _lookup(name)()
    seconds = time.perf_counter() - t0
    entry = {"case": name, "seconds": seconds,
             "arrays": {k: {"sha256": array_digest(a), "dtype": np.asarray(a).dtype.str,
                            "shape": list(np.shape(a))} for k, a in arrays.items()},
             SCENE_KEY: text_digest(toml) if toml is not None else None,
             "package": package_info()}
    store = {k: _storable(np.asarray(a)) for k, a in arrays.items()}
    if toml is not None:
        store[SCENE_KEY] = np.array(toml)
    np.savez_compressed(f"{prefix}.npz", **store)
    Path(f"{prefix}.json").write_text(json.dumps(entry))


def spawn_case(name, prefix, timeout=1800):
    """Run one case in a fresh process with this process's environment; its entry."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "_case", name, str(prefix)]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"case {name} failed (exit {proc.returncode}):\n{proc.stderr[-4000:]}")
    entry = json.loads(Path(f"{prefix}.json").read_text())
    entry["wall_seconds"] = wall
    return entry


def npz_path(json_path) -> Path:
    return Path(json_path).with_suffix(".npz")


def record(out, names, progress=True):
    """Run ``names`` each in a fresh process; write OUT (.json) and OUT's .npz. The recording."""
    out = Path(out)
    cases, arrays = {}, {}
    with tempfile.TemporaryDirectory(prefix="cracklab-hashes-") as tmp:
        for k, name in enumerate(names, 1):
            if progress:
                print(f"[{k}/{len(names)}] {name} ...", end=" ", flush=True)
            entry = spawn_case(name, Path(tmp) / name)
            with np.load(Path(tmp) / f"{name}.npz", allow_pickle=False) as z:
                for key in z.files:
                    arrays[f"{name}/{key}"] = z[key]
            cases[name] = entry
            if progress:
                print(f"{entry['seconds']:.1f} s ({entry['wall_seconds']:.1f} s with start-up), "
                      f"{len(entry['arrays'])} arrays", flush=True)
    packages = {json.dumps(e["package"], sort_keys=True) for e in cases.values()}
    result = {"format": FORMAT, "created_unix": time.time(),
              "package": json.loads(packages.pop()) if len(packages) == 1 else None,
              "environment": environment(), "cache": cache_digests(), "cases": cases}
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(npz_path(out), **arrays)
    out.write_text(json.dumps(result, indent=1, sort_keys=True))
    if progress:
        total = sum(e["wall_seconds"] for e in cases.values())
        pkg = result["package"] or {}
        print(f"wrote {out} and {npz_path(out)}: {len(cases)} cases, {total:.0f} s; cracklab "
              f"{pkg.get('version')} from {pkg.get('source')} at {pkg.get('commit')}"
              f"{' (with uncommitted changes)' if pkg.get('dirty') else ''}")
    return result


# ---------------------------------------------------------------------------- comparing
def load(path):
    path = Path(path)
    data = json.loads(path.read_text())
    if data.get("format") != FORMAT:
        raise SystemExit(f"{path}: not a recording of this tool (format {data.get('format')!r})")
    return data


class _Values:
    """The arrays of a recording's .npz, if it is there (lazy)."""

    def __init__(self, json_path):
        p = npz_path(json_path)
        self.z = np.load(p, allow_pickle=False) if p.is_file() else None

    def get(self, key):
        if self.z is None or key not in self.z.files:
            return None
        return self.z[key]


def difference(a, b):
    """(max abs, max relative, NaN-pattern mismatches) of numeric a against base b, or None."""
    if a is None or b is None or a.shape != b.shape or a.dtype.kind not in "fciub" or b.dtype.kind not in "fciub":
        return None
    a = a.astype(np.complex128 if "c" in (a.dtype.kind + b.dtype.kind) else np.float64)
    b = b.astype(a.dtype)
    na, nb = np.isnan(a), np.isnan(b)
    both = ~(na | nb)
    with np.errstate(all="ignore"):
        d = np.abs(a - b)[both]
        rel = d / np.abs(b[both])
        rel = rel[np.abs(b[both]) > 0]
        finite = np.isfinite(d)
    max_abs = float(d[finite].max()) if finite.any() else (math.inf if d.size else 0.0)
    max_rel = float(rel[np.isfinite(rel)].max()) if np.isfinite(rel).any() else 0.0
    return max_abs, max_rel, int(np.count_nonzero(na != nb))


def compare_recordings(base, new, base_path=None, new_path=None, names=None, verbose=False,
                       ignore_scene=False, out=None):
    """Print the comparison of ``new`` against ``base``; True if every array is identical."""
    out = sys.stdout if out is None else out
    bv = _Values(base_path) if base_path else None
    nv = _Values(new_path) if new_path else None
    names = list(names) if names else list(base["cases"])
    ok = True
    rows = []
    for name in names:
        b, n = base["cases"].get(name), new["cases"].get(name)
        if b is None or n is None:
            rows.append((name, "(case)", "MISSING in " + ("base" if b is None else "new"), ""))
            ok = False
            continue
        keys = sorted(set(b["arrays"]) | set(n["arrays"]))
        same = 0
        for key in keys:
            ba, na = b["arrays"].get(key), n["arrays"].get(key)
            if ba is None or na is None:
                rows.append((name, key, "NEW" if ba is None else "MISSING", ""))
                ok = False
            elif ba["sha256"] == na["sha256"]:
                same += 1
                if verbose:
                    rows.append((name, key, "same", ""))
            else:
                ok = False
                detail = ""
                if ba["dtype"] != na["dtype"] or ba["shape"] != na["shape"]:
                    detail = f"dtype/shape {ba['dtype']}{tuple(ba['shape'])} -> {na['dtype']}{tuple(na['shape'])}"
                else:
                    diff = difference(nv.get(f"{name}/{key}") if nv else None,
                                      bv.get(f"{name}/{key}") if bv else None)
                    if diff is not None:
                        detail = f"max abs {diff[0]:.3e}, max rel {diff[1]:.3e}" + \
                                 (f", NaN pattern differs at {diff[2]}" if diff[2] else "")
                    else:
                        detail = "(values not available)"
                rows.append((name, key, "DIFFERENT", detail))
        bs, ns = b.get(SCENE_KEY), n.get(SCENE_KEY)
        if bs != ns:
            rows.append((name, SCENE_KEY, "DIFFERENT" + (" (ignored)" if ignore_scene else ""), ""))
            ok = ok and ignore_scene
        elif verbose and bs is not None:
            rows.append((name, SCENE_KEY, "same", ""))
        if not verbose and same == len(keys) and bs == ns:
            rows.append((name, f"(all {len(keys)} arrays{', scene' if bs else ''})", "same", ""))
        tb, tn = b.get("wall_seconds"), n.get("wall_seconds")
        if tb is not None and tn is not None and verbose:
            rows.append((name, "(run time)", f"{tb:.1f} s -> {tn:.1f} s", ""))
    w0 = max([4] + [len(r[0]) for r in rows])
    w1 = max([5] + [len(r[1]) for r in rows])
    w2 = max([6] + [len(r[2]) for r in rows])
    print(f"{'case':<{w0}}  {'array':<{w1}}  {'result':<{w2}}  difference", file=out)
    for r in rows:
        print(f"{r[0]:<{w0}}  {r[1]:<{w1}}  {r[2]:<{w2}}  {r[3]}".rstrip(), file=out)
    for warning in provenance_warnings(base, new):
        print("note: " + warning, file=out)
    print(("IDENTICAL" if ok else "DIFFERENT") + f": {len(names)} cases, base "
          f"{(base.get('package') or {}).get('commit')}, new {(new.get('package') or {}).get('commit')}",
          file=out)
    return ok


def provenance_warnings(base, new) -> list:
    """Notes on what besides the code differs between two recordings (host, environment,
    library versions, the kernel-fit and FFTW-wisdom caches) and may explain a difference."""
    out = []
    eb, en = base.get("environment", {}), new.get("environment", {})
    if eb.get("host") != en.get("host"):
        out.append(f"recorded on different hosts ({eb.get('host')} / {en.get('host')}): FFTW plans and "
                   f"kernel fits may differ, and with them the last bits")
    if eb.get("env") != en.get("env"):
        out.append(f"environment variables differ: {eb.get('env')} / {en.get('env')}")
    for key in ("numpy", "scipy", "numba", "pyfftw", "python"):
        if eb.get(key) != en.get(key):
            out.append(f"{key} {eb.get(key)} / {en.get(key)}")
    cb, cn = base.get("cache", {}), new.get("cache", {})
    if cb and cn and ("dir" in cb) != ("dir" in cn):
        return out
    if cb.get("dir") != cn.get("dir"):
        out.append(f"recorded with different caches ({cb.get('dir')} / {cn.get('dir')}): the FFTW plans "
                   f"(and kernel fits) may differ, and with them the last bits")
    fb, fn = cb.get("files", {}), cn.get("files", {})
    changed = sorted(k for k in set(fb) & set(fn) if fb[k] != fn[k] and k.startswith("expfit-"))
    if changed:
        out.append(f"{len(changed)} kernel-fit cache files changed between the recordings "
                   f"(e.g. {changed[0]}): differences may come from the cache, not the code")
    wb, wn = cb.get("wisdom", {}), cn.get("wisdom", {})
    for name in sorted(set(wb) & set(wn)):
        lost = set(wb[name]) - set(wn[name])
        if lost:
            out.append(f"{len(lost)} of the {len(wb[name])} FFTW wisdom entries of the base are gone from "
                       f"{name} (replanned): arrays may differ in the last bits because of the plans")
    for name in sorted(set(wb) - set(wn)):
        out.append(f"the FFTW wisdom file {name} of the base is gone: the new run planned afresh, and "
                   f"other plans can change the last bits")
    return out


# ---------------------------------------------------------------------------- command line
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("record", help="run the cases and write OUT.json (+ OUT.npz)")
    p.add_argument("out")
    p.add_argument("--only", nargs="+", metavar="NAME")
    p.add_argument("--cache", metavar="DIR", help="CRACKLAB_CACHE for the runs (kernel fits, FFTW wisdom)")
    p = sub.add_parser("check", help="rerun the cases of BASE.json and compare")
    p.add_argument("base")
    p.add_argument("--cache", metavar="DIR", help="CRACKLAB_CACHE for the runs (kernel fits, FFTW wisdom)")
    p.add_argument("--only", nargs="+", metavar="NAME")
    p.add_argument("--save", metavar="NEW.json", help="keep the new recording")
    p.add_argument("-v", "--verbose", action="store_true", help="a row per array")
    p.add_argument("--ignore-scene", action="store_true", help="leave the scene TOML digests out of the verdict")
    p = sub.add_parser("compare", help="compare two recordings without running")
    p.add_argument("a", help="the base recording")
    p.add_argument("b")
    p.add_argument("--only", nargs="+", metavar="NAME")
    p.add_argument("-v", "--verbose", action="store_true", help="a row per array")
    p.add_argument("--ignore-scene", action="store_true", help="leave the scene TOML digests out of the verdict")
    sub.add_parser("list", help="the cases")
    p = sub.add_parser("_case")  # internal: one case in this (fresh) process
    p.add_argument("name")
    p.add_argument("prefix")
    args = parser.parse_args(argv)

    if args.command == "_case":
        run_case(args.name, args.prefix)
        return 0
    if args.command == "list":
        for name, fn in CASES.items():
            print(f"{name:24s} {(fn.__doc__ or '').strip()}")
        return 0
    if getattr(args, "cache", None):
        os.environ["CRACKLAB_CACHE"] = str(Path(args.cache).resolve())
    if args.command in ("record", "check") and "NUMBA_CACHE_DIR" not in os.environ:
        # compiled loops start from an empty on-disk cache, the same for every recording
        # (see "Compiled loops" in the module docstring)
        os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="cracklab-numba-")
    if args.command == "record":
        names = args.only or list(CASES)
        for name in names:
            _lookup(name)
        record(args.out, names)
        return 0
    if args.command == "check":
        base = load(args.base)
        names = args.only or list(base["cases"])
        for name in names:
            _lookup(name)
        if args.save:
            new_path = Path(args.save)
            new = record(new_path, names)
            return 0 if compare_recordings(base, new, args.base, new_path, names, args.verbose,
                                           args.ignore_scene) else 1
        with tempfile.TemporaryDirectory(prefix="cracklab-check-") as tmp:
            new_path = Path(tmp) / "new.json"
            new = record(new_path, names)
            return 0 if compare_recordings(base, new, args.base, new_path, names, args.verbose,
                                           args.ignore_scene) else 1
    if args.command == "compare":
        a, b = load(args.a), load(args.b)
        names = args.only or list(a["cases"])
        return 0 if compare_recordings(a, b, args.a, args.b, names, args.verbose, args.ignore_scene) else 1
    return 2


if __name__ == "__main__":
    sys.exit(main())
