"""
A flexible arm falling under gravity
====================================

A rigid hub pinned to ground carries a steel link clamped to it; released horizontal, the arm
swings down under gravity while the link bends. The system is built in Python, derived,
generated, compiled and run by flexsym (the first run builds it; later runs reuse the build).
"""
# %%
import matplotlib.pyplot as plt

from flexsym.model.system import (FlexibleBeam, Gravity, Joint, Marker, Output, RigidBody,
                                 Section, System)
from flexsym.apps import api
from flexsym.model.variant import builtin

steel = Section(rho=7850.0, E=2.1e11, A=5.0e-5, I=2.0e-10)  # SI units
arm = System(
    name="gallery_arm",
    bodies=(RigidBody("hub", mass=2.0, inertia=1e-2, markers=(Marker("centre", 0.0, 0.0),)),
            FlexibleBeam("link", 0.5, steel, builtin("m3"), markers=(Marker("mid", 0.25),))),
    joints=(Joint("shoulder", "revolute", "ground", "hub.centre"),
            Joint("weld", "clamp", "hub.centre", "link.root")),
    loads=(Gravity((0.0, -9.81)),),
    outputs=(Output("y_tip", "y(link.tip)"), Output("w_mid", "w(link, mid)"),
             Output("M_root", "M(link, root)")))
result = api.run(arm, t_end=1.0, dt=1e-4, integrator="genalpha")
print(result.status)

# %%
# The tip falls through the lowest point of the swing; the link's bending moment at the clamp
# follows the centripetal and gravity loads.
fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(6, 5))
ax1.plot(result.t, result["y_tip"])
ax1.set_ylabel("y_tip [m]")
ax2.plot(result.t, result["M_root"])
ax2.set_ylabel("M_root [N m]")
ax2.set_xlabel("t [s]")
fig.tight_layout()
