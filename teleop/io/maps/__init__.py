"""Column maps (TOML) for recording layouts other than the interchange CSV (see recording_io)."""
