/* Shared by every run and integrator (common.h): the failure message, the option defaults and
 * the checks made once before a run starts, the generalized-alpha coefficients. */
#include "common.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "flexsym/limits.h"

void fsr_default_options(fsr_options* o)
{
    memset(o, 0, sizeof *o);
    o->method = FSR_GENALPHA;
    o->t_end = FSR_DEFAULT_T_END;
    o->dt = FSR_DEFAULT_DT;
    o->out_every = 1;
    o->rho_inf = FSR_DEFAULT_RHO_INF;
    o->nm_gamma = FSR_DEFAULT_NEWMARK_GAMMA;
    o->nm_beta = FSR_DEFAULT_NEWMARK_BETA;
    o->newton_tol = FSR_DEFAULT_NEWTON_TOL;
    o->newton_max = 25;
    o->tol = FSR_DEFAULT_TOL;
    o->max_steps = FSR_DEFAULT_MAX_STEPS;
    o->blowup = FSR_DEFAULT_BLOWUP;
    o->penalty = FSR_DEFAULT_PENALTY;
}

fsr_status fsr_vfail(fsr_result* r, fsr_status st, const char* fmt, va_list ap)
{
    vsnprintf(r->message, sizeof r->message, fmt, ap);
    r->status = st;
    return st;
}

fsr_status fsr_fail(fsr_result* r, fsr_status st, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fsr_vfail(r, st, fmt, ap);
    va_end(ap);
    return st;
}

fsr_status fsr_check_step_limit(fsr_result* r, const char* name, double dt, double stability,
                                double omega, const char* where, const char* instead)
{
    double limit = stability / omega;
    if (!(dt > limit)) return FSR_OK;
    int e = (int)floor(log10(limit));
    double mant = floor(limit / pow(10.0, e) * 10.0) / 10.0;
    return fsr_fail(r, FSR_UNSTABLE_STEP,
                    "%s step %g ms exceeds the stability limit %.3g ms of this model (omega_max = %.1f "
                    "rad/s%s); use --dt <= %.1fe%d or %s", name, dt * 1e3, limit * 1e3, omega, where,
                    mant, e, instead);
}

fsr_status fsr_factor_failed(fsr_result* r, const fsr_options* o, double L, const double* A, int n,
                             double dq, double t, const char* what)
{
    for (size_t k = 0; k < (size_t)n * (size_t)n; ++k)
        if (!isfinite(A[k]))
            return fsr_fail(r, FSR_DIVERGED, "%s not finite at t = %.6g s: the Newton iterations "
                            "diverged; reduce --dt", what, t);
    if (dq > o->blowup * L)
        return fsr_fail(r, FSR_DIVERGED, "%s singular at t = %.6g s after a Newton update of %.3g, "
                        "beyond %g x L = %.4g m: the iterations diverged; reduce --dt", what, t, dq,
                        o->blowup, o->blowup * L);
    return fsr_fail(r, FSR_SINGULAR, "%s singular at t = %.6g s", what, t);
}

int fsr_band_layout(const fsm_system* m, int nst, int* lo, int* hi)
{
    int bordered = m->band_end > m->band_first;
    *lo = nst * (bordered ? m->band_first : 0);
    *hi = nst * (bordered ? m->band_end : m->nq);
    int kb = nst * (m->bandwidth + 1) - 1;
    return m->bandwidth >= 0 && 2 * kb + 1 < *hi - *lo ? kb : -1;
}

double fsr_length_scale(const fsm_system* m, const double* p)
{
    return m->length_param >= 0 ? p[m->length_param] : m->length_scale;
}

fsr_status fsr_blowup_fail(fsr_result* r, const fsm_system* m, const fsr_options* o, double limit, double t,
                           int i, double qi)
{
    return fsr_fail(r, FSR_DIVERGED, "diverged at t = %.6g s: |%s| = %.5g m exceeds %g x L = %.4g m (runaway growth)",
                    t, m->coord_names[i], fabs(qi), o->blowup, limit);
}

fsr_alpha fsr_alpha_coefficients(double rho_inf)
{
    fsr_alpha c;
    c.am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
    c.af = rho_inf / (rho_inf + 1.0);
    c.gam = 0.5 + c.af - c.am;
    c.bet = 0.25 * (c.gam + 0.5) * (c.gam + 0.5);
    return c;
}

/* Counts are checked as doubles before any conversion to long (no overflow, no UB). */
fsr_status fsr_check_run(const fsr_options* o, const fsm_system* m, fsr_result* r, long capacity)
{
    const int n = m->nq;
    for (int i = 0; o->y0 && i < 2 * n; ++i)
        if (!isfinite(o->y0[i]))
            return fsr_fail(r, FSR_BAD_OPTIONS, "initial %s of %s is not finite", i < n ? "value" : "rate",
                            m->coord_names[i % n]);
    double grid = o->t_end / o->dt, radau = o->step > 0.0 ? o->t_end / o->step : grid;
    if (!(grid <= (double)FSR_MAX_STEPS) || !(radau <= (double)FSR_MAX_STEPS))
        return fsr_fail(r, FSR_BAD_OPTIONS, "t_end / dt = %.3g steps exceeds the limit of %ld",
                        grid > radau ? grid : radau, FSR_MAX_STEPS);
    if (o->max_steps > FSR_MAX_STEPS)
        return fsr_fail(r, FSR_BAD_OPTIONS, "max_steps %ld exceeds the limit of %ld", o->max_steps, FSR_MAX_STEPS);
    double rows = capacity > 0 ? (double)capacity : floor(grid / o->out_every) + 2.0;
    if (rows > (double)FSR_MAX_ROWS || rows * r->ncols * 8.0 > (double)FSR_MAX_ROW_BYTES)
        return fsr_fail(r, FSR_BAD_OPTIONS, "%.3g output rows of %d columns exceed the limits (%ld rows, "
                        "%ld bytes)", rows, r->ncols, FSR_MAX_ROWS, FSR_MAX_ROW_BYTES);
    return FSR_OK;
}

static fsr_status check_length_scale(const fsr_options* o, const fsm_system* m, fsr_result* r)
{
    double L = fsr_length_scale(m, o->p);
    if (!(L > 0.0) || !isfinite(L))
        return fsr_fail(r, FSR_BAD_OPTIONS, "model %s: the length scale must be > 0 (got %g)", m->name, L);
    return FSR_OK;
}

/* The options every run checks: step, end, rows, rho_inf, Newton, blow-up limit. */
static fsr_status check_steps(const fsr_options* o, fsr_result* r)
{
    if (!(o->dt > 0.0) || !isfinite(o->dt)) return fsr_fail(r, FSR_BAD_OPTIONS, "dt must be > 0 (got %g)", o->dt);
    if (!(o->t_end > 0.0) || !isfinite(o->t_end))
        return fsr_fail(r, FSR_BAD_OPTIONS, "t_end must be > 0 (got %g)", o->t_end);
    if (o->out_every < 1) return fsr_fail(r, FSR_BAD_OPTIONS, "out_every must be >= 1 (got %d)", o->out_every);
    if (!(o->rho_inf >= 0.0 && o->rho_inf <= 1.0))
        return fsr_fail(r, FSR_BAD_OPTIONS, "rho_inf must be in [0, 1] (got %g)", o->rho_inf);
    if (o->newton_max < 1 || !(o->newton_tol > 0.0))
        return fsr_fail(r, FSR_BAD_OPTIONS, "newton_max must be >= 1 and newton_tol > 0");
    if (!(o->blowup > 0.0)) return fsr_fail(r, FSR_BAD_OPTIONS, "blowup must be > 0");
    return FSR_OK;
}

fsr_status fsr_check_ode_options(const fsr_options* o, const fsm_system* m, fsr_result* r, const char* method,
                                 long capacity)
{
    if (check_steps(o, r)) return r->status;
    if (o->method == FSR_NEWMARK && !(o->nm_gamma >= 0.5 && o->nm_beta > 0.0))
        return fsr_fail(r, FSR_BAD_OPTIONS, "Newmark gamma = %g, beta = %g: need gamma >= 1/2 and beta > 0 "
                        "(beta < gamma / 2: stable for omega_max dt <= 1 / sqrt(gamma / 2 - beta))",
                        o->nm_gamma, o->nm_beta);
    if (!(o->tol >= 0.0 && o->tol < 1.0))
        return fsr_fail(r, FSR_BAD_OPTIONS, "tol must be in [0, 1) (got %g; 0 = fixed steps)", o->tol);
    if (o->max_steps < 1) return fsr_fail(r, FSR_BAD_OPTIONS, "max_steps must be >= 1 (got %ld)", o->max_steps);
    if (!(o->step >= 0.0) || !isfinite(o->step))
        return fsr_fail(r, FSR_BAD_OPTIONS, "step must be >= 0 (got %g; 0 = steps of dt)", o->step);
    if (o->step > 0.0 && o->method != FSR_RADAU5)
        return fsr_fail(r, FSR_BAD_OPTIONS, "step is for radau5 (%s steps at dt)", method);
    if (fsr_check_run(o, m, r, capacity)) return r->status;
    for (int i = 0; i < m->np; ++i)
        if (!(o->p[i] > 0.0) || !isfinite(o->p[i]))
            return fsr_fail(r, FSR_BAD_OPTIONS, "beam parameter %s must be a positive number (got %g)",
                            m->param_names[i], o->p[i]);
    for (int i = 0; i < m->nmp; ++i)
        if (!isfinite(o->mp[i]))
            return fsr_fail(r, FSR_BAD_OPTIONS, "manoeuvre parameter %s must be finite",
                            m->drive_param_names[i]);
    return check_length_scale(o, m, r);
}

fsr_status fsr_check_constrained_options(const fsr_options* o, const fsm_system* m, fsr_result* r,
                                         const char* method, long capacity)
{
    if (check_steps(o, r)) return r->status;
    if (!(o->penalty > 0.0) || !isfinite(o->penalty))
        return fsr_fail(r, FSR_BAD_OPTIONS, "penalty must be > 0 (got %g)", o->penalty);
    if (o->step != 0.0) return fsr_fail(r, FSR_BAD_OPTIONS, "step is for radau5 (%s steps at dt)", method);
    if (fsr_check_run(o, m, r, capacity)) return r->status;
    if (!m->drive || !m->mass || !m->force || !m->residual_jac || !m->outputs
        || (m->nc > 0 && (!m->constraints || !m->constraint_jac || !m->constraint_rate
                          || !m->constraint_acc || !m->constraint_names)))
        return fsr_fail(r, FSR_BAD_OPTIONS, "model %s lacks a kernel its sizes need (system.h)", m->name);
    if (o->energy && !m->energy)
        return fsr_fail(r, FSR_BAD_OPTIONS, "model %s has no energy kernel", m->name);
    for (int i = 0; i < m->np; ++i)
        if (!isfinite(o->p[i]))
            return fsr_fail(r, FSR_BAD_OPTIONS, "parameter %s must be finite", m->param_names[i]);
    for (int i = 0; i < m->nmp; ++i)
        if (!isfinite(o->mp[i]))
            return fsr_fail(r, FSR_BAD_OPTIONS, "drive parameter %s must be finite", m->drive_param_names[i]);
    return check_length_scale(o, m, r);
}
