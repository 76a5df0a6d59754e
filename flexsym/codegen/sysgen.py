"""A System -> kernels (casadi) -> a generated folder that fills flexsym/system.h's struct.

Kernels (dense, row-major; d = drive [t, theta_k, theta_k', theta_k''], p = parameters):
  mass(q, d, p) -> M        force(q, qd, d, p) -> f          M q'' = f
  residual_jac(q, qd, qdd, d, p) -> dr/dq, dr/dq' of r = M q'' - f
  ef_elastic(e, pe) -> V, g, H   one ANCF element's elastic energy (ef_elastic_grad: V, g):
                                 system.c adds it to force, residual_jac and energy per element
  outputs(q, qd, qdd, lambda, d, p) -> y     energy(q, qd, d, p) -> [T, V, h]     drive(t, mp) -> d
An ef body's kinetic energy is not in the sympy derivation: ef_kinetic_energy instantiates the
generic element's T per element in casadi and build_system_kernels adds its Lagrange terms (AD)
to mass, force, residual_jac, energy and the outputs that read T.
  ef_damping(e, ed, pe, c) -> g, dg/de, dg/ded   a damped ef body's element damping force
                                 -g = -dD/de' (efbody.generic_dissipation, casadi AD):
                                 system.c adds it to force and residual_jac per element, as
                                 ef_elastic; the output `dissipation` (2 D) sums D^e in casadi
                                 (ef_dissipation). An undamped system's files are unchanged.
Deterministic like a variant's folder (generate.py: same writer, manifest and file hashes).
The fingerprint covers the system's spec, the variant generator's hash (the physics modules
and templates) and this module, assemble.py, body_kinds/, efbody.py, system.py and templates/system/.
"""
from __future__ import annotations

import hashlib
import json
import math
import re
import time

import casadi as ca
import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from flexsym.physics.assemble import (EF_D, EF_T, SystemDerivation, param_layout, derive_system,
                                      ef_guided_force, length_param, start_of)
from flexsym.physics.spatial import derive_spatial, spatial_params
from flexsym.physics.exact_body import EXACT_VG, exact_energies, exact_mass, exact_residual
from flexsym.emit.cemit import c_double, emit
from flexsym.physics.efbody import _E, _ED, EA, EI, OM, RA, VX, VY, EfPart, generic_dissipation, generic_element
from flexsym.physics.energy import A, E, I, L, rho
from flexsym.physics.fe import le
from flexsym.codegen.folder import MANIFEST, c_prefix, environment, model_accessor
from flexsym.physics.lagrange import equations_of_motion_sx
from flexsym.emit.kernels import SympyToCasadi, group_by_parameters, make_kernels, matrix_sx
from flexsym.model.maneuver import t as t_sym
from flexsym.core.paths import module_file, templates_dir
from flexsym.model.system import System, length_scale, system_to_dict
from flexsym.core.versions import BODY_KIND_MODULES, generator_hash, tool_versions
from flexsym.scenes.assembly import numeric_rank

_OWN = ("physics.assemble", "physics.spatial", "physics.spatial_ef", "physics.rod3d", "physics.efbody",
        "physics.exact_kinematics", "physics.exact_body", *BODY_KIND_MODULES, "model.system", "codegen.sysgen")


LARGE_KERNELS = 40_000  # operations above which kernels.c is compiled at -O1 (kernels.cmake.j2)
# Kernels a run calls rarely, compiled apart at -O0 (RARE_FILE) above a size each: the
# energies (an output row's, and only when asked) and the Newton matrix's residual_jac (a few
# times a run with the default modified Newton; every step with --newton full, which then runs
# up to 2x slower). gcc's register allocation can grow much faster than a straight-line
# function's length: a planar exact FE body's residual_jac of 141 k operations takes 121 s at
# -O1 (113 s with the reload limit of kernels.cmake.j2), its energy of 52 k 48 s, the whole
# folder at -O0 8 s (docs/reference/generated-code.md). A spatial ef rod's Jacobian (88 k, 226
# evaluations in 2686 steps of S6) stays optimised: it builds in seconds and dominates the run.
RARE_KERNELS = {"energy": 20_000, "residual_jac": 100_000}
RARE_FILE = "kernels_rare.c"
KERNELS_CMAKE = "kernels.cmake"  # the kernels' sources and flags, when they have flags of their own
# A beam section's values: run-time parameters p (their names: assemble.param_layout,
# spatial.spatial_params), never numbers of the derivation (derivation_fingerprint)
RUN_TIME_SECTION = ("rho", "E", "A", "I", "Iy", "J", "G")


def fingerprint(system: System) -> str:
    """The generated folder's: every input of its files (the system with the values of its
    run-time parameters, the generator's source and templates, the tool versions)."""
    return _fingerprint(system_to_dict(system))


def derivation_fingerprint(system: System) -> str:
    """The derivation's: the fingerprint's inputs without the values of the beams' sections
    (RUN_TIME_SECTION), which enter a generated folder only as the run-time parameters'
    defaults (system.c's param_defaults; tests/test_derivation_reuse.py checks it). Folders
    that differ in those values alone have the same kernels.c, header and CMakeLists.txt
    (which carry this fingerprint), share one derivation (toolchain/pipeline.py) and one
    compilation of their kernels (toolchain/build.py)."""
    content = system_to_dict(system)
    for body in content["bodies"]:
        for key in RUN_TIME_SECTION:
            (body.get("section") or {}).pop(key, None)
    return _fingerprint(content)


def _versions(content: dict) -> dict[str, str]:
    """Tool versions; a body from finite-element data adds numpy and scipy (its eigenvectors)."""
    versions = tool_versions()
    if any("body" in (b.get("model") or {}) for b in content["bodies"]):
        import numpy
        import scipy

        versions |= {"numpy": numpy.__version__, "scipy": scipy.__version__}
    return versions


def _fingerprint(content: dict) -> str:
    h = hashlib.sha256(generator_hash().encode())
    for f in [module_file(m) for m in _OWN] + sorted((templates_dir() / "system").glob("*.j2")):
        h.update(f.name.encode() + b"\0" + f.read_bytes().replace(b"\r\n", b"\n"))
    payload = {"system": content, "generator": h.hexdigest(), "versions": _versions(content)}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def build_system_kernels(der: SystemDerivation) -> list:
    n, nd = len(der.q), len(der.drive_symbols)
    x = {"q": ca.SX.sym("q", n), "qd": ca.SX.sym("qd", n), "qdd": ca.SX.sym("qdd", n),
         "d": ca.SX.sym("d", nd), "p": ca.SX.sym("p", len(der.params)), "t": ca.SX.sym("t"),
         "mp": ca.SX.sym("mp", len(der.drive_params)), "lam": ca.SX.sym("lam", len(der.lam))}
    symbols, priority = {}, {}
    for i, (_, sym, _) in enumerate(der.params):
        symbols[sym], priority[sym] = x["p"][i], 0
    for i, sym in enumerate(der.drive_symbols):
        symbols[sym], priority[sym] = x["d"][i], 1
    for i, sym in enumerate(der.lam):
        symbols[sym], priority[sym] = x["lam"][i], 2
    for i in range(n):
        for key, syms in (("q", der.q), ("qd", der.qd), ("qdd", der.qdd)):
            symbols[syms[i]], priority[syms[i]] = x[key][i], 2
    tr = SympyToCasadi(symbols, priority)
    if getattr(der, "casadi_functions", None):  # positions on exact beams that sympy differentiated
        tr.resolve = placeholder_values(der.casadi_functions, tr, x)
    psyms = [sym for _, sym, _ in der.params]
    q, qd, qdd, d, p = x["q"], x["qd"], x["qdd"], x["d"], x["p"]
    # d depends on time only through the guided theta_k: d' = [1, then theta_k', theta_k'', 0
    # per guided joint] (what is differentiated along the motion does not read theta_k'')
    ddot = [ca.SX(1.0)]
    for k in range(len(der.guided)):
        ddot += [d[2 + 3 * k], d[3 + 3 * k], ca.SX(0.0)]
    ddot = ca.vertcat(*ddot)
    x["ddot"] = ddot  # what the exact beams' section loads differentiate along (exact_body)
    M = matrix_sx(tr, der.M, psyms)
    f = matrix_sx(tr, der.f, psyms)
    T_, V_, h_ = der.energies()
    # ef bodies' elastic energy is not in these kernels: system.c adds it per element with the
    # element kernel ef_elastic (its force -dV/dq and stiffness d2V/dq2), see ef_elements()
    en = matrix_sx(tr, sp.Matrix([T_, V_, h_]), psyms)
    frame_T = getattr(der, "frame_T", ())  # a spatial system's bodies (physics/spatial.py)
    casadi_T = getattr(der, "casadi_T", ())  # a spatial system's ef beams (rod3d, casadi)
    exact_bodies = getattr(der, "exact_bodies", ())  # planar beams with exact kinematics
    r_exact = None
    if der.ef_kinetic or frame_T or casadi_T or exact_bodies:
        # Lagrange on the kinetic energy of the ef bodies, of a spatial system's bodies and of
        # the exact beams by AD (lagrange.equations_of_motion_sx): written in their frame's
        # motion, substituted here; the exact beams' gravity V_g too (exact_body.py)
        T_ef = (ef_kinetic_energy(der, tr, x) if der.ef_kinetic else ca.SX(0.0)) \
            + frame_kinetic_energy(tr, frame_T, der.qd, psyms) + sum((c(tr, x) for c in casadi_T), ca.SX(0.0))
        guided = [(d[1 + 3 * k], d[2 + 3 * k], d[3 + 3 * k]) for k in range(len(der.guided))]
        M_ef, f_ef = equations_of_motion_sx(T_ef, 0, q, qd, guided)
        V_x = ca.SX(0.0)
        if exact_bodies:  # M as sum m J^T J; f and the Newton Jacobians from d'Alembert's r
            T_x, V_x = exact_energies(exact_bodies, tr, x)
            M_x = exact_mass(exact_bodies, tr, x)  # f: from r_exact below
            r_exact = ca.mtimes(M + M_ef, qdd) - (f + f_ef) + exact_residual(exact_bodies, tr, x, ddot)
            if der.T_casadi != 0:  # a hanging body's T, reading positions on an exact beam
                T_h = tr(der.T_casadi)
                T_x, M_x = T_x + T_h, M_x + equations_of_motion_sx(T_h, 0, q, qd, guided)[0]
                # its part of r, d/dt dT_h/dq' - dT_h/dq, by one forward sweep along the motion
                r_exact += ca.jtimes(ca.gradient(T_h, qd), ca.vertcat(q, qd, d), ca.vertcat(qd, qdd, ddot)) \
                    - ca.gradient(T_h, q)
            T_ef, M_ef = T_ef + T_x, M_ef + M_x
            tr.symbols[EXACT_VG], tr.priority[EXACT_VG] = V_x, 2
        M += M_ef
        f += f_ef
        T0_ef = ca.substitute(T_ef, qd, ca.SX.zeros(qd.shape))
        h_ef = ca.mtimes(qd.T, ca.mtimes(M_ef, qd)) / 2 - T0_ef
        en += ca.vertcat(T_ef, V_x, h_ef + V_x) if exact_bodies else ca.vertcat(T_ef, 0, h_ef)
        tr.symbols[EF_T] = T_ef
        for k, g in enumerate(der.guided):  # d/dt dT_ef/dtheta' - dT_ef/dtheta (torque outputs)
            p_th = ca.jacobian(T_ef, d[2 + 3 * k])
            tr.symbols[ef_guided_force(g.joint)] = (
                ca.mtimes(ca.jacobian(p_th, q), qd) + ca.mtimes(ca.jacobian(p_th, qd), qdd)
                + ca.mtimes(ca.jacobian(p_th, d), ddot) - ca.jacobian(T_ef, d[1 + 3 * k]))
            if exact_bodies:  # and the exact beams' gravity, dV_g/dtheta
                tr.symbols[ef_guided_force(g.joint)] += ca.jacobian(V_x, d[1 + 3 * k])
    else:
        tr.symbols[EF_T] = ca.SX(0.0)  # the T output's placeholder (spatial: nothing by AD)
    if der.ef_damping and any(e.has(EF_D) for e in der.outputs.values()):
        tr.symbols[EF_D] = ef_dissipation(der, tr, x)  # the output `dissipation` (2 D)
    for sym, value in getattr(der, "casadi_outputs", {}).items():  # spatial ef: placeholders
        tr.symbols[sym], tr.priority[sym] = value(tr, x), 2
    # outputs and ef elastic energies hold square roots and atan2: translated as they are
    y = ca.vertcat(*[tr(e) for e in der.outputs.values()])
    dsyms = {t_sym: x["t"]} | {p.symbol: x["mp"][i] for i, p in enumerate(der.drive_params)}
    dtr = SympyToCasadi(dsyms, {})
    drive = [x["t"]]
    for g in der.guided:
        drive += [dtr(g.theta), dtr(sp.diff(g.theta, t_sym)), dtr(sp.diff(g.theta, t_sym, 2))]
    r = ca.mtimes(M, x["qdd"]) - f if r_exact is None else r_exact
    if r_exact is not None:  # f from d'Alembert's r as well: half the operations of Lagrange's
        f = -ca.substitute(r_exact, qdd, ca.SX.zeros(n))  # (the exact variant's 7.3 k -> 3.5 k)
    constraint_kernels = []
    if der.constraints:
        # Phi depends on time only through the guided theta_k: Phi_t = dPhi/dd * d'
        phi = matrix_sx(tr, sp.Matrix([e for _, e in der.constraints]), psyms)
        phi_q = ca.jacobian(phi, q)
        phi_t = ca.mtimes(ca.jacobian(phi, d), ddot)
        if der.system.dimension == 3:  # forward AD twice along the motion (q, d): S7's gamma
            z, zd = ca.vertcat(q, d), ca.vertcat(qd, ddot)  # 5827 -> 4720 operations
            gamma = -ca.jtimes(ca.jtimes(phi, z, zd), z, zd)
        else:  # planar systems: the Jacobians' form, their golden kernels kept bit for bit
            phi_dot = ca.mtimes(phi_q, qd) + phi_t
            gamma = -(ca.mtimes(ca.jacobian(phi_dot, q), qd) + ca.mtimes(ca.jacobian(phi_dot, d), ddot))
        constraint_kernels = [
            ("constraints", "Phi of the cut joints", [("q", q), ("d", d), ("p", p)], [("phi", phi)]),
            ("constraint_jac", "Phi_q", [("q", q), ("d", d), ("p", p)], [("phi_q", phi_q)]),
            ("constraint_rate", "Phi_t (Phi_q q' + Phi_t = 0)", [("q", q), ("d", d), ("p", p)],
             [("phi_t", phi_t)]),
            ("constraint_acc", "gamma (Phi_q q'' = gamma), casadi AD",
             [("q", q), ("qd", qd), ("d", d), ("p", p)], [("gamma", gamma)]),
            ("constraint_hess", "d(Phi_q^T e)/dq at fixed e (Newton tangent)",
             [("q", q), ("e", x["lam"]), ("d", d), ("p", p)],
             [("h", ca.jacobian(ca.mtimes(phi_q.T, x["lam"]), q))]),
        ]
    # exact beams: r in one pass (d'Alembert), which the implicit integrators iterate on instead
    # of forming M (system.h); not with ef or rod elements, which system.c adds to f per element
    one_pass = [("residual", "r = M q'' - f in one pass (the exact beams' part by d'Alembert)",
                 [("q", q), ("qd", qd), ("qdd", qdd), ("d", d), ("p", p)], [("r", r)])] \
        if r_exact is not None and not ef_elements(der) and not rod_elements(der) else []
    return make_kernels(constraint_kernels + one_pass + _ef_element_kernel(der) + _rod_element_kernel(der)
                        + _rod_kinetic_kernels(der, tr, x, ddot) + _rod_free_kernels(der, tr, x, ddot)
                        + _ef_damping_kernel(der) + _rod_damping_kernel(der) + [
        ("mass", "mass matrix M(q, d)", [("q", q), ("d", d), ("p", p)], [("M", M)]),
        ("force", "right-hand side f of M q'' = f", [("q", q), ("qd", qd), ("d", d), ("p", p)],
         [("f", f)]),
        ("residual_jac", "Jacobians of r = M q'' - f",
         [("q", q), ("qd", qd), ("qdd", qdd), ("d", d), ("p", p)],
         [("dr_dq", ca.jacobian(r, q)), ("dr_dqd", ca.jacobian(r, qd))]),
        ("outputs", "outputs " + ", ".join(der.outputs),
         [("q", q), ("qd", qd), ("qdd", qdd), ("lambda", x["lam"]), ("d", d), ("p", p)],
         [("y", y)]),
        ("energy", "[T, V, h]: kinetic, potential energy and Jacobi integral",
         [("q", q), ("qd", qd), ("d", d), ("p", p)], [("e", en)]),
        ("drive", "d = [t, theta_k, theta_k', theta_k''] of the guided joints",
         [("t", x["t"]), ("mp", x["mp"])], [("d", ca.vertcat(*drive))]),
    ])


def placeholder_values(functions: dict, tr: SympyToCasadi, x: dict):
    """tr.resolve for the applied-function placeholders (name -> value(tr, x), the derivation's
    casadi_functions: positions on an exact beam, exact_body.position_symbols): r(q_b) is its
    casadi value, Derivative(r(q_b), q_i, q_j, ...) casadi's derivatives of that value with
    respect to the same coordinates, one after the other (each order built on the one below,
    computed once)."""
    cache = {}

    def value(name: str, wrt: tuple):
        if (name, wrt) not in cache:
            cache[name, wrt] = (functions[name](tr, x) if not wrt
                                else ca.jacobian(value(name, wrt[:-1]), tr(wrt[-1])))
        return cache[name, wrt]

    def resolve(e):
        base, wrt = (e.expr, e.variables) if isinstance(e, sp.Derivative) else (e, ())
        if not isinstance(base, AppliedUndef) or base.func.__name__ not in functions:
            return None
        return value(base.func.__name__, tuple(sorted(wrt, key=sp.default_sort_key)))
    return resolve


def _ef_element_kernel(der: SystemDerivation) -> list:
    """One ANCF element's elastic energy V(e; le, E, A, I), its gradient and Hessian (casadi AD
    of efbody's Gauss-point energy, as fe.py's one-beam elements): generated once, called per
    element by system.c."""
    if not der.elastic:
        return []
    e, pe = ca.SX.sym("e", 8), ca.SX.sym("pe", 4)
    symbols = {s: e[i] for i, s in enumerate(_E)} | {le: pe[0], E: pe[1], A: pe[2], I: pe[3]}
    priority = {s: 2 for s in _E} | {le: 0, E: 0, A: 0, I: 0}
    V = SympyToCasadi(symbols, priority)(generic_element()[3])
    H, g = ca.hessian(V, e)
    return [("ef_elastic", "one ANCF element: elastic energy, its gradient and Hessian",
             [("e", e), ("pe", pe)], [("V", V), ("g", g), ("H", H)]),
            ("ef_elastic_grad", "one ANCF element: elastic energy and its gradient (no Hessian)",
             [("e", e), ("pe", pe)], [("V", V), ("g", g)])]


def _rod_element_kernel(der: SystemDerivation) -> list:
    """One rod3d element's elastic energy V(e; pe), its gradient and Hessian (casadi AD), e the
    12 nodal values (r1, psi1, r2, psi2), pe = [le, E, G, rho, A, Iy, Iz, J]: generated once,
    called per element by system.c (rod_elastic_add), as the planar ef's ef_elastic."""
    if not getattr(der, "rod_bodies", None):
        return []
    from flexsym.physics.rod3d import elastic_energy
    e, pe = ca.SX.sym("e", 12), ca.SX.sym("pe", 8)
    V = elastic_energy(e, pe[0], pe[1:8])
    H, g = ca.hessian(V, e)
    return [("rod_elastic", "one rod3d element: elastic energy, its gradient and Hessian",
             [("e", e), ("pe", pe)], [("V", V), ("g", g), ("H", H)]),
            ("rod_elastic_grad", "one rod3d element: elastic energy and its gradient (no Hessian)",
             [("e", e), ("pe", pe)], [("V", V), ("g", g)])]


def _rod_damping_kernel(der: SystemDerivation) -> list:
    """One rod3d element's damping force g = dD/de' and its Jacobians (casadi AD), D = c[0]
    rod3d.strain_rate_energy (beta, Kelvin-Voigt) + c[1] rod3d.relative_kinetic_energy with the
    bending inertia factor c[2] (alpha, mass-proportional: its term only when some beam has
    alpha); generated once when a spatial ef beam is damped, called per element by system.c
    (rod_damping_add: f gets -g)."""
    bodies = [b for b in getattr(der, "rod_bodies", ()) if b["damped"]]
    if not bodies:
        return []
    from flexsym.physics.rod3d import relative_kinetic_energy, strain_rate_energy
    e, ed, pe, c = ca.SX.sym("e", 12), ca.SX.sym("ed", 12), ca.SX.sym("pe", 8), ca.SX.sym("c", 3)
    D = c[0] * strain_rate_energy(e, ed, pe[0], pe[1:8])
    if any(b["alpha"] for b in bodies):
        D += c[1] * relative_kinetic_energy(e, ed, pe[0], pe[1:8], c[2])
    g = ca.gradient(D, ed)
    return [("rod_damping", "one rod3d element: damping force g = dD/de' and its Jacobians",
             [("e", e), ("ed", ed), ("pe", pe), ("c", c)],
             [("g", g), ("g_e", ca.jacobian(g, e)), ("g_ed", ca.jacobian(g, ed))]),
            ("rod_damping_force", "one rod3d element: damping force g = dD/de' (no Jacobians)",
             [("e", e), ("ed", ed), ("pe", pe), ("c", c)], [("g", g)])]


def _rod_kinetic_kernels(der: SystemDerivation, tr, x: dict, ddot) -> list:
    """Spatial ef beams whose frame moves with the drive alone: their elements' kinetic energy
    T_e(e, e'; omega, V) and its Lagrange terms r_e = d/dt dT_e/de' - dT_e/de = M_e e'' - f_e,
    one element's kernels (casadi AD) called per element by system.c (rod_kinetic_add), with
    the frame's motion fm = (omega, V, omega', V') of each such body from rod_frame(d, p)."""
    bodies = [b for b in getattr(der, "rod_bodies", ()) if b["kinetic_in_c"]]
    if not bodies:
        return []
    from flexsym.physics.rod3d import kinetic_energy
    e, ed, edd = ca.SX.sym("e", 12), ca.SX.sym("ed", 12), ca.SX.sym("edd", 12)
    fm, pe = ca.SX.sym("fm", 12), ca.SX.sym("pe", 8)
    om, V, omd, Vd = fm[0:3], fm[3:6], fm[6:9], fm[9:12]
    T = kinetic_energy(e, ed, om, V, pe[0], pe[1:8])
    M, p_ = ca.hessian(T, ed)
    dpdt = ca.mtimes(ca.jacobian(p_, e), ed) + ca.mtimes(ca.jacobian(p_, om), omd) \
        + ca.mtimes(ca.jacobian(p_, V), Vd)
    f = ca.gradient(T, e) - dpdt
    r = ca.mtimes(M, edd) - f
    h = ca.mtimes(ed.T, ca.mtimes(M, ed)) / 2 - ca.substitute(T, ed, ca.SX.zeros(12))
    frames = []
    for b in bodies:
        w = ca.vertcat(*[tr(c) for c in b["frame"].omega])
        v = ca.vertcat(*[tr(c) for c in b["frame"].V])
        frames += [w, v, ca.mtimes(ca.jacobian(w, x["d"]), ddot), ca.mtimes(ca.jacobian(v, x["d"]), ddot)]
    return [("rod_frame", "the frame motion (omega, V, omega', V') of each spatial ef beam moved by the drive alone",
             [("d", x["d"]), ("p", x["p"])], [("fm", ca.vertcat(*frames))]),
            ("rod_kinetic_mass", "one rod3d element: its mass matrix d2T/de'2",
             [("e", e), ("pe", pe)], [("M", M)]),
            ("rod_kinetic_force", "one rod3d element in its frame's motion: T, T2 - T0 and f of M e'' = f",
             [("e", e), ("ed", ed), ("fm", fm), ("pe", pe)], [("T", T), ("h", h), ("f", f)]),
            ("rod_kinetic_jac", "one rod3d element: dr/de, dr/de' of r = M e'' - f",
             [("e", e), ("ed", ed), ("edd", edd), ("fm", fm), ("pe", pe)],
             [("dr_de", ca.jacobian(r, e)), ("dr_ded", ca.jacobian(r, ed))])]


def _free_frame(der: SystemDerivation, tr, x: dict, body: dict):
    """(w, fidx) of a spatial ef beam on a free frame: w = (omega, V) in frame components
    (casadi, of q, q', d, p) and the indices of the coordinates it depends on."""
    w = ca.vertcat(*[tr(c) for c in body["frame"].omega], *[tr(c) for c in body["frame"].V])
    dep = ca.jacobian(w, ca.vertcat(x["q"], x["qd"])).sparsity()
    n = len(der.q)
    cols = {c % n for c in dep.get_col()}
    return w, sorted(cols)


def _rod_free_kernels(der: SystemDerivation, tr, x: dict, ddot) -> list:
    """Spatial ef beams on a free frame (moved by the coordinates): Lagrange's equations in the
    quasi-velocities w = (omega, V), the frame's angular velocity and origin velocity in its own
    components, w = J(q, d) q' + w_d(q, d), w' = J q'' + c. An element's T_e(e, e', w) depends on
    the frame's pose only through w, so with z = (w, e'), p = dT_e/dz:
        element rows      R_e = d/dt dT_e/de' - dT_e/de
        frame coordinate  Q_j = J_j . d/dt p_w + B_j . p_w,  B = dJ/dt - dw/dq
    (B: the frame's transpositional term, by AD of its kinematics; for w the body twist it is
    the Hamel/Euler form's omega x, V x). One element's kernels (casadi AD, generated once):
    rod_free_mass H = d2T_e/dz2 (18 x 18, e alone), rod_free_force R = d/dt p (w, e rows) at
    e'' = 0 and w' = c, and p_w; rod_free_energy T_e and T2_e - T0_e; rod_free_jac R, p_w and
    their derivatives in e, e', w. Per such beam k, rod_free_frame{k}(q, qd, d, p) -> w, J, c, B
    on its frame's coordinates (fidx), rod_free_frame_jac{k} -> dw/dq, dw'/dq, dw'/dq' and
    rod_free_frame_hess{k} -> d(J^T F + B^T P)/dq, /dq' at fixed F, P. system.c (rod_free_add) sums the elements' blocks
    and adds M += [J^T H_ww J, J^T H_we; H_ew J, H_ee] etc. on the coordinates' indices."""
    bodies = [b for b in getattr(der, "rod_bodies", ()) if b.get("free_c")]
    if not bodies:
        return []
    from flexsym.physics.rod3d import kinetic_energy
    e, ed, edd = ca.SX.sym("e", 12), ca.SX.sym("ed", 12), ca.SX.sym("edd", 12)
    w, wd, wq, pe = ca.SX.sym("w", 6), ca.SX.sym("wd", 6), ca.SX.sym("wq", 6), ca.SX.sym("pe", 9)
    T = kinetic_energy(e, ed, w[0:3], w[3:6], pe[0], pe[1:8], pe[8])  # pe[8]: bending_inertia
    z, zd = ca.vertcat(w, ed), ca.vertcat(wd, edd)
    H, p_ = ca.hessian(T, z)
    R = ca.mtimes(H, zd) + ca.mtimes(ca.jacobian(p_, e), ed) - ca.vertcat(ca.SX.zeros(6), ca.gradient(T, e))
    pw = p_[0:6]  # = H_wz z: T_e is a quadratic form in z (dp_w/dw = H_ww, dp_w/de' = H_we)
    R0 = ca.substitute(R, edd, ca.SX.zeros(12))
    zq = ca.vertcat(wq, ed)
    h = ca.mtimes(zq.T, ca.mtimes(H, zq)) / 2 - ca.substitute(T, ca.vertcat(ed, w), ca.vertcat(ca.SX.zeros(12), w - wq))
    out = [("rod_free_mass", "one rod3d element: H = d2T/dz2, z = (omega, V, e')",
            [("e", e), ("pe", pe)], [("H", H)]),
           ("rod_free_force", "one rod3d element on a free frame: R = d/dt dT/dz - (0, dT/de) at e'' = 0, w' = wd; p_w = dT/dw",
            [("e", e), ("ed", ed), ("w", w), ("wd", wd), ("pe", pe)], [("R", R0), ("pw", pw)]),
           ("rod_free_energy", "one rod3d element on a free frame: T and T2 - T0 (wq = J q', the rate part of w)",
            [("e", e), ("ed", ed), ("w", w), ("wq", wq), ("pe", pe)], [("T", T), ("h", h)]),
           ("rod_free_jac", "one rod3d element on a free frame: R, p_w, H and their derivatives in e, e', w",
            [("e", e), ("ed", ed), ("edd", edd), ("w", w), ("wd", wd), ("pe", pe)],
            [("R", R), ("pw", pw), ("H", H), ("R_e", ca.jacobian(R, e)), ("R_ed", ca.jacobian(R, ed)),
             ("R_w", ca.jacobian(R, w)), ("pw_e", ca.jacobian(pw, e))])]
    q, qd, qdd, d, p = x["q"], x["qd"], x["qdd"], x["d"], x["p"]
    F, P = ca.SX.sym("F", 6), ca.SX.sym("P", 6)
    for k, b in enumerate(bodies):
        wv, fidx = _free_frame(der, tr, x, b)
        qf, qdf = ca.vertcat(*[q[i] for i in fidx]), ca.vertcat(*[qd[i] for i in fidx])
        J = ca.jacobian(wv, qdf)
        c = ca.mtimes(ca.jacobian(wv, q), qd) + ca.mtimes(ca.jacobian(wv, d), ddot)
        # dJ/dt column by column (J reads q and d only: w is linear in q')
        cols = [ca.mtimes(ca.jacobian(J[:, j], q), qd) + ca.mtimes(ca.jacobian(J[:, j], d), ddot)
                for j in range(len(fidx))]
        B = ca.horzcat(*cols) - ca.jacobian(wv, qf)
        wdot = ca.mtimes(J, ca.vertcat(*[qdd[i] for i in fidx])) + c
        G = ca.mtimes(J.T, F) + ca.mtimes(B.T, P)
        out += [(f"rod_free_frame{k}", f"the free frame of {b['name']}: w = (omega, V), J = dw/dq', c (w' = J q'' + c), B = dJ/dt - dw/dq",
                 [("q", q), ("qd", qd), ("d", d), ("p", p)], [("w", wv), ("J", J), ("c", c), ("B", B)]),
                (f"rod_free_frame_jac{k}", f"the free frame of {b['name']}: dw/dq, dw'/dq, dw'/dq' (w' = J q'' + c)",
                 [("q", q), ("qd", qd), ("qdd", qdd), ("d", d), ("p", p)],
                 [("w_q", ca.jacobian(wv, qf)), ("a_q", ca.jacobian(wdot, qf)), ("a_qd", ca.jacobian(wdot, qdf))]),
                (f"rod_free_frame_hess{k}", f"the free frame of {b['name']}: d(J^T F + B^T P)/dq, /dq' at fixed F, P",
                 [("q", q), ("qd", qd), ("d", d), ("p", p), ("F", F), ("P", P)],
                 [("G_q", ca.jacobian(G, qf)), ("G_qd", ca.jacobian(G, qdf))])]
        b["fidx"] = fidx
    return out


def rod_elements(der: SystemDerivation) -> list[dict]:
    """Per spatial ef beam, what system.c needs to assemble its rod3d elements: the parameter
    indices of [L, E, G, rho, A, Iy, I, J], the element count, and per element and entry
    (r1, psi1, r2, psi2) the coordinate index (-1: the clamped root) and the fraction a of L
    added to it (node k's x = k L / n)."""
    out = []
    for body in getattr(der, "rod_bodies", ()):
        n, idx = body["n"], body["idx"]
        node = [[(i, float(k) / n if c == 0 else 0.0) for c, i in enumerate(idx[k])] for k in range(n + 1)]
        out.append({"name": body["name"], "n": n, "kinetic_in_c": body["kinetic_in_c"],
                    "free_c": bool(body.get("free_c")), "fidx": body.get("fidx", []),
                    "rotary": body["pidx"].get("bending_inertia"), "beta": body["beta"],
                    "alpha": body["alpha"], "damped": body["damped"],
                    "params": [body["pidx"][k] for k in ("L", "E", "G", "rho", "A", "Iy", "I", "J")],
                    "elements": [[(i, c_double(a)) for i, a in node[k] + node[k + 1]] for k in range(n)]})
    return out


def _band(der: SystemDerivation, kernels: list) -> tuple[int, int, int]:
    """(half-bandwidth, band_first, band_end) of M and the Jacobians (system.h): the nodes of a
    system's ef beams (planar ANCF or spatial rod elements), contiguous coordinates
    [band_first, band_end), form a band (a node couples to its neighbours only: the largest
    spread of an element's coordinates, 7 planar, 11 spatial); the others (a joint's, a beam's
    floating frame's) are a dense border for the runtime's bordered band solve. band_first =
    band_end = 0 when every coordinate is a node (no border). (-1, 0, 0): dense, when there is
    no ef beam, the node block is not wider than twice its band, or a generated kernel couples
    two nodes farther apart than the band (M, the Jacobians, d(Phi_q^T lambda)/dq, a
    constraint row through Phi_q^T Phi_q: its structural nonzeros, e.g. a loop closed between
    two beams' nodes; the elements' parts, which system.c adds, are within it by
    construction)."""
    elements = [el for body in rod_elements(der) + ef_elements(der) for el in body["elements"]]
    nodes = [i for i, c in enumerate(der.coords) if c.group == "node"]
    if not elements or nodes != list(range(nodes[0], nodes[-1] + 1)):
        return -1, 0, 0
    lo, hi = nodes[0], nodes[-1] + 1
    bw = max(max(e[0] for e in el if e[0] >= 0) - min(e[0] for e in el if e[0] >= 0)
             for el in elements)
    if hi - lo <= 2 * bw + 1:
        return -1, 0, 0
    fn = {k.name: k.function for k in kernels}

    def spread(name: str, out: int, rows: bool = False) -> int:
        """The largest |i - j| of a structural nonzero (i, j) in the node block (rows: the
        largest spread of one row's node columns)."""
        f = fn[name]
        r, c = ca.sparsify(f.call(f.sx_in())[out]).sparsity().get_triplet()
        pairs = [(i, j) for i, j in zip(r, c) if lo <= j < hi and (rows or lo <= i < hi)]
        if rows:
            cols = {}
            for i, j in pairs:
                cols.setdefault(i, []).append(j)
            return max((max(v) - min(v) for v in cols.values()), default=0)
        return max((abs(i - j) for i, j in pairs), default=0)
    checks = [("mass", 0, False), ("residual_jac", 0, False), ("residual_jac", 1, False)]
    if der.constraints:
        checks += [("constraint_hess", 0, False), ("constraint_jac", 0, True)]
    if any(spread(*c) > bw for c in checks):
        return -1, 0, 0
    return (bw, 0, 0) if (lo, hi) == (0, len(der.coords)) else (bw, lo, hi)


def _ef_damping_element():
    """(e, ed, pe, c, D^e) of efbody's generic element dissipation in casadi: pe = [l_e, rho A,
    E A, E I], c = [alpha, beta]."""
    e, ed, pe, c = ca.SX.sym("e", 8), ca.SX.sym("ed", 8), ca.SX.sym("pe", 4), ca.SX.sym("c", 2)
    symbols = ({s: e[i] for i, s in enumerate(_E)} | {s: ed[i] for i, s in enumerate(_ED)}
               | {le: pe[0], RA: pe[1], EA: pe[2], EI: pe[3]})
    priority = {s: 2 for s in list(_E) + list(_ED)} | {le: 0, RA: 0, EA: 0, EI: 0}
    etr = SympyToCasadi(symbols, priority)
    D_beta, D_alpha = generic_dissipation()
    return e, ed, pe, c, c[0] * etr(D_alpha) + c[1] * etr(D_beta)


def _ef_damping_kernel(der: SystemDerivation) -> list:
    """One ANCF element's damping force g = dD/de' and its Jacobians (casadi AD), generated
    once when an ef body is damped, called per element by system.c (force gets -g)."""
    if not der.ef_damping:
        return []
    e, ed, pe, c, D = _ef_damping_element()
    g = ca.gradient(D, ed)
    return [("ef_damping", "one ANCF element: damping force g = dD/de' and its Jacobians",
             [("e", e), ("ed", ed), ("pe", pe), ("c", c)],
             [("g", g), ("g_e", ca.jacobian(g, e)), ("g_ed", ca.jacobian(g, ed))]),
            ("ef_damping_force", "one ANCF element: damping force g = dD/de' (no Jacobians)",
             [("e", e), ("ed", ed), ("pe", pe), ("c", c)], [("g", g)])]


def frame_kinetic_energy(tr: SympyToCasadi, frame_T, rates, params) -> ca.SX:
    """Sum of the bodies' T written in placeholders of their frame's motion (omega, V), each
    placeholder given its actual value (a sympy expression of q, q', d) in casadi: the sympy
    side never expands a product of the frame's motion and the body's fields. T is quadratic in
    the placeholders and the rates: summed by their monomials, each coefficient (a polynomial of
    the coordinates) evaluated once, it takes 40 % fewer operations than term by term (S6:
    2271 -> 1357), and M and f, its derivatives by AD, 13-16 % fewer."""
    total = ca.SX(0.0)
    for T_b, actual in frame_T:
        for ph, value in actual.items():
            tr.symbols[ph], tr.priority[ph] = tr(value), 2
        gens = list(actual) + [s for s in rates if T_b.has(s)]
        for powers, c in sp.Poly(T_b, *gens).terms():
            c = tr(group_by_parameters(c, params))
            total += c if not any(powers) else tr(sp.Mul(*[g**k for g, k in zip(gens, powers)])) * c
    return total


def ef_kinetic_energy(der: SystemDerivation, tr: SympyToCasadi, x: dict) -> ca.SX:
    """The ef bodies' kinetic energy: efbody's generic element T^e(e, e'; omega, V; le, rho, A),
    one casadi function instantiated per element with its nodal values and rates (the entries
    of ef_elements) and the frame's actual omega and V."""
    e, ed, fr, pe = ca.SX.sym("e", 8), ca.SX.sym("ed", 8), ca.SX.sym("fr", 3), ca.SX.sym("pe", 3)
    symbols = ({s: e[i] for i, s in enumerate(_E)} | {s: ed[i] for i, s in enumerate(_ED)}
               | {OM: fr[0], VX: fr[1], VY: fr[2], le: pe[0], rho: pe[1], A: pe[2]})
    priority = {s: 2 for s in list(_E) + list(_ED)} | {OM: 1, VX: 1, VY: 1, le: 0, rho: 0, A: 0}
    T_e = SympyToCasadi(symbols, priority)(
        group_by_parameters(generic_element()[0], [le, rho, A]))
    element = ca.Function("ef_kinetic", [e, ed, fr, pe], [T_e])
    frames = {k.body: k for k in der.ef_kinetic}
    pindex = {sym: i for i, (_, sym, _) in enumerate(der.params)}
    q, qd, p = x["q"], x["qd"], x["p"]
    T = ca.SX(0.0)
    for body in ef_elements(der):
        k = frames[body["name"]]
        L_, A_ = p[body["params"][0]], p[body["params"][2]]
        rho_ = p[pindex[der.flex[body["name"]].psyms[rho]]]
        motion = ca.vertcat(tr(k.omega), tr(k.V[0]), tr(k.V[1]))
        part = der.flex[body["name"]]
        f = part.fractions
        for e, el in enumerate(body["elements"]):
            # a body from finite-element data: the element's length and rho A relative to the root's
            section = (ca.vertcat(L_ / body["n"], rho_, A_) if part.body is None else
                       ca.vertcat(L_ * float(f[e + 1] - f[e]), rho_ * float(part.ratios[e][0]), A_))
            ev = ca.vertcat(*[(q[i] if i >= 0 else 0) + float(a) * L_ + float(b) for i, a, b in el])
            edv = ca.vertcat(*[qd[i] if i >= 0 else ca.SX(0.0) for i, _, _ in el])
            T += element(ev, edv, motion, section)
    return T


def ef_dissipation(der: SystemDerivation, tr: SympyToCasadi, x: dict) -> ca.SX:
    """The damped ef bodies' element dissipation: efbody's generic D^e = beta D_beta + alpha
    D_alpha (e, e'; l_e, rho A, E A, E I), one casadi function instantiated per element with its
    nodal values, rates and section (ef_elements' entries), as ef_kinetic_energy."""
    e, ed, pe, c, D_e = _ef_damping_element()
    element = ca.Function("ef_dissipation", [e, ed, pe, c], [D_e])
    pindex = {sym: i for i, (_, sym, _) in enumerate(der.params)}
    q, qd, p = x["q"], x["qd"], x["p"]
    D = ca.SX(0.0)
    for body in ef_elements(der):
        if body["name"] not in der.ef_damping:
            continue
        alpha, beta = der.ef_damping[body["name"]]
        part = der.flex[body["name"]]
        L_, E_, A_, I_ = (p[i] for i in body["params"])
        rho_ = p[pindex[part.psyms[rho]]]
        f = part.fractions
        for k, el in enumerate(body["elements"]):
            mu, ea, ei = (float(r) for r in part.ratios[k])
            section = ca.vertcat(L_ * float(f[k + 1] - f[k]), rho_ * A_ * mu, E_ * A_ * ea, E_ * I_ * ei)
            ev = ca.vertcat(*[(q[i] if i >= 0 else 0) + float(a) * L_ + float(b) for i, a, b in el])
            edv = ca.vertcat(*[qd[i] if i >= 0 else ca.SX(0.0) for i, _, _ in el])
            D += element(ev, edv, section, ca.vertcat(float(alpha), float(beta)))
    return D


def ef_elements(der: SystemDerivation) -> list[dict]:
    """Per ef body, what system.c needs to assemble its elements: the parameter indices of
    [L, E, A, I], the element count, and per element and entry (x1 y1 x1' y1' x2 ...) the
    coordinate index (-1: none) and the value a*L + b added to it (fixed root, node x = kL/n,
    or the body's node); a body from finite-element data also gets, per element, its length
    as a fraction of L and its E A and E I relative to the root section ("sections"); a damped
    body its alpha, beta, the index of its rho and, from finite-element data, each element's
    rho A relative to the root's ("damping"; None: undamped)."""
    qindex = {s: i for i, s in enumerate(der.q)}
    pindex = {sym: i for i, (_, sym, _) in enumerate(der.params)}
    out = []
    for part in der.flex.values():
        if not isinstance(part, EfPart):
            continue
        n = part.n
        node = [[(-1, 0.0, 0.0), (-1, 0.0, 0.0), (qindex[part.q["dx0"]], 0.0, 1.0), (-1, 0.0, 0.0)]]
        for k in range(1, n + 1):
            node.append([(qindex[part.q[f"ux{k}"]], float(part.fractions[k]), 0.0), (qindex[part.q[f"uy{k}"]], 0.0, 0.0),
                         (qindex[part.q[f"dx{k}"]], 0.0, 1.0), (qindex[part.q[f"dy{k}"]], 0.0, 0.0)])
        params = [pindex[part.psyms[s]] for s in (L, E, A, I)]
        f = part.fractions
        sections = [] if part.body is None else [
            (c_double(float(f[k + 1] - f[k])), c_double(float(ea)), c_double(float(ei)))
            for k, (_, ea, ei) in enumerate(part.ratios)]
        damping = None
        if part.beam.name in der.ef_damping:
            alpha, beta = der.ef_damping[part.beam.name]
            damping = {"alpha": c_double(float(alpha)), "beta": c_double(float(beta)),
                       "rho": pindex[part.psyms[rho]],
                       "mu": [] if part.body is None else [c_double(float(r[0])) for r in part.ratios]}
        out.append({"name": part.beam.name, "n": n, "params": params, "sections": sections,
                    "damping": damping,
                    "elements": [[(i, c_double(a), c_double(b)) for i, a, b in node[k] + node[k + 1]]
                                 for k in range(n)]})
    return out


def coordinate_label(system: System, c) -> str:
    """A coordinate's name in the model's columns and manifest: its derivation's (a body's
    carry the body's name), or a one-beam variant's own (System.one_beam)."""
    return c.name.removeprefix(f"{c.body}_") if system.one_beam and c.body else c.name


def _unbounded(system: System, c) -> bool:
    """A coordinate the runtime's blow-up limit (blowup x the length scale, in m) does not
    bound: a joint's angle (a revolute, cylindrical or universal joint's turn: it may turn
    without end), an ANCF node's slope (no unit)."""
    if c.group == "joint":
        return any(x.name == c.name and x.motion == "turn" for x in system.joint(c.joint).coordinates)
    return c.group == "node" and c.name.rsplit("_", 1)[-1].startswith("d")


def generate_system_files(system: System, log=None, ef_free_ad: bool = False) -> dict[str, str]:
    """The generated folder's files; log(msg): a line per stage (derivation, kernels), so a
    long derivation (ef bodies: 10-45 s) is not silent. ef_free_ad: derive_spatial's (a check)."""
    return folder_files(system, derive_folder(system, log, ef_free_ad))


def runtime_parameters(system: System) -> list[tuple[str, float]]:
    """(name, value) of the run-time parameters p that the beams' lengths and sections give,
    p's first entries (a derivation may add its own after them: a free spatial ef beam's
    bending_inertia, whose default is the derivation's)."""
    return [(n, v) for n, _, v in (spatial_params if system.dimension == 3 else param_layout)(system)[0]]


# Placeholders of what a derivation leaves open (derive_folder), filled by folder_files
_TOKEN = re.compile(r"@flexsym-(fingerprint|derivation|p[0-9]+)@")


def emitted_kernels(system: System, log=None, ef_free_ad: bool = False) -> tuple:
    """(derivation, casadi kernels, emitted C kernels) of a system; log(msg): a line per stage."""
    log = log or (lambda msg: None)
    start = time.perf_counter()
    der = derive_spatial(system, ef_free_ad) if system.dimension == 3 else derive_system(system)
    log(f"derived ({len(der.q)} coordinates, {len(der.constraints)} constraint rows) in "
        f"{time.perf_counter() - start:.1f} s; building the C kernels (casadi)")
    start = time.perf_counter()
    kernels = build_system_kernels(der)
    emitted = [emit(k, c_prefix(system.name)) for k in kernels]
    log(f"kernels emitted ({sum(k.total_ops for k in emitted)} operations) in {time.perf_counter() - start:.1f} s")
    return der, kernels, emitted


def derive_folder(system: System, log=None, ef_free_ad: bool = False) -> dict:
    """The derivation of a generated folder: its files and manifest with the fingerprints and
    the run-time parameters' values left as placeholders, for folder_files to fill. JSON, so
    that pipeline.prepare_system keeps it for every system of the same derivation_fingerprint."""
    der, kernels, emitted = emitted_kernels(system, log, ef_free_ad)
    versions = _versions(system_to_dict(system))
    mass = next(k.function for k in kernels if k.name == "mass")
    qs, ds, ps = mass.sx_in()
    mass_constant = not ca.depends_on(mass(qs, ds, ps), ca.vertcat(qs, ds)) and not any(
        b["kinetic_in_c"] or b.get("free_c") for b in getattr(der, "rod_bodies", ()))  # rod elements: M_e(e) in C
    scale = length_scale(system)
    initial = [tuple(c_double(v) for v in start_of(system, c)) for c in der.coords]
    sections = len(runtime_parameters(system))  # p's first: the beams' (a derivation may add its own)
    outputs_fn = next(k.function for k in kernels if k.name == "outputs")

    def placeholders_read(name: str) -> bool:
        """The outputs read q'' or the drive through a casadi placeholder (which hides from
        sympy what it reads: an exact beam's section loads read both)."""
        if not getattr(der, "casadi_outputs", None):
            return False
        args = outputs_fn.sx_in()
        return ca.depends_on(outputs_fn(*args), args[outputs_fn.name_in().index(name)])
    ctx = {
        "name": system.name, "NAME": system.name.upper(), "header": f"fsm_{system.name}.h",
        "prefix": c_prefix(system.name), "accessor": model_accessor(system.name),
        "generator": f"flexsym {versions['flexsym']}", "versions": versions,
        "fingerprint": "@flexsym-fingerprint@",
        "summary": f"{len(system.bodies)} bodies, {len(der.q)} coordinates, "
                   f"{len(der.guided)} guided joints, {len(der.constraints)} constraint equations.",
        "constraints": [n for n, _ in der.constraints],
        "kernels": emitted,
        "guided": [g.joint for g in der.guided], "coords": [coordinate_label(system, c) for c in der.coords],
        "outputs": list(der.outputs), "nd": len(der.drive_symbols),
        "params": [{"name": n, "c_default": f"@flexsym-p{i}@" if i < sections else c_double(v)}
                   for i, (n, _, v) in enumerate(der.params)],
        "drive_params": [{"name": p.name, "c_default": c_double(p.default)}
                         for p in der.drive_params],
        "length_scale": c_double(scale), "length_param": length_param(der),
        "unbounded": [int(_unbounded(system, c)) for c in der.coords],
        "held": [_held(system, c) for c in der.coords],
        "mass_constant": mass_constant, "initial": initial,
        "outputs_use_acceleration": der.outputs_use_acceleration or placeholders_read("qdd"),
        "outputs_use_drive": der.outputs_use_drive or placeholders_read("d"),
        "ef_bodies": ef_elements(der), "ef_damped": bool(der.ef_damping),
        "rod_bodies": rod_elements(der),
        "rod_kinetic": any(b["kinetic_in_c"] for b in getattr(der, "rod_bodies", ())),
        "rod_free": any(b.get("free_c") for b in getattr(der, "rod_bodies", ())),
        "rod_damped": any(b["damped"] for b in getattr(der, "rod_bodies", ())),
        "static_start": system.start == "static",
        "kernel_ops": sum(k.total_ops for k in emitted),
        "has_residual": any(k.kernel.name == "residual" for k in emitted), "of_derivation": False,
    }
    ctx["bandwidth"], ctx["band_first"], ctx["band_end"] = _band(der, kernels)
    ctx["large_kernels"] = ctx["kernel_ops"] > LARGE_KERNELS
    rare = [k for k in emitted if k.total_ops > RARE_KERNELS.get(k.kernel.name, math.inf)]
    ctx["rare_kernels"] = [k.kernel.name for k in rare]
    ctx["kernels_cmake"] = ctx["large_kernels"] or bool(rare)  # flags the FMU's build needs too
    if ctx["static_start"]:
        ctx["static_free"], ctx["static_rows"] = _static_unknowns(system, der, kernels)
    env = environment()
    # the kernels, their header and how they compile carry the derivation's fingerprint only:
    # byte for byte the same in every folder of the derivation (build.py compiles them once)
    shared = ctx | {"fingerprint": "@flexsym-derivation@", "of_derivation": True}
    header = f"fsm_{system.name}.h"
    files = {
        header: env.get_template("system/system.h.j2").render(shared),
        "kernels.c": env.get_template("kernels.c.j2").render(
            shared | {"kernels": [k for k in emitted if k not in rare]}),
        "system.c": env.get_template("system/system.c.j2").render(ctx),
        "CMakeLists.txt": env.get_template("system/CMakeLists.txt.j2").render(shared),
    }
    if rare:
        files[RARE_FILE] = env.get_template("kernels.c.j2").render(shared | {"kernels": rare})
    if ctx["kernels_cmake"]:
        files[KERNELS_CMAKE] = env.get_template("system/kernels.cmake.j2").render(shared)
    manifest = {
        "kind": "system", "generator": ctx["generator"], "versions": versions,
        "fingerprint": "@flexsym-fingerprint@", "derivation": "@flexsym-derivation@",
        "model": ctx["accessor"],
        "spec": None,
        "tree": {"order": list(der.tree.order), "tree_joints": dict(der.tree.parent_joint),
                 "cut_joints": list(der.tree.cut)},
        "coordinates": [{"name": coordinate_label(system, c), "group": c.group, "body": c.body}
                        for c in der.coords],
        "drive": ["t"] + [f"{g.joint}{s}" for g in der.guided for s in ("", "'", "''")],
        "drive_params": [{"name": p.name, "default": p.default, "unit": p.unit}
                         for p in der.drive_params],
        "params": [{"name": n, "default": None if i < sections else v} for i, (n, _, v) in enumerate(der.params)],
        "constraints": [{"name": n, "phi": str(e)} for n, e in der.constraints],
        "energy_terms": [{"body": b, "term": term, "differentiated_wrt": list(wrt)}
                         for b, term, wrt, _, _ in der.terms],
        "outputs": dict(zip(der.outputs, (o.quantity for o in system.outputs))),
    } | ({"static_start": {"solved": [der.coords[i].name for i in ctx["static_free"]],
                            "constraint_rows": [der.constraints[k][0] for k in ctx["static_rows"]]}}
         if ctx["static_start"] else {}) | ({"damping": {b: ("ef elements: ef_damping kernel, alpha and beta in system.c"
                          if b in der.ef_damping else "modal: -dD/dq' in force")
                      for b in der.dissipation}} if der.dissipation else {}) | {
        "length_scale": scale, "mass_constant": mass_constant,
        "outputs_use_acceleration": ctx["outputs_use_acceleration"],
        "outputs_use_drive": ctx["outputs_use_drive"],
        "left_out": der.dropped,
        "kernels": {k.kernel.name: {"c_name": k.c_name, "ops": k.ops, "total_ops": k.total_ops,
                                    "inputs": {p.name: p.size for p in k.kernel.inputs},
                                    "outputs": {p.name: [p.rows, p.cols] for p in k.kernel.outputs}}
                    for k in emitted},
        # what the compiled kernels depend on: folders with the same files share them (build.py)
        "kernels_inputs": sorted(set(files) - {"system.c"}),
        "files": None,
    }
    return {"files": files, "manifest": manifest}


def folder_files(system: System, derived: dict) -> dict[str, str]:
    """The generated folder of system from its derivation (derive_folder's, of a system with
    the same derivation_fingerprint): the fingerprints and the run-time parameters' values put
    in."""
    values = runtime_parameters(system)
    manifest = json.loads(json.dumps(derived["manifest"]))
    if [p["name"] for p in manifest["params"][:len(values)]] != [n for n, _ in values]:
        raise ValueError(f"system '{system.name}': derived parameters {manifest['params']} "
                             f"are not the system's {values}")
    fill = {"fingerprint": fingerprint(system), "derivation": derivation_fingerprint(system)}
    fill |= {f"p{i}": c_double(v) for i, (_, v) in enumerate(values)}
    files = {name: _TOKEN.sub(lambda m: fill[m.group(1)], text)
             for name, text in derived["files"].items()}
    manifest["fingerprint"], manifest["derivation"] = fill["fingerprint"], fill["derivation"]
    manifest["spec"] = {"name": system.name} | system_to_dict(system)
    for p, (_, v) in zip(manifest["params"], values):
        p["default"] = v
    manifest["files"] = {n: hashlib.sha256(tx.encode()).hexdigest() for n, tx in sorted(files.items())}
    files[MANIFEST] = json.dumps(manifest, indent=2) + "\n"
    return files


def _held(system: System, c) -> int:
    """system.h's coord_held flags of a coordinate (1 its value, 2 its rate), as the assembly at
    t = 0 (scenes/assembly.py) holds them: a flexible body's elastic coordinates (undeformed,
    at rest; an ef body's nodes move with it), a `fixed` joint's angle, a given rate."""
    if c.group == "node":
        return 0
    if c.group != "joint":
        return 3
    j = system.joint(c.joint)
    jc = next((x for x in j.coordinates if x.name == c.name), None)  # None: Euler parameters
    if jc is None:
        return 0
    return (1 if j.fixed and jc.name == j.name else 0) | (2 if jc.rate is not None else 0)


def _static_unknowns(system: System, der: SystemDerivation, kernels: list) -> tuple[list, list]:
    """start = "static": the coordinates the equilibrium at t = 0 is solved for, and the
    constraint rows it keeps. The elastic coordinates; in a closed loop also the joint
    coordinates that follow the loop's deformation, picked from the last coordinate back (the
    joints nearest the cut; never a `fixed` joint's) until they close the loop with the others
    held (the rank of Phi_q over them reaches its rank over every joint coordinate that may
    move), and the rows of Phi_q independent over those (a redundant row has no multiplier of
    its own). Evaluated at the assembled start with the default parameters; the rest of the
    joints stay held, as in an open chain."""
    solved = [i for i, c in enumerate(der.coords) if c.group != "joint"]
    if not der.tree.cut:
        return solved, []
    fn = {k.name: k.function for k in kernels}
    d0 = fn["drive"](0.0, [p.default for p in der.drive_params])
    jac = np.array(fn["constraint_jac"]([start_of(system, c)[0] for c in der.coords], d0,
                                        [v for _, _, v in der.params]))
    movable = [i for i, c in enumerate(der.coords)
               if c.group == "joint" and not system.joint(c.joint).fixed]
    target, follow = numeric_rank(jac[:, movable]), []
    for i in reversed(movable):
        if numeric_rank(jac[:, follow]) == target:
            break
        if numeric_rank(jac[:, follow + [i]]) > numeric_rank(jac[:, follow]):
            follow.append(i)
    solved = sorted(solved + follow)
    rows = []
    for k in range(len(der.constraints)):
        if numeric_rank(jac[rows + [k]][:, solved]) > len(rows):
            rows.append(k)
    return solved, rows


def describe(system: System) -> str:
    """What `inspect` shows of a system's derivation: tree, coordinates, constraint rows, which
    energy term acts on which coordinates, and the kernels' operation counts."""
    files = generate_system_files(system)
    m = json.loads(files[MANIFEST])
    lines = [f"system '{system.name}': {len(system.bodies)} bodies; tree "
             + ", ".join(f"{b} <- {j}" for b, j in m["tree"]["tree_joints"].items())
             + (f"; cut joints: {', '.join(m['tree']['cut_joints'])}" if m["tree"]["cut_joints"] else ""),
             "coordinates: " + ", ".join(f"{c['name']} ({c['group']})" for c in m["coordinates"]),
             "drive d: " + ", ".join(m["drive"])]
    for c in m["constraints"]:
        lines.append(f"constraint {c['name']}: {c['phi']} = 0")
    for t_ in m["energy_terms"]:
        where = f"body {t_['body']}: " if t_["body"] else ""
        lines.append(f"{where}{t_['term']} acts on {', '.join(t_['differentiated_wrt'])}")
    for body, how in m.get("damping", {}).items():
        lines.append(f"body {body}: structural damping on its elastic coordinates ({how})")
    for name, k in m["kernels"].items():
        lines.append(f"kernel {k['c_name']}: {k['total_ops']} operations")
    return "\n".join(lines) + "\n"
