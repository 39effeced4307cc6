/* test_scene: the built-in scene, the parametrised boxes and clvr-gen's
 * outputs are valid meshes that tile their domains: every index in range,
 * every element of positive volume (VTK conventions), volumes summing to the
 * domain's (no gaps, no overlaps). With --slow: the same on multi-million
 * element clvr-gen outputs. */
#include "test_util.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "mesh_io.h"
#include "scene.h"

typedef struct vol_stats {
    double sum, min, max;
    uint64_t nonpositive, elements;
} vol_stats;

static void volume_stats(const clvr_mesh *m, vol_stats *st)
{
    st->sum = 0.0;
    st->min = INFINITY;
    st->max = -INFINITY;
    st->nonpositive = st->elements = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        for (uint64_t e = 0; e < m->num_cells[t]; ++e) {
            double v = clvr_scene_cell_volume(t, m->positions, m->indices[t] + e * nv);
            st->sum += v;
            st->min = fmin(st->min, v);
            st->max = fmax(st->max, v);
            st->nonpositive += !(v > 0.0);
            ++st->elements;
        }
    }
}

/* Valid indices, positive elements, volumes summing to domain_volume. */
static void check_tiling(const clvr_mesh *m, double domain_volume, const char *name)
{
    clvr_error err = {0};
    vol_stats st;
    TU_CHECK_STATUS(clvr_mesh_validate(m, name, &err), CLVR_OK, &err);
    volume_stats(m, &st);
    if (st.nonpositive) fprintf(stderr, "%s: %" PRIu64 " non-positive elements\n", name, st.nonpositive);
    TU_CHECK_EQ_U64(st.nonpositive, 0);
    TU_CHECK_NEAR(st.sum / domain_volume, 1.0, 1e-4);
}

static void set_box(clvr_scene_box_params *p, uint32_t nx, uint32_t ny, uint32_t nz, clvr_scene_mix mix)
{
    clvr_scene_box_params_init(p);
    p->nx = nx;
    p->ny = ny;
    p->nz = nz;
    p->lo[0] = -1.5f;
    p->lo[1] = 0.25f;
    p->lo[2] = 2.0f;
    p->hi[0] = 0.5f;
    p->hi[1] = 1.0f;
    p->hi[2] = 5.0f;
    p->mix = mix;
}

static double box_volume(const clvr_scene_box_params *p)
{
    return ((double)p->hi[0] - p->lo[0]) * ((double)p->hi[1] - p->lo[1]) * ((double)p->hi[2] - p->lo[2]);
}

/* Unit elements in VTK order, checked against vtkCellValidator (VTK 9.1):
 * the wedge below is valid there, its mirror is "faces oriented incorrectly". */
static void test_volume_conventions(void)
{
    const float x[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 0.5f, 0.5f, 1};
    const uint32_t tet[4] = {0, 1, 3, 4}, pyr[5] = {0, 1, 2, 3, 8}, hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    const uint32_t wedge[6] = {0, 3, 1, 4, 7, 5}; /* (0,0,0) (0,1,0) (1,0,0) over z = 1 */
    TU_CHECK_NEAR(clvr_scene_cell_volume(CLVR_CELL_TET, x, tet), 1.0 / 6.0, 1e-12);
    TU_CHECK_NEAR(clvr_scene_cell_volume(CLVR_CELL_PYRAMID, x, pyr), 1.0 / 3.0, 1e-12);
    TU_CHECK_NEAR(clvr_scene_cell_volume(CLVR_CELL_WEDGE, x, wedge), 0.5, 1e-12);
    TU_CHECK_NEAR(clvr_scene_cell_volume(CLVR_CELL_HEX, x, hex), 1.0, 1e-12);
    /* Mirrored elements are negative: the checks below can fail. */
    const uint32_t tet_m[4] = {0, 3, 1, 4}, wedge_m[6] = {0, 1, 3, 4, 5, 7}, hex_m[8] = {0, 3, 2, 1, 4, 7, 6, 5};
    TU_CHECK(clvr_scene_cell_volume(CLVR_CELL_TET, x, tet_m) < 0.0);
    TU_CHECK(clvr_scene_cell_volume(CLVR_CELL_WEDGE, x, wedge_m) < 0.0);
    TU_CHECK(clvr_scene_cell_volume(CLVR_CELL_HEX, x, hex_m) < 0.0);
}

static void test_box_single_types(void)
{
    static const clvr_scene_mix mixes[4] = {CLVR_SCENE_MIX_TET, CLVR_SCENE_MIX_PYRAMID, CLVR_SCENE_MIX_WEDGE,
                                            CLVR_SCENE_MIX_HEX}; /* by CLVR_CELL_* */
    static const uint64_t per_cube[4] = {6, 6, 2, 1};
    static const uint32_t sizes[3][3] = {{1, 1, 1}, {3, 5, 7}, {8, 2, 3}};
    for (uint32_t t = 0; t < 4; ++t)
        for (int sz = 0; sz < 3; ++sz)
            for (int jit = 0; jit < 2; ++jit) {
                clvr_scene_box_params p;
                clvr_mesh m;
                clvr_error err = {0};
                char name[64];
                set_box(&p, sizes[sz][0], sizes[sz][1], sizes[sz][2], mixes[t]);
                p.jitter = jit ? 0.15f : 0.0f;
                p.seed = 7;
                snprintf(name, sizeof name, "box %s %ux%ux%u jitter %g", clvr_cell_type_name(t), p.nx, p.ny, p.nz,
                         (double)p.jitter);
                TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_OK, &err);
                const uint64_t cubes = (uint64_t)p.nx * p.ny * p.nz;
                const uint64_t lattice = (uint64_t)(p.nx + 1) * (p.ny + 1) * (p.nz + 1);
                for (uint32_t u = 0; u < 4; ++u) TU_CHECK_EQ_U64(m.num_cells[u], u == t ? per_cube[t] * cubes : 0);
                TU_CHECK_EQ_U64(m.num_vertices, lattice + (t == CLVR_CELL_PYRAMID ? cubes : 0));
                for (int a = 0; a < 3; ++a) {
                    TU_CHECK_NEAR(m.bounds_lo[a], p.lo[a], 0.0);
                    TU_CHECK_NEAR(m.bounds_hi[a], p.hi[a], 0.0);
                }
                check_tiling(&m, box_volume(&p), name);
                clvr_mesh_free(&m);
            }
}

/* Jitter moves interior lattice vertices only, and deterministically. */
static void test_box_jitter(void)
{
    clvr_scene_box_params p;
    clvr_mesh a, b;
    clvr_error err = {0};
    set_box(&p, 4, 3, 5, CLVR_SCENE_MIX_HEX);
    TU_CHECK_STATUS(clvr_scene_box(&p, &a, &err), CLVR_OK, &err);
    p.jitter = 0.2f;
    p.seed = 99;
    TU_CHECK_STATUS(clvr_scene_box(&p, &b, &err), CLVR_OK, &err);
    uint64_t moved_interior = 0, moved_boundary = 0;
    for (uint32_t k = 0; k <= p.nz; ++k)
        for (uint32_t j = 0; j <= p.ny; ++j)
            for (uint32_t i = 0; i <= p.nx; ++i) {
                uint64_t v = ((uint64_t)k * (p.ny + 1) + j) * (p.nx + 1) + i;
                int moved = memcmp(a.positions + 3 * v, b.positions + 3 * v, 3 * sizeof(float)) != 0;
                int interior = i > 0 && i < p.nx && j > 0 && j < p.ny && k > 0 && k < p.nz;
                if (interior) moved_interior += moved;
                else moved_boundary += moved;
            }
    TU_CHECK_EQ_U64(moved_interior, (uint64_t)(p.nx - 1) * (p.ny - 1) * (p.nz - 1));
    TU_CHECK_EQ_U64(moved_boundary, 0);
    clvr_mesh c;
    TU_CHECK_STATUS(clvr_scene_box(&p, &c, &err), CLVR_OK, &err);
    TU_CHECK(memcmp(b.positions, c.positions, 3 * sizeof(float) * b.num_vertices) == 0);
    clvr_mesh_free(&a);
    clvr_mesh_free(&b);
    clvr_mesh_free(&c);
}

static void test_box_mixed(void)
{
    static const uint32_t sizes[3][3] = {{1, 1, 1}, {2, 3, 5}, {17, 13, 11}};
    for (int mx = 0; mx < 2; ++mx)
        for (int sz = 0; sz < 3; ++sz) {
            clvr_scene_box_params p;
            clvr_mesh m;
            clvr_error err = {0};
            char name[64];
            set_box(&p, sizes[sz][0], sizes[sz][1], sizes[sz][2], mx ? CLVR_SCENE_MIX_MIXED : CLVR_SCENE_MIX_CYCLE);
            p.field = CLVR_SCENE_FIELD_BLOBS;
            snprintf(name, sizeof name, "box %s %ux%ux%u", mx ? "mixed" : "cycle", p.nx, p.ny, p.nz);
            TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_OK, &err);
            check_tiling(&m, box_volume(&p), name);
            uint64_t nv, nc[4];
            TU_CHECK_STATUS(clvr_scene_box_count(&p, &nv, nc, &err), CLVR_OK, &err);
            TU_CHECK_EQ_U64(nv, m.num_vertices);
            for (uint32_t t = 0; t < 4; ++t) TU_CHECK_EQ_U64(nc[t], m.num_cells[t]);
            if (!mx && sz > 0)
                for (uint32_t t = 0; t < 4; ++t) TU_CHECK(m.num_cells[t] > 0);
            clvr_mesh_free(&m);
        }
}

static void test_box_fields(void)
{
    clvr_scene_box_params p;
    clvr_mesh m;
    clvr_error err = {0};
    set_box(&p, 5, 4, 3, CLVR_SCENE_MIX_PYRAMID); /* centre vertices too */
    p.field = CLVR_SCENE_FIELD_RAMP_X;
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_OK, &err);
    double worst = 0.0;
    for (uint64_t v = 0; v < m.num_vertices; ++v)
        worst = fmax(worst, fabs(m.scalars[v] - (m.positions[3 * v] - p.lo[0]) / (p.hi[0] - p.lo[0])));
    TU_CHECK_NEAR(worst, 0.0, 1e-6);
    TU_CHECK_NEAR(m.scalar_min, 0.0, 1e-7);
    TU_CHECK_NEAR(m.scalar_max, 1.0, 1e-7);
    clvr_mesh_free(&m);

    p.field = CLVR_SCENE_FIELD_CONSTANT;
    p.value = 0.375f;
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(m.scalar_min, 0.375, 0.0);
    TU_CHECK_NEAR(m.scalar_max, 0.375, 0.0);
    clvr_mesh_free(&m);

    /* The blob field stays in [0, 1] and has its peak (clamped to 1) inside. */
    uint64_t st = 5;
    float lo = 1.0f, hi = 0.0f;
    for (int i = 0; i < 200000; ++i) {
        float u[3] = {tu_randf(&st), tu_randf(&st), tu_randf(&st)};
        float f = clvr_scene_blobs(u);
        lo = fminf(lo, f);
        hi = fmaxf(hi, f);
    }
    TU_CHECK(lo >= 0.0f && lo < 0.01f);
    TU_CHECK(hi <= 1.0f && hi > 0.99f);
}

static void test_box_rejects_bad_params(void)
{
    clvr_scene_box_params p;
    clvr_mesh m;
    clvr_error err = {0};
    set_box(&p, 0, 1, 1, CLVR_SCENE_MIX_HEX);
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(m.positions == NULL && m.num_vertices == 0);
    set_box(&p, 2, 2, 2, CLVR_SCENE_MIX_HEX);
    p.hi[1] = p.lo[1];
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_ERR_USAGE, &err);
    set_box(&p, 2, 2, 2, CLVR_SCENE_MIX_MIXED);
    p.jitter = 0.1f;
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_ERR_USAGE, &err);
    set_box(&p, 2, 2, 2, CLVR_SCENE_MIX_HEX);
    p.jitter = 0.3f;
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_ERR_USAGE, &err);
    set_box(&p, 2000, 2000, 2000, CLVR_SCENE_MIX_HEX);
    uint64_t nv, nc[4];
    TU_CHECK_STATUS(clvr_scene_box_count(&p, &nv, nc, &err), CLVR_ERR_OVERFLOW, &err);
}

/* The tiling checks notice a gap and an inverted element. */
static void test_checks_can_fail(void)
{
    clvr_scene_box_params p;
    clvr_mesh m;
    clvr_error err = {0};
    vol_stats st;
    set_box(&p, 3, 3, 3, CLVR_SCENE_MIX_CYCLE);
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_OK, &err);
    m.num_cells[CLVR_CELL_HEX] -= 1; /* a hole */
    volume_stats(&m, &st);
    TU_CHECK(fabs(st.sum / box_volume(&p) - 1.0) > 1e-3);
    m.num_cells[CLVR_CELL_HEX] += 1;
    /* Mirror the first wedge: swap vertices 1, 2 and 4, 5. */
    uint32_t *w = m.indices[CLVR_CELL_WEDGE], tmp = w[1];
    w[1] = w[2];
    w[2] = tmp;
    tmp = w[4];
    w[4] = w[5];
    w[5] = tmp;
    volume_stats(&m, &st);
    TU_CHECK_EQ_U64(st.nonpositive, 1);
    clvr_mesh_free(&m);
}

static void test_default_scene(void)
{
    clvr_mesh m;
    clvr_error err = {0};
    TU_CHECK_STATUS(clvr_scene_default(&m, &err), CLVR_OK, &err);
    uint64_t total = clvr_mesh_num_elements(&m);
    printf("default scene: %" PRIu64 " elements (%" PRIu64 " tets, %" PRIu64 " pyramids, %" PRIu64 " wedges, %" PRIu64
           " hexes), %" PRIu64 " vertices, scalars %g..%g\n",
           total, m.num_cells[0], m.num_cells[1], m.num_cells[2], m.num_cells[3], m.num_vertices, (double)m.scalar_min,
           (double)m.scalar_max);
    TU_CHECK(total >= 100000 && total <= 300000);
    for (uint32_t t = 0; t < 4; ++t) TU_CHECK(m.num_cells[t] >= total / 20);
    check_tiling(&m, 8.0, "default scene");
    TU_CHECK(m.scalar_min < 0.01f);
    TU_CHECK(m.scalar_max > 0.95f && m.scalar_max <= 1.0f);
    clvr_mesh_free(&m);
}

/* ------------------------------------------------------------ clvr-gen */

/* Runs clvr-gen with args into dir/name; returns its exit code (-1 if it
 * could not run). */
static int run_gen(const char *dir, const char *name, const char *args)
{
    const char *build = getenv("CLVR_BUILD_DIR");
    char cmd[2048], kind[32];
    /* args begin with KIND: the command is clvr-gen KIND OUT rest. */
    const char *rest = strchr(args, ' ');
    snprintf(kind, sizeof kind, "%.*s", rest ? (int)(rest - args) : (int)strlen(args), args);
    snprintf(cmd, sizeof cmd, "'%s/clvr-gen' %s '%s/%s' %s --quiet", build ? build : ".", kind, dir, name,
             rest ? rest : "");
    int rc = system(cmd);
    if (rc == -1 || !WIFEXITED(rc)) return -1;
    return WEXITSTATUS(rc);
}

static int load_gen(const char *dir, const char *name, clvr_mesh *m)
{
    char path[1024];
    clvr_error err = {0};
    snprintf(path, sizeof path, "%s/%s", dir, name);
    clvr_status s = clvr_mesh_load(path, NULL, m, &err);
    TU_CHECK_STATUS(s, CLVR_OK, &err);
    remove(path);
    return s == CLVR_OK;
}

static void check_count(uint64_t got, uint64_t target, double tol)
{
    TU_CHECK_NEAR((double)got / (double)target, 1.0, tol);
}

static void test_gen(const char *dir, uint64_t n)
{
    char args[256];
    clvr_mesh m;
    vol_stats st;

    snprintf(args, sizeof args, "mixed --elements %" PRIu64, n);
    TU_CHECK_EQ_U64(run_gen(dir, "mixed.bin", args), 0);
    if (load_gen(dir, "mixed.bin", &m)) {
        check_count(clvr_mesh_num_elements(&m), n, 0.08);
        for (uint32_t t = 0; t < 4; ++t) TU_CHECK(m.num_cells[t] > 0);
        check_tiling(&m, 8.0, "clvr-gen mixed");
        TU_CHECK(m.scalar_max - m.scalar_min > 0.9f);
        clvr_mesh_free(&m);
    }

    snprintf(args, sizeof args, "amr --elements %" PRIu64, n);
    TU_CHECK_EQ_U64(run_gen(dir, "amr.bin", args), 0);
    if (load_gen(dir, "amr.bin", &m)) {
        check_count(clvr_mesh_num_elements(&m), n, 0.15);
        TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_HEX], clvr_mesh_num_elements(&m));
        double dom = 1.0;
        for (int a = 0; a < 3; ++a) dom *= (double)m.bounds_hi[a] - m.bounds_lo[a];
        TU_CHECK_NEAR(dom, 2.0, 1e-5);
        check_tiling(&m, dom, "clvr-gen amr");
        volume_stats(&m, &st);
        TU_CHECK(st.max / st.min >= 4096.0 * (1.0 - 1e-3));
        TU_CHECK(m.scalar_max > 0.9f && m.scalar_min < 0.1f);
        clvr_mesh_free(&m);
    }

    /* Lattice cellvar: 0 % tiles the unit cube; 100 % inverts some tets. */
    snprintf(args, sizeof args, "cellvar --method lattice --variance 0 --elements %" PRIu64, n);
    TU_CHECK_EQ_U64(run_gen(dir, "cvl0.bin", args), 0);
    if (load_gen(dir, "cvl0.bin", &m)) {
        check_count(m.num_cells[CLVR_CELL_TET], n, 0.15);
        check_tiling(&m, 1.0, "clvr-gen cellvar lattice 0%");
        clvr_mesh_free(&m);
    }
    snprintf(args, sizeof args, "cellvar --method lattice --variance 100 --elements %" PRIu64, n);
    TU_CHECK_EQ_U64(run_gen(dir, "cvl100.bin", args), 0);
    if (load_gen(dir, "cvl100.bin", &m)) {
        volume_stats(&m, &st);
        TU_CHECK(st.nonpositive > 0 && st.nonpositive < st.elements / 2);
        clvr_mesh_free(&m);
    }
}

static void test_gen_delaunay(const char *dir, uint64_t n)
{
    char args[256];
    clvr_mesh m;
    vol_stats st;
    if (access("/usr/bin/tetgen", X_OK) != 0) {
        fprintf(stderr, "note: /usr/bin/tetgen missing, Delaunay cellvar not tested\n");
        return;
    }
    /* Delaunay of Poisson-disk points: all positive, sizes even (max/min
     * volume bounded); 50 % displacement makes them vary. */
    double ratio0 = 0.0;
    for (int v = 0; v <= 50; v += 50) {
        snprintf(args, sizeof args, "cellvar --method delaunay --variance %d --elements %" PRIu64, v, n);
        TU_CHECK_EQ_U64(run_gen(dir, "cvd.bin", args), 0);
        if (!load_gen(dir, "cvd.bin", &m)) continue;
        clvr_error err = {0};
        TU_CHECK_STATUS(clvr_mesh_validate(&m, "cellvar delaunay", &err), CLVR_OK, &err);
        check_count(m.num_cells[CLVR_CELL_TET], n, 0.15);
        volume_stats(&m, &st);
        if (v == 0) {
            TU_CHECK_EQ_U64(st.nonpositive, 0);
            /* The hull of points in the unit cube, less a boundary layer. */
            TU_CHECK(st.sum > 0.85 && st.sum <= 1.0);
            ratio0 = st.max / st.min;
        } else {
            TU_CHECK(st.nonpositive > 0);
        }
        clvr_mesh_free(&m);
    }
    TU_CHECK(ratio0 > 1.0);
}

int main(int argc, char **argv)
{
    int slow = argc > 1 && !strcmp(argv[1], "--slow");
    if (!slow) {
        test_volume_conventions();
        test_box_single_types();
        test_box_jitter();
        test_box_mixed();
        test_box_fields();
        test_box_rejects_bad_params();
        test_checks_can_fail();
        test_default_scene();
    }
    char dir[] = "/tmp/test_scene-XXXXXX";
    if (!mkdtemp(dir)) {
        fprintf(stderr, "cannot create a temporary directory\n");
        return 1;
    }
    if (slow) {
        test_gen(dir, 5000000);
    } else {
        test_gen(dir, 60000);
        test_gen_delaunay(dir, 40000);
    }
    rmdir(dir);
    return tu_finish(slow ? "test_scene --slow" : "test_scene");
}
