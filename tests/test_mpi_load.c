/* test_mpi_load.c: clvr_mpi_load_share_bin under mpirun -n K, against a
 * single-process clvr_mesh_load of the same file on every rank.
 *
 * For each mesh (all four element types; a jittered tet lattice; fewer
 * elements than ranks; one element, so most slices are empty; fewer
 * vertices than ranks; version 2 files with vector, scalar and cell
 * fields) and for a large and a tiny exchange chunk (many MPI rounds):
 *   - the regions are what clvr_mpi_regions gives on the deterministic
 *     sample of the whole file's centroids (so identical on all ranks) and
 *     tile the bounds;
 *   - rank r holds exactly the elements whose vertex box overlaps its
 *     region, in file order per type, each with the positions and scalars
 *     of its vertices bit for bit; every element is on at least one rank;
 *   - vertices are deduplicated (as many as the distinct ids used);
 *   - owned counts are the elements whose centroid the rank owns and sum
 *     to the total; bounds and scalar range equal the single process's bit
 *     for bit; each rank read at most about 1/K of the file.
 * Corrupt files (bad magic, truncated, out-of-range index and NaN
 * coordinate in the last rank's slice, missing file, cell field) give the
 * single-process status on every rank, the same message everywhere, naming
 * the file and the rank that saw it.
 *
 * --exit-check DIR: writes a file with a bad index in DIR, loads it and
 * exits with clvr_status_exit_code (tests/test_mpi_load_exit.sh). */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mesh_io.h"
#include "mpi_load.h"
#include "scene.h"
#include "test_util.h"

#define SAMPLE_MAX 65536u

static int g_rank, g_size;

/* Centroid and vertex box exactly as mpi_load.h documents them. */
static void geometry(const clvr_mesh *m, uint32_t t, uint64_t j, float lo[3], float hi[3], float cen[3])
{
    const uint32_t nv = clvr_cell_vertex_count(t);
    const uint32_t *e = m->indices[t] + j * nv;
    for (int k = 0; k < 3; ++k) {
        float a = m->positions[3 * e[0] + k], b = a, sum = a;
        for (uint32_t q = 1; q < nv; ++q) {
            float x = m->positions[3 * e[q] + k];
            a = x < a ? x : a;
            b = x > b ? x : b;
            sum += x;
        }
        float mean = sum / (float)nv;
        lo[k] = a;
        hi[k] = b;
        cen[k] = mean < a ? a : (mean > b ? b : mean);
    }
}

static void write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, n, f) != n) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
    fclose(f);
}

static uint8_t *read_file(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)len + 1);
    *n = fread(b, 1, (size_t)len, f);
    fclose(f);
    return b;
}

/* A version 2 file by hand (docs/bin-format.md): fields "vel" (point, 3
 * components), "p" (point, 1) and "id" (cell, 1), in that order. */
static void write_v2(const char *path, const clvr_mesh *m)
{
    const uint64_t V = m->num_vertices, E = clvr_mesh_num_elements(m);
    size_t idx_words = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) idx_words += (size_t)clvr_mesh_num_indices(m, t);
    size_t n = 256 + 12 * V + 4 * idx_words + 3 * 128 + 4 * (3 * V + V + E);
    uint8_t *b = calloc(1, n), *p = b;
    memcpy(p, "CLVRMESH", 8);
    uint32_t u32;
    u32 = 2;
    memcpy(p + 8, &u32, 4);
    u32 = 256;
    memcpy(p + 12, &u32, 4);
    memcpy(p + 16, &V, 8);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) memcpy(p + 24 + 8 * t, &m->num_cells[t], 8);
    memcpy(p + 88, "vel", 3);
    u32 = 3;
    memcpy(p + 156, &u32, 4);
    p += 256;
    memcpy(p, m->positions, 12 * V);
    p += 12 * V;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        size_t k = (size_t)clvr_mesh_num_indices(m, t) * 4;
        memcpy(p, m->indices[t], k);
        p += k;
    }
    const char *names[3] = {"vel", "p", "id"};
    const uint32_t assoc[3] = {0, 0, 1}, comps[3] = {3, 1, 1};
    for (int f = 0; f < 3; ++f, p += 128) {
        memcpy(p, names[f], strlen(names[f]));
        memcpy(p + 64, &assoc[f], 4);
        memcpy(p + 68, &comps[f], 4);
    }
    float *fv = (float *)p;
    for (uint64_t i = 0; i < V; ++i) {
        fv[3 * i] = m->scalars[i];
        fv[3 * i + 1] = m->positions[3 * i] * 0.37f - 1.0f;
        fv[3 * i + 2] = (float)(i % 7) * 0.1f;
    }
    fv += 3 * V;
    for (uint64_t i = 0; i < V; ++i) fv[i] = m->positions[3 * i + 2] * 3.0f + (float)(i % 5);
    fv += V;
    for (uint64_t e = 0; e < E; ++e) fv[e] = (float)e;
    write_file(path, b, n);
    free(b);
}

/* One loaded share against the single-process mesh ref. */
static void check_share(const char *what, const char *path, const clvr_mesh *ref, const clvr_mpi_share *sh,
                        const clvr_mpi_load_stats *st)
{
    const uint64_t E = clvr_mesh_num_elements(ref);
    TU_CHECK_EQ_U64(sh->global_elements, E);
    TU_CHECK_EQ_U64(sh->global_vertices, ref->num_vertices);
    /* Bounds and scalar range, bit for bit, in the share and (as the
     * renderer reads them) the same on every rank. */
    TU_CHECK(memcmp(sh->bounds_lo, ref->bounds_lo, sizeof ref->bounds_lo) == 0);
    TU_CHECK(memcmp(sh->bounds_hi, ref->bounds_hi, sizeof ref->bounds_hi) == 0);
    TU_CHECK(memcmp(&sh->scalar_min, &ref->scalar_min, sizeof(float)) == 0);
    TU_CHECK(memcmp(&sh->scalar_max, &ref->scalar_max, sizeof(float)) == 0);
    TU_CHECK(strcmp(sh->mesh.scalar_name, ref->scalar_name) == 0);

    /* The regions: every rank's box, gathered, equals clvr_mpi_regions on
     * the whole file's sample (every ceil(E / 65536)-th centroid). */
    float *all = malloc(6u * (size_t)g_size * sizeof(float)), mine[6];
    memcpy(mine, sh->region_lo, 3 * sizeof(float));
    memcpy(mine + 3, sh->region_hi, 3 * sizeof(float));
    MPI_Allgather(mine, 6, MPI_FLOAT, all, 6, MPI_FLOAT, MPI_COMM_WORLD);
    const uint64_t stride = (E + SAMPLE_MAX - 1) / SAMPLE_MAX;
    float *sample = malloc((E / stride + 1) * 3 * sizeof(float)), *want = malloc(6u * (size_t)g_size * sizeof(float));
    uint64_t ns = 0, g = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        for (uint64_t j = 0; j < ref->num_cells[t]; ++j, ++g)
            if (g % stride == 0) {
                float lo[3], hi[3];
                geometry(ref, t, j, lo, hi, sample + 3 * ns++);
            }
    clvr_error err;
    TU_CHECK_STATUS(clvr_mpi_regions(sample, ns, ref->bounds_lo, ref->bounds_hi, (uint32_t)g_size, want, &err),
                    CLVR_OK, &err);
    if (memcmp(all, want, 6u * (size_t)g_size * sizeof(float)) != 0) {
        ++tu_fail_;
        fprintf(stderr, "%s: rank %d: the regions differ from those of the file's sample\n", what, g_rank);
    } else {
        ++tu_pass_;
    }

    /* The elements this rank must hold, in file order per type, compared
     * corner by corner with the share; presence counted over ranks. */
    int *present = calloc(E ? E : 1, sizeof *present), *overlaps = calloc(E ? E : 1, sizeof *overlaps);
    uint8_t *used = calloc(ref->num_vertices ? ref->num_vertices : 1, 1);
    uint64_t owned = 0, distinct = 0, mismatch = 0, count_bad = 0;
    g = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        uint64_t k = 0; /* next share element of type t */
        for (uint64_t j = 0; j < ref->num_cells[t]; ++j, ++g) {
            float lo[3], hi[3], cen[3];
            geometry(ref, t, j, lo, hi, cen);
            for (int d = 0; d < g_size; ++d) overlaps[g] += clvr_mpi_boxes_overlap(lo, hi, all + 6 * d, all + 6 * d + 3);
            if (!clvr_mpi_boxes_overlap(lo, hi, sh->region_lo, sh->region_hi)) continue;
            owned += clvr_mpi_region_of(all, (uint32_t)g_size, cen) == (uint32_t)g_rank;
            present[g] = 1;
            if (k >= sh->mesh.num_cells[t]) {
                ++mismatch;
                continue;
            }
            const uint32_t *a = ref->indices[t] + j * nv, *b = sh->mesh.indices[t] + k * nv;
            for (uint32_t q = 0; q < nv; ++q) {
                if (b[q] >= sh->mesh.num_vertices ||
                    memcmp(ref->positions + 3 * a[q], sh->mesh.positions + 3 * (uint64_t)b[q], 12) != 0 ||
                    memcmp(ref->scalars + a[q], sh->mesh.scalars + b[q], 4) != 0) {
                    ++mismatch;
                    break;
                }
                if (!used[a[q]]) {
                    used[a[q]] = 1;
                    ++distinct;
                }
            }
            ++k;
        }
        if (k != sh->mesh.num_cells[t]) ++count_bad;
    }
    if (mismatch || count_bad)
        fprintf(stderr, "%s: rank %d: %llu elements differ, %llu types with other counts\n", what, g_rank,
                (unsigned long long)mismatch, (unsigned long long)count_bad);
    TU_CHECK_EQ_U64(mismatch, 0);
    TU_CHECK_EQ_U64(count_bad, 0);
    TU_CHECK_EQ_U64(sh->mesh.num_vertices, distinct);
    TU_CHECK_EQ_U64(sh->owned_elements, owned);
    MPI_Allreduce(MPI_IN_PLACE, present, (int)(E ? E : 1), MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    uint64_t wrong = 0;
    for (uint64_t i = 0; i < E; ++i)
        if (present[i] < 1 || present[i] != overlaps[i]) ++wrong;
    TU_CHECK_EQ_U64(wrong, 0);
    uint64_t owned_sum = 0, share_sum = 0, share = clvr_mesh_num_elements(&sh->mesh);
    MPI_Allreduce(&sh->owned_elements, &owned_sum, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(&share, &share_sum, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
    TU_CHECK_EQ_U64(owned_sum, E);
    TU_CHECK_EQ_U64(st->share_elements, share);
    TU_CHECK_EQ_U64(st->ghost_elements, share - sh->owned_elements);
    /* The share's own ranges are of its vertices. */
    clvr_mesh copy = sh->mesh;
    clvr_mesh_update_ranges(&copy);
    TU_CHECK(memcmp(copy.bounds_lo, sh->mesh.bounds_lo, 12) == 0 && memcmp(&copy.scalar_max, &sh->mesh.scalar_max, 4) == 0);

    /* Read only 1/K of the vertices and of the elements: the header, at
     * most ceil(V / K) vertices (position and a tuple of up to 3 floats)
     * and ceil(E / K) elements (at most 8 indices each). Slices are by
     * element count, so a slice of hexes reads more bytes than one of tets. */
    size_t fsz = 0;
    uint8_t *bytes = read_file(path, &fsz);
    free(bytes);
    uint64_t maxread = 0;
    const uint64_t K = (uint64_t)g_size;
    MPI_Allreduce(&st->slice_bytes, &maxread, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
    TU_CHECK(maxread <= 256 + (ref->num_vertices + K - 1) / K * 24 + (E + K - 1) / K * 32);
    /* Reads stay inside those regions: the vertex slice once, the element
     * slice at most three times (sample, count pass, send pass). */
    TU_CHECK(st->bytes_read <= 3 * st->slice_bytes);
    TU_CHECK(st->bytes_read >= st->slice_bytes);
    TU_CHECK_EQ_U64(st->slice_elements, E / K + ((uint64_t)g_rank < E % K));
    TU_CHECK_EQ_U64(st->slice_vertices, ref->num_vertices / K + ((uint64_t)g_rank < ref->num_vertices % K));
    if (g_rank == 0)
        printf("%-28s K=%d E=%-6llu sample %-5llu rounds %-4llu ghosts %5.1f%% of E, max read %llu of %zu bytes\n",
               what, g_size, (unsigned long long)E, (unsigned long long)st->sample,
               (unsigned long long)st->exchange_rounds, 100.0 * (double)(share_sum - E) / (double)E,
               (unsigned long long)maxread, fsz);
    free(all);
    free(sample);
    free(want);
    free(present);
    free(overlaps);
    free(used);
}

static void check_file(const char *what, const char *path, const char *spec, int tiny_chunks)
{
    clvr_load_options lo;
    memset(&lo, 0, sizeof lo);
    lo.scalar_name = spec;
    clvr_mesh ref;
    clvr_error err;
    TU_CHECK_STATUS(clvr_mesh_load(path, &lo, &ref, &err), CLVR_OK, &err);
    /* Default rounds; 40 bytes (one element per piece, every exchange in
     * rounds through scratch); 4000 bytes (pieces of 111 / K elements). */
    const uint64_t chunks[3] = {0, 40, 4000};
    for (int c = 0; c < (tiny_chunks ? 3 : 1); ++c) {
        clvr_mpi_share sh;
        clvr_mpi_load_stats st;
        clvr_status s = clvr_mpi_load_share_bin_ex(MPI_COMM_WORLD, path, &lo, chunks[c], &sh, &st, &err);
        TU_CHECK_STATUS(s, CLVR_OK, &err);
        if (s == CLVR_OK) {
            char label[128];
            snprintf(label, sizeof label, "%s%s", what, c == 1 ? " (40 B rounds)" : c == 2 ? " (4000 B rounds)" : "");
            check_share(label, path, &ref, &sh, &st);
        }
        clvr_mpi_share_free(&sh);
    }
    clvr_mesh_free(&ref);
}

/* Every rank gets the single-process status, one message, naming the file
 * and (when given) the rank that saw it. */
static void check_bad(const char *what, const char *path, const char *spec, clvr_status want, int want_rank,
                      clvr_status single)
{
    clvr_load_options lo;
    memset(&lo, 0, sizeof lo);
    lo.scalar_name = spec;
    clvr_mesh ref;
    clvr_error e1, e2;
    memset(&e2, 0, sizeof e2);
    clvr_status s1 = clvr_mesh_load(path, &lo, &ref, &e1);
    TU_CHECK_STATUS(s1, single, &e1);
    if (s1 == CLVR_OK) clvr_mesh_free(&ref);
    clvr_mpi_share sh;
    clvr_status s = clvr_mpi_load_share_bin(MPI_COMM_WORLD, path, &lo, &sh, &e2);
    TU_CHECK_STATUS(s, want, &e2);
    TU_CHECK(sh.mesh.positions == NULL && clvr_mesh_num_elements(&sh.mesh) == 0);
    char *msgs = malloc((size_t)g_size * sizeof e2.msg);
    MPI_Allgather(e2.msg, (int)sizeof e2.msg, MPI_CHAR, msgs, (int)sizeof e2.msg, MPI_CHAR, MPI_COMM_WORLD);
    int same = 1;
    for (int r = 1; r < g_size; ++r)
        if (strcmp(msgs, msgs + (size_t)r * sizeof e2.msg) != 0) same = 0;
    TU_CHECK(same);
    TU_CHECK(strstr(e2.msg, path) != NULL);
    if (want_rank >= 0) {
        char tag[32];
        snprintf(tag, sizeof tag, "rank %d of %d", want_rank, g_size);
        TU_CHECK(strncmp(e2.msg, tag, strlen(tag)) == 0);
    }
    if (g_rank == 0) printf("%-28s K=%d -> %s: %s\n", what, g_size, clvr_status_name(s), e2.msg);
    free(msgs);
}

static void save(const char *path, clvr_mesh *m)
{
    clvr_error err;
    if (g_rank == 0) TU_CHECK_STATUS(clvr_mesh_save_bin(path, m, &err), CLVR_OK, &err);
    MPI_Barrier(MPI_COMM_WORLD);
}

/* A mesh from index lists given by hand (vertices on a jittered line). */
static void small_mesh(clvr_mesh *m, uint64_t nv, uint32_t t, const uint32_t *idx, uint64_t nc)
{
    uint64_t cells[CLVR_CELL_TYPE_COUNT] = {0};
    cells[t] = nc;
    clvr_error err;
    if (clvr_mesh_alloc(m, nv, cells, &err) != CLVR_OK) exit(1);
    for (uint64_t i = 0; i < nv; ++i) {
        m->positions[3 * i] = (float)(i & 1);
        m->positions[3 * i + 1] = (float)((i >> 1) & 1);
        m->positions[3 * i + 2] = (float)(i >> 2) + 0.25f * (float)i;
        m->scalars[i] = (float)i - 1.5f;
    }
    memcpy(m->indices[t], idx, (size_t)nc * clvr_cell_vertex_count(t) * sizeof *idx);
    clvr_mesh_update_ranges(m);
}

static int exit_check(const char *dir)
{
    char path[512];
    snprintf(path, sizeof path, "%s/exit-check-bad-index.bin", dir);
    clvr_scene_box_params p;
    clvr_scene_box_params_init(&p);
    p.nx = 4;
    p.ny = p.nz = 3;
    p.mix = CLVR_SCENE_MIX_TET;
    clvr_mesh m;
    clvr_error err;
    if (clvr_scene_box(&p, &m, &err) != CLVR_OK) return 1;
    m.indices[CLVR_CELL_TET][4 * m.num_cells[CLVR_CELL_TET] - 1] = (uint32_t)m.num_vertices + 3;
    if (g_rank == 0 && clvr_mesh_save_bin(path, &m, &err) != CLVR_OK) return 1;
    clvr_mesh_free(&m);
    MPI_Barrier(MPI_COMM_WORLD);
    clvr_mpi_share sh;
    clvr_status s = clvr_mpi_load_share_bin(MPI_COMM_WORLD, path, NULL, &sh, &err);
    if (s == CLVR_OK) {
        if (g_rank == 0) printf("loaded: no error\n");
        clvr_mpi_share_free(&sh);
        return 0;
    }
    if (g_rank == 0) fprintf(stderr, "clvr: %s\n", err.msg);
    return clvr_status_exit_code(s);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
    if (argc == 3 && !strcmp(argv[1], "--exit-check")) {
        int code = exit_check(argv[2]);
        MPI_Finalize();
        return code;
    }
    char dir[256] = "";
    if (g_rank == 0) {
        snprintf(dir, sizeof dir, "/tmp/clvr-test-mpi-load-XXXXXX");
        if (!mkdtemp(dir)) {
            fprintf(stderr, "cannot create a temporary directory\n");
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
    }
    MPI_Bcast(dir, sizeof dir, MPI_CHAR, 0, MPI_COMM_WORLD);
    char path[512], bad[512];
    clvr_error err;

    /* Every type next to every other, blobs field. */
    clvr_scene_box_params p;
    clvr_scene_box_params_init(&p);
    p.nx = 5;
    p.ny = 4;
    p.nz = 3;
    p.mix = CLVR_SCENE_MIX_CYCLE;
    p.field = CLVR_SCENE_FIELD_BLOBS;
    clvr_mesh cyc;
    TU_CHECK_STATUS(clvr_scene_box(&p, &cyc, &err), CLVR_OK, &err);
    snprintf(path, sizeof path, "%s/cycle.bin", dir);
    save(path, &cyc);
    check_file("four types", path, NULL, 1);
    check_file("four types, by name", path, cyc.scalar_name, 1);

    /* Jittered tets: centroids off the lattice, ties rare. */
    clvr_scene_box_params_init(&p);
    p.nx = 9;
    p.ny = 7;
    p.nz = 6;
    p.mix = CLVR_SCENE_MIX_TET;
    p.field = CLVR_SCENE_FIELD_RAMP_X;
    p.jitter = 0.2f;
    p.seed = 7;
    clvr_mesh tets;
    TU_CHECK_STATUS(clvr_scene_box(&p, &tets, &err), CLVR_OK, &err);
    snprintf(path, sizeof path, "%s/tets.bin", dir);
    save(path, &tets);
    check_file("jittered tets", path, NULL, 1);

    /* More elements than the sample holds: every ceil(E / 65536)-th
     * centroid (stride 2 here), from every rank's slice. */
    clvr_scene_box_params_init(&p);
    p.nx = 23;
    p.ny = 23;
    p.nz = 23;
    p.mix = CLVR_SCENE_MIX_TET;
    p.field = CLVR_SCENE_FIELD_BLOBS;
    p.jitter = 0.15f;
    p.seed = 3;
    clvr_mesh big;
    TU_CHECK_STATUS(clvr_scene_box(&p, &big, &err), CLVR_OK, &err);
    snprintf(path, sizeof path, "%s/big.bin", dir);
    save(path, &big);
    check_file("73k tets, sampled", path, NULL, 0);
    /* A bad index in an element the sample skips (odd id, stride 2): only
     * the pass that reads every piece can see it. */
    TU_CHECK(big.num_cells[CLVR_CELL_TET] % 2 == 0);
    big.indices[CLVR_CELL_TET][4 * (big.num_cells[CLVR_CELL_TET] - 1) + 2] = (uint32_t)big.num_vertices + 1;
    snprintf(bad, sizeof bad, "%s/bad.bin", dir);
    save(bad, &big);
    clvr_mesh_free(&big);
    check_bad("bad index, not sampled", bad, NULL, CLVR_ERR_BAD_INDEX, g_size - 1, CLVR_ERR_BAD_INDEX);

    /* Mixed (the default scene's mix) at 12^3 cubes. */
    clvr_scene_box_params_init(&p);
    p.nx = p.ny = p.nz = 12;
    p.mix = CLVR_SCENE_MIX_MIXED;
    p.field = CLVR_SCENE_FIELD_BLOBS;
    clvr_mesh mixed;
    TU_CHECK_STATUS(clvr_scene_box(&p, &mixed, &err), CLVR_OK, &err);
    snprintf(path, sizeof path, "%s/mixed.bin", dir);
    save(path, &mixed);
    check_file("mixed", path, NULL, 1);
    clvr_mesh_free(&mixed);

    /* Fewer elements than ranks (2 tets), one element (most slices
     * empty), fewer vertices than ranks (a degenerate tet on 3). */
    clvr_mesh small;
    const uint32_t two[8] = {0, 1, 2, 3, 1, 2, 3, 4};
    small_mesh(&small, 5, CLVR_CELL_TET, two, 2);
    snprintf(path, sizeof path, "%s/two.bin", dir);
    save(path, &small);
    check_file("two tets", path, NULL, 1);
    clvr_mesh_free(&small);
    /* Signed zeros: +0 first in file order, -0 in the last rank's slice.
     * One scan keeps the first of equal minima (+0); a reduction that
     * combined the slices in another order would give -0. */
    small_mesh(&small, 5, CLVR_CELL_TET, two, 2);
    small.positions[0] = 0.0f;
    small.positions[3 * 4] = -0.0f;
    for (uint64_t i = 0; i < 5; ++i) small.scalars[i] = i == 4 ? -0.0f : (i == 0 ? 0.0f : (float)i);
    clvr_mesh_update_ranges(&small);
    TU_CHECK(!signbit(small.bounds_lo[0]) && !signbit(small.scalar_min));
    snprintf(path, sizeof path, "%s/zeros.bin", dir);
    save(path, &small);
    check_file("signed zeros", path, NULL, 1);
    clvr_mesh_free(&small);
    const uint32_t hex[8] = {0, 1, 3, 2, 4, 5, 7, 6};
    small_mesh(&small, 8, CLVR_CELL_HEX, hex, 1);
    snprintf(path, sizeof path, "%s/one.bin", dir);
    save(path, &small);
    check_file("one hex", path, NULL, 1);
    clvr_mesh_free(&small);
    const uint32_t degen[4] = {0, 1, 2, 2};
    small_mesh(&small, 3, CLVR_CELL_TET, degen, 1);
    snprintf(path, sizeof path, "%s/three.bin", dir);
    save(path, &small);
    check_file("3 vertices", path, NULL, 1);
    clvr_mesh_free(&small);

    /* A flat hex whose 8 equal x coordinates (1.00000072f) have a float
     * mean one ulp above them (1.00000083f): its centroid must be clamped
     * into its box, or the median split through it leaves the element's
     * owner without the element (or the regions differ from the test's). */
    {
        uint64_t cells[CLVR_CELL_TYPE_COUNT] = {0, 0, 0, 3};
        clvr_mesh flat;
        TU_CHECK_STATUS(clvr_mesh_alloc(&flat, 24, cells, &err), CLVR_OK, &err);
        uint32_t xbits = 0x3f800006u;
        float x0;
        memcpy(&x0, &xbits, sizeof x0);
        const float xs[3][2] = {{0.0f, 0.5f}, {x0, x0}, {2.0f, 3.0f}};
        for (uint32_t h = 0; h < 3; ++h)
            for (uint32_t q = 0; q < 8; ++q) {
                const uint32_t v = 8 * h + q;
                /* VTK hex order: bottom face 0-3 counter-clockwise, top 4-7. */
                const int bx = (q == 1 || q == 2 || q == 5 || q == 6), by = (q == 2 || q == 3 || q == 6 || q == 7);
                flat.positions[3 * v] = xs[h][bx];
                flat.positions[3 * v + 1] = 0.1f * (float)by;
                flat.positions[3 * v + 2] = 0.1f * (float)(q >= 4);
                flat.scalars[v] = (float)v;
                flat.indices[CLVR_CELL_HEX][v] = v;
            }
        clvr_mesh_update_ranges(&flat);
        volatile float sum = x0;
        for (int k = 1; k < 8; ++k) sum = sum + x0;
        TU_CHECK(sum / 8.0f > x0); /* the case this mesh is for */
        snprintf(path, sizeof path, "%s/flat.bin", dir);
        save(path, &flat);
        clvr_mesh_free(&flat);
        check_file("flat hex, rounding centroid", path, NULL, 1);
    }

    /* Version 2: a vector's magnitude (default), a scalar, a component. */
    snprintf(path, sizeof path, "%s/v2.bin", dir);
    if (g_rank == 0) write_v2(path, &cyc);
    MPI_Barrier(MPI_COMM_WORLD);
    check_file("v2 vel magnitude", path, NULL, 1);
    check_file("v2 p", path, "p", 1);
    check_file("v2 vel:y", path, "vel:y", 1);
    check_bad("v2 cell field", path, "cell:id", CLVR_ERR_BAD_FIELD, 0, CLVR_OK);
    check_bad("v2 no such field", path, "nope", CLVR_ERR_BAD_FIELD, 0, CLVR_ERR_BAD_FIELD);

    /* Corrupt copies of the four-type file. The bad index and the NaN sit
     * in the last rank's slice: only that rank can see them. */
    snprintf(path, sizeof path, "%s/cycle.bin", dir);
    size_t n = 0;
    uint8_t *good = read_file(path, &n);
    snprintf(bad, sizeof bad, "%s/bad.bin", dir);
    const uint64_t V = cyc.num_vertices;
    if (g_rank == 0) {
        uint8_t *b = malloc(n);
        memcpy(b, good, n);
        b[0] = 'X';
        write_file(bad, b, n);
        free(b);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    check_bad("bad magic", bad, NULL, CLVR_ERR_BAD_MAGIC, 0, CLVR_ERR_BAD_MAGIC);
    if (g_rank == 0) write_file(bad, good, n - 100);
    MPI_Barrier(MPI_COMM_WORLD);
    check_bad("truncated", bad, NULL, CLVR_ERR_TRUNCATED, 0, CLVR_ERR_TRUNCATED);
    if (g_rank == 0) {
        uint8_t *b = malloc(n);
        memcpy(b, good, n);
        uint32_t far = (uint32_t)V + 7; /* the last hex's last corner: the end of the file */
        memcpy(b + n - 4, &far, 4);
        write_file(bad, b, n);
        free(b);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    check_bad("out-of-range index", bad, NULL, CLVR_ERR_BAD_INDEX, g_size - 1, CLVR_ERR_BAD_INDEX);
    if (g_rank == 0) {
        uint8_t *b = malloc(n);
        memcpy(b, good, n);
        float nan = NAN;
        memcpy(b + 256 + 12 * (V - 1) + 4, &nan, 4); /* the last vertex's y */
        write_file(bad, b, n);
        free(b);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    check_bad("NaN coordinate", bad, NULL, CLVR_ERR_BAD_VALUE, g_size - 1, CLVR_ERR_BAD_VALUE);
    snprintf(bad, sizeof bad, "%s/missing.bin", dir);
    check_bad("missing file", bad, NULL, CLVR_ERR_IO, 0, CLVR_ERR_IO);
    /* An empty mesh: the header alone. */
    if (g_rank == 0) {
        clvr_mesh empty;
        uint64_t zero[CLVR_CELL_TYPE_COUNT] = {0};
        clvr_mesh_alloc(&empty, 0, zero, &err);
        snprintf(bad, sizeof bad, "%s/empty.bin", dir);
        clvr_mesh_save_bin(bad, &empty, &err);
        clvr_mesh_free(&empty);
    }
    snprintf(bad, sizeof bad, "%s/empty.bin", dir);
    MPI_Barrier(MPI_COMM_WORLD);
    check_bad("no elements", bad, NULL, CLVR_ERR_EMPTY, 0, CLVR_ERR_EMPTY);
    free(good);
    clvr_mesh_free(&cyc);
    clvr_mesh_free(&tets);

    /* Every rank's verdict, then clean up. */
    int fails = tu_fail_, total = 0;
    MPI_Allreduce(&fails, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    MPI_Barrier(MPI_COMM_WORLD);
    if (g_rank == 0) {
        const char *names[] = {"cycle.bin", "tets.bin", "mixed.bin", "two.bin", "one.bin", "three.bin", "v2.bin",
                               "bad.bin", "empty.bin", "big.bin", "zeros.bin", "flat.bin"};
        for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
            snprintf(path, sizeof path, "%s/%s", dir, names[i]);
            unlink(path);
        }
        rmdir(dir);
    }
    if (total && !tu_fail_) tu_fail_ = 1; /* another rank failed: so does this one */
    int code = g_rank == 0 || tu_fail_ ? tu_finish("test_mpi_load") : 0;
    if (g_rank != 0 && !tu_fail_) code = 0;
    MPI_Finalize();
    return code;
}
