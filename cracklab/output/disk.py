"""The disk space a run's store needs, known before it starts.

``output_size(scene)`` bounds the bytes a run writes into its Zarr store from the scene
alone: the snapshots of the recorded fields (float64 on the recorded region), the station
series, the rupture times, the scene's input fields and the coordinates, each chunk as
zstd writes it at worst (its input plus 1/256 and a frame header: zstd's own bound, since
data that does not compress is stored raw) with its crc32c checksum, in a file of its own
that takes whole blocks of the file system. Fields compress, often several times (a
crack's opening is zero ahead of its front), but by how much depends on the run: the
bound is what ``check_disk`` holds against the free space of the store's file system, so
that a run is never started that its disk may not hold.
"""
from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from ..errors import DiskBudgetError
from ..model.record import face_field

#: the file system's allocation unit assumed for each chunk file (the common 4 kB)
BLOCK = 4096
#: bytes of zarr metadata per array (zarr.json) and of the group's attrs, at most
META = 8192
#: the snapshots of one chunk hold at most this many bytes (output/simulate.py, Recorder.create)
CHUNK_BYTES = 8 << 20
#: snapshots a run keeps before it writes them (Recorder's flush_every)
FLUSH = 8


def snapshots_per_chunk(n1: int, n3: int, flush_every: int = FLUSH) -> int:
    """Snapshots of one chunk of a recorded field on n1 x n3 nodes: at most ``flush_every``
    (what a write holds) and at most ``CHUNK_BYTES`` of float64, at least one."""
    return max(1, min(flush_every, CHUNK_BYTES // max(1, 8 * n1 * n3)))


def _zstd_bound(n: int) -> int:
    """zstd's worst-case compressed size of n bytes (ZSTD_COMPRESSBOUND) plus the crc32c."""
    return n + (n >> 8) + ((128 << 10) - n >> 11 if n < (128 << 10) else 0) + 64 + 4


def _on_disk(nbytes: int) -> int:
    return BLOCK * math.ceil(max(1, _zstd_bound(nbytes)) / BLOCK)


@dataclass(frozen=True)
class OutputEstimate:
    """Bytes a run writes: ``raw`` (the arrays uncompressed) and ``bound`` (the most its
    store takes on disk); ``snapshots``: the number of snapshots, ``fields`` recorded."""

    snapshots: int
    fields: int
    raw: int
    bound: int

    def describe(self) -> str:
        """"at most 16.0 TB (7.68e+06 snapshots of 4 fields; 16.0 TB uncompressed)"."""
        from ..solver.budget import fmt_bytes

        return (f"at most {fmt_bytes(self.bound)} ({self.snapshots:.3g} snapshots of {self.fields} "
                f"field{'s' if self.fields != 1 else ''}; {fmt_bytes(self.raw)} uncompressed)")


def output_size(scene) -> OutputEstimate:
    """The bytes a run of ``scene`` writes into its store (see the module docstring)."""
    grid, rec = scene.grid, scene.record
    n1r, n3r = (len(range(*s.indices(n))) for s, n in zip(rec.region_slices(grid), grid.shape))
    if scene.sequence is not None:      # an estimate: a sequence's steps and events are its own
        nsnap, rows = scene.sequence.expected_rows(scene)
    else:
        nsnap, rows = (rec.snapshot_count(scene.nsteps, scene.dt) if rec.fields else 0), scene.nsteps + 1
    frame = 8 * n1r * n3r
    per_chunk = snapshots_per_chunk(n1r, n3r)
    full, rest = divmod(nsnap, per_chunk)
    field = full * _on_disk(per_chunk * frame) + (_on_disk(rest * frame) if rest else 0)
    raw = nsnap * frame * len(rec.fields)
    bound = field * len(rec.fields)
    # the time coordinate, station series (one array per field, station x t_station), rupture time
    nst = len(rec.stations or {})
    series = 8 * rows * nst
    nser = 3 * len(scene.components) + 1 + sum(1 for f in rec.fields if face_field(f))
    small = [8 * nsnap, 8 * grid.shape[0] * grid.shape[1]] + [series] * (nser if nst else 0)
    small += [8 * grid.shape[0] * grid.shape[1]] * sum(1 for _ in _input_fields(scene))
    raw += sum(small)
    bound += sum(_on_disk(b) for b in small) + META * (len(rec.fields) + len(small) + 8)
    return OutputEstimate(int(nsnap), len(rec.fields), int(raw), int(bound))


def _input_fields(scene):
    from ..model.scene_io import scene_to_data

    return scene_to_data(scene)[1]


def _existing(path: Path) -> Path:
    """The nearest existing folder at or above ``path``."""
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def _size(path: Path) -> int:
    """Bytes a store already takes (what replacing or resuming it frees or reuses)."""
    if not path.is_dir():
        return 0
    total = 0
    for top, _, files in os.walk(path):
        for f in files:
            try:
                total += os.lstat(os.path.join(top, f)).st_blocks * 512
            except OSError:
                pass
    return total


def free_space(path) -> int:
    """Bytes free for this user on the file system that holds (or will hold) ``path``."""
    return shutil.disk_usage(_existing(Path(path))).free


def check_disk(estimate: OutputEstimate, path, *, what: str = "the run", hint: str = "", reuse: bool = True) -> int:
    """Raise DiskBudgetError when the store at ``path`` (a local path) cannot hold
    ``estimate.bound`` bytes: the free space of its file system, plus with ``reuse`` what
    a store already there takes (a resumed or replaced run reuses it; a sweep adds to its
    store). Return the bytes available."""
    from ..solver.budget import fmt_bytes

    path = Path(path)
    where = _existing(path)
    fs = os.statvfs(where)
    if not os.access(where, os.W_OK) or fs.f_flag & os.ST_RDONLY or fs.f_blocks == 0:
        return 0      # read-only, or a pseudo file system with no blocks: creating the store says so
    room = free_space(path) + (_size(path) if reuse else 0)
    if estimate.bound > room:
        raise DiskBudgetError("record", f"{what} writes {estimate.describe()} into {path}, but its file system has "
                                        f"{fmt_bytes(room)} free; refused before any step"
                                        f"{'; ' + hint if hint else ''}")
    return room
