/* The on-line Kothare solve in C99: see ipm.h.
 *
 * The method is lmi.ipm.solver.BlockLMISolver._run on the dense ("rows") path: infeasible-start
 * primal-dual path following with Nesterov-Todd scaling and Mehrotra's predictor-corrector
 * (CVXOPT's coneqp), CVXOPT's initial point, the same stopping tests (tolerances, objective
 * agreement, per-block residuals, the stall window, the Farkas-ray radius), the same warm start
 * (the iterate kept at a relative gap in [warm_gap / 10, warm_gap]), the block weights and the
 * variable equilibration fixed at the first solve, the Schur complement H = P'P factored by
 * Cholesky until a relative pivot falls below the QR switch or a step misses its dual equation,
 * then the QR factorisation of P. Not carried: phase one, the rebalanced retry and the Clarabel
 * fallback of lmi.backends.ipm.IPMKothare (a failed solve returns its status), the
 * unboundedness test (Kothare's objective is bounded below), the factored ("direct") Schur path.
 *
 * Storage: a block is a RMPC_KMAX x RMPC_KMAX row-major array; a packed vector holds each
 * block's upper triangle row by row, off-diagonal entries times sqrt(2).
 */
/* the problem fixed at generation time (an export), or given at run time (the extension) */
#ifdef KOTHARE_RUNTIME
#include "runtime.h"
#else
#include "rmpc_problem.h"
#endif

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "dense.h"
#include "ipm.h"

#define KM RMPC_KMAX
#define KK (RMPC_KMAX * RMPC_KMAX)
#define NV RMPC_NV
#define NVP (((RMPC_NV + 3) / 4) * 4 + 4) /* rows of P' with zero rows past NV (at least 3) */
#define NB RMPC_NB
#define SZ RMPC_SIZE
#define SZP (((RMPC_SIZE + 3) / 4) * 4) /* row stride of P' (zero-padded to a multiple of 4) */
#define CK RMPC_CERT_K
#define MAXIT (RMPC_MAX_ITER > RMPC_WARM_MAX_ITER ? RMPC_MAX_ITER : RMPC_WARM_MAX_ITER)
#define STALL_WINDOW 15
#define REDUCED_TOL 1e-6
#define RAY_TOL 1e-6
#define REFINE_STEPS 3
#define REFINE_TARGET 1e-12 /* lmi.ipm.kernels.step.REFINE_TARGET */
#define SQRT2 1.4142135623730951

/* Phase times, in a profiling build only (KOTHARE_PHASE_TIMES, see ipm.h): PHASE_NOW() reads
 * the caller's clock, PHASE_ADD adds the time since t0 to a phase; otherwise both vanish. */
#ifdef KOTHARE_PHASE_TIMES
static double phase_sec[KOTHARE_NPHASES];
static long phase_count[KOTHARE_NPHASES];
#define PHASE_NOW() kothare_phase_clock()
#define PHASE_ADD(p, t0) (phase_sec[p] += kothare_phase_clock() - (t0), ++phase_count[p])
#else
#define PHASE_NOW() 0.0
#define PHASE_ADD(p, t0) ((void)(t0))
#endif

/* the solver's own words */
enum { W_OPTIMAL, W_INFEASIBLE, W_MAX_ITER, W_NUMERICAL, W_STALL, W_INACCURATE };
/* newton step codes (lmi.ipm.kernels) */
enum { STEP_OK = 0, STEP_BAD_LENGTH = 1, STEP_NOT_PD = 2, STEP_LOST_PD = 3, STEP_SINGULAR = 4,
       STEP_INACCURATE = 5 };

/* The workspace's arrays as X-macro lists (type, name, entries): an export declares them as
 * arrays of sizes fixed at generation time, in one static workspace; the run-time build
 * (KOTHARE_RUNTIME) as pointers into the caller's buffer, carved by kothare_rt_init. */
#define POINT_ARRAYS(X) X(double, x, NV) X(double, s, NB * KK) X(double, z, NB * KK)
/* An iterate kept for later (the warm start, the best and the stalled points): x and each
 * block's upper triangle row by row, in the packed layout's order without its weights, so that
 * restoring it gives back the symmetric blocks exactly. */
#define SAVED_ARRAYS(X) X(double, x, NV) X(double, s, SZ) X(double, z, SZ)
#define CORE_ARRAYS(X)                                                                         \
    X(double, dscale, NV) X(double, bw, NB)                                                    \
    X(double, sq, NB * NV) /* squared coefficient norms per (block, variable) */               \
    X(int, ent_row, SZ) X(int, ent_col, SZ) X(int, ent_blk, SZ) X(double, ent_w, SZ)           \
    X(double, bound, RMPC_NBOUND) X(double, hvec, SZ) X(double, cvec, NV)                      \
    X(double, val, RMPC_NENT) X(double, spv, RMPC_NENT) X(double, gv, RMPC_NENT)               \
    X(double, s_chol, NB * KK) X(double, chol_new, NB * KK) X(double, kk, NB * KK)             \
    X(double, lam, NB * KM) X(double, pt, NVP * SZP) X(double, qrh, NVP * SZP)                 \
    X(double, tau, NV) X(double, h, NV * NV) X(double, l, NV * NV) X(double, basis, RMPC_BASIS) \
    /* packed vectors: SZP entries, the padding past SZ always zero (read by dotv) */          \
    X(double, r0, SZP) X(double, rd, NV) X(double, rp, SZP) X(double, sp, SZP)                 \
    X(double, zp, SZP) X(double, gx, SZP) X(double, gtz, NV) X(double, u, SZP)                 \
    X(double, ucor, SZP) X(double, rpt, SZP) X(double, v, SZP) X(double, dsa, SZP)             \
    X(double, dza, SZP) X(double, dst, SZP) X(double, dzt, SZP) X(double, dzt2, SZP)           \
    X(double, tv, SZP) X(double, yv, SZP) X(double, err, NV) X(double, err2, NV)               \
    X(double, dx, NV) X(double, ddx, NV) X(double, wv, NV) X(double, vn, NV)                   \
    X(double, m1, KK) X(double, m2, KK) X(double, m3, KK) X(double, m4, KK)                    \
    X(double, ev, KM) X(double, ee, KM) X(double, e1, KM) X(double, e2, KM)                    \
    X(double, merits, (MAXIT + 1) * 3) X(double, ray, MAXIT + 1)
/* the certificate and the gain of an export (solve_state) */
#define EXPORT_ARRAYS(X)                                                                       \
    X(double, cm, CK * CK) X(double, cw, CK) X(double, ce, CK) X(double, cv, CK * CK)          \
    X(double, qm, RMPC_NX * RMPC_NX) X(double, ym, RMPC_NU * RMPC_NX)                          \
    X(double, qc, RMPC_NX * RMPC_NX) X(double, fm, RMPC_NU * RMPC_NX)                          \
    X(double, gj, RMPC_NX * RMPC_NX) X(double, tmp, RMPC_NX * RMPC_NX)                         \
    X(double, gain, RMPC_NU * RMPC_NX)
#define NBYTES(count) ((size_t)(count) * sizeof(double))

#ifdef KOTHARE_RUNTIME
#define DECLARE(type, name, count) type *name;
#else
#define DECLARE(type, name, count) type name[count];
#endif

typedef struct {
    POINT_ARRAYS(DECLARE)
} point_t;

typedef struct {
    SAVED_ARRAYS(DECLARE)
} saved_t;

struct workspace {
    int laid_out;           /* the packed layout's tables filled */
    int ready;              /* equilibration fixed */
    int has_warm, has_gain;
    void *home;             /* the run-time build: where the arrays were carved */
    point_t cur, nxt;
    saved_t warm, warm_next, best, stall;
    double info[8];
    CORE_ARRAYS(DECLARE)
#ifndef KOTHARE_RUNTIME
    EXPORT_ARRAYS(DECLARE)
#endif
};

#ifdef KOTHARE_RUNTIME
/* the problem and the workspace of the call under way (set by every kothare_rt_* entry) */
static const kothare_problem_t *rt;
static struct workspace *ws_at;
#define ws (*ws_at)
#else
static struct workspace ws;
#endif

/* ------------------------------------------------------------------ layout and data */

static void layout(void)
{
    int j, a, b, t;
    for (j = 0; j < NB; ++j) {
        int k = rmpc_order[j];
        t = rmpc_offset[j];
        for (a = 0; a < k; ++a) {
            for (b = a; b < k; ++b, ++t) {
                ws.ent_row[t] = a;
                ws.ent_col[t] = b;
                ws.ent_blk[t] = j;
                ws.ent_w[t] = a == b ? 1.0 : SQRT2;
            }
        }
    }
}

static void pack(const double *mats, double *out)
{
    int t;
    for (t = 0; t < SZ; ++t) {
        const double *m = mats + ws.ent_blk[t] * KK;
        out[t] = m[ws.ent_row[t] * KM + ws.ent_col[t]] * ws.ent_w[t];
    }
}

static void unpack_block(const double *vec, int j, double *out)
{
    int t;
    for (t = rmpc_offset[j]; t < rmpc_offset[j + 1]; ++t) {
        double v = vec[t] / ws.ent_w[t];
        out[ws.ent_row[t] * KM + ws.ent_col[t]] = v;
        out[ws.ent_col[t] * KM + ws.ent_row[t]] = v;
    }
}

static void pack_block(const double *mat, int j, double *out)
{
    int t;
    for (t = rmpc_offset[j]; t < rmpc_offset[j + 1]; ++t) {
        out[t] = mat[ws.ent_row[t] * KM + ws.ent_col[t]] * ws.ent_w[t];
    }
}

static void unpack(const double *vec, double *mats)
{
    int j;
    for (j = 0; j < NB; ++j) {
        unpack_block(vec, j, mats + j * KK);
    }
}

static double norm2(const double *v, int n)
{
    double s = 0.0;
    int i;
    for (i = 0; i < n; ++i) {
        s += v[i] * v[i];
    }
    return sqrt(s);
}

/* sum of a[t] b[t] over t < n (n a multiple of 4) in four lanes by t mod 4: independent
 * accumulators that a compiler can keep in one vector register without reordering a sum */
static double dotv(const double *a, const double *b, int n)
{
    double c[4] = {0.0, 0.0, 0.0, 0.0};
    int t;
    for (t = 0; t < n; t += 4) {
        c[0] += a[t] * b[t];
        c[1] += a[t + 1] * b[t + 1];
        c[2] += a[t + 2] * b[t + 2];
        c[3] += a[t + 3] * b[t + 3];
    }
    return (c[0] + c[1]) + (c[2] + c[3]);
}

/* sum of a[t] b[t] over from <= t < SZP (zero padding past SZ): a scalar head to a multiple of 4,
 * then dotv */
static double dot_from(const double *a, const double *b, int from)
{
    double s = 0.0;
    int t = from;
    for (; t % 4 != 0; ++t) {
        s += a[t] * b[t];
    }
    return s + dotv(a + t, b + t, SZP - t);
}

static double maxd(double a, double b) { return a > b ? a : b; }

/* G x (packed) from the coefficient entries */
static void g_times(const double *x, double *out)
{
    int t, e = 0;
    for (t = 0; t < SZ; ++t) {
        out[t] = 0.0;
    }
    for (e = 0; e < RMPC_NENT; ++e) {
        out[rmpc_ent_t[e]] += ws.gv[e] * x[rmpc_ent_var[e]];
    }
}

/* G' z */
static void gt_times(const double *zp, double *out)
{
    int i, e;
    for (i = 0; i < NV; ++i) {
        out[i] = 0.0;
    }
    for (e = 0; e < RMPC_NENT; ++e) {
        out[rmpc_ent_var[e]] += ws.gv[e] * zp[rmpc_ent_t[e]];
    }
}

/* Block weights (lmi.ipm.blocks.block_weights) and the variable scaling, from ws.sq. */
static void equilibrate(void)
{
    double w[NB], d[NV];
    int j, i, pass, any = 0;
    double wmax = 0.0, wmin = HUGE_VAL;
    for (j = 0; j < NB; ++j) {
        w[j] = 1.0;
    }
    for (i = 0; i < NV; ++i) {
        d[i] = 1.0;
    }
    for (pass = 0; pass < 10; ++pass) {
        for (i = 0; i < NV; ++i) {
            double col = 0.0;
            for (j = 0; j < NB; ++j) {
                col += w[j] * w[j] * ws.sq[j * NV + i];
            }
            col = sqrt(col) * d[i];
            d[i] = d[i] / sqrt(col > 0.0 ? col : 1.0);
        }
        for (j = 0; j < NB; ++j) {
            double row = 0.0;
            for (i = 0; i < NV; ++i) {
                row += d[i] * d[i] * ws.sq[j * NV + i];
            }
            row = sqrt(row / rmpc_order[j]) * w[j];
            w[j] = w[j] / sqrt(row > 0.0 ? row : 1.0);
        }
    }
    for (j = 0; j < NB; ++j) {
        double live = 0.0;
        for (i = 0; i < NV; ++i) {
            live += ws.sq[j * NV + i];
        }
        if (live > 0.0) {
            any = 1;
            if (w[j] > wmax) {
                wmax = w[j];
            }
        }
    }
    for (j = 0; j < NB; ++j) {
        ws.bw[j] = 1.0;
    }
    if (any) {
        for (j = 0; j < NB; ++j) {
            double live = 0.0;
            for (i = 0; i < NV; ++i) {
                live += ws.sq[j * NV + i];
            }
            w[j] = live > 0.0 ? w[j] / wmax : 1.0;
            if (live > 0.0 && w[j] < wmin) {
                wmin = w[j];
            }
        }
        if (!(1.0 <= 100.0 * wmin)) { /* the largest live weight is 1 */
            for (j = 0; j < NB; ++j) {
                ws.bw[j] = exp2(nearbyint(log2(w[rmpc_copies[j]])));
            }
        }
    }
    for (i = 0; i < NV; ++i) {
        double s = 0.0;
        for (j = 0; j < NB; ++j) {
            s += ws.bw[j] * ws.bw[j] * ws.sq[j * NV + i];
        }
        s = sqrt(s);
        ws.dscale[i] = s > 0.0 ? 1.0 / s : 1.0;
    }
}

/* The data at the normalised state xs and the (normalised) bounds in ws.bound. */
static void set_data(const double *xs)
{
    int j, t, e;
    double *val = ws.val;
    for (e = 0; e < RMPC_NENT; ++e) {
        int bi = rmpc_ent_bound[e];
        val[e] = bi < 0 ? rmpc_ent_val[e] : rmpc_ent_val[e] * (1.0 / ws.bound[bi]);
    }
    if (!ws.ready) {
        for (j = 0; j < NB * NV; ++j) {
            ws.sq[j] = 0.0;
        }
        for (j = 0; j < NB; ++j) {
            for (e = rmpc_ent_off[j]; e < rmpc_ent_off[j + 1]; ++e) {
                int p = rmpc_ent_pos[e];
                double mult = rmpc_pos_row[p] == rmpc_pos_col[p] ? 1.0 : 2.0;
                ws.sq[j * NV + rmpc_ent_var[e]] += mult * val[e] * val[e];
            }
        }
        equilibrate();
        ws.ready = 1;
    }
    for (j = 0; j < NB; ++j) {
        for (e = rmpc_ent_off[j]; e < rmpc_ent_off[j + 1]; ++e) {
            ws.spv[e] = val[e] * (ws.dscale[rmpc_ent_var[e]] * ws.bw[j]);
            ws.gv[e] = ws.spv[e] * ws.ent_w[rmpc_ent_t[e]];
        }
        for (t = rmpc_offset[j]; t < rmpc_offset[j + 1]; ++t) {
            double c = rmpc_const[t];
            if (j == 0) { /* the state block [[1, x'], [x, 0]] */
                int a = ws.ent_row[t], b = ws.ent_col[t];
                c = (a == 0 && b == 0) ? 1.0 : (a == 0 ? xs[b - 1] : 0.0);
            }
            ws.hvec[t] = c * ws.ent_w[t] * ws.bw[j];
        }
    }
    for (j = 0; j < NV; ++j) {
        ws.cvec[j] = rmpc_c[j] * ws.dscale[j];
    }
}

/* ------------------------------------------------------------------ pieces of _run */

static int cholesky_blocks(const double *mats, double *out)
{
    int j;
    for (j = 0; j < NB; ++j) {
        if (dense_cholesky(mats + j * KK, KM, rmpc_order[j], out + j * KK, KM) != 0) {
            return 0;
        }
    }
    return 1;
}

/* mats + t I, t = 1 + max(0, -lambda_min) over every block; 0 if an eigenvalue failed */
static int shift_interior(double *mats)
{
    int j, a;
    double low = HUGE_VAL, shift;
    for (j = 0; j < NB; ++j) {
        int k = rmpc_order[j];
        if (dense_sym_eig(mats + j * KK, KM, k, ws.ev, NULL, 0, ws.ee, ws.m1) != 0) {
            return 0;
        }
        if (ws.ev[0] < low) {
            low = ws.ev[0];
        }
    }
    shift = 1.0 + maxd(0.0, -low);
    for (j = 0; j < NB; ++j) {
        for (a = 0; a < rmpc_order[j]; ++a) {
            mats[j * KK + a * KM + a] += shift;
        }
    }
    return 1;
}

/* CVXOPT's initial point (least squares, shifted into the interiors) into ws.cur */
static int initial_point(void)
{
    int t, e, f, i;
    memset(ws.h, 0, NBYTES(NV * NV));
    e = 0;
    while (e < RMPC_NENT) { /* G'G from the entries of each packed row */
        int t0 = rmpc_ent_t[e], stop = e;
        while (stop < RMPC_NENT && rmpc_ent_t[stop] == t0) {
            ++stop;
        }
        for (f = e; f < stop; ++f) {
            int g;
            for (g = e; g < stop; ++g) {
                ws.h[rmpc_ent_var[f] * NV + rmpc_ent_var[g]] += ws.gv[f] * ws.gv[g];
            }
        }
        e = stop;
    }
    for (i = 0; i < NV; ++i) {
        ws.h[i * NV + i] += 1e-12;
    }
    if (dense_cholesky(ws.h, NV, NV, ws.l, NV) != 0) {
        return 0;
    }
    gt_times(ws.hvec, ws.cur.x);
    dense_forward(ws.l, NV, NV, ws.cur.x);
    dense_backward(ws.l, NV, NV, ws.cur.x);
    g_times(ws.cur.x, ws.gx);
    for (t = 0; t < SZ; ++t) {
        ws.tv[t] = ws.hvec[t] - ws.gx[t];
    }
    memset(ws.cur.s, 0, NBYTES(NB * KK));
    unpack(ws.tv, ws.cur.s);
    memcpy(ws.wv, ws.cvec, NBYTES(NV));
    dense_forward(ws.l, NV, NV, ws.wv);
    dense_backward(ws.l, NV, NV, ws.wv);
    g_times(ws.wv, ws.tv);
    for (t = 0; t < SZ; ++t) {
        ws.tv[t] = -ws.tv[t];
    }
    memset(ws.cur.z, 0, NBYTES(NB * KK));
    unpack(ws.tv, ws.cur.z);
    return shift_interior(ws.cur.s) && shift_interior(ws.cur.z);
}

/* lmi.ipm.kernels.packed.blocks_within */
static int blocks_within(const double *x, double tol)
{
    int j, t, e = 0;
    for (j = 0; j < NB; ++j) {
        double size = 0.0, worst = 0.0;
        for (t = rmpc_offset[j]; t < rmpc_offset[j + 1]; ++t) {
            double terms = 0.0;
            while (e < RMPC_NENT && rmpc_ent_t[e] == t) {
                terms += fabs(ws.gv[e]) * fabs(x[rmpc_ent_var[e]]);
                ++e;
            }
            size = maxd(size, maxd(fabs(ws.hvec[t]), maxd(terms, fabs(ws.sp[t]))));
            worst = maxd(worst, fabs(ws.rp[t]));
        }
        if (!(worst <= tol * size)) {
            return 0;
        }
    }
    return 1;
}

/* NT scaling of block j (lmi.ipm.kernels.schur._nt_block) into ws.kk, ws.lam */
static int nt_block(int j)
{
    int k = rmpc_order[j], a, b, c;
    const double *ell = ws.s_chol + j * KK, *zj = ws.cur.z + j * KK;
    double *kj = ws.kk + j * KK, *lam = ws.lam + j * KM;
    double *zl = ws.m1, *m = ws.m2, *qv = ws.m3, *rr = ws.m4;
    for (a = 0; a < k; ++a) { /* zl = Z L (L lower) */
        for (b = 0; b < k; ++b) {
            double s = 0.0;
            for (c = b; c < k; ++c) {
                s += zj[a * KM + c] * ell[c * KM + b];
            }
            zl[a * KM + b] = s;
        }
    }
    for (a = 0; a < k; ++a) { /* m = L' (Z L) */
        for (b = 0; b < k; ++b) {
            double s = 0.0;
            for (c = a; c < k; ++c) {
                s += ell[c * KM + a] * zl[c * KM + b];
            }
            m[a * KM + b] = s;
        }
    }
    for (a = 0; a < k; ++a) {
        for (b = 0; b < a; ++b) {
            double s = 0.5 * (m[a * KM + b] + m[b * KM + a]);
            m[a * KM + b] = s;
            m[b * KM + a] = s;
        }
    }
    if (dense_sym_eig(m, KM, k, ws.ev, qv, KM, ws.ee, NULL) != 0 || !(ws.ev[0] > 0.0)) {
        return 0;
    }
    for (a = 0; a < k; ++a) {
        lam[a] = sqrt(ws.ev[a]);
    }
    for (a = 0; a < k; ++a) { /* rr = (L Q) / sqrt(lam) by columns */
        for (b = 0; b < k; ++b) {
            double s = 0.0;
            for (c = 0; c <= a; ++c) {
                s += ell[a * KM + c] * qv[c * KM + b];
            }
            rr[a * KM + b] = s / sqrt(lam[b]);
        }
    }
    for (a = 0; a < k; ++a) { /* K = (rr' Z) / lam by rows */
        for (b = 0; b < k; ++b) {
            double s = 0.0;
            for (c = 0; c < k; ++c) {
                s += rr[c * KM + a] * zj[c * KM + b];
            }
            kj[a * KM + b] = s / lam[a];
        }
    }
    return 1;
}

/* The packed K (e_a e_b' + e_b e_a') K' (halved for a = b) of block j (kernels.schur._pair_basis) */
static void pair_basis(const double *kj, int k, int a, int b, double *out)
{
    int p, r, t = 0;
    for (p = 0; p < k; ++p) {
        double kap = kj[p * KM + a];
        if (a == b) {
            out[t] = 1.0 * kap * kap;
            for (r = p + 1; r < k; ++r) {
                out[t + r - p] = SQRT2 * kap * kj[r * KM + a];
            }
        } else {
            double kbp = kj[p * KM + b];
            out[t] = 1.0 * (kap * kbp + kbp * kap);
            for (r = p + 1; r < k; ++r) {
                out[t + r - p] = SQRT2 * (kap * kj[r * KM + b] + kbp * kj[r * KM + a]);
            }
        }
        t += k - p;
    }
}

/* NT scaling of every block and P' (ws.pt, NV x SZ) (kernels.schur.scaling_and_schur_rows) */
static int scaling_and_p(void)
{
    int j, i, e, t;
    for (j = 0; j < NB; ++j) {
        int k = rmpc_order[j], lo = rmpc_offset[j], size = rmpc_offset[j + 1] - lo;
        int first = rmpc_pos_off[j], q;
        if (!nt_block(j)) {
            return 0;
        }
        for (q = first; q < rmpc_pos_off[j + 1]; ++q) {
            pair_basis(ws.kk + j * KK, k, rmpc_pos_row[q], rmpc_pos_col[q], ws.basis + (q - first) * size);
        }
        for (i = 0; i < NV; ++i) {
            memset(ws.pt + i * SZP + lo, 0, (size_t)size * sizeof(double));
        }
        for (e = rmpc_ent_off[j]; e < rmpc_ent_off[j + 1]; ++e) {
            double v = ws.spv[e];
            double *row = ws.pt + rmpc_ent_var[e] * SZP + lo;
            const double *src = ws.basis + (rmpc_ent_pos[e] - first) * size;
            for (t = 0; t < size; ++t) {
                row[t] += v * src[t];
            }
        }
    }
    return 1;
}

/* the dot products of rows i0..i0+3 of P' with rows k0..k0+3 into acc (a 4 x 4 tile: each
 * loaded entry serves four products), each sum split in four by t mod 4 (independent
 * accumulators, so that a compiler can use vector registers without reordering a sum) */
static void tile(const double *pa, const double *pb, double acc[16])
{
    int t, r, q, w;
    double c[16][4];
    for (r = 0; r < 16; ++r) {
        for (w = 0; w < 4; ++w) {
            c[r][w] = 0.0;
        }
    }
    for (t = 0; t < SZP; t += 4) {
        for (r = 0; r < 4; ++r) {
            const double *a = pa + r * SZP + t;
            for (q = 0; q < 4; ++q) {
                const double *b = pb + q * SZP + t;
                c[r * 4 + q][0] += a[0] * b[0];
                c[r * 4 + q][1] += a[1] * b[1];
                c[r * 4 + q][2] += a[2] * b[2];
                c[r * 4 + q][3] += a[3] * b[3];
            }
        }
    }
    for (r = 0; r < 16; ++r) {
        acc[r] = (c[r][0] + c[r][1]) + (c[r][2] + c[r][3]);
    }
}

static void schur_complement(void)
{
    int i0, k0, r, q;
    double acc[16];
    for (i0 = 0; i0 < NV; i0 += 4) {
        for (k0 = i0; k0 < NV; k0 += 4) {
            tile(ws.pt + i0 * SZP, ws.pt + k0 * SZP, acc);
            for (r = 0; r < 4 && i0 + r < NV; ++r) {
                for (q = 0; q < 4 && k0 + q < NV; ++q) {
                    ws.h[(i0 + r) * NV + k0 + q] = acc[r * 4 + q];
                    ws.h[(k0 + q) * NV + i0 + r] = acc[r * 4 + q];
                }
            }
        }
    }
}

/* every relative pivot |L_ii| / sqrt(H_ii) >= RMPC_QR_SWITCH and every entry finite */
static int factor_ok(void)
{
    int i, j;
    double low = HUGE_VAL;
    for (i = 0; i < NV; ++i) {
        double rel = fabs(ws.l[i * NV + i]) / sqrt(maxd(ws.h[i * NV + i], 1e-300));
        if (rel < low || rel != rel) {
            low = rel;
        }
        for (j = 0; j <= i; ++j) {
            double v = ws.l[i * NV + j];
            if (!(v - v == 0.0)) {
                return 0;
            }
        }
    }
    return low >= RMPC_QR_SWITCH;
}

/* P' v (NV) and P dx (SZ) with the formed P */
static void pt_times(const double *v, double *out)
{
    int i;
    for (i = 0; i < NV; ++i) {
        out[i] = dotv(ws.pt + i * SZP, v, SZP);
    }
}

static void p_times(const double *dx, double *out)
{
    int i, t;
    for (t = 0; t < SZ; ++t) {
        out[t] = 0.0;
    }
    for (i = 0; i < NV; ++i) {
        const double *row = ws.pt + i * SZP;
        double a = dx[i];
        for (t = 0; t < SZ; ++t) {
            out[t] += row[t] * a;
        }
    }
}

static void solve_normal(double *b)
{
    dense_forward(ws.l, NV, NV, b);
    dense_backward(ws.l, NV, NV, b);
}

/* kernels.step._newton: (dx, ds~ = u - dz~, dz~) for the right-hand side u; returns ||P'dz~ + rd|| */
static double newton_chol(const double *u, double ref_scale, double *dx, double *ds, double *dz)
{
    int i, t, it;
    double err_norm;
    for (t = 0; t < SZ; ++t) {
        ws.v[t] = u[t] + ws.rpt[t];
    }
    pt_times(ws.v, dx);
    for (i = 0; i < NV; ++i) {
        dx[i] = -ws.rd[i] - dx[i];
    }
    solve_normal(dx);
    p_times(dx, dz);
    for (t = 0; t < SZ; ++t) {
        dz[t] += ws.v[t];
    }
    pt_times(dz, ws.err);
    for (i = 0; i < NV; ++i) {
        ws.err[i] += ws.rd[i];
    }
    err_norm = norm2(ws.err, NV);
    for (it = 0; it < REFINE_STEPS; ++it) {
        double new_norm;
        if (err_norm <= REFINE_TARGET * ref_scale) {
            break;
        }
        for (i = 0; i < NV; ++i) {
            ws.ddx[i] = -ws.err[i];
        }
        solve_normal(ws.ddx);
        p_times(ws.ddx, ws.dzt2);
        for (t = 0; t < SZ; ++t) {
            ws.dzt2[t] += dz[t];
        }
        pt_times(ws.dzt2, ws.err2);
        for (i = 0; i < NV; ++i) {
            ws.err2[i] += ws.rd[i];
        }
        new_norm = norm2(ws.err2, NV);
        if (new_norm >= err_norm) {
            break;
        }
        for (i = 0; i < NV; ++i) {
            dx[i] += ws.ddx[i];
            ws.err[i] = ws.err2[i];
        }
        memcpy(dz, ws.dzt2, sizeof(double) * SZ);
        err_norm = new_norm;
    }
    for (t = 0; t < SZ; ++t) {
        ds[t] = u[t] - dz[t];
    }
    return err_norm;
}

/* Q'y (transpose) or Q y in place, Q = H_0 ... H_{n-1} from the Householder factors in ws.qrh */
static void householder_apply(double *y, int transpose)
{
    int step, t;
    for (step = 0; step < NV; ++step) {
        int k = transpose ? step : NV - 1 - step;
        const double *hk = ws.qrh + k * SZP;
        double s = y[k] + dot_from(hk, y, k + 1);
        s *= ws.tau[k];
        y[k] -= s;
        for (t = k + 1; t < SZ; ++t) {
            y[t] -= s * hk[t];
        }
    }
}

/* H_k = I - tau v v' (v = [1; hk[k+1:]]) applied to the four columns of P stored as the rows
 * h, h + SZP, h + 2 SZP, h + 3 SZP of P' (entries k.. of each) */
static void reflect4(const double *restrict hk, double *restrict h, int k, double tau)
{
    double c[4][4] = {{0.0}}, s[4];
    double *restrict h0 = h, *restrict h1 = h + SZP, *restrict h2 = h + 2 * SZP, *restrict h3 = h + 3 * SZP;
    int t = k + 1, r, w;
    for (r = 0; r < 4; ++r) {
        s[r] = 0.0;
    }
    for (; t % 4 != 0; ++t) {
        s[0] += hk[t] * h0[t];
        s[1] += hk[t] * h1[t];
        s[2] += hk[t] * h2[t];
        s[3] += hk[t] * h3[t];
    }
    for (; t < SZP; t += 4) {
        for (w = 0; w < 4; ++w) {
            double v = hk[t + w];
            c[0][w] += v * h0[t + w];
            c[1][w] += v * h1[t + w];
            c[2][w] += v * h2[t + w];
            c[3][w] += v * h3[t + w];
        }
    }
    s[0] = tau * (h0[k] + (s[0] + ((c[0][0] + c[0][1]) + (c[0][2] + c[0][3]))));
    s[1] = tau * (h1[k] + (s[1] + ((c[1][0] + c[1][1]) + (c[1][2] + c[1][3]))));
    s[2] = tau * (h2[k] + (s[2] + ((c[2][0] + c[2][1]) + (c[2][2] + c[2][3]))));
    s[3] = tau * (h3[k] + (s[3] + ((c[3][0] + c[3][1]) + (c[3][2] + c[3][3]))));
    h0[k] -= s[0];
    h1[k] -= s[1];
    h2[k] -= s[2];
    h3[k] -= s[3];
    for (t = k + 1; t < SZ; ++t) {
        double v = hk[t];
        h0[t] -= s[0] * v;
        h1[t] -= s[1] * v;
        h2[t] -= s[2] * v;
        h3[t] -= s[3] * v;
    }
}

/* Householder QR of P (LAPACK's dgeqrf conventions): reflectors in ws.qrh, R' into ws.l.
 * Returns 0 if R is singular or not finite. */
static int householder_qr(void)
{
    int k, i, t;
    memcpy(ws.qrh, ws.pt, NBYTES(NVP * SZP));
    for (k = 0; k < NV; ++k) {
        double *hk = ws.qrh + k * SZP;
        double alpha = hk[k], xnorm = sqrt(dot_from(hk, hk, k + 1)), beta, tau, sc;
        if (xnorm == 0.0) {
            ws.tau[k] = 0.0;
        } else {
            beta = -copysign(hypot(alpha, xnorm), alpha);
            tau = (beta - alpha) / beta;
            sc = 1.0 / (alpha - beta);
            for (t = k + 1; t < SZ; ++t) {
                hk[t] *= sc;
            }
            hk[k] = beta;
            ws.tau[k] = tau;
            for (i = k + 1; i < NV; i += 4) { /* four columns at a time (zero rows past NV) */
                reflect4(hk, ws.qrh + i * SZP, k, tau);
            }
        }
    }
    for (i = 0; i < NV; ++i) { /* L = R': L[i][t] = R[t][i] = qrh[i][t], t <= i */
        for (t = 0; t < NV; ++t) {
            double v = t <= i ? ws.qrh[i * SZP + t] : 0.0;
            if (!(v - v == 0.0)) {
                return 0;
            }
            ws.l[i * NV + t] = v;
        }
        if (ws.l[i * NV + i] == 0.0) {
            return 0;
        }
    }
    return 1;
}

/* kernels.step._newton_qr */
static void newton_qr(const double *u, double ref_scale, double *dx, double *ds, double *dz)
{
    int i, t, it;
    double err_norm;
    for (t = 0; t < SZ; ++t) {
        ws.v[t] = u[t] + ws.rpt[t];
    }
    memcpy(ws.wv, ws.rd, NBYTES(NV));
    dense_forward(ws.l, NV, NV, ws.wv); /* R' w = rd */
    memcpy(ws.tv, ws.v, NBYTES(SZP));
    householder_apply(ws.tv, 1);
    for (i = 0; i < NV; ++i) {
        dx[i] = -(ws.wv[i] + ws.tv[i]);
    }
    dense_backward(ws.l, NV, NV, dx); /* R dx = -(w + t1) */
    memcpy(dz, ws.tv, sizeof(double) * SZ);
    for (i = 0; i < NV; ++i) {
        dz[i] = -ws.wv[i];
    }
    householder_apply(dz, 0);
    pt_times(dz, ws.err);
    for (i = 0; i < NV; ++i) {
        ws.err[i] += ws.rd[i];
    }
    err_norm = norm2(ws.err, NV);
    for (it = 0; it < REFINE_STEPS; ++it) {
        double new_norm;
        if (err_norm <= REFINE_TARGET * ref_scale) {
            break;
        }
        memcpy(ws.vn, ws.err, NBYTES(NV));
        dense_forward(ws.l, NV, NV, ws.vn); /* cw */
        for (t = 0; t < SZ; ++t) {
            ws.yv[t] = t < NV ? ws.vn[t] : 0.0;
        }
        householder_apply(ws.yv, 0);
        for (t = 0; t < SZ; ++t) {
            ws.dzt2[t] = dz[t] - ws.yv[t];
        }
        pt_times(ws.dzt2, ws.err2);
        for (i = 0; i < NV; ++i) {
            ws.err2[i] += ws.rd[i];
        }
        new_norm = norm2(ws.err2, NV);
        if (new_norm >= err_norm) {
            break;
        }
        dense_backward(ws.l, NV, NV, ws.vn);
        for (i = 0; i < NV; ++i) {
            dx[i] -= ws.vn[i];
            ws.err[i] = ws.err2[i];
        }
        memcpy(dz, ws.dzt2, sizeof(double) * SZ);
        err_norm = new_norm;
    }
    for (t = 0; t < SZ; ++t) {
        ds[t] = u[t] - dz[t];
    }
}

#define STEP_CAP (1.0 / 0.99)

/* largest a <= STEP_CAP with diag(lambda) + a d >= 0 for d = ds and dz, every block */
static double max_step(const double *ds, const double *dz)
{
    double alpha = STEP_CAP;
    int j, a, b, which;
    for (j = 0; j < NB; ++j) {
        int k = rmpc_order[j];
        const double *lam = ws.lam + j * KM;
        for (a = 0; a < k; ++a) {
            ws.e1[a] = 1.0 / sqrt(lam[a]);
        }
        for (which = 0; which < 2; ++which) {
            double t;
            unpack_block(which == 0 ? ds : dz, j, ws.m1);
            for (a = 0; a < k; ++a) {
                for (b = 0; b < k; ++b) {
                    ws.m1[a * KM + b] *= ws.e1[a] * ws.e1[b];
                }
            }
            t = dense_smallest_eigenvalue(ws.m1, KM, k, -1.0 / alpha, 1e-9, ws.ev, ws.ee, ws.e2, ws.m2);
            if (t < -1.0 / alpha) {
                alpha = -1.0 / t;
            }
        }
    }
    return alpha;
}

/* out = K' M K (k x k) for block j */
static void congruence_t(int j, const double *mat, double *out)
{
    int k = rmpc_order[j], a, b, c;
    const double *kj = ws.kk + j * KK;
    for (a = 0; a < k; ++a) { /* m4 = M K */
        for (b = 0; b < k; ++b) {
            double s = 0.0;
            for (c = 0; c < k; ++c) {
                s += mat[a * KM + c] * kj[c * KM + b];
            }
            ws.m4[a * KM + b] = s;
        }
    }
    for (a = 0; a < k; ++a) {
        for (b = 0; b < k; ++b) {
            double s = 0.0;
            for (c = 0; c < k; ++c) {
                s += kj[c * KM + a] * ws.m4[c * KM + b];
            }
            out[a * KM + b] = s;
        }
    }
}

/* kernels.step.newton_step; x, theta updated in place on success */
static int newton_step(int use_qr, double *theta, double mu, double ref_scale, double err_limit)
{
    int j, a, b, c, t, i, tries;
    double alpha_aff, sigma, alpha, t0;
    for (j = 0; j < NB; ++j) { /* rpt = K rp K' */
        int k = rmpc_order[j];
        const double *kj = ws.kk + j * KK;
        unpack_block(ws.rp, j, ws.m1);
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) {
                double s = 0.0;
                for (c = 0; c < k; ++c) {
                    s += kj[a * KM + c] * ws.m1[c * KM + b];
                }
                ws.m2[a * KM + b] = s;
            }
        }
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) {
                double s = 0.0;
                for (c = 0; c < k; ++c) {
                    s += ws.m2[a * KM + c] * kj[b * KM + c];
                }
                ws.m3[a * KM + b] = s;
            }
        }
        pack_block(ws.m3, j, ws.rpt);
    }
    for (t = 0; t < SZ; ++t) {
        ws.u[t] = 0.0;
    }
    for (j = 0; j < NB; ++j) {
        int k = rmpc_order[j];
        for (a = 0; a < k; ++a) {
            ws.u[rmpc_offset[j] + a * k - (a * (a - 1)) / 2] = -ws.lam[j * KM + a];
        }
    }
    t0 = PHASE_NOW();
    if (use_qr) {
        newton_qr(ws.u, ref_scale, ws.dx, ws.dsa, ws.dza);
    } else {
        newton_chol(ws.u, ref_scale, ws.dx, ws.dsa, ws.dza);
    }
    PHASE_ADD(KOTHARE_PHASE_SOLVES, t0);
    t0 = PHASE_NOW();
    alpha_aff = max_step(ws.dsa, ws.dza);
    PHASE_ADD(KOTHARE_PHASE_STEP_LENGTH, t0);
    if (alpha_aff > 1.0) {
        alpha_aff = 1.0;
    }
    sigma = (1.0 - alpha_aff) * (1.0 - alpha_aff) * (1.0 - alpha_aff);
    for (j = 0; j < NB; ++j) {
        int k = rmpc_order[j];
        const double *lam = ws.lam + j * KM;
        unpack_block(ws.dsa, j, ws.m1);
        unpack_block(ws.dza, j, ws.m2);
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) {
                double s = 0.0;
                for (c = 0; c < k; ++c) {
                    s += ws.m1[a * KM + c] * ws.m2[c * KM + b];
                }
                ws.m3[a * KM + b] = s;
            }
        }
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) {
                ws.m4[a * KM + b] = -0.5 * (ws.m3[a * KM + b] + ws.m3[b * KM + a]);
            }
        }
        for (a = 0; a < k; ++a) {
            ws.m4[a * KM + a] += sigma * mu - lam[a] * lam[a];
        }
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) {
                ws.m4[a * KM + b] *= 2.0 / (lam[a] + lam[b]);
            }
        }
        pack_block(ws.m4, j, ws.ucor);
    }
    t0 = PHASE_NOW();
    if (use_qr) {
        newton_qr(ws.ucor, ref_scale, ws.dx, ws.dst, ws.dzt);
    } else {
        double err = newton_chol(ws.ucor, ref_scale, ws.dx, ws.dst, ws.dzt);
        if (!(err <= err_limit)) {
            PHASE_ADD(KOTHARE_PHASE_SOLVES, t0);
            return STEP_INACCURATE;
        }
    }
    PHASE_ADD(KOTHARE_PHASE_SOLVES, t0);
    t0 = PHASE_NOW();
    alpha = 0.99 * max_step(ws.dst, ws.dzt);
    PHASE_ADD(KOTHARE_PHASE_STEP_LENGTH, t0);
    if (alpha > 1.0) {
        alpha = 1.0;
    }
    if (!(alpha - alpha == 0.0 && alpha > 1e-12)) {
        return STEP_BAD_LENGTH;
    }
    for (tries = 0; tries < 6; ++tries) {
        double theta_new = *theta * (1.0 - alpha);
        int ok = 1;
        for (i = 0; i < NV; ++i) {
            ws.nxt.x[i] = ws.cur.x[i] + alpha * ws.dx[i];
        }
        g_times(ws.nxt.x, ws.gx);
        for (t = 0; t < SZ; ++t) {
            ws.tv[t] = ws.hvec[t] - ws.gx[t] + theta_new * ws.r0[t];
        }
        for (j = 0; j < NB; ++j) {
            unpack_block(ws.tv, j, ws.nxt.s + j * KK);
            if (dense_cholesky(ws.nxt.s + j * KK, KM, rmpc_order[j], ws.chol_new + j * KK, KM) != 0) {
                ok = 0;
                break;
            }
        }
        if (!ok) {
            alpha *= 0.8;
            continue;
        }
        for (j = 0; j < NB; ++j) {
            int k = rmpc_order[j];
            double *zo = ws.nxt.z + j * KK;
            const double *zc = ws.cur.z + j * KK;
            unpack_block(ws.dzt, j, ws.m1);
            congruence_t(j, ws.m1, ws.m2);
            for (a = 0; a < k; ++a) {
                for (b = 0; b < k; ++b) {
                    zo[a * KM + b] = zc[a * KM + b] + (0.5 * alpha) * (ws.m2[a * KM + b] + ws.m2[b * KM + a]);
                }
            }
            if (dense_cholesky(zo, KM, k, ws.m3, KM) != 0) {
                unpack_block(ws.dzt, j, ws.m1);
                for (a = 0; a < k; ++a) {
                    for (b = 0; b < k; ++b) {
                        ws.m1[a * KM + b] *= alpha;
                    }
                    ws.m1[a * KM + a] += ws.lam[j * KM + a];
                }
                congruence_t(j, ws.m1, ws.m2);
                for (a = 0; a < k; ++a) {
                    for (b = 0; b < k; ++b) {
                        zo[a * KM + b] = 0.5 * (ws.m2[a * KM + b] + ws.m2[b * KM + a]);
                    }
                }
            }
        }
        *theta = theta_new;
        return STEP_OK;
    }
    return STEP_NOT_PD;
}

/* kernels.iteration.rows_iteration */
static int iteration(int *use_qr, double *theta, double mu, double ref_scale, double err_limit)
{
    int code, ok;
    double t0 = PHASE_NOW();
    ok = scaling_and_p();
    PHASE_ADD(KOTHARE_PHASE_SCALING, t0);
    if (!ok) {
        return STEP_LOST_PD;
    }
    if (!*use_qr) {
        t0 = PHASE_NOW();
        schur_complement();
        PHASE_ADD(KOTHARE_PHASE_SCHUR, t0);
        t0 = PHASE_NOW();
        ok = dense_cholesky(ws.h, NV, NV, ws.l, NV) == 0 && factor_ok();
        PHASE_ADD(KOTHARE_PHASE_CHOLESKY, t0);
        if (ok) {
            t0 = PHASE_NOW();
            code = newton_step(0, theta, mu, ref_scale, err_limit);
            PHASE_ADD(KOTHARE_PHASE_NEWTON, t0);
            if (code != STEP_INACCURATE) {
                return code;
            }
        }
    }
    *use_qr = 1;
    t0 = PHASE_NOW();
    ok = householder_qr();
    PHASE_ADD(KOTHARE_PHASE_QR, t0);
    if (!ok) {
        return STEP_SINGULAR;
    }
    t0 = PHASE_NOW();
    code = newton_step(1, theta, mu, ref_scale, HUGE_VAL);
    PHASE_ADD(KOTHARE_PHASE_NEWTON, t0);
    return code;
}

static void copy_point(point_t *dst, const point_t *src)
{
    memcpy(dst->x, src->x, NBYTES(NV));
    memcpy(dst->s, src->s, NBYTES(NB * KK));
    memcpy(dst->z, src->z, NBYTES(NB * KK));
}

static void copy_saved(saved_t *dst, const saved_t *src)
{
    memcpy(dst->x, src->x, NBYTES(NV));
    memcpy(dst->s, src->s, NBYTES(SZ));
    memcpy(dst->z, src->z, NBYTES(SZ));
}

static void save_point(saved_t *dst, const point_t *src)
{
    int t;
    memcpy(dst->x, src->x, NBYTES(NV));
    for (t = 0; t < SZ; ++t) {
        int at = ws.ent_blk[t] * KK + ws.ent_row[t] * KM + ws.ent_col[t];
        dst->s[t] = src->s[at];
        dst->z[t] = src->z[at];
    }
}

/* the blocks of src into dst (their leading k x k parts, the only parts read) */
static void restore_point(point_t *dst, const saved_t *src)
{
    int t;
    memcpy(dst->x, src->x, NBYTES(NV));
    for (t = 0; t < SZ; ++t) {
        int at = ws.ent_blk[t] * KK + ws.ent_row[t] * KM + ws.ent_col[t];
        int mirror = ws.ent_blk[t] * KK + ws.ent_col[t] * KM + ws.ent_row[t];
        dst->s[at] = src->s[t];
        dst->s[mirror] = src->s[t];
        dst->z[at] = src->z[t];
        dst->z[mirror] = src->z[t];
    }
}

/* BlockLMISolver._run: returns the solver's word; the answer (equilibrated x) in ws.cur */
static int run(int warm, int max_iter, int *iterations, double *pres_o, double *dres_o, double *gap_o,
               double *radius_o)
{
    int it = 0, i, t, status = W_MAX_ITER, use_qr = 0, have_best = 0, have_stall = 0, have_next = 0;
    int count = 0;
    double c_norm = maxd(1.0, norm2(ws.cvec, NV)), h_norm = maxd(1.0, norm2(ws.hvec, SZ));
    double theta = 1.0, pres = HUGE_VAL, dres = HUGE_VAL, gap = HUGE_VAL, radius = 0.0;
    double best_m[3] = {0.0, 0.0, 0.0}, stall_m[3] = {0.0, 0.0, 0.0};
    if (warm) {
        restore_point(&ws.cur, &ws.warm);
        for (i = 0; i < NV; ++i) {
            ws.cur.x[i] = ws.warm.x[i] / ws.dscale[i];
        }
    } else if (!initial_point()) {
        *iterations = 0;
        *pres_o = *dres_o = *gap_o = HUGE_VAL;
        return W_NUMERICAL;
    }
    pack(ws.cur.s, ws.sp);
    g_times(ws.cur.x, ws.gx);
    for (t = 0; t < SZ; ++t) {
        ws.r0[t] = ws.sp[t] + ws.gx[t] - ws.hvec[t];
    }
    if (!cholesky_blocks(ws.cur.s, ws.s_chol)) {
        max_iter = -1;
        status = W_NUMERICAL;
    }
    for (it = 0; it <= max_iter; ++it) {
        double n_rp, n_gx, n_sp, n_rd, n_gtz, pcost = 0.0, dcost = 0.0, rel_gap, gnorm = 0.0;
        int agree, halved = 0, stalled, ray_grows = 0, code;
        pack(ws.cur.s, ws.sp);
        pack(ws.cur.z, ws.zp);
        g_times(ws.cur.x, ws.gx);
        gt_times(ws.zp, ws.gtz);
        for (i = 0; i < NV; ++i) {
            ws.rd[i] = ws.gtz[i] + ws.cvec[i];
            pcost += ws.cvec[i] * ws.cur.x[i];
        }
        gap = 0.0;
        for (t = 0; t < SZ; ++t) {
            ws.rp[t] = ws.gx[t] + ws.sp[t] - ws.hvec[t];
            gap += ws.sp[t] * ws.zp[t];
            dcost -= ws.hvec[t] * ws.zp[t];
        }
        n_rp = norm2(ws.rp, SZ);
        n_gx = norm2(ws.gx, SZ);
        n_sp = norm2(ws.sp, SZ);
        n_rd = norm2(ws.rd, NV);
        n_gtz = norm2(ws.gtz, NV);
        pres = n_rp / maxd(h_norm, maxd(n_gx, n_sp));
        dres = n_rd / maxd(c_norm, n_gtz);
        rel_gap = gap / maxd(fabs(pcost), maxd(fabs(dcost), 1e-300));
        agree = fabs(pcost - dcost) <= REDUCED_TOL * maxd(1.0, maxd(fabs(pcost), fabs(dcost)));
        if (agree && pres <= RMPC_TOL_FEAS && dres <= RMPC_TOL_FEAS
            && (gap <= RMPC_TOL_GAP_ABS || rel_gap <= RMPC_TOL_GAP_REL) && blocks_within(ws.cur.x, RMPC_TOL_FEAS)) {
            status = W_OPTIMAL;
            break;
        }
        if (!have_stall && agree && maxd(pres, dres) <= REDUCED_TOL
            && (gap < rel_gap ? gap : rel_gap) <= REDUCED_TOL && blocks_within(ws.cur.x, REDUCED_TOL)) {
            save_point(&ws.best, &ws.cur);
            best_m[0] = pres;
            best_m[1] = dres;
            best_m[2] = gap;
            have_best = 1;
        }
        /* the dual iterate as a Farkas ray */
        for (i = 0; i < NV; ++i) {
            double g = ws.gtz[i] / ws.dscale[i];
            gnorm += g * g;
        }
        radius = dcost > 0.0 ? dcost / maxd(sqrt(gnorm), 1e-300) : 0.0;
        if (radius >= RMPC_INF_RADIUS && n_gtz <= RAY_TOL * norm2(ws.zp, SZ)) {
            status = W_INFEASIBLE;
            have_best = 0;
            break;
        }
        ws.merits[3 * count] = pres;
        ws.merits[3 * count + 1] = dres;
        ws.merits[3 * count + 2] = gap < rel_gap ? gap : rel_gap;
        ws.ray[count] = radius > 0.0 ? 1.0 / radius : HUGE_VAL;
        ++count;
        if (it >= STALL_WINDOW) {
            int q, last = count - 1, then = count - 1 - STALL_WINDOW;
            ray_grows = ws.ray[last] <= 0.5 * ws.ray[then];
            for (q = 0; q < 3; ++q) {
                if (ws.merits[3 * last + q] <= 0.5 * ws.merits[3 * then + q]) {
                    halved = 1;
                }
            }
        }
        stalled = it >= STALL_WINDOW && !halved;
        if (!have_stall) {
            if (stalled) {
                if (!ray_grows) {
                    status = W_STALL;
                    break;
                }
                save_point(&ws.stall, &ws.cur);
                stall_m[0] = pres;
                stall_m[1] = dres;
                stall_m[2] = gap;
                have_stall = 1;
            }
        } else if (halved) {
            have_stall = 0;
        } else if (!ray_grows) {
            break;
        }
        if (!have_stall && 0.1 * RMPC_WARM_GAP <= rel_gap && rel_gap <= RMPC_WARM_GAP
            && maxd(pres, dres) <= RMPC_WARM_FEAS) {
            save_point(&ws.warm_next, &ws.cur);
            for (i = 0; i < NV; ++i) {
                ws.warm_next.x[i] = ws.cur.x[i] * ws.dscale[i];
            }
            have_next = 1;
        }
        if (it == max_iter) {
            break;
        }
        code = iteration(&use_qr, &theta, gap / RMPC_DEGREE, maxd(c_norm, n_gtz),
                         maxd(n_rd, RMPC_TOL_FEAS * maxd(c_norm, n_gtz)));
        if (code != STEP_OK) {
            status = W_NUMERICAL;
            break;
        }
        copy_point(&ws.cur, &ws.nxt);
        memcpy(ws.s_chol, ws.chol_new, NBYTES(NB * KK));
    }
    if (it > max_iter) {
        it = max_iter < 0 ? 0 : max_iter;
    }
    if (have_stall && status != W_OPTIMAL && status != W_INFEASIBLE) {
        status = W_STALL;
        restore_point(&ws.cur, &ws.stall);
        pres = stall_m[0];
        dres = stall_m[1];
        gap = stall_m[2];
    }
    if (status == W_OPTIMAL && have_next) {
        copy_saved(&ws.warm, &ws.warm_next);
        ws.has_warm = 1;
    }
    if (status != W_OPTIMAL && have_best) {
        status = W_INACCURATE;
        restore_point(&ws.cur, &ws.best);
        pres = best_m[0];
        dres = best_m[1];
        gap = best_m[2];
    }
    *iterations = it;
    *pres_o = pres;
    *dres_o = dres;
    *gap_o = gap;
    *radius_o = radius;
    return status;
}

/* BlockLMISolver.solve at the data set_data set: a warm start if asked and kept, retried cold
 * unless it ended optimal or infeasible (its iterations counted); the solver's word */
static int solve_data(int warm_start, int *its, double *pres, double *dres, double *gap, double *radius)
{
    int word = -1, spent = 0;
    if (warm_start && ws.has_warm) {
        word = run(1, RMPC_WARM_MAX_ITER, its, pres, dres, gap, radius);
        if (word != W_OPTIMAL && word != W_INFEASIBLE) {
            spent = *its;
            word = -1;
        }
    }
    if (word < 0) {
        word = run(0, RMPC_MAX_ITER, its, pres, dres, gap, radius);
    }
    *its += spent;
    return word;
}

#ifndef KOTHARE_RUNTIME
/* ------------------------------------------------------------------ the certificate */

static double rel_min_eig(double *mat, int k)
{
    int a, b;
    double scale;
    for (a = 0; a < k; ++a) {
        for (b = 0; b < a; ++b) {
            double s = 0.5 * (mat[a * CK + b] + mat[b * CK + a]);
            mat[a * CK + b] = s;
            mat[b * CK + a] = s;
        }
    }
    if (dense_sym_eig(mat, CK, k, ws.cw, NULL, 0, ws.ce, ws.cv) != 0) {
        return -HUGE_VAL;
    }
    scale = maxd(fabs(ws.cw[0]), fabs(ws.cw[k - 1]));
    scale = maxd(scale, 2.2250738585072014e-308);
    return ws.cw[0] / scale;
}

/* [[top, G', Q Q1h', Y' Rh'], [G, Q, 0, 0], [Q1h Q, 0, gam I, 0], [Rh Y, 0, 0, gam I]] */
static double vertex_margin(const double *top, const double *g, const double *q, const double *y, double gam)
{
    const int n = RMPC_NX, p = RMPC_P1, m = RMPC_NU, k = CK;
    int a, b, c;
    for (a = 0; a < k * CK; ++a) {
        ws.cm[a] = 0.0;
    }
    for (a = 0; a < n; ++a) {
        for (b = 0; b < n; ++b) {
            ws.cm[a * CK + b] = top[a * n + b];
            ws.cm[(n + a) * CK + b] = g[a * n + b];
            ws.cm[b * CK + n + a] = g[a * n + b];
            ws.cm[(n + a) * CK + n + b] = q[a * n + b];
        }
    }
    for (a = 0; a < p; ++a) {
        for (b = 0; b < n; ++b) {
            double s = 0.0;
            for (c = 0; c < n; ++c) {
                s += rmpc_cert_q1h[a * n + c] * q[c * n + b];
            }
            ws.cm[(2 * n + a) * CK + b] = s;
            ws.cm[b * CK + 2 * n + a] = s;
        }
    }
    for (a = 0; a < m; ++a) {
        for (b = 0; b < n; ++b) {
            double s = 0.0;
            for (c = 0; c < m; ++c) {
                s += rmpc_cert_rh[a * m + c] * y[c * n + b];
            }
            ws.cm[(2 * n + p + a) * CK + b] = s;
            ws.cm[b * CK + 2 * n + p + a] = s;
        }
    }
    for (a = 2 * n; a < k; ++a) {
        ws.cm[a * CK + a] = gam;
    }
    return rel_min_eig(ws.cm, k);
}

/* lmi.certificate.certify: the worst relative margin at the state x (original units) */
static double certify(const double *x, double gam, const double *q, const double *y)
{
    const int n = RMPC_NX, m = RMPC_NU;
    int a, b, c, j;
    double worst = HUGE_VAL, nrm, sc, mg;
    for (a = 0; a < n * n; ++a) {
        if (!(q[a] - q[a] == 0.0)) {
            return -HUGE_VAL;
        }
    }
    for (a = 0; a < m * n; ++a) {
        if (!(y[a] - y[a] == 0.0)) {
            return -HUGE_VAL;
        }
    }
    if (!(gam - gam == 0.0)) {
        return -HUGE_VAL;
    }
    nrm = norm2(x, n);
    sc = nrm > 0.0 ? 1.0 / nrm : 1.0;
    ws.cm[0] = 1.0;
    for (a = 0; a < n; ++a) {
        ws.cm[a + 1] = sc * x[a];
        ws.cm[(a + 1) * CK] = sc * x[a];
        for (b = 0; b < n; ++b) {
            ws.cm[(a + 1) * CK + b + 1] = sc * sc * q[a * n + b];
        }
    }
    mg = rel_min_eig(ws.cm, n + 1);
    worst = mg < worst ? mg : worst;
    for (j = 0; j < RMPC_NVERT; ++j) {
        const double *aj = rmpc_cert_a + j * n * n, *bj = rmpc_cert_b + j * n * m;
        double hmat[RMPC_NX * RMPC_NX], top[RMPC_NX * RMPC_NX], sh[RMPC_NX * RMPC_NX];
        const double sdt = sqrt(RMPC_DT);
        for (a = 0; a < n; ++a) { /* G = A Q + B Y */
            for (b = 0; b < n; ++b) {
                double s = 0.0, s2 = 0.0;
                for (c = 0; c < n; ++c) {
                    s += aj[a * n + c] * q[c * n + b];
                }
                for (c = 0; c < m; ++c) {
                    s2 += bj[a * m + c] * y[c * n + b];
                }
                ws.gj[a * n + b] = s + s2;
            }
        }
        mg = vertex_margin(q, ws.gj, q, y, gam);
        worst = mg < worst ? mg : worst;
        for (a = 0; a < n * n; ++a) {
            hmat[a] = (ws.gj[a] - q[a]) / RMPC_DT;
            sh[a] = sdt * hmat[a];
        }
        for (a = 0; a < n; ++a) {
            for (b = 0; b < n; ++b) {
                top[a * n + b] = -(hmat[a * n + b] + hmat[b * n + a]);
            }
        }
        mg = vertex_margin(top, sh, q, y, RMPC_DT * gam);
        worst = mg < worst ? mg : worst;
    }
    if (dense_cholesky(q, n, n, ws.qc, n) != 0) {
        return -HUGE_VAL; /* Q not invertible as a positive definite matrix */
    }
#if RMPC_INPUT_KIND == 1
    {
        double u2 = rmpc_bound[0] * rmpc_bound[0];
        for (a = 0; a < (m + n) * CK; ++a) {
            ws.cm[a] = 0.0;
        }
        for (a = 0; a < m; ++a) {
            ws.cm[a * CK + a] = u2;
            for (b = 0; b < n; ++b) {
                ws.cm[a * CK + m + b] = y[a * n + b];
                ws.cm[(m + b) * CK + a] = y[a * n + b];
            }
        }
        for (a = 0; a < n; ++a) {
            for (b = 0; b < n; ++b) {
                ws.cm[(m + a) * CK + m + b] = q[a * n + b];
            }
        }
        mg = rel_min_eig(ws.cm, m + n);
        worst = mg < worst ? mg : worst;
    }
#elif RMPC_INPUT_KIND == 2
    for (a = 0; a < m; ++a) {
        double w[RMPC_NX], peak = 0.0;
        for (b = 0; b < n; ++b) {
            w[b] = y[a * n + b];
        }
        dense_forward(ws.qc, n, n, w);
        for (b = 0; b < n; ++b) {
            peak += w[b] * w[b];
        }
        mg = 1.0 - peak / (rmpc_bound[a] * rmpc_bound[a]);
        worst = mg < worst ? mg : worst;
    }
#endif
#if RMPC_POUT > 0
    for (a = 0; a < RMPC_POUT; ++a) {
        double most = 0.0;
        for (j = 0; j < RMPC_NVERT; ++j) {
            const double *aj = rmpc_cert_a + j * n * n, *bj = rmpc_cert_b + j * n * m;
            double row[RMPC_NX], val = 0.0;
            for (b = 0; b < n; ++b) {
                double s = 0.0;
                for (c = 0; c < n; ++c) {
                    int d;
                    double g = 0.0;
                    for (d = 0; d < n; ++d) {
                        g += aj[c * n + d] * q[d * n + b];
                    }
                    for (d = 0; d < m; ++d) {
                        g += bj[c * m + d] * y[d * n + b];
                    }
                    s += rmpc_cert_cout[a * n + c] * g;
                }
                row[b] = s;
            }
            dense_forward(ws.qc, n, n, row);
            for (b = 0; b < n; ++b) {
                val += row[b] * row[b];
            }
            most = val > most ? val : most;
        }
        mg = 1.0 - most / (rmpc_bound[RMPC_NUB + a] * rmpc_bound[RMPC_NUB + a]);
        worst = mg < worst ? mg : worst;
    }
#endif
    return worst;
}

/* ------------------------------------------------------------------ the public calls */

void kothare_reset_warm_start(void) { ws.has_warm = 0; }

void kothare_reset(void)
{
    ws.ready = 0;
    ws.has_warm = 0;
    ws.has_gain = 0;
}

size_t kothare_workspace_bytes(void) { return sizeof ws; }

#ifdef KOTHARE_PHASE_TIMES
void kothare_phase_times(double seconds[KOTHARE_NPHASES], long counts[KOTHARE_NPHASES])
{
    memcpy(seconds, phase_sec, sizeof phase_sec);
    memcpy(counts, phase_count, sizeof phase_count);
}
#endif

void kothare_last_info(double info[8]) { memcpy(info, ws.info, sizeof ws.info); }

static void apply_gain(const double *x, double *u, double *F)
{
    int a, b;
    for (a = 0; a < RMPC_NU; ++a) {
        double s = 0.0;
        if (ws.has_gain && x != NULL) {
            for (b = 0; b < RMPC_NX; ++b) {
                s += ws.gain[a * RMPC_NX + b] * x[b];
            }
        }
        u[a] = s;
    }
    for (a = 0; a < RMPC_NU; ++a) {
        if (!(u[a] - u[a] == 0.0)) { /* F x overflowed: no command rather than inf or NaN */
            for (b = 0; b < RMPC_NU; ++b) {
                u[b] = 0.0;
            }
            break;
        }
    }
    if (F != NULL) {
        for (a = 0; a < RMPC_NU * RMPC_NX; ++a) {
            F[a] = ws.has_gain ? ws.gain[a] : 0.0;
        }
    }
}

int kothare_apply_gain(const double *x, double *u)
{
    apply_gain(x, u, NULL);
    return ws.has_gain;
}

static int solve_state(const double *x, double *u, double *F, double *gamma, int *iterations);

int kothare_solve(const double *x, double *u, double *F, double *gamma, int *iterations)
{
    double t0 = PHASE_NOW();
    int status = solve_state(x, u, F, gamma, iterations);
    PHASE_ADD(KOTHARE_PHASE_SOLVE, t0);
    return status;
}

static int solve_state(const double *x, double *u, double *F, double *gamma, int *iterations)
{
    const int n = RMPC_NX, m = RMPC_NU;
    double xs[RMPC_NX], scale, nrm = 1.0, pres, dres, gap, radius = 0.0, gam, s2, worst;
    int i, a, b, word, its = 0, status;
    if (!ws.laid_out) {
        layout();
        ws.laid_out = 1;
    }
    for (i = 0; i < 8; ++i) {
        ws.info[i] = 0.0;
    }
    if (gamma != NULL) {
        *gamma = NAN;
    }
    if (iterations != NULL) {
        *iterations = 0;
    }
    for (i = 0; i < n; ++i) {
        if (!(x[i] - x[i] == 0.0)) {
            apply_gain(NULL, u, F);
            return KOTHARE_STATUS_NONFINITE_X;
        }
    }
    scale = norm2(x, n);
    if (!(scale < HUGE_VAL)) { /* so large that its norm overflows: treated as non-finite */
        apply_gain(NULL, u, F);
        return KOTHARE_STATUS_NONFINITE_X;
    }
    if (scale == 0.0) {
        apply_gain(NULL, u, F);
        return KOTHARE_STATUS_ZERO_STATE;
    }
    for (i = 0; i < n; ++i) {
        xs[i] = x[i] / scale;
    }
    for (i = 0; i < RMPC_NUB + RMPC_NYB; ++i) {
        ws.bound[i] = rmpc_bound[i] / scale;
    }
#if RMPC_SCALED
    for (i = 0; i < n; ++i) {
        xs[i] = xs[i] / rmpc_t[i];
    }
    nrm = norm2(xs, n);
    for (i = 0; i < n; ++i) {
        xs[i] = xs[i] / nrm;
    }
    for (i = 0; i < RMPC_NUB + RMPC_NYB; ++i) {
        ws.bound[i] = ws.bound[i] / nrm;
    }
#endif
    set_data(xs);
    word = solve_data(RMPC_WARM_START, &its, &pres, &dres, &gap, &radius);
    if (iterations != NULL) {
        *iterations = its;
    }
    ws.info[0] = pres;
    ws.info[1] = dres;
    ws.info[2] = gap;
    ws.info[3] = word;
    ws.info[6] = word == W_INFEASIBLE ? radius : NAN;
    ws.info[7] = its;
    if (word != W_OPTIMAL) {
        apply_gain(x, u, F);
        switch (word) {
        case W_INFEASIBLE: return KOTHARE_STATUS_INFEASIBLE;
        case W_MAX_ITER: return KOTHARE_STATUS_MAX_ITERATIONS;
        case W_INACCURATE: return KOTHARE_STATUS_INACCURATE;
        default: return KOTHARE_STATUS_NUMERICAL_ERROR;
        }
    }
    /* Q~, Y~ from the variables, then back to the state's units (IPMKothare._unscale and
     * KothareProblem._finish) */
    for (i = 0; i < NV; ++i) {
        ws.vn[i] = ws.cur.x[i] * ws.dscale[i];
    }
    memset(ws.qm, 0, sizeof ws.qm);
    memset(ws.ym, 0, sizeof ws.ym);
    for (i = 0; i < RMPC_NQMAP; ++i) {
        ws.qm[rmpc_q_cell[i]] += ws.vn[rmpc_q_var[i]] * rmpc_q_val[i];
    }
    for (i = 0; i < RMPC_NYMAP; ++i) {
        ws.ym[rmpc_y_cell[i]] += ws.vn[rmpc_y_var[i]] * rmpc_y_val[i];
    }
    gam = ws.vn[0] / RMPC_GAMMA_DIV;
    ws.info[5] = ws.vn[0];
    s2 = nrm * nrm;
#if RMPC_SCALED
    for (a = 0; a < n; ++a) {
        for (b = 0; b < n; ++b) {
            ws.qm[a * n + b] = ws.qm[a * n + b] * (rmpc_t[a] * rmpc_t[b]) * s2;
        }
    }
    for (a = 0; a < m; ++a) {
        for (b = 0; b < n; ++b) {
            ws.ym[a * n + b] = ws.ym[a * n + b] * rmpc_t[b] * s2;
        }
    }
    gam = gam * s2;
#endif
    s2 = scale * scale;
    for (a = 0; a < n; ++a) {
        for (b = 0; b < n; ++b) {
            ws.tmp[a * n + b] = 0.5 * (ws.qm[a * n + b] + ws.qm[b * n + a]) * s2;
        }
    }
    memcpy(ws.qm, ws.tmp, sizeof ws.qm);
    for (a = 0; a < m * n; ++a) {
        ws.ym[a] *= s2;
    }
    gam *= s2;
    worst = certify(x, gam, ws.qm, ws.ym);
    ws.info[4] = worst;
    status = (worst - worst == 0.0 && worst >= -RMPC_CERT_TOL) ? KOTHARE_STATUS_OPTIMAL
                                                               : KOTHARE_STATUS_CERTIFICATE_FAILED;
    if (status == KOTHARE_STATUS_OPTIMAL) { /* F = Y Q^-1 (Q = L L') */
        if (dense_cholesky(ws.qm, n, n, ws.qc, n) != 0) {
            status = KOTHARE_STATUS_CERTIFICATE_FAILED;
        } else {
            for (a = 0; a < m; ++a) {
                double row[RMPC_NX];
                for (b = 0; b < n; ++b) {
                    row[b] = ws.ym[a * n + b];
                }
                dense_forward(ws.qc, n, n, row);
                dense_backward(ws.qc, n, n, row);
                for (b = 0; b < n; ++b) {
                    if (!(row[b] - row[b] == 0.0)) {
                        status = KOTHARE_STATUS_CERTIFICATE_FAILED;
                    }
                    ws.fm[a * n + b] = row[b];
                }
            }
        }
    }
    if (status == KOTHARE_STATUS_OPTIMAL) {
        memcpy(ws.gain, ws.fm, sizeof ws.gain);
        ws.has_gain = 1;
        if (gamma != NULL) {
            *gamma = gam;
        }
    }
    apply_gain(x, u, F);
    return status;
}
#endif /* KOTHARE_RUNTIME */

#ifdef KOTHARE_RUNTIME
/* ------------------------------------------------------------------ the run-time calls */

#define ALIGNED(bytes) (((bytes) + 15u) & ~(size_t)15u)
#define CARVE(type, name, count)                                                               \
    if (base != NULL) {                                                                        \
        owner->name = (type *)(void *)(base + at);                                             \
    }                                                                                          \
    at += ALIGNED((size_t)(count) * sizeof(type));

static size_t carve_point(point_t *owner, unsigned char *base, size_t at)
{
    POINT_ARRAYS(CARVE)
    return at;
}

static size_t carve_saved(saved_t *owner, unsigned char *base, size_t at)
{
    SAVED_ARRAYS(CARVE)
    return at;
}

/* the arrays of the workspace at base (base NULL: only the bytes counted), after the struct */
static size_t carve(struct workspace *owner, unsigned char *base)
{
    size_t at = ALIGNED(sizeof(struct workspace));
    at = carve_point(&owner->cur, base, at);
    at = carve_point(&owner->nxt, base, at);
    at = carve_saved(&owner->warm, base, at);
    at = carve_saved(&owner->warm_next, base, at);
    at = carve_saved(&owner->best, base, at);
    at = carve_saved(&owner->stall, base, at);
    CORE_ARRAYS(CARVE)
    return at;
}

/* every run-time call starts here: the problem and workspace of this call; a workspace whose
 * bytes were copied elsewhere (its pointers still into the old place) is carved again there */
static void enter(const kothare_problem_t *problem, void *work)
{
    rt = problem;
    ws_at = (struct workspace *)work;
    if (ws.home != work) {
        carve(ws_at, (unsigned char *)work);
        ws.home = work;
    }
}

size_t kothare_rt_workspace_bytes(const kothare_problem_t *problem)
{
    struct workspace counting;
    rt = problem;
    return carve(&counting, NULL);
}

void kothare_rt_init(const kothare_problem_t *problem, void *work)
{
    memset(work, 0, kothare_rt_workspace_bytes(problem));
    enter(problem, work);
    layout();
    ws.laid_out = 1;
}

void kothare_rt_reset_warm_start(const kothare_problem_t *problem, void *work)
{
    enter(problem, work);
    ws.has_warm = 0;
}

int kothare_rt_solve(const kothare_problem_t *problem, void *work, const double *xs, const double *bounds,
                     int warm_start, double *x, double *z, double *weights, double info[5])
{
    int i, its = 0, word;
    double pres = HUGE_VAL, dres = HUGE_VAL, gap = HUGE_VAL, radius = 0.0;
    enter(problem, work);
    for (i = 0; i < RMPC_NBOUND; ++i) {
        ws.bound[i] = bounds[i];
    }
    set_data(xs);
    word = solve_data(warm_start, &its, &pres, &dres, &gap, &radius);
    for (i = 0; i < NV; ++i) {
        x[i] = ws.cur.x[i] * ws.dscale[i];
    }
    memcpy(z, ws.cur.z, NBYTES(NB * KK));
    memcpy(weights, ws.bw, NBYTES(NB));
    info[0] = pres;
    info[1] = dres;
    info[2] = gap;
    info[3] = radius;
    info[4] = its;
    return word;
}
#endif /* KOTHARE_RUNTIME */
