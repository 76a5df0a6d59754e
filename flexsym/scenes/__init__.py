"""Layer 2, scenes: scene files (TOML) and finite-element folders read into model objects,
each problem refused in one line that names the file and key."""
