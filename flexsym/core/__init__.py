"""Layer 0, core: what every layer may use and none of them is about: one-line user errors,
where the package finds its data and cache, progress bars, the tool versions and the
generator fingerprint."""
