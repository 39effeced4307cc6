/* mpi_main.c: `mpirun -n N clvr ...`: every rank loads its share of the mesh
 * (a convex region, mpi_share.h), clusters and renders the medium inside its
 * region with the urm estimator, and rank 0 composites the ranks' per-pixel
 * records front to back (mpi_composite.h), picks one shadow-ray origin per
 * pixel among all ranks, multiplies the ranks' transmittances along it and
 * writes the image (docs/mpi-compositing.md). Every step that can fail on
 * one rank ends in agree(): all ranks learn the first failing rank and its
 * message, rank 0 prints it once, and all return the same exit code, so a
 * failure never leaves the others waiting in a collective.
 *
 * Built into the MPI module libclvr_mpi.so (clvr_mpi.h) with its own
 * hidden copy of the pipeline, which is why it may use the library's
 * internal headers; the program (host/app) calls only clvr_mpi.h. */
#define CLVR_MPI_BUILD 1
#include "clvr_mpi.h"

#include <fcntl.h>
#include <malloc.h>
#include <math.h>
#include <mpi.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "camera.h"
#include "cli.h"
#include "clock.h"
#include "clvr.h"
#include "clvr_internal.h"
#include "image.h"
#include "limits_check.h"
#include "mesh_io.h"
#include "mpi_composite.h"
#include "mpi_share.h"
#include "mpi_share_mesh.h"
#include "partition.h"
#include "pixel_cv.h"
#include "render.h"
#include "rng.h"
#include "scene.h"
#include "series_file.h"
#include "tf.h"
#include "tf_auto.h"
#ifdef CLVR_HAVE_MPI_LOAD_BIN
#include "mpi_load.h"
#endif

int clvr_mpi_launched(void)
{
    return getenv("OMPI_COMM_WORLD_SIZE") != NULL || getenv("PMI_SIZE") != NULL || getenv("PMIX_RANK") != NULL;
}

/* The per-rank figures rank 0 gathers for --stats and --stats-json. */
typedef struct rank_stats {
    double elements, owned_elements, vertices;
    double peak_rss, resident;
    double load_s, preprocess_s, render_s, comm_s, light_s;
    double bytes_sent, samples;
    double region[6];
} rank_stats;
#define RANK_STATS_DOUBLES (sizeof(rank_stats) / sizeof(double))

typedef struct mpi_run {
    MPI_Comm comm;
    int rank, size;
    double comm_s;      /* seconds inside MPI calls (communication and waiting for other ranks) */
    double bytes_sent;  /* payload this rank sent */
} mpi_run;

/* Set by SIGINT or SIGTERM on any rank: every rank stops after the frame
 * that all of them have finished, and rank 0 writes what was accumulated
 * (exit code 130, as the single-process program). Under Open MPI 4 a Ctrl-C
 * reaches mpirun only (its ranks run in their own process groups); mpirun
 * sends the ranks SIGCONT, then SIGTERM odls_base_sigkill_timeout seconds
 * later (default 1), then SIGKILL as long again: the ranks have that long to
 * finish the frame and write (measured; README: "Interrupting"). A signal
 * handler can only reach a flag with static storage; nothing else reads or
 * writes it. */
static volatile sig_atomic_t g_mpi_stop;
static void on_stop_signal(int sig)
{
    (void)sig;
    g_mpi_stop = 1;
}

/* 1 when any rank was asked to stop (one MPI_Allreduce). */
static int stop_requested(mpi_run *m)
{
    const double t0 = clvr_clock_monotonic_s();
    int mine = g_mpi_stop ? 1 : 0, any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, m->comm);
    m->comm_s += clvr_clock_monotonic_s() - t0;
    return any;
}

/* Every rank passes its status; all get the first failing rank's status and
 * message (rank 0 prints it, naming the rank when there are several). */
static clvr_status agree(mpi_run *m, clvr_status s, clvr_error *err)
{
    const double t0 = clvr_clock_monotonic_s();
    int mine = s == CLVR_OK ? m->size : m->rank, first = m->size;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, m->comm);
    if (first < m->size) {
        struct { int status; char msg[sizeof err->msg]; } b;
        b.status = (int)s;
        memcpy(b.msg, err->msg, sizeof b.msg);
        b.msg[sizeof b.msg - 1] = 0;
        MPI_Bcast(&b, (int)sizeof b, MPI_BYTE, first, m->comm);
        err->status = (clvr_status)b.status;
        /* A message that an inner agreement (clvr_mpi_agree, the loader's)
         * already attributes ("rank K of N ...") is not prefixed again. */
        const int ranked = strncmp(b.msg, "rank ", 5) == 0 && b.msg[5] >= '0' && b.msg[5] <= '9';
        if (m->size > 1 && !ranked) snprintf(err->msg, sizeof err->msg, "rank %d: %s", first, b.msg);
        else memcpy(err->msg, b.msg, sizeof err->msg);
        s = err->status == CLVR_OK ? CLVR_ERR_INTERNAL : err->status;
    }
    m->comm_s += clvr_clock_monotonic_s() - t0;
    return s;
}

/* Test hook (docs/mpi-compositing.md): CLVR_MPI_TEST_FAIL_RANK=k makes rank k
 * fail after loading, as a rank whose input or device fails would. */
static clvr_status test_fail_hook(int rank, clvr_error *err)
{
    const char *e = getenv("CLVR_MPI_TEST_FAIL_RANK");
    if (e && *e && atoi(e) == rank)
        return clvr_error_set(err, CLVR_ERR_INTERNAL, "failed on purpose (test hook CLVR_MPI_TEST_FAIL_RANK=%s)", e);
    return CLVR_OK;
}

/* Options this mode cannot honour: refused before any work, the same on
 * every rank (they all parse the same command line). */
static clvr_status check_options(const clvr_options *o, clvr_error *err)
{
    if (o->view) return clvr_error_set(err, CLVR_ERR_USAGE, "--view is not available under mpirun; render to a file with -o");
    if (o->info) return clvr_error_set(err, CLVR_ERR_USAGE, "--info: run clvr --info without mpirun");
    if (o->orbit) return clvr_error_set(err, CLVR_ERR_USAGE, "--orbit is not available under mpirun yet; render one view per run");
    if (o->method == CLVR_RENDER_MARCH)
        return clvr_error_set(err, CLVR_ERR_USAGE, "--method march is not available under mpirun: the ranks' "
                              "images are composited with the urm estimator; use dda (the default), bins or track");
    if (o->estimator == CLVR_ESTIMATOR_DELTA)
        return clvr_error_set(err, CLVR_ERR_USAGE, "--estimator %s is not available under mpirun: MPI mode "
                              "composites the urm estimator exactly; drop --estimator",
                              clvr_render_estimator_name(o->estimator));
    if (o->mesh_path && clvr_series_is(o->mesh_path))
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: time series are not available under mpirun; render each step",
                              o->mesh_path);
    /* One MPI message per rank and frame carries the records (an int count). */
    if ((uint64_t)o->width * o->height * sizeof(clvr_mpi_record) > (uint64_t)INT32_MAX)
        return clvr_error_set(err, CLVR_ERR_USAGE, "--size %ux%u: too large for MPI mode's per-pixel gather "
                              "(%zu bytes per pixel, 2 GiB per message); use at most about 44M pixels",
                              o->width, o->height, sizeof(clvr_mpi_record));
    if (o->legend || o->outline)
        return clvr_error_set(err, CLVR_ERR_USAGE, "--legend and --outline are not available under mpirun yet");
    if (o->denoise)
        return clvr_error_set(err, CLVR_ERR_USAGE, "--denoise is not available under mpirun yet; render the image "
                              "without it, or with clvr on one process");
    /* The default runs without it (rank 0 composites every pixel once per
     * frame); asked for by name, it is refused rather than dropped. */
    if (o->adaptive > 0.0f)
        return clvr_error_set(err, CLVR_ERR_USAGE, "--adaptive %g is not available under mpirun yet: every pixel gets "
                              "one sample per frame there; drop the option (or --adaptive off), or render with clvr "
                              "on one process", (double)o->adaptive);
    return CLVR_OK;
}

static clvr_status load_whole(const clvr_options *o, clvr_mesh *m, clvr_error *err)
{
    if (!o->mesh_path) return clvr_scene_default(m, err);
    clvr_load_options lo = {0};
    lo.scalar_name = o->scalar_name;
    lo.cell_flat = o->cell_flat;
    return clvr_mesh_load(o->mesh_path, &lo, m, err);
}

/* This rank's share: the marked spot where .bin files go to the distributed
 * loader once it is merged (each rank reads about 1/N of the file); every
 * other input is loaded whole on every rank and cut (mpi_share_mesh.h).
 * *whole keeps the whole mesh where there is one (for the transfer function). */
static clvr_status load_share(mpi_run *m, const clvr_options *o, clvr_mesh *whole, clvr_mpi_share *share,
                              clvr_error *err)
{
    const size_t len = o->mesh_path ? strlen(o->mesh_path) : 0;
    const int is_bin = len > 4 && !strcmp(o->mesh_path + len - 4, ".bin");
#ifdef CLVR_HAVE_MPI_LOAD_BIN /* --- the distributed .bin loader (host/mpi/mpi_load.h) --- */
    /* A cell field needs every element around a vertex to average it (or
     * its own copies of the vertices, --cell-data flat): such a .bin is
     * read whole and cut like other formats. Rank 0 reads the header and
     * tells the others, so every rank takes the same path. */
    int parts = is_bin;
    if (parts && m->rank == 0) {
        clvr_bin_layout lay;
        clvr_error ignored = {0}; /* a bad header: the distributed loader reports it on every rank */
        const int fd = open(o->mesh_path, O_RDONLY);
        if (fd >= 0 && clvr_mesh_bin_layout(fd, o->mesh_path, o->scalar_name, &lay, &ignored) == CLVR_OK &&
            lay.has_scalar && lay.scalar_association == CLVR_FIELD_CELL)
            parts = 0;
        if (fd >= 0) close(fd);
    }
    MPI_Bcast(&parts, 1, MPI_INT, 0, m->comm);
    if (parts) {
        clvr_load_options lo = {0};
        lo.scalar_name = o->scalar_name;
        lo.cell_flat = o->cell_flat;
        return clvr_mpi_load_share_bin(m->comm, o->mesh_path, &lo, share, err);
    }
#endif
    /* Other formats have no offsets to read a part at: every rank reads the
     * file whole, once, and keeps its share. Say so, with the way out. */
    if (o->mesh_path && m->rank == 0 && m->size > 1 && !o->quiet) {
        if (is_bin)
            fprintf(stderr,
                    "clvr: note: every rank reads %s whole and keeps its share: its field is cell data, which "
                    "needs every element around a vertex; with a point field (--scalar point:NAME) each rank "
                    "reads about 1/%d of the file\n",
                    o->mesh_path, m->size);
        else
            fprintf(stderr,
                    "clvr: note: every rank reads %s whole and keeps its share; convert it to .bin "
                    "(tools/clvr-convert) and each rank reads about 1/%d of the file\n",
                    o->mesh_path, m->size);
    }
    clvr_status s = load_whole(o, whole, err);
    s = agree(m, s, err);
    if (s != CLVR_OK) return s;
    return clvr_mpi_share_from_mesh(m->comm, whole, share, err);
}

static double now(void) { return clvr_clock_monotonic_s(); }

/* The transfer function of a share loaded in parts (no rank holds the
 * whole mesh): built the same way on every rank from the agreed range and
 * bounds, with the automatic opacity's histogram and the automatic
 * density's grid summed over the ranks from the elements each owns, so
 * that every element counts once and the result is the single process's
 * (up to the order of floating-point sums). */
static clvr_status distributed_tf(mpi_run *m, const clvr_options *o, const clvr_mpi_share *share, clvr_tf *tf,
                                  float *auto_density, clvr_error *err)
{
    *auto_density = 1.0f;
    clvr_status s = clvr_tf_from_options(tf, o->colormap ? o->colormap : "cool-warm", o->tf_file, o->range_set,
                                         o->range_lo, o->range_hi, o->density_auto ? 1.0f : o->density,
                                         share->scalar_min, share->scalar_max, err);
    if (s == CLVR_OK) clvr_tf_set_extent(tf, share->bounds_lo, share->bounds_hi);
    s = agree(m, s, err);
    if (s != CLVR_OK) return s;
    double t = now();
    if (!o->opacity_ramp && !tf->opacity_set) {
        double hist[CLVR_TF_AUTO_BINS];
        clvr_tf_auto_histogram_kept(&share->mesh, share->owned, tf->range_lo, tf->range_hi, hist, CLVR_TF_AUTO_BINS);
        MPI_Allreduce(MPI_IN_PLACE, hist, (int)CLVR_TF_AUTO_BINS, MPI_DOUBLE, MPI_SUM, m->comm);
        s = clvr_tf_auto_opacity(tf, hist, CLVR_TF_AUTO_BINS, err);
    }
    s = agree(m, s, err);
    if (s != CLVR_OK) return s;
    if (o->density_auto) {
        clvr_tf unit = *tf; /* shallow: the grid only reads the points */
        unit.density = 1.0f;
        clvr_tf_auto_grid g;
        s = clvr_tf_auto_grid_create(share->bounds_lo, share->bounds_hi, &g, err);
        if (s == CLVR_OK) s = clvr_tf_auto_grid_add(&g, &share->mesh, share->owned, &unit, err);
        s = agree(m, s, err);
        if (s == CLVR_OK && g.cells) /* sigma and covered are one array of 2 x cells */
            MPI_Allreduce(MPI_IN_PLACE, g.sigma, (int)(2 * g.cells), MPI_DOUBLE, MPI_SUM, m->comm);
        float med = 0.0f;
        if (s == CLVR_OK) s = clvr_tf_auto_grid_median(&g, &med, err);
        clvr_tf_auto_grid_free(&g);
        s = agree(m, s, err);
        if (s != CLVR_OK) return s;
        *auto_density = clvr_tf_auto_density_of_median(med);
        tf->density *= *auto_density;
    }
    m->comm_s += now() - t;
    return CLVR_OK;
}


/* Writes the per-rank table (--stats) or JSON (--stats-json, written to a
 * temporary name and renamed, so a failure leaves no half file). */
static void print_stats(FILE *out, const rank_stats *rs, int n, uint32_t frames, double wall_s, uint32_t w, uint32_t h)
{
    fprintf(out, "MPI mode: %d rank%s, %u frames of %ux%u in %.3f s (%.4f s/frame)\n", n, n == 1 ? "" : "s", frames, w,
            h, wall_s, frames ? wall_s / frames : 0.0);
    fprintf(out, "%5s %10s %10s %10s %9s %8s %8s %8s %7s %10s %12s\n", "rank", "elements", "owned", "vertices", "peak MiB",
            "load s", "prep s", "render s", "comm %", "sent MiB", "lookups");
    for (int r = 0; r < n; ++r) {
        const rank_stats *q = rs + r;
        fprintf(out, "%5d %10.0f %10.0f %10.0f %9.1f %8.3f %8.3f %8.3f %7.1f %10.2f %12.0f\n", r, q->elements,
                q->owned_elements, q->vertices, q->peak_rss / 1048576.0, q->load_s, q->preprocess_s, q->render_s,
                q->render_s > 0 ? 100.0 * q->comm_s / q->render_s : 0.0, q->bytes_sent / 1048576.0, q->samples);
    }
}

static clvr_status write_stats_json(const char *path, const rank_stats *rs, int n, uint32_t frames, double wall_s,
                                    uint32_t w, uint32_t h, uint64_t global_elements, clvr_error *err)
{
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%s.tmp%ld", path, (long)getpid());
    FILE *f = fopen(tmp, "w");
    if (!f) return clvr_error_set(err, CLVR_ERR_WRITE, "--stats-json %s: cannot write; check the directory", path);
    fprintf(f, "{\n  \"mode\": \"mpi\",\n  \"ranks\": %d,\n  \"width\": %u,\n  \"height\": %u,\n  \"frames\": %u,\n", n,
            w, h, frames);
    fprintf(f, "  \"elements\": %llu,\n  \"render_wall_s\": %.6f,\n  \"frame_s\": %.6f,\n  \"per_rank\": [\n",
            (unsigned long long)global_elements, wall_s, frames ? wall_s / frames : 0.0);
    for (int r = 0; r < n; ++r) {
        const rank_stats *q = rs + r;
        fprintf(f,
                "    {\"rank\": %d, \"elements\": %.0f, \"owned_elements\": %.0f, \"vertices\": %.0f, "
                "\"bytes_peak_rss\": %.0f, \"bytes_resident\": %.0f, \"load_s\": %.6f, \"preprocess_s\": %.6f, "
                "\"render_s\": %.6f, \"light_grid_s\": %.6f, \"comm_s\": %.6f, \"comm_share\": %.6f, "
                "\"bytes_sent\": %.0f, \"samples\": %.0f, "
                "\"region\": [%g, %g, %g, %g, %g, %g]}%s\n",
                r, q->elements, q->owned_elements, q->vertices, q->peak_rss, q->resident, q->load_s, q->preprocess_s,
                q->render_s, q->light_s, q->comm_s, q->render_s > 0 ? q->comm_s / q->render_s : 0.0, q->bytes_sent,
                q->samples, q->region[0], q->region[1], q->region[2], q->region[3], q->region[4], q->region[5],
                r + 1 < n ? "," : "");
    }
    fprintf(f, "  ]\n}\n");
    if (fclose(f) != 0 || rename(tmp, path) != 0) {
        remove(tmp);
        return clvr_error_set(err, CLVR_ERR_WRITE, "--stats-json %s: write failed; check the disk", path);
    }
    return CLVR_OK;
}

/* Adds frame `frame`'s camera-ray offsets from the pixel centres (what
 * kernels/render_mpi.cl's clvr_mpi_camera_ray draws from the frame's seed, the
 * same on every rank) to ctl, 4 per pixel as clvr_render_frame's controls.
 * The first uniform of a frame differs between ranks (their own streams),
 * so it is left at 0: the composited image gets the jitter's control
 * variate only (kernels/pixel_cv.h). */
static void add_jitters(double *ctl, uint32_t w, uint32_t h, uint32_t frame, uint64_t seed, uint32_t sampler,
                        uint32_t pixel_filter)
{
    if (pixel_filter == CLVR_PIXEL_POINT) return; /* every offset 0 */
    const clvr_u32 lo = (clvr_u32)seed, hi = (clvr_u32)(seed >> 32);
    for (uint32_t p = 0; p < w * h; ++p) {
        /* The streams of clvr_mpi_camera_ray. */
        clvr_rng rng = clvr_rng_make(p, frame, lo, hi);
        float ld[CLVR_LD_DIMS], jx, jy;
        if (sampler == CLVR_SAMPLER_LD) clvr_ld_sample(p, frame, lo, hi, ld);
        clvr_pixel_jitter(sampler == CLVR_SAMPLER_LD ? ld : NULL, &rng, pixel_filter, &jx, &jy);
        ctl[4 * (size_t)p] += jx - 0.5f;
        ctl[4 * (size_t)p + 1] += jy - 0.5f;
    }
}

static int run(mpi_run *m, const clvr_options *o)
{
    clvr_error err = {0};
    clvr_message msg = {0};
    clvr_mesh whole = {0};
    clvr_mpi_share share = {0};
    clvr_tf tf = {0};
    clvr_context *ctx = NULL;
    clvr_dataset *ds = NULL;
    clvr_tracer *tracer = NULL;
    float *table = NULL, *pick_t = NULL, *tau = NULL, *tau_all = NULL, *img = NULL, *grid = NULL, *grid_all = NULL;
    double *sum = NULL, *ctl = NULL;
    float *sumf = NULL, *ctlf = NULL;
    uint64_t seed = 0;
    uint32_t sampler = 0, pixel_filter = 0;
    clvr_mpi_record *rec = NULL, *rec_all = NULL;
    clvr_mpi_shadow_pick *picks = NULL;
    rank_stats st;
    memset(&st, 0, sizeof st);
    const int root = m->rank == 0;
    const size_t npix = (size_t)o->width * o->height;
    uint32_t frames = 0;
    double wall_s = 0.0;
    int stopped = 0; /* stopped by a signal (g_mpi_stop): exit code 130 */
    clvr_status s = check_options(o, &err);

    /* --- output checked by rank 0 before any work */
    if (s == CLVR_OK && root) s = clvr_image_check_output(o->output, &err);
    s = agree(m, s, &err);
    if (s != CLVR_OK) goto done;

    /* --- the share of the mesh */
    double t = now();
    if (root && !o->quiet)
        fprintf(stderr, "clvr: %d rank%s: loading %s\n", m->size, m->size == 1 ? "" : "s",
                o->mesh_path ? o->mesh_path : "the built-in scene");
    s = load_share(m, o, &whole, &share, &err);
    if (s == CLVR_OK) s = test_fail_hook(m->rank, &err);
    s = agree(m, s, &err);
    if (s != CLVR_OK) goto done;
    st.load_s = now() - t;
    st.elements = (double)clvr_mesh_num_elements(&share.mesh);
    st.owned_elements = (double)share.owned_elements;
    st.vertices = (double)share.mesh.num_vertices;
    for (int a = 0; a < 3; ++a) { st.region[a] = share.region_lo[a]; st.region[3 + a] = share.region_hi[a]; }

    /* --- the transfer function: built once on rank 0 (from the whole mesh
     * where every rank has it, else from rank 0's share over the global
     * scalar range), baked, broadcast: every rank gets the same table. */
    struct { uint32_t n; float lo, hi, density, auto_density; } tfh = {0, 0, 0, 0, 0};
    const int have_whole = whole.num_vertices > 0;
    float dens = o->density;
    if (!have_whole) {
        s = distributed_tf(m, o, &share, &tf, &dens, &err);
        if (s != CLVR_OK) goto done;
    }
    if (root) {
        if (have_whole)
            s = clvr_internal_tf_build(&whole, o->colormap, o->tf_file, o->range_set, o->range_lo, o->range_hi,
                                       o->density_auto ? 0.0f : o->density, o->opacity_ramp, &tf, &dens, &err);
        if (s == CLVR_OK) {
            /* Opacity to extinction relative to the whole mesh's diagonal. */
            clvr_tf_set_extent(&tf, share.bounds_lo, share.bounds_hi);
            tfh.n = clvr_tf_table_size(&tf);
            tfh.lo = tf.range_lo;
            tfh.hi = tf.range_hi;
            tfh.density = tf.density;
            tfh.auto_density = dens;
            table = malloc((size_t)tfh.n * 4 * sizeof(float));
            if (!table) s = clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for the transfer function");
            else clvr_tf_bake(&tf, table, tfh.n);
        }
    }
    s = agree(m, s, &err);
    if (s != CLVR_OK) goto done;
    t = now();
    MPI_Bcast(&tfh, (int)sizeof tfh, MPI_BYTE, 0, m->comm);
    if (!root) table = malloc((size_t)tfh.n * 4 * sizeof(float));
    m->comm_s += now() - t;
    s = table ? CLVR_OK : clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for the transfer function");
    s = agree(m, s, &err);
    if (s != CLVR_OK) goto done;
    t = now();
    MPI_Bcast(table, (int)(tfh.n * 4), MPI_FLOAT, 0, m->comm);
    m->comm_s += now() - t;
    if (root && o->density_auto && !o->quiet)
        fprintf(stderr, "clvr: automatic density %.3g (--density auto)\n", (double)tfh.auto_density);
    clvr_mesh_free(&whole); /* from here each rank holds its share only */
#ifdef __GLIBC__
    malloc_trim(0); /* hand the whole mesh's pages back now, not at exit */
#endif

    /* --- device, Quick Clusters of the share, renderer */
    t = now();
    s = clvr_internal_status(clvr_context_create(o->device, &ctx, &msg), &msg, &err);
    if (s == CLVR_OK) s = clvr_internal_dataset_adopt(&share.mesh, &ds, &err);
    clvr_renderer *renderer = NULL;
    if (s == CLVR_OK) {
        clvr_preprocess_settings ps;
        clvr_preprocess_settings_init(&ps);
        ps.name = o->mesh_path ? o->mesh_path : "(built-in default scene)";
        if (o->leaf_size) ps.leaf_size = o->leaf_size;
        if (o->sampling_size) ps.sampling_size = o->sampling_size;
        ps.one_curve = o->one_curve;
        /* As many partitions per rank as one process would cut the whole
         * mesh into (partition.h's default size), so that each rank's are
         * 1/N the size and its preprocessing peak is 1/N of one process's:
         * a share is heap memory, not a mapped file, and one 2.5M-element
         * partition had put its peak at 1.34 x 1/N of one process's
         * (bench/mpi.sh, 5M mixed, 2 ranks; with this 1.0x). */
        const uint64_t part = clvr_partition_elements(share.global_elements, 0);
        ps.partitions = o->partitions ? o->partitions : part ? (uint32_t)((share.global_elements + part - 1) / part) : 1;
        ps.consume = 1;
        ps.width = o->width;
        ps.height = o->height;
        /* Every render setting of the command line, converted as the
         * program converts them (cli.c, then the library's checks). */
        clvr_tracer_settings ts;
        clvr_tracer_settings_init(&ts);
        clvr_render_settings rsv;
        int shadows = 0;
        s = clvr_internal_status(clvr_cli_tracer_settings(o, &ts, &msg), &msg, &err);
        if (s == CLVR_OK) s = clvr_internal_render_settings(&ts, o->width, o->height, &rsv, &shadows, &err);
        /* The ranks' regions are composited with urm's records (a walk's
         * tets would cross the regions' cuts): walk and auto render as urm
         * here, the same expected image. */
        if (rsv.estimator != CLVR_ESTIMATOR_DELTA) rsv.estimator = CLVR_ESTIMATOR_URM;
        rsv.pixel_filter = o->pixel_filter; /* clvr_setting_name("pixel_filter") is in CLVR_PIXEL_* order */
        /* Rank 0 composites every pixel once per frame: no refine passes
         * (adaptive sampling is a single-process feature), nor their sums. */
        rsv.adaptive = 0.0f;
        seed = rsv.seed;
        sampler = rsv.sampler;
        pixel_filter = rsv.pixel_filter;
        clvr_render_settings *rs = &rsv;
        /* The region is one more clip box (intersected with --clip-box):
         * camera rays, shadow rays and the light grid's rays are all cut to
         * it (clvr_ray_clip), so the rank contributes exactly the medium
         * inside its region. An empty intersection is a zero-size box at a
         * corner: rays meet it in intervals of length 0. The macrocell and
         * light grids span the whole mesh's bounds on every rank. */
        int empty = 0;
        for (int a = 0; a < 3; ++a) {
            rs->clip_lo[a] = o->clip_box_set ? fmaxf(o->clip_lo[a], share.region_lo[a]) : share.region_lo[a];
            rs->clip_hi[a] = o->clip_box_set ? fminf(o->clip_hi[a], share.region_hi[a]) : share.region_hi[a];
            if (rs->clip_lo[a] > rs->clip_hi[a]) empty = 1;
            rs->grid_lo[a] = share.bounds_lo[a];
            rs->grid_hi[a] = share.bounds_hi[a];
        }
        if (empty)
            for (int a = 0; a < 3; ++a) rs->clip_lo[a] = rs->clip_hi[a] = share.region_lo[a];
        /* Every rank's light grid has the same cells (they are combined
         * cell by cell): sized for the whole mesh, not the rank's part. */
        if (rs->light_res == 0) rs->light_res = clvr_light_res_for(share.global_elements);
        /* The broadcast table is set on the renderer below; the tracer's own
         * automatic transfer function (at a first clvr_tracer_render, which
         * this driver never calls) is not computed from the share. */
        /* One quantization box for all ranks (the whole mesh's bounds): the
         * shares' Hilbert curves are pieces of one curve. */
        if (s == CLVR_OK)
            s = clvr_internal_tracer_create(ctx, ds, &ps, share.bounds_lo, share.bounds_hi, rs, shadows, &tracer,
                                            &st.preprocess_s, &err);
    }
    if (s == CLVR_OK) {
        renderer = clvr_internal_tracer_renderer(tracer);
        clvr_tracer_drop_dataset(tracer, &msg);
        clvr_dataset_destroy(ds);
        ds = NULL;
        s = clvr_renderer_set_tf(renderer, table, tfh.n, tfh.lo, tfh.hi, tfh.density, &err);
    }
    /* The camera frames the whole mesh's bounds, as one process does. */
    if (s == CLVR_OK) {
        clvr_camera cam;
        float eye[3], target[3], up[3];
        s = clvr_internal_status(clvr_cli_view(o, share.bounds_lo, share.bounds_hi, eye, target, up, &msg), &msg, &err);
        if (s == CLVR_OK) s = clvr_camera_look_at(&cam, eye, target, up, o->fovy, o->width, o->height, &err);
        if (s == CLVR_OK) s = clvr_renderer_set_camera(renderer, &cam, &err);
    }
    s = agree(m, s, &err);
    if (s != CLVR_OK) goto done;
    if (root && !o->quiet)
        fprintf(stderr, "clvr: %d rank%s clustered their shares in %.2f s (rank 0)\n", m->size,
                m->size == 1 ? "" : "s", st.preprocess_s);
    {
        uint64_t cur = 0;
#ifdef __GLIBC__
        malloc_trim(0);
#endif
        clvr_mem_rss(&cur, NULL);
        st.resident = (double)cur;
    }

    /* --- buffers */
    const int shadows = o->shadows != 0;
    rec = malloc(npix * sizeof *rec);
    pick_t = malloc(npix * sizeof(float));
    tau = malloc(npix * sizeof(float));
    if (root) {
        rec_all = malloc((size_t)m->size * npix * sizeof *rec);
        tau_all = malloc(npix * sizeof(float));
        picks = malloc(npix * sizeof *picks);
        img = malloc(npix * 4 * sizeof(float));
        sum = calloc(npix * 4, sizeof(double));
        ctl = calloc(npix * 4, sizeof(double));
        sumf = malloc(npix * 4 * sizeof(float));
        ctlf = malloc(npix * 4 * sizeof(float));
    }
    s = rec && pick_t && tau && (!root || (rec_all && tau_all && picks && img && sum && ctl && sumf && ctlf))
            ? CLVR_OK
            : clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for %ux%u MPI records", o->width, o->height);
    s = agree(m, s, &err);
    if (s != CLVR_OK) goto done;

    /* --- the light grid: each rank's grid sees the medium in its region
     * only; their product is the global one (docs/mpi-compositing.md). */
    const double render0 = now(), comm0 = m->comm_s;
    if (shadows) {
        const size_t cap = clvr_light_nodes(CLVR_URM_LIGHT_RES);
        uint32_t res = 0;
        grid = malloc(cap * sizeof(float));
        grid_all = malloc(cap * sizeof(float));
        s = grid && grid_all ? clvr_renderer_light_grid(renderer, grid, &res, &err)
                             : clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for the light grid");
        s = agree(m, s, &err);
        if (s != CLVR_OK) goto done;
        const size_t ng = clvr_light_nodes(res); /* the same on every rank: the same settings */
        t = now();
        MPI_Allreduce(grid, grid_all, (int)ng, MPI_FLOAT, MPI_PROD, m->comm);
        m->comm_s += now() - t;
        m->bytes_sent += (double)ng * sizeof(float);
        /* Test hook (docs/mpi-compositing.md): G = 1 everywhere, still
         * unbiased, so that every shadow comes from the correction rays and
         * the tests see the cross-rank pick at full strength. */
        const char *lg = getenv("CLVR_MPI_TEST_LIGHT_GRID");
        if (lg && !strcmp(lg, "one"))
            for (size_t i = 0; i < ng; ++i) grid_all[i] = 1.0f;
        s = clvr_renderer_set_light_grid(renderer, grid_all, &err);
        s = agree(m, s, &err);
        if (s != CLVR_OK) goto done;
        st.light_s = now() - render0;
    }

    /* --- frames */
    clvr_mpi_composite_params cp;
    memset(&cp, 0, sizeof cp);
    memcpy(cp.background, o->background, sizeof cp.background);
    cp.light_intensity = o->light_intensity;
    cp.shadows = shadows;
    cp.seed = o->seed ^ 0xC0A1E5CEull;
    uint32_t jitter_shift = 0; /* 1: the image's controls from the wrong frames (test hook) */
    {
        /* Test hook (docs/mpi-compositing.md): a compositing that is wrong
         * on purpose, for the tests that must notice it; "jitter" keeps the
         * image unbiased but takes each frame's jitter control from the
         * next frame's draws, so that the control variate only adds noise. */
        const char *b = getenv("CLVR_MPI_TEST_BREAK");
        if (b && !strcmp(b, "rank0")) cp.broken = CLVR_MPI_BREAK_RANK0;
        else if (b && !strcmp(b, "order")) cp.broken = CLVR_MPI_BREAK_ORDER;
        else if (b && !strcmp(b, "jitter")) jitter_shift = 1;
    }
    const uint32_t rank_key = (uint32_t)m->rank + 1u;
    const int rec_bytes = (int)(npix * sizeof *rec);
    double last_report = render0;
    signal(SIGINT, on_stop_signal);
    signal(SIGTERM, on_stop_signal);
    for (frames = 0; frames < o->spp; ++frames) {
        if (stop_requested(m)) {
            stopped = 1;
            break;
        }
        uint64_t n1 = 0, n2 = 0;
        s = clvr_renderer_mpi_record(renderer, frames, rank_key, rec, &n1, &err);
        s = agree(m, s, &err);
        if (s != CLVR_OK) goto done;
        t = now();
        MPI_Gather(rec, rec_bytes, MPI_BYTE, rec_all, rec_bytes, MPI_BYTE, 0, m->comm);
        m->comm_s += now() - t;
        if (!root) m->bytes_sent += rec_bytes;
        if (root) {
            cp.frame = frames;
            for (size_t p = 0; p < npix; ++p) {
                clvr_mpi_composite_pixel(rec_all + p, npix, (uint32_t)m->size, &cp, (uint32_t)p, img + 4 * p, picks + p);
                pick_t[p] = picks[p].t;
            }
        }
        if (shadows) {
            t = now();
            MPI_Bcast(pick_t, (int)npix, MPI_FLOAT, 0, m->comm);
            m->comm_s += now() - t;
            if (root) m->bytes_sent += (double)npix * sizeof(float) * (m->size - 1);
            s = clvr_renderer_mpi_shadow(renderer, frames, rank_key, pick_t, tau, &n2, &err);
            s = agree(m, s, &err);
            if (s != CLVR_OK) goto done;
            t = now();
            MPI_Reduce(tau, tau_all, (int)npix, MPI_FLOAT, MPI_PROD, 0, m->comm);
            m->comm_s += now() - t;
            if (!root) m->bytes_sent += (double)npix * sizeof(float);
            if (root)
                for (size_t p = 0; p < npix; ++p)
                    if (picks[p].t >= 0.0f)
                        for (int a = 0; a < 3; ++a) img[4 * p + a] += picks[p].factor[a] * (tau_all[p] - picks[p].g);
        }
        st.samples += (double)(n1 + n2);
        if (root) {
            for (size_t i = 0; i < npix * 4; ++i) sum[i] += img[i];
            add_jitters(ctl, o->width, o->height, frames + jitter_shift, seed, sampler, pixel_filter);
            const double tn = now();
            if (!o->quiet && (tn - last_report > 1.0 || frames + 1 == o->spp)) {
                const double per = (tn - render0) / (frames + 1);
                fprintf(stderr, "clvr: frame %u/%u, %.2f s/frame, %.0f s left\n", frames + 1, o->spp, per,
                        per * (o->spp - frames - 1));
                last_report = tn;
            }
        }
    }
    wall_s = now() - render0;
    st.render_s = wall_s;
    st.comm_s = m->comm_s - comm0;
    st.bytes_sent = m->bytes_sent;

    /* --- image (none when stopped before the first frame) */
    if (stopped && frames == 0) {
        if (root) fprintf(stderr, "clvr: interrupted before the first frame of %s; not written\n", o->output);
        goto done;
    }
    if (root) {
        /* The means less the jitter's control variate, as one process's
         * image read (clvr_pixel_cv, the device pass's host reference). */
        for (size_t i = 0; i < npix * 4; ++i) {
            sumf[i] = (float)sum[i];
            ctlf[i] = (float)ctl[i];
        }
        const float inv_n = 1.0f / (float)(frames ? frames : 1);
        for (uint32_t y = 0; y < o->height; ++y)
            for (uint32_t x = 0; x < o->width; ++x)
                clvr_pixel_cv(sumf, ctlf, inv_n, NULL, NULL, 0, o->width, o->height, x, y, img + 4 * ((size_t)y * o->width + x));
        clvr_image_display display = {o->exposure, (clvr_tonemap)o->tonemap, o->transparent, NULL};
        s = clvr_image_write_display(o->output, o->width, o->height, img, &display, &err);
    }
    s = agree(m, s, &err);
    if (s != CLVR_OK) goto done;
    if (root && !o->quiet) fprintf(stderr, "clvr: wrote %s (%ux%u, %u spp, %d ranks)\n", o->output, o->width, o->height,
                                   frames, m->size);
    if (stopped && root)
        fprintf(stderr, "clvr: interrupted after %u of %u frames; the image holds what was accumulated\n", frames,
                o->spp);

    /* --- stats */
    {
        uint64_t peak = 0;
        clvr_mem_rss(NULL, &peak);
        st.peak_rss = (double)peak;
        rank_stats *all = root ? malloc((size_t)m->size * sizeof *all) : NULL;
        s = !root || all ? CLVR_OK : clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for the stats");
        s = agree(m, s, &err);
        if (s == CLVR_OK)
            MPI_Gather(&st, (int)RANK_STATS_DOUBLES, MPI_DOUBLE, all, (int)RANK_STATS_DOUBLES, MPI_DOUBLE, 0, m->comm);
        if (s == CLVR_OK && root) {
            if (o->stats) print_stats(stdout, all, m->size, frames, wall_s, o->width, o->height);
            if (o->stats_json)
                s = write_stats_json(o->stats_json, all, m->size, frames, wall_s, o->width, o->height,
                                     share.global_elements, &err);
        }
        free(all);
        s = agree(m, s, &err);
    }

done:
    if (s != CLVR_OK && root) fprintf(stderr, "clvr: %s\n", err.msg);
    free(table);
    free(pick_t);
    free(tau);
    free(tau_all);
    free(img);
    free(sum);
    free(ctl);
    free(sumf);
    free(ctlf);
    free(rec);
    free(rec_all);
    free(picks);
    free(grid);
    free(grid_all);
    clvr_tracer_destroy(tracer);
    clvr_dataset_destroy(ds);
    clvr_context_destroy(ctx);
    clvr_tf_free(&tf);
    clvr_mpi_share_free(&share);
    clvr_mesh_free(&whole);
    return s != CLVR_OK ? clvr_status_exit_code(s) : stopped ? 130 : 0;
}

int clvr_mpi_main(int argc, char **argv)
{
    /* The program parsed this command line once already (for --help and
     * friends); the module parses it again, with the same parser (cli.c is
     * compiled into both), rather than take the program's struct across the
     * library boundary. A bad command line fails here before MPI starts,
     * on every rank alike. */
    clvr_options opts;
    clvr_message msg = {0};
    if (clvr_cli_parse(argc, argv, &opts, &msg) != CLVR_RESULT_OK) {
        fprintf(stderr, "clvr: %s\n", msg.text);
        return clvr_result_exit_code(msg.result);
    }
    const clvr_options *o = &opts;
    int inited = 0;
    MPI_Initialized(&inited);
    if (!inited) MPI_Init(&argc, &argv);
    mpi_run m = {MPI_COMM_WORLD, 0, 1, 0.0, 0.0};
    MPI_Comm_rank(m.comm, &m.rank);
    MPI_Comm_size(m.comm, &m.size);
    if (o->kernel_dir) setenv("CLVR_KERNEL_DIR", o->kernel_dir, 1);
    int rc = run(&m, o);
    MPI_Finalize();
    return rc;
}
