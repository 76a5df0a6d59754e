/* Many runs of one model (the struct of system.h) in one call (in-process runs and sweeps from
 * Python, see runtime.h).
 *
 * Every run goes through fsr_simulate with options built exactly as the driver builds them
 * (fsr_default_options, the model's default parameters, then the named inputs), so a run
 * here gives the same rows, bit for bit, as `flexsym_<variant>` with the same options.
 * Initial values q0_<coordinate>, qd0_<coordinate> (not a driver option) start a run from
 * another state; the coordinates not named start where the model starts them (its
 * initial_state, e.g. a system's joint `initial` values, else rest).
 * Summaries are taken over the stored rows (the output grid), so a sweep need not move them;
 * a model with constraints (nc > 0) has its violation column summarized between the outputs
 * and the coordinates, as in its rows.
 * A run that fails keeps its status, message and the summaries of the rows it computed;
 * the other runs are not affected.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "flexsym/runtime.h"
#include "flexsym/system.h"

/* How a named input reaches the options: a field of fsr_options, or a model parameter. */
typedef enum { IN_DOUBLE, IN_INT, IN_LONG, IN_METHOD, IN_P, IN_MP, IN_Y0 } input_kind;
typedef struct {
    input_kind kind;
    size_t offset;  /* IN_DOUBLE/IN_INT/IN_LONG: offset in fsr_options; IN_P/IN_MP/IN_Y0: index */
} input_slot;

typedef struct { const char* name; input_kind kind; size_t offset; } option_name;
static const option_name OPTIONS[] = {
    {"method", IN_METHOD, 0},
    {"t_end", IN_DOUBLE, offsetof(fsr_options, t_end)},
    {"dt", IN_DOUBLE, offsetof(fsr_options, dt)},
    {"out_every", IN_INT, offsetof(fsr_options, out_every)},
    {"step", IN_DOUBLE, offsetof(fsr_options, step)},
    {"rho_inf", IN_DOUBLE, offsetof(fsr_options, rho_inf)},
    {"nm_gamma", IN_DOUBLE, offsetof(fsr_options, nm_gamma)},
    {"nm_beta", IN_DOUBLE, offsetof(fsr_options, nm_beta)},
    {"newton_tol", IN_DOUBLE, offsetof(fsr_options, newton_tol)},
    {"newton_max", IN_INT, offsetof(fsr_options, newton_max)},
    {"newton_full", IN_INT, offsetof(fsr_options, newton_full)},
    {"tol", IN_DOUBLE, offsetof(fsr_options, tol)},
    {"max_steps", IN_LONG, offsetof(fsr_options, max_steps)},
    {"blowup", IN_DOUBLE, offsetof(fsr_options, blowup)},
    {"penalty", IN_DOUBLE, offsetof(fsr_options, penalty)},
};

static int find_input(const fsm_system* m, const char* name, input_slot* slot)
{
    for (size_t i = 0; i < sizeof OPTIONS / sizeof OPTIONS[0]; ++i)
        if (!strcmp(name, OPTIONS[i].name)) {
            slot->kind = OPTIONS[i].kind;
            slot->offset = OPTIONS[i].offset;
            return 1;
        }
    for (int i = 0; i < m->np; ++i)
        if (!strcmp(name, m->param_names[i])) { slot->kind = IN_P; slot->offset = (size_t)i; return 1; }
    for (int i = 0; i < m->nmp; ++i)
        if (!strcmp(name, m->drive_param_names[i])) { slot->kind = IN_MP; slot->offset = (size_t)i; return 1; }
    int rate = !strncmp(name, "qd0_", 4);
    if (rate || !strncmp(name, "q0_", 3))
        for (int i = 0; i < m->nq; ++i)
            if (!strcmp(name + (rate ? 4 : 3), m->coord_names[i])) {
                slot->kind = IN_Y0;
                slot->offset = (size_t)(rate ? m->nq + i : i);
                return 1;
            }
    return 0;
}

static void set_input(const input_slot* s, double v, fsr_options* o, double* p, double* mp, double* y0)
{
    char* base = (char*)o;
    switch (s->kind) {
    case IN_DOUBLE: *(double*)(base + s->offset) = v; break;
    case IN_INT: *(int*)(base + s->offset) = (int)v; break;
    case IN_LONG: *(long*)(base + s->offset) = (long)v; break;
    case IN_METHOD: o->method = (fsr_method)(int)v; break;
    case IN_P: p[s->offset] = v; break;
    case IN_MP: mp[s->offset] = v; break;
    case IN_Y0: y0[s->offset] = v; o->y0 = y0; break;
    }
}

static double thread_cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Per column j of the rows (1 .. ny [+ violation] + nq): min, max, their times, time of the peak |y|,
 * final value, then the values at the times `at` (linear between the bracketing rows, exact
 * at a row; NaN past the last row). */
static void summarize(const fsr_result* r, int ncs, int nat, const double* at, double* out)
{
    int nf = FSR_SUM_FIELDS + nat;
    for (int j = 0; j < ncs; ++j) {
        double* s = out + (size_t)j * (size_t)nf;
        for (int f = 0; f < nf; ++f) s[f] = NAN;
        if (r->nrows < 1) continue;
        const double* col = r->rows + 1 + j;
        size_t w = (size_t)r->ncols;
        double lo = col[0], hi = col[0], peak = fabs(col[0]);
        long ilo = 0, ihi = 0, ipeak = 0;
        for (long k = 1; k < r->nrows; ++k) {
            double v = col[(size_t)k * w];
            if (v < lo) { lo = v; ilo = k; }
            if (v > hi) { hi = v; ihi = k; }
            if (fabs(v) > peak) { peak = fabs(v); ipeak = k; }
        }
        s[FSR_SUM_MIN] = lo;
        s[FSR_SUM_MAX] = hi;
        s[FSR_SUM_T_MIN] = r->rows[(size_t)ilo * w];
        s[FSR_SUM_T_MAX] = r->rows[(size_t)ihi * w];
        s[FSR_SUM_T_PEAK] = r->rows[(size_t)ipeak * w];
        s[FSR_SUM_FINAL] = col[(size_t)(r->nrows - 1) * w];
        long k = 0;  /* the times are searched in order when sorted, from the start otherwise */
        for (int a = 0; a < nat; ++a) {
            if (a > 0 && at[a] < at[a - 1]) k = 0;
            while (k + 1 < r->nrows && r->rows[(size_t)(k + 1) * w] <= at[a]) ++k;
            double t0 = r->rows[(size_t)k * w];
            if (at[a] == t0) s[FSR_SUM_FIELDS + a] = col[(size_t)k * w];
            else if (k + 1 < r->nrows && at[a] > t0) {
                double t1 = r->rows[(size_t)(k + 1) * w], x = (at[a] - t0) / (t1 - t0);
                s[FSR_SUM_FIELDS + a] = col[(size_t)k * w] + x * (col[(size_t)(k + 1) * w] - col[(size_t)k * w]);
            }
        }
    }
}

/* Peak of sum_j w_j |y_j| over the rows, and the first time it exceeded limit (NaN: never). */
static void bound(const fsr_result* r, int ncs, const double* wts, double limit, double* peak, double* t_over)
{
    *peak = NAN;
    *t_over = NAN;
    for (long k = 0; k < r->nrows; ++k) {
        const double* row = r->rows + (size_t)k * (size_t)r->ncols;
        double b = 0.0;
        for (int j = 0; j < ncs; ++j)
            if (wts[j] != 0.0) b += wts[j] * fabs(row[1 + j]);
        if (k == 0 || b > *peak) *peak = b;
        if (b > limit && isnan(*t_over)) *t_over = row[0];
    }
}

int fsr_batch(const fsm_system* m, int ninputs, const char* const* names, int nruns, const double* inputs,
              int nat, const double* at, const double* bound_weights, double bound_limit,
              double* summary, double* stats, int* status, char* messages, double** rows)
{
    input_slot slots[64];
    if (ninputs > 64 || m->np > 64 || m->nmp > 64) {
        snprintf(messages, FSR_BATCH_MESSAGE, "too many inputs or parameters (at most 64)");
        return -1;
    }
    for (int i = 0; i < ninputs; ++i)
        if (!find_input(m, names[i], &slots[i])) {
            snprintf(messages, FSR_BATCH_MESSAGE, "unknown input '%s'", names[i]);
            return -1;
        }
    int named_y0 = 0;
    for (int i = 0; i < ninputs; ++i) named_y0 |= slots[i].kind == IN_Y0;
    int ncs = m->ny + (m->nc > 0) + m->nq;  /* the row's columns after t (violation when nc > 0) */
    double* y0 = calloc((size_t)(2 * m->nq), sizeof(double));
    if (!y0) {
        snprintf(messages, FSR_BATCH_MESSAGE, "out of memory");
        return -1;
    }
    size_t per_run = (size_t)ncs * (size_t)(FSR_SUM_FIELDS + nat);
    int failed = 0;
    for (int i = 0; i < nruns; ++i) {
        fsr_options o;
        double p[64], mp[64];
        fsr_default_options(&o);
        memcpy(p, m->param_defaults, sizeof(double) * (size_t)m->np);
        memcpy(mp, m->drive_param_defaults, sizeof(double) * (size_t)m->nmp);
        const double* in = inputs + (size_t)i * (size_t)ninputs;
        for (int j = 0; j < ninputs; ++j)
            if (slots[j].kind != IN_Y0) set_input(&slots[j], in[j], &o, p, mp, y0);
        if (named_y0) {  /* the others from the model's initial state (this run's p, mp), or rest */
            memset(y0, 0, sizeof(double) * (size_t)(2 * m->nq));
            if (m->initial_state) m->initial_state(p, mp, y0, y0 + m->nq);
            for (int j = 0; j < ninputs; ++j)
                if (slots[j].kind == IN_Y0) set_input(&slots[j], in[j], &o, p, mp, y0);
        }
        o.p = p;
        o.mp = mp;
        fsr_result r;
        double t0 = thread_cpu_seconds();
        fsr_simulate(m, &o, &r);
        double cpu = thread_cpu_seconds() - t0;

        status[i] = (int)r.status;
        failed += r.status != FSR_OK;
        memcpy(messages + (size_t)i * FSR_BATCH_MESSAGE, r.message, FSR_BATCH_MESSAGE);
        messages[(size_t)i * FSR_BATCH_MESSAGE + FSR_BATCH_MESSAGE - 1] = '\0';
        summarize(&r, ncs, nat, at, summary + (size_t)i * per_run);
        double* st = stats + (size_t)i * FSR_STAT_FIELDS;
        st[FSR_STAT_T_STOP] = r.t_stop;
        st[FSR_STAT_STEPS] = (double)r.steps;
        st[FSR_STAT_REJECTED] = (double)r.rejected_steps;
        st[FSR_STAT_NEWTON] = (double)r.newton_iterations;
        st[FSR_STAT_JACOBIANS] = (double)r.jacobian_evaluations;
        st[FSR_STAT_FORCES] = (double)r.force_evaluations;
        st[FSR_STAT_OMEGA_MAX] = r.omega_max;
        st[FSR_STAT_NROWS] = (double)r.nrows;
        st[FSR_STAT_NCOLS] = (double)r.ncols;
        st[FSR_STAT_CPU] = cpu;
        st[FSR_STAT_BOUND_PEAK] = st[FSR_STAT_BOUND_T] = NAN;
        if (bound_weights) {
            double L = m->length_param >= 0 ? p[m->length_param] : m->length_scale;
            bound(&r, ncs, bound_weights, bound_limit * L, &st[FSR_STAT_BOUND_PEAK],
                  &st[FSR_STAT_BOUND_T]);
        }
        if (rows) {
            rows[i] = r.rows;  /* the caller owns it now: fsr_batch_free */
            r.rows = NULL;
        }
        fsr_free(&r);
    }
    free(y0);
    return failed;
}

void fsr_batch_free(double** rows, int nruns)
{
    for (int i = 0; i < nruns; ++i) {
        free(rows[i]);
        rows[i] = NULL;
    }
}
