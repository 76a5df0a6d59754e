/* A rigid compound pendulum (uniform bar of length l, 1 kg/m, pinned at an end to ground at the
 * origin) under gravity, released from rest horizontal along +x: a tree without cut joints
 * (nc = 0) and without guided joints (nd = 1), run by every integrator. q = [psi]. */
#include "planar.h"

enum { L, RHO };
static const char* const coord_names[] = {"psi"};
static const unsigned char coord_unbounded[] = {1};  /* angles: no blow-up bound */
static const char* const output_names[] = {"x_tip", "y_tip"};
static const char* const param_names[] = {"l", "rho_l"};
static const double param_defaults[] = {1.0, 1.0};

void pl_describe(const double* p, pl_model* m)
{
    *m = (pl_model){0};
    m->nq = 1;
    m->nb = 1;
    m->g[1] = -9.81;
    pl_angle psi = {0.0, 0.0, {1.0}};
    pl_body* b = &m->body[0];
    b->m = p[RHO] * p[L];
    b->J = b->m * p[L] * p[L] / 12.0;
    b->psi = psi;
    b->G.narms = 1;
    b->G.len[0] = 0.5 * p[L];
    b->G.arm[0] = psi;
}

static void drive(const double* t, const double* mp, double* d)
{
    (void)mp;
    d[0] = *t;
}

static void outputs(const double* q, const double* qd, const double* qdd, const double* lambda,
                    const double* d, const double* p, double* y)
{
    pl_model m;
    pl_point tip = {{0.0, 0.0}, 1, {0.0}, {{0.0, 0.0, {1.0}}}, {{0.0}}};
    double pos[2], vel[2], J[2 * PL_MAXQ], conv[2];
    (void)qdd, (void)lambda;
    pl_describe(p, &m);
    tip.len[0] = p[L];
    pl_point_eval(&tip, 1, q, qd, d, pos, vel, J, conv);
    y[0] = pos[0];
    y[1] = pos[1];
}

static const fsm_system model = {
    .name = "pendulum", .fingerprint = "hand-written", .generator = "tests/c_models",
    .nq = 1, .nd = 1, .nc = 0, .ny = 2, .np = 2, .nmp = 0,
    .length_scale = 1.0, .length_param = 0, .mass_constant = 1, .bandwidth = -1,
    .outputs_use_acceleration = 0, .outputs_use_drive = 0,
    .coord_names = coord_names, .coord_unbounded = coord_unbounded, .output_names = output_names,
    .param_names = param_names, .param_defaults = param_defaults,
    .drive = drive, .mass = pl_mass, .force = pl_force, .residual_jac = pl_residual_jac,
    .outputs = outputs, .energy = pl_energy};

const fsm_system* fsm_pendulum_model(void)
{
    return &model;
}
