"""Layer 7, sim: built models run in this process (batches of parameter sets), in sweeps
(local pool or Dask) and exported as FMI 3.0 Co-Simulation units."""
