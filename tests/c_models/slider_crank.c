/* Rigid slider-crank: crank (radius r) guided by the paper's profile phi = P(t; ws, ts) + phi0,
 * connecting rod (length l, uniform, mass m_rod) on a revolute joint at the crank pin, slider
 * (mass m_s) on a prismatic joint along x. q = [beta (rod angle relative to the crank), s]; the
 * revolute joint rod tip - slider is the cut joint (2 equations). Outputs: x_s, the crank angle,
 * the slider's acceleration and the two multipliers (lambda_x = m_s x_s'' for a slider on a
 * frictionless guide). */
#include <math.h>

#include "planar.h"

static const double PI = 3.14159265358979323846;

enum { R, LEN, MROD, MS };
static const char* const coord_names[] = {"beta", "s"};
static const unsigned char coord_unbounded[] = {1, 0};  /* beta: an angle, no blow-up bound */
static const char* const constraint_names[] = {"slider_pin.x", "slider_pin.y"};
static const char* const output_names[] = {"x_s", "phi", "a_s", "lambda_x", "lambda_y"};
static const char* const param_names[] = {"r", "l", "m_rod", "m_s"};
static const double param_defaults[] = {0.15, 0.3, 0.0668, 0.0334};
static const char* const drive_param_names[] = {"ws", "ts", "phi0"};
static const double drive_param_defaults[] = {150.0, 0.1, 0.0};

void pl_describe(const double* p, pl_model* m)
{
    *m = (pl_model){0};
    m->nq = 2;
    m->nb = 2;
    m->nc = 2;
    /* crank pin C = r e(theta); rod: psi = theta + beta, G = C + (l/2) e(psi) */
    pl_angle crank = {0.0, 1.0, {0.0, 0.0}}, rod = {0.0, 1.0, {1.0, 0.0}};
    pl_body* b = &m->body[0];
    b->m = p[MROD];
    b->J = p[MROD] * p[LEN] * p[LEN] / 12.0;
    b->psi = rod;
    b->G.narms = 2;
    b->G.len[0] = p[R];
    b->G.arm[0] = crank;
    b->G.len[1] = 0.5 * p[LEN];
    b->G.arm[1] = rod;
    b = &m->body[1];  /* slider: (s, 0) */
    b->m = p[MS];
    b->G.lin[1][0] = 1.0;
    for (int c = 0; c < 2; ++c) {
        pl_point* tip = &m->con[c].a;
        tip->narms = 2;
        tip->len[0] = p[R];
        tip->arm[0] = crank;
        tip->len[1] = p[LEN];
        tip->arm[1] = rod;
        m->con[c].b.lin[1][0] = 1.0;
        m->con[c].comp = c;
    }
}

/* the paper's eq. (39) plus phi0: d = [t, theta, theta', theta''] */
static void drive(const double* t, const double* mp, double* d)
{
    const double ws = mp[0], ts = mp[1], tt = *t, w = 2.0 * PI / ts;
    d[0] = tt;
    if (tt <= ts) {
        d[1] = mp[2] + ws / ts * (tt * tt / 2.0 + (cos(w * tt) - 1.0) / (w * w));
        d[2] = ws / ts * (tt - sin(w * tt) / w);
        d[3] = ws / ts * (1.0 - cos(w * tt));
    } else {
        d[1] = mp[2] + ws * (tt - ts / 2.0);
        d[2] = ws;
        d[3] = 0.0;
    }
}

static void outputs(const double* q, const double* qd, const double* qdd, const double* lambda,
                    const double* d, const double* p, double* y)
{
    (void)qd;
    (void)p;
    y[0] = q[1];
    y[1] = d[1];
    y[2] = qdd[1];
    y[3] = lambda[0];
    y[4] = lambda[1];
}

/* a rough guess: the assembly Newton closes the loop */
static void initial_state(const double* p, const double* mp, double* q, double* qd)
{
    q[0] = 0.1 - mp[2];
    q[1] = 0.9 * (p[R] + p[LEN]);
    qd[0] = qd[1] = 0.0;
}

static const fsm_system model = {
    .name = "slider_crank", .fingerprint = "hand-written", .generator = "tests/c_models",
    .nq = 2, .nd = 4, .nc = 2, .ny = 5, .np = 4, .nmp = 3,
    .length_scale = 0.45, .length_param = -1, .mass_constant = 1, .bandwidth = -1,
    .outputs_use_acceleration = 1, .outputs_use_drive = 1,
    .coord_names = coord_names, .coord_unbounded = coord_unbounded,
    .constraint_names = constraint_names, .output_names = output_names,
    .param_names = param_names, .param_defaults = param_defaults,
    .drive_param_names = drive_param_names, .drive_param_defaults = drive_param_defaults,
    .drive = drive, .mass = pl_mass, .force = pl_force, .residual_jac = pl_residual_jac,
    .constraints = pl_constraints, .constraint_jac = pl_constraint_jac,
    .constraint_rate = pl_constraint_rate, .constraint_acc = pl_constraint_acc,
    .outputs = outputs, .energy = pl_energy, .initial_state = initial_state};

const fsm_system* fsm_slider_crank_model(void)
{
    return &model;
}
