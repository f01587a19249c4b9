"""The interface protocol: the plane x2 = 0 between a top (x2 > 0) and a bottom (x2 < 0)
half space, and the elastodynamic part of step (v), tau = tau0 + f - eta V (Eqs. 3-4).

An interface type is one file here (docs/developer/developer.md, "Add a half-space type"). It
gives the interface law what the law's step needs, whatever the half spaces are:

* ``eta``: {component: V_jj}, the radiation damping of the pair, Eq. (4);
* ``functional(delta, v_prev=None)`` (displacement and velocity schemes) or
  ``predict(v_prev)`` and ``correct(v_pred)`` (product scheme): f_j at the current
  step from the history of the displacement discontinuity delta and its rate V;
* ``settle(v_new)`` after step (v) (default: nothing);
* ``channels`` (its kernels and engines, by name), ``fft`` (the transforms it uses),
  ``wait()``, ``get_state()`` and ``set_state(state)`` (checkpoints).
"""
from __future__ import annotations


class Interface:
    """Defaults of the protocol (see the module docstring)."""

    eta: dict
    channels: dict

    def settle(self, v_new) -> None:
        """After step (v), with the jump rate of the step: nothing by default (the
        bimaterial interface splits it between its faces)."""

    def wait(self) -> None:
        """Let the history engines finish the work their last push started."""
