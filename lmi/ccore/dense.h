/* Small dense kernels of the C core of the interior-point solver (lmi/ccore).
 *
 * C99, no allocation, only <math.h>. Matrices are row-major with a leading dimension (the
 * length of a stored row), so a k x k block can sit in a larger kmax x kmax array.
 */
#ifndef LMI_CCORE_DENSE_H
#define LMI_CCORE_DENSE_H

#include <stddef.h>

/* Lower Cholesky factor L (L L' = A) of a[:k, :k] into l[:k, :k] (upper part zeroed), the
 * arithmetic of lmi.ipm.kernels.packed.cholesky_into. Returns 0, or -1 when a pivot is not
 * positive and finite. */
int dense_cholesky(const double *a, int lda, int k, double *l, int ldl);

/* Solve L y = b (forward) and L' x = y (backward) in place, L lower triangular. */
void dense_forward(const double *l, int ldl, int k, double *b);
void dense_backward(const double *l, int ldl, int k, double *b);

/* Symmetric eigen-decomposition of a[:k, :k] (Householder tridiagonalisation and the implicit
 * QL method, the tred2/tql2 of EISPACK as in JAMA): eigenvalues ascending into w, and, when v
 * is not NULL, the orthonormal eigenvectors as the columns of v[:k, :k] (ldv). e is a work
 * vector of k entries and vwork (k x k, leading dimension k) is used when v is NULL. Returns 0,
 * or -1 if the QL iteration did not converge (non-finite data). */
int dense_sym_eig(const double *a, int lda, int k, double *w, double *v, int ldv, double *e,
                  double *vwork);

/* A lower bound on the smallest eigenvalue of symmetric a[:k, :k] (a is overwritten):
 * Householder reduction to tridiagonal form, then bisection on Sturm counts until the bracket is
 * narrower than rtol times its largest end; if the smallest eigenvalue is not below upper,
 * upper is returned (lmi.ipm.kernels.step.smallest_eigenvalue). d, e, v, w: work of k entries. */
double dense_smallest_eigenvalue(double *a, int lda, int k, double upper, double rtol, double *d,
                                 double *e, double *v, double *w);

#endif
