/* The explicit Runge-Kutta engine of rk4.c and dopri5.c (erk.h): the stages of a Butcher
 * tableau, dense output, and for an embedded pair (dopri5 with tol > 0) the step-size control;
 * fixed steps are refused above the stability limit of the model (ode.c: sim_omega_max). */
#include "erk.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "linalg.h"

/* Dense output of a step of tableau T from (t, y) to (t + h, y1) at t + theta h (y' stages k). */
static void dense_at(const void* tableau, int m, double theta, double h, const double* y,
                     const double* y1, const double* k, double* out)
{
    const erk_tableau* T = tableau;
    const double* klast = k + (size_t)(T->stages - 1) * (size_t)m;
    double th1 = 1.0 - theta;
    for (int j = 0; j < m; ++j) {
        double dy = y1[j] - y[j], bspl = h * k[j] - dy, r4 = dy - h * klast[j] - bspl, r5 = 0.0;
        for (int i = 0; i < T->stages; ++i) r5 += T->d[i] * k[(size_t)i * (size_t)m + (size_t)j];
        out[j] = y[j] + theta * (dy + th1 * (bspl + theta * (r4 + th1 * h * r5)));
    }
}

static void erk_dense(const dense_step* d, double theta, const double* y1, double* out)
{
    dense_at(d->T, d->m, theta, d->h, d->y, y1, d->k, out);
}

/* out = y + h sum_j w_j k_j over the first nk stages. */
static void combine(double* out, const double* y, double h, const double* w, const double* k, int nk, int m)
{
    memcpy(out, y, sizeof(double) * (size_t)m);
    for (int j = 0; j < nk; ++j) {
        if (w[j] == 0.0) continue;
        double c = h * w[j];
        const double* kj = k + (size_t)j * (size_t)m;
        for (int l = 0; l < m; ++l) out[l] += c * kj[l];
    }
}

/* Stages 2..s of a step from (t, y) to t1 (k[0] = f(t, y) on entry); y1 = the new state. */
static fsr_status erk_stages(sim* s, const erk_tableau* T, double t, double t1, const double* y,
                           double* k, double* y1, double* ys)
{
    int m = 2 * s->n;
    double h = t1 - t;
    for (int i = 1; i < T->stages; ++i) {
        double* yi = T->fsal && i == T->stages - 1 ? y1 : ys;  /* FSAL: the last stage is at y1 */
        combine(yi, y, h, T->a[i], k, i, m);
        fsr_status st = sim_deriv(s, T->c[i] == 1.0 ? t1 : t + T->c[i] * h, yi, k + (size_t)i * (size_t)m);
        if (st) return st;
    }
    if (!T->fsal) combine(y1, y, h, T->b, k, T->stages, m);
    return FSR_OK;
}

/* Error norm of dopri5 (Hairer's RMS norm): component j of the embedded estimate
 * h sum e_i k_i is measured against tol * (sc_j + max(|y_j|, |y1_j|)), sc = L for the
 * coordinates [m] and L / (1 s) for their rates [m/s]: rtol = tol, atol = tol * L. */
static double error_norm(const sim* s, const erk_tableau* T, double h, const double* k,
                         const double* y, const double* y1)
{
    int m = 2 * s->n;
    double sum = 0.0;
    for (int j = 0; j < m; ++j) {
        double e = 0.0;
        for (int i = 0; i < T->stages; ++i) e += T->e[i] * k[(size_t)i * (size_t)m + (size_t)j];
        double sc = s->o->tol * (s->L + fsr_max_abs(fabs(y[j]), y1[j]));
        sum += (h * e / sc) * (h * e / sc);
    }
    return sqrt(sum / m);
}

static double norm_scaled(const sim* s, const double* x, const double* y)
{
    int m = 2 * s->n;
    double sum = 0.0;
    for (int j = 0; j < m; ++j) {
        double v = x[j] / (s->o->tol * (s->L + fabs(y[j])));
        sum += v * v;
    }
    return sqrt(sum / m);
}

/* First step of dopri5 (Hairer & Wanner's HINIT): one extra evaluation. */
static fsr_status initial_step(sim* s, const double* y, const double* k0, double* k1, double* ys, double* h)
{
    int m = 2 * s->n;
    double d0 = norm_scaled(s, y, y), d1 = norm_scaled(s, k0, y);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = fmin(h0, s->o->t_end);
    for (int j = 0; j < m; ++j) ys[j] = y[j] + h0 * k0[j];
    fsr_status st = sim_deriv(s, h0, ys, k1);
    if (st) return st;
    for (int j = 0; j < m; ++j) ys[j] = k1[j] - k0[j];
    double d2 = norm_scaled(s, ys, y) / h0, dm = fmax(d1, d2);
    double h1 = dm <= 1e-15 ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / dm, 0.2);
    *h = fmin(fmin(100.0 * h0, h1), s->o->t_end);
    return FSR_OK;
}

/* Refuse a fixed explicit step above the stability limit instead of integrating garbage. */
static fsr_status check_fixed_step(sim* s, const erk_tableau* T)
{
    return sim_check_step_limit(s, T->name, T->stability, "an implicit integrator");
}

fsr_status erk_begin(sim* s, const erk_tableau* T)
{
    erk_state* e = s->ms;
    fsr_status st = sim_omega_max(s, s->work, &s->r->omega_max);
    if (!st && (!T->embedded || s->o->tol == 0.0)) st = check_fixed_step(s, T);
    if (st) return st;
    int m = 2 * s->n;
    double *k = s->work, *y1 = k + (size_t)MAX_STAGES * (size_t)m, *ys = y1 + m;
    e->T = T;
    e->adaptive = T->embedded && s->o->tol > 0.0;
    e->t = 0.0;
    e->h = s->o->dt;
    e->err_old = 1e-4;
    e->have_k0 = e->rejected = 0;
    s->done = s->msteps < 1;
    if (!e->adaptive) return FSR_OK;
    st = sim_deriv(s, 0.0, s->state, k);
    if (st) return st;
    e->have_k0 = 1;
    return initial_step(s, s->state, k, k + m, ys, &e->h);
}

/* Step-size control of dopri5 (Hairer & Wanner, DOPRI5): factor err^-(0.2 - 0.75 beta) *
 * err_old^beta (a PI controller), safety 0.9, shrink at most 5x and grow at most 10x per step,
 * no growth right after a rejection. beta = 0.08, Hairer's advice where stability limits the
 * step, as here (undamped modes): 78 rejections in 1100 steps on #3 instead of 265 at 0.04. */
#define PI_BETA 0.08
#define SAFETY 0.9
#define FAC_MIN 0.2
#define FAC_MAX 10.0

fsr_status erk_advance(sim* s)
{
    erk_state* e = s->ms;
    const fsr_options* o = s->o;
    const erk_tableau* T = e->T;
    int m = 2 * s->n, adaptive = e->adaptive;
    double *y = s->state, *k = s->work, *y1 = k + (size_t)MAX_STAGES * (size_t)m, *ys = y1 + m;
    double t = e->t, h = e->h, t1;
    fsr_status st;
    if (adaptive) {
        if (s->r->steps + s->r->rejected_steps >= o->max_steps)
            return sim_fail(s, FSR_STEP_FAILED,
                            "%s gave up at t = %.6g s after %ld steps (step %.3g s = %.2g / omega_max, "
                            "omega_max = %.1f rad/s: stiff for explicit steps); use an implicit "
                            "integrator, a looser --tol or a larger --max-steps", T->name, t,
                            o->max_steps, h, h * s->r->omega_max, s->r->omega_max);
        if (t + 1.01 * h >= o->t_end) h = o->t_end - t;
        t1 = t + h >= o->t_end ? o->t_end : t + h;
        if (h <= 16.0 * DBL_EPSILON * fmax(1.0, t))
            return sim_fail(s, FSR_STEP_FAILED, "%s step size underflow at t = %.6g s (h = %.3g s)", T->name, t, h);
    } else {
        t1 = sim_time(s, s->k + 1);
    }
    if (!e->have_k0 && (st = sim_deriv(s, t, y, k))) return st;
    if ((st = erk_stages(s, T, t, t1, y, k, y1, ys))) return st;
    double h_next = h;
    if (adaptive) {
        double err = error_norm(s, T, t1 - t, k, y, y1);
        double fac11 = pow(err, 0.2 - 0.75 * PI_BETA);
        if (!(err <= 1.0)) {  /* rejected (also NaN): shrink, keep k[0] = f(t, y) */
            s->r->rejected_steps++;
            e->rejected = 1;
            e->h = h / fmin(1.0 / FAC_MIN, fac11 / SAFETY);
            return FSR_OK;
        }
        double fac = fmax(1.0 / FAC_MAX, fmin(1.0 / FAC_MIN, fac11 / pow(e->err_old, PI_BETA) / SAFETY));
        h_next = (t1 - t) / fac;
        if (e->rejected) h_next = fmin(h_next, t1 - t);
        e->err_old = fmax(err, 1e-4);
        e->rejected = 0;
    }
    const double* klast = k + (size_t)(T->stages - 1) * (size_t)m;
    dense_step d = {erk_dense, T, m, t, t1 - t, y, k};
    if ((st = sim_accept(s, t1, t1 - t, y1, T->fsal ? klast + s->n : NULL, adaptive ? &d : NULL)))
        return st;
    memcpy(y, y1, sizeof(double) * (size_t)m);
    if (T->fsal) memcpy(k, klast, sizeof(double) * (size_t)m);
    e->have_k0 = T->fsal;
    e->t = t1;
    e->h = h_next;
    ++s->k;
    s->done = adaptive ? !(t1 < o->t_end) : s->k >= s->msteps;
    return FSR_OK;
}


fsr_status erk_retune(sim* s)
{
    erk_state* e = s->ms;
    fsr_status st = sim_omega_max(s, s->work, &s->r->omega_max);
    if (!st && !e->adaptive) st = check_fixed_step(s, e->T);
    e->have_k0 = 0;  /* k[0] and the work space were overwritten */
    return st;
}

size_t erk_work_size(int n)
{
    return (size_t)(2 * MAX_STAGES + 4) * (size_t)n;
}

int erk_stability_limited(const fsr_options* o)
{
    (void)o;
    return 1;
}
