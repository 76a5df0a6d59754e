/* What the constrained integrators (ali3p.c, genalpha3.c, rk4p.c) share: a run of a model given as a
 * struct (system.h) with constraints (any nc), its workspace, rows, consistent initial
 * conditions and the solve of the constraint block (constrained.c). Internal to the runtime. */
#ifndef FLEXSYM_CONSTRAINED_H
#define FLEXSYM_CONSTRAINED_H

#include "common.h"
#include "integrator.h"
#include "linalg.h"

typedef struct csim {
    const fsm_system* m;
    const fsr_options* o;
    fsr_result* r;
    int n, nc;
    double L;        /* length scale */
    double tol;      /* Newton tolerance: newton_tol x L */
    long nsteps;     /* grid points t_k = k dt, t_nsteps = t_end */
    long next_row;   /* grid index of the next row */
    long capacity;
    long k;          /* steps taken */
    /* state at t_k: q, q', q'', multipliers (ali3p: lambda*), the algorithmic acceleration
     * (genalpha3; ali3p keeps qh'' there) */
    double *q, *v, *a, *lam, *ab;
    double* mult;    /* the multipliers the outputs see (genalpha3: lam; ali3p: from q'') */
    double* vout;    /* the velocities the rows see: v projected (v when nc = 0) */
    /* iterates at t_k+1 */
    double *q1, *v1, *a1, *lam1;  /* ali3p: lam1 the velocity defect of the step's start q' */
    double* d;       /* drive (nd) */
    double* y;       /* outputs */
    double *M, *S, *Jq, *Jv;  /* n x n; S: the LU-factored iteration matrix (ali3p: W) */
    double* P;       /* ali3p: M + (h/2) C + (h^2/4) K, W without the penalty term */
    double* work;    /* the integrator's workspace (its work_size; zeros at the start) */
    int* piv;
    int chol;        /* S holds a Cholesky factor (rk4p: M symmetric), not an LU one */
    int banded;      /* the model has a band (system.h): S is factored as a bordered band matrix */
    fsr_bordered band;  /* its layout and border part (linalg.h) */
    double *Pq, *phi, *phit, *gam;  /* Phi_q (nc x n), Phi, Phi_t, gamma */
    double* H;                      /* d(Phi_q^T e)/dq (n x n) */
    double *Z, *G;   /* n x (nc + 1): S^-1 [b, Phi_q^T] (cs_kkt); nc x nc: Phi_q S^-1 Phi_q^T */
    int* cp;         /* column order of the complete pivoting of G */
    double *res, *f, *w1, *w2;  /* n */
    double *e1, *e2; /* nc */
    double* zero;    /* max(n, nc) zeros: lambda when nc = 0 */
    /* method coefficients and Newton state */
    double alpha;    /* ali3p penalty */
    double am, af, gm, bt, ra, pa, pb;  /* genalpha3 */
    double h_mat;    /* step the iteration matrix was built for; 0: none */
} csim;

fsr_status cs_fail(csim* s, fsr_status st, const char* fmt, ...);
double cs_time(const csim* s, long k);
/* s->d = the drive at t */
void cs_drive(csim* s, double t);
/* Phi, Phi_q at (q, s->d) */
void cs_constraints(csim* s, const double* q);
double cs_max_abs(const double* x, int n);
/* LU-factor A (n x n; the iteration matrix or M, in place), as a bordered band matrix when
 * the model has a band; 0, or k + 1 for a vanishing pivot at coordinate k. */
int cs_factor(csim* s, double* A);
/* The columns of row i of an n x n matrix of the model that can be nonzero, as up to three
 * ascending spans [sp[2k], sp[2k + 1]); returns 2 x their count. Dense: [0, n). With a band
 * (s->banded): a border row whole; a block row the border's columns and the band, i - bw to
 * i + bw, or to i + 2 bw with fill (the entries the band LU fills in: an iteration matrix
 * formed for cs_factor needs them zero). The entries left out are zero in M, the Jacobians
 * and d(Phi_q^T lambda)/dq: products and sums over the spans are those over the whole row. */
int cs_row_spans(const csim* s, int i, int fill, int sp[6]);
/* x = A^-1 x with A factored by cs_factor (or by Cholesky, s->chol) in s->S (or the identity
 * when A is NULL) */
void cs_solve(csim* s, const double* A, double* x);
/* Solve  A x + Phi_q^T lam = b,  Phi_q x = c  for x (in b) and lam, with A LU-factored in A
 * (NULL: identity) and Phi_q in s->Pq, by the Schur complement Phi_q A^-1 Phi_q^T. Dependent
 * (redundant) constraint rows are recognised by complete pivoting and dropped: for consistent
 * equations x is unique and lam one of the solutions. Returns the rank. */
int cs_kkt(csim* s, const double* A, double* b, const double* c, double* lam);
/* The state (q, v) made consistent at t = 0 and (a, lam) solved from the equations. */
fsr_status cs_consistent_start(csim* s);
/* 1 when the step being taken (k -> k + 1) ends on a row: work only the rows read can wait */
int cs_row_due(const csim* s);
/* An accepted step to t1 with the state in q, v, a, lam: finiteness, counters, row if due. */
fsr_status cs_accept(csim* s, double t1);
fsr_status cs_newton_failed(csim* s, double t1, double dq, int it);

/* A run of model m by integrator `it`, resumable step by step (simulate.c: fsr_simulate,
 * fsr_stepper): cs_open with room for `capacity` rows (0: every row of the run), cs_start
 * (consistent initial state, the row at t = 0), then it->cs_begin, it->cs_step until
 * s->k == s->nsteps, cs_close. */
fsr_status cs_open(csim* s, const fsr_integrator* it, const fsm_system* m, const fsr_options* o,
                   fsr_result* r, long capacity);
fsr_status cs_start(csim* s);
void cs_close(csim* s);

#endif
