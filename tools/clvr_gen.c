/* clvr-gen: synthetic test meshes of any size, streamed to clvr's .bin.
 *
 *   clvr-gen KIND OUT.bin [--elements N] [--seed S] [--variance PCT]
 *            [--method auto|delaunay|lattice] [--quiet]
 *
 * KIND
 *   cellvar  The paper's cell-variance sets (Morrical et al. 2022, 4.1):
 *            tetrahedra of even size whose vertices are then displaced by up
 *            to PCT % of the sampling radius r, in a random direction (uniform
 *            in the ball), which makes element sizes vary and, as in the paper,
 *            may invert tets near 100 % (the count is printed).
 *            --method delaunay: Bridson Poisson-disk points of radius r in the
 *              unit cube, Delaunay-tetrahedralised by /usr/bin/tetgen (as a
 *              subprocess, on a temporary .node file); holds the mesh in
 *              memory, fine to ~20M tets.
 *            --method lattice: a regular lattice of spacing r (the nearest
 *              neighbour distance, as the Poisson radius is), each cube split
 *              into the 6 Kuhn tets (Delaunay-like, equal volumes), streamed
 *              per layer: any size. auto = delaunay up to 12M elements.
 *   amr      An AMR-like hex mesh (the NASA Landing Gear situation): a
 *            2:1:1 domain of coarse bricks, each refined as an octree up to
 *            4 levels (finest cells 1/4096 of a brick's volume) where it nears
 *            a thin feature (a wheel-like torus and a strut-like cylinder).
 *            Hanging nodes, no overlaps, exact tiling. Scalar: a Gaussian of
 *            the distance to the feature (width 4 finest cells), plus a faint
 *            background ramp, so large values live in the fine cells.
 *   mixed    The default scene's mixed tet/pyramid/wedge/hex split of a cube
 *            lattice (host/io/scene.h) at any resolution, same "blobs" field.
 *
 * --elements N is a target: the actual count is within a few % and printed.
 * Everything is deterministic from --seed. Memory stays well below the file
 * size (chunks are appended with clvr_bin_writer), except delaunay cellvar.
 * Exit codes as clvr (host/cl/status.h). */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "clock.h"
#include "mesh.h"
#include "mesh_io.h"
#include "scene.h"

extern char **environ;

#define TETGEN_PATH "/usr/bin/tetgen"
/* Delaunay cellvar above this many elements goes to the lattice (tetgen's
 * memory and time grow past what a 2-core, 24 GiB box does in a minute). */
#define DELAUNAY_MAX_ELEMENTS 12000000ull

typedef enum gen_method { METHOD_AUTO, METHOD_DELAUNAY, METHOD_LATTICE } gen_method;

typedef struct gen_args {
    const char *kind, *out;
    uint64_t elements;
    uint64_t seed;
    double variance; /* fraction, 0..1+ */
    gen_method method;
    int quiet;
} gen_args;

/* ------------------------------------------------------------ small utilities */

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static double rand01(uint64_t *state) { return (double)(splitmix64(state) >> 11) * (1.0 / 9007199254740992.0); }

/* A random vector uniform in the ball of the given radius, from a state
 * seeded per vertex (so streamed and in-memory paths agree). */
static void ball_offset(uint64_t seed, uint64_t vertex, double radius, double d[3])
{
    uint64_t st = seed ^ (vertex * 0xd1b54a32d192ed03ull);
    splitmix64(&st);
    do {
        for (int a = 0; a < 3; ++a) d[a] = 2.0 * rand01(&st) - 1.0;
    } while (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 1.0);
    for (int a = 0; a < 3; ++a) d[a] *= radius;
}

static double tet_det(const float *a, const float *b, const float *c, const float *d)
{
    double u[3], v[3], w[3];
    for (int i = 0; i < 3; ++i) {
        u[i] = (double)b[i] - a[i];
        v[i] = (double)c[i] - a[i];
        w[i] = (double)d[i] - a[i];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static uint64_t bin_bytes(uint64_t nv, const uint64_t nc[CLVR_CELL_TYPE_COUNT])
{
    uint64_t words = 4 * nv;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) words += nc[t] * clvr_cell_vertex_count(t);
    return 256 + 4 * words;
}

/* Fails early, before any work, when the output's file system lacks room. */
static clvr_status check_disk(const char *path, uint64_t need, clvr_error *err)
{
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (!slash) snprintf(dir, sizeof dir, ".");
    else if (slash == dir) dir[1] = '\0';
    else *slash = '\0';
    struct statvfs sv;
    if (statvfs(dir, &sv) != 0)
        return clvr_error_set(err, CLVR_ERR_WRITE, "%s: cannot inspect directory %s: %s", path, dir, strerror(errno));
    uint64_t avail = (uint64_t)sv.f_bavail * (uint64_t)sv.f_frsize;
    if (avail < need + (need >> 6))
        return clvr_error_set(err, CLVR_ERR_WRITE,
                              "%s: the mesh needs %.2f GB but %s has %.2f GB free; free space or ask for fewer "
                              "--elements",
                              path, (double)need / 1e9, dir, (double)avail / 1e9);
    return CLVR_OK;
}

/* Progress on stderr, at most once a second. */
typedef struct progress {
    int quiet;
    uint64_t total, done;
    double t0, last;
    const char *what;
} progress;

static void progress_start(progress *p, int quiet, const char *what, uint64_t total)
{
    p->quiet = quiet;
    p->total = total;
    p->done = 0;
    p->t0 = p->last = clvr_clock_monotonic_s();
    p->what = what;
}

static void progress_add(progress *p, uint64_t n)
{
    p->done += n;
    double t = clvr_clock_monotonic_s();
    if (p->quiet || t - p->last < 1.0) return;
    p->last = t;
    fprintf(stderr, "\rclvr-gen: %s %5.1f%%  %.1fM elements/s   ", p->what,
            p->total ? 100.0 * (double)p->done / (double)p->total : 100.0,
            (double)p->done / 1e6 / (t - p->t0 > 1e-9 ? t - p->t0 : 1e-9));
    fflush(stderr);
}

static void progress_end(progress *p)
{
    if (!p->quiet && p->last > p->t0) fprintf(stderr, "\n");
}

static void print_summary(const gen_args *a, uint64_t nv, const uint64_t nc[CLVR_CELL_TYPE_COUNT], double t0)
{
    uint64_t total = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) total += nc[t];
    printf("%s: %s: %" PRIu64 " elements (target %" PRIu64 ", %+.2f%%): %" PRIu64 " tets, %" PRIu64 " pyramids, %" PRIu64
           " wedges, %" PRIu64 " hexes; %" PRIu64 " vertices; %.3f GB; %.2f s\n",
           a->out, a->kind, total, a->elements,
           a->elements ? 100.0 * ((double)total - (double)a->elements) / (double)a->elements : 0.0, nc[0], nc[1], nc[2],
           nc[3], nv, (double)bin_bytes(nv, nc) / 1e9, clvr_clock_monotonic_s() - t0);
}

/* ------------------------------------------------------------ mixed */

static void mixed_params(uint32_t n, clvr_scene_box_params *p)
{
    clvr_scene_box_params_init(p);
    p->nx = p->ny = p->nz = n;
    for (int a = 0; a < 3; ++a) {
        p->lo[a] = -1.0f;
        p->hi[a] = 1.0f;
    }
    p->mix = CLVR_SCENE_MIX_MIXED;
    p->field = CLVR_SCENE_FIELD_BLOBS;
}

static uint64_t sum4(const uint64_t c[CLVR_CELL_TYPE_COUNT]) { return c[0] + c[1] + c[2] + c[3]; }

static clvr_status gen_mixed(const gen_args *a, clvr_error *err)
{
    const double t0 = clvr_clock_monotonic_s();
    clvr_scene_box_params p;
    uint64_t nv, nc[CLVR_CELL_TYPE_COUNT];
    clvr_status s;
    /* Elements per cube hardly depend on the resolution: calibrate on 64^3. */
    mixed_params(64, &p);
    if ((s = clvr_scene_box_count(&p, &nv, nc, err)) != CLVR_OK) return s;
    double per_cube = (double)sum4(nc) / (64.0 * 64.0 * 64.0);
    /* Refuse early, from the calibration's bytes per element, before the
     * exact count (minutes at billions of cubes). */
    if ((s = check_disk(a->out, (uint64_t)(0.97 * (double)bin_bytes(nv, nc) / (double)sum4(nc) * (double)a->elements), err)) !=
        CLVR_OK)
        return s;
    double n = cbrt((double)a->elements / per_cube);
    mixed_params((uint32_t)fmax(1.0, fmin(4000.0, floor(n + 0.5))), &p);
    if ((s = clvr_scene_box_count(&p, &nv, nc, err)) != CLVR_OK) return s;
    if ((s = check_disk(a->out, bin_bytes(nv, nc), err)) != CLVR_OK) return s;

    uint64_t max_cells[CLVR_CELL_TYPE_COUNT], max_centres;
    clvr_scene_box_slab_bound(&p, max_cells, &max_centres);
    const uint64_t layer_verts = ((uint64_t)p.nx + 1) * ((uint64_t)p.ny + 1);
    float *xyz = malloc(3 * sizeof(float) * (layer_verts > max_centres ? layer_verts : max_centres));
    float *sc = malloc(sizeof(float) * (layer_verts > max_centres ? layer_verts : max_centres));
    uint32_t *cells[CLVR_CELL_TYPE_COUNT] = {0};
    int ok = xyz && sc;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        cells[t] = malloc(sizeof(uint32_t) * clvr_cell_vertex_count(t) * max_cells[t]);
        ok = ok && cells[t];
    }
    clvr_bin_writer *w = NULL;
    if (!ok) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "clvr-gen mixed: cannot allocate slab buffers for %u^3 cubes", p.nx);
        goto cleanup;
    }
    if ((s = clvr_bin_writer_open(a->out, nv, nc, "blobs", &w, err)) != CLVR_OK) goto cleanup;

    /* Pass 1: lattice vertices, layer by layer. Pass 2: cells and the
     * pyramid centres, which follow the lattice in the vertex array. */
    for (uint32_t k = 0; k <= p.nz && s == CLVR_OK; ++k) {
        clvr_scene_box_layer(&p, k, xyz, sc);
        s = clvr_bin_writer_positions(w, xyz, layer_verts, err);
        if (s == CLVR_OK) s = clvr_bin_writer_scalars(w, sc, layer_verts, err);
    }
    progress pr;
    progress_start(&pr, a->quiet, "mixed", sum4(nc));
    uint64_t centre = layer_verts * ((uint64_t)p.nz + 1);
    for (uint32_t k = 0; k < p.nz && s == CLVR_OK; ++k) {
        uint64_t got[CLVR_CELL_TYPE_COUNT], ncent;
        clvr_scene_box_slab(&p, k, centre, cells, got, xyz, sc, &ncent);
        centre += ncent;
        if (ncent) {
            s = clvr_bin_writer_positions(w, xyz, ncent, err);
            if (s == CLVR_OK) s = clvr_bin_writer_scalars(w, sc, ncent, err);
        }
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t)
            if (got[t]) s = clvr_bin_writer_cells(w, t, cells[t], got[t], err);
        progress_add(&pr, sum4(got));
    }
    progress_end(&pr);
    if (s == CLVR_OK) {
        s = clvr_bin_writer_close(w, err);
        w = NULL;
    }
    if (s == CLVR_OK && !a->quiet) {
        printf("mixed: %u^3 cubes of [-1,1]^3\n", p.nx);
        print_summary(a, nv, nc, t0);
    }
cleanup:
    clvr_bin_writer_abort(w);
    free(xyz);
    free(sc);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) free(cells[t]);
    return s;
}

/* ------------------------------------------------------------ amr */

#define AMR_LEVELS 4u
#define AMR_FINE (1u << AMR_LEVELS)   /* finest cells per brick edge: 16 */
#define AMR_LAT (AMR_FINE + 1u)       /* lattice points per brick edge: 17 */

typedef struct amr_ctx {
    uint32_t nb;            /* bricks along y and z; 2 * nb along x */
    uint32_t nx, ny, nz;    /* bricks per axis */
    double h;               /* brick edge */
    double hf;              /* finest cell edge */
    double band;            /* fine cells within this distance of the feature surface */
    /* per brick scratch */
    uint32_t map[AMR_LAT * AMR_LAT * AMR_LAT]; /* local lattice point -> global vertex id */
    uint32_t touched[AMR_LAT * AMR_LAT * AMR_LAT];
    uint32_t num_touched;
    /* output (NULL in the counting pass) */
    uint32_t *hexes;        /* 8 per hex */
    float *xyz, *sc;        /* new vertices */
    uint64_t num_hexes, num_new;  /* in the buffers (or counted) */
    uint64_t next_vertex;   /* global id of the next new vertex */
    uint64_t per_level[AMR_LEVELS + 1]; /* leaves by refinement level (0: a whole brick) */
} amr_ctx;

/* Distance to the surface of the feature: a wheel (torus of major radius
 * 0.22, tube 0.05, axis along y, centre (0.8, 0.5, 0.42)) and a strut
 * (cylinder of radius 0.025 from the wheel's hub up to the top, z = 1). */
static double amr_distance(const double x[3])
{
    double dx = x[0] - 0.8, dy = x[1] - 0.5, dz = x[2] - 0.42;
    double rho = sqrt(dx * dx + dz * dz) - 0.22;
    double d_wheel = fabs(sqrt(rho * rho + dy * dy) - 0.05);
    /* Strut: segment from (0.8, 0.5, 0.42) to (0.8, 0.5, 1.0), radius 0.025. */
    double tz = fmin(fmax(dz, 0.0), 0.58);
    double ez = dz - tz;
    double d_strut = fabs(sqrt(dx * dx + dy * dy + ez * ez) - 0.025);
    return fmin(d_wheel, d_strut);
}

static float amr_scalar(const amr_ctx *c, const double x[3])
{
    double d = amr_distance(x), sigma = 4.0 * c->hf;
    return (float)(exp(-d * d / (2.0 * sigma * sigma)) + 0.02 * x[0] / 2.0);
}

static void amr_init(amr_ctx *c, uint32_t nb)
{
    memset(c, 0, sizeof *c);
    c->nb = nb;
    c->nx = 2 * nb;
    c->ny = c->nz = nb;
    c->h = 1.0 / nb;
    c->hf = c->h / AMR_FINE;
    c->band = 1.5 * c->hf;
}

/* Global id of local lattice point (a, b, c) of brick (bi, bj, bk). Brick
 * corners are the coarse lattice vertices (shared by neighbouring bricks,
 * numbered first); other points are new vertices of this brick (duplicated
 * where two refined bricks share a face: cheap, as only refined faces have
 * them). */
static uint32_t amr_vertex(amr_ctx *c, uint32_t bi, uint32_t bj, uint32_t bk, uint32_t a, uint32_t b, uint32_t d)
{
    const uint32_t l = (d * AMR_LAT + b) * AMR_LAT + a;
    if (c->map[l] != UINT32_MAX) return c->map[l];
    uint32_t id;
    if ((a == 0 || a == AMR_FINE) && (b == 0 || b == AMR_FINE) && (d == 0 || d == AMR_FINE)) {
        id = (uint32_t)(((uint64_t)(bk + d / AMR_FINE) * (c->ny + 1) + (bj + b / AMR_FINE)) * (c->nx + 1) +
                        (bi + a / AMR_FINE));
    } else {
        id = (uint32_t)c->next_vertex++;
        if (c->xyz) {
            /* From integer fine coordinates, so shared points agree bit for bit. */
            double x[3] = {(double)((uint64_t)bi * AMR_FINE + a) * c->hf, (double)((uint64_t)bj * AMR_FINE + b) * c->hf,
                           (double)((uint64_t)bk * AMR_FINE + d) * c->hf};
            float *o = c->xyz + 3 * c->num_new;
            for (int k = 0; k < 3; ++k) o[k] = (float)x[k];
            c->sc[c->num_new] = amr_scalar(c, x);
        }
        ++c->num_new;
    }
    c->map[l] = id;
    c->touched[c->num_touched++] = l;
    return id;
}

static void amr_cell(amr_ctx *c, uint32_t bi, uint32_t bj, uint32_t bk, uint32_t level, uint32_t a, uint32_t b,
                     uint32_t d)
{
    const uint32_t size = AMR_FINE >> level;
    if (level < AMR_LEVELS) {
        double x[3] = {((double)((uint64_t)bi * AMR_FINE + a) + 0.5 * size) * c->hf,
                       ((double)((uint64_t)bj * AMR_FINE + b) + 0.5 * size) * c->hf,
                       ((double)((uint64_t)bk * AMR_FINE + d) + 0.5 * size) * c->hf};
        /* Refine every cell that may touch the band: centre distance within
         * the half-diagonal plus the band. */
        if (amr_distance(x) < 0.8660254037844386 * size * c->hf + c->band) {
            const uint32_t hs = size / 2;
            for (uint32_t o = 0; o < 8; ++o)
                amr_cell(c, bi, bj, bk, level + 1, a + (o & 1u) * hs, b + ((o >> 1) & 1u) * hs, d + ((o >> 2) & 1u) * hs);
            return;
        }
    }
    static const uint8_t corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    uint32_t ids[8];
    for (int k = 0; k < 8; ++k)
        ids[k] = amr_vertex(c, bi, bj, bk, a + corner[k][0] * size, b + corner[k][1] * size, d + corner[k][2] * size);
    if (c->hexes) memcpy(c->hexes + 8 * c->num_hexes, ids, sizeof ids);
    ++c->num_hexes;
    ++c->per_level[level];
}

static void amr_brick(amr_ctx *c, uint32_t bi, uint32_t bj, uint32_t bk)
{
    amr_cell(c, bi, bj, bk, 0, 0, 0, 0);
    for (uint32_t t = 0; t < c->num_touched; ++t) c->map[c->touched[t]] = UINT32_MAX;
    c->num_touched = 0;
}

/* Counts hexes and new vertices for nb without writing anything. */
static void amr_count(amr_ctx *c, uint32_t nb, uint64_t *hexes, uint64_t *verts)
{
    amr_init(c, nb);
    memset(c->map, 0xff, sizeof c->map);
    const uint64_t coarse = ((uint64_t)c->nx + 1) * (c->ny + 1) * (c->nz + 1);
    c->next_vertex = coarse;
    for (uint32_t bk = 0; bk < c->nz; ++bk)
        for (uint32_t bj = 0; bj < c->ny; ++bj)
            for (uint32_t bi = 0; bi < c->nx; ++bi) amr_brick(c, bi, bj, bk);
    *hexes = c->num_hexes;
    *verts = c->next_vertex;
}

static clvr_status gen_amr(const gen_args *a, clvr_error *err)
{
    const double t0 = clvr_clock_monotonic_s();
    clvr_status s = CLVR_OK;
    amr_ctx *c = malloc(sizeof *c);
    if (!c) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "clvr-gen amr: out of memory");
    /* Hexes grow as a nb^3 (coarse) + b nb^2 (the shells around the feature):
     * fit on two small meshes, solve for the target, then one correction. */
    uint64_t h16, h32, hx, nv;
    amr_count(c, 16, &h16, &nv);
    amr_count(c, 32, &h32, &nv);
    const uint64_t nc32[CLVR_CELL_TYPE_COUNT] = {0, 0, 0, h32};
    if ((s = check_disk(a->out, (uint64_t)(0.95 * (double)bin_bytes(nv, nc32) / (double)h32 * (double)a->elements),
                        err)) != CLVR_OK) {
        free(c);
        return s;
    }
    double n1 = 16, n2 = 32, y1 = (double)h16, y2 = (double)h32;
    /* a n^3 + b n^2 = y  at n1, n2 */
    double ca = (y2 / (n2 * n2) - y1 / (n1 * n1)) / (n2 - n1), cb = y1 / (n1 * n1) - ca * n1;
    double target = (double)a->elements;
    double nb = 16;
    for (double lo = 1, hi = 5000, it = 0; it < 60; ++it) {
        nb = 0.5 * (lo + hi);
        if (ca * nb * nb * nb + cb * nb * nb < target) lo = nb;
        else hi = nb;
    }
    uint32_t nbi = (uint32_t)fmax(1.0, floor(nb + 0.5));
    amr_count(c, nbi, &hx, &nv);
    if (fabs((double)hx - target) > 0.02 * target && nbi > 4) {
        /* Local scaling exponent ~ 2.5 between the two regimes. */
        double f = pow(target / (double)hx, 1.0 / 2.5);
        uint32_t n2i = (uint32_t)fmax(1.0, floor(nbi * f + 0.5));
        if (n2i != nbi) {
            nbi = n2i;
            amr_count(c, nbi, &hx, &nv);
        }
    }
    uint64_t nc[CLVR_CELL_TYPE_COUNT] = {0, 0, 0, hx};
    if (nv > UINT32_MAX) {
        free(c);
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "clvr-gen amr: %" PRIu64 " vertices exceed 32-bit indices; ask for fewer --elements", nv);
    }
    if ((s = check_disk(a->out, bin_bytes(nv, nc), err)) != CLVR_OK) {
        free(c);
        return s;
    }

    /* Buffers flushed whenever one more brick might not fit. */
    const uint64_t cap_hex = 1u << 20, cap_vert = 1u << 20;
    const uint64_t brick_max_hex = AMR_FINE * AMR_FINE * AMR_FINE, brick_max_vert = AMR_LAT * AMR_LAT * AMR_LAT;
    uint32_t *hexbuf = malloc(sizeof(uint32_t) * 8 * cap_hex);
    float *xyz = malloc(sizeof(float) * 3 * cap_vert), *sc = malloc(sizeof(float) * cap_vert);
    clvr_bin_writer *w = NULL;
    if (!hexbuf || !xyz || !sc) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "clvr-gen amr: cannot allocate chunk buffers");
        goto cleanup;
    }
    if ((s = clvr_bin_writer_open(a->out, nv, nc, "vorticity", &w, err)) != CLVR_OK) goto cleanup;
    amr_init(c, nbi);
    memset(c->map, 0xff, sizeof c->map);
    /* The coarse lattice (brick corners), layer by layer. */
    {
        const uint64_t lv = ((uint64_t)c->nx + 1) * (c->ny + 1);
        for (uint32_t k = 0; k <= c->nz && s == CLVR_OK; ++k) {
            for (uint64_t v = 0; v < lv; v += cap_vert) {
                uint64_t n = lv - v < cap_vert ? lv - v : cap_vert;
                for (uint64_t q = 0; q < n; ++q) {
                    uint64_t i = (v + q) % (c->nx + 1), j = (v + q) / (c->nx + 1);
                    double x[3] = {(double)(i * AMR_FINE) * c->hf, (double)(j * AMR_FINE) * c->hf,
                                   (double)((uint64_t)k * AMR_FINE) * c->hf};
                    for (int e = 0; e < 3; ++e) xyz[3 * q + e] = (float)x[e];
                    sc[q] = amr_scalar(c, x);
                }
                s = clvr_bin_writer_positions(w, xyz, n, err);
                if (s == CLVR_OK) s = clvr_bin_writer_scalars(w, sc, n, err);
                if (s != CLVR_OK) break;
            }
        }
        c->next_vertex = lv * ((uint64_t)c->nz + 1);
    }
    c->hexes = hexbuf;
    c->xyz = xyz;
    c->sc = sc;
    progress pr;
    progress_start(&pr, a->quiet, "amr", hx);
    for (uint32_t bk = 0; bk < c->nz && s == CLVR_OK; ++bk)
        for (uint32_t bj = 0; bj < c->ny && s == CLVR_OK; ++bj)
            for (uint32_t bi = 0; bi < c->nx && s == CLVR_OK; ++bi) {
                if (c->num_hexes + brick_max_hex > cap_hex || c->num_new + brick_max_vert > cap_vert) {
                    s = clvr_bin_writer_cells(w, CLVR_CELL_HEX, hexbuf, c->num_hexes, err);
                    if (s == CLVR_OK && c->num_new) s = clvr_bin_writer_positions(w, xyz, c->num_new, err);
                    if (s == CLVR_OK && c->num_new) s = clvr_bin_writer_scalars(w, sc, c->num_new, err);
                    progress_add(&pr, c->num_hexes);
                    c->num_hexes = c->num_new = 0;
                    if (s != CLVR_OK) break;
                }
                amr_brick(c, bi, bj, bk);
            }
    if (s == CLVR_OK && c->num_hexes) s = clvr_bin_writer_cells(w, CLVR_CELL_HEX, hexbuf, c->num_hexes, err);
    if (s == CLVR_OK && c->num_new) s = clvr_bin_writer_positions(w, xyz, c->num_new, err);
    if (s == CLVR_OK && c->num_new) s = clvr_bin_writer_scalars(w, sc, c->num_new, err);
    progress_add(&pr, c->num_hexes);
    progress_end(&pr);
    if (s == CLVR_OK) {
        s = clvr_bin_writer_close(w, err);
        w = NULL;
    }
    if (s == CLVR_OK && !a->quiet) {
        printf("amr: %u x %u x %u bricks of edge %g on [0,2]x[0,1]x[0,1], %u levels (coarse/fine volume %u)\n", c->nx,
               c->ny, c->nz, c->h, AMR_LEVELS, AMR_FINE * AMR_FINE * AMR_FINE);
        printf("amr: hexes by level 0..%u:", AMR_LEVELS);
        for (uint32_t l = 0; l <= AMR_LEVELS; ++l) printf(" %" PRIu64, c->per_level[l]);
        printf("\n");
        print_summary(a, nv, nc, t0);
    }
cleanup:
    clvr_bin_writer_abort(w);
    free(hexbuf);
    free(xyz);
    free(sc);
    free(c);
    return s;
}

/* ------------------------------------------------------------ cellvar */

static float cellvar_scalar(const float x[3])
{
    float u[3];
    for (int a = 0; a < 3; ++a) u[a] = fminf(1.0f, fmaxf(0.0f, x[a]));
    return clvr_scene_blobs(u);
}

/* Bridson's Poisson-disk sampling (SIGGRAPH sketch 2007) in the unit cube:
 * no two points closer than r; k = 30 candidates per active point. */
static clvr_status poisson_disk(double r, uint64_t seed, float **out_xyz, uint64_t *out_n, clvr_error *err)
{
    const double cell = r / sqrt(3.0);
    const uint32_t g = (uint32_t)ceil(1.0 / cell);
    const uint64_t gcells = (uint64_t)g * g * g;
    int32_t *grid = malloc(sizeof(int32_t) * gcells);
    uint64_t cap = gcells < 1024 ? 1024 : gcells; /* at most one point per grid cell */
    float *pts = malloc(sizeof(float) * 3 * cap);
    uint32_t *active = malloc(sizeof(uint32_t) * cap);
    if (!grid || !pts || !active) {
        free(grid);
        free(pts);
        free(active);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "clvr-gen cellvar: cannot allocate a %u^3 Poisson grid", g);
    }
    memset(grid, 0xff, sizeof(int32_t) * gcells);
    uint64_t st = seed * 0x9e3779b97f4a7c15ull + 12345u, n = 0, na = 0;
#define GRID_AT(x) ((uint32_t)fmin((double)(g - 1), floor((x) / cell)))
    {
        double p[3] = {rand01(&st), rand01(&st), rand01(&st)};
        for (int a = 0; a < 3; ++a) pts[a] = (float)p[a];
        grid[((uint64_t)GRID_AT(p[2]) * g + GRID_AT(p[1])) * g + GRID_AT(p[0])] = 0;
        active[na++] = 0;
        n = 1;
    }
    while (na > 0) {
        uint64_t ai = splitmix64(&st) % na;
        const float *c = pts + 3 * (uint64_t)active[ai];
        int found = 0;
        for (int tries = 0; tries < 30 && !found; ++tries) {
            /* Uniform in the shell r..2r around c. */
            double d[3], len2;
            do {
                for (int a = 0; a < 3; ++a) d[a] = 2.0 * rand01(&st) - 1.0;
                len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            } while (len2 > 1.0 || len2 < 1e-6);
            double rad = r * cbrt(1.0 + 7.0 * rand01(&st)) / sqrt(len2);
            double q[3];
            int inside = 1;
            for (int a = 0; a < 3; ++a) {
                q[a] = c[a] + d[a] * rad;
                inside = inside && q[a] >= 0.0 && q[a] < 1.0;
            }
            if (!inside) continue;
            int gi = (int)GRID_AT(q[0]), gj = (int)GRID_AT(q[1]), gk = (int)GRID_AT(q[2]);
            int ok = 1;
            for (int kk = gk - 2; kk <= gk + 2 && ok; ++kk)
                for (int jj = gj - 2; jj <= gj + 2 && ok; ++jj)
                    for (int ii = gi - 2; ii <= gi + 2 && ok; ++ii) {
                        if (ii < 0 || jj < 0 || kk < 0 || ii >= (int)g || jj >= (int)g || kk >= (int)g) continue;
                        int32_t o = grid[((uint64_t)kk * g + jj) * g + ii];
                        if (o < 0) continue;
                        const float *op = pts + 3 * (uint64_t)o;
                        double e0 = op[0] - q[0], e1 = op[1] - q[1], e2 = op[2] - q[2];
                        if (e0 * e0 + e1 * e1 + e2 * e2 < r * r) ok = 0;
                    }
            if (!ok) continue;
            for (int a = 0; a < 3; ++a) pts[3 * n + a] = (float)q[a];
            grid[((uint64_t)gk * g + gj) * g + gi] = (int32_t)n;
            active[na++] = (uint32_t)n;
            ++n;
            found = 1;
        }
        if (!found) active[ai] = active[--na];
    }
#undef GRID_AT
    free(grid);
    free(active);
    *out_xyz = pts;
    *out_n = n;
    return CLVR_OK;
}

/* Runs tetgen on the points; returns the tets (4 per tet, 0-based). */
static clvr_status run_tetgen(const float *pts, uint64_t n, uint32_t **out_tets, uint64_t *out_nt, clvr_error *err)
{
    char dir[] = "/tmp/clvr-gen-XXXXXX";
    char node[64], ele[64];
    clvr_status s = CLVR_OK;
    uint32_t *tets = NULL;
    if (!mkdtemp(dir)) return clvr_error_set(err, CLVR_ERR_WRITE, "clvr-gen: cannot create a temporary directory in /tmp: %s", strerror(errno));
    snprintf(node, sizeof node, "%s/p.node", dir);
    snprintf(ele, sizeof ele, "%s/p.ele", dir);
    FILE *f = fopen(node, "w");
    if (!f) {
        s = clvr_error_set(err, CLVR_ERR_WRITE, "clvr-gen: cannot write %s: %s", node, strerror(errno));
        goto done;
    }
    fprintf(f, "%" PRIu64 " 3 0 0\n", n);
    for (uint64_t i = 0; i < n; ++i)
        fprintf(f, "%" PRIu64 " %.9g %.9g %.9g\n", i, (double)pts[3 * i], (double)pts[3 * i + 1], (double)pts[3 * i + 2]);
    if (fclose(f) != 0) {
        s = clvr_error_set(err, CLVR_ERR_WRITE, "clvr-gen: cannot write %s (disk full?)", node);
        goto done;
    }
    {
        /* -Q quiet, -N -F no .node/.face output, -I no iteration number:
         * only p.ele, the Delaunay tetrahedralisation of the points. */
        char *argv[] = {"tetgen", "-QNFI", node, NULL};
        pid_t pid;
        posix_spawn_file_actions_t fa;
        int status = 0;
        posix_spawn_file_actions_init(&fa);
        /* tetgen prints "Opening ..." even with -Q; keep stdout for our summary. */
        posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
        int rc = posix_spawn(&pid, TETGEN_PATH, &fa, NULL, argv, environ);
        posix_spawn_file_actions_destroy(&fa);
        if (rc != 0) {
            s = clvr_error_set(err, CLVR_ERR_USAGE, "clvr-gen: cannot run %s: %s; install Debian's tetgen or use --method lattice",
                               TETGEN_PATH, strerror(rc));
            goto done;
        }
        if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
            s = clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr-gen: %s failed on %s (status %d); use --method lattice",
                               TETGEN_PATH, node, status);
            goto done;
        }
    }
    f = fopen(ele, "r");
    if (!f) {
        s = clvr_error_set(err, CLVR_ERR_IO, "clvr-gen: tetgen wrote no %s", ele);
        goto done;
    }
    {
        unsigned long long nt = 0;
        int npt = 0, attr = 0;
        if (fscanf(f, "%llu %d %d", &nt, &npt, &attr) != 3 || npt != 4) {
            fclose(f);
            s = clvr_error_set(err, CLVR_ERR_FORMAT, "clvr-gen: %s: unexpected header", ele);
            goto done;
        }
        tets = malloc(sizeof(uint32_t) * 4 * (nt ? nt : 1));
        if (!tets) {
            fclose(f);
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "clvr-gen: cannot hold %llu tets", nt);
            goto done;
        }
        for (uint64_t t = 0; t < nt; ++t) {
            unsigned long long id, v[4];
            if (fscanf(f, "%llu %llu %llu %llu %llu", &id, &v[0], &v[1], &v[2], &v[3]) != 5 || v[0] >= n || v[1] >= n ||
                v[2] >= n || v[3] >= n) {
                fclose(f);
                free(tets);
                tets = NULL;
                s = clvr_error_set(err, CLVR_ERR_FORMAT, "clvr-gen: %s: bad tet %" PRIu64, ele, t);
                goto done;
            }
            for (int k = 0; k < 4; ++k) tets[4 * t + k] = (uint32_t)v[k];
        }
        fclose(f);
        *out_nt = nt;
    }
done:
    remove(ele);
    remove(node);
    rmdir(dir);
    *out_tets = tets;
    return s;
}

/* Points per unit volume of Bridson sampling with radius r: about
 * POISSON_DENSITY / r^3 (measured with k = 30: 0.585 at 400k points, 0.597 at
 * 28k); Delaunay tets per point in the unit cube: 6.5 (6.47 at 28k, 6.51 at
 * 400k points). The point count is corrected once if it misses. */
#define POISSON_DENSITY 0.585
#define TETS_PER_POINT 6.5

static clvr_status gen_cellvar_delaunay(const gen_args *a, clvr_error *err)
{
    const double t0 = clvr_clock_monotonic_s();
    double npts = (double)a->elements / TETS_PER_POINT;
    double r = cbrt(POISSON_DENSITY / (npts > 4 ? npts : 4));
    float *pts = NULL, *sc = NULL;
    uint32_t *tets = NULL;
    uint64_t n = 0, nt = 0, inverted = 0;
    clvr_bin_writer *w = NULL;
    clvr_status s = poisson_disk(r, a->seed, &pts, &n, err);
    if (s != CLVR_OK) return s;
    if (fabs((double)n - npts) > 0.02 * npts) {
        r *= cbrt((double)n / npts);
        free(pts);
        pts = NULL;
        if ((s = poisson_disk(r, a->seed, &pts, &n, err)) != CLVR_OK) return s;
    }
    if (!a->quiet) fprintf(stderr, "clvr-gen: %" PRIu64 " Poisson-disk points (r = %.5g), running tetgen\n", n, r);
    if ((s = run_tetgen(pts, n, &tets, &nt, err)) != CLVR_OK) goto cleanup;
    /* Positive orientation before the displacement (tetgen's own order is
     * not VTK's promise), so inversions counted below are the displacement's. */
    for (uint64_t t = 0; t < nt; ++t) {
        uint32_t *e = tets + 4 * t;
        if (tet_det(pts + 3 * (uint64_t)e[0], pts + 3 * (uint64_t)e[1], pts + 3 * (uint64_t)e[2],
                    pts + 3 * (uint64_t)e[3]) < 0) {
            uint32_t tmp = e[2];
            e[2] = e[3];
            e[3] = tmp;
        }
    }
    sc = malloc(sizeof(float) * (n ? n : 1));
    if (!sc) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "clvr-gen cellvar: out of memory");
        goto cleanup;
    }
    for (uint64_t i = 0; i < n; ++i) {
        double d[3];
        ball_offset(a->seed, i, a->variance * r, d);
        for (int k = 0; k < 3; ++k) pts[3 * i + k] = (float)(pts[3 * i + k] + d[k]);
        sc[i] = cellvar_scalar(pts + 3 * i);
    }
    for (uint64_t t = 0; t < nt; ++t) {
        const uint32_t *e = tets + 4 * t;
        if (tet_det(pts + 3 * (uint64_t)e[0], pts + 3 * (uint64_t)e[1], pts + 3 * (uint64_t)e[2],
                    pts + 3 * (uint64_t)e[3]) <= 0)
            ++inverted;
    }
    uint64_t nc[CLVR_CELL_TYPE_COUNT] = {nt, 0, 0, 0};
    if ((s = check_disk(a->out, bin_bytes(n, nc), err)) != CLVR_OK) goto cleanup;
    if ((s = clvr_bin_writer_open(a->out, n, nc, "blobs", &w, err)) != CLVR_OK) goto cleanup;
    s = clvr_bin_writer_positions(w, pts, n, err);
    if (s == CLVR_OK) s = clvr_bin_writer_scalars(w, sc, n, err);
    if (s == CLVR_OK) s = clvr_bin_writer_cells(w, CLVR_CELL_TET, tets, nt, err);
    if (s == CLVR_OK) {
        s = clvr_bin_writer_close(w, err);
        w = NULL;
    }
    if (s == CLVR_OK && !a->quiet) {
        printf("cellvar (delaunay): %" PRIu64 " Poisson-disk points, r = %.6g, displacement up to %.0f%% of r; "
               "inverted tets: %" PRIu64 " (%.3f%%)\n",
               n, r, 100.0 * a->variance, inverted, nt ? 100.0 * (double)inverted / (double)nt : 0.0);
        print_summary(a, n, nc, t0);
    }
cleanup:
    clvr_bin_writer_abort(w);
    free(pts);
    free(sc);
    free(tets);
    return s;
}

/* Lattice vertex (i, j, k) of an m^3 lattice of spacing h, displaced. */
static void lattice_vertex(uint32_t m, double h, double disp, uint64_t seed, uint32_t i, uint32_t j, uint32_t k,
                           float out[3])
{
    double d[3];
    uint64_t id = ((uint64_t)k * m + j) * m + i;
    ball_offset(seed, id, disp, d);
    out[0] = (float)(i * h + d[0]);
    out[1] = (float)(j * h + d[1]);
    out[2] = (float)(k * h + d[2]);
}

static clvr_status gen_cellvar_lattice(const gen_args *a, clvr_error *err)
{
    static const uint8_t corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    static const uint8_t kuhn[6][4] = {{0, 1, 2, 6}, {0, 1, 6, 5}, {0, 3, 6, 2},
                                       {0, 3, 7, 6}, {0, 4, 5, 6}, {0, 4, 6, 7}};
    const double t0 = clvr_clock_monotonic_s();
    uint32_t cubes = (uint32_t)fmax(1.0, floor(cbrt((double)a->elements / 6.0) + 0.5));
    const uint32_t m = cubes + 1;
    const double h = 1.0 / cubes, disp = a->variance * h;
    const uint64_t nv = (uint64_t)m * m * m, layer = (uint64_t)m * m;
    uint64_t nc[CLVR_CELL_TYPE_COUNT] = {6ull * cubes * cubes * cubes, 0, 0, 0}, inverted = 0;
    if (nv > UINT32_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "clvr-gen cellvar: %" PRIu64 " vertices exceed 32-bit indices", nv);
    clvr_status s = check_disk(a->out, bin_bytes(nv, nc), err);
    if (s != CLVR_OK) return s;
    float *xyz = malloc(sizeof(float) * 3 * layer), *sc = malloc(sizeof(float) * layer);
    float *lay0 = malloc(sizeof(float) * 3 * layer), *lay1 = malloc(sizeof(float) * 3 * layer);
    uint32_t *tets = malloc(sizeof(uint32_t) * 4 * 6 * (uint64_t)cubes * cubes);
    clvr_bin_writer *w = NULL;
    if (!xyz || !sc || !tets || !lay0 || !lay1) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "clvr-gen cellvar: cannot allocate layer buffers");
        goto cleanup;
    }
    if ((s = clvr_bin_writer_open(a->out, nv, nc, "blobs", &w, err)) != CLVR_OK) goto cleanup;
    for (uint32_t k = 0; k < m && s == CLVR_OK; ++k) {
        for (uint32_t j = 0; j < m; ++j)
            for (uint32_t i = 0; i < m; ++i) {
                uint64_t v = (uint64_t)j * m + i;
                lattice_vertex(m, h, disp, a->seed, i, j, k, xyz + 3 * v);
                sc[v] = cellvar_scalar(xyz + 3 * v);
            }
        s = clvr_bin_writer_positions(w, xyz, layer, err);
        if (s == CLVR_OK) s = clvr_bin_writer_scalars(w, sc, layer, err);
    }
    progress pr;
    progress_start(&pr, a->quiet, "cellvar", nc[0]);
    /* lay0/lay1 hold the displaced positions of layers k and k+1, to count
     * inverted tets without a second pass over the file. */
    for (uint32_t j = 0; j < m; ++j)
        for (uint32_t i = 0; i < m; ++i) lattice_vertex(m, h, disp, a->seed, i, j, 0, lay0 + 3 * ((uint64_t)j * m + i));
    for (uint32_t k = 0; k < cubes && s == CLVR_OK; ++k) {
        for (uint32_t j = 0; j < m; ++j)
            for (uint32_t i = 0; i < m; ++i)
                lattice_vertex(m, h, disp, a->seed, i, j, k + 1, lay1 + 3 * ((uint64_t)j * m + i));
        uint64_t e = 0;
        for (uint32_t j = 0; j < cubes; ++j)
            for (uint32_t i = 0; i < cubes; ++i) {
                uint32_t v[8];
                const float *x[8];
                for (int c = 0; c < 8; ++c) {
                    uint64_t l = (uint64_t)(j + corner[c][1]) * m + (i + corner[c][0]);
                    v[c] = (uint32_t)((uint64_t)(k + corner[c][2]) * layer + l);
                    x[c] = (corner[c][2] ? lay1 : lay0) + 3 * l;
                }
                for (int t = 0; t < 6; ++t, ++e) {
                    for (int c = 0; c < 4; ++c) tets[4 * e + c] = v[kuhn[t][c]];
                    if (tet_det(x[kuhn[t][0]], x[kuhn[t][1]], x[kuhn[t][2]], x[kuhn[t][3]]) <= 0) ++inverted;
                }
            }
        s = clvr_bin_writer_cells(w, CLVR_CELL_TET, tets, e, err);
        float *tmp = lay0;
        lay0 = lay1;
        lay1 = tmp;
        progress_add(&pr, e);
    }
    progress_end(&pr);
    if (s == CLVR_OK) {
        s = clvr_bin_writer_close(w, err);
        w = NULL;
    }
    if (s == CLVR_OK && !a->quiet) {
        printf("cellvar (lattice): %u^3 cubes x 6 Kuhn tets, spacing r = %.6g, displacement up to %.0f%% of r; "
               "inverted tets: %" PRIu64 " (%.3f%%)\n",
               cubes, h, 100.0 * a->variance, inverted, 100.0 * (double)inverted / (double)nc[0]);
        print_summary(a, nv, nc, t0);
    }
cleanup:
    clvr_bin_writer_abort(w);
    free(xyz);
    free(sc);
    free(lay0);
    free(lay1);
    free(tets);
    return s;
}

/* ------------------------------------------------------------ main */

static int usage(const char *msg)
{
    if (msg) fprintf(stderr, "clvr-gen: %s\n", msg);
    fprintf(stderr,
            "usage: clvr-gen KIND OUT.bin [--elements N] [--seed S] [--variance PCT] [--method auto|delaunay|lattice] "
            "[--quiet]\n"
            "  KIND: cellvar (tets, displaced by PCT %% of the sampling radius), amr (adaptive hexes, 4 levels),\n"
            "        mixed (tets, pyramids, wedges, hexes; the default scene at any size)\n"
            "  N accepts suffixes k, M, G (10M = 10000000); default 1M\n");
    return clvr_status_exit_code(CLVR_ERR_USAGE);
}

static int parse_count(const char *s, uint64_t *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || errno) return 0;
    if (*end == 'k' || *end == 'K') v *= 1e3, ++end;
    else if (*end == 'm' || *end == 'M') v *= 1e6, ++end;
    else if (*end == 'g' || *end == 'G') v *= 1e9, ++end;
    if (*end || !(v >= 1.0) || v > 1e12) return 0;
    *out = (uint64_t)(v + 0.5);
    return 1;
}

int main(int argc, char **argv)
{
    gen_args a = {0};
    a.elements = 1000000;
    a.seed = 1;
    a.method = METHOD_AUTO;
    int positional = 0;
    for (int i = 1; i < argc; ++i) {
        const char *o = argv[i];
        if (!strcmp(o, "--help") || !strcmp(o, "-h")) {
            usage(NULL);
            return 0;
        } else if (!strcmp(o, "--quiet")) {
            a.quiet = 1;
        } else if (!strcmp(o, "--elements") || !strcmp(o, "--seed") || !strcmp(o, "--variance") || !strcmp(o, "--method")) {
            if (i + 1 >= argc) return usage("an option lacks its value");
            const char *v = argv[++i];
            if (!strcmp(o, "--elements")) {
                if (!parse_count(v, &a.elements)) return usage("--elements needs a positive count like 1000000 or 10M");
            } else if (!strcmp(o, "--seed")) {
                char *end;
                a.seed = strtoull(v, &end, 0);
                if (*end || end == v) return usage("--seed needs an integer");
            } else if (!strcmp(o, "--variance")) {
                char *end;
                double pct = strtod(v, &end);
                if (*end || end == v || !(pct >= 0.0 && pct <= 1000.0))
                    return usage("--variance needs a percentage in [0, 1000], e.g. 50");
                a.variance = pct / 100.0;
            } else {
                if (!strcmp(v, "auto")) a.method = METHOD_AUTO;
                else if (!strcmp(v, "delaunay")) a.method = METHOD_DELAUNAY;
                else if (!strcmp(v, "lattice")) a.method = METHOD_LATTICE;
                else return usage("--method is auto, delaunay or lattice");
            }
        } else if (o[0] == '-' && o[1]) {
            fprintf(stderr, "clvr-gen: unknown option %s\n", o);
            return usage(NULL);
        } else if (positional == 0) {
            a.kind = o;
            ++positional;
        } else if (positional == 1) {
            a.out = o;
            ++positional;
        } else {
            return usage("too many arguments");
        }
    }
    if (positional != 2) return usage("KIND and OUT.bin are required");

    clvr_error err = {0};
    clvr_status s;
    if (!strcmp(a.kind, "mixed")) {
        s = gen_mixed(&a, &err);
    } else if (!strcmp(a.kind, "amr")) {
        s = gen_amr(&a, &err);
    } else if (!strcmp(a.kind, "cellvar")) {
        int delaunay = a.method == METHOD_DELAUNAY || (a.method == METHOD_AUTO && a.elements <= DELAUNAY_MAX_ELEMENTS);
        s = delaunay ? gen_cellvar_delaunay(&a, &err) : gen_cellvar_lattice(&a, &err);
    } else {
        fprintf(stderr, "clvr-gen: unknown KIND %s\n", a.kind);
        return usage(NULL);
    }
    if (s != CLVR_OK) {
        fprintf(stderr, "clvr-gen: %s: %s\n", clvr_status_name(s), err.msg);
        return clvr_status_exit_code(s);
    }
    return 0;
}
