/* A run of M(q) q'' = f (a model without constraints, nc = 0) for the integrators rk4, dopri5,
 * genalpha, newmark and radau5 (integrator.h): the state y = [q, q'], workspace allocated once
 * before the first step (the step loop never allocates), the drive, the mass matrix, divergence
 * checks and rows (ode.c). Internal to the runtime.
 *
 * Divergence (non-finite state, or a coordinate beyond blowup x the length scale) stops the
 * run with a message naming the time; the rows stored up to then are kept. A run is resumable
 * step by step: fsr_simulate runs it to t_end, fsr_stepper to the times the caller asks for (an
 * FMU's communication points), so both give the same rows bit for bit. */
#ifndef FLEXSYM_ODE_H
#define FLEXSYM_ODE_H

#include <string.h>

#include "common.h"
#include "integrator.h"
#include "linalg.h"

/* drive vectors of the callers: DW_ACCEL, DW_ROW, DW_STEP (+ stage: 3 radau stages), nd each */
enum { DW_ACCEL = 0, DW_ROW = 1, DW_STEP = 2, DW_COUNT = 2 + 3 };

typedef struct sim {
    const fsm_system* m;  /* the model (system.h) */
    const fsr_options* o;
    fsr_result* r;
    int n;
    int bw;        /* half-bandwidth of M used by the solvers, -1 = dense (or with a border) */
    int nst;       /* stages coupled in the Newton system: 1, or 3 for radau5 */
    int N;         /* its size, nst n (unknowns interleaved: coordinate r, stage i at r nst + i) */
    int kb;        /* its half-bandwidth (of its band block when the model has a border, see
                      fsr_band_layout), nst (bandwidth + 1) - 1, or -1 = dense */
    fsr_bordered band;  /* with kb >= 0: its factor's layout and border part (linalg.h) */
    double L;      /* length scale (fsr_length_scale) */
    long nsteps;   /* grid points t_k = k dt, t_nsteps = t_end */
    long next_row; /* grid index of the next output row; nsteps + 1 when all are written */
    double* Mraw;  /* mass matrix as evaluated */
    double* Mfac;  /* its Cholesky factor, or its LU factor (mass_lu) */
    double* Minv;  /* its inverse, when constant and dense */
    double* S;     /* Newton iteration matrix (N x N), LU-factored */
    double* Sinv;  /* its inverse, when dense */
    double* tmp;   /* N */
    double* Jq;
    double* Jv;
    double* y;     /* outputs */
    double* qdd;   /* accelerations for outputs that need them */
    double* zero;  /* n zeros */
    double* work;  /* the integrator's workspace (its work_size) */
    void* ms;      /* what the integrator carries from step to step (its state_size) */
    double* dense; /* 2n: a state between steps, for rows */
    int* piv;
    int* mpiv;     /* n: the pivots of M's LU factor */
    int mass_lu;   /* M is not symmetric (a body's prestress that reads its free frame's
                      acceleration, physics/spatial.py): Mfac is its LU factor */
    int mass_have, mass_factored; /* only trusted when the mass is constant */
    int nd;        /* drive vector d = [t, theta, theta', theta'', ...] */
    double* dw;    /* drive vectors of the callers (DW_*), nd each */
    double drive_t[2], *drive_v[2];
    int drive_valid[2], drive_next;
    int drive_held;   /* drive from the caller (fsr_stepper_set_drive), not the manoeuvre: */
    double hold_t, hold[2], hold_theta;  /* theta' = hold[0] + hold[1] (t - hold_t), theta'' =
                                            hold[1], theta = hold_theta + its integral */
    long capacity; /* rows */
    double* state; /* [q, q'] */
    long k;        /* steps taken (fixed steps) */
    long msteps;   /* steps of the method: nsteps, or radau5's own with --step */
    int done;      /* set by the integrator's step after the last */
} sim;

/* Check the options and allocate a run of model m by integrator `it` (method o->method) with
 * room for `capacity` rows (0: every row of the run); the state starts at o->y0, else at the
 * model's initial_state, else at rest. sim_close releases it. */
fsr_status sim_open(sim* s, const fsr_integrator* it, const fsm_system* m, const fsr_options* o, fsr_result* r,
                    long capacity);
void sim_close(sim* s);
/* After the caller changed o->p or o->mp: options checked again, caches dropped. */
fsr_status sim_retune(sim* s, const fsr_integrator* it);
fsr_status sim_fail(sim* s, fsr_status st, const char* fmt, ...);
/* Largest natural frequency of the model linearised at rest (power iteration on M^-1 K at five
 * times of the run; scratch: 2n doubles); a step of a method stable up to omega_max dt <=
 * stability refused above it, with `instead` suggested. */
fsr_status sim_omega_max(sim* s, double* scratch, double* omega);
fsr_status sim_check_step_limit(sim* s, const char* name, double stability, const char* instead);
/* t_k: k dt, t_end for k >= nsteps */
static inline double sim_time(const sim* s, long k)
{
    return fsr_step_time(s->o, s->nsteps, k);
}
/* The drive vector d (nd) at t into d (the last two times cached). */
void sim_drive(sim* s, double t, double* d);
/* M(q, d) into Mraw and, with factor, its Cholesky factor into Mfac; once when M is constant. */
fsr_status sim_mass(sim* s, double t, const double* q, const double* d, int factor);
/* res = f - M a at (q, v, a, d): the negated residual of an implicit integrator's iteration, in
 * one pass when the model has a residual kernel, else from mass and force (ma: n doubles). */
fsr_status sim_residual(sim* s, double t, const double* q, const double* v, const double* a,
                        const double* d, double* res, double* ma);
/* M at (q, d) in Mraw for a Newton matrix: there already when sim_residual formed it there. */
static inline fsr_status sim_newton_mass(sim* s, double t, const double* q, const double* d)
{
    return s->m->residual ? sim_mass(s, t, q, d, 0) : FSR_OK;
}
/* a = q'' = M^-1 f at (t, q, v) */
fsr_status sim_accel(sim* s, double t, const double* q, const double* v, double* a);
/* k = y' = [q', q''] at (t, y). */
fsr_status sim_deriv(sim* s, double t, const double* y, double* k);
/* x = A^-1 x by the explicit inverse of a dense A of size dim. */
static inline void sim_apply_inverse(sim* s, const double* Ainv, int dim, double* x)
{
    fsr_matvec(Ainv, dim, -1, x, s->tmp);
    memcpy(x, s->tmp, sizeof(double) * (size_t)dim);
}
/* FSR_OK, or FSR_DIVERGED naming the coordinate: not finite, or beyond blowup x L. */
fsr_status sim_check_state(sim* s, double t, const double* q, const double* v);
/* Append a row: t, outputs, q (and T, V, h with energy). */
fsr_status sim_store(sim* s, double t, const double* q, const double* v, const double* a);

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

/* Bookkeeping of an accepted step of length h ending at t1 with state y1 (and its acceleration
 * a1, or NULL): divergence check, counters, the rows due in (t1 - h, t1] (from the dense output
 * d between grid points; NULL: the step ends on the grid). */
fsr_status sim_accept(sim* s, double t1, double h, const double* y1, const double* a1, const dense_step* d);

#endif
