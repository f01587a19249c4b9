"""The kernels C_I, C_II, C_III (and Z) under their public name ``cracklab.kernels``
(the module itself is cracklab.elastic.kernels)."""
from .elastic.kernels import *  # noqa: F401,F403
