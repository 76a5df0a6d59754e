/* The bordered band solve (linalg.c: fsr_bordered_*) against the dense LU on random matrices
 * (tests/test_linalg_bordered.py). Each case: S (n x n) with a block [lo, hi) of half-bandwidth
 * bw and a dense border, x = S^-1 b for three right-hand sides stored as the columns of a
 * row-major n x 3 matrix (stride 3, as the constrained integrators' block solve), against the
 * dense LU's x. Prints one line per case: n bw lo hi, the largest |difference| relative to the
 * largest |x|. With no border the bordered solve must be the band LU's bit for bit. Exit 1 when
 * a difference exceeds 1e-10 or a factorisation fails. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linalg.h"

static unsigned long long state = 88172645463325252ULL;

static double uniform(void)  /* xorshift64: the same numbers on every platform */
{
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return (double)(state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

static int in_block(int i, int lo, int hi)
{
    return i >= lo && i < hi;
}

static int check(int n, int bw, int lo, int hi)
{
    const int nrhs = 3, m = n - (hi - lo);
    double* S = calloc((size_t)n * (size_t)n, sizeof(double));
    double* D = malloc(sizeof(double) * (size_t)n * (size_t)n);
    double* B = malloc(sizeof(double) * (size_t)n * (size_t)nrhs);
    double* x = malloc(sizeof(double) * (size_t)n);
    double* dw = malloc(sizeof(double) * (FSR_BORDERED_DOUBLES(m, hi - lo) + 1));
    int* iw = malloc(sizeof(int) * (FSR_BORDERED_INTS(m) + 1));
    int *piv = malloc(sizeof(int) * (size_t)n), *dpiv = malloc(sizeof(int) * (size_t)n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            if (!in_block(i, lo, hi) || !in_block(j, lo, hi) || abs(i - j) <= bw)
                S[i * n + j] = uniform() + (i == j ? 2.0 : 0.0);
    for (int i = 0; i < n * nrhs; ++i) B[i] = uniform();
    memcpy(D, S, sizeof(double) * (size_t)n * (size_t)n);
    fsr_bordered f;
    fsr_bordered_init(&f, n, bw, lo, hi, dw, iw);
    if (fsr_bordered_factor(&f, S, piv) || fsr_lu_factor(D, n, dpiv)) {
        printf("%d %d %d %d singular\n", n, bw, lo, hi);
        return 1;
    }
    double worst = 0.0;
    int same = 1;
    for (int c = 0; c < nrhs; ++c) {
        for (int i = 0; i < n; ++i) x[i] = B[i * nrhs + c];
        fsr_lu_solve(D, n, dpiv, x);
        fsr_bordered_solve(&f, S, piv, B + c, nrhs);
        double big = 0.0, diff = 0.0;
        for (int i = 0; i < n; ++i) {
            big = fmax(big, fabs(x[i]));
            diff = fmax(diff, fabs(x[i] - B[i * nrhs + c]));
        }
        worst = fmax(worst, diff / big);
    }
    if (m == 0) {  /* no border: the band LU's factor and solve, bit for bit */
        double* E = malloc(sizeof(double) * (size_t)n * (size_t)n);
        int* epiv = malloc(sizeof(int) * (size_t)n);
        state = 7;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                E[i * n + j] = abs(i - j) <= bw ? uniform() + (i == j ? 2.0 : 0.0) : 0.0;
        for (int i = 0; i < n; ++i) x[i] = uniform();
        memcpy(S, E, sizeof(double) * (size_t)n * (size_t)n);
        memcpy(B, x, sizeof(double) * (size_t)n);
        fsr_band_lu_factor(E, n, bw, bw, epiv);
        fsr_band_lu_solve(E, n, bw, bw, epiv, x);
        fsr_bordered_factor(&f, S, piv);
        fsr_bordered_solve(&f, S, piv, B, 1);
        same = !memcmp(E, S, sizeof(double) * (size_t)n * (size_t)n) && !memcmp(x, B, sizeof(double) * (size_t)n);
        free(E);
        free(epiv);
    }
    printf("%d %d %d %d %.3g%s\n", n, bw, lo, hi, worst, same ? "" : " differs from the band LU");
    free(S); free(D); free(B); free(x); free(dw); free(iw); free(piv); free(dpiv);
    return !(worst <= 1e-10) || !same;
}

int main(void)
{
    /* n, bw, lo, hi: S6's shape at n = 4 and 8 (4 Euler parameters, then the nodes), S7's (5
     * joint coordinates first), a border on both sides, at the end only, none, a border only */
    static const int cases[][4] = {{28, 11, 4, 28}, {52, 11, 4, 52}, {29, 11, 5, 29},
                                   {40, 3, 2, 35}, {60, 11, 0, 54}, {30, 5, 0, 30},
                                   {7, 1, 3, 3}, {100, 11, 4, 100}};
    int bad = 0;
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k)
        bad |= check(cases[k][0], cases[k][1], cases[k][2], cases[k][3]);
    return bad;
}
