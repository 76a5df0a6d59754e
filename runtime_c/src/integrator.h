/* The one interface of the runtime's integrators, one file each: src/<name>.c gives the
 * descriptor fsr_integrator_<name>() below. rk4.c, dopri5.c (both on the explicit Runge-Kutta
 * engine erk.c), genalpha.c, newmark.c, radau5.c integrate M q'' = f on a run of ode.h (nc = 0);
 * ali3p.c, genalpha3.c, rk4p.c integrate with constraints on a run of constrained.h (any nc).
 * Which integrators exist, their names, codes and capabilities are the registry's, the one list
 * in flexsym/integrators.h; adding an integrator is its file plus one line there. The run loop
 * (simulate.c) picks one from the registry by method or name, opens the run with the workspace
 * the descriptor declares, calls begin once, then step until the run is done. Internal to the
 * runtime. */
#ifndef FLEXSYM_INTEGRATOR_H
#define FLEXSYM_INTEGRATOR_H

#include <stddef.h>

#include "flexsym/runtime.h"

struct sim;   /* ode.h */
struct csim;  /* constrained.h */

typedef struct fsr_integrator {
    /* 1 when these options make the step limited by stability (explicit methods; Newmark with
     * beta < gamma / 2): a drive given step by step is refused. NULL: never */
    int (*stability_limited)(const fsr_options* o);
    int stages;                 /* stages coupled in its Newton system (radau5: 3; else 1) */
    size_t state_size;          /* bytes of what it carries from step to step (sim.ms) */
    size_t (*work_size)(int n); /* doubles of workspace for n coordinates (sim.work, csim.work) */
    /* without FSR_CAP_FIXED_GRID: 1 when these options make the run take steps of dt on the
     * output grid (fsr_stepper takes no other); NULL with FSR_CAP_FIXED_GRID */
    int (*fixed_grid)(const fsr_options* o);
    /* exactly one family, as the registry line says (FSR_CAP_CONSTRAINED): a run of
     * M q'' = f (nc = 0) ... */
    fsr_status (*begin)(struct sim* s);
    fsr_status (*step)(struct sim* s);     /* one step (an adaptive one may be rejected) */
    fsr_status (*retune)(struct sim* s);   /* after o->p or o->mp changed; NULL: nothing kept */
    /* ... or a run with constraints (any nc), begun after the consistent initial state */
    fsr_status (*cs_begin)(struct csim* s);
    fsr_status (*cs_step)(struct csim* s);
} fsr_integrator;

/* Each integrator's file gives its descriptor: fsr_integrator_<name>() for each registry line. */
#define FSR_INTEGRATOR(name, NAME, code, caps) const fsr_integrator* fsr_integrator_##name(void);
#include "flexsym/integrators.h"
#undef FSR_INTEGRATOR

#endif
