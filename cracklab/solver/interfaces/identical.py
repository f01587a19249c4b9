"""Two half spaces of one material. Under any load on the plane they move
antisymmetrically, u+ = -u- = delta/2, so the pair answers delta as one half space
answers delta/2: one computation, with mu/2 in the prefactors (the combined form of
Eqs. 32-33) and eta = V_jj of Eq. (4), mu/(2 c_s) in shear and mu c_d/(2 c_s^2) in opening.
"""
from __future__ import annotations

from ..halfspace import HalfSpace, active_channels
from .base import Interface, register


@register
class Identical(Interface):
    """The interface between two half spaces of ``material`` (options: HalfSpace's)."""

    margin = 1.0                # the one material's own limit
    energy_refusal = None       # analysis/energy.py's budget is this pair's

    @classmethod
    def accepts(cls, top, bottom) -> bool:
        return top == bottom

    @classmethod
    def build(cls, top, bottom, grid, dt, components, **options) -> "Identical":
        return cls(top, grid, dt, components, **options)

    @classmethod
    def engine_channels(cls, scene) -> tuple:
        """One engine per channel the active components drive, of the one material."""
        return tuple((kernel, scene.material) for kernel in active_channels(scene.grid.plane, scene.components))

    @classmethod
    def mode_arrays(cls, scene) -> tuple:
        """Spectra: two forward slots per component, an engine output per channel, the
        rotations (3D shear), the FFT buffers; real: q, k1/q, k3/q, gamma and the channels'
        prefactors."""
        comps, plane = scene.components, scene.grid.plane
        shear3d = not plane and any(c in comps for c in (1, 3))
        return 2 * len(comps) + len(active_channels(plane, comps)) + (6 if shear3d else 0) + 2, 10

    def __init__(self, material, grid, dt, components, **options):
        self.material = material
        self.half = HalfSpace(material, grid, dt, components, scale=0.5, **options)
        self.components = self.half.components
        self.channels = self.half.channels
        self.fft = self.half.fft
        self.eta = {c: material.eta(c) for c in self.components}

    @property
    def n(self) -> int:
        """Steps pushed so far."""
        return self.half.n

    def functional(self, delta, v_prev=None):
        return self.half.functional(delta, v_prev)

    def predict(self, v_prev):
        return self.half.predict(v_prev)

    def correct(self, v_pred):
        return self.half.correct(v_pred)

    def wait(self):
        self.half.wait()

    def get_state(self) -> dict:
        return self.half.get_state()

    def set_state(self, state: dict) -> None:
        self.half.set_state(state)
