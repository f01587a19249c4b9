"""The quasi-dynamic elastic response: the static traction of a slip distribution between
two identical half spaces (docs/reference/equations.md, "Sequences: the quasi-dynamic
response"), the long-time limit of Eq. (32) for a mode that has stopped moving:

    F_II = -(mu q / 2) D_II / (1 - nu),   F_III = -(mu q / 2) D_III,
    F_I  = -(mu q / 2) D_I / (1 - nu)

(int_0^inf C dT of each kernel, ``elastic.kernels.static_integral``), with the shear pair
rotated by Eq. (28) in 3D. The q = 0 mode carries no static traction; a spring of
stiffness k on it (the mean slip) loads the plane as a slider, F_0 = -k D_0."""
from __future__ import annotations

from ...elastic.kernels import static_integral
from ...elastic.modes import directions
from ..loops import rotate
from ..spectral import Transforms

CHANNEL = {1: "II", 2: "I", 3: "III"}


class StaticResponse:
    """The static traction of the slip on ``grid`` between two half spaces of ``material``,
    for the ``components`` that slip; ``stiffness``: the spring on the mean slip (stress per
    length). ``traction(delta)`` -> {component: field}."""

    def __init__(self, material, grid, components, stiffness=0.0, transforms=None):
        self.components = tuple(sorted(components))
        self.fft = transforms or Transforms(grid)
        self.q, self.c, self.s = directions(grid)
        q = self.q
        self.rotated = (not grid.plane) and 1 in self.components and 3 in self.components
        # -(mu q / 2) int C dT per channel, for an identical pair (mu / 2 per side's half of the jump)
        self.factor = {CHANNEL[c]: -0.5 * material.mu * q * static_integral(CHANNEL[c], material.nu)
                       for c in self.components}
        self.stiffness = float(stiffness)
        self.zero = (0, 0)     # the q = 0 mode in the spectral layout

    def spectra(self, fields: dict) -> tuple[dict, dict]:
        """({channel: spectrum}, {component: its q = 0 mode}) of {component: field} (Eq. 28's
        rotation in 3D shear)."""
        X = self.fft.forward_components({c: fields[c] for c in self.components})
        zeros = {c: X[c][self.zero] for c in self.components}
        if not self.rotated:
            return {CHANNEL[c]: X[c] for c in self.components}, zeros
        out = dict(zip(("II", "III"), rotate(self.c, self.s, X[1], X[3])))
        if 2 in self.components:
            out["I"] = X[2]
        return out, zeros

    def fields(self, F: dict, zeros: dict) -> dict:
        """{component: field} of the channels' spectra ``F``; the q = 0 mode of each component
        is the spring's -k times the slip's (``zeros``, from :meth:`spectra`)."""
        if self.rotated:
            out = dict(zip((1, 3), rotate(self.c, self.s, F["II"], F["III"], inverse=True)))
            if 2 in self.components:
                out[2] = F["I"]
        else:
            out = {c: F[CHANNEL[c]] for c in self.components}
        for c in self.components:
            out[c][self.zero] = -self.stiffness * zeros[c]
        return self.fft.inverse_components(out)

    def traction(self, delta: dict) -> dict:
        """{component: the static traction of the slip ``delta``} ({component: field})."""
        X, zeros = self.spectra(delta)
        return self.fields({ch: self.factor[ch] * x for ch, x in X.items()}, zeros)
