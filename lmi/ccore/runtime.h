/* The C core's interior-point method with the problem given at run time: the build the Python
 * package calls (lmi.ccore.runtime, compiled by `pip install .` as lmi.ccore._core).
 *
 * ipm.c compiled with -DKOTHARE_RUNTIME includes this header instead of the generated
 * "rmpc_problem.h": the sizes, settings and tables an export fixes as macros and static arrays
 * are read from a kothare_problem_t, and the workspace is the caller's buffer instead of one
 * static struct. The iterations are the same source, so the Python package and an exported
 * controller run one core. Only the interior-point solve is here (the certificate, the
 * balancing of the state and the fallbacks stay in Python, lmi.backends.ipm.IPMKothare).
 *
 * Not reentrant: a call keeps its problem and workspace in two file-scope pointers for its
 * duration (the Python caller holds a lock around every call).
 */
#ifndef LMI_CCORE_RUNTIME_H
#define LMI_CCORE_RUNTIME_H

#include <stddef.h>

/* One problem: the fields of rmpc_problem.h that the interior-point method reads. The
 * coefficient tables are those of lmi.ccore.generate (entries of each block's upper triangle,
 * ordered by block, packed position, variable). Field order is mirrored by
 * lmi.ccore.runtime.Problem (ctypes): change both together. */
typedef struct {
    int nv;            /* variables */
    int nb;            /* blocks */
    int kmax;          /* largest block order */
    int size;          /* entries of a packed vector */
    int nent;          /* non-zero coefficient entries */
    int basis;         /* work entries of the largest block's pair basis */
    int nbound;        /* input and output bounds (at least 1) */
    int degree;        /* sum of the block orders */
    int max_iter;      /* iteration limit of a cold start */
    int warm_max_iter; /* iteration limit of a warm start */
    double tol_feas, tol_gap_abs, tol_gap_rel, warm_gap, warm_feas, inf_radius, qr_switch;
    const int *order, *offset, *copies, *ent_off, *ent_var, *ent_pos, *ent_t, *ent_bound, *pos_off,
        *pos_row, *pos_col;
    const double *cnst, *ent_val, *c;
} kothare_problem_t;

#ifdef KOTHARE_RUNTIME
/* ipm.c reads the problem of the call under way */
#define RMPC_NV (rt->nv)
#define RMPC_NB (rt->nb)
#define RMPC_KMAX (rt->kmax)
#define RMPC_SIZE (rt->size)
#define RMPC_NENT (rt->nent)
#define RMPC_BASIS (rt->basis)
#define RMPC_NBOUND (rt->nbound)
#define RMPC_DEGREE (rt->degree)
#define RMPC_MAX_ITER (rt->max_iter)
#define RMPC_WARM_MAX_ITER (rt->warm_max_iter)
#define RMPC_TOL_FEAS (rt->tol_feas)
#define RMPC_TOL_GAP_ABS (rt->tol_gap_abs)
#define RMPC_TOL_GAP_REL (rt->tol_gap_rel)
#define RMPC_WARM_GAP (rt->warm_gap)
#define RMPC_WARM_FEAS (rt->warm_feas)
#define RMPC_INF_RADIUS (rt->inf_radius)
#define RMPC_QR_SWITCH (rt->qr_switch)
#define rmpc_order (rt->order)
#define rmpc_offset (rt->offset)
#define rmpc_copies (rt->copies)
#define rmpc_ent_off (rt->ent_off)
#define rmpc_ent_var (rt->ent_var)
#define rmpc_ent_pos (rt->ent_pos)
#define rmpc_ent_t (rt->ent_t)
#define rmpc_ent_bound (rt->ent_bound)
#define rmpc_pos_off (rt->pos_off)
#define rmpc_pos_row (rt->pos_row)
#define rmpc_pos_col (rt->pos_col)
#define rmpc_const (rt->cnst)
#define rmpc_ent_val (rt->ent_val)
#define rmpc_c (rt->c)
#endif

/* Bytes of the workspace of problem (a buffer the caller owns, aligned to 16 bytes). */
size_t kothare_rt_workspace_bytes(const kothare_problem_t *problem);

/* Zero the workspace and lay out its arrays: no warm start, the equilibration fixed at the next
 * solve (as a new lmi.ipm.BlockLMISolver). A copy of the workspace's bytes is a copy of its
 * state (the arrays are carved again where the copy lives at its first call). */
void kothare_rt_init(const kothare_problem_t *problem, void *work);

/* Forget the warm-start point (the next solve starts cold). */
void kothare_rt_reset_warm_start(const kothare_problem_t *problem, void *work);

/* lmi.ipm.BlockLMISolver.solve on the data at the normalised state xs (the state block's
 * entries) and the normalised bounds (nbound entries, dividing the bound-scaled coefficients):
 * with warm_start, from the kept warm-start point if there is one, retried cold unless that ends
 * optimal or infeasible. Writes x (nv: the variables, equilibration undone), z (nb * kmax * kmax:
 * the dual blocks as iterated, in the block weights' units), weights (nb: the block weights) and
 * info (relative primal and dual residuals, gap, the Farkas ray's radius, iterations). Returns
 * the solver's word: 0 optimal, 1 infeasible, 2 max_iterations, 3 numerical_error,
 * 4 insufficient_progress, 5 inaccurate. */
int kothare_rt_solve(const kothare_problem_t *problem, void *work, const double *xs, const double *bounds,
                     int warm_start, double *x, double *z, double *weights, double info[5]);

#endif
