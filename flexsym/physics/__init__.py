"""Layer 4, physics: modal integrals, energies, Lagrange's equations, stress recovery, the
one-beam modal and exact-kinematics derivations, the `ef` (ANCF) element and bodies, the
derivation of a mechanism on its spanning tree, and the validity criteria."""
