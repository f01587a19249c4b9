"""One half space answering its own face displacement: the independent formulation
(docs/reference/equations.md, "One half space: Eqs. (20)-(22)"), product scheme.

Per mode, in the frame of the wave vector (L along q, N normal, T transverse), the face
of the upper half space answers its velocity history v with

    f_L = F[H11](v_L) + i F[H12](v_N),   f_N = F[H22](v_N) - i F[H12](v_L),   f_T = F[III](v_T),

where F[K](v) is one product-scheme channel of kernel K and modulus mu (its static term,
its convolution of Z against v, solver/schemes/product.py). The lower half space gives the
same channels of its own material with the diagonal terms negated (Eq. 22, corrected).
All work is spectral: the interface hands in and takes back the rotated spectra.
"""
from __future__ import annotations

import numpy as np

from ..history import make_engine
from .halfspace import predict_channel
from .schemes import scheme_of
from .stability import mode_gamma

#: channel -> (kernel, the velocity it convolves)
CHANNELS = {"L": ("H11", "L"), "N": ("H22", "N"), "LN": ("H12", "N"), "NL": ("H12", "L"), "T": ("III", "T")}


class Face:
    """The face of one half space of ``material`` (``inplane``: the L, N channels and their
    coupling; ``transverse``: the T channel); ``sign`` +1 for the top, -1 for the bottom;
    ``scheme``: a product scheme (its name or the scheme)."""

    def __init__(self, material, grid, dt, q, *, sign, inplane, transverse, engine="direct", window=None,
                 nsteps=None, threads=None, scheme="product"):
        self.material = material
        self.sign = float(sign)
        self.dt = dt
        scheme = scheme_of(scheme)
        gamma = mode_gamma(q, material.cs, dt)
        names = (("L", "N", "LN", "NL") if inplane else ()) + (("T",) if transverse else ())
        self.channels = {}
        for name in names:
            kernel = CHANNELS[name][0]
            eng = make_engine(engine, kernel=kernel, gamma=gamma, nu=material.nu, rule=scheme.rule,
                              formulation=scheme.convolves, lag=scheme.lag, window=window, threads=threads,
                              nsteps=nsteps)
            self.channels[name] = scheme.channel(kernel, eng, q, gamma, material.mu, material.cs, material.nu)
        #: radiation damping of this face alone, per rotated component (Eq. 4 without the 1/2)
        self.eta = {"L": material.mu / material.cs, "T": material.mu / material.cs,
                    "N": material.mu * material.a / material.cs}
        self.n = 0
        self._F = {}

    def _combine(self) -> dict:
        """f of this face (top's form, times ``sign`` on the diagonal) from the channels' F."""
        F, s = self._F, self.sign
        out = {}
        if "L" in F:
            out["L"] = s * F["L"] + 1j * F["LN"]
            out["N"] = s * F["N"] - 1j * F["NL"]
        if "T" in F:
            out["T"] = s * F["T"]
        return out

    def predict(self, v: dict) -> dict:
        """Step n: push v_{n-1} (rotated spectra) and give f_n with the velocity held at v_{n-1}."""
        n = self.n
        self.n = n + 1
        for name, ch in self.channels.items():
            V = v[CHANNELS[name][1]]
            if n == 0:
                ch.H = None
                self._F[name] = np.zeros_like(V)
            else:
                self._F[name] = predict_channel(ch, V, n, self.dt)
        for ch in self.channels.values():
            ch.engine.launch()
        return self._combine()

    def correct(self, v: dict) -> dict:
        """f_n with the current velocity taken as ``v`` (rotated spectra)."""
        for name, ch in self.channels.items():
            if ch.H is not None:
                self._F[name] = ch.H + ch.K * v[CHANNELS[name][1]]
        return self._combine()

    def displacement(self, v: dict) -> dict:
        """The face's displacement spectra {part: D_n} after step n, from its velocity ``v``
        of that step (rotated spectra): each channel holds D_{n-1} + dt V_{n-1}/2 (Channel.dknown),
        so D_n = dknown + dt V_n/2, the trapezoid of the slip update (50); 0 before step 1."""
        out = {}
        for part in v:
            ch = self.channels[part]
            out[part] = np.zeros_like(v[part]) if ch.dknown is None else ch.dknown + 0.5 * self.dt * v[part]
        return out

    def wait(self) -> None:
        for ch in self.channels.values():
            ch.engine.wait()

    def get_state(self) -> dict:
        out = {"n": self.n, "channels": {}}
        for name, ch in self.channels.items():
            out["channels"][name] = {"engine": ch.engine.get_state(),
                                     **{k: (None if getattr(ch, k) is None else getattr(ch, k).copy())
                                        for k in ("v0", "dknown", "H")}}
        return out

    def set_state(self, state: dict) -> None:
        self.n = int(state["n"])
        for name, ch in self.channels.items():
            cs = state["channels"][name]
            ch.engine.set_state(cs["engine"])
            for k in ("v0", "dknown", "H"):
                setattr(ch, k, None if cs[k] is None else np.array(cs[k]))
