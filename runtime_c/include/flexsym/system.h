/* A model as one struct: sizes, scales and kernels behind function pointers. Every entry point
 * of the runtime takes the model as a pointer to this struct (fsr_simulate, fsr_stepper_new,
 * fsr_batch: runtime.h), so several models live in one process. A model's sources export one
 * function that returns it, its accessor `const fsm_system* fsm_<name>_model(void)`, and name
 * every other global symbol after the model (a generated folder's kernels are fsm_<name>_*), so
 * several models link into one program. Who uses which model is said in one place: the
 * accessor given to flexsym_add_model (flexsym_runtime.cmake) compiles the driver with
 * -DFSM_MODEL=<accessor>; the manifest's "model" names it for the in-process library (Python,
 * ctypes) and an FMU (FSU_MODEL). A one-beam variant is its spin-up system S0, with nc = 0. Integrators without
 * FSR_CAP_CONSTRAINED (flexsym/integrators.h) need nc = 0; the constrained ones take any nc.
 *
 * Equations, with the drive vector d (size nd) = [t, then theta_k, theta_k', theta_k'' for each
 * guided joint k] and the parameters p:
 *     M(q) q'' = f(q, q', d, p) - Phi_q^T lambda,    Phi(q, d, p) = 0   (nc equations).
 * All matrices are dense and row-major. Kernels never allocate and have no state. When nc = 0
 * the constraint kernels are never called (they may be NULL).
 */
#ifndef FLEXSYM_SYSTEM_H
#define FLEXSYM_SYSTEM_H

typedef struct fsm_system {
    const char* name;
    const char* fingerprint;     /* spec fingerprint recorded in the manifest */
    const char* generator;       /* "flexsym X.Y.Z" */
    int nq;                      /* unknown coordinates q */
    int nd;                      /* drive vector d: 1 + 3 x (guided joints) */
    int nc;                      /* constraint equations (cut joints); 0: none */
    int ny;                      /* outputs */
    int np;                      /* parameters p */
    int nmp;                     /* drive parameters (read by drive only) */
    double length_scale;         /* m: the mechanism's size. Newton tolerances (newton_tol x it),
                                    blow-up and the violation column are relative to it (to
                                    p[length_param] when there is one). */
    int length_param;            /* index in p of a parameter that is the length scale (a one-beam
                                    model's L, so that it follows --param L=...), or -1 */
    int mass_constant;           /* 1 when M depends on neither q nor d: factored once */
    int bandwidth;               /* half-bandwidth of M and the Jacobians (of their block
                                    [band_first, band_end) when given); -1 when dense */
    int outputs_use_acceleration;/* 1 when outputs read q'' (else it may be anything) */
    int outputs_use_drive;       /* 1 when outputs read d (else it may be anything) */
    const char* const* coord_names;       /* nq */
    const char* const* constraint_names;  /* nc, e.g. "slider.x": named in messages */
    const char* const* output_names;      /* ny */
    const char* const* param_names;       /* np */
    const double* param_defaults;         /* np */
    const char* const* drive_param_names; /* nmp */
    const double* drive_param_defaults;   /* nmp */

    /* d at time *t from the drive parameters mp */
    void (*drive)(const double* t, const double* mp, double* d);
    /* M depends on d when a guided joint sits between coordinates (a prismatic joint on ground
     * carrying a guided arm carrying a revolute one); a one-beam model ignores d */
    void (*mass)(const double* q, const double* d, const double* p, double* M);
    void (*force)(const double* q, const double* qd, const double* d, const double* p, double* f);
    /* dr/dq, dr/dq' of r = M(q) q'' - f(q, q', d, p) (without the constraint forces) */
    void (*residual_jac)(const double* q, const double* qd, const double* qdd, const double* d,
                         const double* p, double* dr_dq, double* dr_dqd);
    /* Phi (nc) */
    void (*constraints)(const double* q, const double* d, const double* p, double* phi);
    /* Phi_q (nc x nq) */
    void (*constraint_jac)(const double* q, const double* d, const double* p, double* phi_q);
    /* Phi_t (nc): the velocity constraint is Phi_q q' + Phi_t = 0 */
    void (*constraint_rate)(const double* q, const double* d, const double* p, double* phi_t);
    /* gamma (nc): the acceleration constraint is Phi_q q'' = gamma,
     * gamma = -(Phi_q q')_q q' - 2 Phi_qt q' - Phi_tt */
    void (*constraint_acc)(const double* q, const double* qd, const double* d, const double* p,
                           double* gamma);
    /* outputs; lambda: the nc multipliers (reactions of the cut joints), zeros when nc = 0 */
    void (*outputs)(const double* q, const double* qd, const double* qdd, const double* lambda,
                    const double* d, const double* p, double* y);
    /* e = [T, V, h]: kinetic, potential energy, Jacobi integral (NULL: no --energy) */
    void (*energy)(const double* q, const double* qd, const double* d, const double* p, double* e);
    /* starting guess q (consistent initial conditions correct it) and q' (NULL: q = q' = 0) */
    void (*initial_state)(const double* p, const double* mp, double* q, double* qd);
    /* h (n x n) = d(Phi_q^T e)/dq at fixed e: the constraint forces' geometric stiffness in the
     * Newton tangent (NULL: left out) */
    void (*constraint_hess)(const double* q, const double* e, const double* d, const double* p,
                            double* h);
    /* nq flags: 1 for a coordinate that the blow-up limit does not bound (a revolute joint's
     * angle may turn without end; an ANCF slope has no unit); NULL: every coordinate is bounded
     * by blowup x the length scale */
    const unsigned char* coord_unbounded;
    /* Last, so that a positional initializer that ends before it leaves it NULL.
     * r = M(q) q'' - f(q, q', d, p) in one pass, or NULL (then from mass and force). A model whose
     * M is costly to form (the exact kinematics: n^2 products over the quadrature points) gives
     * it, and the implicit integrators' Newton iterations then never form M (sim_residual). */
    void (*residual)(const double* q, const double* qd, const double* qdd, const double* d,
                     const double* p, double* r);
    /* With bandwidth >= 0: the coordinates [band_first, band_end) are the band's (a spatial ef
     * beam's nodes); the others, a dense border (a joint's or a floating frame's coordinates),
     * may couple with every coordinate. After residual, so that a positional initializer that
     * ends before them leaves 0, 0: the band is every coordinate. */
    int band_first, band_end;
    /* nq flags of the consistent start at t = 0 (cs_consistent_start): 1 holds a coordinate's
     * value, 2 its rate, as flexsym's assembly holds them: a flexible body's elastic
     * coordinates (undeformed, at rest), a `fixed` joint's angle, a rate the scene gives. So a
     * start that a run-time parameter or initial state opened closes by the joints, never by
     * straining a body; NULL: every coordinate may move (hand-written models). */
    const unsigned char* coord_held;
} fsm_system;  /* mirrored field by field in flexsym/toolchain/native.py (SystemStruct): keep in step */

#endif
