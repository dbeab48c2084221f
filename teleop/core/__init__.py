"""Core layer: geometry, kinematics, tension distribution, the effect catalogue, sensors, estimation,
rendering, mapping, control and the compiled kernels. Imports nothing above it (numpy, scipy, numba only)."""
