/* The explicit Runge-Kutta engine (erk.c) behind rk4.c and dopri5.c: y' = [q', q''] with
 * M(q) q'' = f, one Butcher tableau per method. Internal to the runtime. */
#ifndef FLEXSYM_ERK_H
#define FLEXSYM_ERK_H

#include "ode.h"

enum { MAX_STAGES = 7 };

/* Stability for the undamped modes of these models (eigenvalues +-i omega): RK4 needs
 * dt omega <= 2.83 (2.785 used: its real-axis bound, a margin for the damping-like terms);
 * dopri5 leaves the imaginary axis at 1.0 (|R| = 1 + 1.4e-6 there, 1.005 at 1.6, 1.03 at 2)
 * although its real-axis bound is 3.3. Its error control holds adaptive steps near 1.4. */
typedef struct erk_tableau {
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

/* What the engine carries from step to step (sim.ms) */
typedef struct {
    const erk_tableau* T;
    int adaptive;      /* embedded pair and tol > 0: step-size control */
    int have_k0;       /* k[0] = f(t, y) is in the workspace */
    int rejected;      /* the last step was rejected */
    double t, h, err_old;
} erk_state;

/* The start of a run (after the row at t = 0): the stability estimate r->omega_max, a fixed
 * step above the stability limit refused, the first step of an adaptive run. */
fsr_status erk_begin(sim* s, const erk_tableau* T);
/* One step (accepted, or rejected by the adaptive step control); s->done after the last. */
fsr_status erk_advance(sim* s);
/* After new parameters: the stability estimate and the fixed-step check again. */
fsr_status erk_retune(sim* s);
/* doubles: 7 stages of 2n, y1 and a stage point */
size_t erk_work_size(int n);
/* explicit steps are always limited by stability */
int erk_stability_limited(const fsr_options* o);

#endif
