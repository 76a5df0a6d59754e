"""Layer 8, analysis: studies and reports built on runs: the spin-up main job, the paper's
figures, benchmarks of speed against error, model selection, plots and inspection."""
