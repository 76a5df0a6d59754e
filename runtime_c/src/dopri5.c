/* dopri5: Dormand-Prince 5(4) on the explicit engine erk.c. With tol > 0, adaptive steps
 * (rtol = tol, atol = tol x the length scale) and rows on the dt grid from its dense output;
 * with tol = 0, fixed steps of dt, refused above the stability limit (dt omega_max <= 1). */
#include "erk.h"

static const erk_tableau DOPRI5 = {
    "dopri5", 7, 1, 1, 1.0, {0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0},
    {{0.0},
     {0.2},
     {3.0 / 40.0, 9.0 / 40.0},
     {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
     {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
     {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0},
     {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0}},
    {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0},
    {71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0,
     -1.0 / 40.0},
    {-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0,
     -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
     -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0}};

static fsr_status dopri5_begin(sim* s)
{
    return erk_begin(s, &DOPRI5);
}

static int dopri5_fixed_grid(const fsr_options* o)
{
    return o->tol == 0.0;
}

static const fsr_integrator INTEGRATOR = {
    .stability_limited = erk_stability_limited, .stages = 1,
    .state_size = sizeof(erk_state), .work_size = erk_work_size, .fixed_grid = dopri5_fixed_grid,
    .begin = dopri5_begin, .step = erk_advance, .retune = erk_retune};

const fsr_integrator* fsr_integrator_dopri5(void)
{
    return &INTEGRATOR;
}
