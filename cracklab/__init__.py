"""cracklab: spectral boundary-integral simulation of dynamic fracture on planar cracks."""

__version__ = "0.1.0"
