/* A small driver of the C core (lmi/ccore): reads states (RMPC_NX numbers a line) from the file
 * given as the first argument, solves at each with kothare_solve, and prints a line per state:
 * status, gamma, iterations, u (RMPC_NU entries, %.17g) and the solve's wall time in ns
 * and its thread CPU time in ns (clock_gettime, CLOCK_MONOTONIC and CLOCK_THREAD_CPUTIME_ID). Used by the sanitizer test and the timing script.
 * Built with -DKOTHARE_PHASE_TIMES, it also prints on stderr, at the end, one line "phases"
 * followed by the seconds and then the counts of every phase of ipm.h (KOTHARE_NPHASES each),
 * summed over the solves after the first (the cold one), in the thread's CPU time. */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>

#include "rmpc_problem.h"
#include "ipm.h"

#ifdef KOTHARE_PHASE_TIMES
double kothare_phase_clock(void)
{
    struct timespec c;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c);
    return (double)c.tv_sec + 1e-9 * (double)c.tv_nsec;
}

/* the phases since the first solve (first_*: their values after it) */
static void print_phases(const double *first_sec, const long *first_count)
{
    double sec[KOTHARE_NPHASES];
    long count[KOTHARE_NPHASES];
    int p;
    kothare_phase_times(sec, count);
    fprintf(stderr, "phases");
    for (p = 0; p < KOTHARE_NPHASES; ++p) {
        fprintf(stderr, " %.9f", sec[p] - first_sec[p]);
    }
    for (p = 0; p < KOTHARE_NPHASES; ++p) {
        fprintf(stderr, " %ld", count[p] - first_count[p]);
    }
    fprintf(stderr, "\n");
}
#endif

int main(int argc, char **argv)
{
    FILE *in;
    double x[RMPC_NX], u[RMPC_NU], gamma;
    int it, i, status, solves = 0;
#ifdef KOTHARE_PHASE_TIMES
    double first_sec[KOTHARE_NPHASES] = {0.0};
    long first_count[KOTHARE_NPHASES] = {0};
#endif
    if (argc < 2) {
        fprintf(stderr, "usage: %s STATES\n", argv[0]);
        return 2;
    }
    in = fopen(argv[1], "r");
    if (in == NULL) {
        fprintf(stderr, "%s: cannot open %s\n", argv[0], argv[1]);
        return 2;
    }
    kothare_reset();
    for (;;) {
        struct timespec t0, t1, c0, c1;
        long ns, cpu;
        for (i = 0; i < RMPC_NX; ++i) {
            if (fscanf(in, "%lf", &x[i]) != 1) {
                fclose(in);
#ifdef KOTHARE_PHASE_TIMES
                print_phases(first_sec, first_count);
#endif
                return 0;
            }
        }
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
        clock_gettime(CLOCK_MONOTONIC, &t0);
        status = kothare_solve(x, u, NULL, &gamma, &it);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
        if (++solves == 1) {
#ifdef KOTHARE_PHASE_TIMES
            kothare_phase_times(first_sec, first_count);
#endif
        }
        ns = (long)(t1.tv_sec - t0.tv_sec) * 1000000000L + (t1.tv_nsec - t0.tv_nsec);
        cpu = (long)(c1.tv_sec - c0.tv_sec) * 1000000000L + (c1.tv_nsec - c0.tv_nsec);
        printf("%d %.17g %d", status, gamma, it);
        for (i = 0; i < RMPC_NU; ++i) {
            printf(" %.17g", u[i]);
        }
        printf(" %ld %ld\n", ns, cpu);
    }
}
