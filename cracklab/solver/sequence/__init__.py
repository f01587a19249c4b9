"""Sequences of earthquakes and aseismic slip: a time step chosen by the solution.

* :mod:`.pairs`: embedded Runge-Kutta pairs, each a frozen dataclass of its coefficients;
* :mod:`.control`: the step control (tolerance, bounds, the step after an error estimate);
* :mod:`.static`: the quasi-dynamic elastic response, the static kernels per mode;
* :mod:`.quasi_dynamic`: slip and state of a rate-and-state plane as one ODE system, the
  traction from the static response plus radiation damping, loaded by a plate rate;
* :mod:`.integrate`: the adaptive integration of such a system, one accepted step at a time;
* :mod:`.run`: a sequence scene's run (its system, control and pair), resumable from its state.
"""
