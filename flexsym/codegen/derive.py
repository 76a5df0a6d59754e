"""A one-beam variant's symbolic derivation, by its strain model's kinematics: the modal
(second-order) kinematics of modal.py or the exact kinematics of exact.py (what `flexsym
inspect` shows; the generated code is its S0's, codegen/generate.py)."""
from __future__ import annotations

from flexsym.physics.exact import derive_exact
from flexsym.physics.modal import Derivation, derive_modal
from flexsym.model.variant import VariantSpec, check_clamped_root


def derive(spec: VariantSpec) -> Derivation:
    spec.validate()
    check_clamped_root(spec)
    return derive_exact(spec) if spec.exact_kinematics else derive_modal(spec)
