/* radau5: the 3-stage Radau IIA method (order 5, L-stable) on M q'' = f by modified Newton on
 * the stage accelerations (newton.h); its own step length with --step, rows on the dt grid
 * from its collocation polynomial. */
#include <math.h>
#include <string.h>

#include "linalg.h"
#include "newton.h"

enum { RADAU_STAGES = 3 };

typedef struct {
    double c[RADAU_STAGES];
    double a[RADAU_STAGES][RADAU_STAGES];
    double aa[RADAU_STAGES][RADAU_STAGES];  /* a a: the displacement coefficients */
    double e[RADAU_STAGES][RADAU_STAGES];   /* predictor: A at c_i + 1 from the last step's A */
    double x[RADAU_STAGES + 1];             /* dense output: the nodes 0, c_1, c_2, c_3 */
    double wden[RADAU_STAGES + 1];          /* 1 / prod_{l != j} (x_j - x_l) */
} radau_tableau;

/* What the method carries from step to step (sim.ms) */
typedef struct {
    radau_tableau rt;
    double H, h_prev;   /* step length, last step */
    newton_state ns;
} radau_state;

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
            m = fsr_max_abs(m, zq);
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
    radau_state* rs = s->ms;
    const fsr_options* o = s->o;
    const int n = s->n;
    double *q = s->state, *A = s->work;
    radau_init(&rs->rt);
    rs->h_prev = 0.0;
    rs->H = o->step > 0.0 ? o->step : o->dt;
    s->msteps = (long)ceil(o->t_end / rs->H - 1e-9);
    if (s->msteps < 1) s->msteps = 1;
    rs->ns = (newton_state){0.0, -1.0, 0};
    s->done = 0;
    fsr_status st = sim_accel(s, 0.0, q, q + n, A);
    if (st) return st;
    for (int i = 1; i < RADAU_STAGES; ++i) memcpy(A + i * n, A, sizeof(double) * (size_t)n);
    return FSR_OK;
}

static fsr_status radau_step(sim* s)
{
    radau_state* rs = s->ms;
    const fsr_options* o = s->o;
    const int n = s->n, m = RADAU_STAGES * n, last = RADAU_STAGES - 1;
    const radau_tableau* T = &rs->rt;
    double *y = s->state, *q = y, *v = y + n;
    double *A = s->work, *Q = A + m, *V = Q + m, *res = V + m, *f = res + m, *ma = f + n;
    double* y0 = ma + n;  /* [q, q'] at the start of the step, for rows inside it */
    double* drive[RADAU_STAGES];
    double tol = o->newton_tol * s->L;
    const double H = rs->H;
    const long nsteps = s->msteps, k = s->k;
    newton_state* ns = &rs->ns;
    fsr_status st;
    double t = (double)k * H, t1 = k + 1 >= nsteps ? o->t_end : (double)(k + 1) * H, h = t1 - t;
    double cq[RADAU_STAGES][RADAU_STAGES], cv[RADAU_STAGES][RADAU_STAGES];
    for (int i = 0; i < RADAU_STAGES; ++i) {
        drive[i] = s->dw + (DW_STEP + i) * s->nd;
        sim_drive(s, i == last ? t1 : t + T->c[i] * h, drive[i]);
        for (int j = 0; j < RADAU_STAGES; ++j) {
            cq[i][j] = h * h * T->aa[i][j];
            cv[i][j] = h * T->a[i][j];
        }
    }
    if (k > 0) radau_predict(T, n, fabs(h - rs->h_prev) <= 1e-6 * h, A);
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
            if ((st = sim_residual(s, t + T->c[i] * h, Qi, Vi, Ai, drive[i], f, ma))) return st;
            for (int r = 0; r < n; ++r) res[r * RADAU_STAGES + i] = f[r];
            if (rebuild && (o->newton_full || i == last)) {
                if ((st = sim_newton_mass(s, t + T->c[i] * h, Qi, drive[i]))) return st;
                s->m->residual_jac(Qi, Vi, Ai, drive[i], o->p, s->Jq, s->Jv);
                for (int b = o->newton_full ? i : 0; b <= i; ++b) newton_rows(s, b, cq[b], cv[b]);
            }
        }
        if (rebuild) {
            if ((st = newton_factor(s, t1, dq))) return st;
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
        if (dq_prev > 0.0) theta_hi = ratios++ ? fsr_max_abs(theta_hi, ns->theta) : ns->theta;
        if (radau_converged(s, dq, tol, theta_hi, ratios)) break;
        if (slow) rebuild = 1;
        dq_prev = dq;
    }
    memcpy(y0, y, sizeof(double) * (size_t)(2 * n));
    memcpy(q, Q + last * n, sizeof(double) * (size_t)n);
    memcpy(v, V + last * n, sizeof(double) * (size_t)n);
    rs->h_prev = h;
    s->k = k + 1;
    s->done = s->k >= nsteps;
    dense_step d = {radau_dense, T, 2 * n, t, h, y0, Q};
    return sim_accept(s, t1, h, y, A + last * n, &d);
}

static fsr_status radau_retune(sim* s)
{
    radau_state* rs = s->ms;
    rs->ns.h = 0.0;  /* a new Newton matrix at the next step */
    return FSR_OK;
}

/* doubles: A, Q, V, res (3n each), f, ma, and y0 (2n) */
static size_t radau_work_size(int n)
{
    return 16 * (size_t)n;
}

static int radau_fixed_grid(const fsr_options* o)
{
    return o->step == 0.0 || o->step == o->dt;
}

static const fsr_integrator INTEGRATOR = {
    .stages = RADAU_STAGES,
    .state_size = sizeof(radau_state), .work_size = radau_work_size, .fixed_grid = radau_fixed_grid,
    .begin = radau_begin, .step = radau_step, .retune = radau_retune};

const fsr_integrator* fsr_integrator_radau5(void)
{
    return &INTEGRATOR;
}
