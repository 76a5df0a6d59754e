"""The ringing that S3's release excites in the strip's bending modes, and what it does to M_mid
(docs/theory/exact-kinematics.md, "In a mechanism", S3):

    python docs/validation/s3_ringing.py

A linear estimate. At t = 0 the strip (scenes/pendulum.toml) is undeformed and horizontal, pinned at
the root, and its rigid angular acceleration is 3g/2L, so in the pin's rotating frame it carries the
transverse load q(x) = rho A g (1 - 1.5 x/L). Applied from rest, q gives each pinned-free mode k the
motion s_k (1 - cos w_k t) (s_k its static modal deflection) and M at x = L/2 the ringing
a_k cos(w_k t), a_k = EI s_k phi_k''(L/2). Printed per mode, as fractions of R64's |M_mid| peak: a_k;
the sum of |a_j| over the modes j > K (what K modes leave out, in phase at some instant); the
signed -sum of a_j over j > K, which a model with K modes and M from equilibrium reads at t = 0
(where the truth is M = 0); and the bound sum_k |a_k| |2 sin(dphi_k/2)| on the M_mid error of generalized-alpha at step h over the
2 s, dphi_k = w_k^3 h^2 t / 12 its period error (exact modes, exact frequencies; beyond
mode 200 the tail a_k ~ C k^-3 is added). Modes from tan(bL) = tanh(bL)."""
import numpy as np
from scipy.optimize import brentq

RHO, E, A, I, L, G = 2700.0, 7e10, 1e-4, 2.0833333333333336e-10, 1.0, 9.81   # scenes/pendulum.toml
PEAK = 0.1844   # |M_mid| peak of R64 [N m]
KMAX = 200
EI, MU = E * I, RHO * A


def modes(kmax: int = KMAX):
    """(w_k, a_k / PEAK) of the pinned-free modes 1..kmax."""
    x, wq = np.polynomial.legendre.leggauss(64)
    edges = np.linspace(0.0, L, 4 * kmax + 1)   # composite Gauss rule, 4 pieces per mode's half-wave
    xs = np.concatenate([(a + b) / 2 + (b - a) / 2 * x for a, b in zip(edges[:-1], edges[1:])])
    ws = np.concatenate([(b - a) / 2 * wq for a, b in zip(edges[:-1], edges[1:])])
    out = []
    for k in range(1, kmax + 1):
        z0 = (k + 0.25) * np.pi
        b = brentq(lambda z: np.sin(z) - np.cos(z) * np.tanh(z), z0 - 0.3, z0 + 0.3) / L
        # sinh(b x) sin(bL) / sinh(bL), written without overflow
        hyp = lambda s: np.sin(b * L) * np.exp(b * (s - L)) * (1 - np.exp(-2 * b * s)) / (1 - np.exp(-2 * b * L))
        phi = np.sin(b * xs) + hyp(xs)
        m_k = MU * np.sum(ws * phi**2)
        f_k = np.sum(ws * MU * G * (1 - 1.5 * xs / L) * phi)
        w = b**2 * np.sqrt(EI / MU)
        d2 = b**2 * (-np.sin(b * L / 2) + hyp(L / 2))
        out.append((w, EI * f_k / (m_k * w**2) * d2 / PEAK))
    return np.array(out)


def main() -> None:
    tab = modes()
    w, a = tab[:, 0], np.abs(tab[:, 1])
    k = np.arange(1, KMAX + 1)
    C = np.exp(np.mean(np.log(a[-50:]) + 3 * np.log(k[-50:])))   # a_k ~ C k^-3 (mean of odd and even)
    beyond = C / (2 * (KMAX + 0.5) ** 2)
    print(f"mode   w [rad/s]   a_k / peak   sum of |a_j|, j > k   (a_k ~ {C:.2f} k^-3 beyond)")
    for K in (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 15, 16, 20, 25, 30, 40, 60):
        print(f"{K:4d} {w[K - 1]:11.0f} {a[K - 1]:11.2e} {a[K:].sum() + beyond:14.2e}")
    print("signed M_mid at t = 0 that K modes leave (their equilibrium moment at the first row):",
          " ".join(f"K={K}: {-tab[K:, 1].sum():+.1e}" for K in (3, 5, 8, 10)))
    print("generalized-alpha's period error over 2 s, bound on M_mid's error at step h (fraction of the peak):")
    for h in (12.5e-6, 6.25e-6, 3.125e-6, 1.5625e-6, 1e-6, 3e-7, 1e-7):
        d = w**3 * h**2 * 2.0 / 12
        e = np.sum(a * np.where(d < np.pi, 2 * np.abs(np.sin(d / 2)), 2.0)) + 2 * beyond
        print(f"  h = {h:.4g} s: {e:.1e}")


if __name__ == "__main__":
    main()
