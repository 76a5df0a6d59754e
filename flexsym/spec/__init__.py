"""Layer 1, spec: a model as data. Mode shapes, manoeuvres, strain models, output names,
one-beam variants, mechanisms (`System`), the benchmark library, bodies from finite-element
data and the table of run options. Checked against data only; no derivation happens here."""
