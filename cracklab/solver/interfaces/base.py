"""The interface protocol: the plane x2 = 0 between a top (x2 > 0) and a bottom (x2 < 0)
half space, and the elastodynamic part of step (v), tau = tau0 + f - eta V (Eqs. 3-4).

An interface type is one file here (docs/developer/developer.md, "Add a half-space type"), a class
registered with :func:`register`. The class says, before any is built:

* ``accepts(top, bottom)``: whether it is the interface of that pair of materials (exactly
  one registered type accepts a pair), and ``build(top, bottom, grid, dt, components,
  **options)`` the interface;
* ``accepts_scheme(scheme)`` and ``scheme_error(formulation)``: the time schemes it runs,
  and the message that refuses another; ``auto_scheme(preferred)``: the scheme it runs for
  ``Numerics(formulation="auto")``;
* ``margin``: the fraction of the smaller side's stable beta a scene may use (and
  ``margin_note``, what the refusal of a larger beta says of it);
* ``engine_channels(scene)``: the (kernel, material) of each history engine it builds, in
  the order it builds them, and ``mode_arrays(scene)``: the (complex, real) arrays of one
  value per Fourier mode it holds besides them, for the memory estimate (solver/budget.py);
* ``energy_refusal``: None when the energy budget (analysis/energy.py) covers it, else why not;
* ``holds_faces``: whether it holds the faces' own motions apart (``face_fields``).

An instance gives the interface law what the law's step needs, whatever the half spaces are:

* ``eta``: {component: V_jj}, the radiation damping of the pair, Eq. (4);
* ``functional(delta, v_prev=None)`` (displacement and velocity schemes) or
  ``predict(v_prev)`` and ``correct(v_pred)`` (product scheme): f_j at the current
  step from the history of the displacement discontinuity delta and its rate V;
* ``settle(v_new)`` after step (v) (default: nothing);
* ``channels`` (its kernels and engines, by name), ``fft`` (the transforms it uses),
  ``wait()``, ``get_state()`` and ``set_state(state)`` (checkpoints).
"""
from __future__ import annotations

#: the registered interface types, in the order they were registered
TYPES: list = []


def register(cls):
    """Class decorator: register the interface type ``cls``."""
    if cls not in TYPES:
        TYPES.append(cls)
    return cls


class Interface:
    """Defaults of the protocol (see the module docstring)."""

    eta: dict
    channels: dict
    margin = 1.0
    energy_refusal: str | None = None
    holds_faces = False

    @classmethod
    def accepts(cls, top, bottom) -> bool:
        """Whether this type is the interface between the materials ``top`` and ``bottom``."""
        raise NotImplementedError

    @classmethod
    def build(cls, top, bottom, grid, dt, components, **options) -> "Interface":
        """The interface between ``top`` and ``bottom`` (options: HalfSpace's)."""
        return cls(top, bottom, grid, dt, components, **options)

    @classmethod
    def accepts_scheme(cls, scheme) -> bool:
        """Whether it runs the time scheme ``scheme`` (solver/schemes): every one by default."""
        return True

    @classmethod
    def auto_scheme(cls, preferred: str) -> str:
        """The scheme ``formulation="auto"`` runs on this interface: ``preferred`` (the
        choice by the active components, model.scene.resolve_formulation) when it is accepted,
        else the first accepted scheme in the order of ``schemes.SCHEMES``."""
        from ..schemes import SCHEMES

        if cls.accepts_scheme(preferred):
            return preferred
        accepted = [name for name in SCHEMES if cls.accepts_scheme(name)]
        if not accepted:
            raise LookupError(f"the {cls.__name__} interface accepts none of the schemes {list(SCHEMES)}")
        return accepted[0]

    @classmethod
    def scheme_error(cls, formulation) -> str:
        """The refusal of the scheme ``formulation`` (InputError of numerics.formulation)."""
        return f"the {cls.__name__} interface does not run the {formulation!r} scheme"

    @classmethod
    def margin_note(cls) -> str:
        """What the refusal of a beta above the limit says of ``margin`` ("" without one)."""
        return ""

    @classmethod
    def engine_channels(cls, scene) -> tuple:
        """((kernel, material), ...) of the history engines a run of ``scene`` builds, in
        the order it builds them."""
        raise NotImplementedError

    @classmethod
    def mode_arrays(cls, scene) -> tuple:
        """(complex, real): how many arrays of one value per Fourier mode a run of ``scene``
        holds in its interface besides the engines' own (spectra, prefactors, FFT buffers)."""
        raise NotImplementedError

    def settle(self, v_new) -> None:
        """After step (v), with the jump rate of the step: nothing by default (the
        bimaterial interface splits it between its faces)."""

    def wait(self) -> None:
        """Let the history engines finish the work their last push started."""
