/* example.c: a 1 kHz loop over a trajectory, as a controller would run it.
 *
 * Usage: ./csjm_example trajectory.csv > tensions.csv
 * Input CSV (header line, then one row per 1 ms step): t_s,qw,qx,qy,qz,tau_x,tau_y,tau_z
 * Output CSV: t_s,status,t1..tm (N),l1..lm (m),iterations (m = CSJM_N_CABLES cables), and on stderr the worst call time.
 * Each step warm-starts from the previous step's active set; on a real controller the loop
 * body is what runs in the 1 ms cycle (reading the sensors and writing the drives instead of
 * the files). */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>

#include "csjm.h"

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e9 * (double)ts.tv_sec + (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    FILE *in;
    char header[512];
    double t, q[4], tau[3], worst_ns = 0.0;
    csjm_warm_start warm = {{0}, {0}};
    csjm_plan plan;
    long steps = 0, failures = 0;
    int i;
    if (argc != 2) {
        fprintf(stderr, "usage: %s trajectory.csv\n", argv[0]);
        return 2;
    }
    in = fopen(argv[1], "r");
    if (in == NULL) {
        fprintf(stderr, "%s: cannot open %s\n", argv[0], argv[1]);
        return 2;
    }
    if (fgets(header, sizeof header, in) == NULL) {
        fprintf(stderr, "%s: %s is empty\n", argv[0], argv[1]);
        fclose(in);
        return 2;
    }
    printf("t_s,status");
    for (i = 1; i <= CSJM_N_CABLES; ++i) printf(",t%d_N", i);
    for (i = 1; i <= CSJM_N_CABLES; ++i) printf(",l%d_m", i);
    printf(",iterations\n");
    while (fscanf(in, " %lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &t, &q[0], &q[1], &q[2], &q[3], &tau[0], &tau[1],
                  &tau[2]) == 8) {
        double t0 = now_ns(), dt;
        int status = csjm_plan_tensions_q(q, tau, NULL, 0, &warm, &plan);
        dt = now_ns() - t0;
        if (dt > worst_ns) worst_ns = dt;
        ++steps;
        if (status != CSJM_SOLVED) {
            ++failures;
            printf("%.6f,%d", t, status);
            for (i = 0; i < 2 * CSJM_N_CABLES; ++i) printf(",nan");
            printf(",0\n");
            continue;
        }
        printf("%.6f,%d", t, status);
        for (i = 0; i < CSJM_N_CABLES; ++i) printf(",%.17g", plan.tensions_N[i]);
        for (i = 0; i < CSJM_N_CABLES; ++i) printf(",%.17g", plan.rest_lengths_m[i]);
        printf(",%d\n", plan.iterations);
    }
    fclose(in);
    fprintf(stderr, "%ld steps, %ld not solved, slowest plan call %.0f ns\n", steps, failures, worst_ns);
    return failures ? 1 : 0;
}
