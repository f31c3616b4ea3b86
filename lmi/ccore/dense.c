/* Small dense kernels of the C core (see dense.h). */
#include <math.h>
#include <string.h>

#include "dense.h"

int dense_cholesky(const double *a, int lda, int k, double *l, int ldl)
{
    int i, j, p;
    for (j = 0; j < k; ++j) {
        double s, d;
        for (i = 0; i < j; ++i) {
            l[i * ldl + j] = 0.0;
        }
        s = a[j * lda + j];
        for (p = 0; p < j; ++p) {
            s -= l[j * ldl + p] * l[j * ldl + p];
        }
        if (!(s > 0.0 && s < HUGE_VAL)) {
            return -1;
        }
        d = sqrt(s);
        l[j * ldl + j] = d;
        for (i = j + 1; i < k; ++i) {
            s = a[i * lda + j];
            for (p = 0; p < j; ++p) {
                s -= l[i * ldl + p] * l[j * ldl + p];
            }
            l[i * ldl + j] = s / d;
        }
    }
    return 0;
}

void dense_forward(const double *l, int ldl, int k, double *b)
{
    int i, p;
    for (i = 0; i < k; ++i) {
        double s = b[i];
        for (p = 0; p < i; ++p) {
            s -= l[i * ldl + p] * b[p];
        }
        b[i] = s / l[i * ldl + i];
    }
}

void dense_backward(const double *l, int ldl, int k, double *b)
{
    int i, p;
    for (i = k - 1; i >= 0; --i) {
        double s = b[i];
        for (p = i + 1; p < k; ++p) {
            s -= l[p * ldl + i] * b[p];
        }
        b[i] = s / l[i * ldl + i];
    }
}

/* sqrt(a^2 + b^2) without overflow (faster than the correctly rounded hypot of libm) */
static double pythag(double a, double b)
{
    double x = fabs(a), y = fabs(b), r;
    if (x < y) {
        r = x;
        x = y;
        y = r;
    }
    if (x == 0.0) {
        return 0.0;
    }
    r = y / x;
    return x * sqrt(1.0 + r * r);
}

/* Householder reduction of v (k x k, symmetric on entry) to tridiagonal form: d the diagonal,
 * e the sub-diagonal (e[0] = 0), v the accumulated transformation (tred2). */
static void tred2(double *v, int ldv, int k, double *d, double *e)
{
    int i, j, m;
    for (j = 0; j < k; ++j) {
        d[j] = v[(k - 1) * ldv + j];
    }
    for (i = k - 1; i > 0; --i) {
        double scale = 0.0, h = 0.0;
        for (m = 0; m < i; ++m) {
            scale += fabs(d[m]);
        }
        if (scale == 0.0) {
            e[i] = d[i - 1];
            for (j = 0; j < i; ++j) {
                d[j] = v[(i - 1) * ldv + j];
                v[i * ldv + j] = 0.0;
                v[j * ldv + i] = 0.0;
            }
        } else {
            double f, g, hh;
            for (m = 0; m < i; ++m) {
                d[m] /= scale;
                h += d[m] * d[m];
            }
            f = d[i - 1];
            g = sqrt(h);
            if (f > 0.0) {
                g = -g;
            }
            e[i] = scale * g;
            h = h - f * g;
            d[i - 1] = f - g;
            for (j = 0; j < i; ++j) {
                e[j] = 0.0;
            }
            for (j = 0; j < i; ++j) {
                f = d[j];
                v[j * ldv + i] = f;
                g = e[j] + v[j * ldv + j] * f;
                for (m = j + 1; m <= i - 1; ++m) {
                    g += v[m * ldv + j] * d[m];
                    e[m] += v[m * ldv + j] * f;
                }
                e[j] = g;
            }
            f = 0.0;
            for (j = 0; j < i; ++j) {
                e[j] /= h;
                f += e[j] * d[j];
            }
            hh = f / (h + h);
            for (j = 0; j < i; ++j) {
                e[j] -= hh * d[j];
            }
            for (j = 0; j < i; ++j) {
                f = d[j];
                g = e[j];
                for (m = j; m <= i - 1; ++m) {
                    v[m * ldv + j] -= (f * e[m] + g * d[m]);
                }
                d[j] = v[(i - 1) * ldv + j];
                v[i * ldv + j] = 0.0;
            }
        }
        d[i] = h;
    }
    for (i = 0; i < k - 1; ++i) {
        double h;
        v[(k - 1) * ldv + i] = v[i * ldv + i];
        v[i * ldv + i] = 1.0;
        h = d[i + 1];
        if (h != 0.0) {
            for (m = 0; m <= i; ++m) {
                d[m] = v[m * ldv + i + 1] / h;
            }
            for (j = 0; j <= i; ++j) {
                double g = 0.0;
                for (m = 0; m <= i; ++m) {
                    g += v[m * ldv + i + 1] * v[m * ldv + j];
                }
                for (m = 0; m <= i; ++m) {
                    v[m * ldv + j] -= g * d[m];
                }
            }
        }
        for (m = 0; m <= i; ++m) {
            v[m * ldv + i + 1] = 0.0;
        }
    }
    for (j = 0; j < k; ++j) {
        d[j] = v[(k - 1) * ldv + j];
        v[(k - 1) * ldv + j] = 0.0;
    }
    v[(k - 1) * ldv + k - 1] = 1.0;
    e[0] = 0.0;
}

/* Implicit QL on the tridiagonal (d, e) from tred2, rotating v along (tql2); eigenvalues sorted
 * ascending with their vectors. Returns -1 when an eigenvalue takes more than 60 sweeps. */
static int tql2(double *v, int ldv, int k, double *d, double *e)
{
    int i, j, l, m;
    double f = 0.0, tst1 = 0.0;
    const double eps = 2.220446049250313e-16;
    for (i = 1; i < k; ++i) {
        e[i - 1] = e[i];
    }
    e[k - 1] = 0.0;
    for (l = 0; l < k; ++l) {
        double t = fabs(d[l]) + fabs(e[l]);
        if (t > tst1) {
            tst1 = t;
        }
        m = l;
        while (m < k - 1) {
            if (fabs(e[m]) <= eps * tst1) {
                break;
            }
            ++m;
        }
        if (m > l) {
            int iter = 0;
            do {
                double g, p, r, dl1, h, c, c2, c3, el1, s, s2;
                if (++iter > 60) {
                    return -1;
                }
                g = d[l];
                p = (d[l + 1] - g) / (2.0 * e[l]);
                r = pythag(p, 1.0);
                if (p < 0) {
                    r = -r;
                }
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                dl1 = d[l + 1];
                h = g - d[l];
                for (i = l + 2; i < k; ++i) {
                    d[i] -= h;
                }
                f = f + h;
                p = d[m];
                c = 1.0;
                c2 = c;
                c3 = c;
                el1 = e[l + 1];
                s = 0.0;
                s2 = 0.0;
                for (i = m - 1; i >= l; --i) {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    g = c * e[i];
                    h = c * p;
                    r = pythag(p, e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    if (v != NULL) {
                        for (j = 0; j < k; ++j) {
                            h = v[j * ldv + i + 1];
                            v[j * ldv + i + 1] = s * v[j * ldv + i] + c * h;
                            v[j * ldv + i] = c * v[j * ldv + i] - s * h;
                        }
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                if (!(fabs(e[l]) == fabs(e[l])) || !(tst1 < HUGE_VAL)) {
                    return -1;
                }
            } while (fabs(e[l]) > eps * tst1);
        }
        d[l] = d[l] + f;
        e[l] = 0.0;
    }
    for (i = 0; i < k - 1; ++i) {
        double p = d[i];
        int kk = i;
        for (j = i + 1; j < k; ++j) {
            if (d[j] < p) {
                kk = j;
                p = d[j];
            }
        }
        if (kk != i) {
            d[kk] = d[i];
            d[i] = p;
            if (v != NULL) {
                for (j = 0; j < k; ++j) {
                    double t = v[j * ldv + i];
                    v[j * ldv + i] = v[j * ldv + kk];
                    v[j * ldv + kk] = t;
                }
            }
        }
    }
    return 0;
}

int dense_sym_eig(const double *a, int lda, int k, double *w, double *v, int ldv, double *e,
                  double *vwork)
{
    int i, j;
    double *vv = v != NULL ? v : vwork;
    int ld = v != NULL ? ldv : k;
    for (i = 0; i < k; ++i) {
        for (j = 0; j < k; ++j) {
            vv[i * ld + j] = a[i * lda + j];
            if (!(a[i * lda + j] - a[i * lda + j] == 0.0)) {
                return -1; /* NaN or inf */
            }
        }
    }
    if (k == 1) {
        w[0] = vv[0];
        vv[0] = 1.0;
        return 0;
    }
    tred2(vv, ld, k, w, e);
    return tql2(v != NULL ? vv : NULL, ld, k, w, e);
}

/* Number of eigenvalues below sigma of the tridiagonal (d, e) (LDL' inertia). */
static int sturm_count(const double *d, const double *e, int k, double sigma)
{
    int i, count = 0;
    double q = d[0] - sigma;
    for (i = 0; i < k; ++i) {
        if (i > 0) {
            if (q == 0.0) {
                q = 1e-300;
            }
            q = d[i] - sigma - e[i - 1] * e[i - 1] / q;
        }
        if (q < 0.0) {
            ++count;
        }
    }
    return count;
}

/* lmi.ipm.kernels.step._tridiagonalize: d the diagonal, e the sub-diagonal (e[k-1] = 0). */
static void tridiagonalize(double *a, int lda, int k, double *d, double *e, double *v, double *w)
{
    int c, i, j;
    for (i = 0; i < k; ++i) {
        e[i] = 0.0;
        v[i] = 0.0;
        w[i] = 0.0;
    }
    for (c = 0; c < k - 2; ++c) {
        double s = 0.0, alpha, vv, beta, half;
        for (i = c + 1; i < k; ++i) {
            s += a[i * lda + c] * a[i * lda + c];
        }
        if (s == 0.0) {
            e[c] = 0.0;
            continue;
        }
        alpha = a[(c + 1) * lda + c] > 0.0 ? -sqrt(s) : sqrt(s);
        for (i = c + 1; i < k; ++i) {
            v[i] = a[i * lda + c];
        }
        v[c + 1] -= alpha;
        vv = s - a[(c + 1) * lda + c] * a[(c + 1) * lda + c] + v[c + 1] * v[c + 1];
        beta = 2.0 / vv;
        for (i = c + 1; i < k; ++i) {
            double t = 0.0;
            for (j = c + 1; j < k; ++j) {
                t += a[i * lda + j] * v[j];
            }
            w[i] = beta * t;
        }
        half = 0.0;
        for (i = c + 1; i < k; ++i) {
            half += v[i] * w[i];
        }
        half *= 0.5 * beta;
        for (i = c + 1; i < k; ++i) {
            w[i] -= half * v[i];
        }
        for (i = c + 1; i < k; ++i) {
            for (j = c + 1; j < k; ++j) {
                a[i * lda + j] -= v[i] * w[j] + w[i] * v[j];
            }
        }
        e[c] = alpha;
    }
    for (i = 0; i < k; ++i) {
        d[i] = a[i * lda + i];
    }
    if (k >= 2) {
        e[k - 2] = a[(k - 1) * lda + k - 2];
    }
}

double dense_smallest_eigenvalue(double *a, int lda, int k, double upper, double rtol, double *d,
                                 double *e, double *v, double *w)
{
    int i, it;
    double lo = HUGE_VAL, hi = -HUGE_VAL, width;
    tridiagonalize(a, lda, k, d, e, v, w);
    for (i = 0; i < k; ++i) {
        double radius = (i > 0 ? fabs(e[i - 1]) : 0.0) + (i < k - 1 ? fabs(e[i]) : 0.0);
        if (d[i] - radius < lo || lo != lo) {
            lo = d[i] - radius;
        }
        if (d[i] + radius > hi || hi != hi) {
            hi = d[i] + radius;
        }
    }
    if (upper < hi) {
        if (sturm_count(d, e, k, upper) == 0) {
            return upper;
        }
        hi = upper;
    }
    if (!(lo < hi)) {
        return lo;
    }
    width = rtol * (fabs(lo) > fabs(hi) ? fabs(lo) : fabs(hi)) + 1e-300;
    for (it = 0; it < 200; ++it) {
        double mid;
        if (hi - lo <= width) {
            break;
        }
        mid = 0.5 * (lo + hi);
        if (sturm_count(d, e, k, mid) >= 1) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    return lo;
}
