/* The generalized-alpha step on M q'' = f (genalpha.c), shared by genalpha and newmark.
 * Internal to the runtime. */
#ifndef FLEXSYM_GENALPHA_H
#define FLEXSYM_GENALPHA_H

#include "newton.h"

/* What the method carries from step to step (sim.ms) */
typedef struct {
    double am, af, gam, bet;  /* alpha_m, alpha_f, gamma, beta */
    double ra, pa, pb;        /* the algorithmic acceleration's recursion (alpha_begin) */
    int extrapolate;          /* predict a1 by linear extrapolation (extrapolation_wins) */
    newton_state ns;
} alpha_state;

/* The start of a run with coefficients c (after the row at t = 0): the acceleration at t = 0. */
fsr_status alpha_begin(sim* s, fsr_alpha c);
fsr_status alpha_step(sim* s);
fsr_status alpha_retune(sim* s);
/* doubles: a, ab, a1, q1, v1, res, ma, a_old */
size_t alpha_work_size(int n);

#endif
