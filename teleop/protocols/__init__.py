"""teleop/protocols."""
