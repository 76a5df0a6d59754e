/* Index-3 generalized-alpha (Arnold & Bruls 2007: Chung-Hulbert's alpha_m, alpha_f, beta,
 * gamma from rho_inf; the equations of motion and the position constraints at t1,
 *     M(q1) a1 + Phi_q(q1)^T lambda1 = f(q1, v1, t1),   Phi(q1, t1) = 0,
 * q1, v1 from the algorithmic acceleration as in genalpha.c) by Newton on
 * [a1, lambda1] with the constraint block
 *     [S  Phi_q^T] [da  ]   [f - M a1 - Phi_q^T lambda1]
 *     [Phi_q   0 ] [dlam] = [-Phi / cb                 ],   S = M + cb K + cg C,
 * (dq1 = cb da, dv1 = cg da; K, C the generated Jacobians of r = M q'' - f, K with the
 * constraint forces' geometric stiffness d(Phi_q^T lambda1)/dq when the model has it, reused across
 * iterations and steps while they contract (modified Newton); Phi_q fresh every iteration),
 * solved by the Schur complement Phi_q S^-1 Phi_q^T with complete pivoting, which drops the rows
 * of redundant constraints (cs_kkt). Converged when |dq1| <= tol and max |Phi| <= tol.
 * Then the velocities are projected onto Phi_q v + Phi_t = 0 (the smallest correction in the
 * metric of S, exact up to rounding) for the rows (outputs, energy) only: fed back into the
 * next step, the projection made the accelerations and multipliers first order in the step
 * (slider-crank fixture: the error in the slider's acceleration went 16 -> 8 m/s^2 from
 * dt = 1e-4 to 5e-5 s, against 0.37 -> 0.095 m/s^2 without feedback). Positions need no
 * projection (Phi = 0 to the Newton tolerance); accelerations are not projected (they drive
 * the algorithmic acceleration of the next step).
 */
#include <math.h>
#include <string.h>

#include "constrained.h"
#include "linalg.h"

#define GA3_THETA_MAX 0.1

static fsr_status genalpha3_begin(csim* s)
{
    fsr_alpha c = fsr_alpha_coefficients(s->o->rho_inf);
    s->am = c.am;
    s->af = c.af;
    s->gm = c.gam;
    s->bt = c.bet;
    s->ra = (1.0 - s->af) / (1.0 - s->am);
    s->pa = s->af / (1.0 - s->am);
    s->pb = -s->am / (1.0 - s->am);
    memcpy(s->ab, s->a, sizeof(double) * (size_t)s->n);
    s->h_mat = 0.0;
    return FSR_OK;
}

static fsr_status genalpha3_step(csim* s)
{
    const fsm_system* m = s->m;
    const fsr_options* o = s->o;
    const int n = s->n, nc = s->nc;
    const long k = s->k;
    const double t1 = cs_time(s, k + 1), h = t1 - cs_time(s, k);
    const double bt = s->bt, gm = s->gm, ra = s->ra, cb = h * h * bt * ra, cg = h * gm * ra;
    double *q = s->q, *v = s->v, *a = s->a, *ab = s->ab, *lam = s->lam;
    double *q1 = s->q1, *v1 = s->v1, *a1 = s->a1, *lam1 = s->lam1, *res = s->res;
    double *c = s->gam, *dlam = s->phit;  /* scratch during the iteration */
    for (int i = 0; i < n; ++i) {  /* predictor a1 = a; ab becomes ab(t1) - ra a1 */
        double abo = ab[i], abp = s->pa * a[i] + s->pb * abo, ab1 = abp + ra * a[i];
        a1[i] = a[i];
        ab[i] = abp;
        q1[i] = q[i] + h * v[i] + h * h * ((0.5 - bt) * abo + bt * ab1);
        v1[i] = v[i] + h * ((1.0 - gm) * abo + gm * ab1);
    }
    memcpy(lam1, lam, sizeof(double) * (size_t)nc);
    cs_drive(s, t1);
    int rebuild = o->newton_full || fabs(h - s->h_mat) > 1e-6 * h;
    double dq = 0.0, dq_prev = -1.0;
    for (int it = 0;; ++it) {
        m->mass(q1, s->d, o->p, s->M);
        m->force(q1, v1, s->d, o->p, res);
        s->r->force_evaluations++;
        if (nc) cs_constraints(s, q1);
        if (it > 0 && dq <= s->tol && cs_max_abs(s->phi, nc) <= s->tol) break;
        if (it == o->newton_max) return cs_newton_failed(s, t1, dq, it);
        for (int i = 0; i < n; ++i) {
            double r = res[i];
            int sp[6], ns = cs_row_spans(s, i, 0, sp);
            for (int k = 0; k < ns; k += 2)
                for (int j = sp[k]; j < sp[k + 1]; ++j) r -= s->M[i * n + j] * a1[j];
            for (int l = 0; l < nc; ++l) r -= s->Pq[l * n + i] * lam1[l];
            res[i] = r;
        }
        if (rebuild) {
            int hess = nc && m->constraint_hess;  /* + cb d(Phi_q^T lambda1)/dq */
            m->residual_jac(q1, v1, a1, s->d, o->p, s->Jq, s->Jv);
            if (hess) m->constraint_hess(q1, lam1, s->d, o->p, s->H);
            for (int i = 0; i < n; ++i) {
                int sp[6], ns = cs_row_spans(s, i, 1, sp);
                for (int k = 0; k < ns; k += 2)
                    for (size_t ij = (size_t)i * (size_t)n + (size_t)sp[k]; ij < (size_t)i * (size_t)n + (size_t)sp[k + 1]; ++ij) {
                        s->S[ij] = s->M[ij] + cb * s->Jq[ij] + cg * s->Jv[ij];
                        if (hess) s->S[ij] += cb * s->H[ij];
                    }
            }
            s->r->jacobian_evaluations++;
            s->h_mat = h;
            if (cs_factor(s, s->S))
                return fsr_factor_failed(s->r, s->o, s->L, s->S, n, dq, t1, "genalpha3: iteration matrix");
            rebuild = o->newton_full;
            dq_prev = -1.0;
        }
        for (int l = 0; l < nc; ++l) c[l] = -s->phi[l] / cb;
        cs_kkt(s, s->S, res, c, dlam);
        dq = 0.0;
        for (int i = 0; i < n; ++i) {
            a1[i] += res[i];
            q1[i] += cb * res[i];
            v1[i] += cg * res[i];
            double x = fabs(cb * res[i]);
            if (x > dq || x != x) dq = x;
        }
        for (int l = 0; l < nc; ++l) lam1[l] += dlam[l];
        s->r->newton_iterations++;
        if (!isfinite(dq)) return cs_fail(s, FSR_DIVERGED, "diverged at t = %.6g s: Newton update not finite", t1);
        if (dq_prev > 0.0 && dq > GA3_THETA_MAX * dq_prev) rebuild = 1;
        dq_prev = dq;
    }
    for (int i = 0; i < n; ++i) ab[i] += ra * a1[i];
    if (nc) {  /* velocity projection: S x + Phi_q^T mu = 0, Phi_q (v1 + x) = -Phi_t */
        m->constraint_rate(q1, s->d, o->p, s->phit);
        for (int l = 0; l < nc; ++l) {
            double e = s->phit[l];
            for (int i = 0; i < n; ++i) e += s->Pq[l * n + i] * v1[i];
            c[l] = -e;
        }
        memset(res, 0, sizeof(double) * (size_t)n);
        cs_kkt(s, s->S, res, c, dlam);
        for (int i = 0; i < n; ++i) s->vout[i] = v1[i] + res[i];
    } else {
        memcpy(s->vout, v1, sizeof(double) * (size_t)n);
    }
    memcpy(q, q1, sizeof(double) * (size_t)n);
    memcpy(v, v1, sizeof(double) * (size_t)n);
    memcpy(a, a1, sizeof(double) * (size_t)n);
    memcpy(lam, lam1, sizeof(double) * (size_t)nc);
    memcpy(s->mult, lam1, sizeof(double) * (size_t)nc);
    s->k = k + 1;
    return cs_accept(s, t1);
}

static size_t genalpha3_work_size(int n)
{
    (void)n;
    return 0;
}

static const fsr_integrator INTEGRATOR = {
    .stages = 1, .work_size = genalpha3_work_size,
    .cs_begin = genalpha3_begin, .cs_step = genalpha3_step};

const fsr_integrator* fsr_integrator_genalpha3(void)
{
    return &INTEGRATOR;
}
