/* limits_check.c: up-front device-memory estimate and the mesh scan for elements
 * that render but deserve a warning (limits_check.h). Host only; no OpenCL call,
 * so the fuzz targets link it without a device. */
#include "limits_check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "elements.h"

/* Defaults of clvr_preprocess_options_default, repeated so that this module
 * does not need the preprocessing code linked (fuzz targets). */
#define LIMITS_DEFAULT_LEAF 16u
#define LIMITS_DEFAULT_SAMPLING 16u
#define LIMITS_DEFAULT_BITS 16u
/* Bytes per pixel of the renderer's image buffers: float4 accumulator,
 * float4 second moments, float4 controls, the float4 image read, 3 uint ray
 * counters (host/pipeline/render.c). */
#define LIMITS_PIXEL_BYTES (16u + 16u + 16u + 16u + 12u)
/* A BVH over L leaves has about L / 3 nodes (4-wide). */
#define LIMITS_BVH_NODE_BYTES sizeof(clvr_bvh_node)

/* Saturating arithmetic: an estimate that overflows is simply "too much". */
static uint64_t sat_add(uint64_t a, uint64_t b) { return b > UINT64_MAX - a ? UINT64_MAX : a + b; }
static uint64_t sat_mul(uint64_t a, uint64_t b) { return a && b > UINT64_MAX / a ? UINT64_MAX : a * b; }
static uint64_t max_u64(uint64_t a, uint64_t b) { return a > b ? a : b; }

void clvr_limits_estimate_bytes(const clvr_mesh *m, const clvr_preprocess_options *o, uint32_t width,
                                uint32_t height, clvr_limits_estimate *out)
{
    clvr_limits_estimate_parts(m, o, 0, width, height, out);
}

void clvr_limits_estimate_parts(const clvr_mesh *m, const clvr_preprocess_options *o, uint64_t part_elements,
                                uint32_t width, uint32_t height, clvr_limits_estimate *out)
{
    memset(out, 0, sizeof *out);
    uint32_t leaf = o && o->leaf_size ? o->leaf_size : LIMITS_DEFAULT_LEAF;
    uint32_t sampling = o && o->sampling_size ? o->sampling_size : LIMITS_DEFAULT_SAMPLING;
    uint32_t bits = o && o->index_bits ? o->index_bits : LIMITS_DEFAULT_BITS;
    uint64_t N = 0, S = 0, V = m->num_vertices;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        N = sat_add(N, m->num_cells[t]);
        S = sat_add(S, sat_mul(m->num_cells[t], clvr_cell_vertex_count(t)));
    }
    out->num_elements = N;
    out->num_slots = S;
    out->num_vertices = V;
    /* the clustered mesh's slots: 8 per cell on one curve (preprocess.h) */
    const clvr_preprocess_options defaults = {0}; /* one_curve 0: auto, the default */
    const uint64_t SS = clvr_pp_sorted_slots(o ? o : &defaults, m->num_cells);

    /* Preprocessing (host/pipeline/preprocess.c), two moments that are certain:
     * during the sort, positions + scalars (16 V), the element indices (4 S)
     * and two key/value pairs (24 N); during the split, positions, scalars,
     * the input and the gathered index lists (8 S) and the local indices
     * (2 or 4 S). */
    /* Partitioned (partition.h), the preprocessing buffers are one
     * partition's: its share of the elements, slots and (at most) vertices. */
    const uint64_t PN = part_elements && part_elements < N ? part_elements : N;
    const double f = N ? (double)PN / (double)N : 1.0;
    const uint64_t PS = (uint64_t)((double)S * f), PV = (uint64_t)((double)V * f), PSS = (uint64_t)((double)SS * f);
    uint64_t sort_phase = sat_add(sat_add(sat_mul(PV, 16), sat_mul(PS, 4)), sat_mul(PN, 24));
    uint64_t split_phase = sat_add(sat_mul(PV, 16), sat_mul(PSS, bits == 32 ? 12 : 10));
    out->preprocess_peak_bytes = max_u64(sort_phase, split_phase);

    /* Rendering: local indices, leaf boxes, sampling clusters, BVH nodes and
     * the image; the clustered vertices (>= one float4 per referenced
     * vertex) are left out because unreferenced vertices are not copied. */
    uint64_t leaves = N / leaf + (N % leaf != 0);
    uint64_t resident = sat_mul(SS, bits == 32 ? 4 : 2);
    resident = sat_add(resident, sat_mul(leaves, sizeof(clvr_box)));
    resident = sat_add(resident, sat_mul(N / sampling, sizeof(clvr_sampling_cluster)));
    resident = sat_add(resident, sat_mul(leaves / 3, LIMITS_BVH_NODE_BYTES));
    const uint64_t ebox = o && o->no_element_boxes ? 0 : sat_mul(N, 6); /* element boxes (kernels/locate.h) */
    resident = sat_add(resident, ebox);
    /* entry grids (kernels/locate.h): about 2 cells of 8 bytes per leaf of tets (up to 3 with rounding), 8
     * per leaf of the other types (up to 9); the occupancy grid about a bit per element (a byte counted
     * for rounding) */
    const uint64_t NT = m->num_cells[CLVR_CELL_TET], tet_leaves = NT / leaf + (NT % leaf != 0),
                   other_leaves = (N - NT) / leaf + ((N - NT) % leaf != 0);
    resident = sat_add(resident, sat_add(sat_add(sat_mul(tet_leaves, 24), sat_mul(other_leaves, 72)), N));
    uint64_t pixels = (uint64_t)width * height;
    out->image_bytes = sat_mul(pixels, LIMITS_PIXEL_BYTES);
    out->render_bytes = sat_add(resident, out->image_bytes);
    out->peak_bytes = max_u64(out->preprocess_peak_bytes, out->render_bytes);

    /* The largest single buffer, named as clvr_cl_buffer names it. The
     * arrays of instance clusters are split into pieces when the mesh is
     * preprocessed in partitions (host/pipeline/partition.c), so then they
     * are no candidates; their largest total is split_bytes. */
    const int parted = PN < N;
    const uint64_t idx_bytes = sat_mul(SS, bits == 32 ? 4 : 2);
    const char *idx_name = bits == 32 ? "32-bit indices" : "16-bit indices";
    struct { uint64_t bytes; const char *name; int per_partition, split; } cand[] = {
        {sat_mul(PV, 12), "vertex positions", 1, 0},
        {sat_mul(PS, 4), "element indices", 1, 0},
        {sat_mul(PSS, 4), "sorted element indices", 1, 0}, /* more than the input's on one curve */
        {sat_mul(PN, 8), "sort keys", 1, 0},
        /* (not the clustered vertices: unreferenced vertices are not copied,
         * so 16 V is no lower bound) */
        {idx_bytes, idx_name, 1, parted},
        {sat_mul(pixels, 16), "image accumulator", 0, 0},
        {ebox, "element boxes", 1, parted},
        /* never split (docs/large-meshes.md): 1/8 of the indices or less */
        {sat_mul(leaves, sizeof(clvr_box)), "leaf boxes", 0, 0},
        {sat_mul(N / sampling, sizeof(clvr_sampling_cluster)), "sampling clusters", 0, 0},
    };
    out->largest_buffer = out->whole_buffer = cand[0].name;
    for (size_t i = 0; i < sizeof cand / sizeof cand[0]; ++i) {
        if (cand[i].bytes > out->largest_buffer_bytes) {
            out->largest_buffer_bytes = cand[i].bytes;
            out->largest_buffer = cand[i].name;
        }
        if (!cand[i].split && cand[i].bytes > out->whole_buffer_bytes) {
            out->whole_buffer_bytes = cand[i].bytes;
            out->whole_buffer = cand[i].name;
            out->whole_per_partition = cand[i].per_partition;
        }
    }
    if (parted) {
        out->split_bytes = idx_bytes > ebox ? idx_bytes : ebox;
        out->split_array = idx_bytes >= ebox ? idx_name : "element boxes";
    }
}

static double gb(uint64_t b) { return (double)b / 1e9; }

clvr_status clvr_limits_check_named(const clvr_cl *cl, const clvr_mesh *m, const char *what,
                                    const clvr_preprocess_options *o, uint32_t width, uint32_t height,
                                    clvr_error *err)
{
    return clvr_limits_check_parts(cl, m, what, o, 0, width, height, err);
}

clvr_status clvr_limits_check_parts(const clvr_cl *cl, const clvr_mesh *m, const char *what,
                                    const clvr_preprocess_options *o, uint64_t part_elements, uint32_t width,
                                    uint32_t height, clvr_error *err)
{
    clvr_limits_estimate e;
    clvr_limits_estimate_parts(m, o, part_elements, width, height, &e);
    const char *name = what ? what : "mesh";
    int image_is_it = e.whole_buffer && strcmp(e.whole_buffer, "image accumulator") == 0;
    const uint64_t limit = cl->max_alloc_bytes;
    char lowered[96] = "";
    if (cl->device_max_alloc_bytes > limit)
        snprintf(lowered, sizeof lowered, ", lowered from %.3f GB by CLVR_MAX_ALLOC_BYTES",
                 gb(cl->device_max_alloc_bytes));
    if (e.whole_buffer_bytes > limit) {
        char fix[256];
        if (image_is_it)
            snprintf(fix, sizeof fix, "render a smaller --size, or use another --device (clvr --list-devices)");
        else if (e.whole_per_partition) {
            /* Partitions whose largest buffer fits (the arrays of instance
             * clusters are then split into pieces). */
            const uint64_t pn = part_elements && part_elements < e.num_elements ? part_elements : e.num_elements;
            const double per = (double)e.whole_buffer_bytes / (double)(pn ? pn : 1);
            const uint64_t fit = (uint64_t)((double)limit / per);
            const uint64_t parts = fit ? (e.num_elements + fit - 1) / fit : e.num_elements;
            snprintf(fix, sizeof fix, "preprocess in more partitions (--partitions %llu or more), or use a "
                     "smaller (cropped or decimated) mesh or a device with a larger allocation limit (--device, see "
                     "clvr --list-devices)",
                     (unsigned long long)(parts > 1 ? parts : 2));
        } else
            snprintf(fix, sizeof fix, "use a smaller (cropped or decimated) mesh, a larger --leaf-size, or a device "
                     "with a larger allocation limit (--device, see clvr --list-devices)");
        return clvr_error_set(
            err, CLVR_ERR_DEVICE_MEMORY,
            "%s: %llu elements, %llu vertices at %ux%u: the largest buffer (%s) needs %.3f GB but %s allows at most "
            "%.3f GB per buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE%s); %s",
            name, (unsigned long long)e.num_elements, (unsigned long long)e.num_vertices, width, height,
            e.whole_buffer, gb(e.whole_buffer_bytes), cl->device_name, gb(limit), lowered, fix);
    }
    if (e.split_bytes > sat_mul(limit, CLVR_MAX_SPLITS))
        return clvr_error_set(
            err, CLVR_ERR_DEVICE_MEMORY,
            "%s: %llu elements, %llu vertices: the %s take %.3f GB, which needs %llu pieces of at most %.3f GB "
            "(CL_DEVICE_MAX_MEM_ALLOC_SIZE%s) but they are cut into at most %u pieces (CLVR_MAX_SPLITS); use a "
            "smaller (cropped or decimated) mesh or a device with a larger allocation limit (--device, see clvr "
            "--list-devices)",
            name, (unsigned long long)e.num_elements, (unsigned long long)e.num_vertices, e.split_array,
            gb(e.split_bytes), (unsigned long long)((e.split_bytes + limit - 1) / limit), gb(limit), lowered,
            CLVR_MAX_SPLITS);
    if (e.peak_bytes > cl->global_mem_bytes) {
        int render_is_it = e.render_bytes >= e.preprocess_peak_bytes;
        return clvr_error_set(
            err, CLVR_ERR_DEVICE_MEMORY,
            "%s: %llu elements, %llu vertices at %ux%u need at least %.3f GB of device memory (%s: %.3f GB for "
            "preprocessing, %.3f GB while rendering, %.3f GB of it the image) but %s has %.3f GB "
            "(CL_DEVICE_GLOBAL_MEM_SIZE); %s",
            name, (unsigned long long)e.num_elements, (unsigned long long)e.num_vertices, width, height,
            gb(e.peak_bytes), render_is_it ? "rendering is the peak" : "preprocessing is the peak",
            gb(e.preprocess_peak_bytes), gb(e.render_bytes), gb(e.image_bytes), cl->device_name,
            gb(cl->global_mem_bytes),
            render_is_it && e.image_bytes * 2 > e.render_bytes
                ? "render a smaller --size, or use another --device (clvr --list-devices)"
                : "use a smaller (cropped or decimated) mesh, or a device with more memory "
                  "(--device, see clvr --list-devices)");
    }
    return CLVR_OK;
}

clvr_status clvr_limits_check(const clvr_cl *cl, const clvr_mesh *m, const clvr_preprocess_options *o,
                              uint32_t width, uint32_t height, clvr_error *err)
{
    return clvr_limits_check_named(cl, m, NULL, o, width, height, err);
}

/* ------------------------------------------------------------ host memory */

/* The number after `key` in a "Key:   123 kB" file (meminfo, status), in bytes. */
static uint64_t kb_field(const char *path, const char *key)
{
    FILE *f = fopen(path, "r");
    char line[256];
    uint64_t v = 0;
    size_t kl = strlen(key);
    if (!f) return 0;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, kl) && line[kl] == ':') {
            unsigned long long x = 0;
            if (sscanf(line + kl + 1, "%llu", &x) == 1) v = (uint64_t)x * 1024u;
            break;
        }
    fclose(f);
    return v;
}

/* A file holding one number ("max" or missing: UINT64_MAX). */
static uint64_t number_file(const char *path)
{
    FILE *f = fopen(path, "r");
    unsigned long long x = 0;
    uint64_t v = UINT64_MAX;
    if (!f) return v;
    if (fscanf(f, "%llu", &x) == 1) v = (uint64_t)x;
    fclose(f);
    return v;
}

void clvr_mem_rss(uint64_t *current, uint64_t *peak)
{
    if (current) *current = kb_field("/proc/self/status", "VmRSS");
    if (peak) *peak = kb_field("/proc/self/status", "VmHWM");
}

void clvr_mem_limits_read(clvr_mem_limits *out)
{
    memset(out, 0, sizeof *out);
    uint64_t a = kb_field("/proc/meminfo", "MemAvailable");
    out->mem_available = a ? a : UINT64_MAX;
    /* cgroup v2 at the unified mount (the process's own group is what
     * containers mount there); v1's memory controller otherwise. A limit
     * above 2^60 is "none" (v1 writes a huge number for it). */
    uint64_t max = number_file("/sys/fs/cgroup/memory.max"), cur = number_file("/sys/fs/cgroup/memory.current");
    if (max == UINT64_MAX) {
        max = number_file("/sys/fs/cgroup/memory/memory.limit_in_bytes");
        cur = number_file("/sys/fs/cgroup/memory/memory.usage_in_bytes");
    }
    out->cgroup_left = max >= (1ull << 60) ? UINT64_MAX : cur == UINT64_MAX ? max : max > cur ? max - cur : 0;
    struct rlimit rl;
    out->as_left = UINT64_MAX;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        uint64_t used = kb_field("/proc/self/status", "VmSize");
        out->as_left = (uint64_t)rl.rlim_cur > used ? (uint64_t)rl.rlim_cur - used : 0;
    }
    out->limit = out->mem_available;
    out->binding = "available memory (MemAvailable in /proc/meminfo)";
    if (out->cgroup_left < out->limit) {
        out->limit = out->cgroup_left;
        out->binding = "the cgroup's memory limit (memory.max)";
    }
    if (out->as_left < out->limit) {
        out->limit = out->as_left;
        out->binding = "the address-space limit (ulimit -v, RLIMIT_AS)";
    }
}

void clvr_limits_host_estimate(uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                               uint64_t part_elements, uint32_t width, uint32_t height, clvr_host_estimate *out)
{
    const clvr_host_layout lay = {0, CLVR_EBOX_ON};
    clvr_limits_host_estimate_layout(num_vertices, num_cells, part_elements, width, height, &lay, out);
}

void clvr_limits_host_estimate_layout(uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                                      uint64_t part_elements, uint32_t width, uint32_t height,
                                      const clvr_host_layout *lay, clvr_host_estimate *out)
{
    memset(out, 0, sizeof *out);
    uint64_t N = 0, S = 0, V = num_vertices;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        N = sat_add(N, num_cells[t]);
        S = sat_add(S, sat_mul(num_cells[t], clvr_cell_vertex_count(t)));
    }
    /* A mapped .bin is page cache (evictable, counted as available), not
     * the process's memory: only what the run makes counts. */
    out->mesh_bytes = lay->mapped ? 0 : sat_add(sat_mul(V, 16), sat_mul(S, 4));
    /* Clustered vertices (one float4 per vertex and 10% duplicated across
     * instance clusters), 16-bit indices, leaf boxes, sampling clusters and
     * BVH nodes at the default sizes (16 elements per leaf and per sampling
     * cluster: 2 + 4 + ~0.4 bytes per element). Measured, 500M mixed in 120
     * partitions: vertices 1.10 x 16 V, leaves + BVH + sampling 6.67 bytes
     * per element, 15.84 GB in all against 15.99 estimated (6 bytes and
     * 16 V, the earlier figures, gave 14.95). */
    const clvr_preprocess_options defaults = {0}; /* the clustered indices at the default (auto) one curve */
    const uint64_t SS = clvr_pp_sorted_slots(&defaults, num_cells);
    out->result_bytes = sat_add(sat_add(sat_mul(V, 16) / 10 * 11, sat_mul(SS, 2)), sat_mul(N, 7));
    /* and the point-location element boxes, CLVR_EBOX_BYTES (6) per element */
    if (lay->element_boxes != CLVR_EBOX_OFF) out->result_bytes = sat_add(out->result_bytes, sat_mul(N, 6));
    /* One partition's preprocessing: its share of the mesh as a sub-mesh,
     * the sort (24 bytes per element) and the split's lists (8 per slot),
     * its result before the append. */
    uint64_t pe = part_elements && part_elements < N ? part_elements : N;
    double f = N ? (double)pe / (double)N : 0.0;
    double scratch = f * (double)(sat_mul(V, 16) + sat_mul(S, 4)) * 2.0 + (double)pe * 24.0 + f * (double)SS * 8.0;
    /* Partitioned runs also keep 2 bytes per element (the plan) and a vertex
     * map; a mapped mesh's order list (4 per element) is freed as the
     * partitions are gathered, so it counts against the result below. */
    if (pe < N) scratch += (lay->mapped ? 0.0 : 2.0 * (double)N) + 4.0 * (double)V;
    out->scratch_bytes = scratch >= 1.8e19 ? UINT64_MAX : (uint64_t)scratch;
    out->image_bytes = sat_mul((uint64_t)width * height, LIMITS_PIXEL_BYTES + 16u);
    /* In partitions the mesh is consumed as the result grows (partition.h):
     * the vertices stay, the element lists go as the result comes, so the
     * peak is the larger of the input and vertices + result (100M mixed:
     * 4.89 GB measured against 3.7 + 3.5 GB side by side). In one piece
     * both are alive at the end of preprocessing. */
    uint64_t held = pe < N ? max_u64(out->mesh_bytes, sat_add(sat_mul(V, 16), out->result_bytes))
                           : sat_add(out->mesh_bytes, out->result_bytes);
    /* Mapped: the input's vertices are the file's too; the plan and the
     * order list (6 per element) at the start, the result at the end. */
    if (lay->mapped) held = pe < N ? max_u64(sat_mul(N, 6), out->result_bytes) : out->result_bytes;
    out->total_bytes = sat_add(held, sat_add(out->scratch_bytes, out->image_bytes));
}

static clvr_status check_host_layout(const char *what, uint64_t num_vertices,
                                    const uint64_t num_cells[CLVR_CELL_TYPE_COUNT], uint64_t part_elements,
                                    uint32_t width, uint32_t height, int mesh_loaded, const clvr_host_layout *lay,
                                    const clvr_mem_limits *l, clvr_error *err)
{
    clvr_host_estimate e;
    clvr_limits_host_estimate_layout(num_vertices, num_cells, part_elements, width, height, lay, &e);
    /* A loaded mesh is in use already: only what comes on top of it is needed. */
    uint64_t need = mesh_loaded ? (e.total_bytes > e.mesh_bytes ? e.total_bytes - e.mesh_bytes : 0) : e.total_bytes;
    const int as_binds = l->limit == l->as_left && l->as_left != UINT64_MAX;
    if (as_binds) need = sat_add(need, CLVR_LIMITS_DRIVER_VM_BYTES);
    /* A mapping is address space all the same (VmSize has it once loaded). */
    if (as_binds && lay->mapped && !mesh_loaded) {
        uint64_t S = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) S = sat_add(S, sat_mul(num_cells[t], clvr_cell_vertex_count(t)));
        need = sat_add(need, sat_add(sat_mul(num_vertices, 16), sat_mul(S, 4)));
    }
    /* The estimate is only about right (300M mixed: 3% above it) and the
     * system needs room too: at most 90% of memory; the address space is
     * exact. A sparse 500M-element .bin piled on one vertex that passed the
     * bare limit by 1% ended in the OOM killer at 23.5 GB. */
    const uint64_t allowed = as_binds ? l->limit : l->limit / 10 * 9;
    if (need <= allowed) return CLVR_OK;
    uint64_t N = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) N = sat_add(N, num_cells[t]);
    return clvr_error_set(
        err, CLVR_ERR_NO_MEMORY,
        "%s: %llu elements, %llu vertices need about %.2f GB of memory (mesh %.2f GB%s, clustered result %.2f GB%s, "
        "preprocessing scratch %.2f GB, image %.2f GB%s) but %s leaves %.2f GB (%.2f GB usable); refusing before "
        "%s. %s",
        what ? what : "mesh", (unsigned long long)N, (unsigned long long)num_vertices, gb(need), gb(e.mesh_bytes),
        mesh_loaded ? ", loaded already" : "", gb(e.result_bytes),
        e.total_bytes < sat_add(sat_add(e.mesh_bytes, e.result_bytes), sat_add(e.scratch_bytes, e.image_bytes))
            ? " growing as the mesh is consumed"
            : "",
        gb(e.scratch_bytes), gb(e.image_bytes),
        as_binds ? ", driver address space 1.07 GB" : "", l->binding, gb(l->limit), gb(allowed),
        mesh_loaded ? "preprocessing starts" : "the mesh is read",
        as_binds ? "Raise the limit (ulimit -v), or render a smaller (cropped or decimated) mesh"
                 : "Free memory or raise the limit, use a machine with more memory, or render a smaller (cropped or "
                   "decimated) mesh; more --partitions only shrink the scratch part");
}

clvr_status clvr_limits_check_host(const char *what, uint64_t num_vertices,
                                   const uint64_t num_cells[CLVR_CELL_TYPE_COUNT], uint64_t part_elements,
                                   uint32_t width, uint32_t height, int mesh_loaded, const clvr_mem_limits *l,
                                   clvr_error *err)
{
    const clvr_host_layout lay = {0, CLVR_EBOX_ON};
    return check_host_layout(what, num_vertices, num_cells, part_elements, width, height, mesh_loaded, &lay, l, err);
}

clvr_status clvr_limits_check_host_boxes(const char *what, uint64_t num_vertices,
                                         const uint64_t num_cells[CLVR_CELL_TYPE_COUNT], uint64_t part_elements,
                                         uint32_t width, uint32_t height, int mesh_loaded, int mapped,
                                         int *element_boxes, const clvr_mem_limits *l, FILE *notice,
                                         clvr_error *err)
{
    clvr_host_layout on = {mapped, CLVR_EBOX_ON}, off = {mapped, CLVR_EBOX_OFF};
    const int mode = *element_boxes;
    clvr_error e_on = {0};
    clvr_status s = CLVR_OK;
    if (mode != CLVR_EBOX_OFF) {
        s = check_host_layout(what, num_vertices, num_cells, part_elements, width, height, mesh_loaded, &on, l, &e_on);
        if (s == CLVR_OK) {
            *element_boxes = CLVR_EBOX_ON;
            return CLVR_OK;
        }
    }
    s = check_host_layout(what, num_vertices, num_cells, part_elements, width, height, mesh_loaded, &off, l, err);
    if (mode == CLVR_EBOX_OFF) return s;
    uint64_t N = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) N = sat_add(N, num_cells[t]);
    if (s != CLVR_OK) return s; /* even without the boxes: that need is the smallest */
    if (mode == CLVR_EBOX_ON) { /* asked for: refuse, and say what would fit */
        if (err) {
            char why[sizeof err->msg];
            memcpy(why, e_on.msg, sizeof why);
            clvr_error_set(err, e_on.status, "%s. Without the element boxes (%.2f GB) it fits: --element-boxes off", why,
                           gb(sat_mul(N, 6)));
        }
        return e_on.status;
    }
    *element_boxes = CLVR_EBOX_OFF;
    if (notice)
        fprintf(notice,
                "clvr: %s: the mesh fits in memory only without the element boxes (%.2f GB, 6 bytes per element); "
                "rendering without them (slower point location, same image; --element-boxes)\n",
                what ? what : "mesh", gb(sat_mul(N, 6)));
    return CLVR_OK;
}

/* ------------------------------------------------------------ mesh scan */

/* Parametric centre of each type (pyramid: below the singular apex). */
static const float k_centre[CLVR_CELL_TYPE_COUNT][3] = {
    {0.25f, 0.25f, 0.25f}, {0.5f, 0.5f, 0.25f}, {1.0f / 3.0f, 1.0f / 3.0f, 0.5f}, {0.5f, 0.5f, 0.5f}};

/* Sign of the isoparametric map's Jacobian at the centre for an element in
 * VTK's own vertex order: VTK orders tets, pyramids and hexes so that the
 * base's right-hand normal points into the element (positive here) but
 * wedges so that the normal of (0, 1, 2) points away from (3, 4, 5)
 * (vtkWedge's documentation), which makes the Jacobian of this map
 * negative. Checked on VTK's own files (tests/data). */
static const int k_vtk_sign[CLVR_CELL_TYPE_COUNT] = {1, 1, -1, 1};

/* 1: degenerate, 2: inverted, 0: fine. The determinant is compared with
 * the product of the columns' sizes, as clvr_solve3 does, so an element is
 * "degenerate" exactly when it is too flat for the renderer to locate
 * points in it (in double precision, with float's resolution). */
static int classify(uint32_t t, const float *pos, const uint32_t *idx)
{
    float N[CLVR_CELL_MAX_VERTS], Nu[CLVR_CELL_MAX_VERTS], Nv[CLVR_CELL_MAX_VERTS], Nw[CLVR_CELL_MAX_VERTS];
    clvr_element_shape(t, k_centre[t][0], k_centre[t][1], k_centre[t][2], N, Nu, Nv, Nw);
    const uint32_t nv = clvr_cell_vertex_count(t);
    const float *p0 = pos + 3 * (uint64_t)idx[0];
    double J[3][3] = {{0}};
    for (uint32_t i = 1; i < nv; ++i) {
        const float *p = pos + 3 * (uint64_t)idx[i];
        for (int k = 0; k < 3; ++k) {
            double d = (double)p[k] - (double)p0[k];
            J[0][k] += Nu[i] * d;
            J[1][k] += Nv[i] * d;
            J[2][k] += Nw[i] * d;
        }
    }
    double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                 J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
    double scale = 1.0;
    for (int r = 0; r < 3; ++r) scale *= fabs(J[r][0]) + fabs(J[r][1]) + fabs(J[r][2]);
    if (!(fabs(det) > 1e-7 * scale)) return 1;
    return det * k_vtk_sign[t] < 0.0 ? 2 : 0;
}

static void sorted_key(const uint32_t *idx, uint32_t nv, uint32_t *key)
{
    memcpy(key, idx, nv * sizeof *key);
    for (uint32_t i = 1; i < nv; ++i) /* insertion sort of at most 8 */
        for (uint32_t j = i; j > 0 && key[j - 1] > key[j]; --j) {
            uint32_t tmp = key[j];
            key[j] = key[j - 1];
            key[j - 1] = tmp;
        }
}

/* Hash of an element's vertex set, independent of the vertices' order: a
 * sum of strongly mixed ids (splitmix64's finalizer), so no sort and no
 * data-dependent branch per element; equal hashes are confirmed by
 * comparing the sorted vertex lists. */
static uint64_t mix64(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/* Type of global element id g (ids count the four type lists in order). */
static uint32_t type_of(uint64_t g, const uint64_t first[CLVR_CELL_TYPE_COUNT])
{
    return (uint32_t)(g >= first[1]) + (uint32_t)(g >= first[2]) + (uint32_t)(g >= first[3]);
}

static uint64_t element_hash(const clvr_mesh *m, uint32_t t, uint64_t e)
{
    const uint32_t nv = clvr_cell_vertex_count(t);
    const uint32_t *ix = m->indices[t] + e * nv;
    uint64_t h = 0;
    for (uint32_t i = 0; i < nv; ++i) h += mix64(ix[i]);
    return mix64(h ^ t);
}

/* Duplicates by vertex set, as a cache-conscious hash join: the elements'
 * (hash, id) pairs are first partitioned by the hash's top bits (a
 * streaming pass with 256 output runs, in id order), then each partition
 * gets an open-addressing table small enough for the cache. One table over
 * all elements (128 MB at 10M) took a cache miss per element and 1.5 s of
 * the 2.1 s scan of a 10M-hex mesh. Key vectors are compared only when the
 * 64-bit hashes match. Within a partition elements come in id order, so
 * the table keeps the earliest of equal elements and every later one
 * counts as a duplicate of it, as a single pass in id order would. */
/* Mapped index lists (clvr_mesh.map_base): each pass below gives the pages
 * of the last SCAN_BLOCK elements back behind it, so scanning a mesh does
 * not make its file resident. Called with e the element just scanned. */
#define SCAN_BLOCK ((uint64_t)1 << 20)
static void scan_release(const clvr_mesh *m, uint32_t t, uint64_t e)
{
    /* All of the mapping: the elements' vertices (read at random) too. */
    if (m->map_base && ((e + 1) % SCAN_BLOCK == 0 || e + 1 == m->num_cells[t])) clvr_mesh_release_all_pages(m);
}

/* Bytes of (hash, id) pairs the duplicate scan holds at once: the hash
 * partitions are processed in groups of about this size (one pass over the
 * elements per group), so a 788M-element mesh does not need 9.5 GB of
 * scratch beside itself (issue #15: the scan was the peak of a 100M run). */
#define LIMITS_SCAN_BUDGET ((uint64_t)256 << 20)

static void scan_duplicates(const clvr_mesh *m, uint64_t budget, clvr_limits_report *r)
{
    uint64_t n = clvr_mesh_num_elements(m), first[CLVR_CELL_TYPE_COUNT], acc = 0;
    if (n >= 0x7fffffffull) return; /* ids are 32-bit with room for the doubling below */
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        first[t] = acc;
        acc += m->num_cells[t];
    }
    /* Partitions of about 32k elements (a 64k-slot table of 4 bytes per
     * partition), at most 1024. */
    uint32_t pbits = 0;
    while (pbits < 10 && (n >> pbits) > 32768) ++pbits;
    const uint32_t np = 1u << pbits;
    uint64_t *start = calloc(np + 1, sizeof *start), *fill = malloc(np * sizeof *fill);
    uint64_t *hs = NULL;
    uint32_t *ids = NULL, *table = NULL;
    if (!start || !fill) goto done;
    uint32_t key[CLVR_CELL_MAX_VERTS], other[CLVR_CELL_MAX_VERTS];
    /* Pass 1: partition sizes. */
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        for (uint64_t e = 0; e < m->num_cells[t]; ++e) {
            uint64_t h = element_hash(m, t, e);
            ++start[pbits ? (h >> (64 - pbits)) + 1 : 1];
            scan_release(m, t, e);
        }
    uint64_t maxp = 0;
    for (uint32_t p = 0; p < np; ++p) {
        if (start[p + 1] > maxp) maxp = start[p + 1];
        start[p + 1] += start[p];
    }
    /* Groups of consecutive partitions of at most the budget (at least one partition each). */
    const uint64_t per_group = budget / 12u > maxp ? budget / 12u : maxp;
    hs = malloc((n < per_group ? (n ? n : 1) : per_group) * sizeof *hs);
    ids = malloc((n < per_group ? (n ? n : 1) : per_group) * sizeof *ids);
    uint64_t cap = 16;
    while (cap < 2 * maxp) cap <<= 1;
    table = malloc(cap * sizeof *table);
    if (!hs || !ids || !table) goto done;
    r->duplicates_checked = 1;
    uint64_t best = UINT64_MAX; /* global id of the first duplicate */
    for (uint32_t g0 = 0; g0 < np;) {
        uint32_t g1 = g0 + 1;
        while (g1 < np && start[g1 + 1] - start[g0] <= per_group) ++g1;
        const uint64_t base = start[g0];
        /* Pass 2 for this group: scatter (hash, id) in id order. */
        memcpy(fill, start, np * sizeof *fill);
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
            for (uint64_t e = 0; e < m->num_cells[t]; ++e) {
                uint64_t h = element_hash(m, t, e);
                uint32_t p = pbits ? (uint32_t)(h >> (64 - pbits)) : 0;
                scan_release(m, t, e);
                if (p < g0 || p >= g1) continue;
                uint64_t at = fill[p]++ - base;
                hs[at] = h;
                ids[at] = (uint32_t)(first[t] + e);
            }
        for (uint32_t p = g0; p < g1; ++p) {
            const uint64_t b = start[p] - base, e = start[p + 1] - base;
            uint64_t c = 16;
            while (c < 2 * (e - b)) c <<= 1;
            memset(table, 0, c * sizeof *table);
            for (uint64_t i = b; i < e; ++i) {
                const uint64_t h = hs[i];
                const uint32_t t = type_of(ids[i], first);
                int have_key = 0;
                for (uint64_t sl = h & (c - 1);; sl = (sl + 1) & (c - 1)) {
                    const uint32_t slot = table[sl];
                    if (slot == 0) {
                        table[sl] = (uint32_t)(i - b + 1);
                        break;
                    }
                    const uint64_t j = b + slot - 1;
                    if (hs[j] != h || type_of(ids[j], first) != t) continue;
                    const uint32_t nv = clvr_cell_vertex_count(t);
                    if (!have_key) {
                        sorted_key(m->indices[t] + (ids[i] - first[t]) * nv, nv, key);
                        have_key = 1;
                    }
                    sorted_key(m->indices[t] + (ids[j] - first[t]) * nv, nv, other);
                    if (memcmp(key, other, nv * sizeof *key) == 0) {
                        ++r->duplicates;
                        if (ids[i] < best) {
                            best = ids[i];
                            r->first_duplicate_type = t;
                            r->first_duplicate = ids[i] - first[t];
                            r->duplicate_of = ids[j] - first[t];
                        }
                        break;
                    }
                }
            }
        }
        g0 = g1;
    }
done:
    free(hs);
    free(ids);
    free(start);
    free(fill);
    free(table);
}

void clvr_limits_scan(const clvr_mesh *m, clvr_limits_report *out)
{
    /* Each group is a pass over every element (500M mixed: 24 passes of
     * 256 MB, minutes on 2 cores). The scan runs before preprocessing and
     * frees its scratch, so up to a quarter of the available memory (at
     * most 3 GB: under the result of any mesh that needs more than one
     * group of it) costs no peak: 500M elements in 2 passes. */
    clvr_mem_limits l;
    clvr_mem_limits_read(&l);
    uint64_t budget = l.limit / 4;
    budget = budget > ((uint64_t)3 << 30) ? (uint64_t)3 << 30 : budget;
    clvr_limits_scan_budget(m, budget > LIMITS_SCAN_BUDGET ? budget : LIMITS_SCAN_BUDGET, out);
}

void clvr_limits_scan_budget(const clvr_mesh *m, uint64_t scan_bytes, clvr_limits_report *out)
{
    memset(out, 0, sizeof *out);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        for (uint64_t e = 0; e < m->num_cells[t]; ++e) {
            int c = classify(t, m->positions, m->indices[t] + e * nv);
            if (c == 1 && out->degenerate++ == 0) {
                out->first_degenerate_type = t;
                out->first_degenerate = e;
            } else if (c == 2 && out->inverted++ == 0) {
                out->first_inverted_type = t;
                out->first_inverted = e;
            }
            scan_release(m, t, e);
        }
    }
    scan_duplicates(m, scan_bytes, out);
    if (m->num_vertices > 0 && m->scalar_min == m->scalar_max) {
        out->constant_scalar = 1;
        out->constant_value = m->scalar_min;
    }
    /* Unreferenced vertices: a bitmap, skipped when it cannot be had. */
    uint8_t *used = calloc((size_t)(m->num_vertices / 8 + 1), 1);
    if (used) {
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            uint64_t ni = clvr_mesh_num_indices(m, t);
            const uint32_t vpe = clvr_cell_vertex_count(t);
            for (uint64_t j = 0; j < ni; ++j) {
                used[m->indices[t][j] >> 3] |= (uint8_t)(1u << (m->indices[t][j] & 7));
                if ((j + 1) % vpe == 0) scan_release(m, t, j / vpe);
            }
        }
        for (uint64_t v = 0; v < m->num_vertices; ++v) out->unused_vertices += !(used[v >> 3] >> (v & 7) & 1);
        free(used);
    }
}

int clvr_limits_print_warnings(FILE *out, const char *what, const clvr_limits_report *r)
{
    int n = 0;
    const char *name = what ? what : "mesh";
    if (r->degenerate) {
        fprintf(out,
                "clvr: warning: %s: %llu degenerate element%s (zero volume), the first is %s[%llu]; "
                "they contain no point and are skipped when rendering\n",
                name, (unsigned long long)r->degenerate, r->degenerate == 1 ? "" : "s",
                clvr_cell_type_name(r->first_degenerate_type), (unsigned long long)r->first_degenerate);
        ++n;
    }
    if (r->inverted) {
        fprintf(out,
                "clvr: warning: %s: %llu inverted element%s (vertex order mirrored against VTK's), the first is "
                "%s[%llu]; they render correctly (containment does not depend on orientation) but other tools "
                "may reject them\n",
                name, (unsigned long long)r->inverted, r->inverted == 1 ? "" : "s",
                clvr_cell_type_name(r->first_inverted_type), (unsigned long long)r->first_inverted);
        ++n;
    }
    if (r->duplicates) {
        fprintf(out,
                "clvr: warning: %s: %llu duplicate element%s, the first is %s[%llu] (the same vertices as %s[%llu]); "
                "overlapping copies render once (the first one found)\n",
                name, (unsigned long long)r->duplicates, r->duplicates == 1 ? "" : "s",
                clvr_cell_type_name(r->first_duplicate_type), (unsigned long long)r->first_duplicate,
                clvr_cell_type_name(r->first_duplicate_type), (unsigned long long)r->duplicate_of);
        ++n;
    }
    if (r->constant_scalar) {
        fprintf(out,
                "clvr: warning: %s: the scalar field is constant (%g at every vertex); the transfer-function "
                "window is widened around it (choose one with --range LO HI)\n",
                name, (double)r->constant_value);
        ++n;
    }
    return n;
}
