/* A run of a model given as a struct (system.h) by a constrained integrator: options, workspace
 * (allocated once), consistent initial conditions, the constraint block solve, rows.
 * The methods themselves are ali3p.c, genalpha3.c and rk4p.c (integrator.h); the run loop simulate.c.
 *
 * Row: t, outputs, violation = max_i |Phi_i(q, t)| / L (only when nc > 0), q, and
 * with energy T, V, h. Outputs receive the multipliers lambda (ali3p: its lambda*), so that a
 * joint reaction is an output.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "constrained.h"
#include "linalg.h"

/* A pivot of the Schur complement below this fraction of the first one marks a constraint
 * that depends on the others (redundant): it is dropped from the solve. Dependent rows leave
 * pivots at rounding level (1e-16 relative); independent ones of the tests are above 1e-3. */
#define RANK_TOL 1e-10
/* Newton iterations for the initial positions before an assembly is refused */
#define ASSEMBLY_MAX_ITER 50

fsr_status cs_fail(csim* s, fsr_status st, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fsr_vfail(s->r, st, fmt, ap);
    va_end(ap);
    return st;
}

double cs_time(const csim* s, long k)
{
    return fsr_step_time(s->o, s->nsteps, k);
}

void cs_drive(csim* s, double t)
{
    s->m->drive(&t, s->o->mp, s->d);
}

void cs_constraints(csim* s, const double* q)
{
    s->m->constraints(q, s->d, s->o->p, s->phi);
    s->m->constraint_jac(q, s->d, s->o->p, s->Pq);
}

double cs_max_abs(const double* x, int n)
{
    double m = 0.0;
    for (int i = 0; i < n; ++i) {
        double a = fabs(x[i]);
        if (a > m || a != a) m = a;  /* NaN propagates */
    }
    return m;
}

int cs_factor(csim* s, double* A)
{
    return s->banded ? fsr_bordered_factor(&s->band, A, s->piv) : fsr_lu_factor(A, s->n, s->piv);
}

int cs_row_spans(const csim* s, int i, int fill, int sp[6])
{
    const int n = s->n, lo = s->band.lo, hi = s->band.hi, bw = s->band.bw;
    if (!s->banded || i < lo || i >= hi) {
        sp[0] = 0;
        sp[1] = n;
        return 2;
    }
    int k = 0, j0 = i - bw < lo ? lo : i - bw, j1 = i + (fill ? 2 : 1) * bw;
    if (lo > 0) sp[k++] = 0, sp[k++] = lo;
    sp[k++] = j0;
    sp[k++] = j1 < hi ? j1 + 1 : hi;
    if (hi < n) sp[k++] = hi, sp[k++] = n;
    return k;
}

/* B = A^-1 B (n x m) by the factor in A, Cholesky or LU (s->chol), bordered band (s->banded) */
static void solve_columns(csim* s, const double* A, double* B, int m)
{
    if (s->chol) fsr_chol_solve_columns(A, s->n, B, m);
    else if (s->banded)
        for (int c = 0; c < m; ++c) fsr_bordered_solve(&s->band, A, s->piv, B + c, m);
    else fsr_lu_solve_columns(A, s->n, s->piv, B, m);
}

void cs_solve(csim* s, const double* A, double* x)
{
    if (A) solve_columns(s, A, x, 1);
}

/* x = G^+ b for G (m x m, overwritten) by Gaussian elimination with complete pivoting; the
 * unknowns of pivots below RANK_TOL x the first are 0 (a basic solution; for a consistent
 * system it solves it). Returns the rank. */
static int rank_solve(csim* s, int m, double* b, double* x)
{
    double *G = s->G, *z = s->e2;
    int* cp = s->cp;
    int rank = 0;
    double first = 0.0;
    for (int i = 0; i < m; ++i) cp[i] = i;
    for (int k = 0; k < m; ++k) {
        int p = k, c = k;
        double best = -1.0;
        for (int i = k; i < m; ++i)
            for (int j = k; j < m; ++j)
                if (fabs(G[i * m + j]) > best) { best = fabs(G[i * m + j]); p = i; c = j; }
        if (k == 0) first = best;
        if (!(best > RANK_TOL * first)) break;
        if (p != k) {
            for (int j = 0; j < m; ++j) { double t = G[k * m + j]; G[k * m + j] = G[p * m + j]; G[p * m + j] = t; }
            double t = b[k]; b[k] = b[p]; b[p] = t;
        }
        if (c != k) {
            for (int i = 0; i < m; ++i) { double t = G[i * m + k]; G[i * m + k] = G[i * m + c]; G[i * m + c] = t; }
            int t = cp[k]; cp[k] = cp[c]; cp[c] = t;
        }
        for (int i = k + 1; i < m; ++i) {
            double l = G[i * m + k] / G[k * m + k];
            if (l == 0.0) continue;
            for (int j = k + 1; j < m; ++j) G[i * m + j] -= l * G[k * m + j];
            b[i] -= l * b[k];
        }
        rank = k + 1;
    }
    for (int i = rank - 1; i >= 0; --i) {
        double t = b[i];
        for (int j = i + 1; j < rank; ++j) t -= G[i * m + j] * z[j];
        z[i] = t / G[i * m + i];
    }
    for (int i = 0; i < m; ++i) x[cp[i]] = i < rank ? z[i] : 0.0;
    return rank;
}

int cs_kkt(csim* s, const double* A, double* b, const double* c, double* lam)
{
    const int n = s->n, nc = s->nc, m = nc + 1;
    double* Z = s->Z;
    if (nc == 0) {
        cs_solve(s, A, b);
        return 0;
    }
    for (int i = 0; i < n; ++i) {  /* Z = A^-1 [b, Phi_q^T] = [y, A^-1 Phi_q^T], in one solve */
        Z[i * m] = b[i];
        for (int j = 0; j < nc; ++j) Z[i * m + 1 + j] = s->Pq[j * n + i];
    }
    if (A) solve_columns(s, A, Z, m);
    for (int i = 0; i < nc; ++i) {  /* G = Phi_q A^-1 Phi_q^T, e1 = Phi_q y - c */
        double r = -c[i];
        for (int l = 0; l < n; ++l) r += s->Pq[i * n + l] * Z[l * m];
        s->e1[i] = r;
        for (int j = 0; j < nc; ++j) {
            double g = 0.0;
            for (int l = 0; l < n; ++l) g += s->Pq[i * n + l] * Z[l * m + 1 + j];
            s->G[i * nc + j] = g;
        }
    }
    int rank = rank_solve(s, nc, s->e1, lam);
    for (int i = 0; i < n; ++i) {  /* x = y - A^-1 Phi_q^T lam */
        double t = 0.0;
        for (int j = 0; j < nc; ++j) t += Z[i * m + 1 + j] * lam[j];
        b[i] = Z[i * m] - t;
    }
    return rank;
}

static int worst_constraint(const csim* s)
{
    int w = 0;
    for (int i = 1; i < s->nc; ++i)
        if (fabs(s->phi[i]) > fabs(s->phi[w])) w = i;
    return w;
}

/* The columns of Phi_q of the coordinates whose value (bit 1) or rate (bit 2) the model's
 * coord_held holds, zeroed: a minimum-norm correction through Phi_q then leaves them as they are. */
static void hold(csim* s, unsigned char bit)
{
    const unsigned char* held = s->m->coord_held;
    if (!held) return;
    for (int l = 0; l < s->n; ++l)
        if (held[l] & bit)
            for (int i = 0; i < s->nc; ++i) s->Pq[i * s->n + l] = 0.0;
}

/* Positions: Newton on Phi(q, 0) = 0 with minimum-norm corrections (Gauss-Newton; redundant
 * rows dropped) of the coordinates the model does not hold (coord_held: flexible bodies stay
 * undeformed; flexsym's assembly closed the loop with the scene's values, so this moves only
 * what a run-time parameter or initial state opened), refused after ASSEMBLY_MAX_ITER
 * iterations naming the largest residual of the best iterate; velocities: the minimum-norm
 * change with Phi_q q' = -Phi_t, likewise; accelerations and multipliers from
 * [M Phi_q^T; Phi_q 0] [q''; lambda] = [f; gamma]. */
fsr_status cs_consistent_start(csim* s)
{
    const fsm_system* m = s->m;
    const int n = s->n, nc = s->nc;
    double *q = s->q, *v = s->v;
    if (s->o->y0) {  /* the caller's initial state, as a starting guess like initial_state's */
        memcpy(q, s->o->y0, sizeof(double) * (size_t)n);
        memcpy(v, s->o->y0 + n, sizeof(double) * (size_t)n);
    } else if (m->initial_state) {
        m->initial_state(s->o->p, s->o->mp, q, v);
    }
    cs_drive(s, 0.0);
    if (nc > 0) {
        int it = 0, w_best = 0;
        double best = INFINITY;  /* the smallest max |Phi| met, for the message */
        for (;; ++it) {
            cs_constraints(s, q);
            double err = cs_max_abs(s->phi, nc);
            if (err <= s->tol) break;
            if (err < best) {
                best = err;
                w_best = worst_constraint(s);
            }
            if (it == ASSEMBLY_MAX_ITER || !isfinite(err) || !isfinite(cs_max_abs(q, n)))
                return cs_fail(s, FSR_ASSEMBLY,
                               "assembly cannot close at t = 0: constraint %s is off by %.3g at "
                               "best (%.3g x the length scale %g m) after %d Newton iterations%s",
                               m->constraint_names[w_best], best, best / s->L, s->L, it,
                               m->coord_held ? ", moving the joints with the bodies undeformed (the "
                               "start was assembled with the model's defaults: a parameter or initial "
                               "state given to the run opened the loop)" : "");
            for (int i = 0; i < nc; ++i) s->lam[i] = -s->phi[i];
            hold(s, 1);
            memset(s->w1, 0, sizeof(double) * (size_t)n);
            cs_kkt(s, NULL, s->w1, s->lam, s->lam1);
            for (int i = 0; i < n; ++i) q[i] += s->w1[i];
        }
        m->constraint_rate(q, s->d, s->o->p, s->phit);
        for (int i = 0; i < nc; ++i) {
            double r = s->phit[i];
            for (int l = 0; l < n; ++l) r += s->Pq[i * n + l] * v[l];
            s->lam[i] = -r;
        }
        hold(s, 2);
        memset(s->w1, 0, sizeof(double) * (size_t)n);
        cs_kkt(s, NULL, s->w1, s->lam, s->lam1);
        for (int i = 0; i < n; ++i) v[i] += s->w1[i];
        cs_constraints(s, q);  /* Phi_q whole again, for the accelerations */
    }
    m->mass(q, s->d, s->o->p, s->M);
    memcpy(s->S, s->M, sizeof(double) * (size_t)n * (size_t)n);
    if (cs_factor(s, s->S))
        return cs_fail(s, FSR_SINGULAR, "mass matrix singular at t = 0");
    s->h_mat = 0.0;
    m->force(q, v, s->d, s->o->p, s->a);
    s->r->force_evaluations++;
    if (nc > 0) m->constraint_acc(q, v, s->d, s->o->p, s->gam);
    memset(s->lam, 0, sizeof(double) * (size_t)nc);
    cs_kkt(s, s->S, s->a, s->gam, s->lam);
    memcpy(s->mult, s->lam, sizeof(double) * (size_t)nc);
    memcpy(s->vout, s->v, sizeof(double) * (size_t)n);
    return FSR_OK;
}

static fsr_status store(csim* s, double t)
{
    fsr_result* r = s->r;
    const fsm_system* m = s->m;
    if (r->nrows >= s->capacity) return FSR_OK;
    double* row = r->rows + (size_t)r->nrows * (size_t)r->ncols;
    int c = 1 + m->ny;
    cs_drive(s, t);
    row[0] = t;
    m->outputs(s->q, s->vout, s->a, s->nc ? s->mult : s->zero, s->d, s->o->p, s->y);
    memcpy(row + 1, s->y, sizeof(double) * (size_t)m->ny);
    if (s->nc) {
        m->constraints(s->q, s->d, s->o->p, s->phi);
        row[c++] = cs_max_abs(s->phi, s->nc) / s->L;
    }
    memcpy(row + c, s->q, sizeof(double) * (size_t)s->n);
    if (s->o->energy) m->energy(s->q, s->vout, s->d, s->o->p, row + c + s->n);
    r->nrows++;
    return FSR_OK;
}

int cs_row_due(const csim* s)
{
    return s->k + 1 == s->next_row;
}

fsr_status cs_accept(csim* s, double t1)
{
    const double limit = s->o->blowup * s->L;
    for (int i = 0; i < s->n; ++i) {
        if (!isfinite(s->q[i]) || !isfinite(s->v[i]) || !isfinite(s->a[i]))
            return cs_fail(s, FSR_DIVERGED, "diverged at t = %.6g s: %s is not finite", t1,
                           s->m->coord_names[i]);
        if (fsr_beyond_blowup(s->m, limit, i, s->q[i])) return fsr_blowup_fail(s->r, s->m, s->o, limit, t1, i, s->q[i]);
    }
    fsr_result* r = s->r;
    double h = t1 - cs_time(s, s->k - 1);
    if (r->steps == 0 || h < r->h_min) r->h_min = h;
    if (h > r->h_max) r->h_max = h;
    r->steps++;
    r->t_stop = t1;
    if (s->k != s->next_row) return FSR_OK;
    s->next_row = fsr_next_row(s->next_row, s->o->out_every, s->nsteps);
    return store(s, t1);
}

fsr_status cs_newton_failed(csim* s, double t1, double dq, int it)
{
    return cs_fail(s, FSR_NEWTON_FAILED,
                   "Newton iterations did not converge at t = %.6g s (|dq| = %.3g, max |Phi| = %.3g "
                   "after %d iterations); reduce --dt", t1, dq, cs_max_abs(s->phi, s->nc), it);
}

/* Workspace in one block: doubles, then ints. */
fsr_status cs_open(csim* s, const fsr_integrator* it, const fsm_system* m, const fsr_options* o,
                   fsr_result* r, long capacity)
{
    memset(s, 0, sizeof *s);
    memset(r, 0, sizeof *r);
    s->m = m;
    s->o = o;
    s->r = r;
    s->n = m->nq;
    s->nc = m->nc;
    r->ncols = 1 + m->ny + (m->nc > 0) + m->nq + (o->energy ? 3 : 0);
    fsr_status st = fsr_check_constrained_options(o, m, r, fsr_method_name(o->method), capacity);
    if (st) return st;
    const size_t n = (size_t)s->n, nc = (size_t)s->nc, nn = n * n;
    s->L = fsr_length_scale(m, o->p);
    s->tol = o->newton_tol * s->L;
    s->nsteps = fsr_step_count(o);
    s->next_row = fsr_next_row(0, o->out_every, s->nsteps);
    s->capacity = capacity > 0 ? capacity : s->nsteps / o->out_every + 2;
    size_t nz = n > nc ? n : nc;
    size_t work = it->work_size(s->n);
    int lo, hi;
    s->banded = fsr_band_layout(m, 1, &lo, &hi) >= 0;
    int border = s->banded ? s->n - (hi - lo) : 0;
    size_t doubles = 12 * n + 6 * nc + (size_t)m->nd + (size_t)m->ny + 5 * nn + (2 * nc + 1) * n + nc * nc
                     + 2 * nc + nz + 1 + work + FSR_BORDERED_DOUBLES(border, hi - lo);
    r->rows = malloc(sizeof(double) * (size_t)s->capacity * (size_t)r->ncols);
    double* x = calloc(doubles, sizeof(double));
    s->piv = malloc(sizeof(int) * (n + nc + 1 + FSR_BORDERED_INTS(border)));
    if (!r->rows || !x || !s->piv) {
        free(x);
        free(s->piv);
        s->piv = NULL;
        s->M = NULL;
        return cs_fail(s, FSR_NO_MEMORY, "out of memory for %ld output rows", s->capacity);
    }
    s->M = x; x += nn;  /* the start of the block */
    s->S = x; x += nn;
    s->Jq = x; x += nn;
    s->Jv = x; x += nn;
    s->H = x; x += nn;
    s->q = x; x += n;
    s->v = x; x += n;
    s->a = x; x += n;
    s->ab = x; x += n;
    s->q1 = x; x += n;
    s->v1 = x; x += n;
    s->a1 = x; x += n;
    s->res = x; x += n;
    s->f = x; x += n;
    s->w1 = x; x += n;
    s->w2 = x; x += n;
    s->vout = x; x += n;
    s->lam = x; x += nc;
    s->lam1 = x; x += nc;
    s->mult = x; x += nc;
    s->phi = x; x += nc;
    s->phit = x; x += nc;
    s->gam = x; x += nc;
    s->e1 = x; x += nc;
    s->e2 = x; x += nc;
    s->d = x; x += m->nd;
    s->y = x; x += m->ny;
    s->Pq = x; x += nc * n;
    s->Z = x; x += (nc + 1) * n;
    s->G = x; x += nc * nc;
    s->work = x; x += work;
    s->zero = x; x += nz + 1;
    s->cp = s->piv + n;
    if (s->banded) fsr_bordered_init(&s->band, s->n, m->bandwidth, lo, hi, x, s->cp + nc + 1);
    return FSR_OK;
}

fsr_status cs_start(csim* s)
{
    fsr_status st = cs_consistent_start(s);
    if (!st) st = store(s, 0.0);
    return st;
}

void cs_close(csim* s)
{
    free(s->M);  /* the start of the workspace */
    free(s->piv);
    s->M = NULL;
    s->piv = NULL;
}
