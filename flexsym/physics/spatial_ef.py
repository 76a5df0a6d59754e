"""The geometrically exact reference `ef` of spatial systems (physics/rod3d.py's elements,
casadi), the spatial `ef` kind's (body_kinds/spatial/ef.py): its coordinates, gravity
potential, axis points and section forces.

A uniform beam clamped to its floating frame at its root, n two-node Simo-Reissner elements.
Coordinates per free node k = 1..n (frame components): the displacement (ux, uy, uz) from the
undeformed position (k L / n, 0, 0) and the section's rotation vector (px, py, pz); all zero
at the undeformed start. Gravity is linear in the nodes and stays in sympy. The elements'
kinetic energy (in the frame's actual omega and V) is an element kernel called per element by
system.c: when the drive alone moves the frame, in the frame's given motion; when the
coordinates move it (a free frame), in quasi-velocities (the element's Hessian in z = (omega,
V, e'), its Lagrange rows and its frame 6-vector, assembled with the frame's Jacobian J =
dw/dq' by system.c, sysgen._rod_free_kernels). derive_spatial(ef_free_ad=True) puts a free
frame's elements into the whole-system AD path instead (der.casadi_T, whose kernels grow by
~2e4 operations per element), a check of the C path; their elastic energy is one casadi element
kernel called per element by system.c (sysgen._rod_element_kernel, der.rod_bodies). Outputs
that need the element (section forces, the elastic energy) are placeholders in the sympy
outputs, each given its casadi value by sysgen (der.casadi_outputs).
"""
from __future__ import annotations

import casadi as ca
import numpy as np
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.exact_numbers import exact
from flexsym.physics.rod3d import (element_functions, qconj, qlog, qmul, quaternion, relative_kinetic_energy,
                                   strain_rate_energy)

EF_NODE = ("ux", "uy", "uz", "px", "py", "pz")
EF_V = sp.Symbol("V_rod_", real=True)  # the rod elements' elastic energy (casadi)


def ef_coordinates(b) -> list[str]:
    """The coordinate names (without the body prefix) of a spatial ef beam."""
    return [f"{c}{k}" for k in range(1, b.model.elements + 1) for c in EF_NODE]


def ef_part(der, b, P: dict) -> None:
    """Registers a spatial ef beam's nodes (der.spatial[name]) before the frames are posed: a
    body hung from its marker and a loop closed there read them."""
    n = b.model.elements
    qindex = {c.name: i for i, c in enumerate(der.coords)}
    idx = [[-1] * 6] + [[qindex[f"{b.name}_{c}{k}"] for c in EF_NODE] for k in range(1, n + 1)]
    pindex = {sym: i for i, (_, sym, _) in enumerate(der.params)}
    pidx = {k: pindex[v] for k, v in P.items()}
    L = P["L"]

    def node(k):  # sympy position of node k in the frame
        if k == 0:
            return sp.zeros(3, 1)
        return sp.Matrix([sp.Rational(k, n) * L + der.q[idx[k][0]], der.q[idx[k][1]], der.q[idx[k][2]]])

    der.spatial[b.name] = dict(kind="ef", n=n, P=P, idx=idx, pidx=pidx, node=node, length=b.length)


def bending_inertia_param(system, body: str) -> str | None:
    """The run-time parameter of a spatial ef beam's bending rotary inertia factor: a beam
    whose frame a free joint moves has one ("bending_inertia", or "<body>_bending_inertia" when
    the system has more flexible bodies); a driven frame's beam has none (None)."""
    if system.frame_driven(body):
        return None
    return "bending_inertia" if sum(x.flexible for x in system.bodies) == 1 else f"{body}_bending_inertia"


def ef_body(der, b, P: dict, fr, om, vf, actual, gvec) -> sp.Expr:
    """Registers a spatial ef beam's elements (der.rod_bodies, der.casadi_T) in its frame fr and
    returns its gravity potential (sympy)."""
    info = der.spatial[b.name]
    n, idx, pidx, node = info["n"], info["idx"], info["pidx"], info["node"]
    if not der.system.frame_driven(b.name):
        # a free frame's beam: its sections' bending rotary inertia rho b (I_y, I_z) with the
        # factor b a run-time parameter (rod3d's bending_inertia; 1: physical). A small b is the
        # modal models' and the benchmark's beam (none); b = 0 makes M singular.
        pname = bending_inertia_param(der.system, b.name)
        pidx["bending_inertia"] = len(der.params)
        der.params.append((pname, sp.Symbol(pname, positive=True), 1.0))
    L, rho, A = P["L"], P["rho"], P["A"]
    info["frame"] = fr
    # a frame whose motion is the drive's alone (a guided hub, a clamp chain to ground): the
    # elements' kinetic energy is a second element kernel called per element in C (its Lagrange
    # terms by casadi AD within the element); else it joins the system's AD path (der.casadi_T),
    # whose kernels grow by ~2e4 operations per element
    in_c = der.system.frame_driven(b.name)
    # a free frame (moved by the coordinates): the elements' kinetic energy in quasi-velocities,
    # element kernels called per element in C as well (sysgen._rod_free_kernels), unless the
    # derivation asks for the whole-system AD path (der.ef_free_ad: a check of the C path)
    free_c = not in_c and not getattr(der, "ef_free_ad", False)
    # Kelvin-Voigt (strain rate) and mass-proportional (rates relative to the frame) damping
    beta, alpha = (float(getattr(b.damping, k)) if b.damped else 0.0 for k in ("beta", "alpha"))
    der.rod_bodies.append(dict(name=b.name, n=n, pidx=pidx, idx=idx, kinetic_in_c=in_c,
                               free_c=free_c, frame=fr,
                               beta=beta, alpha=alpha, damped=bool(beta or alpha)))
    info["kinetic_in_c"], info["free_c"] = in_c, free_c
    der.terms.append((b.name, "rod3d_elastic", ("node",), None, None))

    def kinetic(tr, x, info=info):
        f = element_functions()["kinetic"]
        omega = ca.vertcat(*[tr(e) for e in fr.omega])
        V = ca.vertcat(*[tr(e) for e in fr.V])
        nodes, rates = rod_nodes(info, x["q"], x["p"]), rod_nodes(info, x["qd"], None)
        le, sec = x["p"][pidx["L"]] / n, rod_section(info, x["p"])
        bi = rod_bending_inertia(info, x["p"])
        return sum((f(ca.vertcat(nodes[k], nodes[k + 1]), ca.vertcat(rates[k], rates[k + 1]),
                      omega, V, le, sec, bi) for k in range(n)), ca.SX(0.0))
    if in_c or free_c:
        der.casadi_T_out.append(kinetic)  # only the T output reads it (energy: system.c)
    else:
        der.casadi_T.append(kinetic)
    g_c = fr.g
    return (-rho * A * L * gvec.dot(fr.R)
            - rho * A * L / (2 * n) * sum((g_c.dot(node(k) + node(k + 1)) for k in range(n)), sp.Integer(0)))


def rod_section(info, p):
    """sec = (E, G, rho, A, Iy, Iz, J) of rod3d from the run-time parameters."""
    return ca.vertcat(*[p[info["pidx"][k]] for k in ("E", "G", "rho", "A", "Iy", "I", "J")])


def rod_bending_inertia(info, p):
    """rod3d's bending_inertia factor from the run-time parameters (a free frame's beam has it,
    spatial_ef.ef_body; else 1)."""
    return p[info["pidx"]["bending_inertia"]] if "bending_inertia" in info["pidx"] else 1.0


def rod_nodes(info, v, p):
    """Nodal 6-vectors (frame components) k = 0..n of a spatial ef beam from the coordinate
    vector v (casadi): positions when p is given (x = k L / n added), else rates."""
    n, out = info["n"], [ca.SX.zeros(6)]
    for k in range(1, n + 1):
        ent = [v[i] for i in info["idx"][k]]
        if p is not None:
            ent[0] = ent[0] + p[info["pidx"]["L"]] * k / n
        out.append(ca.vertcat(*ent))
    return out


def ef_at(der, body: str, x: float) -> sp.Matrix:
    """The deformed axis point at station x (linear between the nodes), frame components."""
    info = der.spatial[body]
    n = info["n"]
    s_ = exact(x) / exact(info["length"]) * n
    j = min(int(sp.floor(s_)), n - 1)
    tt = s_ - j
    return (1 - tt) * info["node"](j) + tt * info["node"](j + 1)


def ef_node(der, body: str, x: float) -> int:
    """The node at station x of a spatial ef beam (a marker a joint or an orientation reads;
    System.validate has checked that it is one)."""
    info = der.spatial[body]
    k = exact(x) / exact(info["length"]) * info["n"]
    if k != int(k):
        raise SpecError(f"system '{der.system.name}': the marker at x = {x} of the ef beam '{body}' "
                        f"must sit on one of its {info['n']} elements' nodes")
    return int(k)


def ef_quaternion(der, body: str, x: float) -> sp.Matrix:
    """The unit quaternion e = (cos(t/2), sin(t/2) psi / t), t = |psi|, of a node's section at
    station x (a marker of a spatial ef beam: a body hung from it, a loop closed at it, its
    orientation R(...)), psi the node's rotation vector: four applied functions e_k(psi),
    registered in der.casadi_functions, whose values (and derivatives) casadi computes
    (rod3d.quaternion, its series regular at psi = 0; sysgen.placeholder_values) while sympy
    differentiates them as any function; der.ef_start holds their values at the undeformed
    start (1, 0, 0, 0). The root's is (1, 0, 0, 0)."""
    return ef_node_quaternion(der, body, ef_node(der, body, x))


def ef_node_quaternion(der, body: str, k: int) -> sp.Matrix:
    """ef_quaternion of node k (0: the root)."""
    info = der.spatial[body]
    if k == 0:
        return sp.Matrix([1, 0, 0, 0])
    quats = info.setdefault("quaternions", {})
    if k not in quats:
        idx = info["idx"][k][3:6]
        names = [f"rod_{body}_e{k}_{c}" for c in range(4)]
        quats[k] = sp.Matrix([sp.Function(nm, real=True)(*[der.q[c] for c in idx]) for nm in names])
        for c, nm in enumerate(names):
            der.casadi_functions[nm] = lambda tr, xx, c=c, idx=idx: quaternion(ca.vertcat(*[xx["q"][i] for i in idx]))[c]
        if not hasattr(der, "ef_start"):
            der.ef_start = {}
        der.ef_start |= {e: sp.Integer(int(c == 0)) for c, e in enumerate(quats[k])}
    return quats[k]


def ef_station_quaternion(der, body: str, x: float) -> sp.Matrix:
    """The unit quaternion of the section at station x (rotation relative to the frame): at a
    node its own (ef_node_quaternion), between nodes k and k+1 the elements' interpolation of
    the rotations, e_k (x) exp(t log(e_k* (x) e_k+1)) at t = (x - x_k) / l_e (rod3d's
    Crisfield-Jelenic interpolation), as output placeholders given their casadi values by
    sysgen (an output only projects on it: no time derivative)."""
    info = der.spatial[body]
    n = info["n"]
    s_ = exact(x) / exact(info["length"]) * n
    if s_ == int(s_):
        return ef_node_quaternion(der, body, int(s_))
    k, t = int(s_), float(s_ - int(s_))
    out = []
    for c in range(4):
        sym = sp.Symbol(f"rod_{body}_q{c}_{len(der.casadi_outputs)}", real=True)

        def value(tr, xx, info=info, k=k, t=t, c=c):
            e1, e2 = (quaternion(ca.vertcat(*[xx["q"][i] for i in info["idx"][j][3:6]]))
                      if j > 0 else ca.DM([1, 0, 0, 0]) for j in (k, k + 1))
            return qmul(e1, quaternion(t * qlog(qmul(qconj(e1), e2))))[c]
        der.casadi_outputs[sym] = value
        out.append(sym)
    return sp.Matrix(out)


def ef_section(der, beam, x: float, fn: str) -> sp.Expr:
    """N, Qy, Qz, Mx, My, Mz at x: rod3d's constitutive section forces (deformed section axes:
    the Simo-Reissner element has shear strains, so Q is GA Gamma_y, GA Gamma_z) at the
    element midpoints, linear in x between them and extrapolated over the end half-elements
    (rod3d.ClampedBeam.section_forces_at), as a placeholder given its casadi value by sysgen."""
    info = der.spatial[beam.name]
    n = info["n"]
    sym = sp.Symbol(f"rod_{beam.name}_{fn}_{len(der.casadi_outputs)}", real=True)
    comp = {"N": 0, "Qy": 1, "Qz": 2, "Mx": 3, "My": 4, "Mz": 5}[fn]
    s_ = float(x) / float(info["length"]) * n  # in element lengths
    k = min(max(int(np.floor(s_ - 0.5)), 0), max(n - 2, 0))
    tt = s_ - (k + 0.5)

    def value(tr, xx, info=info, k=k, tt=tt, comp=comp):
        f = element_functions()["forces"]
        nodes = rod_nodes(info, xx["q"], xx["p"])
        le, sec = xx["p"][info["pidx"]["L"]] / n, rod_section(info, xx["p"])
        Fk = f(ca.vertcat(nodes[k], nodes[k + 1]), le, sec)[comp]
        if n == 1:
            return Fk
        Fk1 = f(ca.vertcat(nodes[k + 1], nodes[k + 2]), le, sec)[comp]
        return (1 - tt) * Fk + tt * Fk1
    der.casadi_outputs[sym] = value
    return sym


def ef_elastic_output(der) -> sp.Expr:
    """The rod elements' elastic energy in the V output (a placeholder, casadi)."""
    if EF_V not in der.casadi_outputs:
        def value(tr, xx):
            f = element_functions()["elastic"]
            total = ca.SX(0.0)
            for body in der.rod_bodies:
                info = der.spatial[body["name"]]
                nodes = rod_nodes(info, xx["q"], xx["p"])
                le, sec = xx["p"][info["pidx"]["L"]] / info["n"], rod_section(info, xx["p"])
                total += sum((f(ca.vertcat(nodes[k], nodes[k + 1]), le, sec)
                              for k in range(info["n"])), ca.SX(0.0))
            return total
        der.casadi_outputs[EF_V] = value
    return EF_V


EF_TK = sp.Symbol("T_rod_", real=True)  # the T of ef beams whose elements' T is a C kernel


def ef_kinetic_output(der) -> sp.Expr:
    if EF_TK not in der.casadi_outputs:
        der.casadi_outputs[EF_TK] = lambda tr, xx: sum((c(tr, xx) for c in der.casadi_T_out),
                                                       ca.SX(0.0))
    return EF_TK


ROD_D = sp.Symbol("D_rod_", real=True)  # the damped rods' dissipation (casadi)


def rod_dissipation_output(der) -> sp.Expr:
    """The damped spatial ef beams' dissipation D = sum over elements of beta
    rod3d.strain_rate_energy + alpha rod3d.relative_kinetic_energy in the `dissipation` output
    (a placeholder, casadi)."""
    if ROD_D not in der.casadi_outputs:
        def value(tr, xx):
            total = ca.SX(0.0)
            for body in der.rod_bodies:
                if not body["damped"]:
                    continue
                info = der.spatial[body["name"]]
                nodes, rates = rod_nodes(info, xx["q"], xx["p"]), rod_nodes(info, xx["qd"], None)
                le, sec = xx["p"][info["pidx"]["L"]] / info["n"], rod_section(info, xx["p"])
                bi = rod_bending_inertia(info, xx["p"])
                for k in range(info["n"]):
                    e, ed = ca.vertcat(nodes[k], nodes[k + 1]), ca.vertcat(rates[k], rates[k + 1])
                    if body["beta"]:
                        total += body["beta"] * strain_rate_energy(e, ed, le, sec)
                    if body["alpha"]:
                        total += body["alpha"] * relative_kinetic_energy(e, ed, le, sec, bi)
            return total
        der.casadi_outputs[ROD_D] = value
    return ROD_D
