/* Time integration of a generated model: explicit RK4, generalized-alpha and Newmark.
 *
 * Workspace is allocated once before the step loop; the loop itself never allocates.
 * Divergence (non-finite state, or a coordinate beyond blowup * L) stops the run with a
 * message naming the time; the rows stored up to then are kept.
 */
#include "flexsym/runtime.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flexsym/model.h"
#include "linalg.h"

typedef struct {
    const fsm_model_info* m;
    const fsr_options* o;
    fsr_result* r;
    int n;
    double L;
    double* Mraw;  /* mass matrix as evaluated */
    double* Mfac;  /* its Cholesky factor */
    double* S;     /* Newton iteration matrix, LU-factored */
    double* Jq;
    double* Jv;
    double* y;
    double* qdd;   /* accelerations for outputs that need them */
    int* piv;
    int mass_ready;
    long capacity; /* rows */
} sim;

void fsr_default_options(fsr_options* o)
{
    memset(o, 0, sizeof *o);
    o->method = FSR_GENALPHA;
    o->t_end = 20.0;
    o->dt = 1e-3;
    o->out_every = 1;
    o->rho_inf = 0.9;
    o->nm_gamma = 0.5;
    o->nm_beta = 0.25;
    o->newton_tol = 1e-12;
    o->newton_max = 25;
    o->blowup = 10.0;
}

const char* fsr_method_name(fsr_method m)
{
    switch (m) {
    case FSR_RK4: return "rk4";
    case FSR_GENALPHA: return "genalpha";
    case FSR_NEWMARK: return "newmark";
    }
    return "?";
}

static fsr_status fail(sim* s, fsr_status st, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(s->r->message, sizeof s->r->message, fmt, ap);
    va_end(ap);
    s->r->status = st;
    return st;
}

static void drive_at(const sim* s, double t, double* drive)
{
    double d3[3];
    fsm_maneuver(&t, s->o->mp, d3);
    drive[0] = d3[1];
    drive[1] = d3[2];
}

/* Evaluate (and factor) M(q) unless it is constant and already done. */
static fsr_status mass_at(sim* s, double t, const double* q)
{
    int n = s->n;
    if (s->m->mass_constant && s->mass_ready) return FSR_OK;
    fsm_mass(q, s->o->p, s->Mraw);
    memcpy(s->Mfac, s->Mraw, sizeof(double) * (size_t)(n * n));
    int k = fsr_chol_factor(s->Mfac, n);
    if (k) return fail(s, FSR_SINGULAR, "mass matrix not positive definite at t = %.6g s (pivot %d, %s)",
                       t, k, s->m->coord_names[k - 1]);
    s->mass_ready = 1;
    return FSR_OK;
}

static fsr_status accel(sim* s, double t, const double* q, const double* v, double* a)
{
    double drive[2];
    fsr_status st = mass_at(s, t, q);
    if (st) return st;
    drive_at(s, t, drive);
    fsm_force(q, v, drive, s->o->p, a);
    s->r->force_evaluations++;
    fsr_chol_solve(s->Mfac, s->n, a);
    return FSR_OK;
}

static fsr_status check_state(sim* s, double t, const double* q, const double* v)
{
    double limit = s->o->blowup * s->L;
    for (int i = 0; i < s->n; ++i) {
        if (!isfinite(q[i]) || !isfinite(v[i]))
            return fail(s, FSR_DIVERGED, "diverged at t = %.6g s: %s is not finite",
                        t, s->m->coord_names[i]);
        if (fabs(q[i]) > limit)
            return fail(s, FSR_DIVERGED,
                        "diverged at t = %.6g s: |%s| = %.5g m exceeds %g x L = %.4g m (runaway growth)",
                        t, s->m->coord_names[i], fabs(q[i]), s->o->blowup, limit);
    }
    return FSR_OK;
}

/* Append a row: t, outputs, q. Outputs that read q'' get it from M(q) q'' = f. */
static fsr_status store(sim* s, double t, const double* q, const double* v)
{
    fsr_result* r = s->r;
    if (r->nrows >= s->capacity) return FSR_OK;
    double* row = r->rows + (size_t)r->nrows * (size_t)r->ncols;
    double drive[2];
    drive_at(s, t, drive);
    if (s->m->outputs_use_acceleration) {
        fsr_status st = accel(s, t, q, v, s->qdd);
        if (st) return st;
    }
    row[0] = t;
    fsm_outputs(q, v, s->qdd, drive, s->o->p, s->y);
    memcpy(row + 1, s->y, sizeof(double) * (size_t)s->m->ny);
    memcpy(row + 1 + s->m->ny, q, sizeof(double) * (size_t)s->n);
    r->nrows++;
    return FSR_OK;
}

static double time_of(const fsr_options* o, long k, long nsteps)
{
    return k == nsteps ? o->t_end : (double)k * o->dt;
}

static fsr_status run_rk4(sim* s, double* q, double* v, long nsteps, double* w)
{
    int n = s->n;
    double *q2 = w, *v2 = w + n, *a1 = w + 2 * n, *a2 = w + 3 * n, *a3 = w + 4 * n, *a4 = w + 5 * n;
    double *v3 = w + 6 * n, *v4 = w + 7 * n;
    fsr_status st;
    for (long k = 0; k < nsteps; ++k) {
        double t = time_of(s->o, k, nsteps), h = time_of(s->o, k + 1, nsteps) - t;
        if ((st = accel(s, t, q, v, a1))) return st;
        for (int i = 0; i < n; ++i) { q2[i] = q[i] + 0.5 * h * v[i]; v2[i] = v[i] + 0.5 * h * a1[i]; }
        if ((st = accel(s, t + 0.5 * h, q2, v2, a2))) return st;
        for (int i = 0; i < n; ++i) { q2[i] = q[i] + 0.5 * h * v2[i]; v3[i] = v[i] + 0.5 * h * a2[i]; }
        if ((st = accel(s, t + 0.5 * h, q2, v3, a3))) return st;
        for (int i = 0; i < n; ++i) { q2[i] = q[i] + h * v3[i]; v4[i] = v[i] + h * a3[i]; }
        if ((st = accel(s, t + h, q2, v4, a4))) return st;
        for (int i = 0; i < n; ++i) {
            q[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            v[i] += h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i]);
        }
        if ((st = check_state(s, t + h, q, v))) return st;
        s->r->steps++;
        s->r->t_stop = t + h;
        if (((k + 1) % s->o->out_every == 0 || k + 1 == nsteps) && (st = store(s, t + h, q, v))) return st;
    }
    return FSR_OK;
}

/* Generalized-alpha (Chung & Hulbert; Arnold & Bruls form for M(q) q'' = f) with Newton
 * iterations on the acceleration. Newmark(gamma, beta) is the special case am = af = 0. */
static fsr_status run_alpha(sim* s, double* q, double* v, long nsteps, double* w)
{
    const fsr_options* o = s->o;
    int n = s->n;
    double am, af, gam, bet;
    if (o->method == FSR_NEWMARK) {
        am = af = 0.0;
        gam = o->nm_gamma;
        bet = o->nm_beta;
    } else {
        double r = o->rho_inf;
        am = (2.0 * r - 1.0) / (r + 1.0);
        af = r / (r + 1.0);
        gam = 0.5 + af - am;
        bet = 0.25 * (gam + 0.5) * (gam + 0.5);
    }
    double *a = w, *ab = w + n, *an = w + 2 * n, *abn = w + 3 * n, *q1 = w + 4 * n, *v1 = w + 5 * n;
    double *qp = w + 6 * n, *vp = w + 7 * n, *res = w + 8 * n, *abp = w + 9 * n;
    double drive[2];
    fsr_status st;
    if ((st = accel(s, 0.0, q, v, a))) return st;
    memcpy(ab, a, sizeof(double) * (size_t)n);
    double tol = o->newton_tol * s->L;
    for (long k = 0; k < nsteps; ++k) {
        double t = time_of(o, k, nsteps), h = time_of(o, k + 1, nsteps) - t, t1 = t + h;
        double cb = h * h * bet * (1.0 - af) / (1.0 - am), cg = h * gam * (1.0 - af) / (1.0 - am);
        for (int i = 0; i < n; ++i) {
            qp[i] = q[i] + h * v[i] + h * h * (0.5 - bet) * ab[i];
            vp[i] = v[i] + h * (1.0 - gam) * ab[i];
            abp[i] = (af * a[i] - am * ab[i]) / (1.0 - am);
            an[i] = a[i];
        }
        drive_at(s, t1, drive);
        int it = 0, converged = 0;
        double dq = 0.0;
        while (!converged) {
            for (int i = 0; i < n; ++i) {
                abn[i] = abp[i] + (1.0 - af) / (1.0 - am) * an[i];
                q1[i] = qp[i] + h * h * bet * abn[i];
                v1[i] = vp[i] + h * gam * abn[i];
            }
            if (it == o->newton_max)
                return fail(s, FSR_NEWTON_FAILED,
                            "Newton iterations did not converge at t = %.6g s (|dq| = %.3g m after %d "
                            "iterations); reduce --dt", t1, dq, it);
            if ((st = mass_at(s, t1, q1))) return st;
            fsm_force(q1, v1, drive, o->p, res);
            s->r->force_evaluations++;
            for (int i = 0; i < n; ++i) {
                double acc = -res[i];
                for (int j = 0; j < n; ++j) acc += s->Mraw[i * n + j] * an[j];
                res[i] = -acc;
            }
            fsm_residual_jac(q1, v1, an, drive, o->p, s->Jq, s->Jv);
            for (int i = 0; i < n * n; ++i) s->S[i] = s->Mraw[i] + cb * s->Jq[i] + cg * s->Jv[i];
            int bw = s->m->bandwidth, banded = bw >= 0 && 2 * bw + 1 < n;
            int bad = banded ? fsr_band_lu_factor(s->S, n, bw, bw, s->piv) : fsr_lu_factor(s->S, n, s->piv);
            if (bad) return fail(s, FSR_SINGULAR, "Newton matrix singular at t = %.6g s", t1);
            if (banded) fsr_band_lu_solve(s->S, n, bw, bw, s->piv, res);
            else fsr_lu_solve(s->S, n, s->piv, res);
            dq = 0.0;
            for (int i = 0; i < n; ++i) {
                an[i] += res[i];
                if (!isfinite(an[i])) return check_state(s, t1, an, an);
                double d = fabs(cb * res[i]);
                if (d > dq) dq = d;
            }
            ++it;
            s->r->newton_iterations++;
            converged = dq <= tol;
        }
        for (int i = 0; i < n; ++i) {
            abn[i] = abp[i] + (1.0 - af) / (1.0 - am) * an[i];
            q[i] = qp[i] + h * h * bet * abn[i];
            v[i] = vp[i] + h * gam * abn[i];
            a[i] = an[i];
            ab[i] = abn[i];
        }
        if ((st = check_state(s, t1, q, v))) return st;
        s->r->steps++;
        s->r->t_stop = t1;
        if (((k + 1) % o->out_every == 0 || k + 1 == nsteps) && (st = store(s, t1, q, v))) return st;
    }
    return FSR_OK;
}

static fsr_status check_options(sim* s)
{
    const fsr_options* o = s->o;
    if (!(o->dt > 0.0) || !isfinite(o->dt)) return fail(s, FSR_BAD_OPTIONS, "dt must be > 0 (got %g)", o->dt);
    if (!(o->t_end > 0.0) || !isfinite(o->t_end))
        return fail(s, FSR_BAD_OPTIONS, "t_end must be > 0 (got %g)", o->t_end);
    if (o->out_every < 1) return fail(s, FSR_BAD_OPTIONS, "out_every must be >= 1 (got %d)", o->out_every);
    if (!(o->rho_inf >= 0.0 && o->rho_inf <= 1.0))
        return fail(s, FSR_BAD_OPTIONS, "rho_inf must be in [0, 1] (got %g)", o->rho_inf);
    if (o->method == FSR_NEWMARK && !(o->nm_gamma >= 0.5 && o->nm_beta >= 0.25 * (0.5 + o->nm_gamma) * (0.5 + o->nm_gamma) - 1e-15))
        return fail(s, FSR_BAD_OPTIONS,
                    "Newmark gamma = %g, beta = %g is not unconditionally stable (need gamma >= 1/2, "
                    "beta >= (gamma + 1/2)^2 / 4)", o->nm_gamma, o->nm_beta);
    if (o->newton_max < 1 || !(o->newton_tol > 0.0))
        return fail(s, FSR_BAD_OPTIONS, "newton_max must be >= 1 and newton_tol > 0");
    if (!(o->blowup > 0.0)) return fail(s, FSR_BAD_OPTIONS, "blowup must be > 0");
    for (int i = 0; i < s->m->np; ++i)
        if (!(o->p[i] > 0.0) || !isfinite(o->p[i]))
            return fail(s, FSR_BAD_OPTIONS, "beam parameter %s must be a positive number (got %g)",
                        s->m->param_names[i], o->p[i]);
    for (int i = 0; i < s->m->nmp; ++i)
        if (!isfinite(o->mp[i]))
            return fail(s, FSR_BAD_OPTIONS, "manoeuvre parameter %s must be finite",
                        s->m->maneuver_param_names[i]);
    return FSR_OK;
}

fsr_status fsr_simulate(const fsr_options* o, fsr_result* r)
{
    const fsm_model_info* m = fsm_model();
    sim s;
    memset(&s, 0, sizeof s);
    memset(r, 0, sizeof *r);
    s.m = m;
    s.o = o;
    s.r = r;
    s.n = m->nq;
    r->ncols = 1 + m->ny + m->nq;
    fsr_status st = check_options(&s);
    if (st) return st;
    s.L = o->p[m->length_param];
    long nsteps = (long)ceil(o->t_end / o->dt - 1e-9);
    if (nsteps < 1) nsteps = 1;
    int n = s.n;
    s.capacity = nsteps / o->out_every + 2;
    r->rows = malloc(sizeof(double) * (size_t)s.capacity * (size_t)r->ncols);
    double* mem = malloc(sizeof(double) * (size_t)(5 * n * n + 13 * n + m->ny));
    s.piv = malloc(sizeof(int) * (size_t)n);
    if (!r->rows || !mem || !s.piv) {
        free(mem);
        free(s.piv);
        return fail(&s, FSR_NO_MEMORY, "out of memory for %ld output rows", s.capacity);
    }
    s.Mraw = mem;
    s.Mfac = mem + n * n;
    s.S = mem + 2 * n * n;
    s.Jq = mem + 3 * n * n;
    s.Jv = mem + 4 * n * n;
    s.y = mem + 5 * n * n;
    s.qdd = s.y + m->ny;
    double* q = s.qdd + n;
    double* v = q + n;
    double* work = v + n;
    memset(s.qdd, 0, sizeof(double) * (size_t)(3 * n));
    st = store(&s, 0.0, q, v);
    if (!st) st = o->method == FSR_RK4 ? run_rk4(&s, q, v, nsteps, work) : run_alpha(&s, q, v, nsteps, work);
    free(mem);
    free(s.piv);
    r->status = st;
    return st;
}

void fsr_free(fsr_result* r)
{
    free(r->rows);
    r->rows = NULL;
    r->nrows = 0;
}
