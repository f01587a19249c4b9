"""Ensembles: parameter sweeps run on dask.distributed into one Zarr v3 store.

A sweep turns one base (a ``Scene``, or a scene builder with its base arguments) into
members: the Cartesian product of the ``product`` axes, plus explicit ``members``, each
optionally repeated ``replicates`` times with its own random seed. Parameter names are

* builder arguments (``diameter``, ``contrast``, ``n1``, ...): any keyword the builder
  accepts; ``builder`` itself may be a member parameter (another builder for that member);
* scene paths: ``<section>.<key>`` with section one of material, grid, law, loading,
  record, numerics (``law.tau_c``, ``loading.tau0_2``, ``record.every``), or the top-level
  ``t_end``, ``beta``, ``name`` when the builder does not take them itself. They are
  applied to the built scene with ``dataclasses.replace`` (so they are validated).

Every member has an id: the first 16 hex digits of the SHA-256 of the canonical JSON
(sorted keys, no whitespace) of its resolved parameters and its base; the id does not
depend on the order in which parameters are given and is the same in every run.

Store layout (one Zarr v3 store)::

    STORE.zarr/                  root group, attrs: cracklab_ensemble (format), study, members
      <coordinates>              the member table: member (ids), one array per swept parameter,
                                 status (written at the end of every sweep, with the store's
                                 consolidated metadata: xarray.open_zarr(STORE) shows it)
      members/
        <id>/                    what ``cracklab.simulate(scene, store=...)`` writes, plus attrs
                                 member_id, member_params (JSON), member_swept (JSON),
                                 status (running | complete | failed | damaged), elapsed_s,
                                 worker, error and traceback (failed), and complete (true,
                                 written last)

Workers write their member group directly; only a small status record goes back to
the client. A rerun verifies the members whose group says ``complete`` (``cracklab.output.verify``),
skips the sound ones and redoes the others, damaged ones included. A complete member
that is run again is written to a hidden sibling group and swapped in whole.

Modules: ``spec`` (Builder, Sweep, Study, Member, SweepResult), ``identity`` (canonical
values, member ids, digests), ``planning`` (the members
of a sweep, one member's scene), ``store`` (paths, checks, member records, atomic
replacement), ``lock`` (the store lock), ``running`` (dask, ``run``, the worker task),
``study`` (STUDY.toml), ``read`` (member_status, open_member, open_ensemble, member_scene),
``members_table`` (the member table at the root: written, and checked against the
members), ``checks`` (a member's parameters against its id and scene), ``verify`` (what
``cracklab verify`` checks of a store);
the builder registry is ``cracklab.scenes.registry``;
``summary`` (the table of parameters and measures per member) is computed by
``cracklab.analysis``;
the netCDF export is ``cracklab.ensemble.netcdf``.

See docs/guide/ensembles.md for the STUDY.toml format and examples.
"""
from ..errors import InputError, StoreError
from .netcdf import export_netcdf, netcdf_ready
from ..scenes.registry import (ENTRY_POINT_GROUP, builder_name, register_builder, registered_builders,
                               resolve_builder, unregister_builder)
from .identity import (FORMAT, ID_LENGTH, canonical, canonical_json, coordinate_name, member_id,
                       scene_digest)
from .lock import LOCK_GRACE_S, LOCK_NAME, StoreLocked, store_lock
from .planning import SECTIONS, SEED_BITS, TOP_LEVEL, apply_paths, build_scene, plan
from .read import NO_INTEGER, UNREADABLE, member_scene, member_status, open_ensemble, open_member
from .running import run
from .spec import Builder, Member, Study, Sweep, SweepResult
from .members_table import write_member_table
from .store import MEMBERS, SWAP_TAG, is_ensemble, member_path, store_kind
from .study import STUDY_KEYS, load_study, run_study

__all__ = ["Builder", "Sweep", "Study", "Member", "SweepResult", "load_study", "plan", "run",
           "run_study", "open_ensemble", "open_member", "member_status", "member_scene",
           "build_scene", "is_ensemble", "store_kind", "coordinate_name", "export_netcdf", "store_lock",
           "StoreLocked", "register_builder", "unregister_builder", "registered_builders",
           "resolve_builder", "ENTRY_POINT_GROUP", "summary", "NO_INTEGER"]


def summary(store, *, complete_only=False):
    """Parameters and summary measures per member of the ensemble ``store`` (or of an
    ``open_ensemble`` Dataset, or a run) as an xarray Dataset along ``member``;
    ``.to_dataframe()`` is a tidy pandas table, one row per member. Computed by
    :func:`cracklab.analysis.summary`, which documents the measures."""
    from ..analysis.table import summary as table

    return table(store, complete_only=complete_only)
