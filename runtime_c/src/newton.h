/* The Newton iteration shared by the implicit integrators of M q'' = f (genalpha, newmark,
 * radau5: newton.c): the iteration matrix of nst coupled stages (banded when the model is), its
 * factorisation and solve, and the tests of modified Newton. Internal to the runtime. */
#ifndef FLEXSYM_NEWTON_H
#define FLEXSYM_NEWTON_H

#include "ode.h"

/* Modified Newton: rebuild the iteration matrix when an iteration contracts the update by
 * less than this. Small, so that the stopping test below passes after one iteration in most
 * steps; rebuilds stay rare (ef at 1 ms: 133 in 20000 steps; #1-#3: a handful). */
#define NEWTON_THETA_MAX 0.005
/* A measured contraction is trusted by the stopping test for this many steps. Longer trust
 * (10 steps) let steps stop after one iteration on a contraction that had since worsened:
 * ef with 4 elements at dt = 5 ms drifted 2.4e-6 m from full Newton over 8 s (tolerance
 * 1e-11 m per step); with 2 steps the drift is 5e-10 m, at similar cost. */
#define NEWTON_THETA_AGE 2

/* Modified Newton: the factored iteration matrix is kept across iterations and steps. */
typedef struct {
    double h;          /* step it was built for; 0: none */
    double theta;      /* contraction |dq_k| / |dq_k-1| last measured with it; < 0: unknown */
    long theta_step;   /* the step of that measurement */
} newton_state;

/* Rows r nst + i (r < n) of the Newton iteration matrix of a method with nst coupled stages:
 * block (i, j) = [i == j] M + cq[j] dr/dq + cv[j] dr/dq' from Mraw, Jq, Jv (generalized-alpha:
 * one stage, S = M + cb dr/dq + cg dr/dq'). The unknowns are interleaved by coordinate, so a
 * banded model gives a banded matrix (half-bandwidth kb = nst (bw + 1) - 1; with a border, a
 * bordered band one: its band block's rows get the band and the border's columns, the border's
 * rows every column); the band LU fills in up to 2 kb above the diagonal, and those entries
 * are written too (zeros: the model's matrices vanish outside their band). */
void newton_rows(sim* s, int i, const double* cq, const double* cv);

/* LU-factor the iteration matrix, (bordered) banded when the model is; a dense one also gets its inverse
 * (the solves are then matrix-vector products, which have no dependency chain: radau5 on #3 at
 * 0.25 s takes 0.127 ms with it, 0.153 ms with LU solves). dq: the last Newton update (0: none),
 * for fsr_factor_failed. */
fsr_status newton_factor(sim* s, double t, double dq);

/* x = S^-1 x */
static inline void newton_solve(sim* s, double* x)
{
    if (s->kb >= 0) fsr_bordered_solve(&s->band, s->S, s->piv, x, 1);
    else sim_apply_inverse(s, s->Sinv, s->N, x);
}

/* Converged when the update is below tol, or (modified Newton) when the error it leaves,
 * theta / (1 - theta) |dq| for a contraction theta measured in the last NEWTON_THETA_AGE steps,
 * is (Hairer & Wanner II, IV.8): usually after one iteration instead of two. */
static inline int newton_converged(const sim* s, const newton_state* ns, long k, double dq, double tol)
{
    if (dq <= tol) return 1;
    if (s->o->newton_full || ns->theta < 0.0 || k - ns->theta_step > NEWTON_THETA_AGE) return 0;
    return ns->theta < 1.0 && ns->theta / (1.0 - ns->theta) * dq <= tol;
}

/* Record the contraction of an iteration; ask for a new matrix when it is too slow. */
static inline int newton_contraction(newton_state* ns, long k, double dq, double dq_prev, double theta_max)
{
    if (dq_prev > 0.0) {
        ns->theta = dq / dq_prev;
        ns->theta_step = k;
    }
    return ns->theta > theta_max;
}

fsr_status newton_failed(sim* s, double t1, double dq, int it);

/* A non-finite Newton update: name the coordinate (q, v: nq values each, stage after stage). */
fsr_status newton_diverged(sim* s, double t1, const double* q, const double* v, int nq);

#endif
