/* fuzz_mesh.h: the body shared by the mesh-reader fuzz targets. Each input
 * is parsed twice, as `clvr MESH` does (validated) and as `clvr --info`
 * does for broken files (validation skipped), and the result must keep the
 * readers' contract (host/io/mesh_io.h):
 *   - failure: a status that is an error, the same status in err, a
 *     non-empty one-line message naming the file, and nothing allocated;
 *   - success: arrays for every count (ASan sees any short allocation when
 *     they are read in full), ranges equal to a recomputation, and with
 *     validation: at least one element, every index in range, every value
 *     finite (clvr_mesh_validate agrees), and the warnings scan
 *     (clvr_limits_scan) runs on it.
 * A broken contract aborts, which libFuzzer and the replay report as a
 * crash with the input. */
#ifndef CLVR_FUZZ_MESH_H
#define CLVR_FUZZ_MESH_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "limits_check.h"
#include "mesh_io.h"
#include "fuzz_assert.h"

typedef clvr_status (*fuzz_parse_fn)(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                     clvr_mesh *out, clvr_error *err);

/* Reads every byte of an array so that a short allocation is caught; the
 * sum is returned so the compiler keeps the loop. */
static inline unsigned fuzz_touch(const void *p, uint64_t bytes)
{
    const volatile unsigned char *c = (const volatile unsigned char *)p;
    unsigned s = 0;
    for (uint64_t i = 0; i < bytes; ++i) s += c[i];
    return s;
}

static inline void fuzz_check_mesh(const clvr_mesh *m, int validated, const char *name)
{
    volatile unsigned sink = 0;
    FUZZ_ASSERT(m->num_vertices == 0 || (m->positions && m->scalars), "%llu vertices without arrays",
                (unsigned long long)m->num_vertices);
    sink += fuzz_touch(m->positions, m->num_vertices * 12);
    sink += fuzz_touch(m->scalars, m->num_vertices * 4);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        FUZZ_ASSERT(m->num_cells[t] == 0 || m->indices[t], "%llu %s without an array",
                    (unsigned long long)m->num_cells[t], clvr_cell_type_name(t));
        sink += fuzz_touch(m->indices[t], clvr_mesh_num_indices(m, t) * 4);
    }
    FUZZ_ASSERT(memchr(m->scalar_name, 0, sizeof m->scalar_name) != NULL, "scalar_name not terminated");
    clvr_mesh copy = *m; /* ranges recomputed must match what the reader set */
    clvr_mesh_update_ranges(&copy);
    for (int k = 0; k < 3; ++k)
        FUZZ_ASSERT(memcmp(&copy.bounds_lo[k], &m->bounds_lo[k], 4) == 0 &&
                        memcmp(&copy.bounds_hi[k], &m->bounds_hi[k], 4) == 0,
                    "bounds not set by the reader");
    if (!validated) return;
    clvr_error err = {0};
    clvr_status s = clvr_mesh_validate(m, name, &err);
    FUZZ_ASSERT(s == CLVR_OK, "the reader returned a mesh that fails validation: %s", err.msg);
    FUZZ_ASSERT(clvr_mesh_num_elements(m) > 0, "validated mesh without elements");
    for (int k = 0; k < 3; ++k) FUZZ_ASSERT(m->bounds_lo[k] <= m->bounds_hi[k], "bounds inverted");
    FUZZ_ASSERT(m->scalar_min <= m->scalar_max && isfinite(m->scalar_min) && isfinite(m->scalar_max),
                "scalar range [%g, %g]", (double)m->scalar_min, (double)m->scalar_max);
    clvr_limits_report r;
    clvr_limits_scan(m, &r);
    FUZZ_ASSERT(r.degenerate + r.inverted <= clvr_mesh_num_elements(m), "scan counts");
    FUZZ_ASSERT(r.duplicates < clvr_mesh_num_elements(m), "scan counts");
    clvr_limits_estimate e;
    clvr_limits_estimate_bytes(m, NULL, 64, 64, &e);
    FUZZ_ASSERT(e.peak_bytes >= e.largest_buffer_bytes,
                "estimate: peak %llu < largest buffer %llu", (unsigned long long)e.peak_bytes,
                (unsigned long long)e.largest_buffer_bytes);
    (void)sink;
}

static inline int fuzz_mesh_one(fuzz_parse_fn parse, const uint8_t *data, size_t size, const char *name)
{
    for (int skip = 0; skip < 2; ++skip) {
        clvr_load_options opt = {0};
        clvr_mesh m;
        clvr_error err = {0};
        opt.skip_validation = skip;
        memset(&m, 0xA5, sizeof m); /* the reader must reset it, whatever it held */
        clvr_status s = parse(data, size, name, &opt, &m, &err);
        if (s != CLVR_OK) {
            FUZZ_ASSERT(s > CLVR_OK && s < CLVR_STATUS_COUNT, "status %d", (int)s);
            FUZZ_ASSERT(err.status == s, "err.status %s but returned %s", clvr_status_name(err.status),
                        clvr_status_name(s));
            FUZZ_ASSERT(err.msg[0] != 0, "empty message for %s", clvr_status_name(s));
            FUZZ_ASSERT(strstr(err.msg, name) != NULL, "message does not name the file: %s", err.msg);
            FUZZ_ASSERT(strchr(err.msg, '\n') == NULL, "message is not one line: %s", err.msg);
            FUZZ_ASSERT(m.positions == NULL && m.scalars == NULL && m.indices[0] == NULL && m.indices[1] == NULL &&
                            m.indices[2] == NULL && m.indices[3] == NULL,
                        "failed parse left arrays behind (%s)", err.msg);
            continue;
        }
        fuzz_check_mesh(&m, !skip, name);
        clvr_mesh_free(&m);
    }
    return 0;
}

#endif /* CLVR_FUZZ_MESH_H */
