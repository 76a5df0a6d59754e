/* A run of M(q) q'' = f (ode.h): workspace, drive, mass matrix, divergence checks, rows. */
#include "ode.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linalg.h"

fsr_status sim_fail(sim* s, fsr_status st, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fsr_vfail(s->r, st, fmt, ap);
    va_end(ap);
    return st;
}

/* The drive vector d (nd) at t into d. The last two times are cached: RK stages and output
 * rows ask for the same time repeatedly, and the manoeuvre costs a sin and a cos. */
void sim_drive(sim* s, double t, double* d)
{
    if (s->drive_held) {  /* one guided joint (nd = 4, checked by fsr_stepper_new) */
        double tau = t - s->hold_t;
        d[0] = t;
        d[1] = s->hold_theta + tau * (s->hold[0] + 0.5 * s->hold[1] * tau);
        d[2] = s->hold[0] + s->hold[1] * (t - s->hold_t);
        d[3] = s->hold[1];
        return;
    }
    const int nd = s->nd;  /* a loop, not memcpy: a call to it cost 4-10 % on #3 and prestress */
    for (int i = 0; i < 2; ++i)
        if (s->drive_valid[i] && s->drive_t[i] == t) {
            for (int j = 0; j < nd; ++j) d[j] = s->drive_v[i][j];
            return;
        }
    int k = s->drive_next;
    s->drive_next = 1 - k;
    s->drive_valid[k] = 1;
    s->drive_t[k] = t;
    s->m->drive(&t, s->o->mp, s->drive_v[k]);
    for (int j = 0; j < nd; ++j) d[j] = s->drive_v[k][j];
}

/* M^-1 b in place with the factor in Mfac. */
static void mass_solve(const sim* s, double* b)
{
    if (s->mass_lu) fsr_lu_solve(s->Mfac, s->n, s->mpiv, b);
    else fsr_chol_solve(s->Mfac, s->n, b);
}

/* M(q, d) into Mraw and, with factor, its Cholesky (or, not symmetric, LU) factor into Mfac;
 * once when M is constant. */
fsr_status sim_mass(sim* s, double t, const double* q, const double* d, int factor)
{
    int n = s->n, constant = s->m->mass_constant;
    if (!constant || !s->mass_have) {
        s->m->mass(q, d, s->o->p, s->Mraw);
        s->mass_have = 1;
        s->mass_factored = 0;
    }
    if (!factor || (constant && s->mass_factored)) return FSR_OK;
    memcpy(s->Mfac, s->Mraw, sizeof(double) * (size_t)n * (size_t)n);
    s->mass_lu = !fsr_symmetric(s->Mraw, n);
    int k = s->mass_lu ? fsr_lu_factor(s->Mfac, n, s->mpiv) : fsr_chol_factor(s->Mfac, n);
    if (k) return sim_fail(s, FSR_SINGULAR, "mass matrix %s at t = %.6g s (pivot %d, %s)",
                           s->mass_lu ? "singular" : "not positive definite", t, k,
                           s->m->coord_names[k - 1]);
    if (constant && s->bw < 0) {
        if (s->mass_lu) fsr_lu_inverse(s->Mfac, n, s->mpiv, s->Minv, s->tmp);
        else fsr_chol_inverse(s->Mfac, n, s->Minv, s->tmp);
    }
    s->mass_factored = 1;
    return FSR_OK;
}

/* x = A^-1 x by the explicit inverse of a dense A of size dim. */
fsr_status sim_accel(sim* s, double t, const double* q, const double* v, double* a)
{
    double* drive = s->dw + DW_ACCEL * s->nd;
    sim_drive(s, t, drive);
    fsr_status st = sim_mass(s, t, q, drive, 1);
    if (st) return st;
    s->m->force(q, v, drive, s->o->p, a);
    s->r->force_evaluations++;
    if (s->m->mass_constant && s->bw < 0) sim_apply_inverse(s, s->Minv, s->n, a);
    else mass_solve(s, a);
    return FSR_OK;
}

fsr_status sim_residual(sim* s, double t, const double* q, const double* v, const double* a,
                        const double* d, double* res, double* ma)
{
    const int n = s->n;
    s->r->force_evaluations++;
    if (s->m->residual) {
        s->m->residual(q, v, a, d, s->o->p, res);
        for (int i = 0; i < n; ++i) res[i] = -res[i];
        return FSR_OK;
    }
    fsr_status st = sim_mass(s, t, q, d, 0);
    if (st) return st;
    s->m->force(q, v, d, s->o->p, res);
    fsr_matvec(s->Mraw, n, s->bw, a, ma);
    for (int i = 0; i < n; ++i) res[i] -= ma[i];
    return FSR_OK;
}

/* k = y' = [q', q''] at (t, y). */
fsr_status sim_deriv(sim* s, double t, const double* y, double* k)
{
    memcpy(k, y + s->n, sizeof(double) * (size_t)s->n);
    return sim_accel(s, t, y, y + s->n, k + s->n);
}

fsr_status sim_check_state(sim* s, double t, const double* q, const double* v)
{
    double limit = s->o->blowup * s->L;
    for (int i = 0; i < s->n; ++i) {
        if (!isfinite(q[i]) || !isfinite(v[i]))
            return sim_fail(s, FSR_DIVERGED, "diverged at t = %.6g s: %s is not finite",
                            t, s->m->coord_names[i]);
        if (fsr_beyond_blowup(s->m, limit, i, q[i])) return fsr_blowup_fail(s->r, s->m, s->o, limit, t, i, q[i]);
    }
    return FSR_OK;
}

/* Append a row: t, outputs, q. Outputs that read q'' get a when given, else M(q) q'' = f.
 * The drive only when something reads it: rows between steps would pay a sin and a cos. */
fsr_status sim_store(sim* s, double t, const double* q, const double* v, const double* a)
{
    fsr_result* r = s->r;
    if (r->nrows >= s->capacity) return FSR_OK;
    double* row = r->rows + (size_t)r->nrows * (size_t)r->ncols;
    double* drive = s->dw + DW_ROW * s->nd;  /* zeros unless something reads it */
    const double* qdd = s->qdd;
    if (s->m->outputs_use_drive || s->o->energy) sim_drive(s, t, drive);
    if (s->m->outputs_use_acceleration) {
        if (a) qdd = a;
        else {
            fsr_status st = sim_accel(s, t, q, v, s->qdd);
            if (st) return st;
        }
    }
    row[0] = t;
    s->m->outputs(q, v, qdd, s->zero, drive, s->o->p, s->y);  /* no multipliers: nc = 0 */
    memcpy(row + 1, s->y, sizeof(double) * (size_t)s->m->ny);
    memcpy(row + 1 + s->m->ny, q, sizeof(double) * (size_t)s->n);
    if (s->o->energy) s->m->energy(q, v, drive, s->o->p, row + 1 + s->m->ny + s->n);
    r->nrows++;
    return FSR_OK;
}

/* Write the rows due in (t, t1]: the state (y1, a1) at t1, or the dense output of step d
 * between grid points (only adaptive or radau5 --step steps fall between them). */
static fsr_status emit_rows(sim* s, double t1, const double* y1, const double* a1, const dense_step* d)
{
    int n = s->n;
    while (s->next_row <= s->nsteps) {
        double tr = sim_time(s, s->next_row);
        if (tr > t1) break;
        fsr_status st;
        if (tr == t1 || !d) st = sim_store(s, t1, y1, y1 + n, a1);
        else {
            double* ys = s->dense;
            d->at(d, (tr - d->t) / d->h, y1, ys);
            st = sim_store(s, tr, ys, ys + n, NULL);
        }
        if (st) return st;
        s->next_row = fsr_next_row(s->next_row, s->o->out_every, s->nsteps);
    }
    return FSR_OK;
}

/* Bookkeeping of an accepted step of length h ending at t1 with state y1. */
fsr_status sim_accept(sim* s, double t1, double h, const double* y1, const double* a1, const dense_step* d)
{
    fsr_status st = sim_check_state(s, t1, y1, y1 + s->n);
    if (st) return st;
    fsr_result* r = s->r;
    if (r->steps == 0 || h < r->h_min) r->h_min = h;
    if (h > r->h_max) r->h_max = h;
    r->steps++;
    r->t_stop = t1;
    return emit_rows(s, t1, y1, a1, d);
}

fsr_status sim_open(sim* s, const fsr_integrator* it, const fsm_system* m, const fsr_options* o, fsr_result* r,
                    long capacity)
{
    const char* name = fsr_method_name(o->method);
    memset(s, 0, sizeof *s);
    memset(r, 0, sizeof *r);
    s->m = m;
    s->o = o;
    s->r = r;
    s->n = m->nq;
    r->ncols = 1 + m->ny + m->nq + (o->energy ? 3 : 0);
    fsr_status st = fsr_check_ode_options(o, m, r, name, capacity);
    if (!st && m->nc > 0)
        st = sim_fail(s, FSR_BAD_OPTIONS, "%s: this model has %d constraint equations: use ali3p, genalpha3 or rk4p",
                      name, m->nc);
    if (st) return st;
    int n = s->n;
    s->nd = m->nd;
    s->L = fsr_length_scale(m, o->p);
    int lo, hi;  /* M's band: only without a border (a bordered M is treated as dense) */
    s->bw = fsr_band_layout(m, 1, &lo, &hi) >= 0 && lo == 0 && hi == n ? m->bandwidth : -1;
    s->nsteps = fsr_step_count(o);
    s->msteps = s->nsteps;
    s->next_row = fsr_next_row(0, o->out_every, s->nsteps);
    s->capacity = capacity > 0 ? capacity : s->nsteps / o->out_every + 2;
    /* the Newton system: nst stages of n coordinates, interleaved (see newton.h) */
    s->nst = it->stages;
    s->N = s->nst * n;
    s->kb = fsr_band_layout(m, s->nst, &lo, &hi);
    int border = s->kb >= 0 ? s->N - (hi - lo) : 0;
    size_t nn = (size_t)n * (size_t)n, NN = (size_t)s->N * (size_t)s->N;
    size_t work = 2 * (size_t)n + it->work_size(n);  /* 2n: dense, then the integrator's */
    r->rows = malloc(sizeof(double) * (size_t)s->capacity * (size_t)r->ncols);
    size_t base = 5 * nn + 2 * NN + (size_t)m->ny + (size_t)s->N + 4 * (size_t)n + work
                  + FSR_BORDERED_DOUBLES(border, hi - lo);
    size_t drives = (size_t)(DW_COUNT + 2) * (size_t)m->nd;  /* after the rest, at mem + base */
    double* mem = malloc(sizeof(double) * (base + drives));
    s->piv = malloc(sizeof(int) * ((size_t)(s->N + n) + FSR_BORDERED_INTS(border)));
    s->ms = it->state_size ? calloc(1, it->state_size) : NULL;
    if (!r->rows || !mem || !s->piv || (it->state_size && !s->ms)) {
        free(mem);
        free(s->piv);
        free(s->ms);
        s->piv = NULL;
        s->ms = NULL;
        return sim_fail(s, FSR_NO_MEMORY, "out of memory for %ld output rows", s->capacity);
    }
    s->mpiv = s->piv + s->N;
    s->mass_lu = 0;
    s->Mraw = mem;
    s->Mfac = mem + nn;
    s->Jq = mem + 2 * nn;
    s->Jv = mem + 3 * nn;
    s->Minv = mem + 4 * nn;
    s->S = mem + 5 * nn;
    s->Sinv = s->S + NN;
    s->y = s->Sinv + NN;
    s->tmp = s->y + m->ny;
    s->qdd = s->tmp + s->N;
    s->zero = s->qdd + n;
    s->state = s->zero + n;  /* [q, q'] */
    s->dense = s->state + 2 * n;
    s->work = s->dense + 2 * n;
    if (s->kb >= 0)
        fsr_bordered_init(&s->band, s->N, s->kb, lo, hi, s->work + work - 2 * (size_t)n, s->piv + s->N + n);
    s->dw = mem + base;
    s->drive_v[0] = s->dw + DW_COUNT * m->nd;
    s->drive_v[1] = s->drive_v[0] + m->nd;
    memset(s->dw, 0, sizeof(double) * drives);
    memset(s->qdd, 0, sizeof(double) * (size_t)(4 * n));
    memset(s->S, 0, sizeof(double) * NN);
    if (o->y0) memcpy(s->state, o->y0, sizeof(double) * (size_t)(2 * n));
    else if (m->initial_state) m->initial_state(o->p, o->mp, s->state, s->state + n);
    return FSR_OK;
}

fsr_status sim_retune(sim* s, const fsr_integrator* it)
{
    fsr_status st = fsr_check_ode_options(s->o, s->m, s->r, fsr_method_name(s->o->method), s->capacity);
    if (st) return st;
    s->L = fsr_length_scale(s->m, s->o->p);
    s->mass_have = s->mass_factored = 0;        /* M(p) again, factored */
    s->drive_valid[0] = s->drive_valid[1] = 0;  /* the manoeuvre at the new mp */
    return it->retune ? it->retune(s) : FSR_OK;
}

void sim_close(sim* s)
{
    free(s->Mraw);  /* the start of the workspace */
    free(s->piv);
    free(s->ms);
    s->Mraw = NULL;
    s->piv = NULL;
    s->ms = NULL;
}

/* Largest natural frequency of the model linearised at rest: sqrt|lambda_max| of M(0)^-1 K,
 * K = dr/dq at q = q' = q'' = 0, by power iteration, maximised over the drive at five times
 * of the run (rotation stiffens: 68.7 rad/s at rest for #3, 72.8 rad/s at 6 rad/s). The
 * damping-like dr/dq' is left out. */
/* z = M^-1 K x with K = dr/dq = -(df/dq) at rest (Jq, Mfac of sim_omega_max) */
static void mass_inverse_stiffness(void* ctx, const double* x, double* z)
{
    sim* s = ctx;
    fsr_matvec(s->Jq, s->n, -1, x, z);
    mass_solve(s, z);
}

fsr_status sim_omega_max(sim* s, double* scratch, double* omega)
{
    int n = s->n;
    double *x = scratch, *z = x + n, lam = 0.0, *drive = s->dw + DW_STEP * s->nd;
    sim_drive(s, 0.0, drive);
    fsr_status st = sim_mass(s, 0.0, s->zero, drive, 1);
    if (st) return st;
    for (int i = 0; i < n; ++i) x[i] = (1.0 + 0.1 * i) / sqrt((double)n);
    for (int sample = 0; sample < 5; ++sample) {
        sim_drive(s, s->o->t_end * sample / 4.0, drive);
        s->m->residual_jac(s->zero, s->zero, s->zero, drive, s->o->p, s->Jq, s->Jv);
        double est = fsr_power_iteration(n, x, z, 1000, mass_inverse_stiffness, s);
        if (est > lam) lam = est;
    }
    *omega = sqrt(lam);
    return FSR_OK;
}

/* Refuse a fixed step above a method's stability limit (omega_max dt <= stability) instead of
 * integrating garbage. */
fsr_status sim_check_step_limit(sim* s, const char* name, double stability, const char* instead)
{
    return fsr_check_step_limit(s->r, name, s->o->dt, stability, s->r->omega_max, "", instead);
}
