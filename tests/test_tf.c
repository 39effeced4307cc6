/* Proves the transfer function: colour maps against published values
 * (matplotlib's tables, VTK's diverging/Lab/HSV interpolation, ParaView's
 * piecewise opacity with midpoint and sharpness), the baked table and the
 * shared lookup, the majorant as a true upper bound of every lookup in an
 * interval (10^5 random intervals over random transfer functions), and both
 * file parsers on good and bad input, every error naming file:line. */
#include <unistd.h>

#include "image.h"
#include "test_util.h"
#include "tf.h"

#define CHECK_RGB(tf, x, r, g, b, tol)                                                                         \
    do {                                                                                                      \
        float c_[3];                                                                                          \
        clvr_tf_color((tf), (x), c_);                                                                         \
        TU_CHECK_NEAR(c_[0], (r), (tol));                                                                     \
        TU_CHECK_NEAR(c_[1], (g), (tol));                                                                     \
        TU_CHECK_NEAR(c_[2], (b), (tol));                                                                     \
    } while (0)

static void test_colormaps(void)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    /* ParaView "Cool to Warm": its control points, and VTK 9.1's
     * vtkColorTransferFunction (Diverging) between them. Moreland's published
     * table gives 0.25 -> (0.553, 0.689, 0.995) and 0.75 -> (0.958, 0.603, 0.482). */
    TU_CHECK_STATUS(clvr_tf_init(&tf, "cool-warm", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.0f, 0.231373, 0.298039, 0.752941, 1e-6);
    CHECK_RGB(&tf, 0.5f, 0.865, 0.865, 0.865, 1e-7);
    CHECK_RGB(&tf, 1.0f, 0.705882, 0.015686, 0.149020, 1e-6);
    CHECK_RGB(&tf, 0.1f, 0.351957, 0.468420, 0.890251, 1e-3);
    CHECK_RGB(&tf, 0.25f, 0.553524, 0.688407, 0.994915, 1e-3);
    CHECK_RGB(&tf, 0.4f, 0.753730, 0.830173, 0.960956, 1e-3);
    CHECK_RGB(&tf, 0.6f, 0.947808, 0.794878, 0.716996, 1e-3);
    CHECK_RGB(&tf, 0.75f, 0.958279, 0.602921, 0.481727, 1e-3);
    CHECK_RGB(&tf, 0.9f, 0.842208, 0.326550, 0.266686, 1e-3);
    CHECK_RGB(&tf, -1.0f, 0.231373, 0.298039, 0.752941, 1e-6); /* clamped */
    CHECK_RGB(&tf, NAN, 0.231373, 0.298039, 0.752941, 1e-6);

    /* matplotlib's viridis and inferno: entries at x = i / 255, including
     * entries that are not control points (within 0.5%). */
    TU_CHECK_STATUS(clvr_tf_init(&tf, "viridis", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.0f, 0.267004, 0.004874, 0.329415, 1e-6);
    CHECK_RGB(&tf, 128.0f / 255.0f, 0.127568, 0.566949, 0.550556, 1e-6);
    CHECK_RGB(&tf, 1.0f, 0.993248, 0.906157, 0.143936, 1e-6);
    CHECK_RGB(&tf, 63.0f / 255.0f, 0.231674, 0.318106, 0.544834, 0.005);
    CHECK_RGB(&tf, 130.0f / 255.0f, 0.125394, 0.574318, 0.549086, 0.005);
    CHECK_RGB(&tf, 201.0f / 255.0f, 0.449368, 0.813768, 0.335384, 0.005);
    CHECK_RGB(&tf, 254.0f / 255.0f, 0.983868, 0.904867, 0.136897, 0.005);
    TU_CHECK_STATUS(clvr_tf_init(&tf, "inferno", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.0f, 0.001462, 0.000466, 0.013866, 1e-6);
    CHECK_RGB(&tf, 128.0f / 255.0f, 0.735683, 0.215906, 0.330245, 1e-6);
    CHECK_RGB(&tf, 1.0f, 0.988362, 0.998364, 0.644924, 1e-6);
    CHECK_RGB(&tf, 63.0f / 255.0f, 0.335217, 0.060060, 0.428524, 0.005);
    CHECK_RGB(&tf, 130.0f / 255.0f, 0.747127, 0.222378, 0.322856, 0.005);
    CHECK_RGB(&tf, 201.0f / 255.0f, 0.986502, 0.623105, 0.027814, 0.005);
    CHECK_RGB(&tf, 254.0f / 255.0f, 0.982257, 0.994109, 0.631017, 0.005);
    /* matplotlib's jet: piecewise linear per channel. */
    TU_CHECK_STATUS(clvr_tf_init(&tf, "jet", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.0f, 0.0, 0.0, 0.5, 1e-6);
    CHECK_RGB(&tf, 0.5f, 0.15 / 0.31, 1.0, 0.15 / 0.31, 1e-5);
    CHECK_RGB(&tf, 1.0f, 0.5, 0.0, 0.0, 1e-6);
    CHECK_RGB(&tf, 0.2f, 0.0, 0.075 / 0.25, 1.0, 1e-5);
    TU_CHECK_STATUS(clvr_tf_init(&tf, "grayscale", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.3f, 0.3, 0.3, 0.3, 1e-6);
    TU_CHECK_STATUS(clvr_tf_init(&tf, "no-such-map", &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "no-such-map") && strstr(err.msg, "viridis"));
    clvr_tf_free(&tf);
}

static clvr_status parse_str(clvr_tf *tf, const char *text, clvr_error *err)
{
    return clvr_tf_parse(tf, text, strlen(text), "mem.tf", err);
}

static void test_color_spaces(void)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    /* Values from VTK 9.1 vtkColorTransferFunction, red -> blue. */
    TU_CHECK_STATUS(clvr_tf_init(&tf, NULL, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(parse_str(&tf, "colorspace Lab\ncolor 0 1 0 0\ncolor 1 0 0 1\n", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.5f, 0.790313, 0.0, 0.535188, 2e-3);
    TU_CHECK_STATUS(parse_str(&tf, "colorspace HSV\ncolor 0 1 0 0\ncolor 1 0 0 1\n", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.5f, 1.0, 0.0, 1.0, 1e-5);
    CHECK_RGB(&tf, 0.25f, 1.0, 0.0, 0.5, 1e-5);
    TU_CHECK_STATUS(parse_str(&tf, "colorspace RGB\ncolor 0 1 0 0\ncolor 1 0 0 1\n", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.25f, 0.75, 0.0, 0.25, 1e-6);
    TU_CHECK_STATUS(parse_str(&tf, "colorspace Step\ncolor 0 1 0 0\ncolor 0.5 0 1 0\ncolor 1 0 0 1\n", &err), CLVR_OK,
                    &err);
    CHECK_RGB(&tf, 0.49f, 1.0, 0.0, 0.0, 0.0);
    CHECK_RGB(&tf, 0.5f, 0.0, 1.0, 0.0, 0.0);
    /* A repeated position is a discontinuity: the later point wins there. */
    TU_CHECK_STATUS(parse_str(&tf, "colorspace RGB\ncolor 0 0 0 0\ncolor 0.5 0 0 0\ncolor 0.5 1 1 1\ncolor 1 1 1 1\n",
                              &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.4999f, 0.0, 0.0, 0.0, 0.0);
    CHECK_RGB(&tf, 0.5f, 1.0, 1.0, 1.0, 0.0);
    clvr_tf_free(&tf);
}

static void test_opacity(void)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    TU_CHECK_STATUS(clvr_tf_init(&tf, NULL, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.0f), 0.0, 0.0);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.3f), 0.3, 1e-7);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 1.0f), 1.0, 0.0);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 2.0f), 1.0, 0.0);
    TU_CHECK_STATUS(parse_str(&tf, "opacity 0 0\nopacity 0.5 1\nopacity 1 0.2\n", &err), CLVR_OK, &err);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.25f), 0.5, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.75f), 0.6, 1e-6);
    TU_CHECK_STATUS(parse_str(&tf, "opacity 0.2 0.4\nopacity 0.6 0.8\n", &err), CLVR_OK, &err);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.1f), 0.4, 1e-7); /* before the first point: its value */
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.4f), 0.6, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.9f), 0.8, 1e-7);
    /* vtkPiecewiseFunction (VTK 9.1) with midpoint 0.3, and with sharpness 0.5. */
    TU_CHECK_STATUS(parse_str(&tf, "opacity 0 0 0.3 0\nopacity 1 1\n", &err), CLVR_OK, &err);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.15f), 0.25, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.3f), 0.5, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.5f), 0.6428571, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.65f), 0.75, 1e-6);
    TU_CHECK_STATUS(parse_str(&tf, "opacity 0 0.2 0.5 0.5\nopacity 1 0.8\n", &err), CLVR_OK, &err);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.1f), 0.2000096, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.25f), 0.2023984, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.4f), 0.2534324, 1e-6);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.75f), 0.7976016, 1e-6);
    clvr_tf_free(&tf);
}

static void test_bake_and_lookup(void)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    TU_CHECK_STATUS(clvr_tf_init(&tf, "viridis", &err), CLVR_OK, &err);
    const float lo3[3] = {0, 0, 0}, hi3[3] = {0, 2, 0};
    clvr_tf_set_extent(&tf, lo3, hi3);
    TU_CHECK_NEAR(tf.extent, 2.0, 0.0);
    TU_CHECK_NEAR(clvr_tf_extinction_scale(&tf), CLVR_TF_DIAGONAL_DEPTH / 2.0, 1e-6);
    uint32_t n = clvr_tf_table_size(&tf);
    TU_CHECK_EQ_U64(n, 256);
    float *t = malloc(sizeof(float) * 4 * n);
    clvr_tf_bake(&tf, t, n);
    /* Entries: linear (sRGB-decoded) colour, extinction = opacity * K / extent. */
    TU_CHECK_NEAR(t[0], clvr_image_srgb_decode(0.267004f), 1e-6);
    TU_CHECK_NEAR(t[3], 0.0, 0.0);
    TU_CHECK_NEAR(t[4 * 255 + 2], clvr_image_srgb_decode(0.143936f), 1e-6);
    TU_CHECK_NEAR(t[4 * 255 + 3], CLVR_TF_DIAGONAL_DEPTH / 2.0, 1e-5);
    TU_CHECK_NEAR(t[4 * 51 + 3], 0.2 * CLVR_TF_DIAGONAL_DEPTH / 2.0, 1e-5);
    /* Lookup over the window [10, 20] with density 3. */
    float o[4];
    clvr_tf_lookup(t, n, 10.0f, 20.0f, 3.0f, 10.0f, o);
    TU_CHECK_NEAR(o[0], t[0], 0.0);
    TU_CHECK_NEAR(o[3], 0.0, 0.0);
    clvr_tf_lookup(t, n, 10.0f, 20.0f, 3.0f, 20.0f, o);
    TU_CHECK_NEAR(o[1], t[4 * 255 + 1], 0.0);
    TU_CHECK_NEAR(o[3], 3.0 * t[4 * 255 + 3], 1e-6);
    clvr_tf_lookup(t, n, 10.0f, 20.0f, 3.0f, 10.0f + 10.0f * 100.5f / 255.0f, o); /* halfway between 100 and 101 */
    TU_CHECK_NEAR(o[2], 0.5 * (t[4 * 100 + 2] + t[4 * 101 + 2]), 1e-5);
    TU_CHECK_NEAR(o[3], 3.0 * 0.5 * (t[4 * 100 + 3] + t[4 * 101 + 3]), 1e-4);
    clvr_tf_lookup(t, n, 10.0f, 20.0f, 3.0f, -1e30f, o); /* clamped below, above, NaN */
    TU_CHECK_NEAR(o[0], t[0], 0.0);
    clvr_tf_lookup(t, n, 10.0f, 20.0f, 3.0f, INFINITY, o);
    TU_CHECK_NEAR(o[0], t[4 * 255], 0.0);
    clvr_tf_lookup(t, n, 10.0f, 20.0f, 3.0f, NAN, o);
    TU_CHECK_NEAR(o[0], t[0], 0.0);
    free(t);
    clvr_tf_free(&tf);
}

/* Plain-double reference of the lookup's extinction, independent of the
 * shared code. */
static double ref_extinction(const float *t, uint32_t n, float lo, float hi, float density, float s)
{
    double p = ((double)s - lo) / ((double)hi - lo) * (n - 1);
    if (!(p > 0.0)) p = 0.0;
    if (p > n - 1) p = n - 1;
    uint32_t i = (uint32_t)p;
    if (i > n - 2) i = n - 2;
    double f = p - i;
    return density * ((1.0 - f) * t[4 * i + 3] + f * t[4 * i + 7]);
}

static void test_majorant(void)
{
    uint64_t rng = 12345;
    clvr_error err = {0};
    clvr_tf tf = {0};
    const int tfs = 200, intervals_per_tf = 500, samples = 12;
    uint64_t violations = 0, ref_violations = 0, tighter = 0, total = 0;
    double worst = 0.0;
    float *t = malloc(sizeof(float) * 4 * 400);
    for (int k = 0; k < tfs; ++k) {
        /* Random opacity curve (with steps and plateaus), table size, window. */
        char text[4096];
        int len = 0, np = 1 + (int)(tu_rand(&rng) % 12);
        float x = 0.0f;
        for (int i = 0; i < np; ++i) {
            if (tu_rand(&rng) % 4) x += tu_randf(&rng) * (1.0f - x) * 0.5f;
            float a = tu_rand(&rng) % 5 == 0 ? 0.0f : tu_randf(&rng);
            len += snprintf(text + len, sizeof text - (size_t)len, "opacity %.6f %.6f\n", x, a);
        }
        uint32_t n = 2 + (uint32_t)(tu_rand(&rng) % 399);
        len += snprintf(text + len, sizeof text - (size_t)len, "table %u\n", n);
        TU_CHECK_STATUS(clvr_tf_init(&tf, "jet", &err), CLVR_OK, &err);
        if (parse_str(&tf, text, &err) != CLVR_OK) { fprintf(stderr, "%s\n%s", err.msg, text); TU_CHECK(0); continue; }
        float lo = (tu_randf(&rng) - 0.5f) * 1000.0f, hi = lo + 1e-3f + tu_randf(&rng) * 500.0f;
        float density = tu_randf(&rng) * 10.0f;
        n = clvr_tf_table_size(&tf);
        clvr_tf_bake(&tf, t, n);
        float global = clvr_tf_majorant(t, n, lo, hi, density, -INFINITY, INFINITY);
        for (int j = 0; j < intervals_per_tf; ++j) {
            float span = hi - lo;
            float a = lo - 0.2f * span + tu_randf(&rng) * 1.4f * span;
            float b = tu_rand(&rng) % 8 == 0 ? a : a + tu_randf(&rng) * tu_randf(&rng) * span;
            if (tu_rand(&rng) % 10 == 0) { float c = a; a = b; b = c; } /* reversed interval */
            float m = clvr_tf_majorant(t, n, lo, hi, density, a, b);
            float amin = fminf(a, b), amax = fmaxf(a, b);
            for (int q = 0; q < samples; ++q) {
                float s = q == 0 ? amin : q == 1 ? amax : amin + tu_randf(&rng) * (amax - amin);
                float o[4];
                clvr_tf_lookup(t, n, lo, hi, density, s, o);
                if (o[3] > m) { ++violations; worst = fmax(worst, (double)o[3] - m); }
                if (ref_extinction(t, n, lo, hi, density, s) > (double)m * (1.0 + 1e-6)) ++ref_violations;
            }
            tighter += m < global;
            ++total;
        }
    }
    printf("majorant: %llu intervals, %llu lookups above the majorant (worst excess %g), %llu reference values above, "
           "%llu intervals with a majorant below the global one\n",
           (unsigned long long)total, (unsigned long long)violations, worst, (unsigned long long)ref_violations,
           (unsigned long long)tighter);
    TU_CHECK_EQ_U64(total, (uint64_t)tfs * intervals_per_tf);
    TU_CHECK_EQ_U64(violations, 0);
    TU_CHECK_EQ_U64(ref_violations, 0);
    /* Not a trivial bound: most intervals get less than the global maximum. */
    TU_CHECK(tighter > total / 4);
    /* Exactness on a known table: entries 0..4 with extinction 0,1,5,2,0. */
    const float tab[20] = {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 5, 0, 0, 0, 2, 0, 0, 0, 0};
    TU_CHECK_NEAR(clvr_tf_majorant(tab, 5, 0.0f, 4.0f, 1.0f, 0.0f, 0.5f), 1.0 * CLVR_TF_MAJORANT_SLACK, 1e-7);
    TU_CHECK_NEAR(clvr_tf_majorant(tab, 5, 0.0f, 4.0f, 1.0f, 3.0f, 4.0f), 2.0 * CLVR_TF_MAJORANT_SLACK, 1e-7);
    TU_CHECK_NEAR(clvr_tf_majorant(tab, 5, 0.0f, 4.0f, 2.0f, 1.5f, 1.5f), 10.0 * CLVR_TF_MAJORANT_SLACK, 1e-6);
    TU_CHECK_NEAR(clvr_tf_majorant(tab, 5, 0.0f, 4.0f, 1.0f, 9.0f, 12.0f), 2.0 * CLVR_TF_MAJORANT_SLACK, 1e-7);
    free(t);
    clvr_tf_free(&tf);
}

/* Each bad input: expected status, a fragment of the message and tf left as
 * it was. */
static void expect_bad(const char *text, size_t len, const char *where, const char *needle)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    clvr_tf_init(&tf, "viridis", &err);
    uint32_t nc = tf.num_colors;
    clvr_status s = clvr_tf_parse(&tf, text, len, "bad.tf", &err);
    if (s != CLVR_ERR_BAD_FIELD || !strstr(err.msg, where) || (needle && !strstr(err.msg, needle))) {
        fprintf(stderr, "input <<%.*s>>: got %s \"%s\", expected ERR_BAD_FIELD with \"%s\" and \"%s\"\n",
                (int)(len > 200 ? 200 : len), text, clvr_status_name(s), err.msg, where, needle ? needle : "");
        TU_CHECK(0);
    } else {
        TU_CHECK(1);
    }
    TU_CHECK_EQ_U64(tf.num_colors, nc);
    clvr_tf_free(&tf);
}
#define BAD(text, where, needle) expect_bad((text), strlen(text), (where), (needle))

static void test_text_format(void)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    TU_CHECK_STATUS(clvr_tf_init(&tf, NULL, &err), CLVR_OK, &err);
    const char *good = "# a transfer function\n"
                       "colorspace Lab\r\n"
                       "color 0   0 0 1   # blue\n"
                       "\n"
                       "color 1   1 1 0\n"
                       "opacity 0 0\n"
                       "opacity 0.5 0.25\n"
                       "opacity 1 1\n"
                       "range -2.5 7.5\n"
                       "density 2\n"
                       "table 64\n";
    TU_CHECK_STATUS(parse_str(&tf, good, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(tf.space, CLVR_TF_SPACE_LAB);
    TU_CHECK_EQ_U64(tf.num_colors, 2);
    TU_CHECK_EQ_U64(tf.num_opacity, 3);
    TU_CHECK(tf.range_set && tf.range_lo == -2.5f && tf.range_hi == 7.5f);
    TU_CHECK_NEAR(tf.density, 2.0, 0.0);
    TU_CHECK_EQ_U64(clvr_tf_table_size(&tf), 64);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.25f), 0.125, 1e-6);
    TU_CHECK_STATUS(parse_str(&tf, "colormap inferno\n", &err), CLVR_OK, &err);
    TU_CHECK(strcmp(tf.name, "inferno") == 0);
    CHECK_RGB(&tf, 1.0f, 0.988362, 0.998364, 0.644924, 1e-6);
    clvr_tf_free(&tf);

    BAD("", "bad.tf:1", "no transfer-function lines");
    BAD("# only a comment\n\n", "bad.tf:2", "no transfer-function lines");
    BAD("color 0 0 0 0\ncolor 1 1 1 1\nfoo 1\n", "bad.tf:3:", "unknown keyword \"foo\"");
    BAD("color 0 0 0\n", "bad.tf:1:", "4 numbers");
    BAD("color 0 0 0 0\ncolor 1 1.5 1 1\n", "bad.tf:2:", "\"1.5\"");
    BAD("color 0.5 0 0 0\ncolor 0.2 1 1 1\n", "bad.tf:2:", "must not decrease");
    BAD("opacity 0.5 1\nopacity 0.4 0\n", "bad.tf:2:", "must not decrease");
    BAD("opacity 0 abc\n", "bad.tf:1:", "\"abc\"");
    BAD("opacity 0 1 2\n", "bad.tf:1:", "opacity x a");
    BAD("opacity 0 0.5 0.5 1.5\n", "bad.tf:1:", "\"1.5\"");
    BAD("\n\nrange 5 5\n", "bad.tf:3:", "lo < hi");
    BAD("range 0 inf\n", "bad.tf:1:", "range lo hi");
    BAD("range 0 1e39\n", "bad.tf:1:", "range lo hi");
    BAD("density -1\n", "bad.tf:1:", "density d");
    BAD("density 1 2\n", "bad.tf:1:", "density d");
    BAD("density 1x\n", "bad.tf:1:", "density d");
    BAD("colormap nope\n", "bad.tf:1:", "unknown colormap \"nope\"");
    BAD("color 0 0 0 0\ncolormap jet\n", "bad.tf:2:", "colormap");
    BAD("colormap jet\ncolor 0 0 0 0\n", "bad.tf:2:", "colormap");
    BAD("colorspace CMYK\n", "bad.tf:1:", "colorspace");
    BAD("table 1\n", "bad.tf:1:", "table N");
    BAD("table 2.5\n", "bad.tf:1:", "table N");
    BAD("table 100000\n", "bad.tf:1:", "table N");
    BAD("color 0 0 0 0 0 0 0 0 0 0\n", "bad.tf:1:", "too many values");
    expect_bad("density 1\n\0", 11, "bad.tf:2:", "NUL");
    char longline[3000];
    memset(longline, ' ', sizeof longline);
    memcpy(longline, "density", 7);
    longline[sizeof longline - 2] = '1';
    longline[sizeof longline - 1] = '\n';
    expect_bad(longline, sizeof longline, "bad.tf:1:", "longer than");
}

static const char *k_paraview =
    "[\n"
    "  {\n"
    "    \"ColorSpace\" : \"Diverging\",\n"
    "    \"Creator\" : \"ParaView\",\n"
    "    \"Name\" : \"Cool to Warm \\u00e9\",\n"
    "    \"NanColor\" : [ 1, 1, 0 ],\n"
    "    \"Points\" : [ 10, 0, 0.5, 0, 15, 0.2, 0.3, 0, 30, 1, 0.5, 0.5 ],\n"
    "    \"RGBPoints\" : [ 10, 0.23137254902, 0.298039215686, 0.752941176471,\n"
    "                      20, 0.865, 0.865, 0.865,\n"
    "                      30, 0.705882352941, 0.0156862745098, 0.149019607843 ]\n"
    "  }\n"
    "]\n";

static void test_json(void)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    TU_CHECK_STATUS(clvr_tf_init(&tf, "viridis", &err), CLVR_OK, &err);
    TU_CHECK_STATUS(parse_str(&tf, k_paraview, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(tf.space, CLVR_TF_SPACE_DIVERGING);
    TU_CHECK(strcmp(tf.name, "Cool to Warm \xc3\xa9") == 0);
    TU_CHECK_EQ_U64(tf.num_colors, 3);
    TU_CHECK_EQ_U64(tf.num_opacity, 3);
    /* Positions 10..30 normalised to 0..1: the same map as the built-in one. */
    CHECK_RGB(&tf, 0.25f, 0.553524, 0.688407, 0.994915, 1e-3);
    TU_CHECK_NEAR(clvr_tf_opacity(&tf, 0.25f), 0.2, 1e-6);
    TU_CHECK_NEAR(tf.opacity[4 + 2], 0.3, 1e-7); /* midpoint kept */
    /* The data-space span is the window (--range overrides it later). */
    TU_CHECK(tf.range_set && tf.range_lo == 10.0f && tf.range_hi == 30.0f);
    /* A bare object, BOM, no Points (opacity stays), underflowing number. */
    TU_CHECK_STATUS(parse_str(&tf, "\xEF\xBB\xBF{\"RGBPoints\":[0,0,0,0, 1e-400,1,1,1, 2, 0.5, 0.5, 0.5]}", &err),
                    CLVR_OK, &err);
    TU_CHECK_EQ_U64(tf.space, CLVR_TF_SPACE_RGB);
    TU_CHECK_EQ_U64(tf.num_opacity, 3);
    /* Exporters' rounding noise just outside [0, 1] is accepted and clamped. */
    TU_CHECK_STATUS(parse_str(&tf, "[{\"RGBPoints\":[0,1.0000001,0,-1e-9, 1,0,0,0]}]", &err), CLVR_OK, &err);
    CHECK_RGB(&tf, 0.0f, 1.0, 0.0, 0.0, 0.0);
    clvr_tf_free(&tf);

    /* Every truncation of a valid document fails cleanly with a position. */
    size_t n = strlen(k_paraview);
    int trunc_bad = 0;
    for (size_t cut = 0; cut + 2 < n; ++cut) {
        clvr_tf t2 = {0};
        clvr_tf_init(&t2, NULL, &err);
        clvr_status s = clvr_tf_parse(&t2, k_paraview, cut, "cut.json", &err);
        /* The cut may leave only the text format's view of it (empty). */
        if (s != CLVR_ERR_BAD_FIELD || !strstr(err.msg, "cut.json:")) {
            fprintf(stderr, "truncated at %zu: %s %s\n", cut, clvr_status_name(s), err.msg);
            ++trunc_bad;
        }
        clvr_tf_free(&t2);
    }
    TU_CHECK_EQ_U64(trunc_bad, 0);

    /* Deep nesting: an error, not a stack overflow. */
    size_t depth = 100000;
    char *deep = malloc(depth);
    memset(deep, '[', depth);
    expect_bad(deep, depth, "bad.tf:1:65", "nested deeper");
    free(deep);

    BAD("[{\"RGBPoints\":[0,0,0,0,1e400,1,1,1]}]", "bad.tf:1:24", "out of range");
    BAD("[{\"RGBPoints\":[0,0,0,0,1e39,1,1,1]}]", "bad.tf:1:24", "out of range");
    BAD("[{\"RGBPoints\":[0,0,0,0,1,1,2,1]}]", "bad.tf:1:28", "out of range");
    BAD("[{\"RGBPoints\":\"0 0 0 0\"}]", "bad.tf:1:15", "must be an array");
    BAD("[{\"RGBPoints\":[0,0,0,\"x\"]}]", "bad.tf:1:22", "must be a number");
    BAD("[{\"RGBPoints\":[0,0,0,null]}]", "bad.tf:1:22", "found null");
    BAD("[{\"RGBPoints\":[0,0,0]}]", "bad.tf:1:15", "multiple of 4");
    BAD("[{\"RGBPoints\":[]}]", "bad.tf:1:15", "multiple of 4");
    BAD("[{\"RGBPoints\":[1,0,0,0, 0,1,1,1]}]", "bad.tf:1:25", "must not decrease");
    BAD("[{\"RGBPoints\":[1,0,0,0, 1,1,1,1]}]", "bad.tf:1:15", "positions are equal");
    BAD("[{\"ColorSpace\":3,\"RGBPoints\":[0,0,0,0]}]", "bad.tf:1:16", "ColorSpace");
    BAD("[{\"ColorSpace\":\"CMYK\",\"RGBPoints\":[0,0,0,0]}]", "bad.tf:1:16", "ColorSpace");
    BAD("[{\"Name\":[],\"RGBPoints\":[0,0,0,0]}]", "bad.tf:1:10", "\"Name\" must be a string");
    BAD("[{\"Name\":\"a\"}]", "bad.tf:1:2", "no \"RGBPoints\"");
    BAD("[{\"RGBPoints\":[0,0,0,0],\n \"RGBPoints\":[0,0,0,0]}]", "bad.tf:2:2", "duplicate key");
    BAD("[{\"RGBPoints\":[0,0,0,0],\"Points\":[0,2,0.5,0]}]", "bad.tf:1:37", "out of range");
    BAD("[{\"RGBPoints\":[0,0,0,0]}] x", "bad.tf:1:27", "after the end");
    BAD("[{\"RGBPoints\":[0,0,0,0],}]", "bad.tf:1:25", "member name");
    BAD("[{\"RGBPoints\" [0,0,0,0]}]", "bad.tf:1:15", "expected ':'");
    BAD("[{\"RGBPoints\":[0,0,0,0,]}]", "bad.tf:1:24", "expected a value");
    BAD("[{\"RGBPoints\":[0,0,0,01]}]", "bad.tf:1:23", "expected ',' or ']'");
    BAD("[{\"RGBPoints\":[0,0,0,1.]}]", "bad.tf:1:24", "after the decimal point");
    BAD("[{\"RGBPoints\":[0,0,0,-]}]", "bad.tf:1:23", "expected a digit");
    BAD("[{\"RGBPoints\":[0,0,0,1e+]}]", "bad.tf:1:25", "exponent");
    BAD("[{\"RGBPoints\":[0,0,0,.5]}]", "bad.tf:1:22", "expected a value");
    BAD("[{\"RGBPoints\":[0,0,0,tru]}]", "bad.tf:1:22", "invalid literal");
    BAD("[{\"Name\":\"a\\qb\",\"RGBPoints\":[0,0,0,0]}]", "bad.tf:1:12", "invalid escape");
    BAD("[{\"Name\":\"a\tb\",\"RGBPoints\":[0,0,0,0]}]", "bad.tf:1:12", "control character");
    BAD("[{\"Name\":\"\\ud800\",\"RGBPoints\":[0,0,0,0]}]", "bad.tf:1:", "surrogate");
    BAD("[{\"Name\":\"\\u12g4\",\"RGBPoints\":[0,0,0,0]}]", "bad.tf:1:", "hexadecimal");
    BAD("[{\"Name\":\"abc", "bad.tf:1:", "unterminated string");
    BAD("[]", "bad.tf:1:1", "empty array");
    BAD("[1]", "bad.tf:1:2", "found a number");
    BAD("{\"RGBPoints\":[0,0,0,0]", "bad.tf:1:23", "expected ',' or '}'");
    BAD("\n\n  [{\"RGBPoints\":\n[0,0,0,0,\n0.5,0,0,7]}]", "bad.tf:5:9", "out of range");
    char longnum[600] = "[{\"RGBPoints\":[0,0,0,0,1";
    size_t ln = strlen(longnum);
    memset(longnum + ln, '0', 500);
    strcpy(longnum + ln + 500, ",0,0,0]}]");
    BAD(longnum, "bad.tf:1:24", "longer than");

    /* Random corruption of valid inputs: OK or a clean error, never a crash
     * (run under CLVR_SANITIZE to catch memory errors). */
    uint64_t rng = 99;
    const char *seeds[2] = {k_paraview, "colorspace HSV\ncolor 0 1 0 0\ncolor 1 0 0 1\nopacity 0 0\nrange 0 1\n"};
    int fuzz_bad = 0;
    for (int it = 0; it < 20000; ++it) {
        const char *seed = seeds[it & 1];
        size_t len = strlen(seed);
        char *buf = malloc(len);
        memcpy(buf, seed, len);
        int flips = 1 + (int)(tu_rand(&rng) % 4);
        for (int f = 0; f < flips; ++f) {
            const char alphabet[] = "[]{}\",:0123456789.eE-+ \n\\ux";
            buf[tu_rand(&rng) % len] = tu_rand(&rng) % 3 ? alphabet[tu_rand(&rng) % (sizeof alphabet - 1)]
                                                          : (char)(tu_rand(&rng) & 0xff);
        }
        clvr_tf t3 = {0};
        clvr_tf_init(&t3, NULL, &err);
        clvr_status s = clvr_tf_parse(&t3, buf, tu_rand(&rng) % 5 ? len : tu_rand(&rng) % len, "fuzz", &err);
        if (s != CLVR_OK && (s != CLVR_ERR_BAD_FIELD || strncmp(err.msg, "fuzz:", 5))) ++fuzz_bad;
        if (s == CLVR_OK) {
            float tab[64];
            clvr_tf_bake(&t3, tab, 16);
            for (int i = 0; i < 64; ++i) fuzz_bad += !isfinite(tab[i]) || tab[i] < 0.0f;
        }
        clvr_tf_free(&t3);
        free(buf);
    }
    TU_CHECK_EQ_U64(fuzz_bad, 0);
}

static void test_from_options_and_files(void)
{
    clvr_error err = {0};
    clvr_tf tf = {0};
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, "inferno", NULL, 0, 0, 0, 2.0f, -3.0f, 5.0f, &err), CLVR_OK, &err);
    TU_CHECK(tf.range_lo == -3.0f && tf.range_hi == 5.0f);
    TU_CHECK_NEAR(tf.density, 2.0, 0.0);
    TU_CHECK(strcmp(tf.name, "inferno") == 0);
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, NULL, NULL, 1, 1.0f, 2.0f, 1.0f, -3.0f, 5.0f, &err), CLVR_OK, &err);
    TU_CHECK(tf.range_lo == 1.0f && tf.range_hi == 2.0f && strcmp(tf.name, "cool-warm") == 0);
    /* A constant field gets a small window around its value. */
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, NULL, NULL, 0, 0, 0, 1.0f, 4.0f, 4.0f, &err), CLVR_OK, &err);
    TU_CHECK(tf.range_lo < 4.0f && tf.range_hi > 4.0f);
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, NULL, NULL, 0, 0, 0, 1.0f, NAN, 4.0f, &err), CLVR_ERR_BAD_VALUE, &err);
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, "rainbow", NULL, 0, 0, 0, 1.0f, 0, 1, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "cool-warm, viridis, inferno, grayscale, jet") != NULL);

    char dir[] = "/tmp/clvr_test_tf_XXXXXX";
    if (!mkdtemp(dir)) { TU_CHECK(0); return; }
    char path[256], missing[256];
    snprintf(path, sizeof path, "%s/my.tf", dir);
    snprintf(missing, sizeof missing, "%s/missing.tf", dir);
    FILE *f = fopen(path, "w");
    fputs("colormap viridis\nrange 10 20\ndensity 3\n", f);
    fclose(f);
    /* File range wins over the data range; --range over the file; densities multiply. */
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, "jet", path, 0, 0, 0, 2.0f, 0.0f, 1.0f, &err), CLVR_OK, &err);
    TU_CHECK(tf.range_lo == 10.0f && tf.range_hi == 20.0f && strcmp(tf.name, "viridis") == 0);
    TU_CHECK_NEAR(tf.density, 6.0, 1e-6);
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, "jet", path, 1, -1.0f, 1.0f, 1.0f, 0.0f, 1.0f, &err), CLVR_OK, &err);
    TU_CHECK(tf.range_lo == -1.0f && tf.range_hi == 1.0f);
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, NULL, missing, 0, 0, 0, 1.0f, 0.0f, 1.0f, &err), CLVR_ERR_IO, &err);
    TU_CHECK(strstr(err.msg, missing) != NULL);
    f = fopen(path, "w");
    fputs("colormap viridis\nrange 10 20\ndensity -3\n", f);
    fclose(f);
    TU_CHECK_STATUS(clvr_tf_from_options(&tf, NULL, path, 0, 0, 0, 1.0f, 0.0f, 1.0f, &err), CLVR_ERR_BAD_FIELD, &err);
    char where[300];
    snprintf(where, sizeof where, "%s:3:", path);
    TU_CHECK(strstr(err.msg, where) != NULL);
    unlink(path);
    rmdir(dir);
    clvr_tf_free(&tf);
}

/* Two exports that ParaView renders alike: opacity points over a wider span
 * than the colours (constant colour beyond its ends) and the same map with
 * the colours' end points repeated at the opacity span. One common span
 * rescales both, so both bake to the same table and the same window. */
static void test_json_common_span_and_presets(void)
{
    clvr_error err = {0};
    clvr_tf a = {0}, b = {0};
    const char *ja = "[{\"RGBPoints\":[0,0,0,1, 10,1,0,0],\"Points\":[-10,0,0.5,0, 20,1,0.5,0]}]";
    const char *jb = "[{\"RGBPoints\":[-10,0,0,1, 0,0,0,1, 10,1,0,0, 20,1,0,0],"
                     "\"Points\":[-10,0,0.5,0, 5,0.5,0.5,0, 20,1,0.5,0]}]";
    TU_CHECK_STATUS(clvr_tf_init(&a, NULL, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_tf_init(&b, NULL, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(parse_str(&a, ja, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(parse_str(&b, jb, &err), CLVR_OK, &err);
    TU_CHECK(a.range_set && a.range_lo == -10.0f && a.range_hi == 20.0f);
    TU_CHECK(b.range_set && b.range_lo == -10.0f && b.range_hi == 20.0f);
    float ta[4 * 64], tb[4 * 64];
    clvr_tf_bake(&a, ta, 64);
    clvr_tf_bake(&b, tb, 64);
    double worst = 0.0;
    for (int i = 0; i < 4 * 64; ++i) worst = fmax(worst, fabs((double)ta[i] - tb[i]));
    TU_CHECK_NEAR(worst, 0.0, 1e-5);
    /* Data value 0 (x = 1/3): the first colour, opacity 1/3. */
    CHECK_RGB(&a, 1.0f / 3.0f, 0.0, 0.0, 1.0, 1e-5);
    TU_CHECK_NEAR(clvr_tf_opacity(&a, 1.0f / 3.0f), 1.0 / 3.0, 1e-5);

    /* A presets file: pick by name; an unknown name lists the names. */
    const char *presets = "[{\"Name\":\"Blue\",\"RGBPoints\":[0,0,0,1, 1,0,0,1]},"
                          "{\"Name\":\"Red\",\"RGBPoints\":[5,1,0,0, 7,1,0,0]}]";
    TU_CHECK_STATUS(clvr_tf_parse_preset(&a, presets, strlen(presets), "p.json", "Red", &err), CLVR_OK, &err);
    TU_CHECK(strcmp(a.name, "Red") == 0 && a.range_lo == 5.0f && a.range_hi == 7.0f);
    CHECK_RGB(&a, 0.5f, 1.0, 0.0, 0.0, 0.0);
    TU_CHECK_STATUS(clvr_tf_parse_preset(&a, presets, strlen(presets), "p.json", "Green", &err), CLVR_ERR_BAD_FIELD,
                    &err);
    TU_CHECK(strstr(err.msg, "p.json: no colour map named \"Green\"; the file has \"Blue\", \"Red\"") != NULL);
    TU_CHECK_STATUS(clvr_tf_parse_preset(&a, "color 0 1 1 1\n", 14, "t.tf", "Red", &err), CLVR_ERR_BAD_FIELD, &err);
    TU_CHECK(strstr(err.msg, "ParaView JSON only") != NULL);

    /* FILE:PRESET through the loader, and --range stretching the common span. */
    char dir[] = "/tmp/clvr_test_tfp_XXXXXX";
    if (!mkdtemp(dir)) { TU_CHECK(0); return; }
    char path[256], spec[300];
    snprintf(path, sizeof path, "%s/presets.json", dir);
    FILE *f = fopen(path, "w");
    fputs(presets, f);
    fclose(f);
    snprintf(spec, sizeof spec, "%s:Red", path);
    TU_CHECK_STATUS(clvr_tf_load(&b, spec, &err), CLVR_OK, &err);
    TU_CHECK(strcmp(b.name, "Red") == 0);
    snprintf(spec, sizeof spec, "%s:Nope", path);
    TU_CHECK_STATUS(clvr_tf_load(&b, spec, &err), CLVR_ERR_BAD_FIELD, &err);
    TU_CHECK(strstr(err.msg, "\"Blue\", \"Red\"") != NULL);
    clvr_tf_free(&b);
    snprintf(spec, sizeof spec, "%s:Blue", path);
    TU_CHECK_STATUS(clvr_tf_from_options(&b, NULL, spec, 1, 100.0f, 200.0f, 1.0f, 0.0f, 1.0f, &err), CLVR_OK, &err);
    TU_CHECK(b.range_lo == 100.0f && b.range_hi == 200.0f && strcmp(b.name, "Blue") == 0);
    unlink(path);
    rmdir(dir);
    clvr_tf_free(&a);
    clvr_tf_free(&b);
}

int main(void)
{
    test_colormaps();
    test_color_spaces();
    test_opacity();
    test_bake_and_lookup();
    test_majorant();
    test_text_format();
    test_json();
    test_json_common_span_and_presets();
    test_from_options_and_files();
    return tu_finish("test_tf");
}
