/* flexsym runtime: time integration of a model given as the struct of system.h; every entry
 * point takes it (several models may live in one process). */
#ifndef FLEXSYM_RUNTIME_H
#define FLEXSYM_RUNTIME_H

#include "flexsym/system.h"

/* The integrators: one file each (src/integrator.h) and one line each in the registry,
 * flexsym/integrators.h, which gives their fsr_method codes and capabilities. ali3p, genalpha3,
 * rk4p (FSR_CAP_CONSTRAINED): the constrained integrators; they also run models without
 * constraints (nc = 0). */
enum {
    FSR_CAP_CONSTRAINED = 1,  /* a run with constraints (any nc); else a run of M q'' = f, nc = 0 */
    FSR_CAP_IMPLICIT = 2,     /* solves with Newton (the Newton options apply) */
    FSR_CAP_ADAPTIVE = 4,     /* adapts its step to tol (0: fixed steps of dt) */
    FSR_CAP_FIXED_GRID = 8,   /* steps of dt on the output grid whatever the options (without it:
                                 only for some, e.g. dopri5 with tol = 0, radau5 with step = dt) */
    FSR_CAP_DRIVE_INPUT = 16  /* takes a drive given step by step (fsr_stepper_new) */
};
typedef enum {
#define FSR_INTEGRATOR(name, NAME, code, caps) FSR_##NAME = code,
#include "flexsym/integrators.h"
#undef FSR_INTEGRATOR
} fsr_method;

typedef enum {
    FSR_OK = 0,
    FSR_DIVERGED = 1,        /* non-finite state or runaway growth */
    FSR_NEWTON_FAILED = 2,   /* implicit step did not converge */
    FSR_SINGULAR = 3,        /* mass or iteration matrix singular / not positive definite */
    FSR_BAD_OPTIONS = 4,
    FSR_NO_MEMORY = 5,
    FSR_UNSTABLE_STEP = 6,   /* fixed explicit step above the stability limit: refused */
    FSR_STEP_FAILED = 7,     /* adaptive step control gave up (too many steps, step underflow) */
    FSR_ASSEMBLY = 8         /* constraints cannot be satisfied at t = 0: refused before any step */
} fsr_status;

typedef struct {
    fsr_method method;
    double t_end;            /* integrate on [0, t_end] */
    double dt;               /* fixed step (last one shortened to end at t_end); for dopri5 the
                                output grid: rows at multiples of out_every * dt, and t_end */
    int out_every;           /* store every out_every-th grid point (and the last one) */
    double step;             /* radau5: step length, rows on the dt grid from its collocation
                                polynomial; 0 = steps of dt */
    double rho_inf;          /* generalized-alpha spectral radius at infinity, in [0, 1] */
    double nm_gamma, nm_beta;/* Newmark parameters (method FSR_NEWMARK) */
    double newton_tol;       /* on |delta q|_inf, relative to the length scale (system.h) */
    int newton_max;
    int newton_full;         /* 1: new Jacobian and factorisation every iteration (reference);
                                0: modified Newton, the iteration matrix is reused */
    double tol;              /* dopri5: rtol = atol / L (see erk.c); 0 = fixed steps dt */
    long max_steps;          /* dopri5: accepted + rejected steps before giving up */
    double blowup;           /* diverged when a coordinate exceeds blowup x the length scale
                                (system.h: coord_unbounded are exempt) */
    int energy;              /* 1: rows end with T, V and the Jacobi integral h (fsm_energy) */
    double penalty;          /* ali3p: kappa, the penalty term's weight against the mass matrix
                                (alpha = kappa (4 / dt^2) tr M / |Phi_q|_F^2 at t = 0) */
    const double* p;         /* parameters (model->np) */
    const double* mp;        /* manoeuvre parameters (model->nmp) */
    const double* y0;        /* initial state [q, q'] (2 nq values); NULL: at rest */
} fsr_options;

typedef struct {
    fsr_status status;
    char message[512];
    double t_stop;           /* time of the last accepted step */
    long steps;              /* accepted steps */
    long rejected_steps;     /* dopri5 */
    double h_min, h_max;     /* smallest and largest accepted step */
    long newton_iterations;
    long jacobian_evaluations; /* iteration matrices built (and factored) */
    long force_evaluations;
    double omega_max;        /* explicit methods: stability estimate [rad/s], else 0 */
    int ncols;               /* 1 + ny + nq: t, outputs, coordinates; constrained integrators on
                                a model with nc > 0: t, outputs, violation, coordinates */
    int nrows;
    double* rows;            /* nrows x ncols, row-major; owned, release with fsr_free */
} fsr_result;

void fsr_default_options(fsr_options* o);
/* Integrate model m (system.h) with method o->method; returns the status (also in r->status).
 * Rows computed before a failure are kept. A model with constraints (nc > 0) needs a
 * constrained integrator (FSR_CAP_CONSTRAINED); with those, the initial state is first made
 * consistent with the constraints (FSR_ASSEMBLY and a message naming the constraint with the
 * largest residual when it cannot be). */
fsr_status fsr_simulate(const fsm_system* m, const fsr_options* o, fsr_result* r);
void fsr_free(fsr_result* r);
const char* fsr_method_name(fsr_method m);
/* *m = the method named name (as fsr_method_name gives it); returns 0 when there is none. */
int fsr_method_by_name(const char* name, fsr_method* m);

/* The same run advanced by the caller, step by step (an FMU's doStep): fsr_simulate is this
 * loop run to t_end, so the rows at grid points are identical bit for bit. Fixed steps of dt
 * only (genalpha, newmark, rk4, dopri5 with tol = 0, radau5 with step 0 or dt).
 * drive: NULL to take theta', theta'' from the model's manoeuvre (o->mp), or [theta',
 * theta''] at t = 0 given by the caller, then by fsr_stepper_set_drive (implicit methods; a
 * model with one guided joint, nd = 4; theta is their integral from 0; methods with
 * FSR_CAP_DRIVE_INPUT). ali3p, genalpha3, rk4p: the model's own drive only, no retuning yet.
 * Returns NULL only when out of memory; check fsr_stepper_result(p)->status. */
typedef struct fsr_stepper fsr_stepper;
fsr_stepper* fsr_stepper_new(const fsm_system* m, const fsr_options* o, const double* drive);
/* Integrate to grid point t (a multiple of dt after the current time, or t_end). The row at t
 * is then fsr_stepper_result(p)->rows (ncols values). A stopped run stays stopped; a refused
 * request (t off the grid) returns FSR_BAD_OPTIONS with a message and changes nothing. */
fsr_status fsr_stepper_advance(fsr_stepper* p, double t);
/* From the current time on: theta' = theta_d + theta_dd (t - now), theta'' = theta_dd. */
fsr_status fsr_stepper_set_drive(fsr_stepper* p, double theta_d, double theta_dd);
/* After the caller changed values in o->p or o->mp: caches dropped, options checked again. */
fsr_status fsr_stepper_retune(fsr_stepper* p);
const fsr_result* fsr_stepper_result(const fsr_stepper* p);
double fsr_stepper_time(const fsr_stepper* p);
void fsr_stepper_free(fsr_stepper* p);

/* ---- Batch: many runs of model m in one call (batch.c; in-process runs and sweeps from Python) ----
 * Run r takes fsr_default_options and the model's default parameters, then sets the named
 * inputs to inputs[r * ninputs + i]: option names method (an fsr_method), t_end, dt,
 * out_every, step, rho_inf, nm_gamma, nm_beta, newton_tol, newton_max, newton_full, tol,
 * max_steps, blowup, penalty, a beam/manoeuvre parameter name of the model, or q0_<coordinate> /
 * qd0_<coordinate> for the initial state (the others start at rest). Each run goes through
 * fsr_simulate. Outputs, per run r:
 *   summary[r][j][f]  over the stored rows, column j = 0 .. ny + v + nq - 1 (outputs, the
 *                     violation when nc > 0 (v = 1, else 0), then coordinates), f = FSR_SUM_* then the values at the nat times `at`
 *                     (linear between rows, exact at a row, NaN past the last row);
 *   stats[r][FSR_STAT_*]; status[r] (fsr_status); messages + r * FSR_BATCH_MESSAGE;
 *   bound_weights (ny + v + nq, may be NULL): FSR_STAT_BOUND_PEAK is the peak over the rows of
 *     sum_j w_j |y_j|, FSR_STAT_BOUND_T the first time it exceeded bound_limit * L (NaN: never);
 *   rows (may be NULL): rows[r] receives run r's rows (FSR_STAT_NROWS x FSR_STAT_NCOLS,
 *     as fsr_result.rows), released with fsr_batch_free.
 * Returns the number of runs that did not end FSR_OK, or -1 (message in messages[0]) when an
 * input name is unknown. */
#define FSR_BATCH_MESSAGE 512
enum { FSR_SUM_MIN, FSR_SUM_MAX, FSR_SUM_T_MIN, FSR_SUM_T_MAX, FSR_SUM_T_PEAK, FSR_SUM_FINAL,
       FSR_SUM_FIELDS };
enum { FSR_STAT_T_STOP, FSR_STAT_STEPS, FSR_STAT_REJECTED, FSR_STAT_NEWTON, FSR_STAT_JACOBIANS,
       FSR_STAT_FORCES, FSR_STAT_OMEGA_MAX, FSR_STAT_NROWS, FSR_STAT_NCOLS, FSR_STAT_CPU,
       FSR_STAT_BOUND_PEAK, FSR_STAT_BOUND_T, FSR_STAT_FIELDS };
int fsr_batch(const fsm_system* m, int ninputs, const char* const* names, int nruns, const double* inputs,
              int nat, const double* at, const double* bound_weights, double bound_limit,
              double* summary, double* stats, int* status, char* messages, double** rows);
void fsr_batch_free(double** rows, int nruns);

#endif
