"""Fields of a scene kept in files: the file references of a TOML scene and its sidecar.

In a scene file a field (a law parameter of kind "field" or "mask", a load ``tau0_j``)
is a number, a literal nested list, or a reference to an array in a file::

    tau_c = { file = "toughness.nc", var = "tau_c" }     # netCDF (.nc, .nc4, .cdf)
    tau_c = { file = "toughness.zarr", var = "tau_c" }   # Zarr (a directory)
    tau_c = { file = "toughness.npy" }                   # one numpy array, no var

A relative ``file`` is resolved against the directory of the scene file (of ``base``).
A scene reads files only from its own folder and the folders below it (after symbolic
links are followed), and only regular files (a Zarr field: a directory of them): a scene
received from someone else then cannot copy the reader's other data into its output, nor
hang the run on a FIFO or a device. Other folders are read only when the user allows them
(``allow``: ``cracklab run --allow-files DIR``, or the environment variable
CRACKLAB_ALLOW_FILES, folders separated by ``os.pathsep``). Where each field came from
(the reference as written and the SHA-256 of the file's bytes) is kept with the scene
(``Scene.sources``) and written as the ``source`` attribute of its input variable.
The array must have the grid's shape (``Grid.shape``: (n1, n3), or (n1, n3 + 1) on a
half plane; in the plane problem (n1,) is taken as (n1, 1)). A netCDF or Zarr variable
must lie on the dims ``x1`` and ``x3`` (either order), and each must carry its coordinate,
equal to the grid's nodes (``Grid.x1``, ``Grid.x3``) to a millionth of a cell: a field
written for another grid or another cell is refused rather than silently misplaced. A
mask is boolean, or integers 0 and 1 (netCDF has no boolean type). Every failure (no such
file, no such variable, a file that cannot be read, the wrong dims, shape, coordinates or
values) is one InputError naming the field and saying what was expected.

``write_sidecar`` writes every array-valued parameter of a scene into one netCDF file
(``Scene.to_toml(path)``): variables ``<section>_<key>`` on (x1, x3) with the grid's
coordinates, as ``Scene.to_dataset`` lays them out, and nothing else (the scalars live
in the TOML, once).
"""
from __future__ import annotations

import hashlib
import os
import stat
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError
from .units import convert

NETCDF_SUFFIXES = (".nc", ".nc4", ".netcdf", ".cdf")
ZARR_SUFFIXES = (".zarr",)
NPY_SUFFIXES = (".npy",)
FORMATS = "netCDF (.nc, .nc4, .netcdf, .cdf), Zarr (.zarr, a directory) or numpy (.npy)"
REF_KEYS = ("file", "var")
#: a coordinate of a file matches the grid's node when within this fraction of a cell
COORD_TOLERANCE = 1e-6
#: folders besides the scene file's own from which field files may be read (os.pathsep-separated)
ALLOW_ENV = "CRACKLAB_ALLOW_FILES"
#: a Zarr field with more entries than this is not walked (and refused)
MAX_ZARR_ENTRIES = 100_000


def is_file_reference(value) -> bool:
    """True for a table with the key ``file`` (what a field reads from a file)."""
    return isinstance(value, dict) and "file" in value


def describe(ref) -> str:
    """The reference as the TOML writes it, for messages."""
    parts = [f"{k} = {ref[k]!r}" for k in REF_KEYS if k in ref]
    return "{" + ", ".join(parts) + "}"


def _format(path: Path) -> str | None:
    suffix = path.suffix.lower()
    if suffix in NETCDF_SUFFIXES:
        return "netcdf"
    if suffix in ZARR_SUFFIXES or (path.is_dir() and suffix not in NPY_SUFFIXES):
        return "zarr"
    if suffix in NPY_SUFFIXES:
        return "npy"
    return None


def allowed_roots(base, allow=()) -> list[Path]:
    """The folders field files may be read from: the scene file's (``base``; None: the
    current directory), the ``allow`` folders and those of CRACKLAB_ALLOW_FILES."""
    extra = [a for a in os.environ.get(ALLOW_ENV, "").split(os.pathsep) if a.strip()]
    roots = [Path(base if base is not None else os.getcwd())] + [Path(a).expanduser() for a in (*allow, *extra)]
    return [r.resolve() for r in roots]


def _kind_of(mode) -> str | None:
    """The name of a special file's kind (None for a regular file or a directory)."""
    for test, name in ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return None if stat.S_ISREG(mode) or stat.S_ISDIR(mode) else "not a regular file"


def _inside(path: Path, roots) -> bool:
    return any(path == r or path.is_relative_to(r) for r in roots)


def _outside_message(name, real, roots, base) -> str:
    where = "the scene file's folder" if base is not None else "the current directory"
    return (f"file {name!r} lies outside {where} ({roots[0]}): a scene reads field files only from its "
            f"own folder and below ({real} is not), so that a scene from someone else cannot copy other "
            f"data of yours into its output; to read it, allow its folder (cracklab run --allow-files "
            f"{real.parent}, or {ALLOW_ENV}={real.parent})")


def _check_place(field, name, path, roots, base):
    """The file (or each entry of a Zarr directory) is a regular file inside ``roots``."""
    real = path.resolve()
    if not _inside(real, roots):
        raise InputError(field, _outside_message(name, real, roots, base))
    mode = os.stat(real).st_mode
    kind = _kind_of(mode)
    if kind is not None:
        raise InputError(field, f"file {name!r} is {kind}: a field is read only from a regular file (or a "
                                f"Zarr directory of them)")
    if stat.S_ISDIR(mode):
        count = 0
        for top, dirs, files in os.walk(real):
            for entry in dirs + files:
                count += 1
                if count > MAX_ZARR_ENTRIES:
                    raise InputError(field, f"file {name!r}: a directory of more than {MAX_ZARR_ENTRIES} "
                                            f"entries is not read as a field")
                inner = Path(top) / entry
                target = inner.resolve()
                if not _inside(target, roots):
                    raise InputError(field, f"file {name!r}: its entry {inner.relative_to(real)} links to "
                                            f"{target}, outside the folders field files are read from")
                try:
                    mode = os.stat(target).st_mode
                except OSError:
                    continue  # a dangling link: the reader reports what it misses
                kind = _kind_of(mode)
                if kind is not None:
                    raise InputError(field, f"file {name!r}: its entry {inner.relative_to(real)} is {kind}; "
                                            f"a field is read only from regular files")
    return real


def source_of(ref, path: Path) -> str:
    """Where a field came from, for the store's provenance: the reference as the scene
    wrote it and the SHA-256 of the bytes read (of every file of a Zarr directory, in
    path order)."""
    h = hashlib.sha256()
    files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
    for p in files:
        if p is not path:
            h.update(str(p.relative_to(path)).encode() + b"\0")
        with open(p, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    return f"file reference {describe(ref)}, sha256 {h.hexdigest()}"


def resolve(field: str, ref, base, allow=()) -> tuple[Path, str, str | None]:
    """(path, format, var) of a file reference, checked for its keys and for the file: a
    regular file (or a Zarr directory of them) inside the folders of :func:`allowed_roots`."""
    if not isinstance(ref, dict):
        raise InputError(field, f"must be a file reference {{file = ..., var = ...}}, got {ref!r}")
    unknown = [k for k in ref if k not in REF_KEYS]
    if unknown:
        raise InputError(field, f"unknown key {unknown[0]!r} in the file reference {describe(ref)}; "
                                f"accepted: {', '.join(REF_KEYS)}")
    name = ref["file"]
    if not isinstance(name, str) or not name.strip() or "\x00" in name:
        raise InputError(field, f"file must be the path of a file (a string), got {name!r}")
    path = Path(name).expanduser()
    if not path.is_absolute():
        path = Path(base if base is not None else os.getcwd()) / path
    try:
        exists = path.exists()
    except (OSError, ValueError):
        exists = False
    if not exists:
        where = "the scene file's directory" if base is not None else "the current directory"
        raise InputError(field, f"no such file {name!r} (looked for {path}; a relative path is taken from "
                                f"{where})")
    path = _check_place(field, name, path, allowed_roots(base, allow), base)
    fmt = _format(path)
    if fmt is None:
        raise InputError(field, f"file {name!r}: unknown format {path.suffix or '(no suffix)'!r}; a field is read "
                                f"from {FORMATS}")
    var = ref.get("var")
    if fmt == "npy":
        if var is not None:
            raise InputError(field, f"file {name!r} is a .npy file, which holds one array: give no var, got "
                                    f"var = {var!r}")
    elif not isinstance(var, str) or not var:
        got = "none" if var is None else repr(var)
        raise InputError(field, f"file {name!r} is {'netCDF' if fmt == 'netcdf' else 'Zarr'}: give the variable "
                                f"that holds the field, {{file = {name!r}, var = \"...\"}}, got var {got}")
    return path, fmt, var


def _open(field, path, fmt, name):
    import xarray as xr

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")       # consolidated metadata or not: either is read
            if fmt == "netcdf":
                return xr.open_dataset(path, decode_times=False, decode_timedelta=False)
            return xr.open_dataset(path, engine="zarr", consolidated=None, decode_times=False,
                                   decode_timedelta=False)
    except Exception as exc:  # noqa: BLE001 - any unreadable file is one clear error
        kind = "netCDF" if fmt == "netcdf" else "Zarr"
        raise InputError(field, f"file {name!r} cannot be read as {kind}: {type(exc).__name__}: {exc}") from None


def _check_coords(field, da, grid, name, var):
    """The x1 (and x3) coordinates of ``da`` are the grid's nodes."""
    for dim, nodes, step, n, length in (("x1", grid.x1, grid.dx1, "n1", "L1"), ("x3", grid.x3, grid.dx3, "n3", "L3")):
        if dim not in da.dims:
            continue
        if dim not in da.coords:
            raise InputError(field, f"variable {var!r} of {name!r} has no {dim} coordinate: give the dims x1 and "
                                    f"x3 their coordinates (the grid's nodes, {dim} = k {length} / {n}), or use a "
                                    f".npy file for a bare array")
        values = np.asarray(da[dim].values)
        if values.dtype.kind not in "fiu":
            raise InputError(field, f"the {dim} coordinate of {var!r} in {name!r} must be numbers, got dtype "
                                    f"{values.dtype}")
        values = values.astype(float)
        off = np.abs(values - nodes) > COORD_TOLERANCE * step
        if np.any(off):
            k = int(np.argmax(off))
            shown = f"{nodes[0]:g}, {nodes[1]:g}, ..., {nodes[-1]:g}" if len(nodes) > 2 else \
                ", ".join(f"{x:g}" for x in nodes)
            raise InputError(field, f"the {dim} coordinate of {var!r} in {name!r} must be the grid's nodes {dim} = "
                                    f"{shown} ({n} = {len(nodes)}, d{dim} = {step:g}); it differs at index {k}: "
                                    f"{values[k]:g} instead of {nodes[k]:g}")


def _expected(grid) -> str:
    if grid.free_surface:
        return f"(n1, n3 + 1) = {grid.shape} (the half plane below the free surface)"
    return f"(n1, n3) = {grid.shape}" + (f" (or ({grid.n1},) in the plane problem)" if grid.plane else "")


def _from_dataset(field, path, fmt, var, name, grid, unit=None):
    ds = _open(field, path, fmt, name)
    with ds:
        if var not in ds.variables:
            held = [v for v in ds.data_vars] or list(ds.variables)
            raise InputError(field, f"file {name!r} has no variable {var!r}; it has: "
                                    f"{', '.join(map(str, held)) or 'none'}")
        da = ds[var]
        dims = tuple(da.dims)
        if set(dims) == {"x1", "x3"} and len(dims) == 2:
            da = da.transpose("x1", "x3")
        elif not (grid.plane and dims == ("x1",)):
            plane = " (or (x1,) in the plane problem)" if grid.plane else ""
            raise InputError(field, f"variable {var!r} of {name!r} must lie on the dims (x1, x3){plane}, got "
                                    f"{dims}")
        shape = tuple(da.shape)
        want = grid.shape if len(dims) == 2 else (grid.n1,)
        if shape != want:
            raise InputError(field, f"field shape must be {_expected(grid)}, got {shape} (variable {var!r} of "
                                    f"{name!r}, dims {tuple(da.dims)})")
        _check_coords(field, da, grid, name, var)
        try:
            values = np.asarray(da.values)
        except Exception as exc:  # noqa: BLE001 - damaged chunks, missing data
            raise InputError(field, f"variable {var!r} of {name!r} cannot be read: {type(exc).__name__}: "
                                    f"{exc}") from None
        if unit is not None and values.dtype.kind in "iuf":
            values = convert(field, values, da.attrs.get("units"), unit, f"variable {var!r} of {name!r}")
    return values.reshape(grid.shape)


def _from_npy(field, path, name, grid):
    try:
        with open(path, "rb") as fh:
            magic = fh.read(6)
    except OSError as exc:
        raise InputError(field, f"file {name!r} cannot be read: {exc.strerror or exc}") from None
    if magic != b"\x93NUMPY":
        raise InputError(field, f"file {name!r} is not a .npy file (as numpy.save writes them)")
    try:
        values = np.load(path, allow_pickle=False)
    except ValueError as exc:
        raise InputError(field, f"file {name!r} cannot be read as a .npy array of numbers: {exc}") from None
    except Exception as exc:  # noqa: BLE001 - not a .npy file, a directory, no permission
        raise InputError(field, f"file {name!r} cannot be read as .npy: {type(exc).__name__}: {exc}") from None
    if not isinstance(values, np.ndarray):
        raise InputError(field, f"file {name!r} must hold one array (np.save), not an archive of several")
    shape = values.shape
    if shape != grid.shape and not (grid.plane and shape == (grid.n1,)):
        raise InputError(field, f"field shape must be {_expected(grid)}, got {shape} (the array in {name!r})")
    return values.reshape(grid.shape)


def read_field_file(field: str, ref, grid, kind: str = "field", base=None, allow=(),
                    sources: dict | None = None, unit: str | None = None) -> np.ndarray:
    """The array a file reference ``ref`` points at, for the field named ``field`` (e.g.
    ``law.tau_c``), checked against ``grid``: a float array for kind "field", a boolean one
    for "mask". ``base``: the directory relative paths start from (None: the current one);
    ``allow``: further folders files may be read from (:func:`allowed_roots`); ``sources``:
    a dict that receives ``{field: source_of(ref, path)}``. ``unit``: the scene's unit of
    the field; a netCDF or Zarr variable with a ``units`` attr is converted to it
    (``cracklab.model.units.convert``), one without is taken as in it."""
    path, fmt, var = resolve(field, ref, base, allow)
    if sources is not None:
        try:
            sources[field] = source_of(ref, path)
        except OSError as exc:
            raise InputError(field, f"file {ref['file']!r} cannot be read: {exc.strerror or exc}") from None
    name = ref["file"]
    values = _from_npy(field, path, name, grid) if fmt == "npy" else \
        _from_dataset(field, path, fmt, var, name, grid, unit)
    source = f"{var!r} of {name!r}" if var else repr(name)
    if kind == "mask":
        if values.dtype == bool:
            return values
        if values.dtype.kind in "iu" and np.all((values == 0) | (values == 1)):
            return values.astype(bool)
        raise InputError(field, f"must be a boolean mask: booleans, or integers 0 and 1, got dtype {values.dtype} "
                                f"in {source}")
    if values.dtype.kind in "iu":
        return values.astype(float)
    if values.dtype.kind != "f":
        raise InputError(field, f"must be a field of numbers, got dtype {values.dtype} in {source}")
    if np.isnan(values).any():
        raise InputError(field, f"field values must be finite, got NaN in {source} (a missing value or a "
                                f"_FillValue of the file?)")
    return values


def sidecar_path(toml_path) -> Path:
    """The sidecar of a scene file: ``scene.toml`` -> ``scene.fields.nc`` next to it."""
    toml_path = Path(toml_path)
    return toml_path.with_name(toml_path.stem + ".fields.nc")


def write_sidecar(scene, path, fields: dict, toml_name: str) -> None:
    """Write ``fields`` ({variable name: (section, key, array)}) of ``scene`` into the
    netCDF file ``path`` (replaced atomically), on (x1, x3) with the grid's coordinates."""
    import xarray as xr

    from ..version import __version__
    from .units import input_unit

    grid, length = scene.grid, scene.units.get("length", "1")
    coords = {
        "x1": ("x1", grid.x1, {"units": length, "long_name": "distance along x1", "axis": "X"}),
        "x3": ("x3", grid.x3, {"units": length, "long_name": "distance along x3", "axis": "Y"}),
    }
    ds = xr.Dataset(coords=coords)
    for name, (section, key, value) in fields.items():
        ds[name] = (("x1", "x3"), np.asarray(value),
                    {"long_name": f"scene parameter {section}.{key}", "units": input_unit(scene, section, key)})
    ds.attrs = {"title": f"fields of the cracklab scene {scene.name!r}",
                "source": f"cracklab {__version__}: Scene.to_toml",
                "comment": f"referenced from {toml_name}; the scalar parameters are in that file"}
    encoding = {name: {"zlib": True, "complevel": 4, "shuffle": True, "_FillValue": None} for name in fields}
    encoding.update({c: {"_FillValue": None} for c in ("x1", "x3")})
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
