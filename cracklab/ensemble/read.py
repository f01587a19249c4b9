"""Reading an ensemble store: ``member_status``, ``open_member``, ``open_ensemble`` (one
Dataset with a ``member`` dimension, or a DataTree) and ``member_scene``."""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..errors import InputError, StoreError
from .identity import FORMAT, canonical_json, coordinate_name
from .store import MEMBERS, check_metadata, error_line, member_attrs, open_group, store_kind, store_str
from ..output.stores import is_url, zarr_of


def member_status(store) -> list[dict]:
    """One dict per member group in the store (plan order): id, status, complete, params,
    swept, error, traceback, elapsed_s."""
    store = store_str(store)
    if store_kind(store) != "ensemble":
        raise InputError("store", f"{store} is not a cracklab ensemble store (it is a single run)")
    root = open_group(store, "r")
    ids = list(root.attrs.get("members", []))
    local = not is_url(store)
    if local:
        check_metadata(store, Path(store) / MEMBERS / "zarr.json",
                        "rerun the sweep (cracklab sweep STUDY.toml -o STORE) to repair it")
    try:
        members_group = root[MEMBERS] if MEMBERS in root else None
        if members_group is None:
            present = []
        elif local:         # listed by their directories: one damaged member must not hide the others
            present = sorted(e.name for e in os.scandir(Path(store) / MEMBERS)
                             if e.is_dir() and not e.name.startswith(".") and Path(e.path, "zarr.json").exists())
        else:
            present = sorted(k for k in members_group.group_keys() if not k.startswith("."))
    except (ValueError, KeyError, OSError) as exc:
        raise StoreError(store, f"its members group {store}/{MEMBERS} cannot be read ({exc}); rerun the sweep "
                                f"(cracklab sweep STUDY.toml -o STORE) to repair it") from None
    order = [i for i in ids if i in set(present)] + [i for i in present if i not in set(ids)]
    out = []
    for mid in order:
        try:
            a = dict(members_group[mid].attrs)
            entry = {"id": mid, "status": a.get("status", "unknown"), "complete": a.get("complete") is True,
                     "params": json.loads(a.get("member_params", "{}")),
                     "swept": json.loads(a.get("member_swept", "[]")),
                     "error": a.get("error"), "traceback": a.get("traceback"),
                     "elapsed_s": a.get("elapsed_s")}
        except (ValueError, KeyError, TypeError, OSError) as exc:     # damaged metadata: reported, never read
            meta = f"{store}/{MEMBERS}/{mid}/zarr.json"
            entry = {"id": mid, "status": "damaged", "complete": False, "params": {}, "swept": [],
                     "error": f"damaged: {meta}: {UNREADABLE} ({error_line(exc)})",
                     "traceback": None, "elapsed_s": None}
        out.append(entry)
    return out


UNREADABLE = "the member's metadata cannot be read"


def _member_damage(store, mid):
    """None, or a StoreError for the complete member ``mid`` whose metadata or chunk
    listing is damaged, or whose metadata does not match what is stored (cheap: no data is
    read but the scene's inputs; a changed byte raises when read). At a URL the same
    checks, over the member's keys only (one listing)."""
    from ..output.verify import store_tree
    from .checks import check_member

    report = check_member(store_tree(store, members=[mid]) if is_url(store) else store, mid, read=False)
    if report.ok:
        return None
    return StoreError(store, f"member {mid} is damaged: {report.first()}; rerun the sweep (cracklab sweep "
                             f"STUDY.toml -o STORE): it recomputes damaged members")


def open_member(store, member: str):
    """One member's Dataset, as ``cracklab.simulate`` wrote it (``scene_of`` works on it)."""
    import xarray as xr

    store = store_str(store)
    attrs = member_attrs(store, member)
    if attrs is None and not is_url(store) and (Path(store) / MEMBERS / member / "zarr.json").exists():
        check_metadata(store, Path(store) / MEMBERS / member / "zarr.json",
                        "rerun the sweep (cracklab sweep STUDY.toml -o STORE): it recomputes the member")
    if attrs is not None and attrs.get("complete") is True:
        err = _member_damage(store, member)
        if err is not None:
            raise err
    try:
        return xr.open_zarr(zarr_of(store), group=f"{MEMBERS}/{member}", consolidated=False)
    except FileNotFoundError:
        raise InputError("member", f"{member!r} is not a member of {store}") from None
    except (ValueError, KeyError, OSError) as exc:
        raise StoreError(store, f"member {member} cannot be read ({error_line(exc)}); cracklab verify {store} "
                                f"names the damaged files; rerun the sweep to recompute it") from None


NO_INTEGER = -1      # an integer parameter a member does not have (a seed of an unseeded member)


def _coord_values(values):
    """(1-D coordinate array, extra attrs) from per-member values (None where a member lacks
    it): booleans as bool, integers as int64 (``NO_INTEGER`` where missing), other numbers
    as float64 (NaN where missing), anything else as text ("" where missing; lists and
    tables as JSON)."""
    present = [v for v in values if v is not None]
    full = len(present) == len(values)
    if present and full and all(isinstance(v, bool) for v in present):
        return np.array(values, dtype=bool), {}
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        if all(isinstance(v, int) for v in present):
            out = np.array([NO_INTEGER if v is None else v for v in values], dtype=np.int64)
            return out, ({} if full else {"comment": f"{NO_INTEGER}: the member does not have this parameter"})
        return np.array([np.nan if v is None else float(v) for v in values]), {}
    return np.array(["" if v is None else (v if isinstance(v, str) else json.dumps(v)) for v in values],
                    dtype=object), {}


def swept_names(status) -> list[str]:
    """The swept parameters of these members (``member_status`` entries), in order; plus
    ``builder`` when they use different builders."""
    swept = list(dict.fromkeys(k for s in status for k in s["swept"]))
    if len({s["params"].get("builder") for s in status}) > 1 and "builder" not in swept:
        swept.append("builder")
    return swept


def member_coords(status, swept=None) -> dict:
    """The coordinates along ``member`` of these members (``member_status`` entries): the
    ids (``member``), one per swept parameter in its own type (see ``open_ensemble``) and
    ``status``."""
    swept = swept_names(status) if swept is None else swept
    coords = {"member": ("member", np.array([s["id"] for s in status], dtype=object),
                         {"long_name": "ensemble member id"})}
    for name in swept:
        values, extra = _coord_values([s["params"].get(name) for s in status])
        coords[coordinate_name(name)] = ("member", values,
                                         {"long_name": f"swept parameter {name}", "parameter": name, **extra})
    coords["status"] = ("member", np.array([str(s["status"]) for s in status], dtype=object),
                        {"long_name": "status of the member's run (complete, failed, running, damaged)"})
    return coords


def open_ensemble(store, *, members=None, complete_only=True, tree=False):
    """The ensemble as one lazily loaded xarray Dataset with a ``member`` dimension.

    Coordinates along ``member``: the member ids (``member``), one per swept parameter in
    its own type (dots in names become underscores: law.tau_c -> law_tau_c; attr
    ``parameter`` keeps the name): integers (seeds included) as int64, other numbers as
    float64, booleans as bool, text as str; a member without the parameter has NaN, -1
    for an integer (``NO_INTEGER``), "" for text. Then ``status`` (complete, or the
    status of a member read with ``complete_only=False``) and ``scene_name``. The scenes
    are not coordinates: attr ``scenes`` holds them (JSON {id: scene}; ``member_scene``
    rebuilds one). So ``crack_length(ens).isel(t=-1).to_dataframe()`` is a tidy table.

    Members on different grids or snapshot times are aligned by an outer join (the union
    of the coordinates, NaN where a member has no value). With ``tree=True`` a DataTree is
    returned instead: the member coordinates at its root, one node /members/<id> per
    member (no padding). Only complete members are read unless ``complete_only=False``;
    ``members``: only these ids (e.g. ``[m.id for m in result.members]`` of one sweep).
    Ready for ``ds.groupby("contrast")`` and ``ds.set_xindex("diameter").sel(diameter=...)``;
    every function of ``cracklab.analysis`` takes it (one result per member)."""
    import xarray as xr

    store = store_str(store)
    status = member_status(store)
    if members is not None:
        wanted = [getattr(m, "id", m) for m in members]
        by_id = {s["id"]: s for s in status}
        missing = [m for m in wanted if m not in by_id]
        if missing:
            raise InputError("members", f"not in {store}: {', '.join(missing[:5])}")
        status = [by_id[m] for m in wanted]
    unreadable = [s for s in status if s["status"] == "damaged" and UNREADABLE in str(s.get("error"))]
    if unreadable:
        raise StoreError(store, f"member {unreadable[0]['id']} is {unreadable[0]['error']}; rerun the sweep "
                                f"(cracklab sweep STUDY.toml -o STORE): it recomputes damaged members")
    if complete_only:
        status = [s for s in status if s["complete"]]
    if not status:
        raise InputError("store", f"{store} holds no complete members")
    root_attrs = dict(open_group(store, "r").attrs)
    datasets, scenes, kept = [], [], []
    for s in status:
        try:
            ds = open_member(store, s["id"])
        except InputError:
            if complete_only:           # replaced meanwhile (a sweep swapping it): not complete now
                continue
            raise
        if complete_only and ds.attrs.get("complete") is not True:
            continue                    # rewritten since it was listed: the group read is not complete
        kept.append(s)
        scene_json = ds.attrs.get("scene", "{}")
        scenes.append(scene_json)
        ds = with_input_coords(ds, scene_json)
        ds.attrs = {k: v for k, v in ds.attrs.items() if k in ("Conventions", "source", "cracklab_version")}
        datasets.append(ds)
    status = kept
    if not status:
        raise InputError("store", f"{store} holds no complete members")
    swept = swept_names(status)
    coords = member_coords(status, swept)
    names = []
    for text in scenes:
        try:
            names.append(str(json.loads(text).get("name", "")))
        except (ValueError, AttributeError):
            names.append("")
    coords["scene_name"] = ("member", np.array(names, dtype=object), {"long_name": "scene name"})
    attrs = {**_ensemble_attrs(root_attrs, store), "swept": json.dumps(swept), "scenes": _scenes_attr(status, scenes)}
    if tree:
        nodes = {"/": xr.Dataset(coords=coords, attrs=attrs)}
        for s, ds, text in zip(status, datasets, scenes):
            nodes[f"/{MEMBERS}/{s['id']}"] = ds.assign_attrs(scene=text, member_id=s["id"],
                                                             member_params=canonical_json(s["params"]))
        return xr.DataTree.from_dict(nodes)
    try:
        ens = xr.concat(datasets, dim="member", join="outer", data_vars="all", coords="different",
                        compat="equals", combine_attrs="drop_conflicts", fill_value=np.nan)
    except (ValueError, KeyError) as exc:
        raise StoreError(store, f"its members cannot be combined ({error_line(exc)}); a member is probably "
                                f"damaged: cracklab verify {store} names the files, and rerunning the sweep "
                                f"recomputes damaged members") from None
    ens = ens.assign_coords(coords)
    ens.attrs.update(attrs)
    return ens


def _scenes_attr(status, scenes) -> str:
    """The ``scenes`` attr of an ensemble: JSON {member id: the member's scene (its JSON form)}."""
    out = {}
    for s, text in zip(status, scenes):
        try:
            out[s["id"]] = json.loads(text)
        except ValueError:
            out[s["id"]] = {}
    return json.dumps(out, sort_keys=False, separators=(",", ":"))


def scene_text(ens, member=None) -> str:
    """The scene JSON of one member of an ``open_ensemble`` Dataset (``member``: its id), or
    of a single run's Dataset (its ``scene`` attr); "{}" when there is none."""
    if member is None and "member" in ens.coords and ens["member"].ndim == 0:
        member = ens["member"].item()
    if member is not None and "scenes" in ens.attrs:
        scene = json.loads(ens.attrs["scenes"]).get(str(member))
        if scene is not None:
            return json.dumps(scene)
    if member is not None and "scene" in ens.coords:         # a netCDF file of an older cracklab
        da = ens["scene"]
        return str(da.sel(member=member).item() if "member" in da.dims else da.item())
    return ens.attrs.get("scene", "{}")


def with_input_coords(ds, scene_json):
    """Give the input_x1/input_x3 dims (full-grid scene inputs) their coordinates, in the
    scene's length unit, so that members on different grids align on them."""
    dims = [d for d in ("input_x1", "input_x3") if d in ds.dims and d not in ds.coords]
    if not dims:
        return ds
    try:
        scene = json.loads(scene_json)
        grid = scene["grid"]
        length = str((scene.get("units") or {}).get("length", "1"))
    except (ValueError, KeyError, TypeError, AttributeError):
        return ds
    coords = {}
    for d, n, L in (("input_x1", "n1", "L1"), ("input_x3", "n3", "L3")):
        # a free surface's half plane has n3 + 1 nodes along x3 (cracklab.Grid)
        nodes = int(grid.get(n, 0)) + (d == "input_x3" and grid.get("free_surface") is True)
        if d in dims and n in grid and L in grid and nodes == ds.sizes[d]:
            coords[d] = (d, np.arange(nodes) * float(grid[L]) / int(grid[n]),
                         {"long_name": f"{d[len('input_'):]} of the scene inputs", "units": length})
    return ds.assign_coords(coords)


def _ensemble_attrs(root_attrs, store):
    return {"title": root_attrs.get("title", "cracklab ensemble"), "cracklab_ensemble": FORMAT,
            "study": root_attrs.get("study", "{}"), "axes": root_attrs.get("axes", "[]"),
            "ensemble_store": store}


def member_scene(ens, member):
    """The Scene of one member of an ``open_ensemble`` Dataset (its ``scenes`` attr), or of
    any Dataset with a ``scene`` attr."""
    from ..model.scene_io import scene_from_data

    ds = ens.sel(member=member) if "member" in ens.dims else ens
    text = scene_text(ens, member if "member" in ens.dims else None)
    if text == "{}":
        raise InputError("member", f"no scene of member {member!r} in this Dataset")
    arrays = {}
    for n in ds.data_vars:
        if n.startswith("input_"):
            a = ds[n]
            a = a.dropna("input_x1", how="all").dropna("input_x3", how="all") if a.dtype.kind == "f" else a
            arrays[n] = np.asarray(a.values)
    data = json.loads(text)
    wanted = set()

    def refs(d):
        if isinstance(d, dict):
            if set(d) == {"array"}:
                wanted.add(d["array"])
            for v in d.values():
                refs(v)

    refs(data)
    arrays = {k: (v.astype(bool) if k.endswith(("bonded", "initial_crack")) and v.dtype != bool else v)
              for k, v in arrays.items() if k in wanted}
    return scene_from_data(data, arrays)
