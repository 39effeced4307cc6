/* bench_preprocess: elements/s of every preprocessing stage on a generated
 * hex grid of about N elements, against a tuned plain-C 2-thread LSD radix
 * sort (pthreads, 8-bit digits, constant digits skipped) and a memcpy of the
 * same key array. Usage:
 *   bench_preprocess [--device SPEC] [--json FILE] [--elements N[,N...]] [--repeat R]
 * Prints the device, driver and a Markdown table per size; --json writes the
 * same numbers. Timings are OpenCL event profiling (device seconds) after a
 * warm-up run; the C baselines take the best of R runs. */
#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "preprocess.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Structured hex grid n^3 with a smooth scalar. */
static int make_hexes(clvr_mesh *m, uint32_t n, clvr_error *err)
{
    uint64_t cells[4] = {0, 0, 0, (uint64_t)n * n * n};
    uint64_t nv = (uint64_t)(n + 1) * (n + 1) * (n + 1);
    if (clvr_mesh_alloc(m, nv, cells, err) != CLVR_OK) return 1;
    for (uint64_t k = 0, v = 0; k <= n; ++k)
        for (uint64_t j = 0; j <= n; ++j)
            for (uint64_t i = 0; i <= n; ++i, ++v) {
                float x = (float)i / n, y = (float)j / n, z = (float)k / n;
                m->positions[3 * v] = x;
                m->positions[3 * v + 1] = y;
                m->positions[3 * v + 2] = z;
                m->scalars[v] = sinf(6 * x) * cosf(4 * y) + z;
            }
    uint32_t *p = m->indices[3];
    const uint64_t s = n + 1;
    for (uint64_t k = 0; k < n; ++k)
        for (uint64_t j = 0; j < n; ++j)
            for (uint64_t i = 0; i < n; ++i) {
                uint64_t b = (k * s + j) * s + i;
                uint32_t h[8] = {(uint32_t)b, (uint32_t)(b + 1), (uint32_t)(b + s + 1), (uint32_t)(b + s),
                                 (uint32_t)(b + s * s), (uint32_t)(b + s * s + 1), (uint32_t)(b + s * s + s + 1),
                                 (uint32_t)(b + s * s + s)};
                memcpy(p, h, sizeof h);
                p += 8;
            }
    clvr_mesh_update_ranges(m);
    return 0;
}

/* ---- plain-C 2-thread LSD radix sort: each thread histograms and scatters
 * its half; offsets are combined so the sort stays stable. */
typedef struct radix_job {
    const uint64_t *ks;
    const uint32_t *vs;
    uint64_t *kd;
    uint32_t *vd;
    uint64_t b, e;
    uint32_t shift;
    uint64_t hist[256];
    uint64_t off[256];
    int phase;
} radix_job;

static void *radix_worker(void *arg)
{
    radix_job *j = arg;
    if (j->phase == 0) {
        memset(j->hist, 0, sizeof j->hist);
        for (uint64_t i = j->b; i < j->e; ++i) ++j->hist[(j->ks[i] >> j->shift) & 255];
    } else {
        uint64_t off[256];
        memcpy(off, j->off, sizeof off);
        for (uint64_t i = j->b; i < j->e; ++i) {
            uint64_t k = j->ks[i];
            uint64_t p = off[(k >> j->shift) & 255]++;
            j->kd[p] = k;
            j->vd[p] = j->vs[i];
        }
    }
    return NULL;
}

static void c_radix2(uint64_t *keys, uint32_t *vals, uint64_t *kt, uint32_t *vt, uint64_t n)
{
    uint64_t a = ~0ull, o = 0;
    for (uint64_t i = 0; i < n; ++i) { a &= keys[i]; o |= keys[i]; }
    uint64_t *ks = keys, *kd = kt;
    uint32_t *vs = vals, *vd = vt;
    radix_job job[2];
    for (uint32_t shift = 0; shift < 64; shift += 8) {
        if ((((a ^ o) >> shift) & 255) == 0) continue;
        pthread_t th;
        for (int t = 0; t < 2; ++t) {
            job[t].ks = ks; job[t].vs = vs; job[t].kd = kd; job[t].vd = vd; job[t].shift = shift;
            job[t].b = n * t / 2; job[t].e = n * (t + 1) / 2; job[t].phase = 0;
        }
        pthread_create(&th, NULL, radix_worker, &job[1]);
        radix_worker(&job[0]);
        pthread_join(th, NULL);
        uint64_t acc = 0;
        for (int d = 0; d < 256; ++d)
            for (int t = 0; t < 2; ++t) { job[t].off[d] = acc; acc += job[t].hist[d]; }
        for (int t = 0; t < 2; ++t) job[t].phase = 1;
        pthread_create(&th, NULL, radix_worker, &job[1]);
        radix_worker(&job[0]);
        pthread_join(th, NULL);
        uint64_t *tk = ks; ks = kd; kd = tk;
        uint32_t *tv = vs; vs = vd; vd = tv;
    }
    if (ks != keys) { memcpy(keys, ks, n * 8); memcpy(vals, vs, n * 4); }
}

int main(int argc, char **argv)
{
    const char *device = NULL, *json = NULL, *sizes = "1000000,10000000";
    int repeat = 3;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--device") && i + 1 < argc) device = argv[++i];
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--elements") && i + 1 < argc) sizes = argv[++i];
        else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_preprocess [--device SPEC] [--json FILE] [--elements N[,N...]] [--repeat R]\n");
            return 2;
        }
    }
    clvr_cl cl;
    clvr_error err = {0};
    if (clvr_cl_create(device, &cl, &err) != CLVR_OK) { fprintf(stderr, "bench_preprocess: %s\n", err.msg); return 4; }
    printf("device: %s (%s), %s, driver %s, %u compute units\n", cl.device_name, cl.platform_name, cl.device_version,
           cl.driver_version, cl.compute_units);
    FILE *jf = json ? fopen(json, "w") : NULL;
    if (jf) fprintf(jf, "{\n  \"device\": \"%s\",\n  \"driver\": \"%s\",\n  \"runs\": [\n", cl.device_name, cl.driver_version);
    int first_run = 1, rc = 0;
    for (const char *p = sizes; *p;) {
        uint64_t want = strtoull(p, (char **)&p, 10);
        if (*p == ',') ++p;
        uint32_t n = (uint32_t)llround(cbrt((double)want));
        if (n < 1) n = 1;
        clvr_mesh m = {0};
        if (make_hexes(&m, n, &err)) { fprintf(stderr, "bench_preprocess: %s\n", err.msg); rc = 1; break; }
        const uint64_t N = clvr_mesh_num_elements(&m);
        clvr_preprocess_options o;
        clvr_preprocess_options_default(&o);
        clvr_clustered c = {0};
        double best_wall = 1e30, stage[CLVR_PP_STAGE_COUNT];
        clvr_clustered keep = {0};
        for (int r = 0; r < repeat + 1; ++r) { /* run 0 warms up (kernel build cache, page faults) */
            if (clvr_preprocess(&cl, &m, &o, &c, &err) != CLVR_OK) { fprintf(stderr, "bench_preprocess: %s\n", err.msg); rc = 1; break; }
            if (r > 0 && c.wall_s - c.build_s < best_wall) {
                best_wall = c.wall_s - c.build_s;
                memcpy(stage, c.stage_s, sizeof stage);
                clvr_clustered_release(&cl, &keep);
                keep = c;
                memset(&c, 0, sizeof c);
            }
            clvr_clustered_release(&cl, &c);
        }
        if (rc) { clvr_mesh_free(&m); break; }
        /* C baselines on the same keys (the host reference computes them bit-identically). */
        clvr_pp_layout L;
        clvr_pp_layout_make(&L, m.num_cells);
        clvr_box b;
        clvr_pp_ref_bounds(m.positions, m.scalars, m.num_vertices, &b);
        uint64_t *keys = malloc(N * 8), *k2 = malloc(N * 8), *kt = malloc(N * 8);
        uint32_t *vals = malloc(N * 4), *v2 = malloc(N * 4), *vt = malloc(N * 4);
        clvr_pp_ref_keys(m.positions, m.indices[3], &L, &b, 0, keys, vals);
        double t_radix = 1e30, t_memcpy = 1e30;
        for (int r = 0; r < repeat; ++r) {
            memcpy(k2, keys, N * 8);
            memcpy(v2, vals, N * 4);
            double t0 = now_s();
            c_radix2(k2, v2, kt, vt, N);
            double t1 = now_s();
            if (t1 - t0 < t_radix) t_radix = t1 - t0;
            t0 = now_s();
            memcpy(kt, keys, N * 8);
            t1 = now_s();
            if (t1 - t0 < t_memcpy) t_memcpy = t1 - t0;
        }
        double hilbert = stage[CLVR_PP_STAGE_KEYS] + stage[CLVR_PP_STAGE_SORT] + stage[CLVR_PP_STAGE_GATHER] +
                         stage[CLVR_PP_STAGE_LEAVES];
        double dev_total = 0;
        for (int s = 0; s < CLVR_PP_STAGE_COUNT; ++s) dev_total += stage[s];
        printf("\n### %" PRIu64 " hex elements (%" PRIu64 " vertices)\n\n| stage | seconds | Melements/s |\n|---|---:|---:|\n",
               N, m.num_vertices);
        for (int s = 0; s < CLVR_PP_STAGE_COUNT; ++s)
            printf("| %s | %.4f | %.1f |\n", clvr_pp_stage_name(s), stage[s], stage[s] > 0 ? N / stage[s] / 1e6 : 0.0);
        printf("| **device total** | %.4f | %.1f |\n", dev_total, N / dev_total / 1e6);
        printf("| **wall (no build)** | %.4f | %.1f |\n", best_wall, N / best_wall / 1e6);
        printf("| Hilbert clustering (keys+sort+gather+leaves) | %.4f | %.1f |\n", hilbert, N / hilbert / 1e6);
        printf("| C radix sort, 2 threads | %.4f | %.1f |\n", t_radix, N / t_radix / 1e6);
        printf("| memcpy of the keys | %.4f | %.1f |\n", t_memcpy, N / t_memcpy / 1e6);
        printf("\nratios: device sort / C radix = %.2f; Hilbert clustering / C radix = %.2f; C radix / memcpy = %.1f\n",
               stage[CLVR_PP_STAGE_SORT] / t_radix, hilbert / t_radix, t_radix / t_memcpy);
        printf("memory: vertices %.1f MB -> %.1f MB, indices %.1f MB -> %.1f MB (%.2f), %" PRIu64 " instances (avg %.0f elements), %" PRIu64 " leaves\n",
               keep.bytes_vertices_before / 1e6, keep.bytes_vertices_after / 1e6, keep.bytes_indices_before / 1e6,
               keep.bytes_indices_after / 1e6, (double)keep.bytes_indices_after / (double)keep.bytes_indices_before,
               keep.num_instances, keep.avg_instance_elements, keep.num_leaves);
        if (jf) {
            fprintf(jf, "%s    {\"elements\": %" PRIu64 ", \"vertices\": %" PRIu64 ", \"stages_s\": {", first_run ? "" : ",\n", N,
                    m.num_vertices);
            for (int s = 0; s < CLVR_PP_STAGE_COUNT; ++s) fprintf(jf, "%s\"%s\": %.6f", s ? ", " : "", clvr_pp_stage_name(s), stage[s]);
            fprintf(jf, "}, \"device_total_s\": %.6f, \"wall_s\": %.6f, \"hilbert_clustering_s\": %.6f, \"c_radix2_s\": %.6f, "
                        "\"memcpy_s\": %.6f, \"bytes_indices_before\": %" PRIu64 ", \"bytes_indices_after\": %" PRIu64 ", "
                        "\"bytes_vertices_before\": %" PRIu64 ", \"bytes_vertices_after\": %" PRIu64 "}",
                    dev_total, best_wall, hilbert, t_radix, t_memcpy, keep.bytes_indices_before, keep.bytes_indices_after,
                    keep.bytes_vertices_before, keep.bytes_vertices_after);
            first_run = 0;
        }
        clvr_clustered_release(&cl, &keep);
        free(keys); free(k2); free(kt); free(vals); free(v2); free(vt);
        clvr_mesh_free(&m);
    }
    if (jf) { fprintf(jf, "\n  ]\n}\n"); fclose(jf); }
    clvr_cl_destroy(&cl);
    return rc;
}
