/* test_api.c: libclvr's public API through clvr.h alone (linked against the
 * shared library, no internal header). Proves:
 *  - arguments are checked before any device work, with the result code and
 *    a message naming the argument (a NaN point, an index out of range, an
 *    unknown cell type, a repeated type, a missing field, a short buffer);
 *  - nothing the caller passes is modified, and CLVR_COPY really copies:
 *    the caller's arrays are overwritten with garbage right after the calls
 *    and the dataset still renders (a borrowing implementation would render
 *    NaNs or fail to preprocess);
 *  - a mesh built from arrays renders the same image, in distribution, as
 *    the same mesh loaded from a .bin written by clvr-gen (per 4x4 block and
 *    channel, K_SIGMA standard errors from the spread of independent
 *    batches), and the comparison has power: the same mesh without its
 *    hexahedra is told apart;
 *  - a tracer keeps its dataset alive after clvr_dataset_destroy; the image
 *    writers work and report an unwritable path.
 * Exit 77 (skipped) without an OpenCL device. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "clvr.h"
#include "api_check.h"


#define W 32
#define H 32
#define BATCHES 8
#define FRAMES 4
/* 6 SE, not 5: variances from 8 batches have Student-t tails and 1024
 * blocks are compared; the broken case differs by tens of SE. */
#define K_SIGMA 6.0

static const char *const cell_types[4] = {"tetra", "pyramid", "wedge", "hexahedron"};
static const uint32_t cell_verts[4] = {4, 5, 6, 8};

/* A .bin read by hand from docs/bin-format.md (not through clvr). */
typedef struct bin_mesh {
    uint64_t nv, nc[4];
    float *xyz, *scalars;
    uint32_t *cells[4];
} bin_mesh;

static int read_bin(const char *path, bin_mesh *b)
{
    FILE *f = fopen(path, "rb");
    unsigned char h[256];
    if (!f || fread(h, 1, 256, f) != 256 || memcmp(h, "CLVRMESH", 8)) {
        if (f) fclose(f);
        return 1;
    }
    memcpy(&b->nv, h + 16, 8);
    memcpy(b->nc, h + 24, 32);
    b->xyz = malloc(b->nv * 12);
    b->scalars = malloc(b->nv * 4);
    int bad = !b->xyz || !b->scalars || fread(b->xyz, 12, b->nv, f) != b->nv ||
              fread(b->scalars, 4, b->nv, f) != b->nv;
    for (int t = 0; t < 4 && !bad; ++t) {
        b->cells[t] = malloc(b->nc[t] * cell_verts[t] * 4 + 4);
        bad = !b->cells[t] || fread(b->cells[t], 4 * cell_verts[t], b->nc[t], f) != b->nc[t];
    }
    fclose(f);
    return bad;
}

/* Per-pixel mean and variance of the mean over BATCHES independent batches
 * of FRAMES frames each (seeds base, base + 1, ...). */
static void render_batches(clvr_tracer *tr, uint64_t base, float *mean, float *var)
{
    clvr_message msg = {0};
    const size_t n = (size_t)W * H * 4;
    float *img = malloc(n * sizeof(float));
    double *s = calloc(n, sizeof(double)), *q = calloc(n, sizeof(double));
    CHECK(img && s && q);
    for (int b = 0; b < BATCHES; ++b) {
        OK(clvr_tracer_set_seed(tr, base + (uint64_t)b, &msg));
        OK(clvr_tracer_render(tr, FRAMES, &msg));
        OK(clvr_tracer_read_image(tr, img, n, &msg));
        for (size_t i = 0; i < n; ++i) {
            s[i] += img[i];
            q[i] += (double)img[i] * img[i];
        }
    }
    for (size_t i = 0; i < n; ++i) {
        const double m = s[i] / BATCHES, v = (q[i] / BATCHES - m * m) * BATCHES / (BATCHES - 1);
        mean[i] = (float)m;
        var[i] = (float)(v > 0 ? v / BATCHES : 0);
    }
    free(img);
    free(s);
    free(q);
}

/* Blocks (4x4 pixels, per channel) whose summed difference exceeds K_SIGMA
 * standard errors (plus a float-rounding floor). */
static int differing_blocks(const float *ma, const float *va, const float *mb, const float *vb)
{
    int bad = 0;
    double worst = 0;
    for (int by = 0; by < H; by += 4)
        for (int bx = 0; bx < W; bx += 4)
            for (int c = 0; c < 4; ++c) {
                double d = 0, v = 0;
                for (int y = by; y < by + 4; ++y)
                    for (int x = bx; x < bx + 4; ++x) {
                        const size_t i = 4 * ((size_t)y * W + x) + c;
                        d += (double)ma[i] - mb[i];
                        v += (double)va[i] + vb[i];
                    }
                const double se = sqrt(v);
                if (fabs(d) > K_SIGMA * se + 1e-4) {
                    ++bad;
                    if (se > 0 && fabs(d) / se > worst) worst = fabs(d) / se;
                }
            }
    fprintf(stderr, "  %d of %d blocks differ by more than %g SE (worst %.1f SE)\n", bad, (W / 4) * (H / 4) * 4,
            K_SIGMA, worst);
    return bad;
}

static void test_arguments(void)
{
    clvr_message msg = {0};
    clvr_dataset *ds = NULL;
    float xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const float xyz_orig[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    uint32_t tet[4] = {0, 1, 2, 3}, bad_tet[4] = {0, 1, 2, 4};
    float field[4] = {0, 1, 2, 3};

    CHECK(clvr_api_version() == CLVR_API_VERSION);
    CHECK(strlen(clvr_version_string()) > 0);
    CHECK(!strcmp(clvr_result_name(CLVR_RESULT_ERR_BAD_INDEX), "ERR_BAD_INDEX"));
    CHECK(clvr_result_exit_code(CLVR_RESULT_ERR_USAGE) == 2);

    CHECK_FAILS(clvr_dataset_create(4, NULL, CLVR_COPY, &ds, &msg), CLVR_RESULT_ERR_USAGE, "xyz is NULL");
    CHECK_FAILS(clvr_dataset_create(0, xyz, CLVR_COPY, &ds, &msg), CLVR_RESULT_ERR_USAGE, "num_points");
    CHECK_FAILS(clvr_dataset_create(4, xyz, (clvr_ownership)7, &ds, &msg), CLVR_RESULT_ERR_USAGE, "CLVR_BORROW");
    xyz[4] = NAN;
    CHECK_FAILS(clvr_dataset_create(4, xyz, CLVR_COPY, &ds, &msg), CLVR_RESULT_ERR_BAD_VALUE, "point 1");
    CHECK(ds == NULL); /* out-parameters only on success */
    xyz[4] = 0;
    OK(clvr_dataset_create(4, xyz, CLVR_COPY, &ds, &msg));
    CHECK(msg.result == CLVR_RESULT_OK && msg.text[0] == '\0');
    CHECK_FAILS(clvr_dataset_add_cells(ds, "tet", 1, tet, CLVR_COPY, &msg), CLVR_RESULT_ERR_USAGE, "hexahedron");
    CHECK_FAILS(clvr_dataset_add_cells(ds, "tetra", 1, bad_tet, CLVR_COPY, &msg), CLVR_RESULT_ERR_BAD_INDEX,
                "tetra cell 0 vertex 3 is 4 but the dataset has 4 points");
    OK(clvr_dataset_add_cells(ds, "tetra", 1, tet, CLVR_BORROW, &msg));
    CHECK_FAILS(clvr_dataset_add_cells(ds, "tetra", 1, tet, CLVR_COPY, &msg), CLVR_RESULT_ERR_USAGE, "once");
    field[2] = INFINITY;
    CHECK_FAILS(clvr_dataset_add_field(ds, "f", field, CLVR_COPY, &msg), CLVR_RESULT_ERR_BAD_VALUE, "point 2");
    field[2] = 2;
    CHECK_FAILS(clvr_dataset_add_field(ds, "", field, CLVR_COPY, &msg), CLVR_RESULT_ERR_USAGE, "field name");
    CHECK_FAILS(clvr_dataset_add_field(ds, "a\"b", field, CLVR_COPY, &msg), CLVR_RESULT_ERR_USAGE, "field name");
    OK(clvr_dataset_add_field(ds, "f", field, CLVR_COPY, &msg));
    CHECK_FAILS(clvr_dataset_add_field(ds, "f", field, CLVR_COPY, &msg), CLVR_RESULT_ERR_USAGE, "already");
    float lo, hi;
    CHECK_FAILS(clvr_dataset_field_range(ds, "g", &lo, &hi, &msg), CLVR_RESULT_ERR_BAD_FIELD, "'f'");
    OK(clvr_dataset_field_range(ds, "f", &lo, &hi, &msg));
    CHECK(lo == 0 && hi == 3);
    float blo[3], bhi[3];
    OK(clvr_dataset_bounds(ds, blo, bhi, &msg));
    CHECK(blo[0] == 0 && bhi[0] == 1 && bhi[2] == 1);
    uint64_t np, nc[4];
    uint32_t nf;
    char name[8];
    OK(clvr_dataset_counts(ds, &np, nc, &nf, &msg));
    CHECK(np == 4 && nc[0] == 1 && nc[3] == 0 && nf == 1);
    OK(clvr_dataset_field_name(ds, 0, name, sizeof name, &msg));
    CHECK(!strcmp(name, "f"));
    CHECK_FAILS(clvr_dataset_field_name(ds, 1, name, sizeof name, &msg), CLVR_RESULT_ERR_USAGE, "field 1");
    /* Nothing passed in was modified. */
    CHECK(!memcmp(xyz, xyz_orig, sizeof xyz) && tet[3] == 3 && bad_tet[3] == 4 && field[3] == 3);
    clvr_dataset_destroy(ds);
    clvr_dataset_destroy(NULL);
    CHECK_FAILS(clvr_dataset_load("/nonexistent/x.bin", NULL, &ds, &msg), CLVR_RESULT_ERR_IO, "/nonexistent/x.bin");
    CHECK_FAILS(clvr_tracer_create(NULL, NULL, NULL, 8, 8, NULL, &msg), CLVR_RESULT_ERR_USAGE, "ctx is NULL");
    float px[16] = {0};
    CHECK_FAILS(clvr_image_save("x.jpg", 2, 2, px, 0, NULL, 0, &msg), CLVR_RESULT_ERR_USAGE, "x.jpg");
    CHECK_FAILS(clvr_image_save("x.png", 2, 2, px, 0, "sepia", 0, &msg), CLVR_RESULT_ERR_USAGE, "sepia");
    CHECK_FAILS(clvr_image_save("/nonexistent/dir/x.png", 2, 2, px, 0, NULL, 0, &msg), CLVR_RESULT_ERR_WRITE,
                "/nonexistent");
    /* msg may be NULL. */
    CHECK(clvr_dataset_create(0, xyz, CLVR_COPY, &ds, NULL) == CLVR_RESULT_ERR_USAGE);
}

/* The arrays of b as a dataset, copied, with or without its hexahedra; the
 * caller's arrays (copies of b's) are overwritten right after the calls. */
static clvr_dataset *dataset_from(const bin_mesh *b, int with_hexes)
{
    clvr_message msg = {0};
    clvr_dataset *ds = NULL;
    float *xyz = malloc(b->nv * 12), *f = malloc(b->nv * 4);
    memcpy(xyz, b->xyz, b->nv * 12);
    memcpy(f, b->scalars, b->nv * 4);
    OK(clvr_dataset_create(b->nv, xyz, CLVR_COPY, &ds, &msg));
    OK(clvr_dataset_add_field(ds, "scalar", f, CLVR_COPY, &msg));
    CHECK(!memcmp(xyz, b->xyz, b->nv * 12) && !memcmp(f, b->scalars, b->nv * 4));
    for (uint64_t i = 0; i < 3 * b->nv; ++i) xyz[i] = NAN;
    for (uint64_t i = 0; i < b->nv; ++i) f[i] = NAN;
    for (int t = 0; t < 4; ++t) {
        if (t == 3 && !with_hexes) continue;
        const size_t bytes = b->nc[t] * cell_verts[t] * 4;
        uint32_t *idx = malloc(bytes + 4);
        memcpy(idx, b->cells[t], bytes);
        OK(clvr_dataset_add_cells(ds, cell_types[t], b->nc[t], idx, CLVR_COPY, &msg));
        CHECK(!memcmp(idx, b->cells[t], bytes));
        memset(idx, 0xff, bytes);
        free(idx);
    }
    free(xyz);
    free(f);
    return ds;
}

int main(void)
{
    test_arguments();

    clvr_message msg = {0};
    clvr_context *ctx = NULL;
    if (clvr_context_create(tu_device_spec(), &ctx, &msg) != CLVR_RESULT_OK) {
        fprintf(stderr, "test_api: no OpenCL device (%s): skipped\n", msg.text);
        return failures ? 1 : 77;
    }
    char dev[64], plat[64];
    OK(clvr_context_describe(ctx, dev, sizeof dev, plat, sizeof plat, &msg));
    fprintf(stderr, "test_api: %s (%s)\n", dev, plat);

    const char *build = getenv("CLVR_BUILD_DIR");
    char bin[512], cmd[1200];
    snprintf(bin, sizeof bin, "/tmp/clvr_test_api_%d.bin", (int)getpid());
    snprintf(cmd, sizeof cmd, "%s/clvr-gen mixed %s --elements 4000 --seed 3 --quiet", build ? build : ".", bin);
    if (system(cmd) != 0) {
        fprintf(stderr, "test_api: %s failed\n", cmd);
        return 1;
    }
    bin_mesh b = {0};
    CHECK(read_bin(bin, &b) == 0);
    CHECK(b.nc[0] && b.nc[1] && b.nc[2] && b.nc[3]); /* every type present */

    clvr_dataset *loaded = NULL, *arrays = dataset_from(&b, 1), *no_hexes = dataset_from(&b, 0);
    OK(clvr_dataset_load(bin, NULL, &loaded, &msg));
    {
        /* A scene that consumed its file's cells (the clvr program's way):
         * the tracer's automatic transfer function, made at its first use
         * (here a figure asked before any transfer function), cannot measure
         * cells that are gone; it is the ramp over the field's range, not a
         * read of freed lists (which AddressSanitizer reports), and asking
         * for a dataset-made transfer function says why it cannot be. */
        clvr_dataset *once = NULL;
        clvr_scene *sc = NULL;
        clvr_tracer *tc = NULL;
        OK(clvr_dataset_load(bin, NULL, &once, &msg));
        clvr_preprocess_settings ps;
        clvr_preprocess_settings_init(&ps);
        ps.consume = 1;
        OK(clvr_scene_create(ctx, once, NULL, &ps, &sc, &msg));
        clvr_dataset_destroy(once);
        OK(clvr_tracer_create_on(sc, NULL, W, H, &tc, &msg));
        clvr_scene_destroy(sc);
        double d = 0;
        OK(clvr_tracer_stat(tc, "density", &d, &msg));
        CHECK(d > 0);
        CHECK_FAILS(clvr_tracer_set_tf(tc, "viridis", NULL, NAN, NAN, 1, 0, &msg), CLVR_RESULT_ERR_USAGE, "consumed");
        OK(clvr_tracer_render(tc, 1, &msg));
        clvr_tracer_destroy(tc);
    }
    unlink(bin);
    clvr_tracer *tl = NULL, *ta = NULL, *tn = NULL;
    OK(clvr_tracer_create(ctx, loaded, NULL, W, H, &tl, &msg));
    /* The tracer keeps the dataset alive. */
    clvr_dataset_destroy(loaded);
    OK(clvr_tracer_create(ctx, arrays, "scalar", W, H, &ta, &msg));
    OK(clvr_tracer_create(ctx, no_hexes, NULL, W, H, &tn, &msg));
    CHECK_FAILS(clvr_tracer_create(ctx, arrays, "nope", W, H, &tn, &msg), CLVR_RESULT_ERR_BAD_FIELD, "nope");

    const size_t n = (size_t)W * H * 4;
    float *img = malloc(n * 4);
    CHECK_FAILS(clvr_tracer_read_image(ta, img, n, &msg), CLVR_RESULT_ERR_USAGE, "clvr_tracer_render first");
    CHECK_FAILS(clvr_tracer_render(ta, 0, &msg), CLVR_RESULT_ERR_USAGE, "frames is 0");
    CHECK_FAILS(clvr_tracer_set_method(ta, "magic", NULL, &msg), CLVR_RESULT_ERR_USAGE, "dda");
    double dl, da, el, ea;
    OK(clvr_tracer_stat(tl, "density", &dl, &msg));
    OK(clvr_tracer_stat(ta, "density", &da, &msg));
    OK(clvr_tracer_stat(tl, "elements", &el, &msg));
    OK(clvr_tracer_stat(ta, "elements", &ea, &msg));
    CHECK(dl == da && el == ea && el > 3000);
    CHECK_FAILS(clvr_tracer_stat(ta, "speed", &dl, &msg), CLVR_RESULT_ERR_USAGE, "frames, rays");
    /* The hull's figures: a mesh that fills its box keeps none. */
    double hf = -1, hb = -1, he = -1, hs = -1;
    OK(clvr_tracer_stat(ta, "hull_faces", &hf, &msg));
    OK(clvr_tracer_stat(ta, "hull_bytes", &hb, &msg));
    OK(clvr_tracer_stat(ta, "hull_empty_fraction", &he, &msg));
    OK(clvr_tracer_stat(ta, "hull_skipped", &hs, &msg));
    CHECK(hf == 0 && hb == 0 && he >= 0 && he < 0.15 && hs == 0);
    double ab = -1, as = -1;
    OK(clvr_tracer_stat(ta, "adjacency_bytes", &ab, &msg));
    OK(clvr_tracer_stat(ta, "adjacency_skipped", &as, &msg));
    CHECK(ab >= 0 && as == 0);

    float *ml = malloc(n * 4), *vl = malloc(n * 4), *ma = malloc(n * 4), *va = malloc(n * 4), *mn = malloc(n * 4),
          *vn = malloc(n * 4);
    render_batches(tl, 100, ml, vl);
    render_batches(ta, 200, ma, va);
    render_batches(tn, 300, mn, vn);
    fprintf(stderr, "test_api: arrays vs .bin:\n");
    CHECK(differing_blocks(ma, va, ml, vl) == 0);
    fprintf(stderr, "test_api: without hexahedra vs .bin (must differ):\n");
    CHECK(differing_blocks(mn, vn, ml, vl) > 5);
    double frames, rays;
    OK(clvr_tracer_stat(ta, "frames", &frames, &msg));
    OK(clvr_tracer_stat(ta, "rays", &rays, &msg));
    CHECK(frames == FRAMES && rays >= (double)W * H * FRAMES);
    /* The image pass that made the last image read (render_batches reads
     * it), and the light grid (shadows are on by default). */
    double image_s = -1, light_s = -1;
    OK(clvr_tracer_stat(ta, "image_s", &image_s, &msg));
    OK(clvr_tracer_stat(ta, "light_s", &light_s, &msg));
    CHECK(image_s > 0 && light_s > 0);
    int lit = 0;
    for (size_t i = 3; i < n; i += 4) lit += ma[i] > 0.05f;
    CHECK(lit > W * H / 8); /* not an empty image */

    /* A short buffer; then a PNG and an EXR written. */
    CHECK_FAILS(clvr_tracer_read_image(ta, img, n - 1, &msg), CLVR_RESULT_ERR_USAGE, "needs 4096");
    char png[256];
    snprintf(png, sizeof png, "/tmp/clvr_test_api_%d.png", (int)getpid());
    OK(clvr_image_save(png, W, H, ma, 0, NULL, 0, &msg));
    CHECK(access(png, R_OK) == 0);
    unlink(png);

    /* Camera and settings round trip. */
    const float eye[3] = {3, 2, 5}, target[3] = {0.5f, 0.5f, 0.5f}, up[3] = {0, 1, 0};
    float e2[3], t2[3];
    OK(clvr_tracer_set_camera(ta, eye, target, up, 40, &msg));
    OK(clvr_tracer_get_camera(ta, e2, t2, NULL, &msg));
    CHECK(e2[0] == 3 && e2[2] == 5 && t2[1] == 0.5f);
    CHECK_FAILS(clvr_tracer_set_camera(ta, eye, eye, up, 40, &msg), CLVR_RESULT_ERR_USAGE, "");
    const float light[3] = {1, 1, 1}, bg[3] = {0, 0, 0};
    OK(clvr_tracer_set_light(ta, light, 1, 0.2f, 0, &msg));
    OK(clvr_tracer_set_background(ta, bg, &msg));
    OK(clvr_tracer_set_method(ta, "track", "delta", &msg));
    OK(clvr_tracer_set_tf(ta, "viridis", NULL, NAN, NAN, 2, 1, &msg));
    const float table[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    OK(clvr_tracer_set_tf_table(ta, table, 2, 0, 1, 1, &msg));
    CHECK_FAILS(clvr_tracer_set_tf_table(ta, table, 2, 1, 0, 1, &msg), CLVR_RESULT_ERR_USAGE, "lo < hi");
    OK(clvr_tracer_render(ta, 1, &msg));
    OK(clvr_tracer_read_image(ta, img, n, &msg));

    clvr_tracer_destroy(tl);
    clvr_tracer_destroy(tn);
    /* The context destroyed before its last tracer (Python's collector at
     * exit may do this): released with the tracer, which still renders
     * (AddressSanitizer finds a use after free if ctx went first). */
    clvr_dataset_destroy(arrays);
    clvr_dataset_destroy(no_hexes);
    clvr_context_destroy(ctx);
    OK(clvr_tracer_render(ta, 1, &msg));
    clvr_tracer_destroy(ta);
    free(img);
    free(ml); free(vl); free(ma); free(va); free(mn); free(vn);
    for (int t = 0; t < 4; ++t) free(b.cells[t]);
    free(b.xyz);
    free(b.scalars);
    if (failures) fprintf(stderr, "test_api: %d failure(s)\n", failures);
    else fprintf(stderr, "test_api: all passed\n");
    return failures ? 1 : 0;
}
