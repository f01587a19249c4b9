"""A small ensemble for the store tests: three elliptical cracks on 16 x 8 grids, swept
into one store synchronously; a sound store made once per module and a fresh copy of it
per test (tests/output/test_store_integrity.py, tests/ensemble/test_ensemble_metadata_trust.py)."""
from __future__ import annotations

import shutil

from cracklab import ensemble as E

BUILDER = E.Builder("elliptical_crack", n=16, a=0.25, b=0.2, t_end=0.3)
SWEEP = E.Sweep(product={"p": [1.0, 2.0, 3.0]},
                base={"record.every": 2, "record.stations": {"c": [0.5, 0.5]}})


#: a study file of two cracks (n = 16, t_end = 0.05), for sweeps through the command line (the
#: object-store tests: tests/output/test_object_store_input.py, test_object_store_lock.py,
#: tests/ensemble/test_object_store_members.py)
STUDY = """
[study]
name = "s3"
builder = "elliptical_crack"
[base]
n = 16
a = 0.25
b = 0.2
t_end = 0.05
record.every = 2
[sweep]
p = [1.0, 1.2]
"""

#: four members of the same cracks, for the sweeps on a cluster (tests/ensemble/test_cluster_slurm.py,
#: test_cluster_processes.py): enough for two workers
CLUSTER_STUDY = STUDY.replace('name = "s3"', 'name = "cluster"').replace("p = [1.0, 1.2]", "p = [1.0, 1.2, 1.4, 1.6]")


def sweep(store, **kw):
    return E.run(BUILDER, SWEEP, store, scheduler="synchronous", progress=False, **kw)


def sound_ensemble(tmp_path_factory, name):
    """(store, its Dataset loaded) of a sweep that succeeded."""
    store = tmp_path_factory.mktemp(name) / "ens.zarr"
    assert sweep(store).ok
    return store, E.open_ensemble(store).load()


def copy_of(sound, tmp_path):
    """A copy of the sound store to damage."""
    store = tmp_path / "ens.zarr"
    shutil.copytree(sound[0], store)
    return store


def member_ids(store):
    return [s["id"] for s in E.member_status(store)]
