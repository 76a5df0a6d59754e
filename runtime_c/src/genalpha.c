/* genalpha: generalized-alpha (genalpha.h), its coefficients from rho_inf. newmark.c runs
 * the same step with am = af = 0. */
#include "genalpha.h"

#include <math.h>
#include <string.h>

#include "linalg.h"

/* Predict the next acceleration by linear extrapolation (a + (a - a_old)) when that would
 * have predicted the last one better than a alone: at large steps it takes #1-#3 from 1.5-1.9
 * to 1.1-1.3 iterations per step; where the acceleration rings at high frequency (ef at 5 ms)
 * the constant predictor keeps winning. */
static int extrapolation_wins(int n, const double* a1, const double* a, const double* a_old)
{
    double e_const = 0.0, e_extra = 0.0;
    for (int i = 0; i < n; ++i) {
        e_const = fsr_max_abs(e_const, a1[i] - a[i]);
        e_extra = fsr_max_abs(e_extra, a1[i] - 2.0 * a[i] + a_old[i]);
    }
    return e_extra < e_const;
}

/* Generalized-alpha (Chung & Hulbert; Arnold & Bruls form for M(q) q'' = f) with Newton
 * iterations on the acceleration a1; q1 and v1 follow it linearly (dq1 = cb da, dv1 = cg da).
 * Newmark(gamma, beta) is the special case am = af = 0. The iteration matrix is rebuilt (at
 * the current iterate) when the step size changes or an iteration contracts the update by
 * less than NEWTON_THETA_MAX; every iteration with newton_full. */
fsr_status alpha_begin(sim* s, fsr_alpha c)
{
    alpha_state* g = s->ms;
    int n = s->n;
    g->am = c.am;
    g->af = c.af;
    g->gam = c.gam;
    g->bet = c.bet;
    g->ra = (1.0 - g->af) / (1.0 - g->am);
    g->pa = g->af / (1.0 - g->am);
    g->pb = -g->am / (1.0 - g->am);
    g->ns = (newton_state){0.0, -1.0, 0};
    g->extrapolate = 0;
    s->done = s->msteps < 1;
    /* work: a, ab, a1, q1, v1, res, ma, a_old (see alpha_step) */
    double *q = s->state, *a = s->work, *ab = a + n, *a_old = ab + 6 * n;
    fsr_status st = sim_accel(s, 0.0, q, q + n, a);
    if (st) return st;
    memcpy(ab, a, sizeof(double) * (size_t)n);
    memcpy(a_old, a, sizeof(double) * (size_t)n);
    return FSR_OK;
}

fsr_status alpha_step(sim* s)
{
    alpha_state* g = s->ms;
    const fsr_options* o = s->o;
    int n = s->n;
    const double bet = g->bet, gam = g->gam, ra = g->ra, pa = g->pa, pb = g->pb;
    double *q = s->state, *v = q + n;
    /* a: acceleration, ab: the algorithmic acceleration; 1: their values at t1 */
    double *a = s->work, *ab = a + n, *a1 = ab + n, *q1 = a1 + n, *v1 = q1 + n, *res = v1 + n, *ma = res + n;
    double* a_old = ma + n;
    double *drive = s->dw + DW_STEP * s->nd, tol = o->newton_tol * s->L;
    newton_state* ns = &g->ns;
    fsr_status st;
    long k = s->k;
    double t = sim_time(s, k), t1 = sim_time(s, k + 1), h = t1 - t;
    double cb = h * h * bet * ra, cg = h * gam * ra, h2 = h * h;
    for (int i = 0; i < n; ++i) {  /* predictor a1; ab becomes ab(t1) - ra a1 */
        double abo = ab[i], abp = pa * a[i] + pb * abo;
        a1[i] = g->extrapolate ? 2.0 * a[i] - a_old[i] : a[i];
        double ab1 = abp + ra * a1[i];
        ab[i] = abp;
        q1[i] = q[i] + h * v[i] + h2 * ((0.5 - bet) * abo + bet * ab1);
        v1[i] = v[i] + h * ((1.0 - gam) * abo + gam * ab1);
    }
    sim_drive(s, t1, drive);
    /* a new matrix for a new step size, not for the rounding of t1 - t */
    int rebuild = o->newton_full || fabs(h - ns->h) > 1e-6 * h;
    double dq = 0.0, dq_prev = -1.0;
    for (int it = 0;; ++it) {
        if (it == o->newton_max) return newton_failed(s, t1, dq, it);
        if ((st = sim_residual(s, t1, q1, v1, a1, drive, res, ma))) return st;  /* -(M a1 - f) */
        if (rebuild) {
            if ((st = sim_newton_mass(s, t1, q1, drive))) return st;
            s->m->residual_jac(q1, v1, a1, drive, o->p, s->Jq, s->Jv);
            newton_rows(s, 0, &cb, &cg);
            if ((st = newton_factor(s, t1, dq))) return st;
            ns->h = h;
            ns->theta = dq_prev = -1.0;
            rebuild = o->newton_full;
        }
        newton_solve(s, res);
        dq = 0.0;
        for (int i = 0; i < n; ++i) {
            a1[i] += res[i];
            q1[i] += cb * res[i];
            v1[i] += cg * res[i];
            dq = fsr_max_abs(dq, cb * res[i]);
        }
        s->r->newton_iterations++;
        if (!isfinite(dq)) return newton_diverged(s, t1, q1, v1, n);
        int slow = newton_contraction(ns, k, dq, dq_prev, NEWTON_THETA_MAX);
        if (newton_converged(s, ns, k, dq, tol)) break;
        if (slow) rebuild = 1;
        dq_prev = dq;
    }
    for (int i = 0; i < n; ++i) ab[i] += ra * a1[i];
    g->extrapolate = extrapolation_wins(n, a1, a, a_old);
    memcpy(a_old, a, sizeof(double) * (size_t)n);
    memcpy(a, a1, sizeof(double) * (size_t)n);
    memcpy(q, q1, sizeof(double) * (size_t)(2 * n));  /* q1, v1 are contiguous, as q, v */
    s->k = k + 1;
    s->done = s->k >= s->msteps;
    return sim_accept(s, t1, h, q, a, NULL);
}


fsr_status alpha_retune(sim* s)
{
    alpha_state* g = s->ms;
    g->ns.h = 0.0;  /* a new Newton matrix at the next step */
    return FSR_OK;
}

size_t alpha_work_size(int n)
{
    return 8 * (size_t)n;
}

static fsr_status genalpha_begin(sim* s)
{
    return alpha_begin(s, fsr_alpha_coefficients(s->o->rho_inf));
}

static const fsr_integrator INTEGRATOR = {
    .stages = 1,
    .state_size = sizeof(alpha_state), .work_size = alpha_work_size,
    .begin = genalpha_begin, .step = alpha_step, .retune = alpha_retune};

const fsr_integrator* fsr_integrator_genalpha(void)
{
    return &INTEGRATOR;
}
