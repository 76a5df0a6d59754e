/* Rigid four-bar under gravity (g = 9.81 m/s^2 along -y), released from rest: crank (l1) pinned
 * to ground at the origin, coupler (l2) pinned to the crank tip, rocker (l3) pinned to ground at
 * (a, 0); uniform bars of 1 kg/m. q = [psi1 (crank angle), beta (coupler relative to crank),
 * psi3 (rocker angle)]; the pin coupler - rocker is the cut joint. No guided joint (nd = 1).
 * Outputs: the three angles' rates are not needed; x, y of the coupler - rocker pin. */
#include "planar.h"

enum { A, L1, L2, L3, RHO };
static const char* const coord_names[] = {"psi1", "beta", "psi3"};
static const unsigned char coord_unbounded[] = {1, 1, 1};  /* angles: no blow-up bound */
static const char* const constraint_names[] = {"coupler_rocker.x", "coupler_rocker.y"};
static const char* const output_names[] = {"x_pin", "y_pin", "lambda_x", "lambda_y"};
static const char* const param_names[] = {"a", "l1", "l2", "l3", "rho_l"};
static const double param_defaults[] = {0.3, 0.1, 0.35, 0.25, 1.0};
static const char* const drive_param_names[] = {"psi1_0"};
static const double drive_param_defaults[] = {1.2};

static void bar(pl_body* b, double rho, double l)
{
    b->m = rho * l;
    b->J = b->m * l * l / 12.0;
}

void pl_describe(const double* p, pl_model* m)
{
    *m = (pl_model){0};
    m->nq = 3;
    m->nb = 3;
    m->nc = 2;
    m->g[1] = -9.81;
    pl_angle crank = {0.0, 0.0, {1.0, 0.0, 0.0}}, coupler = {0.0, 0.0, {1.0, 1.0, 0.0}},
             rocker = {0.0, 0.0, {0.0, 0.0, 1.0}};
    pl_body* b = &m->body[0];
    bar(b, p[RHO], p[L1]);
    b->psi = crank;
    b->G.narms = 1;
    b->G.len[0] = 0.5 * p[L1];
    b->G.arm[0] = crank;
    b = &m->body[1];
    bar(b, p[RHO], p[L2]);
    b->psi = coupler;
    b->G.narms = 2;
    b->G.len[0] = p[L1];
    b->G.arm[0] = crank;
    b->G.len[1] = 0.5 * p[L2];
    b->G.arm[1] = coupler;
    b = &m->body[2];
    bar(b, p[RHO], p[L3]);
    b->psi = rocker;
    b->G.base[0] = p[A];
    b->G.narms = 1;
    b->G.len[0] = 0.5 * p[L3];
    b->G.arm[0] = rocker;
    for (int c = 0; c < 2; ++c) {
        pl_point *end = &m->con[c].a, *tip = &m->con[c].b;
        end->narms = 2;
        end->len[0] = p[L1];
        end->arm[0] = crank;
        end->len[1] = p[L2];
        end->arm[1] = coupler;
        tip->base[0] = p[A];
        tip->narms = 1;
        tip->len[0] = p[L3];
        tip->arm[0] = rocker;
        m->con[c].comp = c;
    }
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
    double pos[2], vel[2], J[2 * PL_MAXQ], conv[2];
    (void)qdd;
    pl_describe(p, &m);
    pl_point_eval(&m.con[0].b, m.nq, q, qd, d, pos, vel, J, conv);
    y[0] = pos[0];
    y[1] = pos[1];
    y[2] = lambda[0];
    y[3] = lambda[1];
}

/* crank at psi1_0; coupler and rocker roughly where the open branch closes */
static void initial_state(const double* p, const double* mp, double* q, double* qd)
{
    (void)p;
    q[0] = mp[0];
    q[1] = -0.9;
    q[2] = 1.4;
    qd[0] = qd[1] = qd[2] = 0.0;
}

static const fsm_system model = {
    .name = "fourbar", .fingerprint = "hand-written", .generator = "tests/c_models",
    .nq = 3, .nd = 1, .nc = 2, .ny = 4, .np = 5, .nmp = 1,
    .length_scale = 0.3, .length_param = -1, .mass_constant = 0, .bandwidth = -1,
    .outputs_use_acceleration = 1, .outputs_use_drive = 1,
    .coord_names = coord_names, .coord_unbounded = coord_unbounded,
    .constraint_names = constraint_names, .output_names = output_names,
    .param_names = param_names, .param_defaults = param_defaults,
    .drive_param_names = drive_param_names, .drive_param_defaults = drive_param_defaults,
    .drive = drive, .mass = pl_mass, .force = pl_force, .residual_jac = pl_residual_jac,
    .constraints = pl_constraints, .constraint_jac = pl_constraint_jac,
    .constraint_rate = pl_constraint_rate, .constraint_acc = pl_constraint_acc,
    .outputs = outputs, .energy = pl_energy, .initial_state = initial_state};

const fsm_system* fsm_fourbar_model(void)
{
    return &model;
}
