/* Small dense linear algebra for the runtime (row-major, in place, no allocation).
 * Factorisations store the reciprocal of each pivot on the diagonal, so that the solves,
 * which run every Newton iteration or right-hand side evaluation, multiply instead of divide. */
#ifndef FLEXSYM_LINALG_H
#define FLEXSYM_LINALG_H

#include <stddef.h>

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
/* A bordered band matrix S (n x n, row-major): its coordinates [lo, hi) form a block A of
 * half-bandwidth bw (a spatial ef beam's nodes), the others (the border: a joint's or frame's
 * coordinates, before lo and from hi on) couple with everything. Ordered [A B; C D], S is
 * factored by block elimination: A by band LU (in place in S), X = A^-1 B, and the Schur
 * complement G = D - C X (m x m, m the border's size) by dense LU; the solve is
 * y = A^-1 x_A, x_D = G^-1 (x_D - C y), x_A = y - X x_D. With m = 0 it is the band LU. The
 * block's pivots are chosen inside A only: A must be regular (a mass matrix's node block is). */
typedef struct {
    int n, bw, lo, hi;
    int m;        /* border size, n - (hi - lo) */
    int* idx;     /* m: the border's coordinates, ascending */
    int* gpiv;    /* m: G's pivots */
    double* X;    /* m x (hi - lo): row c is A^-1 (column idx[c] of S in the block's rows) */
    double* G;    /* m x m: G's LU factor */
    double* r;    /* m: scratch of the solve */
} fsr_bordered;
/* Workspace: FSR_BORDERED_DOUBLES doubles and FSR_BORDERED_INTS ints for border size m and
 * block size nb. */
#define FSR_BORDERED_DOUBLES(m, nb) ((size_t)(m) * ((size_t)(nb) + (size_t)(m) + 1))
#define FSR_BORDERED_INTS(m) (2 * (size_t)(m))
void fsr_bordered_init(fsr_bordered* b, int n, int bw, int lo, int hi, double* dwork, int* iwork);
/* Factor S in place (its block part; the border's rows and columns are read, not written);
 * piv: n ints (the block's pivots at lo..hi - 1). Returns 0, or i + 1 for the coordinate i at
 * which a pivot vanished. */
int fsr_bordered_factor(fsr_bordered* b, double* S, int* piv);
/* x = S^-1 x for x with stride inc (a column of a row-major matrix: inc = its columns). */
void fsr_bordered_solve(const fsr_bordered* b, const double* S, const int* piv, double* x, int inc);
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
