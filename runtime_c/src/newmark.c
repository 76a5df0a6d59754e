/* newmark: Newmark's method with the parameters gamma, beta (o->nm_gamma, o->nm_beta): the
 * generalized-alpha step of genalpha.c with am = af = 0. beta >= (gamma + 1/2)^2 / 4 is
 * unconditionally stable (the default trapezoidal rule, beta = 1/4); beta < gamma / 2 only for
 * omega dt <= 1 / sqrt(gamma / 2 - beta) undamped, checked against the model's omega_max
 * before the first step and at a retune (sqrt(6) for Fox-Goodwin's beta = 1/12, whose period
 * error is fourth order, (omega dt)^4 / 480, against (omega dt)^2 / 12 for beta = 1/4). */
#include "genalpha.h"

#include <math.h>

static int conditional(const fsr_options* o)
{
    return o->nm_beta < 0.5 * o->nm_gamma;
}

/* omega_max's scratch past the 8n of the generalized-alpha state, which a retune keeps */
static fsr_status check_step(sim* s)
{
    const fsr_options* o = s->o;
    if (!conditional(o)) return FSR_OK;
    fsr_status st = sim_omega_max(s, s->work + alpha_work_size(s->n), &s->r->omega_max);
    if (st) return st;
    return sim_check_step_limit(s, "newmark", 1.0 / sqrt(0.5 * o->nm_gamma - o->nm_beta),
                                "a larger --newmark-beta");
}

static fsr_status newmark_begin(sim* s)
{
    fsr_alpha c = {0.0, 0.0, s->o->nm_gamma, s->o->nm_beta};
    fsr_status st = check_step(s);
    return st ? st : alpha_begin(s, c);
}

static fsr_status newmark_retune(sim* s)
{
    fsr_status st = alpha_retune(s);
    return st ? st : check_step(s);
}

static size_t newmark_work_size(int n)
{
    return alpha_work_size(n) + 2 * (size_t)n;
}

static const fsr_integrator INTEGRATOR = {
    .stability_limited = conditional, .stages = 1,
    .state_size = sizeof(alpha_state), .work_size = newmark_work_size,
    .begin = newmark_begin, .step = alpha_step, .retune = newmark_retune};

const fsr_integrator* fsr_integrator_newmark(void)
{
    return &INTEGRATOR;
}
