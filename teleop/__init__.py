"""cdpr-teleop: teleoperation and haptic rendering for a cable-driven parallel surgical robot.

Units are SI inside (m, N, s, rad); other units appear only at the edges, named in the identifier
(`_mm`, `_deg`, `_counts`) and converted once.
"""

__version__ = "0.1.0"
