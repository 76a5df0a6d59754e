"""The paper's planar beam element (eq. 7-8): linear axial + Hermite cubic bending, dofs
(u1, v1, th1, u2, v2, th2). One place for its matrices: the stress recovery (outputs.py) uses
them symbolically, the finite-element bodies (fedata.py) numerically.

K_G^e is the geometric stiffness for a unit axial load; its (th1, th2) entry is -le/30: the
paper prints +le/30, a sign misprint (the integral of the cubic energy term for Hermite shapes
gives -le/30; tests/test_integrals.py).
"""
from __future__ import annotations

from functools import lru_cache

import sympy as sp


def element_matrices(le, EA, EI, rhoA=0):
    """(M^e consistent mass, K_L^e (7), K_G^e (8)) as sympy matrices."""
    a, b, r = EA / le, EI, sp.Rational
    KL = sp.Matrix([
        [a, 0, 0, -a, 0, 0],
        [0, 12 * b / le**3, 6 * b / le**2, 0, -12 * b / le**3, 6 * b / le**2],
        [0, 6 * b / le**2, 4 * b / le, 0, -6 * b / le**2, 2 * b / le],
        [-a, 0, 0, a, 0, 0],
        [0, -12 * b / le**3, -6 * b / le**2, 0, 12 * b / le**3, -6 * b / le**2],
        [0, 6 * b / le**2, 2 * b / le, 0, -6 * b / le**2, 4 * b / le]])
    KG = sp.Matrix([
        [0, 0, 0, 0, 0, 0],
        [0, r(6, 5) / le, r(1, 10), 0, -r(6, 5) / le, r(1, 10)],
        [0, r(1, 10), 2 * le / 15, 0, -r(1, 10), -le / 30],
        [0, 0, 0, 0, 0, 0],
        [0, -r(6, 5) / le, -r(1, 10), 0, r(6, 5) / le, -r(1, 10)],
        [0, r(1, 10), -le / 30, 0, -r(1, 10), 2 * le / 15]])
    m = rhoA * le
    M = sp.zeros(6, 6)
    for i, j, v in ((0, 0, 2), (0, 3, 1), (3, 0, 1), (3, 3, 2)):
        M[i, j] = m * r(v, 6)
    hermite = [[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
               [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]]
    for i, gi in enumerate((1, 2, 4, 5)):
        for j, gj in enumerate((1, 2, 4, 5)):
            M[gi, gj] = m * hermite[i][j] / 420
    return M, KL, KG


@lru_cache(maxsize=None)
def numeric_element_matrices():
    """(le, EA, EI, rhoA) -> (M, K_L, K_G) as numpy arrays: the same matrices, compiled once."""
    le, EA, EI, rhoA = sp.symbols("le EA EI rhoA", positive=True)
    return sp.lambdify((le, EA, EI, rhoA), element_matrices(le, EA, EI, rhoA), "numpy")
