"""teleop/apps/protocols."""
