"""Two half spaces of different materials: each face answers its own velocity history
(solver/face.py, the independent formulation) and the interface joins them.

With tau = tau0 - eta+ v+ + f+ (top) = tau0 + eta- v- + f- (bottom) and V = v+ - v-,

    tau = tau0 + f - eta V,   f = (eta- f+ + eta+ f-)/(eta+ + eta-),   eta = eta+ eta-/(eta+ + eta-),

per component (docs/developer/developer.md, "Add a half-space type"), and once V is known the faces
move with

    v+ = [(f+ - f-) + eta- V]/(eta+ + eta-),   v- = v+ - V.

Everything is linear with constant coefficients, so it is done on the rotated spectra: two
forward and two inverse transforms per step, as for one material. Product scheme only.
The in-plane channels (L, N and their coupling) run whenever an in-plane component is
active: the faces' normal and tangential motions are coupled even where the jump of one
of them is held at zero (an inactive component has V = 0).

With numba each stage runs compiled passes over the modes (solver/loops.py, ``bim_*``):
the predictor's ten channel updates, then the faces' f and the join; the corrector's split,
then the faces' f and the join (the same two passes); the split after the step. The faces' velocities, running terms and
f then live in arrays per face and part (or channel), and the channels' attributes are
views of them. The two coupling channels of a face (LN, NL) share kernel and time steps,
hence their start-up weight E_0(n), computed once. Without numba (or
``loops.python_only``) the numpy expressions below run, the same numbers to round-off.
"""
from __future__ import annotations

import numpy as np

from ..face import CHANNELS, Face
from ...jit import compiled_loop as _compiled
from ..loops import rotate
from ..schemes import SCHEMES, scheme_of
from ..spectral import Transforms
from ...elastic.modes import directions
from .base import Interface, register


class _Rows:
    """Work arrays (lead..., Mp) whose rows of M values start at different offsets modulo
    4096 bytes (64 bytes apart, from one array to the next too): a compiled pass that reads
    and writes some sixty such rows per mode then keeps them in different cache sets (rows
    whose starts agree modulo 4096 bytes, e.g. M = 256 x 65 complex values, compete for one
    set and evict each other). Index [..., :M] for a row's values."""

    def __init__(self, M):
        self.M, self.row = M, 0

    def __call__(self, lead, dtype=complex):
        item = np.dtype(dtype).itemsize
        Mp = self.M + ((64 - self.M * item) % 4096) // item     # row stride = 64 modulo 4096 bytes
        n = int(np.prod(lead))
        pool = np.zeros(n * Mp + 4096 // item, dtype=dtype)
        off = ((self.row * 64 - pool.ctypes.data) % 4096) // item
        self.row += n
        return pool[off:off + n * Mp].reshape(tuple(lead) + (Mp,))


def _parts(plane, components) -> tuple:
    """(inplane, transverse): whether the faces carry the L, N channels and their coupling,
    and the T channel (in the plane: for an in-plane, for the anti-plane component)."""
    comps = set(components)
    if plane:
        return bool(comps & {1, 2}), 3 in comps
    return True, bool(comps & {1, 3})


@register
class Bimaterial(Interface):
    """The interface between ``top`` (x2 > 0) and ``bottom`` (options: HalfSpace's)."""

    #: of two different materials, the stable limit is this fraction of the smaller side's
    #: (measured on the traction-free mixed-mode faces: stable at 0.9, growing from 0.97;
    #: docs/studies/performance.md, "Bimaterial interface")
    margin = 0.9
    energy_refusal = ("energy_budget covers an interface between two half spaces of one material; "
                      "this scene has two (the bimaterial budget is not implemented)")
    holds_faces = True

    @classmethod
    def accepts(cls, top, bottom) -> bool:
        return top != bottom

    @classmethod
    def accepts_scheme(cls, scheme) -> bool:
        """The product schemes (product2: the same response, another law update)."""
        return scheme_of(scheme).rule == "product"

    @classmethod
    def scheme_error(cls, formulation) -> str:
        names = " or ".join(repr(name) for name, s in SCHEMES.items() if cls.accepts_scheme(s))
        return (f"a pair of different materials runs the product scheme ({names}); got {formulation!r} "
                f"(formulation 'auto' takes {cls.auto_scheme('displacement')!r})")

    @classmethod
    def margin_note(cls) -> str:
        return f"; of two materials {cls.margin:g} of the smaller side's limit"

    @classmethod
    def engine_channels(cls, scene) -> tuple:
        """Each face's channels, of its own material: L, N, LN, NL (kernels H11, H22, H12,
        H12) with an in-plane component, T (C_III) with a transverse one."""
        inplane, transverse = _parts(scene.grid.plane, scene.components)
        names = (("L", "N", "LN", "NL") if inplane else ()) + (("T",) if transverse else ())
        return tuple((CHANNELS[name][0], material) for material in scene.materials for name in names)

    #: rows of one value per mode of the compiled passes (``_bind``): complex (V, S, v0, dk,
    #: H, f, X, O, W), real (e0, st, pre, K, wp, wm, em, den, c and s)
    BOUND_ROWS = (2 * 3 + 2 * 5 + 2 * 3 + 2 * 3 + 2 * 5 + 2 * 3 + 3 + 3 + 2 * 3,
                  4 * 2 * 5 + 4 * 3 + 2)

    @classmethod
    def mode_arrays(cls, scene) -> tuple:
        """Spectra: the compiled passes' rows (BOUND_ROWS, both faces' five channels
        whatever parts are active), each channel's f of a face (Face._F), the zero spectrum
        and the FFT buffers; real: the passes' rows, each channel's static, pre and K terms,
        q, k1/q, k3/q (the engines' start-up weights are in the engines' memory)."""
        inplane, transverse = _parts(scene.grid.plane, scene.components)
        channels = 2 * ((4 if inplane else 0) + (1 if transverse else 0))
        spectra, reals = cls.BOUND_ROWS
        return spectra + channels + 3, reals + 3 * channels + 3

    def __init__(self, top, bottom, grid, dt, components, *, formulation="product", engine="direct", window=None,
                 transforms=None, nsteps=None, threads=None, rule=None):
        scheme = scheme_of(formulation)
        if not self.accepts_scheme(scheme):
            raise NotImplementedError(f"the bimaterial interface runs the product scheme, not {scheme.name!r}")
        self.materials = (top, bottom)
        self.components = tuple(sorted(components))
        self.fft = transforms or Transforms(grid)
        q, self.c, self.s = directions(grid)
        inplane, transverse = _parts(grid.plane, self.components)
        self.parts = (("L", "N") if inplane else ()) + (("T",) if transverse else ())
        opts = dict(engine=engine, window=window, nsteps=nsteps, threads=threads or self.fft.workers, scheme=scheme)
        self.faces = (Face(top, grid, dt, q, sign=1, inplane=inplane, transverse=transverse, **opts),
                      Face(bottom, grid, dt, q, sign=-1, inplane=inplane, transverse=transverse, **opts))
        self.channels = {f"{side}.{name}": ch for side, face in zip(("top", "bottom"), self.faces)
                         for name, ch in face.channels.items()}
        ep, em = self.faces[0].eta, self.faces[1].eta
        self._wp = {p: em[p] / (ep[p] + em[p]) for p in self.parts}   # weight of f+
        self._wm = {p: ep[p] / (ep[p] + em[p]) for p in self.parts}   # weight of f-
        self._den = {p: ep[p] + em[p] for p in self.parts}
        self._em = em
        axis = {1: "L", 3: "T", 2: "N"}
        self.eta = {c: ep[axis[c]] * em[axis[c]] / (ep[axis[c]] + em[axis[c]]) for c in self.components}
        zero = self.fft.empty()
        zero[...] = 0.0
        self._zero = zero
        self.v = ({p: zero.copy() for p in self.parts}, {p: zero.copy() for p in self.parts})
        self._f = (None, None)
        self._out = {c: self.fft.empty(spectral=False) for c in self.components}
        self._fused = None    # the compiled passes' arrays (_bind), once a step runs them

    # -- the compiled passes -----------------------------------------------------------
    _PARTS = ("L", "N", "T")
    _CH = ("L", "N", "LN", "NL", "T")

    def _compiled_passes(self):
        """The four compiled passes (the predictor's channel updates, the faces' f, the split,
        the join), or None (no numba, or loops.python_only)."""
        passes = tuple(_compiled(name) for name in ("bim_predict", "bim_correct", "bim_settle", "bim_join"))
        return None if any(p is None for p in passes) else passes

    def _bind(self, n):
        """The compiled passes' arrays, the channels' running terms (and ``v``) made views of
        them: filled from the channels' and ``v``'s current values (after set_state or the
        numpy path's steps); at n = 1 (nothing pushed yet) the start-up terms are set by
        the first pass."""
        shape = self.fft.empty().shape
        M = int(np.prod(shape))
        rows = _Rows(M)
        B = dict(V=rows((2, 3)), S=rows((2, 5)), e0=rows((2, 5), float), v0=rows((2, 3)), dk=rows((2, 3)),
                 H=rows((2, 5)), st=rows((2, 5), float), pre=rows((2, 5), float), K=rows((2, 5), float),
                 f=rows((2, 3)), wp=rows((3,), float), wm=rows((3,), float), em=rows((3,), float),
                 den=rows((3,), float), cs=rows((2,), float), X=rows((3,)), O=rows((3,)), W=rows((2, 3)))
        B["den"][...] = 1.0
        B["sign"] = np.array([face.sign for face in self.faces])
        for j, a in enumerate((self.c, self.s)):
            B["cs"][j, :M] = np.broadcast_to(a, shape).reshape(-1)
        B["c"], B["s"] = B["cs"][0, :M], B["cs"][1, :M]
        for j, p in enumerate(self._PARTS):
            if p in self.parts:
                for key, x in (("wp", self._wp), ("wm", self._wm), ("em", self._em), ("den", self._den)):
                    B[key][j, :M] = np.broadcast_to(x[p], shape).reshape(-1)
        # component spectra of a jump rate (the inactive ones stay zero) and the interface's f
        # spectra (1/N applied), in the transforms' spectral shape
        B["Xs"] = [B["X"][k, :M].reshape(shape) for k in range(3)]
        B["Os"] = [B["O"][k, :M].reshape(shape) for k in range(3)]
        view = lambda a: a[:M].reshape(shape)
        for a, face in enumerate(self.faces):
            for j, name in enumerate(self._CH):
                ch = face.channels.get(name)
                if ch is None:
                    continue
                k = self._PARTS.index(CHANNELS[name][1])
                for key, val in (("st", ch.static), ("pre", ch.pre), ("K", ch.K)):
                    B[key][a, j, :M] = np.broadcast_to(val, shape).reshape(-1)
                if n > 1:   # running terms of the steps so far (the L / NL and N / LN pairs agree)
                    B["H"][a, j, :M] = ch.H.reshape(-1)
                    B["v0"][a, k, :M] = ch.v0.reshape(-1)
                    B["dk"][a, k, :M] = ch.dknown.reshape(-1)
                ch.H, ch.v0, ch.dknown = view(B["H"][a, j]), view(B["v0"][a, k]), view(B["dk"][a, k])
            for k, p in enumerate(self._PARTS):
                if p in self.parts:
                    B["V"][a, k, :M] = self.v[a][p].reshape(-1)
        self.v = tuple({p: view(B["V"][a, k]) for k, p in enumerate(self._PARTS) if p in self.parts}
                       for a in range(2))
        B["M"], B["shape"] = M, shape
        self._fused = B

    def _inverse_fused(self) -> dict:
        """The active components' f from the spectra the last pass wrote (O, 1/N applied)."""
        O = self._fused["Os"]
        return self.fft.inverse_components({c: O[c - 1] for c in self.components}, self._out, prescaled=True)

    def _forward_fused(self, fields: dict) -> list:
        """Component spectra of the jump ``fields`` into X (the inactive ones stay zero), flat."""
        B = self._fused
        X = B["Xs"]
        self.fft.forward_components({c: fields[c] for c in self.components}, {c: X[c - 1] for c in self.components})
        return [B["X"][k, :B["M"]] for k in range(3)]

    def _predict_fused(self, passes, n):
        B = self._fused
        shape, M = B["shape"], B["M"]
        if n == 1:   # the start-up terms: v0 = V_0 and, through the pass's dknown += dt V, dknown = dt V_0 / 2
            B["v0"][...] = B["V"]
            np.multiply(B["V"], -0.5 * self.faces[0].dt, out=B["dk"])
        for a, face in enumerate(self.faces):
            face.n = n + 1
            chans = face.channels
            for j, name in enumerate(self._CH):
                ch = chans.get(name)
                if ch is None:
                    continue
                ch.engine.push(B["V"][a, self._PARTS.index(CHANNELS[name][1]), :M],
                               out=B["S"][a, j, :M].reshape(shape))
                if name != "NL":   # NL: the same engine's E_0 as LN (same kernel and gammas)
                    B["e0"][a, j, :M] = ch.engine.start_weight(n).reshape(-1)
            for ch in chans.values():
                ch.engine.launch()
        O = B["O"][:, :M]
        predict, faces_f, _, join = passes
        predict(M, B["V"], B["S"], B["e0"], B["v0"], B["dk"], B["st"], B["pre"], float(self.faces[0].dt), B["H"])
        faces_f(M, B["H"], B["K"], B["sign"], B["V"], B["f"])
        join(B["f"], B["wp"], B["wm"], B["c"], B["s"], float(self.fft.norm), *O)
        return self._inverse_fused()

    @property
    def n(self) -> int:
        return self.faces[0].n

    # -- spectra ---------------------------------------------------------------------
    def _rotated(self, fields: dict) -> dict:
        """{L, N, T} spectra of the jump ``fields`` (inactive components: zero)."""
        X = self.fft.forward_components({c: fields[c] for c in self.components})
        full = {c: X.get(c, self._zero) for c in (1, 2, 3)}
        L, T = rotate(self.c, self.s, full[1], full[3])
        return {"L": L, "N": full[2], "T": T}

    def _join(self) -> dict:
        """f of the interface (real fields of the active components) from the faces' f."""
        fp, fm = self._f
        F = {p: self._wp[p] * fp[p] + self._wm[p] * fm[p] for p in self.parts}
        zero = self._zero
        F1, F3 = rotate(self.c, self.s, F.get("L", zero), F.get("T", zero), inverse=True)
        spectra = {1: F1, 2: F.get("N", zero), 3: F3}
        return self.fft.inverse_components({c: spectra[c].copy() for c in self.components}, self._out)

    def _split(self, V: dict) -> tuple:
        """(v+, v-) of the faces for the jump rate V (rotated spectra) and the faces' current f."""
        fp, fm = self._f
        vp = {p: ((fp[p] - fm[p]) + self._em[p] * V[p]) / self._den[p] for p in self.parts}
        return vp, {p: vp[p] - V[p] for p in self.parts}

    # -- protocol --------------------------------------------------------------------
    def predict(self, v_prev):
        n = self.faces[0].n
        passes = self._compiled_passes() if n >= 1 else None
        if passes is not None:
            if self._fused is None:
                self._bind(n)
            return self._predict_fused(passes, n)
        self._unbind()
        self._f = tuple(face.predict(v) for face, v in zip(self.faces, self.v))
        return self._join()

    def correct(self, v_pred):
        if self._fused is not None:
            B = self._fused
            X = self._forward_fused(v_pred)
            _, faces_f, split, join = self._compiled_passes()
            split(*X, B["c"], B["s"], B["f"], B["em"], B["den"], B["W"])
            faces_f(B["M"], B["H"], B["K"], B["sign"], B["W"], B["f"])
            join(B["f"], B["wp"], B["wm"], B["c"], B["s"], float(self.fft.norm), *B["O"][:, :B["M"]])
            return self._inverse_fused()
        V = self._rotated(v_pred)
        vs = self._split(V)
        self._f = tuple(face.correct(v) for face, v in zip(self.faces, vs))
        return self._join()

    def settle(self, v_new):
        """After step (v): the faces' velocities of this step, for the next push."""
        if self._fused is not None:
            B = self._fused
            X = self._forward_fused(v_new)
            self._compiled_passes()[2](*X, B["c"], B["s"], B["f"], B["em"], B["den"], B["V"])
            return
        self.v = self._split(self._rotated(v_new))

    def _unbind(self):
        """Back to the numpy path: the channels and ``v`` keep their values in arrays of their own."""
        if self._fused is None:
            return
        for face in self.faces:
            for ch in face.channels.values():
                ch.H, ch.v0, ch.dknown = (None if x is None else x.copy() for x in (ch.H, ch.v0, ch.dknown))
        self.v = tuple({p: x.copy() for p, x in v.items()} for v in self.v)
        f, M, shape = self._fused["f"], self._fused["M"], self._fused["shape"]
        self._f = tuple({p: f[a, k, :M].reshape(shape).copy() for k, p in enumerate(self._PARTS) if p in self.parts}
                        for a in range(2))
        self._fused = None

    def face_fields(self, kind: str, jump: dict) -> dict:
        """Each face's own motion after the last step: {(side, component): field}, side
        "top" (x2 = 0+) or "bottom" (x2 = 0-), of its displacement (``kind`` "u") or velocity
        ("v"), for the components the faces carry (1, 2, 3 in 3D; in plane 1, 2 with an
        in-plane component, 3 with the anti-plane one). An inverse transform of the faces'
        spectra (``v``, and the channels' displacement, ``Face.displacement``): call it only
        for what is recorded. ``jump``: delta (kind "u") or its rate V ("v") of the same step,
        {component: field}; it gives the uniform mode of components 1 and 3, which the rotated
        spectra do not carry (q = 0 has no direction) and which the faces share as
        u+ = eta- delta/(eta+ + eta-), u- = u+ - delta (neither face's history acts on it)."""
        if kind not in ("u", "v"):
            raise ValueError(f"kind must be 'u' or 'v', got {kind!r}")
        zero = self._zero
        comps = (1, 2, 3) if not self.fft.plane else \
            (((1, 2) if "L" in self.parts else ()) + ((3,) if "T" in self.parts else ()))
        shear = "L" if "L" in self.parts else "T"          # L and T share eta = mu / c_s
        mean = {c: (self.fft.forward(np.asarray(jump[c], dtype=float), component=c).flat[0] if c in jump else 0.0)
                for c in (1, 3) if c in comps}
        out = {}
        for side, face, v in zip(("top", "bottom"), self.faces, self.v):
            spec = v if kind == "v" else face.displacement(v)
            S1, S3 = rotate(self.c, self.s, spec.get("L", zero), spec.get("T", zero), inverse=True)
            spectra = {c: np.array(x, dtype=complex) for c, x in ((1, S1), (2, spec.get("N", zero)), (3, S3))
                       if c in comps}
            share = self._wp[shear] if side == "top" else -self._wm[shear]
            for c, m in mean.items():
                spectra[c].flat[0] = share * m
            fields = self.fft.inverse_components(spectra)
            out.update({(side, c): fields[c] for c in comps})
        return out

    def functional(self, delta, v_prev=None):
        raise NotImplementedError("the bimaterial interface runs the product scheme")

    def wait(self):
        for face in self.faces:
            face.wait()

    def get_state(self) -> dict:
        return {"faces": [face.get_state() for face in self.faces],
                "v": [{p: a.copy() for p, a in v.items()} for v in self.v]}

    def set_state(self, state: dict) -> None:
        self._fused = None   # the compiled passes rebind to the restored arrays at the next step
        for face, st in zip(self.faces, state["faces"]):
            face.set_state(st)
        self.v = tuple({p: np.array(a) for p, a in v.items()} for v in state["v"])
