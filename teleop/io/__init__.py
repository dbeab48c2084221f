"""I/O layer: session recordings (MCAP), the interchange CSV, model and calibration files, result files,
progress reporting. Imports only the core below it."""
