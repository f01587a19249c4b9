"""Two half spaces of different materials: each face answers its own velocity history
(solver/face.py, the independent formulation) and the interface joins them.

With tau = tau0 - eta+ v+ + f+ (top) = tau0 + eta- v- + f- (bottom) and V = v+ - v-,

    tau = tau0 + f - eta V,   f = (eta- f+ + eta+ f-)/(eta+ + eta-),   eta = eta+ eta-/(eta+ + eta-),

per component (docs/developer.md, "Add a half-space type"), and once V is known the faces
move with

    v+ = [(f+ - f-) + eta- V]/(eta+ + eta-),   v- = v+ - V.

Everything is linear with constant coefficients, so it is done on the rotated spectra: two
forward and two inverse transforms per step, as for one material. Product scheme only.
The in-plane channels (L, N and their coupling) run whenever an in-plane component is
active: the faces' normal and tangential motions are coupled even where the jump of one
of them is held at zero (an inactive component has V = 0).
"""
from __future__ import annotations

import numpy as np

from ..face import Face
from ..loops import rotate
from ..schemes import SCHEMES
from ..spectral import Transforms
from .base import Interface


class Bimaterial(Interface):
    """The interface between ``top`` (x2 > 0) and ``bottom`` (options: HalfSpace's)."""

    def __init__(self, top, bottom, grid, dt, components, *, formulation="product", engine="direct", window=None,
                 transforms=None, nsteps=None, threads=None, rule=None):
        if SCHEMES[formulation].rule != "product":   # product2: the same response, another law update
            raise NotImplementedError(f"the bimaterial interface runs the product scheme, not {formulation!r}")
        self.materials = (top, bottom)
        self.components = tuple(sorted(components))
        self.fft = transforms or Transforms(grid)
        k, m = grid.wavenumbers()
        q = np.sqrt(k**2 + m**2)
        with np.errstate(invalid="ignore", divide="ignore"):
            self.c = np.where(q > 0, k / q, 0.0)
            self.s = np.where(q > 0, m / q, 0.0)
        comps = set(self.components)
        if grid.plane:
            inplane, transverse = bool(comps & {1, 2}), 3 in comps
        else:
            inplane, transverse = True, bool(comps & {1, 3})
        self.parts = (("L", "N") if inplane else ()) + (("T",) if transverse else ())
        opts = dict(engine=engine, window=window, nsteps=nsteps, threads=threads or self.fft.workers)
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
        self._f = tuple(face.predict(v) for face, v in zip(self.faces, self.v))
        return self._join()

    def correct(self, v_pred):
        V = self._rotated(v_pred)
        vs = self._split(V)
        self._f = tuple(face.correct(v) for face, v in zip(self.faces, vs))
        return self._join()

    def settle(self, v_new):
        """After step (v): the faces' velocities of this step, for the next push."""
        self.v = self._split(self._rotated(v_new))

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
        for face, st in zip(self.faces, state["faces"]):
            face.set_state(st)
        self.v = tuple({p: np.array(a) for p, a in v.items()} for v in state["v"])
