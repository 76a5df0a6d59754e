/* newmark: Newmark's method with the parameters gamma, beta (o->nm_gamma, o->nm_beta; checked
 * for unconditional stability in common.c): the generalized-alpha step of genalpha.c with
 * am = af = 0. */
#include "genalpha.h"

static fsr_status newmark_begin(sim* s)
{
    fsr_alpha c = {0.0, 0.0, s->o->nm_gamma, s->o->nm_beta};
    return alpha_begin(s, c);
}

static const fsr_integrator INTEGRATOR = {
    .name = "newmark", .method = FSR_NEWMARK, .stages = 1,
    .state_size = sizeof(alpha_state), .work_size = alpha_work_size,
    .begin = newmark_begin, .step = alpha_step, .retune = alpha_retune};

const fsr_integrator* fsr_integrator_newmark(void)
{
    return &INTEGRATOR;
}
