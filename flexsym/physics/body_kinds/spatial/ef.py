"""A spatial `ef` beam (physics/spatial_ef.py, rod3d's Simo-Reissner elements in casadi) as a
body: its nodes' coordinates; gravity in sympy, the elements' T and elastic energy by sysgen
(der.rod_bodies, der.casadi_T); its axis points, section axes at a node, the frame of a body
hung from a node's marker, and section forces."""
from __future__ import annotations

import numpy as np
import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.physics.assemble import Coordinate
from flexsym.physics.body_kinds import ef as planar
from flexsym.physics.body_kinds.spatial.base import (Frame, SpatialBeam, along_motion, cross, euler_G,
                                                     euler_rotation)
from flexsym.physics.spatial_ef import (ef_at, ef_body, ef_coordinates, ef_node_quaternion, ef_part,
                                        ef_quaternion, ef_section, ef_station_quaternion)
from flexsym.physics.validity import Prefixed, strain_gauge


class Ef(SpatialBeam):
    name = "ef"
    applies = staticmethod(planar.KIND.applies)  # the same data in both dimensions

    def coordinates(self, b) -> list:
        """Per free node, the displacement and the rotation vector."""
        return [Coordinate(f"{b.name}_{n}", "node", b.name, start=(0.0, 0.0)) for n in ef_coordinates(b)]

    def gauges(self, b, length: float) -> list:
        """The axial strain of each element's chord, |X_k - X_k-1| / (L / n) - 1, X_k the node's
        position in its frame (k L / n, 0, 0) + (ux, uy, uz)_k, the root's X_0 = 0."""
        n = b.model.elements

        def strain(cols):
            c = Prefixed(cols, b.name)
            X = [np.zeros((len(c["ux1"]), 3))] + [
                np.column_stack([k * length / n + c[f"ux{k}"], c[f"uy{k}"], c[f"uz{k}"]])
                for k in range(1, n + 1)]
            return np.max([np.abs(np.linalg.norm(X[k] - X[k - 1], axis=1) * n / length - 1)
                           for k in range(1, n + 1)], axis=0)
        return [strain_gauge(b, strain)]

    def part(self, der, b, P) -> None:
        ef_part(der, b, P)

    def hang(self, der, fr: Frame, body: str, m):
        """The section's frame at a node: origin at the node r, axes Lambda(e) from the beam's
        frame, e the node's quaternion (functions of its rotation vector psi that sympy
        differentiates: spatial_ef.ef_quaternion); its angular velocity in its own axes
        Lambda^T omega + 2 G(e) e', as a ball joint's, its origin's velocity
        Lambda^T (V + omega x r + r')."""
        r, e = ef_at(der, body, m.x), ef_quaternion(der, body, m.x)
        Lam = euler_rotation(e)
        return Frame(fr.A * Lam, fr.R + fr.A * r, Lam.T * fr.omega + 2 * euler_G(e) * der.ddt(e),
                     Lam.T * (fr.V + cross(fr.omega, r) + der.ddt(r)), Lam.T * fr.g), sp.zeros(3, 1)

    def contribute(self, der, b, P, fr, motion, gvec) -> None:
        der.V_grav += ef_body(der, b, P, fr, motion.om, motion.vf, motion.actual, gvec)

    def first_moment(self, der, b, fr):
        """m R + A int rho A r dx: the linear elements' rho A (L/n) (r_k + r_k+1)/2 each."""
        info = der.spatial[b.name]
        n, node, P = info["n"], info["node"], info["P"]
        m = P["rho"] * P["A"] * P["L"]
        local = sum((node(k) + node(k + 1) for k in range(n)), sp.zeros(3, 1)) * m / (2 * n)
        return m, m * fr.R + fr.A * local

    def momentum(self, der, b, fr) -> sp.Matrix:
        """Angular momentum about the ground origin (ground components), conjugate to rod3d's T
        (spatial_ef.ef_body): _moment_of_rates with the absolute velocities."""
        return fr.A * _moment_of_rates(der, b, fr, relative=False)[1]

    def damping_load(self, der, b):
        """The mass-proportional damper's load (alpha; beta's strain-rate stress is internal):
        D_alpha is rod3d's kinetic energy of the rates relative to the frame, so on a rigid
        virtual motion of the beam its force -dD/de' does the work of -alpha times the
        momentum of those rates: the force -alpha int rho A r' dx and its moment (about the
        ground origin, ground components) -alpha (H of the relative rates)."""
        alpha = _alpha(b)
        if not alpha:
            return None
        fr = der.spatial["frames"][b.name]
        force, moment = _moment_of_rates(der, b, fr, relative=True)
        return -alpha * fr.A * force, -alpha * fr.A * moment

    def axis_point(self, der, body: str, x: float) -> sp.Matrix:
        return ef_at(der, body, x)

    def section_rotation(self, der, body: str, m) -> sp.Matrix:
        """A node's section: exp(psi), exact (the rotation of its quaternion: spatial_ef.ef_quaternion)."""
        return der.spatial["frames"][body].A * euler_rotation(ef_quaternion(der, body, m.x))

    def displacement(self, der, beam, x: float, fn: str) -> sp.Expr:
        r = ef_at(der, beam.name, x)
        k = ("u", "v", "vz").index(fn)
        return r[k] - (exact(x) / exact(beam.length) * der.spatial[beam.name]["P"]["L"] if k == 0 else 0)

    def section(self, der, beam, x: float, fn: str, loads_beyond, side: int = 0) -> sp.Expr:
        """Those of the part beyond x (_equilibrium), in the deformed section's axes, unless
        `moment` / `axial_force` (Q and the moments / N) say "constitutive": then rod3d's own
        (strains, shear included), which converge from a larger start (S5's T_A on 32
        elements: 6.1e-3 of its peak off 64 against 6.2e-5, docs/validation/spatial.md)."""
        source = beam.model.axial_force if fn == "N" else beam.model.moment
        if source == "constitutive":  # (continuous: a side reads the same)
            return ef_section(der, beam, x, fn)
        S, M = _equilibrium(der, beam, x, loads_beyond, side)
        turn = euler_rotation(ef_station_quaternion(der, beam.name, x)).T  # frame -> section
        return (turn * (S if fn in ("N", "Qy", "Qz") else M))[("N", "Qy", "Qz", "Mx", "My", "Mz").index(fn) % 3]


def _moment_of_rates(der, b, fr, relative: bool) -> tuple[sp.Matrix, sp.Matrix]:
    """(linear momentum, angular momentum about the ground origin), frame components, of a
    spatial ef beam's velocities v_k = r_k' (+ V + omega x r_k unless relative) and its
    sections' angular velocities W_k = 2 G(e_k) e_k' (+ Lambda_k^T omega), positions
    p_k = A^T R + r_k: per element rho A le/2 (v1 + v2) and rho A le/6 (2 p1 x v1 + p1 x v2 +
    p2 x v1 + 2 p2 x v2) (the linear element's consistent mass, exact), and at each node its
    lumped rotary inertia (le/2 per element, the root's too) Lambda_k J W_k,
    J = rho diag(I_y + I_z, b I_y, b I_z), as rod3d's T (spatial_ef.ef_body)."""
    info = der.spatial[b.name]
    n, node, P = info["n"], info["node"], info["P"]
    le = P["L"] / n
    J = _rotary_inertia(der, info)
    Rl = fr.A.T * fr.R
    pos = [Rl + node(k) for k in range(n + 1)]
    vel = [der.ddt(node(k)) + (sp.zeros(3, 1) if relative else fr.V + cross(fr.omega, node(k))) for k in range(n + 1)]
    lin, H = sp.zeros(3, 1), sp.zeros(3, 1)
    for k in range(n):
        (p1, v1), (p2, v2) = (pos[k], vel[k]), (pos[k + 1], vel[k + 1])
        lin += P["rho"] * P["A"] * le / 2 * (v1 + v2)
        H += P["rho"] * P["A"] * le / 6 * (2 * cross(p1, v1) + cross(p1, v2) + cross(p2, v1) + 2 * cross(p2, v2))
    for k in range(n + 1):
        Lam, W_rel = _node_rotation(der, b.name, k)
        W = W_rel + (sp.zeros(3, 1) if relative else Lam.T * fr.omega)
        H += (le / 2 if k in (0, n) else le) * Lam * J * W
    return lin, H


def _alpha(b):
    """The beam's mass-proportional damping coefficient alpha (exact), 0 when it has none (the
    damper's load on its joints and the equilibrium's -alpha rho A r' read it alike)."""
    return exact(b.damping.alpha) if b.damped and b.damping.alpha else 0


def _rotary_inertia(der, info) -> sp.Matrix:
    """J = rho diag(I_y + I_z, b I_y, b I_z) per unit length, the sections' rotary inertia as
    rod3d's T lumps it (b: its bending_inertia factor, a run-time parameter of a free frame's
    beam, else 1)."""
    P, pidx = info["P"], info["pidx"]
    bi = der.params[pidx["bending_inertia"]][1] if "bending_inertia" in pidx else 1
    return sp.diag(P["rho"] * (P["Iy"] + P["I"]), bi * P["rho"] * P["Iy"], bi * P["rho"] * P["I"])


def _node_rotation(der, body: str, k: int) -> tuple[sp.Matrix, sp.Matrix]:
    """(Lambda_k, W_rel,k): node k's section rotation relative to the frame and its angular
    velocity relative to the frame in the section's axes, 2 G(e_k) e_k' (e_k its quaternion)."""
    e = ef_node_quaternion(der, body, k)
    return euler_rotation(e), 2 * euler_G(e) * der.ddt(e)


def _equilibrium(der, b, x: float, loads_beyond, side: int = 0) -> tuple[sp.Matrix, sp.Matrix]:
    """(S, M): the force and the moment about the section's axis point of every load on the part
    of the beam beyond station x, inertia included (frame components), once per station. Per
    element the part beyond x of rho A (g - a - alpha r') with the linear element's position r,
    rate r' and acceleration a = a_0 + alpha_f x r + omega x (omega x r) + 2 omega x r' + r''
    (each linear in the element: 2 Gauss points are exact for the moments); at each node minus
    the rate of its sections' lumped spin momentum h_k = Lambda_k J W_k (d/dt along the motion
    plus omega x h_k) and alpha Lambda_k J W_rel,k, weighted by the part of its tributary
    length (l_e/2 each side, as rod3d's T lumps it) beyond x; then the loads on its markers
    beyond x (loads_beyond). At the root this is the whole beam's momentum balance, which a
    tree joint's reaction takes by another path (_moment_of_rates, along_motion). side: the
    station's, for the loads on markers at x (system.loads_at)."""
    memo = der.spatial[b.name].setdefault("equilibrium", {})
    if (x, side) in memo:
        return memo[(x, side)]
    info = der.spatial[b.name]
    n, node, P = info["n"], info["node"], info["P"]
    fr = der.spatial["frames"][b.name]
    L, rho, A = P["L"], P["rho"], P["A"]
    le = L / n
    om = fr.omega
    al, a0 = der.ddt(om), der.ddt(fr.V) + cross(om, fr.V)
    alpha = _alpha(b)
    s_ = exact(x) / exact(b.length) * n  # the station in element lengths
    section = ef_at(der, b.name, x)
    pos = [node(k) for k in range(n + 1)]
    vel = [der.ddt(r) for r in pos]
    acc = [der.ddt(v) for v in vel]
    S, M = sp.zeros(3, 1), sp.zeros(3, 1)
    gauss = (sp.Rational(1, 2) - sp.sqrt(3) / 6, sp.Rational(1, 2) + sp.sqrt(3) / 6)
    for k in range(n):
        t0 = max(sp.Integer(0), s_ - k)
        if t0 >= 1:
            continue
        for g in gauss:  # t in [t0, 1], each point's weight (1 - t0) / 2 of the element
            t = t0 + (1 - t0) * g
            r = (1 - t) * pos[k] + t * pos[k + 1]
            v = (1 - t) * vel[k] + t * vel[k + 1]
            a = a0 + cross(al, r) + cross(om, cross(om, r)) + 2 * cross(om, v) + (1 - t) * acc[k] + t * acc[k + 1]
            f = rho * A * le * (1 - t0) / 2 * (fr.g - a - alpha * v)
            S += f
            M += cross(r - section, f)
    J = _rotary_inertia(der, info)
    for k in range(n + 1):
        lo, hi = max(sp.Rational(2 * k - 1, 2), 0, s_), min(sp.Rational(2 * k + 1, 2), n)
        if hi <= lo:
            continue
        Lam, W_rel = _node_rotation(der, b.name, k)
        h = Lam * J * (Lam.T * om + W_rel)
        M -= (hi - lo) * le * (along_motion(der, h, 1) + cross(om, h) + alpha * Lam * J * W_rel)
    S = sp.Matrix([loads_beyond(der, b, x, "S" + c, S[i], section, side) for i, c in enumerate("xyz")])
    M = sp.Matrix([loads_beyond(der, b, x, "M" + c, M[i], section, side) for i, c in enumerate("xyz")])
    memo[(x, side)] = (S, M)
    return memo[(x, side)]


KIND = Ef()
