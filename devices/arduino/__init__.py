"""devices/arduino."""
