/* csjm_host.c: loops over many poses and per-call timing, for the Python bindings, tests and
 * benchmarks on the host. Not needed on the target (it uses POSIX clock_gettime). */
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>

#include "csjm.h"

/* Plan n poses (R: n x 9 row-major, tau: n x 3, t_ref: NULL or n x m), warm-started along the rows
 * when warm != 0, cold otherwise. Outputs: T, l (n x m), distance (n), status, iterations, fallback (n). */
void csjm_host_plan_batch(int n, const double *R, const double *tau, const double *t_ref, int max_iter,
                          int warm, double *T, double *l, double *distance, int *status, int *iterations,
                          int *fallback)
{
    csjm_warm_start ws = {{0}, {0}};
    csjm_plan plan;
    int m, i;
    for (m = 0; m < n; ++m) {
        status[m] = csjm_plan_tensions_R(R + 9 * m, tau + 3 * m, t_ref != NULL ? t_ref + CSJM_N_CABLES * m : NULL, max_iter,
                                         warm ? &ws : NULL, &plan);
        for (i = 0; i < CSJM_N_CABLES; ++i) {
            T[CSJM_N_CABLES * m + i] = status[m] == CSJM_BAD_INPUT ? 0.0 : plan.tensions_N[i];
            l[CSJM_N_CABLES * m + i] = status[m] == CSJM_BAD_INPUT ? 0.0 : plan.rest_lengths_m[i];
        }
        distance[m] = status[m] == CSJM_BAD_INPUT ? 0.0 : plan.distance_Nm;
        iterations[m] = status[m] == CSJM_BAD_INPUT ? 0 : plan.iterations;
        fallback[m] = status[m] == CSJM_BAD_INPUT ? 0 : plan.fallback;
    }
}

/* K for n poses and tensions. */
void csjm_host_stiffness_batch(int n, const double *R, const double *T, double *K, int *status)
{
    int m;
    for (m = 0; m < n; ++m) status[m] = csjm_stiffness_R(R + 9 * m, T + CSJM_N_CABLES * m, K + 9 * m);
}

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e9 * (double)ts.tv_sec + (double)ts.tv_nsec;
}

/* Time each of n plan calls (ns), warm-started along the rows when warm != 0; overhead_ns receives the
 * median-free mean cost of an empty pair of clock readings (subtract it to compare). Returns the number
 * of calls that did not return CSJM_SOLVED. */
int csjm_host_time_plan(int n, const double *R, const double *tau, int max_iter, int warm, double *ns,
                        double *overhead_ns)
{
    csjm_warm_start ws = {{0}, {0}};
    csjm_plan plan;
    double t0, t1, sum = 0.0;
    int m, failed = 0;
    for (m = 0; m < 1000; ++m) {
        t0 = now_ns();
        t1 = now_ns();
        sum += t1 - t0;
    }
    *overhead_ns = sum / 1000.0;
    for (m = 0; m < n; ++m) {
        int s;
        t0 = now_ns();
        s = csjm_plan_tensions_R(R + 9 * m, tau + 3 * m, NULL, max_iter, warm ? &ws : NULL, &plan);
        t1 = now_ns();
        ns[m] = t1 - t0;
        failed += s != CSJM_SOLVED;
    }
    return failed;
}
