/* clock.h: the two clocks clvr measures with. Whole-run and stage times use
 * the monotonic clock (never the wall calendar, which can jump); benchmarks on
 * shared machines also report process CPU time, which other jobs do not
 * inflate. Kernel times come from OpenCL event profiling instead
 * (clvr_cl_event_seconds). */
#ifndef CLVR_CLOCK_H
#define CLVR_CLOCK_H

/* Seconds on CLOCK_MONOTONIC: differences are elapsed time. */
double clvr_clock_monotonic_s(void);
/* CPU seconds used by this process so far, all threads. */
double clvr_clock_cpu_s(void);

#endif
