/* The interface every one-beam flexsym model generated before systems implements. The runtime
 * reads it through the struct of system.h (runtime_c/src/model_adapter.c); FMU export reads
 * the names and defaults here.
 *
 * A model is a set of kernels over the elastic coordinates q (size nq) of one beam in a
 * frame that rotates with the guided angle theta(t):
 *     M(q) q'' = f(q, q', drive, p),   drive = [theta', theta''],  p = beam parameters.
 * All matrices are dense and row-major. Kernels never allocate and have no state.
 */
#ifndef FLEXSYM_MODEL_H
#define FLEXSYM_MODEL_H

typedef struct {
    const char* variant;      /* variant name, e.g. "geometric" */
    const char* fingerprint;  /* spec fingerprint recorded in manifest.json */
    const char* generator;    /* "flexsym X.Y.Z" */
    int nq;                   /* elastic coordinates */
    int ny;                   /* output quantities */
    int np;                   /* beam parameters */
    int nmp;                  /* manoeuvre parameters */
    const char* const* coord_names;
    const char* const* output_names;
    const char* const* param_names;
    const double* param_defaults;
    const char* const* maneuver_param_names;
    const double* maneuver_param_defaults;
    int mass_constant;        /* 1 when M does not depend on q: factor it once */
    int outputs_use_acceleration; /* 1 when fsm_outputs reads qdd (else it may be anything) */
    int outputs_use_drive;    /* 1 when fsm_outputs reads drive (else it may be anything) */
    int bandwidth;            /* half-bandwidth of M and the Jacobians; -1 when dense */
    int length_param;         /* index of the beam length in p (divergence threshold) */
    int v_tip_output;         /* index of v_tip in the outputs, or -1 */
} fsm_model_info;

const fsm_model_info* fsm_model(void);

void fsm_mass(const double* q, const double* p, double* M);
void fsm_force(const double* q, const double* qd, const double* drive, const double* p, double* f);
/* Jacobians of the residual r = M(q) qdd - f(q, qd, drive, p). */
void fsm_residual_jac(const double* q, const double* qd, const double* qdd, const double* drive,
                      const double* p, double* dr_dq, double* dr_dqd);
void fsm_outputs(const double* q, const double* qd, const double* qdd, const double* drive,
                 const double* p, double* y);
/* e = [T, V, h]: kinetic energy, potential energy, Jacobi integral. */
void fsm_energy(const double* q, const double* qd, const double* drive, const double* p, double* e);
/* drive3 = [theta, theta', theta''] at time *t. */
void fsm_maneuver(const double* t, const double* mp, double* drive3);

#endif
