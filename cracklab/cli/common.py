"""What the commands share: the ``cracklab`` command group, the options every command
takes, one-line errors in terms of the options typed (``fail``), the exit on Ctrl-C, and
reading a scene (a TOML file, or the store of an earlier run) or a study file."""
from __future__ import annotations

import os
import sys

import click


CONTEXT = {"help_option_names": ["-h", "--help"]}


class StoreArgument(click.ParamType):
    """A store to read: a URL (``s3://bucket/ens.zarr``: checked by the command, through its
    ``Store``), or a local path that must exist (a directory, with ``dir_only``)."""

    name = "store"

    def __init__(self, dir_only: bool = False):
        self.path = click.Path(exists=True, file_okay=not dir_only)

    def convert(self, value, param, ctx):
        if "://" in str(value):
            return str(value).rstrip("/")
        return self.path.convert(value, param, ctx)


def output_beside(store: str):
    """(directory, stem) of the default outputs next to ``store``; the current directory
    for a store at a URL."""
    from pathlib import Path

    name = Path(store.rstrip("/").rsplit("/", 1)[-1]).name.removesuffix(".zarr")
    return (Path(".") if "://" in store else Path(store.rstrip("/")).parent), name
INTERRUPTED = 130       # exit status on Ctrl-C (128 + SIGINT), as shells report it


@click.group(context_settings=CONTEXT)
@click.version_option(package_name="cracklab")
def main() -> None:
    """cracklab: spectral boundary-integral simulation of dynamic fracture."""


def fail(exc, flags: dict | None = None):
    """A ClickException for ``exc``, an InputError named in terms of the options typed:
    ``flags`` maps an error's field (or its first part) to the option, e.g.
    {"grid.n1": "--n1", "checkpoint_every": "--checkpoint-every"}:
    "--n1 (grid.n1): must be ...", "--checkpoint-every: must be ..."."""
    from ..errors import InputError

    text = str(exc)
    if isinstance(exc, InputError) and flags:
        field = exc.field
        flag = flags.get(field) or flags.get(field.split(".")[0])
        if flag is not None and flag != field:
            rest = text[len(field) + 2:] if text.startswith(field + ": ") else text
            same = flag.lstrip("-").replace("-", "_") == field
            text = f"{flag}: {rest}" if same else f"{flag} ({field}): {rest}"
    return click.ClickException(text)


def exit_interrupted(line: str):
    click.echo(f"cracklab: {line}", err=True)
    sys.exit(INTERRUPTED)


def load_toml(path: str, what: str) -> dict:
    """The tables of a TOML input file: one InputError for a binary file, malformed TOML or
    an empty file (``what``: "a scene", "a study")."""
    from ..errors import InputError
    from ..model.scene_io import read_toml_file

    data = read_toml_file(path)
    if not data:
        raise InputError(path, f"is empty: no TOML tables or keys (expected {what}; see docs/guide/getting_started.md)")
    return data


def load_scene(path: str, allow=()):
    """The scene of a TOML file (its field files read from its folder and below, or the
    ``allow`` folders) or of the store of an earlier run."""
    from ..errors import InputError

    if path.endswith(".toml") or not os.path.isdir(path):     # a scene TOML, whatever its name
        from pathlib import Path

        from ..model.scene_io import scene_from_data

        data = load_toml(path, "a scene: [material], [grid], [law], [loading], t_end")
        return scene_from_data(data, base=Path(path).absolute().parent, allow=allow)  # references relative to it
    from ..output.simulate import scene_of, scene_of_store

    if os.path.exists(os.path.join(path, "zarr.json")):     # Zarr v3: read past arrays changed by hand
        return scene_of_store(path)
    import xarray as xr

    try:
        ds = xr.open_zarr(path, consolidated=False)
    except Exception as exc:  # noqa: BLE001 - reported as one clear line
        raise InputError(path, f"cannot open as a scene TOML or a cracklab Zarr store: {exc}") from None
    if "scene" not in ds.attrs:
        raise InputError(path, "is a Zarr store but not a cracklab run (no 'scene' attribute)")
    return scene_of(ds)


def fmt_time(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.3g} s"
    if seconds < 5400:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"


def disk_line(estimate, output, what: str = "the run", reuse: bool = True, label: str = "output") -> tuple[str, bool]:
    """(the dry run's line on the output's size and the free disk space, whether it fits);
    ``output``: the store (None: the current directory); ``label``: what writes it."""
    from ..errors import DiskBudgetError
    from ..output import disk
    from ..output.stores import is_url
    from ..solver.budget import fmt_bytes

    head = f"  disk      {label} {estimate.describe()}; "
    if output is not None and is_url(output):
        return head + f"{output} is a URL: free space not checked", True
    where = output if output is not None else "."
    where_text = f"free where {output} goes" if output is not None else "free in the current directory (no -o)"
    try:
        room = disk.check_disk(estimate, where, what=what, reuse=reuse)
    except DiskBudgetError:
        return head + f"{fmt_bytes(disk.free_space(where))} {where_text}: does NOT fit: {what} would be refused " \
                      f"(--no-disk-check runs it anyway)", False
    if room == 0:
        return head + f"{where} is not writable: not checked", True
    return head + f"{fmt_bytes(room)} {where_text}: fits", True


def print_note(text: str):
    click.echo(f"cracklab: {text}", err=True)


def pick_member(status, member, allow_partial):
    """The member id for --member (an id, or a position among the members in plan order)."""
    ids = [s["id"] for s in status]
    if member in ids:
        return member
    if member.lstrip("-").isdigit():
        i = int(member)
        if 0 <= i < len(ids):
            return ids[i]
        raise click.ClickException(f"--member {member}: no such member; the store has {len(ids)} member"
                                   f"{'s' if len(ids) != 1 else ''} (positions 0 to {len(ids) - 1}, or an id: "
                                   f"{', '.join(ids[:4])}{', ...' if len(ids) > 4 else ''})")
    raise click.ClickException(f"--member {member}: not a member id of this store (ids: {', '.join(ids[:4])}"
                               f"{', ...' if len(ids) > 4 else ''}; or give a position 0 to {len(ids) - 1})")
