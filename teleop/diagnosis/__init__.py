"""teleop/diagnosis."""
