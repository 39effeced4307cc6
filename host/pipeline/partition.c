/* partition.c: partitioned preprocessing along the Hilbert curve
 * (partition.h). Host-side plan and sub-mesh gathers; each partition is
 * clustered by clvr_preprocess and appended to page-aligned host arrays
 * that become the result's buffers. */
#define _GNU_SOURCE /* mremap */
#include "partition.h"

#include <math.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "bounds.h"
#include "clock.h"
#include "preprocess_stages.h"

/* ------------------------------------------------------------ coarse keys */

/* Coarse key (top CLVR_PARTITION_KEY_BITS of the 48-bit curve key) of
 * element e of type t: the same key clvr_pp_keys computes, so partitions
 * are contiguous pieces of the curve the sort orders each partition by. */
static uint32_t coarse_key(const clvr_mesh *m, uint32_t t, uint64_t e, const clvr_box *b, float scale, int morton)
{
    const uint32_t vpe = clvr_cell_vertex_count(t);
    float lo[3], hi[3];
    clvr_pp_element_box(m->positions, m->indices[t] + e * vpe, vpe, lo, hi);
    const uint64_t key = clvr_pp_element_key(t, lo, hi, b->lo, scale, morton) & ((1ull << 48) - 1);
    return (uint32_t)(key >> (48u - CLVR_PARTITION_KEY_BITS));
}

/* Elements per step of the key pass between page releases of a mapped
 * mesh (16 to 32 MB of indices). */
#define KEY_BLOCK ((uint64_t)1 << 20)

/* One thread's share of a pass over all elements (mesh order). */
typedef struct key_job {
    const clvr_mesh *m;
    const clvr_partition_plan *plan;
    const uint32_t *bin_part;  /* pass 2: (first) partition of each bin */
    const uint32_t *bin_split; /* pass 2: partitions a bin is split into (a bin above max_elements) */
    uint32_t *rank;            /* pass 2: this thread's next rank inside each bin */
    uint64_t max_elements;
    int morton;
    uint64_t begin, end;       /* global element ids */
    uint32_t *hist;            /* pass 1: 2^KEY_BITS counts (this thread's own) */
    uint64_t (*counts)[CLVR_CELL_TYPE_COUNT]; /* pass 2: per partition and type (this thread's own) */
} key_job;

static void *key_pass(void *arg)
{
    key_job *j = arg;
    const clvr_mesh *m = j->m;
    const float scale = clvr_pp_scale(&j->plan->box);
    uint16_t *part = j->plan->part_of16;
    uint64_t first = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint64_t n = m->num_cells[t];
        if (j->end <= first) break;
        const uint64_t b = j->begin > first ? j->begin - first : 0, e = j->end - first < n ? j->end - first : n;
        if (j->hist) /* pass 1: the element's coarse key, kept in its partition slot */
            for (uint64_t b0 = b; b0 < e; b0 += KEY_BLOCK) {
                const uint64_t b1 = e - b0 < KEY_BLOCK ? e : b0 + KEY_BLOCK;
                for (uint64_t i = b0; i < b1; ++i) {
                    const uint32_t k = coarse_key(m, t, i, &j->plan->box, scale, j->morton);
                    part[first + i] = (uint16_t)k;
                    ++j->hist[k];
                }
                /* A mapped mesh: its pages back to the page cache behind
                 * the pass (the vertices, read at random, too). */
                clvr_mesh_release_all_pages(m);
            }
        else /* pass 2: coarse key -> partition, in place */
            for (uint64_t i = b; i < e; ++i) {
                const uint32_t bin = part[first + i];
                uint32_t q = j->bin_part[bin];
                /* A bin too big for one partition (elements piled into one
                 * spot of the grid): its elements in mesh order, max_elements
                 * per partition; the ranks continue across threads. */
                if (j->bin_split[bin] > 1) q += (uint32_t)(j->rank[bin]++ / j->max_elements);
                part[first + i] = (uint16_t)q;
                ++j->counts[q][t];
            }
        first += n;
    }
    return NULL;
}

/* Runs key_pass over all n elements on nt <= 8 threads: jobs[i] (hist or
 * counts already its own) gets the i-th share. A thread that cannot be
 * started has its share done here. */
static void run_key_pass(key_job *jobs, uint32_t nt, uint64_t n)
{
    pthread_t th[8];
    int started[8] = {0};
    for (uint32_t i = 0; i < nt; ++i) {
        jobs[i].begin = n * i / nt;
        jobs[i].end = n * (i + 1) / nt;
    }
    for (uint32_t i = 1; i < nt; ++i) started[i] = pthread_create(&th[i], NULL, key_pass, &jobs[i]) == 0;
    key_pass(&jobs[0]);
    for (uint32_t i = 1; i < nt; ++i) {
        if (started[i]) pthread_join(th[i], NULL);
        else key_pass(&jobs[i]);
    }
}

static uint32_t host_threads(void)
{
    long c = sysconf(_SC_NPROCESSORS_ONLN);
    return c < 1 ? 1u : c > 8 ? 8u : (uint32_t)c;
}

/* ------------------------------------------------------------ plan */

void clvr_partition_plan_free(clvr_partition_plan *p)
{
    if (!p) return;
    free(p->parts);
    free(p->part_of16);
    if (p->order) munmap(p->order, (size_t)p->order_bytes);
    memset(p, 0, sizeof *p);
}

uint32_t clvr_partition_of(const clvr_partition_plan *p, uint64_t g)
{
    return p->part_of16[g];
}

/* qbox: the quantization box of the coarse keys and of every partition's
 * curve (NULL: the mesh's bounds), so that several meshes (MPI ranks'
 * shares) can be pieces of one curve. */
static clvr_status plan_make(const clvr_mesh *m, uint32_t count, uint64_t max_elements, int morton,
                             const clvr_box *qbox, clvr_partition_plan *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const double t0 = clvr_clock_monotonic_s();
    const uint32_t nbins = 1u << CLVR_PARTITION_KEY_BITS;
    uint32_t nt = host_threads();
    uint32_t *hist = NULL, *bin_part = NULL, *bin_split = NULL, *tot = NULL;
    uint64_t(*counts)[CLVR_CELL_TYPE_COUNT] = NULL;
    key_job jobs[8], proto;
    memset(out, 0, sizeof *out);
    const uint64_t N = clvr_mesh_num_elements(m);
    if (N == 0) return clvr_error_set(err, CLVR_ERR_EMPTY, "partition: the mesh has no elements");
    if (N > 0xffffffffull)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "partition: %llu elements; at most 2^32 - 1 are addressable",
                              (unsigned long long)N);
    if (count > 65535u)
        return clvr_error_set(err, CLVR_ERR_USAGE, "partition: %u partitions asked for; at most 65535", count);
    if (max_elements == 0) max_elements = CLVR_PARTITION_DEFAULT_ELEMENTS;
    out->num_elements = N;
    for (int k = 0; k < 3; ++k) {
        out->box.lo[k] = qbox ? qbox->lo[k] : m->bounds_lo[k];
        out->box.hi[k] = qbox ? qbox->hi[k] : m->bounds_hi[k];
    }

    /* Pass 1: histogram of the coarse keys, one table per thread. */
    hist = calloc((size_t)nbins * nt, sizeof *hist);
    bin_part = malloc((size_t)nbins * sizeof *bin_part);
    bin_split = malloc((size_t)nbins * sizeof *bin_split);
    tot = calloc(nbins, sizeof *tot);
    out->part_of16 = malloc(N * sizeof *out->part_of16);
    if (!hist || !bin_part || !bin_split || !tot || !out->part_of16) goto oom;
    memset(&proto, 0, sizeof proto);
    proto.m = m;
    proto.plan = out;
    proto.morton = morton;
    {
        for (uint32_t i = 0; i < nt; ++i) {
            jobs[i] = proto;
            jobs[i].hist = hist + (size_t)nbins * i;
        }
        run_key_pass(jobs, nt, N);
        /* Totals, and each thread's histogram turned into its first rank
         * inside every bin (the counts of the threads before it). */
        for (uint32_t i = 0; i < nt; ++i)
            for (uint32_t b = 0; b < nbins; ++b) {
                const uint32_t c = hist[(size_t)nbins * i + b];
                hist[(size_t)nbins * i + b] = tot[b];
                tot[b] += c;
            }
    }
    for (uint32_t b = 0; b < nbins; ++b) bin_split[b] = 1;

    /* Cut the curve into contiguous bin ranges. */
    {
        uint32_t k = 0;
        uint64_t acc = 0, in_part = 0;
        if (count > 0) {
            /* Partition k ends once the running count reaches its share
             * (k + 1) * N / count; a bin that crosses several shares leaves
             * the partitions in between empty. */
            for (uint32_t b = 0; b < nbins; ++b) {
                bin_part[b] = k;
                acc += tot[b];
                while (k + 1 < count && acc >= (uint64_t)(((unsigned __int128)N * (k + 1)) / count)) ++k;
            }
            out->count = count;
        } else {
            for (uint32_t b = 0; b < nbins; ++b) {
                if (in_part > 0 && in_part + tot[b] > max_elements) {
                    ++k;
                    in_part = 0;
                }
                bin_part[b] = k;
                if (tot[b] > max_elements) { /* partitions of its own, the last one full */
                    bin_split[b] = (uint32_t)((tot[b] + max_elements - 1) / max_elements);
                    k += bin_split[b] - 1;
                    in_part = max_elements;
                } else in_part += tot[b];
                if (k >= 65535u) {
                    s = clvr_error_set(err, CLVR_ERR_OVERFLOW,
                                       "partition: more than 65535 partitions of at most %llu elements; "
                                       "allow larger partitions", (unsigned long long)max_elements);
                    goto cleanup;
                }
            }
            out->count = k + 1;
        }
    }
    out->parts = calloc(out->count, sizeof *out->parts);
    if (!out->parts) goto oom;
    for (uint32_t p = 0; p < out->count; ++p) {
        out->parts[p].id = p;
        out->parts[p].bin_lo = nbins;
        out->parts[p].bin_hi = 0;
    }
    for (uint32_t b = 0; b < nbins; ++b)
        for (uint32_t j = 0; j < bin_split[b] && tot[b]; ++j) { /* empty bins do not widen the ranges */
            clvr_partition *q = &out->parts[bin_part[b] + j];
            if (b < q->bin_lo) q->bin_lo = b;
            if (b + 1 > q->bin_hi) q->bin_hi = b + 1;
        }
    for (uint32_t p = 0; p < out->count; ++p)
        if (out->parts[p].bin_lo > out->parts[p].bin_hi) out->parts[p].bin_lo = out->parts[p].bin_hi;

    /* Pass 2: partition of every element, counts per partition and type. */
    counts = calloc((size_t)out->count * nt, sizeof *counts);
    if (!counts) goto oom;
    proto.bin_part = bin_part;
    proto.bin_split = bin_split;
    proto.max_elements = max_elements;
    for (uint32_t i = 0; i < nt; ++i) {
        jobs[i] = proto;
        jobs[i].counts = counts + (size_t)out->count * i;
        jobs[i].rank = hist + (size_t)nbins * i;
    }
    run_key_pass(jobs, nt, N);
    for (uint32_t p = 0; p < out->count; ++p)
        for (uint32_t i = 0; i < nt; ++i)
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
                out->parts[p].num_cells[t] += counts[(size_t)out->count * i + p][t];
                out->parts[p].num_elements += counts[(size_t)out->count * i + p][t];
            }
    out->seconds = clvr_clock_monotonic_s() - t0;
    goto cleanup;
oom:
    s = clvr_error_set(err, CLVR_ERR_NO_MEMORY,
                       "partition: out of memory for the partition plan of %llu elements (%llu MB)",
                       (unsigned long long)N, (unsigned long long)((N * 2 + (4ull << CLVR_PARTITION_KEY_BITS) * nt) >> 20));
cleanup:
    free(hist);
    free(bin_part);
    free(bin_split);
    free(tot);
    free(counts);
    if (s != CLVR_OK) clvr_partition_plan_free(out);
    return s;
}

clvr_status clvr_partition_plan_make(const clvr_mesh *m, uint32_t count, uint64_t max_elements,
                                     clvr_partition_plan *out, clvr_error *err)
{
    return plan_make(m, count, max_elements, 0, NULL, out, err);
}

/* The reorder of a mapped mesh: p->order, a counting sort of the element
 * ids by partition (stable: mesh order inside each). Left as it is (the
 * extraction scans part_of16) when the memory is not there. */
static void plan_order(const clvr_mesh *m, clvr_partition_plan *p)
{
    const uint64_t N = p->num_elements, bytes = (N ? N : 1) * sizeof(uint32_t);
    uint64_t *next = malloc((size_t)p->count * sizeof *next);
    void *o = mmap(NULL, (size_t)bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (!next || o == MAP_FAILED) {
        free(next);
        if (o != MAP_FAILED) munmap(o, (size_t)bytes);
        return;
    }
    (void)m;
    uint64_t at = 0;
    for (uint32_t k = 0; k < p->count; ++k) {
        p->parts[k].first = next[k] = at;
        at += p->parts[k].num_elements;
    }
    uint32_t *ord = o;
    for (uint64_t g = 0; g < N; ++g) ord[next[p->part_of16[g]]++] = (uint32_t)g;
    free(next);
    free(p->part_of16);
    p->part_of16 = NULL;
    p->order = ord;
    p->order_bytes = bytes;
    p->reordered = 1;
}

void clvr_partition_plan_reorder(clvr_mesh *m, clvr_partition_plan *p)
{
    if (p->reordered) return;
    if (m->map_base) { /* read-only lists: an order list instead of moving them */
        plan_order(m, p);
        return;
    }
    uint64_t *next = malloc((size_t)p->count * sizeof *next), first = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t vpe = clvr_cell_vertex_count(t);
        uint64_t at = 0;
        for (uint32_t k = 0; k < p->count; ++k) {
            p->parts[k].first_cell[t] = at;
            at += p->parts[k].num_cells[t];
        }
        if (!next) continue; /* no memory for the cursors: stays in mesh order */
        for (uint32_t k = 0; k < p->count; ++k) next[k] = p->parts[k].first_cell[t];
        uint32_t *idx = m->indices[t];
        /* Cycle leader: each slot of bucket k is settled by swapping the
         * element there to the next free slot of its own bucket. */
        for (uint32_t k = 0; k < p->count; ++k) {
            const uint64_t end = p->parts[k].first_cell[t] + p->parts[k].num_cells[t];
            while (next[k] < end) {
                const uint64_t e = next[k];
                const uint32_t q = clvr_partition_of(p, first + e);
                if (q == k) { ++next[k]; continue; }
                const uint64_t d = next[q]++;
                uint32_t tmp[CLVR_CELL_MAX_VERTS];
                memcpy(tmp, idx + e * vpe, vpe * 4u);
                memcpy(idx + e * vpe, idx + d * vpe, vpe * 4u);
                memcpy(idx + d * vpe, tmp, vpe * 4u);
                /* The partition ids travel with the elements. */
                const uint16_t old = p->part_of16[first + d];
                p->part_of16[first + d] = (uint16_t)q;
                p->part_of16[first + e] = old;
            }
        }
        first += m->num_cells[t];
    }
    if (!next) return; /* out of memory: left in mesh order (extraction scans part_of) */
    free(next);
    free(p->part_of16);
    p->part_of16 = NULL;
    p->reordered = 1;
}

/* ------------------------------------------------------------ extraction */

clvr_status clvr_partition_extract(const clvr_mesh *m, const clvr_partition_plan *p, uint32_t part, uint32_t *vmap,
                                   clvr_mesh *sub, uint32_t **ids, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    uint32_t *verts = NULL, *idl = NULL;
    memset(sub, 0, sizeof *sub);
    if (ids) *ids = NULL;
    if (part >= p->count)
        return clvr_error_set(err, CLVR_ERR_USAGE, "partition %u of a plan of %u", part, p->count);
    const clvr_partition *q = &p->parts[part];
    uint64_t slots = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) slots += q->num_cells[t] * clvr_cell_vertex_count(t);
    /* At most one new vertex per index slot, and at most the mesh's. */
    const uint64_t vcap = slots < m->num_vertices ? slots : m->num_vertices;
    s = clvr_mesh_alloc(sub, vcap, q->num_cells, err);
    if (s != CLVR_OK) return s;
    verts = malloc((vcap ? vcap : 1) * sizeof *verts);
    if (ids) idl = malloc((q->num_elements ? q->num_elements : 1) * sizeof *idl);
    if (!verts || (ids && !idl)) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "partition %u: out of memory for its %llu vertices", part,
                           (unsigned long long)vcap);
        goto cleanup;
    }
    uint64_t nv = 0, first = 0, k = 0;
    if (p->order) { /* a mapped mesh's partition: a range of the order list, ascending ids */
        uint64_t type_first[CLVR_CELL_TYPE_COUNT + 1] = {0};
        uint32_t *dst[CLVR_CELL_TYPE_COUNT];
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            type_first[t + 1] = type_first[t] + m->num_cells[t];
            dst[t] = sub->indices[t];
        }
        uint32_t t = 0;
        for (uint64_t i = q->first; i < q->first + q->num_elements; ++i) {
            const uint64_t g = p->order[i];
            while (g >= type_first[t + 1]) ++t;
            const uint32_t vpe = clvr_cell_vertex_count(t);
            const uint32_t *src = m->indices[t] + (g - type_first[t]) * vpe;
            for (uint32_t j = 0; j < vpe; ++j) {
                const uint32_t v = src[j];
                if (vmap[v] == UINT32_MAX) {
                    vmap[v] = (uint32_t)nv;
                    verts[nv++] = v;
                }
                *dst[t]++ = vmap[v];
            }
            if (idl) idl[k] = (uint32_t)g;
            ++k;
        }
    }
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && !p->order; ++t) {
        const uint32_t vpe = clvr_cell_vertex_count(t);
        uint32_t *dst = sub->indices[t];
        const uint32_t *src = m->indices[t];
        /* Reordered: the partition is one range of the list; else a scan. */
        const uint64_t e0 = p->reordered ? q->first_cell[t] : 0,
                       e1 = p->reordered ? q->first_cell[t] + q->num_cells[t] : m->num_cells[t];
        for (uint64_t e = e0; e < e1; ++e) {
            if (!p->reordered && clvr_partition_of(p, first + e) != part) continue;
            for (uint32_t j = 0; j < vpe; ++j) {
                const uint32_t v = src[e * vpe + j];
                if (vmap[v] == UINT32_MAX) {
                    vmap[v] = (uint32_t)nv;
                    verts[nv++] = v;
                }
                *dst++ = vmap[v];
            }
            if (idl) idl[k] = (uint32_t)(first + e);
            ++k;
        }
        first += m->num_cells[t];
    }
    for (uint64_t i = 0; i < nv; ++i) {
        const uint32_t v = verts[i];
        memcpy(sub->positions + 3 * i, m->positions + 3 * (uint64_t)v, 3 * sizeof(float));
        sub->scalars[i] = m->scalars[v];
        vmap[v] = UINT32_MAX; /* reset from the partition's own list: cost of its size, not the mesh's */
    }
    sub->num_vertices = nv;
    /* Give back the tail of the upper-bound allocation (untouched pages). */
    if (nv > 0 && nv < vcap) {
        float *pp = realloc(sub->positions, nv * 3 * sizeof(float)), *ss = realloc(sub->scalars, nv * sizeof(float));
        if (pp) sub->positions = pp;
        if (ss) sub->scalars = ss;
    }
    memcpy(sub->scalar_name, m->scalar_name, sizeof sub->scalar_name);
    clvr_mesh_update_ranges(sub);
    if (ids) {
        *ids = idl;
        idl = NULL;
    }
cleanup:
    free(verts);
    free(idl);
    if (s != CLVR_OK) clvr_mesh_free(sub);
    return s;
}

/* ------------------------------------------------------------ result assembly */

/* A growable page-aligned anonymous mapping: the final arrays grow by
 * mremap (no copy of what is there, no second copy alive) and are handed to
 * the device with CL_MEM_USE_HOST_PTR, which PoCL uses in place when the
 * pointer is aligned. */
typedef struct grow_array {
    void *p;
    uint64_t used, mapped;
} grow_array;

static uint64_t page_round(uint64_t n)
{
    const uint64_t pg = 4096;
    return (n + pg - 1) / pg * pg;
}

/* Makes room for `more` bytes past used; returns the address of the tail
 * (non-NULL also for 0 bytes, where nothing may be written), NULL when out
 * of memory. */
static void *grow(grow_array *a, uint64_t more)
{
    if (more == 0) return a->p ? (uint8_t *)a->p + a->used : (void *)a;
    const uint64_t need = page_round(a->used + more);
    if (need > a->mapped) {
        /* Grow by at least an eighth: fewer remaps when many partitions append. */
        uint64_t want = need > a->mapped + a->mapped / 8 ? need : page_round(a->mapped + a->mapped / 8);
        void *q = a->p ? mremap(a->p, a->mapped, want, MREMAP_MAYMOVE)
                       : mmap(NULL, want, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (q == MAP_FAILED && want > need) { /* retry with the bare need */
            want = need;
            q = a->p ? mremap(a->p, a->mapped, want, MREMAP_MAYMOVE)
                     : mmap(NULL, want, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        }
        if (q == MAP_FAILED) return NULL;
        /* Transparent huge pages for the result's arrays (THP is often
         * "madvise" only): each partition's append writes fresh pages, and
         * with 4 KiB pages their faults made the merge stage superlinear.
         * Measured on 100M mixed (24 partitions, interleaved runs, load
         * 1.5-2): merge 3.0-3.4 s -> 0.47-0.50 s; 10M: 0.109 -> 0.037-0.041
         * s; peak RSS unchanged (4.12 GB). Advice only: failure is harmless. */
        (void)madvise(q, want, MADV_HUGEPAGE);
        a->p = q;
        a->mapped = want;
    }
    void *tail = (uint8_t *)a->p + a->used;
    a->used += more;
    return tail;
}

static void grow_free(grow_array *a)
{
    if (a->p) munmap(a->p, a->mapped);
    memset(a, 0, sizeof *a);
}

enum { ARR_VERTICES, ARR_IDX16, ARR_IDX32, ARR_INSTANCES, ARR_LEAVES, ARR_SAMPLING, ARR_ORDER, ARR_COUNT };

/* ------------------------------------------------------------ pieces */

clvr_status clvr_partition_pieces(clvr_instance *inst, uint64_t n, uint64_t limit, int element_boxes,
                                  const char *what, clvr_clustered *c, clvr_error *err)
{
    /* The split arrays: entry size, total entries, and for instance i its
     * first entry and entry count. */
    enum { SV, S16, S32, SBOX, SN };
    static const char *const names[SN] = {"clustered vertices", "16-bit indices", "32-bit indices", "element boxes"};
    static const uint64_t size[SN] = {16, 2, 4, 6};
    const uint64_t total[SN] = {c->num_vertices, c->num_idx16, c->num_idx32, element_boxes ? c->num_elements : 0};
    const char *name = what ? what : "mesh";
    uint64_t base[SN] = {0}, end[SN] = {0}; /* the current piece's first entry; the entries so far */
    uint32_t piece = 0, piece_first_element = 0;
    memset(c->piece_vertices, 0, sizeof c->piece_vertices);
    memset(c->piece_idx16, 0, sizeof c->piece_idx16);
    memset(c->piece_idx32, 0, sizeof c->piece_idx32);
    memset(c->piece_elements, 0, sizeof c->piece_elements);
    /* First the one cause no number of pieces mends: an instance cluster
     * whose own share of an array exceeds the limit. */
    for (uint64_t i = 0; i < n; ++i) {
        const clvr_instance *in = &inst[i];
        const uint64_t slots = (uint64_t)in->num_elements * clvr_cell_vertex_count(in->type);
        const uint64_t bytes[SN] = {in->num_vertices * size[SV], in->index_bits == 32 ? 0 : slots * size[S16],
                                    in->index_bits == 32 ? slots * size[S32] : 0,
                                    element_boxes ? in->num_elements * size[SBOX] : 0};
        for (int a = 0; a < SN; ++a)
            if (bytes[a] > limit)
                return clvr_error_set(
                    err, CLVR_ERR_DEVICE_MEMORY,
                    "%s: instance cluster %llu alone needs %llu bytes (%.3f GB) of %s in one buffer but the device "
                    "allows at most %llu bytes per buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE, or CLVR_MAX_ALLOC_BYTES "
                    "when set); the split arrays are cut only between instance clusters: raise CLVR_MAX_ALLOC_BYTES "
                    "(a testing knob) or use a device with a larger allocation limit",
                    name, (unsigned long long)i, (unsigned long long)bytes[a], (double)bytes[a] / 1e9, names[a],
                    (unsigned long long)limit);
    }
    for (uint64_t i = 0; i < n; ++i) {
        clvr_instance *in = &inst[i];
        const uint64_t slots = (uint64_t)in->num_elements * clvr_cell_vertex_count(in->type);
        const int wide = in->index_bits == 32;
        uint64_t first[SN] = {in->first_vertex, wide ? end[S16] : in->first_index, wide ? in->first_index : end[S32],
                              in->first_element};
        uint64_t count[SN] = {in->num_vertices, wide ? 0 : slots, wide ? slots : 0, element_boxes ? in->num_elements : 0};
        for (int a = 0; a < SN; ++a) {
            if (a == SBOX && !element_boxes) first[a] = end[a];
            if (first[a] != end[a]) /* the arrays follow the instance order (preprocessing writes them so) */
                return clvr_error_set(err, CLVR_ERR_INTERNAL,
                                      "%s: instance %llu's %s start at %llu, not after the previous instance's "
                                      "(%llu); the arrays cannot be cut into pieces (a bug: please report it)",
                                      name, (unsigned long long)i, names[a], (unsigned long long)first[a],
                                      (unsigned long long)end[a]);
        }
        int cut = 0;
        for (int a = 0; a < SN; ++a) cut |= (end[a] + count[a] - base[a]) * size[a] > limit;
        if (cut) {
            if (piece + 1 >= CLVR_MAX_SPLITS) {
                uint64_t need = 0; /* at least this many pieces, from the largest array */
                int worst = 0;
                for (int a = 0; a < SN; ++a) {
                    const uint64_t k = (total[a] * size[a] + limit - 1) / limit;
                    if (k > need) need = k, worst = a;
                }
                if (need <= CLVR_MAX_SPLITS) need = CLVR_MAX_SPLITS + 1; /* instance boundaries cost the rest */
                return clvr_error_set(
                    err, CLVR_ERR_DEVICE_MEMORY,
                    "%s: the %s take %.3f GB, more than %u pieces of at most %.3f GB (the device's largest buffer, "
                    "CL_DEVICE_MAX_MEM_ALLOC_SIZE, or CLVR_MAX_ALLOC_BYTES when set) hold (at least %llu needed); "
                    "use a smaller (cropped or decimated) mesh or a device with a larger allocation limit",
                    name, names[worst], (double)(total[worst] * size[worst]) / 1e9, CLVR_MAX_SPLITS,
                    (double)limit / 1e9, (unsigned long long)need);
            }
            ++piece;
            for (int a = 0; a < SN; ++a) base[a] = end[a];
            piece_first_element = in->first_element;
            c->piece_vertices[piece] = base[SV];
            c->piece_idx16[piece] = base[S16];
            c->piece_idx32[piece] = base[S32];
            c->piece_elements[piece] = piece_first_element;
        }
        for (int a = 0; a < SN; ++a) end[a] += count[a];
        in->piece = piece;
        in->piece_first_element = piece_first_element;
        in->first_vertex -= (uint32_t)base[SV];
        in->first_index -= wide ? base[S32] : base[S16];
    }
    if (end[SV] != total[SV] || end[S16] != total[S16] || end[S32] != total[S32])
        return clvr_error_set(err, CLVR_ERR_INTERNAL,
                              "%s: the instances cover %llu vertices and %llu + %llu indices of %llu and %llu + %llu "
                              "(a bug: please report it)",
                              name, (unsigned long long)end[SV], (unsigned long long)end[S16],
                              (unsigned long long)end[S32], (unsigned long long)total[SV],
                              (unsigned long long)total[S16], (unsigned long long)total[S32]);
    c->num_pieces = piece + 1;
    c->piece_vertices[c->num_pieces] = total[SV];
    c->piece_idx16[c->num_pieces] = total[S16];
    c->piece_idx32[c->num_pieces] = total[S32];
    c->piece_elements[c->num_pieces] = c->num_elements;
    return CLVR_OK;
}

static clvr_status read_into(clvr_cl *cl, grow_array *a, cl_mem b, uint64_t bytes, const char *what, void **tail,
                             clvr_error *err)
{
    clvr_status s = CLVR_OK;
    void *dst = grow(a, bytes);
    if (tail) *tail = dst;
    if (!dst)
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "partitioned preprocessing: out of memory growing the %s to %.3f GB",
                              what, (double)(a->used + bytes) / 1e9);
    if (bytes) CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, b, CL_TRUE, 0, bytes, dst, 0, NULL, NULL));
cleanup:
    return s;
}

/* Gives the pages of type lists' indices before each partition's end back
 * to the OS (consume mode): released[t] bytes of list t are gone already. */
static void release_gathered(clvr_mesh *m, const clvr_partition *q, uint64_t released[CLVR_CELL_TYPE_COUNT])
{
    const uintptr_t pg = 4096;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        if (!m->indices[t] || q->num_cells[t] == 0) continue;
        const uintptr_t base = (uintptr_t)m->indices[t];
        const uint64_t end = (q->first_cell[t] + q->num_cells[t]) * clvr_cell_vertex_count(t) * 4ull;
        const uintptr_t a = (base + released[t] + pg - 1) / pg * pg, b = (base + end) / pg * pg;
        /* Only whole pages inside the list: its neighbours on the heap are untouched. */
        if (b > a && madvise((void *)a, b - a, MADV_DONTNEED) == 0) released[t] = b - base;
    }
}

clvr_status clvr_preprocess_partitioned(clvr_cl *cl, clvr_mesh *m, const clvr_preprocess_options *o,
                                        uint32_t count, uint64_t max_elements, int consume, clvr_clustered *out,
                                        uint32_t *num_partitions, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_preprocess_options opt;
    clvr_partition_plan plan = {0};
    clvr_clustered pc = {0};
    clvr_mesh sub = {0};
    uint32_t *vmap = NULL, *ids = NULL;
    grow_array arr[ARR_COUNT];
    const double t_start = clvr_clock_monotonic_s();
    memset(arr, 0, sizeof arr);
    memset(out, 0, sizeof *out);
    if (num_partitions) *num_partitions = 0;
    uint64_t released[CLVR_CELL_TYPE_COUNT] = {0}, order_released = 0;
    CLVR_TRY(clvr_pp_options_resolve(o, &opt, err));
    /* A mapped mesh is never moved (an order list instead): its ids stay. */
    if (consume && opt.keep_order && !m->map_base) {
        s = clvr_error_set(err, CLVR_ERR_USAGE, "partitioned preprocessing: keep_order needs the mesh kept (consume 0)");
        goto cleanup;
    }
    const uint64_t N = clvr_mesh_num_elements(m);
    if (max_elements == 0) max_elements = CLVR_PARTITION_DEFAULT_ELEMENTS;
    /* One partition: the plain pipeline (no plan, no host assembly). */
    if (count == 1 || (count == 0 && N <= max_elements)) {
        opt.quantize_box = o ? o->quantize_box : NULL;
        CLVR_TRY(clvr_preprocess(cl, m, &opt, out, err));
        if (num_partitions) *num_partitions = 1;
        goto cleanup;
    }
    /* A mapped mesh: whatever earlier passes left mapped goes back to the
     * page cache before the result grows (the pages are the file's). */
    clvr_mesh_release_all_pages(m);
    CLVR_TRY(plan_make(m, count, max_elements, opt.morton, o ? o->quantize_box : NULL, &plan, err));
    if (consume) {
        const double t0 = clvr_clock_monotonic_s();
        clvr_partition_plan_reorder(m, &plan);
        out->stage_s[CLVR_PP_STAGE_PARTITION] += clvr_clock_monotonic_s() - t0;
    }
    out->stage_s[CLVR_PP_STAGE_PARTITION] += plan.seconds;
    opt.quantize_box = &plan.box;
    /* One curve or not, decided once for the whole mesh: every partition
     * then stores its cells alike (a partition of one type stays as it is). */
    opt.one_curve = clvr_pp_one_curve(&opt, m->num_cells) ? CLVR_ONE_CURVE_ON : CLVR_ONE_CURVE_OFF;
    vmap = malloc((m->num_vertices ? m->num_vertices : 1) * sizeof *vmap);
    if (!vmap) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "partitioned preprocessing: out of memory for the %.3f GB vertex map",
                           (double)m->num_vertices * 4 / 1e9);
        goto cleanup;
    }
    memset(vmap, 0xff, (m->num_vertices ? m->num_vertices : 1) * sizeof *vmap);

    out->leaf_size = opt.leaf_size;
    out->no_element_boxes = opt.no_element_boxes;
    out->sampling_size = opt.sampling_size;
    out->index_bits = opt.index_bits;
    out->morton = opt.morton;
    out->num_elements = N;
    out->num_partitions = 0;
    /* Summed over the partitions: with one curve (preprocess.h) a partition
     * of several types holds collapsed hexes, one of a single type its own. */
    memset(out->num_cells, 0, sizeof out->num_cells);
    for (int k = 0; k < 3; ++k) {
        out->bounds.lo[k] = m->bounds_lo[k];
        out->bounds.hi[k] = m->bounds_hi[k];
    }
    out->bounds.lo[3] = out->scalar_min = m->scalar_min;
    out->bounds.hi[3] = out->scalar_max = m->scalar_max;
    int first_done = 0;
    uint64_t elements_done = 0; /* global sorted ids of the partitions appended so far */
    for (uint32_t k = 0; k < plan.count; ++k) {
        if (plan.parts[k].num_elements == 0) continue;
        double t0 = clvr_clock_monotonic_s();
        CLVR_TRY(clvr_partition_extract(m, &plan, k, vmap, &sub, opt.keep_order ? &ids : NULL, err));
        if (m->map_base) {
            /* A mapped mesh: the pages this gather read go back to the page
             * cache (a later partition sharing a page faults it in again),
             * and so does the consumed part of the order list. */
            clvr_mesh_release_all_pages(m);
            if (plan.order) {
                const uint64_t pg = 4096, done = (plan.parts[k].first + plan.parts[k].num_elements) * 4 / pg * pg;
                if (done > order_released) {
                    madvise((uint8_t *)plan.order + order_released, (size_t)(done - order_released), MADV_DONTNEED);
                    order_released = done;
                }
            }
        } else if (consume && plan.reordered) {
            release_gathered(m, &plan.parts[k], released);
        }
        out->stage_s[CLVR_PP_STAGE_EXTRACT] += clvr_clock_monotonic_s() - t0;
        s = clvr_preprocess(cl, &sub, &opt, &pc, err);
        if (s != CLVR_OK && err) {
            char why[sizeof err->msg];
            memcpy(why, err->msg, sizeof why);
            clvr_error_set(err, s, "partition %u of %u (%llu elements): %s", k, plan.count,
                           (unsigned long long)plan.parts[k].num_elements, why);
        }
        if (s != CLVR_OK) goto cleanup;
        clvr_mesh_free(&sub); /* before the appends grow the result */
        t0 = clvr_clock_monotonic_s();
        for (int st = 0; st < CLVR_PP_STAGE_PARTITION; ++st) out->stage_s[st] += pc.stage_s[st];
        out->build_s += pc.build_s;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            out->num_cells[t] += pc.num_cells[t];
            out->collapsed[t] += pc.collapsed[t];
        }
        if (!first_done) {
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) out->first_cell[t] = pc.first_cell[t];
            first_done = 1;
        }
        /* Offsets of this partition in the result: 32-bit fields of
         * clvr_instance must still hold them. */
        const uint64_t base_e = elements_done, base_v = out->num_vertices, base_l = out->num_leaves, base_16 = out->num_idx16,
                       base_32 = out->num_idx32;
        if (base_v + pc.num_vertices > 0xffffffffull || base_l + pc.num_leaves > 0xffffffffull) {
            s = clvr_error_set(err, CLVR_ERR_OVERFLOW,
                               "preprocess: the clustered mesh would hold %llu vertices and %llu leaf clusters; at "
                               "most 2^32 - 1 of each are addressable (clvr_instance.first_vertex, first_leaf)",
                               (unsigned long long)(base_v + pc.num_vertices),
                               (unsigned long long)(base_l + pc.num_leaves));
            goto cleanup;
        }
        CLVR_TRY(read_into(cl, &arr[ARR_VERTICES], pc.vertices, pc.num_vertices * 16, "clustered vertices", NULL, err));
        CLVR_TRY(read_into(cl, &arr[ARR_IDX16], pc.idx16, pc.num_idx16 * 2, "16-bit indices", NULL, err));
        CLVR_TRY(read_into(cl, &arr[ARR_IDX32], pc.idx32, pc.num_idx32 * 4, "32-bit indices", NULL, err));
        CLVR_TRY(read_into(cl, &arr[ARR_LEAVES], pc.leaf_boxes, pc.num_leaves * sizeof(clvr_box), "leaf boxes", NULL,
                           err));
        CLVR_TRY(read_into(cl, &arr[ARR_SAMPLING], pc.sampling, pc.num_sampling * sizeof(clvr_sampling_cluster),
                           "sampling clusters", NULL, err));
        {
            clvr_instance *in = grow(&arr[ARR_INSTANCES], pc.num_instances * sizeof(clvr_instance));
            if (!in) {
                s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "partitioned preprocessing: out of memory for instances");
                goto cleanup;
            }
            for (uint64_t i = 0; i < pc.num_instances; ++i) {
                clvr_instance c = pc.host_instances[i];
                c.first_element += (uint32_t)base_e;
                c.first_vertex += (uint32_t)base_v;
                c.first_index += c.index_bits == 16 ? base_16 : base_32;
                c.first_leaf += (uint32_t)base_l;
                in[i] = c;
            }
        }
        if (opt.keep_order) {
            uint32_t *ord = NULL;
            CLVR_TRY(read_into(cl, &arr[ARR_ORDER], pc.order, pc.num_elements * 4, "element order", (void **)&ord, err));
            for (uint64_t i = 0; i < pc.num_elements; ++i) ord[i] = ids[ord[i]];
            free(ids);
            ids = NULL;
        }
        out->num_vertices += pc.num_vertices;
        out->num_idx16 += pc.num_idx16;
        out->num_idx32 += pc.num_idx32;
        out->num_instances += pc.num_instances;
        out->num_leaves += pc.num_leaves;
        out->num_sampling += pc.num_sampling;
        out->num_partitions++;
        elements_done += pc.num_elements;
        clvr_clustered_release(cl, &pc);
        out->stage_s[CLVR_PP_STAGE_MERGE] += clvr_clock_monotonic_s() - t0;
    }

    /* The result's buffers, over the host arrays. */
    {
        const double t0 = clvr_clock_monotonic_s();
        const int cpu = (cl->device_type & CL_DEVICE_TYPE_CPU) != 0;
        const cl_mem_flags fl = CL_MEM_READ_WRITE | (cpu ? CL_MEM_USE_HOST_PTR : CL_MEM_COPY_HOST_PTR);
        struct { int a; cl_mem *m; const char *what; } bufs[] = {
            {ARR_VERTICES, &out->vertices, "clustered vertices"}, {ARR_IDX16, &out->idx16, "16-bit indices"},
            {ARR_IDX32, &out->idx32, "32-bit indices"},          {ARR_INSTANCES, &out->instances, "instances"},
            {ARR_LEAVES, &out->leaf_boxes, "leaf boxes"},        {ARR_SAMPLING, &out->sampling, "sampling clusters"},
            {ARR_ORDER, &out->order, "element order"},
        };
        /* Arrays of instance clusters above the device's largest buffer
         * are cut into pieces at instance boundaries (docs/large-meshes.md). */
        CLVR_TRY(clvr_partition_pieces((clvr_instance *)arr[ARR_INSTANCES].p, out->num_instances, cl->max_alloc_bytes,
                                       !opt.no_element_boxes, NULL, out, err));
        out->host_instances = malloc((out->num_instances ? out->num_instances : 1) * sizeof(clvr_instance));
        if (!out->host_instances) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the instance table");
            goto cleanup;
        }
        if (out->num_instances)
            memcpy(out->host_instances, arr[ARR_INSTANCES].p, out->num_instances * sizeof(clvr_instance));
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, 16, NULL, "piece placeholder", &out->piece_dummy, err));
        for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; ++i) {
            grow_array *a = &arr[bufs[i].a];
            if (bufs[i].a == ARR_ORDER && !opt.keep_order) continue;
            const uint64_t *prefix = bufs[i].a == ARR_VERTICES ? out->piece_vertices
                                     : bufs[i].a == ARR_IDX16  ? out->piece_idx16
                                     : bufs[i].a == ARR_IDX32  ? out->piece_idx32
                                                               : NULL;
            if (prefix && out->num_pieces > 1) {
                /* One buffer per piece over its range of the host array (on
                 * a CPU device in place, as the whole array would be). */
                const uint64_t esize = bufs[i].a == ARR_VERTICES ? 16 : bufs[i].a == ARR_IDX16 ? 2 : 4;
                cl_mem *more = bufs[i].a == ARR_VERTICES ? out->vertices_more
                               : bufs[i].a == ARR_IDX16  ? out->idx16_more
                                                         : out->idx32_more;
                for (uint32_t p = 0; p < out->num_pieces; ++p) {
                    const uint64_t bytes = (prefix[p + 1] - prefix[p]) * esize;
                    CLVR_TRY(clvr_cl_buffer(cl, fl, bytes, bytes ? (char *)a->p + prefix[p] * esize : NULL,
                                            bufs[i].what, p ? &more[p - 1] : bufs[i].m, err));
                }
            } else {
                CLVR_TRY(clvr_cl_buffer(cl, fl, a->used, a->p, bufs[i].what, bufs[i].m, err));
            }
            if (cpu && a->used) { /* the buffer lives in the mapping: the result owns it now */
                out->host_arrays[i] = a->p;
                out->host_array_bytes[i] = a->mapped;
                memset(a, 0, sizeof *a);
            } else grow_free(a);
        }
        out->stage_s[CLVR_PP_STAGE_MERGE] += clvr_clock_monotonic_s() - t0;
    }
    clvr_clustered_fill_stats(out, m);
    if (num_partitions) *num_partitions = plan.count;
#ifdef __GLIBC__
    /* The partitions' smaller arrays (below glibc's mmap threshold) were
     * freed into the heap, which keeps the pages: hand them back, or the
     * footprint after preprocessing keeps one partition's scratch. */
    malloc_trim(0);
#endif
    out->wall_s = clvr_clock_monotonic_s() - t_start;

cleanup:
    clvr_clustered_release(cl, &pc);
    clvr_mesh_free(&sub);
    free(ids);
    free(vmap);
    for (int i = 0; i < ARR_COUNT; ++i) grow_free(&arr[i]);
    clvr_partition_plan_free(&plan);
    if (consume) clvr_mesh_free_indices(m); /* or unmaps them */
    if (s != CLVR_OK) clvr_clustered_release(cl, out);
    return s;
}
