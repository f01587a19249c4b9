"""Real FFTs between the plane (x1, x3) and its Fourier modes (Eq. 36).

Layout (Grid.spectral_shape): in 3D a real transform along x3, the contiguous axis
(n3//2 + 1 modes), and a complex one along x1; the plane problem (n3 == 1) uses 1D real
transforms along x1 only.

Free surface (``Grid(free_surface=True)``: the half plane x3 = k dx3, k = 0 .. n3, of the
doubled cell of 2 n3 nodes whose fields are mirrored about x3 = 0): the spectrum of a field
is the doubled cell's Fourier coefficients of its mirrored field on k1 >= 0, (n1//2 + 1,
n3 + 1) modes k3 = pi j / L3. For an even component (1, 2) that is the cosine transform
(DCT-I) along x3, then a real FFT along x1; for the odd component 3, -i times its sine
transform (DST-I), then the same FFT. Holding the doubled cell's coefficients, every mode
is rotated (Eq. 28) and convolved as in the periodic problem, and the inverse carries
1/N with N = n1 2 n3, the doubled cell's (docs/reference/equations.md, "A free surface by mirror
symmetry"). The transforms are computed as the doubled cell's real 2D FFT, which FFTW
does faster than its own cosine and sine transforms (its r2r kinds have no SIMD
codelets), with an even and an odd field at once: their doubled fields are added, and
the spectrum of the sum splits into its even and odd parts by its Hermitian symmetry
along x1 (``forward_components``, ``inverse_components``: the 3D shear pair (1, 3) costs
one transform of the doubled cell, i.e. about what the two transforms of the periodic
n1 x n3 grid cost; a lone even field costs the doubled cell's transform too).

Backends: pyfftw when it is installed (plans made once per grid with FFTW_MEASURE,
wisdom cached per host under the user cache directory as FFTW's own text, in a JSON file:
nothing read from the cache is unpickled), otherwise scipy.fft.
Choose with the environment variable CRACKLAB_FFT=pyfftw|scipy; threads with
``workers`` or CRACKLAB_FFT_THREADS.
"""
from __future__ import annotations

import contextlib
import json
import os
import socket
import tempfile
from pathlib import Path

import numpy as np
import scipy.fft as sfft

from .loops import mirror_join, mirror_pack, mirror_separate, mirror_split

try:  # optional fast backend
    import pyfftw
except ImportError:  # pragma: no cover - exercised on machines without pyfftw
    pyfftw = None


def cache_dir() -> Path:
    """Per-user cache directory ($CRACKLAB_CACHE, else $XDG_CACHE_HOME/cracklab)."""
    root = os.environ.get("CRACKLAB_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "cracklab")
    return Path(root)


#: the wisdom file's format tag, and its largest accepted size (FFTW's wisdom of every size a
#: run plans is a few kB; anything far larger is not a file this module wrote)
WISDOM_FORMAT = "cracklab-fftw-wisdom/1"
WISDOM_MAX_BYTES = 16 * 2**20
#: pyfftw's wisdom is a tuple of FFTW's exported text, one per precision, in this order
_PRECISIONS = ("double", "single", "long double")


def _wisdom_path() -> Path:
    return cache_dir() / f"fftw-wisdom-{socket.gethostname()}.json"


def wisdom_to_json(wisdom) -> str:
    """pyfftw's wisdom (FFTW's exported text per precision, as bytes) as a JSON document."""
    return json.dumps({"format": WISDOM_FORMAT,
                       **{k: w.decode("ascii") for k, w in zip(_PRECISIONS, wisdom)}})


def wisdom_from_json(text: str):
    """The wisdom tuple of a document of :func:`wisdom_to_json`; ValueError if it is not one.
    Only data is read: FFTW's own parser then reads each text (pyfftw.import_wisdom)."""
    doc = json.loads(text)
    if not isinstance(doc, dict) or doc.get("format") != WISDOM_FORMAT:
        raise ValueError("not a cracklab FFTW wisdom file")
    parts = [doc.get(k) for k in _PRECISIONS]
    if not all(isinstance(p, str) for p in parts):
        raise ValueError("wisdom file: a precision's text is missing")
    return tuple(p.encode("ascii") for p in parts)


def _load_wisdom():
    """Make the host's wisdom file the process's wisdom (when it can be read): every plan is
    then the one the file holds for its size, whichever process measured it first, so that
    a run and its resumption in another process transform with the same plan (and give the
    same numbers to the bit).  Without a readable file the process keeps its own wisdom.
    The file is JSON holding FFTW's text (never a pickle: a file planted in the cache must
    not run code); one that is not a regular file, too large or not such a document is
    ignored."""
    path = _wisdom_path()
    try:
        if not path.is_file() or path.stat().st_size > WISDOM_MAX_BYTES:
            return
        wisdom = wisdom_from_json(path.read_text(encoding="ascii"))
    except (OSError, ValueError, UnicodeError):
        return  # no or unreadable wisdom: plan afresh
    pyfftw.forget_wisdom()
    try:
        pyfftw.import_wisdom(wisdom)
    except (ValueError, TypeError):
        pass


def _save_wisdom():
    path = _wisdom_path()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".wisdom-")
        with os.fdopen(fd, "w", encoding="ascii") as fh:
            fh.write(wisdom_to_json(pyfftw.export_wisdom()))
        os.replace(tmp, path)  # atomic: concurrent writers never leave a torn file
    except (OSError, UnicodeError):
        pass  # a read-only cache only costs planning time


@contextlib.contextmanager
def _wisdom_lock():
    """Plans are made one process at a time per host (a lock file beside the wisdom): the
    first to plan a size measures it and saves it, the others then read it (_load_wisdom)."""
    try:
        import fcntl

        path = _wisdom_path().with_suffix(".lock")
        path.parent.mkdir(parents=True, exist_ok=True)
        fh = open(path, "a")
    except (ImportError, OSError):
        yield  # no locking here (another platform, or a read-only cache)
        return
    try:
        fcntl.flock(fh, fcntl.LOCK_EX)
        yield
    finally:
        fh.close()  # releases the lock


@contextlib.contextmanager
def host_wisdom():
    """Plans made inside take the host's wisdom and add theirs to it, one process at a time
    (``_wisdom_lock``, ``_load_wisdom``, ``_save_wisdom``): the same plan, and the same numbers
    to the bit, in a run and in its resumption in another process."""
    with _wisdom_lock():
        _load_wisdom()
        yield
        _save_wisdom()


#: the components odd about a free surface (delta_3, v_3, tau_3); the others are even
ODD = (3,)


def backend_name() -> str:
    choice = os.environ.get("CRACKLAB_FFT", "pyfftw" if pyfftw is not None else "scipy")
    return "pyfftw" if choice == "pyfftw" and pyfftw is not None else "scipy"


class Transforms:
    """Forward and inverse transforms for one grid (``component``: which field they
    transform, which matters only with a free surface: component 3 is odd, :data:`ODD`)."""

    def __init__(self, grid, workers: int | None = None, backend: str | None = None):
        self.shape = grid.shape
        self.plane = grid.plane
        #: a free surface by mirror symmetry: cosine / sine transforms along x3
        self.mirror = bool(getattr(grid, "free_surface", False))
        self.workers = int(workers or os.environ.get("CRACKLAB_FFT_THREADS", "1"))
        self.backend = backend or backend_name()
        self.spectral_shape = grid.spectral_shape
        #: 1/N, the factor of the inverse transform (see ``inverse(prescaled=True)``); with a
        #: free surface N = n1 2 n3, the doubled cell's
        self.norm = 1.0 / (grid.n1 * 2 * grid.n3) if self.mirror else 1.0 / (self.shape[0] * self.shape[1])
        #: transforms run so far, forward and inverse (``cracklab bench`` counts them per step)
        self.count = 0
        if self.backend == "pyfftw":
            self._plan()

    def _plan(self):
        with host_wisdom():
            self._make_plans()

    def _make_plans(self):
        n1, n3 = self.shape
        flags = ("FFTW_MEASURE",)
        if self.mirror:
            self._make_mirror_plans(flags)
        elif self.plane:
            a = pyfftw.empty_aligned(n1, dtype="float64")
            b = pyfftw.empty_aligned(n1 // 2 + 1, dtype="complex128")
            self._fwd = pyfftw.FFTW(a, b, threads=self.workers, flags=flags)
            self._inv = pyfftw.FFTW(b.copy(), a.copy(), direction="FFTW_BACKWARD", threads=self.workers,
                                    flags=flags)
        else:
            a = pyfftw.empty_aligned((n1, n3), dtype="float64")
            b = pyfftw.empty_aligned((n1, n3 // 2 + 1), dtype="complex128")
            self._fwd = pyfftw.FFTW(a, b, axes=(0, 1), threads=self.workers, flags=flags)
            self._inv = pyfftw.FFTW(pyfftw.empty_aligned(b.shape, dtype="complex128"),
                                    pyfftw.empty_aligned(a.shape, dtype="float64"), axes=(0, 1),
                                    direction="FFTW_BACKWARD", threads=self.workers, flags=flags)

    def empty(self, spectral: bool = True) -> np.ndarray:
        """A work array the transforms read or write in place (``out=``, ``overwrite=``):
        complex of the spectral shape, or real of the grid's shape (aligned for FFTW)."""
        shape, dtype = (self.spectral_shape, complex) if spectral else (self.shape, float)
        if self.backend == "pyfftw":
            return pyfftw.empty_aligned(shape, dtype=dtype)
        return np.empty(shape, dtype=dtype)

    def _make_mirror_plans(self, flags):
        """Free surface: the doubled cell's real 2D transforms, (n1, 2 n3) <-> (n1, n3 + 1), each
        in place (its field a view into its spectrum's rows: fewer bytes in the caches); two
        buffers, one each way, since the fused passes of loops.mirror_* read the forward
        spectrum while they write the inverse one (in place, the possible aliasing keeps them
        from vectorising)."""
        n1, m = self.shape
        kw = dict(axes=(0, 1), threads=self.workers, flags=flags)
        fwd = pyfftw.empty_aligned((n1, m), dtype="complex128")
        bwd = pyfftw.empty_aligned((n1, m), dtype="complex128")
        self._fd = pyfftw.FFTW(fwd.view(np.float64)[:, :2 * (m - 1)], fwd, **kw)
        self._bd = pyfftw.FFTW(bwd, bwd.view(np.float64)[:, :2 * (m - 1)], direction="FFTW_BACKWARD", **kw)

    # -- free surface ----------------------------------------------------------------
    def _doubled_forward(self, z):
        """The doubled cell's spectrum (n1, n3 + 1) of its real field z (n1, 2 n3)."""
        if self.backend == "pyfftw":
            self._fd.execute()  # z is the plan's own input
            return self._fd.output_array
        return sfft.rfftn(z, axes=(0, 1), workers=self.workers)

    def _doubled_inverse(self, W):
        """The doubled cell's real field of its spectrum W, unnormalised (W destroyed)."""
        if self.backend == "pyfftw":
            self._bd.execute()  # W is the plan's own input
            return self._bd.output_array
        n1, m = self.shape
        return sfft.irfftn(W, s=(n1, 2 * (m - 1)), axes=(0, 1), workers=self.workers, norm="forward")

    def _doubled_buffers(self):
        """(z, W): the input of the doubled forward transform and of the inverse one."""
        if self.backend == "pyfftw":
            return self._fd.input_array, self._bd.input_array
        n1, m = self.shape
        if not hasattr(self, "_zbuf"):
            self._zbuf = np.empty((n1, 2 * (m - 1)))
            self._wbuf = np.empty((n1, m), dtype=complex)
        return self._zbuf, self._wbuf

    def _pack_forward(self, even, odd):
        """The doubled cell's spectrum of the mirrored ``even`` plus the mirrored ``odd`` field."""
        z, _ = self._doubled_buffers()
        mirror_pack(even, odd, z)
        return self._doubled_forward(z)

    def _inverse_split(self, out_even, out_odd, prescaled):
        """The even and odd parts (where wanted) of the doubled field of :meth:`inverse_buffer`."""
        z = self._doubled_inverse(self._doubled_buffers()[1])
        return mirror_split(z, 1.0 if prescaled else self.norm, out_even, out_odd)

    def forward_pair(self, even, odd) -> np.ndarray:
        """Free surface: the doubled cell's spectrum W (n1, n3 + 1) of the mirrored ``even`` plus
        the mirrored ``odd`` field (two transforms' worth: one of the doubled cell); a work
        array, valid until the next transform. loops.mirror_separate splits it into the two
        fields' spectra; loops.mirror_rotate into the channels of Eq. (28) at once."""
        self.count += 2
        return self._pack_forward(even, odd)

    def inverse_buffer(self) -> np.ndarray:
        """Free surface: the doubled cell's spectrum (n1, n3 + 1) that :meth:`inverse_pair`
        transforms (loops.mirror_join, or a fused pass, writes it)."""
        return self._doubled_buffers()[1]

    def inverse_pair(self, out_even=None, out_odd=None, prescaled=False) -> tuple:
        """Free surface: the even and the odd field of the half plane (into ``out_even``,
        ``out_odd`` where given) of the doubled spectrum in :meth:`inverse_buffer` (destroyed)."""
        self.count += 2
        return self._inverse_split(np.empty(self.shape) if out_even is None else out_even,
                                   np.empty(self.shape) if out_odd is None else out_odd, prescaled)

    def _groups(self, keys):
        """Free surface: the components in pairs (even, odd) that share a transform of the
        doubled cell (None: no partner)."""
        odd = [c for c in keys if c in ODD]
        even = [c for c in keys if c not in ODD]
        while odd or even:
            yield (even.pop(0) if even else None), (odd.pop(0) if odd else None)

    def forward_components(self, fields: dict, out: dict | None = None) -> dict:
        """{component: spectrum} of {component: field}, into the arrays of ``out`` where given.
        Without a free surface: :meth:`forward` of each; with one, an even and the odd
        component share one transform of the doubled cell (1 and 3 in 3D shear)."""
        out = out or {}
        if not self.mirror:
            return {c: self.forward(x, out=out.get(c), component=c) for c, x in fields.items()}
        res = {}
        for e, o in self._groups(fields):
            self.count += (e is not None) + (o is not None)
            W = self._pack_forward(None if e is None else fields[e], None if o is None else fields[o])
            dest = [None if c is None else (out.get(c) if out.get(c) is not None else self.empty()) for c in (e, o)]
            mirror_separate(W, *dest)
            res.update({c: X for c, X in zip((e, o), dest) if c is not None})
        return {c: res[c] for c in fields}

    def inverse_components(self, spectra: dict, out: dict | None = None, prescaled: bool = False) -> dict:
        """{component: field} of {component: spectrum} (the inverse of :meth:`forward_components`;
        ``out`` and ``prescaled`` as for :meth:`inverse`; the spectra may be destroyed)."""
        out = out or {}
        if not self.mirror:
            return {c: self.inverse(X, out=out.get(c), overwrite=True, prescaled=prescaled, component=c)
                    for c, X in spectra.items()}
        res = {}
        for e, o in self._groups(spectra):
            self.count += (e is not None) + (o is not None)
            mirror_join(None if e is None else spectra[e], None if o is None else spectra[o], self.inverse_buffer())
            dest = [None if c is None else (out.get(c) if out.get(c) is not None else np.empty(self.shape))
                    for c in (e, o)]
            self._inverse_split(*dest, prescaled)
            res.update({c: x for c, x in zip((e, o), dest) if c is not None})
        return {c: res[c] for c in spectra}

    def forward(self, x: np.ndarray, out: np.ndarray | None = None, component: int | None = None) -> np.ndarray:
        """Spectrum of the real field x: a new array, or written into ``out`` (spectral shape).
        ``component``: the field's component (with a free surface, 3 is odd: :data:`ODD`)."""
        if self.mirror:
            c = 0 if component is None else component  # no component: an even field
            return self.forward_components({c: x}, None if out is None else {c: out})[c]
        self.count += 1
        if self.backend == "pyfftw":
            fwd = self._fwd
            src = x[:, 0] if self.plane else x
            if out is None:
                fwd.input_array[...] = src
                fwd.execute()
                res = fwd.output_array.copy()
                return res[:, None] if self.plane else res
            # a real-to-complex plan leaves its input alone: run it from x itself when it can
            if not (src.dtype == np.float64 and src.flags.c_contiguous and src.shape == fwd.input_array.shape
                    and pyfftw.is_byte_aligned(src, fwd.input_alignment)):
                fwd.input_array[...] = src
                src = fwd.input_array
            self._execute_into(fwd, src, out)
            return out
        if self.plane:
            res = sfft.rfft(x[:, 0], workers=self.workers)[:, None]
        else:
            res = sfft.rfftn(x, axes=(0, 1), workers=self.workers)
        if out is None:
            return res
        out[...] = res
        return out

    def inverse(self, X: np.ndarray, out: np.ndarray | None = None, overwrite: bool = False,
                prescaled: bool = False, component: int | None = None) -> np.ndarray:
        """Real field of the spectrum X (normalised by 1/N like scipy's inverse): a new array,
        or written into ``out``; ``overwrite=True`` lets the transform destroy X (no copy in);
        ``prescaled=True``: X already carries the factor :attr:`norm` = 1/N (no pass for it);
        ``component`` as for :meth:`forward`."""
        if self.mirror:
            c = 0 if component is None else component
            return self.inverse_components({c: X}, None if out is None else {c: out}, prescaled=prescaled)[c]
        self.count += 1
        if self.backend == "pyfftw":
            inv = self._inv
            src = X[:, 0] if self.plane else X
            if not (overwrite and out is not None and pyfftw.is_byte_aligned(src, inv.input_alignment)
                    and src.flags.c_contiguous):
                inv.input_array[...] = src  # a complex-to-real transform overwrites its input
                src = inv.input_array
            if out is None:
                inv.execute()
                res = inv.output_array.copy() if prescaled else inv.output_array * self.norm
                return res[:, None] if self.plane else res
            self._execute_into(inv, src, out)
            if not prescaled:
                np.multiply(out, self.norm, out=out)
            return out
        norm = "forward" if prescaled else "backward"
        if self.plane:
            res = sfft.irfft(X[:, 0], n=self.shape[0], workers=self.workers, norm=norm)[:, None]
        else:
            res = sfft.irfftn(X, s=self.shape, axes=(0, 1), workers=self.workers, norm=norm)
        if out is None:
            return res
        out[...] = res
        return out

    def _execute_into(self, plan, src, out):
        """Run ``plan`` from src into out (in place when out has the plan's alignment)."""
        view = out[:, 0] if self.plane else out
        own_in, own_out = plan.input_array, plan.output_array
        if view.shape != own_out.shape:
            raise ValueError(f"out has shape {out.shape}, the transform gives {own_out.shape}")
        if not ((pyfftw.is_byte_aligned(view, plan.output_alignment) and pyfftw.is_byte_aligned(src, plan.input_alignment)) and view.flags.c_contiguous):
            if src is not own_in:
                own_in[...] = src
            plan.execute()
            view[...] = own_out
            return
        plan.update_arrays(src, view)
        try:
            plan.execute()
        finally:
            plan.update_arrays(own_in, own_out)  # the plan keeps its own arrays between calls
