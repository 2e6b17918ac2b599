"""Studies: sweeps and analytical reference solutions."""
