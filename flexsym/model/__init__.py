"""Layer 1, model: a model as data, what is simulated. Mode shapes, manoeuvres, strain
models, output names, one-beam variants, mechanisms (`System`), the benchmark library, bodies
from finite-element data, the table of run options and the limits every number is checked
against. Checked against data only; no derivation happens here."""
