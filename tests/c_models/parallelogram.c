/* A parallelogram linkage with a redundant bar, under gravity (g along -y), released from rest:
 * three equal cranks (length l) pinned to ground at (0, 0), (a/2, 0) and (a, 0), a coupler
 * (length a) pinned to the first crank's tip and, by cut joints, to the tips of the other two
 * (at its end and its middle). q = [psi1, beta (coupler relative to crank 1), psi2, psi3]:
 * 4 coordinates, 4 constraint equations of rank 3 (the middle bar is redundant), 1 degree of
 * freedom. Uniform bars of 1 kg/m. The motion is the 1-DOF pendulum
 *     (sum m_crank l^2/3 + m_c l^2) psi'' = -g cos(psi) (l/2 sum m_crank + l m_c). */
#include "planar.h"

enum { A, L, RHO };
static const char* const coord_names[] = {"psi1", "beta", "psi2", "psi3"};
static const unsigned char coord_unbounded[] = {1, 1, 1, 1};  /* angles: no blow-up bound */
static const char* const constraint_names[] = {"coupler_crank2.x", "coupler_crank2.y",
                                                "coupler_crank3.x", "coupler_crank3.y"};
static const char* const output_names[] = {"psi1_rate", "lambda_2x", "lambda_3x"};
static const char* const param_names[] = {"a", "l", "rho_l"};
static const double param_defaults[] = {0.4, 0.2, 1.0};
static const char* const drive_param_names[] = {"psi0"};
static const double drive_param_defaults[] = {-1.0707963267948966};  /* -pi/2 + 0.5 */

static void bar(pl_body* b, double rho, double l)
{
    b->m = rho * l;
    b->J = b->m * l * l / 12.0;
}

static void crank(pl_body* b, const double* p, double x0, int j)
{
    pl_angle psi = {0.0, 0.0, {0.0}};
    psi.B[j] = 1.0;
    bar(b, p[RHO], p[L]);
    b->psi = psi;
    b->G.base[0] = x0;
    b->G.narms = 1;
    b->G.len[0] = 0.5 * p[L];
    b->G.arm[0] = psi;
}

void pl_describe(const double* p, pl_model* m)
{
    *m = (pl_model){0};
    m->nq = 4;
    m->nb = 4;
    m->nc = 4;
    m->g[1] = -9.81;
    crank(&m->body[0], p, 0.0, 0);
    crank(&m->body[2], p, p[A], 2);
    crank(&m->body[3], p, 0.5 * p[A], 3);
    pl_angle c1 = {0.0, 0.0, {1.0, 0.0, 0.0, 0.0}}, cp = {0.0, 0.0, {1.0, 1.0, 0.0, 0.0}};
    pl_body* b = &m->body[1];
    bar(b, p[RHO], p[A]);
    b->psi = cp;
    b->G.narms = 2;
    b->G.len[0] = p[L];
    b->G.arm[0] = c1;
    b->G.len[1] = 0.5 * p[A];
    b->G.arm[1] = cp;
    for (int c = 0; c < 4; ++c) {  /* coupler point at s = a (c < 2) or a/2 = crank tip */
        int k = c < 2 ? 2 : 3;
        pl_point *on = &m->con[c].a, *tip = &m->con[c].b;
        on->narms = 2;
        on->len[0] = p[L];
        on->arm[0] = c1;
        on->len[1] = c < 2 ? p[A] : 0.5 * p[A];
        on->arm[1] = cp;
        *tip = m->body[k].G;
        tip->len[0] = p[L];
        m->con[c].comp = c % 2;
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
    (void)q, (void)qdd, (void)d, (void)p;
    y[0] = qd[0];
    y[1] = lambda[0];
    y[2] = lambda[2];
}

static void initial_state(const double* p, const double* mp, double* q, double* qd)
{
    (void)p;
    q[0] = mp[0];
    q[1] = -mp[0] + 0.03;
    q[2] = mp[0] - 0.02;
    q[3] = mp[0] + 0.01;
    qd[0] = qd[1] = qd[2] = qd[3] = 0.0;
}

static const fsm_system model = {
    .name = "parallelogram", .fingerprint = "hand-written", .generator = "tests/c_models",
    .nq = 4, .nd = 1, .nc = 4, .ny = 3, .np = 3, .nmp = 1,
    .length_scale = 0.4, .length_param = -1, .mass_constant = 0, .bandwidth = -1,
    .outputs_use_acceleration = 1, .outputs_use_drive = 1,
    .coord_names = coord_names, .coord_unbounded = coord_unbounded,
    .constraint_names = constraint_names, .output_names = output_names,
    .param_names = param_names, .param_defaults = param_defaults,
    .drive_param_names = drive_param_names, .drive_param_defaults = drive_param_defaults,
    .drive = drive, .mass = pl_mass, .force = pl_force, .residual_jac = pl_residual_jac,
    .constraints = pl_constraints, .constraint_jac = pl_constraint_jac,
    .constraint_rate = pl_constraint_rate, .constraint_acc = pl_constraint_acc,
    .outputs = outputs, .energy = pl_energy, .initial_state = initial_state};

const fsm_system* fsm_parallelogram_model(void)
{
    return &model;
}
