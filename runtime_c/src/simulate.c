/* Time integration of a generated model: explicit RK4 and Dormand-Prince 5(4) (one Butcher
 * tableau engine), implicit generalized-alpha and Newmark, and the 3-stage Radau IIA method
 * (order 5), both by modified Newton on one iteration-matrix builder.
 *
 * The state is y = [q, q'] (contiguous); y' = [q', q''] with M(q) q'' = f.
 * Workspace is allocated once before the step loop; the loop itself never allocates.
 * Divergence (non-finite state, or a coordinate beyond blowup * L) stops the run with a
 * message naming the time; the rows stored up to then are kept.
 * A run is resumable step by step (sim_open, sim_begin, sim_step; each method carries its state
 * in sim between steps): fsr_simulate runs it to t_end, fsr_stepper to times the caller asks
 * for (an FMU's communication points), so both give the same rows bit for bit.
 */
#include "flexsym/runtime.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "constrained.h"
#include "flexsym/limits.h"
#include "flexsym/system.h"
#include "linalg.h"

/* Modified Newton: rebuild the iteration matrix when an iteration contracts the update by
 * less than this. Small, so that the stopping test below passes after one iteration in most
 * steps; rebuilds stay rare (ef at 1 ms: 133 in 20000 steps; #1-#3: a handful). */
#define NEWTON_THETA_MAX 0.005
/* A measured contraction is trusted by the stopping test for this many steps. Longer trust
 * (10 steps) let steps stop after one iteration on a contraction that had since worsened:
 * ef with 4 elements at dt = 5 ms drifted 2.4e-6 m from full Newton over 8 s (tolerance
 * 1e-11 m per step); with 2 steps the drift is 5e-10 m, at similar cost. */
#define NEWTON_THETA_AGE 2

enum { MAX_STAGES = 7 };

/* Stability for the undamped modes of these models (eigenvalues +-i omega): RK4 needs
 * dt omega <= 2.83 (2.785 used: its real-axis bound, a margin for the damping-like terms);
 * dopri5 leaves the imaginary axis at 1.0 (|R| = 1 + 1.4e-6 there, 1.005 at 1.6, 1.03 at 2)
 * although its real-axis bound is 3.3. Its error control holds adaptive steps near 1.4. */
typedef struct {
    const char* name;
    int stages;
    int embedded;                      /* has an error estimate e and a dense output d */
    int fsal;                          /* last stage = f(t + h, y_new): the next first stage */
    double stability;                  /* stability bound of dt * omega for undamped modes */
    double c[MAX_STAGES];
    double a[MAX_STAGES][MAX_STAGES];  /* a[i][j], j < i */
    double b[MAX_STAGES];
    double e[MAX_STAGES];              /* b - b_hat, the embedded error estimate; 0: none */
    double d[MAX_STAGES];              /* dense output (Hairer's CONTD5); 0: none */
} erk_tableau;

static const erk_tableau RK4 = {
    "rk4", 4, 0, 0, 2.785, {0.0, 0.5, 0.5, 1.0},
    {{0.0}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}},
    {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}, {0.0}, {0.0}};

static const erk_tableau DOPRI5 = {
    "dopri5", 7, 1, 1, 1.0, {0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0},
    {{0.0},
     {0.2},
     {3.0 / 40.0, 9.0 / 40.0},
     {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
     {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
     {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0},
     {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0}},
    {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0},
    {71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0,
     -1.0 / 40.0},
    {-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0,
     -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
     -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0}};

/* Modified Newton: the factored iteration matrix is kept across iterations and steps. */
typedef struct {
    double h;          /* step it was built for; 0: none */
    double theta;      /* contraction |dq_k| / |dq_k-1| last measured with it; < 0: unknown */
    long theta_step;   /* the step of that measurement */
} newton_state;

enum { RADAU_STAGES = 3 };  /* radau5: see radau_step */

typedef struct {
    double c[RADAU_STAGES];
    double a[RADAU_STAGES][RADAU_STAGES];
    double aa[RADAU_STAGES][RADAU_STAGES];  /* a a: the displacement coefficients */
    double e[RADAU_STAGES][RADAU_STAGES];   /* predictor: A at c_i + 1 from the last step's A */
    double x[RADAU_STAGES + 1];             /* dense output: the nodes 0, c_1, c_2, c_3 */
    double wden[RADAU_STAGES + 1];          /* 1 / prod_{l != j} (x_j - x_l) */
} radau_tableau;

typedef struct {
    const fsm_system* m;  /* the model (system.h; a one-beam model through model_adapter.c) */
    const fsr_options* o;
    fsr_result* r;
    int n;
    int bw;        /* half-bandwidth of the model's matrices used by the solvers, -1 = dense */
    int nst;       /* stages coupled in the Newton system: 1, or 3 for radau5 */
    int N;         /* its size, nst n (unknowns interleaved: coordinate r, stage i at r nst + i) */
    int kb;        /* its half-bandwidth, nst (bw + 1) - 1, or -1 = dense */
    double L;
    long nsteps;   /* grid points t_k = k dt, t_nsteps = t_end */
    long next_row; /* grid index of the next output row; nsteps + 1 when all are written */
    double* Mraw;  /* mass matrix as evaluated */
    double* Mfac;  /* its Cholesky factor */
    double* Minv;  /* its inverse, when constant and dense */
    double* S;     /* Newton iteration matrix (N x N), LU-factored */
    double* Sinv;  /* its inverse, when dense */
    double* tmp;   /* N */
    double* Jq;
    double* Jv;
    double* y;     /* outputs */
    double* qdd;   /* accelerations for outputs that need them */
    double* zero;  /* n zeros */
    double* work;  /* method workspace */
    double* dense; /* 2n: a state between steps, for rows */
    int* piv;
    int mass_have, mass_factored; /* only trusted when the mass is constant */
    int nd;        /* drive vector d = [t, theta, theta', theta'', ...] */
    double* dw;    /* drive vectors of the callers: DW_ACCEL, DW_ROW, DW_STEP (+ stage), nd each */
    double drive_t[2], *drive_v[2];
    int drive_valid[2], drive_next;
    int drive_held;   /* drive from the caller (fsr_stepper_set_drive), not the manoeuvre: */
    double hold_t, hold[2], hold_theta;  /* theta' = hold[0] + hold[1] (t - hold_t), theta'' =
                                            hold[1], theta = hold_theta + its integral */
    long capacity; /* rows */
    /* the run, resumable step by step (sim_step): the state and what a method carries over */
    double* state; /* [q, q'] */
    long k;        /* steps taken (fixed steps) */
    long msteps;   /* steps of the method: nsteps, or radau5's own with --step */
    int done;
    newton_state ns;
    double am, af, gam, bet, ra, pa, pb; /* generalized-alpha / Newmark coefficients */
    int extrapolate;
    radau_tableau rt;
    double H, h_prev;                    /* radau5: step length, last step */
    const erk_tableau* T;                /* explicit: tableau, adaptive step control */
    int adaptive, have_k0, rejected;
    double t, h, err_old;
} sim;

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

const char* fsr_method_name(fsr_method m)
{
    switch (m) {
    case FSR_RK4: return "rk4";
    case FSR_GENALPHA: return "genalpha";
    case FSR_NEWMARK: return "newmark";
    case FSR_DOPRI5: return "dopri5";
    case FSR_RADAU5: return "radau5";
    case FSR_ALI3P: return "ali3p";
    case FSR_GENALPHA3: return "genalpha3";
    }
    return "?";
}

/* r->message from fmt, r->status = st; returns st (shared with constrained.c). */
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

static fsr_status fail(sim* s, fsr_status st, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fsr_vfail(s->r, st, fmt, ap);
    va_end(ap);
    return st;
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

/* max(m, |x|) for m >= 0 (libm's fmax is a call in strict C99). */
static double max_abs(double m, double x)
{
    x = fabs(x);
    return x > m ? x : m;
}

enum { DW_ACCEL = 0, DW_ROW = 1, DW_STEP = 2, DW_COUNT = 2 + 3 };  /* DW_STEP: 3 radau stages */

/* The drive vector d (nd) at t into d. The last two times are cached: RK stages and output
 * rows ask for the same time repeatedly, and the manoeuvre costs a sin and a cos. */
static void drive_at(sim* s, double t, double* d)
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

/* M(q, d) into Mraw and, with factor, its Cholesky factor into Mfac; once when M is constant. */
static fsr_status mass_at(sim* s, double t, const double* q, const double* d, int factor)
{
    int n = s->n, constant = s->m->mass_constant;
    if (!constant || !s->mass_have) {
        s->m->mass(q, d, s->o->p, s->Mraw);
        s->mass_have = 1;
        s->mass_factored = 0;
    }
    if (!factor || (constant && s->mass_factored)) return FSR_OK;
    memcpy(s->Mfac, s->Mraw, sizeof(double) * (size_t)n * (size_t)n);
    int k = fsr_chol_factor(s->Mfac, n);
    if (k) return fail(s, FSR_SINGULAR, "mass matrix not positive definite at t = %.6g s (pivot %d, %s)",
                       t, k, s->m->coord_names[k - 1]);
    if (constant && s->bw < 0) fsr_chol_inverse(s->Mfac, n, s->Minv, s->tmp);
    s->mass_factored = 1;
    return FSR_OK;
}

/* x = A^-1 x by the explicit inverse of a dense A of size dim. */
static void apply_inverse(sim* s, const double* Ainv, int dim, double* x)
{
    fsr_matvec(Ainv, dim, -1, x, s->tmp);
    memcpy(x, s->tmp, sizeof(double) * (size_t)dim);
}

static fsr_status accel(sim* s, double t, const double* q, const double* v, double* a)
{
    double* drive = s->dw + DW_ACCEL * s->nd;
    drive_at(s, t, drive);
    fsr_status st = mass_at(s, t, q, drive, 1);
    if (st) return st;
    s->m->force(q, v, drive, s->o->p, a);
    s->r->force_evaluations++;
    if (s->m->mass_constant && s->bw < 0) apply_inverse(s, s->Minv, s->n, a);
    else fsr_chol_solve(s->Mfac, s->n, a);
    return FSR_OK;
}

/* k = y' = [q', q''] at (t, y). */
static fsr_status deriv(sim* s, double t, const double* y, double* k)
{
    memcpy(k, y + s->n, sizeof(double) * (size_t)s->n);
    return accel(s, t, y, y + s->n, k + s->n);
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

/* Append a row: t, outputs, q. Outputs that read q'' get a when given, else M(q) q'' = f.
 * The drive only when something reads it: rows between steps would pay a sin and a cos. */
static fsr_status store(sim* s, double t, const double* q, const double* v, const double* a)
{
    fsr_result* r = s->r;
    if (r->nrows >= s->capacity) return FSR_OK;
    double* row = r->rows + (size_t)r->nrows * (size_t)r->ncols;
    double* drive = s->dw + DW_ROW * s->nd;  /* zeros unless something reads it */
    const double* qdd = s->qdd;
    if (s->m->outputs_use_drive || s->o->energy) drive_at(s, t, drive);
    if (s->m->outputs_use_acceleration) {
        if (a) qdd = a;
        else {
            fsr_status st = accel(s, t, q, v, s->qdd);
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

static double time_of(const sim* s, long k)
{
    return k >= s->nsteps ? s->o->t_end : (double)k * s->o->dt;
}

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

/* An accepted step from t to t + h, for rows that fall inside it: at(d, theta, y1, out) writes
 * the state [q, q'] at t + theta h (y1: the state at t + h) to out (2n). */
typedef struct dense_step dense_step;
struct dense_step {
    void (*at)(const dense_step* d, double theta, const double* y1, double* out);
    const void* T;     /* the method's tableau */
    int m;             /* 2n */
    double t, h;
    const double *y, *k;  /* the state at t; the stages (ERK: y'; radau5: Q, then V) */
};

static void erk_dense(const dense_step* d, double theta, const double* y1, double* out)
{
    dense_at(d->T, d->m, theta, d->h, d->y, y1, d->k, out);
}

/* Write the rows due in (t, t1]: the state (y1, a1) at t1, or the dense output of step d
 * between grid points (only adaptive or radau5 --step steps fall between them). */
static fsr_status emit_rows(sim* s, double t1, const double* y1, const double* a1, const dense_step* d)
{
    int n = s->n;
    while (s->next_row <= s->nsteps) {
        double tr = time_of(s, s->next_row);
        if (tr > t1) break;
        fsr_status st;
        if (tr == t1 || !d) st = store(s, t1, y1, y1 + n, a1);
        else {
            double* ys = s->dense;
            d->at(d, (tr - d->t) / d->h, y1, ys);
            st = store(s, tr, ys, ys + n, NULL);
        }
        if (st) return st;
        long next = s->next_row + s->o->out_every;
        s->next_row = s->next_row == s->nsteps ? s->nsteps + 1 : (next < s->nsteps ? next : s->nsteps);
    }
    return FSR_OK;
}

/* Bookkeeping of an accepted step of length h ending at t1 with state y1. */
static fsr_status accept(sim* s, double t1, double h, const double* y1, const double* a1, const dense_step* d)
{
    fsr_status st = check_state(s, t1, y1, y1 + s->n);
    if (st) return st;
    fsr_result* r = s->r;
    if (r->steps == 0 || h < r->h_min) r->h_min = h;
    if (h > r->h_max) r->h_max = h;
    r->steps++;
    r->t_stop = t1;
    return emit_rows(s, t1, y1, a1, d);
}

/* ---------------------------------------------------------------- explicit Runge-Kutta */

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
static fsr_status erk_step(sim* s, const erk_tableau* T, double t, double t1, const double* y,
                           double* k, double* y1, double* ys)
{
    int m = 2 * s->n;
    double h = t1 - t;
    for (int i = 1; i < T->stages; ++i) {
        double* yi = T->fsal && i == T->stages - 1 ? y1 : ys;  /* FSAL: the last stage is at y1 */
        combine(yi, y, h, T->a[i], k, i, m);
        fsr_status st = deriv(s, T->c[i] == 1.0 ? t1 : t + T->c[i] * h, yi, k + (size_t)i * (size_t)m);
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
        double sc = s->o->tol * (s->L + max_abs(fabs(y[j]), y1[j]));
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
    fsr_status st = deriv(s, h0, ys, k1);
    if (st) return st;
    for (int j = 0; j < m; ++j) ys[j] = k1[j] - k0[j];
    double d2 = norm_scaled(s, ys, y) / h0, dm = fmax(d1, d2);
    double h1 = dm <= 1e-15 ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / dm, 0.2);
    *h = fmin(fmin(100.0 * h0, h1), s->o->t_end);
    return FSR_OK;
}

/* Step-size control of dopri5 (Hairer & Wanner, DOPRI5): factor err^-(0.2 - 0.75 beta) *
 * err_old^beta (a PI controller), safety 0.9, shrink at most 5x and grow at most 10x per step,
 * no growth right after a rejection. beta = 0.08, Hairer's advice where stability limits the
 * step, as here (undamped modes): 78 rejections in 1100 steps on #3 instead of 265 at 0.04. */
#define PI_BETA 0.08
#define SAFETY 0.9
#define FAC_MIN 0.2
#define FAC_MAX 10.0

static fsr_status erk_begin(sim* s, const erk_tableau* T)
{
    int m = 2 * s->n;
    double *k = s->work, *y1 = k + (size_t)MAX_STAGES * (size_t)m, *ys = y1 + m;
    s->T = T;
    s->adaptive = T->embedded && s->o->tol > 0.0;
    s->t = 0.0;
    s->h = s->o->dt;
    s->err_old = 1e-4;
    s->have_k0 = s->rejected = 0;
    s->done = s->msteps < 1;
    if (!s->adaptive) return FSR_OK;
    fsr_status st = deriv(s, 0.0, s->state, k);
    if (st) return st;
    s->have_k0 = 1;
    return initial_step(s, s->state, k, k + m, ys, &s->h);
}

/* One step (accepted, or rejected by the adaptive step control). */
static fsr_status erk_advance(sim* s)
{
    const fsr_options* o = s->o;
    const erk_tableau* T = s->T;
    int m = 2 * s->n, adaptive = s->adaptive;
    double *y = s->state, *k = s->work, *y1 = k + (size_t)MAX_STAGES * (size_t)m, *ys = y1 + m;
    double t = s->t, h = s->h, t1;
    fsr_status st;
    if (adaptive) {
        if (s->r->steps + s->r->rejected_steps >= o->max_steps)
            return fail(s, FSR_STEP_FAILED,
                        "%s gave up at t = %.6g s after %ld steps (step %.3g s = %.2g / omega_max, "
                        "omega_max = %.1f rad/s: stiff for explicit steps); use an implicit "
                        "integrator, a looser --tol or a larger --max-steps", T->name, t,
                        o->max_steps, h, h * s->r->omega_max, s->r->omega_max);
        if (t + 1.01 * h >= o->t_end) h = o->t_end - t;
        t1 = t + h >= o->t_end ? o->t_end : t + h;
        if (h <= 16.0 * DBL_EPSILON * fmax(1.0, t))
            return fail(s, FSR_STEP_FAILED, "%s step size underflow at t = %.6g s (h = %.3g s)", T->name, t, h);
    } else {
        t1 = time_of(s, s->k + 1);
    }
    if (!s->have_k0 && (st = deriv(s, t, y, k))) return st;
    if ((st = erk_step(s, T, t, t1, y, k, y1, ys))) return st;
    double h_next = h;
    if (adaptive) {
        double err = error_norm(s, T, t1 - t, k, y, y1);
        double fac11 = pow(err, 0.2 - 0.75 * PI_BETA);
        if (!(err <= 1.0)) {  /* rejected (also NaN): shrink, keep k[0] = f(t, y) */
            s->r->rejected_steps++;
            s->rejected = 1;
            s->h = h / fmin(1.0 / FAC_MIN, fac11 / SAFETY);
            return FSR_OK;
        }
        double fac = fmax(1.0 / FAC_MAX, fmin(1.0 / FAC_MIN, fac11 / pow(s->err_old, PI_BETA) / SAFETY));
        h_next = (t1 - t) / fac;
        if (s->rejected) h_next = fmin(h_next, t1 - t);
        s->err_old = fmax(err, 1e-4);
        s->rejected = 0;
    }
    const double* klast = k + (size_t)(T->stages - 1) * (size_t)m;
    dense_step d = {erk_dense, T, m, t, t1 - t, y, k};
    if ((st = accept(s, t1, t1 - t, y1, T->fsal ? klast + s->n : NULL, adaptive ? &d : NULL)))
        return st;
    memcpy(y, y1, sizeof(double) * (size_t)m);
    if (T->fsal) memcpy(k, klast, sizeof(double) * (size_t)m);
    s->have_k0 = T->fsal;
    s->t = t1;
    s->h = h_next;
    ++s->k;
    s->done = adaptive ? !(t1 < o->t_end) : s->k >= s->msteps;
    return FSR_OK;
}

/* Largest natural frequency of the model linearised at rest: sqrt|lambda_max| of M(0)^-1 K,
 * K = dr/dq at q = q' = q'' = 0, by power iteration, maximised over the drive at five times
 * of the run (rotation stiffens: 68.7 rad/s at rest for #3, 72.8 rad/s at 6 rad/s). The
 * damping-like dr/dq' is left out. */
static fsr_status estimate_omega_max(sim* s, double* omega)
{
    int n = s->n;
    /* x, z past the 8n of the generalized-alpha / Newmark state, which a retuned conditionally
     * stable Newmark run keeps (work holds at least 12n) */
    double *x = s->work + 8 * n, *z = x + n, lam = 0.0, *drive = s->dw + DW_STEP * s->nd;
    drive_at(s, 0.0, drive);
    fsr_status st = mass_at(s, 0.0, s->zero, drive, 1);
    if (st) return st;
    for (int i = 0; i < n; ++i) x[i] = (1.0 + 0.1 * i) / sqrt((double)n);
    for (int sample = 0; sample < 5; ++sample) {
        double est = 0.0;
        drive_at(s, s->o->t_end * sample / 4.0, drive);
        s->m->residual_jac(s->zero, s->zero, s->zero, drive, s->o->p, s->Jq, s->Jv);
        for (int it = 0; it < 1000; ++it) {
            fsr_matvec(s->Jq, n, -1, x, z);
            fsr_chol_solve(s->Mfac, n, z);
            double nz = 0.0;
            for (int i = 0; i < n; ++i) nz += z[i] * z[i];
            nz = sqrt(nz);
            if (!(nz > 0.0) || !isfinite(nz)) break;
            for (int i = 0; i < n; ++i) x[i] = z[i] / nz;
            int done = fabs(nz - est) <= 1e-10 * nz;
            est = nz;
            if (done) break;
        }
        if (est > lam) lam = est;
    }
    *omega = sqrt(lam);
    return FSR_OK;
}

/* Refuse a fixed step above a method's stability limit (omega_max dt <= stability) instead of
 * integrating garbage. */
static fsr_status check_step_limit(sim* s, const char* name, double stability, const char* instead)
{
    double om = s->r->omega_max, limit = stability / om, dt = s->o->dt;
    if (!(dt > limit)) return FSR_OK;
    int e = (int)floor(log10(limit));
    double mant = floor(limit / pow(10.0, e) * 10.0) / 10.0;
    return fail(s, FSR_UNSTABLE_STEP,
                "%s step %g ms exceeds the stability limit %.3g ms of this model (omega_max = %.1f "
                "rad/s); use --dt <= %.1fe%d or %s", name, dt * 1e3, limit * 1e3, om, mant, e, instead);
}

static fsr_status check_fixed_step(sim* s, const erk_tableau* T)
{
    return check_step_limit(s, T->name, T->stability, "an implicit integrator");
}

/* Newmark with beta < gamma / 2 is only conditionally stable: omega dt <= 1 / sqrt(gamma / 2 -
 * beta) undamped (sqrt(6) for Fox-Goodwin's beta = 1/12, whose period error is fourth order,
 * (omega dt)^4 / 480, against (omega dt)^2 / 12 for the trapezoidal beta = 1/4). */
static int newmark_conditional(const fsr_options* o)
{
    return o->method == FSR_NEWMARK && o->nm_beta < 0.5 * o->nm_gamma;
}

static fsr_status check_newmark_step(sim* s)
{
    const fsr_options* o = s->o;
    if (!newmark_conditional(o)) return FSR_OK;
    fsr_status st = estimate_omega_max(s, &s->r->omega_max);
    if (st) return st;
    return check_step_limit(s, "newmark", 1.0 / sqrt(0.5 * o->nm_gamma - o->nm_beta),
                            "a larger --newmark-beta");
}

/* ------------------------------------------- implicit methods: the Newton iteration matrix */

/* Rows r nst + i (r < n) of the Newton iteration matrix of a method with nst coupled stages:
 * block (i, j) = [i == j] M + cq[j] dr/dq + cv[j] dr/dq' from Mraw, Jq, Jv (generalized-alpha:
 * one stage, S = M + cb dr/dq + cg dr/dq'). The unknowns are interleaved by coordinate, so a
 * banded model gives a banded matrix (half-bandwidth kb = nst (bw + 1) - 1); the band LU fills
 * in up to 2 kb above the diagonal, and those entries are written too (zeros: the model's
 * matrices vanish outside their band). */
static void newton_rows(sim* s, int i, const double* cq, const double* cv)
{
    int n = s->n, N = s->N, nst = s->nst, kb = s->kb;
    for (int r = 0; r < n; ++r) {
        int R = r * nst + i;
        int C0 = kb < 0 || R < kb ? 0 : R - kb, C1 = kb < 0 || R + 2 * kb >= N ? N - 1 : R + 2 * kb;
        double* row = s->S + (size_t)R * (size_t)N;
        for (int C = C0, c = C0 / nst, j = C0 - c * nst; C <= C1; ++C) {  /* C = c nst + j */
            size_t rc = (size_t)r * (size_t)n + (size_t)c;
            row[C] = (i == j ? s->Mraw[rc] : 0.0) + cq[j] * s->Jq[rc] + cv[j] * s->Jv[rc];
            if (++j == nst) j = 0, ++c;
        }
    }
}

/* LU-factor the iteration matrix, banded when the model is; a dense one also gets its inverse
 * (the solves are then matrix-vector products, which have no dependency chain: radau5 on #3 at
 * 0.25 s takes 0.127 ms with it, 0.153 ms with LU solves). */
static fsr_status newton_factor(sim* s, double t)
{
    int N = s->N, kb = s->kb;
    s->r->jacobian_evaluations++;
    int bad = kb >= 0 ? fsr_band_lu_factor(s->S, N, kb, kb, s->piv) : fsr_lu_factor(s->S, N, s->piv);
    if (bad) return fail(s, FSR_SINGULAR, "Newton matrix singular at t = %.6g s", t);
    if (kb < 0) fsr_lu_inverse(s->S, N, s->piv, s->Sinv, s->tmp);
    return FSR_OK;
}

/* x = S^-1 x */
static void newton_solve(sim* s, double* x)
{
    if (s->kb >= 0) fsr_band_lu_solve(s->S, s->N, s->kb, s->kb, s->piv, x);
    else apply_inverse(s, s->Sinv, s->N, x);
}

/* Converged when the update is below tol, or (modified Newton) when the error it leaves,
 * theta / (1 - theta) |dq| for a contraction theta measured in the last NEWTON_THETA_AGE steps,
 * is (Hairer & Wanner II, IV.8): usually after one iteration instead of two. */
static int newton_converged(const sim* s, const newton_state* ns, long k, double dq, double tol)
{
    if (dq <= tol) return 1;
    if (s->o->newton_full || ns->theta < 0.0 || k - ns->theta_step > NEWTON_THETA_AGE) return 0;
    return ns->theta < 1.0 && ns->theta / (1.0 - ns->theta) * dq <= tol;
}

/* Record the contraction of an iteration; ask for a new matrix when it is too slow. */
static int newton_contraction(newton_state* ns, long k, double dq, double dq_prev, double theta_max)
{
    if (dq_prev > 0.0) {
        ns->theta = dq / dq_prev;
        ns->theta_step = k;
    }
    return ns->theta > theta_max;
}

static fsr_status newton_failed(sim* s, double t1, double dq, int it)
{
    return fail(s, FSR_NEWTON_FAILED,
                "Newton iterations did not converge at t = %.6g s (|dq| = %.3g m after %d "
                "iterations); reduce --dt", t1, dq, it);
}

/* A non-finite Newton update: name the coordinate (q, v: nq values each, stage after stage). */
static fsr_status newton_diverged(sim* s, double t1, const double* q, const double* v, int nq)
{
    for (int i = 0; i < nq; i += s->n) {
        fsr_status st = check_state(s, t1, q + i, v + i);
        if (st) return st;
    }
    return fail(s, FSR_DIVERGED, "diverged at t = %.6g s: Newton update not finite", t1);
}

/* Predict the next acceleration by linear extrapolation (a + (a - a_old)) when that would
 * have predicted the last one better than a alone: at large steps it takes #1-#3 from 1.5-1.9
 * to 1.1-1.3 iterations per step; where the acceleration rings at high frequency (ef at 5 ms)
 * the constant predictor keeps winning. */
static int extrapolation_wins(int n, const double* a1, const double* a, const double* a_old)
{
    double e_const = 0.0, e_extra = 0.0;
    for (int i = 0; i < n; ++i) {
        e_const = max_abs(e_const, a1[i] - a[i]);
        e_extra = max_abs(e_extra, a1[i] - 2.0 * a[i] + a_old[i]);
    }
    return e_extra < e_const;
}

/* ------------------------------------------------------------ generalized-alpha, Newmark */

/* Generalized-alpha (Chung & Hulbert; Arnold & Bruls form for M(q) q'' = f) with Newton
 * iterations on the acceleration a1; q1 and v1 follow it linearly (dq1 = cb da, dv1 = cg da).
 * Newmark(gamma, beta) is the special case am = af = 0. The iteration matrix is rebuilt (at
 * the current iterate) when the step size changes or an iteration contracts the update by
 * less than NEWTON_THETA_MAX; every iteration with newton_full. */
static fsr_status alpha_begin(sim* s)
{
    const fsr_options* o = s->o;
    int n = s->n;
    if (o->method == FSR_NEWMARK) {
        s->am = s->af = 0.0;
        s->gam = o->nm_gamma;
        s->bet = o->nm_beta;
    } else {
        fsr_alpha c = fsr_alpha_coefficients(o->rho_inf);
        s->am = c.am;
        s->af = c.af;
        s->gam = c.gam;
        s->bet = c.bet;
    }
    s->ra = (1.0 - s->af) / (1.0 - s->am);
    s->pa = s->af / (1.0 - s->am);
    s->pb = -s->am / (1.0 - s->am);
    s->ns = (newton_state){0.0, -1.0, 0};
    s->extrapolate = 0;
    s->done = s->msteps < 1;
    /* work: a, ab, a1, q1, v1, res, ma, a_old (see alpha_step) */
    double *q = s->state, *a = s->work, *ab = a + n, *a_old = ab + 6 * n;
    fsr_status st = accel(s, 0.0, q, q + n, a);
    if (st) return st;
    memcpy(ab, a, sizeof(double) * (size_t)n);
    memcpy(a_old, a, sizeof(double) * (size_t)n);
    return FSR_OK;
}

static fsr_status alpha_step(sim* s)
{
    const fsr_options* o = s->o;
    int n = s->n;
    const double bet = s->bet, gam = s->gam, ra = s->ra, pa = s->pa, pb = s->pb;
    double *q = s->state, *v = q + n;
    /* a: acceleration, ab: the algorithmic acceleration; 1: their values at t1 */
    double *a = s->work, *ab = a + n, *a1 = ab + n, *q1 = a1 + n, *v1 = q1 + n, *res = v1 + n, *ma = res + n;
    double* a_old = ma + n;
    double *drive = s->dw + DW_STEP * s->nd, tol = o->newton_tol * s->L;
    newton_state* ns = &s->ns;
    fsr_status st;
    long k = s->k;
    double t = time_of(s, k), t1 = time_of(s, k + 1), h = t1 - t;
    double cb = h * h * bet * ra, cg = h * gam * ra, h2 = h * h;
    for (int i = 0; i < n; ++i) {  /* predictor a1; ab becomes ab(t1) - ra a1 */
        double abo = ab[i], abp = pa * a[i] + pb * abo;
        a1[i] = s->extrapolate ? 2.0 * a[i] - a_old[i] : a[i];
        double ab1 = abp + ra * a1[i];
        ab[i] = abp;
        q1[i] = q[i] + h * v[i] + h2 * ((0.5 - bet) * abo + bet * ab1);
        v1[i] = v[i] + h * ((1.0 - gam) * abo + gam * ab1);
    }
    drive_at(s, t1, drive);
    /* a new matrix for a new step size, not for the rounding of t1 - t */
    int rebuild = o->newton_full || fabs(h - ns->h) > 1e-6 * h;
    double dq = 0.0, dq_prev = -1.0;
    for (int it = 0;; ++it) {
        if (it == o->newton_max) return newton_failed(s, t1, dq, it);
        if ((st = mass_at(s, t1, q1, drive, 0))) return st;
        s->m->force(q1, v1, drive, o->p, res);
        s->r->force_evaluations++;
        fsr_matvec(s->Mraw, n, s->bw, a1, ma);
        for (int i = 0; i < n; ++i) res[i] -= ma[i];  /* -(M a1 - f) */
        if (rebuild) {
            s->m->residual_jac(q1, v1, a1, drive, o->p, s->Jq, s->Jv);
            newton_rows(s, 0, &cb, &cg);
            if ((st = newton_factor(s, t1))) return st;
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
            dq = max_abs(dq, cb * res[i]);
        }
        s->r->newton_iterations++;
        if (!isfinite(dq)) return newton_diverged(s, t1, q1, v1, n);
        int slow = newton_contraction(ns, k, dq, dq_prev, NEWTON_THETA_MAX);
        if (newton_converged(s, ns, k, dq, tol)) break;
        if (slow) rebuild = 1;
        dq_prev = dq;
    }
    for (int i = 0; i < n; ++i) ab[i] += ra * a1[i];
    s->extrapolate = extrapolation_wins(n, a1, a, a_old);
    memcpy(a_old, a, sizeof(double) * (size_t)n);
    memcpy(a, a1, sizeof(double) * (size_t)n);
    memcpy(q, q1, sizeof(double) * (size_t)(2 * n));  /* q1, v1 are contiguous, as q, v */
    s->k = k + 1;
    s->done = s->k >= s->msteps;
    return accept(s, t1, h, q, a, NULL);
}

/* ------------------------------------------------------------------ Radau IIA, 3 stages */

/* The 3-stage Radau IIA method (order 5, stage order 3, L-stable; Hairer & Wanner II, IV.5)
 * applied to y' = [q', q''], written on the stage accelerations A_i: the stage points are
 *     Q_i = q + c_i h q' + h^2 sum_j (a a)_ij A_j,   V_i = q' + h sum_j a_ij A_j,
 * and the 3n equations M(Q_i) A_i = f(Q_i, V_i, t + c_i h) are solved by Newton on A with the
 * matrix blocks (i, j) = [i == j] M + h^2 (a a)_ij dr/dq + h a_ij dr/dq' (newton_rows). The
 * method is stiffly accurate (c_3 = 1): q1 = Q_3, q1' = V_3, and A_3 is the acceleration at t1.
 * L-stability damps the stiff axial and high element modes that the step does not resolve. */

/* Rebuild radau5's iteration matrix when an iteration contracts by less than this, and at the
 * start of a step when the last one did (the first iteration is not spent on a stale matrix).
 * A rebuild (Jacobians, LU and inverse of the 3n x 3n matrix; ef: band LU of 195 unknowns) costs
 * 2-5 iterations, and the stopping test needs 3 iterations at large steps even with a fresh
 * matrix, so rebuilding often does not pay. CPU at 0.003 / 0.03 / 0.2: #3 at 0.25 s 0.140 /
 * 0.121 / 0.126 ms, #2 at 0.2 s 0.48 / 0.36 / 0.21 ms, prestress at 0.25 s 0.079 / 0.055 /
 * 0.054 ms; ef at 0.1 s 40 ms at 0.03, 34 at 0.1, 30 at 0.2, 28 at 0.3. */
#define RADAU_THETA_MAX 0.2

/* radau5's stopping test: the update is below tol, or (modified Newton) the error it leaves,
 * theta / (1 - theta) |dq|, is, theta being the largest of at least two contractions measured
 * in this step. No estimate from an earlier step, and not one ratio alone: the first, from the
 * predictor, can understate the contraction of the iterations after it (#1 at 0.2 s: |dq| =
 * 2.8e-4 then 1.8e-8 m, theta = 6.5e-5, an estimated error of 1.2e-12 m; the error left was
 * 1.9e-10 m, the next contraction 1e-2; stopping there, modified and full Newton differed by
 * 6e-7 m in v_tip over the 20 s, and by 7e-11 m with this test). */
static int radau_converged(const sim* s, double dq, double tol, double theta_hi, int ratios)
{
    if (dq <= tol) return 1;
    if (s->o->newton_full || ratios < 2 || !(theta_hi < 1.0)) return 0;
    return theta_hi / (1.0 - theta_hi) * dq <= tol;
}

static void radau_init(radau_tableau* T)
{
    const double r6 = sqrt(6.0);
    const double c[RADAU_STAGES] = {(4.0 - r6) / 10.0, (4.0 + r6) / 10.0, 1.0};
    const double a[RADAU_STAGES][RADAU_STAGES] = {
        {(88.0 - 7.0 * r6) / 360.0, (296.0 - 169.0 * r6) / 1800.0, (-2.0 + 3.0 * r6) / 225.0},
        {(296.0 + 169.0 * r6) / 1800.0, (88.0 + 7.0 * r6) / 360.0, (-2.0 - 3.0 * r6) / 225.0},
        {(16.0 - r6) / 36.0, (16.0 + r6) / 36.0, 1.0 / 9.0}};
    for (int i = 0; i < RADAU_STAGES; ++i) {
        T->c[i] = c[i];
        for (int j = 0; j < RADAU_STAGES; ++j) {
            T->a[i][j] = a[i][j];
            T->aa[i][j] = 0.0;
            for (int l = 0; l < RADAU_STAGES; ++l) T->aa[i][j] += a[i][l] * a[l][j];
            /* Lagrange basis polynomial j of the nodes c, at 1 + c_i */
            T->e[i][j] = 1.0;
            for (int l = 0; l < RADAU_STAGES; ++l)
                if (l != j) T->e[i][j] *= (1.0 + c[i] - c[l]) / (c[j] - c[l]);
        }
        T->x[i + 1] = c[i];
    }
    T->x[0] = 0.0;
    for (int j = 0; j <= RADAU_STAGES; ++j) {
        double d = 1.0;
        for (int l = 0; l <= RADAU_STAGES; ++l)
            if (l != j) d *= T->x[j] - T->x[l];
        T->wden[j] = 1.0 / d;
    }
}

/* Stage accelerations predicted by extrapolating the last step's (the polynomial through its
 * A_i at c_i, at c_i + 1; with a new step size, its A_3): it beats the constant predictor on
 * #1-#3 and ef at every step tried (2.8 instead of 3.4 iterations per step on #2 at 0.2 s). */
static void radau_predict(const radau_tableau* T, int n, int same_h, double* A)
{
    for (int r = 0; r < n; ++r) {
        double old[RADAU_STAGES];
        for (int j = 0; j < RADAU_STAGES; ++j) old[j] = A[j * n + r];
        for (int i = 0; i < RADAU_STAGES; ++i) {
            double x = 0.0;
            for (int j = 0; j < RADAU_STAGES; ++j) x += T->e[i][j] * old[j];
            A[i * n + r] = same_h ? x : old[RADAU_STAGES - 1];
        }
    }
}

/* Q_i += sum_j cq_ij d_j, V_i += sum_j cv_ij d_j (the stage points move with the stage
 * accelerations; d_j of coordinate r at d[r dr + j di]); returns max |sum_j cq_ij d_j|. */
static double radau_move(int n, double cq[RADAU_STAGES][RADAU_STAGES], double cv[RADAU_STAGES][RADAU_STAGES],
                         const double* d, int dr, int di, double* Q, double* V)
{
    double m = 0.0;
    for (int r = 0; r < n; ++r) {
        const double* x = d + r * dr;
        for (int i = 0; i < RADAU_STAGES; ++i) {
            double zq = 0.0, zv = 0.0;
            for (int j = 0; j < RADAU_STAGES; ++j) {
                zq += cq[i][j] * x[j * di];
                zv += cv[i][j] * x[j * di];
            }
            Q[i * n + r] += zq;
            V[i * n + r] += zv;
            m = max_abs(m, zq);
        }
    }
    return m;
}

/* The collocation polynomial of a radau5 step (degree 3 through [q, q'] at t and the stages at
 * t + c_i h; RADAU5's dense output, Hairer & Wanner II, IV.8) at t + theta h. It carries the
 * stage order, 3: the cubic through the stage points of the exact solution is within 5e-6 m of
 * it on v_tip over the spin-up at 0.2-0.25 s steps (#1-#3), 1.4e-7 m for ef at 0.1 s. */
static void radau_dense(const dense_step* d, double theta, const double* y1, double* out)
{
    const radau_tableau* T = d->T;
    const int n = d->m / 2;
    const double *Q = d->k, *V = d->k + RADAU_STAGES * n;
    double w[RADAU_STAGES + 1];
    for (int j = 0; j <= RADAU_STAGES; ++j) {  /* Lagrange basis on the nodes 0, c_1, c_2, c_3 */
        w[j] = T->wden[j];
        for (int l = 0; l <= RADAU_STAGES; ++l)
            if (l != j) w[j] *= theta - T->x[l];
    }
    for (int r = 0; r < n; ++r) {
        double zq = w[0] * d->y[r], zv = w[0] * d->y[n + r];
        for (int i = 0; i < RADAU_STAGES; ++i) {
            zq += w[i + 1] * Q[i * n + r];
            zv += w[i + 1] * V[i * n + r];
        }
        out[r] = zq;
        out[n + r] = zv;
    }
    (void)y1;  /* = the last stage */
}

/* Steps of --step (default dt; the last one ends at t_end), rows every dt from radau_dense.
 * Modified Newton as generalized-alpha: one matrix from the Jacobians at the
 * last stage, kept across iterations and steps, rebuilt at the current iterate on a new step
 * size or a contraction slower than RADAU_THETA_MAX; stopping test: radau_converged (3 or 4
 * iterations at large steps, 2 or 3 at small ones). newton_full: each block row from its own stage's
 * Jacobians, rebuilt every iteration (the exact Newton matrix), stopping on |dq| <= tol. */
static fsr_status radau_begin(sim* s)
{
    const fsr_options* o = s->o;
    const int n = s->n;
    double *q = s->state, *A = s->work;
    radau_init(&s->rt);
    s->h_prev = 0.0;
    s->H = o->step > 0.0 ? o->step : o->dt;
    s->msteps = (long)ceil(o->t_end / s->H - 1e-9);
    if (s->msteps < 1) s->msteps = 1;
    s->ns = (newton_state){0.0, -1.0, 0};
    s->done = 0;
    fsr_status st = accel(s, 0.0, q, q + n, A);
    if (st) return st;
    for (int i = 1; i < RADAU_STAGES; ++i) memcpy(A + i * n, A, sizeof(double) * (size_t)n);
    return FSR_OK;
}

static fsr_status radau_step(sim* s)
{
    const fsr_options* o = s->o;
    const int n = s->n, m = RADAU_STAGES * n, last = RADAU_STAGES - 1;
    const radau_tableau* T = &s->rt;
    double *y = s->state, *q = y, *v = y + n;
    double *A = s->work, *Q = A + m, *V = Q + m, *res = V + m, *f = res + m, *ma = f + n;
    double* y0 = ma + n;  /* [q, q'] at the start of the step, for rows inside it */
    double* drive[RADAU_STAGES];
    double tol = o->newton_tol * s->L;
    const double H = s->H;
    const long nsteps = s->msteps, k = s->k;
    newton_state* ns = &s->ns;
    fsr_status st;
    double t = (double)k * H, t1 = k + 1 >= nsteps ? o->t_end : (double)(k + 1) * H, h = t1 - t;
    double cq[RADAU_STAGES][RADAU_STAGES], cv[RADAU_STAGES][RADAU_STAGES];
    for (int i = 0; i < RADAU_STAGES; ++i) {
        drive[i] = s->dw + (DW_STEP + i) * s->nd;
        drive_at(s, i == last ? t1 : t + T->c[i] * h, drive[i]);
        for (int j = 0; j < RADAU_STAGES; ++j) {
            cq[i][j] = h * h * T->aa[i][j];
            cv[i][j] = h * T->a[i][j];
        }
    }
    if (k > 0) radau_predict(T, n, fabs(h - s->h_prev) <= 1e-6 * h, A);
    for (int i = 0; i < RADAU_STAGES; ++i)
        for (int r = 0; r < n; ++r) {
            Q[i * n + r] = q[r] + T->c[i] * h * v[r];
            V[i * n + r] = v[r];
        }
    radau_move(n, cq, cv, A, 1, n, Q, V);
    int rebuild = o->newton_full || fabs(h - ns->h) > 1e-6 * h || ns->theta > RADAU_THETA_MAX;
    double dq = 0.0, dq_prev = -1.0, theta_hi = 0.0;
    int ratios = 0;
    for (int it = 0;; ++it) {
        if (it == o->newton_max) return newton_failed(s, t1, dq, it);
        for (int i = 0; i < RADAU_STAGES; ++i) {  /* res = -(M(Q_i) A_i - f_i), interleaved */
            const double *Qi = Q + i * n, *Vi = V + i * n, *Ai = A + i * n;
            if ((st = mass_at(s, t + T->c[i] * h, Qi, drive[i], 0))) return st;
            s->m->force(Qi, Vi, drive[i], o->p, f);
            s->r->force_evaluations++;
            fsr_matvec(s->Mraw, n, s->bw, Ai, ma);
            for (int r = 0; r < n; ++r) res[r * RADAU_STAGES + i] = f[r] - ma[r];
            if (rebuild && (o->newton_full || i == last)) {
                s->m->residual_jac(Qi, Vi, Ai, drive[i], o->p, s->Jq, s->Jv);
                for (int b = o->newton_full ? i : 0; b <= i; ++b) newton_rows(s, b, cq[b], cv[b]);
            }
        }
        if (rebuild) {
            if ((st = newton_factor(s, t1))) return st;
            ns->h = h;
            ns->theta = dq_prev = -1.0;
            ratios = 0;
            rebuild = o->newton_full;
        }
        newton_solve(s, res);
        for (int r = 0; r < n; ++r)
            for (int i = 0; i < RADAU_STAGES; ++i) A[i * n + r] += res[r * RADAU_STAGES + i];
        dq = radau_move(n, cq, cv, res, RADAU_STAGES, 1, Q, V);
        s->r->newton_iterations++;
        if (!isfinite(dq)) return newton_diverged(s, t1, Q, V, m);
        int slow = newton_contraction(ns, k, dq, dq_prev, RADAU_THETA_MAX);
        if (dq_prev > 0.0) theta_hi = ratios++ ? max_abs(theta_hi, ns->theta) : ns->theta;
        if (radau_converged(s, dq, tol, theta_hi, ratios)) break;
        if (slow) rebuild = 1;
        dq_prev = dq;
    }
    memcpy(y0, y, sizeof(double) * (size_t)(2 * n));
    memcpy(q, Q + last * n, sizeof(double) * (size_t)n);
    memcpy(v, V + last * n, sizeof(double) * (size_t)n);
    s->h_prev = h;
    s->k = k + 1;
    s->done = s->k >= nsteps;
    dense_step d = {radau_dense, T, 2 * n, t, h, y0, Q};
    return accept(s, t1, h, y, A + last * n, &d);
}

/* What every run checks (shared with constrained.c): a finite initial state and the run-size
 * limits of limits.h (r->ncols set). Counts are checked as doubles before any conversion to
 * long (no overflow, no UB). */
fsr_status fsr_check_run(const fsr_options* o, const fsm_system* m, fsr_result* r)
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
    double rows = floor(grid / o->out_every) + 2.0;
    if (rows > (double)FSR_MAX_ROWS || rows * r->ncols * 8.0 > (double)FSR_MAX_ROW_BYTES)
        return fsr_fail(r, FSR_BAD_OPTIONS, "%.3g output rows of %d columns exceed the limits (%ld rows, "
                        "%ld bytes)", rows, r->ncols, FSR_MAX_ROWS, FSR_MAX_ROW_BYTES);
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
    if (o->method == FSR_NEWMARK && !(o->nm_gamma >= 0.5 && o->nm_beta > 0.0))
        return fail(s, FSR_BAD_OPTIONS, "Newmark gamma = %g, beta = %g: need gamma >= 1/2 and beta > 0 "
                    "(beta < gamma / 2: stable for omega_max dt <= 1 / sqrt(gamma / 2 - beta))",
                    o->nm_gamma, o->nm_beta);
    if (o->newton_max < 1 || !(o->newton_tol > 0.0))
        return fail(s, FSR_BAD_OPTIONS, "newton_max must be >= 1 and newton_tol > 0");
    if (!(o->tol >= 0.0 && o->tol < 1.0))
        return fail(s, FSR_BAD_OPTIONS, "tol must be in [0, 1) (got %g; 0 = fixed steps)", o->tol);
    if (o->max_steps < 1) return fail(s, FSR_BAD_OPTIONS, "max_steps must be >= 1 (got %ld)", o->max_steps);
    if (!(o->blowup > 0.0)) return fail(s, FSR_BAD_OPTIONS, "blowup must be > 0");
    if (!(o->step >= 0.0) || !isfinite(o->step))
        return fail(s, FSR_BAD_OPTIONS, "step must be >= 0 (got %g; 0 = steps of dt)", o->step);
    if (o->step > 0.0 && o->method != FSR_RADAU5)
        return fail(s, FSR_BAD_OPTIONS, "step is for radau5 (%s steps at dt)", fsr_method_name(o->method));
    if (fsr_check_run(o, s->m, s->r)) return s->r->status;
    for (int i = 0; i < s->m->np; ++i)
        if (!(o->p[i] > 0.0) || !isfinite(o->p[i]))
            return fail(s, FSR_BAD_OPTIONS, "beam parameter %s must be a positive number (got %g)",
                        s->m->param_names[i], o->p[i]);
    for (int i = 0; i < s->m->nmp; ++i)
        if (!isfinite(o->mp[i]))
            return fail(s, FSR_BAD_OPTIONS, "manoeuvre parameter %s must be finite",
                        s->m->drive_param_names[i]);
    return FSR_OK;
}

/* Everything before the first step: the method's starting values and, for explicit methods,
 * the stability check. */
static fsr_status sim_begin(sim* s)
{
    fsr_method method = s->o->method;
    if (method == FSR_GENALPHA || method == FSR_NEWMARK) {
        fsr_status st = check_newmark_step(s);
        return st ? st : alpha_begin(s);
    }
    if (method == FSR_RADAU5) return radau_begin(s);
    const erk_tableau* T = method == FSR_RK4 ? &RK4 : &DOPRI5;
    int fixed = !T->embedded || s->o->tol == 0.0;
    fsr_status st = estimate_omega_max(s, &s->r->omega_max);
    if (!st && fixed) st = check_fixed_step(s, T);
    if (!st) st = erk_begin(s, T);
    return st;
}

/* One step of the method (an adaptive one may be rejected); s->done after the last. */
static fsr_status sim_step(sim* s)
{
    fsr_method method = s->o->method;
    if (method == FSR_GENALPHA || method == FSR_NEWMARK) return alpha_step(s);
    if (method == FSR_RADAU5) return radau_step(s);
    return erk_advance(s);
}

/* Check the options and allocate a run with room for `capacity` rows (0: every row of the
 * run); the state starts at o->y0, else at the model's initial_state, else at rest.
 * sim_close releases it. */
static fsr_status sim_open(sim* s, const fsr_options* o, fsr_result* r, long capacity)
{
    const fsm_system* m = fsm_system_model();
    memset(s, 0, sizeof *s);
    memset(r, 0, sizeof *r);
    s->m = m;
    s->o = o;
    s->r = r;
    s->n = m->nq;
    r->ncols = 1 + m->ny + m->nq + (o->energy ? 3 : 0);
    fsr_status st = check_options(s);
    if (!st && m->nc > 0)
        st = fail(s, FSR_BAD_OPTIONS, "%s: this model has %d constraint equations: use ali3p or genalpha3",
                  fsr_method_name(o->method), m->nc);
    if (st) return st;
    int n = s->n;
    s->nd = m->nd;
    s->L = m->length_param >= 0 ? o->p[m->length_param] : m->length_scale;
    s->bw = m->bandwidth >= 0 && 2 * m->bandwidth + 1 < n ? m->bandwidth : -1;
    s->nsteps = (long)ceil(o->t_end / o->dt - 1e-9);
    if (s->nsteps < 1) s->nsteps = 1;
    s->msteps = s->nsteps;
    s->next_row = o->out_every < s->nsteps ? o->out_every : s->nsteps;
    s->capacity = capacity > 0 ? capacity : s->nsteps / o->out_every + 2;
    /* the Newton system: nst stages of n coordinates, interleaved (see newton_rows) */
    s->nst = o->method == FSR_RADAU5 ? RADAU_STAGES : 1;
    s->N = s->nst * n;
    s->kb = s->bw >= 0 && 2 * (s->nst * (s->bw + 1) - 1) + 1 < s->N ? s->nst * (s->bw + 1) - 1 : -1;
    /* work: alpha 8 n; radau5 16 n; explicit 18 n (7 stages, y1 and a stage of 2n); + 2n dense rows */
    size_t nn = (size_t)n * (size_t)n, NN = (size_t)s->N * (size_t)s->N;
    size_t work = (size_t)(2 * MAX_STAGES + 4) * (size_t)n + 2 * (size_t)n;
    r->rows = malloc(sizeof(double) * (size_t)s->capacity * (size_t)r->ncols);
    size_t base = 5 * nn + 2 * NN + (size_t)m->ny + (size_t)s->N + 4 * (size_t)n + work;
    size_t drives = (size_t)(DW_COUNT + 2) * (size_t)m->nd;  /* after the rest, at mem + base */
    double* mem = malloc(sizeof(double) * (base + drives));
    s->piv = malloc(sizeof(int) * (size_t)s->N);
    if (!r->rows || !mem || !s->piv) {
        free(mem);
        free(s->piv);
        s->piv = NULL;
        return fail(s, FSR_NO_MEMORY, "out of memory for %ld output rows", s->capacity);
    }
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

static void sim_close(sim* s)
{
    free(s->Mraw);  /* the start of the workspace */
    free(s->piv);
    s->Mraw = NULL;
    s->piv = NULL;
}

static int constrained_method(fsr_method m)
{
    return m == FSR_ALI3P || m == FSR_GENALPHA3;
}

fsr_status fsr_simulate(const fsr_options* o, fsr_result* r)
{
    /* the constrained integrators take the model as a struct (constrained.c, system.h) */
    if (constrained_method(o->method)) return fsr_simulate_system(fsm_system_model(), o, r);
    sim s;
    fsr_status st = sim_open(&s, o, r, 0);
    if (!st) st = store(&s, 0.0, s.state, s.state + s.n, NULL);
    if (!st) st = sim_begin(&s);
    while (!st && !s.done) st = sim_step(&s);
    sim_close(&s);
    r->status = st;
    return st;
}

/* ------------------------------------------------------------ a run advanced by the caller */

struct fsr_stepper {
    sim s;
    csim c;         /* instead of s for ali3p and genalpha3 (constrained.c) */
    int constrained;
    fsr_options o;  /* a copy; p and mp still point to the caller's arrays */
    fsr_result r;   /* status, message, counters; rows: the one row at the current time */
};

fsr_stepper* fsr_stepper_new(const fsr_options* o, const double* drive)
{
    fsr_stepper* p = calloc(1, sizeof *p);
    if (!p) return NULL;
    sim* s = &p->s;
    p->o = *o;
    p->o.out_every = 1;  /* any grid point may be asked for */
    if (constrained_method(o->method)) {
        csim* c = &p->c;
        p->constrained = 1;
        fsr_status st = cs_open(c, fsm_system_model(), &p->o, &p->r, 1);
        if (!st && drive)
            st = cs_fail(c, FSR_BAD_OPTIONS, "%s: no drive given step by step (the model's drive runs)",
                         fsr_method_name(o->method));
        if (!st) st = cs_start(c);
        p->r.status = st;
        return p;
    }
    fsr_status st = sim_open(s, &p->o, &p->r, 1);
    if (!st && !(o->method == FSR_GENALPHA || o->method == FSR_NEWMARK || o->method == FSR_RK4
                 || (o->method == FSR_DOPRI5 && o->tol == 0.0)
                 || (o->method == FSR_RADAU5 && (o->step == 0.0 || o->step == o->dt))))
        st = fail(s, FSR_BAD_OPTIONS, "%s: the stepper takes fixed steps of dt (dopri5 needs tol = 0, "
                  "radau5 no step other than dt)", fsr_method_name(o->method));
    if (!st && drive && (o->method == FSR_RK4 || o->method == FSR_DOPRI5 || newmark_conditional(o)))
        st = fail(s, FSR_BAD_OPTIONS, "%s: a drive given step by step needs an unconditionally stable "
                  "method (the stability limit of this one depends on the drive to come)",
                  fsr_method_name(o->method));
    if (!st && drive && s->nd != 4)
        st = fail(s, FSR_BAD_OPTIONS, "a drive given step by step needs a model with one guided joint "
                  "(this one has %d drive values)", s->nd);
    if (!st && drive) {
        s->drive_held = 1;
        s->hold_t = 0.0;
        s->hold_theta = 0.0;
        s->hold[0] = drive[0];
        s->hold[1] = drive[1];
    }
    if (!st) st = store(s, 0.0, s->state, s->state + s->n, NULL);
    if (!st) st = sim_begin(s);
    p->r.status = st;
    return p;
}

const fsr_result* fsr_stepper_result(const fsr_stepper* p)
{
    return &p->r;
}

double fsr_stepper_time(const fsr_stepper* p)
{
    return p->constrained ? cs_time(&p->c, p->c.k) : time_of(&p->s, p->s.k);
}

/* A refused request leaves the run as it was: the message says why, the status stays. */
static fsr_status refuse(fsr_stepper* p, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(p->r.message, sizeof p->r.message, fmt, ap);
    va_end(ap);
    return FSR_BAD_OPTIONS;
}

fsr_status fsr_stepper_advance(fsr_stepper* p, double t)
{
    sim* s = &p->s;
    csim* c = &p->c;
    fsr_result* r = &p->r;
    const fsr_options* o = &p->o;
    if (r->status) return r->status;
    long now = p->constrained ? c->k : s->k, nsteps = p->constrained ? c->nsteps : s->nsteps;
    double dt = o->dt, x = t / dt;
    if (!(x > (double)now && x < (double)nsteps + 0.5))
        return refuse(p, "t = %.17g s is not after the current time %.17g s and up to t_end = %.17g s", t,
                      fsr_stepper_time(p), o->t_end);
    double eps = 1e-9 * (dt > fabs(t) ? dt : fabs(t));
    long k = fabs(t - o->t_end) <= eps ? nsteps : (long)floor(x + 0.5);
    if (k > nsteps) k = nsteps;
    double tk = k >= nsteps ? o->t_end : (double)k * dt;
    if (k <= now || !(fabs(tk - t) <= eps))
        return refuse(p, "t = %.17g s is not on the step grid (multiples of dt = %.17g s, and t_end)", t, dt);
    r->nrows = 0;
    fsr_status st = FSR_OK;
    if (p->constrained) {
        c->next_row = k;
        while (!st && c->k < k) st = cs_step(c);
    } else {
        s->next_row = k;
        while (!st && s->k < k) st = sim_step(s);
    }
    r->nrows = 1;  /* the row at t_k; after a failure, the last row stored */
    r->status = st;
    return st;
}

fsr_status fsr_stepper_set_drive(fsr_stepper* p, double theta_d, double theta_dd)
{
    sim* s = &p->s;
    if (!s->drive_held) return refuse(p, "this run takes its drive from the manoeuvre");
    if (!isfinite(theta_d) || !isfinite(theta_dd)) return refuse(p, "drive values must be finite");
    double now = time_of(s, s->k), tau = now - s->hold_t;
    s->hold_theta += tau * (s->hold[0] + 0.5 * s->hold[1] * tau);  /* theta continues */
    s->hold_t = now;
    s->hold[0] = theta_d;
    s->hold[1] = theta_dd;
    return FSR_OK;
}

fsr_status fsr_stepper_retune(fsr_stepper* p)
{
    sim* s = &p->s;
    fsr_result* r = &p->r;
    if (r->status) return r->status;
    if (p->constrained) return refuse(p, "%s: retuning is not available yet", fsr_method_name(p->o.method));
    fsr_status st = check_options(s);
    if (st) return st;
    s->L = s->m->length_param >= 0 ? s->o->p[s->m->length_param] : s->m->length_scale;
    s->mass_have = s->mass_factored = 0;     /* M(p) again, factored */
    s->drive_valid[0] = s->drive_valid[1] = 0;  /* the manoeuvre at the new mp */
    s->ns.h = 0.0;                            /* a new Newton matrix at the next step */
    if (s->T) {                               /* explicit: the stability limit may have moved */
        st = estimate_omega_max(s, &r->omega_max);
        if (!st && !s->adaptive) st = check_fixed_step(s, s->T);
        s->have_k0 = 0;                       /* k[0] and the work space were overwritten */
    } else if (!st) {
        st = check_newmark_step(s);          /* a conditionally stable Newmark: likewise */
    }
    r->status = st;
    return st;
}

void fsr_stepper_free(fsr_stepper* p)
{
    if (!p) return;
    if (p->constrained) cs_close(&p->c);
    else sim_close(&p->s);
    fsr_free(&p->r);
    free(p);
}

void fsr_free(fsr_result* r)
{
    free(r->rows);
    r->rows = NULL;
    r->nrows = 0;
}
