"""Layer 5, codegen: a derivation's kernels written into a generated folder (C, CMakeLists,
manifest.json) through the jinja2 templates, deterministically."""
