#include "linalg.h"

#include <math.h>

int fsr_chol_factor(double* A, int n)
{
    for (int j = 0; j < n; ++j) {
        double d = A[j * n + j];
        for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
        if (!(d > 0.0)) return j + 1;
        d = sqrt(d);
        A[j * n + j] = d;
        for (int i = j + 1; i < n; ++i) {
            double s = A[i * n + j];
            for (int k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = s / d;
        }
    }
    return 0;
}

void fsr_chol_solve(const double* A, int n, double* b)
{
    for (int i = 0; i < n; ++i) {
        double s = b[i];
        for (int k = 0; k < i; ++k) s -= A[i * n + k] * b[k];
        b[i] = s / A[i * n + i];
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int k = i + 1; k < n; ++k) s -= A[k * n + i] * b[k];
        b[i] = s / A[i * n + i];
    }
}

int fsr_lu_factor(double* A, int n, int* piv)
{
    for (int k = 0; k < n; ++k) {
        int p = k;
        double best = fabs(A[k * n + k]);
        for (int i = k + 1; i < n; ++i) {
            double v = fabs(A[i * n + k]);
            if (v > best) { best = v; p = i; }
        }
        if (!(best > 0.0)) return k + 1;
        piv[k] = p;
        if (p != k) {
            for (int j = 0; j < n; ++j) {
                double t = A[k * n + j]; A[k * n + j] = A[p * n + j]; A[p * n + j] = t;
            }
        }
        double inv = 1.0 / A[k * n + k];
        for (int i = k + 1; i < n; ++i) {
            double l = A[i * n + k] * inv;
            A[i * n + k] = l;
            if (l != 0.0)
                for (int j = k + 1; j < n; ++j) A[i * n + j] -= l * A[k * n + j];
        }
    }
    return 0;
}

void fsr_lu_solve(const double* A, int n, const int* piv, double* b)
{
    for (int k = 0; k < n; ++k) {
        int p = piv[k];
        if (p != k) { double t = b[k]; b[k] = b[p]; b[p] = t; }
    }
    for (int i = 0; i < n; ++i) {
        double s = b[i];
        for (int k = 0; k < i; ++k) s -= A[i * n + k] * b[k];
        b[i] = s;
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int k = i + 1; k < n; ++k) s -= A[i * n + k] * b[k];
        b[i] = s / A[i * n + i];
    }
}

/* Banded LU with partial pivoting (LAPACK dgbtrf's algorithm) on dense row-major storage.
 * Row interchanges widen the upper band to kl + ku; the multipliers of column k stay where
 * step k put them, so the forward solve interleaves interchanges and eliminations. */
int fsr_band_lu_factor(double* A, int n, int kl, int ku, int* piv)
{
    int ku2 = kl + ku;
    for (int k = 0; k < n; ++k) {
        int last = k + kl < n - 1 ? k + kl : n - 1;
        int jend = k + ku2 < n - 1 ? k + ku2 : n - 1;
        int p = k;
        double best = fabs(A[k * n + k]);
        for (int i = k + 1; i <= last; ++i) {
            double v = fabs(A[i * n + k]);
            if (v > best) { best = v; p = i; }
        }
        if (!(best > 0.0)) return k + 1;
        piv[k] = p;
        if (p != k) {
            for (int j = k; j <= jend; ++j) {
                double t = A[k * n + j]; A[k * n + j] = A[p * n + j]; A[p * n + j] = t;
            }
        }
        double inv = 1.0 / A[k * n + k];
        for (int i = k + 1; i <= last; ++i) {
            double l = A[i * n + k] * inv;
            A[i * n + k] = l;
            if (l != 0.0)
                for (int j = k + 1; j <= jend; ++j) A[i * n + j] -= l * A[k * n + j];
        }
    }
    return 0;
}

void fsr_band_lu_solve(const double* A, int n, int kl, int ku, const int* piv, double* b)
{
    int ku2 = kl + ku;
    for (int k = 0; k < n; ++k) {
        int p = piv[k], last = k + kl < n - 1 ? k + kl : n - 1;
        if (p != k) { double t = b[k]; b[k] = b[p]; b[p] = t; }
        for (int i = k + 1; i <= last; ++i) b[i] -= A[i * n + k] * b[k];
    }
    for (int i = n - 1; i >= 0; --i) {
        int jend = i + ku2 < n - 1 ? i + ku2 : n - 1;
        double s = b[i];
        for (int j = i + 1; j <= jend; ++j) s -= A[i * n + j] * b[j];
        b[i] = s / A[i * n + i];
    }
}
