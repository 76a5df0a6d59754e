/* A one-beam model generated before systems (model.h: global kernels, drive = [theta',
 * theta'']) seen through the system interface (system.h): d = [t, theta, theta', theta''],
 * so the old kernels read d + 2; no constraints; length scale = the default beam length.
 * Compiled into every model built by flexsym_add_model (flexsym_runtime.cmake) unless the
 * model defines fsm_system_model itself (flexsym_add_model(NAME SYSTEM ...)). */
#include "flexsym/model.h"
#include "flexsym/system.h"

static void drive(const double* t, const double* mp, double* d)
{
    d[0] = *t;
    fsm_maneuver(t, mp, d + 1);
}

static void force(const double* q, const double* qd, const double* d, const double* p, double* f)
{
    fsm_force(q, qd, d + 2, p, f);
}

static void mass(const double* q, const double* d, const double* p, double* M)
{
    (void)d;
    fsm_mass(q, p, M);
}

static void residual_jac(const double* q, const double* qd, const double* qdd, const double* d,
                         const double* p, double* dr_dq, double* dr_dqd)
{
    fsm_residual_jac(q, qd, qdd, d + 2, p, dr_dq, dr_dqd);
}

static void outputs(const double* q, const double* qd, const double* qdd, const double* lambda,
                    const double* d, const double* p, double* y)
{
    (void)lambda;
    fsm_outputs(q, qd, qdd, d + 2, p, y);
}

static void energy(const double* q, const double* qd, const double* d, const double* p, double* e)
{
    fsm_energy(q, qd, d + 2, p, e);
}

const fsm_system* fsm_system_model(void)
{
    static fsm_system s;
    static int ready = 0;
    if (!ready) {
        const fsm_model_info* m = fsm_model();
        s.name = m->variant;
        s.fingerprint = m->fingerprint;
        s.generator = m->generator;
        s.nq = m->nq;
        s.nd = 4;
        s.nc = 0;
        s.ny = m->ny;
        s.np = m->np;
        s.nmp = m->nmp;
        s.length_scale = m->param_defaults[m->length_param];
        s.length_param = m->length_param;
        s.mass_constant = m->mass_constant;
        s.bandwidth = m->bandwidth;
        s.outputs_use_acceleration = m->outputs_use_acceleration;
        s.outputs_use_drive = m->outputs_use_drive;
        s.coord_names = m->coord_names;
        s.output_names = m->output_names;
        s.param_names = m->param_names;
        s.param_defaults = m->param_defaults;
        s.drive_param_names = m->maneuver_param_names;
        s.drive_param_defaults = m->maneuver_param_defaults;
        s.drive = drive;
        s.mass = mass;
        s.force = force;
        s.residual_jac = residual_jac;
        s.outputs = outputs;
        s.energy = energy;
        ready = 1;
    }
    return &s;
}
