#include "planar.h"

#include <math.h>
#include <string.h>

static void angle_eval(const pl_angle* a, int nq, const double* q, const double* qd, const double* d,
                       double* psi, double* psid)
{
    /* d[1], d[2] only with a guided angle: a model without one has nd = 1 */
    double x = a->offset + (a->drive != 0.0 ? a->drive * d[1] : 0.0);
    double xd = a->drive != 0.0 ? a->drive * d[2] : 0.0;
    for (int j = 0; j < nq; ++j) {
        x += a->B[j] * q[j];
        xd += a->B[j] * qd[j];
    }
    *psi = x;
    *psid = xd;
}

void pl_point_eval(const pl_point* P, int nq, const double* q, const double* qd, const double* d,
                   double* pos, double* vel, double* J, double* conv)
{
    pos[0] = P->base[0];
    pos[1] = P->base[1];
    vel[0] = vel[1] = conv[0] = conv[1] = 0.0;
    for (int j = 0; j < nq; ++j) {
        J[j] = P->lin[j][0];
        J[nq + j] = P->lin[j][1];
        pos[0] += P->lin[j][0] * q[j];
        pos[1] += P->lin[j][1] * q[j];
        vel[0] += P->lin[j][0] * qd[j];
        vel[1] += P->lin[j][1] * qd[j];
    }
    for (int k = 0; k < P->narms; ++k) {
        double psi, psid, l = P->len[k];
        angle_eval(&P->arm[k], nq, q, qd, d, &psi, &psid);
        double c = cos(psi), s = sin(psi);
        pos[0] += l * c;
        pos[1] += l * s;
        vel[0] -= l * s * psid;
        vel[1] += l * c * psid;
        /* P'' - J q'' = l [e_perp drive theta'' - e psi'^2] */
        double dd = P->arm[k].drive != 0.0 ? P->arm[k].drive * d[3] : 0.0;
        conv[0] += l * (-s * dd - c * psid * psid);
        conv[1] += l * (c * dd - s * psid * psid);
        for (int j = 0; j < nq; ++j) {
            J[j] -= l * s * P->arm[k].B[j];
            J[nq + j] += l * c * P->arm[k].B[j];
        }
    }
}

static const double ZERO[PL_MAXQ];

void pl_mass(const double* q, const double* d, const double* p, double* M)
{
    pl_model m;
    pl_describe(p, &m);
    const int n = m.nq;
    memset(M, 0, sizeof(double) * (size_t)(n * n));
    for (int b = 0; b < m.nb; ++b) {
        double pos[2], vel[2], J[2 * PL_MAXQ], conv[2];
        pl_point_eval(&m.body[b].G, n, q, ZERO, d, pos, vel, J, conv);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                M[i * n + j] += m.body[b].m * (J[i] * J[j] + J[n + i] * J[n + j])
                                + m.body[b].J * m.body[b].psi.B[i] * m.body[b].psi.B[j];
    }
}

void pl_force(const double* q, const double* qd, const double* d, const double* p, double* f)
{
    pl_model m;
    pl_describe(p, &m);
    const int n = m.nq;
    memset(f, 0, sizeof(double) * (size_t)n);
    for (int b = 0; b < m.nb; ++b) {
        const pl_body* B = &m.body[b];
        double pos[2], vel[2], J[2 * PL_MAXQ], conv[2];
        pl_point_eval(&B->G, n, q, qd, d, pos, vel, J, conv);
        /* -(m J^T conv + J_G B psi_conv) + J^T m g; psi's convective term is drive theta'' */
        for (int i = 0; i < n; ++i)
            f[i] += B->m * (J[i] * (m.g[0] - conv[0]) + J[n + i] * (m.g[1] - conv[1]))
                    - (B->psi.drive != 0.0 ? B->J * B->psi.B[i] * B->psi.drive * d[3] : 0.0);
    }
}

static void residual(const double* q, const double* qd, const double* qdd, const double* d,
                     const double* p, int n, double* r)
{
    double M[PL_MAXQ * PL_MAXQ];
    pl_force(q, qd, d, p, r);
    pl_mass(q, d, p, M);
    for (int i = 0; i < n; ++i) {
        double s = -r[i];
        for (int j = 0; j < n; ++j) s += M[i * n + j] * qdd[j];
        r[i] = s;
    }
}

void pl_residual_jac(const double* q, const double* qd, const double* qdd, const double* d,
                     const double* p, double* dr_dq, double* dr_dqd)
{
    pl_model m;
    pl_describe(p, &m);
    const int n = m.nq;
    double x[PL_MAXQ], rp[PL_MAXQ], rm[PL_MAXQ];
    for (int pass = 0; pass < 2; ++pass) {
        const double* base = pass ? qd : q;
        double* out = pass ? dr_dqd : dr_dq;
        for (int j = 0; j < n; ++j) {
            double h = 1e-6 * (1.0 + fabs(base[j]));
            memcpy(x, base, sizeof(double) * (size_t)n);
            x[j] = base[j] + h;
            residual(pass ? q : x, pass ? x : qd, qdd, d, p, n, rp);
            x[j] = base[j] - h;
            residual(pass ? q : x, pass ? x : qd, qdd, d, p, n, rm);
            for (int i = 0; i < n; ++i) out[i * n + j] = (rp[i] - rm[i]) / (2.0 * h);
        }
    }
}

/* Phi_i, its row of Phi_q, Phi_t and the convective term of constraint i */
static void con_eval(const pl_model* m, int i, const double* q, const double* qd, const double* d,
                     double* phi, double* row, double* phit, double* conv)
{
    const int n = m->nq, c = m->con[i].comp;
    double pa[2], va[2], Ja[2 * PL_MAXQ], ca[2], pb[2], vb[2], Jb[2 * PL_MAXQ], cb[2];
    pl_point_eval(&m->con[i].a, n, q, qd, d, pa, va, Ja, ca);
    pl_point_eval(&m->con[i].b, n, q, qd, d, pb, vb, Jb, cb);
    *phi = pa[c] - pb[c];
    double jq = 0.0;
    for (int j = 0; j < n; ++j) {
        row[j] = Ja[c * n + j] - Jb[c * n + j];
        jq += row[j] * qd[j];
    }
    *phit = (va[c] - vb[c]) - jq;  /* Phi' = Phi_q q' + Phi_t */
    *conv = ca[c] - cb[c];
}

void pl_constraints(const double* q, const double* d, const double* p, double* phi)
{
    pl_model m;
    pl_describe(p, &m);
    double row[PL_MAXQ], pt, cv;
    for (int i = 0; i < m.nc; ++i) con_eval(&m, i, q, ZERO, d, &phi[i], row, &pt, &cv);
}

void pl_constraint_jac(const double* q, const double* d, const double* p, double* phi_q)
{
    pl_model m;
    pl_describe(p, &m);
    double phi, pt, cv;
    for (int i = 0; i < m.nc; ++i) con_eval(&m, i, q, ZERO, d, &phi, phi_q + i * m.nq, &pt, &cv);
}

void pl_constraint_rate(const double* q, const double* d, const double* p, double* phi_t)
{
    pl_model m;
    pl_describe(p, &m);
    double phi, row[PL_MAXQ], cv;
    for (int i = 0; i < m.nc; ++i) con_eval(&m, i, q, ZERO, d, &phi, row, &phi_t[i], &cv);
}

void pl_constraint_acc(const double* q, const double* qd, const double* d, const double* p, double* gamma)
{
    pl_model m;
    pl_describe(p, &m);
    double phi, row[PL_MAXQ], pt, cv;
    for (int i = 0; i < m.nc; ++i) {
        con_eval(&m, i, q, qd, d, &phi, row, &pt, &cv);
        gamma[i] = -cv;
    }
}

void pl_energy(const double* q, const double* qd, const double* d, const double* p, double* e)
{
    pl_model m;
    pl_describe(p, &m);
    double T = 0.0, V = 0.0;
    for (int b = 0; b < m.nb; ++b) {
        const pl_body* B = &m.body[b];
        double pos[2], vel[2], J[2 * PL_MAXQ], conv[2], psi, psid;
        pl_point_eval(&B->G, m.nq, q, qd, d, pos, vel, J, conv);
        angle_eval(&B->psi, m.nq, q, qd, d, &psi, &psid);
        T += 0.5 * B->m * (vel[0] * vel[0] + vel[1] * vel[1]) + 0.5 * B->J * psid * psid;
        V -= B->m * (m.g[0] * pos[0] + m.g[1] * pos[1]);
    }
    e[0] = T;
    e[1] = V;
    e[2] = T + V;
}
