#include "linalg.h"

#include <math.h>

int fsr_chol_factor(double* A, int n)
{
    for (int j = 0; j < n; ++j) {
        double d = A[j * n + j];
        for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
        if (!(d > 0.0)) return j + 1;
        double inv = 1.0 / sqrt(d);
        A[j * n + j] = inv;
        for (int i = j + 1; i < n; ++i) {
            double s = A[i * n + j];
            for (int k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = s * inv;
        }
    }
    return 0;
}

void fsr_chol_solve(const double* A, int n, double* b)
{
    for (int i = 0; i < n; ++i) {
        double s = b[i];
        for (int k = 0; k < i; ++k) s -= A[i * n + k] * b[k];
        b[i] = s * A[i * n + i];
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int k = i + 1; k < n; ++k) s -= A[k * n + i] * b[k];
        b[i] = s * A[i * n + i];
    }
}

/* A triangular solve in dot form on the m columns of B (n x m): row by row, down (up when
 * upward), B_i = (B_i - sum_k T(i, k) B_k) T(i, i) over the rows k done before i, with
 * T(i, k) = A[i * ri + k * ki]; two columns at a time, their sums in registers. */
static void tri_solve_columns(const double* A, int n, int ri, int ki, int upward, double* B, int m)
{
    for (int t = 0; t < n; ++t) {
        int i = upward ? n - 1 - t : t, k0 = upward ? i + 1 : 0, k1 = upward ? n : i;
        double d = A[i * (ri + ki)];
        for (int c = 0; c < m; c += 2) {
            int two = c + 1 < m;
            double s0 = B[i * m + c], s1 = two ? B[i * m + c + 1] : 0.0;
            for (int k = k0; k < k1; ++k) {
                double a = A[i * ri + k * ki];
                s0 -= a * B[k * m + c];
                if (two) s1 -= a * B[k * m + c + 1];
            }
            B[i * m + c] = s0 * d;
            if (two) B[i * m + c + 1] = s1 * d;
        }
    }
}

void fsr_chol_solve_columns(const double* A, int n, double* B, int m)
{
    tri_solve_columns(A, n, n, 1, 0, B, m);  /* L y = b */
    tri_solve_columns(A, n, 1, n, 1, B, m);  /* L^T x = y */
}

int fsr_symmetric(const double* A, int n)
{
    double big = 0.0, off = 0.0;  /* comparisons, not fmax (a libm call: a fifth of rk4p's time) */
    for (int i = 0; i < n; ++i)
        for (int j = 0; j <= i; ++j) {
            double a = fabs(A[i * n + j]), b = fabs(A[j * n + i]), d = fabs(A[i * n + j] - A[j * n + i]);
            if (a > big) big = a;
            if (b > big) big = b;
            if (d > off) off = d;
        }
    return off <= 1e-13 * big;
}

static int min_int(int a, int b)
{
    return a < b ? a : b;
}

int fsr_lu_factor(double* A, int n, int* piv)
{
    return fsr_band_lu_factor(A, n, n - 1, n - 1, piv);
}

void fsr_lu_solve(const double* A, int n, const int* piv, double* b)
{
    fsr_band_lu_solve(A, n, n - 1, n - 1, piv, b);
}

/* Banded LU with partial pivoting (LAPACK dgbtrf's algorithm) on dense row-major storage
 * (row stride ld: the n x n block may sit inside a larger matrix). Row interchanges widen the
 * upper band to kl + ku; the multipliers of column k stay where step k put them, so the
 * forward solve interleaves interchanges and eliminations. With kl = ku = n - 1 it is the
 * dense LU. */
static int band_lu_factor(double* A, int n, int ld, int kl, int ku, int* piv)
{
    int ku2 = min_int(kl + ku, n - 1);
    for (int k = 0; k < n; ++k) {
        int last = min_int(k + kl, n - 1), jend = min_int(k + ku2, n - 1);
        int p = k;
        double best = fabs(A[k * ld + k]);
        for (int i = k + 1; i <= last; ++i) {
            double v = fabs(A[i * ld + k]);
            if (v > best) { best = v; p = i; }
        }
        if (!(best > 0.0)) return k + 1;
        piv[k] = p;
        if (p != k) {
            for (int j = k; j <= jend; ++j) {
                double t = A[k * ld + j]; A[k * ld + j] = A[p * ld + j]; A[p * ld + j] = t;
            }
        }
        double inv = 1.0 / A[k * ld + k];
        A[k * ld + k] = inv;
        for (int i = k + 1; i <= last; ++i) {
            double l = A[i * ld + k] * inv;
            A[i * ld + k] = l;
            if (l != 0.0)
                for (int j = k + 1; j <= jend; ++j) A[i * ld + j] -= l * A[k * ld + j];
        }
    }
    return 0;
}

/* Its solve, b with stride inc. */
static void band_lu_solve(const double* A, int n, int ld, int kl, int ku, const int* piv, double* b, int inc)
{
    int ku2 = min_int(kl + ku, n - 1);
    for (int k = 0; k < n; ++k) {
        int p = piv[k], last = min_int(k + kl, n - 1);
        if (p != k) { double t = b[k * inc]; b[k * inc] = b[p * inc]; b[p * inc] = t; }
        for (int i = k + 1; i <= last; ++i) b[i * inc] -= A[i * ld + k] * b[k * inc];
    }
    for (int i = n - 1; i >= 0; --i) {
        int jend = min_int(i + ku2, n - 1);
        double s = b[i * inc];
        for (int j = i + 1; j <= jend; ++j) s -= A[i * ld + j] * b[j * inc];
        b[i * inc] = s * A[i * ld + i];
    }
}

int fsr_band_lu_factor(double* A, int n, int kl, int ku, int* piv)
{
    return band_lu_factor(A, n, n, kl, ku, piv);
}

void fsr_band_lu_solve(const double* A, int n, int kl, int ku, const int* piv, double* b)
{
    band_lu_solve(A, n, n, kl, ku, piv, b, 1);
}

void fsr_bordered_init(fsr_bordered* b, int n, int bw, int lo, int hi, double* dwork, int* iwork)
{
    b->n = n;
    b->bw = bw;
    b->lo = lo;
    b->hi = hi;
    b->m = n - (hi - lo);
    b->idx = iwork;
    b->gpiv = iwork + b->m;
    b->X = dwork;
    b->G = dwork + (size_t)b->m * (size_t)(hi - lo);
    b->r = b->G + (size_t)b->m * (size_t)b->m;
    for (int i = 0, c = 0; i < n; ++i)
        if (i < lo || i >= hi) b->idx[c++] = i;
}

int fsr_bordered_factor(fsr_bordered* b, double* S, int* piv)
{
    const int n = b->n, lo = b->lo, nb = b->hi - b->lo, m = b->m;
    double *A = S + (size_t)lo * (size_t)n + lo, *X = b->X, *G = b->G;
    int bad = band_lu_factor(A, nb, n, b->bw, b->bw, piv + lo);
    if (bad) return lo + bad;
    for (int c = 0; c < m; ++c) {  /* row c of X: A^-1 times the block's part of column idx[c] */
        double* x = X + (size_t)c * (size_t)nb;
        for (int i = 0; i < nb; ++i) x[i] = A[(size_t)i * (size_t)n + (b->idx[c] - lo)];
        band_lu_solve(A, nb, n, b->bw, b->bw, piv + lo, x, 1);
    }
    for (int a = 0; a < m; ++a) {  /* G = D - C A^-1 B */
        const double* Ca = S + (size_t)b->idx[a] * (size_t)n + lo;
        for (int c = 0; c < m; ++c) {
            const double* x = X + (size_t)c * (size_t)nb;
            double g = 0.0;
            for (int i = 0; i < nb; ++i) g += Ca[i] * x[i];
            G[a * m + c] = S[(size_t)b->idx[a] * (size_t)n + b->idx[c]] - g;
        }
    }
    bad = m ? fsr_lu_factor(G, m, b->gpiv) : 0;
    return bad ? b->idx[bad - 1] + 1 : 0;
}

void fsr_bordered_solve(const fsr_bordered* b, const double* S, const int* piv, double* x, int inc)
{
    const int n = b->n, lo = b->lo, nb = b->hi - b->lo, m = b->m;
    const double* A = S + (size_t)lo * (size_t)n + lo;
    double *y = x + (size_t)lo * (size_t)inc, *r = b->r;
    band_lu_solve(A, nb, n, b->bw, b->bw, piv + lo, y, inc);  /* y = A^-1 x_A */
    if (!m) return;
    for (int a = 0; a < m; ++a) {  /* r = x_D - C y */
        const double* Ca = S + (size_t)b->idx[a] * (size_t)n + lo;
        double s = 0.0;
        for (int i = 0; i < nb; ++i) s += Ca[i] * y[(size_t)i * (size_t)inc];
        r[a] = x[(size_t)b->idx[a] * (size_t)inc] - s;
    }
    fsr_lu_solve(b->G, m, b->gpiv, r);  /* x_D = G^-1 r */
    for (int i = 0; i < nb; ++i) {  /* x_A = y - A^-1 B x_D */
        double s = 0.0;
        for (int c = 0; c < m; ++c) s += b->X[(size_t)c * (size_t)nb + i] * r[c];
        y[(size_t)i * (size_t)inc] -= s;
    }
    for (int a = 0; a < m; ++a) x[(size_t)b->idx[a] * (size_t)inc] = r[a];
}

void fsr_lu_solve_columns(const double* A, int n, const int* piv, double* B, int m)
{
    for (int k = 0; k < n; ++k) {
        double* bk = B + k * m;
        if (piv[k] != k) {
            double* bp = B + piv[k] * m;
            for (int c = 0; c < m; ++c) { double t = bk[c]; bk[c] = bp[c]; bp[c] = t; }
        }
        for (int i = k + 1; i < n; ++i) {
            double l = A[i * n + k], *bi = B + i * m;
            for (int c = 0; c < m; ++c) bi[c] -= l * bk[c];
        }
    }
    tri_solve_columns(A, n, n, 1, 1, B, m);  /* U x = y (as fsr_lu_solve's dot products) */
}

static void unit_column(int n, int j, double* e)
{
    for (int i = 0; i < n; ++i) e[i] = i == j ? 1.0 : 0.0;
}

static void set_column(double* Ainv, int n, int j, const double* x)
{
    for (int i = 0; i < n; ++i) Ainv[i * n + j] = x[i];
}

void fsr_chol_inverse(const double* A, int n, double* Ainv, double* work)
{
    for (int j = 0; j < n; ++j) {
        unit_column(n, j, work);
        fsr_chol_solve(A, n, work);
        set_column(Ainv, n, j, work);
    }
}

void fsr_lu_inverse(const double* A, int n, const int* piv, double* Ainv, double* work)
{
    for (int j = 0; j < n; ++j) {
        unit_column(n, j, work);
        fsr_lu_solve(A, n, piv, work);
        set_column(Ainv, n, j, work);
    }
}

void fsr_matvec(const double* A, int n, int bw, const double* x, double* y)
{
    if (bw < 0 || bw >= n - 1) {
        for (int i = 0; i < n; ++i) {
            const double* Ai = A + i * n;
            double s0 = 0.0, s1 = 0.0;
            int j = 0;
            for (; j + 1 < n; j += 2) {  /* two chains: small n gets no vector code */
                s0 += Ai[j] * x[j];
                s1 += Ai[j + 1] * x[j + 1];
            }
            if (j < n) s0 += Ai[j] * x[j];
            y[i] = s0 + s1;
        }
        return;
    }
    for (int i = 0; i < n; ++i) {
        int j0 = i - bw > 0 ? i - bw : 0, j1 = min_int(i + bw, n - 1);
        double s = 0.0;
        for (int j = j0; j <= j1; ++j) s += A[i * n + j] * x[j];
        y[i] = s;
    }
}

double fsr_power_iteration(int n, double* x, double* z, int max_it,
                           void (*apply)(void* ctx, const double* x, double* z), void* ctx)
{
    double est = 0.0;
    for (int it = 0; it < max_it; ++it) {
        apply(ctx, x, z);
        double nz = 0.0;
        for (int i = 0; i < n; ++i) nz += z[i] * z[i];
        nz = sqrt(nz);
        if (!(nz > 0.0) || !isfinite(nz)) break;
        for (int i = 0; i < n; ++i) x[i] = z[i] / nz;
        int done = fabs(nz - est) <= 1e-10 * nz;
        est = nz;
        if (done) break;
    }
    return est;
}
