/* The one interface of the runtime's integrators, one file each: rk4.c, dopri5.c (both on the
 * explicit Runge-Kutta engine erk.c), genalpha.c, newmark.c, radau5.c integrate M q'' = f on a
 * run of ode.h (nc = 0); ali3p.c, genalpha3.c, rk4p.c integrate with constraints on a run of
 * constrained.h (any nc). The run loop (simulate.c) picks one from its table by method or name,
 * opens the run with the workspace the integrator declares, calls begin once, then step until
 * the run is done. Internal to the runtime. */
#ifndef FLEXSYM_INTEGRATOR_H
#define FLEXSYM_INTEGRATOR_H

#include <stddef.h>

#include "flexsym/runtime.h"

struct sim;   /* ode.h */
struct csim;  /* constrained.h */

typedef struct fsr_integrator {
    const char* name;           /* as in --integrator */
    fsr_method method;
    /* 1 when these options make the step limited by stability (explicit methods; Newmark with
     * beta < gamma / 2): a drive given step by step is refused. NULL: never */
    int (*stability_limited)(const fsr_options* o);
    int stages;                 /* stages coupled in its Newton system (radau5: 3; else 1) */
    size_t state_size;          /* bytes of what it carries from step to step (sim.ms) */
    size_t (*work_size)(int n); /* doubles of workspace for n coordinates (sim.work, csim.work) */
    /* 1 when the run takes steps of dt on the output grid (fsr_stepper); NULL: always */
    int (*fixed_grid)(const fsr_options* o);
    /* exactly one family: a run of M q'' = f (nc = 0) ... */
    fsr_status (*begin)(struct sim* s);
    fsr_status (*step)(struct sim* s);     /* one step (an adaptive one may be rejected) */
    fsr_status (*retune)(struct sim* s);   /* after o->p or o->mp changed; NULL: nothing kept */
    /* ... or a run with constraints (any nc), begun after the consistent initial state */
    fsr_status (*cs_begin)(struct csim* s);
    fsr_status (*cs_step)(struct csim* s);
} fsr_integrator;

/* Each integrator's file gives its descriptor. */
const fsr_integrator* fsr_integrator_rk4(void);
const fsr_integrator* fsr_integrator_dopri5(void);
const fsr_integrator* fsr_integrator_genalpha(void);
const fsr_integrator* fsr_integrator_newmark(void);
const fsr_integrator* fsr_integrator_radau5(void);
const fsr_integrator* fsr_integrator_ali3p(void);
const fsr_integrator* fsr_integrator_genalpha3(void);
const fsr_integrator* fsr_integrator_rk4p(void);

#endif
