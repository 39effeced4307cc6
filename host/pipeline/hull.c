/* hull.c: boundary faces of a clustered mesh (hull.h). */
#include "hull.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../kernels/hull.h"
#include "limits_check.h"
#include "preprocess_stages.h"

clvr_status clvr_hull_face_first(const clvr_instance *instances, uint64_t num_instances, uint32_t *face_first,
                                 clvr_error *err)
{
    uint64_t slot = 0;
    for (uint64_t i = 0; i < num_instances; ++i) {
        face_first[i] = (uint32_t)slot;
        slot += (uint64_t)instances[i].num_elements * clvr_hull_face_count(instances[i].type);
        if (slot > CLVR_BVH_MAX_PRIMS)
            return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                                  "hull: the mesh's elements have more than 2^31 - 1 faces; render it as "
                                  "partitions (--mpi) or without the hull");
    }
    face_first[num_instances] = (uint32_t)slot;
    return CLVR_OK;
}

void clvr_hull_release(clvr_cl *cl, clvr_hull *h)
{
    if (!h) return;
    clvr_cl_release(cl, &h->faces);
    clvr_cl_release(cl, &h->nodes);
    memset(h, 0, sizeof *h);
}

uint64_t clvr_hull_bytes(const clvr_hull *h)
{
    if (!h || !h->kept) return 0;
    return (uint64_t)h->num_faces * sizeof(clvr_hull_face) + (uint64_t)h->num_nodes * sizeof(clvr_bvh_node);
}

#define PIECE_ARGS(pc)                                                                                                 \
    CLVR_ARG(pc.vertices[0]), CLVR_ARG(pc.idx16[0]), CLVR_ARG(pc.idx32[0]), CLVR_ARG(pc.vertices[1]),                  \
        CLVR_ARG(pc.idx16[1]), CLVR_ARG(pc.idx32[1]), CLVR_ARG(pc.vertices[2]), CLVR_ARG(pc.idx16[2]),                 \
        CLVR_ARG(pc.idx32[2]), CLVR_ARG(pc.vertices[3]), CLVR_ARG(pc.idx16[3]), CLVR_ARG(pc.idx32[3])

/* n rays (org, dir: 4 floats each) through kernel k over the tree `nodes`:
 * clvr_hull_rays' (or clvr_hull_gap_rays') arguments when faces is a hull's
 * faces, clvr_bvh_ray_span's (no faces argument) when it is NULL;
 * out_floats floats per ray into out. */
static clvr_status rays_through(clvr_cl *cl, cl_kernel k, cl_mem nodes, cl_mem faces, const float *org,
                                const float *dir, uint32_t n, size_t out_floats, float *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem bo = NULL, bd = NULL, bt = NULL;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)n * 16, (void *)org, "hull rays", &bo,
                            err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)n * 16, (void *)dir, "hull rays", &bd,
                            err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)n * out_floats * sizeof(float), NULL, "hull ray results",
                            &bt, err));
    const cl_uint nn = n;
    if (faces)
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(bo), CLVR_ARG(bd), CLVR_ARG(nn), CLVR_ARG(nodes), CLVR_ARG(faces),
                              CLVR_ARG(bt)));
    else
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(bo), CLVR_ARG(bd), CLVR_ARG(nn), CLVR_ARG(nodes), CLVR_ARG(bt)));
    CLVR_TRY(clvr_cl_run1d(cl, k, n, 64, NULL, err));
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, bt, CL_TRUE, 0, (size_t)n * out_floats * sizeof(float), out, 0, NULL,
                                      NULL));
cleanup:
    clvr_cl_release(cl, &bo);
    clvr_cl_release(cl, &bd);
    clvr_cl_release(cl, &bt);
    return s;
}

clvr_status clvr_hull_gap_rays(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_hull *h, const float *org,
                               const float *dir, uint32_t n, float *out, clvr_error *err)
{
    if (n == 0) return CLVR_OK;
    if (h->num_faces == 0) return clvr_error_set(err, CLVR_ERR_USAGE, "clvr_hull_gap_rays: the hull has no faces");
    return rays_through(cl, k->hull_gap_rays, h->nodes, h->faces, org, dir, n, CLVR_HULL_GAP_STRIDE, out, err);
}

clvr_status clvr_hull_rays(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_hull *h, const float *org,
                           const float *dir, uint32_t n, float *out, clvr_error *err)
{
    if (n == 0) return CLVR_OK;
    if (h->num_faces == 0) {
        for (uint32_t i = 0; i < n; ++i) {
            out[4 * i] = 0.0f;
            out[4 * i + 1] = INFINITY;
            out[4 * i + 2] = 0.0f;
            out[4 * i + 3] = 0.0f;
        }
        return CLVR_OK;
    }
    return rays_through(cl, k->hull_rays, h->nodes, h->faces, org, dir, n, 4, out, err);
}

/* The probes of clvr_hull.empty_fraction: 128 rays from each of the 6 axis
 * and 8 diagonal directions, through points spread over the box (a fixed
 * sequence, so the figure is the same on every run). */
enum { PROBE_PER = 128, PROBE_DIRS = 14, PROBE_N = PROBE_PER * PROBE_DIRS };

static void probe_rays(const float lo[3], const float hi[3], float *org, float *dir)
{
    const float ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    const float diag = sqrtf(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]);
    uint64_t state = 0x2545F4914F6CDD1Dull;
    for (uint32_t i = 0; i < PROBE_N; ++i) {
        const uint32_t d = i / PROBE_PER;
        float dv[3] = {0, 0, 0};
        if (d < 6) dv[d / 2] = d % 2 ? -1.0f : 1.0f;
        else {
            const uint32_t b = d - 6;
            for (int c = 0; c < 3; ++c) dv[c] = ((b >> c) & 1u) ? -0.57735027f : 0.57735027f;
        }
        float p[3];
        for (int c = 0; c < 3; ++c) {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            p[c] = lo[c] + ext[c] * (float)((state >> 40) * (1.0 / 16777216.0));
        }
        for (int c = 0; c < 3; ++c) {
            org[4 * i + c] = p[c] - dv[c] * 2.0f * diag;
            dir[4 * i + c] = dv[c];
        }
        org[4 * i + 3] = dir[4 * i + 3] = 0.0f;
    }
}

/* The mean share of each probe ray's chord through the box [lo, hi] that
 * lies outside its interval res (t0, t1, hit: clvr_hull_rays' layout); a
 * ray without a hit counts 1. */
static float probe_fraction(const float lo[3], const float hi[3], const float *org, const float *dir, const float *res)
{
    double sum = 0.0;
    uint32_t counted = 0;
    for (uint32_t i = 0; i < PROBE_N; ++i) {
        /* The chord of the (exact) box. */
        float a = 0.0f, b = INFINITY;
        for (int c = 0; c < 3; ++c) {
            if (dir[4 * i + c] == 0.0f) continue;
            const float inv = 1.0f / dir[4 * i + c];
            const float t0 = (lo[c] - org[4 * i + c]) * inv, t1 = (hi[c] - org[4 * i + c]) * inv;
            a = fmaxf(a, fminf(t0, t1));
            b = fminf(b, fmaxf(t0, t1));
        }
        if (!(b > a)) continue;
        ++counted;
        if (res[4 * i + 2] == 0.0f) {
            sum += 1.0;
            continue;
        }
        const double cut = (double)fmaxf(res[4 * i] - a, 0.0f) + (double)fmaxf(b - res[4 * i + 1], 0.0f);
        sum += fmin(cut / (b - a), 1.0);
    }
    return counted ? (float)(sum / counted) : 0.0f;
}

/* The probe's rays through the hull h (tree = NULL) or through the boxes
 * under a single-level tree (clvr_bvh_ray_span): *fraction. */
static clvr_status probe(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_hull *h, cl_mem tree, const float lo[3],
                         const float hi[3], float *fraction, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    float *org = malloc(PROBE_N * 16), *dir = malloc(PROBE_N * 16), *res = malloc(PROBE_N * 16);
    if (!org || !dir || !res) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "hull: out of host memory for the probe");
        goto cleanup;
    }
    probe_rays(lo, hi, org, dir);
    if (tree) CLVR_TRY(rays_through(cl, k->ray_span, tree, NULL, org, dir, PROBE_N, 4, res, err));
    else CLVR_TRY(clvr_hull_rays(cl, k, h, org, dir, PROBE_N, res, err));
    *fraction = probe_fraction(lo, hi, org, dir, res);
cleanup:
    free(org);
    free(dir);
    free(res);
    return s;
}

/* The first steps of both the hull's and the adjacency's builds: the key
 * of every face slot of c (layout ffb on the device), sorted with its slot
 * into fs->keys, fs->vals; fs->keys_tmp, fs->vals_tmp are the sort's
 * spares, left to the caller (24 bytes per face slot in all). The caller
 * releases the four (face_sort_release), also after an error. */
typedef struct face_sort {
    cl_mem keys, vals, keys_tmp, vals_tmp;
} face_sort;

static void face_sort_release(clvr_cl *cl, face_sort *fs)
{
    clvr_cl_release(cl, &fs->keys);
    clvr_cl_release(cl, &fs->keys_tmp);
    clvr_cl_release(cl, &fs->vals);
    clvr_cl_release(cl, &fs->vals_tmp);
}

static clvr_status sorted_faces(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_clustered *c, clvr_pp *pp,
                                cl_mem ffb, cl_uint ninst, cl_uint nslots, face_sort *fs, double *build_s,
                                clvr_error *err)
{
    clvr_status s = CLVR_OK;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nslots * 8, NULL, "face keys", &fs->keys, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nslots * 8, NULL, "face keys", &fs->keys_tmp, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nslots * 4, NULL, "face slots", &fs->vals, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nslots * 4, NULL, "face slots", &fs->vals_tmp, err));
    clvr_clustered_pieces pc;
    clvr_clustered_get_pieces(c, &pc);
    CLVR_TRY(CLVR_CL_ARGS(k->hull_keys, err, CLVR_ARG(c->instances), CLVR_ARG(ninst), CLVR_ARG(ffb), CLVR_ARG(nslots),
                          CLVR_ARG(fs->keys), PIECE_ARGS(pc)));
    CLVR_TRY(clvr_pp_launch(pp, k->hull_keys, nslots, 64, build_s, err));
    CLVR_TRY(clvr_pp_sort(pp, &fs->keys, &fs->vals, &fs->keys_tmp, &fs->vals_tmp, nslots, 1, 0xffffffffull, build_s,
                          err));
cleanup:
    return s;
}

clvr_status clvr_hull_build(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_clustered *c, cl_mem cluster_tree,
                            int mode, clvr_hull *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    memset(out, 0, sizeof *out);
    uint32_t *ff = NULL;
    cl_mem ffb = NULL, boxes = NULL;
    face_sort fs = {0};
    clvr_pp pp;
    int pp_made = 0;
    out->box_fraction = -1.0f;
    if (c->num_instances == 0 || mode == CLVR_HULL_OFF) return CLVR_OK;
    /* The box the renderer clips rays to (render.c: the mesh's bounds). */
    const float *lo = c->bounds.lo, *hi = c->bounds.hi;
    if (mode == CLVR_HULL_AUTO && cluster_tree) {
        /* The clusters' boxes contain the mesh, so their empty fraction is at
         * most the hull's: a mesh that fills its box shows it here already,
         * for a few thousand box-tree walks instead of the whole build. */
        CLVR_TRY(probe(cl, k, NULL, cluster_tree, lo, hi, &out->box_fraction, err));
        if (out->box_fraction < CLVR_HULL_MIN_BOX_EMPTY) {
            out->empty_fraction = out->box_fraction;
            out->boxes_only = 1;
            return CLVR_OK;
        }
    }
    ff = malloc((size_t)(c->num_instances + 1) * sizeof *ff);
    if (!ff) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "hull: out of host memory for the face layout");
    CLVR_TRY(clvr_hull_face_first(c->host_instances, c->num_instances, ff, err));
    const cl_uint ninst = (cl_uint)c->num_instances, nslots = ff[c->num_instances];
    out->num_slots = nslots;
    if (nslots == 0) goto cleanup;
    {
        /* The build's transient buffers: keys and slots, twice over for the
         * sort (24 bytes per face slot), then faces and boxes (96 bytes per
         * boundary face, counted here as if a tenth of the slots were). 4 to 6
         * slots per element make this 100-170 bytes per element, several
         * times what the renderer keeps per element (docs/large-meshes.md),
         * so on a large mesh it may not fit where the mesh does: then no hull
         * (CLVR_HULL_AUTO renders without it) rather than a build that runs
         * the device, or on a CPU device the host, out of memory. Half of
         * what is free is the most it takes. Its keys are also one buffer
         * larger than any array of the clustered mesh (32 bytes or more per
         * element), so a mesh split into pieces below the device's largest
         * allocation (docs/large-meshes.md) fails here or in that buffer's
         * allocation and renders without the cut too. */
        const uint64_t need = (uint64_t)nslots * 24u + (uint64_t)nslots / 10u * 96u;
        uint64_t room = cl->global_mem_bytes > cl->allocated_bytes ? cl->global_mem_bytes - cl->allocated_bytes : 0;
        if (cl->device_type & CL_DEVICE_TYPE_CPU) {
            clvr_mem_limits ml;
            clvr_mem_limits_read(&ml);
            if (ml.limit < room) room = ml.limit;
        }
        if (need > room / 2) {
            s = clvr_error_set(err, CLVR_ERR_DEVICE_MEMORY,
                               "hull: the boundary faces' build needs %.1f MB for %u face slots, more than half of the "
                               "%.1f MB free on %s; the mesh renders without cutting rays to its boundary",
                               (double)need / 1e6, (unsigned)nslots, (double)room / 1e6, cl->device_name);
            goto cleanup;
        }
    }
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)(ninst + 1) * 4, ff,
                            "hull face layout", &ffb, err));
    clvr_clustered_pieces pc;
    clvr_clustered_get_pieces(c, &pc);
    CLVR_TRY(clvr_pp_create(cl, &pp, err));
    pp_made = 1;
    CLVR_TRY(sorted_faces(cl, k, c, &pp, ffb, ninst, nslots, &fs, &out->build_s, err));
    cl_mem keys = fs.keys, vals = fs.vals;
    /* The sort's spare buffers hold the flags (slot order) and the
     * selected slots. */
    cl_mem flags = fs.vals_tmp, sel = fs.keys_tmp;
    CLVR_TRY(CLVR_CL_ARGS(k->hull_flags, err, CLVR_ARG(c->instances), CLVR_ARG(ninst), CLVR_ARG(ffb),
                          CLVR_ARG(nslots), CLVR_ARG(keys), CLVR_ARG(vals), CLVR_ARG(flags), PIECE_ARGS(pc)));
    CLVR_TRY(clvr_pp_launch(&pp, k->hull_flags, nslots, 64, &out->build_s, err));
    uint32_t nb = 0;
    CLVR_TRY(clvr_pp_select(&pp, flags, NULL, sel, nslots, &nb, &out->build_s, err));
    clvr_cl_release(cl, &fs.keys);
    clvr_cl_release(cl, &fs.vals);
    clvr_cl_release(cl, &fs.vals_tmp);
    if (nb == 0) goto cleanup;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nb * sizeof(clvr_hull_face), NULL, "hull faces",
                            &out->faces, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nb * 32, NULL, "hull face boxes", &boxes, err));
    const cl_uint ncl = nb;
    CLVR_TRY(CLVR_CL_ARGS(k->hull_faces, err, CLVR_ARG(c->instances), CLVR_ARG(ninst), CLVR_ARG(ffb), CLVR_ARG(sel),
                          CLVR_ARG(ncl), CLVR_ARG(out->faces), CLVR_ARG(boxes), PIECE_ARGS(pc)));
    CLVR_TRY(clvr_pp_launch(&pp, k->hull_faces, nb, 64, &out->build_s, err));
    CLVR_TRY(clvr_bvh_build_boxes_device(cl, k, boxes, nb, &out->nodes, err));
    out->num_faces = nb;
    out->num_nodes = clvr_bvh_nodes_bound(nb);
    CLVR_TRY(probe(cl, k, out, NULL, lo, hi, &out->empty_fraction, err));
    out->kept = mode == CLVR_HULL_ON || out->empty_fraction >= CLVR_HULL_MIN_EMPTY;
    if (!out->kept) {
        clvr_cl_release(cl, &out->faces);
        clvr_cl_release(cl, &out->nodes);
    }
cleanup:
    if (pp_made) clvr_pp_destroy(&pp);
    clvr_cl_release(cl, &ffb);
    face_sort_release(cl, &fs);
    clvr_cl_release(cl, &boxes);
    free(ff);
    if (s != CLVR_OK) clvr_hull_release(cl, out);
    return s;
}

clvr_status clvr_adjacency_build(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_clustered *c, clvr_adjacency *out,
                                 clvr_error *err)
{
    clvr_status s = CLVR_OK;
    memset(out, 0, sizeof *out);
    uint32_t *ff = NULL;
    face_sort fs = {0};
    clvr_pp pp;
    int pp_made = 0;
    if (c->num_instances == 0) return CLVR_OK;
    ff = malloc((size_t)(c->num_instances + 1) * sizeof *ff);
    if (!ff) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "face adjacency: out of host memory for the face layout");
    CLVR_TRY(clvr_hull_face_first(c->host_instances, c->num_instances, ff, err));
    const cl_uint ninst = (cl_uint)c->num_instances, nslots = ff[c->num_instances];
    if (nslots == 0) goto cleanup;
    /* The hull's keys and sort (sorted_faces: 24 bytes per face slot while
     * it runs); kept: 4 bytes per face slot. */
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)(ninst + 1) * 4, ff,
                            "face adjacency layout", &out->face_first, err));
    clvr_clustered_pieces pc;
    clvr_clustered_get_pieces(c, &pc);
    CLVR_TRY(clvr_pp_create(cl, &pp, err));
    pp_made = 1;
    CLVR_TRY(sorted_faces(cl, k, c, &pp, out->face_first, ninst, nslots, &fs, &out->build_s, err));
    clvr_cl_release(cl, &fs.keys_tmp);
    clvr_cl_release(cl, &fs.vals_tmp);
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nslots * 4, NULL, "face adjacency", &out->adj, err));
    CLVR_TRY(CLVR_CL_ARGS(k->hull_adjacency, err, CLVR_ARG(c->instances), CLVR_ARG(ninst), CLVR_ARG(out->face_first),
                          CLVR_ARG(nslots), CLVR_ARG(fs.keys), CLVR_ARG(fs.vals), CLVR_ARG(out->adj), PIECE_ARGS(pc)));
    CLVR_TRY(clvr_pp_launch(&pp, k->hull_adjacency, nslots, 64, &out->build_s, err));
    out->num_slots = nslots;
    out->bytes = (uint64_t)nslots * 4u + (uint64_t)(ninst + 1) * 4u;
cleanup:
    if (pp_made) clvr_pp_destroy(&pp);
    face_sort_release(cl, &fs);
    free(ff);
    if (s != CLVR_OK) clvr_adjacency_release(cl, out);
    return s;
}

void clvr_adjacency_release(clvr_cl *cl, clvr_adjacency *a)
{
    if (!a) return;
    clvr_cl_release(cl, &a->adj);
    clvr_cl_release(cl, &a->face_first);
    memset(a, 0, sizeof *a);
}

typedef struct key_slot {
    uint64_t key;
    uint32_t slot;
} key_slot;

static int by_key_then_slot(const void *a, const void *b)
{
    const key_slot *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->slot < y->slot ? -1 : x->slot > y->slot;
}

clvr_status clvr_hull_sorted_slots_ref(const clvr_clustered_host *h, uint64_t num_instances, uint32_t key_bits,
                                      uint32_t *face_first, uint64_t **keys, uint32_t **slots, uint32_t *n,
                                      clvr_error *err)
{
    clvr_status s = CLVR_OK;
    *keys = NULL;
    *slots = NULL;
    *n = 0;
    key_slot *ks = NULL;
    CLVR_TRY(clvr_hull_face_first(h->instances, num_instances, face_first, err));
    const uint32_t ns = face_first[num_instances];
    const clvr_mesh_view m = {NULL, NULL, h->instances, (const clvr_vec4 *)h->vertices, h->idx16, h->idx32, 0, 0,
                              NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
    ks = malloc((size_t)ns * sizeof *ks + 1);
    *keys = malloc((size_t)ns * sizeof **keys + 1);
    *slots = malloc((size_t)ns * sizeof **slots + 1);
    if (!ks || !*keys || !*slots) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "hull: out of host memory for %u faces", ns);
        goto cleanup;
    }
    const uint32_t shift = key_bits >= 32u ? 0u : 32u - (key_bits ? key_bits : 1u);
    for (uint32_t i = 0; i < ns; ++i) {
        clvr_hull_face f;
        clvr_hull_slot_load(&m, h->instances, face_first, (uint32_t)num_instances, i, &f);
        ks[i] = (key_slot){clvr_hull_face_key(&f) >> shift, i};
    }
    qsort(ks, ns, sizeof *ks, by_key_then_slot);
    for (uint32_t i = 0; i < ns; ++i) {
        (*keys)[i] = ks[i].key;
        (*slots)[i] = ks[i].slot;
    }
    *n = ns;
cleanup:
    if (s != CLVR_OK) {
        free(*keys);
        free(*slots);
        *keys = NULL;
        *slots = NULL;
    }
    free(ks);
    return s;
}

clvr_status clvr_hull_build_ref(const clvr_clustered_host *h, uint64_t num_instances, clvr_hull_face **faces,
                                float **boxes, uint32_t *num_faces, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    *faces = NULL;
    *boxes = NULL;
    *num_faces = 0;
    uint32_t *ff = malloc((size_t)(num_instances + 1) * sizeof *ff), *flags = NULL, *slots = NULL, n = 0;
    uint64_t *keys = NULL;
    if (!ff) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "hull: out of host memory");
    CLVR_TRY(clvr_hull_sorted_slots_ref(h, num_instances, 32u, ff, &keys, &slots, &n, err));
    const clvr_mesh_view m = {NULL, NULL, h->instances, (const clvr_vec4 *)h->vertices, h->idx16, h->idx32, 0, 0,
                              NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
    flags = malloc((size_t)n * sizeof *flags + 1);
    if (!flags) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "hull: out of host memory for %u faces", n);
        goto cleanup;
    }
    uint32_t nb = 0;
    for (uint32_t i = 0; i < n; ++i) {
        flags[slots[i]] = clvr_hull_boundary(&m, h->instances, ff, (uint32_t)num_instances, n, keys, slots, i);
        nb += flags[slots[i]];
    }
    if (nb > 0) {
        *faces = malloc((size_t)nb * sizeof **faces);
        *boxes = malloc((size_t)nb * 8 * sizeof **boxes);
        if (!*faces || !*boxes) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "hull: out of host memory for %u faces", nb);
            goto cleanup;
        }
        uint32_t k = 0;
        for (uint32_t i = 0; i < n; ++i)
            if (flags[i]) {
                clvr_hull_face_at(&m, h->instances, ff, (uint32_t)num_instances, i, &(*faces)[k], *boxes + 8u * k);
                ++k;
            }
    }
    *num_faces = nb;
cleanup:
    if (s != CLVR_OK) {
        free(*faces);
        free(*boxes);
        *faces = NULL;
        *boxes = NULL;
    }
    free(ff);
    free(keys);
    free(slots);
    free(flags);
    return s;
}
