"""lagrange.py, the one place of Lagrange's equations (variants, ef elements, systems), against
equations of motion derived by hand, and its casadi form against its sympy form."""
import casadi as ca
import numpy as np
import sympy as sp

from flexsym.physics.lagrange import equations_of_motion, equations_of_motion_sx, jacobi_integral

m, a, l1, l2, g = sp.symbols("m a l1 l2 g", positive=True)
y, yd, w, alpha = sp.symbols("y y_d w alpha", real=True)
th, thd, thdd, phi, phid = sp.symbols("th th_d th_dd phi phi_d", real=True)


def _transverse():
    """A mass at (a, y) in a frame turning at the guided rate w (alpha = w'): T reads w only."""
    T = m / 2 * ((w * y)**2 + (yd + w * a)**2)
    return T, sp.Matrix([y]), sp.Matrix([yd])


def test_rotating_frame_rate_and_acceleration_terms():
    """y'' = w^2 y - a alpha (centrifugal and the frame's angular acceleration)."""
    T, q, qd = _transverse()
    M, f = equations_of_motion(T, sp.zeros(1, 1), q, qd, [(None, w, alpha)])
    assert M == sp.Matrix([m])
    assert sp.simplify(f[0] - m * (w**2 * y - a * alpha)) == 0


def test_guided_angle_read_by_T():
    """Second link (angle phi) of a double pendulum whose first link's angle th(t) is guided:
    m l2^2 phi'' = m l1 l2 (th'^2 sin(th - phi) - th'' cos(th - phi)) - m g l2 cos(phi)."""
    T = m / 2 * (l1**2 * thd**2 + l2**2 * phid**2 + 2 * l1 * l2 * thd * phid * sp.cos(th - phi))
    V = m * g * (l1 * sp.sin(th) + l2 * sp.sin(phi))
    q, qd = sp.Matrix([phi]), sp.Matrix([phid])
    M, f = equations_of_motion(T, sp.Matrix([-sp.diff(V, phi)]), q, qd, [(th, thd, thdd)])
    assert sp.simplify(M[0, 0] - m * l2**2) == 0
    expected = m * l1 * l2 * (thd**2 * sp.sin(th - phi) - thdd * sp.cos(th - phi)) \
        - m * g * l2 * sp.cos(phi)
    assert sp.simplify(f[0] - expected) == 0


def test_jacobi_integral_conserved_at_constant_rate():
    """h = T2 - T0 + V is constant along the motion of the rotating frame at constant w."""
    T, q, qd = _transverse()
    k = sp.Symbol("k", positive=True)
    V = k * y**2 / 2
    M, f = equations_of_motion(T, sp.Matrix([-k * y]), q, qd, [(None, w, alpha)])
    h = jacobi_integral(T, M, qd, V)
    ydd = (f[0] / M[0, 0]).subs(alpha, 0)
    assert sp.simplify(sp.diff(h, y) * yd + sp.diff(h, yd) * ydd) == 0


def test_casadi_form_equals_sympy_form():
    """equations_of_motion_sx on the same T (the exact kinematics' check uses it) gives the same
    M and f at random states."""
    T = m / 2 * (l1**2 * thd**2 + l2**2 * phid**2 + 2 * l1 * l2 * thd * phid * sp.cos(th - phi))
    Q = sp.Matrix([-m * g * l2 * sp.cos(phi)])
    M, f = equations_of_motion(T, Q, sp.Matrix([phi]), sp.Matrix([phid]), [(th, thd, thdd)])
    syms = (m, l1, l2, g, th, thd, thdd, phi, phid)
    ref = sp.lambdify(syms, [M[0, 0], f[0]])
    x = {s: ca.SX.sym(str(s)) for s in syms}
    Tsx = x[m] / 2 * (x[l1]**2 * x[thd]**2 + x[l2]**2 * x[phid]**2
                      + 2 * x[l1] * x[l2] * x[thd] * x[phid] * ca.cos(x[th] - x[phi]))
    Msx, fsx = equations_of_motion_sx(Tsx, -x[m] * x[g] * x[l2] * ca.cos(x[phi]), x[phi], x[phid],
                                      [(x[th], x[thd], x[thdd])])
    fn = ca.Function("eom", [x[s] for s in syms], [Msx, fsx])
    rng = np.random.default_rng(7)
    for _ in range(5):
        v = rng.uniform(0.5, 2.0, len(syms))
        got = [float(z) for z in fn(*v)]
        assert np.allclose(got, ref(*v), rtol=1e-13, atol=1e-13)
