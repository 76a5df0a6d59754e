/* ALI3-P: index-3 augmented Lagrangian formulation with velocity and acceleration projections
 * and the trapezoidal rule (Bayo, Garcia de Jalon, Serna 1988; Cuadrado, Cardenal, Bayo 1997;
 * Cuadrado, Cardenal, Morer, Bayo 2000).
 *
 * The trapezoidal rule written on the positions q of t1 = t + h:
 *     q' = (2/h) q + qh',   qh' = -((2/h) q_n + q'_n),
 *     q'' = (4/h^2) q + qh'', qh'' = -((4/h^2) q_n + (4/h) q'_n + q''_n).
 * Newton on the equations of motion with the augmented Lagrangian constraint forces,
 *     g(q) = (h^2/4) [M q'' - f + Phi_q^T (alpha Phi + lambda*)] = 0,
 * tangent W = M + (h/2) C + (h^2/4) (K + alpha Phi_q^T Phi_q + H) with K = dr/dq, C = dr/dq' of
 * r = M q'' - f (the generated Jacobians) and H = d(Phi_q^T lambda*)/dq at fixed lambda* (the
 * constraint forces' geometric stiffness, when the model has the kernel; the alpha Phi part
 * of it is left out: far from convergence it is huge and made S2 with #1 diverge). Without H,
 * S2 with #1 rod at 0.1 ms contracted by only 0.4 per iteration where the slider pin force is
 * kN (t = 0.226 s) and stopped there; with it, it runs to 0.26 s at 0.1 ms and through at
 * 0.05 ms. After each iteration
 * lambda* <- lambda* + alpha Phi. Converged when |dq| <= tol and max |Phi| <= tol
 * (tol = newton_tol x length_scale). Modified Newton: P = M + (h/2) C + (h^2/4) K is kept
 * across iterations and steps (rebuilt on a new step size or a slow contraction), but the
 * penalty term is formed with the current Phi_q and W refactored at every iteration: with a
 * stale Phi_q the penalty term's error (kappa times the mass term, times the rotation of
 * Phi_q in a step) made the iterations diverge (four-bar fixture, kappa = 1e5, dt = 1 ms).
 * Then the projections (W with Phi_q at the converged point):
 *     W q' = P q'* - (h^2/4) alpha Phi_q^T Phi_t,   W q'' = P q''* + (h^2/4) alpha Phi_q^T gamma,
 * (P = W without the penalty term; the minimum of |x - x*|_P^2 + (h^2/4) alpha |Phi_q x - c|^2)
 * computed as corrections x = x* - W^-1 (h^2/4) alpha Phi_q^T (Phi_q x* - c). No rank condition on Phi_q: redundant constraints work.
 * The projected accelerations start the next step; the projected velocities are what the rows
 * (outputs, energy) and gamma see, while the next step starts from the trapezoidal q'*: fed
 * back, the velocity projection cost the method its second order (four-bar fixture, crank
 * angle at 0.5 s against dt = 1/16000 s: observed orders 1.2-1.6 over dt = 5 ... 0.3 ms and
 * 1.1e-4 rad at 0.31 ms, against 2.0-2.1 and 1.8e-5 rad with the projected velocities kept
 * out of the recursion; energy drift likewise 5.3e-5 against 2.3e-5 J at 0.5 ms).
 * Kept out entirely, though, the recursion's velocity defect d = Phi_q q'* + Phi_t is a mode
 * of the trapezoidal rule at -1 (d_{n+1} = -d_n + O(h^2): no damping at the Nyquist
 * frequency): neutral on the planar loops (S2: |d| ~ 1e-4 at 0.1 ms, bounded), it grew
 * like exp(100 t / s) on S7 (Euler parameters: a q'* off e.e' = 0 turns the rotation
 * equations' gyroscopic terms, ~ (e.e') omega), from 1e-7 to 1 m/s by t = 0.25 s, where Newton
 * failed, at any dt and kappa). So the velocity that starts the next step is projected on the
 * alternating part of the defect only, (d_{n+1} - d_n)/2 (d_n: the previous start's defect):
 * the mode's factor -1 becomes O(h), while a smooth defect (the trapezoidal rule's own O(h^2)
 * velocity error, which the positions are consistent with) is left in, its change per step
 * O(h^3): the four-bar keeps order 2.1-2.2 (errors within 13% of the unfiltered ones) and S7
 * runs (x_s 6e-10 m, N_mid 4e-5 of the peak from genalpha3's at 0.01 ms).
 * With nc = 0 this is the trapezoidal rule (Newmark 1/2, 1/4) with Newton on q.
 *
 * lambda* starts each step at the last step's value (extrapolating it from the last two
 * steps changed no iteration count on the test models). lambda* is accurate only to the force the Newton tolerance leaves, about
 * (1 + kappa) (4/h^2) M tol, so the multipliers the outputs see (reactions) are instead the
 * least-squares solution of Phi_q^T lambda = f - M q'' with the projected q'' (accurate to
 * the integration error).
 *
 * Penalty: alpha = kappa (4 / dt^2) tr M / |Phi_q|_F^2 at t = 0, so that the penalty term of W
 * weighs kappa times the mass term (kappa = --penalty, default 1e7): the lambda* iteration then
 * removes a factor of about 1 + kappa of the violation per iteration, and the projections leave
 * a residual of order 1/kappa (slider-crank fixture: the slider force from the projected q''
 * off by 4e-4, 4e-5, 4e-7, 4e-9 N at kappa = 1e2, 1e3, 1e5, 1e7; four-bar crank angle 1e-4 rad
 * apart between kappa = 1e2 and 1e5, 2e-8 rad between 1e5 and 1e9); W's condition number grows
 * like kappa (1e7: 9 digits left for the Newton update, which the next residual corrects).
 */
#include <math.h>
#include <string.h>

#include "constrained.h"
#include "linalg.h"

/* modified Newton: a new W when an iteration contracts |dq| by less than this while |dq| is
 * above ALI3P_SLOW_FLOOR x tol (below it the lag of lambda* sets the pace, not W). With the
 * floor at 1, S6 ran without full Newton (it crawls at |dq| ~ 1e-11, factor -0.98 per
 * iteration, on the strip's spin, and fails at t = 1.7 ms; so does S7 at dt <= 5 us), but S2
 * with a #1 rod at 0.05 ms then diverged at t = 0.253 s: the floor stays, and S6 takes
 * --newton full */
#define ALI3P_THETA_MAX 0.02
#define ALI3P_SLOW_FLOOR 100.0

/* P = M + (h/2) C + (h^2/4) K at (q1, v1, a1) */
static void build_p(csim* s, double h)
{
    const int n = s->n;
    const double c1 = 0.25 * h * h, cv = 0.5 * h;
    s->m->mass(s->q1, s->d, s->o->p, s->M);
    s->m->residual_jac(s->q1, s->v1, s->a1, s->d, s->o->p, s->Jq, s->Jv);
    for (int i = 0; i < n; ++i) {
        int sp[6], ns = cs_row_spans(s, i, 1, sp);
        for (int k = 0; k < ns; k += 2)
            for (size_t ij = (size_t)i * (size_t)n + (size_t)sp[k]; ij < (size_t)i * (size_t)n + (size_t)sp[k + 1]; ++ij)
                s->P[ij] = s->M[ij] + cv * s->Jv[ij] + c1 * s->Jq[ij];
    }
    s->r->jacobian_evaluations++;
    s->h_mat = h;
}

/* W = P + (h^2/4) alpha Phi_q^T Phi_q with the current Phi_q, LU-factored into S; dq: the last
 * Newton update (0: none), which tells a diverging iteration from a singular W */
static fsr_status factor_w(csim* s, double h, double t1, int newton, double dq)
{
    const int n = s->n, nc = s->nc, hess = newton && nc && s->m->constraint_hess;
    const double c = 0.25 * h * h * s->alpha;
    if (hess) s->m->constraint_hess(s->q1, s->lam, s->d, s->o->p, s->H);
    for (int i = 0; i < n; ++i) {
        int sp[6], ns = cs_row_spans(s, i, 1, sp);
        for (int k = 0; k < ns; k += 2)
            for (int j = sp[k]; j < sp[k + 1]; ++j) {
                double pen = 0.0;
                for (int l = 0; l < nc; ++l) pen += s->Pq[l * n + i] * s->Pq[l * n + j];
                s->S[i * n + j] = s->P[i * n + j] + c * pen;
                if (hess) s->S[i * n + j] += 0.25 * h * h * s->H[i * n + j];  /* + (h^2/4) d(Phi_q^T lambda*)/dq */
            }
    }
    if (cs_factor(s, s->S))
        return fsr_factor_failed(s->r, s->o, s->L, s->S, n, dq, t1, "ali3p: iteration matrix");
    return FSR_OK;
}

/* x -= W^-1 (h^2/4) alpha Phi_q^T e */
static void project(csim* s, double h, const double* e, double* x)
{
    const int n = s->n, nc = s->nc;
    const double c = 0.25 * h * h * s->alpha;
    for (int i = 0; i < n; ++i) {
        double t = 0.0;
        for (int l = 0; l < nc; ++l) t += s->Pq[l * n + i] * e[l];
        s->w2[i] = c * t;
    }
    cs_solve(s, s->S, s->w2);
    for (int i = 0; i < n; ++i) x[i] -= s->w2[i];
}

static fsr_status ali3p_begin(csim* s)
{
    const int n = s->n, nc = s->nc;
    double tr = 0.0, fro = 0.0;
    for (int i = 0; i < n; ++i) tr += s->M[i * n + i];
    for (int i = 0; i < nc * n; ++i) fro += s->Pq[i] * s->Pq[i];
    s->P = s->work;
    s->alpha = fro > 0.0 ? s->o->penalty * 4.0 / (s->o->dt * s->o->dt) * tr / fro : 0.0;
    s->h_mat = 0.0;
    if (nc) {  /* lam1: the velocity defect Phi_q q' + Phi_t of the q' that starts a step */
        s->m->constraint_rate(s->q, s->d, s->o->p, s->phit);
        for (int l = 0; l < nc; ++l) {
            double e = s->phit[l];
            for (int i = 0; i < n; ++i) e += s->Pq[l * n + i] * s->v[i];
            s->lam1[l] = e;
        }
    }
    return FSR_OK;
}

static fsr_status ali3p_step(csim* s)
{
    const fsm_system* m = s->m;
    const fsr_options* o = s->o;
    const int n = s->n, nc = s->nc;
    const long k = s->k;
    const double t1 = cs_time(s, k + 1), h = t1 - cs_time(s, k);
    const double c1 = 0.25 * h * h, cv = 2.0 / h, ca = 4.0 / (h * h);
    double *q = s->q, *v = s->v, *a = s->a, *lam = s->lam;
    double *q1 = s->q1, *v1 = s->v1, *a1 = s->a1, *hv = s->w1, *ha = s->ab, *res = s->res;
    fsr_status st;
    for (int i = 0; i < n; ++i) {
        hv[i] = -(cv * q[i] + v[i]);
        ha[i] = -(ca * q[i] + 4.0 / h * v[i] + a[i]);
        q1[i] = q[i] + h * v[i] + 0.5 * h * h * a[i];
        v1[i] = cv * q1[i] + hv[i];
        a1[i] = ca * q1[i] + ha[i];
    }
    cs_drive(s, t1);
    if (nc) cs_constraints(s, q1);
    int rebuild = o->newton_full || fabs(h - s->h_mat) > 1e-6 * h;
    int factored = nc == 0;  /* nc = 0: W = P, factored when P is built */
    double dq = 0.0, dq_prev = -1.0;
    for (int it = 0;; ++it) {
        if (it == o->newton_max) return cs_newton_failed(s, t1, dq, it);
        m->mass(q1, s->d, o->p, s->M);
        m->force(q1, v1, s->d, o->p, s->f);
        s->r->force_evaluations++;
        for (int l = 0; l < nc; ++l) s->e1[l] = s->alpha * s->phi[l] + lam[l];
        for (int i = 0; i < n; ++i) {  /* -g */
            double r = -s->f[i];
            int sp[6], ns = cs_row_spans(s, i, 0, sp);
            for (int k = 0; k < ns; k += 2)
                for (int j = sp[k]; j < sp[k + 1]; ++j) r += s->M[i * n + j] * a1[j];
            for (int l = 0; l < nc; ++l) r += s->Pq[l * n + i] * s->e1[l];
            res[i] = -c1 * r;
        }
        if (rebuild) {
            build_p(s, h);
            rebuild = o->newton_full;
            dq_prev = -1.0;
            factored = 0;
        }
        if (nc || !factored) {
            if ((st = factor_w(s, h, t1, 1, dq))) return st;
            factored = 1;
        }
        cs_solve(s, s->S, res);
        dq = 0.0;
        for (int i = 0; i < n; ++i) {
            q1[i] += res[i];
            v1[i] += cv * res[i];
            a1[i] += ca * res[i];
            double x = fabs(res[i]);
            if (x > dq || x != x) dq = x;
        }
        s->r->newton_iterations++;
        if (!isfinite(dq)) return cs_fail(s, FSR_DIVERGED, "diverged at t = %.6g s: Newton update not finite", t1);
        if (nc) {
            cs_constraints(s, q1);
            for (int l = 0; l < nc; ++l) lam[l] += s->alpha * s->phi[l];
        }
        if (dq <= s->tol && cs_max_abs(s->phi, nc) <= s->tol) break;
        if (dq_prev > ALI3P_SLOW_FLOOR * s->tol && dq > ALI3P_THETA_MAX * dq_prev) rebuild = 1;
        dq_prev = dq;
    }
    if (nc) {  /* projections with W at the converged point */
        if ((st = factor_w(s, h, t1, 0, 0.0))) return st;  /* converged: a failure is the matrix's own */
        m->constraint_rate(q1, s->d, o->p, s->phit);
        for (int l = 0; l < nc; ++l) {
            double e = s->phit[l];
            for (int i = 0; i < n; ++i) e += s->Pq[l * n + i] * v1[i];
            s->e1[l] = e;
        }
        memcpy(s->vout, v1, sizeof(double) * (size_t)n);
        /* the recursion's q': only the alternating part of the defect projected out (see the
           top); s->lam1 holds the defect of the q' that started this step */
        for (int l = 0; l < nc; ++l) s->e2[l] = 0.5 * (s->e1[l] - s->lam1[l]);
        project(s, h, s->e2, v1);
        for (int l = 0; l < nc; ++l) {
            double e = s->phit[l];
            for (int i = 0; i < n; ++i) e += s->Pq[l * n + i] * v1[i];
            s->lam1[l] = e;
        }
        project(s, h, s->e1, s->vout);
        m->constraint_acc(q1, s->vout, s->d, o->p, s->gam);
        for (int l = 0; l < nc; ++l) {
            double e = -s->gam[l];
            for (int i = 0; i < n; ++i) e += s->Pq[l * n + i] * a1[i];
            s->e1[l] = e;
        }
        project(s, h, s->e1, a1);
        if (cs_row_due(s)) {  /* multipliers for the outputs: Phi_q^T mult = f - M q'' in least
                                 squares; only the rows read them (a force evaluation and a
                                 constraint-block solve per step saved between rows) */
            m->force(q1, s->vout, s->d, o->p, res);
            s->r->force_evaluations++;
            for (int i = 0; i < n; ++i) {
                int sp[6], ns = cs_row_spans(s, i, 0, sp);
                for (int k = 0; k < ns; k += 2)
                    for (int j = sp[k]; j < sp[k + 1]; ++j) res[i] -= s->M[i * n + j] * a1[j];
            }
            memset(s->e2, 0, sizeof(double) * (size_t)nc);
            memcpy(s->gam, s->e2, sizeof(double) * (size_t)nc);
            cs_kkt(s, NULL, res, s->gam, s->mult);
        }
    }
    memcpy(q, q1, sizeof(double) * (size_t)n);
    memcpy(v, v1, sizeof(double) * (size_t)n);
    if (!nc) memcpy(s->vout, v1, sizeof(double) * (size_t)n);
    memcpy(a, a1, sizeof(double) * (size_t)n);
    s->k = k + 1;
    return cs_accept(s, t1);
}

/* doubles: P (n x n) */
static size_t ali3p_work_size(int n)
{
    return (size_t)n * (size_t)n;
}

static const fsr_integrator INTEGRATOR = {
    .stages = 1, .work_size = ali3p_work_size,
    .cs_begin = ali3p_begin, .cs_step = ali3p_step};

const fsr_integrator* fsr_integrator_ali3p(void)
{
    return &INTEGRATOR;
}
