/* test_tf_auto: the automatic transfer function (host/io/tf_auto.h, issue 17).
 *
 * - A synthetic field where 90% of the volume holds one value (0.5) and the
 *   rest holds values spread over [0, 1]: the dominant value's opacity is
 *   low (<= 0.05), the rare values' high (their volume-weighted mean >= 0.4,
 *   the extremes >= 0.8); the linear ramp (the old default) gives the
 *   dominant value 0.5, so the check tells the two apart.
 * - Real data (tests/data/vtk/post.vtk, notch_stress.vtk) and the built-in
 *   scene: the histogram's most common bin gets opacity <= 0.1 (<= 0.01 when
 *   it holds half the volume or more: notch_stress, the scene), and the
 *   opacity rises to >= 0.8 somewhere (rare values are shown).
 * - The probe's median optical depth on a homogeneous box matches the
 *   median of exact chords through it (within 3%); the automatic density
 *   is set from the probe on every mesh above (unclamped); the camera-ray
 *   figure is checked end to end by tests/test_tf_auto.py.
 * - A constant field keeps the ramp; a --tf file's opacity points are
 *   flagged (clvr's main then leaves them alone). */
#include "test_util.h"

#include "mesh_io.h"
#include "scene.h"
#include "tf.h"
#include "tf_auto.h"

static float opacity_at(const clvr_tf *tf, float s)
{
    return clvr_tf_opacity(tf, (s - tf->range_lo) / (tf->range_hi - tf->range_lo));
}

/* Builds the default transfer function over m's data range with the
 * automatic opacity, as clvr's main does. */
static void auto_tf(const clvr_mesh *m, clvr_tf *tf, double *hist)
{
    clvr_error err;
    TU_CHECK(clvr_tf_from_options(tf, NULL, NULL, 0, 0, 0, 1.0f, m->scalar_min, m->scalar_max, &err) == CLVR_OK);
    clvr_tf_set_extent(tf, m->bounds_lo, m->bounds_hi);
    clvr_tf_auto_histogram(m, tf->range_lo, tf->range_hi, hist, CLVR_TF_AUTO_BINS);
    TU_CHECK(clvr_tf_auto_opacity(tf, hist, CLVR_TF_AUTO_BINS, &err) == CLVR_OK);
}

static void check_density(const clvr_mesh *m, clvr_tf *tf, const char *what)
{
    clvr_error err;
    float d = 0.0f, med = 0.0f, med_ramp = 0.0f;
    TU_CHECK(clvr_tf_auto_density(m, tf, &d, &err) == CLVR_OK);
    /* Not clamped: the probe saw the medium. (The probe at density d then
     * reads CLVR_TF_AUTO_DEPTH by construction, the probe being linear in
     * the density; the probe itself is checked against exact chords in
     * test_probe_exact.) */
    TU_CHECK(d > 1e-3f && d < 1e4f);
    tf->density = d;
    TU_CHECK(clvr_tf_auto_probe(m, tf, &med, &err) == CLVR_OK);
    clvr_tf ramp = {0};
    TU_CHECK(clvr_tf_from_options(&ramp, NULL, NULL, 0, 0, 0, 1.0f, m->scalar_min, m->scalar_max, &err) == CLVR_OK);
    clvr_tf_set_extent(&ramp, m->bounds_lo, m->bounds_hi);
    TU_CHECK(clvr_tf_auto_probe(m, &ramp, &med_ramp, &err) == CLVR_OK);
    printf("%s: automatic density %.3g: probe median optical depth %.3f (the ramp at density 1: %.3f)\n", what,
           (double)d, (double)med, (double)med_ramp);
    clvr_tf_free(&ramp);
}

/* Most common bin's opacity low, some bin's high. */
static void check_real(const clvr_mesh *m, const char *what)
{
    clvr_tf tf = {0};
    double hist[CLVR_TF_AUTO_BINS], total = 0.0;
    auto_tf(m, &tf, hist);
    uint32_t mode = 0;
    for (uint32_t b = 0; b < CLVR_TF_AUTO_BINS; ++b) {
        total += hist[b];
        if (hist[b] > hist[mode]) mode = b;
    }
    float w = (tf.range_hi - tf.range_lo) / CLVR_TF_AUTO_BINS, amax = 0.0f;
    float a_mode = opacity_at(&tf, tf.range_lo + (mode + 0.5f) * w);
    for (uint32_t b = 0; b < CLVR_TF_AUTO_BINS; ++b) amax = fmaxf(amax, opacity_at(&tf, tf.range_lo + (b + 0.5f) * w));
    printf("%s: the most common bin (%u, %.1f%% of the volume) has opacity %.3f; the largest opacity is %.3f\n", what,
           mode, 100.0 * hist[mode] / total, (double)a_mode, (double)amax);
    /* post.vtk's most common bin holds only 8.8% (5.6x a uniform share, next
     * to the smoothed mode): 0.085. Where one bin fills most: 0. */
    TU_CHECK(a_mode <= (hist[mode] >= 0.5 * total ? 0.01f : 0.1f));
    TU_CHECK(amax >= 0.8f);
    check_density(m, &tf, what);
    clvr_tf_free(&tf);
}

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 33;
}

static void test_synthetic(void)
{
    clvr_error err;
    clvr_mesh m = {0};
    clvr_scene_box_params p;
    clvr_scene_box_params_init(&p);
    p.nx = p.ny = p.nz = 40;
    TU_CHECK(clvr_scene_box(&p, &m, &err) == CLVR_OK);
    /* Vertices with x >= 0.925 (the last 3 of 40 cube layers and their
     * shared face) take random values in [0, 1]; the rest 0.5. */
    uint64_t seed = 7;
    for (uint64_t v = 0; v < m.num_vertices; ++v) {
        float x = m.positions[3 * v];
        m.scalars[v] = x >= 0.925f - 1e-6f ? (float)(lcg(&seed) % 100001) / 100000.0f : 0.5f;
    }
    clvr_mesh_update_ranges(&m);
    clvr_tf tf = {0};
    double hist[CLVR_TF_AUTO_BINS], total = 0.0;
    auto_tf(&m, &tf, hist);
    for (uint32_t b = 0; b < CLVR_TF_AUTO_BINS; ++b) total += hist[b];
    uint32_t dom = (uint32_t)((0.5f - tf.range_lo) / (tf.range_hi - tf.range_lo) * CLVR_TF_AUTO_BINS);
    double dom_share = hist[dom] / total;
    TU_CHECK(dom_share >= 0.88 && dom_share <= 0.93); /* the premise: ~90% of the volume holds 0.5 */
    float a_dom = opacity_at(&tf, 0.5f);
    /* Volume-weighted mean opacity of the rare values (vertex share of each element). */
    double rare_a = 0.0, rare_w = 0.0;
    for (uint64_t c = 0; c < m.num_cells[CLVR_CELL_HEX]; ++c) {
        const uint32_t *idx = m.indices[CLVR_CELL_HEX] + 8 * c;
        double vol = clvr_scene_cell_volume(CLVR_CELL_HEX, m.positions, idx) / 8.0;
        for (int k = 0; k < 8; ++k) {
            float s = m.scalars[idx[k]];
            if (s == 0.5f) continue;
            rare_a += vol * opacity_at(&tf, s);
            rare_w += vol;
        }
    }
    float a_lo = opacity_at(&tf, 0.03f), a_hi = opacity_at(&tf, 0.97f);
    printf("synthetic: %.1f%% of the volume at 0.5 has opacity %.3f; the rare values' mean opacity %.3f, at 0.03 and "
           "0.97: %.3f, %.3f\n",
           100.0 * dom_share, (double)a_dom, rare_a / rare_w, (double)a_lo, (double)a_hi);
    TU_CHECK(a_dom <= 0.05f);
    TU_CHECK(rare_a / rare_w >= 0.4);
    TU_CHECK(a_lo >= 0.8f && a_hi >= 0.8f);
    /* The old default, the ramp, fails the first of these. */
    clvr_tf ramp = {0};
    TU_CHECK(clvr_tf_from_options(&ramp, NULL, NULL, 0, 0, 0, 1.0f, m.scalar_min, m.scalar_max, &err) == CLVR_OK);
    TU_CHECK(opacity_at(&ramp, 0.5f) > 0.4f);
    TU_CHECK(!ramp.opacity_set);
    check_density(&m, &tf, "synthetic");
    clvr_tf_free(&ramp);
    clvr_tf_free(&tf);
    clvr_mesh_free(&m);
}

static void test_real(const char *rel)
{
    const char *dir = getenv("CLVR_SHARED_DATA");
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir ? dir : "tests/data", rel);
    clvr_mesh m = {0};
    clvr_error err;
    clvr_load_options lo = {0};
    if (clvr_mesh_load(path, &lo, &m, &err) != CLVR_OK) {
        fprintf(stderr, "%s\n", err.msg);
        TU_CHECK(0);
        return;
    }
    check_real(&m, rel);
    clvr_mesh_free(&m);
}

/* A constant field has nothing rarer than anything else: the ramp stays, so
 * it renders as a uniform medium (tests/hostile: constant_field is visible). */
static void test_constant(void)
{
    clvr_error err;
    clvr_mesh m = {0};
    clvr_scene_box_params p;
    clvr_scene_box_params_init(&p);
    TU_CHECK(clvr_scene_box(&p, &m, &err) == CLVR_OK);
    clvr_tf tf = {0};
    double hist[CLVR_TF_AUTO_BINS];
    auto_tf(&m, &tf, hist);
    TU_CHECK_EQ_U64(tf.num_opacity, 2);
    TU_CHECK_NEAR(opacity_at(&tf, 1.0f), 0.5, 1e-3); /* the window is centred on the value */
    clvr_tf_free(&tf);
    clvr_mesh_free(&m);
}

/* The probe (clvr_tf_auto_probe: extinction deposited on a grid, parallel
 * rays marched through it) against exact chords: a homogeneous box of 2 x 1
 * x 0.5 (hexes, the constant field's ramp: opacity 0.5 everywhere), the
 * probe's own rays (48 x 48 across each of its 7 directions, the axes and
 * the diagonals, spanning the box's extent across the ray), each ray's
 * depth the extinction times its exact chord through the box; the median
 * over the rays that meet the box, within 3%. */
static void test_probe_exact(void)
{
    clvr_error err;
    clvr_mesh m = {0};
    clvr_scene_box_params p;
    clvr_scene_box_params_init(&p);
    p.nx = 20, p.ny = 10, p.nz = 5;
    p.hi[0] = 2.0f, p.hi[1] = 1.0f, p.hi[2] = 0.5f;
    TU_CHECK(clvr_scene_box(&p, &m, &err) == CLVR_OK);
    clvr_tf tf = {0};
    double hist[CLVR_TF_AUTO_BINS];
    auto_tf(&m, &tf, hist);
    tf.density = 1.0f;
    const double sigma = clvr_tf_extinction_scale(&tf) * opacity_at(&tf, 1.0f);
    float med = 0.0f;
    TU_CHECK(clvr_tf_auto_probe(&m, &tf, &med, &err) == CLVR_OK);
    enum { N = 48 };
    static const double dirs[7][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {-1, 1, 1}, {1, -1, 1}, {1, 1, -1}};
    double ext[3], ctr[3], depth[7 * N * N], dmax = 0.0;
    for (int a = 0; a < 3; ++a) {
        ext[a] = (double)m.bounds_hi[a] - m.bounds_lo[a];
        ctr[a] = m.bounds_lo[a] + 0.5 * ext[a];
    }
    int nd = 0;
    for (int di = 0; di < 7; ++di) {
        double d[3], u[3], v[3], e[3] = {0, 0, 0};
        const double dl = sqrt(dirs[di][0] * dirs[di][0] + dirs[di][1] * dirs[di][1] + dirs[di][2] * dirs[di][2]);
        for (int a = 0; a < 3; ++a) d[a] = dirs[di][a] / dl;
        e[fabs(d[0]) <= fabs(d[1]) && fabs(d[0]) <= fabs(d[2]) ? 0 : fabs(d[1]) <= fabs(d[2]) ? 1 : 2] = 1.0;
        u[0] = d[1] * e[2] - d[2] * e[1], u[1] = d[2] * e[0] - d[0] * e[2], u[2] = d[0] * e[1] - d[1] * e[0];
        const double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (int a = 0; a < 3; ++a) u[a] /= ul;
        v[0] = d[1] * u[2] - d[2] * u[1], v[1] = d[2] * u[0] - d[0] * u[2], v[2] = d[0] * u[1] - d[1] * u[0];
        double ur = 0.0, vr = 0.0;
        for (int a = 0; a < 3; ++a) {
            ur += 0.5 * ext[a] * fabs(u[a]);
            vr += 0.5 * ext[a] * fabs(v[a]);
        }
        for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i) {
                const double cu = ur * (2.0 * (i + 0.5) / N - 1.0), cv = vr * (2.0 * (j + 0.5) / N - 1.0);
                double t0 = -INFINITY, t1 = INFINITY;
                for (int a = 0; a < 3; ++a) {
                    const double o = ctr[a] + cu * u[a] + cv * v[a];
                    if (fabs(d[a]) < 1e-12) {
                        if (o < m.bounds_lo[a] || o > m.bounds_hi[a]) t1 = -INFINITY;
                        continue;
                    }
                    const double ta = (m.bounds_lo[a] - o) / d[a], tb = (m.bounds_hi[a] - o) / d[a];
                    t0 = fmax(t0, fmin(ta, tb));
                    t1 = fmin(t1, fmax(ta, tb));
                }
                depth[nd] = t1 > t0 ? sigma * (t1 - t0) : 0.0;
                dmax = fmax(dmax, depth[nd++]);
            }
    }
    int k = 0;
    for (int i = 0; i < nd; ++i)
        if (depth[i] > 1e-3 * dmax) depth[k++] = depth[i];
    /* median by insertion sort: a few thousand values */
    for (int i = 1; i < k; ++i)
        for (int j = i; j > 0 && depth[j - 1] > depth[j]; --j) {
            const double t = depth[j];
            depth[j] = depth[j - 1];
            depth[j - 1] = t;
        }
    const double want = k % 2 ? depth[k / 2] : 0.5 * (depth[k / 2 - 1] + depth[k / 2]);
    printf("probe on a homogeneous 2 x 1 x 0.5 box: median optical depth %.4f, exact chords %.4f\n", (double)med,
           want);
    TU_CHECK(k > 7 * N * N / 2);
    TU_CHECK_NEAR(med, want, 0.03 * want);
    clvr_tf_free(&tf);
    clvr_mesh_free(&m);
}

static void test_file_points_win(void)
{
    /* A file with opacity points sets opacity_set (main then keeps them);
     * one with colours only does not. */
    clvr_tf tf = {0};
    clvr_error err;
    TU_CHECK(clvr_tf_init(&tf, NULL, &err) == CLVR_OK);
    const char *with = "opacity 0 0\nopacity 1 0.3\n", *without = "colormap viridis\n";
    TU_CHECK(clvr_tf_parse(&tf, with, strlen(with), "with", &err) == CLVR_OK);
    TU_CHECK(tf.opacity_set);
    TU_CHECK(clvr_tf_init(&tf, NULL, &err) == CLVR_OK);
    TU_CHECK(!tf.opacity_set);
    TU_CHECK(clvr_tf_parse(&tf, without, strlen(without), "without", &err) == CLVR_OK);
    TU_CHECK(!tf.opacity_set);
    clvr_tf_free(&tf);
}

int main(void)
{
    test_probe_exact();
    test_synthetic();
    test_real("vtk/post.vtk");
    test_real("vtk/notch_stress.vtk");
    {
        clvr_mesh m = {0};
        clvr_error err;
        TU_CHECK(clvr_scene_default(&m, &err) == CLVR_OK);
        check_real(&m, "built-in scene");
        clvr_mesh_free(&m);
    }
    test_constant();
    test_file_points_win();
    return tu_finish("test_tf_auto");
}
