/* flexsym runtime: time integration of a generated model (see model.h). */
#ifndef FLEXSYM_RUNTIME_H
#define FLEXSYM_RUNTIME_H

typedef enum { FSR_RK4 = 0, FSR_GENALPHA = 1, FSR_NEWMARK = 2 } fsr_method;

typedef enum {
    FSR_OK = 0,
    FSR_DIVERGED = 1,        /* non-finite state or runaway growth */
    FSR_NEWTON_FAILED = 2,   /* implicit step did not converge */
    FSR_SINGULAR = 3,        /* mass or iteration matrix singular / not positive definite */
    FSR_BAD_OPTIONS = 4,
    FSR_NO_MEMORY = 5
} fsr_status;

typedef struct {
    fsr_method method;
    double t_end;            /* integrate on [0, t_end] */
    double dt;               /* fixed step; the last step is shortened to end at t_end */
    int out_every;           /* store every out_every-th step (and the last one) */
    double rho_inf;          /* generalized-alpha spectral radius at infinity, in [0, 1] */
    double nm_gamma, nm_beta;/* Newmark parameters (method FSR_NEWMARK) */
    double newton_tol;       /* on |delta q|_inf, relative to the beam length */
    int newton_max;
    double blowup;           /* diverged when any |q_i| or |v_tip| exceeds blowup * L */
    const double* p;         /* beam parameters (model->np) */
    const double* mp;        /* manoeuvre parameters (model->nmp) */
} fsr_options;

typedef struct {
    fsr_status status;
    char message[512];
    double t_stop;           /* time of the last accepted step */
    long steps;
    long newton_iterations;
    long force_evaluations;
    int ncols;               /* 1 + ny + nq: t, outputs, coordinates */
    int nrows;
    double* rows;            /* nrows x ncols, row-major; owned, release with fsr_free */
} fsr_result;

void fsr_default_options(fsr_options* o);
/* Integrate; returns the status (also in r->status). Rows computed before a failure are kept. */
fsr_status fsr_simulate(const fsr_options* o, fsr_result* r);
void fsr_free(fsr_result* r);
const char* fsr_method_name(fsr_method m);

#endif
