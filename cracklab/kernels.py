"""The kernels C_I, C_II, C_III (and Z) under their public name ``cracklab.kernels``
(the solver's module is cracklab.solver.kernels)."""
from .solver.kernels import *  # noqa: F401,F403
