/* The on-line Kothare solve in C99 (lmi/ccore): the interior-point method of the Python
 * lmi.ipm.BlockLMISolver for the fixed block structure of one Kothare problem, its per-state data
 * update and the certificate of lmi.certify, in one static workspace (no allocation).
 *
 * The sizes and data come from the generated "rmpc_problem.h" (lmi.ccore.generate), included by
 * ipm.c before anything else: one source serves every size.
 */
#ifndef LMI_CCORE_IPM_H
#define LMI_CCORE_IPM_H

#include <stddef.h>

/* Status codes of kothare_solve (lmi.ccore.generate.STATUS_CODES). */
#define KOTHARE_STATUS_OPTIMAL 0            /* solved and certified: u = F x with the new gain */
#define KOTHARE_STATUS_INFEASIBLE 1         /* proved infeasible (the dual iterate's Farkas ray) */
#define KOTHARE_STATUS_MAX_ITERATIONS 2     /* iteration limit */
#define KOTHARE_STATUS_NUMERICAL_ERROR 3    /* breakdown or stall (insufficient progress) */
#define KOTHARE_STATUS_CERTIFICATE_FAILED 4 /* converged, but an LMI recomputed at the answer fails */
#define KOTHARE_STATUS_NONFINITE_X 5        /* NaN or inf in x (or |x| overflows): nothing solved, u = 0 */
#define KOTHARE_STATUS_INACCURATE 6         /* stalled at reduced accuracy (Python's "inaccurate") */
#define KOTHARE_STATUS_ZERO_STATE 7         /* x = 0: the problem is degenerate, u = 0 */
#define KOTHARE_STATUS_HELD 8               /* rmpc_step near x_ref (hold radius): no solve, u = F_last x */

/* Solve at the state x (RMPC_NX entries). On status 0, u = F x with the new certified gain F
 * (RMPC_NU x RMPC_NX, row-major) and gamma the certified bound; otherwise u = F_last x with the
 * last certified gain (zero before any, and for a non-finite x), F = F_last (or zeros), gamma
 * NaN. u is never NaN or inf (zero if F x overflows). F and gamma may be NULL. Returns the status. */
int kothare_solve(const double *x, double *u, double *F, double *gamma, int *iterations);

/* Forget everything: the warm start, the equilibration (recomputed at the next solve, as a new
 * Python back-end does at its first solve) and the last certified gain. */
void kothare_reset(void);

/* u = F_last x with the last certified gain (zero before any); 1 if there is one, else 0. */
int kothare_apply_gain(const double *x, double *u);

/* Forget only the warm-start point (the next solve starts cold). */
void kothare_reset_warm_start(void);

/* Diagnostics of the last solve: relative primal and dual residuals, the gap, the solver's own
 * word (0 optimal, 1 infeasible, 2 max_iterations, 3 numerical_error, 4 insufficient_progress,
 * 5 inaccurate), the certificate's worst relative margin, the objective gamma_s, the radius of
 * an infeasibility proof, the iterations. */
void kothare_last_info(double info[8]);

/* Bytes of the static workspace. */
size_t kothare_workspace_bytes(void);

/* Phase times of a profiling build (compiled with -DKOTHARE_PHASE_TIMES; the program defines
 * kothare_phase_clock, a clock in seconds, e.g. the thread's CPU time): the seconds spent in, and
 * the number of entries to, each phase below, summed over every solve since the program started.
 * A build without the macro has neither function and no clock calls. */
#define KOTHARE_NPHASES 8
#define KOTHARE_PHASE_SCALING 0     /* NT scaling of every block and P formed (per iteration) */
#define KOTHARE_PHASE_SCHUR 1       /* H = P'P (Cholesky iterations) */
#define KOTHARE_PHASE_CHOLESKY 2    /* Cholesky factor of H and its pivot test */
#define KOTHARE_PHASE_QR 3          /* Householder QR of P (QR iterations) */
#define KOTHARE_PHASE_NEWTON 4      /* the predictor-corrector step, all of it (includes 5 and 6) */
#define KOTHARE_PHASE_SOLVES 5      /* its Newton solves with their refinement (two per step) */
#define KOTHARE_PHASE_STEP_LENGTH 6 /* its step lengths (smallest eigenvalues, two per step) */
#define KOTHARE_PHASE_SOLVE 7       /* kothare_solve, all of it */
#ifdef KOTHARE_PHASE_TIMES
double kothare_phase_clock(void);
void kothare_phase_times(double seconds[KOTHARE_NPHASES], long counts[KOTHARE_NPHASES]);
#endif

#endif
