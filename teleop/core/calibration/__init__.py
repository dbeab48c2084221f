"""Sensor calibration: fits, their uncertainty and plots (reading and writing the files is teleop.io:
table, calibration_csv, calfile).

- fsr: the loading and unloading quintics of seed 000 eq 2 / Fig 7 from a step protocol.
- fbg: FBG force sensitivity [pm/N], hysteresis and temperature ratio r from load steps at two or more
  temperatures (seed 001 sec. 2.1.3-2.1.4, 3.1).
- one_sensor: Kp, Kr and the transition widths of one instrumented cable (seed 001 eq 7).
- generate: step protocols made from the sensor physics models, with known parameters (tests, examples).

The fits never import `generate`; `generate` never imports the fits: they share only the physics models
(teleop.core.sensors, teleop.core.physics).
"""
