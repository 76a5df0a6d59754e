/* Rigid planar mechanisms in relative coordinates, written by hand for the tests of the
 * constrained integrators (no derivation by flexsym): a fixture describes its bodies and cut
 * joints through pl_describe, and planar.c turns that into the kernels of system.h.
 *
 * Every angle is linear in q and the guided angle theta (d = [t, theta, theta', theta'']):
 *     psi = offset + sum_j B_j q_j + drive theta,
 * and every point is a sum of arms of fixed length along such angles plus prismatic terms:
 *     P = base + sum_k len_k e(psi_k) + sum_j lin_j q_j,   e(psi) = (cos psi, sin psi).
 * Then dP/dq, dP/dt and the convective term P'' - (dP/dq) q'' are exact closed forms. */
#ifndef PLANAR_H
#define PLANAR_H

#include "flexsym/system.h"

enum { PL_MAXQ = 8, PL_MAXARM = 4, PL_MAXBODY = 6, PL_MAXCON = 8 };

typedef struct {
    double offset, drive;
    double B[PL_MAXQ];
} pl_angle;

typedef struct {
    double base[2];
    int narms;
    double len[PL_MAXARM];
    pl_angle arm[PL_MAXARM];
    double lin[PL_MAXQ][2];
} pl_point;

typedef struct {
    double m, J;  /* mass, moment of inertia about G */
    pl_point G;
    pl_angle psi;
} pl_body;

typedef struct {  /* Phi = a[comp] - b[comp] */
    pl_point a, b;
    int comp;
} pl_constraint;

typedef struct {
    int nq, nb, nc;
    double g[2];
    pl_body body[PL_MAXBODY];
    pl_constraint con[PL_MAXCON];
} pl_model;

/* defined by each fixture: its mechanism at parameters p (called by every kernel) */
void pl_describe(const double* p, pl_model* m);

/* kernels of system.h for the described mechanism (residual_jac by central differences: it
 * only steers Newton) */
void pl_mass(const double* q, const double* d, const double* p, double* M);
void pl_force(const double* q, const double* qd, const double* d, const double* p, double* f);
void pl_residual_jac(const double* q, const double* qd, const double* qdd, const double* d,
                     const double* p, double* dr_dq, double* dr_dqd);
void pl_constraints(const double* q, const double* d, const double* p, double* phi);
void pl_constraint_jac(const double* q, const double* d, const double* p, double* phi_q);
void pl_constraint_rate(const double* q, const double* d, const double* p, double* phi_t);
void pl_constraint_acc(const double* q, const double* qd, const double* d, const double* p, double* gamma);
/* e = [T, V, T + V] */
void pl_energy(const double* q, const double* qd, const double* d, const double* p, double* e);

/* a point's position, velocity, dP/dq (2 x nq) and convective acceleration */
void pl_point_eval(const pl_point* P, int nq, const double* q, const double* qd, const double* d,
                   double* pos, double* vel, double* J, double* conv);

#endif
