/* Small dense linear algebra for the runtime (row-major, in place, no allocation). */
#ifndef FLEXSYM_LINALG_H
#define FLEXSYM_LINALG_H

/* Cholesky A = L L^T in the lower triangle; returns 0, or k+1 if the k-th pivot is not positive. */
int fsr_chol_factor(double* A, int n);
void fsr_chol_solve(const double* A, int n, double* b);
/* LU with partial pivoting; returns 0, or k+1 if column k has no usable pivot. */
int fsr_lu_factor(double* A, int n, int* piv);
void fsr_lu_solve(const double* A, int n, const int* piv, double* b);
/* The same for a matrix with kl sub- and ku super-diagonals (zero elsewhere). */
int fsr_band_lu_factor(double* A, int n, int kl, int ku, int* piv);
void fsr_band_lu_solve(const double* A, int n, int kl, int ku, const int* piv, double* b);

#endif
