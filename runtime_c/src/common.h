/* What every run and every integrator of the runtime shares (common.c): the failure message,
 * the option defaults and checks, the generalized-alpha coefficients. Internal; calls nothing
 * of the runtime above linalg. */
#ifndef FLEXSYM_COMMON_H
#define FLEXSYM_COMMON_H

#include <math.h>
#include <stdarg.h>

#include "flexsym/runtime.h"
#include "flexsym/system.h"

/* r->message from fmt, r->status = st; returns st. */
fsr_status fsr_vfail(fsr_result* r, fsr_status st, const char* fmt, va_list ap);
fsr_status fsr_fail(fsr_result* r, fsr_status st, const char* fmt, ...);
/* Refuse a fixed step dt above a method's stability limit omega dt <= stability (FSR_OK within
 * it): one message for every method, `where` qualifies omega, `instead` is suggested. */
fsr_status fsr_check_step_limit(fsr_result* r, const char* name, double dt, double stability,
                                double omega, const char* where, const char* instead);

/* What every run checks: a finite o->y0 and the run-size limits of limits.h (r->ncols set): the
 * steps, and the rows when the run stores all of them (capacity 0; a stepper keeps one row, so
 * its length is bounded by the steps only). */
fsr_status fsr_check_run(const fsr_options* o, const fsm_system* m, fsr_result* r, long capacity);
/* The options of a run of M q'' = f by integrator `method` (rk4 ... radau5), with
 * fsr_check_run; FSR_OK or FSR_BAD_OPTIONS with the message in r. */
fsr_status fsr_check_ode_options(const fsr_options* o, const fsm_system* m, fsr_result* r, const char* method,
                                 long capacity);
/* The same for a constrained run (ali3p, genalpha3), and the kernels the model's sizes need. */
fsr_status fsr_check_constrained_options(const fsr_options* o, const fsm_system* m, fsr_result* r,
                                         const char* method, long capacity);

/* The model's length scale (system.h): p[length_param] when the model has one (a one-beam
 * model's L, so that it follows --param L=...), else length_scale. Newton tolerances
 * (newton_tol x it), the blow-up limit (blowup x it) and the violation column scale with it. */
double fsr_length_scale(const fsm_system* m, const double* p);

/* The model's band (system.h) for solvers of nst coupled stages whose unknowns interleave the
 * coordinates (coordinate r, stage i at r nst + i): the half-bandwidth nst (bandwidth + 1) - 1
 * of the unknowns [nst band_first, nst band_end) into *lo, *hi; -1 (dense) when the model has
 * none or the band would not be narrower than half its block. */
int fsr_band_layout(const fsm_system* m, int nst, int* lo, int* hi);

/* A factorization of `what` (A, n x n) that failed at t, dq the last Newton update before it
 * (0: none): the Newton iterations diverged when A holds a non-finite entry (a NaN pivot
 * reads as a vanishing one) or dq is beyond blowup x L (FSR_DIVERGED, reduce --dt: a diverging
 * iteration reaches a singular matrix where a converging one would not); else A is singular. */
fsr_status fsr_factor_failed(fsr_result* r, const fsr_options* o, double L, const double* A, int n,
                             double dq, double t, const char* what);

/* Coordinate i (value qi) is beyond limit = blowup x the length scale, and m->coord_unbounded
 * does not exempt it (inline: every step asks, for every coordinate). */
static inline int fsr_beyond_blowup(const fsm_system* m, double limit, int i, double qi)
{
    return fabs(qi) > limit && !(m->coord_unbounded && m->coord_unbounded[i]);
}
/* FSR_DIVERGED, the message naming coordinate i (value qi at t) and the limit. */
fsr_status fsr_blowup_fail(fsr_result* r, const fsm_system* m, const fsr_options* o, double limit, double t,
                           int i, double qi);

/* Generalized-alpha coefficients (Chung-Hulbert) from the spectral radius at infinity */
typedef struct { double am, af, gam, bet; } fsr_alpha;
fsr_alpha fsr_alpha_coefficients(double rho_inf);

/* max(m, |x|) for m >= 0 (libm's fmax is a call in strict C99). */
/* The steps of dt up to t_end (the last one shorter when dt does not divide t_end), at least 1 */
static inline long fsr_step_count(const fsr_options* o)
{
    long n = (long)ceil(o->t_end / o->dt - 1e-9);
    return n < 1 ? 1 : n;
}

/* t_k of a run of nsteps fixed steps: k dt, and exactly t_end from the last step on */
static inline double fsr_step_time(const fsr_options* o, long nsteps, long k)
{
    return k >= nsteps ? o->t_end : (double)k * o->dt;
}

/* The output row after step `row` with a row every out_every steps: the last step always gets
 * one, and after it there is none (nsteps + 1). From row 0 it is the first row. */
static inline long fsr_next_row(long row, int out_every, long nsteps)
{
    long next = row + out_every;
    return row == nsteps ? nsteps + 1 : (next < nsteps ? next : nsteps);
}

static inline double fsr_max_abs(double m, double x)
{
    x = fabs(x);
    return x > m ? x : m;
}

#endif
