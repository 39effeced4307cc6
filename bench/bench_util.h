/* bench_util.h: what every benchmark program needs besides clvr itself: the
 * machine's load (benchmarks run on shared machines and print it beside each
 * figure) and medians of repeated runs. */
#ifndef CLVR_BENCH_UTIL_H
#define CLVR_BENCH_UTIL_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* Threads for the CPU baselines (the C radix sort, Embree): the machine's
 * online cores, 1..64, so that a ceiling uses the whole CPU as PoCL does;
 * CLVR_BENCH_THREADS=N sets another count. */
static inline int bench_cpu_threads(void)
{
    const char *e = getenv("CLVR_BENCH_THREADS");
    const long n = e && atoi(e) > 0 ? atol(e) : sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 64 ? 64 : (int)n;
}

/* 1-minute load average from /proc/loadavg, -1 when unknown. */
static inline double bench_load1(void)
{
    double l = -1.0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1) l = -1.0;
        fclose(f);
    }
    return l;
}

static inline int bench_cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median of n >= 1 values (sorts v in place; the mean of the middle two for
 * even n). */
static inline double bench_median(double *v, uint32_t n)
{
    qsort(v, n, sizeof *v, bench_cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#endif
