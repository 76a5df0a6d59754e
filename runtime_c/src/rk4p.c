/* rk4p: the classical 4-stage Runge-Kutta method on the index-1 form of the equations with
 * constraints, with coordinate projection after every step (Hairer & Wanner, Solving ODEs II,
 * section VII.2: projection keeps the order of the method it follows).
 *
 * The index-1 form: the accelerations and multipliers at (q, v, t) from
 *     [M(q) Phi_q^T; Phi_q 0] [q''; lambda] = [f(q, v, t); gamma(q, v, t)]
 * (constrained.c's block solve, cs_kkt: redundant rows dropped), an ODE in (q, v) that RK4
 * integrates to order 4. It keeps Phi'' = 0 only, so Phi and Phi' drift by the local error;
 * after each step q is projected onto Phi(q, t1) = 0 (Newton with corrections of least
 * M-norm, M at the last stage, until max |Phi| <= newton_tol x L) and then v onto
 * Phi_q v = -Phi_t at that q (the same norm). The accelerations and multipliers of the
 * projected state are the first stage of the next step and what the rows see.
 *
 * Explicit, so its step is limited by stability: omega_max dt <= 2.785 (rk4.c's bound), with
 * omega_max the largest frequency of the linearised motion on the constraint manifold at t = 0
 * (power iteration on M^-1 K restricted to Phi_q x = 0, K = dr/dq of r = M q'' - f at the
 * consistent start: velocity-dependent terms and the change of the frequencies with the
 * configuration are not in it). A step above it is refused; stiff modes (an axial one) make
 * the method useless, as for rk4. No Newton iteration in the step: per step four evaluations
 * of M (factored), f, Phi_q and gamma with a constraint-block solve (stages 2-4 and the
 * projected state's), plus the projection (Phi and Phi_q per Newton iteration, Phi_t, a
 * block solve each).
 */
#include <math.h>
#include <string.h>

#include "constrained.h"
#include "linalg.h"

#define RK4P_STABILITY 2.785  /* rk4.c */
#define RK4P_POWER_ITER 2000

/* a, lam = the index-1 accelerations and multipliers at (q, v, t); M(q) factored in S */
static fsr_status accel(csim* s, double t, const double* q, const double* v, double* a, double* lam)
{
    const fsm_system* m = s->m;
    const int n = s->n;
    cs_drive(s, t);
    m->mass(q, s->d, s->o->p, s->S);
    s->chol = !s->banded && fsr_symmetric(s->S, n);  /* Cholesky: half LU's work (as ode.c's M) */
    if (s->chol ? fsr_chol_factor(s->S, n) : cs_factor(s, s->S))
        return cs_fail(s, FSR_SINGULAR, "rk4p: mass matrix singular at t = %.6g s", t);
    m->force(q, v, s->d, s->o->p, a);
    s->r->force_evaluations++;
    if (s->nc) {  /* Phi_q and gamma: Phi itself is not read here */
        m->constraint_jac(q, s->d, s->o->p, s->Pq);
        m->constraint_acc(q, v, s->d, s->o->p, s->gam);
    }
    cs_kkt(s, s->S, a, s->gam, lam);
    return FSR_OK;
}

/* z = M^-1 (K x - Phi_q^T l) with Phi_q z = 0: K restricted to the constraint manifold */
static void constrained_stiffness(void* ctx, const double* x, double* z)
{
    csim* s = ctx;
    fsr_matvec(s->Jq, s->n, 1, x, z);        /* z = K x */
    memset(s->e2, 0, sizeof(double) * (size_t)s->nc);
    memcpy(s->gam, s->e2, sizeof(double) * (size_t)s->nc);
    cs_kkt(s, s->S, z, s->gam, s->lam1);
}

/* omega_max on the constraint manifold at the consistent start (S: M(q0) factored) */
static double omega_max(csim* s)
{
    const int n = s->n;
    double *x = s->w1, *z = s->res;
    s->m->residual_jac(s->q, s->v, s->a, s->d, s->o->p, s->Jq, s->Jv);
    s->r->jacobian_evaluations++;
    for (int i = 0; i < n; ++i) x[i] = (1.0 + 0.1 * i) / sqrt((double)n);
    double est = fsr_power_iteration(n, x, z, RK4P_POWER_ITER, constrained_stiffness, s);
    return sqrt(est);
}

static fsr_status rk4p_begin(csim* s)
{
    s->r->omega_max = omega_max(s);
    cs_drive(s, 0.0);
    if (s->nc) cs_constraints(s, s->q);
    return fsr_check_step_limit(s->r, "rk4p", s->o->dt, RK4P_STABILITY, s->r->omega_max,
                                " on the constraint manifold at t = 0", "ali3p");
}

/* q1 onto Phi(q1, t1) = 0, then v1 onto Phi_q v1 = -Phi_t (M of the last stage in S) */
static fsr_status project(csim* s, double t1)
{
    const fsm_system* m = s->m;
    const int n = s->n, nc = s->nc;
    double *q1 = s->q1, *v1 = s->v1, *x = s->w1;
    cs_drive(s, t1);
    for (int it = 0;; ++it) {
        cs_constraints(s, q1);
        if (cs_max_abs(s->phi, nc) <= s->tol) break;
        if (it == s->o->newton_max || !isfinite(cs_max_abs(s->phi, nc)))
            return cs_fail(s, FSR_NEWTON_FAILED, "rk4p: the projection onto the constraints did not "
                           "converge at t = %.6g s (max |Phi| = %.3g after %d iterations); reduce --dt",
                           t1, cs_max_abs(s->phi, nc), it);
        for (int l = 0; l < nc; ++l) s->e2[l] = -s->phi[l];
        memcpy(s->gam, s->e2, sizeof(double) * (size_t)nc);
        memset(x, 0, sizeof(double) * (size_t)n);
        cs_kkt(s, s->S, x, s->gam, s->lam1);
        for (int i = 0; i < n; ++i) q1[i] += x[i];
        s->r->newton_iterations++;
    }
    m->constraint_rate(q1, s->d, s->o->p, s->phit);
    for (int l = 0; l < nc; ++l) {
        double e = s->phit[l];
        for (int i = 0; i < n; ++i) e += s->Pq[l * n + i] * v1[i];
        s->gam[l] = -e;
    }
    memset(x, 0, sizeof(double) * (size_t)n);
    cs_kkt(s, s->S, x, s->gam, s->lam1);
    for (int i = 0; i < n; ++i) v1[i] += x[i];
    return FSR_OK;
}

static fsr_status rk4p_step(csim* s)
{
    const int n = s->n;
    const long k = s->k;
    const double t = cs_time(s, k), t1 = cs_time(s, k + 1), h = t1 - t;
    double *q = s->q, *v = s->v, *a = s->a;
    double *Q = s->q1, *V = s->v1, *A = s->a1, *sq = s->f, *sv = s->ab;
    static const double c[3] = {0.5, 0.5, 1.0}, b[3] = {1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0};
    fsr_status st;
    for (int i = 0; i < n; ++i) {  /* stage 1: (v, a), a from the last step */
        sq[i] = v[i] / 6.0;
        sv[i] = a[i] / 6.0;
        V[i] = v[i];
        A[i] = a[i];
    }
    for (int j = 0; j < 3; ++j) {  /* stages 2-4 */
        for (int i = 0; i < n; ++i) {
            Q[i] = q[i] + c[j] * h * V[i];
            V[i] = v[i] + c[j] * h * A[i];
        }
        if ((st = accel(s, t + c[j] * h, Q, V, A, s->lam1))) return st;
        for (int i = 0; i < n; ++i) {
            sq[i] += b[j] * V[i];
            sv[i] += b[j] * A[i];
        }
    }
    for (int i = 0; i < n; ++i) {
        Q[i] = q[i] + h * sq[i];
        V[i] = v[i] + h * sv[i];
    }
    if (s->nc && (st = project(s, t1))) return st;
    memcpy(q, Q, sizeof(double) * (size_t)n);
    memcpy(v, V, sizeof(double) * (size_t)n);
    if ((st = accel(s, t1, q, v, a, s->lam))) return st;
    memcpy(s->vout, v, sizeof(double) * (size_t)n);
    memcpy(s->mult, s->lam, sizeof(double) * (size_t)s->nc);
    s->k = k + 1;
    return cs_accept(s, t1);
}

static size_t rk4p_work_size(int n)
{
    (void)n;
    return 0;
}

static int always(const fsr_options* o)
{
    (void)o;
    return 1;
}

static const fsr_integrator INTEGRATOR = {
    .stability_limited = always, .stages = 1,
    .work_size = rk4p_work_size, .cs_begin = rk4p_begin, .cs_step = rk4p_step};

const fsr_integrator* fsr_integrator_rk4p(void)
{
    return &INTEGRATOR;
}
