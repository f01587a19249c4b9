"""Elastodynamics of a half space, shared by every layer above: the convolution kernels C
and Z of the modes (kernels.py, Eqs. 29-31), the faces' kernels of two different materials
(face_kernels.py) and their branch cuts (cuts.py), the convolution weights of the time
schemes (weights.py, Eqs. 45-47) and the wave speeds (waves.py). Imports nothing of
cracklab but its errors (tests/test_layers.py)."""
