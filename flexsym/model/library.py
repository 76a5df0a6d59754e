"""The benchmark mechanisms S0-S3 as System data (docs/theory/mechanisms.md).

S0 is today's one-beam spin-up: a beam whose root revolute joint to ground is guided by the
variant's manoeuvre. S1-S3 follow the benchmark definitions (parameters in SI)."""
from __future__ import annotations

import math

from flexsym.model.system import (Driver, FlexibleBeam, Gravity, Joint, Marker, Output, RigidBody, Section,
                     System)

PAPER_SECTION = Section(rho=3000.0, E=7.0e10, A=4.0e-4, I=2.0e-7)
PAPER_LENGTH = 10.0


def spin_up_system(model, section: Section = PAPER_SECTION, length: float = PAPER_LENGTH,
                   maneuver: str | None = None) -> System:
    """S0: a built-in/custom variant as a one-body system (the variant's manoeuvre guides the
    root revolute; its mode set/strain model or elements are the beam's deformation model)."""
    return System(
        name=f"spin_up_{model.name}",
        bodies=(FlexibleBeam("beam", length, section, model),),
        joints=(Joint("hub", "revolute", "ground", "beam.root"),),
        drivers=(Driver("spin", "guided", "hub", maneuver=maneuver or model.maneuver),),
        outputs=(Output("theta", "angle(hub)"), Output("v_tip", "v(beam, tip)"),
                 Output("M_A", "M(beam, root)")),
    ).validate()


def variant_system(spec) -> System:
    """A one-beam variant (a VariantSpec or an FESpec) as the system its folder is generated
    from: S0 named after it, its beam the paper's section and length or its finite-element
    body's, its output positions (points) the beam's markers, its outputs under their one-beam
    names (aliases of the system grammar), and N and M recovered as the one-beam spin-up
    recovers them: "auto" is the modes' curvature (the paper's), ef's elements' own, where a
    mechanism's beam takes equilibrium."""
    from dataclasses import replace

    import sympy as sp

    model = replace(spec, **{k: "constitutive" for k in ("axial_force", "moment")
                             if getattr(spec, k) == "auto"})
    section, length = PAPER_SECTION, PAPER_LENGTH
    if spec.body is not None:
        r = spec.body.reference
        section, length = Section(r.rho, r.E, r.A, r.I), spec.body.length
    s0 = spin_up_system(model, section, length)
    markers = tuple(Marker(label, float(sp.Rational(frac)) * length) for label, frac in spec.points)
    return replace(s0, name=spec.name, bodies=(replace(s0.bodies[0], markers=markers),),
                   outputs=tuple(Output(o, o) for o in spec.outputs), one_beam=True).validate()


def hub_system(model, hub_inertia: float = 40.0) -> System:
    """S1: rigid hub (J_h) on a revolute to ground, beam clamped at the hub centre, motor torque
    tau = (J_h + rho A L^3/3) theta_P''(t), P(t; 6 rad/s, 15 s)."""
    s, L = PAPER_SECTION, PAPER_LENGTH
    J = hub_inertia + s.rho * s.A * L**3 / 3
    acc = "ifelse(t <= 15, (6/15)*(1 - cos(2*pi*t/15)), 0)"
    return System(
        name="hub",
        bodies=(RigidBody("hub", 1.0, hub_inertia, markers=(Marker("centre", 0.0),)),
                FlexibleBeam("beam", L, s, model)),
        joints=(Joint("hub_joint", "revolute", "ground", "hub.centre"),
                Joint("clamp", "clamp", "hub.centre", "beam.root")),
        drivers=(Driver("motor", "motor", "hub_joint", expression=f"{J!r}*{acc}"),),
        outputs=(Output("theta_h", "angle(hub_joint)"), Output("omega_h", "rate(hub_joint)"),
                 Output("v_tip", "v(beam, tip)"), Output("M_A", "M(beam, root)")),
    ).validate()


PENDULUM_SECTION = Section(rho=2700.0, E=7.0e10, A=1.0e-4, I=0.02 * 0.005**3 / 12)


def pendulum_system(model, section: Section = PENDULUM_SECTION, length: float = 1.0) -> System:
    """S3: flexible pendulum pinned at ground, released horizontal along +x, gravity -y."""
    return System(
        name="pendulum",
        bodies=(FlexibleBeam("beam", length, section, model,
                             markers=(Marker("mid", length / 2),)),),
        joints=(Joint("pin", "revolute", "ground", "beam.root"),),
        loads=(Gravity((0.0, -9.81)),),
        outputs=(Output("x_tip", "x(beam.tip)"), Output("y_tip", "y(beam.tip)"),
                 Output("w_mid", "w(beam, mid)"), Output("M_mid", "M(beam, mid)")),
    ).validate()


def slider_crank_system(model) -> System:
    """S2: rigid crank (guided), flexible rod pinned to crank and slider, slider on x. N_mid
    only for ef or a model with axial coordinates (#3's foreshortening carries no axial force)."""
    d = 0.006
    rod = Section(rho=7870.0, E=2.0e11, A=math.pi * d**2 / 4, I=math.pi * d**4 / 64)
    m_rod = rod.rho * rod.A * 0.3
    return System(
        name="slider_crank",
        bodies=(RigidBody("crank", 0.1, 1e-4, com=(0.075, 0.0),
                          markers=(Marker("root", 0.0), Marker("tip", 0.15))),
                FlexibleBeam("rod", 0.3, rod, model, markers=(Marker("mid", 0.15),)),
                RigidBody("slider", m_rod / 2, 1e-6, markers=(Marker("pin", 0.0),))),
        joints=(Joint("crank_joint", "revolute", "ground", "crank.root"),
                Joint("crank_pin", "revolute", "crank.tip", "rod.root"),
                Joint("slide", "prismatic", "ground", "slider.pin", axis=(1.0, 0.0),
                      initial=0.45),
                Joint("slider_pin", "revolute", "rod.tip", "slider.pin")),
        drivers=(Driver("crank_drive", "guided", "crank_joint", maneuver="spin_up",
                        params=(("ws", 150.0), ("ts", 0.1))),),
        outputs=(Output("x_s", "x(slider.pin)"), Output("w_mid", "w(rod, mid)"))
        + ((Output("N_mid", "N(rod, mid)"),) if model.kind == "fe" or model.axial else ()),
    ).validate()
