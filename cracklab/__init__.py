"""cracklab: spectral boundary-integral simulation of dynamic fracture on planar cracks.

Geubelle & Rice (1995), J. Mech. Phys. Solids 43(11): modes I, II and III, 3D and 2D.
"""

import os as _os

from .version import __version__

# The history engine's numba loop runs on OpenMP threads, the FFTs on FFTW's own: OpenMP
# workers that spin after a parallel region (the GNU default) take the cores the FFTs
# need, which made two threads slower than one (docs/studies/performance.md).  Sleep instead,
# unless the user chose otherwise; this must be set before the OpenMP runtime loads.
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from . import analysis, ensemble, kernels, scenes  # noqa: E402
from .analysis import energy  # noqa: E402
from .ensemble import open_ensemble, register_builder  # noqa: E402
from .errors import InputError, SimulationError  # noqa: E402
from .model.grid import Grid  # noqa: E402
from .laws import LAWS as _LAWS  # noqa: E402
from .model.loading import Loading, point_load  # noqa: E402
from .model.material import Material  # noqa: E402
from .analysis.modal import modal_response  # noqa: E402
from .model.record import Record  # noqa: E402
from .model.scene import Numerics, Scene  # noqa: E402
from .model.sequence import Sequence  # noqa: E402
from .output.simulate import scene_of, simulate, stations  # noqa: E402

#: every law of cracklab.laws, by its class name (LinearCohesive, SlipWeakening, ...)
globals().update({_law.__name__: _law for _law in _LAWS.values()})

__all__ = [
    "Grid", "InputError", "Loading", "Material", "Numerics",
    "Record", "Scene", "Sequence", "SimulationError", "analysis", "ensemble",
    "kernels", "modal_response", "open_ensemble", "register_builder",
    "point_load", "scene_of", "scenes", "simulate", "stations", "__version__",
] + sorted(_law.__name__ for _law in _LAWS.values())
