/* test_api_scene.c: libclvr's API 1.1 through clvr.h alone (linked against
 * the shared library). Proves:
 *  - a file's fields are all listed (legacy VTK with two scalars and a
 *    vector), another field is read when a scene names it, and renders the
 *    same pixels as a dataset built from arrays with that field's values,
 *    while the file's first field renders other pixels (so a scene that
 *    ignored the name would fail);
 *  - preprocessing is its own call (clvr_scene_create) whose cluster sizes
 *    reach the clusters (leaf_size 8 -> leaves of 8), timed, with the
 *    trees' stage last; two tracers share a scene and, with the same
 *    settings and seed, render the same pixels; another method differs;
 *  - every render setting round-trips through get/set, a bad one is
 *    refused naming the member and changes nothing; a struct with a short
 *    size is refused;
 *  - render statistics count the frames, clvr_tracer_set_size resizes, the
 *    transfer function can be read, edited and made apart from a tracer;
 *  - CLVR_BORROW keeps the caller's array (clvr_dataset_get_array) and
 *    CLVR_COPY does not; the caller's arrays are left unchanged.
 * Exit 77 (skipped) without an OpenCL device. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <stddef.h>
#include <string.h>
#include <unistd.h>

#include "clvr.h"
#include "api_check.h"


#define N 7 /* points per axis: 6^3 hexahedra */
#define W 24
#define H 20
#define SPP 4

static clvr_message msg;

typedef struct grid {
    float xyz[N * N * N * 3];
    float a[N * N * N], b[N * N * N];
    float v[N * N * N * 3];
    uint32_t hex[(N - 1) * (N - 1) * (N - 1) * 8];
} grid;

static void make_grid(grid *g)
{
    uint32_t p = 0, c = 0;
    for (int k = 0; k < N; ++k)
        for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i, ++p) {
                const float x = (float)i / (N - 1), y = (float)j / (N - 1), z = (float)k / (N - 1);
                g->xyz[3 * p] = x;
                g->xyz[3 * p + 1] = y;
                g->xyz[3 * p + 2] = z;
                g->a[p] = x;                        /* a ramp along x */
                g->b[p] = 4.0f * (y - 0.5f) * (y - 0.5f); /* a valley along y: another image */
                g->v[3 * p] = z;
                g->v[3 * p + 1] = 0.5f;
                g->v[3 * p + 2] = -x;
            }
#define ID(i, j, k) ((uint32_t)((k) * N * N + (j) * N + (i)))
    for (int k = 0; k + 1 < N; ++k)
        for (int j = 0; j + 1 < N; ++j)
            for (int i = 0; i + 1 < N; ++i) {
                const uint32_t h[8] = {ID(i, j, k),         ID(i + 1, j, k),         ID(i + 1, j + 1, k),
                                       ID(i, j + 1, k),     ID(i, j, k + 1),         ID(i + 1, j, k + 1),
                                       ID(i + 1, j + 1, k + 1), ID(i, j + 1, k + 1)};
                memcpy(g->hex + 8 * c++, h, sizeof h);
            }
}

/* The grid as a legacy VTK file with fields a, b and the vector v. */
static int write_vtk(const grid *g, const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f) return 1;
    const int np = N * N * N, nc = (N - 1) * (N - 1) * (N - 1);
    fprintf(f, "# vtk DataFile Version 3.0\ngrid\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS %d float\n", np);
    for (int p = 0; p < np; ++p) fprintf(f, "%.9g %.9g %.9g\n", g->xyz[3 * p], g->xyz[3 * p + 1], g->xyz[3 * p + 2]);
    fprintf(f, "CELLS %d %d\n", nc, nc * 9);
    for (int c = 0; c < nc; ++c) {
        fprintf(f, "8");
        for (int k = 0; k < 8; ++k) fprintf(f, " %u", g->hex[8 * c + k]);
        fprintf(f, "\n");
    }
    fprintf(f, "CELL_TYPES %d\n", nc);
    for (int c = 0; c < nc; ++c) fprintf(f, "12\n");
    fprintf(f, "POINT_DATA %d\nSCALARS a float\nLOOKUP_TABLE default\n", np);
    for (int p = 0; p < np; ++p) fprintf(f, "%.9g\n", g->a[p]);
    fprintf(f, "SCALARS b float\nLOOKUP_TABLE default\n");
    for (int p = 0; p < np; ++p) fprintf(f, "%.9g\n", g->b[p]);
    fprintf(f, "VECTORS v float\n");
    for (int p = 0; p < np; ++p) fprintf(f, "%.9g %.9g %.9g\n", g->v[3 * p], g->v[3 * p + 1], g->v[3 * p + 2]);
    return fclose(f) != 0;
}

/* SPP frames with a fixed seed and a ramp transfer function over [0, 1]
 * (the same for every field, so images differ only by the field). */
static void render(clvr_tracer *tr, float *img)
{
    OK(clvr_tracer_set_seed(tr, 7, &msg));
    OK(clvr_tracer_set_tf(tr, "viridis", NULL, 0.0f, 1.0f, 1.0f, 1, &msg));
    OK(clvr_tracer_render(tr, SPP, &msg));
    OK(clvr_tracer_read_image(tr, img, (size_t)W * H * 4, &msg));
}

static double mean_abs_diff(const float *x, const float *y, size_t n)
{
    double d = 0;
    for (size_t i = 0; i < n; ++i) d += fabs((double)x[i] - (double)y[i]);
    return d / (double)n;
}

static void test_fields(clvr_context *ctx, const grid *g, const char *path)
{
    clvr_dataset *file = NULL, *arrays = NULL;
    OK(clvr_dataset_load_with(path, NULL, &file, &msg));
    clvr_dataset_info info;
    info.size = sizeof info;
    OK(clvr_dataset_get_info(file, &info, &msg));
    CHECK(info.num_fields == 3 && info.file_fields == 3);
    CHECK(info.num_points == (uint64_t)N * N * N && info.num_cells[3] == (uint64_t)(N - 1) * (N - 1) * (N - 1));
    CHECK(!strcmp(info.current_name, "a"));
    const char *names[3] = {"a", "b", "v"};
    const uint32_t comps[3] = {1, 1, 3};
    for (uint32_t i = 0; i < 3; ++i) {
        clvr_dataset_field f;
        f.size = sizeof f;
        OK(clvr_dataset_get_field(file, i, &f, &msg));
        CHECK(!strcmp(f.name, names[i]) && f.components == comps[i] && !f.is_cell);
        CHECK(f.loaded == (i == 0));
    }
    clvr_dataset_field f;
    f.size = sizeof f;
    CHECK_FAILS(clvr_dataset_get_field(file, 3, &f, &msg), CLVR_RESULT_ERR_USAGE, "has 3");

    /* Field b by name, read from the file now, against the arrays' b. */
    OK(clvr_dataset_create(N * N * N, g->xyz, CLVR_COPY, &arrays, &msg));
    OK(clvr_dataset_add_cells(arrays, "hexahedron", (N - 1) * (N - 1) * (N - 1), g->hex, CLVR_COPY, &msg));
    OK(clvr_dataset_add_field(arrays, "a", g->a, CLVR_COPY, &msg));
    OK(clvr_dataset_add_field(arrays, "b", g->b, CLVR_COPY, &msg));
    static float img_fb[W * H * 4], img_ab[W * H * 4], img_fa[W * H * 4];
    clvr_tracer *tr = NULL;
    OK(clvr_tracer_create(ctx, file, "b", W, H, &tr, &msg));
    render(tr, img_fb);
    clvr_tracer_destroy(tr);
    OK(clvr_dataset_get_field(file, 1, &f, &msg));
    CHECK(f.loaded == 1 && f.has_range && fabsf(f.max - 1.0f) < 1e-6f);
    OK(clvr_tracer_create(ctx, arrays, "b", W, H, &tr, &msg));
    render(tr, img_ab);
    clvr_tracer_destroy(tr);
    OK(clvr_tracer_create(ctx, file, "a", W, H, &tr, &msg));
    render(tr, img_fa);
    clvr_tracer_destroy(tr);
    const double same = mean_abs_diff(img_fb, img_ab, W * H * 4), other = mean_abs_diff(img_fb, img_fa, W * H * 4);
    printf("fields: |file b - arrays b| = %.3g, |file b - file a| = %.3g (mean per channel)\n", same, other);
    CHECK(same == 0.0);
    CHECK(other > 1e-3);

    /* A vector's component by spec; an unknown name lists the fields. */
    OK(clvr_tracer_create(ctx, file, "v:x", W, H, &tr, &msg));
    clvr_tracer_destroy(tr);
    CHECK_FAILS(clvr_tracer_create(ctx, file, "nope", W, H, &tr, &msg), CLVR_RESULT_ERR_BAD_FIELD, "nope");
    clvr_dataset_destroy(file);
    clvr_dataset_destroy(arrays);
}

static void test_scene(clvr_context *ctx, const grid *g)
{
    clvr_dataset *ds = NULL;
    OK(clvr_dataset_create(N * N * N, g->xyz, CLVR_COPY, &ds, &msg));
    OK(clvr_dataset_add_cells(ds, "hexahedron", (N - 1) * (N - 1) * (N - 1), g->hex, CLVR_COPY, &msg));
    OK(clvr_dataset_add_field(ds, "b", g->b, CLVR_COPY, &msg));

    clvr_preprocess_settings ps;
    clvr_preprocess_settings_init(&ps);
    clvr_scene *sc = NULL;
    ps.leaf_size = 0;
    CHECK_FAILS(clvr_scene_create(ctx, ds, NULL, &ps, &sc, &msg), CLVR_RESULT_ERR_USAGE, "leaf_size");
    ps.leaf_size = 8;
    ps.size = 4;
    CHECK_FAILS(clvr_scene_create(ctx, ds, NULL, &ps, &sc, &msg), CLVR_RESULT_ERR_USAGE, "size");
    ps.size = sizeof ps;
    ps.one_curve = 3;
    CHECK_FAILS(clvr_scene_create(ctx, ds, NULL, &ps, &sc, &msg), CLVR_RESULT_ERR_USAGE, "one_curve");
    /* A program built against 1.9's header has no one_curve: whatever lies
     * past its struct is not read, and it gets auto. */
    ps.size = (uint32_t)offsetof(clvr_preprocess_settings, one_curve);
    ps.sampling_size = 4;
    OK(clvr_scene_create(ctx, ds, NULL, &ps, &sc, &msg));
    clvr_scene_destroy(sc);
    sc = NULL;
    ps.size = sizeof ps;
    ps.one_curve = CLVR_ONE_CURVE_ON;
    OK(clvr_scene_create(ctx, ds, NULL, &ps, &sc, &msg));
    clvr_dataset_destroy(ds); /* the scene holds it */
    clvr_scene_stats st;
    st.size = sizeof st;
    OK(clvr_scene_get_stats(sc, &st, &msg));
    printf("scene: %llu elements, %llu leaves of %u, %llu sampling clusters of %u, %.3f s, %u stages\n",
           (unsigned long long)st.elements, (unsigned long long)st.leaves, st.leaf_size,
           (unsigned long long)st.sampling_clusters, st.sampling_size, st.preprocess_s, st.num_stages);
    CHECK(st.elements == (uint64_t)(N - 1) * (N - 1) * (N - 1));
    CHECK(st.leaf_size == 8 && st.sampling_size == 4);
    CHECK(st.leaves >= (st.elements + 7) / 8); /* leaves of at most 8 elements */
    CHECK(st.sampling_clusters >= (st.elements + 3) / 4);
    CHECK(st.preprocess_s > 0 && st.num_stages >= 2 && !strcmp(st.stage_name[st.num_stages - 2], "bvh") &&
          !strcmp(st.stage_name[st.num_stages - 1], "hull"));
    CHECK(st.bytes_points_after > 0 && st.bytes_bvh > 0 && st.device_bytes > 0);
    /* hexes only: nothing to collapse, whatever one_curve says */
    CHECK(st.collapsed_cells[0] == 0 && st.collapsed_cells[1] == 0 && st.collapsed_cells[2] == 0 &&
          st.collapsed_cells[3] == 0);
    uint32_t oc = 9;
    OK(clvr_setting_index("one_curve", "off", &oc, &msg));
    CHECK(oc == CLVR_ONE_CURVE_OFF && !strcmp(clvr_setting_name("one_curve", CLVR_ONE_CURVE_AUTO), "auto") &&
          !clvr_setting_name("one_curve", 3));
    /* entry grids: at least a cell per instance, 8 bytes each, and about 2 cells per leaf of tets, 8 per
     * leaf of other types (at most 9); the occupancy grid: a header and a word at least, about a bit per
     * element (at most 8, rounding cells up) */
    CHECK(st.bytes_entry_grids >= (st.instances + 1) * 48 + st.instances * 8 + 4 &&
          st.bytes_entry_grids <= (st.instances + 1) * 48 + st.leaves * 72 + st.instances * 8 * 64 + st.elements + 4);
    /* A program built against 1.8's header (no bytes_entry_grids) gets the
     * members it knows and nothing past its struct; one smaller than the
     * 1.1 struct is refused. */
    {
        const size_t old_size = offsetof(clvr_scene_stats, bytes_entry_grids);
        clvr_scene_stats old;
        memset(&old, 0xab, sizeof old);
        old.size = (uint32_t)old_size;
        OK(clvr_scene_get_stats(sc, &old, &msg));
        uint64_t past;
        memcpy(&past, (const char *)&old + old_size, sizeof past);
        CHECK(old.size == old_size && old.elements == st.elements && old.leaves == st.leaves &&
              old.scalar_max == st.scalar_max && !strcmp(old.stage_name[old.num_stages - 1], "hull"));
        CHECK(past == 0xababababababababull);
        old.size = (uint32_t)old_size - 4u;
        CHECK_FAILS(clvr_scene_get_stats(sc, &old, &msg), CLVR_RESULT_ERR_USAGE, "size");
    }

    /* Two tracers on one scene. */
    clvr_tracer *t1 = NULL, *t2 = NULL;
    CHECK_FAILS(clvr_tracer_create_on(sc, NULL, 0, H, &t1, &msg), CLVR_RESULT_ERR_USAGE, "width");
    OK(clvr_tracer_create_on(sc, NULL, W, H, &t1, &msg));
    OK(clvr_tracer_create_on(sc, NULL, W, H, &t2, &msg));
    CHECK(clvr_tracer_scene(t1) == sc && clvr_tracer_scene(t2) == sc);
    clvr_scene_destroy(sc); /* the tracers hold it */
    static float i1[W * H * 4], i2[W * H * 4];
    render(t1, i1);
    render(t2, i2);
    CHECK(mean_abs_diff(i1, i2, W * H * 4) == 0.0);

    /* Settings: round trip, all-or-nothing, another method differs. */
    clvr_tracer_settings s0, s1, s2;
    s0.size = s1.size = s2.size = sizeof s0;
    OK(clvr_tracer_get_settings(t2, &s0, &msg));
    clvr_tracer_settings def;
    clvr_tracer_settings_init(&def);
    CHECK(!strcmp(s0.method, def.method) && !strcmp(s0.estimator, def.estimator) && s0.seed == 7);
    OK(clvr_tracer_set_settings(t2, &s0, &msg));
    OK(clvr_tracer_get_settings(t2, &s1, &msg));
    CHECK(!memcmp(&s0, &s1, sizeof s0));
    s1.urm_steps = 0;
    CHECK_FAILS(clvr_tracer_set_settings(t2, &s1, &msg), CLVR_RESULT_ERR_USAGE, "urm_steps");
    s1.urm_steps = s0.urm_steps;
    s1.bins = 33;
    CHECK_FAILS(clvr_tracer_set_settings(t2, &s1, &msg), CLVR_RESULT_ERR_USAGE, "bins");
    s1.bins = s0.bins;
    CHECK(def.macrocells == 0); /* the automatic grid (1.11) */
    s1.macrocells = 1025;
    CHECK_FAILS(clvr_tracer_set_settings(t2, &s1, &msg), CLVR_RESULT_ERR_USAGE, "macrocells");
    s1.macrocells = s0.macrocells;
    snprintf(s1.method, sizeof s1.method, "magic");
    CHECK_FAILS(clvr_tracer_set_settings(t2, &s1, &msg), CLVR_RESULT_ERR_USAGE, "magic");
    s1.size = 8;
    CHECK_FAILS(clvr_tracer_set_settings(t2, &s1, &msg), CLVR_RESULT_ERR_USAGE, "size");
    s1.size = sizeof s1;
    OK(clvr_tracer_get_settings(t2, &s2, &msg));
    CHECK(!memcmp(&s0, &s2, sizeof s0)); /* nothing of the refused calls stuck */
    s2 = s0;
    snprintf(s2.method, sizeof s2.method, "march");
    s2.step = 0.05f;
    s2.num_clip_planes = 1;
    s2.clip_planes[0][0] = 1;
    s2.clip_planes[0][3] = 0.5f;
    OK(clvr_tracer_set_settings(t2, &s2, &msg));
    OK(clvr_tracer_get_settings(t2, &s1, &msg));
    CHECK(!strcmp(s1.method, "march") && s1.step == 0.05f && s1.num_clip_planes == 1 && s1.clip_planes[0][3] == 0.5f);
    render(t2, i2);
    CHECK(mean_abs_diff(i1, i2, W * H * 4) > 1e-3);

    /* Statistics, size, transfer function. */
    clvr_render_stats rs;
    rs.size = sizeof rs;
    OK(clvr_tracer_get_render_stats(t1, &rs, &msg));
    CHECK(rs.frames == SPP && rs.rays >= (uint64_t)W * H * SPP && rs.width == W && !strcmp(rs.method, def.method));
    /* dda's grid in use: the automatic grid's choice, 128 or its blocks' 32 */
    CHECK(!strcmp(rs.method, "dda") && (rs.macrocells == 128 || rs.macrocells == 32));
    {   /* built against 1.10's header: no macrocells member */
        clvr_render_stats old;
        memset(&old, 0xab, sizeof old);
        old.size = (uint32_t)offsetof(clvr_render_stats, macrocells);
        OK(clvr_tracer_get_render_stats(t1, &old, &msg));
        CHECK(!strcmp(old.estimator, rs.estimator) && old.macrocells == 0xabababab);
    }
    {   /* built against 1.5's header: no estimator member */
        clvr_render_stats old;
        memset(&old, 0xab, sizeof old);
        old.size = (uint32_t)offsetof(clvr_render_stats, estimator);
        OK(clvr_tracer_get_render_stats(t1, &old, &msg));
        CHECK(old.frames == rs.frames && old.rays == rs.rays && !strcmp(old.method, rs.method));
        CHECK((unsigned char)old.estimator[0] == 0xab && rs.estimator[0] != (char)0xab);
        old.size = 8;
        CHECK_FAILS(clvr_tracer_get_render_stats(t1, &old, &msg), CLVR_RESULT_ERR_USAGE, "size");
    }
    OK(clvr_tracer_set_size(t1, 16, 8, &msg));
    OK(clvr_tracer_render(t1, 1, &msg));
    static float small[16 * 8 * 4];
    OK(clvr_tracer_read_image(t1, small, 16 * 8 * 4, &msg));
    uint32_t w, h;
    OK(clvr_tracer_size(t1, &w, &h, &msg));
    CHECK(w == 16 && h == 8);
    clvr_tf_info ti;
    ti.size = sizeof ti;
    OK(clvr_tracer_get_tf(t1, &ti, &msg));
    CHECK(!strcmp(ti.colormap, "viridis") && ti.range_lo == 0.0f && ti.range_hi == 1.0f && ti.table_size >= 2);
    OK(clvr_tracer_edit_tf(t1, "grayscale", NAN, NAN, 2.0f * ti.density, &msg));
    clvr_tf_info t2i;
    t2i.size = sizeof t2i;
    OK(clvr_tracer_get_tf(t1, &t2i, &msg));
    CHECK(!strcmp(t2i.colormap, "grayscale") && t2i.density == 2.0f * ti.density && t2i.range_hi == 1.0f);
    float *table = malloc((size_t)t2i.table_size * 4 * sizeof(float));
    OK(clvr_tracer_get_tf_table(t1, table, (size_t)t2i.table_size * 4, &msg));
    CHECK(table[0] == table[1] && table[1] == table[2]); /* grey */
    CHECK_FAILS(clvr_tracer_get_tf_table(t1, table, 3, &msg), CLVR_RESULT_ERR_USAGE, "needs");
    CHECK_FAILS(clvr_tracer_edit_tf(t1, NULL, 2.0f, 1.0f, NAN, &msg), CLVR_RESULT_ERR_USAGE, "range");
    free(table);

    /* The image writer with a legend, and the path checks. */
    char path[256];
    snprintf(path, sizeof path, "/tmp/clvr_test_api_scene_%ld.png", (long)getpid());
    clvr_image_settings is;
    clvr_image_settings_init(&is);
    float leg[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    is.legend_table = leg;
    is.legend_entries = 2;
    is.legend_lo = 0;
    is.legend_hi = 1;
    is.legend_name = "b";
    OK(clvr_image_save_with(path, 16, 8, small, &is, &msg));
    CHECK(access(path, F_OK) == 0);
    remove(path);
    CHECK_FAILS(clvr_image_check_path("/tmp/x.jpeg", &msg), CLVR_RESULT_ERR_USAGE, "jpeg");
    CHECK(clvr_image_path_is_png("A.PNG") && !clvr_image_path_is_png("a.exr"));
    char numbered[64];
    OK(clvr_image_path_numbered("out/a.png", 7, numbered, sizeof numbered, &msg));
    CHECK(!strcmp(numbered, "out/a.0007.png"));
    clvr_tracer_destroy(t1);
    clvr_tracer_destroy(t2);
}

static void test_borrow(const grid *g)
{
    static grid copy;
    copy = *g;
    clvr_dataset *ds = NULL;
    const void *p;
    int borrowed;
    OK(clvr_dataset_create(N * N * N, copy.xyz, CLVR_BORROW, &ds, &msg));
    OK(clvr_dataset_add_cells(ds, "hexahedron", (N - 1) * (N - 1) * (N - 1), copy.hex, CLVR_COPY, &msg));
    OK(clvr_dataset_add_field(ds, "a", copy.a, CLVR_BORROW, &msg));
    OK(clvr_dataset_get_array(ds, "points", &p, &borrowed, &msg));
    CHECK(p == copy.xyz && borrowed == 1);
    OK(clvr_dataset_get_array(ds, "hexahedron", &p, &borrowed, &msg));
    CHECK(p != copy.hex && borrowed == 0);
    OK(clvr_dataset_get_array(ds, "a", &p, &borrowed, &msg));
    CHECK(p == copy.a && borrowed == 1);
    CHECK_FAILS(clvr_dataset_get_array(ds, "zz", &p, &borrowed, &msg), CLVR_RESULT_ERR_BAD_FIELD, "zz");
    clvr_dataset_destroy(ds);
    CHECK(!memcmp(&copy, g, sizeof copy)); /* nothing written */
}

int main(void)
{
    static grid g;
    make_grid(&g);
    test_borrow(&g);
    char path[256];
    snprintf(path, sizeof path, "/tmp/clvr_test_api_scene_%ld.vtk", (long)getpid());
    if (write_vtk(&g, path)) {
        fprintf(stderr, "cannot write %s\n", path);
        return 1;
    }
    clvr_context *ctx = NULL;
    if (clvr_context_create(tu_device_spec(), &ctx, &msg) != CLVR_RESULT_OK &&
        clvr_context_create(NULL, &ctx, &msg) != CLVR_RESULT_OK) {
        printf("skipped: no OpenCL device (%s)\n", msg.text);
        remove(path);
        return 77;
    }
    test_fields(ctx, &g, path);
    test_scene(ctx, &g);
    clvr_context_destroy(ctx);
    remove(path);
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    else printf("test_api_scene: all checks passed\n");
    return failures ? 1 : 0;
}
