/* rk4: the classical 4-stage Runge-Kutta method with fixed steps of dt, on the explicit
 * engine erk.c; refused above the model's stability limit (dt omega_max <= 2.785). */
#include "erk.h"

static const erk_tableau RK4 = {
    "rk4", 4, 0, 0, 2.785, {0.0, 0.5, 0.5, 1.0},
    {{0.0}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}},
    {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}, {0.0}, {0.0}};

static fsr_status rk4_begin(sim* s)
{
    return erk_begin(s, &RK4);
}

static const fsr_integrator INTEGRATOR = {
    .stability_limited = erk_stability_limited, .stages = 1,
    .state_size = sizeof(erk_state), .work_size = erk_work_size,
    .begin = rk4_begin, .step = erk_advance, .retune = erk_retune};

const fsr_integrator* fsr_integrator_rk4(void)
{
    return &INTEGRATOR;
}
