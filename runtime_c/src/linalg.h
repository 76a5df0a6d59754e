/* Small dense linear algebra for the runtime (row-major, in place, no allocation).
 * Factorisations store the reciprocal of each pivot on the diagonal, so that the solves,
 * which run every Newton iteration or right-hand side evaluation, multiply instead of divide. */
#ifndef FLEXSYM_LINALG_H
#define FLEXSYM_LINALG_H

/* Cholesky A = L L^T in the lower triangle (diagonal: 1 / L_jj); returns 0, or k+1 if the
 * k-th pivot is not positive. */
int fsr_chol_factor(double* A, int n);
void fsr_chol_solve(const double* A, int n, double* b);
/* fsr_chol_solve on the m columns of B (n x m, row-major) at once, as fsr_lu_solve_columns. */
void fsr_chol_solve_columns(const double* A, int n, double* B, int m);
/* Is A (n x n) symmetric to rounding? Every model's M is by construction, but for a body's
 * prestress that reads its free frame's acceleration (its q'' moved into M). */
int fsr_symmetric(const double* A, int n);
/* LU with partial pivoting (diagonal: 1 / U_kk); returns 0, or k+1 if column k has no usable pivot. */
int fsr_lu_factor(double* A, int n, int* piv);
void fsr_lu_solve(const double* A, int n, const int* piv, double* b);
/* The same for a matrix with kl sub- and ku super-diagonals (zero elsewhere). */
int fsr_band_lu_factor(double* A, int n, int kl, int ku, int* piv);
void fsr_band_lu_solve(const double* A, int n, int kl, int ku, const int* piv, double* b);
/* fsr_lu_solve on the m columns of B (n x m, row-major) at once: each column gets the same
 * operations in the same order (the same bits); the columns' dependency chains interleave. */
void fsr_lu_solve_columns(const double* A, int n, const int* piv, double* B, int m);
/* Ainv = A^-1 from the factors (column by column; work: n). Small dense systems are then
 * solved by one matrix-vector product, which has no dependency chain. */
void fsr_chol_inverse(const double* A, int n, double* Ainv, double* work);
void fsr_lu_inverse(const double* A, int n, const int* piv, double* Ainv, double* work);
/* y = A x for A with half-bandwidth bw (bw < 0: dense). */
void fsr_matvec(const double* A, int n, int bw, const double* x, double* y);
/* The largest |eigenvalue| of the operator apply(ctx, x, z): z = A x, by power iteration from
 * x (n, updated to the unit eigenvector estimate; z: n of scratch), until two estimates agree
 * to 1e-10 or after max_it; 0 when A x vanishes or is not finite. */
double fsr_power_iteration(int n, double* x, double* z, int max_it,
                           void (*apply)(void* ctx, const double* x, double* z), void* ctx);

#endif
