"""The blind stiffness-ranking study of seed 000 §5.2 (Table 3).

protocol.py: the comparison protocol as pure functions of the answers; participants.py: simulated
participants who feel only the rendered force; probe.py: the poke interface between participant and rig;
study.py: the driver and the results; stats.py: Kendall tau/W, slopes; human.py: real participants with a
resumable state file; rig.py: the simulated rig (full loop on the pybullet pads).
"""
