/* The Newton iteration of the implicit integrators of M q'' = f (newton.h). */
#include "newton.h"

#include <math.h>
#include <string.h>

#include "linalg.h"

/* Row R = r nst + i of the iteration matrix over the columns C0..C1 */
static void row_span(sim* s, int r, int i, const double* cq, const double* cv, double* row, int C0, int C1)
{
    int n = s->n, nst = s->nst;
    for (int C = C0, c = C0 / nst, j = C0 - c * nst; C <= C1; ++C) {  /* C = c nst + j */
        size_t rc = (size_t)r * (size_t)n + (size_t)c;
        row[C] = (i == j ? s->Mraw[rc] : 0.0) + cq[j] * s->Jq[rc] + cv[j] * s->Jv[rc];
        if (++j == nst) j = 0, ++c;
    }
}

void newton_rows(sim* s, int i, const double* cq, const double* cv)
{
    int n = s->n, N = s->N, nst = s->nst, kb = s->kb, lo = s->band.lo, hi = s->band.hi;
    for (int r = 0; r < n; ++r) {
        int R = r * nst + i;
        double* row = s->S + (size_t)R * (size_t)N;
        if (kb < 0 || R < lo || R >= hi) {  /* dense, or a row of the border */
            row_span(s, r, i, cq, cv, row, 0, N - 1);
            continue;
        }
        int C0 = R - kb < lo ? lo : R - kb, C1 = R + 2 * kb >= hi ? hi - 1 : R + 2 * kb;
        if (lo > 0) row_span(s, r, i, cq, cv, row, 0, lo - 1);  /* the border's columns */
        row_span(s, r, i, cq, cv, row, C0, C1);
        if (hi < N) row_span(s, r, i, cq, cv, row, hi, N - 1);
    }
}

fsr_status newton_factor(sim* s, double t, double dq)
{
    int N = s->N, kb = s->kb;
    s->r->jacobian_evaluations++;
    int bad = kb >= 0 ? fsr_bordered_factor(&s->band, s->S, s->piv) : fsr_lu_factor(s->S, N, s->piv);
    if (bad) return fsr_factor_failed(s->r, s->o, s->L, s->S, N, dq, t, "Newton matrix");
    if (kb < 0) fsr_lu_inverse(s->S, N, s->piv, s->Sinv, s->tmp);
    return FSR_OK;
}

fsr_status newton_failed(sim* s, double t1, double dq, int it)
{
    return sim_fail(s, FSR_NEWTON_FAILED,
                    "Newton iterations did not converge at t = %.6g s (|dq| = %.3g m after %d "
                    "iterations); reduce --dt", t1, dq, it);
}

fsr_status newton_diverged(sim* s, double t1, const double* q, const double* v, int nq)
{
    for (int i = 0; i < nq; i += s->n) {
        fsr_status st = sim_check_state(s, t1, q + i, v + i);
        if (st) return st;
    }
    return sim_fail(s, FSR_DIVERGED, "diverged at t = %.6g s: Newton update not finite", t1);
}

