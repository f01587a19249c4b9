"""One elastic half space: its material, the channels of its face (kernels and history
engines) and the face's traction response, the functionals f_j of Eq. (3).

A half space answers the history of the field it is given with f_j scaled by ``scale``:
1 for its own face displacement; 1/2 for the displacement discontinuity of two
identical half spaces (they move antisymmetrically, u+ = -u- = delta/2), which is how
the paper's combined formulation, Eqs. (32)-(33), arises (solver/interfaces/identical.py).

Mode I (component 2) uses kernel C_I, Eq. (32). Shear (components 1, 3) is rotated
into the longitudinal part (kernel C_II) and the transverse part (kernel C_III) of
each mode, Eqs. (27)-(28) and (34): two scalar convolutions per mode, not four.
In the plane problem (n3 == 1) component 1 is mode II and component 3 is mode III.
With a free surface (Grid.free_surface) the transforms take the components together (3 is
odd about the surface, 1 and 2 even: solver/spectral.py) and hand back the doubled cell's
Fourier coefficients, so that the rotation, the channels and the engines below are the same.
The functionals below are written for the identical pair (scale 1/2, the paper's
form); with scale s, mu/2 reads s mu throughout.

Product scheme (velocity formulation, Z integrated exactly against the piecewise-linear
velocity history, docs/reference/stability.md):
    F_n = -(mu q / 2) Z(0) D_n + (mu / 2 c_s) gamma [sum_{m=0}^n W_m V_{n-m} + E_0(n) V_0],
with D_n = D_{n-1} + dt (V_{n-1} + V_n)/2; the V_n terms form K V_n with
K = (mu gamma / 2 c_s)(W_0 - Z(0)/2), applied to a predicted then a corrected velocity.

Displacement formulation, Eq. (32) with Eq. (44):
    F_n = -(mu q / 2) gamma sum_{j=0}^n xk_j D_{n-j},          gamma = q c_s dt.
Velocity formulation, Eq. (33) with Eq. (48), discretised kernel (45):
    F_n = -(mu q / 2) Z(0) D*_n + (mu / 2 c_s) gamma [sum_{j=1}^n xk_j V_{n-j} - xk_n V_0 / 2],
with D*_n = D_{n-1} + dt V_{n-1} / 2; the V_n terms of the semi-implicit update (50)
cancel exactly, so the step stays explicit.
"""
from __future__ import annotations

import numpy as np

from ..history import make_engine
from .loops import (mirror_rotate, mirror_separate, mirror_shear_correct, mirror_shear_predict, plus_product,
                    product_predict, rotate, shear_correct, shear_predict)
from .schemes import Channel, scheme_of
from .spectral import Transforms
from ..elastic.modes import directions
from .stability import mode_gamma


def active_channels(plane: bool, components) -> tuple:
    """The kernels a set of components needs: I for component 2; in 3D, II and III for any
    shear component (the rotation of Eq. 28 mixes them); in the plane, II for 1, III for 3."""
    shear3d = (not plane) and any(c in components for c in (1, 3))
    out = ("I",) if 2 in components else ()
    if shear3d or 1 in components:
        out += ("II",)
    if shear3d or 3 in components:
        out += ("III",)
    return out


def split_channels(X: dict, channels, shear3d: bool, c, s, out_arrays=None) -> dict:
    """Component spectra -> channel spectra (rotation of Eq. 28 for 3D shear; ``c``, ``s``
    are k1/q and k3/q on the spectral layout of X; ``out_arrays``: two arrays for the
    rotated II, III spectra)."""
    out = {}
    if "I" in channels:
        out["I"] = X[2]
    if shear3d:
        out["II"], out["III"] = rotate(c, s, X[1], X[3], out=out_arrays)
    else:
        if "II" in channels:
            out["II"] = X[1]
        if "III" in channels:
            out["III"] = X[3]
    return out


def predict_channel(ch, V, n, dt, out=None):
    """Product scheme, one channel, step n >= 1: push V = V_{n-1} (``out``: the engine's
    output array), set the channel's start-up terms (n = 1) and H, return F = H + K V."""
    if n == 1:
        ch.v0 = V.copy()
        ch.dknown = 0.5 * dt * V
        S = ch.engine.push(V) + ch.engine.start_weight(n) * ch.v0
        ch.H = ch.static * ch.dknown + ch.pre * S
        return ch.H + ch.K * V
    # the same, in one pass: dknown += dt V, H, F
    ch.H, F = product_predict(V, ch.engine.push(V, out=out), ch.engine.start_weight(n), ch.v0, ch.dknown,
                              ch.static, ch.pre, ch.K, dt)
    return F


class HalfSpace:
    """Maps the displacement (and velocity) history of its face to f_j, Eq. (3), times ``scale``.

    ``material``: its material; ``formulation``: the time scheme (solver/schemes: its name or
    the scheme);
    ``rule``: the displacement scheme's convolution rule (the others have their own);
    ``engine``, ``window``, ``nsteps``, ``threads``: its history engines
    (cracklab.history.make_engine); ``transforms``: the FFTs it shares.
    """

    def __init__(self, material, grid, dt, components, *, scale=1.0, formulation="displacement",
                 rule="trapezoid", engine="direct", window=None, transforms=None, nsteps=None, threads=None):
        self.material = material
        self.scale = scale
        self.components = tuple(sorted(components))
        self.fft = transforms or Transforms(grid)
        q, self.c, self.s = directions(grid)
        self.q = q
        gamma = mode_gamma(q, material.cs, dt)
        nu = material.nu
        self.shear3d = (not grid.plane) and any(c in self.components for c in (1, 3))
        #: a free surface: the shear pair (1, 3) goes through one transform of the doubled cell,
        #: its separation and joining fused with the rotations (solver/spectral.py, loops.mirror_*)
        self.pair = self.shear3d and self.fft.mirror
        self.dt = dt
        scheme = scheme_of(formulation)
        self.scheme = scheme
        self.formulation = scheme.name
        # the displacement formulation takes any rule of its weights; the others have their own
        rule = rule if scheme.any_rule else scheme.rule

        def channel(kernel):
            eng = make_engine(engine, kernel=kernel, gamma=gamma, nu=nu, rule=rule, formulation=scheme.convolves,
                              lag=scheme.lag, window=window, threads=threads or self.fft.workers, nsteps=nsteps)
            return scheme.channel(kernel, eng, q, gamma, scale * material.mu, material.cs, nu)

        self.channels: dict[str, Channel] = {name: channel(name)
                                              for name in active_channels(grid.plane, self.components)}
        # work arrays reused every step: spectra of the two forward transforms of a step
        # (displacement, velocity), engine outputs, and the f_j handed back (see functional)
        fft = self.fft
        self._spec = {slot: {c: fft.empty() for c in self.components} for slot in ("D", "V")}
        self._S = {name: fft.empty() for name in self.channels}
        self._f = {c: fft.empty(spectral=False) for c in self.components}
        # 3D shear: the rotated II/III spectra of each forward slot, and of the way back
        self._rot = {k: (fft.empty(), fft.empty()) for k in ("D", "V", "join")} if self.shear3d else {}
        # displacement formulation: the engines apply pre / N (no pass for the 1/N after the inverse)
        self._pre_n = {name: ch.pre * fft.norm for name, ch in self.channels.items()}
        self.n = 0

    # -- state (checkpoints) -----------------------------------------------------------
    def get_state(self) -> dict:
        """The dynamic state: step count, per-channel start-up and product-scheme terms, engines."""
        out = {"n": self.n, "channels": {}}
        for name, ch in self.channels.items():
            out["channels"][name] = {
                "engine": ch.engine.get_state(),
                **{k: (None if getattr(ch, k) is None else getattr(ch, k).copy()) for k in ("v0", "dknown", "H")},
            }
        return out

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (a HalfSpace built for the same scene)."""
        self.n = int(state["n"])
        for name, ch in self.channels.items():
            cs = state["channels"][name]
            ch.engine.set_state(cs["engine"])
            for k in ("v0", "dknown", "H"):
                setattr(ch, k, None if cs[k] is None else np.array(cs[k]))

    def _launch(self) -> None:
        """Every channel is pushed for this step: let the engines advance their states on
        their worker thread while the step goes on (ExponentialEngine.launch)."""
        for ch in self.channels.values():
            ch.engine.launch()

    def wait(self) -> None:
        """Let every channel's engine finish the work its last push started (no thread of
        the half space runs after this until the next step)."""
        for ch in self.channels.values():
            ch.engine.wait()

    # -- spectral helpers ------------------------------------------------------------
    def _split(self, X: dict, slot: str = "D") -> dict:
        return split_channels(X, self.channels, self.shear3d, self.c, self.s, self._rot.get(slot))

    def _join(self, F: dict) -> dict:
        out = {}
        if "I" in F:
            out[2] = F["I"]
        if self.shear3d:
            out[1], out[3] = rotate(self.c, self.s, F["II"], F["III"], inverse=True, out=self._rot["join"])
        else:
            if "II" in F:
                out[1] = F["II"]
            if "III" in F:
                out[3] = F["III"]
        return out

    def _forward(self, fields: dict, slot: str = "D") -> dict:
        if self.pair:  # free surface: the shear pair's doubled spectrum straight into its channels
            out = {}
            if 2 in self.components:  # first: the pair's spectrum lives in the transforms' work array
                out["I"] = self.fft.forward(fields[2], out=self._spec[slot][2], component=2)
            W = self.fft.forward_pair(fields[1], fields[3])
            out["II"], out["III"] = mirror_rotate(self.c, self.s, W, out=self._rot[slot])
            return out
        return self._split(self.fft.forward_components({c: fields[c] for c in self.components}, self._spec[slot]),
                           slot)

    def _inverse(self, F: dict, prescaled: bool = False) -> dict:
        """f_j of the channel spectra F (destroyed), in the work arrays of the half space
        (``prescaled``: F carries the 1/N of the inverse transform; else it is applied to
        the component spectra, as the fused passes of the product scheme do)."""
        F = self._join(F)
        if not prescaled:
            for Fc in F.values():
                np.multiply(Fc, self.fft.norm, out=Fc)
        return self._to_real(F)

    def _to_real(self, F: dict) -> dict:
        """f_j of the component spectra F (destroyed; they carry the 1/N of the inverse
        transform), in the work arrays of the half space."""
        return self.fft.inverse_components(F, self._f, prescaled=True)

    # -- public -----------------------------------------------------------------------
    def predict(self, v_prev: dict) -> dict:
        """Product scheme, step n: f_n with the velocity held at v_{n-1} (the predictor).

        Pushes V_{n-1} into the history; call ``correct`` next with the predicted velocity.
        """
        n = self.n
        self.n = n + 1
        if n == 0:
            for ch in self.channels.values():
                ch.H = None
            return {c: np.zeros(self.fft.shape) for c in self.components}
        V = self._forward(v_prev, "V")
        F = {}
        if n > 1 and self.shear3d and "I" not in self.channels:
            # II and III in one compiled pass, back to components in the same pass
            chans = [self.channels[k] for k in ("II", "III")]
            args = [(V[k], ch.engine.push(V[k], out=self._S[k]), ch.engine.start_weight(n), ch.v0, ch.dknown,
                     ch.static, ch.pre, ch.K) for k, ch in zip(("II", "III"), chans)]
            self._launch()
            H = (chans[0].H, chans[1].H)  # H of the last step is rewritten in place
            if self.pair:  # free surface: the components' spectra joined into the doubled cell's
                HH = mirror_shear_predict(self.c, self.s, args[0], args[1], self.dt, self.fft.inverse_buffer(), H=H,
                                          scale=self.fft.norm)
                if HH is not None:
                    chans[0].H, chans[1].H = HH
                    f1, f3 = self.fft.inverse_pair(self._f[1], self._f[3], prescaled=True)
                    return {1: f1, 3: f3}
            HH = shear_predict(self.c, self.s, args[0], args[1], self.dt, self._rot["join"], H=H,
                               scale=self.fft.norm)
            if HH is not None:
                chans[0].H, chans[1].H = HH
                return self._to_real(dict(zip((1, 3), self._rot["join"])))
            # not fusable: the same step channel by channel (the engines were pushed above)
            for (Vk, Sk, e0, v0, dk, st, pre, K), k, ch in zip(args, ("II", "III"), chans):
                ch.H, F[k] = product_predict(Vk, Sk, e0, v0, dk, st, pre, K, self.dt)
            return self._inverse(F)
        for name, ch in self.channels.items():
            F[name] = predict_channel(ch, V[name], n, self.dt, out=self._S[name])
        self._launch()
        return self._inverse(F)

    def correct(self, v_pred: dict) -> dict:
        """Product scheme: f_n with the current velocity taken as ``v_pred`` (the corrector)."""
        if self.shear3d and "I" not in self.channels:
            # rotation, corrector and rotation back in one compiled pass
            II, III = self.channels["II"], self.channels["III"]
            if self.pair:  # free surface: from and into the doubled cell's spectra, in the same pass
                W = self.fft.forward_pair(v_pred[1], v_pred[3])
                if mirror_shear_correct(self.c, self.s, W, II.H, II.K, III.H, III.K, self.fft.inverse_buffer(),
                                        scale=self.fft.norm) is not None:
                    f1, f3 = self.fft.inverse_pair(self._f[1], self._f[3], prescaled=True)
                    return {1: f1, 3: f3}
                X = dict(zip((1, 3), mirror_separate(W, self._spec["V"][1], self._spec["V"][3])))
            else:
                X = self.fft.forward_components({c: v_pred[c] for c in self.components}, self._spec["V"])
            out = shear_correct(self.c, self.s, X[1], X[3], II.H, II.K, III.H, III.K, self._rot["join"],
                                scale=self.fft.norm)
            if out is not None:
                return self._to_real(dict(zip((1, 3), out)))
            V = self._split(X, "V")
        else:
            V = self._forward(v_pred, "V")
        F = {name: plus_product(ch.H, ch.K, V[name], out=self._S[name]) for name, ch in self.channels.items()}
        return self._inverse(F)

    def functional(self, delta: dict, v_prev: dict | None = None) -> dict:
        """f_j(x1, x3) at the current step, for each active component j.

        Displacement formulation: ``delta`` is delta_n. Velocity formulation: ``delta``
        is delta*_n = delta_{n-1} + dt v_{n-1}/2 and ``v_prev`` is v_{n-1}.
        The arrays returned (here and by predict and correct) are work arrays of the
        half space: valid until its next call.
        """
        n = self.n
        D = self._forward(delta)
        F = {}
        displacement = self.scheme.convolves == "displacement"
        if displacement:
            for name, ch in self.channels.items():  # the prefactor with the 1/N of the inverse FFT
                F[name] = ch.engine.push(D[name], out=self._S[name], scale=self._pre_n[name])
        else:
            V = self._forward(v_prev, "V") if n > 0 else None
            for name, ch in self.channels.items():
                Fn = ch.static * D[name]
                if n > 0:
                    if n == 1:
                        ch.v0 = V[name].copy()
                    conv = ch.engine.push(V[name]) - 0.5 * ch.engine.weight(n - 1) * ch.v0
                    Fn = Fn + ch.pre * conv
                F[name] = Fn
        self._launch()
        self.n = n + 1
        return self._inverse(F, prescaled=displacement)
