"""teleop/physics."""
