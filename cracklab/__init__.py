"""cracklab: spectral boundary-integral simulation of dynamic fracture on planar cracks.

Geubelle & Rice (1995), J. Mech. Phys. Solids 43(11): modes I, II and III, 3D and 2D.
"""

__version__ = "0.1.0"

import os as _os

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
from .laws import LinearCohesive, PrescribedRupture, SlipWeakening, TractionFree  # noqa: E402
from .model.loading import Loading, point_load  # noqa: E402
from .model.material import Material  # noqa: E402
from .analysis.modal import modal_response  # noqa: E402
from .model.record import Record  # noqa: E402
from .model.scene import Numerics, Scene  # noqa: E402
from .output.simulate import scene_of, simulate, stations  # noqa: E402

__all__ = [
    "Grid", "InputError", "LinearCohesive", "Loading", "Material", "Numerics", "PrescribedRupture",
    "Record", "Scene", "SimulationError", "SlipWeakening", "TractionFree", "analysis", "ensemble",
    "kernels", "modal_response", "open_ensemble", "register_builder",
    "point_load", "scene_of", "scenes", "simulate", "stations", "__version__",
]
